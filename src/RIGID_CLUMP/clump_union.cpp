// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
#include "clump_union.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <tuple>

namespace clump {

namespace {

// 4-point Gauss-Legendre on [-1, 1]
const double GX[4] = {-0.86113631159405257522, -0.33998104358485626480, 0.33998104358485626480,
                      0.86113631159405257522};
const double GW[4] = {0.34785484513745385737, 0.65214515486254614263, 0.65214515486254614263,
                      0.34785484513745385737};

// Moments of one piece about its ball's centre: integrals of 1, x, y, z, xx, yy, zz, yz, xz,
// xy (x relative to the centre).
const int NQ = 10;
const long SIG_NONE = -1000000, SIG_MIXED = -2000000;
struct Q {
  double v[NQ] = {0, 0, 0, 0, 0, 0, 0, 0, 0, 0};
  // which constraints end the segment (upper * 4096 + lower, -1 = the sphere / the centre,
  // empty segment = -2) at all the rule's points, or SIG_MIXED if they differ
  long sig = SIG_NONE;
  void merge_sig(long other)
  {
    if (sig == SIG_NONE) sig = other;
    else if (other != SIG_NONE && other != sig) sig = SIG_MIXED;
  }
  void add(const Q &o)
  {
    for (int k = 0; k < NQ; ++k) v[k] += o.v[k];
    merge_sig(o.sig);
  }
  void sub(const Q &o)
  {
    for (int k = 0; k < NQ; ++k) v[k] -= o.v[k];
  }
};

// a radical plane bounding the power cell of ball i: points c_i + t w with
// t * (w . n) <= a are on i's side
struct Plane {
  double n[3];
  double a;
  double cap_axis[3];    // axis of the directions whose segment the plane shortens
  double cap_theta;      // angular radius of that cap
  double cap_volume;     // volume of the ball beyond the plane (bound for a missed cap)
};

struct Piece {
  double r;
  std::vector<Plane> planes;
};

struct Cell {
  int face, depth;
  double u0, u1, v0, v1;
  Q q;         // rule on the cell
  Q qc;        // sum of the rules on its four children
  Q qch[4];    // the children's rules (reused when the cell is split)
  double err;
};

// cube face f: direction = normalize(u * e1 + v * e2 + e3)
const double FACE[6][3][3] = {
    {{0, 1, 0}, {0, 0, 1}, {1, 0, 0}},  {{0, 0, 1}, {0, 1, 0}, {-1, 0, 0}},
    {{0, 0, 1}, {1, 0, 0}, {0, 1, 0}},  {{1, 0, 0}, {0, 0, 1}, {0, -1, 0}},
    {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}},  {{0, 1, 0}, {1, 0, 0}, {0, 0, -1}}};

inline void direction(int f, double u, double v, double w[3])
{
  double len = std::sqrt(1.0 + u * u + v * v);
  for (int d = 0; d < 3; ++d)
    w[d] = (u * FACE[f][0][d] + v * FACE[f][1][d] + FACE[f][2][d]) / len;
}

// Adaptive angular integration of one piece (ball ∩ power cell).
class PieceIntegrator {
 public:
  explicit PieceIntegrator(const Piece &p) : p_(p) {}
  // integrates until the error estimate is below tol_abs (relative to the piece's volume
  // when tol_abs < 0: -tol_abs is then the relative tolerance); returns the estimate
  double run(double rel_tol, double abs_floor, Q &out, long &ncells);

 private:
  const Piece &p_;
  std::vector<Cell> heap_;
  Q total_;
  double error_ = 0.0;

