#!/usr/bin/env python3
"""The output-folder policy (README, "Output folders"), checked case by case in a scratch folder.

    check_output_policy.py --np N [--launcher "mpiexec -n N ..."] -- PERINOX

Each case runs the driver on a small scene with an --output (or --checkpoint-dir) that must be
refused (exit 2, one line on stderr naming the option, nothing written, the user's files as they
were) or accepted (exit 0, the results where asked). With --np 2 the run is under mpiexec, and a
fault injected on one rank after set-up (PERINOX_FAULT_WRITE_RANK) must end both ranks with the
same sentence and exit 2 within the time limit.
"""
import argparse
import hashlib
import os
import shlex
import shutil
import subprocess
import sys
import tempfile
import time

from check_run import own_lines  # stderr without mpiexec's banners

SCENE = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "xml", "cantilever.xml")
TIMEOUT = 120
failures = []
passes = []


def snapshot(root):
    """Every path below root with its kind and content hash (symlinks not followed)."""
    out = {}
    for dirpath, dirnames, filenames in os.walk(root):
        for name in dirnames + filenames:
            p = os.path.join(dirpath, name)
            if os.path.islink(p):
                out[p] = ("link", os.readlink(p))
            elif os.path.isdir(p):
                out[p] = ("dir", None)
            else:
                with open(p, "rb") as f:
                    out[p] = ("file", hashlib.sha1(f.read()).hexdigest())
    return out


class Runner:
    def __init__(self, perinox, launcher, np, work):
        self.perinox, self.launcher, self.np, self.work = perinox, launcher, np, work

    def run(self, args, env_extra=None, cwd=None):
        env = dict(os.environ)
        env.update(env_extra or {})
        preset = "mumps" if self.np > 1 else "direct"
        cmd = self.launcher + [self.perinox, "run", SCENE, "--quiet", "--set", "Solver/Load Steps=1",
                               "--set", "Solver/Linear Solver Preset=" + preset] + args
        t = time.time()
        try:
            p = subprocess.run(cmd, cwd=cwd or self.work, env=env, capture_output=True, text=True, timeout=TIMEOUT,
                               errors="replace")
        except subprocess.TimeoutExpired:
            return None, "", time.time() - t
        return p.returncode, p.stderr, time.time() - t


def check(name, ok, detail=""):
    print(("ok     " if ok else "FAILED ") + name + ("" if ok else ": " + detail))
    (passes if ok else failures).append(name)


def refused(r, name, args, expect, watch, env_extra=None, cwd=None, absent=()):
    """The run must exit 2 with one line holding `expect`, leave `watch` unchanged and create none of `absent`."""
    before = snapshot(watch)
    code, err, _ = r.run(args, env_extra, cwd)
    lines = own_lines(err)
    after = snapshot(watch)
    problems = []
    if code != 2:
        problems.append("exit %s, not 2" % code)
    if len(lines) != 1 or expect not in lines[0]:
        problems.append("stderr %r does not hold the one sentence %r" % (lines, expect))
    if before != after:
        changed = sorted(set(before.items()) ^ set(after.items()))
        problems.append("files changed: %s" % changed[:4])
    for a in absent:
        if os.path.lexists(a):
            problems.append("%s was created" % a)
    check(name, not problems, "; ".join(problems))


def accepted(r, name, args, out, env_extra=None, cwd=None):
    code, err, _ = r.run(args, env_extra, cwd)
    problems = []
    if code != 0:
        problems.append("exit %s: %s" % (code, own_lines(err)[:2]))
    if not os.path.isfile(os.path.join(out, "summary.json")):
        problems.append("no summary.json in %s" % out)
    if os.path.lexists(out.rstrip("/") + ".partial"):
        problems.append("a staging folder was left behind")
    check(name, not problems, "; ".join(problems))
    return not problems


