// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// kspace_style kifmm with the rigid clumps of fix clump/rigid: the pairs inside a clump are left
// out of the long-range sum (forces, energy, virial, per-atom values equal LAMMPS's own pair
// coul/cut over the same clumps, whose intra-clump pairs fix clump/rigid excludes), also with
// periodic boundaries; a spinning clump keeps its rotational energy under fix kifmm/stride; a
// gas of dipole clumps drifts under a stride about as much as without; the requested accuracy
// holds for the clumps' net forces and torques, also with an explicit leaf size; polarizable
// pebbles (fix kifmm/polarize) see the field of their own clump and change nothing else; a
// permanent dipole on a pebble, and a clump that lost pebbles, are errors; an unreachable
// accuracy is a warning.
#include "clump_test_util.h"
#include "lammps_fixture.h"

#include "atom.h"
#include "comm.h"
#include "lammps.h"
#include "library.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <mpi.h>
#include <random>
#include <set>
#include <sstream>

using namespace kifmm_test;
using clump_test::clump_rows;

namespace {

// n dipole clumps (potentials/dipole3.mol: pebbles -1, 0, +1 at spacing 0.01, radius 0.005) on
// a jittered cubic lattice of spacing a, random orientations, in lj units (qqrd2e = 1)
// (margin: free space around the lattice in the box)
std::string dipole_gas(int n, double a, const std::string &boundary = "f f f", double margin = 0.0,
                       unsigned seed = 7, const std::string &atom_style = "hybrid sphere charge")
{
  const int side = (int) std::ceil(std::cbrt((double) n));
  const double box = side * a + margin;
  std::ostringstream s;
  s.precision(17);
  // shrink-wrapped boundaries are set after the clumps are made (create_atoms shrinks the box)
  const bool shrink = boundary.find('s') != std::string::npos;
  s << "units lj\natom_style " << atom_style << "\natom_modify map array\nboundary "
    << (shrink ? "f f f" : boundary) << "\nregion box block " << -margin << ' ' << box << ' ' << -margin << ' ' << box << ' '
    << -margin << ' ' << box
    << "\ncreate_box 2 box\nfix mol all property/atom mol ghost yes\nmolecule dip "
    << clump_test::potentials << "/dipole3.mol\n";
  std::mt19937_64 g(seed);
  std::uniform_real_distribution<double> jitter(-0.2 * a, 0.2 * a), angle(0.0, 360.0),
      axis(-1.0, 1.0);
  int made = 0;
  for (int i = 0; i < side && made < n; ++i)
    for (int j = 0; j < side && made < n; ++j)
      for (int k = 0; k < side && made < n; ++k, ++made) {
        double ax[3] = {axis(g), axis(g), axis(g)};
        s << "create_atoms 0 single " << (i + 0.5) * a + jitter(g) << ' ' << (j + 0.5) * a + jitter(g)
          << ' ' << (k + 0.5) * a + jitter(g) << " mol dip " << 1000 + made << " rotate "
          << angle(g) << ' ' << ax[0] << ' ' << ax[1] << ' ' << ax[2] + 1e-3 << " units box\n";
      }
  if (shrink) s << "change_box all boundary " << boundary << "\n";
  s << "comm_modify vel yes cutoff 0.05\nneighbor 0.01 bin\nneigh_modify one 10000 page 200000\n"
       "compute pv all pressure NULL pair kspace\n"
       "thermo_style custom step pe elong c_pv\n"
       "thermo_modify norm no\n";
  return s.str();
}

double rel_rms(const std::map<int, std::vector<double>> &a, const std::map<int, std::vector<double>> &b,
               int c0)
{
  double num = 0, den = 0;
  for (const auto &[mol, rb] : b) {
    const auto &ra = a.at(mol);
    for (int d = 0; d < 3; ++d) {
      num += (ra[c0 + d] - rb[c0 + d]) * (ra[c0 + d] - rb[c0 + d]);
      den += rb[c0 + d] * rb[c0 + d];
    }
  }
  return std::sqrt(num / den);
}

// The pairs of charges inside the clumps of dipole_gas (3 consecutive atom IDs per clump,
// charges -1 0 +1, lj units): per atom their force, per-atom virial 1/2 sum_j r_a F_b (xx yy zz
// xy xz yz) and, summed, their energy and virial
struct IntraClumpCharges {
  std::map<int, Vec3> f;
  std::map<int, std::array<double, 6>> v;
  double energy = 0;
  std::array<double, 6> virial{};
};
IntraClumpCharges intra_clump_charges(const std::map<int, Vec3> &x, int nclumps)
{
  IntraClumpCharges out;
  const double q[3] = {-1, 0, 1};
  const int ab[6][2] = {{0, 0}, {1, 1}, {2, 2}, {0, 1}, {0, 2}, {1, 2}};
  for (const auto &[id, xi] : x) out.f[id] = {0, 0, 0}, out.v[id] = {};
  for (int c = 0; c < nclumps; ++c)
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) {
        if (a == b) continue;
        const int i = 3 * c + a + 1, j = 3 * c + b + 1;
        Vec3 r, f;
        double r2 = 0;
        for (int d = 0; d < 3; ++d) r[d] = x.at(i)[d] - x.at(j)[d], r2 += r[d] * r[d];
        const double rr = std::sqrt(r2);
        for (int d = 0; d < 3; ++d) f[d] = q[a] * q[b] * r[d] / (r2 * rr), out.f[i][d] += f[d];
        out.energy += 0.5 * q[a] * q[b] / rr;
        for (int m = 0; m < 6; ++m) {
          out.v[i][m] += 0.5 * r[ab[m][0]] * f[ab[m][1]];
          out.virial[m] += 0.5 * r[ab[m][0]] * f[ab[m][1]];
        }
      }
  return out;
}

