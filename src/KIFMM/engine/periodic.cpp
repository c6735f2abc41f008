// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
#include "periodic.h"

#include "ewald_split.h"
#include "p2p_dipole.h"
#include "surface.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <complex>
#include <map>
#include <mutex>
#include <stdexcept>
#include <tuple>

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

void wrap_into_cell(std::size_t n, const double *xyz, const double center[3], double h, std::vector<double> &out,
                    const double *shape, int dims)
{
  out.resize(3 * n);
  double L[3], lo[3];
  for (int d = 0; d < 3; ++d) {
    L[d] = 2.0 * h * (shape ? shape[d] : 1.0);
    lo[d] = center[d] - 0.5 * L[d];
  }
#pragma omp parallel for schedule(static) if (n > 100000)
  for (std::size_t i = 0; i < n; ++i)
    for (int d = 0; d < 3; ++d) {
      double x = xyz[3 * i + d];
      if (d < dims && (x < lo[d] || x >= lo[d] + L[d])) {
        x -= L[d] * std::floor((x - lo[d]) / L[d]);
        if (x >= lo[d] + L[d]) x -= L[d];    // rounding
        if (x < lo[d]) x = lo[d];
      }
      out[3 * i + d] = x;
    }
}

// ------------------------------------------------------------------------------ Green's functions

