"""Emitting C: one fragment protocol and one template substitution for every generated file.

Every part of a generated library (the robot functions, the controller, the KF/EKF steps,
the online re-timing) is emitted as a :class:`Fragment`: lines for the public header,
lines for the wrapper source and the declarations (:class:`~gtmodel.codegen.declarations.FunctionSpec`)
of the functions it adds. :func:`gtmodel.codegen.generate` joins the fragments in order.

Hand-written C lives in ``.c``/``.h`` template files of the package data folder
``gtmodel/codegen/harness/`` (``template_*.c``/``template_*.h``), never in Python strings;
:func:`fill` is the one substitution: ``@NAME@`` is replaced by the value given for ``NAME``
(every marker must be given a value; a marker alone on its line is a block of whole lines,
and its line goes when the block is empty). Code that depends on the declarations (the
argument checks, calls and Newton loops of each wrapper) is built line by line in Python
and enters the templates as such blocks. The modules of this subpackage:

- :mod:`~gtmodel.codegen.emit.wrapper`: the generic writer (wrapped functions, wrapper source);
- :mod:`~gtmodel.codegen.emit.robot`: the header of a robot's library;
- :mod:`~gtmodel.codegen.emit.controller`: the Kalman state and ILC sizes of the controller;
- :mod:`~gtmodel.codegen.emit.filter`: the KF/EKF state struct and its ``_init``/``_update``;
- :mod:`~gtmodel.codegen.emit.retime`: the online re-timing function.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from functools import lru_cache
from importlib import resources
from pathlib import Path
from typing import TYPE_CHECKING, Iterable, Mapping

from gtmodel._escape import c_comment, c_string
from gtmodel.errors import CodegenError

from gtmodel.codegen.declarations import STATUS_CODES

if TYPE_CHECKING:  # annotations only
    from gtmodel.codegen.declarations import FunctionSpec

__all__ = ["Fragment", "harness_dir", "template", "fill", "header_guard", "c_float"]

_MARKER = re.compile(r"@([A-Z][A-Z0-9_]*)@")
#: A marker in quotes (a C string literal: group 2) or alone (group 3).
_QUOTED_OR_MARKER = re.compile(r'("@([A-Z][A-Z0-9_]*)@")|@([A-Z][A-Z0-9_]*)@')
#: A marker alone on its line: with an empty value the whole line goes (an optional block of lines).
_BLOCK = re.compile(r"^@([A-Z][A-Z0-9_]*)@\n", re.M)
#: Start of the comment that documents a template file (not part of the emitted C).
_DOC_START = "/*@template"


@dataclass(frozen=True)
class Fragment:
    """A part of a generated library: header lines, wrapper-source lines and the functions it declares.

    Parameters
    ----------
    header : tuple of str
        Lines of the public header, placed after the function prototypes.
    source : tuple of str
        Lines appended to the wrapper source.
    specs : tuple of FunctionSpec
        Declarations of the functions the fragment adds (empty for code without a
        CasADi Function of its own).
    """

    header: tuple[str, ...] = ()
    source: tuple[str, ...] = ()
    specs: tuple["FunctionSpec", ...] = ()

    def __add__(self, other: "Fragment") -> "Fragment":
        """The two fragments one after the other."""
        return Fragment(self.header + other.header, self.source + other.source, self.specs + other.specs)

    @staticmethod
    def join(fragments: Iterable["Fragment"]) -> "Fragment":
        """The fragments one after the other (an empty fragment for none).

        Parameters
        ----------
        fragments : iterable of Fragment
            In order.

        Returns
        -------
        Fragment
            Their header lines, source lines and specs concatenated.
        """
        out = Fragment()
        for f in fragments:
            out = out + f
        return out


def harness_dir() -> Path:
    """The folder of the hand-written C shipped with the package.

    ``gtmodel/codegen/harness/`` (package data: the Makefile rules, ``unit_test.c``,
    ``loop.c``, ``retime_example.c``, the heap counter ``heap_watch.h`` they include and
    the ``template_*`` files of the emitted C), in a source checkout and after
    ``pip install .`` alike; ``codegen/Makefile`` of a source checkout includes its Makefile.

    Returns
    -------
    pathlib.Path
        The folder (it may lack files in a broken installation).
    """
    return Path(str(resources.files("gtmodel.codegen") / "harness"))


@lru_cache(maxsize=None)
def template(name: str) -> str:
    """The text of a C template file of the harness folder.

    Parameters
    ----------
    name : str
        File name, e.g. ``"template_retime.c"``.

    Returns
    -------
    str
        Its text, without the leading ``/*@template ... */`` comment that documents the
        file and its markers.

    Raises
    ------
    CodegenError
        The file is missing (a broken installation).
    """
    path = Path(str(resources.files("gtmodel.codegen") / "harness" / name))
    try:
        text = path.read_text()
    except OSError as exc:
        raise CodegenError(f"C template {path} cannot be read ({exc.strerror}): a broken installation?") from None
    if text.startswith(_DOC_START):
        text = text[text.index("*/\n") + 3:]
    return text


def fill(name: str, names: Mapping[str, str] | None = None, **values: object) -> str:
    """A C template file with its ``@NAME@`` markers replaced.

    Parameters
    ----------
    name : str
        Template file name in the harness folder (see :func:`template`).
    names : Mapping[str, str], optional
        ``NAME=text`` per marker whose value is a name or free text (a model or controller
        name, a version string holding one): where the marker stands in quotes
        (``"@NAME@"``) the quotes and marker become :func:`gtmodel._escape.c_string` of the
        text, anywhere else (comments) :func:`gtmodel._escape.c_comment` of it. Nothing a
        user wrote reaches the C any other way.
    **values : object
        C code ``NAME=value`` per marker (more are ignored: one set of values may serve a
        header and a source template); each value is inserted as ``str(value)``. A
        marker alone on its line stands for a block of lines: with an empty value the
        line is removed.

    Returns
    -------
    str
        The filled text.

    Raises
    ------
    CodegenError
        The file is missing, a marker of the file has no value, or one is given both
        as a name and as code.
    """
    text = template(name)
    names = dict(names or {})
    both = sorted(set(names) & set(values))
    missing = sorted(set(_MARKER.findall(text)) - set(values) - set(names))
    if missing or both:
        raise CodegenError(f"C template {name}: no value for the markers {missing}" if missing
                           else f"C template {name}: markers {both} given both as names and as code")
    text = _BLOCK.sub(lambda m: m.group(0) if m.group(1) in names or str(values[m.group(1)]) else "", text)

    def one(m: re.Match) -> str:
        key = m.group(2) or m.group(3)
        if key in names:
            return c_string(names[key]) if m.group(2) else c_comment(names[key])
        return f'"{values[key]}"' if m.group(2) else str(values[key])  # code (an identifier in "@GP@.h")

    return _QUOTED_OR_MARKER.sub(one, text)


def header_guard(P: str) -> tuple[str, str]:
    """The opening and the closing of a generated public header (``harness/template_header_guard.h``).

    Parameters
    ----------
    P : str
        The upper-case prefix (``GT_L1``): the guard is ``<P>_H``.

    Returns
    -------
    opening : str
        Include guard, ``extern "C"`` and the status codes shared by every library
        (:data:`~gtmodel.codegen.declarations.STATUS_CODES`), without a final newline.
    closing : str
        The end of ``extern "C"`` and of the guard, without a final newline.
    """
    text = fill("template_header_guard.h", P=P,
                STATUS_DEFINES="\n".join(f"#define {m} {v} /* {d} */" for m, (v, d) in STATUS_CODES.items()))
    opening, closing = text.split("/*@split*/\n")
    return opening.rstrip("\n"), closing.rstrip("\n")


def c_float(x: float) -> str:
    """A C double literal that reads back exactly.

    Parameters
    ----------
    x : float
        The value.

    Returns
    -------
    str
        ``repr(float(x))``, with ``.0`` added to integral values (e.g. ``"1.0"``, ``"1e-12"``).
    """
    s = repr(float(x))
    return s if any(c in s for c in ".eE") else s + ".0"
