// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
#include "clump_math.h"

#include <cmath>

namespace clump {

bool jacobi_symmetric(int n, const double *a_in, double *evals, double *evecs)
{
  double a[64];
  for (int i = 0; i < n * n; ++i) a[i] = a_in[i];
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) evecs[i * n + j] = (i == j) ? 1.0 : 0.0;

  for (int sweep = 0; sweep < 100; ++sweep) {
    double off = 0.0, diag = 0.0;
    for (int i = 0; i < n; ++i) {
      diag += a[i * n + i] * a[i * n + i];
      for (int j = i + 1; j < n; ++j) off += a[i * n + j] * a[i * n + j];
    }
    if (off <= 1e-30 * diag || off == 0.0) {
      for (int i = 0; i < n; ++i) evals[i] = a[i * n + i];
      return true;
    }
    for (int p = 0; p < n; ++p)
      for (int q = p + 1; q < n; ++q) {
        double apq = a[p * n + q];
        if (apq == 0.0) continue;
        double theta = (a[q * n + q] - a[p * n + p]) / (2.0 * apq);
        double t = (theta >= 0 ? 1.0 : -1.0) / (std::fabs(theta) + std::sqrt(theta * theta + 1.0));
        double c = 1.0 / std::sqrt(t * t + 1.0), s = t * c;
        for (int k = 0; k < n; ++k) {    // A <- A J (columns p, q)
          double akp = a[k * n + p], akq = a[k * n + q];
          a[k * n + p] = c * akp - s * akq;
          a[k * n + q] = s * akp + c * akq;
        }
        for (int k = 0; k < n; ++k) {    // A <- J^T A (rows p, q)
          double apk = a[p * n + k], aqk = a[q * n + k];
          a[p * n + k] = c * apk - s * aqk;
          a[q * n + k] = s * apk + c * aqk;
        }
        for (int k = 0; k < n; ++k) {
          double vkp = evecs[k * n + p], vkq = evecs[k * n + q];
          evecs[k * n + p] = c * vkp - s * vkq;
          evecs[k * n + q] = s * vkp + c * vkq;
        }
      }
  }
  for (int i = 0; i < n; ++i) evals[i] = a[i * n + i];
  return false;
}

Mat3 quat_to_matrix(const std::array<double, 4> &q)
{
  double w = q[0], x = q[1], y = q[2], z = q[3];
  Mat3 r;
  r[0] = {w * w + x * x - y * y - z * z, 2 * (x * y - w * z), 2 * (x * z + w * y)};
  r[1] = {2 * (x * y + w * z), w * w - x * x + y * y - z * z, 2 * (y * z - w * x)};
  r[2] = {2 * (x * z - w * y), 2 * (y * z + w * x), w * w - x * x - y * y + z * z};
  return r;
}

Mat3 matmul(const Mat3 &a, const Mat3 &b)
{
  Mat3 c{};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      for (int k = 0; k < 3; ++k) c[i][j] += a[i][k] * b[k][j];
  return c;
}

Mat3 transpose(const Mat3 &a)
{
  Mat3 t;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) t[i][j] = a[j][i];
  return t;
}

Vec3 matvec(const Mat3 &a, const Vec3 &x)
{
  return {a[0][0] * x[0] + a[0][1] * x[1] + a[0][2] * x[2],
          a[1][0] * x[0] + a[1][1] * x[1] + a[1][2] * x[2],
          a[2][0] * x[0] + a[2][1] * x[1] + a[2][2] * x[2]};
}

