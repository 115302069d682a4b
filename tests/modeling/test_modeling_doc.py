"""docs/modeling.md runs: its Python blocks are executed in order, in one namespace.

The blocks assert their own key figures (closed forms, the thesis' modes 13.8 / 103.3 Hz
of Dressler (2012), eq. (6.15), the pendulum's invariants, the solver statuses), so a
change that makes the tutorial wrong fails here. Fenced blocks with a ``file=NAME`` info
(```` ```python file=two_mass.py ````, ```` ```toml file=... ````) are written to the
working folder instead of executed; the blocks run in a temporary folder.
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest

DOC = Path(__file__).resolve().parents[2] / "docs" / "modeling.md"
FENCE = re.compile(r"^```([^\n`]*)\n(.*?)^```\s*$", re.S | re.M)


def blocks(text: str) -> list[tuple[str, str, str | None]]:
    """``(language, source, file name or None)`` of every fenced block, in order."""
    out = []
    for m in FENCE.finditer(text):
        info = m.group(1).split()
        lang = info[0] if info else ""
        name = next((w.split("=", 1)[1] for w in info[1:] if w.startswith("file=")), None)
        out.append((lang, m.group(2), name))
    return out


def test_the_fence_parser_finds_code_and_file_blocks():
    # reference: a hand-written page with one of each kind of block
    text = "x\n```python\na = 1\n```\n```toml file=p.toml\nk = 1\n```\n```text\nout\n```\n"
    assert blocks(text) == [("python", "a = 1\n", None), ("toml", "k = 1\n", "p.toml"), ("text", "out\n", None)]


@pytest.mark.slow
def test_every_python_block_of_the_tutorial_runs(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr("sys.path", list(__import__("sys").path))  # the doc inserts "." into sys.path
    namespace: dict = {"__name__": "modeling_doc"}
    found = blocks(DOC.read_text(encoding="utf-8"))
    assert sum(lang == "python" and name is None for lang, _, name in found) >= 10
    for k, (lang, source, name) in enumerate(found):
        if name is not None:
            (tmp_path / name).write_text(source, encoding="utf-8")
        elif lang == "python":
            exec(compile(source, f"{DOC.name}[block {k}]", "exec"), namespace)  # noqa: S102 - our own doc
