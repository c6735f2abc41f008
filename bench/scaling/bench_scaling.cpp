// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// Strong-scaling benchmark of the distributed evaluation (engine level, no LAMMPS):
//   mpirun -np P bench_scaling N [uniform|periodic|plummer|clusters|periodic_plummer|periodic_clusters]
//          [order] [reps] [top_level]
//          [choice|tuned|leaf=M|grid=K|-] [charges|dipoles] [warm-ups]
// Each rank makes only its own points: uniform in its brick of a P-brick decomposition of
// [-1,1]^3 (as LAMMPS's processor grid; periodic: the same points, [-1,1]^3 is the periodic
// cell, Laplace with its background term), or, for plummer, the points of a Plummer sphere in its
// brick (every rank draws the same sequence and keeps its own; N <= 1e6); clusters: the two
// Gaussian clusters of the engine tests (bricks of their bounding box, the processor grid of
// least sub-domain surface for its extents, as LAMMPS chooses it); periodic_plummer and
// periodic_clusters: the Plummer sphere and the two clusters scaled into the periodic cell
// [-1,1]^3, charges shifted to a zero sum (as bench_tree_sweep --periodic). Prints one JSON line
// (rank 0): wall time per evaluation (max over ranks), CPU seconds per evaluation (sum over
// ranks), phases (max over ranks), bytes sent per rank and ghost points per rank (min/avg/max),
// and the seconds of the tree choice (choice, tuned: the slowest rank's).
// "dipoles": every point also carries a random dipole moment (evaluate_dipoles_distributed,
// with second derivatives at the targets). "tuned": from the choice, the tree is tuned by timing
// as kspace_style kifmm tunes it on several ranks (kifmm::TreeTuner on the ladders of the stand-in
// of all ranks' points, the slowest rank's time) before the timed evaluations; the JSON line adds the tuning evaluations.
// warm-ups (default 1): untimed evaluations of the tree before the timed ones (the tuned tree:
// after its tuning), so that candidates compared in a sweep can be warmed up alike.
#include "kifmm.h"
#include "mpi_communicator.h"

#include "../bench_points.h"

#include <mpi.h>
#include <omp.h>
#include <sys/resource.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>

namespace {

double cpu_seconds()
{
  rusage u;
  getrusage(RUSAGE_SELF, &u);
  return u.ru_utime.tv_sec + 1e-6 * u.ru_utime.tv_usec + u.ru_stime.tv_sec + 1e-6 * u.ru_stime.tv_usec;
}

// processor grid px*py*pz = P of least sub-domain surface for a box of extents L (LAMMPS
// chooses it so; a cube: as close to a cube as possible)
void grid(int P, int g[3], const double L[3])
{
  double best = 1e300;
  for (int a = 1; a <= P; ++a)
    if (P % a == 0)
      for (int b = 1; b <= P / a; ++b)
        if ((P / a) % b == 0) {
          const int c = P / a / b;
          const double s = L[0] * L[1] / ((double) a * b) + L[1] * L[2] / ((double) b * c) +
              L[0] * L[2] / ((double) a * c);
          if (s < best) {
            best = s;
            g[0] = a;
            g[1] = b;
            g[2] = c;
          }
        }
}

}    // namespace

