"""The controller Functions the codegen tests generate C for: the real ones of gtmodel.estimation.

- ``kalman_step_function(d, dt)``: :meth:`gtmodel.estimation.StationaryKalman.step_function`
  for ``d`` directions (the per-direction model x = [p, v, a], measurements
  y = [z_kin; a_m]) with the x-direction noise figures of the L1 defaults.
- ``ilc_correction_function(table)``: :func:`gtmodel.estimation.ilc_correction_function`.
- ``learned_table(n, d, seed)``: a plausible learned table (test data, not a model).
- ``fusion_filter(rotation)``: :class:`gtmodel.estimation.KalmanFilter` (3-axis, nx 9) or
  :class:`~gtmodel.estimation.ExtendedKalmanFilter` (19-D) of the tracker + IMU fusion at
  1 kHz with noise figures of the order of Cvitanic (2021), Table 7; ``.step_function()`` is
  the ``"kf_step"``/``"ekf_step"`` Function the C is generated from.
"""

from __future__ import annotations

import casadi as ca
import numpy as np
import scipy.signal

from gtmodel.estimation import StationaryKalman, ilc_correction_function
from gtmodel.estimation.filters.end_effector import EndEffectorModel
from gtmodel.estimation.filters.kalman import DEFAULT_JERK_NOISE, DEFAULT_POSITION_NOISE, ExtendedKalmanFilter, KalmanFilter

__all__ = ["DT", "FILTER_DT", "kalman_filter", "kalman_step_function", "ilc_correction_function", "learned_table", "fusion_filter"]

DT = 0.004
#: Sample time of the tracker + IMU fusion [s] (1 kHz).
FILTER_DT = 0.001


def kalman_filter(d: int = 3, dt: float = DT) -> StationaryKalman:
    """The stationary Kalman filter of ``d`` directions (x-direction noise figures of the L1 defaults)."""
    return StationaryKalman(dt=dt, position_noise=DEFAULT_POSITION_NOISE[0], jerk_noise=DEFAULT_JERK_NOISE[0], d=d)


def kalman_step_function(d: int = 3, dt: float = DT) -> ca.Function:
    """``"kalman_step"(x[3d], y[2d]) -> (x_next[3d], z_hat[d])`` of :func:`kalman_filter`."""
    return kalman_filter(d, dt).step_function()


def learned_table(n: int = 400, d: int = 3, seed: int = 0) -> np.ndarray:
    """A plausible learned table ``(n, d)`` [m]: tens of um, smooth, zero at both ends (Tukey window)."""
    t = np.arange(n) * DT
    rng = np.random.default_rng(seed)
    amp = rng.uniform(5e-6, 50e-6, d)
    phase = rng.uniform(0, 2 * np.pi, d)
    u = amp * np.sin(2 * np.pi * 2.5 * t[:, None] + phase)
    return u * scipy.signal.windows.tukey(n, 0.5)[:, None]


def fusion_filter(rotation: bool, dt: float = FILTER_DT, jerk: float = 5.0) -> KalmanFilter | ExtendedKalmanFilter:
    """The KF (``rotation=False``) or EKF of the tracker + IMU fusion: Q from white jerk, R from Table 7-like noise."""
    model = EndEffectorModel(dt, rotation=rotation)
    Q = model.process_noise(jerk, 5.0 if rotation else 0.0)
    R = model.measurement_noise(6.4e-6, 0.012, 2e-5, 1e-3) if rotation else model.measurement_noise(6.4e-6, 0.012)
    x0 = np.zeros(model.nx)
    if rotation:
        x0[9] = 1.0
    cls = ExtendedKalmanFilter if rotation else KalmanFilter
    return cls(model, Q, R, x0, np.eye(model.nx) * 1e-4)
