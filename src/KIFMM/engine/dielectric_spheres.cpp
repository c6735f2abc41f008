// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// Dielectric spheres polarized by a uniform field: the boundary integral equation of kifmm.h
// (polarize_dielectric_spheres), Nystrom on each sphere's grid (sphere_grid.h), the other
// spheres' field by the evaluator, corrections for the nodes near another sphere, GMRES.
#include "gmres.h"
#include "kifmm.h"
#include "sphere_grid.h"

#include <Eigen/Dense>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>
#include <stdexcept>
#include <string>
#include <tuple>

namespace kifmm {

namespace {

constexpr double kPi = 3.14159265358979323846;
// a node takes the graded quadrature for another sphere when it is closer to that sphere's
// surface than this many node spacings (pi a / (L + 1)) of it; farther, the nodes as point
// charges are accurate: with 4 spacings instead, the two-sphere force errors of
// bench/dielectric/results are the same to two digits (gaps up to 0.1 radii; at 0.3 radii and
// degree 16, 3e-6 instead of 8e-7 on the plain grid)
constexpr double kNearSpacings = 2.5;
// widest panel of the graded quadrature (radians): 12 Gauss-Legendre nodes on pi / 4 integrate
// the density of degree <= 40 (the force errors of bench/dielectric/results are the same with
// panels up to pi / 12 and up to pi / 2)
constexpr double kWidest = kPi / 4;

using Matrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

// The grid of a sphere with a close neighbour is drawn towards the contact by a conformal map
// of the sphere: stereographic projection from the far pole, the plane shrunk by `s`, projected
// back. Phi_s(u) for a unit vector u (pole +z) and its area scale: with D = s^2 (1 + u_z) + 1 - u_z,
//   Phi_s(u) = (2 s u_x, 2 s u_y, s^2 (1 + u_z) - (1 - u_z)) / D,   length scale lambda = 2 s / D
// (lambda = 1 / s at the pole, s at the far pole); Phi_s^-1 = Phi_(1/s). Distances obey
// |Phi(u) - Phi(v)|^2 = lambda(u) lambda(v) |u - v|^2 (Moebius maps are conformal), so the
// own sphere's single-layer kernel stays diagonal in the harmonics of g = sigma lambda^(3/2):
//   int sigma(y) / (8 pi a |x - y|) dS_y = lambda(u)^(-1/2) sum_lm g_lm Y_lm(u) / (2 (2l + 1)).
double conformal_scale(double s, const double u[3])
{
  return 2.0 * s / (s * s * (1.0 + u[2]) + (1.0 - u[2]));
}
double conformal_map(double s, const double u[3], double out[3])
{
  const double lambda = conformal_scale(s, u);
  out[0] = lambda * u[0];
  out[1] = lambda * u[1];
  out[2] = lambda * (s * s * (1.0 + u[2]) - (1.0 - u[2])) / (2.0 * s);
  return lambda;
}

// The nodes of a grid drawn towards its pole by the factor s (1: the plain grid), in the
// sphere's own frame (pole +z), and their operator for the own sphere, dimensionless (the same
// for every radius and rotation): the principal-value normal field of sigma (g of degree <= L)
// less the field of the same nodes as point charges, which the evaluation of all nodes includes.
struct MappedGrid {
  double s = 1.0;
  std::vector<double> dir, scale;    // mapped unit vectors (3 per node); lambda at each node
  Matrix own;
};

MappedGrid mapped_grid(const SphereGrid &g, double s)
{
  MappedGrid m;
  m.s = s;
  const int nh = harmonic_count(g.degree);
  const std::size_t nn = g.nodes;
  m.dir.resize(3 * nn);
  m.scale.resize(nn);
  for (std::size_t k = 0; k < nn; ++k) m.scale[k] = conformal_map(s, &g.dir[3 * k], &m.dir[3 * k]);
  Eigen::Map<const Matrix> Y(g.harmonics.data(), nn, nh), T(g.transform.data(), nh, nn);
  Eigen::VectorXd diag(nh), left(nn), right(nn);
  for (int l = 0; l <= g.degree; ++l)
    for (int mm = -l; mm <= l; ++mm) diag[harmonic_index(l, mm)] = 1.0 / (2.0 * (2 * l + 1));
  for (std::size_t k = 0; k < nn; ++k) {
    left[k] = 1.0 / std::sqrt(m.scale[k]);
    right[k] = std::pow(m.scale[k], 1.5);
  }
  m.own = left.asDiagonal() * (Y * diag.asDiagonal() * T) * right.asDiagonal();
  // point charges w_j lambda_j^2 a^2 sigma_j / (4 pi) on the sphere of radius a: normal field
  // n_k . (x_k - x_j) / |x_k - x_j|^3 = 1 / (2 a |x_k - x_j|)
  for (std::size_t k = 0; k < nn; ++k)
    for (std::size_t j = 0; j < nn; ++j) {
      if (j == k) continue;
      const double *a = &m.dir[3 * k], *b = &m.dir[3 * j];
      const double r = std::sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) + (a[2] - b[2]) * (a[2] - b[2]));
      m.own(k, j) -= g.weight[j] * m.scale[j] * m.scale[j] / (8.0 * kPi * r);
    }
  return m;
}

