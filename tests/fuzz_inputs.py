#!/usr/bin/env python3
"""Fuzzes the files perinox reads, on 2 MPI ranks: particle files, Exodus meshes, checkpoints and
block lists.

    python3 tests/fuzz_inputs.py --perinox BIN --meshes DIR --workdir DIR
                                 [--seed N] [--cases N] [--ranks N] [--timeout S] [--case K]

Each case damages one input in one way, drawn from a generator seeded by --seed and the case
number (case K of seed S is always the same case; `--case K` replays it alone):

  particle  tests/scenes/tension_block_particles.txt with lines deleted, repeated or shuffled, a
            particle moved far away (no neighbour) or onto another, a number replaced by a bad
            token (hexadecimal, nan, inf, 1e999, 1e-320, a negative volume or block id, garbage
            bytes), the file cut mid-line or garbage appended;
  mesh      bar.e (tests/exodus/make_exodus_meshes.cpp) with random bytes overwritten, cut short
            or extended, or one of the damaged meshes the generator writes (a stray or duplicated
            element, a long element type name, a negative block id, a replaced body);
  checkpoint a checkpoint of the two-block bar (written once, at the start) with a state.json key
            removed, given another JSON type or an impossible value, or a rank file's line
            damaged, duplicated or removed.
  blocks    tests/scenes/bimaterial_bar.xml (a lattice in two blocks) with one to three of its
            Blocks keys set to a value that is wrong, impossible or merely unusual (ids that name
            no block or two, boxes that overlap or select nothing, moduli of 0 or 1e308, an unknown
            material model, a third entry).

The contract, on every rank count: exit code 0, 2 or 3 (never 1, never a signal, never a hang:
a case longer than --timeout seconds fails); on exit 2 exactly one stderr line (mpiexec's banners
aside) of printable text, at most 300 characters, naming no C++ internals, and no output folder
written. Failing cases keep their folder (WORKDIR/case_K) for replay. Prints each failure, then
`N passed, M failed`; exit 1 if any case failed.
"""
import argparse
import json
import os
import random
import shutil
import subprocess
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from check_run import own_lines  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
FORBIDDEN = ("std::", "Teuchos", "Kokkos", "terminate called", "what():", "json.exception", "buildFamilies",
             "ProblemSpec::", "basic_string")
BAD_TOKENS = ("0x1p3", "nan", "inf", "-inf", "1e999", "1e-320", "-1", "-2.5e-3", "2.5", "1e300", "x", "\x01",
              "\xff\xfe", "1e", "--3", "", "0", "99999999999999999999")


def particle_case(rng, work):
    with open(os.path.join(HERE, "scenes", "tension_block_particles.txt"), encoding="latin-1") as f:
        lines = f.read().splitlines()
    data = [k for k, line in enumerate(lines) if line.strip() and not line.startswith("#")]
    kind = rng.choice(("delete", "repeat", "stray", "onto", "token", "cut", "garbage", "shuffle"))
    if kind == "delete":
        for k in sorted(rng.sample(data, rng.randint(1, 20)), reverse=True):
            del lines[k]
    elif kind == "repeat":
        lines.append(lines[rng.choice(data)])
    elif kind == "stray":
        lines.append(f"{rng.uniform(-50, 50):.6f} {rng.uniform(-50, 50):.6f} 0.0 2.5e-03 1")
    elif kind == "onto":
        a, b = rng.sample(data, 2)
        pa, pb = lines[a].split(), lines[b].split()
        lines[a] = " ".join(pb[:3] + pa[3:])
    elif kind == "token":
        k = rng.choice(data)
        parts = lines[k].split()
        parts[rng.randrange(len(parts))] = rng.choice(BAD_TOKENS)
        lines[k] = " ".join(parts)
    elif kind == "shuffle":
        body = [lines[k] for k in data]
        rng.shuffle(body)
        lines = body
    text = "\n".join(lines) + "\n"
    if kind == "cut":
        text = text[:rng.randrange(len(text))]
    elif kind == "garbage":
        text += "".join(chr(rng.randrange(1, 256)) for _ in range(rng.randint(1, 200)))
    path = os.path.join(work, "particles.txt")
    with open(path, "w", encoding="latin-1") as f:
        f.write(text)
    scene = os.path.join(HERE, "scenes", "tension_block_file.xml")
    return kind, [scene, "--set", f"Discretization/Particle File={path}"]


