// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// kspace_style kifmm with boundary p p p against LAMMPS's kspace_style ewald (tin-foil).
//
// Reference: LAMMPS ewald's k-space part (forces, and energy with its self and net-charge
// background terms; pair coul/long with `pair_modify compute no` only supplies the cutoff) plus
// the real-space sum erfc(alpha r)/r computed here with libm's erfc. LAMMPS's own pair
// coul/long approximates erfc by a polynomial (absolute error up to ~1e-7) or by float-indexed
// tables, so the complete LAMMPS ewald + coul/long is exact only to ~1e-6; that agreement is
// tested separately. Data files are written by rank 0 (atom IDs independent of the rank count);
// ctest also runs this binary on 2 and 4 ranks.
#include "configurations.h"
#include "kspace_kifmm.h"
#include "lammps_fixture.h"

#include "atom.h"
#include "domain.h"
#include "force.h"
#include "kspace.h"
#include "lammps.h"
#include "pair.h"

#include <cmath>
#include <cstdio>
#include <mpi.h>

using namespace kifmm_test;

namespace {

struct Result {
  std::map<int, Vec3> f;
  double energy = 0;
  double wdiag[3] = {0, 0, 0};    // ewald_reference: diagonal of the virial (k-space + real space)
  double w[6] = {0, 0, 0, 0, 0, 0};    // ewald_reference: the virial tensor (xx yy zz xy xz yz)
};

double rel(double a, double b)
{
  return std::fabs(a - b) / std::fabs(b);
}

int rank()
{
  int me = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &me);
  return me;
}

class Periodic : public LammpsFixture {
 protected:
  std::string data_path;
  std::vector<double> charge;    // by atom ID - 1

  void SetUp() override
  {
    LammpsFixture::SetUp();
    std::string name = testing::UnitTest::GetInstance()->current_test_info()->name();
    for (char &c : name)
      if (c == '/') c = '_';
    data_path = "kifmm_periodic_" + name + ".data";
  }
  void TearDown() override
  {
    MPI_Barrier(MPI_COMM_WORLD);
    if (rank() == 0) std::remove(data_path.c_str());
    LammpsFixture::TearDown();
  }

  void load(const Configuration &c, const std::string &boundary = "p p p")
  {
    if (rank() == 0) write_charge_data(data_path, c);
    MPI_Barrier(MPI_COMM_WORLD);
    charge = c.q;
    commands("units lj\natom_style charge\nboundary " + boundary + "\natom_modify map array\n"
             "read_data " + data_path + "\nthermo_style custom step pe elong press\n"
             "thermo_modify norm no\nneighbor 0.05 bin\nneigh_modify one 20000 page 400000\n");
  }

  double box_length() { return lmp->domain->xprd; }

  // LAMMPS ewald k-space part + exact real space (see the file comment). alpha*L = 9 and
  // kmax = 20 converge both parts to ~1e-16 (rectangular boxes: L the shortest edge, kmax in
  // proportion to the edges).
  // slab > 0 (boundary p p f): ewald with kspace_modify slab of that factor (the box enlarged in
  // z, the dipole correction of Yeh and Berkowitz), real space without images in z
  Result ewald_reference(double slab = 0)
  {
    const double Lb[3] = {lmp->domain->xprd, lmp->domain->yprd, lmp->domain->zprd};
    const double Lmin = std::min(Lb[0], std::min(Lb[1], Lb[2])), alpha = 9.0 / Lmin, rc = 0.7 * Lmin;
    int km[3];
    for (int d = 0; d < 3; ++d) km[d] = (int) std::ceil(20.0 * Lb[d] * (d == 2 && slab > 0 ? slab : 1.0) / Lmin - 1e-9);
    commands(fmt_cmd("pair_style coul/long {}\npair_coeff * *\npair_modify compute no\n"
                     "kspace_style ewald 1e-14\nkspace_modify gewald {} kmax/ewald {} {} {}\n",
                     rc, alpha, km[0], km[1], km[2]));
    if (slab > 0) command(fmt_cmd("kspace_modify slab {}", slab));
    command("run 0 post no");
    Result r{forces_by_id(), thermo("elong")};
    for (int k = 0; k < 3; ++k) r.wdiag[k] = lmp->force->kspace->virial[k];
    for (int k = 0; k < 6; ++k) r.w[k] = lmp->force->kspace->virial[k];
    EXPECT_DOUBLE_EQ(lmp->force->kspace->g_ewald, alpha);
    // real space: sum over pairs and images within rc (rc < L: minimum image shell n in {-1,0,1}^3)
    auto x = positions_by_id();
    const int n = (int) x.size();
    std::vector<Vec3> pos(n);
    for (auto &[id, p] : x) pos[id - 1] = p;
    double e = 0;
    std::vector<Vec3> f(n, Vec3{0, 0, 0});
    const double c2 = 2 * alpha / std::sqrt(M_PI);
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < n; ++j)
        for (int a = -1; a <= 1; ++a)
          for (int b = -1; b <= 1; ++b)
            for (int c = slab > 0 ? 0 : -1; c <= (slab > 0 ? 0 : 1); ++c) {
              if (i == j && a == 0 && b == 0 && c == 0) continue;
              const double d[3] = {pos[i][0] - pos[j][0] + a * Lb[0], pos[i][1] - pos[j][1] + b * Lb[1],
                                   pos[i][2] - pos[j][2] + c * Lb[2]};
              const double r2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2], rr = std::sqrt(r2);
              if (rr > rc) continue;
              const double qq = charge[i] * charge[j];
              e += 0.5 * qq * std::erfc(alpha * rr) / rr;
              const double fr = qq * (std::erfc(alpha * rr) / r2 + c2 * std::exp(-alpha * alpha * r2) / rr) / rr;
              for (int k = 0; k < 3; ++k) f[i][k] += fr * d[k];
              for (int k = 0; k < 3; ++k) r.wdiag[k] += 0.5 * fr * d[k] * d[k];
              const int ab[6][2] = {{0, 0}, {1, 1}, {2, 2}, {0, 1}, {0, 2}, {1, 2}};
              for (int k = 0; k < 6; ++k) r.w[k] += 0.5 * fr * d[ab[k][0]] * d[ab[k][1]];
            }
    for (auto &[id, v] : r.f)
      for (int k = 0; k < 3; ++k) v[k] += f[id - 1][k];
    r.energy += e;
    command("pair_modify compute yes");
    return r;
  }

  Result kifmm(const std::string &accuracy, const std::string &modify = "")
  {
    commands("kspace_style none\npair_style zero 0.01\npair_coeff * *\nkspace_style kifmm " + accuracy);
    if (!modify.empty()) command("kspace_modify kifmm " + modify);
    command("run 0 post no");
    return {forces_by_id(), thermo("elong")};
  }

  // kifmm with these kspace_modify kifmm keywords at accuracy 1e-12 equals ewald_reference()
  // (forces and energy to 1e-10)
  void expect_equals_ewald(const std::string &label, const std::string &modify)
  {
    Result ref = ewald_reference();
    Result r = kifmm("1e-12", modify);
    const double ef = relative_force_error(r.f, ref.f), ee = rel(r.energy, ref.energy);
    if (rank() == 0) std::printf("  %s (%s): force %.2e energy %.2e\n", label.c_str(), modify.c_str(), ef, ee);
    EXPECT_LE(ef, 1e-10) << label;
    EXPECT_LE(ee, 1e-10) << label;
  }

  template <class... A> static std::string fmt_cmd(const char *f, A... a)
  {
    std::string s(f);
    std::vector<std::string> v{to_s(a)...};
    for (const std::string &x : v) {
      const size_t p = s.find("{}");
      s.replace(p, 2, x);
    }
    return s;
  }
  static std::string to_s(double d)
  {
    char b[64];
    std::snprintf(b, sizeof b, "%.17g", d);
    return b;
  }

  // output of one command (screen) as a string
  std::string output_of(const std::string &cmd)
  {
    char *buf = nullptr;
    size_t len = 0;
    FILE *mem = open_memstream(&buf, &len);
    FILE *old = lmp->screen;
    lmp->screen = mem;
    command(cmd);
    fflush(mem);
    lmp->screen = old;
    fclose(mem);
    std::string out(buf, len);
    free(buf);
    return out;
  }

  // change_box (box scaled, atoms remapped) and fix deform during a run: kifmm with these
  // kspace_modify kifmm keywords follows the box (compared with ewald on the new box)
  void change_box_and_deform(const std::string &modify)
  {
    load(uniform_cube(800, 50));
    // change_box: scale the box and remap the atoms, then compare with ewald on the new box
    command("change_box all x final 0 1.3 y final 0 1.3 z final 0 1.3 remap units box");
    Result ref = ewald_reference();
    Result r = kifmm("1e-12", modify);
    EXPECT_LE(relative_force_error(r.f, ref.f), 1e-10);
    EXPECT_LE(rel(r.energy, ref.energy), 1e-10);
    // fix deform during a run (box 1.3 -> 1.5): the energies along the run follow the box
    // (no time integration: the atoms only follow the affine remap of the box)
    commands("fix grow all deform 1 x final 0 1.5 y final 0 1.5 z final 0 1.5 remap x\n"
             "thermo 10\nrun 20 post no\nunfix grow");
    EXPECT_NEAR(box_length(), 1.5, 1e-12);
    // fix deform changes the box at the end of a step: the energy of step 20 belongs to the box
    // of step 19 (L = 1.49); the configuration is affine in L and E ~ 1/L
    const double e_run = thermo("elong") * (1.3 + 0.2 * 19.0 / 20.0) / 1.5;
    Result ref2 = ewald_reference();
    if (rank() == 0) std::printf("  after fix deform: energy %.2e\n", rel(e_run, ref2.energy));
    EXPECT_LE(rel(e_run, ref2.energy), 1e-10);
  }
};

