// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// Regenerates the choose_order calibration table of src/KIFMM/engine/calibration.cpp.
// Standard configuration: 100000 uniform random points in a cube, charges uniform in [-1,1]
// (bench::uniform(100000, 1)), Laplace, potential + gradient; error = relative RMS error of
// the gradient (force) on 2000 random targets against the direct sum. For each order the leaf
// size with the smallest single-thread CPU time (robust to other load on the machine) is kept.
// Usage (what produced the table):  OMP_NUM_THREADS=1 ./bench/calibrate > table.txt
//
// `calibrate --cost [--orders 3-14] [--reps 3]` regenerates the cost-model constants (kCost in
// calibration.cpp, see cost_model.h): for each order, single-thread CPU time (minimum of
// --reps) of evaluations of uniform points in the cube [-1,1]^3 (neutral charges, sources =
// targets, fixed root) for both boundaries at N = 1e3, 3e3, 1e4, 3e4 (1e5 for orders <= 8, 1e6 for
// order 3) and the depths with 8 to 4000 points per leaf (leaf_size_for_depth), and of
// clustered points (open, bounding cube; two Plummer spheres, N = 1e4, 3e4, leaf sizes 16 ..
// 4096), then the
// non-negative least-squares fit (relative residuals) of cost = point*N + pair*(near +
// self_extra*self) + translation*trans + cell*cells + entry*entries + spill*spilled +
// periodic*[periodic] + periodic_cell*[periodic]*cells to them, with the counts of the actual
// trees (actual_tree_counts, cost_model.h).
// Prints the table rows (ns) on stdout, the measured and fitted times on stderr.
// `--only-n N` measures only the point sets of that size (to add them to a log for --refit).
// `calibrate --refit COST.err [--shared-entry]` fits again from those measured times (stderr of
// --cost; --shared-entry: one entry constant for all orders, the per-pair task overhead), with
// the counts of the trees computed anew (a changed model, no new measurements).
//
// `calibrate --grid-cost [--orders 3-14] [--reps 3]` regenerates kGridCost (calibration.cpp): the
// per-cell, per-occupied-cell and per-point constants of the periodic single-level grid
// (grid_cost_fit below). `calibrate --grid-refit GRID.err` fits them again from the stderr of
// such a run (no new measurements).
//
// `calibrate --grid-fft [--orders 3-14] [--reps 5]` regenerates kGridForwardFft (calibration.cpp):
// single-thread CPU ns of the forward surface transform of one cell (M2LTransform::forward),
// the minimum over --reps timings of passes over 4096 cells of random densities (at least 50 ms
// each). On several ranks every rank transforms every occupied cell (periodic_grid_core.h,
// grid_m2l): the choice counts these transforms 1 / share times (modelled_grid_cost).
//
// `calibrate --periodic-errors [--orders 3-13]` measures the periodic column of the choose_order
// table: relative RMS force error over all points of periodic evaluations (tree of
// choose_tree) of uniform points in the cell [-1,1]^3 (bench::uniform(n, seed), charges made
// neutral) against order 14 (checked against the Ewald sum, periodic_direct_sum, on 200
// targets), the largest of n = 2e4, 1e5 and seeds 1, 2. (The RMS force of random charges is
// dominated by a few close pairs, so errors on a few hundred sampled targets scatter by 2-3x.)
#include "cost_model.h"
#include "direct_sum.h"
#include "fmm_core.h"
#include "kernels.h"
#include "periodic.h"
#include "periodic_grid.h"
#include "m2l_fft.h"
#include "surface.h"

#include "bench_points.h"

#include <time.h>

#include <Eigen/Dense>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <map>
#include <random>
#include <string>

using namespace kifmm;

