"""Plots of studies (``gtmodel study``): Monte-Carlo calibration, time-optimal maps, sweeps.

Every function takes plain arrays or DataFrames (the study analyses in
:mod:`gtmodel.problems.study.analyses` compute them), writes one PNG and returns the figure
(through :mod:`gtmodel.report._figure`, which imports matplotlib when a figure is made).
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any, Mapping, Sequence

import numpy as np
import pandas as pd

from gtmodel.report._figure import new_figure, save

__all__ = [
    "plot_normalised_errors",
    "plot_parameter_spread",
    "plot_accuracy_vs_poses",
    "plot_time_map",
    "plot_sweep",
    "MAP_MARKERS",
]

#: Marker and label of the map cells without a solution, by class (see
#: :func:`plot_time_map`).
MAP_MARKERS = {
    "infeasible": ("x", "infeasible (no motion within the limits)"),
    "outside": ("s", "outside the workspace (rejected before solving)"),
    "failed": ("^", "not solved (iteration limit, error)"),
}


def plot_normalised_errors(z: np.typing.ArrayLike, path: str | Path, coverage: tuple[float, float] | None = None, title: str = "") -> Any:
    """Histogram of normalised parameter errors ``(estimate - truth) / predicted std``.

    An honest covariance gives a standard normal (drawn over the histogram); the 1- and
    2-sigma bounds are marked.

    Parameters
    ----------
    z : array_like, shape (n,)
        Normalised errors (all parameters and cases).
    path : str or pathlib.Path
        PNG file.
    coverage : tuple of float, optional
        Measured 1- and 2-sigma coverage, shown in the legend.
    title : str, optional
        Figure title.

    Returns
    -------
    matplotlib.figure.Figure
        The figure, written to ``path``.
    """
    za = np.asarray(z, dtype=float).ravel()
    za = za[np.isfinite(za)]
    fig, ax = new_figure()
    lim = max(4.0, float(np.quantile(np.abs(za), 0.999)) if za.size else 4.0)
    edges = np.linspace(-lim, lim, 61)
    label = "cases" if coverage is None else f"measured: {100 * coverage[0]:.1f} % within 1 sigma, {100 * coverage[1]:.1f} % within 2"
    ax.hist(np.clip(za, -lim, lim), bins=edges, density=True, alpha=0.6, label=label)
    x = np.linspace(-lim, lim, 400)
    ax.plot(x, np.exp(-0.5 * x**2) / math.sqrt(2 * math.pi), "k-", label="standard normal (honest: 68.3 %, 95.4 %)")
    for k in (1, 2):
        for sgn in (-1, 1):
            ax.axvline(sgn * k, color="0.4", ls="--" if k == 1 else ":", lw=1)
    ax.set_xlabel("(estimate - truth) / predicted standard deviation")
    ax.set_ylabel("density")
    ax.grid(True)
    ax.legend(fontsize="small")
    fig.suptitle(title or "normalised parameter errors")
    return save(fig, path)


def plot_parameter_spread(per_parameter: pd.DataFrame, path: str | Path, title: str = "") -> Any:
    """Per parameter: spread of the error over the predicted deviation, and coverage.

    Parameters
    ----------
    per_parameter : pandas.DataFrame
        Columns ``parameter``, ``spread_ratio`` (std of the errors / rms predicted std),
        ``coverage_1sigma``, ``coverage_2sigma``.
    path : str or pathlib.Path
        PNG file.
    title : str, optional
        Figure title.

    Returns
    -------
    matplotlib.figure.Figure
        The figure, written to ``path``.
    """
    names = list(per_parameter["parameter"])
    x = np.arange(len(names))
    fig, (ax1, ax2) = new_figure(2, 1, sharex=True, size=(max(7.0, 0.35 * len(names) + 2), 6))
    ax1.bar(x, per_parameter["spread_ratio"], color="tab:blue")
    ax1.axhline(1.0, color="k", lw=1)
    ax1.set_ylabel("error spread / predicted std")
    ax1.grid(True, axis="y")
    ax2.plot(x, per_parameter["coverage_1sigma"], "o", label="within 1 sigma")
    ax2.plot(x, per_parameter["coverage_2sigma"], "s", label="within 2 sigma")
    for v in (math.erf(1 / math.sqrt(2)), math.erf(2 / math.sqrt(2))):
        ax2.axhline(v, color="0.4", ls="--", lw=1)
    ax2.set_ylim(0, 1.02)
    ax2.set_ylabel("coverage")
    ax2.set_xticks(x, names, rotation=60, ha="right", fontsize="small")
    ax2.grid(True, axis="y")
    ax2.legend(fontsize="small")
    fig.suptitle(title or "parameter errors against the predicted deviations")
    return save(fig, path)


def plot_accuracy_vs_poses(groups: pd.DataFrame, path: str | Path, title: str = "") -> Any:
    """TCP error against the noise-free truth vs the number of calibration poses, per pose choice.

    Parameters
    ----------
    groups : pandas.DataFrame
        Columns ``n_calibration``, ``truth_mean_error_m_median`` (and ``_q10``, ``_q90``
        for the band), optionally ``pose_method`` (one line each).
    path : str or pathlib.Path
        PNG file.
    title : str, optional
        Figure title.

    Returns
    -------
    matplotlib.figure.Figure
        The figure, written to ``path``.
    """
    fig, ax = new_figure()
    methods = groups["pose_method"] if "pose_method" in groups else pd.Series(["poses"] * len(groups))
    labels = {"condition": "selected, eq. 5.9", "random": "random"}
    for m in sorted(set(methods.astype(str))):
        g = groups[methods.astype(str).to_numpy() == m].sort_values("n_calibration")
        n = g["n_calibration"].to_numpy(dtype=float)
        line = ax.plot(n, 1e6 * g["truth_mean_error_m_median"].to_numpy(dtype=float), "o-", label=labels.get(m, m))[0]
        if "truth_mean_error_m_q10" in g:
            ax.fill_between(n, 1e6 * g["truth_mean_error_m_q10"].to_numpy(dtype=float), 1e6 * g["truth_mean_error_m_q90"].to_numpy(dtype=float),
                            color=line.get_color(), alpha=0.2)
    from matplotlib.ticker import ScalarFormatter  # heavy optional dependency

    ax.set_xscale("log")
    ax.set_yscale("log")
    for axis in (ax.xaxis, ax.yaxis):
        axis.set_major_formatter(ScalarFormatter())
        axis.set_minor_formatter(ScalarFormatter())
    ax.set_xlabel("calibration poses")
    ax.set_ylabel("mean TCP error vs the truth [um]")
    ax.grid(True, which="both")
    ax.legend(fontsize="small", title="median, 10-90 % band")
    fig.suptitle(title or "accuracy against the number of poses")
    return save(fig, path)


def plot_time_map(
    x: np.typing.ArrayLike,
    y: np.typing.ArrayLike,
    time_s: np.typing.ArrayLike,
    cell_class: Sequence[str],
    path: str | Path,
    labels: tuple[str, str] = ("x [m]", "y [m]"),
    start: tuple[float, float] | None = None,
    title: str = "",
    start_label: str = "start",
) -> Any:
    """Map of minimum motion times over a grid of end positions; cells without a time marked.

    Parameters
    ----------
    x, y : array_like, shape (n,)
        End positions of the cells in the map plane [m] (a grid: the distinct values
        give the columns and rows).
    time_s : array_like, shape (n,)
        Minimum time per cell [s] (NaN where the cell has none).
    cell_class : sequence of str, length n
        ``"solved"`` or a key of :data:`MAP_MARKERS` per cell.
    path : str or pathlib.Path
        PNG file.
    labels : tuple of str, optional
        Axis labels (with units).
    start : tuple of float, optional
        The start position in the map plane [m] (or its projection), marked with a star.
    title : str, optional
        Figure title.
    start_label : str, optional
        Legend text of the start.

    Returns
    -------
    matplotlib.figure.Figure
        The figure, written to ``path``.
    """
    xa, ya, ta = (np.asarray(a, dtype=float).ravel() for a in (x, y, time_s))
    cls = np.asarray(list(cell_class), dtype=object)
    xs, ys = np.unique(xa), np.unique(ya)
    grid = np.full((ys.size, xs.size), np.nan)
    grid[np.searchsorted(ys, ya), np.searchsorted(xs, xa)] = np.where(cls == "solved", ta, np.nan)

    def edges(v: np.ndarray) -> np.ndarray:
        if v.size == 1:
            return np.array([v[0] - 0.05, v[0] + 0.05])
        mid = 0.5 * (v[1:] + v[:-1])
        return np.concatenate([[2 * v[0] - mid[0]], mid, [2 * v[-1] - mid[-1]]])

    fig, ax = new_figure(size=(7, 5.5))
    ax.set_facecolor("0.85")
    mesh = ax.pcolormesh(edges(xs), edges(ys), np.ma.masked_invalid(grid), cmap="viridis", shading="flat")
    fig.colorbar(mesh, ax=ax, label="minimum time [s]")
    for key, (marker, text) in MAP_MARKERS.items():
        sel = cls == key
        if sel.any():
            ax.plot(xa[sel], ya[sel], marker, color="tab:red", ls="none", ms=8, mew=2, label=f"{text} ({int(sel.sum())})")
    if start is not None:
        ax.plot([start[0]], [start[1]], "*", color="white", mec="k", ms=16, ls="none", label=start_label)
    ax.set_xlabel(labels[0])
    ax.set_ylabel(labels[1])
    ax.set_aspect("equal")
    if ax.get_legend_handles_labels()[0]:
        ax.legend(fontsize="small", loc="upper left", bbox_to_anchor=(0, -0.12), ncol=1)
    fig.suptitle(title or "minimum motion time to each end position")
    return save(fig, path)


def plot_sweep(axis: str, values: np.typing.ArrayLike, columns: Mapping[str, np.typing.ArrayLike], path: str | Path,
               solved: np.typing.ArrayLike | None = None, title: str = "") -> Any:
    """Each column of a sweep against the swept value, one panel per column.

    Parameters
    ----------
    axis : str
        Name of the swept field (the x label).
    values : array_like, shape (n,)
        Swept values (numbers).
    columns : Mapping[str, array_like]
        Panel label (with units) -> values per case, shape (n,).
    path : str or pathlib.Path
        PNG file.
    solved : array_like of bool, shape (n,), optional
        Cases with a solution; the others are drawn as open red markers.
    title : str, optional
        Figure title.

    Returns
    -------
    matplotlib.figure.Figure
        The figure, written to ``path``.
    """
    v = np.asarray(values, dtype=float).ravel()
    ok = np.ones(v.shape, dtype=bool) if solved is None else np.asarray(solved, dtype=bool).ravel()
    order = np.argsort(v)
    n = max(1, len(columns))
    fig, axes = new_figure(n, 1, sharex=True, size=(6, 2.3 * n + 0.6))
    axes = np.atleast_1d(axes)
    for ax, (label, col) in zip(axes, columns.items()):
        c = np.asarray(col, dtype=float).ravel()
        ax.plot(v[order][ok[order]], c[order][ok[order]], "o-")
        if (~ok).any():
            ax.plot(v[~ok], np.where(np.isfinite(c[~ok]), c[~ok], np.nan), "o", mfc="none", color="tab:red", label="not solved")
            ax.legend(fontsize="small")
        ax.set_ylabel(label)
        ax.grid(True)
    axes[-1].set_xlabel(axis)
    fig.suptitle(title or f"sweep over {axis}")
    return save(fig, path)
