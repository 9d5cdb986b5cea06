#!/usr/bin/env python3
"""Fuzzes the exit-code and output contract of the perinox driver (issue 15).

    python3 tests/fuzz_contract.py [--perinox PATH] [--seed N] [--cases N] [--jobs N]
                                   [--workdir DIR] [--timeout S] [--keep-going] [--verbose]
                                   [--kind KIND]... [--case K]

Every case is a tiny base scene (a 10 x 4 cantilever, a 1D bar, a 4 x 4 x 4 block; cases
0-2 run them unmutated) with one or two mutations of the scene file or of the command line,
drawn from a generator seeded by --seed and the case number: case K of seed S is always the
same case, and `--case K` replays it alone. The contract checked, for any scene and command:

  * the exit code is 0 (converged), 2 (invalid input) or 3 (a load step failed); never 1, never
    a signal, never longer than --timeout seconds;
  * a mutation that makes the input certainly invalid (a NaN, a duplicate key, truncated
    XML, ...) is refused with exit 2; one that keeps the scene valid (a UTF-8 BOM, an odd but
    legal output path, ...) exits 0; the rest may give 0, 2 or 3;
  * exit 2: stderr holds exactly one non-empty line (the launcher's banners between `-----`
    rules aside), at most 300 characters, naming no C++ internals (std::, Teuchos, Kokkos,
    terminate called, what():), and nothing was written into the case folder: no output
    folder, no .partial, no checkpoint;
  * exit 0 / 3: the output folder holds summary.json, UTF-8 JSON with "converged" true / false
    and no NaN, Infinity or null; no .partial is left behind and nothing is written beside
    the output and checkpoint folders;
  * user files are never touched: the scene, a sentinel file and any user folder of the case
    are unchanged, nothing appears or disappears in the work folder or $HOME, and a command
    smuggled into an output path ($(touch X), backticks, quotes) never runs.

Each case runs in its own folder WORKDIR/case_K (the current directory of the run, TMPDIR
too); a passing case's folder is removed, a failing one's is kept (scene.xml, stdout.txt,
stderr.txt, case.json) for replay. Each failure is printed with its case number, command,
mutations and what broke, then a tally per mutation kind and per failure class, and last,
alone on its line, `N passed, M failed`; the exit code is 1 if any case failed (2 if the
fuzzer cannot start). Without --keep-going the run stops at the first failure. --kind limits
the mutations drawn (for checking one fix); a replay needs the same --seed and --kind and
the same `perinox schema` (keys absent from a base scene are drawn from it), but the kept
scene.xml and the printed command reproduce a failure without the fuzzer.

Where the contract leaves open whether a mutation is invalid, the case accepts 0, 2 or 3.
Judgements made here (see each mut_* function): a non-finite number is invalid in any key,
used or not (kinds *_added: keys the base scene did not have); so are an integer beyond 32
bits, an element nested inside a Parameter, and a second condition prescribing another value
to a prescribed component; a recased key is invalid, a recased enum value may be accepted; a
preset path with ../ may be accepted when it leads to a solver preset.

The driver runs with OMPI_ALLOW_RUN_AS_ROOT(_CONFIRM)=1, OMPI_MCA_rmaps_base_oversubscribe=1
and PERINOX_PLOT_SCRIPT= (empty), as the contract says, plus three settings that only make
Open MPI's singleton start-up faster (ess_singleton_isolated, btl self, pml ob1; cases under
mpiexec -np 2 do without them), and an address-space limit of 4 GiB (a lattice of 2^31
particles must fail inside the run, not swap the machine). The base scenes set Output/Plots
= false for speed; output-path cases turn plots on, the plot command being where a path meets
a shell. A case during which the binary changed (it may be rebuilt meanwhile) is run again.
"""
import argparse
import concurrent.futures
import copy
import json
import math
import os
import random
import re
import shlex
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass, field

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from check_run import own_lines  # noqa: E402  (stderr without mpiexec's banners)

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
DEFAULT_PERINOX = os.path.join(REPO, "build", "drivers", "perinox")
MAX_STDERR_CHARS = 300
FORBIDDEN_IN_MESSAGE = ("std::", "Teuchos", "Kokkos", "terminate called", "what():")
ADDRESS_SPACE_LIMIT = 4 << 30
NAMED_SUBLISTS = ("Regions", "Boundary Conditions", "Loads", "Probes", "Holes")
TEMPLATE_KEYS = {
    "Regions": ("Type", "Lower", "Upper", "Population", "Side", "Thickness", "Point"),
    "Boundary Conditions": ("Region", "Component", "Value", "Gradient"),
    "Loads": ("Region", "Type", "Value"),
    "Probes": ("Region", "Quantity"),
    "Holes": ("Shape", "Center", "Radius", "Half Widths"),
}
# Enumerated keys and their allowed values ("Regions/*/Type" -> values), read from
# `perinox schema --json` at start-up (read_enums): the scene schema is their one home.
ENUMS = {}
REFUSE, ANY, OK = "refuse", "any", "ok"
ABSOLUTE = "(the scene's absolute path)"


# ---------------------------------------------------------------------------------------------
# Scenes: a small tree rendered to Teuchos XML. Strings may carry raw bytes as surrogate escapes
# ("\udcff" is the byte 0xFF), so a mutation can put invalid UTF-8 anywhere.
# ---------------------------------------------------------------------------------------------

@dataclass
class Param:
    name: str
    type: str
    value: str
    inner: list = field(default_factory=list)  # child nodes (a mutation: element inside a Parameter)
    tag: str = "Parameter"
    raw_attrs: str = None  # replaces the rendered attributes (missing or repeated attributes)
    raw_value: bool = False  # the value is written unescaped (entities, a bare '<')


@dataclass
class PList:
    name: str
    children: list
    tag: str = "ParameterList"
    raw_attrs: str = None


@dataclass
class Text:
    text: str  # raw text between elements


def P(name, type_, value):
    return Param(name, type_, value)


def L(name, *children):
    return PList(name, list(children))


def escape(s, quote='"'):
    s = s.replace("&", "&amp;").replace("<", "&lt;").replace(">", "&gt;")
    return s.replace('"', "&quot;") if quote == '"' else s.replace("'", "&apos;")


@dataclass
class Style:
    quote: str = '"'
    newline: str = "\n"
    indent: str = "  "
    header: str = ""


def render(node, style, depth=0):
    pad, nl, q = style.indent * depth, style.newline, style.quote
    if isinstance(node, Text):
        return node.text
    if isinstance(node, Param):
        if node.raw_attrs is not None:
            attrs = node.raw_attrs
        else:
            value = node.value if node.raw_value else escape(node.value, q)
            attrs = f"name={q}{escape(node.name, q)}{q}"
            if node.type is not None:
                attrs += f" type={q}{escape(node.type, q)}{q}"
            if node.value is not None:
                attrs += f" value={q}{value}{q}"
        if node.inner:
            body = "".join(render(c, style, 0).strip(nl) for c in node.inner)
            return f"{pad}<{node.tag} {attrs}>{body}</{node.tag}>{nl}"
        return f"{pad}<{node.tag} {attrs}/>{nl}"
    attrs = node.raw_attrs if node.raw_attrs is not None else f"name={q}{escape(node.name, q)}{q}"
    inner = "".join(render(c, style, depth + 1) for c in node.children)
    return f"{pad}<{node.tag} {attrs}>{nl}{inner}{pad}</{node.tag}>{nl}"


def walk(node, path=()):
    """(path, parent, node) for every element below node, depth first."""
    if not isinstance(node, PList):
        return
    for child in node.children:
        if isinstance(child, (Param, PList)):
            p = path + (child.name,)
            yield p, node, child
            yield from walk(child, p)


def find(root, path):
    for p, parent, node in walk(root):
        if p == tuple(path):
            return parent, node
    return None, None


def ensure_list(root, path):
    node = root
    for name in path:
        nxt = next((c for c in node.children if isinstance(c, PList) and c.name == name), None)
        if nxt is None:
            nxt = L(name)
            node.children.append(nxt)
        node = nxt
    return node


def set_param(root, path, type_, value):
    parent = ensure_list(root, path[:-1])
    for c in parent.children:
        if isinstance(c, Param) and c.name == path[-1]:
            c.type, c.value = type_, value
            return c
    p = P(path[-1], type_, value)
    parent.children.append(p)
    return p


def schema_key(path):
    """'Regions/clamp/Type' -> 'Regions/*/Type': user-named entries of named sublists as '*'."""
    out = list(path)
    for i in range(len(out) - 1):
        if out[i] in NAMED_SUBLISTS and (i == 0 or out[i] == "Holes"):
            out[i + 1] = "*"
    return "/".join(out)


def is_user_name(path):
    """True when the last part of path is a user-chosen name (a region, condition, ...)."""
    return len(path) >= 2 and schema_key(path).endswith("/*")


def split_array(value):
    inner = value.strip()[1:-1]
    return [t.strip() for t in inner.split(",")] if inner.strip() else []


def join_array(items):
    return "{" + ", ".join(items) + "}"


# ---------------------------------------------------------------------------------------------
# Base scenes: tiny, converging in well under a second
# ---------------------------------------------------------------------------------------------

def solver(steps):
    return L("Solver", P("Load Steps", "int", str(steps)), P("Linear Solver Preset", "string", "direct"))


def no_plots():
    return L("Output", P("Plots", "bool", "false"))


def cantilever():
    return L("perinox",
             P("Title", "string", "fuzz cantilever 10 x 4"),
             L("Discretization",
               P("Dimension", "int", "2"),
               P("Lower Corner", "Array(double)", "{0.0, -2.0}"),
               P("Upper Corner", "Array(double)", "{10.0, 2.0}"),
               P("Particles", "Array(int)", "{10, 4}"),
               P("Thickness", "double", "1.0"),
               P("Horizon Factor", "double", "1.015"),
               P("Fictitious Sides", "Array(string)", "{xmin}")),
             L("Material",
               P("Model", "string", "Hencky"),
               P("Plane", "string", "Plane Strain"),
               P("Young's Modulus", "double", "12.0e6"),
               P("Poisson's Ratio", "double", "0.2")),
             L("Regions",
               L("clamp", P("Type", "string", "Fictitious Side"), P("Side", "string", "xmin")),
               L("pin", P("Type", "string", "Box"), P("Population", "string", "Fictitious"),
                 P("Lower", "Array(double)", "{-2.0, -0.6}"), P("Upper", "Array(double)", "{0.0, 0.6}")),
               L("tip", P("Type", "string", "Nearest"), P("Point", "Array(double)", "{10.0, 0.0}"))),
             L("Boundary Conditions",
               L("rollers", P("Region", "string", "clamp"), P("Component", "string", "x")),
               L("pin", P("Region", "string", "pin"), P("Component", "string", "y"))),
             L("Loads",
               L("tip load", P("Region", "string", "tip"), P("Type", "string", "Total Force"),
                 P("Value", "Array(double)", "{0.0, -1.0e4}"))),
             L("Probes", L("tip", P("Region", "string", "tip"))),
             solver(2), no_plots())


