// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// Distributed evaluation (Evaluator::evaluate_distributed over MPI) equals the serial
// evaluation of all points to 1e-10 relative, for uniform, clustered and dipole sets, several
// partitions (slabs with an empty rank, spatial blocks, random, everything on one rank) and top
// tree levels; open and periodic boundaries (Periodic*: the root is the periodic cell, ghosts
// wrap through its faces, the lattice operator acts on the reduced root density). Run under
// mpirun -np 1..4 (ctest label mpi); on one rank it checks the serial communicator path.
#include "fmm_core.h"
#include "kernels.h"
#include "kifmm.h"
#include "mpi_communicator.h"
#include "test_util.h"

#include <gtest/gtest.h>
#include <mpi.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <random>
#include <string>

using namespace kifmm_test;

namespace {

int rank_of_world() { int r; MPI_Comm_rank(MPI_COMM_WORLD, &r); return r; }
int size_of_world() { int s; MPI_Comm_size(MPI_COMM_WORLD, &s); return s; }

// owner rank of every point
using Partition = std::function<std::vector<int>(const Points &, int)>;

std::vector<int> slabs_last_empty(const Points &p, int nranks)
{
  // slabs in x over the first nranks-1 ranks (the last rank holds nothing)
  const int m = std::max(1, nranks - 1);
  double lo = 1e300, hi = -1e300;
  for (std::size_t j = 0; j < p.size(); ++j) {
    lo = std::min(lo, p.xyz[3 * j]);
    hi = std::max(hi, p.xyz[3 * j]);
  }
  std::vector<int> o(p.size());
  for (std::size_t i = 0; i < p.size(); ++i) {
    const int r = (int) ((p.xyz[3 * i] - lo) / (hi - lo + 1e-300) * m);
    o[i] = std::min(std::max(r, 0), m - 1);
  }
  return o;
}

std::vector<int> blocks(const Points &p, int nranks)
{
  // 2x2x1 blocks around the mean, folded onto the ranks
  double c[3] = {0, 0, 0};
  for (std::size_t j = 0; j < p.size(); ++j)
    for (int d = 0; d < 3; ++d) c[d] += p.xyz[3 * j + d] / p.size();
  std::vector<int> o(p.size());
  for (std::size_t i = 0; i < p.size(); ++i) o[i] = ((p.xyz[3 * i] > c[0]) + 2 * (p.xyz[3 * i + 1] > c[1])) % nranks;
  return o;
}

// quadrants at the origin ((x > 0) + 2 (y > 0)), folded onto the ranks: aligned with the cells
// of a root centred at the origin
std::vector<int> quadrants(const Points &p, int nranks)
{
  std::vector<int> o(p.size());
  for (std::size_t i = 0; i < p.size(); ++i) o[i] = ((p.xyz[3 * i] > 0) + 2 * (p.xyz[3 * i + 1] > 0)) % nranks;
  return o;
}

std::vector<int> random_owner(const Points &p, int nranks)
{
  std::vector<int> o(p.size());
  for (std::size_t i = 0; i < p.size(); ++i) o[i] = (int) ((i * 2654435761u) % 7919) % nranks;
  return o;
}

std::vector<int> all_on_last(const Points &p, int nranks) { return std::vector<int>(p.size(), nranks - 1); }

struct Result {
  double grad = 0, pot = 0;    // max abs difference / max abs serial value, over all ranks
  std::size_t ghosts = 0, own = 0, comm_bytes = 0;    // max over ranks
  std::size_t let_cells = 0, let_bytes = 0;           // summed over ranks
  std::size_t mutual_pairs = 0;                        // summed over ranks
};

// periodic_half > 0: periodic boundaries, the cell [-periodic_half, periodic_half]^3 (shape:
// the rectangular cell of half-widths periodic_half * shape[d]); grid > 0: the single-level grid
kifmm::Options test_options(int order, int leaf, int top_level, double periodic_half, int grid,
                            const double *shape = nullptr, int periodic_dims = 3)
{
  kifmm::Options o;
  o.order = order;
  o.leaf_size = leaf;
  o.top_level = top_level;
  if (periodic_half > 0) {
    o.periodic = true;
    o.fixed_root = true;
    o.root_half_width = periodic_half;
    o.periodic_grid = grid;
    if (shape)
      for (int d = 0; d < 3; ++d) o.root_shape[d] = shape[d];
    o.periodic_dims = periodic_dims;
  }
  return o;
}

template <class K>
Result compare(const K &k, const kifmm::KernelSpec &spec, const Points &all, const Partition &part, int top_level,
               int leaf = 24, int order = 6, double periodic_half = 0.0, int grid = 0, const double *shape = nullptr,
               int periodic_dims = 3)
{
  const int me = rank_of_world(), np = size_of_world();
  const kifmm::Options o = test_options(order, leaf, top_level, periodic_half, grid, shape, periodic_dims);
  kifmm::FmmEvaluator<K> serial(k, spec, o), dist(k, spec, o);
  const std::size_t n = all.size();
  std::vector<double> ps(n), gs(3 * n);
  serial.evaluate(n, all.xyz.data(), all.q.data(), n, all.xyz.data(), ps.data(), gs.data());
  Points mine;
  std::vector<std::size_t> idx;
  const std::vector<int> owner = part(all, np);
  for (std::size_t i = 0; i < n; ++i)
    if (owner[i] == me) {
      idx.push_back(i);
      mine.xyz.insert(mine.xyz.end(), &all.xyz[3 * i], &all.xyz[3 * i] + 3);
      mine.q.push_back(all.q[i]);
    }
  std::vector<double> pd(idx.size()), gd(3 * idx.size());
  kifmm::MpiCommunicator comm(MPI_COMM_WORLD);
  dist.evaluate_distributed(comm, idx.size(), mine.xyz.data(), mine.q.data(), pd.data(), gd.data());
  double gmax = 0, pmax = 0, gerr = 0, perr = 0;
  for (std::size_t i = 0; i < n; ++i) {
    pmax = std::max(pmax, std::fabs(ps[i]));
    for (int d = 0; d < 3; ++d) gmax = std::max(gmax, std::fabs(gs[3 * i + d]));
  }
  for (std::size_t k2 = 0; k2 < idx.size(); ++k2) {
    const std::size_t i = idx[k2];
    perr = std::max(perr, std::fabs(pd[k2] - ps[i]));
    for (int d = 0; d < 3; ++d) gerr = std::max(gerr, std::fabs(gd[3 * k2 + d] - gs[3 * i + d]));
  }
  double e[2] = {gerr / gmax, perr / pmax};
  MPI_Allreduce(MPI_IN_PLACE, e, 2, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
  unsigned long long c[3] = {dist.stats().n_ghosts, idx.size(), dist.stats().comm_bytes};
  MPI_Allreduce(MPI_IN_PLACE, c, 3, MPI_UNSIGNED_LONG_LONG, MPI_MAX, MPI_COMM_WORLD);
  unsigned long long l[3] = {dist.stats().let_cells, dist.stats().let_bytes, dist.stats().mutual_pairs};
  MPI_Allreduce(MPI_IN_PLACE, l, 3, MPI_UNSIGNED_LONG_LONG, MPI_SUM, MPI_COMM_WORLD);
  Result r;
  r.let_cells = l[0];
  r.let_bytes = l[1];
  r.mutual_pairs = l[2];
  r.grad = e[0];
  r.pot = e[1];
  r.ghosts = c[0];
  r.own = c[1];
  r.comm_bytes = c[2];
  return r;
}

Points with_zero_charges(Points p)
{
  for (std::size_t i = 0; i < p.size(); i += 7) p.q[i] = 0.0;
  return p;
}

const Partition kPartitions[] = {slabs_last_empty, blocks, random_owner, all_on_last};
const char *kPartitionNames[] = {"slabs (last rank empty)", "blocks", "random", "all on the last rank"};

void check_all_partitions(const Points &p, int top_level, int leaf = 24, double periodic_half = 0.0, int order = 6,
                          int grid = 0, const double *shape = nullptr, int periodic_dims = 3)
{
  kifmm::LaplaceKernel k;
  kifmm::KernelSpec spec;
  for (int j = 0; j < 4; ++j) {
    Result r = compare(k, spec, p, kPartitions[j], top_level, leaf, order, periodic_half, grid, shape, periodic_dims);
    EXPECT_LE(r.grad, 1e-10) << kPartitionNames[j] << ", top level " << top_level << ", grid " << grid;
    EXPECT_LE(r.pot, 1e-10) << kPartitionNames[j] << ", top level " << top_level << ", grid " << grid;
  }
}

Points joined(Points a, const Points &b)
{
  a.xyz.insert(a.xyz.end(), b.xyz.begin(), b.xyz.end());
  a.q.insert(a.q.end(), b.q.begin(), b.q.end());
  return a;
}

// Periodic cell [-1, 1]^3: two dense clusters (sigma 2e-4) centred on the faces x = -1 and
// x = +1 (each straddles the boundary: its halves are neighbours only through the face), a
// sparse uniform halo, and some points given outside the cell (wrapped by the engine).
Points periodic_clusters(std::size_t n, unsigned seed)
{
  Points c = two_clusters(n, seed);
  for (double &x : c.xyz) x *= 0.2;
  Points p = joined(c, uniform_cube(n / 4, seed + 1));
  for (std::size_t i = 0; i < p.size(); i += 11) p.xyz[3 * i + 1] += (i % 2 ? 2.0 : -2.0);
  return p;
}

}    // namespace

TEST(Distributed, UniformEqualsSerial)
{
  Points p = with_zero_charges(uniform_cube(3000, 11));
  for (int top : {0, 2, 3, 4}) check_all_partitions(p, top);
}

TEST(Distributed, PlummerEqualsSerial)
{
  Points p = plummer(3000, 12);
  for (int top : {0, 2, 3}) check_all_partitions(p, top);
}

TEST(Distributed, TwoClustersEqualsSerial)
{
  Points p = two_clusters(2000, 13);
  Points u = uniform_cube(300, 14, 6.0);    // a sparse halo: coarse top leaves next to dense cells
  p.xyz.insert(p.xyz.end(), u.xyz.begin(), u.xyz.end());
  p.q.insert(p.q.end(), u.q.begin(), u.q.end());
  for (int top : {0, 2, 3, 4}) check_all_partitions(p, top);
}

TEST(Distributed, DipolesEqualsSerial)
{
  Points p = dipoles(1200, 15);
  for (int top : {0, 2, 3}) check_all_partitions(p, top);
}

TEST(Distributed, FewPointsAndDefaultTopLevel)
{
  // fewer points than a leaf (the root is a leaf), and a handful (top leaves at levels 0..2)
  for (std::size_t n : {5, 40, 200}) check_all_partitions(uniform_cube(n, 16), 0);
}

// Adaptive top tree (top level 0): a dense cluster refines the top tree far below its uniform
// level, small leaves make deep local subtrees below open frontier cells.
TEST(Distributed, AdaptiveTopTreeEqualsSerial)
{
  Points p = plummer(4000, 21);
  for (std::size_t i = 0; i < p.size(); ++i) p.q[i] = (i % 2 ? 1.0 : -0.5) / p.size();
  check_all_partitions(p, 0, 8);
  Points c = two_clusters(3000, 22);
  Points u = uniform_cube(1000, 23, 8.0);
  c.xyz.insert(c.xyz.end(), u.xyz.begin(), u.xyz.end());
  c.q.insert(c.q.end(), u.q.begin(), u.q.end());
  check_all_partitions(c, 0, 16);
}

// Yukawa (kappa 2): every partition, top level 0 or 3
void check_yukawa(const Points &p, double periodic_half, int grid = 0)
{
  kifmm::KernelSpec spec;
  spec.type = kifmm::KernelType::Yukawa;
  spec.kappa = 2.0;
  kifmm::YukawaKernel k{2.0};
  for (int j = 0; j < 4; ++j) {
    Result r = compare(k, spec, p, kPartitions[j], j % 2 ? 3 : 0, 24, 6, periodic_half, grid);
    EXPECT_LE(r.grad, 1e-10) << kPartitionNames[j] << ", grid " << grid;
    EXPECT_LE(r.pot, 1e-10) << kPartitionNames[j] << ", grid " << grid;
  }
}

TEST(Distributed, YukawaEqualsSerial)
{
  Points p = two_clusters(1500, 17);
  Points u = uniform_cube(1500, 18, 5.0);
  p.xyz.insert(p.xyz.end(), u.xyz.begin(), u.xyz.end());
  p.q.insert(p.q.end(), u.q.begin(), u.q.end());
  check_yukawa(p, 0.0);
}

// No all-gather: with spatial slabs, a rank receives only the points of the frontier cells near
// its slab, not the other ranks' points (periodic: through the cell's faces too).
void check_ghosts_are_local(const Points &p, double periodic_half)
{
  const int np = size_of_world();
  kifmm::LaplaceKernel k;
  kifmm::KernelSpec spec;
  Result r = compare(k, spec, p, slabs_last_empty, 4, 32, 6, periodic_half);
  EXPECT_LE(r.grad, 1e-10);
  EXPECT_LE(r.pot, 1e-10);
  const double n = (double) p.size(), others = n - n / (np - 1);
  EXPECT_LT((double) r.ghosts, 0.75 * others) << "ghosts " << r.ghosts << " of " << others;
  if (rank_of_world() == 0)
    printf("  %s, max over ranks: own points %zu, ghost points %zu (others' points %.0f), bytes sent %zu\n",
           periodic_half > 0 ? "periodic" : "open", r.own, r.ghosts, others, r.comm_bytes);
  EXPECT_GT(r.comm_bytes, 0u);
}

// Pairs of adjacent leaves that hold only own points are evaluated once for both sides (the
// equality with serial is checked by every test above; here that such pairs exist, open and
// periodic, and that a partition where every leaf mixes ranks has none and still equals serial)
TEST(Distributed, OwnLeafPairsAreMutual)
{
  kifmm::LaplaceKernel k;
  kifmm::KernelSpec spec;
  Points p = uniform_cube(8000, 29);
  Result r = compare(k, spec, p, blocks, 0, 32);
  EXPECT_LE(r.grad, 1e-10);
  EXPECT_LE(r.pot, 1e-10);
  EXPECT_GT(r.mutual_pairs, 0u);
  if (size_of_world() > 1) {
    Result m = compare(k, spec, p, random_owner, 0, 32);
    EXPECT_LE(m.grad, 1e-10);
    EXPECT_LE(m.pot, 1e-10);
    EXPECT_EQ(m.mutual_pairs, 0u);
  }
  // periodic: image pairs of own leaves too
  Points pn = neutral(p);
  Result pr = compare(k, spec, pn, blocks, 0, 32, 6, 1.0);
  EXPECT_LE(pr.grad, 1e-10);
  EXPECT_LE(pr.pot, 1e-10);
  EXPECT_GT(pr.mutual_pairs, 0u);
}

TEST(Distributed, GhostsAreLocal)
{
  if (size_of_world() < 3) GTEST_SKIP() << "needs 3 or more ranks";
  check_ghosts_are_local(uniform_cube(8000, 19), 0.0);
}

// Locally essential trees: below an open frontier cell that a rank holds no points of, it
// receives only the part of the subtree its lists reach (cells with densities, the points of the
// leaves next to its cells), not all points of the cell. Top level 2 (frontier cells of a
// quarter of the root), ranks in quadrants aligned with them (no frontier cell is shared):
// equal to serial, LET cells sent, and the ghost points about the layer of leaves next to the
// rank's cells instead of the whole neighbouring frontier cells (rule i).
void check_let(Points p, double periodic_half)
{
  const int me = rank_of_world(), np = size_of_world();
  if (periodic_half == 0) {    // the root [-1, 1]^3 (to 1e-8): cells aligned with the quadrants
    const double corners[6] = {-1, -1, -1, 1, 1, 1};
    p.xyz.insert(p.xyz.end(), corners, corners + 6);
    p.q.insert(p.q.end(), {1.0, -1.0});
  }
  kifmm::LaplaceKernel k;
  kifmm::KernelSpec spec;
  Result r = compare(k, spec, p, quadrants, 2, 64, 6, periodic_half);
  EXPECT_LE(r.grad, 1e-10);
  EXPECT_LE(r.pot, 1e-10);
  EXPECT_GT(r.let_cells, 0u);
  // points of other ranks in the level-2 cells touching this rank's level-2 cells
  kifmm::RootBox root;
  if (periodic_half > 0) root.half_width = periodic_half;
  else root = kifmm::bounding_cube(p.size(), p.xyz.data(), 0, nullptr);
  const std::vector<int> owner = quadrants(p, np);
  auto cell_of = [&](std::size_t i, int d) {
    const double u = (p.xyz[3 * i + d] - root.center[d] + root.half_width) / (2 * root.half_width);
    return std::min(3, std::max(0, (int) std::floor(4 * u)));
  };
  std::vector<char> own(64, 0);
  for (std::size_t i = 0; i < p.size(); ++i)
    if (owner[i] == me) own[cell_of(i, 0) + 4 * cell_of(i, 1) + 16 * cell_of(i, 2)] = 1;
  auto near_own = [&](int cx, int cy, int cz) {
    for (int dx = -1; dx <= 1; ++dx)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dz = -1; dz <= 1; ++dz) {
          int x = cx + dx, y = cy + dy, z = cz + dz;
          if (periodic_half > 0) {
            x = (x + 4) % 4;
            y = (y + 4) % 4;
            z = (z + 4) % 4;
          } else if (x < 0 || y < 0 || z < 0 || x > 3 || y > 3 || z > 3)
            continue;
          if (own[x + 4 * y + 16 * z]) return true;
        }
    return false;
  };
  unsigned long long whole = 0;
  for (std::size_t i = 0; i < p.size(); ++i) {
    const int cx = cell_of(i, 0), cy = cell_of(i, 1), cz = cell_of(i, 2);
    if (owner[i] != me && !own[cx + 4 * cy + 16 * cz] && near_own(cx, cy, cz)) ++whole;
  }
  MPI_Allreduce(MPI_IN_PLACE, &whole, 1, MPI_UNSIGNED_LONG_LONG, MPI_MAX, MPI_COMM_WORLD);
  if (me == 0)
    printf("  %s: max over ranks: own %zu, ghosts %zu, whole neighbouring frontier cells %llu; LET cells %zu, "
           "LET bytes %zu (all ranks)\n",
           periodic_half > 0 ? "periodic" : "open", r.own, r.ghosts, whole, r.let_cells, r.let_bytes);
  // leaves here are an eighth of the root (a frontier cell is two leaves wide): about half
  EXPECT_LT((double) r.ghosts, 0.6 * (double) whole);
}