Configuration shifted_box(Configuration c, double L)
{
  for (auto &x : c.x)
    for (double &v : x) v *= L;
  c.hi = L;
  return c;
}

// three atom types of masses 1, 1.5, 2 with charges equal to the masses (all positive): the
// coulomb sum on them, times -G, is kernel gravity's
Configuration charges_equal_to_masses(Configuration c)
{
  c.type_mass = {1.0, 1.5, 2.0};
  c.type.resize(c.x.size());
  for (size_t i = 0; i < c.x.size(); ++i) {
    c.type[i] = 1 + (int) (i % 3);
    c.q[i] = c.type_mass[c.type[i] - 1];
  }
  return c;
}

// gravity's forces and energy equal coulomb's on charges = masses times -G
void expect_gravity_is_coulomb_times_minus_g(const Result &grav, Result coul, double G, const std::string &label)
{
  for (auto &[id, f] : coul.f)
    for (double &v : f) v *= -G;
  EXPECT_LE(relative_force_error(grav.f, coul.f), 1e-12) << label;
  EXPECT_NEAR(grav.energy, -G * coul.energy, 1e-12 * std::fabs(coul.energy)) << label;
}

// ---------------------------------------------------------------- equal to ewald

TEST_F(Periodic, NeutralRandomEqualsEwald)
{
  load(shifted_box(uniform_cube(1000, 41), 2.0));
  expect_equals_ewald("neutral random", "order 14 leaf 40");
}

TEST_F(Periodic, NeutralDipolesEqualEwald)
{
  load(shifted_box(dipoles(1000, 42, 0.02), 1.0));
  expect_equals_ewald("dipoles", "order 14 leaf 40");
}

TEST_F(Periodic, NetChargeGetsBackgroundAndWarning)
{
  Configuration c = uniform_cube(800, 43);
  for (double &q : c.q) q += 0.25;    // net charge 200
  load(c);
  Result ref = ewald_reference();
  commands("kspace_style none\npair_style zero 0.01\npair_coeff * *\nkspace_style kifmm 1e-12\n"
           "kspace_modify kifmm order 14 leaf 40");
  std::string out = output_of("run 0 post no");
  Result r{forces_by_id(), thermo("elong")};
  const double ef = relative_force_error(r.f, ref.f), ee = rel(r.energy, ref.energy);
  if (rank() == 0) std::printf("  net charge 200: force %.2e energy %.2e (E = %.15g)\n", ef, ee, ref.energy);
  EXPECT_LE(ef, 1e-10);
  EXPECT_LE(ee, 1e-10);
  if (rank() == 0) EXPECT_NE(out.find("neutralizing background"), std::string::npos) << out;
}

// The single-level grid (kspace_modify kifmm grid K; distributed on several ranks): neutral
// random atoms, cancelling dipoles and a net charge equal ewald at 1e-10
TEST_F(Periodic, GridEqualsEwaldOnNeutralRandom)
{
  load(shifted_box(uniform_cube(1000, 41), 2.0));
  expect_equals_ewald("grid, neutral random", "order 14 grid 5");
  auto *ks = dynamic_cast<LAMMPS_NS::KSpaceKIFMM *>(lmp->force->kspace);
  ASSERT_NE(ks, nullptr);
  int nprocs = 1;
  MPI_Comm_size(MPI_COMM_WORLD, &nprocs);
  if (nprocs == 1) EXPECT_EQ(ks->engine_stats().n_leaves, 125u);
}

TEST_F(Periodic, GridEqualsEwaldOnDipolesWithNetCharge)
{
  Configuration c = dipoles(800, 42, 0.02);
  const Configuration u = uniform_cube(200, 55);
  for (std::size_t i = 0; i < u.x.size(); ++i) {    // and 200 atoms of charge +0.25: net charge 50
    c.x.push_back(u.x[i]);
    c.q.push_back(0.25);
  }
  load(c);
  expect_equals_ewald("grid, dipoles + net charge 50", "order 14 grid 4");
}

TEST_F(Periodic, CompleteLammpsEwaldWithCoulLong)
{
  // pair coul/long as it is (polynomial erfc): agreement limited by LAMMPS's erfc (~1e-7)
  load(uniform_cube(1000, 44));
  const double rc = 0.7, alpha = 9.0;
  commands(fmt_cmd("pair_style coul/long {}\npair_coeff * *\npair_modify table 0\nkspace_style ewald 1e-14\n"
                   "kspace_modify gewald {} kmax/ewald 20 20 20\nrun 0 post no",
                   rc, alpha));
  Result ref{forces_by_id(), thermo("pe")};
  const double press_ref = thermo("press");
  Result r = kifmm("1e-12", "order 14 leaf 40");
  const double ef = relative_force_error(r.f, ref.f), ee = rel(r.energy, ref.energy);
  const double ep = rel(thermo("press"), press_ref);
  if (rank() == 0)
    std::printf("  vs ewald + coul/long (LAMMPS erfc): force %.2e energy %.2e pressure %.2e\n", ef, ee, ep);
  EXPECT_LE(ef, 1e-5);
  EXPECT_LE(ee, 1e-6);
  EXPECT_LE(ep, 1e-5) << "scalar pressure (virial trace = energy)";
}

