#!/usr/bin/env python3
"""Turns a Peridigm input deck (YAML) of the elastic-correspondence kind into a perinox scene.

    python3 tools/peridigm_to_scene.py DECK.yaml [--out SCENE.xml] [--preset NAME] [--hencky]

What is translated (docs/exodus.md, "Bringing a Peridigm model"):
  Discretization  Type "Exodus", Input Mesh File     -> Type Exodus, Mesh File (relative to the scene;
                                                        the mesh must exist)
  Materials       "Elastic Correspondence" with any two of Peridigm's elastic constants (Young's
                  Modulus E, Poisson's Ratio nu, Bulk Modulus K, Shear Modulus G; three or four
                  must agree to a relative 1e-6, nu to 1e-6) -> Young's Modulus and Poisson's Ratio
                  by the isotropic relations (from K and G: E = 9KG/(3K+G), nu = (3K-2G)/(2(3K+G)));
                  Small Strain (--hencky: finite deformation); Hourglass Coefficient
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
Anything else (another material model, damage, contact, several horizons, other condition types,
node sets defined in the deck, expressions that are not of that form, Final Time other than 1) is
refused: the scene would not be the same model.

Value expressions are read by the parser below, never by Python's eval. Its whole grammar:

    expression := term { ("+" | "-") term }
    term       := factor { ("*" | "/") factor }
    factor     := ("+" | "-") factor  |  number  |  name  |  "(" expression ")"
    number     := digits [ "." [digits] ] [exponent]  |  "." digits [exponent]
    exponent   := ("e" | "E") [ "+" | "-" ] digits          digits: one or more of 0-9
    name       := "x" | "y" | "z" | "t"

with blanks (space, tab, line breaks) allowed between tokens. Nothing else is read: no powers
(**), functions, other names, attributes, brackets, commas, hexadecimal or underscores in
numbers. An expression has at most 1000 characters and at most 50 levels of parentheses and
signs. A YAML number (Value: 0.0) is read as that number. The expression is then evaluated at
probe points (x, y, z, t) and must equal t (a + b x + c y + d z) there, with finite values and no
division by zero.

Numbers of the deck are YAML numbers, or text holding one decimal number ("1.5e12"); they must be
finite, moduli, densities and horizons above 0, hourglass coefficients 0 or above, the number of
load steps a whole number from 1 to 1000000 (perinox's Load Steps bound). Duplicate keys are
refused. Scalars follow YAML 1.2's core schema (1e12 is a number, yes/no/on/off are text). A deck
has at most 128 KiB (any YAML of that size is read within seconds).

Bad input: one sentence on stderr naming the deck and the key, exit code 2, no scene written (the
scene goes to a temporary file in the same folder, renamed into place only when complete). Exit 0:
the scene is written; exit 1 only when PyYAML is missing.
"""
import argparse
import math
import os
import random
import re
import stat
import sys
import tempfile

try:
    import yaml
except ImportError:  # Debian: python3-yaml
    sys.stderr.write("peridigm_to_scene.py needs PyYAML (Debian package python3-yaml)\n")
    sys.exit(1)

MAX_DECK_BYTES = 128 << 10     # a Peridigm deck is a few kilobytes; 128 KiB of any YAML parse in 1.5 s
MAX_EXPRESSION = 1000          # characters of a Value expression
MAX_DEPTH = 50                 # levels of parentheses and signs in an expression
MAX_LOAD_STEPS = 1000000       # perinox's Solver/Load Steps bound
AGREEMENT = 1e-6               # three or four elastic constants must agree to this
ELASTIC = ("Young's Modulus", "Poisson's Ratio", "Bulk Modulus", "Shear Modulus")
PD = "Prescribed Displacement"
FORM = "is not of the form t (a + b x + c y + d z), which perinox's conditions take"

DECIMAL = re.compile(r"[+-]?(?:[0-9]+(?:\.[0-9]*)?|\.[0-9]+)(?:[eE][+-]?[0-9]+)?")
CONTROL = re.compile(r"[\x00-\x1f\x7f\ud800-\udfff\ufffe\uffff]")  # not allowed in scene text


class Refusal(Exception):
    """The deck cannot be translated; the message is one sentence (without the deck's name)."""


def refuse(msg):
    raise Refusal(msg)


def shown(value, limit=60):
    """value as text for a message: one line, non-printable characters escaped, shortened."""
    s = str(value)
    n = len(s)
    s = "".join(c if c.isprintable() else repr(c)[1:-1] for c in s[:limit])
    return s + (f"... ({n} characters)" if n > limit else "")


def describe(v):
    """What a YAML value is, for a message (never the whole of a list or mapping)."""
    if v is None:
        return "empty"
    if isinstance(v, bool):
        return "the boolean " + ("true" if v else "false")
    if isinstance(v, (int, float)):
        return "the number " + shown(v)
    if isinstance(v, str):
        return f"the text '{shown(v)}'"
    if isinstance(v, list):
        return "a list"
    if isinstance(v, dict):
        return "a mapping"
    return "a value of YAML type " + type(v).__name__


