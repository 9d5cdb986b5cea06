#!/usr/bin/env python3
"""Compares an elastic-plastic plate-with-a-hole run (xml/plate_hole_plastic.xml) with the
finite-element reference of tools/ccx_plate_hole_plastic.py (CalculiX, CPE8R, *PLASTIC).

Force-displacement: the reaction on the right end ('reaction' probe, x component) at every step
against the FE reaction at the same pseudo-time of the load path (the FE rows are equal fractions
of each segment; linear interpolation between them). The difference is measured against the
largest FE reaction of the path, since the reaction passes through zero on unloading.

Plastic zone (with --zone): at the end of the path, the area where the equivalent plastic strain
is positive and the integral of the equivalent plastic strain over the plate, from the run's
fields.csv (each real particle's area is the lattice spacing squared, --spacing) and from the FE
integration points (a quarter of their element's area each; the FE file holds the quarter
x, y >= 0 of the zone, so 4 times its sums).

    check_plate_hole_plastic.py OUTDIR FE.csv [--zone FE_zone.csv] [--rtol 0.05] [--zone-rtol 0.2]
        [--spacing DX]
"""
import argparse
import csv
import os
import sys


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("outdir")
    ap.add_argument("fe")
    ap.add_argument("--zone")
    ap.add_argument("--rtol", type=float, default=0.05, help="largest |reaction - FE| / largest |FE reaction|")
    ap.add_argument("--zone-rtol", type=float, default=0.2)
    ap.add_argument("--spacing", type=float, help="the lattice spacing (particle area dx^2), for --zone")
    a = ap.parse_args()

    with open(os.path.join(a.outdir, "path.csv")) as f:
        run = list(csv.DictReader(f))
    with open(a.fe) as f:
        fe = list(csv.DictReader(row for row in f if not row.startswith("#")))
    if not run or not fe:
        sys.exit("check_plate_hole_plastic: empty run or FE table")
    fe_t = [(k + 1) / len(fe) for k in range(len(fe))]
    fe_r = [float(r["reaction"]) for r in fe]
    scale = max(abs(v) for v in fe_r)

    def fe_at(t):
        if t <= fe_t[0]:
            return fe_r[0] * t / fe_t[0]
        for k in range(1, len(fe_t)):
            if t <= fe_t[k] + 1e-12:
                w = (t - fe_t[k - 1]) / (fe_t[k] - fe_t[k - 1])
                return (1 - w) * fe_r[k - 1] + w * fe_r[k]
        return fe_r[-1]

    worst = 0.0
    print("step  load   reaction      FE            diff / max|FE|")
    for k, r in enumerate(run):
        t = (k + 1) / len(run)
        got, want = float(r["reaction_x"]), fe_at(t)
        d = (got - want) / scale
        worst = max(worst, abs(d))
        print("%4s  %.3f  %12.2f  %12.2f  %+7.2f %%" % (r["step"], float(r["load_factor"]), got, want, 100 * d))
    print("largest difference %.2f %% of the largest FE reaction %.1f N (tolerance %.1f %%)" % (100 * worst, scale, 100 * a.rtol))
    failures = []
    if worst > a.rtol:
        failures.append("force-displacement differs by %.2f %% (tolerance %.1f %%)" % (100 * worst, 100 * a.rtol))

    if a.zone:
        with open(a.zone) as f:
            z = list(csv.DictReader(row for row in f if not row.startswith("#")))
        # The FE file holds the quarter x, y >= 0: the plate's zone is 4 times it.
        fe_area = 4 * sum(float(p["area"]) for p in z if float(p["peeq"]) > 0)
        fe_int = 4 * sum(float(p["area"]) * float(p["peeq"]) for p in z)
        with open(os.path.join(a.outdir, "fields.csv")) as f:
            pts = [p for p in csv.DictReader(f) if p["fictitious"] == "0"]
        if not a.spacing:
            sys.exit("check_plate_hole_plastic: --zone needs --spacing (the lattice spacing)")
        area = a.spacing * a.spacing
        pd_area = sum(area for p in pts if float(p["eqps"]) > 0)
        pd_int = sum(area * float(p["eqps"]) for p in pts)
        ea, ei = pd_area / fe_area - 1, pd_int / fe_int - 1
        print("plastic zone at the end: area %.1f mm^2 (FE %.1f, %+.1f %%), integral of eqps %.4g mm^2 (FE %.4g, %+.1f %%)"
              % (pd_area, fe_area, 100 * ea, pd_int, fe_int, 100 * ei))
        if abs(ea) > a.zone_rtol or abs(ei) > a.zone_rtol:
            failures.append("plastic zone differs by %.1f %% in area and %.1f %% in the eqps integral (tolerance %.0f %%)"
                            % (100 * ea, 100 * ei, 100 * a.zone_rtol))
    if failures:
        print("FAIL: " + "; ".join(failures))
        sys.exit(1)
    print("OK")


if __name__ == "__main__":
    main()
