#!/usr/bin/env python3
"""Turns a Peridigm input deck (YAML) of the elastic-correspondence kind into a perinox scene.

    python3 tools/peridigm_to_scene.py DECK.yaml [--out SCENE.xml] [--preset NAME] [--hencky]

What is translated (docs/exodus.md, "Bringing a Peridigm model"):
  Discretization  Type "Exodus", Input Mesh File     -> Type Exodus, Mesh File (relative to the scene)
  Materials       "Elastic Correspondence": Bulk Modulus K, Shear Modulus G
                                                     -> Young's Modulus 9KG/(3K+G), Poisson's Ratio
                                                        (3K-2G)/(2(3K+G)); Small Strain (--hencky:
                                                        finite deformation); Hourglass Coefficient
                                                        -> Silling stabilisation with G = that value
                                                        (a related control, not Peridigm's)
  Blocks          one Horizon for all blocks -> Discretization/Horizon; with several materials,
                  each block_N of a Peridigm block's Block Names -> a scene Blocks entry (Id N) with
                  its material's E, nu and hourglass G (the first block's material is the
                  top-level Material)
  Boundary Conditions  "Prescribed Displacement" on a Node Set, Coordinate x|y|z, Value an
                  expression of x, y, z, t equal to t (a + b x + c y + d z)
                                                     -> a Node Set region (Peridigm's node-set rule
                                                        is perinox's) and a condition with Value a,
                                                        Gradient (b, c, d); the load factor is t
  Solver          QuasiStatic: Number of Load Steps   -> Solver/Load Steps
  Compute Class Parameters  Nearest_Point_Data of Displacement -> a Nearest region + Displacement probe;
                  Block_Data of Force, Sum over block_N -> a Block region (Id N) + Reaction probe
  Output          -> Output/Format Exodus
Anything else (another material model, damage, several horizons, other condition
types, expressions that are not of that form, Final Time other than 1) is refused with one
sentence on stderr and exit code 2: the scene would not be the same model.
"""
import argparse
import math
import os
import random
import sys
import xml.sax.saxutils as su

try:
    import yaml
except ImportError:  # Debian: python3-yaml
    sys.stderr.write("peridigm_to_scene.py needs PyYAML (Debian package python3-yaml)\n")
    sys.exit(1)


def refuse(deck, msg):
    sys.stderr.write(f"{deck}: {msg}\n")
    sys.exit(2)


