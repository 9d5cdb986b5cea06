#!/usr/bin/env python3
"""Peridigm's text-file meshes and deck-defined node sets, against the Exodus deck they copy.

From Peridigm's QS tension test (validation/peridigm_decks/ElasticCorrespondenceQSTension: an
Exodus mesh of 384 hexahedra whose element number map starts at 289, six node sets) this writes,
in plain Python (tests/netcdf_classic.py reads the mesh):

- a Text File deck: the elements' centroids (mean of the corners, Peridigm's placement) and
  volumes (the trilinear hexahedra's, by Gauss quadrature) as "x y z block volume" lines, with comment lines in
  Peridigm's three styles, and the node sets as Peridigm defines them in a deck: the 1-based line
  numbers of the elements touching each set's nodes, two sets in node-set files (one number a
  line, and all on one line), the others as inline lists;
- an Exodus deck whose node sets are defined in the deck by element ids of the mesh's element
  number map (Peridigm's node numbers for an Exodus mesh), one in a file, the others inline.

All three decks must select the same particles, so perinox's answers (every probe at every step)
must agree with the original deck's to round-off (1e-9 relative); a numbering off by one, or the
map ignored, moves the reactions by their own size.

    check_text_mesh_deck.py PERINOX SOURCE_DIR OUT_DIR [--mpi MPIEXEC ARGS... --]

With --mpi the two derived decks run on those ranks with the distributed construction (each rank
reads its share of the text file, and finds its share of each node set), the original on one.
"""
import json
import os
import re
import subprocess
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
from netcdf_classic import NetcdfClassic  # noqa: E402

exe, src, out = sys.argv[1:4]
mpi = []
if "--mpi" in sys.argv:
    i = sys.argv.index("--mpi")
    mpi = sys.argv[i + 1:sys.argv.index("--", i)]
case = os.path.abspath(os.path.join(src, "validation", "peridigm_decks", "ElasticCorrespondenceQSTension"))
mesh_path = os.path.join(case, "ElasticCorrespondenceQSTension.g")
deck_text = open(os.path.join(case, "ElasticCorrespondenceQSTension.xml")).read()
os.makedirs(out, exist_ok=True)

