// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
#include "sphere_grid.h"

#include <algorithm>
#include <cmath>

namespace kifmm {

HarmonicsTable::HarmonicsTable(int L) : degree(L)
{
  const int nh = harmonic_count(L);
  a.assign(nh, 0.0);
  b.assign(nh, 0.0);
  diag.assign(L + 1, 1.0);
  for (int m = 1; m <= L; ++m) diag[m] = -std::sqrt((2.0 * m + 1.0) / (2.0 * m));
  for (int m = 0; m <= L; ++m)
    for (int l = m + 1; l <= L; ++l) {
      a[harmonic_index(l, m)] = std::sqrt((4.0 * l * l - 1.0) / ((double) l * l - (double) m * m));
      b[harmonic_index(l, m)] = std::sqrt(((l - 1.0) * (l - 1.0) - (double) m * m) / (4.0 * (l - 1.0) * (l - 1.0) - 1.0));
    }
}

void real_harmonics(const HarmonicsTable &t, const double u[3], double *y)
{
  // normalized associated Legendre functions Pbar_l^m (2 pi int Pbar^2 dmu = 1) by the usual
  // stable recurrences in l at fixed m, times cos/sin(m phi) from the recurrence of the angles
  const int degree = t.degree;
  const double mu = std::max(-1.0, std::min(1.0, u[2]));
  const double s = std::sqrt(std::max(0.0, 1.0 - mu * mu));
  const double rho = std::hypot(u[0], u[1]);
  const double c1 = rho > 0 ? u[0] / rho : 1.0, s1 = rho > 0 ? u[1] / rho : 0.0;
  const double pi = std::acos(-1.0), root2 = std::sqrt(2.0);
  double pmm = 1.0 / std::sqrt(4.0 * pi);
  double cm = 1.0, sm = 0.0;    // cos(m phi), sin(m phi)
  for (int m = 0; m <= degree; ++m) {
    if (m > 0) {
      pmm *= t.diag[m] * s;
      const double c = cm * c1 - sm * s1;
      sm = sm * c1 + cm * s1;
      cm = c;
    }
    const double fc = m == 0 ? 1.0 : root2 * cm, fs = root2 * sm;
    double p2 = 0.0, p1 = pmm;
    y[harmonic_index(m, m)] = fc * pmm;
    if (m > 0) y[harmonic_index(m, -m)] = fs * pmm;
    for (int l = m + 1; l <= degree; ++l) {
      const int h = harmonic_index(l, m);
      const double p = t.a[h] * (mu * p1 - t.b[h] * p2);
      p2 = p1;
      p1 = p;
      y[h] = fc * p;
      if (m > 0) y[harmonic_index(l, -m)] = fs * p;
    }
  }
}

void gauss_legendre(int n, std::vector<double> &x, std::vector<double> &w)
{
  x.assign(n, 0.0);
  w.assign(n, 0.0);
  const double pi = std::acos(-1.0);
  for (int i = 0; i < (n + 1) / 2; ++i) {
    double z = std::cos(pi * (i + 0.75) / (n + 0.5)), dp = 1.0;
    for (int it = 0; it < 100; ++it) {
      double p0 = 1.0, p1 = z;
      for (int k = 2; k <= n; ++k) {
        const double p = ((2.0 * k - 1.0) * z * p1 - (k - 1.0) * p0) / k;
        p0 = p1;
        p1 = p;
      }
      dp = n * (z * p1 - p0) / (z * z - 1.0);
      const double dz = p1 / dp;
      z -= dz;
      if (std::fabs(dz) < 1e-16) break;
    }
    x[i] = -z;
    x[n - 1 - i] = z;
    w[i] = w[n - 1 - i] = 2.0 / ((1.0 - z * z) * dp * dp);
  }
}

SphereGrid::SphereGrid(int L) : degree(L), table(L)
{
  std::vector<double> mu, wmu;
  gauss_legendre(L + 1, mu, wmu);
  const int nphi = 2 * L + 2, nh = harmonic_count(L);
  const double pi = std::acos(-1.0);
  nodes = (std::size_t) (L + 1) * nphi;
  dir.resize(3 * nodes);
  weight.resize(nodes);
  harmonics.resize(nodes * nh);
  transform.resize(nodes * nh);
  std::size_t k = 0;
  for (int i = 0; i <= L; ++i)
    for (int j = 0; j < nphi; ++j, ++k) {
      const double phi = 2.0 * pi * (j + 0.5) / nphi, s = std::sqrt(1.0 - mu[i] * mu[i]);
      dir[3 * k] = s * std::cos(phi);
      dir[3 * k + 1] = s * std::sin(phi);
      dir[3 * k + 2] = mu[i];
      weight[k] = wmu[i] * 2.0 * pi / nphi;
      real_harmonics(table, &dir[3 * k], &harmonics[k * nh]);
    }
  for (int h = 0; h < nh; ++h)
    for (std::size_t q = 0; q < nodes; ++q) transform[h * nodes + q] = weight[q] * harmonics[q * nh + h];
}

}    // namespace kifmm
