#!/usr/bin/env python3
"""Parameter study: runs a scene over a sweep (e.g. the stabilisation parameter G) for several
series (e.g. horizons or discretisations) and writes a CSV table and a PNG plot of a probe.

    tools/study.py --scene xml/clamped_beam.xml --probe midspan --component 1 \\
        --sweep "Model/G=0,0.001,0.002,0.005,0.01,0.02,0.05" \\
        --series "Discretization/Horizon Factor=1.015,2.015,3.015" \\
        --normalise -5.08 --reference 0.65 --out out/study_clamped [--set KEY=VALUE ...]
        [--contours 0,0.006]

Every run is the perinox driver with --set overrides, so a study is exactly reproducible from
the command line. Output: OUT/study.csv (one row per run: series, sweep value, probe value,
normalised value, converged, Newton iterations, wall time, e_u if the scene has a reference),
OUT/study.png, and for --contours the sigma_xx pictures of those sweep values
(OUT/contour_<series>_<value>.png).
"""
import argparse
import concurrent.futures as cf
import csv
import json
import math
import os
import shutil
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)


def parse_sweep(spec):
    key, values = spec.split("=", 1)
    # Values separated by commas, but braces may hold commas: split at top level only.
    out, depth, cur = [], 0, ""
    for ch in values:
        if ch == "{":
            depth += 1
        elif ch == "}":
            depth -= 1
        if ch == "," and depth == 0:
            out.append(cur)
            cur = ""
        else:
            cur += ch
    if cur:
        out.append(cur)
    return key, [v.strip() for v in out]