def linear_in_t(deck, where, expr):
    """(a, [b, c, d]) with expr(x, y, z, t) = t (a + b x + c y + d z) for all x, y, z, t, checked at
    random points; refuses any other expression."""
    names = {k: getattr(math, k) for k in ("sin", "cos", "tan", "exp", "log", "sqrt", "pi")}
    try:
        code = compile(str(expr), where, "eval")
    except SyntaxError:
        refuse(deck, f"{where}: cannot read the expression '{expr}'")
    for n in code.co_names:
        if n not in names and n not in ("x", "y", "z", "t"):
            refuse(deck, f"{where}: the expression '{expr}' uses '{n}' (only x, y, z, t are known)")

    def f(x, y, z, t):
        return float(eval(code, {"__builtins__": {}}, dict(names, x=x, y=y, z=z, t=t)))

    a = f(0, 0, 0, 1)
    g = [f(1, 0, 0, 1) - a, f(0, 1, 0, 1) - a, f(0, 0, 1, 1) - a]
    rnd = random.Random(18)
    for _ in range(20):
        x, y, z, t = (rnd.uniform(-3, 3) for _ in range(4))
        want = t * (a + g[0] * x + g[1] * y + g[2] * z)
        got = f(x, y, z, t)
        if abs(got - want) > 1e-12 * (1 + abs(want) + abs(a) + sum(abs(v) for v in g) * 3):
            refuse(deck, f"{where}: '{expr}' is not of the form t (a + b x + c y + d z), which perinox's conditions take")
    return a, g


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("deck")
    ap.add_argument("--out", help="scene file to write (default: the deck's name with .xml, beside it)")
    ap.add_argument("--preset", default="mf-ilu", help="linear-solver preset of the scene (default mf-ilu: 3D meshes are large)")
    ap.add_argument("--hencky", action="store_true", help="finite-deformation Hencky material instead of small strain")
    a = ap.parse_args()
    deck = a.deck
    try:
        with open(deck) as f:
            doc = yaml.safe_load(f)
    except (OSError, yaml.YAMLError) as e:
        refuse(deck, f"cannot read the deck: {str(e).splitlines()[0]}")
    p = (doc or {}).get("Peridigm")
    if not isinstance(p, dict):
        refuse(deck, "is not a Peridigm deck (no top-level 'Peridigm' list)")
    out = a.out or os.path.splitext(deck)[0] + ".xml"

    disc = p.get("Discretization", {})
    if disc.get("Type") != "Exodus":
        refuse(deck, f"Discretization Type is '{disc.get('Type')}'; only Exodus meshes are translated")
    mesh = os.path.join(os.path.dirname(os.path.abspath(deck)), disc["Input Mesh File"])
    mesh_rel = os.path.relpath(mesh, os.path.dirname(os.path.abspath(out)))

    mats = p.get("Materials", {})
    if not mats:
        refuse(deck, "has no materials")
    constants = {}  # material name -> (E, nu, hourglass)
    for mname, m in mats.items():
        if m.get("Material Model") != "Elastic Correspondence":
            refuse(deck, f"material '{mname}' is '{m.get('Material Model')}'; only Elastic Correspondence is translated")
        K, G = float(m["Bulk Modulus"]), float(m["Shear Modulus"])
        constants[mname] = (9 * K * G / (3 * K + G), (3 * K - 2 * G) / (2 * (3 * K + G)), float(m.get("Hourglass Coefficient", 0.0)))

    blocks = p.get("Blocks", {})
    horizons = {float(b["Horizon"]) for b in blocks.values()}
    if len(horizons) != 1:
        refuse(deck, "blocks have different horizons (or none); perinox uses one horizon")
    for bname, b in blocks.items():
        if b.get("Material") not in constants:
            refuse(deck, f"block '{bname}' names material '{b.get('Material')}', which the deck does not define")
    horizon = horizons.pop()
    first = next(iter(blocks.values()))["Material"] if blocks else next(iter(constants))
    E, nu, hourglass = constants[first]
    K, G = float(mats[first]["Bulk Modulus"]), float(mats[first]["Shear Modulus"])
    # Several materials: one scene Blocks entry per Peridigm block_N, with its material's constants.
    per_block = []
    if len({b["Material"] for b in blocks.values()}) > 1:
        for bname, b in blocks.items():
            for n in str(b.get("Block Names", "")).split():
                if not n.startswith("block_") or not n[6:].isdigit():
                    refuse(deck, f"block '{bname}' lists '{n}'; only Peridigm's 'block_<id>' names are translated")
                per_block.append((n, int(n[6:]), b["Material"]) + constants[b["Material"]])
    if "Damage Models" in p or any("Damage Model" in b for b in blocks.values()):
        refuse(deck, "has damage models; they are not translated")

    solver = p.get("Solver", {})
    qs = solver.get("QuasiStatic")
    if qs is None:
        refuse(deck, "the solver is not QuasiStatic; only quasi-static decks are translated")
    if float(solver.get("Final Time", 1.0)) != 1.0 or float(solver.get("Initial Time", 0.0)) != 0.0:
        refuse(deck, "Initial/Final Time must be 0 and 1 (perinox's load factor is t)")
    steps = int(qs.get("Number of Load Steps", 1))

    regions, conditions, probes = [], [], []
    axes = {"x": 0, "y": 1, "z": 2}
    for name, bc in p.get("Boundary Conditions", {}).items():
        if bc.get("Type") != "Prescribed Displacement":
            refuse(deck, f"boundary condition '{name}' is of type '{bc.get('Type')}'; only Prescribed Displacement is translated")
        ns = bc["Node Set"]
        comp = bc["Coordinate"]
        if comp not in axes:
            refuse(deck, f"boundary condition '{name}': Coordinate '{comp}' is not x, y or z")
        val, grad = linear_in_t(deck, f"boundary condition '{name}'", bc["Value"])
        if ns not in [r[0] for r in regions]:
            regions.append((ns, "Node Set", ("Name", "string", ns)))
        conditions.append((name, ns, comp, val, grad))
    for name, c in (p.get("Compute Class Parameters") or {}).items():
        cls = c.get("Compute Class")
        if cls == "Nearest_Point_Data" and c.get("Variable") == "Displacement":
            rn = "near " + c["Output Label"]
            regions.append((rn, "Nearest", ("Point", "Array(double)", "{%r, %r, %r}" % (float(c["X"]), float(c["Y"]), float(c["Z"])))))
            probes.append((c["Output Label"], rn, "Displacement"))
        elif cls == "Block_Data" and c.get("Variable") == "Force" and c.get("Calculation Type") == "Sum":
            blk = c["Block"]
            if not blk.startswith("block_") or not blk[6:].isdigit():
                refuse(deck, f"compute class '{name}' names block '{blk}'; only Peridigm's 'block_<id>' names are translated")
            rn = "block " + blk[6:]
            if rn not in [r[0] for r in regions]:
                regions.append((rn, "Block", ("Id", "int", blk[6:])))
            probes.append((c["Output Label"], rn, "Reaction"))
        # other compute classes (initial positions, ...) have no perinox counterpart: skipped

    q = su.quoteattr

    def par(n, t, v):
        return f"<Parameter name={q(n)} type={q(t)} value={q(str(v))}/>"

    L = ["<!-- Written by tools/peridigm_to_scene.py from %s. Peridigm's Elastic Correspondence with" % su.escape(os.path.basename(deck)),
         "     K = %g, G = %g: E = 9KG/(3K+G), nu = (3K-2G)/(2(3K+G)); hourglass coefficient -> Silling G." % (K, G),
         "     Node sets select the elements touching their nodes, as in Peridigm (docs/exodus.md). -->",
         '<ParameterList name="perinox">',
         "  " + par("Title", "string", "From Peridigm deck " + os.path.basename(deck)),
         '  <ParameterList name="Discretization">',
         "    " + par("Dimension", "int", 3), "    " + par("Type", "string", "Exodus"),
         "    " + par("Mesh File", "string", mesh_rel), "    " + par("Horizon", "double", repr(horizon)),
         "  </ParameterList>",
         '  <ParameterList name="Material">',
         "    " + par("Model", "string", "Hencky" if a.hencky else "Small Strain"),
         "    " + par("Young's Modulus", "double", repr(E)), "    " + par("Poisson's Ratio", "double", repr(nu)),
         "  </ParameterList>"]
    if hourglass > 0 or any(hg > 0 for *_, hg in per_block):
        L += ['  <ParameterList name="Model">', "    " + par("Stabilization", "string", "Silling"),
              "    " + par("G", "double", repr(hourglass)), "  </ParameterList>"]
    if per_block:
        L.append('  <ParameterList name="Blocks">')
        for n, bid, mname, bE, bnu, bhg in per_block:
            L += [f"    <ParameterList name={q(n)}>{par('Id', 'int', bid)}<!-- {su.escape(mname)} -->",
                  '      <ParameterList name="Material">' + par("Young's Modulus", "double", repr(bE)) +
                  par("Poisson's Ratio", "double", repr(bnu)) + "</ParameterList>",
                  '      <ParameterList name="Stabilization">' + par("G", "double", repr(bhg)) + "</ParameterList>",
                  "    </ParameterList>"]
        L.append("  </ParameterList>")
    L.append('  <ParameterList name="Regions">')
    for rn, typ, (k, t, v) in regions:
        L.append(f"    <ParameterList name={q(rn)}>{par('Type', 'string', typ)}{par(k, t, v)}</ParameterList>")
    L += ["  </ParameterList>", '  <ParameterList name="Boundary Conditions">']
    for name, ns, comp, val, grad in conditions:
        g = "" if not any(grad) else par("Gradient", "Array(double)", "{%r, %r, %r}" % tuple(grad))
        L.append(f"    <ParameterList name={q(name)}>{par('Region', 'string', ns)}{par('Component', 'string', comp)}"
                 f"{par('Value', 'double', repr(val))}{g}</ParameterList>")
    L += ["  </ParameterList>", '  <ParameterList name="Probes">']
    for label, rn, quantity in probes:
        L.append(f"    <ParameterList name={q(label)}>{par('Region', 'string', rn)}{par('Quantity', 'string', quantity)}</ParameterList>")
    L += ["  </ParameterList>", '  <ParameterList name="Solver">', "    " + par("Load Steps", "int", steps),
          "    " + par("Linear Solver Preset", "string", a.preset), "  </ParameterList>",
          '  <ParameterList name="Output">', "    " + par("Format", "string", "Exodus"), "  </ParameterList>",
          "</ParameterList>"]
    os.makedirs(os.path.dirname(os.path.abspath(out)), exist_ok=True)
    with open(out, "w") as f:
        f.write("\n".join(L) + "\n")
    print(f"wrote {out}: {len(regions)} regions, {len(conditions)} conditions, {len(probes)} probes, "
          f"E = {E:.6g}, nu = {nu:.6g}, horizon {horizon}" + (f", {len(per_block)} blocks with their own materials" if per_block else ""))


if __name__ == "__main__":
    main()
