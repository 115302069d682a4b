"""The component library under the Modelica Standard Library's class paths, for Modelica and Optimica source.

A drive written for the MSL (``Modelica.Mechanics.Rotational.Components.Inertia motor(J =
1e-4)``, ``Modelica.Electrical.Analog.Basic.RotationalEMF emf(k = 0.05)``, ``connect(emf.flange,
motor.flange_a)``) loads unchanged as far as the shipped classes go: gtmodel ships a package
``Modelica`` of its own (``modelica_library/Modelica.mo``), written from the Modelica Language
Specification and the MSL's documented interfaces (class paths, connector names ``flange_a``/
``flange_b``, ``p``/``n``, ``u``/``y``, parameter names and the equations each class's
documentation states), and adds it to the file's classes when the file names ``Modelica.``
(:func:`prepare`, :func:`extend`). What the file names under ``Modelica.`` and the package does
not hold is refused with the file, line and class (:func:`prepare`), never left to a pymoca
error without a line. The shipped classes: :func:`msl_classes` (``docs/optimica.md`` lists them). The
non-smooth ones (``ElastoBacklash``, ``Blocks.Nonlinear.Limiter``/``DeadZone``) follow the smoothed laws of
gtmodel's library with a width ``smoothing`` of quantity :data:`SMOOTHING_QUANTITY`, which the Modelica import
declares a smoothing width (so the continuation over widths runs on them).

``Modelica.Blocks.Interfaces.RealInput``/``RealOutput`` are short connector classes (``connector
RealInput = input Real``) that pymoca 0.12 drops without a word; a file's declarations of them
are read as ``input Real``/``output Real`` (the same variable, the same ``connect``), which is
what they mean; and ``Modelica.Constants.pi`` as its number (:data:`CONSTANTS`: pymoca 0.12 does not
look a constant up in another package).
"""

from __future__ import annotations

import functools
import logging
import re
from pathlib import Path
from typing import Any

from gtmodel.errors import InputError

__all__ = ["MSL_SOURCE", "CONNECTOR_TYPES", "CONSTANTS", "SMOOTHING_QUANTITY", "code_only", "msl_classes", "uses_msl", "names_library", "add_library", "prepare", "extend"]

_log = logging.getLogger("gtmodel")

#: The shipped package ``Modelica`` (Modelica source).
MSL_SOURCE = Path(__file__).parent / "modelica_library" / "Modelica.mo"
#: MSL short connector classes, read as the declarations they stand for.
CONNECTOR_TYPES = {"Modelica.Blocks.Interfaces.RealInput": "input Real", "Modelica.Blocks.Interfaces.RealOutput": "output Real"}
#: MSL constants, read as their numbers (pymoca 0.12 does not look a constant up in another package).
CONSTANTS = {"Modelica.Constants.pi": "3.14159265358979323846", "Modelica.Constants.e": "2.71828182845904523536",
             "Modelica.Constants.g_n": "9.80665"}
#: The ``quantity`` of a parameter that is a smoothing width (``parameter Real smoothing(quantity =
#: "SmoothingWidth") = 1e-5``): the shipped non-smooth classes' ``smoothing``, or a user's own; such a
#: parameter is a smoothing width of the model (``Model.smoothing``, the continuation's).
SMOOTHING_QUANTITY = "SmoothingWidth"
_COMMENT_RE = re.compile(r"//[^\n]*|/\*.*?\*/|\"(?:[^\"\\]|\\.)*\"", re.S)
_REF_RE = re.compile(r"(?<![\w.])Modelica(?:\s*\.\s*[A-Za-z_][A-Za-z0-9_]*)+")
_IMPORT_RE = re.compile(r"\bimport\s+(?:([A-Za-z_]\w*)\s*=\s*)?(Modelica(?:\s*\.\s*[A-Za-z_]\w*)*)\s*;")
_OWN_RE = re.compile(r"\b(?:package|model|class|block)\s+Modelica\b")
_CLASS_RE = re.compile(r"\b(?:package|model|block|connector|record|type|function|class)\s+([A-Za-z_]\w*)|\bend\s+([A-Za-z_]\w*)\s*;"
                       r"|\bconstant\s+Real\s+([A-Za-z_]\w*)")


def code_only(text: str) -> str:
    """The text with comments and strings blanked (newlines kept, so line numbers and offsets stay).

    Parameters
    ----------
    text : str
        Modelica source.

    Returns
    -------
    str
        Of the same length.
    """
    return _COMMENT_RE.sub(lambda m: re.sub(r"[^\n]", " ", m.group(0)), text)


@functools.lru_cache(maxsize=1)
def msl_classes() -> frozenset[str]:
    """The class paths (and constants, ``Modelica.Constants.pi``) of the shipped package, read from its source.

    Returns
    -------
    frozenset of str
        Dotted paths from ``Modelica`` on, packages included, and the names of
        :data:`CONNECTOR_TYPES`.
    """
    code = code_only(MSL_SOURCE.read_text(encoding="utf-8"))
    names: set[str] = set(CONNECTOR_TYPES) | {"Modelica.Blocks.Interfaces"}
    stack: list[str] = []
    for m in _CLASS_RE.finditer(code):
        opened, closed, constant = m.groups()
        if opened:
            if not code[max(0, m.start() - 4):m.start()].strip().endswith("end"):
                names.add(".".join([*stack, opened]))
                if not re.match(r"\s*=", code[m.end():]):  # a short class (type T = Real(...);) has no end
                    stack.append(opened)
        elif closed:
            if stack and stack[-1] == closed:
                stack.pop()
        elif constant:
            names.add(".".join([*stack, constant]))
    return frozenset(names)


