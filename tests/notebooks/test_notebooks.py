"""Execute every shipped notebook and check it is committed without outputs and checks a result.

Each notebook in ``notebooks/`` is copied to a temporary directory and executed there
(kernel ``python3``, ``MPLBACKEND=Agg``), so nothing is written into the repository. A
failing cell raises :class:`nbclient.exceptions.CellExecutionError`, whose message shows
the cell and the traceback.
"""

from __future__ import annotations

import ast
import shutil
from pathlib import Path

import pytest

nbformat = pytest.importorskip("nbformat")
nbclient = pytest.importorskip("nbclient")

REPO = Path(__file__).resolve().parents[2]
NOTEBOOKS_DIR = REPO / "notebooks"
NOTEBOOKS = sorted(NOTEBOOKS_DIR.glob("*.ipynb"))
IDS = [p.name for p in NOTEBOOKS]
#: Executed in the default run (the own-model story of README, ~10 s); the others take 8-30 s
#: each and run with the tests marked slow (``python -m pytest -m slow``, also in CI).
DEFAULT_RUN = {"10_compliant_drive_axis_from_components.ipynb"}
EXECUTE = [pytest.param(p, id=p.name, marks=() if p.name in DEFAULT_RUN else pytest.mark.slow) for p in NOTEBOOKS]


@pytest.mark.parametrize("path", NOTEBOOKS, ids=IDS)
def test_notebook_has_no_outputs(path: Path) -> None:
    nb = nbformat.read(path, as_version=4)
    dirty = [
        i
        for i, cell in enumerate(nb.cells)
        if cell.cell_type == "code" and (cell.get("outputs") != [] or cell.get("execution_count") is not None)
    ]
    assert not dirty, f"{path.name}: code cells {dirty} have outputs or an execution count; clear them before committing"


def _asserts(source: str) -> int:
    """Number of ``assert`` statements in the source of one code cell."""
    try:
        tree = ast.parse(source)
    except SyntaxError:  # IPython magics or shell escapes: not plain Python
        return 0
    return sum(isinstance(node, ast.Assert) for node in ast.walk(tree))


@pytest.mark.parametrize("path", NOTEBOOKS, ids=IDS)
def test_notebook_asserts_a_result(path: Path) -> None:
    # every notebook checks at least one key figure (against the thesis, a closed form or a
    # second method) with an ``assert`` in a code cell, so that executing it tests something
    nb = nbformat.read(path, as_version=4)
    n = sum(_asserts(cell.source) for cell in nb.cells if cell.cell_type == "code")
    assert n > 0, f"{path.name}: no assert statement in any code cell; check a key figure of the notebook"


@pytest.mark.parametrize("path", EXECUTE)
def test_notebook_executes(path: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("MPLBACKEND", "Agg")  # inherited by the kernel process
    monkeypatch.chdir(tmp_path)
    # notebooks that read shipped problem files find them here (the package may be installed
    # non-editable, away from the checkout)
    monkeypatch.setenv("GTMODEL_PROBLEMS", str(REPO / "problems"))
    copy = tmp_path / path.name
    shutil.copy(path, copy)
    nb = nbformat.read(copy, as_version=4)
    client = nbclient.NotebookClient(
        nb,
        timeout=600,
        kernel_name="python3",
        resources={"metadata": {"path": str(tmp_path)}},
    )
    client.execute()  # raises CellExecutionError on the first failing cell
    errors = [o for c in nb.cells if c.cell_type == "code" for o in c.outputs if o.output_type == "error"]
    assert not errors, f"{path.name}: cells produced errors: {[e.get('ename') for e in errors]}"