def bar():
    return L("perinox",
             P("Title", "string", "fuzz bar 1D"),
             L("Discretization",
               P("Dimension", "int", "1"),
               P("Lower Corner", "Array(double)", "{-0.025}"),
               P("Upper Corner", "Array(double)", "{1.025}"),
               P("Particles", "Array(int)", "{21}"),
               P("Horizon Factor", "double", "1.015")),
             L("Material",
               P("Model", "string", "Small Strain"),
               P("Young's Modulus", "double", "1.0"),
               P("Poisson's Ratio", "double", "0.0")),
             L("Model", P("Zero-Energy Control", "string", "Stress Points")),
             L("Regions",
               L("left end", P("Type", "string", "Nearest"), P("Point", "Array(double)", "{0.0}")),
               L("right end", P("Type", "string", "Nearest"), P("Point", "Array(double)", "{1.0}"))),
             L("Boundary Conditions",
               L("fixed", P("Region", "string", "left end"), P("Component", "string", "x")),
               L("pulled", P("Region", "string", "right end"), P("Component", "string", "x"),
                 P("Value", "double", "0.005"))),
             L("Probes", L("right", P("Region", "string", "right end"), P("Quantity", "string", "Reaction"))),
             L("Reference", P("Type", "string", "Uniform Stretch"), P("Stretch", "double", "1.005")),
             solver(1), no_plots())


def block():
    return L("perinox",
             P("Title", "string", "fuzz block 4 x 4 x 4"),
             L("Discretization",
               P("Dimension", "int", "3"),
               P("Lower Corner", "Array(double)", "{0.0, 0.0, 0.0}"),
               P("Upper Corner", "Array(double)", "{1.0, 1.0, 1.0}"),
               P("Particles", "Array(int)", "{4, 4, 4}"),
               P("Horizon Factor", "double", "1.015")),
             L("Material",
               P("Model", "string", "Small Strain"),
               P("Young's Modulus", "double", "1000.0"),
               P("Poisson's Ratio", "double", "0.3")),
             L("Model", P("Zero-Energy Control", "string", "Stress Points")),
             L("Regions",
               L("bottom", P("Type", "string", "Side Layer"), P("Side", "string", "zmin")),
               L("top", P("Type", "string", "Side Layer"), P("Side", "string", "zmax")),
               L("corner", P("Type", "string", "Nearest"), P("Point", "Array(double)", "{1.0, 1.0, 1.0}"))),
             L("Boundary Conditions",
               L("base", P("Region", "string", "bottom"), P("Component", "string", "all")),
               L("lift", P("Region", "string", "top"), P("Component", "string", "z"), P("Value", "double", "0.01"))),
             L("Probes",
               L("corner", P("Region", "string", "corner")),
               L("top profile", P("Region", "string", "top"), P("Quantity", "string", "Profile"))),
             solver(1), no_plots())


@dataclass(frozen=True)
class Base:
    name: str
    build: object
    weight: float
    required: tuple  # key paths whose removal leaves the scene certainly invalid
    contradictions: tuple  # conditions (region, component, value) clashing with an existing one
    valid_sets: tuple  # --set options after which the scene still converges
    scale_paths: tuple  # loads / prescribed values that may be halved


BASES = (
    Base("cantilever", cantilever, 0.5,
         required=("Material/Young's Modulus", "Discretization/Particles", "Boundary Conditions",
                   "Boundary Conditions/rollers/Region", "Loads/tip load/Region", "Probes/tip/Region",
                   "Regions/clamp", "Regions/tip"),
         contradictions=(("clamp", "x", "0.1"), ("clamp", "all", "0.05"), ("pin", "y", "-0.2")),
         valid_sets=("Solver/Load Steps=1", "Solver/Load Steps=3", "Solver/Tolerance=1e-9", "Output/VTK=false",
                     "Title=set on the command line", "Solver/Max Newton Iterations=40", "Solver/Predictor=false",
                     "Solver/Line Search=Backtrack", "Material/Poisson's Ratio=0.25",
                     "Loads/tip load/Value={0.0, -5.0e3}", "Regions/tip/Point={10.0, 0.5}",
                     "Material/Plane=Plane Stress", "Discretization/Thickness=2.0", "Material/Young's Modulus=2.0e7"),
         scale_paths=("Loads/tip load/Value",)),
    Base("bar", bar, 0.25,
         required=("Material/Young's Modulus", "Discretization/Particles", "Discretization/Dimension",
                   "Boundary Conditions", "Boundary Conditions/fixed/Region", "Boundary Conditions/pulled/Region",
                   "Regions/left end", "Regions/right end", "Probes/right/Region"),
         contradictions=(("right end", "x", "0.0"), ("left end", "x", "0.001"), ("right end", "all", "-0.003")),
         valid_sets=("Solver/Load Steps=2", "Boundary Conditions/pulled/Value=0.004", "Material/Young's Modulus=10.0",
                     "Model/Stress Point Seed=7", "Output/VTK=false", "Discretization/Particles={25}",
                     "Title=bar from --set", "Solver/Tolerance=1e-9"),
         scale_paths=("Boundary Conditions/pulled/Value",)),
    Base("block", block, 0.25,
         required=("Material/Young's Modulus", "Discretization/Particles", "Discretization/Dimension",
                   "Boundary Conditions", "Boundary Conditions/base", "Boundary Conditions/base/Region",
                   "Regions/bottom", "Probes/corner/Region"),
         contradictions=(("top", "all", "0.0"), ("bottom", "z", "0.02"), ("top", "z", "-0.01")),
         valid_sets=("Material/Poisson's Ratio=0.25", "Boundary Conditions/lift/Value=0.02", "Output/VTK=false",
                     "Solver/Load Steps=2", "Model/Stress Point Seed=99", "Title=block from --set"),
         scale_paths=("Boundary Conditions/lift/Value",)),
)


# ---------------------------------------------------------------------------------------------
# A case: a base scene, its mutations and the command line
# ---------------------------------------------------------------------------------------------

class Case:
    def __init__(self, seed, number, base):
        self.seed, self.number, self.base = seed, number, base
        self.root = base.build()
        self.style = Style()
        self.text_ops = []  # bytes -> bytes, applied to the rendered scene in order
        self.kinds, self.notes, self.expects = [], [], []
        self.touched = []  # key paths already mutated: a second mutation leaves them alone
        self.args = []  # options after the scene and --output
        self.output = "out"  # --output, relative to the case folder; None: perinox's default
        self.scene_name = "scene.xml"
        self.scene_arg = None  # how the scene is named on the command line (default: scene_name)
        self.user_files = {}  # path -> bytes, user files created in the case folder
        self.setup_runs = []  # option lists run (each must exit 0) before the case
        self.after_setup = []  # functions(case_dir) run after the setup runs
        self.ranks = 1
        self.marker = f"INJECTED_{seed}_{number}"

    def note(self, kind, expect, text):
        self.kinds.append(kind)
        self.expects.append(expect)
        self.notes.append(f"{kind}: {text}")

    @property
    def expect(self):
        if REFUSE in self.expects:
            return REFUSE
        return ANY if ANY in self.expects else OK

    def free(self, path):
        path = tuple(path)
        return not any(t[:len(path)] == path or path[:len(t)] == t for t in self.touched)

    def touch(self, *paths):
        self.touched.extend(tuple(p) for p in paths)

    def scene_bytes(self):
        data = (self.style.header + render(self.root, self.style)).encode("utf-8", "surrogateescape")
        for op in self.text_ops:
            data = op(data)
        return data

    def argv(self, perinox, case_dir):
        scene = self.scene_arg or self.scene_name
        if scene == ABSOLUTE:
            scene = os.path.join(case_dir, self.scene_name)
        cmd = [perinox, "run", scene]
        if self.output is not None:
            cmd += ["--output", self.output]
        cmd += self.args
        if self.ranks > 1:
            cmd = ["mpiexec", "-np", str(self.ranks)] + cmd
        return cmd

    def paths(self):
        """(output folder, checkpoint folder) as perinox resolves them from the command line."""
        out, ckpt = self.output, None
        it = iter(self.args)
        for a in it:
            if a == "--output":
                out = next(it, out)
            elif a == "--checkpoint-dir":
                ckpt = next(it, ckpt)
        if out is None:
            stem = os.path.basename(self.scene_name if self.scene_arg in (None, ABSOLUTE) else self.scene_arg)
            out = "out/" + (stem.rsplit(".", 1)[0] if "." in stem else stem)
        return out, ckpt if ckpt is not None else out + ".checkpoint"


def params_of(case, types):
    return [(p, n) for p, _, n in walk(case.root)
            if isinstance(n, Param) and n.type in types and case.free(p) and n.raw_attrs is None and not n.inner]


def absent_schema_keys(case, schema, types):
    present = {p for p, _, _ in walk(case.root)}
    return [tuple(k.split("/")) for k, (t, _) in schema.items()
            if t in types and tuple(k.split("/")) not in present and case.free(tuple(k.split("/")))]


def shown(s):
    """A string (possibly with raw bytes) made printable."""
    text = s.encode("utf-8", "surrogateescape").decode("utf-8", "backslashreplace")
    return "".join(c if c.isprintable() else repr(c)[1:-1] for c in text)


def keypath(path):
    return shown("/".join(path))


# ---------------------------------------------------------------------------------------------
# Mutations. Each draws its target with rng, edits the case and records (kind, expectation,
# what it did). REFUSE: the input is certainly invalid; OK: still valid; ANY: either.
# ---------------------------------------------------------------------------------------------