// The LET's choice of points (U, X, W lists of the asking rank) with leaves that are sent as
// densities (at order 6 with leaves of 24 most LET cells are small enough to be sent as points,
// which hides a missing point rule): order 4, leaves of up to 48 points, clustered sets
TEST(Distributed, LetWithLargeLeavesEqualsSerial)
{
  for (int top : {0, 2, 3}) check_all_partitions(plummer(3000, 12), top, 24, 0.0, 4);
  for (int top : {0, 2}) check_all_partitions(neutral(periodic_clusters(2400, 28)), top, 48, 1.0, 4);
}

TEST(Distributed, LocallyEssentialTreesBelowCoarseFrontierCells)
{
  if (size_of_world() < 2) GTEST_SKIP() << "needs 2 or more ranks";
  check_let(uniform_cube(30000, 24), 0.0);
}

// ---------------------------------------------------------------- periodic boundaries

TEST(Distributed, PeriodicUniformEqualsSerial)
{
  Points p = with_zero_charges(neutral(uniform_cube(3000, 31)));
  for (int top : {0, 2, 3, 4}) check_all_partitions(p, top, 24, 1.0);
}

TEST(Distributed, PeriodicClustersEqualSerial)
{
  Points p = neutral(periodic_clusters(2400, 32));
  for (int top : {0, 2, 3}) check_all_partitions(p, top, 24, 1.0);
  check_all_partitions(p, 0, 8, 1.0);    // small leaves: deep local subtrees at the faces
}

