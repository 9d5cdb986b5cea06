#!/usr/bin/env python3
"""Solver/Linear Solver Preset = auto through the driver (perinox's default):

- every scene of xml/ (and xml/hard/) gets a choice the scene accepts: `perinox check` with auto
  is valid and names the choice and its reason;
- runs say the choice in their first line and in summary.json ("linear_solver_auto"), and the
  choice is the one the measurements call for (docs/choosing-a-solver.md): a small short-horizon
  lattice gets KLU2, a large stabilised block the matrix-free scalable solver, a small damaged
  plate GMRES on a kept MUMPS factorisation, a Jacobian the scene gives is kept;
- an explicit preset overrides auto (no "linear_solver_auto" in summary.json);
- perinox check's estimate of the peak memory is within a factor of 3 of the run's.

    check_auto_choice.py PERINOX_EXE SOURCE_DIR OUT_DIR [--mpi MPIEXEC ARGS... --]
"""
import glob
import json
import os
import re
import subprocess
import sys

exe, src, out = sys.argv[1:4]
mpi = []
if "--mpi" in sys.argv:
    i = sys.argv.index("--mpi")
    mpi = sys.argv[i + 1:sys.argv.index("--", i)]
env = dict(os.environ, PERINOX_PLOT_SCRIPT="")
failures = []


def perinox(*args):
    return subprocess.run(mpi + [exe] + list(args), capture_output=True, text=True, env=env, timeout=600)


# 1. Every shipped scene accepts auto's choice (on one rank; --mpi runs only the cases below).
scenes = [] if mpi else sorted(glob.glob(os.path.join(src, "xml", "*.xml")) + glob.glob(os.path.join(src, "xml", "hard", "*.xml")))
for scene in scenes:
    p = perinox("check", scene, "--set", "Solver/Linear Solver Preset=auto")
    if p.returncode == 2 and "'Solver/Linear Solver' is given but 'Solver/Linear Solver Preset' is 'auto'" in p.stderr:
        continue  # a scene with its own custom list must say custom
    if p.returncode != 0 or "linear solver auto: " not in p.stdout:
        failures.append(f"{os.path.relpath(scene, src)}: perinox check with auto exit {p.returncode}: "
                        f"{(p.stderr or p.stdout).strip()[-300:]}")
print(f"{len(scenes)} scenes checked with auto")

BLOCK = os.path.join(src, "xml", "tension_block.xml")
LARGE = ["Discretization/Particles={80,40}", "Discretization/Horizon Factor=3.015", "Model/Stabilization=Silling",
         "Model/G=0.5", "Solver/Load Steps=1"]
# (name, scene, settings, expected (preset, jacobian, forcing term) or None for an explicit preset)
CASES = [
    ("small_lattice", BLOCK, ["Solver/Linear Solver Preset=auto"], ("direct", "Assembled", "Constant")),
    ("large_block", BLOCK, LARGE + ["Solver/Linear Solver Preset=auto"], ("scalable", "Matrix-Free", "Eisenstat-Walker")),
    ("large_block_assembled", BLOCK, LARGE + ["Solver/Linear Solver Preset=auto", "Solver/Jacobian=Assembled"],
     ("scalable", "Assembled", "Constant")),
    ("damaged_plate", os.path.join(src, "xml", "plate_hole_damage.xml"),
     ["Solver/Linear Solver Preset=auto", "Solver/Load Steps=15", "Solver/Max Total Steps=15"],
     ("gmres-mumps", "Matrix-Free", "Eisenstat-Walker")),
    ("explicit_preset", BLOCK, LARGE + ["Solver/Linear Solver Preset=gmres-ilu"], None),
]
for name, scene, sets, expected in CASES:
    folder = os.path.join(out, name)
    args = ["run", scene, "--output", folder]
    for s in sets + ["Output/Plots=false", "Output/VTK=false"]:
        args += ["--set", s]
    p = perinox(*args)
    first = p.stdout.splitlines()[0] if p.stdout else ""
    try:
        with open(os.path.join(folder, "summary.json")) as f:
            j = json.load(f)
    except OSError:
        failures.append(f"{name}: no summary.json (exit {p.returncode}: {p.stderr.strip()[-200:]})")
        continue
    if name != "damaged_plate" and not j["converged"]:
        failures.append(f"{name}: not converged")
    auto = j.get("linear_solver_auto")
    if expected is None:
        if auto is not None or j["linear_solver"] != "gmres-ilu":
            failures.append(f"{name}: an explicit preset was not kept: {j['linear_solver']}, auto {auto}")
        if "linear solver auto" in first:
            failures.append(f"{name}: the first line says auto: {first}")
        continue
    if auto is None:
        failures.append(f"{name}: summary.json has no linear_solver_auto")
        continue
    got = (auto["preset"], auto["jacobian"], auto["forcing_term"])
    if got != expected:
        failures.append(f"{name}: auto chose {got}, expected {expected} ({auto['reason']})")
    if (j["linear_solver"], j["jacobian"], j["forcing_term"]) != got:
        failures.append(f"{name}: the run used {j['linear_solver']}, {j['jacobian']}, {j['forcing_term']}, not auto's {got}")
    phrase = f"linear solver auto: {got[0]}, {got[1]} Jacobian, {got[2]} forcing ({auto['reason']})"
    if phrase not in first:
        failures.append(f"{name}: the first line does not give the choice and its reason: {first!r}")
    print(f"{name}: {got} ({auto['reason']})")
    # perinox check's estimate of the peak memory (a rough power law, docs/choosing-a-solver.md,
    # "Estimates") within a factor of 3 of the run's measured peak.
    if not mpi:
        check = perinox(*(["check", scene] + [x for s_ in sets for x in ("--set", s_)]))
        m = re.search(r"peak memory about (\d+) MiB", check.stdout)
        if not m:
            failures.append(f"{name}: perinox check gives no memory estimate: {check.stdout.strip()[-200:]}")
        else:
            est, meas = float(m.group(1)), j["peak_rss_mib_max_rank"]
            print(f"{name}: estimated peak {est:.0f} MiB, measured {meas:.0f} MiB")
            if not meas / 3 <= est <= 3 * meas:
                failures.append(f"{name}: perinox check estimated {est:.0f} MiB, the run's peak was {meas:.0f} MiB (more than 3x apart)")

if failures:
    print("\n".join("FAILED: " + f for f in failures))
    sys.exit(1)
print("PASSED")