NONFINITE = ("nan", "NaN", "-nan", "inf", "-inf", "Infinity", "-INF", "1e999", "-1e999", "1e400")
BAD_NUMBERS = ("", " ", "abc", "1.0x", "12,5", "1..2", "--1", "1e", "one", "1 2", "+-3", "e5", ".", "0.5.5", "1e+")
EXTREME_NUMBERS = ("1e300", "-1e300", "1.7976931348623157e308", "4.9e-324", "1e-300", "0", "-0", "-1", "-12.5",
                   "1e30", "-1e-30")
NON_INTEGERS = ("3.5", "2.0", "1e1", "0x10", "two", "", "1_000", "3 4", "--2", "+", "NaN", "inf", "7a")
OUT_OF_RANGE = ("2147483648", "-2147483649", "4294967296", "4294967306", "9223372036854775807",
                "9223372036854775808", "-9223372036854775809", "99999999999999999999999")
# Loop limits: a huge value is a legitimately endless run, not a bug to find here.
LOOP_LIMITS = {"Solver/Load Steps", "Solver/Max Newton Iterations", "Solver/Max Total Steps", "Solver/Max Cutbacks",
               "Solver/ADR Max Iterations", "Solver/Arc Length/Max Steps", "Damage/Max Break Rounds",
               "Damage/Max Stall Breaks", "Solver/Verbosity"}


def number_target(rng, case, schema, add_chance=0.25):
    """A double parameter or an entry of an Array(double): (path, index or None, added)."""
    present = params_of(case, ("double", "Array(double)"))
    absent = absent_schema_keys(case, schema, ("double", "Array(double)"))
    if absent and (not present or rng.random() < add_chance):
        path = rng.choice(absent)
        t, default = schema["/".join(path)]
        if t == "Array(double)":
            items = split_array(default) or ["0.0"]
            set_param(case.root, path, t, join_array(items))
            return path, rng.randrange(len(items)), True
        set_param(case.root, path, t, default or "0")
        return path, None, True
    path, node = rng.choice(present)
    if node.type == "Array(double)" and split_array(node.value):
        return path, rng.randrange(len(split_array(node.value))), False
    return path, None, False


def replace_number(case, path, index, text):
    _, node = find(case.root, path)
    if index is None:
        node.value = text
    else:
        items = split_array(node.value)
        items[index] = text
        node.value = join_array(items)
    case.touch(path)
    return f"{keypath(path)}{'' if index is None else f'[{index}]'} = '{shown(node.value)}'"


def mut_number(kind, values, expect):
    def mutate(rng, case, schema):
        path, index, added = number_target(rng, case, schema)
        text = rng.choice([v for v in values if index is None or "," not in v])  # no new array entries
        where = replace_number(case, path, index, text)
        case.note(kind + ("_added" if added else ""), expect, where + (" (key added)" if added else ""))
    return mutate


def mut_extreme_number(rng, case, schema):
    path, index, added = number_target(rng, case, schema)
    _, node = find(case.root, path)
    current = node.value if index is None else split_array(node.value)[index]
    try:
        own = (repr(-float(current)), repr(float(current) * 1e100))
    except ValueError:
        own = ()
    text = rng.choice(EXTREME_NUMBERS + own)
    case.note("extreme_number" + ("_added" if added else ""), ANY,
              replace_number(case, path, index, text) + (" (key added)" if added else ""))


def int_target(rng, case, schema):
    present = params_of(case, ("int", "Array(int)"))
    absent = absent_schema_keys(case, schema, ("int",))
    if absent and (not present or rng.random() < 0.25):
        path = rng.choice(absent)
        set_param(case.root, path, "int", schema["/".join(path)][1] or "0")
        return path, None, True
    path, node = rng.choice(present)
    if node.type == "Array(int)" and split_array(node.value):
        return path, rng.randrange(len(split_array(node.value))), False
    return path, None, False


def mut_int(kind, values_for):
    def mutate(rng, case, schema):
        path, index, added = int_target(rng, case, schema)
        text, expect = values_for(rng, schema_key(path))
        case.note(kind + ("_added" if added else ""), expect,
                  replace_number(case, path, index, text) + (" (key added)" if added else ""))
    return mutate


def noninteger(rng, key):
    return rng.choice(NON_INTEGERS), REFUSE


def out_of_range(rng, key):
    return rng.choice(OUT_OF_RANGE), REFUSE


def extreme_int(rng, key):
    values = ["0", "-1", "-2147483648", "1"]
    if key not in LOOP_LIMITS:
        values += ["2147483647", "100000000"]
    return rng.choice(values), ANY


def mut_array_length(rng, case, schema):
    path, node = rng.choice(params_of(case, ("Array(double)", "Array(int)", "Array(string)")))
    items = split_array(node.value)
    filler = {"Array(double)": "1.0", "Array(int)": "3", "Array(string)": "ymax"}[node.type]
    op = rng.choice(("drop", "add", "empty", "double"))
    new = {"drop": items[:-1], "add": items + [filler] * rng.randint(1, 3), "empty": [],
           "double": items + items}[op]
    if new == items:
        new = items + [filler]
    node.value = join_array(new)
    case.touch(path)
    certain = schema_key(path) == "Discretization/Particles"
    case.note("array_length", REFUSE if certain else ANY, f"{keypath(path)} = {node.value!r} ({op})")


def mut_array_syntax(rng, case, schema):
    path, node = rng.choice(params_of(case, ("Array(double)", "Array(int)", "Array(string)")))
    inner = node.value.strip()[1:-1]
    node.value = rng.choice((inner, "{" + inner, inner + "}", "[" + inner + "]", "{" + inner.replace(",", ";") + "}",
                             "{" + inner.replace(",", " ") + "}" if "," in inner else "{" + inner + " " + inner + "}",
                             "{{" + inner + "}}", "{" + inner + ",," + inner + "}", "(" + inner + ")"))
    case.touch(path)
    case.note("array_syntax", REFUSE, f"{keypath(path)} = {node.value!r}")


def remove_node(root, path):
    parent, node = find(root, path)
    parent.children.remove(node)


def mut_remove_required(rng, case, schema):
    options = [p for p in case.base.required if case.free(tuple(p.split("/"))) and find(case.root, p.split("/"))[1]]
    path = tuple(rng.choice(options).split("/"))
    remove_node(case.root, path)
    case.touch(path)
    case.note("remove_required", REFUSE, f"removed {keypath(path)}")


def mut_remove_key(rng, case, schema):
    required = {tuple(p.split("/")) for p in case.base.required}
    options = [p for p, _, _ in walk(case.root) if case.free(p) and not any(r[:len(p)] == p for r in required)]
    path = rng.choice(options)
    remove_node(case.root, path)
    case.touch(path)
    case.note("remove_key", ANY, f"removed {keypath(path)}")


def mut_duplicate_key(rng, case, schema):
    options = [(p, parent, n) for p, parent, n in walk(case.root) if case.free(p)]
    path, parent, node = rng.choice(options)
    twin = copy.deepcopy(node)
    if isinstance(twin, Param) and rng.random() < 0.5:
        twin.value = {"int": "3", "double": "0.5", "bool": "true"}.get(twin.type, twin.value + " again")
    at = parent.children.index(node) + 1 if rng.random() < 0.5 else len(parent.children)
    parent.children.insert(at, twin)
    case.touch(path)
    what = "sublist" if isinstance(node, PList) else f"value '{shown(twin.value)}'"
    case.note("duplicate_key", REFUSE, f"{keypath(path)} given twice ({what})")


def misspell(rng, word):
    ops = ["lower", "upper", "drop", "swap", "insert", "replace"]
    if "'" in word:
        ops += ["apostrophe"]
    op = rng.choice(ops)
    if op == "lower":
        return word.lower(), "recased"
    if op == "upper":
        return word.upper(), "recased"
    if op == "apostrophe":
        return word.replace("'", rng.choice(("", "\u2019", "`"))), "misspelt"
    i = rng.randrange(len(word))
    if op == "drop" and len(word) > 1:
        return word[:i] + word[i + 1:], "misspelt"
    if op == "swap" and len(word) > 1:
        i = min(i, len(word) - 2)
        swapped = word[:i] + word[i + 1] + word[i] + word[i + 2:]
        if swapped != word:
            return swapped, "misspelt"
    if op == "replace":
        return word[:i] + rng.choice("qzjkx") + word[i + 1:], "misspelt"
    return word[:i] + rng.choice("sxq_") + word[i:], "misspelt"


def valid_names_at(path, schema):
    parent = path[:-1]
    if parent and schema_key(parent).endswith("*"):
        return set(TEMPLATE_KEYS.get(parent[-2], ()))
    prefix = "/".join(parent)
    return {k.split("/")[-1] for k in schema if "/".join(k.split("/")[:-1]) == prefix}


def mut_misspell_key(rng, case, schema):
    options = [(p, n) for p, _, n in walk(case.root) if case.free(p) and not is_user_name(p)]
    path, node = rng.choice(options)
    valid = valid_names_at(path, schema)
    for _ in range(20):
        name, how = misspell(rng, node.name)
        if name not in valid and name != node.name:
            break
    else:
        name, how = node.name + "x", "misspelt"
    node.name = name
    case.touch(path)
    case.note("misspell_key", REFUSE, f"key {keypath(path)} {how} as '{shown(name)}'")


def enum_params(case):
    out = []
    for path, node in params_of(case, ("string", "Array(string)")):
        values = ENUMS.get(schema_key(path))
        if values:
            out.append((path, node, values))
    return out


def mut_enum_value(rng, case, schema):
    path, node, values = rng.choice(enum_params(case))
    items = split_array(node.value) if node.type == "Array(string)" else [node.value]
    i = rng.randrange(len(items))
    if rng.random() < 0.15:
        new, how = items[i] + " ", "trailing space"
    else:
        for _ in range(20):
            new, how = misspell(rng, items[i])
            if new not in values:
                break
        if new.lower() in {v.lower() for v in values}:
            how = "recased"
    items[i] = new
    node.value = join_array(items) if node.type == "Array(string)" else new
    case.touch(path)
    case.note("enum_value", REFUSE if how == "misspelt" else ANY, f"{keypath(path)} = '{shown(node.value)}' ({how})")


