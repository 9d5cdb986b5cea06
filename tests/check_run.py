#!/usr/bin/env python3
"""Runs a perinox command and checks what it produced. Used by CTest.

    check_run.py --out DIR [checks...] -- COMMAND...

Checks:
  --exit-code N        the command must exit with N (default 0)
  --message TEXT       TEXT must appear in the output, and on failure stderr must hold exactly
                       one non-empty line (one clear sentence, not a stack trace)
  --no-output          neither DIR nor DIR.partial may exist afterwards
  --png NAME...        these files exist in DIR and are PNG images (the plot script ran)
  --converged          summary.json says converged, every step recorded
  --distributed        with --partition: the discretisation was built distributed and no rank held
                       more than its owned particles and three times its ghosts
  --max-error X        summary.json's e_u is at most X
  --probe NAME[@LF] C V RTOL  probe NAME, component C, at the last step (or the step with load
                       factor nearest LF) is V within RTOL relative
  --probe-reference NAME C V RTOL  summary.json's probe_references: the scene's analytic reference
                       read as probe NAME (load factor 1), component C, is V within RTOL relative
  --normalised-by WHAT  every step's residual was normalised by WHAT ("reaction" or "external force")
  --expect-from-scene XML  read the scene's top-level "Expected Outcome": "converged" (exit 0,
                       converged) or "failure: TEXT" (exit 3, TEXT in summary.json's failure, the
                       last converged state written, and no NaN in it)
  --quadratic          Newton converges quadratically in its asymptotic range: whenever the
                       normalised residual r_k is below 1e-2, r_{k+1} <= max(C r_k^2, FLOOR)
                       with C = 1e3 and FLOOR = 1e-11 (the round-off floor of the residual;
                       --floor sets it for scenes whose floor is higher, e.g. slender beams).
                       A linearly converging iteration with rate q gives r_{k+1}/r_k^2 = q/r_k,
                       which exceeds 1e3 as soon as r_k < q/1e3, so a wrong tangent fails.
"""
import argparse
import json
import math
import os
import shutil
import subprocess
import sys

C_QUAD = 1e3
FLOOR = 1e-11


def fail(msg):
    print("CHECK FAILED: " + msg)
    sys.exit(1)


def own_lines(stderr):
    """Non-empty stderr lines, without the banners mpiexec adds between dashed rules when a
    rank exits non-zero (those are the launcher's, not perinox's)."""
    out, inside = [], False
    for line in stderr.splitlines():
        if line.startswith("-----"):
            inside = not inside
            continue
        if not inside and line.strip():
            out.append(line)
    return out


