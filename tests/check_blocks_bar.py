#!/usr/bin/env python3
"""The two-material bar in tension (tests/scenes/bimaterial_bar.xml, its Exodus twin) against the
closed form of two bars in series, from the run's summary.json (docs/validation.md):

  R = U / (L1/(E1 A) + L2/(E2 A)),   u(interface) = R L1 / (E1 A),   eps_k = R / (E_k A)

--strain-rtol bounds the strain of each block between two probes away from the grips and the
interface (two horizons or more) against R/(E_k A) with R the measured reaction: the material of
each block and the uniform force, free of the boundary layers. --interface-rtol and
--reaction-rtol bound the interface displacement and the reaction against the closed form: both
carry the grips' nonlocal boundary layers (first order in the horizon over the length).

usage: check_blocks_bar.py OUT --U u --A a --E1 e --E2 e --L1 l --L2 l
         --probes a1=x b1=x a2=x b2=x --strain-rtol t --interface-rtol t --reaction-rtol t
"""
import argparse
import json
import sys


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("out")
    for k in ("U", "A", "E1", "E2", "L1", "L2", "strain-rtol", "interface-rtol", "reaction-rtol"):
        ap.add_argument("--" + k, type=float, required=True)
    ap.add_argument("--probes", nargs=4, required=True, help="a1=x b1=x a2=x b2=x: the probes' positions along x")
    a = ap.parse_args()
    s = json.load(open(a.out + "/summary.json"))
    p = s["probes"]
    pos = dict(kv.split("=") for kv in a.probes)
    u = {n: p[n][-1]["displacement"][0] for n in pos}
    R = p["reaction"][-1]["reaction"][0]
    Rc = a.U / (a.L1 / (a.E1 * a.A) + a.L2 / (a.E2 * a.A))
    uic = Rc * a.L1 / (a.E1 * a.A)
    ui = p["interface"][-1]["displacement"][0]
    checks = [("reaction", R, Rc, a.reaction_rtol), ("interface displacement", ui, uic, a.interface_rtol)]
    for k, E in ((1, a.E1), (2, a.E2)):
        lo, hi = f"a{k}", f"b{k}"
        eps = (u[hi] - u[lo]) / (float(pos[hi]) - float(pos[lo]))
        checks.append((f"strain of block {k}", eps, R / (E * a.A), a.strain_rtol))
    ok = True
    for name, got, want, tol in checks:
        rel = got / want - 1
        good = abs(rel) <= tol
        ok &= good
        print(f"{name}: {got:.10g} against {want:.10g}, relative {rel:+.3e} (bound {tol:g}){'' if good else '  FAILED'}")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