# ---------------------------------------------------------------------------------------------
# Reading the YAML: PyYAML's safe loader with YAML 1.2 core-schema scalars and no duplicate keys.

class DeckLoader(yaml.SafeLoader):
    yaml_implicit_resolvers = {}  # filled below, instead of YAML 1.1's (yes/no booleans, 0x10, 1_000, 1:30)

    def construct_mapping(self, node, deep=False):
        if isinstance(node, yaml.MappingNode):
            seen = set()
            for key_node, _ in node.value:
                if not isinstance(key_node, yaml.ScalarNode) or key_node.tag == "tag:yaml.org,2002:merge":
                    continue
                key = self.construct_object(key_node, deep=True)
                try:
                    twice = key in seen
                    seen.add(key)
                except TypeError:
                    continue
                if twice:
                    raise yaml.constructor.ConstructorError(None, None, f"the key '{shown(key)}' is given twice",
                                                            key_node.start_mark)
        return super().construct_mapping(node, deep=deep)


for _tag, _pattern, _first in (
        ("null", r"~|null|Null|NULL|", ["~", "n", "N", ""]),
        ("bool", r"true|True|TRUE|false|False|FALSE", list("tTfF")),
        ("int", r"[-+]?[0-9]+", list("-+0123456789")),
        ("float", r"[-+]?(?:[0-9]+(?:\.[0-9]*)?|\.[0-9]+)(?:[eE][-+]?[0-9]+)?|[-+]?\.(?:inf|Inf|INF)|\.(?:nan|NaN|NAN)",
         list("-+0123456789.")),
        ("merge", r"<<", ["<"])):
    DeckLoader.add_implicit_resolver("tag:yaml.org,2002:" + _tag, re.compile(f"^(?:{_pattern})$"), _first)


def _scalar_error(node, what):
    return yaml.constructor.ConstructorError(None, None, f"'{shown(node.value)}' is not {what}", node.start_mark)


def _construct_int(loader, node):
    s = loader.construct_scalar(node).strip()
    if not re.fullmatch(r"[-+]?[0-9]+", s):
        raise _scalar_error(node, "a decimal integer")
    return int(s) if len(s) <= 30 else float(s)  # a longer one is out of every range anyway


def _construct_float(loader, node):
    s = loader.construct_scalar(node).strip()
    special = {".inf": math.inf, "+.inf": math.inf, "-.inf": -math.inf, ".nan": math.nan}
    if s.lower() in special:
        return special[s.lower()]
    if not DECIMAL.fullmatch(s):
        raise _scalar_error(node, "a decimal number")
    return float(s)


def _construct_timestamp(loader, node):
    raise _scalar_error(node, "read: a Peridigm deck holds no timestamps")


DeckLoader.add_constructor("tag:yaml.org,2002:int", _construct_int)
DeckLoader.add_constructor("tag:yaml.org,2002:float", _construct_float)
DeckLoader.add_constructor("tag:yaml.org,2002:timestamp", _construct_timestamp)


def yaml_problem(e):
    """One sentence for a PyYAML error."""
    if isinstance(e, yaml.reader.ReaderError):
        c = e.character if isinstance(e.character, int) else ord(e.character)
        return f"holds the character #x{c:04x} at character {e.position + 1}, which YAML does not allow"
    problem = getattr(e, "problem", None) or getattr(e, "context", None)
    mark = getattr(e, "problem_mark", None) or getattr(e, "context_mark", None)
    at = f" at line {mark.line + 1}, column {mark.column + 1}" if mark is not None else ""
    if problem:
        return f"is not valid YAML{at}: {shown(problem, 120)}"
    first = str(e).splitlines()[0] if str(e) else type(e).__name__
    return f"is not valid YAML{at}: {shown(first, 120)}"


