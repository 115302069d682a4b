"""Shared test configuration: headless matplotlib, paths of shipped files."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

os.environ.setdefault("MPLBACKEND", "Agg")

REPO = Path(__file__).resolve().parents[1]
PROBLEMS_DIR = REPO / "problems"
NOTEBOOKS_DIR = REPO / "notebooks"
SHARED_REFERENCE = REPO.parent / "shared" / "reference"


@pytest.fixture(scope="session")
def repo() -> Path:
    return REPO