// net charge: the uniform background term, whose moments are summed over ranks
TEST(Distributed, PeriodicNetChargeAndDipolesEqualSerial)
{
  Points p = uniform_cube(2000, 33);
  for (double &q : p.q) q = std::fabs(q);
  for (int top : {0, 3}) check_all_partitions(p, top, 24, 1.0);
  for (int top : {0, 2}) check_all_partitions(dipoles(1000, 34), top, 24, 1.0);
}

// The periodic single-level grid (Options::periodic_grid): ghosts of the neighbour cells, the
// cells' densities, background moments and wrap marginals summed over ranks
TEST(Distributed, PeriodicGridEqualsSerial)
{
  const Points u = with_zero_charges(neutral(uniform_cube(3000, 31)));
  for (int k : {3, 5}) check_all_partitions(u, 0, 24, 1.0, 6, k);
  check_all_partitions(neutral(periodic_clusters(2400, 32)), 0, 24, 1.0, 6, 6);
  Points nc = uniform_cube(2000, 33);
  for (double &q : nc.q) q = std::fabs(q);
  check_all_partitions(nc, 0, 24, 1.0, 8, 4);
  for (std::size_t n : {5, 40}) check_all_partitions(neutral(uniform_cube(n, 35)), 0, 24, 1.0, 6, 3);
}

