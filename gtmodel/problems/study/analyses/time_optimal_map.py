"""Time-optimal map study: minimum motion time from one start to a grid of end positions.

The study's design has a ``points`` axis over a motion's end position (design columns
``<field>.x``, ``<field>.y``, ``<field>.z``, e.g. ``motion.end.x``): a section of the
workspace where two coordinates vary and the third is fixed. Each case is a
``point_to_point`` (or any motion kind's) solve with a ``final_time_s`` in its summary.

:meth:`TimeOptimalMap.analyse` classifies every cell (:func:`cell_class`): ``solved``
(its minimum time is mapped), ``infeasible`` (no motion within the limits),
``outside`` (the end position was rejected before solving: outside the workspace or not
assembled, status ``invalid_input``) or ``failed`` (iteration limit, solver or internal
error); writes ``map.csv`` and the map plot (axes in m, colour bar in s, the cells
without a time marked, the start marked when it lies in the section).
"""

from __future__ import annotations

import tomllib
from pathlib import Path
from typing import Any, ClassVar, Mapping

import numpy as np
import pandas as pd

from gtmodel.problems.study.analyses.common import SOLVED, check_analyse_args, design_columns, status_counts
from gtmodel.problems.results import json_safe
from gtmodel.problems.study.analysis import StudyAnalysis
from gtmodel.report.study_plots import plot_time_map

__all__ = ["TimeOptimalMap", "cell_class", "point_axes"]


def cell_class(status: str) -> str:
    """Map class of a case's status.

    Parameters
    ----------
    status : str
        The case's status.

    Returns
    -------
    str
        ``"solved"`` (statuses in :data:`~gtmodel.problems.study.analyses.common.SOLVED`),
        ``"infeasible"``, ``"outside"`` (``invalid_input``: rejected when loading, e.g.
        outside the workspace) or ``"failed"``.
    """
    s = str(status)
    return "solved" if s in SOLVED else "infeasible" if s == "infeasible" else "outside" if s == "invalid_input" else "failed"


def point_axes(table: pd.DataFrame) -> tuple[str, list[str], list[str]]:
    """The points field of a study table and which of its coordinates vary.

    Parameters
    ----------
    table : pandas.DataFrame
        The study table (design columns before ``case``).

    Returns
    -------
    field : str
        The dotted field (e.g. ``"motion.end"``); ``""`` if the design has no points axis.
    varying : list of str
        Coordinate columns with more than one value (e.g. ``["motion.end.x", "motion.end.y"]``).
    fixed : list of str
        Coordinate columns with one value.
    """
    cols = design_columns(table) or [str(c) for c in table.columns]
    for c in cols:
        if c.endswith(".x") and f"{c[:-2]}.y" in cols and f"{c[:-2]}.z" in cols:
            field = c[:-2]
            coords = [f"{field}.{a}" for a in "xyz"]
            varying = [k for k in coords if table[k].nunique(dropna=True) > 1]
            return field, varying, [k for k in coords if k not in varying]
    return "", [], []


def _start(table: pd.DataFrame, field: str) -> list[float] | None:
    """The motion's start position from the base problem file (``motion.start``), if readable."""
    if "problem" not in table.columns or not len(table) or not field.endswith(".end"):
        return None
    try:
        doc = tomllib.loads(Path(str(table["problem"].iloc[0])).read_text(encoding="utf-8"))
        node: Any = doc
        for part in field[: -len(".end")].split(".") + ["start"]:
            node = node[part]
        start = [float(v) for v in node]
    except (OSError, KeyError, TypeError, ValueError, tomllib.TOMLDecodeError):
        return None
    return start if len(start) == 3 else None


