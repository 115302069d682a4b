"""Cheap studies for the study engine's tests: the L1 path-constrained motion on a coarse grid.

The convex path-constrained solver takes 0.1-0.8 s per case (``method.grid`` 50..5000),
and a force limit of 60 N is infeasible at once (gravity alone needs more), so a small
design has optimal and infeasible cases.
"""

from __future__ import annotations

from pathlib import Path

from ...conftest import PROBLEMS_DIR

BASE = PROBLEMS_DIR / "l1_path_constrained.toml"


def write_base(folder: Path, grid: int = 50) -> Path:
    """A copy of l1_path_constrained.toml with ``grid`` grid points, as ``folder/base.toml``."""
    text = BASE.read_text()
    assert "grid = 500 " in text, "test fixture out of date: l1_path_constrained.toml changed its grid"
    path = folder / "base.toml"
    path.write_text(text.replace("grid = 500 ", f"grid = {grid} ", 1))
    return path


def write_study(folder: Path, design: str, header: str = "", grid: int = 50, name: str = "study") -> Path:
    """A study file ``folder/<name>.toml`` on :func:`write_base` with this ``[design]`` text."""
    write_base(folder, grid)
    path = folder / f"{name}.toml"
    path.write_text(f'base = "base.toml"\nplots = false\n{header}\n{design}\n')
    return path


#: force limits x grid: 2 infeasible (60 N) and 4 optimal cases.
SMALL_DESIGN = """
[design]
[[design.axes]]
field = "limits.force"
values = [[60.0, 60.0, 60.0], [400.0, 400.0, 400.0], [450.0, 450.0, 450.0]]
[[design.axes]]
field = "method.grid"
values = [40, 60]
"""


def grid_design(n: int, grid: int = 4000) -> str:
    """``n`` optimal cases of about ``grid / 6000`` s each (force limits 400..450 N)."""
    return f"""
[design]
[[design.axes]]
field = "limits.force"
points = {{ x = {{ start = 400.0, stop = 450.0, num = {n} }}, y = 450.0, z = 450.0 }}
[[design.axes]]
field = "method.grid"
values = [{grid}]
"""