// Rectangular periodic cells: the octree in a nearly cubic one, the single-level grid in
// elongated ones (cells per axis in proportion to the edges; nearly cubic or stretched)
TEST(Distributed, PeriodicRectangularCellsEqualSerial)
{
  auto in_box = [](Points p, const double shape[3]) {
    for (std::size_t i = 0; i < p.size(); ++i)
      for (int d = 0; d < 3; ++d) p.xyz[3 * i + d] *= shape[d];
    return p;
  };
  const double near[3] = {1.0, 0.97, 0.96}, needle[3] = {1.0, 0.5, 0.5}, slab[3] = {0.6, 0.8, 1.0};
  check_all_partitions(in_box(neutral(uniform_cube(2000, 37)), near), 0, 24, 1.0, 6, 0, near);
  check_all_partitions(in_box(neutral(periodic_clusters(2000, 38)), near), 2, 24, 1.0, 6, 0, near);
  check_all_partitions(in_box(neutral(uniform_cube(2000, 39)), needle), 0, 24, 1.0, 6, 6, needle);
  Points nc = in_box(uniform_cube(2000, 40), slab);
  for (double &q : nc.q) q = std::fabs(q);    // net charge: background moments and wrap marginals
  check_all_partitions(nc, 0, 24, 1.0, 6, 10, slab);
  // stretched cells (12 x 12 x 2 of 1 x 1 x 0.75): ghosts from 2 cells along z
  const double flat[3] = {1.0, 1.0, 0.125};
  check_all_partitions(in_box(neutral(uniform_cube(2000, 43)), flat), 0, 24, 1.0, 6, 12, flat);
}

