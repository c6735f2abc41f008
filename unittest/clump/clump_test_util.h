// This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
// Shared helpers of the fix clump/rigid tests: the standard box, molecule files written on the
// fly, and the per-clump rows of compute rigid/local "<fix-ID>_local" gathered over ranks.
#pragma once

#include "clump_union.h"

#include "package_styles.h"

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

// A LAMMPS instance on `comm` with the package's styles (quiet unless KIFMM_TEST_VERBOSE).
inline LAMMPS_NS::LAMMPS *make_lammps(MPI_Comm comm, const std::string &log = "none")
{
  std::vector<std::string> args = {"clump_test", "-log", log, "-nocite", "-echo", "none"};
  if (!std::getenv("KIFMM_TEST_VERBOSE")) {
    args.push_back("-screen");
    args.push_back("none");
  }
  std::vector<char *> argv;
  for (auto &a : args) argv.push_back(const_cast<char *>(a.c_str()));
  argv.push_back(nullptr);
  auto *lmp = new LAMMPS_NS::LAMMPS((int) args.size(), argv.data(), comm);
  kifmm_lammps::add_package_styles(lmp);
  return lmp;
}

// Runs the non-blank lines of `script` one by one.
inline void run_script(LAMMPS_NS::LAMMPS *lmp, const std::string &script)
{
  std::istringstream in(script);
  std::string line;
  while (std::getline(in, line))
    if (line.find_first_not_of(" \t") != std::string::npos) lmp->input->one(line);
}

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

struct Pebble {
  double x = 0, y = 0, z = 0, r = 0, q = 0;
};

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

// Pebbles (Coords, Diameters, Charges) of a molecule file as written by tools/clump_shapes.py.
inline std::vector<Pebble> read_molecule(const std::string &path)
{
  std::ifstream f(path);
  std::string line, section;
  std::map<int, Pebble> p;
  while (std::getline(f, line)) {
    auto hash = line.find('#');
    if (hash != std::string::npos) line.resize(hash);
    if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
    if (line == "Coords" || line == "Types" || line == "Charges" || line == "Diameters") {
      section = line;
      continue;
    }
    int id;
    double a, b, c;
    if (section == "Coords" && std::sscanf(line.c_str(), "%d %lf %lf %lf", &id, &a, &b, &c) == 4) {
      p[id].x = a;
      p[id].y = b;
      p[id].z = c;
    } else if (section == "Diameters" && std::sscanf(line.c_str(), "%d %lf", &id, &a) == 2)
      p[id].r = 0.5 * a;
    else if (section == "Charges" && std::sscanf(line.c_str(), "%d %lf", &id, &a) == 2)
      p[id].q = a;
  }
  std::vector<Pebble> out;
  for (auto &[id, q] : p) out.push_back(q);
  return out;
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
  int n = (int) mine.size(), nprocs;
  MPI_Comm_size(lmp->world, &nprocs);
  std::vector<int> counts(nprocs), displs(nprocs);
  MPI_Allgather(&n, 1, MPI_INT, counts.data(), 1, MPI_INT, lmp->world);
  int total = 0;
  for (int p = 0; p < nprocs; ++p) {
    displs[p] = total;
    total += counts[p];
  }
  std::vector<double> all(total);
  MPI_Allgatherv(mine.data(), n, MPI_DOUBLE, all.data(), counts.data(), displs.data(),
                 MPI_DOUBLE, lmp->world);
  std::map<int, std::vector<double>> rows;
  for (int k = 0; k + NCOL <= total; k += NCOL)
    rows[(int) all[k + MOL]] = std::vector<double>(all.begin() + k, all.begin() + k + NCOL);
  return rows;
}

}    // namespace clump_test
