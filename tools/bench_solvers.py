#!/usr/bin/env python3
"""Assembled against matrix-free Newton-Krylov, end to end: wall time, Newton iterations, the
sparse-matrix bytes held and the peak resident memory of the perinox driver, on one scene as the
particle count grows. Prints a table with ratios to the first solver and writes CSV; times are
single runs on a shared machine (the CSV keeps them all), asserts nothing.

    tools/bench_solvers.py [--sizes 40x20 80x40 ...] [--horizon 3.015] [--presets direct mf-ilu ...]
                           [--timeout 900] --out out/bench_solvers

Default scene: xml/tension_block.xml (displacement-driven uniaxial tension of a Hencky block,
fictitious layers at both ends), one load step, delta = 3.015 dx.
"""
import argparse
import csv
import sys
import json
import os
import subprocess
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def peak_rss_mib(pid):
    """VmHWM of a running process (MiB), or None once it has gone."""
    try:
        with open(f"/proc/{pid}/status") as f:
            for line in f:
                if line.startswith("VmHWM:"):
                    return int(line.split()[1]) / 1024.0
    except OSError:
        return None
    return None


def csv_appender(path, keys):
    """A csv.DictWriter appending to path (the header written first into a new file) and its file."""
    new = not os.path.exists(path)
    if not new:
        with open(path, newline="") as old:
            header = next(csv.reader(old), [])
        if header != list(keys):
            sys.exit(f"{path} has other columns ({','.join(header)}) than this benchmark writes; use a new --out")
    f = open(path, "a", newline="")
    w = csv.DictWriter(f, fieldnames=keys)
    if new:
        w.writeheader()
    return w, f


def run_polled(cmd, timeout, env):
    """Runs cmd, polling its peak resident memory; returns (exit code, or "timeout" when it was
    killed at the time limit; wall seconds; peak RSS MiB seen; the last line of its stderr)."""
    t0 = time.time()
    proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, env=env)
    rss = 0.0
    while proc.poll() is None:
        r = peak_rss_mib(proc.pid)
        if r:
            rss = max(rss, r)
        if time.time() - t0 > timeout:
            proc.kill()
            proc.wait()
            return "timeout", time.time() - t0, rss, ""
        time.sleep(0.25)
    err = proc.stderr.read().decode(errors="replace").strip().splitlines()
    return proc.returncode, time.time() - t0, rss, err[-1][:160] if err else ""