// The trace of the virial (what the scalar pressure uses) equals ewald's at 1e-10 on a
// strongly anisotropic neutral arrangement (two charged layers, a capacitor), whose ewald
// virial diagonal is far from isotropic: the tensor components that kifmm does not compute
// (and refuses, see the pressure tests below) really differ from E/3.
TEST_F(Periodic, VirialTraceEqualsEwaldOnAnisotropicLayers)
{
  Configuration c = uniform_cube(800, 61);
  for (size_t i = 0; i < c.x.size(); ++i) c.x[i][2] = (c.q[i] > 0 ? 0.2 : 0.6) + 0.1 * c.x[i][2];
  load(c);
  Result ref = ewald_reference();
  commands("kspace_style none\npair_style zero 0.01\npair_coeff * *\nkspace_style kifmm 1e-12\n"
           "kspace_modify kifmm order 14 leaf 40\nrun 0 post no");
  const double *w = lmp->force->kspace->virial;
  const double tr = w[0] + w[1] + w[2], tr_ref = ref.wdiag[0] + ref.wdiag[1] + ref.wdiag[2];
  const double aniso = std::fabs(ref.wdiag[2] - tr_ref / 3) / std::fabs(tr_ref);
  if (rank() == 0)
    std::printf("  layers: virial trace %.2e (ewald diag %.6g %.6g %.6g, anisotropy %.2f)\n", rel(tr, tr_ref),
                ref.wdiag[0], ref.wdiag[1], ref.wdiag[2], aniso);
  EXPECT_LE(rel(tr, tr_ref), 1e-10);
  EXPECT_LE(rel(tr, thermo("elong")), 1e-12) << "trace = energy (homogeneity)";
  EXPECT_GT(aniso, 0.05);
}

TEST_F(Periodic, MeasuredErrorWithinRequestedAccuracy)
{
  Configuration c = uniform_cube(2000, 45);
  Configuration d = dipoles(1000, 46, 0.01);
  for (size_t i = 0; i < d.x.size(); ++i) {
    c.x.push_back(d.x[i]);
    c.q.push_back(d.q[i]);
  }
  load(c);
  Result ref = ewald_reference();
  // the choice of the cost model (on one rank a single-level grid for these 3000 atoms) and
  // the octree (grid no)
  for (const char *grid : {"auto", "no"})
    for (const char *acc : {"1e-3", "1e-4", "1e-5", "1e-6", "1e-7"}) {
      Result r = kifmm(acc, std::string("grid ") + grid);
      const double ef = relative_force_error(r.f, ref.f), ee = rel(r.energy, ref.energy);
      auto *ks = dynamic_cast<LAMMPS_NS::KSpaceKIFMM *>(lmp->force->kspace);
      if (rank() == 0)
        std::printf("  grid %s (%zu cells/leaves) accuracy %s: measured force error %.2e, energy %.2e\n", grid,
                    ks->engine_stats().n_leaves, acc, ef, ee);
      EXPECT_LE(ef, std::stod(acc)) << acc << " grid " << grid;
      EXPECT_LE(ee, std::stod(acc)) << acc << " grid " << grid;
    }
}

// Without a leaf keyword the leaf size is chosen from the atom positions at the first
// evaluation (one rank: kifmm::choose_tree on the counts of the actual trees), printed with its
// depth, which is the depth of the evaluated tree; the setup output also gives the uniform
// model's choice for the atom count and the boundary (kifmm::choose_tree(order, n, periodic)).
// Open boundaries (f f f) get their own choice.
class PeriodicTreeChoice : public Periodic {
 protected:
  // zero_charge: extra atoms of charge zero, which are not in the tree and must not be counted
  void expect_cost_model_choice(const char *boundary, int zero_charge = 0)
  {
    const bool periodic = boundary[0] == 'p';
    Configuration c3000 = uniform_cube(3000, 48);
    Configuration zero = uniform_cube(zero_charge, 49);
    for (std::size_t i = 0; i < zero.x.size(); ++i) {
      c3000.x.push_back(zero.x[i]);
      c3000.q.push_back(0.0);
    }
    load(c3000, boundary);
    commands("pair_style zero 0.01\npair_coeff * *\nkspace_style kifmm 1e-5");
    const std::string out = output_of("run 0 post no");
    const int order = kifmm::choose_order(kifmm::KernelSpec{}, 1e-5, periodic).order;
    const kifmm::TreeChoice c = kifmm::choose_tree(order, 3000, periodic);
    auto *ks = dynamic_cast<LAMMPS_NS::KSpaceKIFMM *>(lmp->force->kspace);
    ASSERT_NE(ks, nullptr);
    const std::string line = "order = " + std::to_string(order) + ", " +
        (periodic ? "leaf size or single-level grid" : "leaf size") +
        " chosen from the atom positions at the first evaluation (least modelled cost of "
        "the actual trees" + (periodic ? " and grids" : "") + "; for 3000 uniformly spread atoms, " +
        (periodic ? "periodic" : "open") + " boundaries: leaf size " + std::to_string(c.leaf_size) + ", tree depth " +
        std::to_string(c.depth) + ")";
    const std::string settled = "KIFMM order ";
    if (rank() == 0) {
      EXPECT_NE(out.find(line), std::string::npos) << line << "\n" << out;
      // the tree settled on: the one chosen for the order the measurement settled on (each order
      // tried is evaluated on the tree chosen for it), named in the last line of the search
      const std::size_t at = out.rfind(settled);
      ASSERT_NE(at, std::string::npos) << out;
      const std::string last = out.substr(at, out.find('\n', at) - at);
      int final_order = 0, k = 0, leaf = 0, depth = -1;
      if (std::sscanf(last.c_str(), "KIFMM order %d on periodic single-level grid of %d^3 cells", &final_order, &k) ==
          2) {    // periodic: a grid of k^3 cells (no octree depth)
        ASSERT_TRUE(periodic) << out;
        EXPECT_GE(k, 3);
        EXPECT_EQ(ks->engine_stats().n_leaves, (std::size_t) k * k * k) << out;
        EXPECT_EQ(ks->engine_stats().depth, 0);
        EXPECT_NE(out.find(std::to_string(k) + "^3 cells chosen from the atom positions for 3000 atoms"),
                  std::string::npos) << out;
      } else {
        ASSERT_EQ(std::sscanf(last.c_str(), "KIFMM order %d on leaf size %d, tree depth %d", &final_order, &leaf, &depth),
                  3) << last;
        EXPECT_EQ(ks->engine_stats().depth, depth) << boundary;
        EXPECT_GE(depth, 1) << boundary;
        EXPECT_NE(out.find("leaf size " + std::to_string(leaf) + " (tree depth " + std::to_string(depth) + ","),
                  std::string::npos) << out;
      }
      EXPECT_EQ(final_order, ks->engine_order()) << out;
    }
  }
};

TEST_F(PeriodicTreeChoice, PeriodicBoundaries)
{
  expect_cost_model_choice("p p p");
}

TEST_F(PeriodicTreeChoice, OpenBoundaries)
{
  expect_cost_model_choice("f f f");
}

// 3000 charged atoms and 2000 of charge zero: the uniform choice is that of 3000 atoms
TEST_F(PeriodicTreeChoice, ZeroChargeAtomsAreNotCounted)
{
  expect_cost_model_choice("p p p", 2000);
}

