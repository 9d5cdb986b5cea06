#!/usr/bin/env python3
"""Tests the library's reader of Peridigm decks (packages/io PeridigmDeck.cpp) through
`perinox convert DECK --out SCENE`, on decks written to a temporary folder, one subprocess each
(tests/peridigm/peridigm_converter_tests.cmake).

    test_peridigm_converter.py --perinox PATH [--tensile-deck YAML] [--seed N] [--cases N]
                               [--jobs N] [--case K] [--verbose]

The contract: a deck is converted (exit 0, a well-formed scene) or refused with exit code 2 and
exactly one non-empty stderr line, no crash, within 10 s, and no scene file (nor a temporary
.partial) left behind. The decks are YAML (Teuchos' own YAML reader reads them); the mesh they
name exists (empty: convert checks that it is a file, and does not read it). The parts:

  (a) the Value grammar: accepted expressions give the coefficients worked out by hand (Value a,
      Gradient (b, c, d) of t (a + b x + c y + d z)); expressions outside the grammar (Python
      code, powers, functions, hexadecimal, a 100 000-character one, ...) and ones not of that
      form are refused naming the key, and the command smuggled into one never runs (its marker
      file must not appear);
  (b) malformed decks of every kind (not a mapping, sections of the wrong type, missing keys,
      unknown models, empty, binary, not UTF-8, YAML syntax, missing mesh or node-set file,
      duplicate keys, deep nesting, ...): refused;
  (c) impossible decks (non-finite, zero or negative moduli, horizon, density; Poisson's ratio
      outside (-1, 0.5); load steps 0, 2.5, 1e11, ...): refused naming the key and the range;
  (d) elastic constants: any two of E, nu, K, G convert, checked against the closed forms
      K = E/(3(1-2nu)), G = E/(2(1+nu)), E = 9KG/(3K+G), nu = (3K-2G)/(2(3K+G)) computed here;
      one alone, or three that disagree, are refused;
  (e) a mutation loop over Peridigm's tensile deck (--tensile-deck; without it, a deck of the same
      shape written here): --cases decks (default 250), each with one random mutation (a key
      deleted, renamed or added, a value's type changed, a number made text, garbage in an
      expression, the file truncated, bytes inserted or flipped, lines dropped, doubled, swapped
      or re-indented), drawn from a generator seeded by --seed and the case number, so that case K
      is always the same deck (--case K replays it alone). Each must meet the contract.

Prints each failure, then, alone on its line, `N passed, M failed`; exit code 1 if any failed.
"""
import argparse
import concurrent.futures
import copy
import math
import os
import random
import re
import subprocess
import sys
import tempfile
import time
import xml.etree.ElementTree as ET

import yaml

HERE = os.path.dirname(os.path.abspath(__file__))
TIMEOUT = 10.0
FORM = "is not of the form t (a + b x + c y + d z)"

# A deck of the tensile test's shape (Peridigm's examples/tensile_test), written here.
BASE = {"Peridigm": {
    "Verbose": False,
    "Discretization": {"Type": "Exodus", "Input Mesh File": "mesh.g"},
    "Materials": {"Steel": {"Material Model": "Elastic Correspondence", "Density": 8.0,
                            "Bulk Modulus": 1.5e12, "Shear Modulus": 6.923e11, "Hourglass Coefficient": 0.02}},
    "Blocks": {"All": {"Block Names": "block_1 block_2 block_3", "Material": "Steel", "Horizon": 0.16}},
    "Boundary Conditions": {
        "Pull": {"Type": "Prescribed Displacement", "Node Set": "nodelist_1", "Coordinate": "y", "Value": "0.005*y*t"},
        "Hold": {"Type": "Prescribed Displacement", "Node Set": "nodelist_3", "Coordinate": "x", "Value": "0.0"}},
    "Solver": {"Verbose": False, "Initial Time": 0.0, "Final Time": 1.0,
               "QuasiStatic": {"Number of Load Steps": 4, "Absolute Tolerance": 1.0}},
    "Compute Class Parameters": {
        "Top": {"Compute Class": "Nearest_Point_Data", "X": 0.0317, "Y": 1.238, "Z": 0.0,
                "Variable": "Displacement", "Output Label": "Top_Displacement"},
        "Force": {"Compute Class": "Block_Data", "Calculation Type": "Sum", "Block": "block_3",
                  "Variable": "Force", "Output Label": "Top_Force"}},
    "Output": {"Output File Type": "ExodusII", "Output Filename": "out", "Output Frequency": 1}}}


def dump(d):
    return yaml.safe_dump(d, sort_keys=False, allow_unicode=True).encode("utf-8")


def deck_with(*changes):
    """A copy of BASE with changes: (path tuple below 'Peridigm', value), or (path, DELETE)."""
    d = copy.deepcopy(BASE)
    for path, value in changes:
        node = d["Peridigm"]
        for k in path[:-1]:
            node = node[k]
        if value is DELETE:
            del node[path[-1]]
        else:
            node[path[-1]] = value
    return d


DELETE = object()
MAT = ("Materials", "Steel")
PULL = ("Boundary Conditions", "Pull")


# ---------------------------------------------------------------------------------------------
# Running the tool and checking the contract.