def run_one(args, series_key, series_val, sweep_key, sweep_val, outdir):
    run_dir = os.path.join(outdir, "runs", f"{series_val}_{sweep_val}".replace("/", "_").replace(" ", "").replace("{", "").replace("}", "").replace(",", "x"))
    cmd = [args.perinox, "run", args.scene, "--output", run_dir, "--quiet"]
    for s in args.set:
        cmd += ["--set", s]
    if series_key:
        cmd += ["--set", f"{series_key}={series_val}"]
    cmd += ["--set", f"{sweep_key}={sweep_val}"]
    env = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1")
    if not args.pictures:
        env["PERINOX_PLOT_SCRIPT"] = ""
    p = subprocess.run(cmd, capture_output=True, text=True, env=env)
    row = {"series": series_val, "sweep": sweep_val, "exit_code": p.returncode, "dir": run_dir}
    summary = os.path.join(run_dir, "summary.json")
    if os.path.exists(summary):
        with open(summary) as f:
            s = json.load(f)
        hist = s["probes"].get(args.probe, [])
        v = hist[-1]["displacement"][args.component] if hist and s["converged"] else float("nan")
        row.update(value=v, normalised=v / args.normalise if args.normalise else v, converged=s["converged"],
                   newton=sum(st["newton_iterations"] for st in s["steps"]), wall_time_s=s["wall_time_s"],
                   e_u=s.get("errors", {}).get("e_u", ""), failure=s.get("failure", ""))
    else:
        row.update(value=float("nan"), normalised=float("nan"), converged=False, newton=0, wall_time_s=0, e_u="",
                   failure=(p.stderr.strip().splitlines() or ["?"])[-1])
    return row


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--scene", required=True)
    ap.add_argument("--probe", required=True)
    ap.add_argument("--component", type=int, default=1)
    ap.add_argument("--sweep", required=True)
    ap.add_argument("--series", default="")
    ap.add_argument("--set", action="append", default=[])
    ap.add_argument("--normalise", type=float, default=0.0, help="divide the probe value by this")
    ap.add_argument("--reference", type=float, help="reference normalised value drawn as a line")
    ap.add_argument("--reference-label", default="reference")
    ap.add_argument("--contours", default="", help="sweep values whose sigma_xx pictures to keep")
    ap.add_argument("--metric", default="probe", choices=["probe", "e_u"],
                    help="plot the probe (default) or the displacement error e_u against the sweep")
    ap.add_argument("--out", required=True)
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--replot", action="store_true", help="redraw study.png from OUT/study.csv without running")
    ap.add_argument("--perinox", default=os.path.join(ROOT, "build", "drivers", "perinox"))
    a = ap.parse_args()
    sweep_key, sweep_vals = parse_sweep(a.sweep)
    series_key, series_vals = parse_sweep(a.series) if a.series else ("", [""])
    contour_vals = [v.strip() for v in a.contours.split(",") if v.strip()]
    os.makedirs(a.out, exist_ok=True)
    if a.replot:
        with open(os.path.join(a.out, "study.csv")) as f:
            rows = []
            for r in csv.DictReader(f):
                r["normalised"] = float(r["normalised"]) if r["normalised"] not in ("", "nan") else float("nan")
                r["converged"] = r["converged"] == "True"
                r["wall_time_s"] = float(r["wall_time_s"] or 0)
                rows.append(r)
        return plot(a, rows, sweep_key, sweep_vals, series_key, series_vals)
    jobs = []
    with cf.ThreadPoolExecutor(max_workers=a.jobs) as ex:
        for sv in series_vals:
            for wv in sweep_vals:
                b = argparse.Namespace(**vars(a))
                b.pictures = wv in contour_vals
                jobs.append(ex.submit(run_one, b, series_key, sv, sweep_key, wv, a.out))
    rows = [j.result() for j in jobs]
    fields = ["series", "sweep", "value", "normalised", "converged", "newton", "wall_time_s", "e_u", "exit_code", "failure", "dir"]
    with open(os.path.join(a.out, "study.csv"), "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=fields)
        w.writeheader()
        for r in rows:
            w.writerow({k: r.get(k, "") for k in fields})
    for r in rows:
        if r["sweep"] in contour_vals and os.path.exists(os.path.join(r["dir"], "deformed.png")):
            tag = f"{r['series']}_{r['sweep']}".replace(" ", "")
            shutil.copy(os.path.join(r["dir"], "deformed.png"), os.path.join(a.out, f"contour_{tag}.png"))
    for r in rows:
        print(f"{series_key or ''} {r['series']:>8} {sweep_key} {r['sweep']:>8}: normalised {r['normalised']:.6g}"
              f"  converged {r['converged']}  newton {r['newton']}  {r['wall_time_s']:.2f} s {r.get('failure', '')}")
    plot(a, rows, sweep_key, sweep_vals, series_key, series_vals)


def plot(a, rows, sweep_key, sweep_vals, series_key, series_vals):
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("matplotlib missing: no plot (install python3-matplotlib)")
        return
    numeric = all(_is_number(v) for v in sweep_vals)
    fig, ax = plt.subplots(figsize=(7, 4.5))
    for sv in series_vals:
        pts = [(r["sweep"], r["normalised"], r["converged"]) for r in rows if r["series"] == sv]
        if numeric:
            xs = [float(p[0]) for p in pts]
            positive = [x for x in xs if x > 0]
            floor = min(positive) / 3 if positive else 1e-4
            xs = [x if x > 0 else floor for x in xs]
        else:
            xs = list(range(len(pts)))
        if a.metric == "e_u":
            ys = [float(r["e_u"]) if r["e_u"] != "" and r["converged"] else float("nan") for r in rows if r["series"] == sv]
        else:
            ys = [p[1] for p in pts]
        ax.plot(xs, ys, marker="o", label=f"{series_key} = {sv}" if series_key else "perinox")
        for x, y, p in zip(xs, ys, pts):
            if not p[2]:
                ax.plot([x], [0 if math.isnan(y) else y], marker="x", color="red", markersize=10)
    if numeric:
        ax.set_xscale("log")
        ax.set_xlabel(f"{sweep_key} (the leftmost point of each line is {sweep_key} = 0 where swept)")
    else:
        ax.set_xticks(range(len(sweep_vals)))
        ax.set_xticklabels(sweep_vals, rotation=30)
        ax.set_xlabel(sweep_key)
    if a.reference is not None:
        ax.axhline(a.reference, color="k", linestyle="--", label=a.reference_label)
    if a.metric == "e_u":
        ax.set_ylabel("displacement error e_u (seed 000 eq. 56)")
        ax.set_yscale("log")
    else:
        ax.set_ylabel(f"{a.probe}[{'xyz'[a.component]}]" + (f" / {a.normalise:g}" if a.normalise else ""))
    ax.set_title(os.path.basename(a.scene) + "  (red x: not converged)")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(os.path.join(a.out, "study.png"), dpi=110)
    print("wrote", os.path.join(a.out, "study.csv"), "and study.png")


def _is_number(s):
    try:
        float(s)
        return True
    except ValueError:
        return False


if __name__ == "__main__":
    main()