TEST_F(Periodic, CheckUsesThePeriodicReference)
{
  load(uniform_cube(1000, 47));
  Result ref = ewald_reference();
  Result r = kifmm("1e-4", "order 4 leaf 32 check 1 1000");
  const double full = relative_force_error(r.f, ref.f), measured = evaluate("v_kifmm_error");
  EXPECT_GT(full, 1e-7);
  EXPECT_NEAR(measured, full, 1e-3 * full);
}

// 6000 atoms, all sampled: 3.6e7 source-target pairs, above which the reference is the
// engine at order 14 (kifmm::reference_order); the search and the check of step 0 measure
// the same sample of the same atoms: one exact sum
TEST_F(Periodic, CheckInALargeBoxAgainstTheEngineAtOrder14)
{
  load(uniform_cube(6000, 51));
  Result ref = ewald_reference();
  Result r = kifmm("1e-4", "order 4 check 1 6000");
  const double full = relative_force_error(r.f, ref.f), measured = evaluate("v_kifmm_error");
  EXPECT_GT(full, 1e-7);
  EXPECT_NEAR(measured, full, 1e-3 * full);
  commands("kspace_style none\npair_style zero 0.01\npair_coeff * *\nkspace_style kifmm 1e-5\n"
           "kspace_modify kifmm check 1 6000");
  const std::string out = output_of("run 0 post no");
  auto *ks = dynamic_cast<LAMMPS_NS::KSpaceKIFMM *>(lmp->force->kspace);
  ASSERT_NE(ks, nullptr);
  if (rank() == 0) {
    EXPECT_NE(out.find(" on these atoms"), std::string::npos) << out;    // the search: two orders
    EXPECT_NE(out.find("KIFMM check at step 0"), std::string::npos) << out;
  }
  EXPECT_EQ(ks->exact_sums(), 1);
  const double full5 = relative_force_error(forces_by_id(), ref.f);
  EXPECT_LE(full5, 1e-5);
  EXPECT_NEAR(evaluate("v_kifmm_error"), full5, 1e-3 * full5);
}

// ---------------------------------------------------------------- yukawa

TEST_F(Periodic, YukawaEqualsCoulDebyeOverImages)
{
  // coul/debye with a cutoff beyond which exp(-kappa r) < 1e-16 sums the images exactly;
  // kappa L/2 = 4 uses the screened-Ewald root operator, 10 the direct image sum
  for (double kappa : {8.0, 20.0}) {
    if (kappa != 8.0) {
      destroy();
      create();
    }
    load(uniform_cube(kappa == 8.0 ? 300 : 1000, 48));
    const double rc = 37.0 / kappa;
    command("neigh_modify one 100000 page 2000000");
    commands(fmt_cmd("pair_style coul/debye {} {}\npair_coeff * *\nrun 0 post no", kappa, rc));
    Result ref{forces_by_id(), thermo("pe")};
    for (const char *tree : {"leaf 40", "grid 4"}) {    // the octree and the single-level grid
      Result r = kifmm("1e-10", "kernel yukawa " + to_s(kappa) + " order 12 " + tree);
      const double ef = relative_force_error(r.f, ref.f), ee = rel(r.energy, ref.energy);
      if (rank() == 0) std::printf("  yukawa kappa %g, %s: force %.2e energy %.2e\n", kappa, tree, ef, ee);
      EXPECT_LE(ef, 1e-9) << tree;
      EXPECT_LE(ee, 1e-9) << tree;
    }
  }
}

// ---------------------------------------------------------------- gravity

TEST_F(Periodic, GravityJeansEqualsCoulombWithBackground)
{
  load(charges_equal_to_masses(uniform_cube(500, 49)));    // coulomb: net charge
  // the cube (octree) and a rectangular box (single-level grid)
  for (const char *box : {"", "change_box all y final 0 1.3 remap units box"}) {
    if (*box) command(box);
    Result coul = kifmm("1e-10", "order 12");
    Result grav = kifmm("1e-10", "kernel gravity 0.8 jeans yes order 12");
    expect_gravity_is_coulomb_times_minus_g(grav, coul, 0.8, box);
  }
  // and the rectangular box's coulomb with net charge is ewald's (uniform background)
  Result ref = ewald_reference();
  Result coul = kifmm("1e-10", "order 12");
  EXPECT_LE(relative_force_error(coul.f, ref.f), 1e-9);
  EXPECT_LE(rel(coul.energy, ref.energy), 1e-9);
}

// ---------------------------------------------------------------- box changes

TEST_F(Periodic, ChangeBoxAndFixDeformFollowTheBox)
{
  change_box_and_deform("order 14 leaf 40");
}

TEST_F(Periodic, GridFollowsChangeBoxAndFixDeform)
{
  change_box_and_deform("order 14 grid 4");
}

// ---------------------------------------------------------------- errors

TEST_F(Periodic, GravityWithoutJeansIsAnError)
{
  load(uniform_cube(50, 51));
  commands("pair_style zero 0.1\npair_coeff * *\nkspace_style kifmm 1e-4\n"
           "kspace_modify kifmm kernel gravity 1.0");
  EXPECT_LAMMPS_ERROR(command("run 0"), "gravity with periodic boundaries diverges.*jeans yes");
}

// ---------------------------------------------------------------- orthogonal boxes

// rectangular boxes: a nearly cubic one (the octree, every cell of the box's shape) and boxes
// of aspect ratio 1.3, 4 and 8 (the single-level grid, cubic or stretched cells; 8: 1 and 2 cells
// across the thin sides), equal to ewald
TEST_F(Periodic, RectangularBoxesEqualEwald)
{
  struct Box {
    double y, z;
    std::string modify, expect;
  };
  const Box boxes[] = {{0.99, 1.03, "order 14 leaf 40", "leaf size = 40"},
                       {1.3, 1.0, "order 12", "single-level grid of "},
                       {0.25, 1.0, "order 12", "single-level grid of "},
                       {1.0, 0.125, "order 12 grid 8", "single-level grid of 8 x 8 x 1 "},
                       {0.125, 0.125, "order 12 grid 16", "single-level grid of 16 x 2 x 2 "}};
  for (const Box &b : boxes) {
    create();    // a new instance per box
    load(uniform_cube(600, 54));
    command(fmt_cmd("change_box all y final 0 {} z final 0 {} remap units box", b.y, b.z));
    Result ref = ewald_reference();
    commands("kspace_style none\npair_style zero 0.01\npair_coeff * *\nkspace_style kifmm 1e-12\n"
             "kspace_modify kifmm " + b.modify);
    const std::string out = output_of("run 0 post no");
    Result r{forces_by_id(), thermo("elong")};
    const double ef = relative_force_error(r.f, ref.f), ee = rel(r.energy, ref.energy);
    if (rank() == 0) std::printf("  box 1 x %g x %g (%s): force %.2e energy %.2e\n", b.y, b.z, b.modify.c_str(), ef, ee);
    EXPECT_LE(ef, 1e-9) << b.y;
    EXPECT_LE(ee, 1e-9) << b.y;
    if (rank() == 0) EXPECT_NE(out.find(b.expect), std::string::npos) << out;
  }
}

