"""Plots of an optimal trajectory of a user's model (kind ``optimal_control``): one panel per signal.

:func:`plot_result` (``gtmodel.report.plot_result(result, "load.phi", ...)`` in a notebook):
any variable of a :class:`~gtmodel.modeling.OptimizationResult` by name, with the bounds the
solve respected.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any, Mapping

import numpy as np

from gtmodel.errors import InputError
from gtmodel.report._figure import new_figure, save, scale_to_data

__all__ = ["plot_signals", "plot_result", "MAX_PANELS"]

#: Most panels drawn in one figure (further signals are left out, the title says how many).
MAX_PANELS = 12


def plot_signals(
    t: np.ndarray,
    signals: Mapping[str, np.ndarray],
    path: str | Path | None,
    title: str = "",
    bounds: Mapping[str, tuple[float, float]] | None = None,
    units: Mapping[str, str] | None = None,
) -> Any:
    """Plot signals against time, one panel each, with their bounds as dashed lines.

    Parameters
    ----------
    t : numpy.ndarray, shape (K,)
        Time [s].
    signals : Mapping[str, numpy.ndarray]
        Name -> values, each shape ``(K,)`` (SI units of the model).
    path : str, pathlib.Path or None
        PNG file to write (None: none).
    title : str, optional
        Figure title.
    bounds : Mapping[str, tuple of float], optional
        Name -> ``(lo, hi)``; finite bounds near the data are drawn (dashed), a far one is
        named at the panel's edge: the axes are scaled to the data
        (:func:`gtmodel.report._figure.scale_to_data`).
    units : Mapping[str, str], optional
        Name -> SI unit, shown on the y labels as ``name [unit]`` (e.g. :attr:`Model.units
        <gtmodel.modeling.Model.units>`).

    Returns
    -------
    matplotlib.figure.Figure
        The figure, written to ``path`` when given.
    """
    names = list(signals)[:MAX_PANELS]
    cols = min(2, max(1, len(names)))
    rows = max(1, math.ceil(len(names) / cols))
    fig, axes = new_figure(rows, cols, size=(5.2 * cols, 2.4 * rows + 0.6), squeeze=False)
    axes = axes.ravel()
    for ax, name in zip(axes, names):
        values = np.asarray(signals[name], dtype=float).reshape(-1)
        ax.plot(t, values, label=name)
        scale_to_data(ax, values, (bounds or {}).get(name, (-np.inf, np.inf)))
        unit = (units or {}).get(name)
        ax.set_ylabel(f"{name} [{unit}]" if unit else name)
        ax.grid(True)
    for ax in axes[len(names):]:
        ax.set_visible(False)
    for ax in axes[max(0, len(names) - cols):len(names)]:
        ax.set_xlabel("t [s]")
    more = f" (first {MAX_PANELS} of {len(signals)})" if len(signals) > MAX_PANELS else ""
    fig.suptitle((title or "trajectory") + more)
    return save(fig, path)


def _scalar_columns(groups: Mapping[str, Mapping[str, Any]]) -> dict[str, np.ndarray]:
    """Name -> values of every scalar column (``"T[1]"`` for element 1 of a vector variable)."""
    out: dict[str, np.ndarray] = {}
    for values in groups.values():
        for name, v in values.items():
            v = np.asarray(v, dtype=float)
            if v.ndim == 1:
                out[name] = v
            else:
                out.update({f"{name}[{i}]": v[:, i] for i in range(v.shape[1])})
    return out


def _element_bounds(lb: Any, ub: Any, name: str, size: int) -> dict[str, tuple[float, float]]:
    """Scalar-column bounds of a variable from lower/upper values (scalars or ``(size,)``; NaN: not set)."""
    lo = np.broadcast_to(np.asarray(lb, dtype=float).reshape(-1), (size,))
    hi = np.broadcast_to(np.asarray(ub, dtype=float).reshape(-1), (size,))
    keys = [name] if size == 1 else [f"{name}[{i}]" for i in range(size)]
    return {k: (float(a), float(b)) for k, a, b in zip(keys, lo, hi) if not (np.isnan(a) and np.isnan(b))}


def plot_result(result: Any, *names: str, bounds: Mapping[str, Any] | None = None, units: Mapping[str, str] | None = None,
                path: str | Path | None = None, title: str = "") -> Any:
    """Variables of an optimal control result against time, with their bounds.

    Parameters
    ----------
    result : gtmodel.modeling.OptimizationResult
        The result (its values on the collocation mesh ``result.t``).
    *names : str
        Scalar names of states, inputs, algebraic variables or outputs (``"load.phi"``;
        ``"T[0]"`` for an element of a vector variable); default every state and input.
    bounds : Mapping[str, tuple], optional
        Variable name -> ``(lo, hi)``, scalars or one value per element (NaN or inf: open),
        drawn over the model's own bounds (``result.dae``); pass an
        :class:`~gtmodel.modeling.Optimization`'s ``bounds`` to draw those set with
        ``set_bounds``.
    units : Mapping[str, str], optional
        Name -> SI unit for the axis labels (e.g. ``model.units``).
    path : str, pathlib.Path or None, optional
        PNG file to write (default none).
    title : str, optional
        Figure title (default the model's name).

    Returns
    -------
    matplotlib.figure.Figure
        One panel per name (at most :data:`MAX_PANELS`), bounds as dashed lines.

    Raises
    ------
    InputError
        A name that is no variable of the result (the message lists the names it has).
    """
    groups = {g: getattr(result, g) for g in ("states", "inputs", "algebraics", "outputs")}
    pool = _scalar_columns(groups)
    names = list(names) or list(_scalar_columns({g: groups[g] for g in ("states", "inputs")}))
    missing = [n for n in names if n not in pool]
    if missing:
        raise InputError(f"plot: {', '.join(map(repr, missing))} is no variable of this result; it has {', '.join(pool)}")
    drawn: dict[str, tuple[float, float]] = {}
    dae = getattr(result, "dae", None)
    if dae is not None:
        for cat in ("x", "z", "u"):
            lb, ub = getattr(dae, f"{cat}_lb"), getattr(dae, f"{cat}_ub")
            for name, sl in getattr(dae, f"{cat}_vars").items():
                drawn.update(_element_bounds(lb[sl], ub[sl], name, sl.stop - sl.start))
    for name, (lo, hi) in (bounds or {}).items():
        size = int(np.size(np.asarray(lo)))
        for key, (a, b) in _element_bounds(lo, hi, name, size).items():
            old = drawn.get(key, (-np.inf, np.inf))
            drawn[key] = (old[0] if np.isnan(a) else a, old[1] if np.isnan(b) else b)
    default_title = getattr(dae, "name", "") if dae is not None else ""
    return plot_signals(result.t, {n: pool[n] for n in names}, path, title=title or default_title, bounds=drawn, units=units)
