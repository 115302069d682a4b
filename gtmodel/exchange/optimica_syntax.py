"""The Optimica layer of a ``.mop`` file: its tokens and the ``optimization`` class's own parts.

Optimica (Akesson 2008; JModelica.org's dialect) adds to Modelica a class kind
``optimization`` with the class modifiers ``objective``, ``objectiveIntegrand``,
``startTime`` and ``finalTime(free, initialGuess, min, max)``, a ``constraint`` section, the
timed variables ``x(finalTime)`` and the attributes ``free`` and ``initialGuess``. pymoca
parses Modelica only, so this module takes the Optimica parts out with a tokenizer (never
``eval``): :func:`split_optimica` finds the class, reads its header modifiers and its
``constraint`` section, and returns the source with those parts blanked (newlines kept, so
every line number pymoca reports is the file's) and ``optimization`` written ``model``.
:class:`~gtmodel.exchange.optimica_expr.ExprParser` parses the expressions into CasADi SX
over the same tokens. Every error is an :class:`OptimicaError` naming the file, the line
and the construct.

Hostile input is refused before any work: a file over :data:`MAX_BYTES`, more than
:data:`MAX_TOKENS` tokens, parentheses nested deeper than :data:`MAX_DEPTH`, a quoted
identifier (``'any text'``, which could carry any character into generated code), a
character outside Modelica's ASCII syntax, or a name longer than :data:`MAX_NAME` characters.
Names that pass are ``[A-Za-z_][A-Za-z0-9_]*`` (dotted), safe as C identifiers once the
dots are mapped, and are validated again where generated code names them.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from pathlib import Path

from gtmodel.errors import InputError

__all__ = ["CLASS_NAME_RE", "OptimicaError", "Token", "Modifier", "OptimicaClass", "tokenize", "split_optimica",
           "MAX_BYTES", "MAX_TOKENS", "MAX_DEPTH", "MAX_NAME"]

#: Largest ``.mop`` file read, bytes (JModelica.org's examples are a few kB).
MAX_BYTES = 2_000_000
#: Most tokens in a file.
MAX_TOKENS = 400_000
#: Deepest nesting of parentheses, brackets and braces (and of an expression's operators).
MAX_DEPTH = 64
#: Longest name (one identifier), characters.
MAX_NAME = 100

_TOKEN_RE = re.compile(r"""
    (?P<ws>[ \t\r\n\f]+)
  | (?P<comment>//[^\n]*|/\*.*?\*/)
  | (?P<string>"(?:[^"\\]|\\.)*")
  | (?P<quoted>'(?:[^'\\]|\\.)*')
  | (?P<number>(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)
  | (?P<ident>[A-Za-z_][A-Za-z0-9_]*)
  | (?P<op>\.\^|\.\*|\./|\.\+|\.-|<=|>=|==|<>|:=|[-+*/^<>=()\[\]{},;:.])
""", re.X | re.S)
_CLASS_KINDS = frozenset({"model", "block", "class", "package", "connector", "record", "function", "type", "optimization",
                          "operator"})
_SECTIONS = frozenset({"equation", "algorithm", "public", "protected", "constraint", "initial", "annotation"})
#: A class name given on the command line: dotted identifiers, nothing else (it names the result folder).
CLASS_NAME_RE = re.compile(r"[A-Za-z_][A-Za-z0-9_]{0,99}(?:\.[A-Za-z_][A-Za-z0-9_]{0,99}){0,31}")
#: Header modifiers of an ``optimization`` class that gtmodel maps (Optimica, Akesson 2008, section 3).
HEADER_KEYS = ("objective", "objectiveIntegrand", "startTime", "finalTime")


class OptimicaError(InputError):
    """A ``.mop`` file gtmodel cannot read: the message names the file, the line and the construct."""


@dataclass(frozen=True)
class Token:
    """One token of a Modelica/Optimica text.

    Parameters
    ----------
    kind : {"ident", "number", "string", "op"}
        What it is.
    text : str
        Its text.
    start, end : int
        Its character offsets in the file.
    line : int
        Its line, from 1.
    """

    kind: str
    text: str
    start: int
    end: int
    line: int


@dataclass
class Modifier:
    """One modification ``name(sub...) = value`` of a modifier list.

    Parameters
    ----------
    name : str
        The modified name (``finalTime``, ``free``, ``robot.m``).
    line : int
        Its line, from 1.
    subs : dict of str to Modifier, optional
        Its own modifications (``finalTime(free = true)``).
    value : list of Token or None, optional
        The tokens of the expression after ``=``; None without one.
    """

    name: str
    line: int
    subs: dict[str, "Modifier"] = field(default_factory=dict)
    value: list[Token] | None = None


@dataclass
class OptimicaClass:
    """The Optimica parts of one ``optimization`` class (see :func:`split_optimica`).

    Parameters
    ----------
    name : str
        The dotted class name (``"Pkg.Opt"``).
    line : int
        The line of its ``optimization`` keyword.
    header : dict of str to Modifier
        The class modifiers (``objective``, ``finalTime``, ...).
    constraints : list of list of Token
        The statements of its ``constraint`` sections, without the ``;``.
    attributes : dict of str to Modifier
        The declarations of the class with an Optimica attribute (``free``,
        ``initialGuess``): the component path (``"p"``, ``"robot.m"``) -> its modifier list.
    model_text : str
        The file's text with the Optimica parts blanked and the class written as a ``model``.
    """

    name: str
    line: int
    header: dict[str, Modifier]
    constraints: list[list[Token]]
    attributes: dict[str, Modifier]
    model_text: str


def tokenize(path: Path, text: str) -> list[Token]:
    """The tokens of a Modelica/Optimica text (comments and white space dropped).

    Parameters
    ----------
    path : pathlib.Path
        The file (for messages).
    text : str
        Its contents.

    Returns
    -------
    list of Token

    Raises
    ------
    OptimicaError
        A file over :data:`MAX_BYTES` or :data:`MAX_TOKENS`, a quoted identifier, a name over
        :data:`MAX_NAME` characters, an unterminated comment or string, or a character that is
        not Modelica syntax (naming the line).
    """
    if len(text.encode("utf-8", errors="replace")) > MAX_BYTES:
        raise OptimicaError(f"{path}: file too large ({len(text)} characters; at most {MAX_BYTES} bytes are read)")
    out: list[Token] = []
    pos, line, n, depth = 0, 1, len(text), 0
    while pos < n:
        m = _TOKEN_RE.match(text, pos)
        if m is None:
            what = "unterminated comment" if text.startswith("/*", pos) else "unterminated string" if text[pos] == '"' else \
                f"character {text[pos]!r} is not Modelica syntax"
            raise OptimicaError(f"{path}:{line}: {what}")
        kind = m.lastgroup or ""
        if kind == "quoted":
            raise OptimicaError(f"{path}:{line}: unsupported construct: quoted identifier {m.group()[:40]!r} "
                                "(names are [A-Za-z_][A-Za-z0-9_]*)")
        if kind == "ident" and len(m.group()) > MAX_NAME:
            raise OptimicaError(f"{path}:{line}: name too long ({len(m.group())} characters, at most {MAX_NAME})")
        if kind == "op" and m.group() in ("(", "[", "{"):
            depth += 1
            if depth > MAX_DEPTH:
                raise OptimicaError(f"{path}:{line}: nesting deeper than {MAX_DEPTH} levels of brackets")
        elif kind == "op" and m.group() in (")", "]", "}"):
            depth -= 1
        if kind in ("ident", "number", "string", "op"):
            out.append(Token(kind, m.group(), pos, m.end(), line))
            if len(out) > MAX_TOKENS:
                raise OptimicaError(f"{path}:{line}: file too large (more than {MAX_TOKENS} tokens)")
        line += m.group().count("\n")
        pos = m.end()
    return out


def _blank(chars: list[str], a: int, b: int) -> None:
    for i in range(a, b):
        if chars[i] != "\n":
            chars[i] = " "


class _Cursor:
    """Token stream helpers with the file name for messages."""

    def __init__(self, path: Path, toks: list[Token]) -> None:
        self.path, self.toks = path, toks

    def fail(self, tok: Token | None, what: str) -> OptimicaError:
        line = tok.line if tok is not None else (self.toks[-1].line if self.toks else 1)
        return OptimicaError(f"{self.path}:{line}: {what}")

    def closing(self, i: int) -> int:
        """Index of the token closing the bracket at ``i`` (depth-limited)."""
        depth = 0
        for j in range(i, len(self.toks)):
            t = self.toks[j].text
            if t in "([{" and self.toks[j].kind == "op":
                depth += 1
                if depth > MAX_DEPTH:
                    raise self.fail(self.toks[j], f"nesting deeper than {MAX_DEPTH} levels")
            elif t in ")]}" and self.toks[j].kind == "op":
                depth -= 1
                if depth == 0:
                    return j
        raise self.fail(self.toks[i], f"unbalanced {self.toks[i].text!r}")

    def modifiers(self, i: int, j: int) -> dict[str, Modifier]:
        """The modifier list between the brackets at ``i`` and ``j``: ``name(sub) = value, ...``."""
        out: dict[str, Modifier] = {}
        k = i + 1
        while k < j:
            t = self.toks[k]
            while t.text in ("each", "final", "redeclare", "replaceable") and k + 1 < j:
                k += 1
                t = self.toks[k]
            if t.kind != "ident":
                raise self.fail(t, f"unsupported construct in a modification: {t.text!r}")
            name, k = t.text, k + 1
            while k < j and self.toks[k].text == "." and k + 1 < j and self.toks[k + 1].kind == "ident":
                name += "." + self.toks[k + 1].text
                k += 2
            mod = Modifier(name, t.line)
            if k < j and self.toks[k].text == "(":
                close = self.closing(k)
                mod.subs = self.modifiers(k, close)
                k = close + 1
            if k < j and self.toks[k].text == "=":
                end = k + 1
                while end < j and self.toks[end].text != ",":
                    end = self.closing(end) + 1 if self.toks[end].text in "([{" and self.toks[end].kind == "op" else end + 1
                mod.value = self.toks[k + 1:end]
                if not mod.value:
                    raise self.fail(self.toks[k], f"modification {name} = without a value")
                k = end
            while k < j and self.toks[k].kind == "string":  # a description string
                k += 1
            if k < j and self.toks[k].text != ",":
                raise self.fail(self.toks[k], f"unexpected {self.toks[k].text!r} in the modification of {name}")
            out[name] = mod
            k += 1
        return out


def _classes(cur: _Cursor) -> list[tuple[str, str, int, int]]:
    """(kind, dotted name, index of the kind keyword, index of the ``end``) of every long class definition."""
    toks, stack, out = cur.toks, [], []
    for i, t in enumerate(toks):
        if t.kind != "ident":
            continue
        if t.text == "end" and i + 2 < len(toks) and toks[i + 1].kind == "ident" and toks[i + 2].text == ";":
            if toks[i + 1].text in ("if", "for", "when", "while"):
                continue
            if not stack or stack[-1][1] != toks[i + 1].text:
                raise cur.fail(t, f"'end {toks[i + 1].text};' does not close the open class"
                               + (f" {stack[-1][1]!r}" if stack else ""))
            kind, name, at = stack.pop()
            out.append((kind, ".".join([s[1] for s in stack] + [name]), at, i))
        elif t.text in _CLASS_KINDS and i + 1 < len(toks) and toks[i + 1].kind == "ident" and (i == 0 or toks[i - 1].text != "end"):
            nxt = toks[i + 2].text if i + 2 < len(toks) else ""
            if nxt == "=":  # a short class definition: type T = Real(...);
                continue
            if t.text == "operator" and toks[i + 1].text in ("function", "record"):
                continue
            stack.append((t.text, toks[i + 1].text, i))
            if len(stack) > MAX_DEPTH:
                raise cur.fail(t, f"classes nested deeper than {MAX_DEPTH} levels")
    if stack:
        raise cur.fail(toks[stack[-1][2]], f"class {stack[-1][1]!r} has no 'end {stack[-1][1]};'")
    return out


def split_optimica(path: Path, text: str, class_name: str) -> OptimicaClass:
    """Take the Optimica parts out of ``text`` for the ``optimization`` class ``class_name``.

    Parameters
    ----------
    path : pathlib.Path
        The file (for messages).
    text : str
        Its contents.
    class_name : str
        The dotted name of the ``optimization`` class (``"Pkg.Opt"``; a bare name matches a
        unique class of that name in a package).

    Returns
    -------
    OptimicaClass
        Its header modifiers, constraint statements, Optimica attributes and the text for pymoca.

    Raises
    ------
    OptimicaError
        Hostile or malformed input (:func:`tokenize`), no such ``optimization`` class, an
        unknown header modifier, a ``constraint`` section outside it, or Optimica constructs
        gtmodel does not map (naming the line).
    """
    if not CLASS_NAME_RE.fullmatch(class_name or ""):
        raise OptimicaError(f"{path}: class name {str(class_name)[:60]!r} is not a dotted Modelica name "
                            "(Pkg.Opt, [A-Za-z_][A-Za-z0-9_]* parts)")
    toks = tokenize(path, text)
    cur = _Cursor(path, toks)
    classes = _classes(cur)
    opts = [c for c in classes if c[0] == "optimization"]
    found = [c for c in opts if c[1] == class_name] or [c for c in opts if c[1].split(".")[-1] == class_name]
    if len(found) != 1:
        names = ", ".join(sorted(c[1] for c in opts)) or "none"
        what = "is ambiguous" if found else "not found"
        raise OptimicaError(f"{path}: optimization class {class_name!r} {what} (optimization classes in the file: {names})")
    _, full, at, end = found[0]
    chars = list(text)
    kw = toks[at]
    chars[kw.start:kw.end] = list("model".ljust(len("optimization")))
    for kind, _, a, e in classes:  # another optimization class: blanked (pymoca would refuse the keyword)
        if kind == "optimization" and a != at:
            _blank(chars, toks[a].start, toks[e + 2].end)
    inner = [(a, e) for k, n, a, e in classes if a > at and e < end]
    header: dict[str, Modifier] = {}
    k = at + 2
    if k < end and toks[k].text == "(":
        close = cur.closing(k)
        header = cur.modifiers(k, close)
        _blank(chars, toks[k].start, toks[close].end)
        k = close + 1
    for key, mod in header.items():
        if key not in HEADER_KEYS:
            raise OptimicaError(f"{path}:{mod.line}: unsupported Optimica class modifier {key!r} of {full} (supported: {', '.join(HEADER_KEYS)})")
    constraints: list[list[Token]] = []
    attributes: dict[str, Modifier] = {}
    i = k
    while i < end:
        t = toks[i]
        if any(a <= i <= e for a, e in inner):
            i += 1
            continue
        if t.kind == "ident" and t.text == "constraint":
            j = i + 1
            while j < end and not (toks[j].kind == "ident" and toks[j].text in _SECTIONS
                                   and not any(a <= j <= e for a, e in inner)):
                j += 1
            constraints.extend(_statements(cur, i + 1, j))
            _blank(chars, t.start, toks[j - 1].end if j > i + 1 else t.end)
            i = j
            continue
        if t.kind == "ident" and t.text in ("free", "initialGuess") and i + 1 < end and toks[i + 1].text == "=":
            path_, mods = _owner(cur, i, at)
            attributes[path_] = mods
        i += 1
    others = [(a, e) for kind, _, a, e in classes if kind == "optimization" and a != at]  # blanked above
    for kind, name, a, e in classes:  # Optimica outside the class: refused, not silently dropped by pymoca
        if a <= at <= e or any(oa <= a and e <= oe for oa, oe in others):
            continue
        for j in range(a, e):
            if toks[j].kind == "ident" and toks[j].text == "constraint" and not (at <= j <= end):
                raise cur.fail(toks[j], f"unsupported construct: a constraint section in {kind} {name} (only in the "
                                        "optimization class solved)")
            if (toks[j].kind == "ident" and toks[j].text in ("free", "initialGuess") and toks[j + 1].text == "="
                    and toks[j - 1].text in ("(", ",") and not (at <= j <= end)):
                raise cur.fail(toks[j], f"unsupported construct: Optimica attribute {toks[j].text!r} in {kind} {name} (pymoca "
                                        "would drop it; set it in the optimization class, e.g. extends M(p(free = true)))")
    return OptimicaClass(full, kw.line, header, constraints, attributes, "".join(chars))


def _statements(cur: _Cursor, a: int, b: int) -> list[list[Token]]:
    """The ``;``-separated statements of tokens ``a..b`` (``for`` loops and ``if`` refused)."""
    out, stmt, depth = [], [], 0
    for k in range(a, b):
        t = cur.toks[k]
        if t.kind == "ident" and t.text in ("for", "if", "when", "while", "loop") and depth == 0:
            raise cur.fail(t, f"unsupported construct in a constraint section: {t.text!r} (one constraint per statement)")
        if t.kind == "op" and t.text in "([{":
            depth += 1
        elif t.kind == "op" and t.text in ")]}":
            depth -= 1
        if t.text == ";" and depth == 0:
            if stmt:
                out.append(stmt)
            stmt = []
        else:
            stmt.append(t)
    if stmt:
        raise cur.fail(stmt[0], "constraint without a closing ';'")
    return out


def _owner(cur: _Cursor, i: int, floor: int) -> tuple[str, Modifier]:
    """The component path and modifier list owning the attribute at token ``i`` (``p(free = true)``)."""
    toks, path, k, inner = cur.toks, [], i, None
    while True:
        depth = 0
        k -= 1
        while k > floor and not (toks[k].text == "(" and depth == 0):
            depth += toks[k].text == ")"
            depth -= toks[k].text == "(" and depth > 0
            if toks[k].text == ";" and depth == 0:
                raise cur.fail(toks[i], f"unsupported construct: Optimica attribute {toks[i].text!r} outside a modification")
            k -= 1
        if k <= floor or toks[k - 1].kind != "ident":
            raise cur.fail(toks[i], f"unsupported construct: Optimica attribute {toks[i].text!r} outside a declaration")
        mods = cur.modifiers(k, cur.closing(k))
        inner = inner or mods
        owner, before = toks[k - 1].text, toks[k - 2] if k >= 2 else None
        if before is not None and before.text == "extends":
            break
        path.insert(0, owner)
        if before is not None and before.text != "," and before.text != "(":
            # a declaration "Type name(" (or "Type name[n]("): the component name is the owner
            break
        k -= 1
    name = ".".join(path)
    return name, Modifier(name, toks[i].line, subs=inner)
