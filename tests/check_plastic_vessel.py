#!/usr/bin/env python3
"""Checks a thick-walled pressure vessel run (xml/plastic_cylinder.xml, or a sphere of docs/plasticity.md)
against the closed forms of an elastic-perfectly plastic von Mises wall a <= r <= b under an
internal pressure p = lambda * p_ref (small strain):

  cylinder, plane strain: Lame stresses sigma_r = A (1 - b^2/r^2), sigma_theta = A (1 + b^2/r^2),
    sigma_z = nu (sigma_r + sigma_theta), A = p a^2 / (b^2 - a^2); first yield at r = a when
    their von Mises stress reaches sigma_y; limit pressure (2 / sqrt 3) sigma_y ln(b / a);
    bore displacement u(r) = (1 + nu) A / E ((1 - 2 nu) r + b^2 / r).
  sphere: sigma_r = B (1 - b^3/r^3), sigma_theta = B (1 + b^3 / (2 r^3)), B = p a^3 / (b^3 - a^3);
    first yield when sigma_theta - sigma_r = sigma_y at r = a: p = (2/3) sigma_y (1 - a^3/b^3);
    limit pressure 2 sigma_y ln(b / a); u(r) = B / E ((1 - 2 nu) r + (1 + nu) b^3 / (2 r^2)).

The run's first yield is bracketed by the last step with no plastic strain anywhere in the wall
(probe 'plastic strain' over block 1 and 'bore plastic strain' over block 2) and the first with
some; its limit load is summary.json's limit_load_factor (the run stops there, exit 3). The
elastic response is checked at the first step through the bore point's displacement.

    check_plastic_vessel.py OUTDIR --shape cylinder|sphere --E 200e9 --nu 0.3 --yield 250e6
        --p-ref 250e6 --inner 1 --outer 2 --probe-radius 1.025
        [--yield-tol 0.03] [--limit-tol 0.03] [--stiffness-tol 0.03] [--arc]

With --arc (an arc-length run, Solver/Continuation = Arc Length, past the limit) it checks the
plateau instead: the run reaches its target deflection, at least 3 times the deflection where
the load first came within 3 % of the limit pressure, the load stays within --limit-tol of it
from there on, and the plateau's slope is below 1/300 of the elastic stiffness.
"""
import argparse
import csv
import json
import math
import os
import sys


def lame(shape, p, a, b, r, E, nu):
    """(von Mises stress at r, radial displacement at r) of the elastic wall under pressure p."""
    if shape == "cylinder":
        A = p * a * a / (b * b - a * a)
        sr, st = A * (1 - b * b / (r * r)), A * (1 + b * b / (r * r))
        sz = nu * (sr + st)
        vm = math.sqrt(0.5 * ((sr - st) ** 2 + (st - sz) ** 2 + (sz - sr) ** 2))
        u = (1 + nu) * A / E * ((1 - 2 * nu) * r + b * b / r)
    else:
        B = p * a ** 3 / (b ** 3 - a ** 3)
        sr, st = B * (1 - b ** 3 / r ** 3), B * (1 + b ** 3 / (2 * r ** 3))
        vm = abs(st - sr)
        u = B / E * ((1 - 2 * nu) * r + (1 + nu) * b ** 3 / (2 * r * r))
    return vm, u


