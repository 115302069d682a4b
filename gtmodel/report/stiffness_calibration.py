"""Plots of joint-stiffness calibration (Cvitanic (2021), Table 2): identified stiffnesses per method."""

from __future__ import annotations

from pathlib import Path
from typing import Any, Mapping, Sequence

import numpy as np

from gtmodel.report._figure import new_figure, save

__all__ = ["plot_joint_stiffness"]


def plot_joint_stiffness(results: Mapping[str, Any], methods: Sequence[str], k_true: np.ndarray | None, path: str | Path, title: str = "") -> Any:
    """Bar plot (log scale) of the identified joint stiffnesses of several methods.

    Parameters
    ----------
    results : Mapping[str, JointStiffnessResult]
        Method name -> result (``k_theta``, ``std_k_theta``, each shape (6,) [N m/rad]).
    methods : sequence of str
        The methods to draw, in order (e.g. ``("CP", "CP_rotations_scaled_x10", "DPP")``);
        ``"CP"`` is labelled "CP (w = 1)".
    k_true : numpy.ndarray or None, shape (6,)
        True stiffnesses of synthetic data [N m/rad], drawn as markers (None: none).
    path : str or pathlib.Path
        PNG file to write.
    title : str, optional
        Figure title.

    Returns
    -------
    matplotlib.figure.Figure
        The figure, written to ``path``.
    """
    joints = np.arange(1, 7)
    width = 0.8 / len(methods)
    fig, ax = new_figure(size=(8, 4.5))
    for i, m in enumerate(methods):
        r = results[m]
        k = np.where(np.isfinite(r.k_theta), r.k_theta, np.nan) / 1e6
        std = np.where(np.isfinite(r.std_k_theta), r.std_k_theta, 0.0) / 1e6
        ax.bar(joints + (i - 1) * width, k, width, yerr=std, capsize=2, label=m if m != "CP" else "CP (w = 1)")
    if k_true is not None:
        ax.scatter(joints, np.asarray(k_true) / 1e6, marker="_", s=400, color="k", zorder=3, label="truth")
    ax.set_yscale("log")
    ax.set_xticks(joints)
    ax.set_xlabel("joint")
    ax.set_ylabel("k_theta [MN m/rad]")
    ax.set_title(title)
    ax.legend(fontsize=8)
    return save(fig, path)