class ClumpKifmm : public LammpsFixture {
 protected:
  // per atom: forces, energy, virial (xx yy zz xy xz yz) of compute pe/atom and stress/atom
  struct Run {
    std::map<int, Vec3> f;
    std::map<int, std::array<double, 7>> peratom;    // pe, stress * volume (6)
    double energy = 0;
    std::array<double, 6> p{};
  };
  Run run0(const std::string &forces)
  {
    commands(forces + "\nthermo_style custom step pe c_pv[1] c_pv[2] c_pv[3] c_pv[4] c_pv[5] c_pv[6]\n"
             "run 0 post no");
    Run r;
    r.f = forces_by_id();
    r.energy = thermo("pe");
    for (int k = 0; k < 6; ++k) r.p[k] = evaluate("c_pv[" + std::to_string(k + 1) + "]");
    auto *a = lmp->atom;
    auto *pe = static_cast<double *>(lammps_extract_compute(lmp, "pea", LMP_STYLE_ATOM, LMP_TYPE_VECTOR));
    auto **st = static_cast<double **>(lammps_extract_compute(lmp, "sta", LMP_STYLE_ATOM, LMP_TYPE_ARRAY));
    for (int i = 0; i < a->nlocal; ++i) {
      std::array<double, 7> v{};
      v[0] = pe[i];
      for (int k = 0; k < 6; ++k) v[1 + k] = st[i][k];
      r.peratom[(int) a->tag[i]] = v;
    }
    return r;
  }
  std::string clump_fix = "fix c all clump/rigid density 2500";
};

}    // namespace

