// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// bench_solvers: one step of the speed-versus-error comparison of long-range solvers
// (kspace kifmm, LAMMPS msm, direct summation; ewald/pppm for periodic cases) on the same
// atoms, in an in-process LAMMPS instance. Driven by run_bench.py (see run.sh, README.md).
//
//   bench_solvers gen --config NAME --n N --seed S --out FILE.data [--mol FILE.mol] [--a A]
//       writes a configuration as an atom_style charge data file (unit box) and prints a JSON
//       line with its metadata (atom count, clump size for clump configurations)
//   bench_solvers ref --data FILE.data --out FILE.ref [--sample S] [--atom-style STYLE]
//                     [--periodic engine|ACC]
//       exact forces: kifmm::direct_sum over all sources on all atoms, or on a random sample of
//       S atoms (whole clumps with --clump K); periodic (p p p, cubic box): "engine" =
//       kifmm::periodic_direct_sum (Ewald sum with libm erfc, double accuracy; sampling as
//       above), or ACC = LAMMPS kspace ewald at accuracy ACC with pair coul/long (whose erfc
//       polynomial limits it to ~1e-7; kept to compare with); prints the wall and CPU time of
//       the direct sum on the targets (time_direct_sum, c_direct_sum); with a sample, also the
//       RMS force over all atoms (f_rms_all, by the engine at order 12 on all atoms, with that
//       evaluation's error on the sample), the denominator of the runs' errors
//   bench_solvers run --data FILE.data --ref FILE.ref --solver SPEC [--repeats R]
//                     [--min-time T] [--clump K] [--atom-style STYLE] [--periodic]
//       one solver: setup (`run 0`), for kifmm the evaluations of its tree tuning (untimed,
//       counted in tune_evaluations and t_tune, with the one that measures the error of a
//       tuned tree; with a given leaf size, the one evaluation that finds nothing to tune;
//       none with tune=no), then R timed force evaluations (pair->compute +
//       kspace->compute, forces only; wall time t_* and process CPU time c_*), the relative
//       RMS error of the last evaluation's total forces against the reference (a sampled
//       reference: mean squared error on the sample over the mean squared force of all
//       atoms), peak memory; prints one line "RESULT {json}"
//
// Solver SPEC (colon-separated key=value after the name):
//   kifmm:acc=1e-5 | kifmm:order=12[:leaf=M][:cache=none][:tune=no]
//   msm:acc=A:cut=C[:order=O]    pair coul/msm with cutoff C * (mean atom spacing),
//                                 kspace msm accuracy A * F_rms (LAMMPS's accuracy is absolute:
//                                 A is then the requested error relative to the RMS force)
//   direct                        kifmm::direct_sum on all atoms (O(N^2), exact); periodic:
//                                 kifmm::periodic_direct_sum (Ewald, exact erfc)
//   coulcut                       pair coul/cut with a cutoff beyond the box (LAMMPS's O(N^2))
//   ewald:acc=A  pppm:acc=A:cut=C[:order=O]  (periodic only; pair coul/long C * spacing,
//                                 table 0; accuracy A * F_rms as for msm)
// All units are LAMMPS lj (qqrd2e = 1), dielectric 1, serial (1 MPI rank).
#include "configurations.h"
#include "kifmm.h"
#include "periodic.h"
#include "kspace_kifmm.h"
#include "lammps_session.h"

#include "atom.h"
#include "comm.h"
#include "domain.h"
#include "force.h"
#include "input.h"
#include "kspace.h"
#include "lammps.h"
#include "pair.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <fstream>
#include <map>
#include <mpi.h>
#include <omp.h>
#include <random>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

using namespace LAMMPS_NS;

