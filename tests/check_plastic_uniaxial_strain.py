#!/usr/bin/env python3
"""The elastic-plastic block in uniaxial strain (xml/plastic_uniaxial_strain.xml) against J2 at finite strain.

    check_plastic_uniaxial_strain.py DIR --rtol R

Closed form (Hencky elasticity, F = Fe Fp, linear hardening H, plane strain, F = diag(f, 1, 1)
with f = 1 + g lambda, e = ln f). The deviator keeps its direction, so with the axial plastic
strain p (signed) and the accumulated one alpha, the signed Mises stress is q = 2 mu e - 3 mu p;
while |q| <= sigma_y0 + H alpha the point is elastic, beyond it flows until
|q| = sigma_y0 + H alpha: the increment is (|q| - sigma_y0 - H alpha) / (3 mu + H), exact however
large the step, as long as the strain moves one way within it (the load path's steps land on its
corners). Monotonic loading gives alpha = (2 mu e - sigma_y0) / (3 mu + H). The Kirchhoff stress
is tau_xx = kappa e + 2 q / 3, tau_yy = tau_zz = kappa e - q / 3 (kappa = E / (3 (1 - 2 nu))),
the Cauchy stress tau / f. The states of the run's steps (summary.json, with a Load Path
unloading and reloading) are replayed in this order.
Compared at the last step over the middle of the body (x in the middle half, y in the middle
four fifths, away from the O(dx) boundary layer): the mean of sxx, syy, szz and eqps within R
relative, and every particle within 2 R; every particle of the body must have yielded; the
scene's "plastic strain" probe (mean over the middle) within R of the run's largest plastic
strain after every step. The
parameters come from the run's scene.resolved.xml, the load factor from summary.json.
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
ap.add_argument("--rtol", type=float, required=True)
args = ap.parse_args()


def param(root, path):
    node = root
    for name in path[:-1]:
        node = next(n for n in node.findall("ParameterList") if n.get("name") == name)
    return next(n for n in node.findall("Parameter") if n.get("name") == path[-1]).get("value")


def array(text):
    return [float(v) for v in text.strip("{}").split(",")]


root = ET.parse(os.path.join(args.dir, "scene.resolved.xml")).getroot()
E = float(param(root, ["Material", "Young's Modulus"]))
nu = float(param(root, ["Material", "Poisson's Ratio"]))
s0 = float(param(root, ["Material", "Yield Stress"]))
H = float(param(root, ["Material", "Hardening Modulus"]))
g = array(param(root, ["Boundary Conditions", "pull", "Gradient"]))[0]
lo = array(param(root, ["Discretization", "Lower Corner"]))
hi = array(param(root, ["Discretization", "Upper Corner"]))
summary = json.load(open(os.path.join(args.dir, "summary.json")))
mu = E / (2 * (1 + nu))
kappa = E / (3 * (1 - 2 * nu))
p = alpha = 0.0
alphas = []  # the closed form's alpha after every step
for step in summary["steps"]:
    lam = step["load_factor"]
    f = 1 + g * lam
    e = math.log(f)
    q = 2 * mu * e - 3 * mu * p
    over = abs(q) - (s0 + H * alpha)
    if over > 0:
        dp = over / (3 * mu + H)
        sign = 1.0 if q > 0 else -1.0
        p += sign * dp
        alpha += dp
        q -= sign * 3 * mu * dp
    alphas.append(alpha)
if alpha == 0.0:
    sys.exit("the scene stays elastic: nothing to check")
ref = {"sxx": (kappa * e + 2 * q / 3) / f, "syy": (kappa * e - q / 3) / f, "szz": (kappa * e - q / 3) / f, "eqps": alpha}

L, W = hi[0] - lo[0], hi[1] - lo[1]
with open(os.path.join(args.dir, "fields.csv")) as fh:
    body = [r for r in csv.DictReader(fh) if r["fictitious"] == "0"]
middle = [r for r in body if abs(float(r["x"]) - (lo[0] + L / 2)) < L / 4 and abs(float(r["y"]) - (lo[1] + W / 2)) < 0.4 * W]
fails = []
if not summary["converged"]:
    fails.append("the run did not converge")
if not middle:
    fails.append("no particle in the middle of the body")
unyielded = [r["id"] for r in body if r["yielded"] != "1"]
if unyielded:
    fails.append(f"{len(unyielded)} particles of the body did not yield (first: {unyielded[0]})")
line = []
for key, v in ref.items():
    vals = [float(r[key]) for r in middle]
    mean = sum(vals) / len(vals)
    em = abs(mean - v) / abs(v)
    ex = max(abs(x - v) for x in vals) / abs(v)
    line.append(f"{key}: mean {em:.2e}, max {ex:.2e}")
    if em > args.rtol:
        fails.append(f"mean {key} over the middle {mean:.6e} differs from the closed form {v:.6e} by {em:.2e} (> {args.rtol})")
    if ex > 2 * args.rtol:
        fails.append(f"a particle's {key} differs from the closed form {v:.6e} by {ex:.2e} (> {2 * args.rtol})")
# The "plastic strain" probe (Quantity = Plastic Strain over the middle): its mean after every
# step, the committed history through the driver, against the replayed closed form.
probe = summary["probes"].get("plastic strain", [])
if len(probe) != len(alphas):
    fails.append(f"the plastic strain probe has {len(probe)} values for {len(alphas)} steps")
worst_probe = 0.0
for k, (entry, ref_alpha) in enumerate(zip(probe, alphas)):
    mx, mean = entry["plastic_strain"]
    if mx < mean:
        fails.append(f"step {k + 1}: the probe's largest plastic strain {mx} is below its mean {mean}")
    # Relative to the run's largest plastic strain: the boundary layer shifts the strain of the
    # middle by ~R, which is a large fraction of a plastic strain that has only just begun.
    err = abs(mean - ref_alpha) / max(alphas)
    worst_probe = max(worst_probe, err)
    if (ref_alpha > 0 and err > args.rtol) or (ref_alpha == 0 and mx != 0.0):
        fails.append(f"step {k + 1}: mean plastic strain over the middle {mean:.6e}, closed form {ref_alpha:.6e}")
line.append(f"probe mean per step: worst {worst_probe:.2e}")
print(f"load factor {lam}, {len(middle)} particles in the middle; " + "; ".join(line))
for m in fails:
    print("FAIL:", m)
sys.exit(1 if fails else 0)
