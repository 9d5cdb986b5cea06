"""Shared reading and measures for the seed-001 comparisons (tools/seed001_figures.py,
tests/check_seed001.py). numpy only.

Local amplitudes (seed 001 eqs 21-22): a_i = |v_i^num - v_i^ref| / |v_i^ref| (0 where the
reference is 0).

Oscillation measure: the zero-energy modes of a nearest-neighbour correspondence model are
particle-to-particle zigzags, while the discretisation and nonlocal boundary-layer errors are
smooth along a line. So the oscillation of a profile is measured on its difference from the
reference, d_i = v_i^num - v_i^ref, as the largest second difference
|d_{i+1} - 2 d_i + d_{i-1}| over a window of the line, divided by the largest |v^ref| there.
A smooth error (even a large one) has a second difference of order h^2 |d''|; a zigzag of
amplitude A has 4 A.
"""
import csv

import numpy as np


def read_csv(path):
    """Columns of a CSV (skipping '#' lines) as a dict of float arrays."""
    with open(path) as f:
        rows = list(csv.DictReader(l for l in f if not l.startswith("#")))
    return {k: np.array([float(r[k]) for r in rows]) for k in rows[0]}


def profile(run_dir, name, axis):
    """A profile probe of a run sorted along axis ('x', 'y' or 'z')."""
    p = read_csv("%s/profile_%s.csv" % (run_dir, name))
    o = np.argsort(p[axis])
    return {k: v[o] for k, v in p.items()}


def at(ref_s, ref_v, s):
    """The reference interpolated (linearly) at the positions s; the FEM CSVs carry every
    corner node, so at particle positions this is a lookup."""
    return np.interp(s, ref_s, ref_v)


def amplitude(num, ref):
    num, ref = np.asarray(num), np.asarray(ref)
    out = np.zeros_like(ref)
    nz = ref != 0
    out[nz] = np.abs((num[nz] - ref[nz]) / ref[nz])
    return out


def zigzag(s, num, ref, lo, hi):
    """Largest |second difference| of num - ref over the points with lo <= s <= hi (each
    second difference centred on such a point), over max |ref| there."""
    s, d, ref = np.asarray(s), np.asarray(num) - np.asarray(ref), np.asarray(ref)
    idx = [i for i in range(1, len(s) - 1) if lo <= s[i] <= hi]
    z = max(abs(d[i + 1] - 2 * d[i] + d[i - 1]) for i in idx)
    return z / np.max(np.abs(ref[idx]))


def max_rel(s, num, ref, lo, hi):
    """Largest relative deviation |num - ref| / max|ref| over lo <= s <= hi."""
    s, num, ref = map(np.asarray, (s, num, ref))
    m = (s >= lo) & (s <= hi)
    return np.max(np.abs(num[m] - ref[m])) / np.max(np.abs(ref[m]))
