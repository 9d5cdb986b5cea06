#!/usr/bin/env python3
"""The linear solver Auto chooses against every applicable choice, end to end through the perinox
driver: wall time (the driver's own, from reading the scene to the last output; and the process's,
with start-up, sampled every 0.25 s) and peak memory per scene and size, and the ratio of Auto's time to the fastest
choice's. Prints a table and appends rows to a CSV (a rerun skips the rows already there, so the
benchmark resumes where it stopped); asserts nothing.

    tools/bench_auto.py [--rows NAME ...] [--configs NAME ...] [--cap 600] [--np 1] --out out/bench_auto

A choice is a preset with, where it applies, the Jacobian and forcing term (scalable+mf+ew is the
scalable preset with Solver/Jacobian = Matrix-Free and Solver/Forcing Term = Eisenstat-Walker).
A scene's own custom linear solver list is taken out (xml/peridigm_tensile.xml has one).
Choices the scene cannot take (the driver refuses them, exit 2: a direct solver with a matrix-free
Jacobian, conjugate gradients with damage, a matrix-free Jacobian with arc length) are listed as
not applicable. Each run may take at most max(--floor, 3 x the fastest so far in its row), and at
most --cap seconds: a choice stopped there is more than 3x slower than one already measured. A run
shorter than --repeat-below seconds is made three times and its median kept.
"""
import argparse
import csv
import json
import os
import statistics
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from bench_scalable import SETS_3D  # noqa: E402
from bench_solvers import run_polled  # noqa: E402

# name -> driver settings; in the order tried (likely fast first, so the time limit tightens early).
CONFIGS = {
    "auto": ["Solver/Linear Solver Preset=auto"],
    "scalable+mf+ew": ["Solver/Linear Solver Preset=scalable", "Solver/Jacobian=Matrix-Free",
                       "Solver/Forcing Term=Eisenstat-Walker"],
    "scalable-weak+mf+ew": ["Solver/Linear Solver Preset=scalable-weak", "Solver/Jacobian=Matrix-Free",
                            "Solver/Forcing Term=Eisenstat-Walker"],
    "scalable+mf": ["Solver/Linear Solver Preset=scalable", "Solver/Jacobian=Matrix-Free", "Solver/Forcing Term=Constant"],
    "scalable": ["Solver/Linear Solver Preset=scalable", "Solver/Jacobian=Assembled", "Solver/Forcing Term=Constant"],
    "mumps": ["Solver/Linear Solver Preset=mumps", "Solver/Jacobian=Assembled", "Solver/Forcing Term=Constant"],
    "direct": ["Solver/Linear Solver Preset=direct", "Solver/Jacobian=Assembled", "Solver/Forcing Term=Constant"],
    "gmres-mumps+mf": ["Solver/Linear Solver Preset=gmres-mumps", "Solver/Jacobian=Matrix-Free",
                       "Solver/Forcing Term=Eisenstat-Walker"],
    "gmres-mumps": ["Solver/Linear Solver Preset=gmres-mumps", "Solver/Jacobian=Assembled",
                    "Solver/Forcing Term=Eisenstat-Walker"],
    "gmres-ilu": ["Solver/Linear Solver Preset=gmres-ilu", "Solver/Jacobian=Assembled", "Solver/Forcing Term=Constant"],
    "gmres-ilu0": ["Solver/Linear Solver Preset=gmres-ilu0", "Solver/Jacobian=Assembled", "Solver/Forcing Term=Constant"],
    "gmres-muelu": ["Solver/Linear Solver Preset=gmres-muelu", "Solver/Jacobian=Assembled", "Solver/Forcing Term=Constant"],
    "cg-ilu": ["Solver/Linear Solver Preset=cg-ilu", "Solver/Jacobian=Assembled", "Solver/Forcing Term=Constant"],
    "mf-muelu": ["Solver/Linear Solver Preset=mf-muelu", "Solver/Jacobian=Preset", "Solver/Forcing Term=Constant"],
    "mf-ilu": ["Solver/Linear Solver Preset=mf-ilu", "Solver/Jacobian=Preset", "Solver/Forcing Term=Constant"],
    "mf-assembled-ilu": ["Solver/Linear Solver Preset=mf-assembled-ilu", "Solver/Jacobian=Preset",
                         "Solver/Forcing Term=Constant"],
    "jfnk-ilu": ["Solver/Linear Solver Preset=jfnk-ilu", "Solver/Jacobian=Preset", "Solver/Forcing Term=Constant"],
}
# The (preset, Jacobian, forcing term) each choice runs, to tell when auto made the same choice.
SAME = {"scalable+mf+ew": "scalable/Matrix-Free/Eisenstat-Walker", "scalable-weak+mf+ew": "scalable-weak/Matrix-Free/Eisenstat-Walker", "scalable+mf": "scalable/Matrix-Free/Constant",
        "scalable": "scalable/Assembled/Constant", "mumps": "mumps/Assembled/Constant", "direct": "direct/Assembled/Constant",
        "gmres-mumps+mf": "gmres-mumps/Matrix-Free/Eisenstat-Walker", "gmres-mumps": "gmres-mumps/Assembled/Eisenstat-Walker",
        "gmres-ilu": "gmres-ilu/Assembled/Constant", "gmres-ilu0": "gmres-ilu0/Assembled/Constant",
        "gmres-muelu": "gmres-muelu/Assembled/Constant", "cg-ilu": "cg-ilu/Assembled/Constant"}

