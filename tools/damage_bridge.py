#!/usr/bin/env python3
"""Intact bonds across a crack band: which bonds still join particles whose u_x differs by more
than 0.02 mm at the end of a damage run of the plate with a hole (docs/validation.md, 150 x 50).

    python3 tools/damage_bridge.py RUN CHECKPOINT [HORIZON_FACTOR]

RUN is the finished run (fields.csv), CHECKPOINT a checkpoint of it (its rank files list the
broken bonds by global particle id; the last one written, so a few bonds broken after it count as
intact). Prints the number of such bonds, the largest ten with their u_x difference, stretch and
angle to the load axis, and the median angle.
"""
import collections
import csv
import glob
import math
import statistics
import sys

run, ck = sys.argv[1], sys.argv[2]
factor = float(sys.argv[3]) if len(sys.argv) > 3 else 3.015
rows = {int(r['id']): r for r in csv.DictReader(open(run + '/fields.csv'))}
broken = set()
for line in (l for f in glob.glob(ck + '/rank_*.txt') for l in open(f)):
    if line.startswith('bond '):
        _, a, b = line.split(); a, b = int(a), int(b); broken.add((min(a, b), max(a, b)))
if not broken:
    sys.exit('no broken bonds in ' + ck + '/rank_*.txt: not a checkpoint of a damage run')
print('broken bonds in the checkpoint', len(broken))
P = {i: (float(r['x']), float(r['y']), float(r['ux']), float(r['uy']), int(float(r['fictitious']))) for i, r in rows.items()}
xs = sorted({round(p[0], 9) for p in [(float(r['x']),) for r in rows.values()]})
dx = min(b - a for a, b in zip(xs, xs[1:]) if b - a > 1e-9)
delta = factor * dx
# cell grid for neighbour search
cells = collections.defaultdict(list)
for i, (x, y, *_r) in P.items():
    cells[(math.floor(x / delta), math.floor(y / delta))].append(i)
intact_cross = []
for i, (x, y, ux, uy, f) in P.items():
    cx, cy = math.floor(x / delta), math.floor(y / delta)
    for ddx in (-1, 0, 1):
        for ddy in (-1, 0, 1):
            for j in cells[(cx + ddx, cy + ddy)]:
                if j <= i: continue
                xj, yj, uxj, uyj, fj = P[j]
                L = math.hypot(xj - x, yj - y)
                if L > delta + 1e-9: continue
                if (i, j) in broken: continue
                du = uxj - ux
                if abs(du) > 0.02:
                    l = math.hypot(xj + uxj - x - ux, yj + uyj - y - uy)
                    s = l / L - 1
                    ang = math.degrees(math.atan2(abs(yj - y), abs(xj - x)))
                    intact_cross.append((abs(du), s, ang, (x, y), (xj, yj)))
intact_cross.sort(reverse=True)
print('intact bonds with |du_x| > 0.02 mm:', len(intact_cross))
for t in intact_cross[:10]:
    print('du_x %.4f stretch %.5f angle %.0f deg  %s-%s' % t)
if intact_cross:
    print('angles: median %.0f, min %.0f' % (statistics.median(t[2] for t in intact_cross), min(t[2] for t in intact_cross)))
    print('stretch: max %.5f' % max(t[1] for t in intact_cross))
