// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// Shared helpers of the fix clump/rigid tests (LAMMPS instances: lammps_session.h): the standard
// box, molecule files written on the fly, and the per-clump rows of compute rigid/local "<fix-ID>_local" gathered over ranks.
#pragma once

#include "clump_union.h"

#include "configurations.h"
#include "lammps_session.h"

#include "compute.h"
#include "input.h"
#include "lammps.h"
#include "modify.h"

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <mpi.h>
#include <sstream>
#include <string>
#include <unistd.h>
#include <vector>

namespace clump_test {

const std::string potentials = POTENTIALS_DIR;

// Columns of "<ID>_local" (0-based), as documented in doc/fix_clump_rigid.rst.
enum Col {
  ID = 0, MOL, MASS, X, Y, Z, XU, YU, ZU, VX, VY, VZ, FX, FY, FZ, TQX, TQY, TQZ, OMEGAX, OMEGAY,
  OMEGAZ, ANGMOMX, ANGMOMY, ANGMOMZ, QUATW, QUATI, QUATJ, QUATK, INERTIAX, INERTIAY, INERTIAZ,
  NCOL
};

// si units, spheres with charge and molecule IDs, box of +-half, pair zero (no contacts)
inline std::string box_commands(double half = 0.2, const std::string &boundary = "p p p")
{
  char buf[1024];
  std::snprintf(buf, sizeof(buf), R"(
units si
atom_style hybrid sphere charge
atom_modify map array
boundary %s
fix prop all property/atom mol ghost yes
region box block %g %g %g %g %g %g
create_box 2 box
mass * 1.0
comm_modify cutoff %g vel yes
neighbor 0.002 bin
thermo_style custom step
)",
                boundary.c_str(), -half, half, -half, half, -half, half, 0.8 * half);
  return buf;
}

using kifmm_test::open_lammps;
using kifmm_test::run_lines;

// Molecules dim/asym/dip and a row of 8 clumps along x (IDs 100-107), one straddling x = 0
// (the processor boundary on 2 ranks).
inline std::string clump_row_commands(const std::string &dimer_file, const std::string &asym_file)
{
  std::ostringstream s;
  s << "molecule dim " << dimer_file << "\nmolecule asym " << asym_file << "\nmolecule dip "
    << potentials << "/dipole3.mol\n";
  const char *shape[] = {"dim", "asym", "dip", "dim", "asym", "dip", "dim", "asym"};
  for (int k = 0; k < 8; ++k) {
    double x = -0.17 + 0.045 * k;
    s << "create_atoms 0 single " << x << " " << 0.003 * (k % 3) << " " << -0.030 + 0.003 * (k % 2)
      << " mol " << shape[k] << " " << 100 + k << " rotate " << 17 * k + 5 << " 1 " << k % 3
      << " 2\n";
  }
  return s.str();
}

using Pebble = kifmm_test::MoleculePebble;
using kifmm_test::read_molecule;

// Per-process scratch directory, removed when the process exits (also after a LAMMPS error,
// which ends the process through exit()).
inline std::filesystem::path scratch_dir()
{
  static std::string dir;
  if (dir.empty()) {
    dir = (std::filesystem::temp_directory_path() /
           ("clump_test_" + std::to_string((long) getpid())))
              .string();
    std::filesystem::create_directories(dir);
    std::atexit([] {
      std::error_code ec;
      std::filesystem::remove_all(dir, ec);
    });
  }
  return dir;
}

// Writes a molecule file of pebbles (type 1 if q == 0, else 2) into the scratch directory.
inline std::string write_molecule(const std::string &name, const std::vector<Pebble> &p)
{
  auto dir = scratch_dir();
  auto path = (dir / (name + ".mol")).string();
  std::ofstream f(path);
  f.precision(17);
  f << "# " << name << "\n\n" << p.size() << " atoms\n\nCoords\n\n";
  for (size_t i = 0; i < p.size(); ++i)
    f << i + 1 << ' ' << p[i].x << ' ' << p[i].y << ' ' << p[i].z << '\n';
  f << "\nTypes\n\n";
  for (size_t i = 0; i < p.size(); ++i) f << i + 1 << ' ' << (p[i].q != 0.0 ? 2 : 1) << '\n';
  f << "\nCharges\n\n";
  for (size_t i = 0; i < p.size(); ++i) f << i + 1 << ' ' << p[i].q << '\n';
  f << "\nDiameters\n\n";
  for (size_t i = 0; i < p.size(); ++i) f << i + 1 << ' ' << 2 * p[i].r << '\n';
  return path;
}

inline std::vector<clump::Sphere> spheres(const std::vector<Pebble> &p)
{
  std::vector<clump::Sphere> s;
  for (const auto &q : p) s.push_back({{q.x, q.y, q.z}, q.r});
  return s;
}

// overlapping dimer: two pebbles r = 0.005 at +-0.003 on x (overlap 0.004)
inline std::vector<Pebble> dimer()
{
  return {{-0.003, 0, 0, 0.005, 0.0}, {0.003, 0, 0, 0.005, 0.0}};
}

// asymmetric clump: three distinct principal moments, overlapping pebbles
inline std::vector<Pebble> asymmetric()
{
  return {{0, 0, 0, 0.006, 0},
          {0.012, 0, 0, 0.005, 0},
          {-0.012, 0, 0, 0.005, 0},
          {0, 0.008, 0, 0.005, 0},
          {0.003, 0, 0.005, 0.004, 0}};
}

// Rows of compute rigid/local "<fix_id>_local" of all ranks, keyed by molecule ID.
inline std::map<int, std::vector<double>> clump_rows(LAMMPS_NS::LAMMPS *lmp,
                                                      const std::string &fix_id)
{
  int ic = lmp->modify->find_compute(fix_id + "_local");
  std::vector<double> mine;
  if (ic >= 0) {
    LAMMPS_NS::Compute *c = lmp->modify->compute[ic];
    c->compute_local();
    for (int i = 0; i < c->size_local_rows; ++i)
      for (int k = 0; k < NCOL; ++k) mine.push_back(c->array_local[i][k]);
  }
  const std::vector<double> all = kifmm_test::gather_rows(lmp, mine, NCOL);
  std::map<int, std::vector<double>> rows;
  for (std::size_t k = 0; k + NCOL <= all.size(); k += NCOL)
    rows[(int) all[k + MOL]] = std::vector<double>(all.begin() + k, all.begin() + k + NCOL);
  return rows;
}

}    // namespace clump_test