namespace {

double cpu_now()
{
  timespec t;
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return t.tv_sec + 1e-9 * t.tv_nsec;
}

// The point sets of the cost fit: uniform in [-1,1]^3 (neutral charges; both boundaries, fixed
// root) and clustered ones (open, bounding cube): a Plummer sphere of scale 0.05 in the unit
// cube (the bench/solvers "plummer" case) and bench::plummer (scale 1, cut at r = 50)
struct CostSet {
  std::string name;
  bench::Points p;
  bool clustered;
};

std::vector<CostSet> cost_sets()
{
  std::vector<CostSet> sets;
  for (std::size_t n : {1000, 3000, 10000, 30000, 100000, 1000000}) {
    bench::Points p = bench::uniform(n, 2024);
    double s = 0;
    for (double q : p.q) s += q;
    for (double &q : p.q) q -= s / n;
    sets.push_back({"uniform", std::move(p), false});
  }
  for (std::size_t n : {10000, 30000}) {
    sets.push_back({"plummer0.05", bench::plummer_box(n, 7, 0.05), true});
    sets.push_back({"plummer", bench::plummer(n, 8), true});
  }
  return sets;
}

Options cost_options(const CostSet &set, int order, int leaf, bool periodic)
{
  Options o;
  o.order = order;
  o.leaf_size = leaf;
  if (!set.clustered) {
    o.fixed_root = true;
    o.root_half_width = 1.0;
  }
  o.periodic = periodic;
  return o;
}

constexpr int kCostColumns = 8;
using CostRowValues = std::array<double, kCostColumns>;

// the columns of the fit for one tree: n, near (+ self extra), translations, cells, entries,
// spilled, periodic (1 or 0), periodic cells
CostRowValues cost_columns(const CostSet &set, const Options &o)
{
  const std::size_t n = set.p.size();
  const TreeCounts c = actual_tree_counts(KernelSpec{}, o, n, set.p.xyz.data(), o.leaf_size);
  return {(double) n, c.near_pairs + self_pair_extra() * c.self_pairs, c.translations, c.cells, c.entries,
          c.spilled_translations, c.periodic, c.periodic_cells};
}

// Non-negative least squares of the relative residuals (each equation divided by its time,
// columns scaled to O(1)) by enumeration: the best fit over the subsets of the columns whose
// solution has no negative constant (translation and cell terms are nearly collinear). Prints
// the table row on stdout, measured and fitted times on stderr.
// entry < 0: the entry constant is fitted per order; else it is that (seconds), the same for
// every order (the per-pair task overhead of the near field does not depend on the order). quiet:
// only the sum of squared relative residuals is returned.
double fit_cost_row(int order, const std::vector<CostRowValues> &rows, const std::vector<double> &times,
                    const std::vector<std::string> &labels, double entry = -1, bool quiet = false)
{
  constexpr int K = kCostColumns;
  const int ne = (int) rows.size();
  if (ne == 0) return 0;
  Eigen::MatrixXd A(ne, K);
  Eigen::VectorXd b(ne);
  double colscale[K] = {};
  for (int i = 0; i < ne; ++i)
    for (int k = 0; k < K; ++k) colscale[k] = std::max(colscale[k], rows[i][k] / times[i]);
  for (int k = 0; k < K; ++k)
    if (colscale[k] == 0) colscale[k] = 1;
  for (int i = 0; i < ne; ++i) {
    for (int k = 0; k < K; ++k) A(i, k) = rows[i][k] / times[i] / colscale[k];
    b(i) = entry >= 0 ? 1.0 - entry * rows[i][4] / times[i] : 1.0;
  }
  double c[K] = {}, best = 1e300, rms = 0;
  for (int mask = 1; mask < (1 << K); ++mask) {
    std::vector<int> cols;
    if (entry >= 0 && (mask >> 4 & 1)) continue;
    for (int k = 0; k < K; ++k)
      if (mask >> k & 1) cols.push_back(k);
    Eigen::MatrixXd As(ne, (int) cols.size());
    for (std::size_t j = 0; j < cols.size(); ++j) As.col((int) j) = A.col(cols[j]);
    const Eigen::VectorXd x = As.colPivHouseholderQr().solve(b);
    if ((x.array() < 0).any()) continue;
    const double r = (As * x - b).squaredNorm();
    if (r < best) {
      best = r;
      for (int k = 0; k < K; ++k) c[k] = 0;
      for (std::size_t j = 0; j < cols.size(); ++j) c[cols[j]] = x((int) j) / colscale[cols[j]];
      if (entry >= 0) c[4] = entry;
    }
  }
  if (quiet) {
    for (int i = 0; i < ne; ++i) {
      double f = 0;
      for (int k = 0; k < K; ++k) f += c[k] * rows[i][k];
      rms += (f / times[i] - 1) * (f / times[i] - 1);
    }
    return rms;
  }
  for (int i = 0; i < ne; ++i) {
    double f = 0;
    for (int k = 0; k < K; ++k) f += c[k] * rows[i][k];
    rms += (f / times[i] - 1) * (f / times[i] - 1);
    std::fprintf(stderr,
                 "order %d %s: near %.3g trans %.3g cells %.0f entries %.0f spilled %.3g: measured %.4f s, "
                 "model %.4f s\n",
                 order, labels[i].c_str(), rows[i][1], rows[i][2], rows[i][3], rows[i][4], rows[i][5], times[i], f);
  }
  std::printf("    {%d, %.4g, %.4g, %.4g, %.4g, %.4g, %.4g, %.4g, %.4g},    // [%.3f]\n", order, 1e9 * c[0],
              1e9 * c[1], 1e9 * c[2], 1e9 * c[3], 1e9 * c[4], 1e9 * c[5], 1e9 * c[6], 1e9 * c[7], std::sqrt(rms / ne));
  std::fflush(stdout);
  std::fflush(stderr);
  return rms;
}

std::string cost_label(const CostSet &set, int leaf, int depth, bool periodic)
{
  char b[96];
  std::snprintf(b, sizeof b, "%s N %zu leaf %d depth %d %s", set.name.c_str(), set.p.size(), leaf, depth,
                periodic ? "periodic" : "open");
  return b;
}

int cost_fit(int order_lo, int order_hi, int reps, std::size_t only_n)
{
  std::printf("    // order, point, pair, translation, cell, entry, spill, periodic, periodic cell (ns)   [rms relative residual of the fit]\n");
  const std::vector<CostSet> sets = cost_sets();
  for (int order = order_lo; order <= order_hi; ++order) {
    std::vector<CostRowValues> rows;
    std::vector<double> times;
    std::vector<std::string> labels;
    for (const CostSet &set : sets) {
      const bench::Points &p = set.p;
      const std::size_t n = p.size();
      if (only_n && n != only_n) continue;
      if (n > 30000 && order > 8) continue;
      if (n > 100000 && order > 3) continue;
      std::vector<double> pot(n), g(3 * n);
      std::vector<std::pair<int, int>> trees;    // (leaf, periodic)
      if (set.clustered) {
        for (int leaf : {16, 32, 64, 128, 256, 512, 1024, 2048, 4096}) trees.push_back({leaf, 0});
      } else {
        for (int depth = 0; depth <= 8; ++depth) {
          const double m = n / std::ldexp(1.0, 3 * depth);
          if (m < 8 || m > 4000) continue;
          trees.push_back({leaf_size_for_depth(n, depth), 0});
          trees.push_back({leaf_size_for_depth(n, depth), 1});
        }
      }
      for (auto [leaf, periodic] : trees) {
        const Options o = cost_options(set, order, leaf, periodic);
        auto ev = make_evaluator(KernelSpec{}, o);
        ev->evaluate(n, p.xyz.data(), p.q.data(), n, p.xyz.data(), pot.data(), g.data());    // operators
        double t = 1e30;
        for (int r = 0; r < reps; ++r) {
          const double c0 = cpu_now();
          ev->evaluate(n, p.xyz.data(), p.q.data(), n, p.xyz.data(), pot.data(), g.data());
          t = std::min(t, cpu_now() - c0);
        }
        rows.push_back(cost_columns(set, o));
        times.push_back(t);
        labels.push_back(cost_label(set, leaf, ev->stats().depth, periodic));
      }
    }
    fit_cost_row(order, rows, times, labels);
  }
  return 0;
}

// The fit again from the measured times that `calibrate --cost` printed on stderr (lines
// "order P SET N n leaf L depth D open|periodic: ... measured T s, ..."), with the counts of the
// trees computed anew: for a changed model, without measuring again.
int cost_refit(const char *path, bool shared_entry)
{
  std::FILE *f = std::fopen(path, "r");
  if (!f) {
    std::fprintf(stderr, "calibrate --refit: cannot read %s\n", path);
    return 1;
  }
  const std::vector<CostSet> sets = cost_sets();
  std::map<int, std::vector<CostRowValues>> rows;
  std::map<int, std::vector<double>> times;
  std::map<int, std::vector<std::string>> labels;
  char line[1024];
  while (std::fgets(line, sizeof line, f)) {
    int order, leaf, depth;
    std::size_t n;
    char name[64], boundary[16];
    const char *m = std::strstr(line, "measured ");
    double t;
    if (!m || std::sscanf(line, "order %d %63s N %zu leaf %d depth %d %15[a-z]", &order, name, &n, &leaf, &depth,
                          boundary) != 6 ||
        std::sscanf(m, "measured %lf", &t) != 1)
      continue;
    const CostSet *set = nullptr;
    for (const CostSet &s : sets)
      if (s.name == name && s.p.size() == n) set = &s;
    if (!set) continue;
    const bool periodic = !std::strcmp(boundary, "periodic");
    rows[order].push_back(cost_columns(*set, cost_options(*set, order, leaf, periodic)));
    times[order].push_back(t);
    labels[order].push_back(cost_label(*set, leaf, depth, periodic));
  }
  std::fclose(f);
  // one entry constant for all orders: the one of least summed squared residual among 0 ..
  // 3000 ns
  double entry = -1, best = 1e300;
  if (shared_entry)
    for (double e = 0; e <= 3000e-9; e += 50e-9) {
      double r = 0;
      for (auto &[order, rw] : rows) r += fit_cost_row(order, rw, times[order], labels[order], e, true);
      if (r < best) {
        best = r;
        entry = e;
      }
    }
  std::printf("    // order, point, pair, translation, cell, entry, spill, periodic, periodic cell (ns)   [rms relative residual of the fit]\n");
  if (shared_entry) std::printf("    // entry: one constant for all orders, %.0f ns (least squares over all orders)\n", 1e9 * entry);
  for (auto &[order, r] : rows) fit_cost_row(order, r, times[order], labels[order], entry);
  return 0;
}

// all-target gradient of a periodic evaluation of p at this order (tree of choose_tree)
std::vector<double> periodic_grad(const bench::Points &p, int order)
{
  const std::size_t n = p.size();
  Options o;
  o.order = order;
  o.leaf_size = choose_tree(order, n, true).leaf_size;
  o.fixed_root = true;
  o.root_half_width = 1.0;
  o.periodic = true;
  std::vector<double> pot(n), gr(3 * n);
  make_evaluator(KernelSpec{}, o)->evaluate(n, p.xyz.data(), p.q.data(), n, p.xyz.data(), pot.data(), gr.data());
  return gr;
}

int periodic_errors(int order_lo, int order_hi)
{
  // configurations: n = 2e4, 1e5, seeds 1, 2; reference: order 14 over all targets, itself
  // checked against the Ewald sum on 200 sampled targets
  struct Config {
    std::size_t n;
    unsigned seed;
    bench::Points p;
    std::vector<double> ref;
  };
  std::vector<Config> cfg;
  for (std::size_t n : {20000, 100000})
    for (unsigned seed : {1u, 2u}) {
      Config c{n, seed, bench::uniform(n, seed), {}};
      double s = 0;
      for (double q : c.p.q) s += q;
      for (double &q : c.p.q) q -= s / n;
      c.ref = periodic_grad(c.p, 14);
      const std::size_t ns = 200;
      std::vector<double> tx(3 * ns), rp(ns), rg(3 * ns), sg(3 * ns);
      for (std::size_t i = 0; i < ns; ++i)
        for (int d = 0; d < 3; ++d) {
          tx[3 * i + d] = c.p.xyz[3 * (i * (n / ns)) + d];
          sg[3 * i + d] = c.ref[3 * (i * (n / ns)) + d];
        }
      const double c0[3] = {0, 0, 0};
      periodic_direct_sum(KernelSpec{}, c0, 1.0, n, c.p.xyz.data(), c.p.q.data(), ns, tx.data(), rp.data(), rg.data());
      std::fprintf(stderr, "n %zu seed %u: order-14 reference vs Ewald on %zu targets: %.2e\n", n, seed, ns,
                   bench::relative_difference(sg, rg));
      cfg.push_back(std::move(c));
    }
  std::printf("    // order, periodic relative RMS force error over all points (max of n = 2e4, 1e5, seeds 1, 2)\n");
  for (int order = order_lo; order <= order_hi; ++order) {
    double worst = 0;
    std::string each;
    for (const Config &c : cfg) {
      const double e = bench::relative_difference(periodic_grad(c.p, order), c.ref);
      worst = std::max(worst, e);
      char b[32];
      std::snprintf(b, sizeof b, " %.2e", e);
      each += b;
    }
    std::printf("    {%d, %.2e},    //%s\n", order, worst, each.c_str());
    std::fflush(stdout);
  }
  return 0;
}

// Single-thread CPU seconds of one periodic evaluation of p on the grid of k^3 cells in the
// cell [-1,1]^3 (the kernels made first): the minimum over reps rounds, each the mean over
// evaluations repeated for at least min_time seconds (0: one evaluation)
double grid_evaluation_seconds(int order, int k, const bench::Points &p, int reps, double min_time)
{
  Options o;
  o.order = order;
  o.fixed_root = true;
  o.periodic = true;
  o.periodic_grid = k;
  auto ev = make_evaluator(KernelSpec{}, o);
  const std::size_t n = p.size();
  std::vector<double> pot(n), g(3 * n);
  ev->evaluate(n, p.xyz.data(), p.q.data(), n, p.xyz.data(), pot.data(), g.data());    // kernels
  double best = 1e30;
  for (int r = 0; r < reps; ++r) {
    const double c0 = cpu_now();
    int m = 0;
    do {
      ev->evaluate(n, p.xyz.data(), p.q.data(), n, p.xyz.data(), pot.data(), g.data());
      ++m;
    } while (cpu_now() - c0 < min_time);
    best = std::min(best, (cpu_now() - c0) / m);
  }
  return best;
}

// Non-negative least squares min sum_r ((sum_j x_j A[r][j] - y_r) / w_r)^2 by enumerating the
// active sets (few unknowns); returns x and the RMS relative residual
std::pair<std::vector<double>, double> nnls_small(const std::vector<std::vector<double>> &A, const std::vector<double> &y,
                                                  const std::vector<double> &w)
{
  const std::size_t m = A.empty() ? 0 : A[0].size();
  std::vector<double> best_x(m, 0.0);    // all zero: the fit when no term helps
  double best = 0;
  for (std::size_t r = 0; r < A.size(); ++r) best += std::pow(y[r] / w[r], 2);
  for (unsigned mask = 1; mask < (1u << m); ++mask) {
    std::vector<std::size_t> idx;
    for (std::size_t j = 0; j < m; ++j)
      if (mask & (1u << j)) idx.push_back(j);
    const std::size_t k = idx.size();
    Eigen::MatrixXd N = Eigen::MatrixXd::Zero(k, k);
    Eigen::VectorXd b = Eigen::VectorXd::Zero(k);
    for (std::size_t r = 0; r < A.size(); ++r)
      for (std::size_t a = 0; a < k; ++a) {
        b[a] += A[r][idx[a]] * y[r] / (w[r] * w[r]);
        for (std::size_t c = 0; c < k; ++c) N(a, c) += A[r][idx[a]] * A[r][idx[c]] / (w[r] * w[r]);
      }
    const Eigen::VectorXd x = N.ldlt().solve(b);
    if (x.minCoeff() < 0 || !x.allFinite()) continue;
    std::vector<double> full(m, 0.0);
    for (std::size_t a = 0; a < k; ++a) full[idx[a]] = x[a];
    double rr = 0;
    for (std::size_t r = 0; r < A.size(); ++r) {
      double f = 0;
      for (std::size_t j = 0; j < m; ++j) f += full[j] * A[r][j];
      rr += std::pow((f - y[r]) / w[r], 2);
    }
    if (rr < best) best = rr, best_x = full;
  }
  return {best_x, std::sqrt(best / std::max<std::size_t>(1, A.size()))};
}

// Constants of the periodic single-level grid (kGridCost in calibration.cpp): for each order,
// single-thread CPU times (minimum of reps) of grid evaluations of uniform, Plummer and
// two-cluster points (N = 1e3, 3e3, 1e4, 3e4, and uniform 1e5 at orders <= 6, scaled into the
// cell [-1,1]^3, neutral) on every grid of k^3 cells (k <= 12, 24 at orders <= 6, up to
// max_grid_cells) with 4 to 1000 points per cell on average, minus the octree-fitted point,
// pair and entry terms of their actual counts (grid_counts), fitted by non-negative least
// squares of the relative residuals to a * cells log2(cells) (every cell: its share of the
// convolution, FFTs over the cells) + b * occupied cells (P2M, both surface FFTs and L2P are
// skipped for empty cells) + c * N + s * pair * self pairs (a cell with itself costs more than
// the octree's self-pair weight: the dense cells of clustered points). Prints the rows of
// kGridCost with the RMS residual, overall and per point set, and for comparison the residuals
// of the same fit with a * cells (no log2) and of a * cells alone.
// the point, pair and entry terms of kCost for a grid's counts (the part of its time the grid's
// own constants leave to the octree's)
double octree_terms(int order, double n, double near, double self, double entries)
{
  const CostConstants c = cost_constants(order);
  return c.point * n + c.pair * (near + self_pair_extra() * self) + c.entry * entries;
}

struct GridRun {
  int set;    // 0 uniform, 1 Plummer, 2 two clusters
  double n, cells, occupied, self_pairs, cpu, rest;
};

// Prints the row of kGridCost fitted to the runs of one order (see grid_cost_fit)
void print_grid_row(int order, const std::vector<GridRun> &runs)
{
  const double pair = cost_constants(order).pair;
  // fit of the first `terms` columns (cells, occupied, N, pair * self pairs)
  auto fit = [&](int terms, bool log_cells = true) {
    std::vector<std::vector<double>> A;
    std::vector<double> y, w;
    for (const GridRun &r : runs) {
      const double cols[4] = {log_cells ? grid_convolution_cells(r.cells) : r.cells, r.occupied, r.n, pair * r.self_pairs};
      A.emplace_back(cols, cols + terms);
      y.push_back(r.cpu - r.rest);
      w.push_back(r.cpu);
    }
    std::vector<double> x = nnls_small(A, y, w).first;
    x.resize(4, 0.0);
    return x;
  };
  auto residuals = [&](const std::vector<double> &x, bool log_cells = true) {
    std::array<double, 4> rr{}, cnt{};
    for (const GridRun &r : runs) {
      const double f = r.rest + x[0] * (log_cells ? grid_convolution_cells(r.cells) : r.cells) + x[1] * r.occupied +
                       x[2] * r.n + x[3] * pair * r.self_pairs;
      const double e = std::pow((f - r.cpu) / r.cpu, 2);
      rr[0] += e, cnt[0] += 1;
      rr[1 + r.set] += e, cnt[1 + r.set] += 1;
    }
    for (int i = 0; i < 4; ++i) rr[i] = cnt[i] > 0 ? std::sqrt(rr[i] / cnt[i]) : 0.0;
    return rr;
  };
  const std::vector<double> x = fit(4);
  const std::array<double, 4> r = residuals(x);
  std::printf("    {%d, %.4g, %.4g, %.4g, %.3g},    // [%.3f; %.3f %.3f %.3f] (cells without log2: %.3f; alone: %.3f)\n",
              order, 1e9 * x[0], 1e9 * x[1], 1e9 * x[2], x[3], r[0], r[1], r[2], r[3], residuals(fit(4, false), false)[0],
              residuals(fit(1, false), false)[0]);
  std::fflush(stdout);
}

const char *const kGridSets[3] = {"uniform", "plummer", "clusters"};
const char *const kGridHeader =
    "    // order, cell, occupied cell, point (ns), self   [rms relative residual: all; uniform plummer clusters]\n";

int grid_cost_fit(int order_lo, int order_hi, int reps)
{
  std::printf("%s", kGridHeader);
  for (int order = order_lo; order <= order_hi; ++order) {
    std::vector<GridRun> runs;
    for (int set = 0; set < 3; ++set)
      for (double nd : {1e3, 3e3, 1e4, 3e4, 1e5}) {
        if (nd > 3e4 && (order > 6 || set > 0)) continue;
        const std::size_t n = (std::size_t) nd;
        const bench::Points p = bench::into_periodic_cell(set == 0   ? bench::uniform(n, 7)
                                                              : set == 1 ? kifmm_points::plummer(n, 7)
                                                                         : kifmm_points::two_clusters(n, 7));
        for (int k = 3; k <= std::min(order > 6 ? 12 : 24, max_grid_cells_long(order, nullptr)); ++k) {
          const double m = nd / (k * k * k);
          if (m < 4 || m > 1000) continue;
          const double best = grid_evaluation_seconds(order, k, p, reps, 0.05);
          const double center[3] = {0, 0, 0};
          const TreeCounts t = grid_counts(n, p.xyz.data(), center, 1.0, k);
          const double rest = octree_terms(order, nd, t.near_pairs, t.self_pairs, t.entries);
          runs.push_back({set, nd, t.cells, t.occupied_cells, t.self_pairs, best, rest});
          std::fprintf(stderr,
                       "order %d %s N %zu k %d: occupied %g of %g cells, cpu %.5f s, point/pair/entry terms %.5f s"
                       " (near pairs %.6g, self pairs %.6g, entries %g)\n",
                       order, kGridSets[set], n, k, t.occupied_cells * k * k * k / t.cells, t.cells, best, rest,
                       t.near_pairs, t.self_pairs, t.entries);    // occupied: without the DFT-length factor
        }
      }
    print_grid_row(order, runs);
  }
  return 0;
}

// The same fit from the stderr of an earlier --grid-cost run (the constants of kCost now in use)
int grid_cost_refit(const char *log)
{
  std::FILE *f = std::fopen(log, "r");
  if (!f) {
    std::fprintf(stderr, "cannot read %s\n", log);
    return 1;
  }
  std::vector<std::vector<GridRun>> by_order(32);
  char line[512], set[32];
  while (std::fgets(line, sizeof line, f)) {
    int order, k;
    double n, occupied, cells, cpu, rest, near, self, entries;
    if (std::sscanf(line,
                    "order %d %31s N %lf k %d: occupied %lf of %lf cells, cpu %lf s, point/pair/entry terms %lf s"
                    " (near pairs %lf, self pairs %lf, entries %lf)",
                    &order, set, &n, &k, &occupied, &cells, &cpu, &rest, &near, &self, &entries) != 11 ||
        order < 0 || order >= 32)
      continue;
    int s = 0;
    while (s < 2 && std::strcmp(set, kGridSets[s])) ++s;
    rest = octree_terms(order, n, near, self, entries);
    // occupied cells with the grid's DFT-length factor, as grid_counts counts them now
    by_order[order].push_back({s, n, cells, occupied * cells / ((double) k * k * k), self, cpu, rest});
  }
  std::fclose(f);
  std::printf("%s", kGridHeader);
  for (int order = 0; order < 32; ++order)
    if (!by_order[order].empty()) print_grid_row(order, by_order[order]);
  return 0;
}

// ns per cell of the forward surface transform (what kGridForwardFft holds)
int grid_fft_time(int order_lo, int order_hi, int reps)
{
  const int cells = 4096;
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::printf("    // order, ns per cell (forward surface transform, M2LTransform::forward)\n");
  for (int order = order_lo; order <= order_hi; ++order) {
    const M2LTransform fft(order);
    M2LTransform::Workspace ws(fft);
    const int ns = surface_size(order), nblk = fft.nfreq() / 16;
    std::vector<double> equiv((std::size_t) cells * ns), hat((std::size_t) nblk * 32);
    for (double &x : equiv) x = u(rng);
    double best = 1e30, sink = 0;
    int passes = 1;    // passes over the cells per timing, so that one timing takes at least 50 ms
    for (int rep = 0; rep < reps; ++rep) {
      double t = 0;
      do {
        const std::clock_t c0 = std::clock();
        for (int pass = 0; pass < passes; ++pass)
          for (int b = 0; b < cells; ++b) {
            fft.forward(&equiv[(std::size_t) b * ns], hat.data(), 32, ws);
            sink += hat[b % hat.size()];
          }
        t = double(std::clock() - c0) / CLOCKS_PER_SEC;
        if (t < 0.05) passes *= 2;
      } while (t < 0.05);
      best = std::min(best, t / passes);
    }
    std::printf("    {%d, %.4g},\n", order, 1e9 * best / cells);
    std::fprintf(stderr, "order %d: %.4g s per %d cells, %d passes per timing (checksum %g)\n", order, best, cells,
                 passes, sink);
    std::fflush(stdout);
  }
  return 0;
}

// --orders LO-HI, --reps R and --only-n N after the mode (argv[1]); the others keep their defaults
void parse_options(int argc, char **argv, int &lo, int &hi, int &reps, std::size_t *only_n = nullptr)
{
  for (int i = 2; i + 1 < argc; i += 2) {
    if (!std::strcmp(argv[i], "--orders")) std::sscanf(argv[i + 1], "%d-%d", &lo, &hi);
    else if (!std::strcmp(argv[i], "--reps")) reps = std::atoi(argv[i + 1]);
    else if (only_n && !std::strcmp(argv[i], "--only-n")) *only_n = (std::size_t) std::atof(argv[i + 1]);
  }
}

}    // namespace