def load_deck(path):
    """The deck's 'Peridigm' mapping."""
    try:
        st = os.stat(path)
    except (OSError, ValueError) as e:
        refuse(f"cannot read the deck: {getattr(e, 'strerror', None) or e}")
    if stat.S_ISDIR(st.st_mode):
        refuse("is a folder, not a deck file")
    if not stat.S_ISREG(st.st_mode):
        refuse("is not a regular file")
    if st.st_size > MAX_DECK_BYTES:
        refuse(f"has {st.st_size} bytes; this tool reads decks of at most {MAX_DECK_BYTES} (Peridigm's are a few kilobytes)")
    try:
        with open(path, "rb") as f:
            raw = f.read(MAX_DECK_BYTES + 1)
    except OSError as e:
        refuse(f"cannot read the deck: {e.strerror}")
    if len(raw) > MAX_DECK_BYTES:
        refuse(f"has over {MAX_DECK_BYTES} bytes; this tool reads decks of at most that (Peridigm's are a few kilobytes)")
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as e:
        refuse(f"is not UTF-8 text (byte 0x{raw[e.start]:02x} at offset {e.start})")
    if text.startswith("\ufeff"):  # a byte-order mark
        text = text[1:]
    if text.lstrip().startswith("<"):
        refuse("looks like an XML (Teuchos ParameterList) deck; only YAML decks are translated")
    try:
        doc = yaml.load(text, Loader=DeckLoader)
    except yaml.YAMLError as e:
        refuse(yaml_problem(e))
    except RecursionError:
        refuse("nests lists or mappings too deeply to be a Peridigm deck")
    except (ValueError, TypeError, AttributeError, OverflowError, KeyError, IndexError) as e:
        refuse(f"holds a YAML value that cannot be read ({type(e).__name__}: {shown(e, 100)})")
    if doc is None:
        refuse("is empty: no YAML content, not a Peridigm deck")
    if not isinstance(doc, dict):
        refuse(f"holds {describe(doc)} at its top level, not a mapping with a 'Peridigm' key")
    if "Peridigm" not in doc:
        refuse("has no top-level 'Peridigm' key: not a Peridigm deck")
    if not isinstance(doc["Peridigm"], dict):
        refuse(f"'Peridigm' is {describe(doc['Peridigm'])}, not a mapping of sections")
    return Section(doc["Peridigm"], "Peridigm")


class Section:
    """A mapping of the deck and its path; each accessor refuses a missing or ill-typed key by
    naming it ('Peridigm/Materials/Steel/Bulk Modulus')."""

    def __init__(self, data, path):
        self.data, self.path = {}, path
        for k, v in data.items():  # YAML keys that are not text (1:, true:) are read as text
            name = k if isinstance(k, str) else str(k)
            if name in self.data:
                refuse(f"{self.key(name)} is given twice")
            self.data[name] = v

    def key(self, k):
        return f"'{self.path}/{shown(k, 40)}'"

    def has(self, k):
        return k in self.data

    def items(self):
        return list(self.data.items())

    def raw(self, k, required=True):
        if k not in self.data:
            if required:
                refuse(f"{self.key(k)} is missing")
            return None
        return self.data[k]

    def sub(self, k, required=True):
        """The sub-mapping k (None: an optional one that is absent or empty)."""
        v = self.raw(k, required)
        if v is None and (not required or k not in self.data):
            return None
        if not isinstance(v, dict):
            refuse(f"{self.key(k)} is {describe(v)}, not a mapping of keys")
        return Section(v, f"{self.path}/{shown(k, 40)}")

    def text(self, k, required=True, default=None):
        """A non-empty single-line text, as it can go into the scene."""
        if k not in self.data and not required:
            return default
        v = self.raw(k)
        if not isinstance(v, str):
            refuse(f"{self.key(k)} is {describe(v)}, not a text")
        if not v.strip():
            refuse(f"{self.key(k)} is empty")
        if CONTROL.search(v):
            refuse(f"{self.key(k)} ('{shown(v)}') holds a control character")
        return v

    def number(self, k, rule, ok, default=None):
        """A finite number for which ok(value) holds; rule says which, for the message."""
        if k not in self.data and default is not None:
            return default
        v = self.raw(k)
        x = None
        if isinstance(v, (int, float)) and not isinstance(v, bool):
            try:
                x = float(v)
            except OverflowError:
                x = math.inf
        elif isinstance(v, str) and DECIMAL.fullmatch(v.strip()):
            x = float(v.strip())
        if x is None:
            refuse(f"{self.key(k)} is {describe(v)}; it must be {rule}")
        if not math.isfinite(x) or not ok(x):
            refuse(f"{self.key(k)} is {shown(v)}; it must be {rule}")
        return x


def positive(x):
    return x > 0


def finite(x):
    return True


# ---------------------------------------------------------------------------------------------
# Value expressions: tokens, a recursive-descent parser to a small tree, and its evaluation.

class ExpressionError(Exception):
    pass


TOKEN = re.compile(r"[ \t\r\n]*(?:(?P<num>(?:[0-9]+(?:\.[0-9]*)?|\.[0-9]+)(?:[eE][-+]?[0-9]+)?)"
                   r"|(?P<name>[A-Za-z_][A-Za-z0-9_]*)|(?P<op>[-+*/()])|(?P<end>\Z))")
VARIABLES = {"x": 0, "y": 1, "z": 2, "t": 3}


def tokenize(text):
    """[(kind, text, position)], kind num, name, op or end."""
    tokens, pos = [], 0
    while True:
        m = TOKEN.match(text, pos)
        if m is None:
            i = pos + len(text[pos:]) - len(text[pos:].lstrip(" \t\r\n"))
            raise ExpressionError(f"has '{shown(text[i], 10)}' at character {i + 1}, which expressions do not take"
                                  " (only numbers, x, y, z, t, + - * / and parentheses)")
        kind = m.lastgroup
        start = m.start(kind)
        if kind == "end":
            tokens.append(("end", "", start))
            return tokens
        word = m.group(kind)
        if kind == "name" and word not in VARIABLES:
            raise ExpressionError(f"uses the name '{shown(word, 20)}' at character {start + 1}; only x, y, z and t"
                                  " are known (no functions or constants)")
        if kind == "num":
            value = float(word)
            underflow = value == 0 and re.search(r"[1-9]", re.split(r"[eE]", word)[0])
            if not math.isfinite(value) or underflow:
                raise ExpressionError(f"has the number '{shown(word, 20)}', which is out of the range of double precision")
        if kind == "op" and word == "*" and text.startswith("**", start):
            raise ExpressionError(f"has '**' at character {start + 1}; powers are not taken")
        tokens.append((kind, word, start))
        pos = m.end()


