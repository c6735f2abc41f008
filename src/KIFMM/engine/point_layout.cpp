// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// The points of all ranks as the tree choice sees them (kifmm.h: PointLayout, gather_layout):
// an adaptive histogram of the points over the evaluation's root, refined level by level on
// global counts (one reduction per level), and stand-in points spread over its cells.
#include "communicator.h"
#include "distributed.h"
#include "kifmm.h"
#include "morton.h"
#include "octree.h"
#include "periodic.h"

#include <algorithm>
#include <cstdint>

namespace kifmm {

namespace {
// splitmix64: the stand-in points' positions, the same sequence on every rank
uint64_t next_random(uint64_t &state)
{
  uint64_t z = (state += 0x9e3779b97f4a7c15ULL);
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}
double unit_random(uint64_t &state)
{
  return (double) (next_random(state) >> 11) * 0x1.0p-53;
}

// the evaluation's root: the periodic cell (or a fixed root), else the bounding cube of all
// points (as the distributed evaluation takes it: distributed.cpp, global_root)
RootBox layout_root(const KernelSpec &kernel, const Options &options, std::size_t n, const double *xyz,
                    Communicator &comm)
{
  RootBox root;
  if (options.fixed_root) {
    for (int d = 0; d < 3; ++d) root.center[d] = options.root_center[d], root.shape[d] = options.root_shape[d];
    root.half_width = options.root_half_width;
    return root;
  }
  double lo[3], hi[3];
  global_bounds(comm, n, xyz, lo, hi);
  root = bounding_cube_of(lo, hi);
  if (kernel.type == KernelType::Yukawa) root.half_width = std::exp2(std::ceil(std::log2(root.half_width)));
  return root;
}
}    // namespace

PointLayout gather_layout(const KernelSpec &kernel, const Options &options, std::size_t n, const double *xyz,
                          Communicator &comm)
{
  PointLayout out;
  uint64_t total = n;
  comm.allreduce_sum(&total, 1);
  out.n = total;
  out.model = options;
  double most = -(double) n;    // the most points on one rank
  comm.allreduce_min(&most, 1);
  if (total > 0) out.model.model_share = std::min(1.0, -most / (double) total);
  if (total == 0 || total > kLayoutMaxPoints) return out;
  std::vector<double> wrapped;
  if (options.periodic) {
    wrap_into_cell(n, xyz, options.root_center, options.root_half_width, wrapped, options.root_shape,
                   options.periodic_dims);
    xyz = wrapped.data();
  }
  const RootBox root = layout_root(kernel, options, n, xyz, comm);
  // the model's trees over the stand-in points have the evaluation's root
  out.model.fixed_root = true;
  for (int d = 0; d < 3; ++d) out.model.root_center[d] = root.center[d], out.model.root_shape[d] = root.shape[d];
  out.model.root_half_width = root.half_width;

  std::vector<uint64_t> keys;
  morton_keys(root, n, xyz, keys);
  // cells refined (global count above kLayoutCell) at the current level, by level prefix; at[i]:
  // point i's cell among them (-1: its cell is a leaf of the histogram)
  struct Leaf {
    uint64_t prefix;
    int level;
    double count;
  };
  std::vector<Leaf> leaves;
  std::vector<uint64_t> refine;
  std::vector<int> at(n, -1);
  const int max_level = std::max(0, std::min(options.max_depth, kMortonBits));
  if ((double) total > kLayoutCell && max_level > 0) {
    refine.push_back(0);
    std::fill(at.begin(), at.end(), 0);
  } else {
    leaves.push_back(Leaf{0, 0, (double) total});
  }
  for (int level = 0; !refine.empty(); ++level) {
    const int shift = 3 * (kMortonBits - level - 1);
    std::vector<double> counts(8 * refine.size(), 0.0);
    for (std::size_t i = 0; i < n; ++i)
      if (at[i] >= 0) counts[8 * (std::size_t) at[i] + ((keys[i] >> shift) & 7)] += 1;
    comm.allreduce_sum(counts.data(), counts.size());
    std::vector<int> next_index(counts.size(), -1);
    std::vector<uint64_t> next;
    for (std::size_t k = 0; k < counts.size(); ++k) {
      if (counts[k] == 0) continue;
      const uint64_t prefix = 8 * refine[k / 8] + k % 8;
      if (counts[k] > kLayoutCell && level + 1 < max_level) {
        next_index[k] = (int) next.size();
        next.push_back(prefix);
      } else {
        leaves.push_back(Leaf{prefix, level + 1, counts[k]});
      }
    }
    for (std::size_t i = 0; i < n; ++i)
      if (at[i] >= 0) at[i] = next_index[8 * (std::size_t) at[i] + ((keys[i] >> shift) & 7)];
    refine.swap(next);
  }

  // the stand-in points: each histogram cell's count spread uniformly over the cell
  out.xyz.reserve(3 * total);
  uint64_t state = 0x6b69666d6d4c4159ULL;
  double lo[3];
  for (int d = 0; d < 3; ++d) lo[d] = root.center[d] - root.half_width * root.shape[d];
  for (const Leaf &c : leaves) {
    uint32_t a[3];
    morton_decode(c.prefix, a[0], a[1], a[2]);
    double w[3], corner[3];
    for (int d = 0; d < 3; ++d) {
      w[d] = 2.0 * root.half_width * root.shape[d] / (double) (uint64_t(1) << c.level);
      corner[d] = lo[d] + a[d] * w[d];
    }
    // kept 1e-9 of a cell's width off its faces, so that rounding puts no point in a neighbour
    for (long j = 0; j < (long) c.count; ++j)
      for (int d = 0; d < 3; ++d) out.xyz.push_back(corner[d] + (1e-9 + (1 - 2e-9) * unit_random(state)) * w[d]);
  }
  return out;
}

}    // namespace kifmm
