"""Plots of iterative learning control runs (Dressler (2012), Figs. 7.7-7.11 style).

Every function takes plain arrays or mappings of arrays (not result objects), draws on a
:class:`matplotlib.figure.Figure` (no pyplot state, safe under Agg), writes a PNG and
returns the figure:

- :func:`plot_error_measure`: error measure (7.25) per iteration, log scale, one panel per
  case, one line per actuator or tool direction (Figs. 7.7-7.10);
- :func:`plot_tool_path`: tool path in the xy plane, reference vs iteration 0 vs the
  last iteration (Fig. 7.11);
- :func:`plot_iteration_errors`: the error over time of chosen iterations;
- :func:`plot_convergence`: per case ``|Q^-1(f)|`` beside the loop gain
  ``sigma_max(I - L T(f))`` (Figs. 7.14, 7.17) and the lifted ``sigma_max`` (7.16) per channel
  and coupled.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Mapping, Sequence

import numpy as np

from gtmodel.errors import InputError
from gtmodel.report._figure import new_figure, panel_grid, save, shared_legend

__all__ = ["plot_error_measure", "plot_tool_path", "plot_iteration_errors", "plot_convergence", "case_title", "SIGNAL_TITLES"]

#: What each learning signal is, for panel titles (Dressler (2012), Table 7.2).
SIGNAL_TITLES = {
    "actuator": "actuator positions",
    "complementary": "complementary filter (7.17)",
    "kalman": "Kalman filter (7.19)-(7.22)",
    "tool": "measured tool position",
}


def _columns(x: Any, name: str) -> np.ndarray:
    arr = np.asarray(x, dtype=float)
    if arr.ndim == 1:
        arr = arr[:, None]
    if arr.ndim != 2 or arr.shape[0] == 0:
        raise InputError(f"{name}: expected shape (K+1,) or (K+1, d), got {np.shape(x)}")
    return arr


def case_title(name: str, signal: str | None = None) -> str:
    """Panel title of an ILC case as in Dressler (2012), Table 7.2: ``"Case 2A: complementary filter (7.17)"``.

    Parameters
    ----------
    name : str
        Case name (``"1"``, ``"2A"``, ...; a name that starts with "Case" is kept as it is).
    signal : str, optional
        Learning signal (a key of :data:`SIGNAL_TITLES`, or any text); None: no subtitle.

    Returns
    -------
    str
        The title.
    """
    label = name if name.strip().lower().startswith("case") else f"Case {name}"
    return f"{label}: {SIGNAL_TITLES.get(signal, signal)}" if signal else label


def plot_error_measure(
    measures: Mapping[str, Any],
    path: str | Path,
    labels: Sequence[str] | None = None,
    relative: bool = True,
    title: str = "",
    signals: Mapping[str, str] | None = None,
) -> Any:
    """Error measure (7.25) per iteration, log scale, one panel per case (Figs. 7.7-7.10).

    Parameters
    ----------
    measures : Mapping[str, array_like]
        Case name -> measure per iteration, shape ``(K+1,)`` or ``(K+1, d)`` (one line per
        column, e.g. actuators 1-3 or tool x, y) [m].
    path : str or pathlib.Path
        PNG file to write.
    labels : sequence of str, optional
        Column names (default ``"1", "2", ...``).
    relative : bool, optional
        Plot relative to iteration 0 (default True) instead of absolute values [m].
    title : str, optional
        Figure title.
    signals : Mapping[str, str], optional
        Case name -> learning signal, named in the panel title (:func:`case_title`).

    Returns
    -------
    matplotlib.figure.Figure
        The figure, written to ``path``: one axes per case (two per row), titled by
        :func:`case_title`, one legend below them.

    Raises
    ------
    InputError
        No case, or a measure of another shape.
    """
    if not measures:
        raise InputError("measures: expected at least one case")
    data = {name: _columns(m, f"measures[{name!r}]") for name, m in measures.items()}
    rows, cols_ = panel_grid(len(data))
    fig, axes = new_figure(rows, cols_, sharey=True, size=(4.6 * cols_, 2.9 * rows + 1.0), squeeze=False)
    axes = axes.ravel()
    for ax in axes[len(data):]:
        ax.set_visible(False)
    for ax, (name, m) in zip(axes, data.items()):
        cols = labels if labels is not None else [str(j + 1) for j in range(m.shape[1])]
        values = m / np.where(m[0] > 0, m[0], 1.0) if relative else m
        for j in range(m.shape[1]):
            ax.semilogy(np.arange(m.shape[0]), values[:, j], "o-", ms=3, label=cols[j] if j < len(cols) else str(j + 1))
        ax.set_title(case_title(name, (signals or {}).get(name)))
        ax.set_xlabel("iteration")
        ax.grid(True, which="both", alpha=0.3)
    shared_legend(fig, axes[0], fontsize="small")
    for ax in axes[::cols_]:
        ax.set_ylabel("error measure relative to iteration 0" if relative else "error measure [m]")
    fig.suptitle(title or "ILC error measure (7.25)")
    return save(fig, path)


def plot_tool_path(
    reference: Any,
    paths: Mapping[str, Any],
    path: str | Path,
    title: str = "",
) -> Any:
    """Tool path in the xy plane: reference and chosen iterations (Fig. 7.11).

    Coordinates are drawn in mm relative to the first reference sample.

    Parameters
    ----------
    reference : array_like, shape (N, 2) or (N, 3)
        Reference tool positions (x, y[, z]) [m].
    paths : Mapping[str, array_like]
        Label (e.g. ``"iteration 0"``, ``"iteration 10"``) -> tool positions, same shape
        as ``reference`` [m].
    path : str or pathlib.Path
        PNG file to write.
    title : str, optional
        Figure title.

    Returns
    -------
    matplotlib.figure.Figure
        The figure, written to ``path``.

    Raises
    ------
    InputError
        Arrays of the wrong shape.
    """
    ref = np.asarray(reference, dtype=float)
    if ref.ndim != 2 or ref.shape[1] < 2 or ref.shape[0] == 0:
        raise InputError(f"reference: expected shape (N, 2) or (N, 3), got {ref.shape}")
    origin = ref[0, :2]
    fig, ax = new_figure(size=(5.5, 5.0))
    ax.plot(*(1e3 * (ref[:, :2] - origin)).T, "k--", lw=1.0, label="reference")
    for label, p in paths.items():
        arr = np.asarray(p, dtype=float)
        if arr.shape != ref.shape:
            raise InputError(f"paths[{label!r}]: expected shape {ref.shape} like reference, got {arr.shape}")
        ax.plot(*(1e3 * (arr[:, :2] - origin)).T, lw=1.2, label=label)
    ax.set_xlabel("x [mm]")
    ax.set_ylabel("y [mm]")
    ax.set_aspect("equal", adjustable="datalim")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize="small")
    fig.suptitle(title or "tool path")
    return save(fig, path)


def plot_iteration_errors(
    eps: Any,
    dt: float,
    path: str | Path,
    iterations: Sequence[int] | None = None,
    labels: Sequence[str] | None = None,
    title: str = "",
) -> Any:
    """Error over time of chosen iterations, one panel per column (actuator or direction).

    Parameters
    ----------
    eps : array_like, shape (K+1, N, d)
        Error of every iteration [m] (e.g. :attr:`gtmodel.estimation.ILCResult.eps`).
    dt : float
        Sample time [s].
    path : str or pathlib.Path
        PNG file to write.
    iterations : sequence of int, optional
        Iterations to draw (default the first and the last).
    labels : sequence of str, optional
        Column names (default ``"1", "2", ...``).
    title : str, optional
        Figure title.

    Returns
    -------
    matplotlib.figure.Figure
        The figure, written to ``path``.

    Raises
    ------
    InputError
        ``eps`` not three-dimensional, a non-positive ``dt`` or an iteration out of range.
    """
    e = np.asarray(eps, dtype=float)
    if e.ndim != 3 or 0 in e.shape:
        raise InputError(f"eps: expected shape (K+1, N, d), got {e.shape}")
    if not np.isfinite(dt) or dt <= 0:
        raise InputError(f"dt: expected a positive sample time in s, got {dt!r}")
    its = [0, e.shape[0] - 1] if iterations is None else list(iterations)
    if any(not 0 <= k < e.shape[0] for k in its):
        raise InputError(f"iterations: expected indices in [0, {e.shape[0] - 1}], got {its}")
    d = e.shape[2]
    cols = labels if labels is not None else [str(j + 1) for j in range(d)]
    t = np.arange(e.shape[1]) * dt
    fig, axes = new_figure(d, 1, sharex=True, size=(7, 1.9 * d + 0.8))
    axes = np.atleast_1d(axes)
    for j, ax in enumerate(axes):
        for k in its:
            ax.plot(t, 1e3 * e[k, :, j], lw=1.0, label=f"iteration {k}")
        ax.set_ylabel(f"{cols[j] if j < len(cols) else j + 1} [mm]")
        ax.grid(True, alpha=0.3)
    axes[0].legend(fontsize="small")
    axes[-1].set_xlabel("t [s]")
    fig.suptitle(title or "ILC error per iteration")
    return save(fig, path)


def plot_convergence(cases: Mapping[str, Mapping[str, Any]], path: str | Path, title: str = "") -> Any:
    """Monotone-convergence picture of every case (Dressler (2012), Figs. 7.14, 7.17 and eq. 7.16).

    Parameters
    ----------
    cases : Mapping[str, Mapping]
        Case name -> ``{"signal": str, "freqs_hz": (F,), "q": (F,) |Q(f)|, "loop_gain": (F,)
        sigma_max(I - L T(f)), "sigma": {channel: float}, "coupled": float or None}``.
    path : str or pathlib.Path
        PNG file to write.
    title : str, optional
        Figure title.

    Returns
    -------
    matplotlib.figure.Figure
        One panel per case (two per row): ``|Q^-1|``, the loop gain and their product
        ``|Q| g`` against frequency, the lifted figures written in the panel; one legend
        below the panels.

    Raises
    ------
    InputError
        No case.
    """
    if not cases:
        raise InputError("cases: expected at least one case")
    rows, cols = panel_grid(len(cases))
    fig, axes = new_figure(rows, cols, sharey=True, size=(4.6 * cols, 2.9 * rows + 1.0), squeeze=False)
    axes = axes.ravel()
    for ax in axes[len(cases):]:
        ax.set_visible(False)
    for ax, (name, c) in zip(axes, cases.items()):
        f, q, g = (np.asarray(c[k], dtype=float) for k in ("freqs_hz", "q", "loop_gain"))
        ax.semilogy(f, 1.0 / np.maximum(np.abs(q), 1e-12), label="|Q^-1|")
        ax.semilogy(f, g, label="sigma_max(I - L T)")
        ax.semilogy(f, np.abs(q) * g, "--", label="|Q| sigma_max(I - L T)")
        lifted = ", ".join(f"{ch} {v:.3f}" for ch, v in c["sigma"].items())
        coupled = c.get("coupled")
        ax.axhline(1.0, color="k", lw=0.8)
        ax.set_title(case_title(name, c.get("signal")))
        ax.text(0.02, 0.02, f"lifted sigma_max: {lifted}" + (f"\ncoupled {coupled:.3f}" if coupled is not None else ""),
                transform=ax.transAxes, fontsize="x-small", va="bottom")
        ax.set_xlabel("frequency [Hz]")
        ax.set_ylim(1e-2, 1e2)
        ax.grid(True, which="both", alpha=0.3)
    shared_legend(fig, axes[0], fontsize="small")
    for ax in axes[::cols]:
        ax.set_ylabel("magnitude")
    fig.suptitle(title or "ILC monotone convergence (7.16)")
    return save(fig, path)
