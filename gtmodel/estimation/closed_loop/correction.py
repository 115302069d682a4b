"""Response of a serial arm to real-time pose-offset commands, Cvitanic (2021), eqs. (30)-(33).

The KUKA controller takes a pose-offset command every cycle ``dt = 4 ms`` (RSI) and executes
it after the measured controller delay of 52 ms (13 cycles). Cvitanic models the response to
such commands with the single-mode mass-spring-damper of eq. (8) driven by an "equivalent
force" of the command.

Our reading of eqs. (30)-(32) (a decision, stated once here)
-------------------------------------------------------------
Eq. (30) ``F = command / dt^2`` turns a position command into a force; eqs. (31)-(32)
``F_eq = F_commanded - F_feed`` with ``F_feed = feed_rate / dt`` subtract the part of the
command that is the constant-rate feed. We read ``command`` as the position increment of one
cycle ``dc_k = c_k - c_{k-1}`` of the commanded TCP position ``c``, and the feed as the
increment of the previous cycle ``dc_{k-1} = feed_rate dt`` (a constant feed). Then
``F_eq,k / M = (dc_k - dc_{k-1}) / dt^2 = (c_k - 2 c_{k-1} + c_{k-2}) / dt^2``: the equivalent
force is ``M`` times the commanded acceleration (the second difference of the commanded
position), i.e. only the non-smooth part of the command; a feed at a constant rate gives
none (:func:`equivalent_force`, coefficients :data:`EQUIVALENT_FORCE_TAPS`). ``M``, the mass
the command accelerates, is the dominant modal mass of the direction (:data:`TABLE_16`, mean
over its poses: an assumption).

Response model (both the "truth" and the fitted model)
-------------------------------------------------------
The TCP position is the commanded position plus the structural deflection, the base-excited
compliance of eq. (8) under the equivalent force (held over each cycle, zero-order hold)::

    p_k = c_k + delta_k,     delta = - H(s) F_eq,     H(s) = sum_i 1 / (m_i s^2 + c_i s + k_i)

so a constant-rate feed is followed exactly and a single offset command ``d`` moves the TCP
by ``d`` plus a decaying vibration. With one mode and ``m = M`` this is the classical base
excitation ``m delta'' + c delta' + k delta = -m c''``.

The "truth" (the richer simulation) and its assumptions
--------------------------------------------------------
:func:`truth_model` builds per direction a two-mode response at a pose ``(j2, j3)`` of the
joint-2/joint-3 plane, every ingredient labelled:

- dominant mode: mean of Cvitanic (2021), Table 16 over its 12 poses (mass ``m_1``, damping
  ratio ``zeta_1``, stiffness ``k_1``) -- THESIS DATA, pose coordinates not given;
- second mode: mean of Table 17 (stiffness ``k_2``, frequency ``f_2``), damping ratio
  ``zeta_2 = zeta_1`` -- ASSUMPTION (Table 17 gives no damping);
- pose dependence: both stiffnesses scaled by ``C_dd(theta_ref) / C_dd(theta)`` where
  ``C = [J K_theta^-1 J^T]`` (translation block) is the joint-spring compliance of eq. (3) of
  the ILLUSTRATIVE serial arm (:mod:`gtmodel.robots.serial`, ASSUMED geometry) with the
  Table 2 DPP joint stiffnesses, joints 1, 4, 5, 6 held at :data:`WRIST_JOINTS_DEG`
  (ASSUMPTION) and ``theta_ref`` the centroid of the Table 12 poses; masses do not vary with
  the pose (ASSUMPTION), so the frequencies scale with ``sqrt`` of the stiffness factor.

:func:`fit_offset_response` fits ONE mode ``(m, c, k)`` to the truth's response to one offset
command (the thesis' calibration experiment), and :func:`offset_response_gp` interpolates the
fits over ``(j2, j3)`` with :class:`~gtmodel.robots.dynamic_stiffness.DynamicStiffnessGP`.
The loop itself (delay, P controller, stability) is :mod:`gtmodel.estimation.closed_loop.correction_loop`.
"""

from __future__ import annotations

import logging
import math
import warnings
from dataclasses import dataclass
from functools import cached_property
from typing import Any

