// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// Dielectric spheres by the boundary integral equation (kifmm::polarize_dielectric_spheres):
//   accuracy : two spheres of radius 1, permittivity ratio 10, field along their line of
//              centres, at gaps 0.3 .. 0 radii and degrees 8, 12, 16, plain grids and grids
//              drawn towards the contact: the relative error of the force against the
//              converged multipole reference (unittest/common/two_dielectric_spheres.h), and
//              that of the point-dipole model;
//   chain    : three spheres in a row along the field (the middle one has two close neighbours
//              and keeps the undrawn grid), gaps 0.1 .. 0: the relative error of the end
//              sphere's force against the axial multipole solution of three spheres;
//   cost     : k^3 spheres on a cubic lattice with gaps of 0.1 radii, field along a diagonal:
//              one solve with the FMM (order 8) and with the direct sum in the same run (one
//              thread): the setup (grids, near rows), the solve (GMRES and forces) of each and
//              their ratio, GMRES steps, nodes with graded quadrature and their memory, and the
//              largest force difference between the two.
//   bench_dielectric_spheres [--accuracy] [--chain] [--cost] [--lattice 2,3] [--degrees 8,12]
#include "kifmm.h"
#include "two_dielectric_spheres.h"

#include <cmath>
#include <cstdio>
#include <cstring>
#include <sstream>
#include <string>
#include <vector>

namespace {

const double kPi = std::acos(-1.0);

std::vector<int> int_list(const char *s)
{
  std::vector<int> v;
  std::stringstream ss(s);
  std::string t;
  while (std::getline(ss, t, ',')) v.push_back(std::stoi(t));
  return v;
}

void accuracy()
{
  const double eps = 10, beta = (eps - 1) / (eps + 2);
  std::printf("| gap / a | degree | nodes per sphere | plain grid: force error | drawn grid (s) : force error | point-dipole model error |\n");
  std::printf("|---|---|---|---|---|---|\n");
  for (double gap : {0.3, 0.1, 0.05, 0.01, 0.0}) {
    const double d = 2 + gap, ref = kifmm_points::two_sphere_force(1, d, eps, 1, 400);
    const double p = 4 * kPi * beta / (1 - 2 * beta / (d * d * d)), dipole = -6 * p * p / (4 * kPi * std::pow(d, 4));
    for (int L : {8, 12, 16}) {
      double err[2], s = 0;
      for (int k = 0; k < 2; ++k) {
        const double c[6] = {0, 0, 0.5 * d, 0, 0, -0.5 * d}, r[2] = {1, 1}, e[2] = {eps, eps}, E[3] = {0, 0, 1};
        kifmm::DielectricSphereOptions o;
        o.degree = L;
        o.tolerance = 1e-11;
        o.contact_refinement = k == 0 ? 1.0 : 0.0;
        const auto sol = kifmm::polarize_dielectric_spheres(nullptr, 2, c, r, e, E, o);
        err[k] = sol.force[2] / ref - 1;
        if (k == 1) s = sol.refinement[0];
      }
      std::printf("| %g | %d | %d | %+.1e | (%g) %+.1e | %+.2f |\n", gap, L, 2 * (L + 1) * (L + 1), err[0], s, err[1],
                  dipole / ref - 1);
    }
  }
}

void chain()
{
  std::printf("| gap / a | degree | end force error |\n|---|---|---|\n");
  for (double gap : {0.1, 0.05, 0.01, 0.0}) {
    const double d = 2 + gap;
    const auto ref = kifmm_points::axial_spheres_forces({d, 0, -d}, {1, 1, 1}, {10, 10, 10}, 1, 200);
    for (int L : {12, 16}) {
      const double c[9] = {0, 0, d, 0, 0, 0, 0, 0, -d}, r[3] = {1, 1, 1}, e[3] = {10, 10, 10}, E[3] = {0, 0, 1};
      kifmm::DielectricSphereOptions o;
      o.degree = L;
      o.tolerance = 1e-11;
      const auto s = kifmm::polarize_dielectric_spheres(nullptr, 3, c, r, e, E, o);
      std::printf("| %g | %d | %+.1e |\n", gap, L, s.force[2] / ref[0] - 1);
    }
  }
}

void cost(const std::vector<int> &lattice, const std::vector<int> &degrees)
{
  std::printf("| spheres | degree | nodes | GMRES steps | near rows | near memory MB | setup s | solve FMM s | solve direct s | FMM / direct | max force difference / max force |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|---|---|\n");
  for (int k : lattice)
    for (int L : degrees) {
      const std::size_t n = (std::size_t) k * k * k;
      std::vector<double> c(3 * n), r(n, 1.0), e(n, 10.0);
      for (std::size_t i = 0; i < n; ++i) {
        const int a[3] = {(int) (i / (k * k)), (int) ((i / k) % k), (int) (i % k)};
        for (int d = 0; d < 3; ++d) c[3 * i + d] = 2.1 * a[d];
      }
      const double E[3] = {1 / std::sqrt(3.0), 1 / std::sqrt(3.0), 1 / std::sqrt(3.0)};
      kifmm::DielectricSphereOptions o;
      o.degree = L;
      o.tolerance = 1e-8;
      kifmm::Options fo;
      fo.order = 8;
      auto ev = kifmm::make_evaluator(kifmm::KernelSpec{}, fo);
      const auto f = kifmm::polarize_dielectric_spheres(ev.get(), n, c.data(), r.data(), e.data(), E, o);
      const auto dsol = kifmm::polarize_dielectric_spheres(nullptr, n, c.data(), r.data(), e.data(), E, o);
      const double tf = f.seconds_solve, td = dsol.seconds_solve;
      double fmax = 0, diff = 0;
      for (std::size_t i = 0; i < 3 * n; ++i) {
        fmax = std::max(fmax, std::fabs(dsol.force[i]));
        diff = std::max(diff, std::fabs(dsol.force[i] - f.force[i]));
      }
      std::printf("| %zu | %d | %zu | %d | %zu | %.1f | %.2f | %.2f | %.2f | %.2f | %.1e |\n", n, L, n * f.nodes_per_sphere,
                  f.iterations, f.near_rows, 24e-6 * f.near_rows * f.nodes_per_sphere, f.seconds_setup, tf, td, tf / td,
                  diff / fmax);
    }
}

}    // namespace

int main(int argc, char **argv)
{
  bool acc = false, cst = false, chn = false;
  std::vector<int> lattice{2, 3}, degrees{8, 12};
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--accuracy")) acc = true;
    else if (!std::strcmp(argv[i], "--cost")) cst = true;
    else if (!std::strcmp(argv[i], "--chain")) chn = true;
    else if (!std::strcmp(argv[i], "--lattice") && i + 1 < argc) lattice = int_list(argv[++i]);
    else if (!std::strcmp(argv[i], "--degrees") && i + 1 < argc) degrees = int_list(argv[++i]);
    else {
      std::fprintf(stderr, "usage: bench_dielectric_spheres [--accuracy] [--chain] [--cost] [--lattice 2,3] [--degrees 8,12]\n");
      return 1;
    }
  }
  if (!acc && !cst && !chn) acc = chn = cst = true;
  if (acc) accuracy();
  if (chn) chain();
  if (cst) cost(lattice, degrees);
  return 0;
}
