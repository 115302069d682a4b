"""Plots of calibration results: the TCP error histogram of accuracy reports."""

from __future__ import annotations

from pathlib import Path
from typing import Any, Mapping

import numpy as np

from gtmodel.calibration.evaluation import AccuracyReport
from gtmodel.report._figure import new_figure, save

__all__ = ["plot_error_histogram"]


def plot_error_histogram(reports: Mapping[str, AccuracyReport], path: str | Path, bins: int = 30, title: str = "") -> Any:
    """Histogram of TCP errors of one or several models (Dressler (2012), Fig. 3.8).

    Parameters
    ----------
    reports : Mapping[str, AccuracyReport]
        Label -> report.
    path : str or pathlib.Path
        PNG file.
    bins : int, optional
        Number of bins (shared edges).
    title : str, optional
        Figure title.

    Returns
    -------
    matplotlib.figure.Figure
        The figure (one axes; one histogram per report, errors in um), written to ``path``.
    """
    fig, ax = new_figure()
    top = max(r.max_error for r in reports.values()) * 1e6
    edges = np.linspace(0.0, top, bins + 1)
    for label, r in reports.items():
        ax.hist(r.errors * 1e6, bins=edges, alpha=0.55, label=f"{label}: mean {r.mean_error * 1e6:.0f} um, max {r.max_error * 1e6:.0f} um")
    ax.set_xlabel("TCP error [um]")
    ax.set_ylabel("poses")
    ax.grid(True)
    ax.legend(fontsize="small")
    fig.suptitle(title or "TCP error on the validation poses")
    return save(fig, path)