def mesh_case(rng, work, meshes):
    kind = rng.choice(("bytes", "cut", "extend", "prepared"))
    path = os.path.join(work, "mesh.e")
    if kind == "prepared":
        name = rng.choice(("stray_element.e", "duplicate_element.e", "long_type_40.e", "long_type_5000.e",
                           "negative_block.e", "bar_scaled.e", "inverted.e", "not_exodus.e", "no_blocks.e"))
        shutil.copy(os.path.join(meshes, name), path)
        kind += " " + name
    else:
        with open(os.path.join(meshes, "bar.e"), "rb") as f:
            data = bytearray(f.read())
        if kind == "bytes":
            for _ in range(rng.randint(1, 8)):
                data[rng.randrange(len(data))] = rng.randrange(256)
        elif kind == "cut":
            data = data[:rng.randrange(len(data))]
        else:
            data += bytes(rng.randrange(256) for _ in range(rng.randint(1, 4096)))
        with open(path, "wb") as f:
            f.write(data)
    args = [os.path.join(meshes, "bar_exodus.xml"), "--set", f"Discretization/Mesh File={path}"]
    if "duplicate" in kind or "stray" in kind:  # meshes of one block: the scene's block region names it
        args += ["--set", "Regions/second half/Name=left part"]
    return kind, args


def blocks_case(rng, work):
    """tests/scenes/bimaterial_bar.xml (a lattice in two blocks) with its Blocks damaged by --set."""
    scene = os.path.join(HERE, "scenes", "bimaterial_bar.xml")
    B = "Blocks/stiff/"
    choices = (
        (B + "Id", rng.choice(("-1", "-7", "0", "1", "3", "2147483647"))),
        (B + "Box Min", rng.choice(("{5.0, 5.0}", "{0.5, -1.0}", "{-1.0, -1.0}", "{1.0}", "{nan, 0}"))),
        (B + "Box Max", rng.choice(("{0.0, 0.0}", "{1.0, 1.0}", "{3.0, 1.0, 2.0}"))),
        (B + "Name", rng.choice(("stiff", "", "x" * 300))),
        (B + "Material/Young's Modulus", rng.choice(("0", "-4e9", "1e308", "4e-300"))),
        (B + "Material/Poisson's Ratio", rng.choice(("0.5", "-1", "0.49999"))),
        (B + "Material/Model", rng.choice(("Hencky", "Small Strain", "hencky", "J2"))),
        (B + "Stabilization/G", rng.choice(("-1", "0", "1e300"))),
        ("Blocks/soft/Id", rng.choice(("2", "5", "-1"))),
        ("Blocks/third/Id", rng.choice(("3", "1", "2"))),
    )
    picked = rng.sample(choices, rng.randint(1, 3))
    args = [scene]
    for key, value in picked:
        args += ["--set", f"{key}={value}"]
    return ", ".join(f"{k}={v[:20]}" for k, v in picked), args


def json_values(rng):
    return rng.choice((None, True, "text", [], {}, [1, 2], -1, 0, 1e300, -1e300, 2.5, 10**12))


def checkpoint_case(rng, work, source):
    ck = os.path.join(work, "case.checkpoint")
    shutil.copytree(source, ck)
    state_path = os.path.join(ck, "state.json")
    with open(state_path) as f:
        state = json.load(f)
    kind = rng.choice(("remove", "retype", "value", "rank line", "rank dup", "rank remove", "state text"))
    if kind in ("remove", "retype", "value"):
        key = rng.choice(sorted(state))
        if kind == "remove":
            del state[key]
        elif kind == "retype":
            state[key] = json_values(rng)
        else:
            v = state[key]
            if isinstance(v, (int, float)) and not isinstance(v, bool):
                state[key] = rng.choice((v + 1, v - 1, -v, v * 1e6, 0, 1))
            elif isinstance(v, list) and v:
                state[key] = v[:-1] if rng.random() < 0.5 else v + [v[-1]]
            else:
                state[key] = json_values(rng)
        kind += " " + key
        with open(state_path, "w") as f:
            json.dump(state, f)
    elif kind == "state text":
        with open(state_path, "w") as f:
            f.write(rng.choice(("[]", "null", "3", '"x"', "{", "{}", '{"format": 2}')))
    else:
        rank_path = os.path.join(ck, "rank_0.txt")
        with open(rank_path) as f:
            lines = f.read().splitlines()
        k = rng.randrange(len(lines))
        if kind == "rank line":
            parts = lines[k].split()
            parts[rng.randrange(len(parts))] = rng.choice(BAD_TOKENS[:12] + ("123456789", "-5", "bond", "frozen"))
            lines[k] = " ".join(parts)
        elif kind == "rank dup":
            lines.append(lines[k])
        else:
            del lines[k]
        with open(rank_path, "w") as f:
            f.write("\n".join(lines) + "\n")
    return kind, [os.path.join(work, "..", "ck_base", "bar.xml"), "--set", "Solver/Load Steps=3", "--restart", ck]


