"""gtmodel.control is the loop controllers' one room: the former estimation paths are gone (issue 67).

Independent checks: a text scan of the sources (no import of the package under test) for
the former paths, and an import of each that fails.
"""

from __future__ import annotations

import importlib
import re
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]

#: Former path -> the module of gtmodel.control that replaces it.
MOVED = {
    "gtmodel.estimation.mpc": "gtmodel.control.mpc",
    "gtmodel.estimation.mpc_constraints": "gtmodel.control.mpc_constraints",
    "gtmodel.estimation.mpc_fatrop": "gtmodel.control.mpc_fatrop",
    "gtmodel.estimation.tracking": "gtmodel.control.tracking",
    "gtmodel.estimation.reference": "gtmodel.control.reference",
    "gtmodel.estimation.closed_loop.bounds": "gtmodel.control.bounds",
}
#: A use of a former path: dotted (imports, docs) or ``from gtmodel.estimation import mpc``.
OLD_PATH = re.compile(r"gtmodel\.estimation\.(?:mpc|mpc_constraints|mpc_fatrop|tracking|reference|closed_loop\.bounds)\b"
                      r"|from\s+gtmodel\.estimation(?:\.closed_loop)?\s+import\s+[^\n]*\b(?:mpc|mpc_constraints|mpc_fatrop|tracking|reference|bounds)\b")
#: Where code is written: every Python module, notebook and Markdown page of the project.
ROOTS = ["gtmodel", "tests", "benchmarks", "docs", "notebooks"]
#: Prose that names the former paths on purpose: this test (docs/layout.md is generated from the modules).
NAMING_THE_FORMER_PATHS = {REPO / "docs" / "layout.md", Path(__file__).resolve()}


def _sources() -> list[Path]:
    return sorted(p.resolve() for root in ROOTS if (REPO / root).is_dir() for ext in ("py", "ipynb", "md")
                  for p in (REPO / root).rglob(f"*.{ext}") if ".ipynb_checkpoints" not in p.parts)


def test_nothing_uses_the_former_paths():
    sources = _sources()
    users = [f"{p.relative_to(REPO)}: {m.group(0)}" for p in sources if p not in NAMING_THE_FORMER_PATHS
             for m in OLD_PATH.finditer(p.read_text(encoding="utf-8"))]
    assert len(sources) > 100 and users == []


def test_the_scan_finds_a_former_path():
    """The check can fail: an import of a former path is found."""
    assert OLD_PATH.search("from gtmodel.estimation.mpc import MPCController")
    assert OLD_PATH.search("from gtmodel.estimation import tracking")


@pytest.mark.parametrize(("old", "new"), MOVED.items(), ids=list(MOVED))
def test_a_former_path_is_gone_and_its_room_module_imports(old, new):
    with pytest.raises(ModuleNotFoundError, match=old.replace(".", r"\.")):
        importlib.import_module(old)
    assert importlib.import_module(new).__all__


def test_the_room_exports_its_names_lazily():
    import gtmodel.control as control

    assert control.MPCController is importlib.import_module("gtmodel.control.mpc").MPCController
    assert sorted(control.__all__) == sorted(set(control.__all__))