import numpy as np
import scipy.optimize
import scipy.signal

from gtmodel._lazy import lazy_module
from gtmodel._arrays import as_rows, positive_float, positive_int
from gtmodel.defaults import LOOP_PERIOD_S
from gtmodel.errors import InputError
from gtmodel.robots.dynamic_stiffness import DIRECTIONS, DynamicStiffnessGP, ModeFitResult, single_mode_tf
from gtmodel.robots.serial import SerialArm
from gtmodel.status import Status

#: python-control, imported on first use (it imports matplotlib.pyplot: ~2 s of CPU).
control = lazy_module("control")

__all__ = [
    "CYCLE_TIME_S",
    "CONTROLLER_DELAY_S",
    "DELAY_CYCLES",
    "EQUIVALENT_FORCE_TAPS",
    "CALIBRATION_POSES_DEG",
    "VALIDATION_POSES_DEG",
    "TABLE_16",
    "TABLE_17",
    "TABLE_2_DPP_K_THETA",
    "WRIST_JOINTS_DEG",
    "equivalent_force",
    "OffsetResponseModel",
    "joint_angles",
    "pose_compliance",
    "truth_model",
    "fit_offset_response",
    "offset_response_gp",
]

_log = logging.getLogger("gtmodel")

#: Cycle time of the real-time corrections [s] (Cvitanic (2021), section 5.1; KUKA RSI).
CYCLE_TIME_S = LOOP_PERIOD_S
#: Measured controller delay [s] (Cvitanic (2021), section 5.1).
CONTROLLER_DELAY_S = 0.052
#: The delay in cycles (52 ms / 4 ms).
DELAY_CYCLES = 13
#: FIR coefficients of eqs. (30)-(32) as read above: ``F_eq,k = M (c_k - 2 c_{k-1} + c_{k-2}) / dt^2``.
EQUIVALENT_FORCE_TAPS = (1.0, -2.0, 1.0)

#: Cvitanic (2021), Table 12: calibration poses ``(j2, j3)`` [deg].
CALIBRATION_POSES_DEG = np.array([
    [-33.96, 113.53], [-31.26, 98.33], [-26.47, 81.25], [-19.33, 60.68], [-46.14, 115.56], [-41.59, 100.18],
    [-35.48, 83.05], [-27.42, 62.67], [-57.62, 114.56], [-51.05, 99.27], [-43.49, 82.17], [-34.31, 61.7],
    [-67.45, 110.6], [-59.08, 95.65], [-50.15, 78.59], [-39.74, 57.71]])
#: Cvitanic (2021), Table 13: validation poses ``(j2, j3)`` [deg].
VALIDATION_POSES_DEG = np.array([[-38.53, 107.42], [-34.02, 91.33], [-49.4, 107.92], [-43.22, 91.79], [-59.1, 105.55], [-51.27, 89.57]])