// The sum kspace kifmm computes for clumps is that of LAMMPS's pair coul/cut (cutoff beyond the
// box) over the same clumps: fix clump/rigid excludes intra-clump pairs from the pair style, so
// both leave them out. Forces, energy, pressure tensor, per-atom energy and virial.
TEST_F(ClumpKifmm, IntraClumpPairsAreLeftOutAsForPairStyles)
{
  const std::string computes =
      "compute pea all pe/atom\ncompute sta all stress/atom NULL pair kspace\n";
  commands(dipole_gas(40, 0.06) + clump_fix + "\n" + computes);
  Run exact = run0("pair_style coul/cut 10.0\npair_coeff * *\nkspace_style none");
  create();
  commands(dipole_gas(40, 0.06) + clump_fix + "\n" + computes);
  Run fmm = run0("pair_style zero 0.1\npair_coeff * *\nkspace_style kifmm 1e-9");
  // the intra-clump energy (-50 per clump: pairs -1/+1 at 0.02 and +-1/0) is not in the sum
  EXPECT_NEAR(fmm.energy, exact.energy, 1e-7 * std::fabs(exact.energy) + 1e-9);
  EXPECT_LT(std::fabs(exact.energy), 100.0) << "inter-clump energy only (the intra-clump pairs: -2000)";
  EXPECT_LT(relative_force_error(fmm.f, exact.f), 1e-7);
  double pscale = 0;
  for (double v : exact.p) pscale = std::max(pscale, std::fabs(v));
  for (int k = 0; k < 6; ++k) EXPECT_NEAR(fmm.p[k], exact.p[k], 1e-7 * pscale) << "component " << k;
  double num = 0, den = 0;
  for (const auto &[id, v] : exact.peratom)
    for (int k = 0; k < 7; ++k) {
      num += (fmm.peratom.at(id)[k] - v[k]) * (fmm.peratom.at(id)[k] - v[k]);
      den += v[k] * v[k];
    }
  EXPECT_LT(std::sqrt(num / den), 1e-7) << "per-atom energy and virial";
}

// Periodic boundaries: the clumps' sum is the sum of the same atoms without clumps minus each
// intra-clump pair at its own (nearest-image) distance; energy, forces and scalar pressure.
TEST_F(ClumpKifmm, PeriodicSumLeavesOutTheNearestImageOfIntraClumpPairs)
{
  const std::string kspace = "pair_style zero 0.1\npair_coeff * *\nkspace_style kifmm 1e-10\n";
  commands(dipole_gas(27, 0.05, "p p p") + kspace + "run 0 post no");
  const auto free_f = forces_by_id();
  const double free_e = thermo("elong"), free_p = evaluate("c_pv");
  const auto x = positions_by_id();
  const double volume = evaluate("vol");
  create();
  commands(dipole_gas(27, 0.05, "p p p") + clump_fix + "\n" + kspace + "run 0 post no");
  const auto f = forces_by_id();
  // pairs inside a clump: 3 consecutive atom IDs (1..3, 4..6, ...), charges -1 0 +1
  std::map<int, Vec3> expect = free_f;
  double e_intra = 0;
  const double q[3] = {-1, 0, 1};
  for (int c = 0; c < 27; ++c)
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) {
        if (a == b) continue;
        const int i = 3 * c + a + 1, j = 3 * c + b + 1;
        Vec3 r;
        double r2 = 0;
        for (int d = 0; d < 3; ++d) {
          r[d] = x.at(i)[d] - x.at(j)[d];
          r2 += r[d] * r[d];
        }
        const double rr = std::sqrt(r2);
        for (int d = 0; d < 3; ++d) expect[i][d] -= q[a] * q[b] * r[d] / (r2 * rr);
        e_intra += 0.5 * q[a] * q[b] / rr;
      }
  EXPECT_LT(relative_force_error(f, expect), 1e-8);
  EXPECT_NEAR(thermo("elong"), free_e - e_intra, 1e-8 * std::fabs(e_intra));
  // coulomb: trace of the virial = energy, P = U / (3 V) (virial part of the pressure)
  EXPECT_NEAR(evaluate("c_pv"), free_p - e_intra / (3 * volume), 1e-8 * std::fabs(e_intra / volume));
}

