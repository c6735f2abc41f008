#!/usr/bin/env python3
# This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
"""Stability of a nested stack of platelets with the platelets scene's contact model and time
step (examples/platelets/parameters.lmp), for one variant (--quick 1 or 0).

Runs platelet_stack.lmp twice in the example directory (read only, -log none):
  1. the scene's parameters: LAMMPS must finish, the largest |v_z| (stack axis) must never
     exceed 10x its value at step 0 and must end below 0.2x of it (the contacts damp the
     stack's motion), and the number of pebble contacts at the end must be at least half of
     that at step 0 (the stack stays nested);
  2. control: the same with Fdamp = 100 (the damping of restitution e = 0.7 without the cap,
     2 nface damp dt = 2.5 quick, 6.2 full) must FAIL these criteria (LAMMPS error or growth),
     so that the test can tell an unstable setting from a stable one.

usage: check_platelet_stack.py --lmp LMP --example DIR --quick 0|1
"""
import argparse
import os
import subprocess
import sys


def run(lmp, example, quick, extra):
    script = os.path.join(os.path.dirname(os.path.abspath(__file__)), "platelet_stack.lmp")
    cmd = [lmp, "-in", script, "-var", "quick", str(quick), "-log", "none", "-nocite"] + extra
    env = dict(os.environ, OMP_NUM_THREADS=os.environ.get("OMP_NUM_THREADS", "1"))
    p = subprocess.run(cmd, cwd=example, capture_output=True, text=True, env=env)
    rows, header = [], None
    for line in p.stdout.splitlines():
        f = line.split()
        if f and f[0] == "Step":
            header = f
            continue
        if header and len(f) == len(header):
            try:
                rows.append(dict(zip(header, map(float, f))))
            except ValueError:
                header = None
        elif header and f and f[0] == "Loop":
            header = None
    errors = [l for l in (p.stdout + p.stderr).splitlines() if "ERROR" in l]
    return p.returncode, rows, errors, [l for l in p.stdout.splitlines() if l.startswith("stack:")]


def verdict(code, rows, errors):
    """List of failed criteria (empty: stable)."""
    if code != 0 or errors:
        return [f"LAMMPS failed (exit {code}): {errors[:1]}"]
    if len(rows) < 2:
        return ["no thermo output"]
    vz = [max(r["c_vhi[3]"], -r["c_vlo[3]"]) for r in rows]
    bad = []
    if max(vz) > 10 * vz[0]:
        bad.append(f"|v_z| grew from {vz[0]:.3g} to {max(vz):.3g}")
    if vz[-1] > 0.2 * vz[0]:
        bad.append(f"|v_z| at the end {vz[-1]:.3g} > 0.2 x {vz[0]:.3g}")
    if rows[-1]["v_ncontact"] < 0.5 * rows[0]["v_ncontact"]:
        bad.append(f"contacts {rows[0]['v_ncontact']:.0f} -> {rows[-1]['v_ncontact']:.0f}")
    return bad


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--lmp", required=True)
    ap.add_argument("--example", required=True)
    ap.add_argument("--quick", type=int, choices=(0, 1), required=True)
    a = ap.parse_args()
    ok = True
    for name, extra, want_stable in (("scene parameters", [], True),
                                     ("control, Fdamp = 100 (no damping cap)",
                                      ["-var", "Fdamp", "100"], False)):
        code, rows, errors, info = run(a.lmp, a.example, a.quick, extra)
        bad = verdict(code, rows, errors)
        vz = [max(r["c_vhi[3]"], -r["c_vlo[3]"]) for r in rows]
        print(f"{name}: {info[0] if info else ''}")
        if vz:
            print(f"  max |v_z| at step 0 {vz[0]:.3g}, largest {max(vz):.3g}, end {vz[-1]:.3g}; "
                  f"contacts {rows[0]['v_ncontact']:.0f} -> {rows[-1]['v_ncontact']:.0f}")
        print("  " + ("stable" if not bad else "UNSTABLE: " + "; ".join(bad)))
        if (not bad) != want_stable:
            ok = False
            print("  FAIL: expected " + ("stable" if want_stable else "unstable"))
    print("PASSED" if ok else "FAILED")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
