#!/usr/bin/env python3
"""Seed 001 plate and brick (sections 5.2, 5.3) against their independent CalculiX references
(validation/reference/, tools/ccx_seed001.py).

    check_seed001.py plate --fem CSV --sp DIR [--none DIR] [--window LO HI]
                     [--max-u-err A] [--max-s-err B] [--max-zigzag Z] [--max-s-zigzag S]
                     [--min-ratio R]
    check_seed001.py brick --fem CSV --sp DIR [--window LO HI] [--max-u-err A] [--max-zigzag Z]

DIR are driver output folders (the plate's profile probe 'axis 1' along y = 0; the brick's 'line'
along x = 40, z = 0). On the window of the line:
  u error   max |u_PD - u_FEM| / max |u_FEM|  (u_x on the plate, u_z on the brick)
  s error   the same for sigma_xx (plate)
  zigzag    tools/seed001_measures.zigzag of the displacement: the largest second difference of
            u_PD - u_FEM over max |u_FEM|, which sees the particle-to-particle oscillation of the
            zero-energy modes and is blind to smooth errors
  s zigzag  the same measure on sigma_xx (plate)
  ratio     zigzag without control / zigzag with stress points (plate, --none)
Every requested bound is checked; the measured values are printed either way.
"""
import argparse
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "tools"))
import seed001_measures as M  # noqa: E402

ap = argparse.ArgumentParser()
ap.add_argument("case", choices=("plate", "brick"))
ap.add_argument("--fem", required=True)
ap.add_argument("--sp", required=True)
ap.add_argument("--none")
ap.add_argument("--window", nargs=2, type=float)
ap.add_argument("--max-u-err", type=float)
ap.add_argument("--max-s-err", type=float)
ap.add_argument("--max-zigzag", type=float)
ap.add_argument("--max-s-zigzag", type=float)
ap.add_argument("--min-ratio", type=float)
o = ap.parse_args()

ref = M.read_csv(o.fem)
probe, s_key, u_key = ("axis_1", "x", "ux") if o.case == "plate" else ("line", "y", "uz")
lo, hi = o.window or ((20.0, 44.0) if o.case == "plate" else (10.0, 70.0))


def measures(d):
    p = M.profile(d, probe, s_key)
    s = p[s_key]
    uf = M.at(ref[s_key], ref[u_key], s)
    out = {"u error": M.max_rel(s, p[u_key], uf, lo, hi), "zigzag": M.zigzag(s, p[u_key], uf, lo, hi)}
    if o.case == "plate":
        sf = M.at(ref[s_key], ref["sxx"], s)
        out["s error"] = M.max_rel(s, p["sxx"], sf, lo, hi)
        out["s zigzag"] = M.zigzag(s, p["sxx"], sf, lo, hi)
    return out


ok = True


def bound(name, value, limit, upper=True):
    global ok
    if limit is None:
        return
    good = value <= limit if upper else value >= limit
    print("  %-28s %.4g %s %.4g  %s" % (name, value, "<=" if upper else ">=", limit, "ok" if good else "FAILED"))
    ok = ok and good


sp = measures(o.sp)
print("%s, window %g..%g, stress points: %s" % (o.case, lo, hi, ", ".join("%s %.4g" % kv for kv in sp.items())))
bound("u error (stress points)", sp["u error"], o.max_u_err)
bound("sigma_xx error (stress points)", sp.get("s error", 0.0), o.max_s_err)
bound("zigzag (stress points)", sp["zigzag"], o.max_zigzag)
bound("sigma_xx zigzag (stress points)", sp.get("s zigzag", 0.0), o.max_s_zigzag)
if o.none:
    nc = measures(o.none)
    ratio = nc["zigzag"] / sp["zigzag"]
    print("no control: %s; zigzag ratio %.3g" % (", ".join("%s %.4g" % kv for kv in nc.items()), ratio))
    bound("zigzag ratio none / sp", ratio, o.min_ratio, upper=False)
elif o.min_ratio is not None:
    sys.exit("--min-ratio needs --none")
sys.exit(0 if ok else 1)