#: Cvitanic (2021), Table 16: dominant mode per direction (columns x, y, z) at 12 test poses [kg, N s/m, N/m].
TABLE_16 = {
    "m": np.array([[166.5, 41.1, 281.5], [174.8, 223.6, 281.4], [166.5, 41.1, 281.5], [173.7, 212.2, 281.4],
                   [165.3, 36.9, 207.8], [252.7, 75.8, 185.4], [165.3, 36.9, 207.8], [252.7, 75.8, 185.4],
                   [190.2, 352.1, 352.5], [234.0, 358.4, 377.2], [338.8, 398.0, 206.1], [351.7, 380.7, 240.2]]),
    "c": np.array([[3261.3, 1486.3, 281.5], [4047.9, 6526.0, 281.4], [3261.3, 1486.3, 281.5], [4165.3, 6527.9, 281.4],
                   [4124.0, 1653.8, 207.8], [6286.9, 4630.5, 185.4], [4124.0, 1653.8, 207.8], [6286.9, 4630.5, 185.4],
                   [3373.0, 5749.9, 352.5], [5285.4, 7255.4, 377.2], [5209.0, 7709.2, 206.1], [5436.9, 7779.0, 240.2]]),
    "k": 1e6 * np.array([[1.900, 5.500, 1.206], [2.790, 5.967, 1.206], [1.900, 5.500, 1.206], [2.974, 5.405, 1.206],
                         [2.098, 5.204, 0.820], [3.346, 2.415, 0.787], [2.098, 5.204, 0.820], [3.346, 2.415, 0.787],
                         [2.204, 2.596, 1.520], [3.114, 3.079, 1.791], [0.479, 5.722, 0.556], [0.500, 5.499, 0.690]]),
}
#: Cvitanic (2021), Table 17: second most dominant mode per direction: stiffness [N/m], frequency [Hz].
TABLE_17 = {
    "k": 1e6 * np.array([[40, 26, 700], [80, 20, 200], [40, 26, 700], [80, 20, 200], [100, 10, 250], [12, 14, 300],
                         [100, 10, 250], [12, 14, 300], [20, 11, 150], [11, 17, 100], [8, 100, 100], [8, 100, 100]], dtype=float),
    "freq_hz": np.array([[48, 24, 50], [60, 25, 82], [48, 24, 50], [60, 25, 82], [60, 28, 55], [26, 25, 47],
                         [60, 28, 55], [26, 25, 47], [26, 48, 70], [26, 26, 90], [66, 90, 92], [66, 90, 92]], dtype=float),
}
#: Cvitanic (2021), Table 2, DPP joint stiffnesses [N m/rad] (the same row as gtmodel.calibration's TABLE_2_K_THETA).
TABLE_2_DPP_K_THETA = np.array([2.86, 2.36, 1.67, 0.24, 0.16, 0.14]) * 1e6
#: ASSUMPTION: joints 1, 4, 5, 6 [deg] while joints 2, 3 span the Table 12/13 plane (not given by the thesis).
WRIST_JOINTS_DEG = (0.0, 0.0, -60.0, 0.0)


def equivalent_force(command: Any, dt: float = CYCLE_TIME_S, mass: float = 1.0, feed_rate: float = 0.0) -> np.ndarray:
    """Equivalent force of a commanded position history, Cvitanic (2021), eqs. (30)-(32).

    ``F_eq,k = mass (c_k - 2 c_{k-1} + c_{k-2}) / dt^2``: eq. (30) ``F = command / dt^2`` with
    the command the increment of cycle ``k``, minus eq. (31)'s feed term (the increment of
    the previous cycle), eq. (32); see the module docstring for this reading. Before the
    record the command moved at the constant ``feed_rate`` (so a constant feed gives zero).

    Parameters
    ----------
    command : array_like, shape (n,)
        Commanded TCP position per cycle (programmed path plus offsets) [m], n >= 1.
    dt : float, optional
        Cycle time [s] (default :data:`CYCLE_TIME_S`).
    mass : float, optional
        The mass the command accelerates [kg] (default 1: the commanded acceleration [m/s^2]).
    feed_rate : float, optional
        Rate of the command before the record [m/s] (default 0: at rest).

    Returns
    -------
    numpy.ndarray, shape (n,)
        Equivalent force per cycle [N] (held over the cycle).

    Raises
    ------
    InputError
        Not a finite 1-D array, or a non-positive ``dt``/``mass``, or a non-finite ``feed_rate``.
    """
    if np.ndim(command) != 1:
        raise InputError(f"command: expected shape (n,), got {np.shape(command)}")
    c = as_rows(np.reshape(command, (-1, 1)), "command", 1)[0][:, 0]
    dt = positive_float(dt, "dt")
    mass = positive_float(mass, "mass")
    if not isinstance(feed_rate, (int, float, np.floating)) or not math.isfinite(feed_rate):
        raise InputError(f"feed_rate: expected a finite number [m/s], got {feed_rate!r}")
    before = c[0] - feed_rate * dt * np.array([2.0, 1.0])
    return mass * np.convolve(np.concatenate([before, c]), EQUIVALENT_FORCE_TAPS, mode="valid") / dt**2


