// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// fix kifmm/polarize: induced point dipoles of polarizable spheres solved by kspace_style kifmm.
// The dipoles against a dense direct solve of the same linear system written in this test
// (Laplace field tensors, the field of the charges and of fix efield), the forces against the
// numerical derivative of the total energy (kspace, fix efield and the polarization energy),
// energy conservation under fix nve/sphere, the solve's report, and the clear errors. Under
// mpiexec the same comparisons hold on several ranks, and the distributed solve equals the
// solve on one rank.
#include "lammps_fixture.h"

#include "atom.h"
#include "lammps.h"
#include "library.h"

#include <Eigen/Dense>

#include <cmath>
#include <cstdio>

using namespace kifmm_test;

namespace {

constexpr double kRadius = 0.5, kPermittivity = 10.0;
const double kAlpha = kRadius * kRadius * kRadius * (kPermittivity - 1.0) / (kPermittivity + 2.0);
const double kField[3] = {0.1, 0.0, 0.4};

class Polarize : public LammpsFixture {
 public:
  using LammpsFixture::commands;
  using LammpsFixture::forces_by_id;
  using LammpsFixture::positions_by_id;
  using LammpsFixture::thermo;

 protected:
  // k^3 spheres of diameter 1 on a jittered simple cubic lattice of spacing 1.2 (open box):
  // type 1 polarizable and neutral, type 2 charge +1, type 3 charge -1; a uniform field
  static std::string sphere_input(int k, const std::string &boundary = "f f f")
  {
    const std::string lo = "-1.0", hi = std::to_string(1.2 * (k - 1) + 1.0), km = std::to_string(k - 1);
    return "units lj\natom_style hybrid sphere dipole\nboundary " + boundary + "\natom_modify map array\n"
             "lattice sc 1.2\nregion box block " + lo + " " + hi + " " + lo + " " + hi + " " + lo + " " + hi +
             " units box\ncreate_box 3 box\nregion inner block 0 " + km + " 0 " + km + " 0 " + km +
             "\ncreate_atoms 1 region inner\ndisplace_atoms all random 0.08 0.08 0.08 4711 units box\n"
             "set type 1 type/fraction 2 0.2 99\nset type 1 type/fraction 3 0.2 98\n"
             "set type 1 charge 0.0\nset type 2 charge 1.0\nset type 3 charge -1.0\nset group all dipole 0 0 0\n"
             "group pol type 1\nneighbor 0.3 bin\nneigh_modify one 10000 page 200000\n"
             "fix ef all efield " + std::to_string(kField[0]) + " " + std::to_string(kField[1]) + " " +
             std::to_string(kField[2]) + "\nfix_modify ef energy yes\n";
  }
  void spheres(int k, const std::string &boundary = "f f f") { commands(sphere_input(k, boundary)); }
  static std::string polarize_input(const std::string &accuracy, const std::string &fix_args,
                                    const std::string &modify = "")
  {
    return "fix pol pol kifmm/polarize " + fix_args + "\nfix_modify pol energy yes\n"
           "kspace_style kifmm " + accuracy + "\n"
           "thermo_style custom step pe elong f_pol f_pol[1] f_pol[2] f_pol[3]\nthermo_modify norm no\n" +
           (modify.empty() ? std::string() : "kspace_modify kifmm " + modify + "\n");
  }
  void polarize(const std::string &accuracy, const std::string &fix_args, const std::string &modify = "")
  {
    commands(polarize_input(accuracy, fix_args, modify));
  }

