"""Sweep study: each of the kind's table columns against the swept field.

For a study over one field (e.g. ``w``, the Table 3.1 sweep of Dressler (2012), ch. 3.5):
the kind's comparison columns (:attr:`~gtmodel.problems.base.ProblemKind.columns`, e.g.
``final_time_s`` and ``energy`` of the motion kinds) against the first numeric design
column, as a table (``sweep.csv``, ``sweep.md``) and one plot panel per column
(``sweep.png``). Cases without a solution stay in the table with their status and are
drawn as open markers.
"""

from __future__ import annotations

from typing import Any, ClassVar

import numpy as np
import pandas as pd

from gtmodel.errors import GtModelError
from gtmodel.problems.study.analyses.common import SOLVED, check_analyse_args, design_columns, status_counts
from gtmodel.problems.registry import get_kind
from gtmodel.problems.results import json_safe
from gtmodel.problems.study.analysis import StudyAnalysis
from gtmodel.report.study_plots import plot_sweep

__all__ = ["Sweep", "sweep_columns"]


def sweep_columns(table: pd.DataFrame) -> list[tuple[str, str, str]]:
    """The kind's comparison columns present in a study table.

    Parameters
    ----------
    table : pandas.DataFrame
        The study table (a ``kind`` column names the kind; without it, or for an unknown
        kind, every numeric column after ``status`` except ``wall_s``).

    Returns
    -------
    list of (str, str, str)
        ``(column, header with unit, format)`` per column.
    """
    kinds = table["kind"].dropna().astype(str).unique() if "kind" in table.columns else []
    if len(kinds) == 1:
        try:
            return [(c.key, c.header, c.fmt) for c in get_kind(kinds[0]).columns if c.key in table.columns]
        except GtModelError:
            pass
    cols = list(table.columns)
    after = cols[cols.index("status") + 1:] if "status" in cols else cols
    return [(str(c), str(c), "{:.6g}") for c in after if c != "wall_s" and pd.api.types.is_numeric_dtype(table[c])]


class Sweep(StudyAnalysis):
    """The kind's columns against the swept field (Table 3.1 style).

    Attributes
    ----------
    name : str
        ``"sweep"``.
    description : str
        One line for the documentation.
    """

    name: ClassVar[str] = "sweep"
    description: ClassVar[str] = "each of the kind's table columns against the swept field (Table 3.1 style)"

    def analyse(self, table: pd.DataFrame, out: Any, plots: bool) -> tuple[dict[str, Any], list[str]]:
        """``sweep.csv``, ``sweep.md`` and ``sweep.png`` over the first numeric design column.

        Parameters
        ----------
        table : pandas.DataFrame
            The study table (design columns before ``case``, ``status``).
        out : str or pathlib.Path
            The study folder (existing).
        plots : bool
            Write ``sweep.png``.

        Returns
        -------
        figures : dict
            ``axis`` (the swept column), ``columns`` and ``rows`` (one record per case:
            the axis value, ``status`` and the columns), ``statuses``; a ``message``
            instead when no design column is numeric.
        files : list of str

        Raises
        ------
        InputError
            A table without ``status``, ``out`` not a folder, ``plots`` not a bool.
        """
        table, folder = check_analyse_args(table, out, plots)
        figures: dict[str, Any] = {"n_cases": int(len(table)), "statuses": status_counts(table)}
        numeric = [c for c in design_columns(table) if pd.api.types.is_numeric_dtype(table[c])]
        if not numeric:
            figures["message"] = "expected a numeric design column (the swept field) before 'case'"
            return figures, []
        axis = numeric[0]
        cols = sweep_columns(table)
        solved = table["status"].astype(str).isin(SOLVED).to_numpy()
        rows = table[[axis, "status", *(c for c, _, _ in cols)]].copy()
        for c, _, _ in cols:  # a value without a solution is not a figure
            rows[c] = pd.to_numeric(rows[c], errors="coerce").where(solved)
        rows = rows.sort_values(axis, kind="stable")
        rows.to_csv(folder / "sweep.csv", index=False)
        (folder / "sweep.md").write_text(_markdown(rows, axis, cols), encoding="utf-8")
        figures.update(axis=axis, columns=[c for c, _, _ in cols], rows=rows.to_dict(orient="records"))
        files = ["sweep.csv", "sweep.md"]
        if plots and cols:
            plot_sweep(axis, pd.to_numeric(table[axis]).to_numpy(dtype=float),
                       {h: pd.to_numeric(table[c], errors="coerce").to_numpy(dtype=float) for c, h, _ in cols},
                       folder / "sweep.png", solved=solved)
            files.append("sweep.png")
        return json_safe(figures), files


def _markdown(rows: pd.DataFrame, axis: str, cols: list[tuple[str, str, str]]) -> str:
    """A Markdown table of the sweep (the formats of the kind's columns)."""
    head = [axis, "status", *(h for _, h, _ in cols)]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for _, r in rows.iterrows():
        vals = [f"{r[axis]:g}" if isinstance(r[axis], (int, float, np.number)) else str(r[axis]), str(r["status"])]
        vals += ["-" if pd.isna(r[c]) else f.format(r[c]) for c, _, f in cols]
        lines.append("| " + " | ".join(vals) + " |")
    return "\n".join(lines) + "\n"