class Run:
    def __init__(self, tool, folder, deck_bytes, deck_name="deck.yaml", mesh="mesh.g", out="scene.xml",
                 extra=(), deck_path=None, out_arg=True):
        self.folder = folder
        os.makedirs(folder, exist_ok=True)
        if mesh:
            open(os.path.join(folder, mesh), "wb").close()  # the tool only checks that the mesh exists
        self.deck = deck_path or os.path.join(folder, deck_name)
        if deck_bytes is not None:
            with open(self.deck, "wb") as f:
                f.write(deck_bytes)
        self.out = os.path.join(folder, out)
        self.before = set(os.listdir(folder))
        cmd = [tool, "convert", self.deck] + (["--out", self.out] if out_arg else []) + list(extra)
        t0 = time.monotonic()
        try:
            r = subprocess.run(cmd, capture_output=True, timeout=TIMEOUT, cwd=folder)
            self.rc, self.stdout, self.stderr = r.returncode, r.stdout.decode("utf-8", "replace"), r.stderr.decode("utf-8", "replace")
        except subprocess.TimeoutExpired:
            self.rc, self.stdout, self.stderr = None, "", ""
        self.seconds = time.monotonic() - t0
        self.lines = [l for l in self.stderr.splitlines() if l.strip()]
        self.after = set(os.listdir(folder))

    def summary(self):
        return f"exit {self.rc} after {self.seconds:.2f} s, stderr {self.stderr[-600:]!r}"

    def contract(self):
        """Problems with the exit-code and output contract, whatever the exit code."""
        if self.rc is None:
            return [f"no exit within {TIMEOUT} s"]
        bad = []
        if "Traceback" in self.stderr or "Traceback" in self.stdout:
            bad.append("a Python traceback")
        if self.rc not in (0, 2):
            bad.append(f"exit code {self.rc}, not 0 or 2")
        if any(n.endswith(".partial") for n in self.after):
            bad.append("a .partial file left behind")
        if self.rc == 2:
            if len(self.lines) != 1:
                bad.append(f"{len(self.lines)} non-empty stderr lines, not 1")
            elif len(self.lines[0]) > 600:
                bad.append(f"a stderr line of {len(self.lines[0])} characters")
            if self.after - self.before:
                bad.append(f"files written on refusal: {sorted(self.after - self.before)}")
        if self.rc == 0:
            try:
                ET.parse(self.out)
            except (OSError, ET.ParseError) as e:
                bad.append(f"exit 0 without a well-formed scene ({e})")
        return bad

    def refused(self, *fragments):
        bad = self.contract()
        if self.rc is not None and self.rc != 2:
            bad.append("not refused")
        elif self.lines:
            for frag in fragments:
                frag = frag.replace("Peridigm/", "")  # keys are named from the deck's sections
                if frag not in self.lines[0]:
                    bad.append(f"the message does not hold {frag!r}")
        return bad

    def converted(self):
        bad = self.contract()
        if self.rc != 0:
            bad.append("not converted")
        return bad


class Scene:
    """The numbers of a written scene."""

    def __init__(self, path):
        with open(path, encoding="utf-8") as f:
            self.text = f.read()
        self.root = ET.fromstring(self.text)

    def sub(self, node, name):
        for c in node:
            if c.tag == "ParameterList" and c.get("name") == name:
                return c
        raise KeyError(name)

    def value(self, node, name, default=None):
        for c in node:
            if c.tag == "Parameter" and c.get("name") == name:
                return c.get("value")
        if default is not None:
            return default
        raise KeyError(name)

    def material(self):
        m = self.sub(self.root, "Material")
        return float(self.value(m, "Young's Modulus")), float(self.value(m, "Poisson's Ratio"))

    def condition(self, name):
        c = self.sub(self.sub(self.root, "Boundary Conditions"), name)
        g = self.value(c, "Gradient", "{0, 0, 0}")
        return [float(self.value(c, "Value"))] + [float(v) for v in g.strip("{}").split(",")]

    def moduli(self, material):
        m = re.search(r"material '%s': K = (\S+), G = (\S+)," % re.escape(material), ET.fromstring(self.text).find(
            "Parameter[@name='Description']").get("value"))
        return float(m.group(1)), float(m.group(2))


def close(a, b, rel=1e-12, abs_=1e-15):
    return abs(a - b) <= rel * max(abs(a), abs(b)) + abs_


# ---------------------------------------------------------------------------------------------
# (a) the Value grammar

ACCEPTED = [  # expression -> (a, b, c, d), by hand
    ("0.002*t", (0.002, 0, 0, 0)),
    ("t*(1+2*x-3*y+0.5*z)", (1, 2, -3, 0.5)),
    ("(t)*(2)", (2, 0, 0, 0)),
    ("y*0.005*t", (0, 0, 0.005, 0)),
    ("0.0", (0, 0, 0, 0)),
    (0, (0, 0, 0, 0)),
    ("-t", (-1, 0, 0, 0)),
    ("- -t", (1, 0, 0, 0)),
    ("+t", (1, 0, 0, 0)),
    ("0.001*y*t/1.0e-8", (0, 0, 1e5, 0)),  # Peridigm's ElasticCorrespondenceFullyPrescribedTension
    ("t*x/4", (0, 0.25, 0, 0)),
    ("t * ( 1.5E-3 - .5e-3 )", (0.001, 0, 0, 0)),
    ("t*(x+y+z)/3", (0, 1 / 3, 1 / 3, 1 / 3)),
    ("2*t - t + 3.*z*t", (1, 0, 0, 3)),
    ("t*( x - 1e+1)", (-10, 1, 0, 0)),
    ("(" * 40 + "t" + ")" * 40, (1, 0, 0, 0)),
    ("t" + "+0" * 499, (1, 0, 0, 0)),  # 999 characters
]

REFUSED = [  # expression, fragments the message must hold besides the key
    ("__import__('os').system('touch MARKER')", []),
    ("().__class__", []),
    ("().__class__.__bases__[0].__subclasses__()", []),
    ("t.real", []),
    ("[t][0]", []),
    ("t if t else t", []),
    ("lambda: t", []),
    ("(t, t)", []),
    ("9**9**9*t", ["**"]),
    ("t**2", ["**"]),
    ("sin(t)", ["sin"]),
    ("pi*t", ["pi"]),
    ("exp(t)", ["exp"]),
    ("t*x*y", [FORM]),
    ("t*x*x", [FORM]),
    ("x", [FORM]),
    ("1+t", [FORM]),
    ("5", [FORM]),
    ("1/0*t", ["divides by zero"]),
    ("t/x", ["divides by zero"]),
    ("t/(y-y)", ["divides by zero"]),
    ("0x10*t", []),
    ("1_000*t", []),
    ("1e999*t", []),
    ("1e308*1e308*t", []),
    ("2 t", []),
    ("T", []),
    ("t;t", []),
    ("t # a comment", []),
    ("t +", []),
    ("(t", []),
    ("t)", []),
    ("", []),
    ("   ", []),
    ("t\x00", []),
    ("t*\t(x - 1e+1)", ["YAML", "backslash"]),  # PyYAML writes "\t": Teuchos' reader would read it as t
    ("\uff54", []),  # a full-width t
    ("(" * 60 + "t" + ")" * 60, ["50"]),
    ("-" * 60 + "t", ["50"]),
    ("t" + "*1" * 49999 + "*", ["100000 characters"]),
    (True, []),
    (["t"], []),
    ({"t": 1}, []),
    (float("nan"), []),
]


