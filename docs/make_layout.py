"""Write the module table of docs/layout.md from the modules' own docstrings.

Run ``python docs/make_layout.py`` after adding, moving or renaming a module of
``gtmodel/``; ``tests/test_docs_layout.py`` fails while the table is out of date. Each
line is a module's path and the first sentence of its docstring, so the table says what
the code says.
"""

from __future__ import annotations

import ast
import re
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
LAYOUT = REPO / "docs" / "layout.md"
BEGIN, END = "<!-- modules: begin (python docs/make_layout.py) -->", "<!-- modules: end -->"


def summary(path: Path) -> str:
    """The first sentence of a module's docstring, on one line."""
    doc = ast.get_docstring(ast.parse(path.read_text(encoding="utf-8"))) or ""
    first = " ".join(doc.strip().split("\n\n")[0].split())
    return re.split(r"(?<=\.)\s", first, maxsplit=1)[0].rstrip(".") if first else ""


def module_table() -> str:
    """The Markdown table of every module of ``gtmodel/``, grouped by package."""
    lines = [BEGIN, "", "| module | its job |", "|---|---|"]
    for path in sorted((REPO / "gtmodel").rglob("*.py")):
        rel = path.relative_to(REPO).as_posix()
        lines.append(f"| `{rel}` | {summary(path).replace('|', '/')} |")
    return "\n".join([*lines, "", END])


def updated(text: str) -> str:
    """``text`` with the table between the markers replaced by :func:`module_table`."""
    head, _, rest = text.partition(BEGIN)
    _, _, tail = rest.partition(END)
    return head + module_table() + tail


if __name__ == "__main__":
    LAYOUT.write_text(updated(LAYOUT.read_text(encoding="utf-8")), encoding="utf-8")