# Choices not tried at a row's size (they were measured more than 10x slower there: docs/performance.md).
SLOW_LARGE = {"direct", "gmres-ilu", "gmres-ilu0", "cg-ilu", "mf-ilu", "mf-assembled-ilu", "jfnk-ilu", "gmres-muelu", "mf-muelu"}

# Rows where a direct factorisation would need more memory than the machine's 24 GiB (MUMPS took
# 3.3 GB at 51 200 particles in 2D and grows faster than the particle count).
HUGE = {"block2d_204800", "block3d_64000"}
DIRECT = {"mumps", "direct", "gmres-mumps", "gmres-mumps+mf"}

BLOCK = os.path.join(ROOT, "xml", "tension_block.xml")


def block2d(nx, ny):
    return (BLOCK, [f"Discretization/Particles={{{nx},{ny}}}", "Discretization/Horizon Factor=3.015", "Solver/Load Steps=1",
                    "Model/Stabilization=Silling", "Model/G=0.5"])


def block3d(n):
    return (BLOCK, [f"Discretization/Particles={{{2 * n},{n},{n // 2}}}", "Discretization/Horizon Factor=2.015",
                    "Solver/Load Steps=1", "Model/Stabilization=Silling", "Model/G=0.5"] + SETS_3D)


def without_custom_solver(scene, folder):
    """A copy of scene without its Solver/Linear Solver list (a custom list would refuse the presets)
    and with its particle or mesh file by absolute path; scene itself when it has no such list."""
    import xml.etree.ElementTree as ET
    tree = ET.parse(scene)
    solver = tree.getroot().find("ParameterList[@name='Solver']")
    custom = solver.find("ParameterList[@name='Linear Solver']") if solver is not None else None
    if custom is None:
        return scene
    solver.remove(custom)
    for p in solver.findall("Parameter[@name='Linear Solver Preset']") + solver.findall("Parameter[@name='Jacobian']") + \
            solver.findall("Parameter[@name='Forcing Term']"):
        solver.remove(p)
    for p in tree.getroot().iter("Parameter"):
        if p.get("name") in ("Particle File", "Mesh File") and not p.get("value").startswith("/"):
            p.set("value", os.path.normpath(os.path.join(os.path.dirname(scene), p.get("value"))))
    os.makedirs(folder, exist_ok=True)
    out = os.path.join(folder, os.path.basename(scene))
    tree.write(out)
    return out