// A sphere: centre, radius, the rotation from its own frame (columns: e1, e2, pole) and its grid.
struct Sphere {
  const double *c;
  double a;
  double R[9];
  const MappedGrid *grid;
  void to_world(const double u[3], double x[3]) const
  {
    for (int d = 0; d < 3; ++d) x[d] = R[3 * d] * u[0] + R[3 * d + 1] * u[1] + R[3 * d + 2] * u[2];
  }
  void to_own(const double x[3], double u[3]) const
  {
    for (int d = 0; d < 3; ++d) u[d] = R[d] * x[0] + R[3 + d] * x[1] + R[6 + d] * x[2];
  }
};

// The factor s for a sphere whose one close neighbour is `gap` radii away: measured on two
// spheres of permittivity ratio 10 at degrees 12 and 16 (bench/dielectric/results), s = 2 is
// the most accurate from gaps of 0.04 radii up, 3 down to 0.008, 4 below and touching.
double automatic_refinement(double gap)
{
  return gap >= 0.04 ? 2.0 : gap >= 0.008 ? 3.0 : 4.0;
}

// a rotation whose third column is the unit vector p
void frame_with_pole(const double p[3], double R[9])
{
  double e1[3] = {0, 0, 0};
  e1[std::fabs(p[0]) < 0.6 ? 0 : std::fabs(p[1]) < 0.6 ? 1 : 2] = 1.0;
  const double pe = p[0] * e1[0] + p[1] * e1[1] + p[2] * e1[2];
  for (int d = 0; d < 3; ++d) e1[d] -= pe * p[d];
  const double n1 = std::sqrt(e1[0] * e1[0] + e1[1] * e1[1] + e1[2] * e1[2]);
  for (double &v : e1) v /= n1;
  const double e2[3] = {p[1] * e1[2] - p[2] * e1[1], p[2] * e1[0] - p[0] * e1[2], p[0] * e1[1] - p[1] * e1[0]};
  for (int d = 0; d < 3; ++d) {
    R[3 * d] = e1[d];
    R[3 * d + 1] = e2[d];
    R[3 * d + 2] = p[d];
  }
}

