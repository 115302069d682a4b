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

from gtmodel.defaults import defaults
from gtmodel.errors import InputError

__all__ = ["new_figure", "save", "panel_size"]


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