  // the dense solve of mu_i / alpha - sum_j T_ij mu_j = E_i (E: the field and the charges' field)
  std::map<int, Vec3> dense_dipoles()
  {
    const auto x = positions_by_id();
    std::vector<int> pol;
    std::vector<Vec3> charged_x;
    std::vector<double> charged_q;
    for (const auto &[id, xi] : x) {
      const double q = evaluate("q[" + std::to_string(id) + "]");
      if (q == 0.0)
        pol.push_back(id);
      else
        charged_x.push_back(xi), charged_q.push_back(q);
    }
    const std::size_t m = 3 * pol.size();
    Eigen::MatrixXd A = Eigen::MatrixXd::Identity(m, m) / kAlpha;
    Eigen::VectorXd b(m);
    for (std::size_t a = 0; a < pol.size(); ++a) {
      const Vec3 &xa = x.at(pol[a]);
      for (int d = 0; d < 3; ++d) b(3 * a + d) = kField[d];
      for (std::size_t c = 0; c < charged_q.size(); ++c) {
        double r[3], r2 = 0;
        for (int d = 0; d < 3; ++d) r[d] = xa[d] - charged_x[c][d], r2 += r[d] * r[d];
        for (int d = 0; d < 3; ++d) b(3 * a + d) += charged_q[c] * r[d] / (r2 * std::sqrt(r2));
      }
      for (std::size_t o = 0; o < pol.size(); ++o) {
        if (o == a) continue;
        double r[3], r2 = 0;
        for (int d = 0; d < 3; ++d) r[d] = xa[d] - x.at(pol[o])[d], r2 += r[d] * r[d];
        const double r5 = r2 * r2 * std::sqrt(r2);
        for (int d = 0; d < 3; ++d)
          for (int e = 0; e < 3; ++e) A(3 * a + d, 3 * o + e) -= (3 * r[d] * r[e] - (d == e ? r2 : 0.0)) / r5;
      }
    }
    const Eigen::VectorXd mu = A.ldlt().solve(b);
    std::map<int, Vec3> out;
    for (const auto &[id, xi] : x) out[id] = {0, 0, 0};
    for (std::size_t a = 0; a < pol.size(); ++a) out[pol[a]] = {mu(3 * a), mu(3 * a + 1), mu(3 * a + 2)};
    return out;
  }
  std::map<int, Vec3> dipoles() { return dipoles_by_id(lmp); }
};

// the induced dipoles equal the dense solution; the solve is reported (iterations, residual)
TEST_F(Polarize, DipolesEqualTheDenseSolve)
{
  spheres(8);
  polarize("1e-8", "permittivity 10 tol 1e-10", "leaf 16");    // a tree with a far field
  commands("pair_style zero 1.0\npair_coeff * *\nrun 0 post no");
  const std::map<int, Vec3> ref = dense_dipoles(), mu = dipoles();
  const double err = relative_force_error(mu, ref);
  std::printf("  %d atoms, %g polarizable: dipoles %.2e from the dense solve; %g iterations, residual %.2e\n",
              natoms(), evaluate("count(pol)"), err, evaluate("f_pol[1]"), evaluate("f_pol[2]"));
  EXPECT_LE(err, 30 * 1e-8);    // the FMM field error (1e-8 on forces and torques) through the system
  const double first = evaluate("f_pol[1]");
  EXPECT_GT(first, 2);
  EXPECT_LE(evaluate("f_pol[2]"), 1e-10);
  for (const auto &[id, m] : mu)
    if (evaluate("q[" + std::to_string(id) + "]") != 0.0) EXPECT_EQ(m[0] * m[0] + m[1] * m[1] + m[2] * m[2], 0.0);
  // the polarization energy is the fix's scalar: sum mu^2 / (2 alpha)
  double upol = 0;
  for (const auto &[id, m] : ref) upol += (m[0] * m[0] + m[1] * m[1] + m[2] * m[2]) / (2 * kAlpha);
  EXPECT_NEAR(evaluate("f_pol"), upol, 1e-6 * upol);
  // the next evaluation starts from these dipoles: a few iterations (its order may differ)
  command("run 0 post no");
  EXPECT_LE(evaluate("f_pol[1]"), first / 2);
}

// On several ranks (ctest runs this binary under mpiexec -np 2) every field evaluation of the
// solve is distributed; the dipoles, forces and energy equal the same run on one rank (a second
// LAMMPS on MPI_COMM_SELF), open boundaries with a far field and the periodic grid
TEST_F(Polarize, SeveralRanksEqualOneRank)
{
  for (const char *boundary : {"f f f", "p p p"}) {
    const std::string lines = sphere_input(8, boundary) +
        polarize_input("1e-8", "permittivity 10 tol 1e-12", std::string("order 6 leaf 16") +
                                                               (boundary[0] == 'p' ? " grid 3" : "")) +
        "pair_style zero 1.0\npair_coeff * *\nrun 0 post no\n";
    create();
    commands(lines);
    const std::map<int, Vec3> mu = dipoles(), f = forces_by_id();
    const double e = thermo("pe");
    LAMMPS_NS::LAMMPS *one = open_lammps(MPI_COMM_SELF);
    run_lines(one, lines);
    const std::map<int, Vec3> mu1 = dipoles_by_id(one), f1 = kifmm_test::forces_by_id(one);
    const double e1 = lammps_get_thermo(one, "pe");
    delete one;
    EXPECT_EQ(mu.size(), mu1.size());
    EXPECT_GT(mu.size(), 300u);
    EXPECT_LE(relative_force_error(mu, mu1), 1e-9) << boundary;
    EXPECT_LE(relative_force_error(f, f1), 1e-9) << boundary;
    EXPECT_LE(std::fabs(e - e1), 1e-9 * std::fabs(e1)) << boundary;
  }
}

// alpha as a number and as an atom-style variable give the permittivity's dipoles
TEST_F(Polarize, AlphaFromNumberOrVariable)
{
  spheres(5);
  commands("variable a atom " + std::to_string(kAlpha) + "*(x>-100)\n");
  commands("pair_style zero 1.0\npair_coeff * *\n");
  polarize("1e-8", "permittivity 10 tol 1e-10");
  command("run 0 post no");
  const auto ref = dipoles();
  for (const std::string &a : {"alpha " + std::to_string(kAlpha), std::string("alpha v_a")}) {
    command("unfix pol");
    command("set group all dipole 0 0 0");
    polarize("1e-8", a + " tol 1e-10");
    command("run 0 post no");
    EXPECT_LE(relative_force_error(dipoles(), ref), 1e-9) << a;
  }
}

// forces are minus the derivative of the total energy (kspace + fix efield + polarization
// energy) in the positions: the dipoles minimize it, so their own change does not enter.
// Central differences of the energy along x, y, z at a few atoms, against their forces.
void expect_forces_are_energy_derivative(Polarize &t, const std::vector<int> &ids)
{
  const auto f = t.forces_by_id();
  const auto x = t.positions_by_id();
  double frms = 0;
  for (const auto &[id, fi] : f) frms += fi[0] * fi[0] + fi[1] * fi[1] + fi[2] * fi[2];
  frms = std::sqrt(frms / f.size());
  const double h = 1e-4;
  const char *axis[3] = {"x", "y", "z"};
  for (int id : ids)
    for (int d = 0; d < 3; ++d) {
      auto energy_at = [&](double v) {
        char buf[64];
        std::snprintf(buf, sizeof buf, "%.17g", v);
        t.commands("set atom " + std::to_string(id) + " " + axis[d] + " " + buf + "\nrun 0 post no");
        return t.thermo("pe");
      };
      const double up = energy_at(x.at(id)[d] + h), down = energy_at(x.at(id)[d] - h);
      energy_at(x.at(id)[d]);
      EXPECT_NEAR(-(up - down) / (2 * h), f.at(id)[d], 1e-6 * frms) << "atom " << id << " axis " << axis[d];
    }
}

TEST_F(Polarize, ForcesAreTheEnergyDerivative)
{
  spheres(5);
  polarize("1e-10", "permittivity 10 tol 1e-12");
  commands("pair_style zero 1.0\npair_coeff * *\nrun 0 post no");
  expect_forces_are_energy_derivative(*this, {1, 7, 31, 64, 100});
}

// fix nve/sphere with soft repulsion: the total energy (with the polarization energy) is
// conserved as velocity Verlet conserves a true potential energy: its deviation falls as dt^2
// (forces that were not its derivative would leave a drift independent of dt), and it is far
// below the change of the polarization energy over the run
TEST_F(Polarize, NveConservesTheEnergy)
{
  auto deviation = [&](double dt, double &pol_change) {
    create();
    spheres(5, "s s s");
    polarize("1e-8", "permittivity 10 tol 1e-9");
    commands("pair_style soft 1.0\npair_coeff * * 10.0\nvelocity all create 0.3 777 loop geom\n"
             "fix nve all nve/sphere\ntimestep " + std::to_string(dt) + "\ncompute erot all erotate/sphere\n"
             "variable etot equal etotal+c_erot\nvariable epol equal f_pol\n"
             "thermo_style custom step pe etotal c_erot v_etot f_pol f_pol[1]\nthermo_modify norm no\nrun 0 post no");
    const double e0 = evaluate("v_etot"), p0 = evaluate("v_epol");
    double maxdev = 0;
    pol_change = 0;
    const int steps = (int) std::lround(0.1 / dt);
    for (int k = 0; k < 4; ++k) {
      command("run " + std::to_string(steps) + " post no");
      maxdev = std::max(maxdev, std::fabs(evaluate("v_etot") - e0));
      pol_change = std::max(pol_change, std::fabs(evaluate("v_epol") - p0));
    }
    return maxdev;
  };
  double pol = 0, pol_half = 0;
  const double dev = deviation(0.002, pol), dev_half = deviation(0.001, pol_half);
  std::printf("  total energy deviation: %.2e at dt 0.002, %.2e at dt 0.001; polarization energy changed by %.2e\n",
              dev, dev_half, pol);
  EXPECT_LE(dev_half, dev / 3);
  EXPECT_GT(pol, 1000 * dev_half);
}

// periodic boundaries: the tin-foil sum of charges and induced dipoles; the dipoles converge
// and the forces are the derivative of the energy there too
TEST_F(Polarize, PeriodicForcesAreTheEnergyDerivative)
{
  spheres(5, "p p p");
  polarize("1e-10", "permittivity 10 tol 1e-12");
  commands("pair_style zero 1.0\npair_coeff * *\nrun 0 post no");
  EXPECT_LE(evaluate("f_pol[2]"), 1e-12);
  EXPECT_GT(evaluate("f_pol"), 0.0);
  expect_forces_are_energy_derivative(*this, {64});
}

// the start of each solve extrapolated from the last two (predict yes, the default) takes fewer
// iterations than the last dipoles alone, for the same trajectory within the tolerance
TEST_F(Polarize, PredictorSavesIterations)
{
  auto run = [&](const char *predict) {
    create();
    spheres(5);
    polarize("1e-6", std::string("permittivity 10 tol 1e-8 predict ") + predict);
    commands("pair_style soft 1.0\npair_coeff * * 10.0\nvelocity all create 0.3 777 loop geom\n"
             "fix nve all nve/sphere\ntimestep 0.002\nvariable it equal f_pol[1]\n"
             "fix its all ave/time 1 100 100 v_it\nrun 100 post no");
    return std::make_tuple(evaluate("f_its"), positions_by_id(), dipoles());
  };
  const auto [with, x1, mu1] = run("yes");
  const auto [without, x0, mu0] = run("no");
  std::printf("  mean iterations per solve: %.2f predicted, %.2f from the last dipoles\n", with, without);
  EXPECT_LT(with, 0.8 * without);
  EXPECT_LE(relative_force_error(x1, x0), 1e-6);
  EXPECT_LE(relative_force_error(mu1, mu0), 1e-5);
}

// with fix kifmm/stride the dipoles are solved on evaluation steps only: N = 1 is the run
// without the fix bit for bit; with N = 3 the dipoles between evaluations are the last ones
TEST_F(Polarize, StrideSolvesOnEvaluationSteps)
{
  auto trajectory = [&](const std::string &fix, int steps) {
    create();
    spheres(4);
    polarize("1e-6", "permittivity 10 tol 1e-8");
    // tune no: the runs are compared bit for bit, so the modelled tree, not a timed one
    commands("kspace_modify kifmm tune no\npair_style soft 1.0\npair_coeff * * 10.0\nvelocity all create 0.3 777 loop geom\n"
             "fix nve all nve/sphere\ntimestep 0.002");
    if (!fix.empty()) command(fix);
    command("run " + std::to_string(steps) + " post no");
    return std::make_pair(positions_by_id(), dipoles());
  };
  const auto [x0, mu0] = trajectory("", 12);
  const auto [x1, mu1] = trajectory("fix st all kifmm/stride 1", 12);
  EXPECT_EQ(relative_force_error(x1, x0), 0.0);
  EXPECT_EQ(relative_force_error(mu1, mu0), 0.0);
  const auto [x3, mu3] = trajectory("fix st all kifmm/stride 3", 3);    // evaluated at step 3
  const auto [x4, mu4] = trajectory("fix st all kifmm/stride 3", 5);    // held at 4 and 5
  EXPECT_GT(relative_force_error(x4, x3), 1e-6);
  EXPECT_EQ(relative_force_error(mu4, mu3), 0.0);
  EXPECT_GT(relative_force_error(mu3, trajectory("fix st all kifmm/stride 3", 2).second), 1e-8);
}

using PolarizeErrors = Polarize;

TEST_F(PolarizeErrors, NeedsKspaceKifmm)
{
  spheres(3);
  commands("fix pol pol kifmm/polarize alpha 0.1\npair_style zero 1.0\npair_coeff * *");
  EXPECT_LAMMPS_ERROR(command("run 0"), "fix kifmm/polarize requires kspace_style kifmm");
}

TEST_F(PolarizeErrors, GravityIsAnError)
{
  spheres(3);
  commands("fix pol pol kifmm/polarize alpha 0.1\npair_style zero 1.0\npair_coeff * *\nkspace_style kifmm 1e-4\n"
           "kspace_modify kifmm kernel gravity 1.0");
  EXPECT_LAMMPS_ERROR(command("run 0"), "kernel coulomb or yukawa, not gravity");
}

TEST_F(PolarizeErrors, MissingPolarizabilityIsAnError)
{
  spheres(3);
  EXPECT_LAMMPS_ERROR(command("fix pol pol kifmm/polarize tol 1e-6"), "the polarizability is missing");
}

TEST_F(PolarizeErrors, FieldFromVariablesIsAnError)
{
  spheres(3);
  commands("unfix ef\nvariable ez equal 0.4\nfix ef all efield 0 0 v_ez\npair_style zero 1.0\npair_coeff * *");
  polarize("1e-4", "alpha 0.1");
  EXPECT_LAMMPS_ERROR(command("run 0"), "the field of fix ef \\(style efield\\) cannot be its external field: its "
                                        "field is given by variables");
}

// point dipoles this polarizable this close have no stable solution: said, not a NaN
TEST_F(PolarizeErrors, PolarizationCatastropheIsAnError)
{
  commands("units lj\natom_style hybrid sphere dipole\nboundary f f f\nregion box block -3 3 -3 3 -3 3\n"
           "create_box 1 box\ncreate_atoms 1 single 0 0 0\ncreate_atoms 1 single 1 0 0\nset group all charge 0\n"
           "fix ef all efield 1 0 0\npair_style zero 1.0\npair_coeff * *\n"
           "fix pol all kifmm/polarize alpha 1.0\nkspace_style kifmm 1e-6");
  EXPECT_LAMMPS_ERROR(command("run 0"), "the induced dipoles have no stable solution");
}

}    // namespace
