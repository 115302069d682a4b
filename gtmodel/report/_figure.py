"""The one figure helper of the report layer: new figures and PNG files in the style of :mod:`gtmodel.defaults`.

Every report module draws through :func:`new_figure` and writes through :func:`save`, so
the resolution (``defaults["plot.dpi"]``), the standard sizes (``plot.figsize``,
``plot.wide``, ``plot.tall``, ``plot.panel``) and the layout engine are set in one place.
Figures are :class:`matplotlib.figure.Figure` objects, not registered with pyplot (safe
under the ``Agg`` backend and headless); matplotlib is imported when a figure is made.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from gtmodel.defaults import defaults
from gtmodel.errors import InputError

__all__ = ["new_figure", "save", "panel_size", "panel_grid", "shared_legend", "scale_to_data"]


def _size(size: Any) -> tuple[float, float]:
    if size is None:
        size = "plot.figsize"
    if isinstance(size, str):
        if not size.startswith("plot.") or size not in defaults:
            raise InputError(f"size: expected (width, height) in inches or a plot size key of gtmodel.defaults, got {size!r}")
        size = defaults[size]
    try:
        w, h = (float(v) for v in size)
    except (TypeError, ValueError):
        raise InputError(f"size: expected (width, height) in inches, got {size!r}") from None
    if not (w > 0 and h > 0):
        raise InputError(f"size: expected a positive width and height in inches, got {size!r}")
    return w, h


def panel_size(cols: int = 1, rows: int = 1, panel: tuple[float, float] | None = None, extra: float = 0.0) -> tuple[float, float]:
    """Size of a grid of equal panels [in]: ``(cols w, rows h + extra)``.

    Parameters
    ----------
    cols, rows : int, optional
        Panels per row and per column (default 1).
    panel : tuple of float, optional
        ``(w, h)`` of one panel [in] (default ``defaults["plot.panel"]``).
    extra : float, optional
        Height added for the title [in].

    Returns
    -------
    tuple of float
        ``(width, height)`` [in].
    """
    w, h = _size("plot.panel" if panel is None else panel)
    return cols * w, rows * h + extra


def new_figure(rows: int = 1, cols: int = 1, size: Any = None, *, squeeze: bool = True, layout: str | None = None,
               **subplots: Any) -> tuple[Any, Any]:
    """A new figure with a grid of axes, in the style of :mod:`gtmodel.defaults`.

    Parameters
    ----------
    rows, cols : int, optional
        Grid of axes (default one).
    size : tuple of float or str, optional
        ``(width, height)`` [in], or a size key of :data:`gtmodel.defaults.defaults`
        (``"plot.wide"``, ...); default ``"plot.figsize"``.
    squeeze : bool, optional
        As :meth:`matplotlib.figure.Figure.subplots` (default True: one axes, or a 1-D array).
    layout : str, optional
        Layout engine (default ``defaults["plot.layout"]``).
    **subplots
        Further arguments of :meth:`~matplotlib.figure.Figure.subplots` (``sharex``, ...).

    Returns
    -------
    tuple
        ``(figure, axes)``: a :class:`matplotlib.figure.Figure` and what ``subplots`` returns.

    Raises
    ------
    InputError
        A size that is not two positive numbers nor a plot size key.
    """
    from matplotlib.figure import Figure  # matplotlib loads only when a plot is drawn

    fig = Figure(figsize=_size(size), layout=defaults["plot.layout"] if layout is None else layout)
    return fig, fig.subplots(rows, cols, squeeze=squeeze, **subplots)


def save(fig: Any, path: str | Path | None, **savefig: Any) -> Any:
    """Write ``fig`` as PNG at ``defaults["plot.dpi"]`` (nothing when ``path`` is None).

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        The figure.
    path : str, pathlib.Path or None
        The file; None: do not write.
    **savefig
        Further arguments of :meth:`~matplotlib.figure.Figure.savefig` (``bbox_inches``, ...).

    Returns
    -------
    matplotlib.figure.Figure
        ``fig`` (for the report functions to return).
    """
    if path is not None:
        fig.savefig(Path(path), dpi=defaults["plot.dpi"], **savefig)
    return fig


def panel_grid(n: int, max_cols: int = 2) -> tuple[int, int]:
    """``(rows, cols)`` of a near-square grid of ``n`` panels, at most ``max_cols`` wide.

    Parameters
    ----------
    n : int
        Number of panels (at least one is laid out).
    max_cols : int, optional
        Most panels per row (default 2).

    Returns
    -------
    tuple of int
    """
    cols = max(1, min(max_cols, n))
    return max(1, -(-n // cols)), cols


def shared_legend(fig: Any, ax: Any, **legend: Any) -> Any:
    """One legend for panels that draw the same lines: ``ax``'s entries, once, below the figure's panels.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        The figure.
    ax : matplotlib.axes.Axes
        A panel holding every labelled line.
    **legend
        Further arguments of :meth:`~matplotlib.figure.Figure.legend` (``fontsize``, ...).

    Returns
    -------
    matplotlib.legend.Legend
    """
    handles, labels = ax.get_legend_handles_labels()
    return fig.legend(handles, labels, loc="outside lower center", ncols=min(len(labels), 4) or 1, **legend)


def scale_to_data(ax: Any, values: Any, bounds: tuple[float, float] = (-np.inf, np.inf), reach: float = 0.5) -> list[float]:
    """Y limits from the data, the bounds near it drawn (dashed) and the far ones named at the edge.

    A bound within ``reach`` times the data's range of it is drawn and kept in view; one
    farther away would flatten the data to a line, so it is written at the panel's top or
    bottom (``"upper bound 1000 (off scale)"``) instead.

    Parameters
    ----------
    ax : matplotlib.axes.Axes
        The panel.
    values : array_like
        The plotted values (NaN ignored).
    bounds : tuple of float, optional
        ``(lo, hi)``; infinite or NaN: none.
    reach : float, optional
        How far from the data (in data ranges) a bound is still drawn (default 0.5).

    Returns
    -------
    list of float
        The bounds drawn.
    """
    v = np.asarray(values, dtype=float)
    v = v[np.isfinite(v)]
    lo_d, hi_d = (float(v.min()), float(v.max())) if v.size else (0.0, 1.0)
    span = hi_d - lo_d or max(abs(hi_d), 1.0) * 0.1
    drawn, low, high = [], lo_d, hi_d
    for side, b in zip(("lower", "upper"), bounds):
        if b is None or not np.isfinite(b):
            continue
        if lo_d - reach * span <= b <= hi_d + reach * span:
            ax.axhline(b, color="k", linestyle="--", linewidth=0.8)
            drawn.append(float(b))
            low, high = min(low, b), max(high, b)
        else:
            above = b > hi_d
            ax.text(0.99, 0.97 if above else 0.03, f"{side} bound {b:.4g} (off scale)", transform=ax.transAxes,
                    ha="right", va="top" if above else "bottom", fontsize="x-small", color="0.3")
    pad = 0.08 * ((high - low) or span)
    ax.set_ylim(low - pad, high + pad)
    return drawn