def check_plateau(o, rows, summary, p_limit, failures):
    """Arc length past the limit load: the run converges to its target deflection, several times
    the deflection at which the load first came within 3 % of the limit (the knee); along the
    plateau from the knee on the load stays within the limit tolerance of the closed form and
    its slope is a small fraction of the elastic stiffness (what is left is the stabilisation)."""
    if not summary.get("converged"):
        failures.append("the arc-length run did not reach its target: " + summary.get("failure", "?"))
        return
    lam = [float(r["load_factor"]) for r in rows]
    d = [float(r["bore_point_x"]) for r in rows]
    knee = next((k for k, v in enumerate(lam) if v * o.p_ref >= 0.97 * p_limit), None)
    if knee is None:
        failures.append("the load never came within 3 %% of the limit pressure (largest %.4f sigma_y)" % (max(lam) * o.p_ref / o.sy))
        return
    ratio = d[-1] / d[knee]
    print("plateau from deflection %.4g (load %.4f sigma_y) to %.4g (%.1fx), load %.4f .. %.4f sigma_y; closed form %.4f"
          % (d[knee], lam[knee] * o.p_ref / o.sy, d[-1], ratio, min(lam[knee:]) * o.p_ref / o.sy,
             max(lam[knee:]) * o.p_ref / o.sy, p_limit / o.sy))
    if ratio < 3:
        failures.append("the run ended at %.1fx the knee's deflection; it should go well past the limit" % ratio)
    for k in range(knee, len(lam)):
        e = lam[k] * o.p_ref / p_limit - 1
        if abs(e) > o.limit_tol:
            failures.append("step %s: load %.4f sigma_y is %+.2f %% from the limit pressure (tolerance %.1f %%)"
                            % (rows[k]["step"], lam[k] * o.p_ref / o.sy, 100 * e, 100 * o.limit_tol))
            break
    elastic = lam[0] / d[0]
    slope = (lam[-1] - lam[knee + 1]) / (d[-1] - d[knee + 1]) if len(lam) > knee + 2 else 0.0
    print("plateau slope %.3g of the elastic stiffness" % (slope / elastic))
    if not slope / elastic < 1.0 / 300:
        failures.append("the plateau's slope is %.3g of the elastic stiffness (at most 1/300)" % (slope / elastic))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("outdir")
    ap.add_argument("--shape", choices=("cylinder", "sphere"), required=True)
    ap.add_argument("--E", type=float, required=True)
    ap.add_argument("--nu", type=float, required=True)
    ap.add_argument("--yield", dest="sy", type=float, required=True)
    ap.add_argument("--p-ref", type=float, required=True, help="the pressure at load factor 1")
    ap.add_argument("--inner", type=float, required=True)
    ap.add_argument("--outer", type=float, required=True)
    ap.add_argument("--probe-radius", type=float, required=True, help="radius of the 'bore point' probe's particle")
    ap.add_argument("--yield-tol", type=float, default=0.03)
    ap.add_argument("--limit-tol", type=float, default=0.03)
    ap.add_argument("--stiffness-tol", type=float, default=0.03)
    ap.add_argument("--arc", action="store_true",
                    help="an arc-length run past the limit: checks the plateau instead of first yield and the limit stop")
    o = ap.parse_args()
    a, b = o.inner, o.outer
    failures = []

    with open(os.path.join(o.outdir, "summary.json")) as f:
        summary = json.load(f)
    with open(os.path.join(o.outdir, "path.csv")) as f:
        rows = list(csv.DictReader(f))
    if not rows:
        sys.exit("check_plastic_vessel: no converged step in path.csv")

    # Closed forms.
    vm1, _ = lame(o.shape, 1.0, a, b, a, o.E, o.nu)
    p_yield = o.sy / vm1
    p_limit = (2 / math.sqrt(3) if o.shape == "cylinder" else 2.0) * o.sy * math.log(b / a)

    # Elastic stiffness at the first step.
    lam1 = float(rows[0]["load_factor"])
    u1 = float(rows[0]["bore_point_x"])
    _, u_ref = lame(o.shape, lam1 * o.p_ref, a, b, o.probe_radius, o.E, o.nu)
    e_u = u1 / u_ref - 1
    print("elastic bore displacement at p = %.4g: %.6e (closed form %.6e, %+.2f %%)" % (lam1 * o.p_ref, u1, u_ref, 100 * e_u))
    if float(rows[0]["plastic_strain_max"]) > 0 or float(rows[0]["bore_plastic_strain_max"]) > 0:
        failures.append("the first step already yields; it cannot show the elastic stiffness")
    elif abs(e_u) > o.stiffness_tol:
        failures.append("elastic bore displacement off by %.2f %% (tolerance %.1f %%)" % (100 * e_u, 100 * o.stiffness_tol))

    if o.arc:
        check_plateau(o, rows, summary, p_limit, failures)
        if failures:
            print("FAIL: " + "; ".join(failures))
            sys.exit(1)
        print("OK")
        return

    # First yield: bracketed by consecutive steps.
    before, first = 0.0, None
    for r in rows:
        lam = float(r["load_factor"])
        if max(float(r["plastic_strain_max"]), float(r["bore_plastic_strain_max"])) > 0:
            first = lam
            break
        before = lam
    if first is None:
        failures.append("the wall never yields")
    else:
        lo, hi = before * o.p_ref, first * o.p_ref
        print("first yield between p = %.5g and %.5g (%.4f .. %.4f sigma_y); closed form %.5g (%.4f sigma_y)"
              % (lo, hi, lo / o.sy, hi / o.sy, p_yield, p_yield / o.sy))
        # The closed form must lie in the bracket widened by the tolerance on either side.
        miss = max(0.0, lo / p_yield - 1, 1 - hi / p_yield)
        if not (lo <= p_yield * (1 + o.yield_tol) and hi >= p_yield * (1 - o.yield_tol)):
            failures.append("first yield bracket [%.4g, %.4g] misses the closed form %.4g by more than %.1f %% (%.2f %%)"
                            % (lo, hi, p_yield, 100 * o.yield_tol, 100 * miss))

    # Limit pressure.
    lim = summary.get("limit_load_factor")
    if lim is None:
        failures.append("the run did not stop at a limit load (summary.json has no limit_load_factor)")
    else:
        p_run = lim * o.p_ref
        e_l = p_run / p_limit - 1
        print("limit pressure %.6g (%.4f sigma_y); closed form %.6g (%.4f sigma_y): %+.2f %%"
              % (p_run, p_run / o.sy, p_limit, p_limit / o.sy, 100 * e_l))
        if abs(e_l) > o.limit_tol:
            failures.append("limit pressure off by %.2f %% (tolerance %.1f %%)" % (100 * e_l, 100 * o.limit_tol))
    if failures:
        print("FAIL: " + "; ".join(failures))
        sys.exit(1)
    print("OK")


if __name__ == "__main__":
    main()
