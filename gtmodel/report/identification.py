"""Plots of dynamic identification (Dressler (2012), ch. 6.2): measured vs model forces, residuals."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from gtmodel.calibration import DynamicRegressor
from gtmodel.report._figure import new_figure, save

__all__ = ["plot_identification_residuals"]


def plot_identification_residuals(robot: Any, configuration: int, variant: str, samples: Any, result: Any, path: str | Path, title: str = "") -> Any:
    """Plot filtered measured forces against the identified model, and the residuals.

    Top row: per actuator the measured (filtered) force and the model force ``Y theta +
    tau_0`` (eqs. 6.7-6.8) passed through the same filter (parallel filtering); bottom row:
    the residual against the cart velocity, with the band below ``min_speed`` that was not
    fitted.

    Parameters
    ----------
    robot : RobotParameters
        The model's parameter set (kinematics, gravity, friction).
    configuration : int
        IK configuration.
    variant : str
        The identified variant (a name of the Table 6.3 variants), e.g. ``"model_2"``.
    samples : DynamicSamples
        The filtered data (:func:`gtmodel.calibration.preprocess_log`): ``t`` shape (K,)
        [s], ``x``, ``x_dot``, ``x_ddot``, ``tau`` shape (K, 3), ``coordinates``,
        ``smoother``.
    result : DynamicIdentificationResult
        The identification of ``variant`` (``theta``, ``residual_rms`` [N],
        ``info["min_speed"]`` [m/s]).
    path : str or pathlib.Path
        PNG file to write.
    title : str, optional
        Figure title (the residual RMS is appended).

    Returns
    -------
    matplotlib.figure.Figure
        The figure, written to ``path``.
    """
    s = samples
    reg = DynamicRegressor(robot, variant, configuration)
    Y, tau0, q_dot = reg.evaluate(s.x, s.x_dot, s.x_ddot, s.coordinates)
    tau_hat = Y @ result.theta + tau0
    if s.smoother is not None:  # the forces went through this filter; so does the model (parallel filtering)
        tau_hat = s.smoother(tau_hat)
    fig, ax = new_figure(2, 3, sharex="row", size=(13, 6.5))
    for i in range(3):
        ax[0, i].plot(s.t, s.tau[:, i], lw=0.8, label="measured (filtered)")
        ax[0, i].plot(s.t, tau_hat[:, i], lw=0.8, ls="--", label="model (same filter)")
        ax[0, i].set_title(f"actuator {i + 1}")
        ax[0, i].set_xlabel("t [s]")
        ax[1, i].plot(q_dot[:, i], s.tau[:, i] - tau_hat[:, i], ".", ms=2)
        ax[1, i].axvspan(-result.info["min_speed"], result.info["min_speed"], color="0.9", label="not fitted")
        ax[1, i].set_xlabel("cart velocity [m/s]")
    ax[0, 0].set_ylabel("force [N]")
    ax[1, 0].set_ylabel("residual [N]")
    ax[0, 0].legend(fontsize=8)
    ax[1, 0].legend(fontsize=8)
    fig.suptitle(f"{title}: residual RMS {np.round(result.residual_rms, 2).tolist()} N")
    return save(fig, path)