// the accuracy request in a rectangular box: order and grid from the atoms, error measured
TEST_F(Periodic, RectangularBoxMeetsTheRequestedAccuracy)
{
  load(uniform_cube(1500, 55));
  command("change_box all x final 0 2 z final 0 0.7 remap units box");
  Result ref = ewald_reference();
  for (const char *acc : {"1e-4", "1e-7"}) {
    Result r = kifmm(acc);
    const double ef = relative_force_error(r.f, ref.f);
    if (rank() == 0) std::printf("  box 2 x 1 x 0.7, accuracy %s: force %.2e\n", acc, ef);
    EXPECT_LE(ef, std::atof(acc)) << acc;
  }
}

TEST_F(Periodic, GridThatDoesNotFitTheBoxIsAnErrorListingGridsThatDo)
{
  load(uniform_cube(50, 52));
  commands("change_box all y final 0 0.12 units box\npair_style zero 0.1\npair_coeff * *\n"
           "kspace_style kifmm 1e-4\nkspace_modify kifmm grid 3");
  EXPECT_LAMMPS_ERROR(command("run 0"), "grid 3: in the box of lengths 1 0.12 1 .*3 x 1 x 3 cells are too long for "
                                        "their width \\(longest edge 2.778 times the shortest, at most 2\\).*grids "
                                        "that fit \\(cells along the longest edge\\): 5, ");
}

TEST_F(Periodic, OctreeInAnElongatedBoxIsAnError)
{
  load(uniform_cube(50, 56));
  commands("change_box all y final 0 1.25 units box\npair_style zero 0.1\npair_coeff * *\n"
           "kspace_style kifmm 1e-4\nkspace_modify kifmm grid no");
  EXPECT_LAMMPS_ERROR(command("run 0"), "grid no' \\(the octree\\) needs a nearly cubic periodic box.*box "
                                        "lengths are 1 1.25 1");
}

// a box that changes shape during a run: the octree while the box is nearly cubic, then the
// grid; forces and energy follow the box (ewald on the final box)
TEST_F(Periodic, BoxChangingShapeSwitchesFromTheOctreeToAGrid)
{
  load(uniform_cube(600, 60));
  commands("pair_style zero 0.1\npair_coeff * *\nkspace_style kifmm 1e-12\nkspace_modify kifmm order 12 leaf 40\n"
           "fix d all deform 1 x final 0 1.5 remap x\nthermo 1");
  const std::string out = output_of("run 10 post no");
  if (rank() == 0) EXPECT_NE(out.find("the octree no longer fits it, the single-level grid of"), std::string::npos) << out;
  commands("unfix d");
  EXPECT_NEAR(lmp->domain->xprd, 1.5, 1e-12);
  Result ref = ewald_reference();
  Result r = kifmm("1e-12", "order 12 leaf 40");
  EXPECT_LE(relative_force_error(r.f, ref.f), 1e-9);
  EXPECT_LE(rel(r.energy, ref.energy), 1e-9);
}

// ---------------------------------------------------------------- slabs (p p f)

// the doubly periodic sum against ewald with kspace_modify slab: equal at a large slab factor
// (the slab correction's own error decays with the vacuum: at factor 3 it is far larger)
TEST_F(Periodic, SlabEqualsEwaldWithALargeSlabFactor)
{
  load(uniform_cube(600, 70), "p p f");
  command("change_box all z final 0 0.6 remap units box");
  const Result ref10 = ewald_reference(10.0), ref3 = ewald_reference(3.0);
  commands("kspace_style none\npair_style zero 0.01\npair_coeff * *\nkspace_style kifmm 1e-10");
  const std::string out = output_of("run 0 post no");
  Result r{forces_by_id(), thermo("elong")};
  const double ef = relative_force_error(r.f, ref10.f), ee = rel(r.energy, ref10.energy);
  const double ef3 = relative_force_error(r.f, ref3.f), ee3 = rel(r.energy, ref3.energy);
  if (rank() == 0)
    std::printf("  slab vs ewald slab 10: force %.2e energy %.2e; vs ewald slab 3: force %.2e energy %.2e\n", ef, ee,
                ef3, ee3);
  EXPECT_LE(ef, 1e-8);
  EXPECT_LE(ee, 1e-8);
  EXPECT_GT(ef3, 10 * ef);
  if (rank() == 0) EXPECT_NE(out.find("single-level grid of"), std::string::npos) << out;
  // and the measured error meets the request
  const Result r7 = kifmm("1e-6");
  EXPECT_LE(relative_force_error(r7.f, ref10.f), 1e-6);
}

TEST_F(Periodic, SlabNetChargeWarns)
{
  Configuration c = uniform_cube(201, 71);    // odd: net charge 1
  load(c, "p p f");
  commands("pair_style zero 0.1\npair_coeff * *\nkspace_style kifmm 1e-5");
  const std::string out = output_of("run 0 post no");
  if (rank() == 0) EXPECT_NE(out.find("without a neutralizing background"), std::string::npos) << out;
}

// atoms that leave the box in z between reneighborings (before LAMMPS loses them with
// boundary f): the slab's grid covers them, and the result is that of the same atoms in a box
// tall enough to hold them (the doubly periodic sum does not depend on the box height). At a
// tight accuracy: over 4 steps the close pairs of random atoms amplify force differences into
// trajectory differences (at 1e-6, about 10 times)
TEST_F(Periodic, SlabAtomsOutsideTheBoxInZAreCovered)
{
  auto run = [&](bool tall) {
    create();
    load(uniform_cube(300, 63), "p p f");
    if (tall) command("change_box all z final -0.5 1.5 units box");
    commands("set atom 1 z 0.999\nset atom 2 z 0.002\nmass * 1.0\nvelocity all set 0 0 0\n"
             "group up id 1\ngroup down id 2\nvelocity up set 0 0 2.0\nvelocity down set 0 0 -2.0\n"    // out after 1, 3 steps
             "neigh_modify every 100 delay 0 check no\ntimestep 0.005\nfix 1 all nve\n"
             "pair_style zero 0.01\npair_coeff * *\nkspace_style kifmm 1e-10\nrun 4 post no");
    return Result{forces_by_id(), thermo("elong")};
  };
  const Result ref = run(true), r = run(false);
  const double ef = relative_force_error(r.f, ref.f), ee = rel(r.energy, ref.energy);
  if (rank() == 0) std::printf("  atoms outside the slab's box in z: forces %.2e, energy %.2e\n", ef, ee);
  EXPECT_GT(positions_by_id().at(1)[2], 1.0) << "atom 1 is above the box";
  EXPECT_LT(positions_by_id().at(2)[2], 0.0) << "atom 2 is below the box";
  EXPECT_LE(ef, 1e-8);
  EXPECT_LE(ee, 1e-8);
}

// (death tests: not in the MPI runs of this binary, whose filter names the tests it runs)
TEST_F(Periodic, SlabUnsupportedSettingsAreErrors)
{
  load(uniform_cube(200, 71), "p p f");
  commands("pair_style zero 0.1\npair_coeff * *\nkspace_style kifmm 1e-5");
  command("kspace_modify kifmm grid no");
  EXPECT_LAMMPS_ERROR(command("run 0"), "grid no' \\(the octree\\) is not available with boundary p p f");
  command("kspace_modify kifmm grid auto kernel gravity 1.0 jeans yes");
  EXPECT_LAMMPS_ERROR(command("run 0"), "'kspace_modify kifmm jeans yes' is not available with boundary p p f "
                                        "\\(a slab\\).*converges without a background");
  command("kspace_modify kifmm kernel yukawa 2.0 jeans no");
  EXPECT_LAMMPS_ERROR(command("run 0"), "kernel yukawa with boundary p p f \\(a slab\\) is not supported");
}

