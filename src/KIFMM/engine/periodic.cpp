// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
#include "periodic.h"

#include "ewald_split.h"
#include "surface.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <complex>
#include <map>
#include <mutex>
#include <stdexcept>

namespace kifmm {

using namespace ewald;

// ------------------------------------------------------------------------------ lists

std::size_t PeriodicImageLists::bytes() const
{
  std::size_t b = V_shift.capacity() + pairs.capacity() * sizeof(MutualPair) +
      (color_off.capacity() + self_leaves.capacity()) * sizeof(int);
  for (const TopKernel &t : top_kernels) b += t.hat.capacity() * sizeof(double);
  for (const ImageList *l : {&U, &W, &X})
    b += (l->off.capacity() + l->idx.capacity()) * sizeof(int) + l->shift.capacity();
  return b;
}

void build_periodic_interaction_lists(const Octree &tree, InteractionLists &lists, PeriodicImageLists &images)
{
  images.mutual = false;
  images.pairs.clear();
  images.color_off.clear();
  images.self_leaves.clear();
  build_lists<PeriodicImages>(tree, lists, &images);
}

bool plan_mutual_near(const Octree &tree, InteractionLists &lists, PeriodicImageLists &images,
                      const std::vector<char> *only)
{
  auto marked = [&](int c) { return !only || (*only)[c]; };
  const auto &cells = tree.cells;
  const int n = (int) cells.size();
  std::vector<MutualPair> keep;
  std::vector<int> self;
  std::size_t entries = 0, self_entries = 0;
  auto positive = [](const signed char s[3]) {
    return s[0] > 0 || (s[0] == 0 && (s[1] > 0 || (s[1] == 0 && s[2] > 0)));
  };
  for (int li = 0; li < (int) tree.leaves.size(); ++li) {
    const int b = tree.leaves[li];
    if (cells[b].n_trg() == 0 || !marked(b)) continue;
    if (!only && (cells[b].n_src() != cells[b].n_trg() || cells[b].src_begin != cells[b].trg_begin)) return false;
    self.push_back(b);
    if (!lists.U.off.empty())
      for (const int *a = lists.U.begin(b); a != lists.U.end(b); ++a) {
        if (!marked(*a)) continue;
        ++entries;
        if (*a == b) ++self_entries;
        else if (*a > b) keep.push_back({b, *a, {0, 0, 0}});
      }
    if (!images.U.off.empty())
      for (int e = images.U.begin(b); e < images.U.end(b); ++e) {
        const int a = images.U.idx[e];
        if (!marked(a)) continue;
        ++entries;
        const signed char *s = images.U.shift_of(e);
        if (a > b || (a == b && positive(s))) keep.push_back({b, a, {s[0], s[1], s[2]}});
      }
  }
  // every entry must have its mirror (b <- a, s) <-> (a <- b, -s); the leaf with itself once
  if (self_entries != self.size() || entries != self_entries + 2 * keep.size()) return false;
  if (only && self.empty()) return false;
  // greedy edge coloring in a fixed order (deterministic): lowest color free at both leaves
  color_mutual_pairs(n, keep, images.color_off);
  images.pairs = std::move(keep);
  images.self_leaves = std::move(self);
  images.mutual = true;
  // the U entries between two marked leaves (without `only`: all) now live in the pairs and
  // leave the lists; the others stay for the one-sided passes
  CellList u;
  ImageList iu;
  u.off.assign(n + 1, 0);
  iu.off.assign(n + 1, 0);
  for (int b = 0; b < n; ++b) {
    if (!lists.U.off.empty())
      for (const int *a = lists.U.begin(b); a != lists.U.end(b); ++a)
        if (!(marked(b) && marked(*a))) u.idx.push_back(*a);
    if (!images.U.off.empty())
      for (int e = images.U.begin(b); e < images.U.end(b); ++e)
        if (!(marked(b) && marked(images.U.idx[e]))) {
          iu.idx.push_back(images.U.idx[e]);
          iu.shift.insert(iu.shift.end(), images.U.shift_of(e), images.U.shift_of(e) + 3);
        }
    u.off[b + 1] = (int) u.idx.size();
    iu.off[b + 1] = (int) iu.idx.size();
  }
  lists.U = std::move(u);
  images.U = std::move(iu);
  return true;
}

void wrap_into_cell(std::size_t n, const double *xyz, const double center[3], double h, std::vector<double> &out)
{
  out.resize(3 * n);
  const double L = 2.0 * h;
#pragma omp parallel for schedule(static) if (n > 100000)
  for (std::size_t i = 0; i < n; ++i)
    for (int d = 0; d < 3; ++d) {
      const double lo = center[d] - h;
      double x = xyz[3 * i + d];
      if (x < lo || x >= lo + L) {
        x -= L * std::floor((x - lo) / L);
        if (x >= lo + L) x -= L;    // rounding
        if (x < lo) x = lo;
      }
      out[3 * i + d] = x;
    }
}

// ------------------------------------------------------------------------------ Green's functions

namespace {

// Real-space part at r over images |n|_inf <= nreal; `regular`: the n = 0 term without the
// bare kernel (limit at r = 0); `near_regular`: every |n|_inf <= 1 term without the bare kernel.
void real_sum(const Split &s, const double r[3], bool regular, bool near_regular, double &v, double g[3],
              int N)
{
  v = 0;
  g[0] = g[1] = g[2] = 0;
  for (int nx = -N; nx <= N; ++nx)
    for (int ny = -N; ny <= N; ++ny)
      for (int nz = -N; nz <= N; ++nz) {
        const bool zero = nx == 0 && ny == 0 && nz == 0;
        const bool near = std::abs(nx) <= 1 && std::abs(ny) <= 1 && std::abs(nz) <= 1;
        const bool reg = (zero && regular) || (near && near_regular);
        const double d[3] = {r[0] + kPeriod * nx, r[1] + kPeriod * ny, r[2] + kPeriod * nz};
        const double rr = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
        if (s.direct) {
          if (reg || rr == 0.0) continue;    // direct sum: the near/bare terms are simply left out
          double t, F;
          s.real(rr, false, t, F);
          v += t;
          for (int k = 0; k < 3; ++k) g[k] += F * d[k];
          continue;
        }
        if (rr == 0.0) {
          if (reg) v += s.reg0();
          continue;
        }
        if (!reg && rr > kRealCut) continue;    // erfc(alpha r) and the Yukawa terms < 1e-20
        double t, F;
        s.real(rr, reg, t, F);
        v += t;
        for (int k = 0; k < 3; ++k) g[k] += F * d[k];
      }
}

double recip_sum(const Split &s, const double r[3], double g[3])
{
  g[0] = g[1] = g[2] = 0;
  if (s.direct) return 0.0;
  const int K = s.kmax;
  double v = 0;
  std::vector<std::complex<double>> e[3];
  for (int d = 0; d < 3; ++d) {
    e[d].resize(2 * K + 1);
    for (int m = -K; m <= K; ++m) e[d][m + K] = std::polar(1.0, kPi * m * r[d]);
  }
  for (int mx = -K; mx <= K; ++mx)
    for (int my = -K; my <= K; ++my)
      for (int mz = -K; mz <= K; ++mz) {
        const int m2 = mx * mx + my * my + mz * mz;
        if (m2 > K * K) continue;
        const double w = s.weight(m2);
        if (w == 0.0) continue;
        const std::complex<double> ph = e[0][mx + K] * e[1][my + K] * e[2][mz + K];
        v += w * ph.real();
        g[0] -= w * kPi * mx * ph.imag();
        g[1] -= w * kPi * my * ph.imag();
        g[2] -= w * kPi * mz * ph.imag();
      }
  return v;
}

}    // namespace

void periodic_green_unit(const KernelSpec &k, const double r[3], bool regular, double &value, double grad[3])
{
  const Split s(k);
  double gr[3], gk[3], rf[3];
  // fold into [-1, 1]^3 (the regular form keeps r: its n = 0 term is the one at r)
  for (int d = 0; d < 3; ++d) rf[d] = regular ? r[d] : r[d] - kPeriod * std::nearbyint(r[d] / kPeriod);
  r = rf;
  real_sum(s, r, regular, false, value, gr, regular ? 3 : s.nreal);
  value += recip_sum(s, r, gk) + s.background();
  for (int d = 0; d < 3; ++d) grad[d] = gr[d] + gk[d];
}

namespace {

std::shared_ptr<LatticeTable> compute_table(const KernelSpec &k, int p)
{
  const Split s(k);
  auto t = std::make_shared<LatticeTable>();
  t->p = p;
  t->quad = k.type == KernelType::Laplace ? 2 * kPi / (3 * kVolume) : 0.0;
  const int m = 2 * p - 1;
  t->r.assign((std::size_t) m * m * m, 0.0);
  const double step = p > 1 ? 2.0 * kRadiusInner / (p - 1) : 0.0;
  // R is invariant under the cubic group: compute 0 <= i <= j <= k only
  for (int i = 0; i < p; ++i)
    for (int j = i; j < p; ++j)
      for (int l = j; l < p; ++l) {
        const double r[3] = {i * step, j * step, l * step};
        double v, g[3];
        real_sum(s, r, true, true, v, g, s.nreal);
        if (!s.direct) {
          double gk[3];
          v += recip_sum(s, r, gk) + s.background();
        }
        v -= t->quad * (r[0] * r[0] + r[1] * r[1] + r[2] * r[2]);
        const int a[3] = {i, j, l};
        const int perm[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
        for (auto &pm : perm)
          for (int sx = -1; sx <= 1; sx += 2)
            for (int sy = -1; sy <= 1; sy += 2)
              for (int sz = -1; sz <= 1; sz += 2) {
                const int x = sx * a[pm[0]], y = sy * a[pm[1]], z = sz * a[pm[2]];
                t->r[((std::size_t) (x + p - 1) * m + (y + p - 1)) * m + (z + p - 1)] = v;
              }
      }
  return t;
}

}    // namespace

std::shared_ptr<const LatticeTable> lattice_table(const KernelSpec &k, int p)
{
  static std::mutex mtx;
  static std::map<std::pair<double, int>, std::shared_ptr<const LatticeTable>> cache;
  const double key = k.type == KernelType::Yukawa ? k.kappa : -1.0;
  {
    std::lock_guard<std::mutex> lock(mtx);
    auto it = cache.find({key, p});
    if (it != cache.end()) return it->second;
  }
  auto t = compute_table(k, p);
  std::lock_guard<std::mutex> lock(mtx);
  if (cache.size() > 64) cache.clear();    // yukawa boxes that keep changing size
  cache[{key, p}] = t;
  return t;
}

// ------------------------------------------------------------------------------ reference sum

void periodic_direct_sum(const KernelSpec &kernel, const double center[3], double h, std::size_t n_src,
                         const double *src_xyz, const double *src_q, std::size_t n_trg, const double *trg_xyz,
                         double *pot, double *grad)
{
  KernelSpec uk = kernel;
  if (uk.type == KernelType::Yukawa) uk.kappa = kernel.kappa * h;
  const Split s(uk);
  std::vector<double> su, tu;
  wrap_into_cell(n_src, src_xyz, center, h, su);
  wrap_into_cell(n_trg, trg_xyz, center, h, tu);
  for (std::size_t i = 0; i < n_src; ++i)
    for (int d = 0; d < 3; ++d) su[3 * i + d] = (su[3 * i + d] - center[d]) / h;
  for (std::size_t i = 0; i < n_trg; ++i)
    for (int d = 0; d < 3; ++d) tu[3 * i + d] = (tu[3 * i + d] - center[d]) / h;
  // structure factors S(m) = sum_j q_j exp(i pi m.y_j) over a half space of m (plus m = 0)
  const int K = s.kmax;
  std::vector<std::array<int, 3>> ms;
  std::vector<double> w;
  if (!s.direct)
    for (int mx = 0; mx <= K; ++mx)
      for (int my = -K; my <= K; ++my)
        for (int mz = -K; mz <= K; ++mz) {
          if (mx == 0 && (my < 0 || (my == 0 && mz < 0))) continue;
          const int m2 = mx * mx + my * my + mz * mz;
          if (m2 > K * K) continue;
          const double ww = s.weight(m2);
          if (ww == 0.0) continue;
          ms.push_back({mx, my, mz});
          w.push_back(m2 == 0 ? ww : 2 * ww);    // +-m pairs
        }
  const std::size_t nk = ms.size();
  auto phases = [&](const double *u, std::vector<std::complex<double>> &e) {
    e.resize(3 * (2 * K + 1));
    for (int d = 0; d < 3; ++d)
      for (int m = -K; m <= K; ++m) e[d * (2 * K + 1) + m + K] = std::polar(1.0, kPi * m * u[d]);
  };
  std::vector<std::complex<double>> S(nk, 0.0);
  {
    std::vector<std::complex<double>> e;
    for (std::size_t j = 0; j < n_src; ++j) {
      if (src_q[j] == 0.0) continue;
      phases(&su[3 * j], e);
      for (std::size_t q = 0; q < nk; ++q)
        S[q] += src_q[j] * e[ms[q][0] + K] * e[(2 * K + 1) + ms[q][1] + K] * e[2 * (2 * K + 1) + ms[q][2] + K];
    }
  }
  const double bg = s.background();
  double qtot = 0;
  for (std::size_t j = 0; j < n_src; ++j) qtot += src_q[j];
#pragma omp parallel for schedule(dynamic, 4)
  for (std::size_t i = 0; i < n_trg; ++i) {
    double v = bg * qtot, g[3] = {0, 0, 0};
    for (std::size_t j = 0; j < n_src; ++j) {
      if (src_q[j] == 0.0) continue;
      double r[3], t, gg[3];
      for (int d = 0; d < 3; ++d) {
        r[d] = tu[3 * i + d] - su[3 * j + d];
        r[d] -= kPeriod * std::nearbyint(r[d] / kPeriod);    // [-1, 1]: |n| <= 1 covers r < 3
      }
      const bool same = r[0] == 0.0 && r[1] == 0.0 && r[2] == 0.0;
      real_sum(s, r, same, false, t, gg, s.direct ? 2 : 1);
      v += src_q[j] * t;
      for (int d = 0; d < 3; ++d) g[d] += src_q[j] * gg[d];
    }
    if (nk > 0) {
      std::vector<std::complex<double>> e;
      phases(&tu[3 * i], e);
      for (std::size_t q = 0; q < nk; ++q) {
        const std::complex<double> ph =
            e[ms[q][0] + K] * e[(2 * K + 1) + ms[q][1] + K] * e[2 * (2 * K + 1) + ms[q][2] + K] * std::conj(S[q]);
        v += w[q] * ph.real();
        for (int d = 0; d < 3; ++d) g[d] -= w[q] * kPi * ms[q][d] * ph.imag();
      }
    }
    if (pot) pot[i] = v / h;
    if (grad)
      for (int d = 0; d < 3; ++d) grad[3 * i + d] = g[d] / (h * h);
  }
}

}    // namespace kifmm
