"""Plots of the lead-through experiments (Dressler (2012), Figures 8.4-8.9 style).

Every function takes plain arrays, draws on a :class:`matplotlib.figure.Figure` (no pyplot
state, safe headless) and returns it:

- :func:`plot_position_force`: tool position and contact force along the normal over time,
  one row per run (Figure 8.4: with and without tool force control; Figure 8.5: per
  correction range);
- :func:`plot_surface_path`: the tool path in the surface's tangent plane;
- :func:`plot_stable_gain`: the largest stable force gain and the loop's oscillation
  frequency against the contact stiffness;
- :func:`plot_peg`: insertion depth, contact force and the peg's angle to the hole axis.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Sequence

import numpy as np

from gtmodel.errors import InputError
from gtmodel.report._figure import new_figure, panel_size, save

__all__ = ["plot_position_force", "plot_surface_path", "plot_stable_gain", "plot_peg"]


def _series(t: Any, values: Any, name: str) -> tuple[np.ndarray, np.ndarray]:
    t = np.asarray(t, dtype=float)
    v = np.asarray(values, dtype=float)
    if t.ndim != 1 or v.shape[0] != t.size:
        raise InputError(f"{name}: expected {t.size} samples (one per time), got shape {v.shape}")
    return t, v


def plot_position_force(runs: Sequence[tuple[str, Any, Any, Any]], path: str | Path | None = None, *, force_reference: float | None = None,
                        title: str = "") -> Any:
    """Tool position and contact force along the normal, one row per run.

    Parameters
    ----------
    runs : sequence of (str, array_like, array_like, array_like)
        ``(label, t (N,) [s], height (N,) [m] (position against the normal, 0 on the
        surface), force (N,) [N])`` per run.
    path : str or pathlib.Path, optional
        PNG file to write.
    force_reference : float, optional
        Drawn as a dashed line [N].
    title : str, optional
        Figure title.

    Returns
    -------
    matplotlib.figure.Figure

    Raises
    ------
    InputError
        No run, or series of unequal length.
    """
    if not runs:
        raise InputError("runs: expected at least one run")
    fig, axes = new_figure(len(runs), 2, size=panel_size(2, len(runs)), squeeze=False)
    for row, (label, t, height, force) in enumerate(runs):
        t, h = _series(t, height, f"{label} height")
        _, f = _series(t, force, f"{label} force")
        axes[row, 0].plot(t, 1e3 * h, lw=0.8)
        axes[row, 0].set_ylabel("height [mm]")
        axes[row, 0].set_title(f"{label}: tool position")
        axes[row, 1].plot(t, f, lw=0.8)
        if force_reference is not None:
            axes[row, 1].axhline(force_reference, color="k", ls="--", lw=0.8)
        axes[row, 1].set_ylabel("contact force [N]")
        axes[row, 1].set_title(f"{label}: tool force")
        for ax in axes[row]:
            ax.grid(True, alpha=0.3)
    for ax in axes[-1]:
        ax.set_xlabel("t [s]")
    if title:
        fig.suptitle(title)
    return save(fig, path)


def plot_surface_path(u: Any, v: Any, contact: Any, path: str | Path | None = None, *, title: str = "") -> Any:
    """The tool path in the surface's tangent plane, in contact and off it.

    Parameters
    ----------
    u, v : array_like, shape (N,)
        Tangent-plane coordinates [m].
    contact : array_like of bool, shape (N,)
        Controller contact state.
    path : str or pathlib.Path, optional
        PNG file.
    title : str, optional
        Title.

    Returns
    -------
    matplotlib.figure.Figure

    Raises
    ------
    InputError
        Series of unequal length.
    """
    u, v = np.asarray(u, dtype=float), np.asarray(v, dtype=float)
    c = np.asarray(contact, dtype=bool)
    if not u.shape == v.shape == c.shape or u.ndim != 1:
        raise InputError(f"u, v, contact: expected equal 1-D shapes, got {u.shape}, {v.shape}, {c.shape}")
    fig, ax = new_figure()
    ax.plot(1e3 * u, 1e3 * v, color="0.7", lw=0.8, label="path")
    ax.plot(1e3 * np.where(c, u, np.nan), 1e3 * np.where(c, v, np.nan), lw=1.5, label="in contact")
    ax.set_xlabel("along the surface [mm]")
    ax.set_ylabel("across [mm]")
    ax.set_title(title or "tool path on the surface")
    ax.legend()
    ax.grid(True, alpha=0.3)
    return save(fig, path)


def plot_stable_gain(stiffness: Any, gain: Any, frequency: Any, path: str | Path | None = None, *, used_gain: float | None = None,
                     title: str = "") -> Any:
    """Largest stable force gain and the loop's oscillation frequency against the stiffness.

    Parameters
    ----------
    stiffness : array_like, shape (S,)
        Contact stiffness [N/m].
    gain : array_like, shape (S,)
        Largest stable gain [m/(N s)].
    frequency : array_like, shape (S,)
        Oscillation frequency of the dominant pole at the gain used [Hz].
    path : str or pathlib.Path, optional
        PNG file.
    used_gain : float, optional
        The controller's gain, drawn as a line.
    title : str, optional
        Title.

    Returns
    -------
    matplotlib.figure.Figure

    Raises
    ------
    InputError
        Series of unequal length.
    """
    k = np.asarray(stiffness, dtype=float)
    _, g = _series(k, gain, "gain")
    _, f = _series(k, frequency, "frequency")
    fig, axes = new_figure(1, 2, size=panel_size(2))
    axes[0].loglog(k, g, "o-")
    if used_gain is not None:
        axes[0].axhline(used_gain, color="k", ls="--", lw=0.8, label="gain used")
        axes[0].legend()
    axes[0].set_xlabel("contact stiffness [N/m]")
    axes[0].set_ylabel("largest stable gain [m/(N s)]")
    axes[1].semilogx(k, f, "o-")
    axes[1].set_xlabel("contact stiffness [N/m]")
    axes[1].set_ylabel("oscillation frequency [Hz]")
    for ax in axes:
        ax.grid(True, which="both", alpha=0.3)
    if title:
        fig.suptitle(title)
    return save(fig, path)


def plot_peg(runs: Sequence[tuple[str, Any, Any, Any, Any]], path: str | Path | None = None, *, depth: float | None = None,
             title: str = "") -> Any:
    """Insertion depth, contact force and angle to the hole axis, per run (Figures 8.7-8.9 style).

    Parameters
    ----------
    runs : sequence of (str, array_like, array_like, array_like, array_like)
        ``(label, t (N,) [s], insertion (N,) [m], force (N,) [N], angle (N,) [deg])``.
    path : str or pathlib.Path, optional
        PNG file.
    depth : float, optional
        Hole depth [m], drawn as a line.
    title : str, optional
        Title.

    Returns
    -------
    matplotlib.figure.Figure

    Raises
    ------
    InputError
        No run, or series of unequal length.
    """
    if not runs:
        raise InputError("runs: expected at least one run")
    fig, axes = new_figure(1, 3, size=panel_size(3))
    for label, t, ins, force, angle in runs:
        t, ins = _series(t, ins, f"{label} insertion")
        _, force = _series(t, force, f"{label} force")
        _, angle = _series(t, angle, f"{label} angle")
        axes[0].plot(t, 1e3 * ins, lw=0.8, label=label)
        axes[1].plot(t, force, lw=0.8, label=label)
        axes[2].plot(t, angle, lw=0.8, label=label)
    if depth is not None:
        axes[0].axhline(1e3 * depth, color="k", ls="--", lw=0.8, label="hole depth")
    for ax, ylabel in zip(axes, ("insertion [mm]", "contact force [N]", "peg to hole axis [deg]")):
        ax.set_xlabel("t [s]")
        ax.set_ylabel(ylabel)
        ax.grid(True, alpha=0.3)
    axes[0].legend()
    if title:
        fig.suptitle(title)
    return save(fig, path)