class TimeOptimalMap(StudyAnalysis):
    """Map of the minimum motion time over a grid of end positions (a workspace section).

    Attributes
    ----------
    name : str
        ``"time_optimal_map"``.
    description : str
        One line for the documentation.
    """

    name: ClassVar[str] = "time_optimal_map"
    description: ClassVar[str] = "minimum time from one start to a grid of end positions: a map with the cells without a solution marked"

    def row(self, summary: Mapping[str, Any]) -> dict[str, Any]:
        """The cell's map class (see :func:`cell_class`).

        Parameters
        ----------
        summary : Mapping[str, Any]
            The case's ``summary.json``.

        Returns
        -------
        dict
            ``{"cell": class}``.
        """
        return {"cell": cell_class(summary.get("status", "error") if isinstance(summary, Mapping) else "error")}

    def analyse(self, table: pd.DataFrame, out: Any, plots: bool) -> tuple[dict[str, Any], list[str]]:
        """Counts per cell class, the fastest and slowest cells, ``map.csv`` and ``time_map.png``.

        Parameters
        ----------
        table : pandas.DataFrame
            The study table: ``status``, ``final_time_s`` and a points axis' three
            design columns.
        out : str or pathlib.Path
            The study folder (existing).
        plots : bool
            Write ``time_map.png``.

        Returns
        -------
        figures : dict
            ``field``, ``plane`` (the two varying columns) and ``section`` (the fixed
            one and its value), ``cells`` per class, ``min_time_s``/``max_time_s`` with
            their end positions, ``statuses``; a ``message`` instead when the design is
            not a section.
        files : list of str

        Raises
        ------
        InputError
            A table without ``status`` or ``final_time_s``, ``out`` not a folder,
            ``plots`` not a bool.
        """
        table, folder = check_analyse_args(table, out, plots, ("status", "final_time_s"))
        field, varying, fixed = point_axes(table)
        figures: dict[str, Any] = {"n_cases": int(len(table)), "statuses": status_counts(table), "field": field or None}
        if len(varying) != 2:
            figures["message"] = (f"expected a section: a points axis with two varying coordinates, got {len(varying)}"
                                  if field else "expected a points axis over a motion's end position (columns <field>.x/.y/.z)")
            return figures, []
        cls = table["status"].astype(str).map(cell_class)
        t = pd.to_numeric(table["final_time_s"], errors="coerce").where(cls == "solved")
        cells = pd.DataFrame({c: pd.to_numeric(table[c], errors="coerce") for c in (*varying, *fixed)})
        cells["status"], cells["cell"], cells["final_time_s"] = table["status"].astype(str).to_numpy(), cls.to_numpy(), t.to_numpy()
        cells.to_csv(folder / "map.csv", index=False)
        figures.update(plane=varying, section={c: float(cells[c].iloc[0]) for c in fixed},
                       cells={k: int((cls == k).sum()) for k in ("solved", "infeasible", "outside", "failed")})
        if t.notna().any():
            for label, i in (("min", t.idxmin()), ("max", t.idxmax())):
                figures[f"{label}_time_s"] = float(t[i])
                figures[f"{label}_time_end"] = [float(cells.loc[i, c]) for c in (f"{field}.x", f"{field}.y", f"{field}.z")]
        files = ["map.csv"]
        if plots:
            start = _start(table, field)
            axes = [c[-1] for c in varying]
            in_plane = start is not None and all(abs(start["xyz".index(c[-1])] - cells[c].iloc[0]) < 1e-9 for c in fixed)
            plot_time_map(cells[varying[0]], cells[varying[1]], t.to_numpy(dtype=float), list(cls), folder / "time_map.png",
                          labels=(f"{axes[0]} [m]", f"{axes[1]} [m]"),
                          start=None if start is None else (start["xyz".index(axes[0])], start["xyz".index(axes[1])]),
                          start_label="start" if in_plane else "start (projected: " + ", ".join(
                              f"{c[-1]} = {start['xyz'.index(c[-1])]:g} m" for c in fixed) + ")",
                          title=f"minimum time to {field} ({', '.join(f'{c[-1]} = {cells[c].iloc[0]:g} m' for c in fixed)})"
                          + ("" if start is None else f", start {tuple(round(v, 3) for v in start)} m"))
            files.append("time_map.png")
        return json_safe(figures), files