namespace {

// Real-space part at r over the images reaching real_cut() (at least the first shell); `regular`:
// the n = 0 term without the bare kernel (limit at r = 0); `near_regular`: every |n|_inf <= 1
// term without the bare kernel.
void real_sum(const Split &s, const double r[3], bool regular, bool near_regular, double &v, double g[3])
{
  v = 0;
  g[0] = g[1] = g[2] = 0;
  const int N[3] = {s.images(0, std::fabs(r[0])), s.images(1, std::fabs(r[1])), s.images(2, std::fabs(r[2]))};
  const double cut = s.real_cut();
  for (int nx = -N[0]; nx <= N[0]; ++nx)
    for (int ny = -N[1]; ny <= N[1]; ++ny)
      for (int nz = -N[2]; nz <= N[2]; ++nz) {
        const bool zero = nx == 0 && ny == 0 && nz == 0;
        const bool near = std::abs(nx) <= 1 && std::abs(ny) <= 1 && std::abs(nz) <= 1;
        const bool reg = (zero && regular) || (near && near_regular);
        const double d[3] = {r[0] + s.period[0] * nx, r[1] + s.period[1] * ny, r[2] + s.period[2] * nz};
        const double rr = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
        if (s.direct) {
          if (reg || rr == 0.0 || rr > cut) continue;    // direct sum: the near/bare terms are left out
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
        if (!reg && rr > cut) continue;    // erfc(alpha r) and the Yukawa terms < 1e-20
        double t, F;
        s.real(rr, reg, t, F);
        v += t;
        for (int k = 0; k < 3; ++k) g[k] += F * d[k];
      }
}

// reciprocal vectors m (k_d = pi m_d / shape_d) of a half space (plus m = 0) with weights
// (doubled for the +-m pairs), and the phase tables' extent K_d per axis
struct Reciprocal {
  std::vector<std::array<int, 3>> m;
  std::vector<double> w;
  int K[3] = {0, 0, 0};
  explicit Reciprocal(const Split &s)
  {
    if (s.direct) return;
    for (int d = 0; d < 3; ++d) K[d] = s.kmax_axis(d);
    for (int mx = 0; mx <= K[0]; ++mx)
      for (int my = -K[1]; my <= K[1]; ++my)
        for (int mz = -K[2]; mz <= K[2]; ++mz) {
          if (mx == 0 && (my < 0 || (my == 0 && mz < 0))) continue;
          const int v[3] = {mx, my, mz};
          if (!s.k_inside(v)) continue;
          const double ww = s.weight_k2(s.k2_of(v));
          if (ww == 0.0) continue;
          m.push_back({mx, my, mz});
          w.push_back(mx == 0 && my == 0 && mz == 0 ? ww : 2 * ww);
        }
  }
  // e[d][m + K_d] = exp(i pi m u_d / shape_d)
  void phases(const Split &s, const double *u, std::vector<std::complex<double>> e[3]) const
  {
    for (int d = 0; d < 3; ++d) {
      e[d].resize(2 * K[d] + 1);
      for (int q = -K[d]; q <= K[d]; ++q) e[d][q + K[d]] = std::polar(1.0, kPi * q * u[d] / s.shape[d]);
    }
  }
  std::complex<double> phase(const std::vector<std::complex<double>> e[3], std::size_t q) const
  {
    return e[0][m[q][0] + K[0]] * e[1][m[q][1] + K[1]] * e[2][m[q][2] + K[2]];
  }
};

double recip_sum(const Split &s, const Reciprocal &rc, const double r[3], double g[3])
{
  g[0] = g[1] = g[2] = 0;
  if (s.direct) return 0.0;
  std::vector<std::complex<double>> e[3];
  rc.phases(s, r, e);
  double v = 0;
  for (std::size_t q = 0; q < rc.m.size(); ++q) {
    const std::complex<double> ph = rc.phase(e, q);
    v += rc.w[q] * ph.real();
    for (int d = 0; d < 3; ++d) g[d] -= rc.w[q] * kPi * rc.m[q][d] / s.shape[d] * ph.imag();
  }
  return v;
}

}    // namespace

void periodic_green_unit(const KernelSpec &k, const double r[3], bool regular, double &value, double grad[3],
                         const double *shape)
{
  const Split s(k, shape);
  const Reciprocal rc(s);
  double gr[3], gk[3], rf[3];
  // fold into the cell (the regular form keeps r: its n = 0 term is the one at r)
  for (int d = 0; d < 3; ++d) rf[d] = regular ? r[d] : r[d] - s.period[d] * std::nearbyint(r[d] / s.period[d]);
  real_sum(s, rf, regular, false, value, gr);
  value += recip_sum(s, rc, rf, gk) + s.background();
  for (int d = 0; d < 3; ++d) grad[d] = gr[d] + gk[d];
}

namespace {

std::shared_ptr<LatticeTable> compute_table(const KernelSpec &k, int p, const double shape[3])
{
  const Split s(k, shape);
  const Reciprocal rc(s);
  auto t = std::make_shared<LatticeTable>();
  t->p = p;
  t->quad = k.type == KernelType::Laplace ? 2 * kPi / (3 * s.volume) : 0.0;
  for (int d = 0; d < 3; ++d) t->shape[d] = shape[d];
  const int m = 2 * p - 1;
  t->r.assign((std::size_t) m * m * m, 0.0);
  const double step = p > 1 ? 2.0 * kRadiusInner / (p - 1) : 0.0;
  const bool cube = shape[0] == 1.0 && shape[1] == 1.0 && shape[2] == 1.0;
  // R is even in every coordinate; a cube's is also invariant under permutations of the axes
  // (then only 0 <= i <= j <= l is computed)
  std::vector<std::array<int, 3>> todo;
  for (int i = 0; i < p; ++i)
    for (int j = cube ? i : 0; j < p; ++j)
      for (int l = cube ? j : 0; l < p; ++l) todo.push_back({i, j, l});
#pragma omp parallel for schedule(dynamic, 4)
  for (std::size_t e = 0; e < todo.size(); ++e) {
    const int *a = todo[e].data();
    const double r[3] = {a[0] * step * shape[0], a[1] * step * shape[1], a[2] * step * shape[2]};
    double v, g[3];
    real_sum(s, r, true, true, v, g);
    if (!s.direct) {
      double gk[3];
      v += recip_sum(s, rc, r, gk) + s.background();
    }
    v -= t->quad * (r[0] * r[0] + r[1] * r[1] + r[2] * r[2]);
    const int perm[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
    for (int pi = 0; pi < (cube ? 6 : 1); ++pi) {
      const int *pm = perm[pi];
      for (int sx = -1; sx <= 1; sx += 2)
        for (int sy = -1; sy <= 1; sy += 2)
          for (int sz = -1; sz <= 1; sz += 2) {
            const int x = sx * a[pm[0]], y = sy * a[pm[1]], z = sz * a[pm[2]];
            t->r[((std::size_t) (x + p - 1) * m + (y + p - 1)) * m + (z + p - 1)] = v;
          }
    }
  }
  return t;
}

}    // namespace

std::shared_ptr<const LatticeTable> lattice_table(const KernelSpec &k, int p, const double *shape)
{
  static std::mutex mtx;
  static std::map<std::tuple<double, int, double, double, double>, std::shared_ptr<const LatticeTable>> cache;
  const double one[3] = {1.0, 1.0, 1.0};
  const double *sh = shape ? shape : one;
  const auto key = std::make_tuple(k.type == KernelType::Yukawa ? k.kappa : -1.0, p, sh[0], sh[1], sh[2]);
  {
    std::lock_guard<std::mutex> lock(mtx);
    auto it = cache.find(key);
    if (it != cache.end()) return it->second;
  }
  auto t = compute_table(k, p, sh);
  std::lock_guard<std::mutex> lock(mtx);
  if (cache.size() > 64) cache.clear();    // boxes that keep changing size (yukawa) or shape
  cache[key] = t;
  return t;
}

// ------------------------------------------------------------------------------ reference sum

void periodic_direct_sum(const KernelSpec &kernel, const double center[3], double h, std::size_t n_src,
                         const double *src_xyz, const double *src_q, std::size_t n_trg, const double *trg_xyz,
                         double *pot, double *grad, const double *shape)
{
  KernelSpec uk = kernel;
  if (uk.type == KernelType::Yukawa) uk.kappa = kernel.kappa * h;
  const Split s(uk, shape);
  const Reciprocal rc(s);
  std::vector<double> su, tu;
  wrap_into_cell(n_src, src_xyz, center, h, su, shape);
  wrap_into_cell(n_trg, trg_xyz, center, h, tu, shape);
  for (std::size_t i = 0; i < n_src; ++i)
    for (int d = 0; d < 3; ++d) su[3 * i + d] = (su[3 * i + d] - center[d]) / h;
  for (std::size_t i = 0; i < n_trg; ++i)
    for (int d = 0; d < 3; ++d) tu[3 * i + d] = (tu[3 * i + d] - center[d]) / h;
  // structure factors S(m) = sum_j q_j exp(i k.y_j)
  const std::size_t nk = rc.m.size();
  std::vector<std::complex<double>> S(nk, 0.0);
  {
    std::vector<std::complex<double>> e[3];
    for (std::size_t j = 0; j < n_src; ++j) {
      if (src_q[j] == 0.0) continue;
      rc.phases(s, &su[3 * j], e);
      for (std::size_t q = 0; q < nk; ++q) S[q] += src_q[j] * rc.phase(e, q);
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
        r[d] -= s.period[d] * std::nearbyint(r[d] / s.period[d]);    // into the cell
      }
      const bool same = r[0] == 0.0 && r[1] == 0.0 && r[2] == 0.0;
      real_sum(s, r, same, false, t, gg);
      v += src_q[j] * t;
      for (int d = 0; d < 3; ++d) g[d] += src_q[j] * gg[d];
    }
    if (nk > 0) {
      std::vector<std::complex<double>> e[3];
      rc.phases(s, &tu[3 * i], e);
      for (std::size_t q = 0; q < nk; ++q) {
        const std::complex<double> ph = rc.phase(e, q) * std::conj(S[q]);
        v += rc.w[q] * ph.real();
        for (int d = 0; d < 3; ++d) g[d] -= rc.w[q] * kPi * rc.m[q][d] / s.shape[d] * ph.imag();
      }
    }
    if (pot) pot[i] = v / h;
    if (grad)
      for (int d = 0; d < 3; ++d) grad[3 * i + d] = g[d] / (h * h);
  }
}

namespace {
// erfc(alpha r)/r with its derivatives (kernels.h's derivs3 convention): the real-space terms
struct ErfcKernel {
  double alpha;
  void derivs3(double r2, double invr, double &G, double &F, double &H, double &T) const
  {
    const double r = r2 * invr, i2 = invr * invr, c = 2.0 * alpha / kSqrtPi * std::exp(-alpha * alpha * r2);
    const double a2 = 2.0 * alpha * alpha;
    const double b0 = std::erfc(alpha * r) * invr, b1 = (b0 + c) * i2, b2 = (3 * b1 + a2 * c) * i2,
                 b3 = (5 * b2 + a2 * a2 * c) * i2;
    G = b0, F = -b1, H = b2, T = -b3;
  }
};
}    // namespace

void periodic_dipole_direct_sum(const double center[3], double h, const double *shape, std::size_t n_src,
                                const double *src_xyz, const double *src_q, const double *src_mu, std::size_t n_trg,
                                const double *trg_xyz, double *pot, double *grad, double *hess)
{
  const Split s(KernelSpec{}, shape);
  const Reciprocal rc(s);
  std::vector<double> su, tu;
  wrap_into_cell(n_src, src_xyz, center, h, su, shape);
  wrap_into_cell(n_trg, trg_xyz, center, h, tu, shape);
  // unit coordinates: positions (x - c) / h, dipoles mu / h
  std::vector<double> sx(n_src), sy(n_src), sz(n_src), sq(n_src), mx(n_src), my(n_src), mz(n_src);
  double qtot = 0;
  for (std::size_t j = 0; j < n_src; ++j) {
    sx[j] = (su[3 * j] - center[0]) / h, sy[j] = (su[3 * j + 1] - center[1]) / h, sz[j] = (su[3 * j + 2] - center[2]) / h;
    sq[j] = src_q ? src_q[j] : 0.0;
    mx[j] = src_mu ? src_mu[3 * j] / h : 0.0, my[j] = src_mu ? src_mu[3 * j + 1] / h : 0.0;
    mz[j] = src_mu ? src_mu[3 * j + 2] / h : 0.0;
    qtot += sq[j];
  }
  // structure factors S(m) = sum_j (q_j + i k.mu_j) exp(i k.y_j)
  const std::size_t nk = rc.m.size();
  std::vector<std::complex<double>> S(nk, 0.0);
  {
    std::vector<std::complex<double>> e[3];
    for (std::size_t j = 0; j < n_src; ++j) {
      const double v[3] = {sx[j], sy[j], sz[j]};
      rc.phases(s, v, e);
      for (std::size_t q = 0; q < nk; ++q) {
        const double km = kPi * (rc.m[q][0] * mx[j] / s.shape[0] + rc.m[q][1] * my[j] / s.shape[1] +
                                 rc.m[q][2] * mz[j] / s.shape[2]);
        S[q] += std::complex<double>(sq[j], km) * rc.phase(e, q);
      }
    }
  }
  const ErfcKernel ek{s.alpha};
  const double bg = s.background(), cut = s.real_cut();
  const double c1 = 2 * s.alpha / kSqrtPi, c3 = 4 * s.alpha * s.alpha * s.alpha / (3 * kSqrtPi);
  const int ia[6] = {0, 1, 2, 0, 0, 1}, ib[6] = {0, 1, 2, 1, 2, 2};
#pragma omp parallel for schedule(dynamic, 4)
  for (std::size_t i = 0; i < n_trg; ++i) {
    const double u[3] = {(tu[3 * i] - center[0]) / h, (tu[3 * i + 1] - center[1]) / h, (tu[3 * i + 2] - center[2]) / h};
    double v = bg * qtot, g[3] = {0, 0, 0}, hh[6] = {0, 0, 0, 0, 0, 0};
    // real space: the images of every source within the cutoff (the same point at n = 0 left out)
    for (std::size_t j = 0; j < n_src; ++j) {
      double r[3] = {u[0] - sx[j], u[1] - sy[j], u[2] - sz[j]};
      for (int d = 0; d < 3; ++d) r[d] -= s.period[d] * std::nearbyint(r[d] / s.period[d]);
      const bool same = r[0] == 0.0 && r[1] == 0.0 && r[2] == 0.0;
      const int N[3] = {s.images(0, std::fabs(r[0])), s.images(1, std::fabs(r[1])), s.images(2, std::fabs(r[2]))};
      for (int nx = -N[0]; nx <= N[0]; ++nx)
        for (int ny = -N[1]; ny <= N[1]; ++ny)
          for (int nz = -N[2]; nz <= N[2]; ++nz) {
            const double d[3] = {r[0] + s.period[0] * nx, r[1] + s.period[1] * ny, r[2] + s.period[2] * nz};
            const double r2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
            if (r2 == 0.0 || r2 > cut * cut) continue;
            const double tx = d[0], ty = d[1], tz = d[2], zx = 0, zy = 0, zz = 0;
            const PointSpan t{1, &tx, &ty, &tz}, src{1, &zx, &zy, &zz, &sq[j], &mx[j], &my[j], &mz[j]};
            p2p_dipole<ErfcKernel, true, true, false>(
                ek, t, src, {&v, &g[0], &g[1], &g[2], &hh[0], &hh[1], &hh[2], &hh[3], &hh[4], &hh[5]}, nullptr);
          }
      if (same) {    // the reciprocal sum's part of the point itself
        v -= c1 * sq[j];
        g[0] -= c3 * mx[j], g[1] -= c3 * my[j], g[2] -= c3 * mz[j];
        for (int d = 0; d < 3; ++d) hh[d] += c3 * sq[j];
      }
    }
    if (nk > 0) {
      std::vector<std::complex<double>> e[3];
      rc.phases(s, u, e);
      for (std::size_t q = 0; q < nk; ++q) {
        const std::complex<double> ph = rc.phase(e, q) * std::conj(S[q]);
        const double k[3] = {kPi * rc.m[q][0] / s.shape[0], kPi * rc.m[q][1] / s.shape[1], kPi * rc.m[q][2] / s.shape[2]};
        v += rc.w[q] * ph.real();
        for (int d = 0; d < 3; ++d) g[d] -= rc.w[q] * k[d] * ph.imag();
        for (int m = 0; m < 6; ++m) hh[m] -= rc.w[q] * k[ia[m]] * k[ib[m]] * ph.real();
      }
    }
    if (pot) pot[i] = v / h;
    if (grad)
      for (int d = 0; d < 3; ++d) grad[3 * i + d] = g[d] / (h * h);
    if (hess)
      for (int m = 0; m < 6; ++m) hess[6 * i + m] = hh[m] / (h * h * h);
  }
}

}    // namespace kifmm
