"""The ``[[data]]`` tables of an ``optimal_control`` problem file: measurements fitted by least squares.

Each table names a CSV (read with :func:`gtmodel._tables.read_table`), its time column,
the model names it measures (outputs, states, algebraic variables; their CSV columns) and
their standard deviations or weights; :func:`declare_data` declares every measurement on
the :class:`~gtmodel.modeling.Optimization` (:func:`gtmodel.modeling.ocp.estimation.fit_data`)
and returns the least-squares objective. Every error names the file and the field.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import casadi as ca
import numpy as np

from gtmodel._tables import column_names, read_table
from gtmodel.errors import GtModelError
from gtmodel.modeling import Optimization
from gtmodel.modeling.ocp.estimation import fit_data, least_squares
from gtmodel.problems.base import ProblemFile
from gtmodel.problems.kinds.schemas.optimal_control import DataSection

__all__ = ["declare_data"]


def _per_name(file: ProblemFile, field: str, values: list[float] | None, n: int) -> list[float | None]:
    if values is None:
        return [None] * n
    if len(values) not in (1, n):
        raise file.fail(field, f"one value or one per measured name ({n})", values)
    return list(values) * n if len(values) == 1 else list(values)


def declare_data(file: ProblemFile, tables: list[DataSection], opt: Optimization, table: dict[str, Any]) -> ca.SX | None:
    """Declare the measurements of every ``[[data]]`` table; the least-squares objective (None without data).

    Parameters
    ----------
    file : ProblemFile
        The problem file.
    tables : list of DataSection
        The validated ``[[data]]`` tables.
    opt : Optimization
        The problem (fixed final time).
    table : dict
        Name table (aliases included): measured names are looked up in it.

    Returns
    -------
    casadi.SX or None
        ``sum w (y(t_i) - y_i)^2`` over all measurements.

    Raises
    ------
    ProblemError
        Naming the file and ``data[i].<field>``: a missing CSV, NaN or a malformed row
        (the line), a missing column, an unknown or constant measured name, a time outside
        the horizon, a free final time, both ``std`` and ``weights``.
    """
    if not tables:
        return None
    static = set()
    varying = opt._varying()
    for name, value in table.items():
        if not ca.depends_on(value, varying):
            static.add(name)
    for i, d in enumerate(tables):
        key = f"data[{i}]"
        path = Path(file.data_file(f"{key}.file", d.file))
        try:
            data = read_table(path, "measurement data")
        except GtModelError as exc:
            raise file.wrap(f"{key}.file", exc) from None
        cols = list(data.columns)
        if d.time_column not in cols:
            raise file.fail(f"{key}.time_column", f"a column of {path.name} ({column_names(cols)})", d.time_column)
        t = data.data[:, cols.index(d.time_column)]
        if np.any(np.diff(t) <= 0):
            raise file.fail(f"{key}.file", f"times in column {d.time_column!r} increasing strictly", path.name)
        columns = d.columns if d.columns is not None else d.measures
        if len(columns) != len(d.measures):
            raise file.fail(f"{key}.columns", f"one column per measured name ({len(d.measures)})", d.columns)
        if d.std is not None and d.weights is not None:
            raise file.fail(f"{key}.weights", "std or weights, not both")
        stds = _per_name(file, f"{key}.std", d.std, len(d.measures))
        weights = _per_name(file, f"{key}.weights", d.weights, len(d.measures))
        for j, (name, col) in enumerate(zip(d.measures, columns)):
            if name not in table or name in static:
                known = sorted(n for n in table if n not in static)
                raise file.fail(f"{key}.measures", f"names of the model's outputs, states or algebraic variables ({', '.join(known)})", name)
            if col not in cols:
                field = f"{key}.columns" if d.columns is not None else f"{key}.measures"
                raise file.fail(field, f"a column of {path.name} ({column_names(cols)})", col)
            try:
                fit_data(opt, table[name], t, data.data[:, cols.index(col)], std=stds[j], weight=weights[j], name=name)
            except GtModelError as exc:
                raise file.wrap(f"{key}.file", exc) from None
    return least_squares(opt)