@dataclass(frozen=True)
class OffsetResponseModel:
    """Response of one Cartesian direction to pose-offset commands: modes plus the equivalent force.

    ``p = c + delta``, ``delta = -H(s) F_eq`` with ``H(s) = sum_i 1/(m_i s^2 + c_i s + k_i)``
    (eq. (8), one or more modes) and ``F_eq`` of eqs. (30)-(32) (:func:`equivalent_force`, the
    force held over each cycle). Transfer functions are python-control objects.

    Parameters
    ----------
    m : tuple of float
        Modal masses [kg], > 0 (one per mode).
    c : tuple of float
        Modal dampings [N s/m], > 0.
    k : tuple of float
        Modal stiffnesses [N/m], > 0.
    mass : float
        Mass ``M`` of the equivalent force [kg], > 0.
    dt : float, optional
        Cycle time [s] (default :data:`CYCLE_TIME_S`).

    Raises
    ------
    InputError
        Unequal numbers of ``m, c, k``, no mode, or a non-positive value.
    """

    m: tuple[float, ...]
    c: tuple[float, ...]
    k: tuple[float, ...]
    mass: float
    dt: float = CYCLE_TIME_S

    def __post_init__(self) -> None:
        n = len(self.m)
        if n == 0 or len(self.c) != n or len(self.k) != n:
            raise InputError(f"m, c, k: expected the same number (>= 1) of modes, got {len(self.m)}, {len(self.c)}, {len(self.k)}")
        for name in ("m", "c", "k"):
            object.__setattr__(self, name, tuple(positive_float(v, f"{name}[{i}]") for i, v in enumerate(getattr(self, name))))
        object.__setattr__(self, "mass", positive_float(self.mass, "mass"))
        object.__setattr__(self, "dt", positive_float(self.dt, "dt"))

    @property
    def natural_frequencies_hz(self) -> np.ndarray:
        """``sqrt(k_i/m_i) / (2 pi)`` per mode [Hz], shape (n_modes,)."""
        return np.sqrt(np.array(self.k) / np.array(self.m)) / (2 * np.pi)

    @property
    def damping_ratios(self) -> np.ndarray:
        """``c_i / (2 sqrt(k_i m_i))`` per mode [-], shape (n_modes,)."""
        return np.array(self.c) / (2 * np.sqrt(np.array(self.k) * np.array(self.m)))

    def compliance(self) -> control.TransferFunction:
        """Continuous compliance ``H(s) = sum_i 1/(m_i s^2 + c_i s + k_i)`` [m/N], eq. (8).

        Returns
        -------
        control.TransferFunction
        """
        H = single_mode_tf(self.m[0], self.c[0], self.k[0])
        for m, c, k in zip(self.m[1:], self.c[1:], self.k[1:]):
            H = H + single_mode_tf(m, c, k)
        return H

    @cached_property
    def _discrete_compliance(self) -> tuple[np.ndarray, np.ndarray]:
        """``c2d(H, zoh)`` as numerator and denominator in powers of ``z^-1`` (equal lengths)."""
        num, den = np.zeros(1), np.ones(1)
        for m, c, k in zip(self.m, self.c, self.k):
            # eq. (8) as a state space (scipy's tf path of cont2discrete is 10x slower), exact zero-order hold
            Ad, Bd, Cd, Dd, _ = scipy.signal.cont2discrete(scipy.signal.tf2ss([1.0], [m, c, k]), self.dt, method="zoh")
            n_i, d_i = scipy.signal.ss2tf(Ad, Bd, Cd, Dd)
            n_i = np.asarray(n_i, dtype=float).reshape(-1)
            num = np.polyadd(np.polymul(num, d_i), np.polymul(n_i, den))
            den = np.polymul(den, d_i)
        return np.concatenate([np.zeros(den.size - num.size), num]), np.asarray(den, dtype=float)

    def response_ss(self) -> control.StateSpace:
        """Discrete system from the commanded position ``c_k`` to the TCP position ``p_k`` (no delay).

        ``P(z) = 1 - M c2d(H)(z) (1 - z^-1)^2 / dt^2``: the rigid following plus the deflection
        under the equivalent force of eqs. (30)-(32) (zero-order hold over the cycle).

        Returns
        -------
        control.StateSpace
            Discrete, sample time ``dt``; DC gain 1.
        """
        num, den = self._discrete_compliance
        Hd = control.ss(control.tf(num, den, self.dt))
        force = control.ss(control.tf(list(EQUIVALENT_FORCE_TAPS), [1.0, 0.0, 0.0], self.dt)) * (self.mass / self.dt**2)
        return control.ss([], [], [], [[1.0]], self.dt) - Hd * force

    def position(self, command: Any) -> np.ndarray:
        """TCP position under a commanded position history from rest, ``c + delta``.

        ``delta = -c2d(H) F_eq`` with ``F_eq`` of :func:`equivalent_force` (``scipy.signal.lfilter``
        of the same discrete compliance as :meth:`response_ss`).

        Parameters
        ----------
        command : array_like, shape (n,)
            Commanded position per cycle [m] (at rest at 0 before the record).

        Returns
        -------
        numpy.ndarray, shape (n,)
            TCP position [m].

        Raises
        ------
        InputError
            Not a finite 1-D array.
        """
        if np.ndim(command) != 1:
            raise InputError(f"command: expected shape (n,), got {np.shape(command)}")
        F = equivalent_force(np.concatenate([[0.0], np.asarray(command, dtype=float)]), self.dt, self.mass)[1:]
        num, den = self._discrete_compliance
        return np.asarray(command, dtype=float) - scipy.signal.lfilter(num, den, F)

    def offset_response(self, amplitude: float, n: int) -> tuple[np.ndarray, np.ndarray]:
        """TCP response to ONE offset command (the commanded position steps by ``amplitude`` at cycle 0).

        The thesis' calibration experiment of section 5 (without the controller delay).

        Parameters
        ----------
        amplitude : float
            The offset [m], > 0.
        n : int
            Cycles to return, >= 3.

        Returns
        -------
        t : numpy.ndarray, shape (n,)
            Times ``k dt`` [s].
        p : numpy.ndarray, shape (n,)
            TCP position [m] (``amplitude`` plus the vibration).

        Raises
        ------
        InputError
            Non-positive amplitude or ``n < 3``.
        """
        amplitude = positive_float(amplitude, "amplitude")
        n = positive_int(n, "n")
        if n < 3:
            raise InputError(f"n: expected at least 3 cycles, got {n}")
        return np.arange(n) * self.dt, self.position(np.full(n, amplitude))


