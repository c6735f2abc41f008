# This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
"""tools/clump_shapes.py: pebble counts, geometry, charges, duplicates, and the committed
shape files in potentials/ equal the generator's output."""
import importlib.util
import math
import os
import sys
import tempfile

root = sys.argv[1]
spec = importlib.util.spec_from_file_location("clump_shapes",
                                              os.path.join(root, "tools", "clump_shapes.py"))
cs = importlib.util.module_from_spec(spec)
spec.loader.exec_module(cs)

failures = []


def check(cond, msg):
    if not cond:
        failures.append(msg)


# dipole3: 3 pebbles, r = 0.005, spacing 0.01, charges -1 0 +1
d = cs.dipole3()
check(len(d) == 3, "dipole3 has 3 pebbles")
check([p[2] for p in d] == [-1.0, 0.0, 1.0], "dipole3 charges -1 0 +1")
check(all(p[1] == 0.005 for p in d), "dipole3 radius 0.005")
check(math.isclose(math.dist(d[0][0], d[1][0]), 0.01) and
      math.isclose(math.dist(d[1][0], d[2][0]), 0.01), "dipole3 spacing 0.01")

# platelet: 1 + 3n(n-1) per layer, two layers, opposite charges, net zero, HCP geometry
for n in (1, 2, 3, 14):
    p = cs.platelet(n)
    per = 1 + 3 * n * (n - 1)
    check(len(p) == 2 * per, f"platelet n={n}: {len(p)} pebbles, want {2 * per}")
    zs = sorted({round(q[0][2], 12) for q in p})
    check(len(zs) == (2 if n >= 1 else 0), f"platelet n={n}: two layers")
    lower = [q for q in p if q[0][2] < 0]
    upper = [q for q in p if q[0][2] > 0]
    check(len(lower) == per and len(upper) == per, f"platelet n={n}: {per} per layer")
    check(all(q[2] == 1.0 for q in lower) and all(q[2] == -1.0 for q in upper),
          f"platelet n={n}: layers charged +1 / -1")
    check(abs(sum(q[2] for q in p)) < 1e-12, f"platelet n={n}: net charge zero")
    check(all(q[1] == 0.008 for q in p), f"platelet n={n}: radius 0.008")
    check(not cs.find_duplicates(p), f"platelet n={n}: no duplicates")
    if n >= 2:
        # nearest neighbours in and between layers are `spacing` apart
        dmin = min(math.dist(a[0], b[0]) for i, a in enumerate(p) for b in p[i + 1:])
        check(math.isclose(dmin, 0.01, rel_tol=1e-9), f"platelet n={n}: spacing {dmin}")
        dlayer = min(math.dist(a[0], b[0]) for a in lower for b in upper)
        check(math.isclose(dlayer, 0.01, rel_tol=1e-9), f"platelet n={n}: layer gap {dlayer}")
check(len(cs.platelet(14)) == 1094, "platelet n=14 has 1094 pebbles")

# charge magnitude and basis subset
p = cs.platelet(3, charge=0.25, basis_stride=3)
charged = [q for q in p if q[2] != 0.0]
check(len(charged) == 2 * len(range(0, 19, 3)), "basis stride 3 charges every 3rd pebble")
check(all(abs(q[2]) == 0.25 for q in charged), "charge magnitude is a parameter")
check(abs(sum(q[2] for q in p)) < 1e-12, "basis subset keeps net charge zero")
text = cs.format_molecule(p, "t")
check("Types" in text and "\n1 2\n" in text, "charged pebbles are type 2")

# the committed files are the generator's output, and `check` reads them back
for name, pebbles in (("dipole3", cs.dipole3()), ("platelet_n14", cs.platelet(14)),
                      ("platelet_n3", cs.platelet(3))):
    path = os.path.join(root, "potentials", name + ".mol")
    with open(path) as f:
        body = f.read().split("\n", 1)[1]    # everything after the title line
    want = cs.format_molecule(pebbles, "x").split("\n", 1)[1]
    check(body == want, f"potentials/{name}.mol differs from the generator's output")
    back = cs.read_molecule(path)
    check(len(back) == len(pebbles), f"{name}: read back {len(back)} pebbles")
    check(cs.main(["check", path]) == 0, f"{name}: check reports duplicates")

# a file with duplicates fails `check`
with tempfile.TemporaryDirectory() as tmp:
    path = os.path.join(tmp, "dup.mol")
    with open(path, "w") as f:
        f.write(cs.format_molecule(cs.dipole3() + [cs.dipole3()[0]], "dup"))
    check(cs.main(["check", path]) == 1, "check finds duplicate pebbles")
    # truncated file: clear error
    with open(path, "w") as f:
        f.write(cs.format_molecule(cs.dipole3(), "t")[:120])
    try:
        cs.read_molecule(path)
        failures.append("truncated file read without error")
    except ValueError:
        pass

if failures:
    print("FAILED:\n  " + "\n  ".join(failures))
    sys.exit(1)
print("clump shapes: all checks passed")
