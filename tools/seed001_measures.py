"""Shared reading and measures for the seed-001 comparisons (tools/seed001_figures.py,
tests/check_seed001.py). Plain Python (the tests run under any python3); the figure script
turns the lists into numpy arrays.

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
import bisect
import csv


def read_csv(path):
    """Columns of a CSV (skipping '#' lines) as a dict of float lists."""
    with open(path) as f:
        rows = list(csv.DictReader(l for l in f if not l.startswith("#")))
    return {k: [float(r[k]) for r in rows] for k in rows[0]}


def profile(run_dir, name, axis):
    """A profile probe of a run sorted along axis ('x', 'y' or 'z')."""
    p = read_csv("%s/profile_%s.csv" % (run_dir, name))
    o = sorted(range(len(p[axis])), key=lambda i: p[axis][i])
    return {k: [v[i] for i in o] for k, v in p.items()}


def at(ref_s, ref_v, s):
    """The reference (ref_s increasing) interpolated linearly at the positions s; the FEM CSVs
    carry every corner node, so at particle positions this is a lookup."""
    out = []
    for x in s:
        k = min(max(bisect.bisect_left(ref_s, x), 1), len(ref_s) - 1)
        t = (x - ref_s[k - 1]) / (ref_s[k] - ref_s[k - 1])
        out.append((1 - t) * ref_v[k - 1] + t * ref_v[k])
    return out


def amplitude(num, ref):
    return [abs((n - r) / r) if r != 0 else 0.0 for n, r in zip(num, ref)]


def zigzag(s, num, ref, lo, hi):
    """Largest |second difference| of num - ref over the points with lo <= s <= hi (each
    second difference centred on such a point), over max |ref| there."""
    d = [n - r for n, r in zip(num, ref)]
    idx = [i for i in range(1, len(s) - 1) if lo <= s[i] <= hi]
    z = max(abs(d[i + 1] - 2 * d[i] + d[i - 1]) for i in idx)
    return z / max(abs(ref[i]) for i in idx)


def max_rel(s, num, ref, lo, hi):
    """Largest |num - ref| over lo <= s <= hi, divided by the largest |ref| there."""
    idx = [i for i in range(len(s)) if lo <= s[i] <= hi]
    return max(abs(num[i] - ref[i]) for i in idx) / max(abs(ref[i]) for i in idx)