  Q rule(int face, double u0, double u1, double v0, double v1) const;
  double cap_info(int face, double u0, double u1, double v0, double v1, bool &kinked) const;
  void push(int face, int depth, double u0, double u1, double v0, double v1, const Q &q,
            double parent_err);
};

Q PieceIntegrator::rule(int face, double u0, double u1, double v0, double v1) const
{
  Q q;
  const double hu = 0.5 * (u1 - u0), hv = 0.5 * (v1 - v0);
  const double cu = 0.5 * (u0 + u1), cv = 0.5 * (v0 + v1);
  for (int i = 0; i < 4; ++i) {
    const double u = cu + hu * GX[i];
    for (int j = 0; j < 4; ++j) {
      const double v = cv + hv * GX[j];
      const double g = 1.0 + u * u + v * v;
      const double wt = GW[i] * GW[j] * hu * hv / (g * std::sqrt(g));
      double w[3];
      direction(face, u, v, w);
      double lo = 0.0, hi = p_.r;
      long ihi = -1, ilo = -1;
      for (long k = 0; k < (long) p_.planes.size(); ++k) {
        const Plane &pl = p_.planes[k];
        const double s = w[0] * pl.n[0] + w[1] * pl.n[1] + w[2] * pl.n[2];
        if (s > 0.0) {
          const double t = pl.a / s;
          if (t < hi) {
            hi = t;
            ihi = k;
          }
        } else if (s < 0.0) {
          const double t = pl.a / s;
          if (t > lo) {
            lo = t;
            ilo = k;
          }
        } else if (pl.a < 0.0)
          hi = -1.0;
        if (hi <= lo) break;
      }
      if (hi <= lo) {
        q.merge_sig(-2);
        continue;
      }
      q.merge_sig(ihi * 4096 + ilo);
      const double lo2 = lo * lo, hi2 = hi * hi;
      const double m2 = wt * (hi2 * hi - lo2 * lo) / 3.0;
      const double m3 = wt * (hi2 * hi2 - lo2 * lo2) / 4.0;
      const double m4 = wt * (hi2 * hi2 * hi - lo2 * lo2 * lo) / 5.0;
      q.v[0] += m2;
      q.v[1] += w[0] * m3;
      q.v[2] += w[1] * m3;
      q.v[3] += w[2] * m3;
      q.v[4] += w[0] * w[0] * m4;
      q.v[5] += w[1] * w[1] * m4;
      q.v[6] += w[2] * w[2] * m4;
      q.v[7] += w[1] * w[2] * m4;
      q.v[8] += w[0] * w[2] * m4;
      q.v[9] += w[0] * w[1] * m4;
    }
  }
  return q;
}

// Looks at the caps near a cell. Returns the sum of the volumes of the caps that meet the
// cell but are narrower than it (its Gauss points may miss them entirely) and sets `kinked`
// if a cap boundary crosses the cell (where the segment end switches between the sphere and
// a plane, or the segment vanishes).
double PieceIntegrator::cap_info(int face, double u0, double u1, double v0, double v1,
                                 bool &kinked) const
{
  kinked = false;
  if (p_.planes.empty()) return 0.0;
  double wc[3];
  direction(face, 0.5 * (u0 + u1), 0.5 * (v0 + v1), wc);
  double cos_half = 1.0;    // cosine of the cell's angular radius about its centre
  const double us[2] = {u0, u1}, vs[2] = {v0, v1};
  for (double u : us)
    for (double v : vs) {
      double w[3];
      direction(face, u, v, w);
      cos_half = std::min(cos_half, w[0] * wc[0] + w[1] * wc[1] + w[2] * wc[2]);
    }
  const double alpha = std::acos(std::max(-1.0, std::min(1.0, cos_half)));
  double sum = 0.0;
  for (const Plane &pl : p_.planes) {
    const double ca = wc[0] * pl.cap_axis[0] + wc[1] * pl.cap_axis[1] + wc[2] * pl.cap_axis[2];
    const double ang = std::acos(std::max(-1.0, std::min(1.0, ca)));
    if (ang >= pl.cap_theta + alpha) continue;        // cell entirely outside this cap
    if (ang > pl.cap_theta - alpha) kinked = true;    // the cap boundary may cross the cell
    if (pl.cap_theta < alpha) sum += pl.cap_volume;
  }
  return sum;
}

void PieceIntegrator::push(int face, int depth, double u0, double u1, double v0, double v1,
                           const Q &q, double parent_err)
{
  Cell cell;
  cell.face = face;
  cell.depth = depth;
  cell.u0 = u0;
  cell.u1 = u1;
  cell.v0 = v0;
  cell.v1 = v1;
  cell.q = q;
  const double um = 0.5 * (u0 + u1), vm = 0.5 * (v0 + v1);
  // children in the order a (u half) * 2 + b (v half)
  cell.qch[0] = rule(face, u0, um, v0, vm);
  cell.qch[1] = rule(face, u0, um, vm, v1);
  cell.qch[2] = rule(face, um, u1, v0, vm);
  cell.qch[3] = rule(face, um, u1, vm, v1);
  for (int c = 0; c < 4; ++c) cell.qc.add(cell.qch[c]);
  // estimate from the volume, the first moments and the trace of the second moments, so
  // that an accidental agreement of one of them does not hide the error
  const double r = p_.r;
  double e = std::fabs(cell.qc.v[0] - q.v[0]);
  for (int d = 1; d <= 3; ++d) e += std::fabs(cell.qc.v[d] - q.v[d]) / r;
  double trc = cell.qc.v[4] + cell.qc.v[5] + cell.qc.v[6], trq = q.v[4] + q.v[5] + q.v[6];
  e += std::fabs(trc - trq) / (r * r);
  bool kinked = false;
  e += cap_info(face, u0, u1, v0, v1, kinked);
  // the nearest plane switches inside the cell (seen at the 16 + 64 points of the rules)
  Q both = q;
  both.merge_sig(cell.qc.sig);
  if (both.sig == SIG_MIXED) kinked = true;
  // At a kink the Gauss error depends on where the kink falls between the nodes, so the
  // parent-children difference can vanish by accident. In cells that may hold a kink the
  // estimate is therefore not allowed to fall faster than 16x per level (the error of a
  // rule across a kink falls about 8x per halving), starting from the cell's share of the
  // ball volume at the first level.
  if (kinked) {
    const double floor = parent_err > 0.0
        ? parent_err / 32.0
        : 1e-3 * (4.0 / 3.0 * M_PI * r * r * r) * (u1 - u0) * (v1 - v0) / 24.0;
    e = std::max(e, floor);
  }
  cell.err = e;
  total_.add(cell.qc);
  error_ += cell.err;
  heap_.push_back(std::move(cell));
  std::push_heap(heap_.begin(), heap_.end(),
                 [](const Cell &a, const Cell &b) { return a.err < b.err; });
}

double PieceIntegrator::run(double rel_tol, double abs_floor, Q &out, long &ncells)
{
  const int m = 4;    // initial cells per face edge
  for (int f = 0; f < 6; ++f)
    for (int a = 0; a < m; ++a)
      for (int b = 0; b < m; ++b) {
        double u0 = -1.0 + 2.0 * a / m, u1 = -1.0 + 2.0 * (a + 1) / m;
        double v0 = -1.0 + 2.0 * b / m, v1 = -1.0 + 2.0 * (b + 1) / m;
        push(f, 0, u0, u1, v0, v1, rule(f, u0, u1, v0, v1), 0.0);
      }
  const double tol_abs = std::max(rel_tol * std::fabs(total_.v[0]), abs_floor);
  auto cmp = [](const Cell &a, const Cell &b) { return a.err < b.err; };
  const int max_depth = 40;
  std::vector<Cell> done;
  while (!heap_.empty() && error_ > tol_abs) {
    std::pop_heap(heap_.begin(), heap_.end(), cmp);
    Cell cell = std::move(heap_.back());
    heap_.pop_back();
    if (cell.depth >= max_depth) {
      done.push_back(cell);
      continue;
    }
    total_.sub(cell.qc);
    error_ -= cell.err;
    const double um = 0.5 * (cell.u0 + cell.u1), vm = 0.5 * (cell.v0 + cell.v1);
    const double ub[2][2] = {{cell.u0, um}, {um, cell.u1}};
    const double vb[2][2] = {{cell.v0, vm}, {vm, cell.v1}};
    for (int a = 0; a < 2; ++a)
      for (int b = 0; b < 2; ++b)
        push(cell.face, cell.depth + 1, ub[a][0], ub[a][1], vb[b][0], vb[b][1],
             cell.qch[a * 2 + b], cell.err);
  }
  // sums afresh (the running sums accumulate rounding)
  out = Q();
  double err = 0.0;
  for (const Cell &c : heap_) {
    out.add(c.qc);
    err += c.err;
  }
  for (const Cell &c : done) {
    out.add(c.qc);
    err += c.err;
  }
  ncells = (long) (heap_.size() + done.size());
  return err;
}

// Builds the piece of every ball; pieces that are translates of each other (same radius and
// same bounding planes, e.g. the interior pebbles of a lattice) are integrated once.
UnionMoments integrate_union(const std::vector<Sphere> &s_, double rel_tol)
{
  UnionMoments out;
  const int n = (int) s_.size();
  if (n == 0) return out;
  double cell = 0.0, rmax = 0.0;
  for (const auto &sp : s_) {
    cell = std::max(cell, 2.0 * sp.r);
    rmax = std::max(rmax, sp.r);
  }
  if (!(cell > 0.0)) return out;
  std::map<std::tuple<long, long, long>, std::vector<int>> bins;
  auto key = [&](const Sphere &sp) {
    return std::make_tuple((long) std::floor(sp.x[0] / cell), (long) std::floor(sp.x[1] / cell),
                           (long) std::floor(sp.x[2] / cell));
  };
  for (int i = 0; i < n; ++i) bins[key(s_[i])].push_back(i);

  struct Result {
    Q q;
    double err;
  };
  std::map<std::vector<long long>, Result> cache;
  double vol_total = 0.0, err_total = 0.0;
  Q total;    // moments about the origin
  for (int i = 0; i < n; ++i) {
    const Sphere &si = s_[i];
    if (!(si.r > 0.0)) continue;
    Piece p;
    p.r = si.r;
    bool empty = false;
    auto [kx, ky, kz] = key(si);
    for (long dx = -1; dx <= 1 && !empty; ++dx)
      for (long dy = -1; dy <= 1 && !empty; ++dy)
        for (long dz = -1; dz <= 1 && !empty; ++dz) {
          auto it = bins.find(std::make_tuple(kx + dx, ky + dy, kz + dz));
          if (it == bins.end()) continue;
          for (int j : it->second) {
            if (j == i) continue;
            const Sphere &sj = s_[j];
            double dvec[3] = {sj.x[0] - si.x[0], sj.x[1] - si.x[1], sj.x[2] - si.x[2]};
            double dist = std::sqrt(dvec[0] * dvec[0] + dvec[1] * dvec[1] + dvec[2] * dvec[2]);
            if (dist >= si.r + sj.r) continue;    // no overlap: no effect inside B_i
            if (dist == 0.0) {                    // concentric: the larger ball owns it all
              if (sj.r > si.r || (sj.r == si.r && j < i)) {
                empty = true;
                break;
              }
              continue;
            }
            Plane pl;
            for (int d = 0; d < 3; ++d) pl.n[d] = dvec[d] / dist;
            pl.a = (dist * dist + si.r * si.r - sj.r * sj.r) / (2.0 * dist);
            if (pl.a >= si.r) continue;    // plane outside the ball
            if (pl.a <= -si.r) {           // the whole ball is on j's side
              empty = true;
              break;
            }
            double sgn = pl.a >= 0.0 ? 1.0 : -1.0;
            for (int d = 0; d < 3; ++d) pl.cap_axis[d] = sgn * pl.n[d];
            pl.cap_theta = std::acos(std::min(1.0, std::fabs(pl.a) / si.r));
            double h = si.r - std::fabs(pl.a);
            pl.cap_volume = M_PI * h * h * (3.0 * si.r - h) / 3.0;
            p.planes.push_back(pl);
          }
        }
    if (empty) continue;
    // key: radius and planes, rounded to 1e-10 of the largest radius
    std::vector<long long> k;
    const double qscale = 1e10;
    k.push_back(std::llround(si.r / rmax * qscale));
    std::vector<std::array<long long, 4>> pk;
    for (const Plane &pl : p.planes)
      pk.push_back({std::llround(pl.n[0] * qscale), std::llround(pl.n[1] * qscale),
                    std::llround(pl.n[2] * qscale), std::llround(pl.a / rmax * qscale)});
    std::sort(pk.begin(), pk.end());
    for (const auto &a : pk) k.insert(k.end(), a.begin(), a.end());
    auto it = cache.find(k);
    if (it == cache.end()) {
      Result res;
      long nc = 0;
      const double vball = 4.0 / 3.0 * M_PI * si.r * si.r * si.r;
      res.err = PieceIntegrator(p).run(rel_tol, 1e-3 * rel_tol * vball, res.q, nc);
      out.cells += nc;
      it = cache.emplace(std::move(k), res).first;
    }
    const Q &q = it->second.q;
    const double *c = si.x;
    const double v = q.v[0], f[3] = {q.v[1], q.v[2], q.v[3]};
    total.v[0] += v;
    for (int d = 0; d < 3; ++d) total.v[1 + d] += f[d] + c[d] * v;
    const int ia[6] = {0, 1, 2, 1, 0, 0}, ib[6] = {0, 1, 2, 2, 2, 1};
    for (int m = 0; m < 6; ++m) {
      int a = ia[m], b = ib[m];
      total.v[4 + m] += q.v[4 + m] + c[a] * f[b] + c[b] * f[a] + c[a] * c[b] * v;
    }
    vol_total += v;
    err_total += it->second.err;
  }
  out.volume = total.v[0];
  for (int d = 0; d < 3; ++d) out.first[d] = total.v[1 + d];
  for (int m = 0; m < 6; ++m) out.second[m] = total.v[4 + m];
  out.error_volume = err_total;
  return out;
}

}    // namespace

