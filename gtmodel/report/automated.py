"""Plots of an automated calibration (Dressler (2012), Figs. 5.22-5.24): workspace, obstacles, poses."""

from __future__ import annotations

from itertools import product
from pathlib import Path
from typing import Any

import numpy as np

from gtmodel.calibration.automated import AutomatedCalibrationResult, Obstacle
from gtmodel.report._figure import new_figure, save

__all__ = ["plot_calibration_workspace"]


def _box_edges(lo: np.ndarray, hi: np.ndarray) -> list[np.ndarray]:
    corners = np.array([[(lo, hi)[b][k] for k, b in enumerate(bits)] for bits in product((0, 1), repeat=3)])
    edges = []
    for a in range(8):
        for b in range(a + 1, 8):
            if np.count_nonzero(corners[a] != corners[b]) == 1:
                edges.append(np.column_stack([corners[a], corners[b]]))
    return edges


def plot_calibration_workspace(result: AutomatedCalibrationResult, obstacles: tuple[Obstacle, ...], search_box: np.ndarray,
                               guideways: np.ndarray | None = None, path: str | Path | None = None, title: str = "") -> Any:
    """The remaining workspace points, the obstacle boxes, the search box and the chosen poses (Figs. 5.23-5.24).

    Parameters
    ----------
    result : AutomatedCalibrationResult
        The result (its remaining grid points and the last round's poses).
    obstacles : tuple of Obstacle
        The obstacle boxes.
    search_box : numpy.ndarray, shape (3, 2)
        The box of the grid search [m].
    guideways : numpy.ndarray, shape (3, 2, 3), optional
        The ends of each guideway segment [m].
    path : str or pathlib.Path, optional
        Write the PNG here.
    title : str, optional
        Title.

    Returns
    -------
    matplotlib.figure.Figure
    """
    fig = new_figure(size="plot.figsize")[0]
    fig.clf()
    ax = fig.add_subplot(projection="3d")
    if result.workspace_points is not None and result.workspace_points.size:
        W = result.workspace_points
        ax.scatter(W[:, 0], W[:, 1], W[:, 2], s=1, color="0.7", alpha=0.3, label="calibration workspace (grid)")
    for e in _box_edges(search_box[:, 0], search_box[:, 1]):
        ax.plot(*e, "k-", linewidth=0.5)
    for o in obstacles:
        for e in _box_edges(o.lo, o.hi):
            ax.plot(*e, "b-", linewidth=1.0)
    if guideways is not None:
        for g in guideways:
            ax.plot(*g.T, "k-", linewidth=3)
    if result.rounds:
        T = result.final.T
        ax.scatter(T[:, 0], T[:, 1], T[:, 2], s=12, color="r", label=f"{T.shape[0]} poses")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_zlabel("z [m]")
    ax.legend(fontsize=7)
    ax.set_title(title, fontsize=9)
    return save(fig, path)