n = NetcdfClassic(mesh_path)
x, y, z = n.values("coordx"), n.values("coordy"), n.values("coordz")
block_ids = n.values("eb_prop1")
elements = []  # (block id, corner nodes 0-based), in file order: block after block
for b, bid in enumerate(block_ids):
    conn = n.values(f"connect{b + 1}")
    per = n.shape(f"connect{b + 1}")[1]
    for e in range(len(conn) // per):
        elements.append((bid, [c - 1 for c in conn[e * per:(e + 1) * per]]))
number_map = n.values("elem_num_map")
assert len(number_map) == len(elements) and number_map[0] != 1, "the test needs the mesh's non-trivial element number map"

# The text mesh.
lines = ["# x y z block volume (written from ElasticCorrespondenceQSTension.g)", "// Peridigm also skips lines starting with /",
         "* and with *", ""]
CORNERS = [(-1, -1, -1), (1, -1, -1), (1, 1, -1), (-1, 1, -1), (-1, -1, 1), (1, -1, 1), (1, 1, 1), (-1, 1, 1)]  # HEX8 order
GAUSS = (-3 ** -0.5, 3 ** -0.5)


def hex_volume(p):
    """The trilinear hexahedron's volume: det J integrated by 2 x 2 x 2 Gauss points (exact: det J
    is at most quadratic in each reference coordinate)."""
    v = 0.0
    for a in GAUSS:
        for b in GAUSS:
            for c in GAUSS:
                J = [[0.0] * 3 for _ in range(3)]
                for (r, s, t), q in zip(CORNERS, p):
                    d = (r * (1 + s * b) * (1 + t * c) / 8, s * (1 + r * a) * (1 + t * c) / 8, t * (1 + r * a) * (1 + s * b) / 8)
                    for i in range(3):
                        for j in range(3):
                            J[i][j] += q[i] * d[j]
                v += (J[0][0] * (J[1][1] * J[2][2] - J[1][2] * J[2][1]) - J[0][1] * (J[1][0] * J[2][2] - J[1][2] * J[2][0])
                      + J[0][2] * (J[1][0] * J[2][1] - J[1][1] * J[2][0]))
    return v


for bid, nodes in elements:
    assert len(nodes) == 8, "the test's mesh is of HEX8 elements"
    cx = [sum(c[k] for k in nodes) / len(nodes) for c in (x, y, z)]
    volume = hex_volume([(x[k], y[k], z[k]) for k in nodes])
    assert volume > 0, "an inverted element"
    lines.append(f"{cx[0]!r} {cx[1]!r} {cx[2]!r} {bid} {volume!r}")
with open(os.path.join(out, "mesh.txt"), "w") as f:
    f.write("\n".join(lines) + "\n")

# Peridigm's node sets: the elements touching the set's nodes.
sets = {}
for j in range(1, 7):
    members = set(k - 1 for k in n.values(f"node_ns{j}"))
    sets[j] = [e for e, (_, nodes) in enumerate(elements) if members.intersection(nodes)]
    assert sets[j], f"node set {j} touches no element"


def deck_with(disc_type, mesh_file, definitions):
    """The QS deck with another discretisation and node sets defined in Boundary Conditions."""
    t = deck_text.replace('value="Exodus"', f'value="{disc_type}"')
    t = t.replace('value="ElasticCorrespondenceQSTension.g"', f'value="{mesh_file}"')
    defs = "".join(f'\n    <Parameter name="{name}" type="string" value="{value}"/>' for name, value in definitions)
    t = t.replace('<ParameterList name="Boundary Conditions">', '<ParameterList name="Boundary Conditions">' + defs, 1)
    return re.sub(r'value="nodelist_(\d)"', lambda m: f'value="Node Set {m.group(1)}"', t)


# Text deck: sets 1 and 2 in files (line numbers, 1-based), the others inline.
with open(os.path.join(out, "node_set_1.txt"), "w") as f:
    f.write("# node set 1\n" + "\n".join(str(e + 1) for e in sets[1]) + "\n")
with open(os.path.join(out, "node_set_2.txt"), "w") as f:
    f.write("// node set 2, on one line\n" + " ".join(str(e + 1) for e in sets[2]) + "\n")
text_defs = [("Node Set 1", "node_set_1.txt"), ("Node Set 2", "node_set_2.txt")] + \
            [(f"Node Set {j}", " ".join(str(e + 1) for e in sets[j])) for j in range(3, 7)]
with open(os.path.join(out, "text_deck.xml"), "w") as f:
    f.write(deck_with("Text File", "mesh.txt", text_defs))

# Exodus deck with the sets by element id (the element number map), set 1 in a file.
with open(os.path.join(out, "node_set_ids_1.txt"), "w") as f:
    f.write("\n".join(str(number_map[e]) for e in sets[1]) + "\n")
ids_defs = [("Node Set 1", "node_set_ids_1.txt")] + \
           [(f"Node Set {j}", " ".join(str(number_map[e]) for e in sets[j])) for j in range(2, 7)]
with open(os.path.join(out, "ids_deck.xml"), "w") as f:
    f.write(deck_with("Exodus", mesh_path, ids_defs))

env = dict(os.environ, PERINOX_PLOT_SCRIPT="")
results = {}
for name, deck in [("original", os.path.join(case, "ElasticCorrespondenceQSTension.xml")),
                   ("text", os.path.join(out, "text_deck.xml")), ("ids", os.path.join(out, "ids_deck.xml"))]:
    folder = os.path.join(out, "run_" + name)
    cmd = [exe, "run", deck, "--output", folder, "--quiet"]
    if mpi and name != "original":
        cmd = mpi + cmd + ["--set", "Discretization/Construction=Distributed"]
    p = subprocess.run(cmd, capture_output=True, text=True, env=env, timeout=600)
    if p.returncode != 0:
        sys.exit(f"FAILED: the {name} deck: exit {p.returncode}: {p.stderr.strip()[-400:]}")
    with open(os.path.join(folder, "summary.json")) as f:
        results[name] = json.load(f)

failures = []
ref = results["original"]
for name in ("text", "ids"):
    got = results[name]
    if got["particles"] != ref["particles"] or got["dofs"] != ref["dofs"]:
        failures.append(f"{name}: {got['particles']} particles, {got['dofs']} free DOFs; the Exodus deck: "
                        f"{ref['particles']}, {ref['dofs']}")
        continue
    worst = 0.0
    for probe, hist in ref["probes"].items():
        for h_ref, h in zip(hist, got["probes"][probe]):
            key = next(k for k in h_ref if k != "load_factor")
            scale = max(abs(v) for v in h_ref[key]) or 1.0
            for a, b in zip(h_ref[key], h[key]):
                worst = max(worst, abs(a - b) / scale)
    print(f"{name} deck: largest probe difference from the Exodus deck {worst:.3g} (relative to the probe's size)")
    if not worst <= 1e-9:
        failures.append(f"{name}: probes differ from the Exodus deck's by {worst:.3g} relative")
if failures:
    print("\n".join("FAILED: " + f for f in failures))
    sys.exit(1)
print("PASSED")