def grammar_cases(tool, work):
    marker = os.path.join(work, "pwned_marker")
    cases = []
    for i, (expr, want) in enumerate(ACCEPTED):
        def case(i=i, expr=expr, want=want):
            r = Run(tool, os.path.join(work, f"a_ok_{i}"), dump(deck_with((PULL + ("Value",), expr))))
            bad = r.converted()
            if not bad:
                got = Scene(r.out).condition("Pull")
                if not all(close(g, w, 1e-12, 1e-15) for g, w in zip(got, want)):
                    bad.append(f"coefficients {got}, not {list(want)}")
            return bad, r
        cases.append((f"(a) accepts {str(expr)[:50]!r}", case))
    for i, (expr, frags) in enumerate(REFUSED):
        if isinstance(expr, str):
            expr = expr.replace("MARKER", marker)

        def case(i=i, expr=expr, frags=frags):
            r = Run(tool, os.path.join(work, f"a_bad_{i}"), dump(deck_with((PULL + ("Value",), expr))))
            # a YAML list is beyond Teuchos' reader: refused as malformed YAML, at its line
            # a YAML list, brackets or a comment sign in a plain text, and non-ASCII characters are
            # beyond Teuchos' reader: refused as malformed YAML, at their line
            beyond = isinstance(expr, list) or (isinstance(expr, str) and (
                not expr.isascii() or any(ord(ch) < 32 for ch in expr)))
            # (a control character is written as a backslash escape, which perinox refuses)
            want = ["YAML", "line"] + [f for f in frags if f == "backslash"] if beyond else \
                ["Peridigm/Boundary Conditions/Pull/Value"] + frags
            if not beyond and isinstance(expr, str) and 0 < len(expr) <= 40 and expr.isprintable() and expr.strip():
                want.append(expr)  # the expression itself, when short and printable
            bad = r.refused(*want)
            if bad and isinstance(expr, str) and ("[" in expr or " #" in expr) and not r.refused("YAML", "line"):
                bad = []  # written unquoted, brackets or a comment sign are malformed YAML for Teuchos' reader
            return bad, r
        cases.append((f"(a) refuses {str(expr)[:50]!r}", case))
    return cases, marker


# ---------------------------------------------------------------------------------------------
# (b) malformed decks: (name, deck bytes, fragments of the message)