class Parser:
    """Recursive descent over the grammar of the module's docstring. Tree nodes:
    ("num", value), ("var", index), ("neg", node), ("sum", [(+1|-1, node)...]),
    ("prod", [("*"|"/", node)...]) (the first operator of a product is "*")."""

    def __init__(self, text):
        self.tokens = tokenize(text)
        self.i = 0

    def peek(self):
        return self.tokens[self.i]

    def take(self):
        tok = self.tokens[self.i]
        self.i += 1
        return tok

    def parse(self):
        tree = self.expression(0)
        kind, word, pos = self.peek()
        if kind != "end":
            raise ExpressionError(f"has '{shown(word, 20)}' at character {pos + 1} where an operator or the end was expected")
        return tree

    def expression(self, depth):
        terms = [(1, self.term(depth))]
        while self.peek()[1] in ("+", "-") and self.peek()[0] == "op":
            sign = 1 if self.take()[1] == "+" else -1
            terms.append((sign, self.term(depth)))
        return terms[0][1] if len(terms) == 1 else ("sum", terms)

    def term(self, depth):
        factors = [("*", self.factor(depth))]
        while self.peek()[1] in ("*", "/") and self.peek()[0] == "op":
            op = self.take()[1]
            factors.append((op, self.factor(depth)))
        return factors[0][1] if len(factors) == 1 else ("prod", factors)

    def factor(self, depth):
        if depth >= MAX_DEPTH:
            raise ExpressionError(f"nests parentheses and signs more than {MAX_DEPTH} deep")
        kind, word, pos = self.take()
        if kind == "num":
            return ("num", float(word))
        if kind == "name":
            return ("var", VARIABLES[word])
        if kind == "op" and word in ("+", "-"):
            inner = self.factor(depth + 1)
            return inner if word == "+" else ("neg", inner)
        if kind == "op" and word == "(":
            inner = self.expression(depth + 1)
            k, w, p = self.take()
            if (k, w) != ("op", ")"):
                where = "the end" if k == "end" else f"'{shown(w, 20)}' at character {p + 1}"
                raise ExpressionError(f"has {where} where ')' was expected")
            return inner
        where = "ends" if kind == "end" else f"has '{shown(word, 20)}' at character {pos + 1}"
        raise ExpressionError(f"{where} where a number, x, y, z, t or '(' was expected")


def evaluate(node, point):
    """The tree's value at point = (x, y, z, t); ZeroDivisionError on a division by zero."""
    kind = node[0]
    if kind == "num":
        return node[1]
    if kind == "var":
        return point[node[1]]
    if kind == "neg":
        return -evaluate(node[1], point)
    if kind == "sum":
        s = 0.0
        for sign, n in node[1]:
            s += sign * evaluate(n, point)
        return s
    v = 1.0
    for op, n in node[1]:
        f = evaluate(n, point)
        if op == "*":
            v *= f
        elif f == 0:
            raise ZeroDivisionError
        else:
            v /= f
    return v


def linear_in_t(where, value):
    """(a, [b, c, d]) with value(x, y, z, t) = t (a + b x + c y + d z), checked at probe points;
    refuses anything else. where names the key, for messages."""
    if isinstance(value, bool) or not isinstance(value, (str, int, float)):
        refuse(f"{where} is {describe(value)}, not an expression")
    if isinstance(value, (int, float)):
        if not math.isfinite(float(value)):
            refuse(f"{where} is {shown(value)}, not a finite number")
        expr = repr(float(value))
    else:
        expr = value
    quoted = f"'{shown(expr)}'"
    if len(expr) > MAX_EXPRESSION:
        refuse(f"{where} is an expression of {len(expr)} characters ({quoted}); at most {MAX_EXPRESSION} are read")
    if not expr.strip():
        refuse(f"{where} is empty")
    try:
        tree = Parser(expr).parse()
    except ExpressionError as e:
        refuse(f"{where}: {quoted} {e}")

    def f(x, y, z, t):
        try:
            v = evaluate(tree, (x, y, z, t))
        except ZeroDivisionError:
            refuse(f"{where}: {quoted} divides by zero at x = {x:g}, y = {y:g}, z = {z:g}, t = {t:g}, so it {FORM}")
        if not math.isfinite(v):
            refuse(f"{where}: {quoted} is not finite at x = {x:g}, y = {y:g}, z = {z:g}, t = {t:g}, so it {FORM}")
        return v

    a = f(0, 0, 0, 1)
    g = [f(1, 0, 0, 1) - a, f(0, 1, 0, 1) - a, f(0, 0, 1, 1) - a]
    if not all(math.isfinite(c) for c in [a] + g):
        refuse(f"{where}: {quoted} has coefficients beyond double precision")
    scale = 1 + abs(a) + 3 * sum(abs(c) for c in g)
    rnd = random.Random(18)
    for _ in range(20):
        x, y, z, t = (rnd.uniform(-3, 3) for _ in range(4))
        want = t * (a + g[0] * x + g[1] * y + g[2] * z)
        got = f(x, y, z, t)
        if not math.isfinite(want) or not abs(got - want) <= 1e-12 * (scale + abs(want)):
            refuse(f"{where}: {quoted} {FORM}")
    return a + 0.0, [c + 0.0 for c in g]  # + 0.0: no -0.0 in the scene