namespace {

using Args = std::map<std::string, std::string>;

Args parse_args(int argc, char **argv, int first)
{
  Args a;
  for (int i = first; i < argc; ++i) {
    std::string k = argv[i];
    if (k.rfind("--", 0) != 0) throw std::runtime_error("unexpected argument " + k);
    k = k.substr(2);
    if (i + 1 < argc && std::string(argv[i + 1]).rfind("--", 0) != 0)
      a[k] = argv[++i];
    else
      a[k] = "1";
  }
  return a;
}

std::string get(const Args &a, const std::string &k, const std::string &def = "")
{
  auto it = a.find(k);
  if (it != a.end()) return it->second;
  if (def.empty()) throw std::runtime_error("missing --" + k);
  return def;
}

double wall()
{
  return MPI_Wtime();
}

// CPU time of the process (all its threads): with one thread, the time the evaluation
// occupied a core, insensitive to other processes sharing the cores (wall time is not)
double cpu()
{
  timespec ts;
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

// --------------------------------------------------------------------------- memory

long status_kb(const char *key)
{
  std::ifstream in("/proc/self/status");
  std::string line;
  const size_t n = strlen(key);
  while (std::getline(in, line))
    if (line.compare(0, n, key) == 0) return std::atol(line.c_str() + n + 1);
  return -1;
}

// Resets VmHWM to the current RSS (Linux >= 4.0); returns false where unsupported.
bool reset_peak_rss()
{
  FILE *fp = fopen("/proc/self/clear_refs", "w");
  if (!fp) return false;
  bool ok = fputs("5", fp) >= 0;
  ok = (fclose(fp) == 0) && ok;
  return ok;
}

double load_average()
{
  double l = -1;
  FILE *fp = fopen("/proc/loadavg", "r");
  if (fp) {
    if (fscanf(fp, "%lf", &l) != 1) l = -1;
    fclose(fp);
  }
  return l;
}

// --------------------------------------------------------------------------- configurations

int cmd_gen(const Args &a)
{
  const std::string name = get(a, "config");
  const int n = std::stoi(get(a, "n"));
  const unsigned seed = (unsigned) std::stoul(get(a, "seed", "1"));
  kifmm_test::Configuration c;
  int clump = 1;
  double scale = 1.0;
  if (name == "uniform")
    c = kifmm_test::uniform_cube(n, seed);
  else if (name == "plummer")
    c = kifmm_test::plummer(n, seed, std::stod(get(a, "a", "0.05")));
  else if (name == "clusters")
    c = kifmm_test::two_clusters(n, seed);
  else if (name == "dipoles")
    c = kifmm_test::dipoles(n, seed);
  else if (name == "clumps") {
    auto mol = kifmm_test::read_molecule(get(a, "mol"));
    clump = (int) mol.size();
    const int nclumps = std::max(1, (int) std::lround((double) n / clump));
    c = kifmm_test::clumps(mol, nclumps, seed, std::stod(get(a, "pebble-radius", "0.005")), &scale);
  } else
    throw std::runtime_error("unknown configuration " + name);
  kifmm_test::write_charge_data(get(a, "out"), c);
  double qnet = 0;
  for (double q : c.q) qnet += q;
  printf("RESULT {\"natoms\": %zu, \"clump\": %d, \"clump_scale\": %.6g, \"net_charge\": %.6g}\n",
         c.x.size(), clump, scale, qnet);
  return 0;
}

// --------------------------------------------------------------------------- LAMMPS

// LAMMPS's screen output goes to `screen` ("none": nowhere; LAMMPS errors end the process,
// so the driver keeps it in a file that run_bench.py shows when a run fails)
LAMMPS *open_lammps(const std::string &screen)
{
  return kifmm_test::open_lammps(MPI_COMM_WORLD, {"-screen", screen, "-echo", "none"});
}

void load(LAMMPS *lmp, const Args &a, bool periodic)
{
  kifmm_test::run_lines(lmp, "units lj\natom_style " + get(a, "atom-style", "charge") + "\nboundary " +
               (periodic ? "p p p" : "f f f") + "\natom_modify map array\nread_data " +
               get(a, "data") + "\nthermo_style custom step pe\nthermo_modify norm no\n");
}

// per-tag arrays (index = tag - 1; tags without an atom stay NaN / 0)
struct AtomsByTag {
  std::vector<double> x, q, f;
  int maxtag = 0;
};

AtomsByTag gather(LAMMPS *lmp)
{
  Atom *atom = lmp->atom;
  AtomsByTag g;
  for (int i = 0; i < atom->nlocal; ++i) g.maxtag = std::max(g.maxtag, (int) atom->tag[i]);
  g.x.assign(3 * (size_t) g.maxtag, NAN);
  g.f.assign(3 * (size_t) g.maxtag, NAN);
  g.q.assign(g.maxtag, 0.0);
  for (int i = 0; i < atom->nlocal; ++i) {
    const int t = (int) atom->tag[i] - 1;
    for (int d = 0; d < 3; ++d) {
      g.x[3 * t + d] = atom->x[i][d];
      g.f[3 * t + d] = atom->f[i][d];
    }
    g.q[t] = atom->q ? atom->q[i] : 0.0;
  }
  return g;
}

double mean_spacing(LAMMPS *lmp)
{
  const double *lo = lmp->domain->boxlo, *hi = lmp->domain->boxhi;
  const double vol = (hi[0] - lo[0]) * (hi[1] - lo[1]) * (hi[2] - lo[2]);
  return std::cbrt(vol / (double) lmp->atom->natoms);
}

// --------------------------------------------------------------------------- reference

std::string fmtd(double v)
{
  char b[64];
  snprintf(b, sizeof b, "%.10g", v);
  return b;
}

struct Reference {
  int maxtag = 0;
  double f_rms = 0;    // RMS of |F| over the sampled atoms
  std::vector<double> f;    // 3 per tag, NaN where not sampled
  // RMS of |F| over all atoms (sampled references; 0 = not known): the denominator of the
  // error, as in kspace kifmm's own check, so that a sample that misses the closest pairs
  // does not shrink it
  double f_rms_all = 0;
};

void write_reference(const std::string &path, const Reference &r)
{
  FILE *fp = fopen(path.c_str(), "wb");
  if (!fp) throw std::runtime_error("cannot write " + path);
  const char magic[8] = {'K', 'F', 'M', 'M', 'R', 'E', 'F', '1'};
  fwrite(magic, 1, 8, fp);
  fwrite(&r.maxtag, sizeof(int), 1, fp);
  fwrite(&r.f_rms, sizeof(double), 1, fp);
  fwrite(r.f.data(), sizeof(double), r.f.size(), fp);
  fwrite(&r.f_rms_all, sizeof(double), 1, fp);
  if (fclose(fp) != 0) throw std::runtime_error("cannot write " + path);
}

Reference read_reference(const std::string &path)
{
  FILE *fp = fopen(path.c_str(), "rb");
  if (!fp) throw std::runtime_error("cannot read " + path);
  char magic[8];
  Reference r;
  bool ok = fread(magic, 1, 8, fp) == 8 && memcmp(magic, "KFMMREF1", 8) == 0 &&
      fread(&r.maxtag, sizeof(int), 1, fp) == 1 && fread(&r.f_rms, sizeof(double), 1, fp) == 1;
  if (ok) {
    r.f.resize(3 * (size_t) r.maxtag);
    ok = fread(r.f.data(), sizeof(double), r.f.size(), fp) == r.f.size();
    if (ok && fread(&r.f_rms_all, sizeof(double), 1, fp) != 1) r.f_rms_all = 0;    // older file
  }
  fclose(fp);
  if (!ok) throw std::runtime_error("bad reference file " + path);
  return r;
}

// RMS of |F| over all atoms by the engine at order 12 on all atoms (tree chosen from the
// atoms; periodic: the cubic cell as root), and that evaluation's relative RMS error on the
// sampled atoms of ref (which bounds the RMS's own error: the RMS of a force field off by a
// relative e is off by at most e). For samples at N where the direct sum on all atoms is too
// slow; every solver's error is divided by the same number.
struct AllAtomRms {
  double f_rms = 0, sample_error = 0, time = 0;
};

AllAtomRms all_atom_rms(LAMMPS *lmp, const AtomsByTag &g, bool periodic, const Reference &ref)
{
  const double t0 = wall();
  std::vector<double> x, q;
  std::vector<int> tag;
  for (int t = 0; t < g.maxtag; ++t)
    if (std::isfinite(g.x[3 * t])) {
      x.insert(x.end(), {g.x[3 * t], g.x[3 * t + 1], g.x[3 * t + 2]});
      q.push_back(g.q[t]);
      tag.push_back(t);
    }
  kifmm::KernelSpec k;
  kifmm::Options opt;
  opt.order = 12;
  if (periodic) {
    const double *lo = lmp->domain->boxlo, *hi = lmp->domain->boxhi;
    opt.fixed_root = opt.periodic = true;
    for (int d = 0; d < 3; ++d) opt.root_center[d] = 0.5 * (lo[d] + hi[d]);
    opt.root_half_width = 0.5 * (hi[0] - lo[0]);
  }
  const kifmm::TreeChoice tc = kifmm::choose_tree(k, opt, q.size(), x.data());
  opt.leaf_size = tc.leaf_size;
  opt.periodic_grid = tc.grid;
  std::vector<double> grad(x.size());
  kifmm::make_evaluator(k, opt)->evaluate(q.size(), x.data(), q.data(), q.size(), x.data(), nullptr,
                                          grad.data());
  const double qqrd2e = lmp->force->qqr2e / lmp->force->dielectric;
  double s2 = 0, num = 0, den = 0;
  for (size_t i = 0; i < q.size(); ++i)
    for (int d = 0; d < 3; ++d) {
      const double f = -qqrd2e * q[i] * grad[3 * i + d], fe = ref.f[3 * tag[i] + d];
      s2 += f * f;
      if (std::isfinite(fe)) {
        num += (f - fe) * (f - fe);
        den += fe * fe;
      }
    }
  AllAtomRms r;
  r.f_rms = q.empty() ? 0.0 : std::sqrt(s2 / q.size());
  r.sample_error = den > 0 ? std::sqrt(num / den) : 0.0;
  r.time = wall() - t0;
  return r;
}

int cmd_ref(const Args &a)
{
  const bool periodic = a.count("periodic") > 0;
  LAMMPS *lmp = open_lammps(get(a, "screen", "none"));
  load(lmp, a, periodic);
  Reference ref;
  double t0 = wall(), t_exact = 0, c_exact = 0;
  size_t nsample = 0;
  const std::string pref = periodic ? get(a, "periodic") : "";
  if (periodic && pref != "engine") {
    // LAMMPS's ewald at a tight accuracy with a real-space cutoff of a few spacings
    const double cut = 3.0 * mean_spacing(lmp);
    kifmm_test::run_lines(lmp, "pair_style coul/long " + std::to_string(cut) +
                 "\npair_coeff * *\npair_modify table 0\nkspace_style ewald " + pref +
                 "\nneigh_modify one 100000 page 1000000\nrun 0 post no\n");
    AtomsByTag g = gather(lmp);
    ref.maxtag = g.maxtag;
    ref.f = g.f;
    nsample = lmp->atom->natoms;
  } else {
    AtomsByTag g = gather(lmp);
    ref.maxtag = g.maxtag;
    ref.f.assign(3 * (size_t) g.maxtag, NAN);
    // sources: all charged atoms; targets: all atoms or a random sample (whole clumps)
    std::vector<double> sx, sq;
    for (int t = 0; t < g.maxtag; ++t)
      if (std::isfinite(g.x[3 * t]) && g.q[t] != 0.0) {
        sx.insert(sx.end(), {g.x[3 * t], g.x[3 * t + 1], g.x[3 * t + 2]});
        sq.push_back(g.q[t]);
      }
    const int clump = std::stoi(get(a, "clump", "1"));
    const long want = std::stol(get(a, "sample", "0"));
    std::vector<int> targets;
    if (want <= 0 || want >= g.maxtag) {
      for (int t = 0; t < g.maxtag; ++t)
        if (std::isfinite(g.x[3 * t])) targets.push_back(t);
    } else {
      std::mt19937_64 rng(std::stoul(get(a, "seed", "99")));
      const int nclumps = (g.maxtag + clump - 1) / clump;
      std::vector<int> order(nclumps);
      for (int k = 0; k < nclumps; ++k) order[k] = k;
      std::shuffle(order.begin(), order.end(), rng);
      for (int k = 0; k < nclumps && (long) targets.size() < want; ++k)
        for (int t = order[k] * clump; t < std::min(g.maxtag, (order[k] + 1) * clump); ++t)
          if (std::isfinite(g.x[3 * t])) targets.push_back(t);
      std::sort(targets.begin(), targets.end());
    }
    std::vector<double> tx, grad(3 * targets.size());
    for (int t : targets) tx.insert(tx.end(), {g.x[3 * t], g.x[3 * t + 1], g.x[3 * t + 2]});
    kifmm::KernelSpec k;
    const double te = wall(), ce = cpu();
    if (periodic) {
      const double *lo = lmp->domain->boxlo, *hi = lmp->domain->boxhi;
      const double L = hi[0] - lo[0];
      if (std::fabs(hi[1] - lo[1] - L) > 1e-12 * L || std::fabs(hi[2] - lo[2] - L) > 1e-12 * L)
        throw std::runtime_error("periodic reference: the box must be cubic");
      const double center[3] = {0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1]),
                                0.5 * (lo[2] + hi[2])};
      kifmm::periodic_direct_sum(k, center, 0.5 * L, sq.size(), sx.data(), sq.data(),
                                 targets.size(), tx.data(), nullptr, grad.data());
    } else {
      kifmm::direct_sum(k, sq.size(), sx.data(), sq.data(), targets.size(), tx.data(), nullptr,
                        grad.data());
    }
    t_exact = wall() - te;
    c_exact = cpu() - ce;
    const double qqrd2e = lmp->force->qqr2e / lmp->force->dielectric;
    for (size_t k2 = 0; k2 < targets.size(); ++k2)
      for (int d = 0; d < 3; ++d)
        ref.f[3 * targets[k2] + d] = -qqrd2e * g.q[targets[k2]] * grad[3 * k2 + d];
    nsample = targets.size();
  }
  double s2 = 0;
  size_t cnt = 0;
  for (int t = 0; t < ref.maxtag; ++t)
    if (std::isfinite(ref.f[3 * t])) {
      s2 += ref.f[3 * t] * ref.f[3 * t] + ref.f[3 * t + 1] * ref.f[3 * t + 1] +
          ref.f[3 * t + 2] * ref.f[3 * t + 2];
      ++cnt;
    }
  ref.f_rms = cnt ? std::sqrt(s2 / cnt) : 0.0;
  std::string all;
  if ((bigint) nsample < lmp->atom->natoms) {
    const AllAtomRms r = all_atom_rms(lmp, gather(lmp), periodic, ref);
    ref.f_rms_all = r.f_rms;
    all = ", \"f_rms_all\": " + fmtd(r.f_rms) + ", \"f_rms_all_sample_error\": " + fmtd(r.sample_error) +
        ", \"time_f_rms_all\": " + fmtd(r.time);
  }
  write_reference(get(a, "out"), ref);
  printf("RESULT {\"natoms\": %lld, \"sampled\": %zu, \"f_rms\": %.6g, \"time\": %.4g, "
         "\"time_direct_sum\": %.4g, \"c_direct_sum\": %.6g, \"omp_threads\": %d%s}\n",
         (long long) lmp->atom->natoms, nsample, ref.f_rms, wall() - t0, t_exact, c_exact,
         omp_get_max_threads(), all.c_str());
  delete lmp;
  return 0;
}