Mat3 best_rotation(const std::vector<Vec3> &p, const std::vector<Vec3> &q, double &rms)
{
  // S = sum p_i q_i^T; Horn's 4x4 matrix N; its top eigenvector is the rotation quaternion.
  double s[3][3] = {};
  for (size_t i = 0; i < p.size(); ++i)
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) s[a][b] += p[i][a] * q[i][b];
  double sxx = s[0][0], sxy = s[0][1], sxz = s[0][2], syx = s[1][0], syy = s[1][1],
         syz = s[1][2], szx = s[2][0], szy = s[2][1], szz = s[2][2];
  double n[16] = {sxx + syy + szz, syz - szy,        szx - sxz,        sxy - syx,
                  syz - szy,       sxx - syy - szz,  sxy + syx,        szx + sxz,
                  szx - sxz,       sxy + syx,        -sxx + syy - szz, syz + szy,
                  sxy - syx,       szx + sxz,        syz + szy,        -sxx - syy + szz};
  double ev[4], evec[16];
  jacobi_symmetric(4, n, ev, evec);
  int best = 0;
  for (int k = 1; k < 4; ++k)
    if (ev[k] > ev[best]) best = k;
  std::array<double, 4> quat = {evec[0 * 4 + best], evec[1 * 4 + best], evec[2 * 4 + best],
                                evec[3 * 4 + best]};
  double norm = std::sqrt(quat[0] * quat[0] + quat[1] * quat[1] + quat[2] * quat[2] +
                          quat[3] * quat[3]);
  for (auto &c : quat) c /= norm;
  Mat3 r = quat_to_matrix(quat);
  double sum = 0.0;
  for (size_t i = 0; i < p.size(); ++i) {
    Vec3 rp = matvec(r, p[i]);
    for (int a = 0; a < 3; ++a) sum += (rp[a] - q[i][a]) * (rp[a] - q[i][a]);
  }
  rms = p.empty() ? 0.0 : std::sqrt(sum / p.size());
  return r;
}

void fit_rigid_motion(const std::vector<Vec3> &x, const std::vector<Vec3> &v, const Vec3 &c,
                      Vec3 &vc, Vec3 &omega)
{
  const size_t n = x.size();
  Vec3 g{}, vbar{};
  for (size_t i = 0; i < n; ++i)
    for (int a = 0; a < 3; ++a) {
      g[a] += x[i][a] / n;
      vbar[a] += v[i][a] / n;
    }
  // J omega = b with J = sum (|d|^2 1 - d d^T), b = sum d x (v - vbar), d = x - g
  double j[9] = {}, b[3] = {};
  for (size_t i = 0; i < n; ++i) {
    double d[3] = {x[i][0] - g[0], x[i][1] - g[1], x[i][2] - g[2]};
    double u[3] = {v[i][0] - vbar[0], v[i][1] - vbar[1], v[i][2] - vbar[2]};
    double dd = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
    for (int a = 0; a < 3; ++a)
      for (int e = 0; e < 3; ++e) j[a * 3 + e] += (a == e ? dd : 0.0) - d[a] * d[e];
    b[0] += d[1] * u[2] - d[2] * u[1];
    b[1] += d[2] * u[0] - d[0] * u[2];
    b[2] += d[0] * u[1] - d[1] * u[0];
  }
  double ev[3], evec[9];
  jacobi_symmetric(3, j, ev, evec);
  double emax = std::fmax(std::fmax(ev[0], ev[1]), ev[2]);
  omega = {0.0, 0.0, 0.0};
  for (int k = 0; k < 3; ++k) {
    if (ev[k] <= 1e-10 * emax || ev[k] <= 0.0) continue;
    double proj = evec[0 * 3 + k] * b[0] + evec[1 * 3 + k] * b[1] + evec[2 * 3 + k] * b[2];
    for (int a = 0; a < 3; ++a) omega[a] += evec[a * 3 + k] * proj / ev[k];
  }
  // velocity of point c: vbar is the velocity of g
  double r[3] = {c[0] - g[0], c[1] - g[1], c[2] - g[2]};
  vc = {vbar[0] + omega[1] * r[2] - omega[2] * r[1], vbar[1] + omega[2] * r[0] - omega[0] * r[2],
        vbar[2] + omega[0] * r[1] - omega[1] * r[0]};
}

}    // namespace clump
