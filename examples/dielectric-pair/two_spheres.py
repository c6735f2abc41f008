# This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
"""The exact force between two equal dielectric spheres in a uniform field along their line of
centres (no dependencies besides Python): each sphere's exterior Legendre series re-expanded
about the other, the interface conditions degree by degree, a dense solve (Jeffrey, Proc. R.
Soc. A 335, 1973, for the method), converged in the number of degrees (touching spheres of
permittivity ratio 10 at 100 degrees: 2e-5).

Sphere 1 at z = +d/2, sphere 2 at -d/2; outside, the potential is -E z + sum_n A_n r1^-(n+1)
P_n + B_n r2^-(n+1) P_n (a unit charge's potential q / (4 pi r)). The mirror symmetry of the
pair gives B_n = (-1)^(n+1) A_n, so with c(n, m) = C(n+m, m) / d^(n+m+1) (the re-expansion of
r2^-(n+1) P_n about centre 1 has the sign (-1)^m) the coefficients of the field of sphere 2
about centre 1 are L_m = sum_n (-1)^(m+n+1) c(n, m) A_n, and the interface condition of degree
m is A_m = -alpha_m (L_m - E delta_m1), alpha_m = m (eps - 1) / (m eps + m + 1) a^(2m+1). The
force on sphere 1 is -sum_m m L_m q_(m-1), q_n = 4 pi A_n.

force(a, d, eps, E, degrees=200): the attraction in LAMMPS lj units (a unit charge's
potential q / r: divide by 4 pi).
"""
import math


def force(a, d, eps, E, degrees=200):
    N = degrees

    def alpha(m):
        return m * (eps - 1) / (m * eps + m + 1) * a ** (2 * m + 1)

    def coupling(n, m):
        return math.exp(math.lgamma(n + m + 1) - math.lgamma(n + 1) - math.lgamma(m + 1) - (n + m + 1) * math.log(d))

    c = [[coupling(n, m) * (-1) ** (m + n + 1) for n in range(1, N + 1)] for m in range(1, N + 1)]
    # (I + diag(alpha) c) A = alpha_1 E e_1, by Gaussian elimination with partial pivoting
    M = [[(1.0 if i == j else 0.0) + alpha(i + 1) * c[i][j] for j in range(N)] + [alpha(1) * E if i == 0 else 0.0]
         for i in range(N)]
    for k in range(N):
        p = max(range(k, N), key=lambda i: abs(M[i][k]))
        M[k], M[p] = M[p], M[k]
        pivot = M[k]
        for i in range(k + 1, N):
            f = M[i][k] / pivot[k]
            if f != 0.0:
                row = M[i]
                for j in range(k, N + 1):
                    row[j] -= f * pivot[j]
    A = [0.0] * N
    for i in range(N - 1, -1, -1):
        A[i] = (M[i][N] - sum(M[i][j] * A[j] for j in range(i + 1, N))) / M[i][i]
    L = [sum(c[m][n] * A[n] for n in range(N)) for m in range(N)]
    F = -sum((m + 1) * L[m] * 4 * math.pi * A[m - 1] for m in range(1, N))
    return -F / (4 * math.pi)
