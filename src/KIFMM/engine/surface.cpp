// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
#include "surface.h"

namespace kifmm {

std::vector<int> surface_lattice(int p)
{
  std::vector<int> idx;
  idx.reserve(3 * surface_size(p));
  for (int i = 0; i < p; ++i)
    for (int j = 0; j < p; ++j)
      for (int k = 0; k < p; ++k)
        if (i == 0 || i == p - 1 || j == 0 || j == p - 1 || k == 0 || k == p - 1) {
          idx.push_back(i);
          idx.push_back(j);
          idx.push_back(k);
        }
  return idx;
}

SurfacePoints unit_surface(int p, double alpha)
{
  SurfacePoints s;
  const std::vector<int> idx = surface_lattice(p);
  const int n = (int) idx.size() / 3;
  const double step = p > 1 ? 2.0 / (p - 1) : 0.0;
  s.x.resize(n);
  s.y.resize(n);
  s.z.resize(n);
  for (int m = 0; m < n; ++m) {
    s.x[m] = alpha * (p > 1 ? -1.0 + step * idx[3 * m] : 0.0);
    s.y[m] = alpha * (p > 1 ? -1.0 + step * idx[3 * m + 1] : 0.0);
    s.z[m] = alpha * (p > 1 ? -1.0 + step * idx[3 * m + 2] : 0.0);
  }
  return s;
}

SurfacePoints shaped_surface(int p, double alpha, const double shape[3])
{
  SurfacePoints s = unit_surface(p, alpha);
  for (int i = 0; i < s.size(); ++i) {
    s.x[i] *= shape[0];
    s.y[i] *= shape[1];
    s.z[i] *= shape[2];
  }
  return s;
}

void box_surface(const SurfacePoints &unit, const double c[3], double h, SurfacePoints &out)
{
  const int n = unit.size();
  out.x.resize(n);
  out.y.resize(n);
  out.z.resize(n);
  for (int m = 0; m < n; ++m) {
    out.x[m] = c[0] + h * unit.x[m];
    out.y[m] = c[1] + h * unit.y[m];
    out.z[m] = c[2] + h * unit.z[m];
  }
}

}    // namespace kifmm