// gravity in a slab: the doubly periodic sum of the masses as it is (the field of the mean
// surface density is that of a plane), i.e. the coulomb slab sum of charges equal to the masses
// (itself checked against ewald with a large slab factor above) times -G; on 1 to 4 ranks
TEST_F(Periodic, GravitySlabEqualsCoulombOnMasses)
{
  load(charges_equal_to_masses(uniform_cube(400, 72)), "p p f");
  command("change_box all z final 0 0.7 remap units box");
  Result coul = kifmm("1e-10", "order 12");
  Result grav = kifmm("1e-10", "kernel gravity 0.8 order 12");
  expect_gravity_is_coulomb_times_minus_g(grav, coul, 0.8, "slab");
  // the plane field: the mean vertical force on the atoms above the mid-plane points down
  double fz_up = 0.0;
  int n_up = 0;
  for (int i = 0; i < lmp->atom->nlocal; ++i)
    if (lmp->atom->x[i][2] > 0.35) {
      fz_up += lmp->atom->f[i][2];
      ++n_up;
    }
  double mine[2] = {fz_up, (double) n_up}, all[2];
  MPI_Allreduce(mine, all, 2, MPI_DOUBLE, MPI_SUM, MPI_COMM_WORLD);
  EXPECT_LT(all[0] / all[1], 0.0);
}

TEST_F(Periodic, TriclinicIsAnError)
{
  load(uniform_cube(50, 53));
  commands("change_box all triclinic\npair_style zero 0.1\npair_coeff * *\nkspace_style kifmm 1e-4");
  EXPECT_LAMMPS_ERROR(command("run 0"), "triclinic");
}

TEST_F(Periodic, MixedPeriodicityIsAnError)
{
  load(uniform_cube(50, 54), "f p p");    // periodic in y and z only (p p f is a slab)
  commands("pair_style zero 0.1\npair_coeff * *\nkspace_style kifmm 1e-4");
  EXPECT_LAMMPS_ERROR(command("run 0"), "mixed periodicity \\(boundary f p p\\)");
}

TEST_F(Periodic, GridNeedsPeriodicBoundaries)
{
  load(uniform_cube(50, 56), "f f f");
  commands("pair_style zero 0.1\npair_coeff * *\nkspace_style kifmm 1e-4\nkspace_modify kifmm grid 4");
  EXPECT_LAMMPS_ERROR(command("run 0"), "grid 4: the single-level grid needs periodic boundaries");
}

// yukawa on the grid chosen by the cost model: the first change of the box size switches to
// the octree (the grid kernels depend on kappa times the box length)
TEST_F(Periodic, YukawaAutoGridSwitchesToTheOctreeWhenTheBoxChanges)
{
  int nprocs = 1;
  MPI_Comm_size(MPI_COMM_WORLD, &nprocs);
  if (nprocs > 1) GTEST_SKIP() << "one-rank choice";
  load(uniform_cube(3000, 57));
  commands("pair_style zero 0.01\npair_coeff * *\nkspace_style kifmm 1e-5\nkspace_modify kifmm kernel yukawa 4.0");
  std::string out = output_of("run 0 post no");
  auto *ks = dynamic_cast<LAMMPS_NS::KSpaceKIFMM *>(lmp->force->kspace);
  ASSERT_NE(ks, nullptr);
  EXPECT_NE(out.find("KIFMM periodic single-level grid of"), std::string::npos) << out;
  const std::size_t cells = ks->engine_stats().n_leaves;
  EXPECT_EQ(ks->engine_stats().depth, 0);
  command("fix grow all deform 1 x final 0 1.1 y final 0 1.1 z final 0 1.1 remap x");
  out = output_of("run 3 post no");
  EXPECT_NE(out.find("kernel yukawa switches from the single-level grid to the octree"), std::string::npos) << out;
  EXPECT_GE(ks->engine_stats().depth, 1) << "octree after the switch (grid had " << cells << " cells)";
}

TEST_F(Periodic, GridValueIsChecked)
{
  load(uniform_cube(50, 56));
  commands("pair_style zero 0.1\npair_coeff * *\nkspace_style kifmm 1e-4");
  EXPECT_LAMMPS_ERROR(command("kspace_modify kifmm grid 2"), "grid 2 is out of range 3..32");
  EXPECT_LAMMPS_ERROR(command("kspace_modify kifmm grid yes"), "grid 'yes' must be auto, no or an integer");
}

// The virial tensor (pxx .. pyz, fix npt aniso, compute stress/atom) of p p p: equal to ewald's
// (k-space part + the real-space pair virial) in a cube (octree for the forces, a grid for the
// virial), rectangular boxes (grids; a flat one of 8 x 8 x 1 cells) and the anisotropic
// capacitor layers; per-atom virials sum
// to it; the trace is the energy.
TEST_F(Periodic, PressureTensorEqualsEwald)
{
  struct Box {
    double y, z;
    bool layers;
    std::string modify;
  };
  const Box boxes[] = {{1.0, 1.0, false, "order 12 leaf 40"},
                       {1.3, 0.9, false, "order 12"},
                       {1.0, 1.0, true, "order 12 leaf 40"},
                       {1.0, 0.125, false, "order 12 grid 8"}};
  for (const Box &b : boxes) {
    create();
    Configuration c = uniform_cube(500, 71);
    if (b.layers)
      for (size_t i = 0; i < c.x.size(); ++i) c.x[i][2] = (c.q[i] > 0 ? 0.2 : 0.6) + 0.1 * c.x[i][2];
    load(c);
    command(fmt_cmd("change_box all y final 0 {} z final 0 {} remap units box", b.y, b.z));
    Result ref = ewald_reference();
    commands("kspace_style none\npair_style zero 0.01\npair_coeff * *\nkspace_style kifmm 1e-12\n"
             "kspace_modify kifmm " + b.modify + "\ncompute s all stress/atom NULL\n"
             "compute ss all reduce sum c_s[1] c_s[2] c_s[3] c_s[4] c_s[5] c_s[6]\n"
             "thermo_style custom step elong pxx pyy pzz pxy pxz pyz c_ss[1] c_ss[2] c_ss[3] c_ss[4] c_ss[5] c_ss[6]\n"
             "thermo_modify norm no");
    command("run 0 post no");
    const double *w = lmp->force->kspace->virial;
    double scale = 0, err = 0, err_atom = 0;
    for (int k = 0; k < 6; ++k) {
      scale += ref.w[k] * ref.w[k];
      err += (w[k] - ref.w[k]) * (w[k] - ref.w[k]);
      // compute stress/atom: minus the per-atom virial (lj units: no conversion)
      const double sa = -evaluate(fmt_cmd("c_ss[{}]", (double) (k + 1)));
      err_atom += (sa - w[k]) * (sa - w[k]);
    }
    err = std::sqrt(err / scale);
    err_atom = std::sqrt(err_atom / scale);
    const double offdiag = std::sqrt((ref.w[3] * ref.w[3] + ref.w[4] * ref.w[4] + ref.w[5] * ref.w[5]) / scale);
    if (rank() == 0)
      std::printf("  virial tensor, box 1 x %g x %g%s: %.2e (per-atom sum %.2e; off-diagonal part %.2f)\n", b.y, b.z,
                  b.layers ? " layers" : "", err, err_atom, offdiag);
    EXPECT_LE(err, 1e-8) << b.y;
    EXPECT_LE(err_atom, 1e-10) << b.y;
    EXPECT_NEAR(w[0] + w[1] + w[2], thermo("elong"), 1e-8 * std::sqrt(scale)) << "trace = energy";
    // pressure components from the virial (V = box volume, no kinetic part at T = 0)
    const double V = lmp->domain->xprd * lmp->domain->yprd * lmp->domain->zprd;
    EXPECT_NEAR(thermo("pxy"), w[3] / V, 1e-9 * std::sqrt(scale) / V);
  }
}