def joint_angles(j2_j3_deg: Any, wrist_deg: Any = WRIST_JOINTS_DEG) -> np.ndarray:
    """Full joint angles of poses of the joint-2/joint-3 plane, Cvitanic (2021), Tables 12-13.

    Parameters
    ----------
    j2_j3_deg : array_like, shape (2,) or (N, 2)
        Joint 2 and joint 3 [deg].
    wrist_deg : array_like, shape (4,), optional
        Joints 1, 4, 5, 6 [deg] (default :data:`WRIST_JOINTS_DEG`, an assumption).

    Returns
    -------
    numpy.ndarray, shape (N, 6)
        Joint angles [rad].

    Raises
    ------
    InputError
        Wrong shapes or non-finite values.
    """
    q, _ = as_rows(j2_j3_deg, "j2_j3_deg", 2)
    w, _ = as_rows(wrist_deg, "wrist_deg", 4)
    if w.shape[0] != 1:
        raise InputError(f"wrist_deg: expected shape (4,), got {np.shape(wrist_deg)}")
    w = w[0]
    th = np.column_stack([np.full(len(q), w[0]), q[:, 0], q[:, 1], np.full(len(q), w[1]), np.full(len(q), w[2]), np.full(len(q), w[3])])
    return np.radians(th)


def pose_compliance(arm: SerialArm, theta: Any, k_theta: Any = TABLE_2_DPP_K_THETA) -> np.ndarray:
    """Translational joint-spring compliance ``diag(J K_theta^-1 J^T)[:3]`` per pose, Cvitanic (2021), eq. (3).

    Parameters
    ----------
    arm : SerialArm
        The arm (its joint limits are checked).
    theta : array_like, shape (6,) or (N, 6)
        Joint angles [rad].
    k_theta : array_like, shape (6,), optional
        Joint stiffnesses [N m/rad] (default Table 2 DPP).

    Returns
    -------
    numpy.ndarray, shape (N, 3)
        Compliance in x, y, z under a force in the same direction [m/N].

    Raises
    ------
    InputError
        Wrong shapes, non-finite values, non-positive stiffness, or a pose outside the
        arm's joint limits (the message names the joint).
    """
    th = arm.check_joint_limits(theta)
    out = np.zeros((th.shape[0], 3))
    for r, row in enumerate(th):
        for i in range(3):
            F = np.zeros(6)
            F[i] = 1.0
            out[r, i] = arm.deflection(row, F, k_theta)[i]
    return out