def long_text(rng, n):
    alphabet = "abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789 -_.,()+=#%"
    return ("overlong " + "".join(rng.choice(alphabet) for _ in range(n)))[:n]


def rename_region(case, old, new):
    case.touch(("Regions", old))
    for path, _, node in walk(case.root):
        if path == ("Regions", old):
            node.name = new
        elif isinstance(node, Param) and node.name == "Region" and node.value == old:
            node.value = new
            case.touch(path)


def user_names(case, sublist):
    _, node = find(case.root, (sublist,))
    return [c.name for c in node.children if isinstance(c, PList)] if node else []


def rename_target(rng, case, new_name):
    """Renames a region (and its references), a probe, a condition or a load; returns the old key."""
    sub = rng.choice([s for s in ("Regions", "Probes", "Boundary Conditions", "Loads")
                      if user_names(case, s) and case.free((s,))])
    old = rng.choice(user_names(case, sub))
    if sub == "Regions":
        rename_region(case, old, new_name)
    else:
        find(case.root, (sub, old))[1].name = new_name
        case.touch((sub, old))
    return f"{sub}/{old}"


def mut_overlong(rng, case, schema):
    n = rng.randint(33, 200)
    text = long_text(rng, n)
    target = rng.choice(("title", "name", "name", "enum", "preset", "reference"))
    if target == "title" and case.free(("Title",)):
        find(case.root, ("Title",))[1].value = text
        case.touch(("Title",))
        case.note("overlong_string", OK, f"Title of {n} characters")
    elif target == "enum":
        path, node, _ = rng.choice(enum_params(case))
        node.value = join_array([text]) if node.type == "Array(string)" else text
        case.touch(path)
        case.note("overlong_string", REFUSE, f"{keypath(path)} = a value of {n} characters")
    elif target == "preset" and case.free(("Solver", "Linear Solver Preset")):
        set_param(case.root, ("Solver", "Linear Solver Preset"), "string", text)
        case.touch(("Solver", "Linear Solver Preset"))
        case.note("overlong_string", REFUSE, f"Solver/Linear Solver Preset = a name of {n} characters")
    elif target == "reference" and case.free(("Boundary Conditions",)):
        bc = rng.choice(user_names(case, "Boundary Conditions"))
        find(case.root, ("Boundary Conditions", bc, "Region"))[1].value = text
        case.touch(("Boundary Conditions", bc))
        case.note("overlong_string", REFUSE,
                  f"Boundary Conditions/{bc}/Region names an undefined region of {n} characters")
    else:
        old = rename_target(rng, case, text)
        case.note("overlong_string", OK, f"{old} renamed to a name of {n} characters")


NON_UTF8 = ("\udcff\udcfe", "caf\udce9", "\udce9t\udce9", "\udcc3", "\udced\udca0\udc80", "\udcc0\udcaf", "\udc80")


def mut_non_utf8(rng, case, schema):
    raw = rng.choice(NON_UTF8)
    target = rng.choice(("title", "name", "name", "key", "enum"))
    if target == "title" and case.free(("Title",)):
        node = find(case.root, ("Title",))[1]
        node.value = node.value + " " + raw
        case.touch(("Title",))
        case.note("non_utf8", ANY, f"Title ends with the bytes {shown(raw)}")
    elif target == "key":
        path, node = rng.choice([(p, n) for p, _, n in walk(case.root) if case.free(p) and not is_user_name(p)])
        node.name = node.name + raw
        case.touch(path)
        case.note("non_utf8", REFUSE, f"key {keypath(path)} ends with the bytes {shown(raw)}")
    elif target == "enum":
        path, node, _ = rng.choice(enum_params(case))
        node.value = node.value[:-1] + raw + "}" if node.type == "Array(string)" else node.value + raw
        case.touch(path)
        case.note("non_utf8", REFUSE, f"{keypath(path)} = '{shown(node.value)}'")
    else:
        old = rename_target(rng, case, "r\udce9gion " + raw)
        case.note("non_utf8", ANY, f"{old} renamed to '{shown('r' + chr(0xdce9) + 'gion ' + raw)}'")


def mut_nul_byte(rng, case, schema):
    where = rng.choice(("value", "name", "between", "start", "end", "number"))
    if where in ("value", "name"):
        path, node = rng.choice([(p, n) for p, _, n in walk(case.root) if isinstance(n, Param) and case.free(p)])
        if where == "value":
            i = rng.randint(0, len(node.value))
            node.value = node.value[:i] + "\x00" + node.value[i:]
        else:
            node.name = node.name + "\x00"
        case.touch(path)
        case.note("nul_byte", REFUSE, f"NUL in the {where} of {keypath(path)}")
    elif where == "number":
        path, index, _ = number_target(rng, case, schema, add_chance=0)
        _, node = find(case.root, path)
        current = node.value if index is None else split_array(node.value)[index]
        case.note("nul_byte", REFUSE, replace_number(case, path, index, current + "\x00" + "999"))
    elif where == "between":
        plist = rng.choice([n for _, _, n in walk(case.root) if isinstance(n, PList)] + [case.root])
        plist.children.insert(rng.randint(0, len(plist.children)), Text("\x00"))
        case.note("nul_byte", REFUSE, f"NUL between the elements of '{shown(plist.name)}'")
    elif where == "start":
        case.text_ops.append(lambda b: b"\x00" + b)
        case.note("nul_byte", REFUSE, "NUL as the first byte")
    else:
        case.text_ops.append(lambda b: b + b"\x00")
        case.note("nul_byte", REFUSE, "NUL after the root element")


def mut_bom(rng, case, schema):
    header = rng.choice(("", '<?xml version="1.0" encoding="UTF-8"?>\n', "<!-- a comment first -->\n",
                         '<?xml version="1.0"?>\n<!-- comment -->\n'))
    if case.style.header.startswith("<?xml"):
        header = ""
    case.style.header = header + case.style.header
    case.text_ops.append(lambda b: b"\xef\xbb\xbf" + b)
    case.note("bom", OK, "UTF-8 BOM at the start" + (f", then {header.strip()!r}" if header else ""))


def mut_truncated(rng, case, schema):
    mode = rng.choice(("cut", "cut", "cut", "empty", "comment only"))
    if mode == "empty":
        case.text_ops.append(lambda b: b"")
        case.note("truncated", REFUSE, "empty scene file")
    elif mode == "comment only":
        case.text_ops.append(lambda b: b"<!-- nothing but a comment -->\n")
        case.note("truncated", REFUSE, "the scene file holds only a comment")
    else:
        fraction = rng.random()

        def cut(b, fraction=fraction):
            return b[:int(fraction * b.rindex(b">"))]
        case.text_ops.append(cut)
        case.note("truncated", REFUSE, f"cut after {fraction:.0%} of the text")


def random_plist(rng, case):
    return rng.choice([n for _, _, n in walk(case.root) if isinstance(n, PList)] + [case.root])


def mut_text_between(rng, case, schema):
    plist = random_plist(rng, case)
    text = rng.choice(("garbage", "1.0", "Young's Modulus = 5", "&amp; text", "  stray words  ", "<![CDATA[cdata]]>"))
    plist.children.insert(rng.randint(0, len(plist.children)), Text(text))
    case.note("text_between", ANY, f"text {text!r} between the elements of '{shown(plist.name)}'")


def mut_nested_element(rng, case, schema):
    path, node = rng.choice([(p, n) for p, _, n in walk(case.root) if isinstance(n, Param) and case.free(p)])
    if rng.random() < 0.3:
        node.inner = [Text("inner text")]
        case.note("nested_element", ANY, f"text content inside the Parameter {keypath(path)}")
    else:
        node.inner = [rng.choice((P("Extra", "double", "1.0"), L("Sub", P("Extra", "int", "2"))))]
        case.note("nested_element", REFUSE, f"an element nested inside the Parameter {keypath(path)}")
    case.touch(path)


def mut_xml_structure(rng, case, schema):
    path, node = rng.choice([(p, n) for p, _, n in walk(case.root) if isinstance(n, Param) and case.free(p)])
    name, t, v = escape(node.name), escape(node.type or ""), escape(node.value or "")
    op = rng.choice(("no type", "no value", "no name", "unknown type", "unknown element", "two roots",
                     "trailing text", "root tag", "repeated attribute", "bare <", "bare &", "close tag",
                     "unclosed quote", "sublist without name"))
    if op == "no type":
        node.raw_attrs = f'name="{name}" value="{v}"'
    elif op == "no value":
        node.raw_attrs = f'name="{name}" type="{t}"'
    elif op == "no name":
        node.raw_attrs = f'type="{t}" value="{v}"'
    elif op == "unknown type":
        node.type = rng.choice(("float", "Array(float)", "real", "", "Double", "std::string"))
    elif op == "unknown element":
        node.tag = rng.choice(("Parametr", "Param", "parameter", "Value"))
    elif op == "two roots":
        case.text_ops.append(lambda b: b + b'<ParameterList name="second root"/>\n')
    elif op == "trailing text":
        case.text_ops.append(lambda b: b + b"trailing garbage after the root\n")
    elif op == "root tag":
        case.root.tag = rng.choice(("Scene", "ParameterLst", "parameterlist"))
    elif op == "repeated attribute":
        node.raw_attrs = f'name="{name}" name="{name} 2" type="{t}" value="{v}"'
    elif op == "bare <":
        node.value, node.raw_value = (node.value or "") + "<1", True
    elif op == "bare &":
        node.value, node.raw_value = (node.value or "") + " & more", True
    elif op == "close tag":
        plist = random_plist(rng, case)
        plist.children.append(Text("</Parameter>\n"))
    elif op == "unclosed quote":
        node.raw_attrs = f'name="{name}" type="{t}" value="{v}'
    else:
        plist = random_plist(rng, case)
        if plist is not case.root:
            plist.raw_attrs = 'title="no name attribute"'
        else:
            plist.children.append(PList("", [P("Key", "int", "1")], raw_attrs=""))
    case.touch(path)
    case.note("xml_structure", REFUSE, f"{op} ({keypath(path)})")


