#!/usr/bin/env python3
"""Checks the scene `perinox convert` makes of Peridigm's tensile test against the deck's own
numbers (shared/benchmarks/README.md: E = 1.8e12, nu = 0.3 from K = 1.5e12 and G = 6.923e11 to
the 4 digits of G; horizon 0.16; 4 load steps; u_y = 0.005 y t on nodelist_1 and nodelist_2; x
and z held on nodelist_3..6).

    check_peridigm_scene.py SCENE.xml
"""
import sys
import xml.etree.ElementTree as ET


def fail(m):
    print("CHECK FAILED: " + m)
    sys.exit(1)


root = ET.parse(sys.argv[1]).getroot()


def sub(node, name):
    for c in node:
        if c.tag == "ParameterList" and c.get("name") == name:
            return c
    fail(f"no sublist {name}")


def val(node, name):
    for c in node:
        if c.tag == "Parameter" and c.get("name") == name:
            return c.get("value")
    fail(f"no parameter {name}")


def numbers(text):
    return [float(v) for v in text.strip("{}").split(",")] if text else None


d, m, s = sub(root, "Discretization"), sub(root, "Material"), sub(root, "Solver")
mo = sub(root, "Model")
if val(m, "Model") != "Hencky" or val(mo, "Stabilization") != "Silling" or float(val(mo, "G")) != 0.02 \
        or val(mo, "G Form") != "Peridigm Hourglass":
    fail("the material (Hencky) or the hourglass coefficient (G = 0.02 in Peridigm's form)")
if val(d, "Type") != "Exodus" or not val(d, "Mesh File").endswith("tensile_test.g"):
    fail("not the tensile mesh")
if float(val(d, "Horizon")) != 0.16:
    fail("horizon")
# 4 significant digits of G: E and nu to 2e-5 relative of the README's rounded values.
if abs(float(val(m, "Young's Modulus")) / 1.8e12 - 1) > 2e-5 or abs(float(val(m, "Poisson's Ratio")) / 0.3 - 1) > 2e-5:
    fail("E or nu")
if int(val(s, "Load Steps")) != 4:
    fail("load steps")
regions = sub(root, "Regions")
for k in range(1, 7):
    r = sub(regions, f"nodelist_{k}")
    if val(r, "Type") != "Node Set" or val(r, "Name") != f"nodelist_{k}":
        fail(f"nodelist_{k}")
want = {"nodelist_1": ("y", [0.0, 0.005, 0.0]), "nodelist_2": ("y", [0.0, 0.005, 0.0]),
        "nodelist_3": ("x", None), "nodelist_4": ("z", None), "nodelist_5": ("x", None), "nodelist_6": ("z", None)}
bcs = sub(root, "Boundary Conditions")
seen = set()
for c in bcs:
    region = val(c, "Region")
    comp, grad = want[region]
    if val(c, "Component") != comp or float(val(c, "Value")) != 0.0:
        fail(f"condition on {region}")
    g = [p.get("value") for p in c if p.get("name") == "Gradient"]
    if numbers(g[0] if g else None) != grad:
        fail(f"gradient on {region}: {g}")
    seen.add(region)
if seen != set(want):
    fail("conditions missing")
print("the scene holds the deck's material, hourglass coefficient, horizon, steps and conditions")