// A slab (periodic in x and y, open in z): no ghosts across the z faces
TEST(Distributed, SlabEqualsSerial)
{
  const double slab[3] = {1.0, 1.0, 0.5}, tall[3] = {0.5, 0.5, 1.0};
  auto in_box = [](Points p, const double shape[3]) {
    for (std::size_t i = 0; i < p.size(); ++i)
      for (int d = 0; d < 3; ++d) p.xyz[3 * i + d] *= shape[d];
    return p;
  };
  check_all_partitions(in_box(neutral(uniform_cube(1500, 41)), slab), 0, 24, 1.0, 6, 6, slab, 2);
  Points nc = in_box(uniform_cube(1500, 42), tall);
  for (double &q : nc.q) q = std::fabs(q);    // net charge
  check_all_partitions(nc, 0, 24, 1.0, 6, 6, tall, 2);
  const double flat[3] = {1.0, 1.0, 0.125};    // stretched cells, 12 x 12 x 2: 5 z layers
  check_all_partitions(in_box(neutral(uniform_cube(1500, 44)), flat), 0, 24, 1.0, 6, 12, flat, 2);
}

TEST(Distributed, PeriodicFewPointsEqualSerial)
{
  for (std::size_t n : {5, 40, 200}) check_all_partitions(neutral(uniform_cube(n, 35)), 0, 24, 1.0);
}

TEST(Distributed, PeriodicYukawaEqualsSerial)
{
  check_yukawa(periodic_clusters(2400, 36), 1.0);
  check_yukawa(periodic_clusters(2400, 36), 1.0, 5);    // the single-level grid
}

TEST(Distributed, PeriodicLocallyEssentialTrees)
{
  if (size_of_world() < 2) GTEST_SKIP() << "needs 2 or more ranks";
  check_let(neutral(uniform_cube(30000, 38)), 1.0);
}

TEST(Distributed, PeriodicGhostsAreLocal)
{
  if (size_of_world() < 3) GTEST_SKIP() << "needs 3 or more ranks";
  check_ghosts_are_local(neutral(uniform_cube(8000, 37)), 1.0);
}

int main(int argc, char **argv)
{
  MPI_Init(&argc, &argv);
  ::testing::InitGoogleTest(&argc, argv);
  if (rank_of_world() != 0) {
    auto &listeners = ::testing::UnitTest::GetInstance()->listeners();
    delete listeners.Release(listeners.default_result_printer());
  }
  int rc = RUN_ALL_TESTS();
  int worst = 0;
  MPI_Allreduce(&rc, &worst, 1, MPI_INT, MPI_MAX, MPI_COMM_WORLD);
  MPI_Finalize();
  return worst;
}