# ---------------------------------------------------------------------------------------------
# Materials

def elastic_constants(m):
    """(E, nu, K, G, the keys used) of material section m from any two of Peridigm's four elastic
    constants; three or four must agree."""
    E_, NU, K_, G_ = ELASTIC
    given = {}
    for k in ELASTIC:
        if m.has(k):
            if k == NU:
                given[k] = m.number(k, "a number between -1 and 0.5 (both excluded)", lambda v: -1 < v < 0.5)
            else:
                given[k] = m.number(k, "a finite number above 0", positive)
    if len(given) < 2:
        have = f"only {next(iter(given))}" if given else "none"
        refuse(f"material '{m.path}' gives {have} of the elastic constants; give two of "
               f"{', '.join(ELASTIC)}")
    for pair in ((E_, NU), (K_, G_), (E_, G_), (E_, K_), (K_, NU), (G_, NU)):
        if pair[0] in given and pair[1] in given:
            break
    a, b = given[pair[0]], given[pair[1]]
    if pair == (E_, NU):
        E, nu = a, b
    elif pair == (K_, G_):
        E, nu = 9 * a * b / (3 * a + b), (3 * a - 2 * b) / (2 * (3 * a + b))
    elif pair == (E_, G_):
        E, nu = a, a / (2 * b) - 1
    elif pair == (E_, K_):
        E, nu = a, (3 * b - a) / (6 * b)
    elif pair == (K_, NU):
        E, nu = 3 * a * (1 - 2 * b), b
    else:  # (G, nu)
        E, nu = 2 * a * (1 + b), b
    names = f"'{m.path}/{pair[0]}' and '{pair[1]}'"
    if not (math.isfinite(E) and math.isfinite(nu)):
        refuse(f"{names} are too large to convert to Young's modulus and Poisson's ratio")
    if not -1 < nu < 0.5:
        refuse(f"{names} give Poisson's ratio {nu:.6g}, outside -1 < nu < 0.5 (K and G must be above 0)")
    K, G = E / (3 * (1 - 2 * nu)), E / (2 * (1 + nu))
    derived = {E_: E, NU: nu, K_: K, G_: G}
    for k, v in given.items():
        if k in pair:
            continue
        off = abs(v - derived[k]) if k == NU else abs(v - derived[k]) / max(abs(v), abs(derived[k]))
        if not off <= AGREEMENT:
            refuse(f"'{m.path}/{k}' is {v!r} but {pair[0]} and {pair[1]} give {derived[k]:.9g} "
                   f"(difference {off:.3g}, more than {AGREEMENT:g}); give two elastic constants, or ones that agree")
    return E, nu, K, G, [k for k in ELASTIC if k in given]


def read_material(m):
    model = m.text("Material Model")
    if model != "Elastic Correspondence":
        refuse(f"'{m.path}/Material Model' is '{shown(model)}'; only Elastic Correspondence is translated")
    E, nu, K, G, used = elastic_constants(m)
    if m.has("Density"):
        m.number("Density", "a finite number above 0", positive)
    hg = m.number("Hourglass Coefficient", "a finite number, 0 or above", lambda v: v >= 0, default=0.0)
    return {"E": E, "nu": nu, "K": K, "G": G, "hourglass": hg, "from": used}


# ---------------------------------------------------------------------------------------------

BLOCK_NAME = re.compile(r"block_([0-9]{1,9})")


def block_id(name):
    m = BLOCK_NAME.fullmatch(name)
    return int(m.group(1)) if m else None


def node_set_definition(key, v, deck_dir):
    """Checks a node set the deck defines in Boundary Conditions (a file or node numbers)."""
    if isinstance(v, int) and not isinstance(v, bool):
        return "node numbers"
    if not isinstance(v, str) or not v.strip():
        refuse(f"{key} is {describe(v)}; a node set is a file name or a list of node numbers")
    if all(tok.isascii() and tok.isdigit() for tok in v.split()):
        return "node numbers"
    if CONTROL.search(v) or not os.path.isfile(os.path.join(deck_dir, v.strip())):
        refuse(f"{key} names the node set file '{shown(v)}', which does not exist")
    return "a node set file"


