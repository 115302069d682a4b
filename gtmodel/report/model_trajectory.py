"""Plots of an optimal trajectory of a user's model (kind ``optimal_control``): one panel per signal."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any, Mapping

import numpy as np

from gtmodel.report._figure import new_figure, save

__all__ = ["plot_signals", "MAX_PANELS"]

#: Most panels drawn in one figure (further signals are left out, the title says how many).
MAX_PANELS = 12


def plot_signals(
    t: np.ndarray,
    signals: Mapping[str, np.ndarray],
    path: str | Path,
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
    path : str or pathlib.Path
        PNG file to write.
    title : str, optional
        Figure title.
    bounds : Mapping[str, tuple of float], optional
        Name -> ``(lo, hi)``; finite bounds are drawn.
    units : Mapping[str, str], optional
        Name -> SI unit, shown on the y labels as ``name [unit]`` (e.g. :attr:`Model.units
        <gtmodel.modeling.Model.units>`).

    Returns
    -------
    matplotlib.figure.Figure
        The figure, written to ``path``.
    """
    names = list(signals)[:MAX_PANELS]
    cols = min(2, max(1, len(names)))
    rows = max(1, math.ceil(len(names) / cols))
    fig, axes = new_figure(rows, cols, size=(5.2 * cols, 2.4 * rows + 0.6), squeeze=False)
    axes = axes.ravel()
    for ax, name in zip(axes, names):
        ax.plot(t, np.asarray(signals[name], dtype=float).reshape(-1), label=name)
        lo, hi = (bounds or {}).get(name, (-np.inf, np.inf))
        for b in (lo, hi):
            if np.isfinite(b):
                ax.axhline(b, color="k", linestyle="--", linewidth=0.8)
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
