#!/usr/bin/env python3
"""The 1D elastic-plastic bar (xml/plastic_bar.xml) against uniaxial J2 along its load path.

    check_plastic_bar.py DIR [--factor F]

Replays the closed form of uniaxial stress with linear hardening (log strain e = ln(1 + u / L),
tau = E (e - e_p), returned to |tau| = sigma_y0 + H alpha when past it) over the run's steps
and compares the reaction at the pulled end, F times P A with P = tau / (1 + u / L), at every
step to 1e-8 relative to the largest (the Newton tolerance is 1e-10). F = 2 for the stress-point
bar (the scene's comment says why). Also checks that the bar yielded in reverse on the way back
(a compressive reaction at zero load) and that the last step's plastic strain in fields.csv is
the closed form's everywhere.
"""
import argparse
import csv
import json
import math
import os
import sys
import xml.etree.ElementTree as ET

ap = argparse.ArgumentParser()
ap.add_argument("dir")
ap.add_argument("--factor", type=float, default=2.0)
a = ap.parse_args()
root = ET.parse(os.path.join(a.dir, "scene.resolved.xml")).getroot()


def param(path):
    node = root
    for name in path[:-1]:
        node = next(n for n in node.findall("ParameterList") if n.get("name") == name)
    return next(n for n in node.findall("Parameter") if n.get("name") == path[-1]).get("value")


E = float(param(["Material", "Young's Modulus"]))
s0 = float(param(["Material", "Yield Stress"]))
H = float(param(["Material", "Hardening Modulus"]))
A = float(param(["Discretization", "Thickness"]))
u1 = float(param(["Boundary Conditions", "pulled", "Value"]))
L = 1.0  # the pulled particle is at x = 1, the fixed one at x = 0
s = json.load(open(os.path.join(a.dir, "summary.json")))
fails = []
if not s["converged"]:
    fails.append("the run did not converge")
ep = alpha = 0.0
refs = []
for step in s["steps"]:
    f = 1 + u1 * step["load_factor"] / L
    e = math.log(f)
    tau = E * (e - ep)
    over = abs(tau) - (s0 + H * alpha)
    if over > 0:
        d = over / (E + H)
        sign = 1.0 if tau > 0 else -1.0
        ep += sign * d
        alpha += d
        tau -= sign * E * d
    refs.append((step["load_factor"], a.factor * tau / f * A))
got = s["probes"]["reaction"]
scale = max(abs(r) for _, r in refs)
worst = 0.0
for (lf, ref), g in zip(refs, got):
    err = abs(g["reaction"][0] - ref) / scale
    worst = max(worst, err)
    if abs(g["load_factor"] - lf) > 1e-12 or err > 1e-8:
        fails.append(f"load factor {lf}: reaction {g['reaction'][0]:.10e}, closed form {ref:.10e}")
at_zero = [g["reaction"][0] for g in got if abs(g["load_factor"]) < 1e-12]
if not at_zero or not at_zero[0] < -0.5 * s0 * A:
    fails.append(f"no compressive residual reaction at zero load ({at_zero})")
with open(os.path.join(a.dir, "fields.csv")) as fh:
    eq = [float(r["eqps"]) for r in csv.DictReader(fh)]
if max(abs(v - alpha) for v in eq) > 1e-8 * alpha:
    fails.append(f"plastic strain {min(eq):.10e}..{max(eq):.10e}, closed form {alpha:.10e}")
print(f"{len(got)} steps, worst reaction error {worst:.2e} of the largest; final alpha {alpha:.6e}")
for m in fails:
    print("FAIL:", m)
sys.exit(1 if fails else 0)