def mut_wrong_type(rng, case, schema):
    path, node = rng.choice(params_of(case, ("int", "double", "Array(int)", "Array(double)", "bool")))
    if node.type == "int":
        node.type, node.value, expect = "double", node.value + ".5", REFUSE
    elif node.type == "double":
        node.type, node.value, expect = rng.choice((("int", "1", ANY), ("string", node.value, ANY),
                                                    ("bool", "true", REFUSE)))
    elif node.type == "Array(int)":
        node.type, node.value, expect = "Array(double)", join_array(x + ".5" for x in split_array(node.value)), REFUSE
    elif node.type == "Array(double)":
        node.type, expect = rng.choice((("Array(int)", ANY), ("Array(string)", ANY), ("double", REFUSE)))
        if expect == REFUSE:
            node.value = "1.0"
    else:
        node.type, expect = "int", ANY
        node.value = "1"
    case.touch(path)
    case.note("wrong_type", expect, f"{keypath(path)} declared {node.type} = {node.value!r}")


def mut_set_valid(rng, case, schema):
    spec = rng.choice(case.base.valid_sets)
    key = tuple(spec.split("=", 1)[0].split("/"))
    if not case.free(key):
        raise IndexError("that key is taken")
    case.args += ["--set", spec]
    case.touch(key)
    case.note("set_valid", OK, f"--set {spec!r}")


def mut_set_bad_path(rng, case, schema):
    bc = rng.choice(user_names(case, "Boundary Conditions"))
    spec = rng.choice(("Solver/Load Step=2", "Nonexistent/Key=1", "Load Steps=2", "Solver/=1", "/Solver/Load Steps=2",
                       "Solver//Load Steps=2", "Solver/Load Steps", "=3", "Solver/Arc Length=3", "Material=1",
                       f"Boundary Conditions/{bc}/Regoin=x", "solver/load steps=2", "Solver/Load Steps/=2",
                       "Discretization/Holes=1", "Output/VTK/Extra=true", "Solver/Linear Solver Preset/x=direct",
                       "Material/Young's Modulus/x=1"))
    case.args += ["--set", spec]
    case.note("set_bad_path", REFUSE, f"--set {spec!r}")


def mut_set_bad_value(rng, case, schema):
    spec = rng.choice(("Solver/Load Steps=two", "Solver/Load Steps=2.5", "Solver/Load Steps=99999999999",
                       "Solver/Load Steps=-4294967295", "Solver/Tolerance=nan", "Solver/Tolerance=",
                       "Solver/Tolerance=1e-9x",
                       "Material/Young's Modulus=1e999", "Material/Young's Modulus=inf", "Material/Poisson's Ratio=NaN",
                       "Discretization/Particles=10,4", "Discretization/Particles={10,4",
                       "Discretization/Particles={10, 4.5}", "Discretization/Particles={10,99999999999}",
                       "Discretization/Lower Corner={0, nan}", "Discretization/Lower Corner={0,abc}",
                       "Discretization/Lower Corner=0.0", "Discretization/Fictitious Sides=xmin",
                       "Output/VTK=yes", "Output/VTK=", "Solver/Predictor=maybe", "Discretization/Horizon Factor=inf",
                       "Superposed Rotation/Center={nan, 0, 0}", "Model/G=-inf", "Solver/Max Newton Iterations=1e3"))
    key = tuple(spec.split("=", 1)[0].split("/"))
    case.args += ["--set", spec]
    case.touch(key)
    case.note("set_bad_value", REFUSE, f"--set {spec!r}")


def mut_cli(rng, case, schema):
    variants = [
        (["--checkpoint-steps", "0"], REFUSE), (["--checkpoint-steps", "-1"], REFUSE),
        (["--checkpoint-steps", "1.5"], REFUSE), (["--checkpoint-steps", "abc"], REFUSE),
        (["--checkpoint-steps", "1e999"], REFUSE), (["--checkpoint-steps", ""], REFUSE),
        (["--checkpoint-steps", "99999999999"], REFUSE),
        (["--checkpoint-seconds", "-5"], REFUSE), (["--checkpoint-seconds", "nan"], REFUSE),
        (["--checkpoint-seconds", "inf"], REFUSE), (["--checkpoint-seconds", "0"], REFUSE),
        (["--bogus"], REFUSE), (["-o", "x"], REFUSE), (["--output"], REFUSE), (["--set"], REFUSE),
        (["--restart", "nothere.checkpoint"], REFUSE), (["--restart", "notacheckpoint"], REFUSE),
        (["--restart", "notes.txt"], REFUSE), (["--restart", ""], REFUSE), (["extra-positional"], REFUSE),
        (["--quiet"], OK), (["--checkpoint-steps", "1"], OK), (["--checkpoint-seconds", "0.001"], OK),
        (["--checkpoint-steps", "1", "--checkpoint-dir", "my ckpt"], OK),
        (["--set", "Solver/Load Steps=1", "--set", "Solver/Load Steps=2"], OK),
        (["--output", "second out"], OK), (["--quiet", "--quiet"], ANY),
        (["--checkpoint-seconds", "1e-300"], ANY),
    ]
    args, expect = rng.choice(variants)
    if "notacheckpoint" in args:
        case.user_files["notacheckpoint/readme.txt"] = b"a user folder, not a checkpoint\n"
    if args[:1] == ["--set"] and len(args) > 1:
        case.touch(("Solver", "Load Steps"))
    case.args += args
    case.note("cli", expect, shlex.join(args))


def mut_scene_path(rng, case, schema):
    variant = rng.choice(("spaces", "quote", "unicode", "absolute", "dot", "missing", "directory", "dev null",
                          "no extension"))
    expect = OK
    if variant == "spaces":
        case.scene_name = "my scene file.xml"
    elif variant == "quote":
        case.scene_name = "it's \"the\" scene;$(touch " + case.marker + ").xml"
    elif variant == "unicode":
        case.scene_name = "sc\u00e8ne poutre.xml"
    elif variant == "absolute":
        case.scene_arg = ABSOLUTE
    elif variant == "dot":
        case.scene_arg = "./sub/../" + case.scene_name
        case.user_files["sub/.keep"] = b""
    elif variant == "no extension":
        case.scene_name = "scene"
    elif variant == "missing":
        case.scene_arg, expect = "does-not-exist.xml", REFUSE
    elif variant == "directory":
        case.scene_arg, expect = "adir", REFUSE
        case.user_files["adir/file.txt"] = b"user data\n"
    else:
        case.scene_arg, expect = "/dev/null", REFUSE
    case.note("scene_path", expect, f"scene named '{shown(case.scene_arg or case.scene_name)}'")


def add_condition(case, name, region, component, value):
    bcs = ensure_list(case.root, ("Boundary Conditions",))
    bcs.children.append(L(name, P("Region", "string", region), P("Component", "string", component),
                          P("Value", "double", value)))
    case.touch(("Boundary Conditions", name))


def mut_contradicting_bc(rng, case, schema):
    if not case.free(("Boundary Conditions",)):
        raise IndexError("the conditions are taken")
    region, component, value = rng.choice(case.base.contradictions)
    add_condition(case, "contradiction", region, component, value)
    case.touch(("Boundary Conditions",))
    case.note("contradicting_bc", REFUSE, f"region {region!r} component {component} also prescribed to {value}")


def mut_preset_path(rng, case, schema):
    name, expect = rng.choice((("../cantilever", REFUSE), ("../solvers/direct", ANY),
                               ("../../tests/bad_input/malformed", REFUSE), ("../../xml/solvers/direct", ANY),
                               ("../../../../../../../etc/passwd", REFUSE), ("../hard/deep_cantilever", REFUSE),
                               ("direct.xml", ANY), ("", REFUSE), (".", REFUSE), ("..", REFUSE), ("direct/", REFUSE),
                               ("custom", REFUSE), ("../../README", REFUSE), (REPO + "/xml/solvers/direct", ANY),
                               ("./direct", ANY), ("direct/../direct", ANY), ("../../CMakeLists", REFUSE)))
    if case.free(("Solver",)) and rng.random() < 0.7:
        set_param(case.root, ("Solver", "Linear Solver Preset"), "string", name)
        case.touch(("Solver", "Linear Solver Preset"))
        case.note("preset_path", expect, f"Solver/Linear Solver Preset = {name!r}")
    else:
        case.args += ["--set", "Solver/Linear Solver Preset=" + name]
        case.note("preset_path", expect, f"--set 'Solver/Linear Solver Preset={name}'")


def mut_output_path(rng, case, schema):
    m = case.marker
    path = rng.choice(("out dir with spaces", "o'quote", 'o"double"quote', "semi;colon", f"$(touch {m})",
                       f"`touch {m}`", f"a'$(touch {m})'b", f"x'; touch {m}; echo '", f'x"; touch {m}; echo "',
                       "back\\slash", "tab\tname", "\u00fcn\u00efc\u00f8d\u00e9 \u7ed3\u679c", "-leading-dash",
                       "new/nested/dir", "trailing/", "./dot/./path", "o" * 200, "star*and?", "new\nline",
                       f"pipe|touch {m}", f"amp&touch {m}&", f"o'$(touch {m})", f"out/'$(touch {m})'/x",
                       f"..'{m}'", "a" * 100 + "/" + "b" * 100))
    if path.startswith(".."):
        path = "sub/" + path
    case.output = path
    set_param(case.root, ("Output", "Plots"), "bool", "true")  # the plot command is the one with a shell
    case.touch(("Output",))
    case.note("output_path", OK, f"--output '{shown(path)}'")


def mut_output_existing(rng, case, schema):
    variant = rng.choice(("user folder", "cwd", "scene file", "sentinel", "user folder slash"))
    if variant.startswith("user folder"):
        case.user_files["mydata/thesis.txt"] = b"months of work\n"
        case.output = "mydata" + ("/" if variant.endswith("slash") else "")
    elif variant == "cwd":
        case.output = "."
    elif variant == "scene file":
        case.output = case.scene_name
    else:
        case.output = "notes.txt"
    case.note("output_existing", ANY, f"--output {case.output!r} names an existing {variant}")


