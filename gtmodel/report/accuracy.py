"""Plots of pose accuracy analyses: worst-case maps (Figs. 4.8/4.10), face areas (Fig. 4.9), error sets.

Over :class:`~gtmodel.calibration.accuracy.PoseAccuracyResult` cases: the level plot of
the worst TCP error over the workspace section with the actuators marked, the areas of the
parallelepiped's faces along a line through the section, and at one check pose the error
set: the corners of the geometric method, the parallelepiped, the exact worst case and the
Monte-Carlo cloud.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from gtmodel.calibration.accuracy import CaseResult, NominalPoses, parallelepiped
from gtmodel.calibration.accuracy.geometric import CORNER_SIGNS
from gtmodel.report._figure import new_figure, save

__all__ = ["plot_accuracy_map", "plot_face_areas", "plot_error_set"]

#: m -> um.
UM = 1e6


def plot_accuracy_map(case: CaseResult, actuators: np.ndarray, path: str | Path | None = None, title: str = "",
                      line_z: float | None = None) -> Any:
    """Level plot of the worst TCP error over a yz section, actuators as black squares (Fig. 4.8).

    Parameters
    ----------
    case : CaseResult
        One case of a pose accuracy result (its parallelepiped map, equal to the exact NLP
        to a few nm, is drawn).
    actuators : numpy.ndarray, shape (3, 2)
        The guideways' crossings of the section ``(y, z)`` [m].
    path : str or pathlib.Path, optional
        Write the PNG here.
    title : str, optional
        Title prefix.
    line_z : float, optional
        Draw the dashed line ``z = line_z`` (the line of :func:`plot_face_areas`).

    Returns
    -------
    matplotlib.figure.Figure
    """
    fig, ax = new_figure(size="plot.figsize")
    m = case.map
    Y, Z = np.meshgrid(m.ys, m.zs, indexing="ij")
    levels = np.linspace(np.nanmin(m.parallelepiped), np.nanmax(m.parallelepiped), 12) * UM
    cs = ax.contourf(Y, Z, m.parallelepiped * UM, levels=levels, cmap="viridis")
    ax.contour(Y, Z, m.parallelepiped * UM, levels=levels, colors="k", linewidths=0.3)
    fig.colorbar(cs, ax=ax, label="largest TCP error [um]")
    ax.plot(actuators[:, 0], actuators[:, 1], "ks", markersize=9, label="actuators")
    for i, (y, z) in enumerate(actuators):
        ax.annotate(str(i + 1), (y, z), textcoords="offset points", xytext=(6, 4))
    for c in case.checks:
        if not c.label.startswith("pose"):
            ax.plot(c.T[1], c.T[2], "r+", markersize=10)
            ax.annotate(f"{c.label} {c.exact.error * UM:.0f}", (c.T[1], c.T[2]), color="r", fontsize=7,
                        textcoords="offset points", xytext=(4, -10))
    if line_z is not None:
        ax.axhline(line_z, color="w", linestyle="--", linewidth=1.0)
    ax.set_xlabel("y [m]")
    ax.set_ylabel("z [m]")
    ax.set_aspect("equal")
    ax.set_title(f"{title}{case.case.name}: worst-case TCP error, x = {case.map.nominal.T[0, 0]:.3g} m")
    return save(fig, path)


def plot_face_areas(case: CaseResult, line_z: float, path: str | Path | None = None, title: str = "") -> Any:
    """Areas of the parallelepiped's face pairs along ``z = line_z`` (Fig. 4.9).

    Parameters
    ----------
    case : CaseResult
        One case of a pose accuracy result.
    line_z : float
        The line's z [m] (the nearest grid line is used).
    path : str or pathlib.Path, optional
        Write the PNG here.
    title : str, optional
        Title prefix.

    Returns
    -------
    matplotlib.figure.Figure
    """
    m = case.map
    j = int(np.argmin(np.abs(m.zs - line_z)))
    fig, ax = new_figure()
    for i, style in enumerate(("-", "-.", "--")):
        ax.plot(m.ys, m.face_areas[:, j, i] * UM**2, "k" + style, label=f"faces orthogonal to link {i + 1}")
    ax.set_xlabel("y [m]")
    ax.set_ylabel("face area [um^2]")
    ax.legend()
    ax.set_title(f"{title}{case.case.name}: parallelepiped faces along z = {m.zs[j]:.3g} m")
    return save(fig, path)


def plot_error_set(case: CaseResult, check: int = 0, path: str | Path | None = None, title: str = "") -> Any:
    """The error set at a check pose: parallelepiped edges, exact worst case and Monte-Carlo samples (up to 2000).

    Parameters
    ----------
    case : CaseResult
        One case of a pose accuracy result.
    check : int, optional
        Index into ``case.checks``.
    path : str or pathlib.Path, optional
        Write the PNG here.
    title : str, optional
        Title prefix.

    Returns
    -------
    matplotlib.figure.Figure
    """
    c = case.checks[check]
    fig = new_figure(size="plot.figsize")[0]
    fig.clf()
    ax = fig.add_subplot(projection="3d")
    n = case.map.nominal
    k = int(np.argmin(np.linalg.norm(n.T - c.T, axis=1)))
    pp = parallelepiped(NominalPoses(n.T[k:k + 1], n.q[k:k + 1], n.A[k:k + 1], n.u[k:k + 1], n.L, n.v), case.case.tolerances)
    corners = pp.corners[0] * UM
    for a in range(8):
        for b in range(a + 1, 8):
            if np.sum(CORNER_SIGNS[a] != CORNER_SIGNS[b]) == 1:
                ax.plot(*np.column_stack([corners[a], corners[b]]), "k-", linewidth=0.8)
    cloud = c.monte_carlo.deviations[:2000] * UM
    ax.scatter(cloud[:, 0], cloud[:, 1], cloud[:, 2], s=1, color="0.5", alpha=0.4,
               label=f"Monte-Carlo (max {c.monte_carlo.max * UM:.1f} um)")
    d = c.exact.deviation * UM
    ax.scatter(*d, color="r", s=30, label=f"exact worst case {c.exact.error * UM:.1f} um")
    ax.set_xlabel("dx [um]")
    ax.set_ylabel("dy [um]")
    ax.set_zlabel("dz [um]")
    ax.legend(fontsize=7)
    ax.set_title(f"{title}{case.case.name} at {c.label}: parallelepiped (A.4) and exact worst case", fontsize=8)
    return save(fig, path)