def rows(folder):
    """name -> (scene, settings, large): every scene of xml/, the tension block series, Peridigm's test."""
    r = {}
    for f in sorted(os.listdir(os.path.join(ROOT, "xml"))):
        if f.endswith(".xml"):
            r[f[:-4]] = (without_custom_solver(os.path.join(ROOT, "xml", f), folder), [], False)
    r["peridigm_tensile_hencky"] = (r["peridigm_tensile"][0], ["Material/Model=Hencky"], False)
    r["peridigm_deck"] = (os.path.join(ROOT, "validation", "benchmarks", "peridigm_tensile", "tensile_test.yaml"), [], False)
    r["plate_hole_damage_150x50_40steps"] = (os.path.join(ROOT, "xml", "plate_hole_damage.xml"),
                                             ["Discretization/Particles={150,50}", "Damage/Max Stall Breaks=1000",
                                              "Solver/Max Total Steps=40"], True)
    for nx, ny in [(80, 40), (160, 80), (320, 160), (640, 320)]:
        s, sets = block2d(nx, ny)
        r[f"block2d_{nx * ny}"] = (s, sets, nx * ny >= 51200)
    for n in [20, 30, 40]:  # 2n x n x n/2 particles
        s, sets = block3d(n)
        r[f"block3d_{n * n * n}"] = (s, sets, n >= 30)
    return r


