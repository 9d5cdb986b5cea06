#!/usr/bin/env python3
"""Checkpoints are tied to their inputs and checked as data (bad-input tests).

    check_checkpoint_inputs.py --perinox BIN --meshes DIR --work DIR [--mpi "mpiexec -np 1 ..."]

The two-block bar of tests/exodus/bar_exodus.xml (an undamaged scene, here in three load steps)
is copied with its mesh bar.e into WORK, run with a checkpoint every second step (so the one
after step 2, at load factor 2/3, is kept), and then resumed from damaged
or mismatched checkpoints. Each resume must be refused with exit 2, one stderr line holding the
expected words and no C++ or JSON library internals, and no output folder:

  * the mesh replaced by another with the same counts (bar_scaled.e: the same 16 x 4 x 4 hexahedra,
    edge 0.26 instead of 0.25): "is not the file it was written with";
  * state.json an array, a number, a string, null: "not a JSON object";
  * 'format', 'ranks' or 'scene' of the wrong JSON type: "is not a whole number" / "is not the scene's text";
  * a load factor of 1 at step 2 of 3: "is not the load factor";
  * detached particles, a broken bond, a frozen value in this undamaged run: "has no damage".

And the untouched checkpoint must resume (exit 0), so the refusals are not of every checkpoint;
so must the scene and its mesh copied into another folder (the checkpoint is tied to the mesh by
its content, not by where it lies).
Prints `N passed, M failed`; exit 1 if any check failed.
"""
import argparse
import json
import os
import shlex
import shutil
import subprocess
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
from check_run import own_lines  # noqa: E402  (stderr without mpiexec's banners)

ap = argparse.ArgumentParser()
ap.add_argument("--perinox", required=True)
ap.add_argument("--meshes", required=True)
ap.add_argument("--work", required=True)
ap.add_argument("--mpi", default="")
a = ap.parse_args()

here = os.path.dirname(os.path.abspath(__file__))
shutil.rmtree(a.work, ignore_errors=True)
os.makedirs(a.work)
scene = os.path.join(a.work, "bar.xml")
shutil.copy(os.path.join(here, "bar_exodus.xml"), scene)
mesh = os.path.join(a.work, "bar.e")
shutil.copy(os.path.join(a.meshes, "bar.e"), mesh)
launcher = shlex.split(a.mpi)


def run(*args, scene_file=None):
    r = subprocess.run(launcher + [a.perinox, "run", scene_file or scene, "--set", "Solver/Load Steps=3"] + list(args),
                       capture_output=True, text=True, timeout=300)
    return r.returncode, own_lines(r.stderr)


# A checkpoint every second step: the one after step 2 of 3 (load factor 2/3) is the last.
code, err = run("--output", os.path.join(a.work, "first"), "--checkpoint-steps", "2")
if code != 0:
    sys.exit(f"CHECK FAILED: the checkpointed run exited {code}: {err}")
good = os.path.join(a.work, "first.checkpoint")
passed = failed = 0


def expect(name, words, edit, scene_file=None):
    """Copies the checkpoint, applies edit(folder), resumes (the scene scene_file, default the
    first run's): exit 2 with `words`, nothing written; or, when words is empty, exit 0."""
    global passed, failed
    ck = os.path.join(a.work, name + ".checkpoint")
    shutil.rmtree(ck, ignore_errors=True)
    shutil.copytree(good, ck)
    edit(ck)
    out = os.path.join(a.work, name)
    code, err = run("--output", out, "--restart", ck, scene_file=scene_file)
    internals = [w for w in ("json.exception", "std::", "ProblemSpec::", "basic_string", "what():") if err and w in err[0]]
    ok = (code == 2 and len(err) == 1 and words in err[0] and not internals and not os.path.exists(out)) if words else code == 0
    if ok:
        passed += 1
        print(f"ok   {name}: {err[0] if err else 'resumed'}")
    else:
        failed += 1
        print(f"FAIL {name}: exit {code}, stderr {err}, output {'written' if os.path.exists(out) else 'absent'}")


def state_edit(**changes):
    def edit(ck):
        path = os.path.join(ck, "state.json")
        with open(path) as f:
            st = json.load(f)
        st.update(changes)
        with open(path, "w") as f:
            json.dump(st, f)
    return edit


def state_text(text):
    def edit(ck):
        with open(os.path.join(ck, "state.json"), "w") as f:
            f.write(text)
    return edit


def rank_line(line):
    def edit(ck):
        with open(os.path.join(ck, "rank_0.txt"), "a") as f:
            f.write(line + "\n")
    return edit


expect("untouched", "", lambda ck: None)
for text, name in (("[]", "array"), ("3", "number"), ('"checkpoint"', "string"), ("null", "null")):
    expect("state_" + name, "not a JSON object", state_text(text))
expect("format_string", "'format' is not a whole number", state_edit(format="2"))
expect("ranks_string", "'ranks' is not a whole number", state_edit(ranks=[1]))
expect("scene_number", "'scene' is not the scene's text", state_edit(scene=5))
expect("lambda_one", "is not the load factor", state_edit(**{"lambda": 1.0}))
expect("detached_undamaged", "has no damage", state_edit(detached=[3]))
expect("bond_undamaged", "has no damage", rank_line("bond 1 2"))
expect("frozen_undamaged", "has no damage", rank_line("frozen 4 0x0p+0"))
moved = os.path.join(a.work, "elsewhere")
os.makedirs(moved)
shutil.copy(scene, moved)
shutil.copy(mesh, moved)
expect("moved", "", lambda ck: None, scene_file=os.path.join(moved, "bar.xml"))
# Last: the mesh itself replaced, the checkpoint untouched.
shutil.copy(os.path.join(a.meshes, "bar_scaled.e"), mesh)
expect("mesh_replaced", "is not the file it was written with", lambda ck: None)
print(f"{passed} passed, {failed} failed")
sys.exit(1 if failed else 0)