UnionMoments union_moments(const std::vector<Sphere> &spheres, double rel_tol)
{
  // integrate about the centroid of the centres (less cancellation), then shift back
  double g[3] = {0, 0, 0};
  for (const auto &sp : spheres)
    for (int d = 0; d < 3; ++d) g[d] += sp.x[d] / spheres.size();
  std::vector<Sphere> local(spheres);
  for (auto &sp : local)
    for (int d = 0; d < 3; ++d) sp.x[d] -= g[d];
  UnionMoments m = integrate_union(local, rel_tol);
  if (spheres.empty()) return m;
  const double v = m.volume;
  const double f[3] = {m.first[0], m.first[1], m.first[2]};
  // second moments about the origin: S_ab + g_a f_b + g_b f_a + V g_a g_b
  const int ia[6] = {0, 1, 2, 1, 0, 0}, ib[6] = {0, 1, 2, 2, 2, 1};
  for (int k = 0; k < 6; ++k) {
    int a = ia[k], b = ib[k];
    m.second[k] += g[a] * f[b] + g[b] * f[a] + v * g[a] * g[b];
  }
  for (int d = 0; d < 3; ++d) m.first[d] = f[d] + v * g[d];
  return m;
}

MassProperties union_mass_properties(const std::vector<Sphere> &spheres, double rho,
                                     double rel_tol)
{
  MassProperties p;
  if (spheres.empty()) return p;
  double g[3] = {0, 0, 0};
  for (const auto &sp : spheres)
    for (int d = 0; d < 3; ++d) g[d] += sp.x[d] / spheres.size();
  std::vector<Sphere> local(spheres);
  for (auto &sp : local)
    for (int d = 0; d < 3; ++d) sp.x[d] -= g[d];
  UnionMoments m = integrate_union(local, rel_tol);
  const double v = m.volume;
  double c[3];
  for (int d = 0; d < 3; ++d) c[d] = m.first[d] / v;
  // central second moments C_ab = S_ab - V c_a c_b
  const int ia[6] = {0, 1, 2, 1, 0, 0}, ib[6] = {0, 1, 2, 2, 2, 1};
  double cm[6];
  for (int k = 0; k < 6; ++k) cm[k] = m.second[k] - v * c[ia[k]] * c[ib[k]];
  double tr = cm[0] + cm[1] + cm[2];
  p.volume = v;
  p.mass = rho * v;
  for (int d = 0; d < 3; ++d) p.com[d] = g[d] + c[d];
  p.itensor[0] = rho * (tr - cm[0]);
  p.itensor[1] = rho * (tr - cm[1]);
  p.itensor[2] = rho * (tr - cm[2]);
  p.itensor[3] = -rho * cm[3];
  p.itensor[4] = -rho * cm[4];
  p.itensor[5] = -rho * cm[5];
  p.rel_error = v > 0 ? m.error_volume / v : 0.0;
  p.cells = m.cells;
  return p;
}

