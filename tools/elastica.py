#!/usr/bin/env python3
"""Large-deflection cantilever under a dead tip load: the inextensible Euler elastica.

    elastica.py --alpha A             tip displacements / L for alpha = P L^2 / (E I)
    elastica.py --E E --nu NU --depth D --length L --load P [--plane-strain]

Independent reference for the cantilever scenes (seed 000's Molstad solutions are not
available). The beam equation E I theta'' = P cos(theta) with theta(0) = 0 (clamped) and
theta'(L) = 0 (no moment at the tip) is solved by shooting on theta'(0) with RK4 and bisection.
It neglects shear and axial strain, which the plane continuum includes: for L/d = 10 shear adds
about 3 E d^2 / (12 k G L^2) = 0.7 % to the deflection (k = 5/6). Pure Python, no dependencies.
"""
import argparse
import math


def shoot(alpha, k, n=4000):
    """Integrates theta'' = alpha cos(theta) on s in [0, 1] (s = arc length / L) from
    theta(0) = 0, theta'(0) = k; returns theta'(1), x(1), y(1)."""
    h = 1.0 / n
    th, w, x, y = 0.0, k, 0.0, 0.0

    def f(state):
        t, ww, _, _ = state
        return (ww, alpha * math.cos(t), math.cos(t), math.sin(t))

    s = (th, w, x, y)
    for _ in range(n):
        k1 = f(s)
        k2 = f(tuple(a + 0.5 * h * b for a, b in zip(s, k1)))
        k3 = f(tuple(a + 0.5 * h * b for a, b in zip(s, k2)))
        k4 = f(tuple(a + h * b for a, b in zip(s, k3)))
        s = tuple(a + h / 6 * (b + 2 * c + 2 * d + e) for a, b, c, d, e in zip(s, k1, k2, k3, k4))
    return s[1], s[2], s[3]


def tip(alpha):
    """Tip displacement (u/L, v/L) of a cantilever loaded downward with alpha = P L^2/(E I)."""
    lo, hi = -alpha * 1.0000001, 0.0  # theta'(1) <= 0 at lo, > 0 at hi
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        if shoot(alpha, mid)[0] > 0:
            hi = mid
        else:
            lo = mid
        if hi - lo < 1e-14 * max(1.0, alpha):
            break
    _, x, y = shoot(alpha, 0.5 * (lo + hi))
    return x - 1.0, y


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--alpha", type=float)
    ap.add_argument("--E", type=float)
    ap.add_argument("--nu", type=float, default=0.0)
    ap.add_argument("--depth", type=float)
    ap.add_argument("--length", type=float)
    ap.add_argument("--load", type=float)
    ap.add_argument("--thickness", type=float, default=1.0)
    ap.add_argument("--plane-strain", action="store_true")
    a = ap.parse_args()
    if a.alpha is None:
        E = a.E / (1 - a.nu ** 2) if a.plane_strain else a.E
        EI = E * a.thickness * a.depth ** 3 / 12.0
        alpha = a.load * a.length ** 2 / EI
        L = a.length
    else:
        alpha, L = a.alpha, 1.0
    u, v = tip(alpha)
    print(f"alpha {alpha:.6g}  u/L {u:.6f}  v/L {v:.6f}  u {u * L:.6g}  v {v * L:.6g}")


if __name__ == "__main__":
    main()