def contract(code, stderr, out):
    """What broke of the contract, or ''."""
    if code not in (0, 2, 3):
        return f"exit code {code}"
    lines = own_lines(stderr)
    if code == 2:
        if len(lines) != 1:
            return f"{len(lines)} stderr lines"
        line = lines[0]
        if len(line) > 300:
            return "a message of over 300 characters"
        if any(ord(c) < 32 or ord(c) == 127 for c in line):
            return "control characters in the message"
        bad = [w for w in FORBIDDEN if w in line]
        if bad:
            return "the message names internals: " + ", ".join(bad)
        if os.path.exists(out) or os.path.exists(out + ".partial"):
            return "an output folder was written on exit 2"
    return ""


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--perinox", required=True)
    ap.add_argument("--meshes", required=True)
    ap.add_argument("--workdir", required=True)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--cases", type=int, default=120)
    ap.add_argument("--ranks", type=int, default=2)
    ap.add_argument("--timeout", type=float, default=60)
    ap.add_argument("--case", type=int)
    a = ap.parse_args()
    os.makedirs(a.workdir, exist_ok=True)
    launcher = ["mpiexec", "-np", str(a.ranks), "--oversubscribe"]
    env = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1", PERINOX_PLOT_SCRIPT="")
    # The checkpoint every checkpoint case starts from: the bar's, after step 2 of 3.
    base = os.path.join(a.workdir, "ck_base")
    shutil.rmtree(base, ignore_errors=True)
    os.makedirs(base)
    shutil.copy(os.path.join(HERE, "exodus", "bar_exodus.xml"), os.path.join(base, "bar.xml"))
    shutil.copy(os.path.join(a.meshes, "bar.e"), os.path.join(base, "bar.e"))
    r = subprocess.run(launcher + [a.perinox, "run", os.path.join(base, "bar.xml"), "--set", "Solver/Load Steps=3",
                                   "--output", os.path.join(base, "out"), "--checkpoint-steps", "2"],
                       capture_output=True, text=True, env=env, timeout=300)
    if r.returncode != 0:
        sys.exit(f"fuzz_inputs: the base checkpoint run failed (exit {r.returncode}): {r.stderr[-500:]}")
    source = os.path.join(base, "out.checkpoint")
    passed = failed = 0
    cases = [a.case] if a.case is not None else range(a.cases)
    for k in cases:
        rng = random.Random(a.seed * 1000003 + k)
        work = os.path.join(a.workdir, f"case_{k}")
        shutil.rmtree(work, ignore_errors=True)
        os.makedirs(work)
        family = ("particle", "mesh", "checkpoint", "blocks")[k % 4]
        if family == "particle":
            kind, args = particle_case(rng, work)
        elif family == "mesh":
            kind, args = mesh_case(rng, work, a.meshes)
        elif family == "checkpoint":
            kind, args = checkpoint_case(rng, work, source)
        else:
            kind, args = blocks_case(rng, work)
        out = os.path.join(work, "out")
        cmd = launcher + [a.perinox, "run"] + args + ["--output", out]
        t0 = time.time()
        try:
            r = subprocess.run(cmd, capture_output=True, text=True, errors="replace", env=env, timeout=a.timeout)
            problem = contract(r.returncode, r.stderr, out)
            stderr = r.stderr
        except subprocess.TimeoutExpired as e:
            problem = f"no answer within {a.timeout:.0f} s (a hang)"
            stderr = (e.stderr or b"").decode("utf-8", "replace") if isinstance(e.stderr, bytes) else (e.stderr or "")
        if problem:
            failed += 1
            with open(os.path.join(work, "case.json"), "w") as f:
                json.dump({"case": k, "seed": a.seed, "family": family, "kind": kind, "command": cmd,
                           "problem": problem, "stderr": stderr[-2000:]}, f, indent=1)
            print(f"FAIL case {k} ({family}: {kind}): {problem} [{time.time() - t0:.1f} s]")
            print("     " + " ".join(cmd))
        else:
            passed += 1
            shutil.rmtree(work, ignore_errors=True)
    print(f"{passed} passed, {failed} failed")
    sys.exit(1 if failed else 0)


if __name__ == "__main__":
    main()
