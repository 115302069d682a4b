"""The project's checkout, for the maintainer tools that rewrite files of it.

``python -m gtmodel.report.fidelity`` and ``python -m gtmodel.problems.fidelity_fits`` read and
write ``docs/`` and ``problems/`` of a checkout. An installed package carries neither, and its
modules live in site-packages, so these tools find the checkout from the current folder upward
(or from ``GTMODEL_REPOSITORY``), never from their own location. Run-time files of the package
are package data instead (``tests/test_packaging.py``).
"""

from __future__ import annotations

import os
from pathlib import Path

__all__ = ["checkout"]


def _is_checkout(folder: Path) -> bool:
    project = folder / "pyproject.toml"
    try:
        return project.is_file() and (folder / "docs").is_dir() and 'name = "gtmodel"' in project.read_text(encoding="utf-8")
    except OSError:
        return False


def checkout() -> Path:
    """The gtmodel checkout the maintainer tools work on.

    Returns
    -------
    pathlib.Path
        ``GTMODEL_REPOSITORY`` when set; else the first folder from the current one upward that
        holds gtmodel's ``pyproject.toml`` and ``docs/``; else the current folder (whose missing
        files the tools then name).
    """
    given = os.environ.get("GTMODEL_REPOSITORY")
    if given:
        return Path(given).resolve()
    here = Path.cwd().resolve()
    return next((folder for folder in (here, *here.parents) if _is_checkout(folder)), here)
