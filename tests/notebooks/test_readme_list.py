"""notebooks/README.md lists exactly the notebooks of the folder (docs/notebooks.md points to it, counting none)."""

from __future__ import annotations

import re

from ..conftest import NOTEBOOKS_DIR

ROW = re.compile(r"^\| `([^`]+\.ipynb)` \|", re.M)


def listed(text: str) -> list[str]:
    return ROW.findall(text)


def test_the_list_names_every_notebook_once():
    names = listed((NOTEBOOKS_DIR / "README.md").read_text(encoding="utf-8"))
    assert sorted(names) == sorted(p.name for p in NOTEBOOKS_DIR.glob("*.ipynb"))
    assert len(names) == len(set(names))


def test_a_row_is_found_and_a_missing_one_would_show():
    """The check above can fail: the pattern reads the table's rows, not prose mentions."""
    text = "| notebook | what it shows |\n|---|---|\n| `01_a.ipynb` | x, see `02_b.ipynb` |\n| `03_c.ipynb` | y |\n"
    assert listed(text) == ["01_a.ipynb", "03_c.ipynb"]