def run(perinox, scene, out, sets, timeout):
    cmd = [perinox, "run", scene, "--output", out, "--quiet"]
    for s in sets:
        cmd += ["--set", s]
    code, wall, rss, _ = run_polled(cmd, timeout, dict(os.environ, PERINOX_PLOT_SCRIPT=""))
    if code == "timeout":  # a run stopped at the time limit: its memory so far is a lower bound
        return {"timeout": True, "wall": wall, "rss_mib": rss}
    try:
        with open(os.path.join(out, "summary.json")) as f:
            j = json.load(f)
    except OSError:
        return {"failed": True, "wall": wall}
    return {
        "converged": j["converged"],
        "wall": j["wall_time_s"],
        "newton": j.get("newton_iterations_total", sum(s["newton_iterations"] for s in j["steps"])),
        "krylov": j.get("krylov_iterations_total", 0),
        "steps": len(j["steps"]),
        "matrix_mib": j.get("matrix_bytes", 0) / 2**20,
        "rss_mib": j.get("peak_rss_mib_max_rank", float("nan")),
        "probe": next((h[-1].get("reaction", h[-1].get("displacement")) for h in j["probes"].values() if h), None),
    }


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--scene", default=os.path.join(ROOT, "xml", "tension_block.xml"))
    ap.add_argument("--sizes", nargs="+", default=["40x20", "80x40", "160x80"])
    ap.add_argument("--horizon", default="3.015")
    ap.add_argument("--presets", nargs="+", default=["direct", "mf-muelu", "mf-ilu", "jfnk-ilu"])
    ap.add_argument("--timeout", type=float, default=900)
    ap.add_argument("--set", dest="sets", action="append", default=[],
                    help="extra driver settings, e.g. --set Model/Stabilization=Silling --set Model/G=0.5")
    ap.add_argument("--out", default="out/bench_solvers")
    ap.add_argument("--perinox", default=os.path.join(ROOT, "build", "drivers", "perinox"))
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    rows = []
    keys = ["particles", "preset", "status", "wall_s", "newton_iterations", "krylov_iterations", "matrix_mib", "peak_rss_mib",
            "speedup_vs_first", "memory_ratio_first_over_this"]
    csv_file = open(os.path.join(a.out, "bench_solvers.csv"), "w", newline="")
    writer = csv.DictWriter(csv_file, fieldnames=keys)
    writer.writeheader()
    print(f"# {os.path.relpath(a.scene, ROOT)}, delta = {a.horizon} dx, one load step; ratios to {a.presets[0]}")
    print(f"{'particles':>10} {'preset':>18} {'conv':>5} {'wall s':>9} {'Newton':>6} {'Krylov':>7} {'matrix MiB':>10} {'peak MiB':>9}"
          f" {'time ratio':>10} {'mem ratio':>9}")
    for size in a.sizes:
        nx, ny = size.split("x")
        base = None
        for preset in a.presets:
            out = os.path.join(a.out, f"{size}_{preset}")
            r = run(a.perinox, a.scene, out, [f"Discretization/Particles={{{nx},{ny}}}",
                                               f"Discretization/Horizon Factor={a.horizon}", "Solver/Load Steps=1",
                                               f"Solver/Linear Solver Preset={preset}", "Output/Plots=false",
                                               "Output/VTK=false"] + a.sets, a.timeout)
            n = int(nx) * int(ny)
            if r.get("timeout") or r.get("failed"):
                status = "timeout" if r.get("timeout") else "failed"
                print(f"{n:>10} {preset:>18} {status:>5} >{r['wall']:>8.1f} {'':>6} {'':>7} {'':>10} >{r.get('rss_mib', 0):>8.0f}"
                      "   (lower bounds: stopped at the time limit)", flush=True)
                rows.append({"particles": n, "preset": preset, "status": status, "wall_s": r["wall"],
                             "peak_rss_mib": r.get("rss_mib", float("nan"))})
                writer.writerow(rows[-1])
                csv_file.flush()
                if base is None:
                    base = {"wall": r["wall"], "rss_mib": r.get("rss_mib", float("nan")), "bound": True}
                continue
            if base is None:
                base = r
            # Against a reference stopped at the time limit the ratios are lower bounds (">").
            tr = base["wall"] / r["wall"] if r["wall"] > 0 else float("nan")
            mr = base["rss_mib"] / r["rss_mib"] if r["rss_mib"] > 0 else float("nan")
            print(f"{n:>10} {preset:>18} {str(r['converged']):>5} {r['wall']:>9.2f} {r['newton']:>6} {r['krylov']:>7} {r['matrix_mib']:>10.1f}"
                  f" {r['rss_mib']:>9.0f} {'>' if base.get('bound') else ' '}{tr:>9.2f} {mr:>9.2f}", flush=True)
            rows.append({"particles": n, "preset": preset, "status": "converged" if r["converged"] else "not converged",
                         "wall_s": r["wall"], "newton_iterations": r["newton"], "krylov_iterations": r["krylov"], "matrix_mib": r["matrix_mib"],
                         "peak_rss_mib": r["rss_mib"], "speedup_vs_first": tr, "memory_ratio_first_over_this": mr})
            writer.writerow(rows[-1])
            csv_file.flush()
    csv_file.close()
    print(f"# written {os.path.join(a.out, 'bench_solvers.csv')}")


if __name__ == "__main__":
    main()
