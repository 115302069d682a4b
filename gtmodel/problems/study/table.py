"""A study's tidy table, built from its case folders alone (one row per case key).

Columns: the design columns, ``case``, ``key``, ``folder``, ``status``, ``wall_s``, then
every scalar top-level field of the case's ``summary.json`` (numbers, strings, booleans),
then the analysis' own columns (:meth:`~gtmodel.problems.study.analysis.StudyAnalysis.row`).
Written as ``table.parquet`` (pyarrow) and ``table.csv``, each replaced atomically.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any, Mapping, Sequence

import pandas as pd

from gtmodel.errors import ResultWriteError
from gtmodel.problems.study.analysis import StudyAnalysis
from gtmodel.problems.study.cases import CaseTask

__all__ = ["case_row", "build_table", "write_table", "FIRST_COLUMNS"]

#: The columns after the design columns, in order.
FIRST_COLUMNS = ("case", "key", "folder", "status", "wall_s")
_SKIP = {"study", "files", "overrides"}


def _scalar(v: Any) -> bool:
    return v is None or isinstance(v, (bool, int, float, str))


def case_row(task: CaseTask, summary: Mapping[str, Any], root: Path, analysis: StudyAnalysis) -> dict[str, Any]:
    """The table row of one case from its summary.

    Parameters
    ----------
    task : CaseTask
        The case (design columns, label, key, folder).
    summary : Mapping[str, Any]
        Its ``summary.json``.
    root : pathlib.Path
        The study folder (``folder`` is relative to it).
    analysis : StudyAnalysis
        Adds its columns.

    Returns
    -------
    dict
    """
    try:
        folder = str(Path(task.folder).relative_to(root))
    except ValueError:
        folder = str(task.folder)
    row: dict[str, Any] = dict(task.design)
    row.update(case=task.label, key=task.key, folder=folder, status=summary.get("status"),
               wall_s=(summary.get("study") or {}).get("wall_s"))
    for k, v in summary.items():
        if k not in row and k not in _SKIP and _scalar(v):
            row[k] = v
    for k, v in analysis.row(summary).items():
        row.setdefault(k, v)
    return row


def build_table(rows: Sequence[Mapping[str, Any]], design_columns: Sequence[str] = ()) -> pd.DataFrame:
    """A tidy table of case rows (columns in a stable order; mixed-type columns as text).

    Parameters
    ----------
    rows : sequence of Mapping
        From :func:`case_row`.
    design_columns : sequence of str, optional
        The design columns (first, even when there are no rows).

    Returns
    -------
    pandas.DataFrame
        One row per case.
    """
    order: list[str] = list(design_columns)
    for name in FIRST_COLUMNS:
        if name not in order:
            order.append(name)
    for r in rows:
        order += [k for k in r if k not in order]
    table = pd.DataFrame([{k: r.get(k) for k in order} for r in rows], columns=order)
    for name in table.columns:
        kinds = {type(v) for v in table[name] if v is not None and not (isinstance(v, float) and pd.isna(v))}
        if len(kinds) > 1 and not kinds <= {int, float}:
            table[name] = [None if v is None or (isinstance(v, float) and pd.isna(v)) else str(v) for v in table[name]]
    return table


def write_table(table: pd.DataFrame, out: Path) -> list[str]:
    """Write ``table.parquet`` and ``table.csv`` into ``out`` (each replaced atomically).

    Parameters
    ----------
    table : pandas.DataFrame
        The table.
    out : pathlib.Path
        The study folder.

    Returns
    -------
    list of str
        The file names.

    Raises
    ------
    ResultWriteError
        A file cannot be written (names it).
    """
    written = []
    for name, write in (("table.parquet", lambda p: table.to_parquet(p, index=False, engine="pyarrow")),
                        ("table.csv", lambda p: table.to_csv(p, index=False))):
        target = Path(out) / name
        tmp = Path(out) / f".{name}.{os.getpid()}"
        try:
            write(tmp)
            os.replace(tmp, target)
        except OSError as exc:
            tmp.unlink(missing_ok=True)
            raise ResultWriteError(f"cannot write {target}: {exc.strerror or exc}") from None
        written.append(name)
    return written
