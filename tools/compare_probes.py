#!/usr/bin/env python3
"""Refactor safety net (issue 16): compares two snapshots of test outputs (summary.json, path.csv, fields_*.csv, newton.csv):
every number except timings and memory must be bit-identical; reports the others' max relative difference.

    # before a refactor: full suite, then keep the probes
    (cd build/test-output && find . \( -name summary.json -o -name '*.csv' \) -print0 | tar --null -T - -cf -) > before.tar
    # after it: the same into after.tar, unpack both, then
    python3 tools/compare_probes.py BEFORE_DIR AFTER_DIR
"""
import json, os, sys, glob, math
SKIP = {'time_s', 'wall_time_s', 'peak_rss_mib_all_ranks', 'peak_rss_mib_max_rank', 'elapsed_s', 'scene', 'output'}
def walk(a, b, path, out):
    if isinstance(a, dict) and isinstance(b, dict):
        for k in set(a) | set(b):
            if k in SKIP or 'time' in k or 'rss' in k or 'seconds' in k: continue
            if k not in a or k not in b: out.append((path + '/' + k, 'missing', None)); continue
            walk(a[k], b[k], path + '/' + k, out)
    elif isinstance(a, list) and isinstance(b, list):
        if len(a) != len(b): out.append((path, 'length %d vs %d' % (len(a), len(b)), None)); return
        for i, (x, y) in enumerate(zip(a, b)): walk(x, y, '%s[%d]' % (path, i), out)
    elif isinstance(a, (int, float)) and isinstance(b, (int, float)) and not isinstance(a, bool):
        if a != b and not (isinstance(a, float) and math.isnan(a) and math.isnan(b)):
            rel = abs(a - b) / max(abs(a), abs(b), 1e-300)
            out.append((path, '%r vs %r' % (a, b), rel))
    elif a != b:
        out.append((path, '%r vs %r' % (a, b), None))
def csv_diff(fa, fb, out, name):
    la, lb = open(fa).read().split('\n'), open(fb).read().split('\n')
    if la != lb:
        # numbers differ somewhere: relative difference per field
        worst = 0.0
        if len(la) != len(lb): out.append((name, 'rows %d vs %d' % (len(la), len(lb)), None)); return
        for x, y in zip(la, lb):
            for u, v in zip(x.split(','), y.split(',')):
                if u == v: continue
                try:
                    u, v = float(u), float(v); worst = max(worst, abs(u - v) / max(abs(u), abs(v), 1e-300))
                except ValueError: out.append((name, 'text %r vs %r' % (u, v), None))
        out.append((name, 'csv differs', worst))
before, after = sys.argv[1], sys.argv[2]
n_same = n_diff = 0
report = []
for root, dirs, files in os.walk(before):
    rel = os.path.relpath(root, before)
    for f in files:
        if not (f == 'summary.json' or f.endswith('.csv')): continue
        fa, fb = os.path.join(root, f), os.path.join(after, rel, f)
        name = os.path.join(rel, f)
        if not os.path.exists(fb): report.append((name, 'absent after', None)); n_diff += 1; continue
        out = []
        if f.endswith('.json'):
            try: walk(json.load(open(fa)), json.load(open(fb)), '', out)
            except json.JSONDecodeError as e: out.append((name, 'json error %s' % e, None))
        else:  # newton.csv, path.csv, fields.csv: no timings in them
            csv_diff(fa, fb, out, name)
        if out: n_diff += 1; report.append((name, out, None))
        else: n_same += 1
print('files identical: %d, differing: %d' % (n_same, n_diff))
for name, out, _ in report:
    if isinstance(out, str): print(name, out); continue
    print(name)
    for p, what, rel in out[:8]: print('   ', p, what, '' if rel is None else 'rel %.3g' % rel)
