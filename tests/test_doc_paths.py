"""Every dotted ``gtmodel....`` path the docs, README and notebooks name still resolves.

Modules move between rooms (issue 24); the paths users read must keep working. Each path
is resolved as its longest importable module prefix followed by attributes, the way
``from MODULE import NAME`` or ``MODULE.NAME`` in a user's code would find it.
"""

from __future__ import annotations

import importlib
import re

import pytest

from .conftest import REPO

SOURCES = [REPO / "README.md", REPO / "codegen" / "README.md", *sorted((REPO / "docs").glob("*.md")),
           *sorted((REPO / "notebooks").glob("*.ipynb")), REPO / "notebooks" / "README.md"]
#: A dotted name not followed by ``/`` (``"gtmodel.controller/1"`` is a file format's name, not a path).
PATH_RE = re.compile(r"\bgtmodel(?:\.[A-Za-z_][A-Za-z0-9_]*)+(?![\w/])")
#: Placeholders of the prose (``from gtmodel.PACKAGE import NAME``), not paths.
PLACEHOLDERS = {"gtmodel.PACKAGE"}
PATHS = sorted({m.group(0) for src in SOURCES for m in PATH_RE.finditer(src.read_text(encoding="utf-8"))} - PLACEHOLDERS)


def resolve(path: str) -> object:
    """The object a dotted path names: its longest importable module, then attributes."""
    parts = path.split(".")
    for i in range(len(parts), 0, -1):
        try:
            obj = importlib.import_module(".".join(parts[:i]))
        except ModuleNotFoundError:
            continue
        for name in parts[i:]:
            obj = getattr(obj, name)
        return obj
    raise ModuleNotFoundError(path)


def test_the_docs_name_gtmodel_paths():
    assert len(PATHS) > 50


@pytest.mark.parametrize("path", PATHS)
def test_a_path_the_docs_show_resolves(path):
    resolve(path)


def test_a_moved_name_does_not_resolve():
    """The check can fail: a name that is not there raises."""
    with pytest.raises(AttributeError):
        resolve("gtmodel.problems.no_such_name")