// The diagnostics over the ranks (kifmm.h): exact_gradient of all ranks' sources at each
// rank's targets, and point_virial, equal the serial results on the union of the points.
TEST(Distributed, DiagnosticsEqualSerial)
{
  const int me = rank_of_world(), np = size_of_world();
  const Points all = kifmm_test::uniform_cube(900, 21);
  const std::vector<int> owner = random_owner(all, np);
  Points mine;
  std::vector<std::size_t> idx;
  for (std::size_t i = 0; i < all.size(); ++i)
    if (owner[i] == me) {
      idx.push_back(i);
      mine.xyz.insert(mine.xyz.end(), &all.xyz[3 * i], &all.xyz[3 * i] + 3);
      mine.q.push_back(all.q[i]);
    }
  kifmm::Options opt;
  opt.order = 6;
  opt.leaf_size = 32;
  auto ev = kifmm::make_evaluator(kifmm::KernelSpec{}, opt);
  kifmm::MpiCommunicator comm(MPI_COMM_WORLD);
  const std::size_t n = all.size(), m = idx.size();

  std::vector<double> ref(3 * n, 0.0), g(3 * m, 0.0);
  kifmm::direct_sum(kifmm::KernelSpec{}, n, all.xyz.data(), all.q.data(), n, all.xyz.data(), nullptr, ref.data());
  kifmm::exact_gradient(*ev, &comm, m, mine.xyz.data(), mine.q.data(), m, mine.xyz.data(), g.data());
  double e[2] = {0, 0};
  for (std::size_t k = 0; k < m; ++k)
    for (int d = 0; d < 3; ++d)
      e[0] = std::max(e[0], std::fabs(g[3 * k + d] - ref[3 * idx[k] + d]) / (std::fabs(ref[3 * idx[k] + d]) + 1e-3));

  // virial: serial on the union, distributed on each rank's points (gradients of the serial run)
  std::vector<double> gs(3 * n, 0.0), ws(6 * n), wd(6 * m), gm(3 * m);
  ev->evaluate(n, all.xyz.data(), all.q.data(), n, all.xyz.data(), nullptr, gs.data());
  double cs[3], cd[3];
  kifmm::point_virial(*ev, nullptr, n, all.xyz.data(), all.q.data(), gs.data(), 1.0, ws.data(), cs);
  for (std::size_t k = 0; k < m; ++k)
    for (int d = 0; d < 3; ++d) gm[3 * k + d] = gs[3 * idx[k] + d];
  auto evd = kifmm::make_evaluator(kifmm::KernelSpec{}, opt);
  kifmm::point_virial(*evd, &comm, m, mine.xyz.data(), mine.q.data(), gm.data(), 1.0, wd.data(), cd);
  double wmax = 0;
  for (double v : ws) wmax = std::max(wmax, std::fabs(v));
  for (std::size_t k = 0; k < m; ++k)
    for (int c = 0; c < 6; ++c) e[1] = std::max(e[1], std::fabs(wd[6 * k + c] - ws[6 * idx[k] + c]) / wmax);
  for (int d = 0; d < 3; ++d) EXPECT_EQ(cs[d], cd[d]);
  MPI_Allreduce(MPI_IN_PLACE, e, 2, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
  EXPECT_LT(e[0], 1e-11);
  EXPECT_LT(e[1], 1e-10);
}

// ---- point dipoles (evaluate_dipoles_distributed)

namespace {

// moments of about a third of the points (some of them without a charge), the rest charges only
std::vector<double> some_moments(Points &p, unsigned seed)
{
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<double> mu(3 * p.size(), 0.0);
  const double scale = 1.0 / std::cbrt((double) p.size());    // about a charge's field at the spacing
  for (std::size_t i = 0; i < p.size(); ++i) {
    if (i % 3 == 0)
      for (int d = 0; d < 3; ++d) mu[3 * i + d] = scale * u(rng);
    if (i % 6 == 0) p.q[i] = 0.0;    // a dipole without a charge
    if (i % 17 == 5) p.q[i] = 0.0;   // a point of neither (a target only)
  }
  return mu;
}

// the input indices of the points rank `me` owns, and rows (width values per point) of an array
std::vector<std::size_t> own_indices(const std::vector<int> &owner, int me)
{
  std::vector<std::size_t> idx;
  for (std::size_t i = 0; i < owner.size(); ++i)
    if (owner[i] == me) idx.push_back(i);
  return idx;
}
std::vector<double> rows(const std::vector<double> &v, std::size_t width, const std::vector<std::size_t> &idx)
{
  std::vector<double> out;
  for (std::size_t i : idx) out.insert(out.end(), v.begin() + width * i, v.begin() + width * (i + 1));
  return out;
}

struct DipoleResult {
  double pot = 0, grad = 0, hess = 0;    // max abs difference / max abs serial value, all ranks
};

// the distributed pot, grad and hess of charges and dipoles (q_null: no charges) against the
// serial evaluate_dipoles of all points with the same options
template <class K>
DipoleResult compare_dipoles(const K &k, const kifmm::KernelSpec &spec, const Points &all,
                             const std::vector<double> &mu, const Partition &part, int top_level, int leaf,
                             double periodic_half, int grid, bool q_null = false)
{
  const int me = rank_of_world(), np = size_of_world();
  const kifmm::Options o = test_options(6, leaf, top_level, periodic_half, grid);
  kifmm::FmmEvaluator<K> serial(k, spec, o), dist(k, spec, o);
  const std::size_t n = all.size();
  const double *q = q_null ? nullptr : all.q.data();
  std::vector<double> ps(n), gs(3 * n), hs(6 * n);
  serial.evaluate_dipoles(n, all.xyz.data(), q, mu.data(), n, all.xyz.data(), ps.data(), gs.data(), hs.data());
  const std::vector<std::size_t> idx = own_indices(part(all, np), me);
  const std::vector<double> xyz = rows(all.xyz, 3, idx), qm = rows(all.q, 1, idx), mm = rows(mu, 3, idx);
  const std::size_t m = idx.size();
  std::vector<double> pd(m), gd(3 * m), hd(6 * m);
  kifmm::MpiCommunicator comm(MPI_COMM_WORLD);
  dist.evaluate_dipoles_distributed(comm, m, xyz.data(), q_null ? nullptr : qm.data(), mm.data(), pd.data(),
                                    gd.data(), hd.data());
  double err[3] = {0, 0, 0}, big[3] = {0, 0, 0};
  for (std::size_t i = 0; i < n; ++i) {
    big[0] = std::max(big[0], std::fabs(ps[i]));
    for (int d = 0; d < 3; ++d) big[1] = std::max(big[1], std::fabs(gs[3 * i + d]));
    for (int c = 0; c < 6; ++c) big[2] = std::max(big[2], std::fabs(hs[6 * i + c]));
  }
  for (std::size_t j = 0; j < m; ++j) {
    const std::size_t i = idx[j];
    err[0] = std::max(err[0], std::fabs(pd[j] - ps[i]));
    for (int d = 0; d < 3; ++d) err[1] = std::max(err[1], std::fabs(gd[3 * j + d] - gs[3 * i + d]));
    for (int c = 0; c < 6; ++c) err[2] = std::max(err[2], std::fabs(hd[6 * j + c] - hs[6 * i + c]));
  }
  MPI_Allreduce(MPI_IN_PLACE, err, 3, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
  EXPECT_GT(big[2], 0.0);
  return {err[0] / big[0], err[1] / big[1], err[2] / big[2]};
}

void check_dipoles_all_partitions(const Points &p, const std::vector<double> &mu, int top_level, int leaf,
                                  double periodic_half = 0.0, int grid = 0, bool q_null = false)
{
  kifmm::LaplaceKernel k;
  kifmm::KernelSpec spec;
  for (int j = 0; j < 4; ++j) {
    const DipoleResult r = compare_dipoles(k, spec, p, mu, kPartitions[j], top_level, leaf, periodic_half, grid, q_null);
    const std::string what = std::string(kPartitionNames[j]) + ", top level " + std::to_string(top_level) + ", leaf " +
        std::to_string(leaf) + ", grid " + std::to_string(grid) + (q_null ? ", no charges" : "");
    EXPECT_LE(r.pot, 1e-10) << what;
    EXPECT_LE(r.grad, 1e-10) << what;
    EXPECT_LE(r.hess, 1e-10) << what;
  }
}

}    // namespace

// Charges and point dipoles, open boundaries: the moments travel with the ghost and LET points
// (small leaves: locally essential trees below open frontier cells); without charges too
TEST(Distributed, PointDipolesEqualSerial)
{
  Points p = plummer(1500, 51);
  const std::vector<double> mu = some_moments(p, 52);
  for (int top : {0, 3}) check_dipoles_all_partitions(p, mu, top, 24);
  check_dipoles_all_partitions(p, mu, 0, 6);
  check_dipoles_all_partitions(p, mu, 0, 24, 0.0, 0, true);
}

// The same periodic (Laplace, tin-foil): the octree of the cell and the single-level grid (the
// dipoles' part of the background moments and of the wrap correction summed over ranks)
TEST(Distributed, PeriodicPointDipolesEqualSerial)
{
  Points p = uniform_cube(1200, 53);
  const std::vector<double> mu = some_moments(p, 54);
  check_dipoles_all_partitions(p, mu, 0, 24, 1.0);
  check_dipoles_all_partitions(p, mu, 0, 24, 1.0, 4);
  check_dipoles_all_partitions(p, mu, 0, 24, 1.0, 3, true);
}

// Yukawa dipoles, open boundaries
TEST(Distributed, YukawaPointDipolesEqualSerial)
{
  Points p = two_clusters(1000, 55);
  const std::vector<double> mu = some_moments(p, 56);
  kifmm::KernelSpec spec;
  spec.type = kifmm::KernelType::Yukawa;
  spec.kappa = 2.0;
  kifmm::YukawaKernel k{2.0};
  for (int j = 0; j < 4; ++j) {
    const DipoleResult r = compare_dipoles(k, spec, p, mu, kPartitions[j], j % 2 ? 3 : 0, 24, 0.0, 0);
    EXPECT_LE(r.pot, 1e-10) << kPartitionNames[j];
    EXPECT_LE(r.grad, 1e-10) << kPartitionNames[j];
    EXPECT_LE(r.hess, 1e-10) << kPartitionNames[j];
  }
}

// The per-point virial of charges and dipoles on several ranks (each rank its own points as
// sources and targets) equals the one-process virial of all points: open boundaries
// (dipole_point_virial) and the periodic grid (periodic_dipole_point_virial: the offset field's
// cell moments summed over ranks)
TEST(Distributed, DipoleVirialEqualsSerial)
{
  const int me = rank_of_world(), np = size_of_world();
  for (bool periodic : {false, true}) {
    Points all = uniform_cube(1200, 57);
    const std::vector<double> mu = some_moments(all, 58);
    const kifmm::Options o = test_options(6, 24, 0, periodic ? 1.0 : 0.0, 4);
    const std::size_t n = all.size();
    const double center[3] = {0.0, 0.0, 0.0};
    auto serial = kifmm::make_evaluator(kifmm::KernelSpec{}, o), dist = kifmm::make_evaluator(kifmm::KernelSpec{}, o);
    std::vector<double> gs(3 * n), hs(6 * n), ws(6 * n);
    serial->evaluate_dipoles(n, all.xyz.data(), all.q.data(), mu.data(), n, all.xyz.data(), nullptr, gs.data(),
                             hs.data());
    if (periodic)
      kifmm::periodic_dipole_point_virial(*serial, n, all.xyz.data(), all.q.data(), mu.data(), n, all.xyz.data(),
                                          all.q.data(), mu.data(), gs.data(), hs.data(), 1.0, ws.data());
    else
      kifmm::dipole_point_virial(*serial, n, all.xyz.data(), all.q.data(), mu.data(), n, all.xyz.data(), all.q.data(),
                                 mu.data(), gs.data(), hs.data(), 1.0, ws.data(), center);
    const std::vector<std::size_t> idx = own_indices(random_owner(all, np), me);
    const std::vector<double> xyz = rows(all.xyz, 3, idx), q = rows(all.q, 1, idx), m = rows(mu, 3, idx),
                              g = rows(gs, 3, idx), h = rows(hs, 6, idx);
    const std::size_t k = idx.size();
    std::vector<double> wd(6 * k);
    kifmm::MpiCommunicator comm(MPI_COMM_WORLD);
    if (periodic)
      kifmm::periodic_dipole_point_virial(*dist, comm, k, xyz.data(), q.data(), m.data(), g.data(), h.data(), 1.0,
                                          wd.data());
    else
      kifmm::dipole_point_virial(*dist, comm, k, xyz.data(), q.data(), m.data(), g.data(), h.data(), 1.0, wd.data(),
                                 center);
    double wmax = 0, err = 0;
    for (double v : ws) wmax = std::max(wmax, std::fabs(v));
    for (std::size_t j = 0; j < k; ++j)
      for (int c = 0; c < 6; ++c) err = std::max(err, std::fabs(wd[6 * j + c] - ws[6 * idx[j] + c]));
    MPI_Allreduce(MPI_IN_PLACE, &err, 1, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
    EXPECT_GT(wmax, 0.0);
    EXPECT_LE(err / wmax, 1e-10) << (periodic ? "periodic grid" : "open");
  }
}

// The stand-in of all ranks' points for the tree choice (gather_layout): on every rank, for
// every partition, the same points as the serial layout of all points (the histogram's counts
// are summed exactly, the stand-in drawn from the same sequence); open and periodic, clustered.
TEST(Distributed, PointLayoutIsTheSerialOneOnEveryRank)
{
  const int me = rank_of_world(), np = size_of_world();
  kifmm::SerialCommunicator serial;
  kifmm::MpiCommunicator comm(MPI_COMM_WORLD);
  const Points sets[2] = {plummer(6000, 41), periodic_clusters(4000, 42)};
  for (int s = 0; s < 2; ++s) {
    const Points &all = sets[s];
    const kifmm::Options o = test_options(6, 0, 0, s == 1 ? 1.0 : 0.0, 0);
    const kifmm::PointLayout whole = kifmm::gather_layout(kifmm::KernelSpec{}, o, all.size(), all.xyz.data(), serial);
    ASSERT_EQ(whole.xyz.size(), 3 * all.size());
    for (int j = 0; j < 4; ++j) {
      const std::vector<int> owner = kPartitions[j](all, np);
      std::vector<double> mine;
      for (std::size_t i = 0; i < all.size(); ++i)
        if (owner[i] == me) mine.insert(mine.end(), &all.xyz[3 * i], &all.xyz[3 * i] + 3);
      const kifmm::PointLayout layout =
          kifmm::gather_layout(kifmm::KernelSpec{}, o, mine.size() / 3, mine.data(), comm);
      int same = layout.n == all.size() && layout.xyz == whole.xyz;
      for (int d = 0; d < 3; ++d) same = same && layout.model.root_center[d] == whole.model.root_center[d];
      same = same && layout.model.root_half_width == whole.model.root_half_width;
      MPI_Allreduce(MPI_IN_PLACE, &same, 1, MPI_INT, MPI_MIN, MPI_COMM_WORLD);
      EXPECT_EQ(same, 1) << (s == 1 ? "periodic clusters, " : "open plummer, ") << kPartitionNames[j];
    }
  }
}