def convert(args):
    deck = args.deck
    p = load_deck(deck)
    deck_dir = os.path.dirname(os.path.abspath(deck))
    out = args.out if args.out is not None else os.path.splitext(deck)[0] + ".xml"

    disc = p.sub("Discretization")
    dtype = disc.text("Type")
    if dtype != "Exodus":
        refuse(f"'Peridigm/Discretization/Type' is '{shown(dtype)}'; only Exodus meshes are translated")
    mesh_file = disc.text("Input Mesh File")

    mats = p.sub("Materials")
    if mats is None or not mats.data:
        refuse("'Peridigm/Materials' is empty: the deck has no materials")
    materials = {}
    for mname, v in mats.items():
        if not isinstance(v, dict):
            refuse(f"{mats.key(mname)} is {describe(v)}, not a mapping (a material)")
        if CONTROL.search(mname):
            refuse(f"the material name {mats.key(mname)} holds a control character")
        materials[mname] = read_material(mats.sub(mname))

    for section in ("Damage Models", "Contact"):
        if p.has(section):
            refuse(f"has '{section}'; they are not translated")
    blocks = p.sub("Blocks")
    if blocks is None or not blocks.data:
        refuse("'Peridigm/Blocks' is empty: the deck has no blocks")
    horizons, block_material = {}, {}
    for bname, v in blocks.items():
        if not isinstance(v, dict):
            refuse(f"{blocks.key(bname)} is {describe(v)}, not a mapping (a block)")
        b = blocks.sub(bname)
        mat = b.text("Material")
        if mat not in materials:
            refuse(f"'{b.path}/Material' is '{shown(mat)}', which 'Peridigm/Materials' does not define")
        if b.has("Damage Model"):
            refuse(f"'{b.path}' has a Damage Model; damage is not translated")
        horizons[bname] = b.number("Horizon", "a finite number above 0", positive)
        block_material[bname] = (b, mat)
    if len(set(horizons.values())) != 1:
        refuse("the blocks have different horizons (" + ", ".join(f"{shown(n, 30)} {h!r}" for n, h in horizons.items()) +
               "); perinox uses one horizon")
    horizon = next(iter(horizons.values()))
    first = next(iter(block_material.values()))[1]
    # Several materials: one scene Blocks entry per Peridigm block_N, with its material's constants.
    per_block, listed = [], {}
    if len({mat for _, mat in block_material.values()}) > 1:
        for bname, (b, mat) in block_material.items():
            for n in b.text("Block Names").split():
                bid = block_id(n)
                if bid is None:
                    refuse(f"'{b.path}/Block Names' lists '{shown(n)}'; only Peridigm's 'block_<id>' names are translated")
                if bid in listed:
                    refuse(f"'{b.path}/Block Names' lists block_{bid}, which block '{shown(listed[bid], 30)}' lists too")
                listed[bid] = bname
                per_block.append((n, bid, mat, materials[mat]))

    solver = p.sub("Solver")
    if solver is None or not solver.has("QuasiStatic"):
        refuse("'Peridigm/Solver' has no QuasiStatic list; only quasi-static decks are translated")
    for other in ("Verlet", "NOXQuasiStatic", "Implicit", "ImplicitDiagonal", "QuasiStaticExplicit"):
        if solver.has(other):
            refuse(f"'Peridigm/Solver' has {other} besides QuasiStatic; only quasi-static decks are translated")
    qs = solver.sub("QuasiStatic")
    if qs is None:
        refuse("'Peridigm/Solver/QuasiStatic' is empty, not a mapping of keys")
    solver.number("Initial Time", "0 (perinox's load factor is t, from 0 to 1)", lambda v: v == 0, default=0.0)
    solver.number("Final Time", "1 (perinox's load factor is t, from 0 to 1)", lambda v: v == 1, default=1.0)
    steps = int(qs.number("Number of Load Steps", f"a whole number from 1 to {MAX_LOAD_STEPS}",
                          lambda v: v == int(v) and 1 <= v <= MAX_LOAD_STEPS, default=1))

    regions, conditions, probes = [], [], []
    axes = {"x": 0, "y": 1, "z": 2}
    node_sets, prescribed = {}, {}
    bcs = p.sub("Boundary Conditions", required=False)
    for name, v in (bcs.items() if bcs else []):
        if not isinstance(v, dict):
            if "Node Set" in name:
                node_sets[name] = node_set_definition(bcs.key(name), v, deck_dir)
                continue
            refuse(f"{bcs.key(name)} is {describe(v)}, not a mapping (a boundary condition)")
        if CONTROL.search(name):
            refuse(f"the condition name {bcs.key(name)} holds a control character")
        bc = bcs.sub(name)
        typ = bc.text("Type")
        if typ != PD:
            refuse(f"'{bc.path}/Type' is '{shown(typ)}'; only Prescribed Displacement is translated")
        ns = bc.text("Node Set")
        comp = bc.text("Coordinate")
        if comp not in axes:
            refuse(f"'{bc.path}/Coordinate' is '{shown(comp)}'; it must be x, y or z")
        val, grad = linear_in_t(f"boundary condition '{shown(name, 40)}' ('{bc.path}/Value')", bc.raw("Value"))
        if prescribed.setdefault((ns, comp), (val, grad)) != (val, grad):
            refuse(f"boundary condition '{shown(name, 40)}' prescribes {comp} on '{shown(ns, 40)}' differently from another condition")
        if ns not in [r[0] for r in regions]:
            regions.append((ns, "Node Set", ("Name", "string", ns)))
        conditions.append((name, ns, comp, val, grad))
    for _, ns, *_ in conditions:
        if ns in node_sets:
            refuse(f"'Peridigm/Boundary Conditions/{shown(ns, 40)}' defines a node set by {node_sets[ns]}; "
                   "perinox takes node sets from the Exodus mesh by name (nodelist_<id>)")

    ccp = p.sub("Compute Class Parameters", required=False)
    labels = set()
    for name, v in (ccp.items() if ccp else []):
        if not isinstance(v, dict):
            refuse(f"{ccp.key(name)} is {describe(v)}, not a mapping (a compute class)")
        c = ccp.sub(name)
        cls = c.text("Compute Class")
        variable = c.text("Variable", required=False)
        if cls == "Nearest_Point_Data" and variable == "Displacement":
            point = [c.number(k, "a finite number", finite) for k in ("X", "Y", "Z")]
            label = c.text("Output Label")
            rn = "near " + label
            regions.append((rn, "Nearest", ("Point", "Array(double)", "{%r, %r, %r}" % tuple(point))))
            quantity = "Displacement"
        elif cls == "Block_Data" and variable == "Force" and c.text("Calculation Type", required=False) == "Sum":
            blk = c.text("Block")
            bid = block_id(blk)
            if bid is None:
                refuse(f"'{c.path}/Block' is '{shown(blk)}'; only Peridigm's 'block_<id>' names are translated")
            label = c.text("Output Label")
            rn = f"block {bid}"
            if rn not in [r[0] for r in regions]:
                regions.append((rn, "Block", ("Id", "int", bid)))
            quantity = "Reaction"
        else:
            continue  # other compute classes (initial positions, ...) have no perinox counterpart: skipped
        if label in labels:
            refuse(f"'{c.path}/Output Label' is '{shown(label)}', which another compute class uses too")
        labels.add(label)
        probes.append((label, rn, quantity))

    mesh = os.path.join(deck_dir, mesh_file)
    if not os.path.isfile(mesh):
        refuse(f"'Peridigm/Discretization/Input Mesh File' is '{shown(mesh_file)}', which does not exist "
               f"(looked for {shown(mesh, 200)})")
    if not out.strip():
        refuse("the scene's path (--out) is empty")
    if os.path.isdir(out):
        refuse(f"the scene's path {shown(out, 200)} is a folder")
    if os.path.exists(out) and os.path.samefile(out, deck):
        refuse(f"the scene {shown(out, 200)} would overwrite the deck; give another --out")
    mesh_rel = os.path.relpath(mesh, os.path.dirname(os.path.abspath(out)))
    if CONTROL.search(mesh_rel):
        refuse(f"the mesh's path from the scene ('{shown(mesh_rel, 200)}') holds a control character")

    E, nu = materials[first]["E"], materials[first]["nu"]
    hourglass = materials[first]["hourglass"]
    text = scene_text(args, deck, mesh_rel, horizon, materials, first, per_block, regions, conditions, probes, steps)
    write_atomically(out, text)
    print(f"wrote {out}: {len(regions)} regions, {len(conditions)} conditions, {len(probes)} probes, "
          f"E = {E:.6g}, nu = {nu:.6g}, horizon {horizon}" + (f", {len(per_block)} blocks with their own materials" if per_block else ""))
    return 0