def truth_model(arm: SerialArm, j2_j3_deg: Any, wrist_deg: Any = WRIST_JOINTS_DEG) -> list[dict[str, OffsetResponseModel]]:
    """The pose-dependent two-mode "truth" per direction (the richer simulation), see the module docstring.

    Dominant mode: mean of Table 16; second mode: mean of Table 17 with the damping ratio of
    the dominant mode; stiffnesses scaled by the joint-spring compliance ratio of eq. (3)
    (illustrative arm, Table 2 DPP) against the centroid of the Table 12 poses; masses held.
    Equivalent mass ``M`` = the dominant mass.

    Parameters
    ----------
    arm : SerialArm
        The arm of the pose dependence (and its joint limits).
    j2_j3_deg : array_like, shape (2,) or (N, 2)
        Poses [deg].
    wrist_deg : array_like, shape (4,), optional
        Joints 1, 4, 5, 6 [deg].

    Returns
    -------
    list of dict of str to OffsetResponseModel
        Per pose, ``{"x": ..., "y": ..., "z": ...}`` two-mode models.

    Raises
    ------
    InputError
        Bad poses or a pose outside the joint limits.
    """
    th = joint_angles(j2_j3_deg, wrist_deg)
    C = pose_compliance(arm, th)
    C_ref = pose_compliance(arm, joint_angles(CALIBRATION_POSES_DEG.mean(axis=0), wrist_deg))[0]
    m1 = TABLE_16["m"].mean(axis=0)
    k1 = TABLE_16["k"].mean(axis=0)
    zeta = (TABLE_16["c"] / (2 * np.sqrt(TABLE_16["k"] * TABLE_16["m"]))).mean(axis=0)
    k2 = TABLE_17["k"].mean(axis=0)
    m2 = k2 / (2 * np.pi * TABLE_17["freq_hz"].mean(axis=0)) ** 2
    out = []
    for row in C:
        s = C_ref / row
        models = {}
        for i, d in enumerate(DIRECTIONS):
            ks = (k1[i] * s[i], k2[i] * s[i])
            ms = (m1[i], m2[i])
            cs = tuple(2 * zeta[i] * math.sqrt(kk * mm) for kk, mm in zip(ks, ms))
            models[d] = OffsetResponseModel(ms, cs, ks, float(m1[i]))
        out.append(models)
    return out


def _initial_mode(t: np.ndarray, delta: np.ndarray, mass: float) -> np.ndarray:
    """Start (m, c, k) of the fit from zero crossings and the decay of the vibration."""
    sign = np.signbit(delta)
    cross = np.flatnonzero(sign[1:] != sign[:-1])
    period = 2 * np.mean(np.diff(t[cross])) if cross.size >= 3 else 20 * (t[1] - t[0])
    w = 2 * np.pi / period
    peaks = [np.max(np.abs(delta[a:b])) for a, b in zip(cross[:-1], cross[1:]) if b > a]
    ratio = peaks[2] / peaks[0] if len(peaks) >= 3 and peaks[0] > 0 and peaks[2] > 0 else 0.5
    zeta = float(np.clip(-np.log(ratio) / (2 * np.pi), 0.01, 0.5))
    return np.array([mass, 2 * zeta * mass * w, mass * w**2])