// Field at x of sphere S's density (g of degree <= L) minus that of its nodes as point charges,
// as a 3 x nodes matrix acting on the node values of sigma. The density is integrated on a
// quadrature in polar coordinates about the surface point nearest to x (x lies on that axis,
// so the kernel depends on the polar angle only): 12-point Gauss-Legendre panels growing
// geometrically from the distance of x to the surface up to kWidest, then of that width; the
// trapezoidal rule in the azimuth.
Matrix near_correction(const SphereGrid &g, const Sphere &S, const double x[3])
{
  const int L = g.degree, nh = harmonic_count(L);
  const std::size_t nn = g.nodes;
  const double a = S.a, *c = S.c, s = S.grid->s;
  double u[3] = {x[0] - c[0], x[1] - c[1], x[2] - c[2]};
  const double rho = std::sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
  for (double &v : u) v /= rho;
  double F[9];
  frame_with_pole(u, F);

  std::vector<double> edges{0.0};
  double w = std::min(kWidest, std::max(1e-9, (rho - a) / a));
  while (edges.back() < kPi) {
    edges.push_back(std::min(kPi, edges.back() + w));
    w = std::min(kWidest, 2 * w);
  }
  std::vector<double> t, wt;
  gauss_legendre(12, t, wt);
  const int nchi = 2 * L + 8;
  Matrix V = Matrix::Zero(3, nh);
  std::vector<double> y(nh);
  for (std::size_t p = 0; p + 1 < edges.size(); ++p) {
    const double h = 0.5 * (edges[p + 1] - edges[p]), m = 0.5 * (edges[p + 1] + edges[p]);
    for (std::size_t q = 0; q < t.size(); ++q) {
      const double psi = m + h * t[q], sp = std::sin(psi), cp = std::cos(psi);
      const double wpsi = h * wt[q] * a * a * sp * 2.0 * kPi / nchi / (4.0 * kPi);
      for (int j = 0; j < nchi; ++j) {
        const double chi = 2.0 * kPi * j / nchi, cc = std::cos(chi), sc = std::sin(chi);
        double dir[3], r[3], own[3], v[3];
        for (int d = 0; d < 3; ++d) {
          dir[d] = cp * F[3 * d + 2] + sp * (cc * F[3 * d] + sc * F[3 * d + 1]);
          r[d] = x[d] - (c[d] + a * dir[d]);
        }
        const double r2 = r[0] * r[0] + r[1] * r[1] + r[2] * r[2];
        S.to_own(dir, own);
        // sigma(y) = g(v) lambda(v)^(-3/2), v = Phi_s^-1(own)
        conformal_map(1.0 / s, own, v);
        const double lv = conformal_scale(s, v);
        const double k = wpsi / (r2 * std::sqrt(r2) * lv * std::sqrt(lv));
        real_harmonics(g.table, v, y.data());
        for (int d = 0; d < 3; ++d)
          for (int hh = 0; hh < nh; ++hh) V(d, hh) += k * r[d] * y[hh];
      }
    }
  }
  Eigen::Map<const Matrix> T(g.transform.data(), nh, nn);
  Matrix R = V * T;
  for (std::size_t j = 0; j < nn; ++j) {
    const double lj = S.grid->scale[j];
    double r[3], xj[3];
    S.to_world(&S.grid->dir[3 * j], xj);
    for (int d = 0; d < 3; ++d) r[d] = x[d] - (c[d] + a * xj[d]);
    const double r2 = r[0] * r[0] + r[1] * r[1] + r[2] * r[2];
    const double k = g.weight[j] * lj * lj * a * a / (4.0 * kPi * r2 * std::sqrt(r2));
    for (int d = 0; d < 3; ++d) R(d, j) = R(d, j) * lj * std::sqrt(lj) - k * r[d];
  }
  return R;
}

struct NearRow {
  std::size_t node;      // global node index (the target)
  std::size_t sphere;    // the other sphere
  Matrix R;              // 3 x nodes
};

void check_input(Evaluator *ev, std::size_t n, const double *center, const double *radius,
                 const double *eps, const double field[3], const DielectricSphereOptions &opt)
{
  if (opt.degree < 1) throw std::invalid_argument("dielectric spheres: degree must be at least 1");
  if (!(std::isfinite(field[0]) && std::isfinite(field[1]) && std::isfinite(field[2])))
    throw std::invalid_argument("dielectric spheres: the field is not finite");
  if (ev && ev->kernel().type != KernelType::Laplace)
    throw std::invalid_argument("dielectric spheres: the evaluator must have the Laplace kernel");
  for (std::size_t i = 0; i < n; ++i) {
    if (!(radius[i] > 0 && std::isfinite(radius[i]))) throw std::invalid_argument("dielectric spheres: radius of sphere " + std::to_string(i) + " is not positive and finite");
    if (!(eps[i] > 0 && std::isfinite(eps[i]))) throw std::invalid_argument("dielectric spheres: permittivity ratio of sphere " + std::to_string(i) + " is not positive and finite");
    for (int d = 0; d < 3; ++d)
      if (!std::isfinite(center[3 * i + d])) throw std::invalid_argument("dielectric spheres: centre of sphere " + std::to_string(i) + " is not finite");
  }
}