// One freely spinning dipole clump (no other atom): no long-range force acts on it, so its
// rotational energy stays constant under any stride and mode (held pebble forces used to carry
// the intra-clump forces, which turned into a torque as the clump rotated).
TEST_F(ClumpKifmm, SpinningClumpKeepsItsRotationalEnergyUnderAnyStride)
{
  for (const char *stride : {"", "1", "5", "10", "5 mode impulse", "10 mode impulse"}) {
    create();
    commands("units si\natom_style hybrid sphere charge\natom_modify map array\nboundary f f f\n"
             "region box block -1 1 -1 1 -1 1 units box\ncreate_box 2 box\n"
             "fix mol all property/atom mol ghost yes\nmolecule dip " + clump_test::potentials +
             "/dipole3.mol\ncreate_atoms 0 single 0 0 0 mol dip 1 rotate 30 0 0 1\n"
             "set type 2 charge 1e-3\nset atom 1 charge -1e-3\n"
             "pair_style zero 0.1\npair_coeff * *\nkspace_style kifmm 1e-5\n"
             "fix c all clump/rigid density 2500 integrator nve\n"
             "variable vx atom -100*y\nvariable vy atom 100*x\nvelocity all set v_vx v_vy 0\n"
             "timestep 1e-4\nthermo_style custom step f_c[3]\n");
    if (*stride) command(std::string("fix st all kifmm/stride ") + stride);
    command("run 0 post no");
    const double e0 = evaluate("f_c[3]");
    command("run 1000 post no");
    const double e1 = evaluate("f_c[3]");
    SCOPED_TRACE(testing::Message() << "stride '" << stride << "'");
    EXPECT_GT(e0, 1e-3);
    EXPECT_NEAR(e1 / e0, 1.0, 1e-6);
    // the clump's net force is zero to round-off of the intra-clump forces (2.2e7 N here)
    auto rows = clump_rows(lmp, "c");
    ASSERT_EQ(rows.size(), 1u);
    for (int d = 0; d < 3; ++d) EXPECT_LT(std::fabs(rows.begin()->second[clump_test::FX + d]), 1e-6);
  }
}

// 200 free dipole clumps (translation, rotation, dipole-dipole forces between clumps): the
// energy drift with a stride (hold and impulse) against the drift of the run without.
TEST_F(ClumpKifmm, DipoleGasEnergyDriftUnderAStrideIsCloseToTheRunWithout)
{
  auto drift = [&](const std::string &stride) {
    create();
    commands(dipole_gas(200, 1.0, "f f f", 2.0) + clump_fix + " integrator nve\n" +
             "pair_style zero 0.1\npair_coeff * *\nkspace_style kifmm 1e-6\n"
             "velocity all create 1e-6 4928 loop geom\ntimestep 1e-4\n"
             "variable etot equal f_c[4]+elong\nthermo_style custom step f_c[4] elong v_etot\n"
             "thermo_modify norm no\n");
    if (!stride.empty()) command("fix st all kifmm/stride " + stride + " energy every");
    command("run 0 post no");
    const double e0 = evaluate("v_etot"), ke0 = evaluate("f_c[4]");
    double worst = 0;
    for (int k = 0; k < 20; ++k) {
      command("run 50 post no");
      worst = std::max(worst, std::fabs(evaluate("v_etot") - e0));
    }
    std::printf("  stride '%s': E0 %.6g KE0 %.6g, largest |E - E0| %.3e (%.3e of KE0)\n",
                stride.c_str(), e0, ke0, worst, worst / ke0);
    EXPECT_GT(ke0, 0.1);
    return worst / ke0;
  };
  const double exact = drift(""), hold = drift("5"), impulse = drift("5 mode impulse");
  // impulse (kicks of N times the force, time-reversible) stays within 10x the run without;
  // hold applies forces of up to N-1 steps ago to clumps that turn meanwhile (first order in
  // the stride: here 0.07 rad of rotation per stride), a drift of a few 1e-3 of the kinetic
  // energy over the run. Held intra-clump forces (the pebble forces without the exclusion)
  // changed the energy by orders of magnitude more than it holds.
  EXPECT_LT(exact, 1e-4);
  EXPECT_LT(impulse, 10 * exact + 1e-4);
  EXPECT_LT(hold, 1e-2);
}

// The clumps (molecule IDs) whose atoms are owned by more than one rank
static int split_clumps(LAMMPS_NS::LAMMPS *lmp)
{
  std::vector<double> mine;
  for (int i = 0; i < lmp->atom->nlocal; ++i)
    mine.insert(mine.end(), {(double) lmp->atom->molecule[i], (double) lmp->comm->me});
  const std::vector<double> all = kifmm_test::gather_rows(lmp, mine, 2);
  std::map<int, std::set<int>> ranks;
  for (std::size_t k = 0; k + 2 <= all.size(); k += 2) ranks[(int) all[k]].insert((int) all[k + 1]);
  return (int) std::count_if(ranks.begin(), ranks.end(), [](const auto &r) { return r.second.size() > 1; });
}