def main():
    argv = sys.argv[1:]
    split = argv.index("--")
    ap = argparse.ArgumentParser()
    ap.add_argument("--np", type=int, default=1)
    ap.add_argument("--launcher", default="", help="the MPI launcher and its options, as one string")
    a = ap.parse_args(argv[:split])
    perinox = os.path.abspath(argv[split + 1])
    work = tempfile.mkdtemp(prefix="perinox_output_policy_")
    try:
        r = Runner(perinox, shlex.split(a.launcher), a.np, work)
        W = lambda *p: os.path.join(work, *p)

        # A folder with a user's file in it.
        os.makedirs(W("mine"))
        with open(W("mine", "notes.txt"), "w") as f:
            f.write("my notes\n")
        refused(r, "folder with a user's file", ["--output", W("mine")], "which perinox did not write", work)
        # '.', the current folder, and '..'.
        os.makedirs(W("cwd"))
        with open(W("cwd", "keep.txt"), "w") as f:
            f.write("keep\n")
        refused(r, "'.'", ["--output", "."], "'.'", work, cwd=W("cwd"))
        refused(r, "the current folder by name", ["--output", W("cwd")], "current folder", work, cwd=W("cwd"))
        refused(r, "'..'", ["--output", ".."], "'..'", work, cwd=W("cwd"))
        # A file, the scene itself, a symbolic link, a device.
        with open(W("file.txt"), "w") as f:
            f.write("a file\n")
        refused(r, "a file", ["--output", W("file.txt")], "is a file", work)
        with open(SCENE, "rb") as f:
            scene_hash = hashlib.sha1(f.read()).hexdigest()
        refused(r, "the scene file", ["--output", SCENE], "would replace the scene file", work)
        with open(SCENE, "rb") as f:
            check("  the scene file is as it was", hashlib.sha1(f.read()).hexdigest() == scene_hash)
        os.symlink(W("mine"), W("link"))
        refused(r, "a symbolic link", ["--output", W("link")], "symbolic link", work)
        refused(r, "/dev/null", ["--output", "/dev/null"], "device", work)
        check("/dev/null is still a device", os.path.exists("/dev/null") and not os.path.isdir("/dev/null"))
        # Places where nothing can be made: below a file, in /proc, a name too long.
        refused(r, "below a file", ["--output", W("file.txt", "out")], "is a file, not a folder", work)
        refused(r, "in /proc", ["--output", "/proc/perinox_out"], "no folder can be created", work)
        refused(r, "a 300-character name", ["--output", W("n" * 300)], "longer than this file system allows", work)
        refused(r, "the root folder", ["--output", "/"], "root folder", work)
        # The home folder (HOME pointed at a scratch folder, so nothing real is at stake).
        os.makedirs(W("home"))
        refused(r, "the home folder", ["--output", W("home")], "home folder", work, env_extra={"HOME": W("home")})
        # Checkpoints: the same folder as the output, or inside it; a checkpoint folder in /proc.
        refused(r, "checkpoint folder = output folder", ["--output", W("c"), "--checkpoint-steps", "1",
                                                          "--checkpoint-dir", W("c")], "same folder", work,
                absent=[W("c")])
        refused(r, "checkpoint folder inside the output", ["--output", W("c"), "--checkpoint-steps", "1",
                                                            "--checkpoint-dir", W("c", "ck")], "one holds the other",
                work, absent=[W("c")])
        refused(r, "checkpoint folder in /proc", ["--output", W("c"), "--checkpoint-steps", "1", "--checkpoint-dir",
                                                  "/proc/perinox_ck"], "--checkpoint-dir", work, absent=[W("c")])
        # A user's folder where the staging folder goes.
        os.makedirs(W("s.partial"))
        with open(W("s.partial", "data.txt"), "w") as f:
            f.write("data\n")
        refused(r, "a user's folder at the staging name", ["--output", W("s")], "s.partial", work, absent=[W("s")])

        # Accepted: a new folder (with a trailing slash), then the same again (a perinox folder,
        # replaced as a whole), a checkpoint replaced by the next.
        if accepted(r, "a new folder, trailing slash", ["--output", W("run") + "/"], W("run")):
            with open(W("run", "summary.json"), "a") as f:
                f.write("\nOLD RUN\n")  # a trace the new summary cannot hold
            accepted(r, "an existing perinox output folder is replaced", ["--output", W("run")], W("run"))
            with open(W("run", "summary.json")) as f:
                check("  its old files are gone", "OLD RUN" not in f.read())
            with open(W("run", "extra.txt"), "w") as f:
                f.write("added by the user\n")
            refused(r, "a perinox output folder with a user's file added", ["--output", W("run")], "extra.txt", work)
        accepted(r, "checkpoints beside the output", ["--output", W("ck"), "--checkpoint-steps", "1"], W("ck"))
        check("  the checkpoint is there", os.path.isfile(W("ck.checkpoint", "state.json")))
        accepted(r, "checkpoints replaced by a second run", ["--output", W("ck"), "--checkpoint-steps", "1"], W("ck"))
        # An empty folder made by the user beforehand.
        os.makedirs(W("empty"))
        accepted(r, "an empty folder", ["--output", W("empty")], W("empty"))
        # A staging folder a killed run left behind is replaced.
        os.makedirs(W("k.partial"))
        with open(W("k.partial", ".perinox-folder"), "w") as f:
            f.write("perinox staging\n")
        accepted(r, "a killed run's staging folder", ["--output", W("k")], W("k"))
        # Quotes, spaces, ';', $(...) and backticks in the path: the files land there, nothing runs
        # (plots on, so the plot script is started with the path as an argument).
        odd = W("odd dir", "it's; $(touch INJECTED) `touch INJECTED2`; echo 'x")
        accepted(r, "a path with quotes, spaces, ; and $(...)", ["--output", odd, "--set", "Output/Plots=true"], odd,
                 env_extra={"PERINOX_PLOT_SCRIPT": os.path.join(os.path.dirname(SCENE), "..", "drivers", "plot_result.py")})
        check("  no command in the path ran", not any(os.path.exists(p) for p in
              [W("INJECTED"), W("INJECTED2"), os.path.join(W("odd dir"), "INJECTED"), "INJECTED", "INJECTED2"]))
        check("  the plot script ran on it", os.path.isfile(os.path.join(odd, "plot.log")))

        if a.np > 1:
            # An error on one rank alone after set-up: every rank ends, exit 2, one sentence.
            for bad in range(a.np):
                name = "a write fault on rank %d" % bad
                code, err, secs = r.run(["--output", W("fault%d" % bad)], {"PERINOX_FAULT_WRITE_RANK": str(bad)})
                lines = own_lines(err)
                check(name, code == 2 and len(lines) == 1 and ("on rank %d" % bad) in lines[0] and secs < 60
                      and not os.path.lexists(W("fault%d" % bad)) and not os.path.lexists(W("fault%d.partial" % bad)),
                      "exit %s after %.0f s, stderr %r" % (code, secs, lines))
    finally:
        shutil.rmtree(work, ignore_errors=True)
    print("%d passed, %d failed" % (len(passes), len(failures)))
    sys.exit(1 if failures else 0)


if __name__ == "__main__":
    main()
