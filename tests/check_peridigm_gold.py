#!/usr/bin/env python3
"""Compares a perinox run of one of Peridigm's own verification decks with Peridigm's gold file.

    check_peridigm_gold.py --gold CASE_gold.e --out RUN_FOLDER --E 200e9 --nu 0.3 --strain 0.001
                           --steps N (--lateral free|held)

Both decks stretch a bar along y to the strain `--strain` in N equal steps; the bar either
contracts freely across (uniaxial stress, --lateral free) or is held (--lateral held). The
deformation is homogeneous, so each code's answer is its material law at one stretch, and the
difference between the two is computed here, not fitted:

  Peridigm (Elastic Correspondence): a hypoelastic rate form. Each step adds C : d to the Cauchy
    stress, with d = (lambda_k - lambda_k-1) / lambda_k (the rate of deformation over the step at
    the step's end); across a free side d_x = -nu d_y, so lambda_x,k = lambda_x,k-1 / (1 + nu d_y).
    First Piola stress P = J sigma F^-T.
  perinox (Hencky): Kirchhoff stress tau = C : ln V, P = tau F^-T; across a free side
    ln lambda_x = -nu ln lambda_y.

Checks, per load step: the gold reaction equals the Peridigm law's to 1e-6 (this reading of
Peridigm's update is right); perinox's reaction equals minus the gold one (Peridigm sums the
force the bonds exert on the grip, perinox reports the support's force) times the computed ratio
of the two laws, to 1e-6; so it differs from the gold value by the computed constitutive
difference and no more. At the last step, particle by particle (matched by reference position):
the displacement differs from the gold file's by at most the computed difference of the lateral
stretches times the particle's distance across the bar, plus 1e-12 of the largest displacement.
Exit 0 when all hold, 1 otherwise.
"""
import argparse
import csv
import json
import math
import os
import sys

from netcdf_classic import NetcdfClassic


def laws(E, nu, strain, steps, lateral):
    """Per step k = 1..steps: (P_yy Peridigm, P_yy perinox, lambda_x Peridigm, lambda_x perinox)."""
    lam = E * nu / ((1 + nu) * (1 - 2 * nu))
    held_modulus = lam + E / (1 + nu)          # lambda + 2 mu: sigma_yy per d_y with the sides held
    out, sigma, lx, ly_prev = [], 0.0, 1.0, 1.0
    for k in range(1, steps + 1):
        ly = 1 + strain * k / steps
        d = (ly - ly_prev) / ly
        ly_prev = ly
        if lateral == "free":
            sigma += E * d
            lx = lx / (1 + nu * d)
            p_peridigm = lx * lx * sigma         # J sigma / lambda_y with J = lx^2 ly
            p_perinox = E * math.log(ly) / ly
            lx_perinox = math.exp(-nu * math.log(ly))
        else:
            sigma += held_modulus * d
            p_peridigm = sigma                   # J = ly
            p_perinox = held_modulus * math.log(ly) / ly
            lx_perinox = 1.0
        out.append((p_peridigm, p_perinox, lx, lx_perinox))
    return out


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--gold", required=True)
    ap.add_argument("--out", required=True)
    ap.add_argument("--E", type=float, required=True)
    ap.add_argument("--nu", type=float, required=True)
    ap.add_argument("--strain", type=float, required=True)
    ap.add_argument("--steps", type=int, required=True)
    ap.add_argument("--lateral", choices=["free", "held"], required=True)
    a = ap.parse_args()
    ok = True

    def check(cond, msg):
        nonlocal ok
        print(("ok   " if cond else "FAIL ") + msg)
        ok = ok and cond

    g = NetcdfClassic(a.gold)
    glo = g.strings("name_glo_var")
    glo_vals = g.rows("vals_glo_var")
    gold_times = g.values("time_whole")
    with open(os.path.join(a.out, "summary.json")) as f:
        summary = json.load(f)
    probes = summary["probes"]
    model = laws(a.E, a.nu, a.strain, a.steps, a.lateral)
    X = list(zip(g.values("coordx"), g.values("coordy"), g.values("coordz")))
    # The bar's cross-section (particles are the hexahedra's centroids on a lattice): its area is
    # the extent of the centroids plus one spacing, in x times in z.
    area = 1.0
    for c in (0, 2):
        xs = sorted({round(x[c], 12) for x in X})
        h = min(b - a_ for a_, b in zip(xs, xs[1:]))
        area *= xs[-1] - xs[0] + h
    check(len(gold_times) == a.steps + 1, f"gold file has {len(gold_times)} times (t = 0 and {a.steps} steps)")
    for probe, grip_sign in (("Top_Reaction_Force", 1), ("Bottom_Reaction_Force", -1)):
        column = glo.index(probe + "Y")
        history = probes[probe]
        check(len(history) == a.steps, f"{probe}: perinox wrote {len(history)} steps (want {a.steps})")
        for k, rec in enumerate(history[: a.steps]):
            p_pd, p_px, _, _ = model[k]
            gold = glo_vals[k + 1][column]
            law = -grip_sign * p_pd * area            # Peridigm's sum: the bonds' pull on the grip
            dev = abs(gold - law) / abs(law)
            check(dev <= 1e-6, f"{probe} step {k + 1}: gold {gold:.9e} against Peridigm's law {law:.9e} (off {dev:.1e})")
            ours = rec["reaction"][1]
            want = -gold * (p_px / p_pd)
            diff = ours / -gold - 1
            expected = p_px / p_pd - 1
            dev = abs(ours - want) / abs(want)
            check(dev <= 1e-6, f"{probe} step {k + 1}: perinox {ours:.9e}, gold {-gold:.9e}: they differ by {diff:+.3e}, "
                               f"the computed constitutive difference is {expected:+.3e} (off {dev:.1e})")

    # Displacements at the last step, particle by particle.
    dnames = g.strings("name_nod_var")
    n = len(X)
    ug = [g.values(f"vals_nod_var{dnames.index('Displacement' + c) + 1}")[-n:] for c in "XYZ"]
    with open(os.path.join(a.out, "fields.csv")) as f:
        rows = list(csv.DictReader(f))
    check(len(rows) == n, f"{len(rows)} particles in perinox's fields, {n} in the gold file")
    at = {tuple(round(float(r[c]), 9) for c in "xyz"): r for r in rows}
    mine = [at.get(tuple(round(v, 9) for v in x)) for x in X]
    check(all(r is not None for r in mine) and len(at) == n, "every gold particle has its perinox particle (same position)")
    if any(r is None for r in mine):
        return 1
    _, _, lx_pd, lx_px = model[-1]
    scale = max(abs(u) for comp in ug for u in comp)
    for c, name in enumerate("xyz"):
        extent = max(x[c] for x in X) - min(x[c] for x in X) if name != "y" else 0.0
        bound = 1.01 * abs(lx_px - lx_pd) * extent + 1e-12 * scale  # 1 %: round-off of the two stretches
        worst = max(abs(float(r["u" + name]) - u) for r, u in zip(mine, ug[c]))
        check(worst <= bound, f"u_{name}: largest difference {worst:.3e} (of {max(abs(u) for u in ug[c]):.3e}); "
                              f"computed bound {bound:.3e} (lateral stretches {lx_px:.12f} and {lx_pd:.12f})")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