def malformed():
    bomb = "a: &a [x, x, x]\n" + "".join(f"{c}: &{c} [*{p}, *{p}, *{p}, *{p}]\n"
                                       for p, c in zip("abcdefgh", "bcdefghi")) + "Peridigm: *i\n"
    teuchos = (b'<ParameterList>\n  <ParameterList name="Discretization">\n'
               b'    <Parameter name="Type" type="string" value="Exodus"/>\n  </ParameterList>\n</ParameterList>\n')
    text = dump(BASE).decode()
    return [
        ("empty file", b"", ["empty"]),
        ("comments only", b"# nothing here\n\n", ["no YAML content"]),
        ("top level a list", b"- Peridigm\n- 1\n", ["top level"]),
        ("top level a string", b"just some text\n", ["top level"]),
        ("top level a number", b"42\n", ["top level"]),
        ("no Peridigm key", dump({"Albany": BASE["Peridigm"]}), ["'Peridigm:'"]),
        ("Peridigm a list", dump({"Peridigm": [1, 2]}), ["YAML"]),
        ("Peridigm a string", dump({"Peridigm": "deck"}), ["YAML"]),
        ("Peridigm empty", b"Peridigm:\n", ["'Peridigm'"]),
        ("Discretization missing", dump(deck_with((("Discretization",), DELETE))), ["Peridigm/Discretization", "missing"]),
        ("Discretization a list", dump(deck_with((("Discretization",), ["Exodus"]))), ["YAML", "line"]),
        ("Discretization a string", dump(deck_with((("Discretization",), "Exodus"))), ["Peridigm/Discretization"]),
        ("Discretization Type other", dump(deck_with((("Discretization", "Type"), "PdQuickGrid"))), ["Type", "PdQuickGrid"]),
        ("Input Mesh File missing", dump(deck_with((("Discretization", "Input Mesh File"), DELETE))), ["Input Mesh File", "missing"]),
        ("Input Mesh File a list", dump(deck_with((("Discretization", "Input Mesh File"), ["a.g"]))), ["YAML", "line"]),
        ("Input Mesh File absent", dump(deck_with((("Discretization", "Input Mesh File"), "no_such_mesh.g"))), ["Input Mesh File", "no_such_mesh.g", "does not exist"]),
        ("Materials missing", dump(deck_with((("Materials",), DELETE))), ["Peridigm/Materials", "missing"]),
        ("Materials a string", dump(deck_with((("Materials",), "Steel"))), ["Peridigm/Materials"]),
        ("Materials empty mapping", dump(deck_with((("Materials",), {}))), ["Peridigm/Materials", "empty"]),
        ("a material a list", dump(deck_with((MAT, [1, 2]))), ["YAML", "line"]),
        ("Material Model missing", dump(deck_with((MAT + ("Material Model",), DELETE))), ["Material Model", "missing"]),
        ("Material Model unknown", dump(deck_with((MAT + ("Material Model",), "Elastic Plastic Hardening"))), ["Material Model", "Elastic Plastic Hardening"]),
        ("Material Model a number", dump(deck_with((MAT + ("Material Model",), 3))), ["Material Model"]),
        ("Bulk Modulus text", dump(deck_with((MAT + ("Bulk Modulus",), "abc"))), ["Bulk Modulus", "abc"]),
        ("Bulk Modulus with units", dump(deck_with((MAT + ("Bulk Modulus",), "1.5e12 dyn/cm^2"))), ["Bulk Modulus"]),
        ("Bulk Modulus a list", dump(deck_with((MAT + ("Bulk Modulus",), [1.5e12]))), ["YAML", "line"]),
        ("Bulk Modulus a boolean", dump(deck_with((MAT + ("Bulk Modulus",), True))), ["Bulk Modulus", "boolean"]),
        ("Bulk Modulus empty", dump(deck_with((MAT + ("Bulk Modulus",), None))), ["Bulk Modulus"]),
        ("Blocks missing", dump(deck_with((("Blocks",), DELETE))), ["Peridigm/Blocks", "missing"]),
        ("Blocks a list", dump(deck_with((("Blocks",), ["All"]))), ["YAML", "line"]),
        ("a block a string", dump(deck_with((("Blocks", "All"), "block_1"))), ["Peridigm/Blocks/All"]),
        ("block material undefined", dump(deck_with((("Blocks", "All", "Material"), "Brass"))), ["Material", "Brass"]),
        ("block Horizon missing", dump(deck_with((("Blocks", "All", "Horizon"), DELETE))), ["Horizon", "missing"]),
        ("block Horizon text", dump(deck_with((("Blocks", "All", "Horizon"), "wide"))), ["Horizon", "wide"]),
        ("two horizons", dump(deck_with((("Blocks", "Other"), {"Block Names": "block_4", "Material": "Steel", "Horizon": 0.2}))), ["horizons"]),
        ("damage model", dump(deck_with((("Damage Models",), {"D": {"Damage Model": "Critical Stretch"}}))), ["Damage Models"]),
        ("Boundary Conditions a list", dump(deck_with((("Boundary Conditions",), [1]))), ["YAML", "line"]),
        ("a condition a string", dump(deck_with((PULL, "0.005*y*t"))), ["Peridigm/Boundary Conditions/Pull"]),
        ("condition Type unknown", dump(deck_with((PULL + ("Type",), "Initial Velocity"))), ["Type", "Initial Velocity"]),
        ("body force varying in y", dump(deck_with((PULL + ("Type",), "Body Force"))), ["Value", "uniform"]),
        ("condition Node Set missing", dump(deck_with((PULL + ("Node Set",), DELETE))), ["Node Set", "missing"]),
        ("condition Coordinate w", dump(deck_with((PULL + ("Coordinate",), "w"))), ["Coordinate", "x, y or z"]),
        ("condition Value missing", dump(deck_with((PULL + ("Value",), DELETE))), ["Value", "missing"]),
        ("conflicting conditions", dump(deck_with((("Boundary Conditions", "Pull 2"), dict(BASE["Peridigm"]["Boundary Conditions"]["Pull"], Value="0.004*y*t")))), ["nodelist_1"]),
        ("node set file missing", dump(deck_with((("Boundary Conditions", "Node Set One"), "missing_nodes.txt"), (PULL + ("Node Set",), "Node Set One"))), ["Node Set One", "missing_nodes.txt", "does not exist"]),
        ("node set number zero", dump(deck_with((("Boundary Conditions", "Node Set One"), "0 2 3"), (PULL + ("Node Set",), "Node Set One"))), ["Node Set One", "'0'", "from 1"]),
        ("node set number a word", dump(deck_with((("Boundary Conditions", "Node Set One"), "1 two 3"), (PULL + ("Node Set",), "Node Set One"))), ["Node Set One", "'two'"]),
        ("node set named twice", dump(deck_with((("Boundary Conditions", "Node Set One"), "1 2"), (("Boundary Conditions", "node set one"), "3"), (PULL + ("Node Set",), "Node Set One"))), ["node set one", "another node set"]),
        ("Omit Bonds Between Blocks All", dump(deck_with((("Discretization", "Omit Bonds Between Blocks"), "All"))), ["Omit Bonds Between Blocks", "keeps the bonds"]),
        ("Solver missing", dump(deck_with((("Solver",), DELETE))), ["Peridigm/Solver", "missing"]),
        ("Solver a string", dump(deck_with((("Solver",), "QuasiStatic"))), ["Peridigm/Solver"]),
        ("Solver Verlet, tiny dt", dump(deck_with((("Solver", "QuasiStatic"), DELETE), (("Solver", "Verlet"), {"Fixed dt": 1e-9}))), ["Fixed dt", "whole number"]),
        ("Solver Verlet", dump(deck_with((("Solver", "QuasiStatic"), DELETE), (("Solver", "Verlet"), {"Fixed dt": 0.25}))), ["Verlet", "perinox run"]),
        ("QuasiStatic a list", dump(deck_with((("Solver", "QuasiStatic"), [4]))), ["YAML", "line"]),
        ("Final Time 0", dump(deck_with((("Solver", "Final Time"), 0.0))), ["Final Time", "above 0"]),
        ("Compute Class Parameters a list", dump(deck_with((("Compute Class Parameters",), ["Top"]))), ["YAML", "line"]),
        ("compute class X missing", dump(deck_with((("Compute Class Parameters", "Top", "X"), DELETE))), ["Top/X", "missing"]),
        ("compute class X text", dump(deck_with((("Compute Class Parameters", "Top", "X"), "left"))), ["Top/X", "left"]),
        ("compute class Block name", dump(deck_with((("Compute Class Parameters", "Force", "Block"), "grips"))), ["Block", "grips"]),
        ("two compute classes one label", dump(deck_with((("Compute Class Parameters", "Force", "Output Label"), "Top_Displacement"))), ["Output Label", "Top_Displacement"]),
        ("duplicate key", text.replace("      Density: 8.0\n", "      Density: 8.0\n      Bulk Modulus: 2.0e12\n").encode(), ["YAML", "line"]),
        ("duplicate section", (text + "  Materials:\n    Other: {}\n").encode(), ["YAML", "line"]),
        ("YAML syntax: unclosed bracket", b"Peridigm: [1, 2\n", ["YAML"]),
        ("YAML syntax: bad indentation", text.replace("      Density", "     Density", 1).encode(), ["YAML", "line"]),
        ("YAML syntax: a tab", text.replace("      Density", "\tDensity", 1).encode(), ["YAML"]),
        ("two YAML documents", (text + "---\nPeridigm: {}\n").encode(), ["YAML"]),
        ("truncated deck", dump(BASE)[:len(dump(BASE)) // 2], []),
        ("invalid UTF-8", b"Peridigm:\n  Discretization:\n    Type: \"Exod\xffus\"\n", ["UTF-8"]),
        ("Latin-1 text", "Peridigm:\n  Materials:\n    Stahl \u00e4:\n".encode("latin-1"), ["UTF-8"]),
        ("UTF-16 deck", text.encode("utf-16"), ["UTF-8"]),
        ("binary garbage", bytes(random.Random(5).randrange(256) for _ in range(4096)), []),
        ("NUL bytes", b"Peridigm:\x00\x00\n", []),
        ("control character", b"Peridigm:\n  Discretization: \x07\n", ["0x07"]),
        ("deep nesting", b"Peridigm: " + b"[" * 5000 + b"]" * 5000 + b"\n", []),
        ("deep nesting of mappings", b"Peridigm: " + b"{a: " * 3000 + b"1" + b"}" * 3000 + b"\n", []),
        ("alias bomb", bomb.encode(), ["'Peridigm:'"]),
        ("unhashable key", b"Peridigm:\n  ? [a, b]\n  : 1\n", ["YAML"]),
        ("python tag", b"Peridigm: !!python/object/apply:os.system ['touch MARKER']\n", ["YAML"]),
        ("timestamp tag", b"Peridigm: !!timestamp not-a-date\n", ["YAML"]),
        ("Teuchos XML deck", teuchos, ["XML"]),
        ("over 1 MiB", b"# " + b"x" * (1 << 20) + b"\n" + dump(BASE), ["1 MiB"]),
    ]


def malformed_cases(tool, work, marker):
    cases = []
    for i, (name, data, frags) in enumerate(malformed()):
        data = data.replace(b"MARKER", marker.encode())

        def case(i=i, data=data, frags=frags):
            r = Run(tool, os.path.join(work, f"b_{i}"), data)
            return r.refused(*frags), r
        cases.append((f"(b) refuses {name}", case))

    def folder_as_deck():
        folder = os.path.join(work, "b_folder")
        os.makedirs(os.path.join(folder, "deck.yaml"), exist_ok=True)
        r = Run(tool, folder, None)
        return r.refused("directory"), r

    def missing_deck():
        r = Run(tool, os.path.join(work, "b_missing"), None)
        return r.refused("No such file"), r

    def deck_named_like_its_scene():  # --out the deck itself: never overwritten
        folder = os.path.join(work, "b_same")
        data = dump(BASE)
        r = Run(tool, folder, data, deck_name="deck.yaml", out="deck.yaml")
        bad = r.refused("the deck itself")
        with open(r.deck, "rb") as f:
            if f.read() != data:
                bad.append("the deck was changed")
        return bad, r

    def users_file():  # an existing file that is not a scene convert wrote: never replaced
        folder = os.path.join(work, "b_users_file")
        os.makedirs(folder, exist_ok=True)
        with open(os.path.join(folder, "scene.xml"), "w") as f:
            f.write("my notes\n")
        r = Run(tool, folder, dump(BASE))
        bad = r.refused("exists and is not a scene perinox convert wrote")
        with open(r.out) as f:
            if f.read() != "my notes\n":
                bad.append("the user's file was changed")
        return bad, r

    def own_scene_again():  # the scene convert wrote before is replaced by a new conversion
        folder = os.path.join(work, "b_again")
        first = Run(tool, folder, dump(BASE))
        bad = first.converted()
        r = Run(tool, folder, dump(deck_with((("Blocks", "All", "Horizon"), 0.2))))
        bad += r.converted()
        if not bad and float(Scene(r.out).value(Scene(r.out).sub(Scene(r.out).root, "Discretization"), "Horizon")) != 0.2:
            bad.append("the scene was not replaced")
        return bad, r

    def bad_option():
        r = Run(tool, os.path.join(work, "b_option"), dump(BASE), extra=["--no-such-option"])
        return r.refused("--no-such-option"), r

    cases += [("(b) refuses a folder as the deck", folder_as_deck), ("(b) refuses a missing deck", missing_deck),
              ("(b) refuses to overwrite the deck", deck_named_like_its_scene), ("(b) refuses an unknown option", bad_option),
              ("(b) refuses to replace a user's file", users_file), ("(b) replaces the scene it wrote", own_scene_again)]
    return cases


# ---------------------------------------------------------------------------------------------
# (c) impossible decks: (name, changes, fragments)

def impossible():
    nan, inf = float("nan"), float("inf")
    BULK, SHEAR = MAT + ("Bulk Modulus",), MAT + ("Shear Modulus",)
    E_NU = [(BULK, DELETE), (SHEAR, DELETE), (MAT + ("Young's Modulus",), 200e9), (MAT + ("Poisson's Ratio",), 0.3)]
    H = ("Blocks", "All", "Horizon")
    D = MAT + ("Density",)
    STEPS = ("Solver", "QuasiStatic", "Number of Load Steps")
    above0 = "above 0"
    nu_range = "between -1 and 0.5"
    steps_range = "whole number from 1 to 1000000"
    cases = [
        ("negative bulk modulus (nu = 0.8)", [(BULK, -0.6e12), (SHEAR, 1e12)], ["Bulk Modulus", above0]),
        ("zero shear modulus", [(SHEAR, 0.0)], ["Shear Modulus", above0]),
        ("NaN bulk modulus", [(BULK, nan)], ["Bulk Modulus", above0]),
        ("infinite shear modulus", [(SHEAR, inf)], ["Shear Modulus", above0]),
        ("negative Young's modulus", E_NU + [(MAT + ("Young's Modulus",), -200e9)], ["Young's Modulus", above0]),
        ("Poisson's ratio 0.5", E_NU + [(MAT + ("Poisson's Ratio",), 0.5)], ["Poisson's Ratio", nu_range]),
        ("Poisson's ratio 0.8", E_NU + [(MAT + ("Poisson's Ratio",), 0.8)], ["Poisson's Ratio", nu_range]),
        ("Poisson's ratio -1", E_NU + [(MAT + ("Poisson's Ratio",), -1.0)], ["Poisson's Ratio", nu_range]),
        ("Poisson's ratio NaN", E_NU + [(MAT + ("Poisson's Ratio",), nan)], ["Poisson's Ratio", nu_range]),
        ("E = 4 G (nu = 1)", [(BULK, DELETE), (MAT + ("Young's Modulus",), 4 * 6.923e11)], ["Young's Modulus", "Shear Modulus", "-1 < nu < 0.5"]),
        ("E = 10 K (nu < -1)", [(SHEAR, DELETE), (MAT + ("Young's Modulus",), 10 * 1.5e12)], ["Young's Modulus", "Bulk Modulus", "-1 < nu < 0.5"]),
        ("zero horizon", [(H, 0.0)], ["Horizon", above0]),
        ("negative horizon", [(H, -0.16)], ["Horizon", above0]),
        ("NaN horizon", [(H, nan)], ["Horizon", above0]),
        ("infinite horizon", [(H, inf)], ["Horizon", above0]),
        ("zero density", [(D, 0.0)], ["Density", above0]),
        ("negative density", [(D, -8.0)], ["Density", above0]),
        ("NaN density", [(D, nan)], ["Density", above0]),
        ("infinite density", [(D, -inf)], ["YAML", "line 9"]),  # Teuchos reads no -.inf
        ("negative hourglass coefficient", [(MAT + ("Hourglass Coefficient",), -0.1)], ["Hourglass Coefficient", "0 or above"]),
        ("0 load steps", [(STEPS, 0)], ["Number of Load Steps", steps_range]),
        ("2.5 load steps", [(STEPS, 2.5)], ["Number of Load Steps", steps_range]),
        ("1e11 load steps", [(STEPS, 1e11)], ["Number of Load Steps", steps_range]),
        ("1000001 load steps", [(STEPS, 1000001)], ["Number of Load Steps", steps_range]),
        ("-4 load steps", [(STEPS, -4)], ["Number of Load Steps", steps_range]),
        ("NaN load steps", [(STEPS, nan)], ["Number of Load Steps", steps_range]),
        ("10^40 load steps", [(STEPS, 10 ** 40)], ["Number of Load Steps", steps_range]),
        ("load steps as words", [(STEPS, "four")], ["Number of Load Steps", steps_range]),
        ("NaN final time", [(("Solver", "Final Time"), nan)], ["Final Time"]),
        ("infinite probe point", [(("Compute Class Parameters", "Top", "Y"), inf)], ["Top/Y", "finite"]),
    ]
    return cases


def impossible_cases(tool, work):
    cases = []
    for i, (name, changes, frags) in enumerate(impossible()):
        def case(i=i, changes=changes, frags=frags):
            r = Run(tool, os.path.join(work, f"c_{i}"), dump(deck_with(*changes)))
            return r.refused(*frags), r
        cases.append((f"(c) refuses {name}", case))
    for steps in (1, 1000000, "7"):
        def case(steps=steps):
            r = Run(tool, os.path.join(work, f"c_steps_{steps}"), dump(deck_with((("Solver", "QuasiStatic", "Number of Load Steps"), steps))))
            bad = r.converted()
            if not bad and int(Scene(r.out).value(Scene(r.out).sub(Scene(r.out).root, "Solver"), "Load Steps")) != int(steps):
                bad.append("Load Steps differ from the deck's")
            return bad, r
        cases.append((f"(c) accepts {steps!r} load steps", case))
    return cases


# ---------------------------------------------------------------------------------------------
# (d) elastic constants, against the closed forms

def elastic_cases(tool, work):
    E, nu = 200e9, 0.3
    K, G = E / (3 * (1 - 2 * nu)), E / (2 * (1 + nu))  # closed forms
    names = {"E": "Young's Modulus", "nu": "Poisson's Ratio", "K": "Bulk Modulus", "G": "Shear Modulus"}
    values = {"E": E, "nu": nu, "K": K, "G": G}

    def deck_of(given):
        m = {"Material Model": "Elastic Correspondence", "Density": 7800.0}
        m.update({names[k]: v for k, v in given.items()})
        return dump(deck_with((("Materials",), {"Steel": m})))

    cases = []

    def exact_e_nu():
        r = Run(tool, os.path.join(work, "d_e_nu"), deck_of({"E": E, "nu": nu}))
        bad = r.converted()
        if not bad:
            s = Scene(r.out)
            if s.material() != (E, nu):
                bad.append(f"E, nu = {s.material()}, not the deck's {E}, {nu}")
            k, g = s.moduli("Steel")
            if not (close(k, K) and close(g, G)):
                bad.append(f"K, G = {k}, {g}; closed form {K}, {G}")
        return bad, r
    cases.append(("(d) E and nu: K = E/(3(1-2nu)), G = E/(2(1+nu))", exact_e_nu))

    def e_nu_zero():
        r = Run(tool, os.path.join(work, "d_nu0"), deck_of({"E": 3.0, "nu": 0.0}))
        bad = r.converted()
        if not bad:
            k, g = Scene(r.out).moduli("Steel")
            if not (close(k, 1.0) and close(g, 1.5)):
                bad.append(f"K, G = {k}, {g}, not 1 and 1.5")
        return bad, r
    cases.append(("(d) E = 3, nu = 0: K = 1, G = 1.5", e_nu_zero))

    def k_g_tensile():
        k, g = 1.5e12, 6.923e11
        r = Run(tool, os.path.join(work, "d_kg"), deck_of({"K": k, "G": g}))
        bad = r.converted()
        if not bad:
            e, n = Scene(r.out).material()
            if not (close(e, 9 * k * g / (3 * k + g)) and close(n, (3 * k - 2 * g) / (2 * (3 * k + g)))):
                bad.append(f"E, nu = {e}, {n}")
        return bad, r
    cases.append(("(d) K and G: E = 9KG/(3K+G), nu = (3K-2G)/(2(3K+G))", k_g_tensile))

    combos = [("K", "G"), ("E", "K"), ("E", "G"), ("K", "nu"), ("G", "nu"), ("E", "nu", "K"), ("E", "nu", "K", "G"),
              ("nu", "K", "G")]
    for combo in combos:
        def case(combo=combo):
            r = Run(tool, os.path.join(work, "d_" + "_".join(combo)), deck_of({k: values[k] for k in combo}))
            bad = r.converted()
            if not bad:
                e, n = Scene(r.out).material()
                if not (close(e, E, 1e-9) and abs(n - nu) <= 1e-9):
                    bad.append(f"E, nu = {e}, {n}, not {E}, {nu}")
            return bad, r
        cases.append((f"(d) {' and '.join(combo)} give E = 200e9, nu = 0.3", case))

    refusals = [
        ("E alone", {"E": E}, ["Young's Modulus", "give two"]),
        ("none", {}, ["none", "give two"]),
        ("K 1% off E and nu", {"E": E, "nu": nu, "K": K * 1.01}, ["Bulk Modulus"]),
        ("G 1e-4 off in four", {"E": E, "nu": nu, "K": K, "G": G * (1 + 1e-4)}, ["Shear Modulus"]),
        ("nu 0.01 off K and G", {"K": K, "G": G, "nu": 0.31}, ["Poisson's Ratio"]),
    ]
    for name, given, frags in refusals:
        def case(name=name, given=given, frags=frags):
            r = Run(tool, os.path.join(work, "d_bad_" + re.sub(r"\W+", "_", name)), deck_of(given))
            return r.refused(*frags), r
        cases.append((f"(d) refuses {name}", case))

    def within_tolerance():
        r = Run(tool, os.path.join(work, "d_tol"), deck_of({"E": E, "nu": nu, "K": K * (1 + 1e-8)}))
        return r.converted(), r
    cases.append(("(d) accepts K 1e-8 off E and nu", within_tolerance))
    return cases


# ---------------------------------------------------------------------------------------------
# (e) the mutation loop

def garbage_values(rng, marker):
    return [None, True, False, 0, -1, 2.5, 1e300, -1e-300, float("nan"), float("inf"), -float("inf"), 10 ** 40,
            "", " ", "garbage", "0x10", "1e12", " 4 ", "1_000", "t**2", "9**9**9*t", "sin(t)", "t*x*y",
            f"__import__('os').system('touch {marker}')", "\x00\x01\x7f", "\u00e9\u2202\u2028", "x" * rng.choice((100, 5000)),
            "(" * 80 + "t" + ")" * 80, "--", "<!-- -->", "&amp; <tag>", [], [1, "two"], {}, {"a": {"b": [1]}},
            "block_99999999999", "nodelist_1\nnodelist_2"]


def paths(node, prefix=()):
    """Every (container, key) below node."""
    out = []
    if isinstance(node, dict):
        items = list(node.items())
    elif isinstance(node, list):
        items = list(enumerate(node))
    else:
        return out
    for k, v in items:
        out.append((node, k, prefix + (k,)))
        out += paths(v, prefix + (k,))
    return out


def mutate(base_text, rng, marker):
    """(deck bytes, description) with one random mutation of base_text."""
    kind = rng.choice(["delete key", "retype", "number to text", "text to number", "insert key", "rename key",
                       "wrap in list", "expression garbage", "truncate", "insert bytes", "flip byte",
                       "delete line", "double line", "swap lines", "reindent line"])
    data = base_text.encode("utf-8")
    if kind in ("truncate", "insert bytes", "flip byte"):
        i = rng.randrange(len(data) + 1)
        if kind == "truncate":
            return data[:i], f"{kind} at byte {i}"
        if kind == "insert bytes":
            junk = bytes(rng.randrange(256) for _ in range(rng.randint(1, 8)))
            return data[:i] + junk + data[i:], f"{kind} {junk!r} at {i}"
        i = min(i, len(data) - 1)
        b = rng.randrange(256)
        return data[:i] + bytes([b]) + data[i + 1:], f"{kind} {i} to {b}"
    if kind in ("delete line", "double line", "swap lines", "reindent line"):
        lines = base_text.split("\n")
        i, j = rng.randrange(len(lines)), rng.randrange(len(lines))
        if kind == "delete line":
            del lines[i]
        elif kind == "double line":
            lines.insert(i, lines[i])
        elif kind == "swap lines":
            lines[i], lines[j] = lines[j], lines[i]
        else:
            lines[i] = rng.choice(["  ", " ", "\t", ""]) + (lines[i][rng.randint(0, 3):] if rng.random() < 0.5 else lines[i])
        return "\n".join(lines).encode("utf-8"), f"{kind} {i} {j}"
    d = yaml.safe_load(base_text)
    all_paths = paths(d)
    container, key, path = rng.choice(all_paths)
    where = "/".join(map(str, path))
    if kind == "delete key":
        del container[key]
    elif kind == "retype":
        container[key] = rng.choice(garbage_values(rng, marker))
    elif kind == "number to text":
        nums = [p for p in all_paths if isinstance(p[0][p[1]], (int, float)) and not isinstance(p[0][p[1]], bool)]
        if nums:
            container, key, path = rng.choice(nums)
            where = "/".join(map(str, path))
            v = container[key]
            container[key] = rng.choice([str(v), f"{v} units", f"'{v}'", "NaN", "one"])
    elif kind == "text to number":
        texts = [p for p in all_paths if isinstance(p[0][p[1]], str)]
        if texts:
            container, key, path = rng.choice(texts)
            where = "/".join(map(str, path))
            container[key] = rng.choice([0, 1, -3, 0.5, 1e20, float("nan")])
    elif kind == "insert key":
        maps = [p for p in all_paths if isinstance(p[0][p[1]], dict)]
        container, key, path = rng.choice(maps)
        where = "/".join(map(str, path))
        container[key][rng.choice(["Horizon", "Damage Model", "Node Set One", "Value", "junk", "Young's Modulus",
                                   "Poisson's Ratio", "Verlet", "Type"])] = rng.choice(garbage_values(rng, marker) + [0.3, 200e9])
    elif kind == "rename key":
        if isinstance(container, dict):
            new = rng.choice([str(key).lower(), str(key) + " ", "", str(key).replace(" ", "_"), "X" + str(key)])
            container[new] = container.pop(key)
    elif kind == "wrap in list":
        container[key] = [container[key]]
    else:  # expression garbage
        values = [p for p in all_paths if p[1] == "Value"]
        if values:
            container, key, path = rng.choice(values)
            where = "/".join(map(str, path))
            tokens = ["t", "x", "y", "z", "1", "0", "2.5", "1e3", "+", "-", "*", "/", "(", ")", "**", "e", "sin", ".", " ", ",", "[", "'"]
            container[key] = "".join(rng.choice(tokens) for _ in range(rng.randint(1, 14)))
    return dump(d), f"{kind} at {where}"


def mutation_cases(tool, work, base_text, mesh, seed, count, marker, only=None):
    cases = []
    for k in range(count) if only is None else [only]:
        def case(k=k):
            rng = random.Random(f"{seed}:{k}")
            data, how = mutate(base_text, rng, marker)
            r = Run(tool, os.path.join(work, f"e_{k}"), data, mesh=mesh)
            bad = r.contract()
            return [f"{b} (mutation: {how})" for b in bad], r
        cases.append((f"(e) mutation case {k} (seed {seed})", case))
    return cases


# ---------------------------------------------------------------------------------------------

def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--perinox", required=True, help="the perinox driver")
    ap.add_argument("--tensile-deck", help="Peridigm's tensile_test.yaml, the mutation loop's base deck")
    ap.add_argument("--seed", type=int, default=2024, help="seed of the mutation loop")
    ap.add_argument("--cases", type=int, default=250, help="mutation cases")
    ap.add_argument("--case", type=int, help="run only this mutation case")
    ap.add_argument("--jobs", type=int, default=max(2, os.cpu_count() or 2))
    ap.add_argument("--verbose", action="store_true")
    a = ap.parse_args()
    tool = os.path.abspath(a.perinox)
    t0 = time.monotonic()
    with tempfile.TemporaryDirectory(prefix="peridigm_converter_") as work:
        if a.tensile_deck:
            with open(a.tensile_deck, encoding="utf-8") as f:
                base_text = f.read()
        else:
            base_text = dump(BASE).decode()
        mesh = yaml.safe_load(base_text)["Peridigm"]["Discretization"]["Input Mesh File"]
        grammar, marker = grammar_cases(tool, work)
        if a.case is not None:
            cases = mutation_cases(tool, work, base_text, mesh, a.seed, a.cases, marker, only=a.case)
        else:
            cases = grammar + malformed_cases(tool, work, marker) + impossible_cases(tool, work) + elastic_cases(tool, work)
            if a.tensile_deck:
                def tensile():  # the deck unmutated: converted, with E and nu from its K and G
                    r = Run(tool, os.path.join(work, "tensile"), base_text.encode(), mesh=mesh)
                    bad = r.converted()
                    if not bad:
                        k, g = 1.5e12, 6.923e11
                        e, n = Scene(r.out).material()
                        if not (close(e, 9 * k * g / (3 * k + g)) and close(n, (3 * k - 2 * g) / (2 * (3 * k + g)))):
                            bad.append(f"E, nu = {e}, {n}")
                    return bad, r
                cases.append(("(e) the tensile deck itself converts", tensile))
            cases += mutation_cases(tool, work, base_text, mesh, a.seed, a.cases, marker)
        passed = failed = 0
        slowest = 0.0
        with concurrent.futures.ThreadPoolExecutor(max_workers=a.jobs) as pool:
            futures = [(name, pool.submit(fn)) for name, fn in cases]
            for name, fut in futures:
                try:
                    bad, r = fut.result()
                except Exception as e:  # a fault of the test itself counts as a failure
                    bad, r = [f"the test raised {type(e).__name__}: {e}"], None
                if r is not None:
                    slowest = max(slowest, r.seconds)
                if bad:
                    failed += 1
                    print(f"FAILED {name}: {'; '.join(bad)}" + (f"\n    {r.summary()}" if r else ""))
                else:
                    passed += 1
                    if a.verbose:
                        print(f"ok     {name}: " + (r.lines[0] if r.lines else r.stdout.strip())[:200])
        if os.path.exists(marker):
            failed += 1
            print("FAILED: an expression's command ran (the marker file exists)")
    print(f"{len(cases)} cases in {time.monotonic() - t0:.1f} s (slowest run {slowest:.2f} s), {a.jobs} at a time")
    print(f"{passed} passed, {failed} failed")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