// The accuracy request holds for what the integrator uses: the net force and torque of each
// clump (relative RMS over clumps), also with a forced deep tree (leaf 16), where intra-clump
// pairs reach the far field; reference: pair coul/cut over the same clumps. The error the order
// search measured is the exact one (every clump sampled); ctest runs this also on 2 ranks,
// where clumps are split over the ranks.
TEST_F(ClumpKifmm, RequestedAccuracyHoldsForClumpForcesAndTorques)
{
  // the clumps' centres moved by half a spacing: the middle planes of the box, where 2 ranks
  // divide it, run through clumps
  const std::string gas = dipole_gas(200, 0.03, "f f f", 0.02) + "displace_atoms all move 0.015 0.015 0.015 units box\n";
  commands(gas + clump_fix + "\npair_style coul/cut 10.0\npair_coeff * *\n"
           "run 0 post no");
  const auto exact = clump_rows(lmp, "c");
  int differences = 0, me = 0, split = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &me);
  for (const char *leaf : {"", "leaf 16"})
    for (const char *acc : {"1e-3", "1e-5", "1e-7"}) {
      create();
      commands(gas + clump_fix + "\npair_style zero 0.1\npair_coeff * *\n" +
               "kspace_style kifmm " + acc + "\n");
      if (*leaf) command(std::string("kspace_modify kifmm ") + leaf);
      const std::string log = captured("run 0 post no");
      if (*leaf == 0 && std::string(acc) == "1e-3") split = split_clumps(lmp);
      const auto rows = clump_rows(lmp, "c");
      const double ef = rel_rms(rows, exact, clump_test::FX),
                   et = rel_rms(rows, exact, clump_test::TQX);
      std::printf("  %s %s: net force error %.3e, torque error %.3e\n", acc, leaf, ef, et);
      SCOPED_TRACE(testing::Message() << acc << " " << leaf << "\n" << log);
      EXPECT_LE(ef, std::atof(acc));
      EXPECT_LE(et, std::atof(acc));
      if (me != 0) continue;    // the log is rank 0's
      EXPECT_NE(log.find("measured relative error"), std::string::npos);
      // the sample holds every clump (200 < 1000): the error measured at the order settled on
      // (its last line) is the exact one, with clumps split over ranks too
      const std::size_t last = log.rfind("requested");
      ASSERT_NE(last, std::string::npos);
      const std::string line = log.substr(log.rfind('\n', last) + 1);
      const double sampled_f = logged_number(line, "net forces of 200 clumps "),
                   sampled_t = logged_number(line.substr(line.find("clumps ")), "torques ");
      // (printed to 4 digits; both sums differ by rounding, about 1e-15, where the tree is a
      // direct sum)
      EXPECT_NEAR(sampled_f, ef, 1e-3 * ef + 1e-13) << line;
      EXPECT_NEAR(sampled_t, et, 1e-3 * et + 1e-13) << line;
      // where the difference of two orders over all clumps bounded the error, the bound holds
      const double bound = logged_number(log, "relative error at most ");
      if (bound >= 0) EXPECT_GE(1.01 * bound, std::max(ef, et));
      if (log.find("differ by") != std::string::npos) ++differences;
    }
  // the order search took differences over all clumps' net forces and torques
  if (me == 0) EXPECT_GT(differences, 0);
  // on several ranks, clumps with pebbles on two ranks were among them
  if (lmp->comm->nprocs > 1) EXPECT_GT(split, 0);
}