int main(int argc, char **argv)
{
  MPI_Init(&argc, &argv);
  int me, P;
  MPI_Comm_rank(MPI_COMM_WORLD, &me);
  MPI_Comm_size(MPI_COMM_WORLD, &P);
  const std::size_t N = argc > 1 ? (std::size_t) std::atof(argv[1]) : 100000;
  const std::string dist = argc > 2 ? argv[2] : "uniform";
  const int order = argc > 3 ? std::atoi(argv[3]) : 6;
  const int reps = argc > 4 ? std::atoi(argv[4]) : 3;
  const int top = argc > 5 ? std::atoi(argv[5]) : 0;
  // "choice": leaf size (periodic: or single-level grid) chosen as kspace_style kifmm does on
  // several ranks (plan_tree, then choose_tree_from_layout on the stand-in of all ranks' points,
  // gather_layout); default: the per-order leaf size
  // "leaf=M": that leaf size (octree); "grid=K": the periodic single-level grid of K^3 cells
  const std::string how = argc > 6 ? argv[6] : "";
  const bool tuned = how == "tuned";
  const bool choice = how == "choice" || tuned;
  const bool dipoles = argc > 7 && std::string(argv[7]) == "dipoles";
  const int warmups = argc > 8 ? std::max(1, std::atoi(argv[8])) : 1;
  const bool periodic = dist.rfind("periodic", 0) == 0;
  const bool whole = dist == "plummer" || dist == "clusters" || dist == "periodic_plummer" ||
      dist == "periodic_clusters";    // every rank draws all points and keeps its brick's
  bench::Points all;
  double blo[3] = {-1, -1, -1}, bhi[3] = {1, 1, 1};    // the box the bricks divide
  if (dist == "plummer") {
    all = bench::plummer(N, 7);
    for (int d = 0; d < 3; ++d) blo[d] = -50.0, bhi[d] = 50.0;
  } else if (dist == "clusters") {
    all = kifmm_points::two_clusters(N, 3);
    bench::bounding_box(all, blo, bhi);
  } else if (dist == "periodic_plummer") {
    all = bench::into_periodic_cell(bench::plummer(N, 2));
  } else if (dist == "periodic_clusters") {
    all = bench::into_periodic_cell(kifmm_points::two_clusters(N, 3));
  } else if (dist != "uniform" && dist != "periodic") {
    if (me == 0) std::fprintf(stderr, "bench_scaling: unknown point set %s\n", dist.c_str());
    MPI_Abort(MPI_COMM_WORLD, 1);
  }
  const double L[3] = {bhi[0] - blo[0], bhi[1] - blo[1], bhi[2] - blo[2]};
  int g[3];
  grid(P, g, L);
  const int c[3] = {me % g[0], (me / g[0]) % g[1], me / (g[0] * g[1])};
  double lo[3], hi[3];
  for (int d = 0; d < 3; ++d) {
    lo[d] = -1.0 + 2.0 * c[d] / g[d];
    hi[d] = -1.0 + 2.0 * (c[d] + 1) / g[d];
  }
  bench::Points mine;
  if (whole) {
    for (std::size_t i = 0; i < all.size(); ++i) {
      bool in = true;
      for (int d = 0; d < 3; ++d) {
        // bricks of the box (open at the outer faces), in [-1,1] coordinates
        const double x = -1.0 + 2.0 * (all.xyz[3 * i + d] - blo[d]) / std::max(L[d], 1e-300);
        in = in && (c[d] == 0 || x >= lo[d]) && (c[d] == g[d] - 1 || x < hi[d]);
      }
      if (in) {
        mine.xyz.insert(mine.xyz.end(), &all.xyz[3 * i], &all.xyz[3 * i] + 3);
        mine.q.push_back(all.q[i]);
      }
    }
  } else {
    const std::size_t n = N / P + (me < (int) (N % P) ? 1 : 0);
    bench::Points u = bench::uniform(n, 1000 + me);
    for (std::size_t i = 0; i < n; ++i)
      for (int d = 0; d < 3; ++d) u.xyz[3 * i + d] = lo[d] + (u.xyz[3 * i + d] + 1.0) * 0.5 * (hi[d] - lo[d]);
    mine = u;
  }
  kifmm::Options o;
  o.order = order;
  o.top_level = top;
  if (periodic) {
    o.periodic = true;
    o.fixed_root = true;
    o.root_half_width = 1.0;
  }
  kifmm::KernelSpec spec;
  kifmm::MpiCommunicator comm(MPI_COMM_WORLD);
  const kifmm::TreeRequest request{N, 0, o.periodic ? -1 : 0, true};
  double t_choice = 0;    // seconds of the choice (the slowest rank)
  if (choice) {    // as kspace_style kifmm on several ranks: the choice on the stand-in of all ranks' points
    const double t0 = MPI_Wtime();
    const kifmm::TreePlan plan = kifmm::plan_tree(o, request);
    o = plan.options;
    if (plan.from_points) {
      const kifmm::PointLayout layout = kifmm::gather_layout(spec, o, mine.size(), mine.xyz.data(), comm);
      if (!layout.xyz.empty()) kifmm::choose_tree_from_layout(spec, request, o, layout);
    }
    t_choice = MPI_Wtime() - t0;
    MPI_Allreduce(MPI_IN_PLACE, &t_choice, 1, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
  } else if (how.rfind("leaf=", 0) == 0) {
    o.leaf_size = std::atoi(how.c_str() + 5);
    o.periodic_grid = 0;
  } else if (how.rfind("grid=", 0) == 0) {
    o.periodic_grid = std::atoi(how.c_str() + 5);
  }
  std::unique_ptr<kifmm::Evaluator> ev = kifmm::make_evaluator(spec, o);
  const std::size_t n = mine.size();
  std::vector<double> grad(3 * n), hess(dipoles ? 6 * n : 0), mu(dipoles ? 3 * n : 0);
  for (std::size_t i = 0; i < mu.size(); ++i) mu[i] = 0.01 * std::sin(1.0 + 7.0 * (double) (i + 13 * me));
  auto evaluate = [&]() {
    if (dipoles)
      ev->evaluate_dipoles_distributed(comm, n, mine.xyz.data(), mine.q.data(), mu.data(), nullptr, grad.data(),
                                      hess.data());
    else
      ev->evaluate_distributed(comm, n, mine.xyz.data(), mine.q.data(), nullptr, grad.data());
  };
  evaluate();    // warm-up (operators)
  for (int w = 1; w < warmups && !tuned; ++w) evaluate();
  int tuning_evaluations = 0;
  if (tuned) {
    const kifmm::PointLayout layout = kifmm::gather_layout(spec, o, mine.size(), mine.xyz.data(), comm);
    kifmm::TreeTuner tuner(spec, request, o, layout);
    while (tuner.tuning()) {
      tuner.select(ev);
      MPI_Barrier(MPI_COMM_WORLD);
      const double t0 = MPI_Wtime();
      evaluate();
      double t = MPI_Wtime() - t0 - ev->stats().t_precompute, slowest = t;
      MPI_Allreduce(&t, &slowest, 1, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
      tuner.record(slowest);
    }
    tuning_evaluations = tuner.evaluations();
    const kifmm::TreeChoice t = tuner.finish(ev);
    o.leaf_size = t.leaf_size;
    o.periodic_grid = t.grid;
    for (int w = 0; w < warmups; ++w) evaluate();    // warm-up of the tuned tree
  }
  double wall = 0, cpu = 0;
  double ph[8] = {0, 0, 0, 0, 0, 0, 0, 0};
  for (int r = 0; r < reps; ++r) {
    MPI_Barrier(MPI_COMM_WORLD);
    const double t0 = MPI_Wtime(), c0 = cpu_seconds();
    evaluate();
    const double t1 = MPI_Wtime(), c1 = cpu_seconds();
    MPI_Barrier(MPI_COMM_WORLD);
    wall += t1 - t0;
    cpu += c1 - c0;
    const kifmm::Stats &s = ev->stats();
    const double p[8] = {s.t_tree, s.t_lists, s.t_upward, s.t_m2l, s.t_wx, s.t_downward, s.t_p2p, s.t_comm};
    for (int k = 0; k < 8; ++k) ph[k] += p[k];
  }
  const kifmm::Stats &s = ev->stats();
  double mx[10], sum[10], mn[10];
  double v[10] = {wall / reps, cpu / reps, (double) s.comm_bytes, (double) s.n_ghosts, (double) n,
                  (double) s.ghost_bytes, (double) s.let_bytes, (double) s.let_cells, 0, 0};
  MPI_Allreduce(v, mx, 10, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
  MPI_Allreduce(v, sum, 10, MPI_DOUBLE, MPI_SUM, MPI_COMM_WORLD);
  MPI_Allreduce(v, mn, 10, MPI_DOUBLE, MPI_MIN, MPI_COMM_WORLD);
  double phmax[8];
  MPI_Allreduce(ph, phmax, 8, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
  double load[3] = {0, 0, 0};
  if (FILE *f = fopen("/proc/loadavg", "r")) {
    if (fscanf(f, "%lf %lf %lf", &load[0], &load[1], &load[2]) != 3) load[0] = -1;
    fclose(f);
  }
  if (me == 0) {
    printf("{\"grid\": %d, \"leaf\": %d, \"strengths\": \"%s\", \"tuning_evaluations\": %d, \"warmups\": %d, "
           "\"choice_s\": %.4g, ",
           o.periodic_grid, o.leaf_size, dipoles ? "dipoles" : "charges", tuning_evaluations, warmups, t_choice);
    printf("\"N\": %zu, \"dist\": \"%s\", \"order\": %d, \"ranks\": %d, \"threads\": %d, \"top_level\": %d, "
           "\"wall\": %.6g, \"cpu_sum\": %.6g, \"bytes_min\": %.0f, \"bytes_avg\": %.0f, \"bytes_max\": %.0f, "
           "\"ghost_bytes_max\": %.0f, \"let_bytes_max\": %.0f, \"let_cells_avg\": %.1f, "
           "\"ghosts_min\": %.0f, \"ghosts_avg\": %.1f, \"ghosts_max\": %.0f, "
           "\"own_min\": %.0f, \"own_max\": %.0f, \"depth\": %d, "
           "\"phase_max\": {\"tree\": %.4g, \"lists\": %.4g, \"upward\": %.4g, \"m2l\": %.4g, \"wx\": %.4g, "
           "\"downward\": %.4g, \"p2p\": %.4g, \"comm\": %.4g}, \"loadavg\": %.2f}\n",
           N, dist.c_str(), order, P, omp_get_max_threads(), s.top_level, mx[0], sum[1], mn[2], sum[2] / P, mx[2],
           mx[5], mx[6], sum[7] / P, mn[3], sum[3] / P, mx[3], mn[4], mx[4], s.depth, phmax[0] / reps, phmax[1] / reps,
           phmax[2] / reps, phmax[3] / reps, phmax[4] / reps, phmax[5] / reps, phmax[6] / reps, phmax[7] / reps,
           load[0]);
    fflush(stdout);
  }
  MPI_Finalize();
  return 0;
}