// --------------------------------------------------------------------------- run

struct Spec {
  std::string name;
  std::map<std::string, std::string> kv;
  double num(const std::string &k, double def) const
  {
    auto it = kv.find(k);
    return it == kv.end() ? def : std::stod(it->second);
  }
  bool has(const std::string &k) const { return kv.count(k) > 0; }
};

Spec parse_spec(const std::string &s)
{
  Spec sp;
  std::stringstream ss(s);
  std::string item;
  std::getline(ss, sp.name, ':');
  while (std::getline(ss, item, ':')) {
    auto eq = item.find('=');
    if (eq == std::string::npos) throw std::runtime_error("bad solver option " + item);
    sp.kv[item.substr(0, eq)] = item.substr(eq + 1);
  }
  return sp;
}

double median(std::vector<double> v)
{
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n == 0 ? NAN : (n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]));
}

int cmd_run(const Args &a)
{
  const bool periodic = a.count("periodic") > 0;
  const Spec sp = parse_spec(get(a, "solver"));
  const int min_repeats = std::stoi(get(a, "repeats", "3"));
  const double min_time = std::stod(get(a, "min-time", "1.0"));
  const int clump = std::stoi(get(a, "clump", "1"));
  // the reference's RMS force only (the forces are read after the memory measurement)
  double f_rms = 0;
  {
    Reference head = read_reference(get(a, "ref"));
    f_rms = head.f_rms;
  }

  LAMMPS *lmp = open_lammps(get(a, "screen", "none"));
  load(lmp, a, periodic);
  const double spacing = mean_spacing(lmp);
  const long rss0 = status_kb("VmRSS:");
  const bool hwm_reset = reset_peak_rss();
  const double load0 = load_average();

  std::string extra;    // solver parameters for the JSON output
  bool lammps_solver = true;
  kifmm::Choice choice{0, 0, -1};
  if (sp.name == "kifmm") {
    // periodic cases: the style itself checks what it supports (p p p, cubic box)
    std::string acc = sp.has("acc") ? sp.kv.at("acc") : "1e-6";
    std::string mod;
    if (sp.has("order")) {
      mod += " order " + sp.kv.at("order");
      choice.order = std::stoi(sp.kv.at("order"));
    } else {
      choice = kifmm::choose_order(kifmm::KernelSpec{}, std::stod(acc));
    }
    if (sp.has("leaf")) mod += " leaf " + sp.kv.at("leaf");
    if (sp.has("cache")) mod += " cache " + sp.kv.at("cache");
    if (sp.has("tune")) mod += " tune " + sp.kv.at("tune");
    kifmm_test::run_lines(lmp, "pair_style none\nkspace_style kifmm " + acc + "\n" +
                 (mod.empty() ? "" : "kspace_modify kifmm" + mod + "\n"));
    extra = ", \"order\": " + std::to_string(choice.order) +
        ", \"calibrated_error\": " + fmtd(choice.measured_error);
  } else if (sp.name == "msm") {
    if (periodic) throw std::runtime_error("msm is run for open boundaries only here");
    const double cut = sp.num("cut", 3.0) * spacing;
    const double acc = sp.num("acc", 1e-4) * f_rms;
    std::string s = "pair_style coul/msm " + fmtd(cut) + "\npair_coeff * *\npair_modify table 0\n" +
        "kspace_style msm " + fmtd(acc) + "\nkspace_modify cutoff/adjust no\n";
    if (sp.has("order")) s += "kspace_modify order " + sp.kv.at("order") + "\n";
    s += "neighbor " + fmtd(0.1 * cut) + " bin\nneigh_modify one 200000 page 2000000\n";
    kifmm_test::run_lines(lmp, s);
    extra = ", \"cutoff\": " + fmtd(cut) + ", \"accuracy_abs\": " + fmtd(acc);
  } else if (sp.name == "ewald" || sp.name == "pppm") {
    if (!periodic) throw std::runtime_error(sp.name + " is run for periodic cases only");
    const double cut = sp.num("cut", 3.0) * spacing;
    const double acc = sp.num("acc", 1e-4) * f_rms;
    kifmm_test::run_lines(lmp, "pair_style coul/long " + fmtd(cut) + "\npair_coeff * *\npair_modify table 0\n" +
                 "kspace_style " + sp.name + " " + fmtd(acc) + "\nneighbor " + fmtd(0.1 * cut) +
                 " bin\nneigh_modify one 200000 page 2000000\n");
    if (sp.has("order")) kifmm_test::run_lines(lmp, "kspace_modify order " + sp.kv.at("order") + "\n");
    extra = ", \"cutoff\": " + fmtd(cut) + ", \"accuracy_abs\": " + fmtd(acc);
  } else if (sp.name == "coulcut") {
    const double *lo = lmp->domain->boxlo, *hi = lmp->domain->boxhi;
    double diag = 0;
    for (int d = 0; d < 3; ++d) diag += (hi[d] - lo[d]) * (hi[d] - lo[d]);
    const double cut = 1.01 * std::sqrt(diag);
    kifmm_test::run_lines(lmp, "pair_style coul/cut " + fmtd(cut) + "\npair_coeff * *\nneighbor " +
                 fmtd(0.01 * cut) + " nsq\nneigh_modify one 2000000 page 20000000\n");
  } else if (sp.name == "direct") {
    lammps_solver = false;
  } else {
    throw std::runtime_error("unknown solver " + sp.name);
  }

  std::vector<double> t_eval, t_pair, t_kspace, c_eval, c_pair, c_kspace;
  double t_setup = 0, c_setup = 0, t_tune = 0;
  int tune_evaluations = 0;
  AtomsByTag g;
  if (lammps_solver) {
    double t0 = wall(), c0 = cpu();
    kifmm_test::run_lines(lmp, "run 0 post no");
    t_setup = wall() - t0;
    c_setup = cpu() - c0;
    Atom *atom = lmp->atom;
    Force *force = lmp->force;
    auto zero_forces = [&] {
      const int nall = atom->nlocal + (force->newton ? atom->nghost : 0);
      for (int i = 0; i < nall; ++i) atom->f[i][0] = atom->f[i][1] = atom->f[i][2] = 0.0;
    };
    // kifmm's tree tuning (tune yes): the evaluations that time the trees near the modelled
    // choice, and the one that measures the error of a tuned tree other than the modelled
    // choice, come first, so that the timed ones are those of the rest of a run (reported as
    // tune_evaluations and t_tune)
    if (auto *kk = dynamic_cast<KSpaceKIFMM *>(force->kspace)) {
      const double tt = wall();
      while (kk->settling() && tune_evaluations < 1 + (1 + kifmm::kTuneRepeats) * kifmm::kTuneTrees) {
        zero_forces();
        force->kspace->compute(0, 0);
        ++tune_evaluations;
      }
      t_tune = wall() - tt;
    }
    const double t_start = wall();
    for (int r = 0; r < 1000; ++r) {
      double tb = wall(), cb = cpu();
      zero_forces();
      double tp = wall(), cp = cpu();
      if (force->pair) force->pair->compute(0, 0);
      double tk = wall(), ck = cpu();
      if (force->kspace) force->kspace->compute(0, 0);
      double te = wall(), ce = cpu();
      if (force->newton) lmp->comm->reverse_comm();
      double tr = wall(), cr = cpu();
      t_pair.push_back(tk - tp);
      t_kspace.push_back(te - tk);
      t_eval.push_back(tr - tb);
      c_pair.push_back(ck - cp);
      c_kspace.push_back(ce - ck);
      c_eval.push_back(cr - cb);
      if ((int) t_eval.size() >= min_repeats && wall() - t_start >= min_time) break;
      if (wall() - t_start > 30 * min_time && (int) t_eval.size() >= 1) break;
    }
    g = gather(lmp);
  } else {
    g = gather(lmp);
    std::vector<double> sx, sq;
    for (int t = 0; t < g.maxtag; ++t)
      if (std::isfinite(g.x[3 * t]) && g.q[t] != 0.0) {
        sx.insert(sx.end(), {g.x[3 * t], g.x[3 * t + 1], g.x[3 * t + 2]});
        sq.push_back(g.q[t]);
      }
    std::vector<double> grad(3 * (size_t) g.maxtag);
    const double *lo = lmp->domain->boxlo, *hi = lmp->domain->boxhi;
    const double center[3] = {0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1]), 0.5 * (lo[2] + hi[2])};
    const double t_start = wall();
    for (int r = 0; r < 1000; ++r) {
      double tb = wall(), cb = cpu();
      if (periodic)    // the exact periodic sum: Ewald with libm erfc (O(N^2) real space)
        kifmm::periodic_direct_sum(kifmm::KernelSpec{}, center, 0.5 * (hi[0] - lo[0]), sq.size(),
                                   sx.data(), sq.data(), g.maxtag, g.x.data(), nullptr,
                                   grad.data());
      else
        kifmm::direct_sum(kifmm::KernelSpec{}, sq.size(), sx.data(), sq.data(), g.maxtag,
                          g.x.data(), nullptr, grad.data());
      t_eval.push_back(wall() - tb);
      c_eval.push_back(cpu() - cb);
      if ((int) t_eval.size() >= min_repeats && wall() - t_start >= min_time) break;
      if (wall() - t_start > 30 * min_time && (int) t_eval.size() >= 1) break;
    }
    const double qqrd2e = lmp->force->qqr2e / lmp->force->dielectric;
    for (int t = 0; t < g.maxtag; ++t)
      for (int d = 0; d < 3; ++d) g.f[3 * t + d] = -qqrd2e * g.q[t] * grad[3 * t + d];
  }
  const long hwm = status_kb("VmHWM:");
  const double load1 = load_average();

  // errors of the total forces against the reference (sampled atoms only)
  Reference ref = read_reference(get(a, "ref"));
  if (ref.maxtag != g.maxtag) throw std::runtime_error("reference does not match the data file");
  double num = 0, den = 0, fmax_err = 0;
  size_t ns = 0;
  std::map<int, std::array<double, 6>> net;    // clump -> sum F, sum F_exact
  std::map<int, int> net_count;
  for (int t = 0; t < g.maxtag; ++t) {
    if (!std::isfinite(ref.f[3 * t])) continue;
    ++ns;
    for (int d = 0; d < 3; ++d) {
      const double e = g.f[3 * t + d] - ref.f[3 * t + d];
      num += e * e;
      den += ref.f[3 * t + d] * ref.f[3 * t + d];
      fmax_err = std::max(fmax_err, std::fabs(e));
    }
    if (clump > 1) {
      auto &s = net[t / clump];
      for (int d = 0; d < 3; ++d) {
        s[d] += g.f[3 * t + d];
        s[3 + d] += ref.f[3 * t + d];
      }
      ++net_count[t / clump];
    }
  }
  double err = den > 0 ? std::sqrt(num / den) : std::sqrt(num);
  if (ref.f_rms_all > 0 && ns > 0) {
    // sampled reference: the sample's mean squared error over the mean squared force of all
    // atoms (the sample's own ratio stays as error_sample); the RMS of this solver's forces
    // over all atoms is recorded next to the reference's
    double s2 = 0;
    size_t n_all = 0;
    for (int t = 0; t < g.maxtag; ++t)
      if (std::isfinite(g.f[3 * t])) {
        s2 += g.f[3 * t] * g.f[3 * t] + g.f[3 * t + 1] * g.f[3 * t + 1] + g.f[3 * t + 2] * g.f[3 * t + 2];
        ++n_all;
      }
    extra += ", \"error_sample\": " + fmtd(err) + ", \"error_denominator\": \"all atoms\", \"f_rms_all\": " +
        fmtd(ref.f_rms_all) + ", \"f_rms_all_solver\": " + fmtd(n_all ? std::sqrt(s2 / n_all) : 0.0);
    err = std::sqrt(num / ns) / ref.f_rms_all;
  }
  double cnum = 0, cden = 0, cfnet = 0;
  int nclumps = 0;
  for (auto &[c, s] : net) {
    if (net_count[c] != std::min(clump, g.maxtag - c * clump)) continue;    // whole clumps only
    ++nclumps;
    for (int d = 0; d < 3; ++d) {
      cnum += (s[d] - s[3 + d]) * (s[d] - s[3 + d]);
      cden += s[3 + d] * s[3 + d];
    }
  }
  if (nclumps > 0) cfnet = std::sqrt(cden / nclumps);

  // the kifmm style's engine statistics (of the last evaluation)
  if (auto *kk = dynamic_cast<KSpaceKIFMM *>(lmp->force->kspace)) {
    const kifmm::Stats &st = kk->engine_stats();
    extra += ", \"tune_evaluations\": " + std::to_string(tune_evaluations) + ", \"t_tune\": " + fmtd(t_tune) +
        ", \"leaf\": " + std::to_string(kk->engine_leaf_size()) + ", \"grid\": " + std::to_string(kk->engine_grid()) +
        ", \"order_used\": " + std::to_string(kk->engine_order());
    extra += ", \"depth\": " + std::to_string(st.depth) + ", \"leaves\": " +
        std::to_string(st.n_leaves) + ", \"operator_mb\": " + fmtd(st.operator_bytes / 1048576.0) +
        ", \"tree_mb\": " + fmtd(st.tree_bytes / 1048576.0);
  }

  const bool finite = std::isfinite(err);
  printf("RESULT {\"solver\": \"%s\", \"spec\": \"%s\", \"natoms\": %lld, \"sampled\": %zu, "
         "\"error\": %.6e, \"max_abs_error\": %.6e, \"f_rms\": %.6e, "
         "\"clump_error\": %s, \"clumps_sampled\": %d, \"clump_f_rms\": %.6e, "
         "\"t_eval\": %.6e, \"t_eval_min\": %.6e, \"t_pair\": %.6e, \"t_kspace\": %.6e, "
         "\"repeats\": %zu, \"t_setup\": %.6e, \"mem_mb\": %.3f, \"rss_base_mb\": %.3f, "
         "\"hwm_reset\": %s, \"omp_threads\": %d, \"load\": [%.2f, %.2f], "
         "\"spacing\": %.6e, \"c_eval\": %.6e, \"c_eval_min\": %.6e, \"c_pair\": %.6e, "
         "\"c_kspace\": %.6e, \"c_setup\": %.6e%s}\n",
         sp.name.c_str(), get(a, "solver").c_str(), (long long) lmp->atom->natoms, ns,
         finite ? err : -1.0, fmax_err, std::sqrt(den / std::max<size_t>(ns, 1)),
         nclumps > 0 ? fmtd(cden > 0 ? std::sqrt(cnum / cden) : std::sqrt(cnum)).c_str() : "null",
         nclumps, cfnet, median(t_eval), *std::min_element(t_eval.begin(), t_eval.end()),
         t_pair.empty() ? 0.0 : median(t_pair), t_kspace.empty() ? 0.0 : median(t_kspace),
         t_eval.size(), t_setup, std::max(0L, hwm - rss0) / 1024.0, rss0 / 1024.0,
         hwm_reset ? "true" : "false", omp_get_max_threads(), load0, load1, spacing,
         median(c_eval), *std::min_element(c_eval.begin(), c_eval.end()),
         c_pair.empty() ? 0.0 : median(c_pair), c_kspace.empty() ? 0.0 : median(c_kspace),
         c_setup, extra.c_str());
  fflush(stdout);
  delete lmp;
  return finite ? 0 : 3;
}

}    // namespace

int main(int argc, char **argv)
{
  MPI_Init(&argc, &argv);
  int rc = 0;
  try {
    if (argc < 2) throw std::runtime_error("usage: bench_solvers gen|ref|run --key value ...");
    const std::string cmd = argv[1];
    Args a = parse_args(argc, argv, 2);
    if (cmd == "gen")
      rc = cmd_gen(a);
    else if (cmd == "ref")
      rc = cmd_ref(a);
    else if (cmd == "run")
      rc = cmd_run(a);
    else
      throw std::runtime_error("unknown command " + cmd);
  } catch (std::exception &e) {
    fprintf(stderr, "bench_solvers: %s\n", e.what());
    rc = 2;
  }
  MPI_Finalize();
  return rc;
}
