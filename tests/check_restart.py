#!/usr/bin/env python3
"""Checks a run resumed from a checkpoint against the run that wrote the checkpoint.

    check_restart.py --from-step K [--exact | --rtol R] FULL_RUN RESUMED_RUN

The resumed run must say it resumed (run_segments 2, resumed_from.step K), carry the first K
step records of the full run unchanged, and then take the same steps: the same load factors
and the same bonds broken in every step, to the end. --exact (same ranks, same solver) requires
every number of every later step but its time, and every line of fields.csv and path.csv, to be
identical. Otherwise the displacements must agree to R relative to the largest displacement,
the damage index exactly, and the load factors to 1e-9 (partitions change an iterative
solver's round-off, not the steps a converged run takes).
"""
import argparse
import csv
import json
import os
import sys


def fail(msg):
    print("FAILED: " + msg)
    sys.exit(1)


def load(d):
    with open(os.path.join(d, "summary.json")) as f:
        return json.load(f)


def fields(d):
    with open(os.path.join(d, "fields.csv")) as f:
        return {r["id"]: r for r in csv.DictReader(f)}


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--from-step", type=int, required=True)
    ap.add_argument("--exact", action="store_true")
    ap.add_argument("--rtol", type=float, default=0.0)
    ap.add_argument("--load-drop", action="store_true",
                    help="the checkpoint's step K lowered the load factor (a snap-back): checked in the full run")
    ap.add_argument("full")
    ap.add_argument("resumed")
    a = ap.parse_args()
    full, res = load(a.full), load(a.resumed)
    k = a.from_step
    if res.get("run_segments") != 2 or res.get("resumed_from", {}).get("step") != k:
        fail(f"the resumed run reports segments {res.get('run_segments')}, resumed_from {res.get('resumed_from')}; "
             f"expected 2 and step {k}")
    if full.get("run_segments") != 1:
        fail("the full run reports more than one segment")
    if res["converged"] != full["converged"]:
        fail(f"converged: full {full['converged']}, resumed {res['converged']}")
    fs, rs = full["steps"], res["steps"]
    if a.load_drop:
        k0 = a.from_step
        if k0 < 2 or k0 > len(fs) or not fs[k0 - 1]["load_factor"] < fs[k0 - 2]["load_factor"]:
            fail(f"step {k0} of the full run does not lower the load factor (no snap-back at the checkpoint)")
    if len(fs) != len(rs):
        fail(f"{len(fs)} steps in the full run, {len(rs)} in the resumed one")
    if fs[:k] != rs[:k]:
        fail(f"the first {k} step records were not carried over unchanged")
    for f, r in zip(fs[k:], rs[k:]):
        if a.exact:
            fa = {key: v for key, v in f.items() if key != "time_s"}
            ra = {key: v for key, v in r.items() if key != "time_s"}
            if fa != ra:
                diff = [key for key in fa if fa[key] != ra.get(key)]
                fail(f"step {f['step']} differs in {diff}")
        else:
            if abs(f["load_factor"] - r["load_factor"]) > 1e-9:
                fail(f"step {f['step']}: load factor {f['load_factor']} against {r['load_factor']}")
            if f["broken_bonds"] != r["broken_bonds"] or f.get("stall_broken_bonds") != r.get("stall_broken_bonds"):
                fail(f"step {f['step']}: broken bonds {f['broken_bonds']} against {r['broken_bonds']}")
    for key in ("broken_bonds_total", "detached_particles"):
        if full.get(key) != res.get(key):
            fail(f"{key}: {full.get(key)} against {res.get(key)}")
    if a.exact:
        for name in ("fields.csv", "path.csv"):
            with open(os.path.join(a.full, name)) as x, open(os.path.join(a.resumed, name)) as y:
                if x.read() != y.read():
                    fail(f"{name} differs")
        print(f"PASSED: steps {k + 1}-{len(fs)} and the final fields identical bit for bit "
              f"({full.get('broken_bonds_total')} bonds broken in all)")
        return
    ff, rf = fields(a.full), fields(a.resumed)
    if ff.keys() != rf.keys():
        fail("the runs have different particles")
    comps = [c for c in ("ux", "uy", "uz") if c in next(iter(ff.values()))]
    scale = max(abs(float(p[c])) for p in ff.values() for c in comps) or 1.0
    worst = max(abs(float(ff[i][c]) - float(rf[i][c])) for i in ff for c in comps) / scale
    if any(ff[i]["damage"] != rf[i]["damage"] for i in ff):
        fail("the damage index differs")
    print(f"displacements agree to {worst:.3e} relative (tolerance {a.rtol}); damage index identical")
    if worst > a.rtol:
        fail("displacements differ")
    print(f"PASSED: steps {k + 1}-{len(fs)}: same load factors and broken bonds")


if __name__ == "__main__":
    main()