// Polarizable pebbles (fix kifmm/polarize on the pebbles of clumps, in a uniform field): the
// induced dipoles see every field, that of their own clump too, so they equal the dipoles of the
// same atoms without clumps; forces, energy, pressure tensor and per-atom virial differ from that
// run by the pairs of charges inside the clumps only, and the clumps' net forces and torques
// (pebble torques included) not at all.
TEST_F(ClumpKifmm, PolarizablePebblesSeeTheFieldOfTheirOwnClump)
{
  const int nclumps = 27;
  const std::string polarize =
      "set group all dipole 0 0 0\nfix ef all efield 100 0 300\nfix_modify ef energy yes\n"
      "fix pol all kifmm/polarize permittivity 10 tol 1e-12\nfix_modify pol energy yes\n"
      "compute pea all pe/atom\ncompute sta all stress/atom NULL pair kspace\n";
  const std::string gas = dipole_gas(nclumps, 0.04, "f f f", 0.02, 7, "hybrid sphere dipole") + polarize;
  const std::string kspace = "pair_style zero 0.1\npair_coeff * *\nkspace_style kifmm 1e-10";
  commands(gas);
  Run free = run0(kspace);
  const auto free_mu = dipoles_by_id(lmp), free_tq = torques_by_id(), x = positions_by_id();
  const double volume = evaluate("vol");
  create();
  commands(gas + clump_fix + "\n");
  Run fmm = run0(kspace);
  const auto mu = dipoles_by_id(lmp);
  const IntraClumpCharges intra = intra_clump_charges(x, nclumps);

  double mu_rms = 0;
  for (const auto &[id, m] : mu) mu_rms += m[0] * m[0] + m[1] * m[1] + m[2] * m[2];
  mu_rms = std::sqrt(mu_rms / mu.size());
  EXPECT_GT(mu_rms, 1e-4) << "polarized by the charges of their clump (E about 1e4, alpha about 1e-7)";
  EXPECT_LT(relative_force_error(mu, free_mu), 1e-9) << "induced dipoles";
  std::map<int, Vec3> expect_f = free.f;
  for (auto &[id, f] : expect_f)
    for (int d = 0; d < 3; ++d) f[d] -= intra.f.at(id)[d];
  EXPECT_LT(relative_force_error(fmm.f, expect_f), 1e-8) << "forces";
  const double e_intra = intra.energy / (3 * nclumps);    // thermo pe per atom (lj units)
  EXPECT_NEAR(fmm.energy, free.energy - e_intra, 1e-8 * std::fabs(e_intra)) << "energy";
  double pscale = 0;
  for (int k = 0; k < 6; ++k) pscale = std::max(pscale, std::fabs(intra.virial[k] / volume));
  for (int k = 0; k < 6; ++k)
    EXPECT_NEAR(fmm.p[k], free.p[k] - intra.virial[k] / volume, 1e-8 * pscale) << "pressure component " << k;
  // per-atom stress (the negative per-atom virial) and energy
  double num = 0, den = 0;
  for (const auto &[id, v] : free.peratom)
    for (int k = 1; k < 7; ++k) {
      const double want = v[k] + intra.v.at(id)[k - 1];
      num += (fmm.peratom.at(id)[k] - want) * (fmm.peratom.at(id)[k] - want);
      den += want * want;
    }
  EXPECT_LT(std::sqrt(num / den), 1e-8) << "per-atom virial";
  // net force and torque of each clump (rigid/small's, with the pebble torques) against the
  // sums over its pebbles in the run without clumps, where the pairs inside it are included
  const auto rows = clump_rows(lmp, "c");
  ASSERT_EQ((int) rows.size(), nclumps);
  double fnum = 0, fden = 0, tnum = 0, tden = 0;
  for (const auto &[mol, row] : rows) {
    const int first = 3 * (mol - 1) + 1;
    Vec3 fsum{0, 0, 0}, tsum{0, 0, 0};
    for (int i = first; i < first + 3; ++i) {
      const Vec3 &f = free.f.at(i), &t = free_tq.at(i);
      double r[3];
      for (int d = 0; d < 3; ++d) r[d] = x.at(i)[d] - row[clump_test::X + d];
      for (int d = 0; d < 3; ++d) fsum[d] += f[d];
      tsum[0] += r[1] * f[2] - r[2] * f[1] + t[0];
      tsum[1] += r[2] * f[0] - r[0] * f[2] + t[1];
      tsum[2] += r[0] * f[1] - r[1] * f[0] + t[2];
    }
    for (int d = 0; d < 3; ++d) {
      fnum += std::pow(row[clump_test::FX + d] - fsum[d], 2), fden += fsum[d] * fsum[d];
      tnum += std::pow(row[clump_test::TQX + d] - tsum[d], 2), tden += tsum[d] * tsum[d];
    }
  }
  EXPECT_LT(std::sqrt(fnum / fden), 1e-8) << "net forces of the clumps";
  EXPECT_LT(std::sqrt(tnum / tden), 1e-8) << "net torques of the clumps";
}