// pairs of spheres whose surfaces are closer than `reach` (i < j; overlapping ones included), by
// a hash of cells of the largest diameter plus reach; throws for overlapping spheres unless
// `overlaps` is set
std::vector<std::pair<std::size_t, std::size_t>> close_pairs(std::size_t n, const double *c, const double *r, double reach,
                                                             bool overlaps = false)
{
  double rmax = 0, lo[3] = {1e300, 1e300, 1e300};
  for (std::size_t i = 0; i < n; ++i) {
    rmax = std::max(rmax, r[i]);
    for (int d = 0; d < 3; ++d) lo[d] = std::min(lo[d], c[3 * i + d]);
  }
  const double cell = 2 * rmax + reach;
  std::map<std::tuple<long, long, long>, std::vector<std::size_t>> bins;
  auto key = [&](std::size_t i, int dx, int dy, int dz) {
    return std::make_tuple((long) std::floor((c[3 * i] - lo[0]) / cell) + dx, (long) std::floor((c[3 * i + 1] - lo[1]) / cell) + dy,
                           (long) std::floor((c[3 * i + 2] - lo[2]) / cell) + dz);
  };
  for (std::size_t i = 0; i < n; ++i) bins[key(i, 0, 0, 0)].push_back(i);
  std::vector<std::pair<std::size_t, std::size_t>> out;
  for (std::size_t i = 0; i < n; ++i)
    for (int o = 0; o < 27; ++o) {
      auto it = bins.find(key(i, o / 9 - 1, (o / 3) % 3 - 1, o % 3 - 1));
      if (it == bins.end()) continue;
      for (std::size_t j : it->second) {
        if (j <= i) continue;
        double d2 = 0;
        for (int d = 0; d < 3; ++d) d2 += (c[3 * i + d] - c[3 * j + d]) * (c[3 * i + d] - c[3 * j + d]);
        const double gap = std::sqrt(d2) - r[i] - r[j];
        if (!overlaps && gap < -1e-9 * (r[i] + r[j]))
          throw std::invalid_argument("dielectric spheres: spheres " + std::to_string(i) + " and " + std::to_string(j) + " overlap");
        if (gap < reach) out.emplace_back(i, j);
      }
    }
  return out;
}

// The spheres' frames and grids: the pole towards the nearest close neighbour; a sphere with
// exactly one close neighbour takes the grid drawn towards it (factor from the gap, or given).
// grids: one per factor (their own-sphere operators), which the spheres point to.
std::vector<Sphere> place_spheres(const SphereGrid &g, std::size_t n, const double *center, const double *radius,
                                  const std::vector<std::pair<std::size_t, std::size_t>> &pairs, double refinement,
                                  std::map<double, MappedGrid> &grids)
{
  std::vector<int> neighbours(n, 0);
  std::vector<double> nearest_gap(n, 1e300);
  std::vector<Sphere> S(n);
  for (std::size_t i = 0; i < n; ++i) {
    S[i].c = &center[3 * i];
    S[i].a = radius[i];
    const double z[3] = {0, 0, 1};
    frame_with_pole(z, S[i].R);
  }
  for (auto [i, j] : pairs) {
    double p[3], d2 = 0;
    for (int d = 0; d < 3; ++d) d2 += (p[d] = center[3 * j + d] - center[3 * i + d]) * p[d];
    const double dist = std::sqrt(d2), gap = dist - radius[i] - radius[j];
    for (int side = 0; side < 2; ++side) {
      const std::size_t t = side ? j : i;
      ++neighbours[t];
      if (gap < nearest_gap[t]) {
        nearest_gap[t] = gap;
        const double sg = side ? -1.0 : 1.0, q[3] = {sg * p[0] / dist, sg * p[1] / dist, sg * p[2] / dist};
        frame_with_pole(q, S[t].R);
      }
    }
  }
  for (std::size_t i = 0; i < n; ++i) {
    const double sr = neighbours[i] != 1 ? 1.0 : refinement > 0 ? refinement : automatic_refinement(nearest_gap[i] / radius[i]);
    auto it = grids.find(sr);
    if (it == grids.end()) it = grids.emplace(sr, mapped_grid(g, sr)).first;
    S[i].grid = &it->second;
  }
  return S;
}

// The nodes of close pairs nearer than `reach` radii of the other sphere, with their corrections
std::vector<NearRow> near_rows(const SphereGrid &g, const std::vector<Sphere> &S,
                               const std::vector<std::pair<std::size_t, std::size_t>> &pairs,
                               const std::vector<double> &node_xyz, double reach)
{
  const std::size_t nn = g.nodes;
  std::vector<NearRow> near;
  for (auto [i, j] : pairs)
    for (int side = 0; side < 2; ++side) {
      const std::size_t t = side ? j : i, s = side ? i : j;    // targets on t, the field of s
      for (std::size_t k = 0; k < nn; ++k) {
        const double *x = &node_xyz[3 * (t * nn + k)];
        double d2 = 0;
        for (int d = 0; d < 3; ++d) d2 += (x[d] - S[s].c[d]) * (x[d] - S[s].c[d]);
        if (std::sqrt(d2) - S[s].a < reach * S[s].a) near.push_back(NearRow{t * nn + k, s, Matrix()});
      }
    }
#pragma omp parallel for schedule(dynamic)
  for (std::size_t r = 0; r < near.size(); ++r) near[r].R = near_correction(g, S[near[r].sphere], &node_xyz[3 * near[r].node]);
  return near;
}

