#!/usr/bin/env python3
"""Pivots docs/figures/precond_study.csv (written by build/drivers/bench_preconditioners) into the
markdown tables of docs/performance.md: Krylov iterations per lattice per candidate, and the set-up
and solve cost in residual evaluations. Rows are filtered by ranks, state, operator and a scene tag.

    tools/precond_table.py [--csv docs/figures/precond_study.csv] [--ranks 1] [--state affine]
                           [--tag g05] [--candidates a b ...]
"""
import argparse
import csv
from collections import OrderedDict


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--csv", default="docs/figures/precond_study.csv")
    ap.add_argument("--ranks", default="1")
    ap.add_argument("--state", default="affine")
    ap.add_argument("--operator", default="assembled")
    ap.add_argument("--tag", default=None, help="only rows whose 'tag' column equals this (if the column exists)")
    ap.add_argument("--candidates", nargs="*")
    a = ap.parse_args()
    rows = [r for r in csv.DictReader(open(a.csv))
            if r["ranks"] == a.ranks and r["state"] == a.state and r.get("operator", "assembled") == a.operator
            and (a.tag is None or r.get("tag", "") == a.tag)]
    lattices = list(OrderedDict.fromkeys(r["lattice"] for r in rows))
    cands = a.candidates or list(OrderedDict.fromkeys(r["candidate"] for r in rows))
    last, runs = {}, {}
    for r in rows:
        last[(r["candidate"], r["lattice"])] = r  # a later run of the same pair replaces an earlier one
        runs.setdefault((r["candidate"], r["lattice"]), []).append(r)

    def med(c, l, key):
        v = sorted(float(r[key]) for r in runs[(c, l)] if r["status"] != "failed")
        return v[len(v) // 2] if v else float("nan")
    parts = {l: next(r["particles"] for r in rows if r["lattice"] == l) for l in lattices}

    def cell(c, l, f):
        r = last.get((c, l))
        return f(r) if r else ""

    def iters(r):
        s = r["iterations"]
        return s if r["status"] == "converged" else (f">{s} (time)" if r["status"] == "time limit" else r["status"])

    print("| candidate | " + " | ".join(f"{int(parts[l]):,}".replace(",", " ") for l in lattices) + " | growth |")
    print("|---|" + "---|" * (len(lattices) + 1))
    for c in cands:
        its = [last[(c, l)] for l in lattices if (c, l) in last and last[(c, l)]["status"] == "converged"]
        growth = f"{int(its[-1]['iterations']) / int(its[0]['iterations']):.2f}" if len(its) > 1 else ""
        print(f"| {c} | " + " | ".join(cell(c, l, iters) for l in lattices) + f" | {growth} |")
    print()
    print("set-up (preconditioner matrix + preconditioner) + solve, in residual evaluations of the same run"
          " (median over the runs of that pair):")
    print()
    print("| candidate | " + " | ".join(f"{int(parts[l]):,}".replace(",", " ") for l in lattices) + " |")
    print("|---|" + "---|" * len(lattices))
    for c in cands:
        print(f"| {c} | " + " | ".join(
            cell(c, l, lambda r: f"{med(c, l, 'setup_in_residuals'):.0f} + {med(c, l, 'solve_in_residuals'):.0f}")
            for l in lattices) + " |")
    print()
    print("| per lattice | " + " | ".join(f"{int(parts[l]):,}".replace(",", " ") for l in lattices) + " |")
    print("|---|" + "---|" * len(lattices))
    for key, label, fmt in [("t_residual_s", "one residual evaluation, s", "{:.4f}"),
                            ("t_assemble_J_s", "assembling J, residuals", None),
                            ("t_matvec_s", "J v assembled, residuals", None),
                            ("t_jv_matrix_free_s", "J v matrix-free, residuals", None)]:
        vals = []
        for l in lattices:
            rs = [r for r in rows if r["lattice"] == l]
            v = sorted(float(r[key]) / (1.0 if fmt else float(r["t_residual_s"])) for r in rs)
            vals.append((fmt or "{:.2f}").format(v[len(v) // 2]) if v else "")
        print(f"| {label} | " + " | ".join(vals) + " |")


if __name__ == "__main__":
    main()
