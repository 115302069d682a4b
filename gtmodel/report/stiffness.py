"""Plots of static stiffness over the workspace (:mod:`gtmodel.robots.stiffness`)."""

from __future__ import annotations

import textwrap
from pathlib import Path
from typing import Any

import numpy as np

from gtmodel.errors import InputError
from gtmodel.robots.stiffness import MEASURED_D1_N_PER_UM, N_PER_UM, StiffnessMap
from gtmodel.report._figure import new_figure, save

__all__ = ["plot_stiffness_map"]


def plot_stiffness_map(
    smap: StiffnessMap,
    path: str | Path | None = None,
    quantity: str = "min",
    axes: tuple[int, int] = (1, 2),
    ax: Any = None,
    title: str = "",
) -> Any:
    """Colour map of a stiffness quantity over a workspace section, with the stated values.

    Parameters
    ----------
    smap : StiffnessMap
        From :meth:`GantryTau3Stiffness.stiffness_map`.
    path : str or pathlib.Path, optional
        Write the figure as PNG here.
    quantity : {"min", "x", "y", "z", "deflection"}, optional
        Smallest principal stiffness, stiffness along an axis [N/um], or the norm of the
        gravity deflection [um].
    axes : tuple of int, optional
        Coordinates on the plot axes (default ``(1, 2)``: a yz section).
    ax : matplotlib.axes.Axes, optional
        Draw into these axes (default: a new figure, not registered with pyplot).
    title : str, optional
        Title prefix.

    Returns
    -------
    matplotlib.figure.Figure

    Raises
    ------
    InputError
        Unknown quantity or axes.
    """
    values = {
        "min": lambda m: m.min_stiffness / N_PER_UM,
        "x": lambda m: m.axis_stiffness[:, 0] / N_PER_UM,
        "y": lambda m: m.axis_stiffness[:, 1] / N_PER_UM,
        "z": lambda m: m.axis_stiffness[:, 2] / N_PER_UM,
        "deflection": lambda m: np.linalg.norm(m.gravity_deflection, axis=1) * 1e6,
    }
    if quantity not in values:
        raise InputError(f"quantity: expected one of {', '.join(values)}, got {quantity!r}")
    if len(axes) != 2 or any(a not in (0, 1, 2) for a in axes) or axes[0] == axes[1]:
        raise InputError(f"axes: expected two different coordinates of 0, 1, 2, got {axes!r}")
    val = values[quantity](smap)
    if ax is None:
        fig, ax = new_figure(size=(6.4, 5))
    else:
        fig = ax.figure
    a, b = axes
    P = smap.T
    sc = ax.scatter(P[:, a], P[:, b], c=val, cmap="viridis", s=40, marker="s")
    label = "gravity deflection |dT| [um]" if quantity == "deflection" else (
        "smallest principal stiffness [N/um]" if quantity == "min" else f"stiffness along {quantity} [N/um]"
    )
    fig.colorbar(sc, ax=ax, label=label)
    ax.set_xlabel(f"{'xyz'[a]} [m]")
    ax.set_ylabel(f"{'xyz'[b]} [m]")
    ax.set_aspect("equal")
    lo, hi = MEASURED_D1_N_PER_UM
    unit = "um" if quantity == "deflection" else "N/um"
    stated = textwrap.fill(f"stated: {smap.stiffness.describe()}, payload {smap.payload_kg:g} kg", 72)
    ax.set_title(
        f"{title + ': ' if title else ''}{label.split(' [')[0]}: {val.min():.3g}-{val.max():.3g} {unit}"
        + ("" if quantity == "deflection" else f"\n(D1 measured {lo:g}-{hi:g} N/um)")
        + f"\n{stated}",
        fontsize=8,
    )
    return save(fig, path, bbox_inches="tight")