// Forces, torques and dipoles of the surface charges in the field of E0 and the other spheres
// (e: the field of all nodes as point charges and the near corrections; q: the nodes' charges;
// the own sphere's point-charge field taken out directly)
void sphere_forces(std::size_t n, std::size_t nn, const double *center, const double field[3], const std::vector<double> &e,
                   const std::vector<double> &q, DielectricSphereSolve &out)
{
  out.force.assign(3 * n, 0.0);
  out.torque.assign(3 * n, 0.0);
  out.dipole.assign(3 * n, 0.0);
  std::vector<double> own_grad(3 * nn);
  for (std::size_t i = 0; i < n; ++i) {
    direct_sum(KernelSpec{}, nn, &out.node_xyz[3 * i * nn], &q[i * nn], nn, &out.node_xyz[3 * i * nn], nullptr, own_grad.data());
    for (std::size_t k = 0; k < nn; ++k) {
      const std::size_t a = i * nn + k;
      double E[3], r[3];
      for (int d = 0; d < 3; ++d) {
        E[d] = field[d] + e[3 * a + d] + own_grad[3 * k + d];
        r[d] = out.node_xyz[3 * a + d] - center[3 * i + d];
      }
      const double qa = out.node_area[a] * out.sigma[a];
      for (int d = 0; d < 3; ++d) {
        out.force[3 * i + d] += qa * E[d];
        out.dipole[3 * i + d] += qa * r[d];
      }
      out.torque[3 * i] += qa * (r[1] * E[2] - r[2] * E[1]);
      out.torque[3 * i + 1] += qa * (r[2] * E[0] - r[0] * E[2]);
      out.torque[3 * i + 2] += qa * (r[0] * E[1] - r[1] * E[0]);
    }
  }
}

// Radii with which overlapping spheres touch: each sphere loses half of its largest overlap
// (then r_i + r_j <= |c_i - c_j| for every pair; spheres that did not overlap still do not).
// pairs: the number of overlapping pairs.
std::vector<double> touching_radii(std::size_t n, const double *c, const double *r, std::size_t &pairs)
{
  std::vector<double> cut(n, 0.0), out(r, r + n);
  pairs = 0;
  for (auto [i, j] : close_pairs(n, c, r, 0.0, true)) {
    double d2 = 0;
    for (int d = 0; d < 3; ++d) d2 += (c[3 * i + d] - c[3 * j + d]) * (c[3 * i + d] - c[3 * j + d]);
    const double overlap = r[i] + r[j] - std::sqrt(d2);
    if (!(overlap > 0)) continue;
    ++pairs;
    const double half = 0.5 * overlap * (1 + 1e-9);
    cut[i] = std::max(cut[i], half);
    cut[j] = std::max(cut[j], half);
  }
  for (std::size_t i = 0; i < n; ++i) {
    out[i] -= cut[i];
    if (!(out[i] > 0.05 * r[i]))
      throw std::invalid_argument("dielectric spheres: sphere " + std::to_string(i) + " lies (nearly) inside another");
  }
  return out;
}

}    // namespace