std::vector<std::array<int, 2>> duplicate_spheres(const std::vector<Sphere> &spheres,
                                                  double rel_tol)
{
  std::vector<std::array<int, 2>> dups;
  if (spheres.empty()) return dups;
  double cell = 0.0;
  for (const auto &sp : spheres) cell = std::max(cell, sp.r);
  if (cell <= 0.0) cell = 1.0;
  std::map<std::tuple<long, long, long>, std::vector<int>> bins;
  auto key = [&](const Sphere &sp) {
    return std::make_tuple((long) std::floor(sp.x[0] / cell), (long) std::floor(sp.x[1] / cell),
                           (long) std::floor(sp.x[2] / cell));
  };
  for (int i = 0; i < (int) spheres.size(); ++i) bins[key(spheres[i])].push_back(i);
  for (int i = 0; i < (int) spheres.size(); ++i) {
    auto [kx, ky, kz] = key(spheres[i]);
    for (long dx = -1; dx <= 1; ++dx)
      for (long dy = -1; dy <= 1; ++dy)
        for (long dz = -1; dz <= 1; ++dz) {
          auto it = bins.find(std::make_tuple(kx + dx, ky + dy, kz + dz));
          if (it == bins.end()) continue;
          for (int j : it->second) {
            if (j <= i) continue;
            double d2 = 0.0;
            for (int d = 0; d < 3; ++d) {
              double t = spheres[i].x[d] - spheres[j].x[d];
              d2 += t * t;
            }
            double lim = rel_tol * std::min(spheres[i].r, spheres[j].r);
            if (d2 < lim * lim || (d2 == 0.0)) dups.push_back({i, j});
          }
        }
  }
  std::sort(dups.begin(), dups.end());
  return dups;
}

}    // namespace clump