// Clustered atoms next to the octree: on one rank the virial's grid is the one of least
// modelled cost on the atoms' cell occupancies (here 4^3 cells, where the rule of about as many
// cells as the octree's leaves, used on several ranks, gives 5^3); the tensor equals Ewald's.
TEST_F(Periodic, VirialGridOfClusteredAtomsIsChosenFromTheAtoms)
{
  const Configuration c = plummer(3000, 73);
  load(c);
  Result ref = ewald_reference();
  commands("kspace_style none\npair_style zero 0.01\npair_coeff * *\nkspace_style kifmm 1e-6\n"
           "kspace_modify kifmm order 8 leaf 32 tune no\n"
           "thermo_style custom step elong pxx pyy pzz pxy pxz pyz\nthermo_modify norm no");
  const std::string out = output_of("run 0 post no");
  const double *w = lmp->force->kspace->virial;
  double scale = 0, err = 0;
  for (int k = 0; k < 6; ++k) {
    scale += ref.w[k] * ref.w[k];
    err += (w[k] - ref.w[k]) * (w[k] - ref.w[k]);
  }
  EXPECT_LE(std::sqrt(err / scale), 2e-5);    // order 8
  int nproc = 1;
  MPI_Comm_size(MPI_COMM_WORLD, &nproc);
  if (rank() != 0 || nproc > 1) return;
  const std::string tag = "virial tensor (pressure components, per-atom virial) is computed on a single-level grid of ";
  const std::size_t at = out.find(tag);
  ASSERT_NE(at, std::string::npos) << out;
  int k = 0;
  ASSERT_EQ(std::sscanf(out.c_str() + at + tag.size(), "%d^3", &k), 1) << out;
  kifmm::Options o;
  o.order = 8;
  o.leaf_size = 32;
  o.periodic = o.fixed_root = true;
  o.root_half_width = 0.5;
  o.root_center[0] = o.root_center[1] = o.root_center[2] = 0.5;
  std::vector<double> xyz;
  for (const auto &[id, x] : positions_by_id()) xyz.insert(xyz.end(), {x[0], x[1], x[2]});
  int cheapest = 0;
  double least = 0;
  for (const kifmm::TreeChoice &g : kifmm::model_grids(kifmm::KernelSpec{}, o, xyz.size() / 3, xyz.data(), false))
    if (cheapest == 0 || g.cost < least) cheapest = g.grid, least = g.cost;
  EXPECT_EQ(k, cheapest) << out;
  const int uniform_rule = 5;    // cbrt(3000 / 32) = 4.5 cells per axis
  EXPECT_NE(cheapest, uniform_rule) << "the test does not tell the two choices apart";
}

// Shear: pxy against the numerical derivative of the energy under a small tilt (ewald of the
// triclinic box, complete with coul/long): W_xy = -dU/d(gamma), x -> x + gamma y.
TEST_F(Periodic, PressureTensorIsTheStrainDerivativeUnderShear)
{
  load(uniform_cube(400, 72));
  commands("kspace_style kifmm 1e-10\npair_style zero 0.01\npair_coeff * *\nkspace_modify kifmm order 12 leaf 40\n"
           "thermo_style custom step elong pxx pyy pzz pxy pxz pyz\nthermo_modify norm no\nrun 0 post no");
  double w[6];
  for (int k = 0; k < 6; ++k) w[k] = lmp->force->kspace->virial[k];
  const double gamma = 2e-4;
  auto energy_at = [&](double g) {
    create();
    load(uniform_cube(400, 72));
    commands(fmt_cmd("change_box all triclinic\nchange_box all xy final {} remap units box\n"
                     "pair_style coul/long 0.7\npair_coeff * *\npair_modify table 0\nkspace_style ewald 1e-14\n"
                     "kspace_modify gewald 9 kmax/ewald 20 20 20\nthermo_style custom step pe\nthermo_modify norm no\nrun 0 post no",
                     g * lmp->domain->yprd));
    return thermo("pe");
  };
  const double dU = (energy_at(gamma) - energy_at(-gamma)) / (2 * gamma);
  // (the same difference for x -> x + gamma z and y -> y + gamma z would test pxz, pyz)
  if (rank() == 0) std::printf("  shear: W_xy %.10g, -dU/dgamma %.10g (W_xx %.6g)\n", w[3], -dU, w[0]);
  EXPECT_NEAR(w[3], -dU, 1e-5 * std::fabs(w[0] + w[1] + w[2]));
  EXPECT_GT(std::fabs(w[3]), 1e-3 * std::fabs(w[0] + w[1] + w[2])) << "the shear component is not negligible";
}

TEST_F(Periodic, FixNptAnisoRuns)
{
  load(uniform_cube(60, 57));
  commands("pair_style zero 0.1\npair_coeff * *\nkspace_style kifmm 1e-4\nvelocity all create 1.0 5\n"
           "fix 1 all npt temp 1 1 0.1 aniso 1 1 1\nthermo_style custom step press pxx pyy pzz lx ly lz\nrun 5 post no");
  EXPECT_NE(lmp->domain->xprd, lmp->domain->yprd) << "the box deforms anisotropically";
}

// a slab under a barostat on its periodic axes (x and y uncoupled: pxx and pyy)
TEST_F(Periodic, FixNptOnTheAxesOfASlabRuns)
{
  load(uniform_cube(60, 62), "p p f");
  commands("pair_style zero 0.1\npair_coeff * *\nkspace_style kifmm 1e-4\nvelocity all create 1.0 5\n"
           "fix 1 all npt temp 1 1 0.1 x 1 1 1 y 1 1 1 couple none\n"
           "thermo_style custom step press pxx pyy pzz pxy lx ly lz\nrun 5 post no");
  EXPECT_NE(lmp->domain->xprd, lmp->domain->yprd) << "x and y change apart";
  EXPECT_NE(thermo("pxx"), thermo("pyy"));
}

TEST_F(Periodic, PressureScalarYesKeepsTheTrace)
{
  // the trace only: the scalar pressure from the energy, tensor components refused by LAMMPS
  load(uniform_cube(50, 58));
  commands("pair_style zero 0.1\npair_coeff * *\nkspace_style kifmm 1e-4\nkspace_modify pressure/scalar yes\n"
           "thermo_style custom step press elong\nthermo_modify norm no\nrun 0 post no");
  const double *w = lmp->force->kspace->virial;
  EXPECT_NEAR(w[0], thermo("elong") / 3, 1e-12 * std::fabs(thermo("elong")));
  EXPECT_EQ(w[3], 0.0);
  command("thermo_style custom step press pxx");
  EXPECT_LAMMPS_ERROR(command("run 0"), "pressure/scalar no' for tensor components");
}