def fit_offset_response(p: Any, amplitude: float, mass: float, dt: float = CYCLE_TIME_S) -> ModeFitResult:
    """Fit one mode ``(m, c, k)`` to the response to one offset command, Cvitanic (2021), eqs. (8), (30)-(32).

    Model: :class:`OffsetResponseModel` with one mode and equivalent mass ``mass``; start
    from the zero crossings and the decay of ``p - amplitude``; refinement by nonlinear least
    squares (``scipy.optimize.least_squares`` on ``log(m, c, k)``) of the response error.

    Parameters
    ----------
    p : array_like, shape (n,)
        Measured TCP position after the command at cycle 0 [m], n >= 20.
    amplitude : float
        The offset [m], > 0.
    mass : float
        Mass of the equivalent force [kg], > 0.
    dt : float, optional
        Cycle time [s].

    Returns
    -------
    ModeFitResult
        ``m, c, k``, their standard deviations, frequency, damping ratio;
        ``rms_relative_error`` is the RMS of the residual over the RMS of the vibration
        ``p - amplitude``. Status ``"optimal"`` if the solver converged, else ``"error"``.

    Raises
    ------
    InputError
        Bad shapes or values.
    """
    y, _ = as_rows(np.asarray(p, dtype=float).reshape(-1, 1), "p", 1)
    y = y[:, 0]
    if y.size < 20:
        raise InputError(f"p: expected at least 20 cycles, got {y.size}")
    amplitude = positive_float(amplitude, "amplitude")
    mass = positive_float(mass, "mass")
    dt = positive_float(dt, "dt")
    n = y.size
    t = np.arange(n) * dt
    delta = y - amplitude
    scale = max(float(np.sqrt(np.mean(delta**2))), 1e-300)
    p0 = _initial_mode(t, delta, mass)

    def residual(logp: np.ndarray) -> np.ndarray:
        m, c, k = np.exp(logp)
        model = OffsetResponseModel((m,), (c,), (k,), mass, dt)
        return (model.offset_response(amplitude, n)[1] - y) / scale

    sol = scipy.optimize.least_squares(residual, np.log(p0), method="lm", xtol=1e-12, ftol=1e-12)
    m, c, k = np.exp(sol.x)
    r = sol.fun
    try:
        cov_log = (r @ r / max(r.size - 3, 1)) * np.linalg.inv(sol.jac.T @ sol.jac)
        std = np.exp(sol.x) * np.sqrt(np.clip(np.diag(cov_log), 0, None))
    except np.linalg.LinAlgError:
        std = np.full(3, np.inf)
    return ModeFitResult(
        status=Status.OPTIMAL if sol.success else Status.ERROR,
        message=str(sol.message),
        m=float(m), c=float(c), k=float(k), std=std,
        natural_frequency_hz=float(np.sqrt(k / m) / (2 * np.pi)),
        damping_ratio=float(c / (2 * np.sqrt(k * m))),
        rms_relative_error=float(np.sqrt(np.mean(r**2))),
        initial=p0,
    )


def offset_response_gp(j2_j3_deg: Any, fits: list[dict[str, ModeFitResult]], seed: int = 0) -> DynamicStiffnessGP:
    """GPR of the fitted ``(m, c, k)`` per direction over the joint-2/joint-3 plane, Cvitanic (2021), section 5.

    Parameters
    ----------
    j2_j3_deg : array_like, shape (N, 2)
        Calibration poses [deg] (inputs in rad), N >= 3.
    fits : list of dict of str to ModeFitResult
        Per pose, a fit per direction ``"x", "y", "z"``.
    seed : int, optional
        Seed of the optimiser.

    Returns
    -------
    DynamicStiffnessGP
        With ``n_inputs=2``; predict with ``numpy.radians(j2_j3_deg)``.

    Raises
    ------
    InputError
        Shapes that do not match, or a missing direction.
    """
    q, _ = as_rows(j2_j3_deg, "j2_j3_deg", 2)
    if len(fits) != q.shape[0]:
        raise InputError(f"fits: expected one entry per pose ({q.shape[0]}), got {len(fits)}")
    try:
        arr = {n: np.array([[getattr(f[d], n) for d in DIRECTIONS] for f in fits]) for n in ("m", "c", "k")}
    except (KeyError, TypeError):
        raise InputError(f"fits: expected per pose a mapping with the directions {', '.join(DIRECTIONS)}") from None
    from sklearn.exceptions import ConvergenceWarning

    with warnings.catch_warnings():  # hyperparameters at their bounds on 16 smooth points: expected, not news
        warnings.simplefilter("ignore", ConvergenceWarning)
        return DynamicStiffnessGP(np.radians(q), arr["m"], arr["c"], arr["k"], seed=seed, n_inputs=2)