// Clumps of polarizable pebbles turning in a uniform field (fix clump/rigid integrates them): the
// total energy (clumps' kinetic energy, kspace, fix efield and polarization energies) is
// conserved as velocity Verlet conserves a true potential energy, its deviation falling as
// dt^2, far below the kinetic energy the clumps gain.
TEST_F(ClumpKifmm, PolarizablePebblesConserveTheEnergyOfTurningClumps)
{
  auto deviation = [&](double dt, double &ke) {
    create();
    commands(dipole_gas(27, 0.06, "f f f", 0.02, 7, "hybrid sphere dipole") +
             "set group all dipole 0 0 0\nfix ef all efield 100 0 300\nfix_modify ef energy yes\n" + clump_fix + " integrator nve\n"
             "fix pol all kifmm/polarize permittivity 10 tol 1e-11\nfix_modify pol energy yes\n"
             "pair_style zero 0.1\npair_coeff * *\nkspace_style kifmm 1e-9\n"
             "variable etot equal f_c[4]+pe\nthermo_style custom step pe f_c[4] v_etot\nthermo_modify norm no\n"
             "run 0 post no");
    char ts[64];
    std::snprintf(ts, sizeof ts, "timestep %.17g", dt);
    command(ts);
    const double e0 = evaluate("v_etot");
    double maxdev = 0;
    const int steps = (int) std::lround(5e-5 / dt);
    for (int k = 0; k < 4; ++k) {
      command("run " + std::to_string(steps) + " post no");
      maxdev = std::max(maxdev, std::fabs(evaluate("v_etot") - e0));
    }
    ke = evaluate("f_c[4]");
    return maxdev;
  };
  double ke = 0, ke_half = 0;
  const double dev = deviation(1e-6, ke), dev_half = deviation(5e-7, ke_half);
  std::printf("  total energy deviation: %.2e at dt 1e-6, %.2e at dt 5e-7; kinetic energy gained %.3e\n", dev,
              dev_half, ke_half);
  EXPECT_LE(dev_half, dev / 3);
  EXPECT_GT(ke_half, 1000 * dev_half);
}

// A permanent dipole moment on a pebble: an error naming the atom and its clump.
TEST_F(ClumpKifmm, PermanentDipoleOnAPebbleIsAnError)
{
  commands(dipole_gas(8, 0.05, "f f f", 0.0, 7, "hybrid sphere dipole") + clump_fix +
           "\nset group all dipole 0 0 0\nset atom 5 dipole 0 0 0.1\n"
           "pair_style zero 0.1\npair_coeff * *\nkspace_style kifmm 1e-5\n");
  EXPECT_LAMMPS_ERROR(command("run 0 post no"), "atom 5 of clump 2 has a permanent dipole moment");
}

// Pebbles deleted from a clump after its mass properties were computed: an error naming the
// clump (the mass and inertia would be those of the whole clump).
TEST_F(ClumpKifmm, DeletedPebblesOfAClumpAreAnError)
{
  commands(dipole_gas(8, 0.05) + clump_fix + "\npair_style zero 0.1\npair_coeff * *\nrun 0 post no\n"
           "group half id 4 5\ndelete_atoms group half");
  EXPECT_LAMMPS_ERROR(command("run 0 post no"),
                      "Fix clump/rigid c: clump 2 has 1 pebbles, its mass properties were "
                      "computed for 3");
}

// An accuracy below what double precision reaches: a warning with the error that is reached.
TEST_F(ClumpKifmm, UnreachableAccuracyIsAWarning)
{
  commands(dipole_gas(200, 0.03, "f f f", 0.02) + clump_fix + "\npair_style zero 0.1\npair_coeff * *\n"
           "kspace_style kifmm 1e-14\nkspace_modify kifmm leaf 8\n");
  const std::string log = captured("run 0 post no");
  EXPECT_NE(log.find("WARNING: kspace_style kifmm: the requested accuracy 1e-14 is below what the "
                     "highest calibrated order"),
            std::string::npos)
      << log;
  EXPECT_NE(log.find("is out of reach for these atoms: measured"), std::string::npos) << log;
}
