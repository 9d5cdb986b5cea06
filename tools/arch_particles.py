#!/usr/bin/env python3
"""Particle file of a shallow circular arch (2D), for xml/hard/shallow_arch*.xml.

The mid-surface is a circular arc; particles sit at arc-length spacing dx along it and at normal
offsets t = (k - (rows - 1) / 2) dx across the depth, so the lattice of a straight beam is bent
onto the arc (volume dx^2 (1 + t / R), thickness 1). Real columns i = -n..n (the crown column
i = 0 sits on the symmetry axis x = 0); `clamp` further columns at each end form the clamped
supports (block 2), which the scenes prescribe to zero. The rise h is measured at the
mid-surface between the crown and the clamp boundary (half a spacing beyond the last real
column), so R (1 - cos(a / R)) = h with a = (n + 1/2) dx.

    arch_particles.py --half-columns 100 --rows 3 --dx 1.0 --rise 8.0 --clamp 1 OUT
"""
import argparse
import math


def radius(a, h):
    # R (1 - cos(a/R)) = h, from the parabolic guess R = a^2 / (2 h); Newton on R.
    R = a * a / (2 * h)
    for _ in range(100):
        g = R * (1 - math.cos(a / R)) - h
        dg = (1 - math.cos(a / R)) - (a / R) * math.sin(a / R)
        step = g / dg
        R -= step
        if abs(step) < 1e-15 * R:
            break
    return R


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--half-columns", type=int, default=100)
    ap.add_argument("--rows", type=int, default=3)
    ap.add_argument("--dx", type=float, default=1.0)
    ap.add_argument("--rise", type=float, default=8.0)
    ap.add_argument("--clamp", type=int, default=1)
    ap.add_argument("out")
    a = ap.parse_args()
    n, dx = a.half_columns, a.dx
    half = (n + 0.5) * dx
    R = radius(half, a.rise)
    lines = [
        "# Shallow clamped circular arch (tools/arch_particles.py --half-columns %d --rows %d --dx %g --rise %g --clamp %d)"
        % (n, a.rows, dx, a.rise, a.clamp),
        "# mid-surface radius R = %.10g, half arc length %.10g, rise %.10g; block 1 real, block 2 clamp columns" % (R, half, a.rise),
        "# x y z volume block",
    ]
    count = 0
    for i in range(-n - a.clamp, n + a.clamp + 1):
        th = i * dx / R
        for k in range(a.rows):
            t = (k - (a.rows - 1) / 2.0) * dx
            x = (R + t) * math.sin(th)
            y = (R + t) * math.cos(th) - (R - a.rise)
            vol = dx * dx * (1 + t / R)
            blk = 2 if abs(i) > n else 1
            lines.append("%.15g %.15g 0 %.15g %d" % (x, y, vol, blk))
            count += 1
    with open(a.out, "w") as f:
        f.write("\n".join(lines) + "\n")
    print("%d particles, R = %.6g" % (count, R))


if __name__ == "__main__":
    main()
