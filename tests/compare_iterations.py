#!/usr/bin/env python3
"""Adaptive stepping check: the second run (adaptive) must need fewer Newton iterations in all
than the first (fixed small steps) and reach the same final probes (1e-8 relative).

    compare_iterations.py FIXED_DIR ADAPTIVE_DIR
"""
import json
import os
import sys


def load(d):
    with open(os.path.join(d, "summary.json")) as f:
        return json.load(f)


fixed, adaptive = load(sys.argv[1]), load(sys.argv[2])
nf = sum(s["newton_iterations"] for s in fixed["steps"])
na = sum(s["newton_iterations"] for s in adaptive["steps"])
print(f"fixed: {len(fixed['steps'])} steps, {nf} iterations; adaptive: {len(adaptive['steps'])} steps, {na} iterations")
if not (fixed["converged"] and adaptive["converged"]):
    print("FAILED: a run did not converge")
    sys.exit(1)
if na >= nf:
    print("FAILED: adaptive stepping did not save iterations")
    sys.exit(1)
for name, hist in fixed["probes"].items():
    a = hist[-1]["displacement"]
    b = adaptive["probes"][name][-1]["displacement"]
    scale = max(abs(v) for v in a) or 1.0
    diff = max(abs(x - y) for x, y in zip(a, b)) / scale
    print(f"probe {name}: final difference {diff:.2e}")
    if diff > 1e-8:
        print("FAILED: different answers")
        sys.exit(1)
print("PASSED")
