"""Plots of a closed-loop tracking run (Dressler (2012), ch. 7.3): actuator error, tool error, tool path.

Plain arrays in (rows are samples, SI units), PNG files out; matplotlib's object API, no
pyplot state (safe under ``Agg``).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from gtmodel.report._figure import new_figure, save

__all__ = ["plot_actuator_error", "plot_tool_error", "plot_tool_path", "plot_deflection"]



def _unit(x: np.ndarray) -> tuple[float, str]:
    """Scale and name of the plotted unit: mm from 1 mm on, um below."""
    return (1e3, "mm") if np.abs(x).max(initial=0.0) >= 1e-3 else (1e6, "um")


def _errors(t: Any, e: Any, labels: tuple[str, ...], ylabel: str, path: str | Path, title: str, end_time: float | None,
            extra: Any = None, extra_label: str = "") -> Any:
    t = np.asarray(t, dtype=float)
    e = np.asarray(e, dtype=float)
    scale, unit = _unit(e)
    fig, axes = new_figure(len(labels), 1, "plot.tall", sharex=True, squeeze=False)
    for i, label in enumerate(labels):
        ax = axes[i, 0]
        ax.plot(t, e[:, i] * scale, lw=1, label=label)
        if extra is not None:
            ax.plot(t, np.asarray(extra, dtype=float)[:, i] * scale, lw=1, label=f"{extra_label} {'xyz'[i]}")
        if end_time is not None:
            ax.axvline(end_time, color="k", ls=":", lw=1, label="end of the motion")
        ax.legend(loc="upper right", fontsize="small")
        ax.set_ylabel(f"{label} [{unit}]")
        ax.grid(True)
    axes[-1, 0].set_xlabel("t [s]")
    fig.suptitle(f"{title}: {ylabel}" if title else ylabel)
    return save(fig, path)


def plot_actuator_error(t: Any, error: Any, path: str | Path, title: str = "", end_time: float | None = None) -> Any:
    """Actuator tracking error ``q - q_ref`` of each actuator against time.

    Parameters
    ----------
    t : array_like, shape (N,)
        Times [s].
    error : array_like, shape (N, 3)
        ``q - q_ref`` [m] (plotted in mm from 1 mm on, else um).
    path : str or pathlib.Path
        PNG file to write.
    title : str, optional
        Figure title.
    end_time : float, optional
        End of the reference motion [s] (a dotted line).

    Returns
    -------
    matplotlib.figure.Figure
        The figure, written to ``path``.
    """
    return _errors(t, error, ("q1 - q1_ref", "q2 - q2_ref", "q3 - q3_ref"), "actuator error", path, title, end_time)


def plot_tool_error(t: Any, error: Any, path: str | Path, title: str = "", end_time: float | None = None, deflection: Any = None) -> Any:
    """Tool tracking error ``z - T_ref`` in x, y, z against time, with the deflection part.

    Parameters
    ----------
    t : array_like, shape (N,)
        Times [s].
    error : array_like, shape (N, 3)
        ``z - T_ref`` [m] (plotted in mm from 1 mm on, else um).
    path : str or pathlib.Path
        PNG file to write.
    title : str, optional
        Figure title.
    end_time : float, optional
        End of the reference motion [s] (a dotted line).
    deflection : array_like, shape (N, 3), optional
        Structural deflection ``d`` [m], drawn beside the error.

    Returns
    -------
    matplotlib.figure.Figure
        The figure, written to ``path``.
    """
    return _errors(t, error, ("x - x_ref", "y - y_ref", "z - z_ref"), "tool error", path, title, end_time, deflection, "deflection")


def plot_tool_path(T_ref: Any, z: Any, path: str | Path, title: str = "") -> Any:
    """Tool path: reference against the true tool position, in the xy, yz and xz planes.

    Parameters
    ----------
    T_ref : array_like, shape (N, 3)
        Tool reference [m].
    z : array_like, shape (N, 3)
        True tool position [m].
    path : str or pathlib.Path
        PNG file to write.
    title : str, optional
        Figure title.

    Returns
    -------
    matplotlib.figure.Figure
        The figure, written to ``path``.
    """
    T_ref = np.asarray(T_ref, dtype=float)
    z = np.asarray(z, dtype=float)
    fig, axes = new_figure(1, 3, (11, 3.8), squeeze=False)
    for ax, (a, b) in zip(axes[0], (("x", "y"), ("y", "z"), ("x", "z"))):
        i, j = "xyz".index(a), "xyz".index(b)
        ax.plot(T_ref[:, i], T_ref[:, j], "k--", lw=1, label="reference")
        ax.plot(z[:, i], z[:, j], lw=1, label="tool")
        ax.set_xlabel(f"{a} [m]")
        ax.set_ylabel(f"{b} [m]")
        ax.set_aspect("equal", adjustable="datalim")
        ax.grid(True)
    axes[0, 0].legend(fontsize="small")
    fig.suptitle(f"{title}: tool path" if title else "tool path")
    return save(fig, path)


def plot_deflection(t: Any, deflection: Any, path: str | Path, title: str = "", end_time: float | None = None) -> Any:
    """Structural deflection ``d`` of the tool from its kinematic position (x, y, z) against time.

    Dressler (2012), eq. 6.14.

    Parameters
    ----------
    t : array_like, shape (N,)
        Times [s].
    deflection : array_like, shape (N, 3)
        ``d = z - T_kin`` [m].
    path : str or pathlib.Path
        PNG file to write.
    title : str, optional
        Figure title.
    end_time : float, optional
        End of the reference motion [s] (a dotted line).

    Returns
    -------
    matplotlib.figure.Figure
        The figure, written to ``path``.
    """
    return _errors(t, deflection, ("d_x", "d_y", "d_z"), "structural deflection", path, title, end_time)