int main(int argc, char **argv)
{
  if (argc > 1 && !std::strcmp(argv[1], "--grid-fft")) {
    int lo = 3, hi = 14, reps = 5;
    parse_options(argc, argv, lo, hi, reps);
    return grid_fft_time(lo, hi, reps);
  }
  if (argc > 2 && !std::strcmp(argv[1], "--grid-refit")) return grid_cost_refit(argv[2]);
  if (argc > 1 && !std::strcmp(argv[1], "--grid-cost")) {
    int lo = 3, hi = 14, reps = 3;
    parse_options(argc, argv, lo, hi, reps);
    return grid_cost_fit(lo, hi, reps);
  }
  if (argc > 1 && !std::strcmp(argv[1], "--periodic-errors")) {
    int lo = 3, hi = 14;
    if (argc > 3 && !std::strcmp(argv[2], "--orders")) std::sscanf(argv[3], "%d-%d", &lo, &hi);
    return periodic_errors(lo, hi);
  }
  if (argc > 2 && !std::strcmp(argv[1], "--refit"))
    return cost_refit(argv[2], argc > 3 && !std::strcmp(argv[3], "--shared-entry"));
  if (argc > 1 && !std::strcmp(argv[1], "--cost")) {
    int lo = 3, hi = 14, reps = 3;
    std::size_t only_n = 0;
    parse_options(argc, argv, lo, hi, reps, &only_n);
    return cost_fit(lo, hi, reps, only_n);
  }
  const std::size_t n = 100000, ns = 2000;
  bench::Points p = bench::uniform(n, 1);
  std::vector<std::size_t> sample(n);
  for (std::size_t i = 0; i < n; ++i) sample[i] = i;
  std::mt19937_64 g(99);
  std::shuffle(sample.begin(), sample.end(), g);
  sample.resize(ns);
  std::vector<double> tx(3 * ns), rp(ns), rg(3 * ns);
  for (std::size_t i = 0; i < ns; ++i)
    for (int d = 0; d < 3; ++d) tx[3 * i + d] = p.xyz[3 * sample[i] + d];
  direct_sum(KernelSpec{}, n, p.xyz.data(), p.q.data(), ns, tx.data(), rp.data(), rg.data());
  std::printf("    // order, leaf size, relative RMS force error   (single-thread CPU s of one evaluation)\n");
  for (int order = 3; order <= 14; ++order) {
    int best_leaf = 0;
    double best_t = 1e30, best_err = 0;
    for (int leaf : {64, 128, 256, 512}) {
      Options o;
      o.order = order;
      o.leaf_size = leaf;
      auto ev = make_evaluator(KernelSpec{}, o);
      std::vector<double> pot(n), gr(3 * n);
      ev->evaluate(n, p.xyz.data(), p.q.data(), n, p.xyz.data(), pot.data(), gr.data());    // setup
      double t = 1e30;
      for (int rep = 0; rep < 2; ++rep) {
        const std::clock_t c0 = std::clock();
        ev->evaluate(n, p.xyz.data(), p.q.data(), n, p.xyz.data(), pot.data(), gr.data());
        t = std::min(t, double(std::clock() - c0) / CLOCKS_PER_SEC);
      }
      const double err = bench::sampled_relative_rms(gr, sample, rg);
      std::fprintf(stderr, "order %d leaf %d: %.3f s, error %.2e\n", order, leaf, t, err);
      if (t < best_t) {
        best_t = t;
        best_leaf = leaf;
        best_err = err;
      }
    }
    std::printf("    {%d, %d, %.2e},    // %.3f s\n", order, best_leaf, best_err, best_t);
    std::fflush(stdout);
  }
  return 0;
}