// The virial tensor of a slab (p p f): the diagonal is minus the strain derivative of the slab
// energy, taken from ewald with slab factor 10 (its dipole correction makes it the doubly
// periodic energy up to terms that decay as exp(-2 pi gap / L); kspace_modify slab adds no
// virial of its own, so its W_xx is not the reference); xy equals ewald's there (the correction
// has no xy part); per-atom virials sum to it; the trace is the energy.
TEST_F(Periodic, SlabPressureTensorIsTheStrainDerivative)
{
  const Configuration conf = uniform_cube(300, 60);
  auto setup = [&]() {
    create();
    load(conf, "p p f");
    command("change_box all y final 0 0.8 z final 0 0.6 remap units box");
  };
  setup();
  const Result ref = ewald_reference(10.0);
  commands("kspace_style none\npair_style zero 0.01\npair_coeff * *\nkspace_style kifmm 1e-12\n"
           "compute s all stress/atom NULL\ncompute ss all reduce sum c_s[1] c_s[2] c_s[3] c_s[4] c_s[5] c_s[6]\n"
           "thermo_style custom step elong pxx pyy pzz pxy pxz pyz c_ss[1] c_ss[2] c_ss[3] c_ss[4] c_ss[5] c_ss[6]\n"
           "thermo_modify norm no");
  command("run 0 post no");
  double w[6], scale = 0, err_atom = 0;
  for (int k = 0; k < 6; ++k) w[k] = lmp->force->kspace->virial[k];
  for (int k = 0; k < 3; ++k) scale += std::fabs(w[k]);
  for (int k = 0; k < 6; ++k) {
    const double sa = -evaluate(fmt_cmd("c_ss[{}]", (double) (k + 1)));
    err_atom = std::max(err_atom, std::fabs(sa - w[k]) / scale);
  }
  const double V = lmp->domain->xprd * lmp->domain->yprd * lmp->domain->zprd;
  EXPECT_NEAR(thermo("pxy"), w[3] / V, 1e-9 * scale / V);
  EXPECT_NEAR(w[0] + w[1] + w[2], thermo("elong"), 1e-9 * scale) << "trace = energy";
  EXPECT_LE(err_atom, 1e-10);
  EXPECT_NEAR(w[3], ref.w[3], 1e-7 * scale) << "xy against ewald slab 10";
  EXPECT_GT(std::fabs(w[3]), 1e-3 * scale) << "the xy part is not negligible";
  const double eps = 1e-4;
  const char *axis = "xyz";
  double dU[3];
  for (int a = 0; a < 3; ++a) {
    double e[2];
    for (int sg : {1, -1}) {
      setup();
      command(std::string("change_box all ") + axis[a] + fmt_cmd(" scale {} remap", 1 + sg * eps));
      e[sg > 0 ? 0 : 1] = ewald_reference(10.0).energy;
    }
    dU[a] = (e[0] - e[1]) / (2 * eps);
    EXPECT_NEAR(w[a], -dU[a], 1e-7 * scale) << "axis " << axis[a];
  }
  if (rank() == 0)
    std::printf("  slab virial: W %.10g %.10g %.10g xy %.6g; -dU/de %.10g %.10g %.10g; ewald xy %.6g; per-atom %.1e\n", w[0],
                w[1], w[2], w[3], -dU[0], -dU[1], -dU[2], ref.w[3], err_atom);
}

TEST_F(Periodic, OpenBoundariesKeepTheTensor)
{
  // the flag is only set for periodic boxes: open boundaries report pxx (exact tensor)
  load(uniform_cube(50, 59), "f f f");
  commands("pair_style zero 0.1\npair_coeff * *\nkspace_style kifmm 1e-6\nthermo_style custom step pxx pyy pzz\n"
           "run 0 post no");
  EXPECT_NE(thermo("pxx"), 0.0);
  EXPECT_EQ(lmp->force->kspace->scalar_pressure_flag, 0);
}

TEST_F(Periodic, PerAtomVirialAfterPressureScalarYesIsAnError)
{
  load(uniform_cube(50, 55));
  commands("pair_style zero 0.1\npair_coeff * *\nkspace_style kifmm 1e-4\nkspace_modify pressure/scalar yes\n"
           "compute s all stress/atom NULL\ncompute ss all reduce sum c_s[1]\nthermo_style custom step c_ss");
  EXPECT_LAMMPS_ERROR(command("run 0"), "per-atom virial");
}

// periodic yukawa: the virial tensor equals the pair virial of coul/debye with a cutoff beyond
// which exp(-kappa r) < 1e-16 (it sums the images exactly), in a rectangular box (grid) and a
// cube (octree for the forces, a grid next to it for the virial); per-atom virials sum to it;
// pressure/scalar yes gives a third of its trace on the diagonal
TEST_F(Periodic, ScreenedPressureTensorEqualsCoulDebye)
{
  const double kappa = 8.0, rc = 37.0 / kappa;
  for (const char *box : {"1.3 0.9", "1 1"}) {
    create();
    load(uniform_cube(300, 49));
    double ly, lz;
    std::sscanf(box, "%lf %lf", &ly, &lz);
    command(fmt_cmd("change_box all y final 0 {} z final 0 {} remap units box", ly, lz));
    commands(fmt_cmd("neigh_modify one 100000 page 2000000\npair_style coul/debye {} {}\npair_coeff * *\n"
                     "run 0 post no", kappa, rc));
    double ref[6], scale = 0;    // a pair style's virial is per rank
    MPI_Allreduce(lmp->force->pair->virial, ref, 6, MPI_DOUBLE, MPI_SUM, MPI_COMM_WORLD);
    for (int k = 0; k < 3; ++k) scale += std::fabs(ref[k]);
    commands("pair_style zero 0.01\npair_coeff * *\nkspace_style kifmm 1e-10\n"
             "kspace_modify kifmm kernel yukawa " + to_s(kappa) + " order 12\n"
             "compute s all stress/atom NULL\ncompute ss all reduce sum c_s[1] c_s[2] c_s[3] c_s[4] c_s[5] c_s[6]\n"
             "thermo_style custom step pe pxx pyy pzz pxy pxz pyz c_ss[1] c_ss[2] c_ss[3] c_ss[4] c_ss[5] c_ss[6]\n"
             "thermo_modify norm no");
    command("run 0 post no");
    const double *w = lmp->force->kspace->virial;
    double err = 0, err_atom = 0;
    for (int k = 0; k < 6; ++k) {
      err = std::max(err, std::fabs(w[k] - ref[k]) / scale);
      err_atom = std::max(err_atom, std::fabs(-evaluate(fmt_cmd("c_ss[{}]", (double) (k + 1))) - w[k]) / scale);
    }
    const double offdiag = (std::fabs(ref[3]) + std::fabs(ref[4]) + std::fabs(ref[5])) / scale;
    if (rank() == 0)
      std::printf("  yukawa virial, box 1 x %s: %.2e (per-atom sum %.2e; off-diagonal part %.2f)\n", box, err, err_atom,
                  offdiag);
    EXPECT_LE(err, 1e-8) << box;
    EXPECT_LE(err_atom, 1e-10) << box;
    EXPECT_GT(offdiag, 1e-3) << box;
    commands("thermo_style custom step pe press\nuncompute ss\nuncompute s\nkspace_modify pressure/scalar yes\n"
             "run 0 post no");
    const double tr = (ref[0] + ref[1] + ref[2]) / 3;
    EXPECT_NEAR(w[0], tr, 1e-8 * scale) << box;
    EXPECT_NEAR(w[2], tr, 1e-8 * scale) << box;
    EXPECT_EQ(w[3], 0.0) << box;
  }
}

}    // namespace
