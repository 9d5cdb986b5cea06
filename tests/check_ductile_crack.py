#!/usr/bin/env python3
"""The ductile crack of xml/plate_hole_ductile.xml: where and how it grows.

    check_ductile_crack.py DIR

Under tension along x, the plastic zone of the plate with a hole sits in the ligaments above and
below the hole, and a crack driven by the plastic strain must run there, across the load: every
particle with damage >= 0.5 within one spacing of the ligament's centre line (|x| <= dx), the
cracked particles reaching from the hole (|y| <= radius + 2 dx) to the free edges (|y| >= half
height - dx) on both sides, and bonds broken in more than one step (the crack grows, it does not
appear at once). The numbers come from the run's scene.resolved.xml.
"""
import csv
import json
import os
import sys
import xml.etree.ElementTree as ET

d = sys.argv[1]
root = ET.parse(os.path.join(d, "scene.resolved.xml")).getroot()


def param(path):
    node = root
    for name in path[:-1]:
        node = next(n for n in node.findall("ParameterList") if n.get("name") == name)
    return next(n for n in node.findall("Parameter") if n.get("name") == path[-1]).get("value")


lo = [float(v) for v in param(["Discretization", "Lower Corner"]).strip("{}").split(",")]
hi = [float(v) for v in param(["Discretization", "Upper Corner"]).strip("{}").split(",")]
nx = int(param(["Discretization", "Particles"]).strip("{}").split(",")[0])
dx = (hi[0] - lo[0]) / nx
half = 0.5 * (hi[1] - lo[1])
holes = next(n for n in root.findall("ParameterList") if n.get("name") == "Discretization").find("ParameterList[@name='Holes']")
radius = float(next(p for p in holes.iter("Parameter") if p.get("name") == "Radius").get("value"))

summary = json.load(open(os.path.join(d, "summary.json")))
fails = []
if not summary["converged"]:
    fails.append("the run did not converge")
steps_breaking = [s["step"] for s in summary["steps"] if s.get("broken_bonds", 0) > 0]
if len(steps_breaking) < 2:
    fails.append(f"bonds broke in {len(steps_breaking)} step(s); a growing crack breaks them over several")
with open(os.path.join(d, "fields.csv")) as f:
    cracked = [r for r in csv.DictReader(f) if float(r["damage"]) >= 0.5 and r["fictitious"] == "0"]
off = [r for r in cracked if abs(float(r["x"])) > dx + 1e-9]
if off:
    fails.append(f"{len(off)} cracked particles off the ligament, e.g. at ({off[0]['x']}, {off[0]['y']})")
for sign, side in ((1, "upper"), (-1, "lower")):
    ys = [sign * float(r["y"]) for r in cracked if sign * float(r["y"]) > 0]
    if not ys or min(ys) > radius + 2 * dx or max(ys) < half - dx:
        fails.append(f"the {side} ligament is not cracked from the hole to the edge (cracked at |y| in {sorted(ys)})")
print(f"{len(cracked)} cracked particles, bonds broken in steps {steps_breaking}")
for m in fails:
    print("FAIL:", m)
sys.exit(1 if fails else 0)