def uses_msl(code: str) -> bool:
    """Whether a Modelica text names a class under ``Modelica.`` (and does not declare a package ``Modelica`` itself).

    Parameters
    ----------
    code : str
        The text (comments and strings may be blanked first).

    Returns
    -------
    bool
    """
    return names_library(code, _REF_RE, _OWN_RE)


def names_library(code: str, reference: re.Pattern[str], own: re.Pattern[str]) -> bool:
    """Whether a Modelica text refers to a shipped library's classes and does not declare that library itself.

    Parameters
    ----------
    code : str
        The text (comments and strings may be blanked first).
    reference : re.Pattern
        Finds a reference to the library's classes (``Modelica.``, ``GantryTau.``).
    own : re.Pattern
        Finds a declaration of a class of the library's name in the text.

    Returns
    -------
    bool
    """
    return bool(reference.search(code)) and not own.search(code)


def add_library(parser: Any, ast: Any, source: Path, what: str) -> None:
    """Add a shipped library's source to a parsed file's classes (pymoca's tree, in place).

    Parameters
    ----------
    parser : module
        ``pymoca.parser``.
    ast : pymoca.tree.Tree
        The file's parsed classes.
    source : pathlib.Path
        The library's ``.mo`` file, shipped as package data.
    what : str
        The library's name in the debug log.
    """
    ast.extend(parser.parse(source.read_text(encoding="utf-8")))
    _log.debug("%s classes added from %s", what, source)


def prepare(path: Path, text: str) -> str:
    """Check a file's references under ``Modelica.`` against the shipped classes, and read its MSL connectors.

    Parameters
    ----------
    path : pathlib.Path
        The file (for messages).
    text : str
        Its text.

    Returns
    -------
    str
        The text, ``Modelica.Blocks.Interfaces.RealInput``/``RealOutput`` declarations written
        as ``input Real``/``output Real`` and ``Modelica.Constants.pi`` (``e``, ``g_n``) as its number
        (:data:`CONSTANTS`; lines and the rest unchanged); the text itself when
        it names nothing under ``Modelica.`` or declares its own package ``Modelica``.

    Raises
    ------
    InputError
        ``FILE:LINE: unsupported Modelica Standard Library class NAME``: a name under
        ``Modelica.`` that the shipped package does not hold, written out or through an
        ``import`` (``import SI = Modelica.Units.SI;``, ``import Modelica.Mechanics.Rotational.Components;``
        then ``Components.LossyGear``; a wildcard import is not followed).
    """
    code = code_only(text)
    if not uses_msl(code):
        return text
    known = msl_classes()
    spans = []  # (start, end, replacement) of the references read as what they stand for
    imports = [(imp.start(), imp.end()) for imp in _IMPORT_RE.finditer(code)]
    for m, name in _references(code):
        if name not in known:
            raise _unsupported(path, code.count("\n", 0, m.start()) + 1, name, known)
        inside = next(((a, b) for a, b in imports if a <= m.start() < b), None)
        if inside is not None and (name in CONNECTOR_TYPES or name in CONSTANTS):  # an import of one: nothing left to import
            spans.append((inside[0], inside[1], re.sub(r"[^\n]", " ", text[inside[0]:inside[1]])))
        elif inside is None and (name in CONNECTOR_TYPES or name in CONSTANTS):
            spans.append((m.start(), m.end(), CONNECTOR_TYPES.get(name) or f"({CONSTANTS[name]})"))
    out, last = [], 0
    for a, b, replacement in sorted(set(spans)):
        out.append(text[last:a] + replacement)
        last = b
    return "".join(out) + text[last:]


def _references(code: str) -> list[tuple[re.Match[str], str]]:
    """Every reference to a class under ``Modelica.``: written out, or through an ``import`` of it (its dotted full name)."""
    found = [(m, re.sub(r"\s+", "", m.group())) for m in _REF_RE.finditer(code)]
    for imp in _IMPORT_RE.finditer(code):  # import A = Modelica.P; / import Modelica.P.Q; (a wildcard import is not followed)
        target = re.sub(r"\s+", "", imp.group(2))
        alias = imp.group(1) or target.rsplit(".", 1)[-1]
        for m in re.finditer(rf"(?<![\w.]){re.escape(alias)}(?:\s*\.\s*[A-Za-z_][A-Za-z0-9_]*)*(?!\w)", code):
            if imp.start() <= m.start() < imp.end():
                continue
            rest = re.sub(r"\s+", "", m.group())[len(alias):]
            found.append((m, target + rest))
    return found


def _unsupported(path: Path, line: int, name: str, known: frozenset[str]) -> InputError:
    parts = name.split(".")
    held = next(".".join(parts[:k]) for k in range(len(parts), 0, -1) if ".".join(parts[:k]) in known or k == 1)
    inside = sorted(k.rsplit(".", 1)[-1] for k in known if k.rsplit(".", 1)[0] == held)
    return InputError(f"{path}:{line}: unsupported Modelica Standard Library class {name[:200]} (gtmodel ships {len(known)} MSL "
                      f"classes under their names; {held} holds: {', '.join(inside) or 'none'}; docs/optimica.md lists them)")


def extend(parser: Any, ast: Any) -> None:
    """Add the shipped package ``Modelica`` to a parsed file's classes (pymoca's tree, in place).

    Parameters
    ----------
    parser : module
        ``pymoca.parser``.
    ast : pymoca.tree.Tree
        The file's parsed classes (without a class ``Modelica`` of their own).
    """
    add_library(parser, ast, MSL_SOURCE, "Modelica Standard Library")
