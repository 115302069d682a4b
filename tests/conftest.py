"""Shared test configuration: headless matplotlib, paths of shipped files."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

os.environ.setdefault("MPLBACKEND", "Agg")

REPO = Path(__file__).resolve().parents[1]
PROBLEMS_DIR = REPO / "problems"
NOTEBOOKS_DIR = REPO / "notebooks"
#: The reference figures (copies of shared/reference/*.toml, see tests/reference/README.md).
SHARED_REFERENCE = REPO / "tests" / "reference"


def replace_once(old: str, new: str):
    """An edit of a shipped problem file for a table of bad inputs (fails if ``old`` is gone)."""

    def edit(text: str) -> str:
        assert old in text, f"test table out of date: {old!r} is not in the file"
        return text.replace(old, new, 1)

    return edit


@pytest.fixture(scope="session")
def repo() -> Path:
    return REPO
