#!/usr/bin/env python3
"""Particle file of a thick-walled cylinder (2D, plane strain) or sphere (3D), for the pressure
vessel scene xml/plastic_cylinder.xml and the thick-sphere study of docs/plasticity.md.

The wall a <= r <= b is cut into shells of width dr = (b - a) / shells; each shell is split along
its mid-radius into cells of arc length close to dr. 2D: 4 round(2 pi r / (4 dr)) equal angles
starting at theta = 0. 3D: an odd number of latitude bands of height close to dr (one band
centred on the equator z = 0), each split into 4 round(...) equal longitudes starting at 0. A
particle sits at its cell's mid-radius and mid-angle with the cell's exact volume: 2D
(r_o^2 - r_i^2) / 2 dtheta, 3D (r_o^3 - r_i^3) / 3 (cos phi_1 - cos phi_2) dtheta.

So particles lie on the planes x = 0 and y = 0 (and, 3D, z = 0), where the symmetric solution
has u_x = 0, u_y = 0 (u_z = 0): constraining those components there removes the rigid motions
without disturbing the answer. The innermost shell is block 2 (where the scenes put the
pressure, as a Radial Force), the rest of the wall block 1; blocks are tags here, the scenes give
every particle the same material.

    vessel_particles.py --dimension 2 --inner 1 --outer 2 --shells 20 OUT
"""
import argparse
import math


def quarter_multiple(length, dr):
    return max(4, 4 * int(round(length / (4 * dr))))


def cylinder(a, b, shells):
    dr = (b - a) / shells
    for i in range(shells):
        ri, ro = a + i * dr, a + (i + 1) * dr
        rm = 0.5 * (ri + ro)
        n = quarter_multiple(2 * math.pi * rm, dr)
        dt = 2 * math.pi / n
        vol = 0.5 * (ro * ro - ri * ri) * dt
        for j in range(n):
            t = j * dt
            yield rm * math.cos(t), rm * math.sin(t), 0.0, vol, 2 if i == 0 else 1


def sphere(a, b, shells):
    dr = (b - a) / shells
    for i in range(shells):
        ri, ro = a + i * dr, a + (i + 1) * dr
        rm = 0.5 * (ri + ro)
        bands = int(round(math.pi * rm / dr))
        if bands % 2 == 0:
            bands += 1
        dphi = math.pi / bands
        shell = (ro ** 3 - ri ** 3) / 3.0
        for k in range(bands):
            p1, p2 = k * dphi, (k + 1) * dphi
            pm = 0.5 * (p1 + p2)
            n = quarter_multiple(2 * math.pi * rm * math.sin(pm), dr)
            dt = 2 * math.pi / n
            vol = shell * (math.cos(p1) - math.cos(p2)) * dt
            z = 0.0 if 2 * k + 1 == bands else rm * math.cos(pm)
            for j in range(n):
                t = j * dt
                yield rm * math.sin(pm) * math.cos(t), rm * math.sin(pm) * math.sin(t), z, vol, 2 if i == 0 else 1


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--dimension", type=int, choices=(2, 3), default=2)
    ap.add_argument("--inner", type=float, default=1.0)
    ap.add_argument("--outer", type=float, default=2.0)
    ap.add_argument("--shells", type=int, default=20)
    ap.add_argument("out")
    o = ap.parse_args()
    if not (0 < o.inner < o.outer) or o.shells < 2:
        raise SystemExit("vessel_particles.py: need 0 < inner < outer and at least 2 shells")
    pts = list((cylinder if o.dimension == 2 else sphere)(o.inner, o.outer, o.shells))
    # Exact zeros on the symmetry planes (cos(pi/2) is 6e-17, not 0).
    clean = lambda v, r: 0.0 if abs(v) < 1e-12 * r else v
    kind = "cylinder (plane strain)" if o.dimension == 2 else "sphere"
    with open(o.out, "w") as f:
        f.write("# Thick-walled %s, a = %g, b = %g, %d shells of width %g "
                "(tools/vessel_particles.py --dimension %d --inner %g --outer %g --shells %d)\n"
                % (kind, o.inner, o.outer, o.shells, (o.outer - o.inner) / o.shells, o.dimension, o.inner, o.outer, o.shells))
        f.write("# block 2: the innermost shell; block 1: the rest of the wall; %d particles\n# x y z volume block\n" % len(pts))
        for x, y, z, v, blk in pts:
            f.write("%.15g %.15g %.15g %.15g %d\n" % (clean(x, o.outer), clean(y, o.outer), clean(z, o.outer), v, blk))


if __name__ == "__main__":
    main()