def mut_restart(rng, case, schema):
    case.setup_runs.append(["--output", "first", "--checkpoint-steps", "1", "--quiet"])
    case.args += ["--restart", "first.checkpoint"]
    variant = rng.choice(("same", "run control", "physics", "corrupt state", "empty state", "no state",
                          "bad marker", "other scene"))
    expect = REFUSE
    if variant == "same":
        expect = OK
    elif variant == "run control":  # the run controls a resumed run may change (README)
        case.args += ["--set", rng.choice(("Solver/Max Total Steps=50", "Output/VTK=false",
                                           "Solver/Linear Solver Preset=mumps"))]
        expect = OK
    elif variant == "physics":
        case.args += ["--set", "Material/Young's Modulus=5.0e3"]
    elif variant == "other scene":
        case.args += ["--set", "Discretization/Horizon Factor=1.2"]
    else:
        def damage(d, variant=variant):
            state = os.path.join(d, "first.checkpoint", "state.json")
            if variant == "corrupt state":
                with open(state, "r+b") as f:
                    f.truncate(os.path.getsize(state) // 2)
            elif variant == "empty state":
                open(state, "wb").close()
            elif variant == "no state":
                os.remove(state)
            else:
                for name in os.listdir(os.path.dirname(state)):
                    if name.startswith("rank_"):
                        with open(os.path.join(os.path.dirname(state), name), "wb") as f:
                            f.write(b"garbage\n")
        case.after_setup.append(damage)
    case.touch(("Material",), ("Solver",), ("Discretization",))
    case.note("restart", expect, f"restart from a checkpoint ({variant})")


def mut_mpi(rng, case, schema):
    case.ranks = 2
    # direct is MUMPS on more than one rank (KLU2 is wrong in parallel in this build)
    preset, expect = rng.choice((("gmres-ilu", ANY), ("mumps", ANY), ("direct", ANY), ("scalable", ANY)))
    set_param(case.root, ("Solver", "Linear Solver Preset"), "string", preset)
    case.touch(("Solver", "Linear Solver Preset"))
    case.note("mpi2", expect, f"mpiexec -np 2, preset {preset}")


def mut_name_chars(rng, case, schema):
    name = rng.choice(("../../escape", "a/b", "x\ny", "quote'name", 'dq"name', "$(touch " + case.marker + ")",
                       "..", ".", " ", "tab\tname", "semi;colon", "*", "-dash", "name with trailing space "))
    old = rename_target(rng, case, name)
    case.note("name_chars", ANY, f"{old} renamed to '{shown(name)}'")


def mut_valid(rng, case, schema):
    op = rng.choice(("unicode title", "comments", "reorder", "load steps", "scale", "entities", "declaration",
                     "description", "crlf", "tabs", "number spaces", "bool spelling", "single quotes", "cdata"))
    expect = OK
    if op == "unicode title" and case.free(("Title",)):
        title = "Poutre en porte-\u00e0-faux \u2014 \u7247\u6301\u3061\u6881 \u2713 \U0001f9ea"
        find(case.root, ("Title",))[1].value = title
        case.touch(("Title",))
    elif op == "comments":
        for _ in range(3):
            plist = random_plist(rng, case)
            plist.children.insert(rng.randint(0, len(plist.children)), Text("<!-- a comment -->"))
    elif op == "reorder":
        plist = random_plist(rng, case)
        rng.shuffle(plist.children)
    elif op == "load steps" and case.free(("Solver", "Load Steps")):
        set_param(case.root, ("Solver", "Load Steps"), "int", str(rng.randint(1, 3)))
        case.touch(("Solver", "Load Steps"))
    elif op == "scale" and all(case.free(tuple(p.split("/"))) for p in case.base.scale_paths):
        for p in case.base.scale_paths:
            node = find(case.root, p.split("/"))[1]
            if node.type == "double":
                node.value = repr(0.5 * float(node.value))
            else:
                node.value = join_array(repr(0.5 * float(x)) for x in split_array(node.value))
            case.touch(tuple(p.split("/")))
    elif op == "entities" and case.free(("Title",)):
        node = find(case.root, ("Title",))[1]
        node.value, node.raw_value = "A &amp; B &lt;C&gt; &quot;D&quot; &#233;&#x4e2d;", True
        case.touch(("Title",))
    elif op == "declaration" and not case.style.header.startswith("<?xml"):
        case.style.header = '<?xml version="1.0" encoding="UTF-8"?>\n' + case.style.header
    elif op == "description":
        set_param(case.root, ("Description",), "string", "first line\nsecond line, with \u00e9")
    elif op == "crlf":
        case.style.newline = "\r\n"
    elif op == "tabs":
        case.style.indent = "\t"
    elif op == "number spaces" and case.free(("Solver", "Load Steps")):
        find(case.root, ("Solver", "Load Steps"))[1].value = " 2 "
        case.touch(("Solver", "Load Steps"))
        expect = ANY
    elif op == "bool spelling":
        set_param(case.root, ("Output", "VTK"), "bool", rng.choice(("TRUE", "True", "1", "false", "0")))
        expect = ANY
    elif op == "single quotes":
        case.style.quote = "'"
        expect = ANY
    elif op == "cdata":
        random_plist(rng, case).children.append(Text("<![CDATA[ <Parameter name=\"x\"/> ]]>"))
        expect = ANY
    else:
        op = "unchanged"
    case.note("valid", expect, op)


MUTATIONS = {  # kind: (weight, function, may be the second mutation of a case)
    "nonfinite": (22, mut_number("nonfinite", NONFINITE, REFUSE), True),
    "bad_number": (14, mut_number("bad_number", BAD_NUMBERS, REFUSE), True),
    "extreme_number": (18, mut_extreme_number, True),
    "int_noninteger": (11, mut_int("int_noninteger", noninteger), True),
    "int_overflow": (11, mut_int("int_overflow", out_of_range), True),
    "extreme_int": (7, mut_int("extreme_int", extreme_int), True),
    "array_length": (11, mut_array_length, True),
    "array_syntax": (9, mut_array_syntax, True),
    "remove_required": (11, mut_remove_required, True),
    "remove_key": (9, mut_remove_key, True),
    "duplicate_key": (11, mut_duplicate_key, True),
    "misspell_key": (13, mut_misspell_key, True),
    "enum_value": (13, mut_enum_value, True),
    "overlong_string": (11, mut_overlong, True),
    "non_utf8": (11, mut_non_utf8, True),
    "nul_byte": (7, mut_nul_byte, False),
    "bom": (6, mut_bom, True),
    "truncated": (9, mut_truncated, False),
    "text_between": (5, mut_text_between, True),
    "nested_element": (5, mut_nested_element, True),
    "xml_structure": (11, mut_xml_structure, False),
    "wrong_type": (5, mut_wrong_type, True),
    "set_valid": (8, mut_set_valid, True),
    "set_bad_path": (9, mut_set_bad_path, True),
    "set_bad_value": (11, mut_set_bad_value, True),
    "cli": (12, mut_cli, True),
    "scene_path": (5, mut_scene_path, False),
    "contradicting_bc": (9, mut_contradicting_bc, True),
    "preset_path": (9, mut_preset_path, True),
    "output_path": (12, mut_output_path, True),
    "output_existing": (5, mut_output_existing, False),
    "name_chars": (5, mut_name_chars, True),
    "valid": (12, mut_valid, True),
    "restart": (3, mut_restart, False),
    "mpi2": (2, mut_mpi, False),
}


def make_case(seed, number, schema, kinds=None):
    """Case `number` of `seed`: cases 0-2 are the base scenes unmutated."""
    rng = random.Random(f"perinox-fuzz:{seed}:{number}")
    if number < len(BASES) and not kinds:
        case = Case(seed, number, BASES[number])
        case.note("baseline", OK, f"base scene {BASES[number].name} unchanged")
        return case
    base = rng.choices(BASES, weights=[b.weight for b in BASES])[0]
    case = Case(seed, number, base)
    case, first = mutate(rng, case, schema, [k for k in MUTATIONS if not kinds or k in kinds])
    if first and MUTATIONS[first][2] and rng.random() < 0.3:
        second = [k for k in MUTATIONS if MUTATIONS[k][2] and k != first and (not kinds or k in kinds)]
        if second:
            case, _ = mutate(rng, case, schema, second)
    return case


def mutate(rng, case, schema, names):
    """Applies one mutation drawn from names (another one when it finds no target in this case)."""
    for _ in range(20):
        kind = rng.choices(names, weights=[MUTATIONS[k][0] for k in names])[0]
        trial = copy.deepcopy(case)
        try:
            MUTATIONS[kind][1](rng, trial, schema)
        except IndexError:  # nothing left to mutate for this kind
            continue
        return trial, kind
    return case, None


# ---------------------------------------------------------------------------------------------
# Running and checking one case
# ---------------------------------------------------------------------------------------------

def snapshot(root, skip=("tmp",)):
    """relative path -> ('d',) or ('f', size, mtime_ns) for everything under root."""
    out = {}
    for d, dirs, files in os.walk(root):
        rel = os.path.relpath(d, root)
        if rel == ".":
            dirs[:] = [x for x in dirs if x not in skip]
        for x in dirs:
            out[os.path.normpath(os.path.join(rel, x))] = ("d",)
        for x in files:
            p = os.path.join(d, x)
            try:
                st = os.lstat(p)
                out[os.path.normpath(os.path.join(rel, x))] = ("f", st.st_size, st.st_mtime_ns)
            except OSError:
                pass
    return out


def listing(d, ignore=None):
    try:
        return {x for x in os.listdir(d) if not (ignore and ignore.match(x))}
    except OSError:
        return set()


def scan_json(value, where, bad):
    if isinstance(value, dict):
        for k, v in value.items():
            scan_json(v, f"{where}.{k}" if where else k, bad)
    elif isinstance(value, list):
        for i, v in enumerate(value):
            scan_json(v, f"{where}[{i}]", bad)
    elif value is None:
        bad.append(f"{where} = null")
    elif isinstance(value, float) and not math.isfinite(value):
        bad.append(f"{where} = {value}")


def check_summary(folder, converged, problems):
    """summary.json in folder: UTF-8 JSON, no NaN / Infinity / null, 'converged' as expected."""
    path = os.path.join(folder, "summary.json")
    tag = "exit 0" if converged else "exit 3"
    if not os.path.isfile(path):
        problems.append((f"{tag}: no summary.json", f"{path} missing"))
        return
    raw = open(path, "rb").read()
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as e:
        problems.append((f"{tag}: summary.json is not UTF-8", str(e)))
        text = raw.decode("utf-8", "replace")
    constants = []

    def constant(name):
        constants.append(name)
        return float("nan")
    try:
        summary = json.loads(text, parse_constant=constant)
    except ValueError as e:
        problems.append((f"{tag}: summary.json is not JSON", str(e)))
        return
    bad = []
    scan_json(summary, "", bad)
    if constants or bad:
        problems.append((f"{tag}: NaN/Infinity/null in summary.json",
                         "; ".join(bad[:4]) + (" ..." if len(bad) > 4 else "")))
    if not isinstance(summary, dict) or summary.get("converged") is not converged:
        got = summary.get("converged") if isinstance(summary, dict) else type(summary).__name__
        problems.append((f"{tag}: summary.json says converged = {got!r}", f"expected {converged}"))


def marker_hits(case, case_dir, workdir):
    hits = []
    for d in {case_dir, workdir, os.getcwd(), os.path.expanduser("~"), tempfile.gettempdir(), REPO, "/"}:
        if os.path.lexists(os.path.join(d, case.marker)):
            hits.append(os.path.join(d, case.marker))
    for d, _, files in os.walk(case_dir):
        hits += [os.path.join(d, f) for f in files if f == case.marker and os.path.join(d, f) not in hits]
    return hits


@dataclass
class Result:
    case: Case
    command: list
    rc: int = None
    elapsed: float = 0.0
    stdout: str = ""
    stderr: str = ""
    problems: list = field(default_factory=list)
    case_dir: str = ""
    ran: bool = False  # False: a setup run failed, or the fuzzer itself
    rebuilt: bool = False  # the binary changed during the case
    attempts: int = 1


class Runner:
    def __init__(self, args):
        self.perinox = os.path.abspath(args.perinox)
        self.workdir = os.path.abspath(args.workdir)
        self.timeout = args.timeout
        self.verbose = args.verbose
        self.jobs = args.jobs
        env = dict(os.environ)
        env.update(OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1",
                   OMPI_MCA_rmaps_base_oversubscribe="1", PERINOX_PLOT_SCRIPT="")
        self.env = env
        self.fast = dict(OMPI_MCA_ess_singleton_isolated="1", OMPI_MCA_btl="self", OMPI_MCA_pml="ob1")
        self.home = os.path.expanduser("~")
        replay = [sys.executable, sys.argv[0], "--seed", str(args.seed), "--workdir", self.workdir]
        if self.perinox != os.path.abspath(DEFAULT_PERINOX):
            replay += ["--perinox", self.perinox]
        for k in args.kind or ():
            replay += ["--kind", k]
        self.replay = shlex.join(replay)
        self.ignore_work = re.compile(r"case_\d+$")

    def environment(self, case, case_dir):
        env = dict(self.env)
        if case.ranks == 1:
            env.update(self.fast)
        else:  # the singleton settings (btl self) would keep two ranks from talking
            for key in self.fast:
                env.pop(key, None)
        env["TMPDIR"] = os.path.join(case_dir, "tmp")
        return env

    def stamp(self):
        try:
            st = os.stat(self.perinox)
            return st.st_mtime_ns, st.st_ctime_ns, st.st_size, st.st_mode
        except OSError:
            return None

    def wait_for_binary(self, settle=3.0, limit=900.0):
        """Returns once the perinox binary exists and has not changed for `settle` seconds (a
        rebuild may replace it under the fuzzer)."""
        start = time.monotonic()
        told = False
        while time.monotonic() < start + limit:
            s = self.stamp()
            if s and os.access(self.perinox, os.X_OK) and time.time() - max(s[0], s[1]) / 1e9 > settle:
                return
            if not told and time.monotonic() > start + 2 * settle:
                print(f"waiting for {self.perinox} to appear and settle (being built?)", file=sys.stderr, flush=True)
                told = True
            time.sleep(0.5)
        raise RuntimeError(f"{self.perinox} did not settle within {limit:.0f} s")

    def execute(self, argv, cwd, env, result=None):
        """(exit code or None on timeout, stdout, stderr, seconds); the process group is killed on
        timeout. Marks result.rebuilt when the binary changed meanwhile (the run proves nothing)."""
        limit = ["prlimit", f"--as={ADDRESS_SPACE_LIMIT}", "--"] if shutil.which("prlimit") else []
        self.wait_for_binary()
        stamp = self.stamp()
        start = time.monotonic()
        try:
            proc = subprocess.Popen(limit + argv, cwd=cwd, env=env, stdin=subprocess.DEVNULL, stdout=subprocess.PIPE,
                                    stderr=subprocess.PIPE, start_new_session=True)
        except OSError as e:  # the binary is being rewritten
            if result is not None:
                result.rebuilt = True
            return 127, "", str(e), 0.0
        try:
            out, err = proc.communicate(timeout=self.timeout)
            rc = proc.returncode
        except subprocess.TimeoutExpired:
            try:
                os.killpg(proc.pid, signal.SIGKILL)
            except ProcessLookupError:
                pass
            out, err = proc.communicate()
            rc = None
        if result is not None and (self.stamp() != stamp or (rc in (126, 127) and b"failed to execute" in err)):
            result.rebuilt = True
        return rc, out.decode("utf-8", "replace"), err.decode("utf-8", "replace"), time.monotonic() - start

    def inside(self, case_dir, rel):
        full = os.path.realpath(os.path.join(case_dir, rel))
        return full == case_dir or full.startswith(case_dir + os.sep)

    def run(self, case, attempts=3):
        """Runs a case; again (up to `attempts` times) when the binary was rebuilt meanwhile."""
        try:
            for attempt in range(1, attempts + 1):
                r = self.run_checked(case)
                r.attempts = attempt
                if not r.rebuilt:
                    break
            return r
        except Exception as e:  # a bug of this script: report it as a failure, keep going
            import traceback
            r = Result(case, [], case_dir=os.path.join(self.workdir, f"case_{case.number:04d}"))
            r.problems.append(("fuzzer error", "".join(traceback.format_exception_only(type(e), e)).strip()))
            r.stderr = traceback.format_exc()
            return r

    def run_checked(self, case):
        case_dir = os.path.realpath(os.path.join(self.workdir, f"case_{case.number:04d}"))
        shutil.rmtree(case_dir, ignore_errors=True)
        os.makedirs(os.path.join(case_dir, "tmp"))
        out_rel, ckpt_rel = case.paths()
        for rel in (out_rel, ckpt_rel, out_rel + ".partial"):
            if not self.inside(case_dir, rel):  # never let a case point perinox at anything else
                raise RuntimeError(f"case {case.number}: {rel!r} leaves the case folder")
        user = dict(case.user_files)
        user[case.scene_name] = case.scene_bytes()
        user["notes.txt"] = f"sentinel of case {case.number}: {random.random()}\n".encode()
        for rel, data in user.items():
            os.makedirs(os.path.dirname(os.path.join(case_dir, rel)), exist_ok=True)
            with open(os.path.join(case_dir, rel), "wb") as f:
                f.write(data)
        env = self.environment(case, case_dir)
        first_stamp = self.stamp()
        result = Result(case, case.argv(self.perinox, case_dir), case_dir=case_dir)
        for setup in case.setup_runs:
            rc, _, err, _ = self.execute([self.perinox, "run", case.scene_name] + setup, case_dir, env, result)
            if rc != 0:
                result.problems.append(("setup run failed", f"{shlex.join(setup)} -> exit {rc}: {err.strip()[-200:]}"))
                return result
        for op in case.after_setup:
            op(case_dir)
        before = snapshot(case_dir)
        user_stat = {rel: before.get(os.path.normpath(rel)) for rel in user}
        outside_before = (listing(self.workdir, self.ignore_work), listing(self.home))
        rc, result.stdout, result.stderr, result.elapsed = self.execute(result.command, case_dir, env, result)
        result.rc, result.ran = rc, True
        after = snapshot(case_dir)
        outside_after = (listing(self.workdir, self.ignore_work), listing(self.home))
        self.check(case, result, case_dir, out_rel, ckpt_rel, before, after, user, user_stat)
        for where, b, a in zip((self.workdir, self.home), outside_before, outside_after):
            if a != b:
                result.problems.append(("created or deleted outside the case folder",
                                        f"in {where}: new {sorted(a - b)}, gone {sorted(b - a)}" +
                                        (" (or by a case running alongside)" if self.jobs > 1 else "")))
        hits = marker_hits(case, case_dir, self.workdir)
        if hits:
            result.problems.append(("a command in the input ran", f"{case.marker} created: {hits}"))
        result.rebuilt = result.rebuilt or self.stamp() != first_stamp
        return result

    def check(self, case, r, case_dir, out_rel, ckpt_rel, before, after, user, user_stat):
        p = r.problems
        rc = r.rc
        lines = own_lines(r.stderr)
        last = shown(lines[-1][:200]) if lines else "(no stderr)"
        if rc is None:
            p.append(("timeout", f"no exit within {self.timeout} s (killed)"))
        elif rc < 0:
            p.append(("killed by a signal", signal.Signals(-rc).name if -rc in signal.valid_signals() else str(rc)))
        elif rc == 1:
            p.append(("exit 1 (internal error)", last))
        elif rc not in (0, 2, 3):
            p.append((f"exit {rc} (not in the contract)", last))
        elif case.expect == REFUSE and rc != 2:
            p.append((f"certainly invalid input not refused (exit {rc})", "; ".join(case.notes)))
        elif case.expect == OK and rc != 0:
            p.append((f"valid input did not run (exit {rc})", last))
        new = sorted(set(after) - set(before))
        out_abs = os.path.normpath(os.path.join(case_dir, out_rel))
        if rc == 2:
            if len(lines) != 1:
                p.append(("exit 2: stderr is not one line",
                          f"{len(lines)} lines: " + " | ".join(shown(x[:80]) for x in lines[:3])))
            for line in lines:
                if len(line) > MAX_STDERR_CHARS:
                    p.append(("exit 2: message over 300 characters", f"{len(line)} characters: {shown(line[:120])}..."))
                bad = [w for w in FORBIDDEN_IN_MESSAGE if w in line]
                if bad:
                    p.append(("exit 2: message shows C++ internals", f"{bad}: {shown(line[:200])}"))
            if new:
                p.append(("exit 2 but files were written", ", ".join(shown(x) for x in new[:5])))
        if rc in (0, 3):
            check_summary(out_abs, rc == 0, p)
            if os.path.lexists(out_abs + ".partial"):
                p.append((".partial left behind", out_rel + ".partial"))
            allowed = [os.path.normpath(x) for x in (out_rel, ckpt_rel, out_rel + ".partial")]
            stray = [x for x in new if "." not in allowed and
                     not any(x == a or x.startswith(a + os.sep) or a.startswith(x + os.sep) for a in allowed)]
            stray = [x for x in stray if os.path.basename(x) != case.marker]
            if stray:
                p.append(("files written beside the output folder", ", ".join(shown(x) for x in stray[:5])))
        for rel, data in user.items():
            full = os.path.join(case_dir, rel)
            try:
                same = open(full, "rb").read() == data and snapshot_entry(full) == user_stat[rel]
            except OSError:
                same = False
            if not same:
                p.append(("user file changed or deleted", rel))


def snapshot_entry(path):
    st = os.lstat(path)
    return ("f", st.st_size, st.st_mtime_ns)


# ---------------------------------------------------------------------------------------------
# Schema, reporting, main
# ---------------------------------------------------------------------------------------------

def read_schema(runner):
    """'Solver/Load Steps' -> ('int', '10') from `perinox schema`, sublists as ('sublist', '')."""
    env = dict(runner.env, **runner.fast)
    runner.wait_for_binary()
    proc = subprocess.run([runner.perinox, "schema"], env=env, capture_output=True, timeout=120)
    if proc.returncode != 0:
        raise RuntimeError(f"perinox schema exited {proc.returncode}: {proc.stderr.decode(errors='replace')[-300:]}")
    schema, stack = {}, []
    for line in proc.stdout.decode("utf-8", "replace").splitlines():
        m = re.match(r"^( *)(\S.*?) ->\s*$", line) or re.match(r"^( *)(\S.*?) : (\S+) = ?(.*)$", line)
        if not m or m.group(2).startswith("#"):
            continue
        indent = len(m.group(1))
        while stack and stack[-1][0] >= indent:
            stack.pop()
        path = [name for _, name in stack] + [m.group(2)]
        if m.re.groups == 2:
            schema["/".join(path)] = ("sublist", "")
            stack.append((indent, m.group(2)))
        else:
            schema["/".join(path)] = (m.group(3), m.group(4))
    return {k: v for k, v in schema.items() if not k.startswith("Solver/Linear Solver/")}


def read_enums(runner):
    """The allowed values of every enumerated key, from `perinox schema --json`."""
    env = dict(runner.env, **runner.fast)
    proc = subprocess.run([runner.perinox, "schema", "--json"], env=env, capture_output=True, timeout=120)
    if proc.returncode != 0:
        raise RuntimeError(f"perinox schema --json exited {proc.returncode}: {proc.stderr.decode(errors='replace')[-300:]}")
    keys = json.loads(proc.stdout.decode("utf-8"))
    return {k: tuple(v["values"]) for k, v in keys.items() if "values" in v}


def command_line(r):
    return f"cd {shlex.quote(r.case_dir)} && " + shown(shlex.join(r.command))


def report_failure(r, seed, runner):
    """Prints one failed case: mutations, command, expectation, what broke, how to replay it."""
    c = r.case
    rc = ("timeout" if r.rc is None else f"exit {r.rc}") if r.ran else "no run"
    print(f"FAIL seed {seed} case {c.number} [{' + '.join(c.kinds)}] base {c.base.name}")
    for n in c.notes:
        print(f"  mutation: {shown(n)}")
    print(f"  command:  {command_line(r)}")
    again = f" (run {r.attempts} times: perinox was rebuilt meanwhile)" if r.attempts > 1 else ""
    print(f"  expected: {dict(refuse='exit 2', ok='exit 0', any='exit 0, 2 or 3')[c.expect]}; "
          f"got {rc} after {r.elapsed:.2f} s{again}")
    for klass, detail in r.problems:
        print(f"  broke:    {klass}: {detail}")
    if runner.verbose:
        for name, text in (("stdout", r.stdout), ("stderr", r.stderr)):
            tail = text.strip().splitlines()[-6:]
            for line in tail:
                print(f"  {name}| {shown(line[:200])}")
    print(f"  kept:     {os.path.join(r.case_dir, c.scene_name)}")
    print(f"  replay:   {runner.replay} --case {c.number}")


def save(r):
    """Keeps the case folder with what the run printed and what the case was."""
    if os.path.isdir(r.case_dir):
        with open(os.path.join(r.case_dir, "stdout.txt"), "w") as f:
            f.write(r.stdout)
        with open(os.path.join(r.case_dir, "stderr.txt"), "w") as f:
            f.write(r.stderr)
        with open(os.path.join(r.case_dir, "case.json"), "w") as f:
            json.dump({"seed": r.case.seed, "case": r.case.number, "base": r.case.base.name, "kinds": r.case.kinds,
                       "mutations": [shown(n) for n in r.case.notes], "expect": r.case.expect,
                       "command": [shown(a) for a in r.command], "exit": r.rc,
                       "problems": [[k, shown(d)] for k, d in r.problems]}, f, indent=1)


def implicated(case, klass):
    """The mutation kinds of case a failure of class klass is blamed on."""
    blame = {"certainly invalid": REFUSE, "valid input": OK}
    for prefix, expect in blame.items():
        if klass.startswith(prefix):
            return tuple(dict.fromkeys(k for k, e in zip(case.kinds, case.expects) if e == expect))
    return tuple(dict.fromkeys(case.kinds))


def print_tallies(results):
    kinds, classes = {}, {}
    for r in results:
        blamed = set()
        for klass in dict.fromkeys(k for k, _ in r.problems):
            who = implicated(r.case, klass)
            blamed.update(who)
            for kind in who:
                classes.setdefault((klass, kind), []).append(r)
        for k in dict.fromkeys(r.case.kinds):
            total, failed = kinds.get(k, (0, 0))
            kinds[k] = (total + 1, failed + (k in blamed))
    print("\nper mutation kind (cases, failed because of it):")
    for k in sorted(kinds, key=lambda k: (-kinds[k][1], k)):
        print(f"  {k:24s} {kinds[k][0]:4d} {kinds[k][1]:4d}")
    if classes:
        print("\nper failure class and mutation kind (cases, of which with that mutation alone; an example):")
        for key in sorted(classes, key=lambda k: (-len(classes[k]), k)):
            alone = sum(len(r.case.kinds) == 1 for r in classes[key])
            ex = min(classes[key], key=lambda r: (len(r.case.kinds), r.case.number))
            print(f"  {len(classes[key]):4d} {alone:4d}  {key[0]}  [{key[1]}]")
            print(f"             case {ex.case.number}: {command_line(ex)}")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--perinox", default=DEFAULT_PERINOX)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--cases", type=int, default=300)
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--workdir", default=os.path.join(tempfile.gettempdir(), "perinox-fuzz"))
    ap.add_argument("--timeout", type=float, default=20.0, help="seconds per case (default 20)")
    ap.add_argument("--keep-going", action="store_true", help="run every case, not only up to the first failure")
    ap.add_argument("--verbose", action="store_true", help="one line per case; output tails of failures")
    ap.add_argument("--kind", action="append", choices=sorted(MUTATIONS), metavar="KIND",
                    help="only this mutation kind (repeatable): " + ", ".join(sorted(MUTATIONS)))
    ap.add_argument("--case", type=int, help="replay this one case (its folder is kept)")
    args = ap.parse_args()
    os.makedirs(args.workdir, exist_ok=True)
    runner = Runner(args)
    try:
        schema = read_schema(runner)
        ENUMS.update(read_enums(runner))
    except (RuntimeError, OSError, subprocess.TimeoutExpired, ValueError, KeyError) as e:
        print(f"fuzz_contract.py: cannot read the scene schema from {runner.perinox}: {e}", file=sys.stderr)
        return 2

    numbers = [args.case] if args.case is not None else range(args.cases)
    if args.case is None:
        for name in os.listdir(runner.workdir):
            if runner.ignore_work.match(name):
                shutil.rmtree(os.path.join(runner.workdir, name), ignore_errors=True)
    kinds = set(args.kind or ())
    start = time.monotonic()
    results, stopped = [], False
    with concurrent.futures.ThreadPoolExecutor(max_workers=max(1, args.jobs)) as pool:
        pending, todo = set(), iter(numbers)
        while True:
            while not stopped and len(pending) < max(1, args.jobs):
                number = next(todo, None)
                if number is None:
                    break
                pending.add(pool.submit(runner.run, make_case(args.seed, number, schema, kinds)))
            if not pending:
                break
            done, pending = concurrent.futures.wait(pending, return_when=concurrent.futures.FIRST_COMPLETED)
            for fut in done:
                r = fut.result()
                results.append(r)
                if args.verbose:
                    status = "FAIL" if r.problems else "ok"
                    rc = ("timeout" if r.rc is None else r.rc) if r.ran else "-"
                    print(f"case {r.case.number:4d} {status:4s} exit {rc} {r.elapsed:5.2f} s  "
                          f"[{' + '.join(r.case.kinds)}] {shown('; '.join(r.case.notes))[:150]}", flush=True)
                if r.problems:
                    report_failure(r, args.seed, runner)
                    sys.stdout.flush()
                    stopped = stopped or not args.keep_going
                if r.problems or args.case is not None:
                    save(r)
                else:
                    shutil.rmtree(r.case_dir, ignore_errors=True)
    results.sort(key=lambda r: r.case.number)
    failed = sum(bool(r.problems) for r in results)
    print_tallies(results)
    print(f"\n{len(results)} cases in {time.monotonic() - start:.1f} s with {args.jobs} jobs, seed {args.seed}, "
          f"work folder {runner.workdir}")
    rerun = sum(r.attempts > 1 for r in results)
    if rerun:
        print(f"{rerun} cases were run again because perinox was rebuilt while they ran")
    if stopped and len(results) < len(numbers):
        print("stopped at the first failure (--keep-going runs every case)")
    print(f"{len(results) - failed} passed, {failed} failed")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
