#!/usr/bin/env python3
"""Compares an arc-length path with a displacement-controlled path of the same structure.

    check_arch.py --arc DIR --dc DIR --force F --deflection COL --reaction COL --rtol R
                  [--min-drop D] [--order P] [--no-limit] [--out-csv FILE]

DIR/path.csv of the arc-length run gives (load factor, deflection); its load is
load_factor * F (F: the dead force per unit load factor, signed along the deflection
component). The displacement-controlled run gives (deflection, reaction); its load is the
reaction (the internal force on the prescribed DOF, f_int = applied force at equilibrium).
Checks:
  * the arc-length run passed a limit point: summary.json lists one, at the first local maximum
    of the load, and after that peak the load falls by at least D times the peak (default 0.05);
  * at every arc-length point whose deflection lies inside the displacement-controlled range,
    the load equals the displacement-controlled load interpolated at that deflection (cubic
    Lagrange through the 4 nearest points) within R times the peak load, and points past the
    limit point are among those compared.
"""
import argparse
import csv
import json
import os
import sys


def read(path):
    with open(path) as f:
        rows = list(csv.DictReader(f))
    return rows


def lagrange(xs, ys, x):
    s = 0.0
    for i, xi in enumerate(xs):
        w = 1.0
        for j, xj in enumerate(xs):
            if j != i:
                w *= (x - xj) / (xi - xj)
        s += w * ys[i]
    return s


def interp(xd, yd, x, order):
    # nearest order+1 points of the (sorted) grid around x
    k = min(range(len(xd)), key=lambda i: abs(xd[i] - x))
    lo = max(0, min(k - order // 2, len(xd) - order - 1))
    return lagrange(xd[lo:lo + order + 1], yd[lo:lo + order + 1], x)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--arc", required=True)
    ap.add_argument("--dc", required=True)
    ap.add_argument("--force", type=float, required=True)
    ap.add_argument("--deflection", required=True)
    ap.add_argument("--reaction", required=True)
    ap.add_argument("--rtol", type=float, required=True)
    ap.add_argument("--min-drop", type=float, default=0.05)
    ap.add_argument("--order", type=int, default=3, help="degree of the Lagrange interpolation of the displacement-controlled path")
    ap.add_argument("--out-csv")
    ap.add_argument("--no-limit", action="store_true",
                    help="the path has no limit point: skip the limit checks (monotone paths)")
    a = ap.parse_args()
    arc = read(os.path.join(a.arc, "path.csv"))
    dc = read(os.path.join(a.dc, "path.csv"))
    la = [float(r["load_factor"]) * a.force for r in arc]
    da = [float(r[a.deflection]) for r in arc]
    ld = [float(r[a.reaction]) for r in dc]
    dd = [float(r[a.deflection]) for r in dc]
    # orient so that the deflection grows along the displacement-controlled path
    sgn = 1.0 if dd[-1] > dd[0] else -1.0
    dd = [sgn * v for v in dd]
    da = [sgn * v for v in da]
    la = [sgn * v for v in la]
    ld = [sgn * v for v in ld]
    summary = json.load(open(os.path.join(a.arc, "summary.json")))
    ok = True
    ipk = next((i for i in range(1, len(la) - 1) if la[i + 1] < la[i]), len(la) - 1)
    peak = la[ipk]
    drop = (peak - min(la[ipk:])) / peak
    print("arc length: %d points, peak load %.10g at deflection %.6g (step %d); load falls by %.1f %% of it after"
          % (len(la), peak, da[ipk], ipk + 1, 100 * drop))
    lp = summary.get("limit_points") or []
    if a.no_limit:
        if lp:
            print("CHECK FAILED: summary.json lists a limit point on a monotone path")
            ok = False
    elif not lp:
        print("CHECK FAILED: summary.json lists no limit point")
        ok = False
    elif lp[0]["step"] != ipk + 1:
        print("CHECK FAILED: summary.json's first limit point is at step %d, the path's first peak at step %d"
              % (lp[0]["step"], ipk + 1))
        ok = False
    if not a.no_limit and (ipk == len(la) - 1 or drop < a.min_drop):
        print("CHECK FAILED: the load does not fall by %g of the peak after it" % a.min_drop)
        ok = False
    worst, worst3, past, n = 0.0, 0.0, 0, 0
    rows = []
    for l, d in zip(la, da):
        if not (dd[0] <= d <= dd[-1]):
            continue
        p3 = interp(dd, ld, d, a.order)
        p2 = interp(dd, ld, d, a.order - 1)
        err = abs(l - p3) / peak
        worst = max(worst, err)
        worst3 = max(worst3, abs(p3 - p2) / peak)
        n += 1
        past += d > da[ipk]
        rows.append((d, l, p3, err))
    print("compared %d points (%d past the limit point): max |P_arc - P_dc| / P_peak = %.3e "
          "(interpolation-error estimate |degree p - degree p-1| / P_peak up to %.3e); bound %.1e"
          % (n, past, worst, worst3, a.rtol))
    if a.out_csv:
        with open(a.out_csv, "w") as f:
            f.write("deflection,load_arc_length,load_displacement_control,relative_difference\n")
            for r in rows:
                f.write("%.12g,%.12g,%.12g,%.3e\n" % r)
    if n < 10 or (past < 3 and not a.no_limit):
        print("CHECK FAILED: too few points compared (%d, %d past the limit)" % (n, past))
        ok = False
    if worst > a.rtol:
        print("CHECK FAILED: the paths differ by %.3e > %.1e" % (worst, a.rtol))
        ok = False
    sys.exit(0 if ok else 1)


if __name__ == "__main__":
    main()