def run(perinox, scene, out, sets, timeout, np):
    cmd = [perinox, "run", scene, "--output", out, "--quiet"]
    if np > 1:
        cmd = ["mpirun", "--oversubscribe", "-np", str(np)] + cmd
    for s in sets + ["Output/Plots=false", "Output/VTK=false"]:
        cmd += ["--set", s]
    env = dict(os.environ, PERINOX_PLOT_SCRIPT="", OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1")
    code, wall, rss, last = run_polled(cmd, timeout, env)
    if code == "timeout":
        return {"status": "timeout", "wall": wall, "rss": rss}
    if code == 2:
        return {"status": "n/a", "why": last}
    try:
        with open(os.path.join(out, "summary.json")) as f:
            j = json.load(f)
    except OSError:
        return {"status": f"failed ({code})", "why": last, "wall": wall}
    choice = j.get("linear_solver", "")
    if j.get("linear_solver_auto"):
        a = j["linear_solver_auto"]
        choice = f"{a['preset']}/{a['jacobian']}/{a['forcing_term']}"
    return {"status": "converged" if j["converged"] else "not converged", "wall": j["wall_time_s"], "process_wall": wall,
            "rss": j.get("peak_rss_mib_max_rank", rss), "newton": j.get("newton_iterations_total", 0),
            "krylov": j.get("krylov_iterations_total", 0), "choice": choice,
            "load": j["steps"][-1]["load_factor"] if j.get("steps") else 0.0, "limit": j.get("limit_load_factor", "")}


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--rows", nargs="+")
    ap.add_argument("--configs", nargs="+", default=list(CONFIGS))
    ap.add_argument("--cap", type=float, default=600)
    ap.add_argument("--floor", type=float, default=30)
    ap.add_argument("--np", type=int, default=1)
    ap.add_argument("--repeat-below", type=float, default=5.0, help="runs shorter than this (s) are the median of three")
    ap.add_argument("--confirm", type=int, default=0,
                    help="then, per row where auto chose otherwise than the fastest choice, run the two alternately this many "
                         "times each and record the medians (the ratio measured back to back)")
    ap.add_argument("--out", default="out/bench_auto")
    ap.add_argument("--perinox", default=os.path.join(ROOT, "build", "drivers", "perinox"))
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    path = os.path.join(a.out, "bench_auto.csv")
    keys = ["row", "config", "ranks", "status", "wall_s", "process_s", "peak_mib", "newton", "krylov", "load", "limit", "choice", "why"]
    done = {}
    if os.path.exists(path):
        with open(path, newline="") as f:
            for r in csv.DictReader(f):
                done[(r["row"], r["config"], r["ranks"])] = r
    new = not os.path.exists(path)
    f = open(path, "a", newline="")
    w = csv.DictWriter(f, fieldnames=keys)
    if new:
        w.writeheader()
    all_rows = rows(os.path.join(a.out, "scenes"))
    for name in a.rows or list(all_rows):
        scene, sets, large = all_rows[name]
        for config in a.configs:
            key = (name, config, str(a.np))
            if key in done or (large and config in SLOW_LARGE) or (name in HUGE and config in DIRECT):
                continue
            times = [float(r["wall_s"]) for (n, c, p), r in done.items()
                     if n == name and p == str(a.np) and r["status"] in ("converged", "not converged")]
            timeout = min(a.cap, max(a.floor, 3 * min(times))) if times else a.cap
            out = os.path.join(a.out, "runs", f"{name}_{config}_np{a.np}")
            r = run(a.perinox, scene, out, sets + CONFIGS[config], timeout, a.np)
            if r["status"] in ("converged", "not converged") and r["wall"] < a.repeat_below:
                # Short runs: the median of three (one run's noise on a shared machine is tens of percent).
                again = [r] + [run(a.perinox, scene, out, sets + CONFIGS[config], timeout, a.np) for _ in range(2)]
                again = [x for x in again if x["status"] == r["status"]]
                r = sorted(again, key=lambda x: x["wall"])[len(again) // 2]
                r["process_wall"] = statistics.median(x["process_wall"] for x in again)
            row = {"row": name, "config": config, "ranks": a.np, "status": r["status"],
                   "wall_s": f"{r['wall']:.3f}" if "wall" in r else "",
                   "process_s": f"{r['process_wall']:.2f}" if "process_wall" in r else "", "peak_mib": f"{r['rss']:.0f}" if r.get("rss") else "",
                   "newton": r.get("newton", ""), "krylov": r.get("krylov", ""), "load": r.get("load", ""),
                   "limit": r.get("limit", ""), "choice": r.get("choice", ""),
                   "why": r.get("why", "")[:200]}
            w.writerow(row)
            f.flush()
            done[key] = {k: str(v) for k, v in row.items()}
            print(f"{name:34} {config:18} {r['status']:14} {row['wall_s']:>9} s {row['peak_mib']:>6} MiB {row['choice']}",
                  flush=True)
    if a.confirm:
        confirm(a, all_rows, done, w, f)
    f.close()
    table(done, a.np)


def confirm(a, all_rows, done, w, f):
    """Auto against the row's fastest choice, alternately, --confirm times each: the medians are
    kept as configs 'auto (confirm)' and '<choice> (confirm)'."""
    names = []
    for (n, c, p) in done:
        if p == str(a.np) and n not in names and n in all_rows:
            names.append(n)
    for n in names:
        rs = {c: r for (m, c, p), r in done.items() if m == n and p == str(a.np)}
        if any(c.endswith("(confirm)") for c in rs):
            continue
        ok = completed(rs)
        others = {c: float(r["wall_s"]) for c, r in ok.items() if c != "auto" and not c.endswith("(confirm)")}
        au = ok.get("auto")
        if not others or not au:
            continue
        best = min(others, key=others.get)
        if SAME.get(best) == au["choice"]:
            continue  # the same computation
        scene, sets, _ = all_rows[n]
        runs = {"auto": [], best: []}
        for k in range(a.confirm):
            for c in ("auto", best):
                out = os.path.join(a.out, "runs", f"{n}_{c}_confirm")
                r = run(a.perinox, scene, out, sets + CONFIGS[c], a.cap, a.np)
                if r["status"] in ("converged", "not converged"):
                    runs[c].append(r)
        for c, rr in runs.items():
            if not rr:
                continue
            med = sorted(rr, key=lambda x: x["wall"])[len(rr) // 2]
            row = {"row": n, "config": c + " (confirm)", "ranks": a.np, "status": med["status"], "wall_s": f"{med['wall']:.3f}",
                   "process_s": f"{statistics.median(x['process_wall'] for x in rr):.2f}", "peak_mib": f"{med['rss']:.0f}",
                   "newton": med["newton"], "krylov": med["krylov"], "load": med["load"], "limit": med["limit"],
                   "choice": med["choice"], "why": f"median of {len(rr)}, alternating with the other"}
            w.writerow(row)
            f.flush()
            done[(n, row["config"], str(a.np))] = {k: str(v) for k, v in row.items()}
        print(f"{n:34} confirm: auto {statistics.median(x['wall'] for x in runs['auto']) if runs['auto'] else float('nan'):.3f} s, "
              f"{best} {statistics.median(x['wall'] for x in runs[best]) if runs[best] else float('nan'):.3f} s", flush=True)


def completed(rs):
    """The runs of a row that did its work: converged, or (a row that stops unconverged: a limit load
    passed, Max Total Steps reached) got as far in load as the farthest run of the row."""
    finished = {c: r for c, r in rs.items() if r["status"] in ("converged", "not converged")}
    if any(r["status"] == "converged" for r in finished.values()):
        return {c: r for c, r in finished.items() if r["status"] == "converged"}
    loads = [float(r["load"]) for r in finished.values() if r.get("load")]
    far = max(loads, default=0.0)
    return {c: r for c, r in finished.items() if r.get("load") and float(r["load"]) >= far - 1e-9}


def table(done, np):
    """Per row: the fastest choice, Auto's choice and time, their ratio (solve wall time and the
    process's wall time, with start-up). Where auto chose the fastest choice itself the ratio is 1
    (the same computation; two timings of it differ by the machine's noise only); where --confirm
    measured the two back to back, the ratio of those medians."""
    print(f"\n{'row':34} {'fastest':16} {'s':>8} {'auto chose':40} {'auto s':>8} {'ratio':>6} {'process ratio':>13} {'auto MiB':>8}")
    names = []
    for (n, c, p) in done:
        if p == str(np) and n not in names:
            names.append(n)
    ratios = []
    for n in names:
        rs = {c: r for (m, c, p), r in done.items() if m == n and p == str(np)}
        ok = completed(rs)
        others = {c: float(r["wall_s"]) for c, r in ok.items() if c != "auto" and not c.endswith("(confirm)")}
        if not others:
            continue
        best = min(others, key=others.get)
        au = ok.get("auto")
        same = au is not None and SAME.get(best) == au["choice"]
        if au and f"{best} (confirm)" in ok and "auto (confirm)" in ok:
            # Measured back to back: the ratio of the medians.
            au, others[best] = ok["auto (confirm)"], float(ok[f"{best} (confirm)"]["wall_s"])
            ok[best] = ok[f"{best} (confirm)"]
        if au and same:
            ratios.append(1.0)
            print(f"{n:34} {best:16} {others[best]:8.2f} {au['choice']:40} {'(same)':>8} {1.0:6.2f} {1.0:13.2f} {au['peak_mib']:>8}")
        elif au:
            ratio = float(au["wall_s"]) / others[best]
            pr = float(au["process_s"]) / float(ok[best]["process_s"]) if au.get("process_s") and ok[best].get("process_s") else float("nan")
            ratios.append(ratio)
            print(f"{n:34} {best:16} {others[best]:8.2f} {au['choice']:40} {float(au['wall_s']):8.2f} {ratio:6.2f} {pr:13.2f} {au['peak_mib']:>8}")
        else:
            a = rs.get("auto")
            print(f"{n:34} {best:16} {others[best]:8.2f} {'(auto ' + (a['status'] if a else 'not run') + ')':40}")
    if ratios:
        print(f"# auto / fastest: median {statistics.median(ratios):.2f}, worst {max(ratios):.2f}, rows {len(ratios)}")


if __name__ == "__main__":
    main()
