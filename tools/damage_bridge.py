#!/usr/bin/env python3
"""Intact bonds across a crack band: which bonds still join particles whose u_x differs by more
than 0.02 mm at the end of a damage run of the plate with a hole (docs/validation.md, 150 x 50).

    python3 tools/damage_bridge.py RUN CHECKPOINT

RUN is the finished run (fields.csv, scene.resolved.xml), CHECKPOINT a checkpoint of it (its rank
files list the broken bonds by global particle id; the last one written, so a few bonds broken
after it count as intact). The bonds and their stretches are those of tests/check_damage.py
(the families as perinox builds them). Prints the number of such bonds, the largest ten with
their u_x difference, stretch and angle to the load axis, and the median angle.
"""
import csv
import glob
import math
import os
import statistics
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "tests"))
from check_damage import bond_stretches  # noqa: E402

run, ck = sys.argv[1], sys.argv[2]
with open(os.path.join(run, "fields.csv")) as f:
    rows = list(csv.DictReader(f))
where = {int(r["id"]): (float(r["x"]), float(r["y"])) for r in rows}
ux = {(float(r["x"]), float(r["y"])): float(r["ux"]) for r in rows}
broken = set()
for path in glob.glob(os.path.join(ck, "rank_*.txt")):
    with open(path) as f:
        for line in f:
            if line.startswith("bond "):
                _, a, b = line.split()
                broken.add(frozenset((where[int(a)], where[int(b)])))
if not broken:
    sys.exit("no broken bonds in " + ck + "/rank_*.txt: not a checkpoint of a damage run")
print("broken bonds in the checkpoint", len(broken))
_, bonds = bond_stretches(run)
across = []
for xi, yi, xj, yj, s in bonds:
    du = ux[(xj, yj)] - ux[(xi, yi)]
    if abs(du) > 0.02 and frozenset(((xi, yi), (xj, yj))) not in broken:
        angle = math.degrees(math.atan2(abs(yj - yi), abs(xj - xi)))
        across.append((abs(du), s, angle, (xi, yi), (xj, yj)))
across.sort(reverse=True)
print("intact bonds with |du_x| > 0.02 mm:", len(across))
for t in across[:10]:
    print("du_x %.4f stretch %.5f angle %.0f deg  %s-%s" % t)
if across:
    print("angles: median %.0f, min %.0f" % (statistics.median(t[2] for t in across), min(t[2] for t in across)))
    print("stretch: max %.5f" % max(t[1] for t in across))
