"""Plots of optimal trajectories, drawn with matplotlib's object API (no screen needed)."""

from __future__ import annotations

from pathlib import Path
from typing import Any, Mapping

import numpy as np

from gtmodel.report._figure import new_figure, save

__all__ = ["plot_tcp_path", "plot_forces", "plot_overlay", "plot_path_profile", "OVERLAY_FILES"]

#: The files :func:`plot_overlay` writes: the cart forces and the TCP paths of every case.
OVERLAY_FILES = ("overlay_forces.png", "overlay_tcp.png")


def plot_tcp_path(traj: Mapping[str, np.ndarray], start, end, path: str | Path, title: str = "") -> Any:
    """Plot the TCP path: coordinates against time and two projections.

    Parameters
    ----------
    traj : Mapping[str, numpy.ndarray]
        Columns ``t, x, y, z`` (each shape (K,)) [s, m], e.g. from
        :meth:`gtmodel.trajectory.point_to_point.PointToPointSolution.trajectory`.
    start, end : array_like, shape (3,)
        Declared end poses [m], marked on the projections.
    path : str or pathlib.Path
        PNG file to write.
    title : str, optional
        Figure title.

    Returns
    -------
    matplotlib.figure.Figure
        The figure, written to ``path``.
    """
    fig, (ax_t, ax_xy, ax_yz) = new_figure(1, 3, size="plot.wide")
    t = traj["t"]
    for c in "xyz":
        ax_t.plot(t, traj[c] - traj[c][0], label=f"{c} - {c}(0)")
    ax_t.set_xlabel("t [s]")
    ax_t.set_ylabel("TCP displacement [m]")
    ax_t.legend()
    ax_t.grid(True)
    for ax, (a, b) in ((ax_xy, ("x", "y")), (ax_yz, ("y", "z"))):
        i, j = "xyz".index(a), "xyz".index(b)
        ax.plot(traj[a], traj[b], "-", label="optimal path")
        ax.plot([start[i], end[i]], [start[j], end[j]], "k:", label="straight line")
        ax.plot(start[i], start[j], "go", label="start")
        ax.plot(end[i], end[j], "rs", label="end")
        ax.set_xlabel(f"{a} [m]")
        ax.set_ylabel(f"{b} [m]")
        ax.set_aspect("equal", adjustable="datalim")
        ax.grid(True)
    ax_xy.legend(fontsize="small")
    fig.suptitle(f"{title}: TCP path" if title else "TCP path")
    return save(fig, path)


def plot_forces(traj: Mapping[str, np.ndarray], force_limit, path: str | Path, title: str = "") -> Any:
    """Plot the three cart forces against their limits.

    Parameters
    ----------
    traj : Mapping[str, numpy.ndarray]
        Columns ``t, tau1, tau2, tau3`` (each shape (K,)) [s, N].
    force_limit : array_like, shape (3,)
        Symmetric force limits [N], drawn as dashed lines.
    path : str or pathlib.Path
        PNG file to write.
    title : str, optional
        Figure title.

    Returns
    -------
    matplotlib.figure.Figure
        The figure, written to ``path``.
    """
    fig, axes = new_figure(3, 1, sharex=True, size="plot.tall")
    t = traj["t"]
    for i, ax in enumerate(axes):
        lim = float(force_limit[i])
        ax.plot(t, traj[f"tau{i + 1}"], label=f"tau{i + 1}")
        ax.axhline(lim, color="r", ls="--", lw=1, label="limit")
        ax.axhline(-lim, color="r", ls="--", lw=1)
        ax.set_ylabel(f"tau{i + 1} [N]")
        ax.set_ylim(-1.15 * lim, 1.15 * lim)
        ax.grid(True)
        ax.legend(loc="upper right", fontsize="small")
    axes[-1].set_xlabel("t [s]")
    fig.suptitle(f"{title}: cart forces" if title else "cart forces")
    return save(fig, path)


def plot_overlay(trajs: Mapping[str, Mapping[str, np.ndarray]], out_dir: str | Path) -> list[Any]:
    """Overlay the forces and TCP paths of several solutions (Dressler (2012), Figs. 3.9-3.10).

    Parameters
    ----------
    trajs : Mapping[str, Mapping[str, numpy.ndarray]]
        Case label -> trajectory columns ``t, x, y, z, tau1, tau2, tau3`` (each (K,)).
    out_dir : str or pathlib.Path
        Folder for ``overlay_forces.png`` and ``overlay_tcp.png``.

    Returns
    -------
    list of matplotlib.figure.Figure
        The forces and the TCP-path figures, written to ``overlay_forces.png`` and
        ``overlay_tcp.png``.
    """
    out_dir = Path(out_dir)
    fig, axes = new_figure(3, 1, sharex=True, size="plot.tall")
    for label, tr in trajs.items():
        for i, ax in enumerate(axes):
            ax.plot(tr["t"] - tr["t"][0], tr[f"tau{i + 1}"], label=label)
    for i, ax in enumerate(axes):
        ax.set_ylabel(f"tau{i + 1} [N]")
        ax.grid(True)
    axes[0].legend(fontsize="small", loc="upper right")
    axes[-1].set_xlabel("t [s]")
    fig.suptitle("cart forces")
    forces = save(fig, out_dir / OVERLAY_FILES[0])

    fig, axes = new_figure(1, 3, size="plot.wide")
    for label, tr in trajs.items():
        for ax, (a, b) in zip(axes, (("x", "y"), ("y", "z"), ("x", "z"))):
            ax.plot(tr[a], tr[b], label=label)
    for ax, (a, b) in zip(axes, (("x", "y"), ("y", "z"), ("x", "z"))):
        ax.set_xlabel(f"{a} [m]")
        ax.set_ylabel(f"{b} [m]")
        ax.set_aspect("equal", adjustable="datalim")
        ax.grid(True)
    axes[0].legend(fontsize="small")
    fig.suptitle("TCP paths")
    return [forces, save(fig, out_dir / OVERLAY_FILES[1])]


def plot_path_profile(solution, path: str | Path, title: str = "") -> Any:
    """Plot a path-constrained profile: ``s_dot`` and ``s_ddot`` against ``s``.

    Parameters
    ----------
    solution : gtmodel.trajectory.path_constrained.PathSolution
        Solution with grid arrays ``s``, ``s_dot``, ``s_ddot`` (each (N,)).
    path : str or pathlib.Path
        PNG file to write.
    title : str, optional
        Figure title.

    Returns
    -------
    matplotlib.figure.Figure
        The figure, written to ``path``.
    """
    fig, (ax1, ax2) = new_figure(2, 1, sharex=True, size=(8, 5))
    s = np.asarray(solution.s)
    ax1.plot(s, np.asarray(solution.s_dot), "-")
    ax1.set_ylabel("s_dot [1/s]")
    ax1.grid(True)
    sdd = np.asarray(solution.s_ddot)
    ax2.step(s[: sdd.size], sdd, where="post")
    ax2.set_ylabel("s_ddot [1/s^2]")
    ax2.set_xlabel("path coordinate s [-]")
    ax2.grid(True)
    fig.suptitle(f"{title}: path profile" if title else "path profile")
    return save(fig, path)
