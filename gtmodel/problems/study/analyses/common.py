"""Checks and table helpers shared by the study analyses.

The study table (:mod:`gtmodel.problems.study.analysis`) holds the design columns first,
then ``case``, ``key``, ``folder``, ``status``, ``wall_s``, the kind's scalar summary
fields and the analysis' own columns. The helpers here check that layout once, so every
analysis fails on a malformed table with one :class:`~gtmodel.errors.InputError` naming
the argument and what was expected.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any, Iterable

import numpy as np
import pandas as pd

from gtmodel.errors import InputError

__all__ = ["SOLVED", "check_analyse_args", "design_columns", "solved_rows", "finite_or_none", "status_counts"]

#: Statuses whose figures a study analysis uses (a solution; ``acceptable``: a solver
#: stopped at its acceptable tolerance, still a solution to report).
SOLVED = ("optimal", "converged", "completed", "acceptable")


def check_analyse_args(table: Any, out: Any, plots: Any, required: Iterable[str] = ("status",)) -> tuple[pd.DataFrame, Path]:
    """The arguments of :meth:`StudyAnalysis.analyse`, checked up front.

    Parameters
    ----------
    table : Any
        Expected: a pandas.DataFrame with the ``required`` columns.
    out : Any
        Expected: an existing folder (str or pathlib.Path).
    plots : Any
        Expected: a bool.
    required : iterable of str, optional
        Column names the table must have.

    Returns
    -------
    table : pandas.DataFrame
    out : pathlib.Path

    Raises
    ------
    InputError
        A table that is not a DataFrame or misses a required column; ``out`` not an
        existing folder; ``plots`` not a bool.
    """
    if not isinstance(table, pd.DataFrame):
        raise InputError(f"table: expected a pandas.DataFrame of study cases, got {type(table).__name__}")
    missing = [c for c in required if c not in table.columns]
    if missing:
        raise InputError(f"table: expected the column(s) {', '.join(missing)}; got {', '.join(map(str, table.columns)) or 'none'}")
    if not isinstance(out, (str, Path)) or not Path(out).is_dir():
        raise InputError(f"out: expected an existing folder, got {out!r}")
    if not isinstance(plots, (bool, np.bool_)):
        raise InputError(f"plots: expected true or false, got {plots!r}")
    return table, Path(out)


def design_columns(table: pd.DataFrame) -> list[str]:
    """The design columns of a study table: the columns before ``case``.

    Parameters
    ----------
    table : pandas.DataFrame
        The study table.

    Returns
    -------
    list of str
        Empty when the table has no ``case`` column or nothing before it.
    """
    cols = list(table.columns)
    return [str(c) for c in cols[: cols.index("case")]] if "case" in cols else []


def solved_rows(table: pd.DataFrame) -> pd.DataFrame:
    """The rows whose status is in :data:`SOLVED`.

    Parameters
    ----------
    table : pandas.DataFrame
        The study table (with a ``status`` column).

    Returns
    -------
    pandas.DataFrame
    """
    return table[table["status"].astype(str).isin(SOLVED)]


def status_counts(table: pd.DataFrame) -> dict[str, int]:
    """Number of cases per status.

    Parameters
    ----------
    table : pandas.DataFrame
        The study table (with a ``status`` column).

    Returns
    -------
    dict of str to int
    """
    return {str(k): int(v) for k, v in table["status"].astype(str).value_counts().sort_index().items()}


def finite_or_none(x: Any) -> float | None:
    """A finite float, or None (JSON ``null``) for missing and non-finite values.

    Parameters
    ----------
    x : Any
        A number, None or NaN.

    Returns
    -------
    float or None
    """
    try:
        v = float(x)
    except (TypeError, ValueError):
        return None
    return v if math.isfinite(v) else None
