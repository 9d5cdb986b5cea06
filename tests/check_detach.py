#!/usr/bin/env python3
"""Checks a damage run that detaches particles (fields.csv and summary.json of one or more runs).

    check_detach.py --detached X,Y [--detached X,Y ...] DIR [DIR2 ...]

- the run converged to load factor 1 with every step recorded as converged;
- summary.json lists detached particles, and every real particle at a given (X, Y) is among them;
- every detached real particle has lost all its bonds (phi = 1 in fields.csv) and a finite
  displacement (its DOFs are frozen, never NaN), and no field in fields.csv is NaN;
- every particle listed as detached has phi = 1 (a particle with bonds left is never detached);
- with several folders (e.g. 1 and 2 MPI ranks): the same detached particles and broken bonds.
- --fragments N: exactly N particles were reported as free-floating fragments, and --max-drift D:
  the mean u_y of the real particles, zero by the strip's symmetry about its axis, is at most D:
  a fragment left free drifts along its rigid-body mode instead (measured 0.094 mm before
  fragments were detected).
"""
import argparse
import csv
import json
import math
import os
import sys


def fail(msg):
    print("FAILED: " + msg)
    sys.exit(1)


def load(d):
    with open(os.path.join(d, "summary.json")) as f:
        s = json.load(f)
    rows = {}
    with open(os.path.join(d, "fields.csv")) as f:
        for r in csv.DictReader(f):
            for k, v in r.items():
                if k != "id" and not math.isfinite(float(v)):
                    fail(f"{d}: {k} of particle {r['id']} is {v}")
            rows[int(r["id"])] = (float(r["x"]), float(r["y"]), float(r["ux"]), float(r["uy"]),
                                  float(r["damage"]), int(r["fictitious"]))
    return s, rows


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--detached", action="append", default=[], help="X,Y of a particle that must be detached")
    ap.add_argument("--fragments", type=int, help="particles reported in free-floating fragments")
    ap.add_argument("--max-drift", type=float, help="largest |mean u_y| of the real particles")
    ap.add_argument("dirs", nargs="+")
    a = ap.parse_args()
    s, rows = load(a.dirs[0])
    if not s["converged"]:
        fail("run did not converge: " + s.get("failure", ""))
    if abs(s["steps"][-1]["load_factor"] - 1.0) > 1e-12:
        fail(f"the run ended at load factor {s['steps'][-1]['load_factor']}, not 1")
    det = set(s.get("detached_particles", []))
    if not det:
        fail("no particle detached")
    for pid in det:
        phi = rows[pid][4]
        if phi != 1.0:
            fail(f"particle {pid} at ({rows[pid][0]}, {rows[pid][1]}) is detached but has phi = {phi}")
    for xy in a.detached:
        x, y = (float(v) for v in xy.split(","))
        hits = [pid for pid, r in rows.items() if abs(r[0] - x) < 1e-9 and abs(r[1] - y) < 1e-9]
        if not hits:
            fail(f"no particle at ({x}, {y})")
        for pid in hits:
            if pid not in det:
                fail(f"particle {pid} at ({x}, {y}) is not detached (phi = {rows[pid][4]})")
    if a.fragments is not None and s.get("fragment_particles_total") != a.fragments:
        fail(f"{s.get('fragment_particles_total')} particles reported in free-floating fragments, expected {a.fragments}")
    if a.max_drift is not None:
        uy = [r[3] for r in rows.values() if not r[5]]
        drift = abs(sum(uy) / len(uy))
        print(f"mean u_y of the real particles: {drift:.3e} (allowed {a.max_drift})")
        if drift > a.max_drift:
            fail("a real particle drifted across the load (a free fragment moving along a rigid-body mode?)")
    real = sorted(pid for pid in det if not rows[pid][5])
    print(f"{len(det)} detached particles ({len(real)} real: "
          + ", ".join(f"({rows[p][0]}, {rows[p][1]})" for p in real) + f"), {s['broken_bonds_total']} bonds broken")
    for d in a.dirs[1:]:
        s2, _ = load(d)
        if sorted(s2.get("detached_particles", [])) != sorted(det):
            fail(f"{d}: detached {sorted(s2.get('detached_particles', []))}, reference {sorted(det)}")
        if s2["broken_bonds_total"] != s["broken_bonds_total"]:
            fail(f"{d}: {s2['broken_bonds_total']} bonds broken, reference {s['broken_bonds_total']}")
        print(f"{d} ({s2['ranks']} ranks): the same detached particles and broken bonds")
    print("PASSED")


if __name__ == "__main__":
    main()