def main():
    argv = sys.argv[1:]
    if "--" not in argv:
        fail("usage: check_run.py --out DIR [checks] -- COMMAND")
    split = argv.index("--")
    ap = argparse.ArgumentParser()
    ap.add_argument("--out", required=True)
    ap.add_argument("--exit-code", type=int, default=0)
    ap.add_argument("--message")
    ap.add_argument("--no-output", action="store_true")
    ap.add_argument("--converged", action="store_true")
    ap.add_argument("--distributed", action="store_true")
    ap.add_argument("--max-error", type=float)
    ap.add_argument("--quadratic", action="store_true")
    ap.add_argument("--probe", nargs=4, action="append", default=[])
    ap.add_argument("--probe-reference", nargs=4, action="append", default=[])
    ap.add_argument("--normalised-by")
    ap.add_argument("--expect-from-scene")
    ap.add_argument("--last-load-factor", nargs=2, type=float,
                    help="the last (failing) step's load factor lies in [LO, HI]")
    ap.add_argument("--hydrostatic-curve", nargs=5, metavar=("PROBE", "X0", "TRACTION", "LAMBDA_PLUS_MU", "RTOL"),
                    help="probe PROBE at reference x = X0 follows u = (x - 1) X0 with 2(lambda+mu) ln(x)/x = load factor * TRACTION")
    ap.add_argument("--work-counts", choices=["direct", "krylov"],
                    help="check the recorded solver work: totals equal the sums over steps, a linear solve "
                         "for every Newton iteration, and Krylov iterations (>= 1 a solve) or none (direct)")
    ap.add_argument("--max-krylov", type=int,
                    help="with --work-counts krylov: at most this many Krylov iterations in all (a count, not a time)")
    ap.add_argument("--png", nargs="+", default=[])
    ap.add_argument("--linear-failures", choices=["none", "some"],
                    help="with --work-counts: no linear solve, or at least one, recorded as unconverged")
    ap.add_argument("--partition", choices=["RCB", "Multi-Jagged", "Slabs"],
                    help="the run's particles were split by this method, every rank owning some")
    ap.add_argument("--floor", type=float, default=FLOOR,
                    help="round-off floor of the normalised residual for --quadratic")
    a = ap.parse_args(argv[:split])
    cmd = argv[split + 1:]
    expected_failure = None
    if a.expect_from_scene:
        import xml.etree.ElementTree as ET
        root = ET.parse(a.expect_from_scene).getroot()
        outcome = next((p.get("value") for p in root.findall("Parameter") if p.get("name") == "Expected Outcome"), "")
        if outcome == "converged":
            a.converged = True
        elif outcome.startswith("failure:"):
            expected_failure = outcome[len("failure:"):].strip()
            a.exit_code = 3
        else:
            fail(f"{a.expect_from_scene} has no valid 'Expected Outcome' (got {outcome!r})")
    for d in (a.out, a.out + ".partial"):
        shutil.rmtree(d, ignore_errors=True)
    p = subprocess.run(cmd, capture_output=True, text=True)
    text = p.stdout + p.stderr
    print(text[-4000:])
    if p.returncode != a.exit_code:
        fail(f"exit code {p.returncode}, expected {a.exit_code}")
    if a.message is not None:
        if a.message not in text:
            fail(f"expected message containing {a.message!r}")
        if a.exit_code != 0:
            lines = own_lines(p.stderr)
            if len(lines) != 1:
                fail(f"expected one line on stderr, got {len(lines)}")
    if expected_failure is not None:
        with open(os.path.join(a.out, "summary.json")) as f:
            s = json.load(f)
        if s["converged"] or expected_failure not in s.get("failure", ""):
            fail(f"expected a failure mentioning {expected_failure!r}, got {s.get('failure', 'convergence')!r}")
        with open(os.path.join(a.out, "fields.csv")) as f:
            if "nan" in f.read().lower():
                fail("the written state contains NaN")
        print(f"stopped as expected: {s['failure']}")
    if a.last_load_factor or a.hydrostatic_curve:
        with open(os.path.join(a.out, "summary.json")) as f:
            s = json.load(f)
        if a.last_load_factor:
            lf = s["steps"][-1]["load_factor"]
            print(f"last step at load factor {lf}")
            if not a.last_load_factor[0] <= lf <= a.last_load_factor[1]:
                fail(f"last load factor {lf} outside {a.last_load_factor}")
        if a.hydrostatic_curve:
            name, x0, t, lm, rtol = a.hydrostatic_curve
            x0, t, lm, rtol = float(x0), float(t), float(lm), float(rtol)
            worst = 0.0
            for h in s["probes"][name]:
                p = h["load_factor"] * t
                x = 1.0
                for _ in range(100):  # Newton on 2 (lambda+mu) ln(x)/x = p, stable branch
                    g = 2 * lm * math.log(x) / x - p
                    dg = 2 * lm * (1 - math.log(x)) / x ** 2
                    x -= g / dg
                ref = (x - 1) * x0
                worst = max(worst, abs(h["displacement"][0] - ref) / abs(ref))
            print(f"hydrostatic curve: largest relative deviation {worst:.4f} over {len(s['probes'][name])} steps")
            if worst > rtol:
                fail(f"deviation {worst} from the analytic curve exceeds {rtol}")
    if a.partition:
        with open(os.path.join(a.out, "summary.json")) as f:
            s = json.load(f)
        part = s.get("partition", {})
        print(f"partition: {part}")
        if part.get("method") != a.partition:
            fail(f"the run was partitioned by {part.get('method')}, expected {a.partition}")
        if not part.get("owned_min", 0) > 0:
            fail("a rank owned no particles")
        if (s["ranks"] > 1) != (part.get("ghosts_max", 0) > 0):
            fail(f"{part.get('ghosts_max')} ghosts on {s['ranks']} ranks")
        # No rank holds a family array of the whole body, and each holds at most its share.
        if part.get("global_family_entries_max", -1) != 0:
            fail(f"a rank holds {part.get('global_family_entries_max')} entries of the whole body's families")
        if part.get("ranks_beyond_family_share", -1) != 0:
            fail("a rank holds more family entries than twice its owned and ghost particles times the largest family")
        # Construction = Distributed: every rank holds its share only (owned + at most 3 x its
        # ghosts: a second layer and the box's corners), whatever the body's size.
        if a.distributed:
            if part.get("construction") != "Distributed":
                fail(f"the discretisation was built {part.get('construction')}, expected Distributed")
            if part.get("ranks_beyond_particle_share", -1) != 0:
                fail(f"{part.get('ranks_beyond_particle_share')} rank(s) hold more than their owned particles and three "
                     f"times their ghosts (particles_held_max {part.get('particles_held_max')} of {part.get('particles')})")
    if a.work_counts:
        with open(os.path.join(a.out, "summary.json")) as f:
            s = json.load(f)
        st = s["steps"]
        for key, total in (("newton_iterations_all_attempts", "newton_iterations_total"),
                           ("linear_solves", "linear_solves_total"), ("krylov_iterations", "krylov_iterations_total"),
                           ("linear_failures", "linear_failures_total")):
            if sum(x[key] for x in st) != s[total]:
                fail(f"{total} = {s[total]} is not the sum of the steps' {key}")
        newton = sum(x["newton_iterations"] for x in st)
        if not newton <= s["newton_iterations_total"] <= s["linear_solves_total"]:
            fail(f"expected Newton iterations of the converged solves ({newton}) <= all Newton iterations "
                 f"({s['newton_iterations_total']}) <= linear solves ({s['linear_solves_total']})")
        if a.work_counts == "direct" and s["krylov_iterations_total"] != 0:
            fail(f"a direct solver recorded {s['krylov_iterations_total']} Krylov iterations")
        if a.work_counts == "krylov" and not s["krylov_iterations_total"] >= s["linear_solves_total"] > 0:
            fail(f"{s['krylov_iterations_total']} Krylov iterations for {s['linear_solves_total']} solves")
        if a.max_krylov is not None and s["krylov_iterations_total"] > a.max_krylov:
            fail(f"{s['krylov_iterations_total']} Krylov iterations in all, more than {a.max_krylov}")
        failures = s["linear_failures_total"]
        if a.linear_failures == "none" and failures != 0:
            fail(f"{failures} linear solves recorded as unconverged, expected none")
        if a.linear_failures == "some" and not 0 < failures <= s["linear_solves_total"]:
            fail(f"{failures} unconverged linear solves of {s['linear_solves_total']}, expected some")
        said = any("linear solves did not converge" in w for w in s.get("warnings", []))
        if said != (failures > 0):
            fail(f"summary.json's warnings {s.get('warnings', [])} do not match {failures} unconverged linear solves")
        print(f"work: {failures} unconverged linear solves")
        print(f"work: {newton} Newton iterations in converged solves, {s['newton_iterations_total']} in all, "
              f"{s['linear_solves_total']} linear solves, {s['krylov_iterations_total']} Krylov iterations")
    for name in a.png:
        path = os.path.join(a.out, name)
        if not os.path.isfile(path):
            fail(f"{path} was not drawn")
        with open(path, "rb") as f:
            if f.read(8) != b"\x89PNG\r\n\x1a\n":
                fail(f"{path} is not a PNG image")
        print(f"plot: {path}")
    if a.no_output:
        for d in (a.out, a.out + ".partial"):
            if os.path.exists(d):
                fail(f"{d} exists but the run should have written nothing")
    if a.converged or a.max_error is not None or a.quadratic or a.probe or a.normalised_by or a.probe_reference:
        with open(os.path.join(a.out, "summary.json")) as f:
            s = json.load(f)
        if a.converged and not s["converged"]:
            fail("run did not converge: " + s.get("failure", "?"))
        # Arc-length continuation ends at its own target (load factor or deflection), not at 1;
        # a load path at its last corner, pseudo-time 1.
        last = s["steps"][-1]
        if a.converged and s.get("continuation", "Load Stepping") == "Load Stepping" \
                and abs(last.get("pseudo_time", last["load_factor"]) - 1.0) > 1e-12:
            fail("run did not reach the end of its load path" if "pseudo_time" in last else "run did not reach load factor 1")
        if a.max_error is not None:
            e = s["errors"]["e_u"]
            print(f"e_u = {e:.6g} (bound {a.max_error})")
            if not e <= a.max_error:
                fail(f"e_u = {e} exceeds {a.max_error}")
        for name, comp, value, rtol in a.probe:
            at = None
            if "@" in name:
                name, at = name.split("@")
            hist = s["probes"][name]
            entry = hist[-1] if at is None else min(hist, key=lambda h: abs(h["load_factor"] - float(at)))
            key = next(k for k in entry if k != "load_factor")
            got, want = entry[key][int(comp)], float(value)
            print(f"probe {name}[{comp}] = {got:.8g}, reference {want:.8g}, rel. diff {abs(got - want) / abs(want):.3g}")
            if abs(got - want) > float(rtol) * abs(want):
                fail(f"probe {name}[{comp}] = {got} differs from {want} by more than {rtol} relative")
        for name, comp, value, rtol in a.probe_reference:
            ref = s.get("probe_references", {}).get(name)
            if ref is None:
                fail(f"summary.json has no probe_references entry for '{name}'")
            got, want = ref["displacement"][int(comp)], float(value)
            print(f"reference read as probe {name}[{comp}] = {got:.8g}, expected {want:.8g}")
            if abs(got - want) > float(rtol) * abs(want):
                fail(f"the reference read as probe {name}[{comp}] = {got} differs from {want} by more than {rtol} relative")
        if a.normalised_by:
            for st in s["steps"]:
                if st["normalised_by"] != a.normalised_by:
                    fail(f"step {st['step']} normalised by {st['normalised_by']}, expected {a.normalised_by}")
        if a.quadratic:
            pairs = 0
            for st in s["steps"]:
                r = st["residuals"]
                for k in range(len(r) - 1):
                    if r[k] < 1e-2:
                        pairs += 1
                        bound = max(C_QUAD * r[k] ** 2, a.floor)
                        if r[k + 1] > bound:
                            fail(f"step {st['step']}: residual {r[k]:.3e} -> {r[k+1]:.3e} is not quadratic (bound {bound:.3e})")
            if pairs == 0:
                fail("no iteration reached the asymptotic range")
            print(f"quadratic convergence checked on {pairs} iteration pairs")
    print("CHECK PASSED")


if __name__ == "__main__":
    main()
