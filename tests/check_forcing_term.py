#!/usr/bin/env python3
"""Forcing-term check: the second run (Eisenstat-Walker) solves the same scene as the first
(Constant, every Newton system to 1e-12) with the same Newton iterations at every step, at most
--krylov-ratio of its Krylov iterations in all (0.6 unless given), and the same probes at every
step (--rtol, relative to each probe's largest magnitude); with --answers-only the probes alone,
and the Krylov ratio only when --krylov-ratio is given. Counts, not times: stable on a shared
machine.

    check_forcing_term.py CONSTANT_DIR EISENSTAT_WALKER_DIR [--krylov-ratio 0.6] [--rtol 1e-8] [--answers-only]
"""
import argparse
import json
import os
import sys


def load(d):
    with open(os.path.join(d, "summary.json")) as f:
        return json.load(f)


ap = argparse.ArgumentParser()
ap.add_argument("constant")
ap.add_argument("ew")
ap.add_argument("--krylov-ratio", type=float, default=None)
ap.add_argument("--rtol", type=float, default=1e-8)
ap.add_argument("--answers-only", action="store_true", help="compare the probes only (not the work)")
a = ap.parse_args()
c, e = load(a.constant), load(a.ew)
fails = []
if not (c["converged"] and e["converged"]):
    fails.append("a run did not converge")
nc = [s["newton_iterations"] for s in c["steps"]]
ne = [s["newton_iterations"] for s in e["steps"]]
kc, ke = c["krylov_iterations_total"], e["krylov_iterations_total"]
print(f"Constant: Newton {nc}, Krylov {kc}; Eisenstat-Walker: Newton {ne}, Krylov {ke} ({ke / max(kc, 1):.2f})")
if nc != ne and not a.answers_only:
    fails.append("the Newton iterations differ")
ratio = a.krylov_ratio if a.krylov_ratio is not None else (None if a.answers_only else 0.6)
if ratio is not None and not ke <= ratio * kc:
    fails.append(f"Eisenstat-Walker took {ke} Krylov iterations, more than {ratio} x {kc}")
worst = 0.0
for name, hist in c["probes"].items():
    other = e["probes"][name]
    if len(other) != len(hist):
        fails.append(f"probe {name} has {len(hist)} and {len(other)} entries")
        continue
    key = "displacement" if "displacement" in hist[0] else "reaction"
    scale = max(abs(v) for h in hist for v in h[key]) or 1.0
    for h, g in zip(hist, other):
        for x, y in zip(h[key], g[key]):
            worst = max(worst, abs(x - y) / scale)
print(f"largest probe difference {worst:.2e} of the probe's magnitude")
if worst > a.rtol:
    fails.append(f"probes differ by {worst:.2e} > {a.rtol}")
for f in fails:
    print("FAILED:", f)
sys.exit(1 if fails else 0)