def comment(s):
    """s made safe inside an XML comment."""
    s = shown(s, 200)
    while "--" in s:
        s = s.replace("--", "- -")
    return s.rstrip("-")


def quoted(s):
    """s as a double-quoted XML attribute value."""
    for c, entity in (("&", "&amp;"), ("<", "&lt;"), (">", "&gt;"), ('"', "&quot;"), ("\n", "&#10;"), ("\r", "&#13;"), ("\t", "&#9;")):
        s = s.replace(c, entity)
    return f'"{s}"'


def scene_text(args, deck, mesh_rel, horizon, materials, first, per_block, regions, conditions, probes, steps):
    q = quoted

    def par(n, t, v):
        return f"<Parameter name={q(n)} type={q(t)} value={q(str(v))}/>"

    deck_name = shown(os.path.basename(deck), 200)
    mat = materials[first]
    L = [f"<!-- Written by tools/peridigm_to_scene.py from {comment(deck_name)}. Peridigm's Elastic Correspondence:"]
    for name, m in materials.items():
        L.append(f"     material '{comment(name)}': K = {m['K']!r}, G = {m['G']!r}, E = {m['E']!r}, nu = {m['nu']!r} "
                 f"(from {' and '.join(m['from'])}); hourglass {m['hourglass']!r}")
    L += ["     E = 9KG/(3K+G), nu = (3K-2G)/(2(3K+G)); hourglass coefficient -> Silling G.",
          "     Node sets select the elements touching their nodes, as in Peridigm (docs/exodus.md). -->",
          '<ParameterList name="perinox">',
          "  " + par("Title", "string", "From Peridigm deck " + deck_name),
          '  <ParameterList name="Discretization">',
          "    " + par("Dimension", "int", 3), "    " + par("Type", "string", "Exodus"),
          "    " + par("Mesh File", "string", mesh_rel), "    " + par("Horizon", "double", repr(horizon)),
          "  </ParameterList>",
          '  <ParameterList name="Material">',
          "    " + par("Model", "string", "Hencky" if args.hencky else "Small Strain"),
          "    " + par("Young's Modulus", "double", repr(mat["E"])), "    " + par("Poisson's Ratio", "double", repr(mat["nu"])),
          "  </ParameterList>"]
    if mat["hourglass"] > 0 or any(m["hourglass"] > 0 for *_, m in per_block):
        L += ['  <ParameterList name="Model">', "    " + par("Stabilization", "string", "Silling"),
              "    " + par("G", "double", repr(mat["hourglass"])), "  </ParameterList>"]
    if per_block:
        L.append('  <ParameterList name="Blocks">')
        for n, bid, mname, m in per_block:
            L += [f"    <ParameterList name={q(n)}>{par('Id', 'int', bid)}<!-- {comment(mname)} -->",
                  '      <ParameterList name="Material">' + par("Young's Modulus", "double", repr(m["E"])) +
                  par("Poisson's Ratio", "double", repr(m["nu"])) + "</ParameterList>",
                  '      <ParameterList name="Stabilization">' + par("G", "double", repr(m["hourglass"])) + "</ParameterList>",
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
          "    " + par("Linear Solver Preset", "string", args.preset), "  </ParameterList>",
          '  <ParameterList name="Output">', "    " + par("Format", "string", "Exodus"), "  </ParameterList>",
          "</ParameterList>"]
    return "\n".join(L) + "\n"