DielectricSphereSolve polarize_dielectric_spheres(Evaluator *ev, std::size_t n, const double *center,
                                                  const double *radius, const double *eps,
                                                  const double field[3], const DielectricSphereOptions &opt)
{
  check_input(ev, n, center, radius, eps, field, opt);
  using clock = std::chrono::steady_clock;
  const auto t0 = clock::now();
  DielectricSphereSolve out;
  out.radius.assign(radius, radius + n);
  if (opt.touch_overlaps) {
    out.radius = touching_radii(n, center, radius, out.overlapping_pairs);
    radius = out.radius.data();
  }
  const SphereGrid g(opt.degree);
  const std::size_t nn = g.nodes, N = n * nn;
  double rmax = 0;
  for (std::size_t i = 0; i < n; ++i) rmax = std::max(rmax, radius[i]);
  const double reach = kNearSpacings * kPi / (opt.degree + 1);    // in radii
  const auto pairs = close_pairs(n, center, radius, reach * rmax);
  std::map<double, MappedGrid> grids;
  const std::vector<Sphere> S = place_spheres(g, n, center, radius, pairs, opt.contact_refinement, grids);

  out.nodes_per_sphere = nn;
  out.refinement.resize(n);
  for (std::size_t i = 0; i < n; ++i) out.refinement[i] = S[i].grid->s;
  out.node_xyz.resize(3 * N);
  out.node_area.resize(N);
  std::vector<double> normal(3 * N), lambda(n);
  for (std::size_t i = 0; i < n; ++i) {
    lambda[i] = (eps[i] - 1.0) / (eps[i] + 1.0);
    for (std::size_t k = 0; k < nn; ++k) {
      const std::size_t a = i * nn + k;
      S[i].to_world(&S[i].grid->dir[3 * k], &normal[3 * a]);
      for (int d = 0; d < 3; ++d) out.node_xyz[3 * a + d] = center[3 * i + d] + radius[i] * normal[3 * a + d];
      const double l = S[i].grid->scale[k];
      out.node_area[a] = g.weight[k] * l * l * radius[i] * radius[i];
    }
  }
  const std::vector<NearRow> near = near_rows(g, S, pairs, out.node_xyz, reach);
  out.near_rows = near.size();
  const auto t1 = clock::now();
  out.seconds_setup = std::chrono::duration<double>(t1 - t0).count();

  // the field of all surface charges at the nodes (each node's own sphere as point charges,
  // which apply() replaces by the exact operator), plus the near corrections: e (3 per node)
  std::vector<double> q(N), grad(3 * N), e(3 * N);
  auto surface_field = [&](const double *sigma) {
    for (std::size_t k = 0; k < N; ++k) q[k] = out.node_area[k] * sigma[k] / (4.0 * kPi);
    if (ev)
      ev->evaluate(N, out.node_xyz.data(), q.data(), N, out.node_xyz.data(), nullptr, grad.data());
    else
      direct_sum(KernelSpec{}, N, out.node_xyz.data(), q.data(), N, out.node_xyz.data(), nullptr, grad.data());
    ++out.evaluations;
    for (std::size_t k = 0; k < 3 * N; ++k) e[k] = -grad[k];
    for (const NearRow &r : near) {
      Eigen::Map<const Eigen::VectorXd> s(sigma + r.sphere * nn, nn);
      const Eigen::Vector3d de = r.R * s;
      for (int d = 0; d < 3; ++d) e[3 * r.node + d] += de[d];
    }
  };
  auto apply = [&](const double *sigma, double *y) {
    surface_field(sigma);
    for (std::size_t i = 0; i < n; ++i) {
      Eigen::Map<const Eigen::VectorXd> si(sigma + i * nn, nn);
      const Eigen::VectorXd own_field = S[i].grid->own * si;
      for (std::size_t k = 0; k < nn; ++k) {
        const std::size_t a = i * nn + k;
        const double *nk = &normal[3 * a];
        const double en = nk[0] * e[3 * a] + nk[1] * e[3 * a + 1] + nk[2] * e[3 * a + 2];
        y[a] = sigma[a] - 2.0 * lambda[i] * (en + own_field[k]);
      }
    }
  };
  std::vector<double> b(N);
  out.sigma.resize(N);
  for (std::size_t a = 0; a < N; ++a) {
    const std::size_t i = a / nn;
    const double en = normal[3 * a] * field[0] + normal[3 * a + 1] * field[1] + normal[3 * a + 2] * field[2];
    b[a] = 2.0 * lambda[i] * en;
    out.sigma[a] = 3.0 * (eps[i] - 1.0) / (eps[i] + 2.0) * en;
  }
  const GmresResult res = gmres(N, apply, b.data(), out.sigma.data(), opt.tolerance, opt.max_iterations);
  out.iterations = res.iterations;
  out.residual = res.residual;
  out.converged = res.converged;

  surface_field(out.sigma.data());
  sphere_forces(n, nn, center, field, e, q, out);
  out.seconds_solve = std::chrono::duration<double>(clock::now() - t1).count();
  return out;
}

}    // namespace kifmm