def write_atomically(out, text):
    """Writes text to out through a temporary file in out's folder, renamed into place when complete."""
    folder = os.path.dirname(os.path.abspath(out))
    try:
        os.makedirs(folder, exist_ok=True)
    except OSError as e:
        refuse(f"cannot create the scene's folder {shown(folder, 200)}: {e.strerror}")
    try:
        fd, tmp = tempfile.mkstemp(dir=folder, prefix="." + os.path.basename(out)[:60] + ".", suffix=".partial")
    except OSError as e:
        refuse(f"cannot write the scene into {shown(folder, 200)}: {e.strerror}")
    try:
        with os.fdopen(fd, "w", encoding="utf-8") as f:
            f.write(text)
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp, 0o666 & ~umask)
        os.replace(tmp, out)
    except OSError as e:
        os.unlink(tmp)
        refuse(f"cannot write the scene {shown(out, 200)}: {e.strerror}")
    except BaseException:
        os.unlink(tmp)
        raise


class ArgumentParser(argparse.ArgumentParser):
    def error(self, message):
        self.exit(2, f"{self.prog}: {message} (usage: {self.prog} DECK.yaml [--out SCENE.xml] [--preset NAME] [--hencky])\n")


def main(argv=None):
    ap = ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("deck")
    ap.add_argument("--out", help="scene file to write (default: the deck's name with .xml, beside it)")
    ap.add_argument("--preset", default="mf-ilu", help="linear-solver preset of the scene (default mf-ilu: 3D meshes are large)")
    ap.add_argument("--hencky", action="store_true", help="finite-deformation Hencky material instead of small strain")
    args = ap.parse_args(argv)
    if not args.preset.strip() or CONTROL.search(args.preset):
        ap.error(f"--preset '{shown(args.preset)}' is empty or holds a control character")
    try:
        return convert(args)
    except Refusal as r:
        msg = str(r)
    except RecursionError:
        msg = "nests too deeply to be translated"
    except MemoryError:
        msg = "is too large to be translated (out of memory)"
    except Exception as e:  # the last guard: a sentence, never a traceback
        detail = str(e).splitlines()[0] if str(e) else ""
        msg = (f"cannot be translated: unexpected {type(e).__name__} ({shown(detail, 100)}), "
               "a fault of tools/peridigm_to_scene.py worth reporting")
    sys.stderr.write(f"{shown(args.deck, 200)}: {msg.replace(chr(10), ' ').replace(chr(13), ' ')}\n")
    return 2


if __name__ == "__main__":
    sys.exit(main())
