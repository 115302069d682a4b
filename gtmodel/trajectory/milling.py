"""Mechanistic milling force and pose optimisation over the spindle angle, Cvitanic (2021), section 3.

Placed in :mod:`gtmodel.trajectory` (not :mod:`gtmodel.robots`): it is task planning on top
of the robot models: the milling process is not a robot equation, and choosing the
redundant angle ``A`` of a 5-axis milling pose is a motion-planning decision, like the
trajectories of this package.

Milling force, eqs. (12)-(17) (Altintas' mechanistic model with edge and cutting
coefficients, Table 3). Tooth ``j`` of ``N`` is at ``phi_j = phi + 2 pi j / N`` (``phi``
measured clockwise from the +y axis of the workpiece frame, x = feed direction, z = tool
axis). While ``phi_st <= phi_j <= phi_ex`` (entry/exit angles) it cuts a chip of thickness
``h = f_t sin(phi_j)`` over the axial depth ``a``::

    F_t = K_tc a h + K_te a,   F_r = K_rc a h + K_re a,   F_a = K_ac a h + K_ae a
    F_x = -F_t cos(phi_j) - F_r sin(phi_j),  F_y = F_t sin(phi_j) - F_r cos(phi_j),  F_z = F_a

summed over the teeth in cut. The force is one CasADi expression in ``phi``
(:attr:`MillingProcess.force_function`), evaluated on a grid.

Pose optimisation: the spindle is symmetric, so the rotation ``A`` of the TCP frame about
the spindle axis is redundant; it is searched on a grid (1 deg by default). The force is
fixed in the workpiece frame (independent of ``A``); the arm's configuration
``theta(A)`` (inverse kinematics with continuation in ``A``) and thus its compliance
change. Objectives:

* static, eq. (18): ``|| [K_x(theta)^-1 [F_peak; 0]]_translation ||`` with ``F_peak`` the
  force at the instant of largest magnitude [m];
* dynamic, eq. (19): ``max_t || x(t) ||`` of the per-direction single-mode models
  (:func:`gtmodel.robots.dynamic_stiffness.simulate_single_mode`) driven from rest by the
  time-varying force [m] (optionally only after a settling time, i.e. the steady-state
  vibration without the entry transient).
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass, field
from functools import cached_property
from typing import Any, Callable

import casadi as ca
import numpy as np

from gtmodel._arrays import positive_float
from gtmodel._geometry import rot_z
from gtmodel.errors import ConvergenceError, InputError, SingularConfigurationError
from gtmodel.robots.dynamic_stiffness import DynamicStiffnessGP, simulate_single_mode
from gtmodel.robots.serial import SerialArm
from gtmodel.status import Status, StatusResult

__all__ = [
    "MillingCoefficients",
    "TABLE_3_COEFFICIENTS",
    "MillingProcess",
    "SpindleAngleResult",
    "spindle_angle_poses",
    "optimise_spindle_angle",
]

_log = logging.getLogger("gtmodel")


@dataclass(frozen=True)
class MillingCoefficients:
    """Edge and cutting force coefficients of the mechanistic model, Cvitanic (2021), Table 3.

    Parameters
    ----------
    K_te : float
        Tangential edge coefficient [N/m].
    K_tc : float
        Tangential cutting coefficient [N/m^2].
    K_re : float
        Radial edge coefficient [N/m].
    K_rc : float
        Radial cutting coefficient [N/m^2].
    K_ae : float
        Axial edge coefficient [N/m].
    K_ac : float
        Axial cutting coefficient [N/m^2].

    Raises
    ------
    InputError
        A negative or non-finite coefficient.
    """

    K_te: float
    K_tc: float
    K_re: float
    K_rc: float
    K_ae: float
    K_ac: float

    def __post_init__(self) -> None:
        for name in ("K_te", "K_tc", "K_re", "K_rc", "K_ae", "K_ac"):
            v = getattr(self, name)
            if not isinstance(v, (int, float)) or not math.isfinite(v) or v < 0:
                raise InputError(f"MillingCoefficients.{name}: expected a finite number >= 0, got {v!r}")


#: Cvitanic (2021), Table 3.
TABLE_3_COEFFICIENTS = MillingCoefficients(K_te=6.0899e3, K_tc=9.0377e8, K_re=6.6017e3, K_rc=2.9379e8, K_ae=1.1169e3, K_ac=2.7783e8)


class MillingProcess:
    """A milling operation: cutter, cutting conditions and the force model (12)-(17).

    Parameters
    ----------
    n_teeth : int
        Number of teeth ``N`` (>= 1).
    spindle_speed_rpm : float
        Spindle speed [rev/min] (> 0; the only non-SI unit, at the user boundary).
    feed_per_tooth : float
        Feed per tooth ``f_t`` [m] (> 0).
    axial_depth : float
        Axial depth of cut ``a`` [m] (> 0).
    entry_angle : float
        ``phi_st`` [rad], in [0, pi).
    exit_angle : float
        ``phi_ex`` [rad], in (phi_st, pi].
    coefficients : MillingCoefficients, optional
        Force coefficients (default Table 3).

    Raises
    ------
    InputError
        Any value out of range.
    """

    def __init__(
        self,
        n_teeth: int,
        spindle_speed_rpm: float,
        feed_per_tooth: float,
        axial_depth: float,
        entry_angle: float = 0.0,
        exit_angle: float = math.pi,
        coefficients: MillingCoefficients = TABLE_3_COEFFICIENTS,
    ) -> None:
        if isinstance(n_teeth, bool) or not isinstance(n_teeth, (int, np.integer)) or n_teeth < 1:
            raise InputError(f"n_teeth: expected an integer >= 1, got {n_teeth!r}")
        self.n_teeth = int(n_teeth)
        self.spindle_speed_rpm = positive_float(spindle_speed_rpm, "spindle_speed_rpm")
        self.feed_per_tooth = positive_float(feed_per_tooth, "feed_per_tooth")
        self.axial_depth = positive_float(axial_depth, "axial_depth")
        st, ex = float(entry_angle), float(exit_angle)
        if not (math.isfinite(st) and math.isfinite(ex) and 0.0 <= st < ex <= math.pi):
            raise InputError(f"entry_angle, exit_angle: expected 0 <= entry < exit <= pi [rad], got {entry_angle!r}, {exit_angle!r}")
        self.entry_angle, self.exit_angle = st, ex
        if not isinstance(coefficients, MillingCoefficients):
            raise InputError(f"coefficients: expected MillingCoefficients, got {type(coefficients).__name__}")
        self.coefficients = coefficients

    @property
    def revolution_time(self) -> float:
        """Time of one spindle revolution [s]."""
        return 60.0 / self.spindle_speed_rpm

    @property
    def tooth_passing_frequency(self) -> float:
        """Tooth passing frequency ``N n / 60`` [Hz]."""
        return self.n_teeth * self.spindle_speed_rpm / 60.0

    @cached_property
    def force_function(self) -> ca.Function:
        """CasADi function ``phi -> F (3)``: force on the tool in the workpiece frame [N], eqs. (12)-(17)."""
        K = self.coefficients
        a, ft = self.axial_depth, self.feed_per_tooth
        phi = ca.SX.sym("phi")
        F = ca.SX.zeros(3)
        for j in range(self.n_teeth):
            pj = ca.fmod(phi + 2 * math.pi * j / self.n_teeth, 2 * math.pi)
            pj = ca.if_else(pj < 0, pj + 2 * math.pi, pj)
            g = ca.logic_and(pj >= self.entry_angle, pj <= self.exit_angle)
            h = ft * ca.sin(pj)
            Ft = K.K_tc * a * h + K.K_te * a
            Fr = K.K_rc * a * h + K.K_re * a
            Fa = K.K_ac * a * h + K.K_ae * a
            Fj = ca.vertcat(-Ft * ca.cos(pj) - Fr * ca.sin(pj), Ft * ca.sin(pj) - Fr * ca.cos(pj), Fa)
            F = F + ca.if_else(g, Fj, ca.SX.zeros(3))
        return ca.Function("milling_force", [phi], [F], ["phi"], ["F"])

    def force(self, t: Any) -> np.ndarray:
        """Milling force at times ``t`` (``phi = 2 pi n t / 60``), Cvitanic (2021), eqs. (12)-(17).

        Parameters
        ----------
        t : array_like, shape (n,)
            Times [s], finite.

        Returns
        -------
        numpy.ndarray, shape (n, 3)
            Force on the tool in the workpiece frame (x feed, z tool axis) [N].

        Raises
        ------
        InputError
            Non-finite or non-1-D times.
        """
        tt = np.asarray(t, dtype=float)
        if tt.ndim != 1 or tt.size == 0 or not np.all(np.isfinite(tt)):
            raise InputError("t: expected a finite 1-D array of times [s]")
        phi = 2 * math.pi * self.spindle_speed_rpm / 60.0 * tt
        fmap = self.force_function.map(tt.size)
        return np.array(fmap(phi.reshape(1, -1))).T

    def time_grid(self, n_revolutions: float = 1.0, samples_per_revolution: int = 360) -> np.ndarray:
        """Equally spaced times over ``n_revolutions`` spindle revolutions.

        Parameters
        ----------
        n_revolutions : float, optional
            Duration in revolutions (> 0).
        samples_per_revolution : int, optional
            Samples per revolution (>= 8).

        Returns
        -------
        numpy.ndarray, shape (n,)
            Times [s]: the midpoints of ``n`` equal intervals from 0 (midpoints, so that no
            sample falls exactly on a tooth's entry or exit angle, where the force jumps
            and round-off would pick either side).

        Raises
        ------
        InputError
            Out-of-range arguments.
        """
        n_revolutions = positive_float(n_revolutions, "n_revolutions")
        if int(samples_per_revolution) != samples_per_revolution or samples_per_revolution < 8:
            raise InputError(f"samples_per_revolution: expected an integer >= 8, got {samples_per_revolution!r}")
        n = int(round(n_revolutions * samples_per_revolution))
        return (np.arange(n) + 0.5) * self.revolution_time / samples_per_revolution


@dataclass
class SpindleAngleResult(StatusResult):
    """Result of the spindle-angle search (status, never None).

    Implements :class:`gtmodel.status.SolverResult`: :attr:`success` is True if at least
    one grid angle is feasible.

    Parameters
    ----------
    status : Status
        ``"optimal"`` (best grid point found) or ``"infeasible"`` (no feasible angle);
        keyword only.
    message : str
        Summary (number of infeasible angles and why); keyword only.
    A_deg : numpy.ndarray, shape (n,)
        Grid of spindle angles [deg] (user boundary).
    theta : numpy.ndarray, shape (n, 6)
        Joint angles per grid angle [rad] (NaN where infeasible).
    feasible : numpy.ndarray, shape (n,), bool
        IK converged, non-singular and within the joint limits.
    static_objective : numpy.ndarray, shape (n,)
        Eq. (18), translation deflection under the peak force [m] (NaN where infeasible).
    dynamic_objective : numpy.ndarray, shape (n,)
        Eq. (19), peak simulated displacement [m] (NaN where infeasible or not computed).
    best_static_deg : float
        Grid angle minimising eq. (18) [deg] (NaN if infeasible).
    best_dynamic_deg : float
        Grid angle minimising eq. (19) [deg] (NaN if not computed or infeasible).
    F_peak : numpy.ndarray, shape (3,)
        Peak force in the base frame [N].
    extra : dict, optional
        ``t`` (time grid [s]) and ``F_base`` (force history in the base frame [N], shape
        (n, 3)).
    """

    A_deg: np.ndarray
    theta: np.ndarray
    feasible: np.ndarray
    static_objective: np.ndarray
    dynamic_objective: np.ndarray
    best_static_deg: float
    best_dynamic_deg: float
    F_peak: np.ndarray
    extra: dict[str, Any] = field(default_factory=dict)


def spindle_angle_poses(arm: SerialArm, T_nominal: Any, theta0: Any, A_deg: Any, theta_limits: Any = None) -> tuple[np.ndarray, np.ndarray, list[str]]:
    """Joint angles of the TCP pose rotated by ``A`` about the spindle (tool z) axis.

    Target ``T(A) = T_nominal * Rot_z(A)``; inverse kinematics by continuation: from
    ``theta0`` at the grid angle nearest 0, then outwards, each solve starting from its
    neighbour's solution.

    Parameters
    ----------
    arm : SerialArm
        The arm.
    T_nominal : array_like, shape (4, 4)
        TCP pose at ``A = 0`` [m].
    theta0 : array_like, shape (6,)
        IK start near ``T_nominal`` [rad] (selects the configuration).
    A_deg : array_like, shape (n,)
        Strictly increasing spindle angles [deg].
    theta_limits : array_like, shape (6, 2), optional
        Lower/upper joint limits [rad]; poses outside are infeasible.

    Returns
    -------
    theta : numpy.ndarray, shape (n, 6)
        Joint angles [rad], NaN where infeasible.
    feasible : numpy.ndarray, shape (n,), bool
        Which angles have a solution.
    reasons : list of str
        Why each infeasible angle failed.

    Raises
    ------
    InputError
        Bad shapes or values.
    """
    A = np.asarray(A_deg, dtype=float)
    if A.ndim != 1 or A.size == 0 or not np.all(np.isfinite(A)) or np.any(np.diff(A) <= 0):
        raise InputError("A_deg: expected a finite strictly increasing 1-D array of angles [deg]")
    Tn = SerialArm._transform(T_nominal, "T_nominal")
    th0 = np.asarray(theta0, dtype=float)
    if th0.shape != (6,) or not np.all(np.isfinite(th0)):
        raise InputError(f"theta0: expected 6 finite joint angles [rad], got shape {th0.shape}")
    lim = None
    if theta_limits is not None:
        lim = np.asarray(theta_limits, dtype=float)
        if lim.shape != (6, 2) or np.any(lim[:, 0] >= lim[:, 1]):
            raise InputError("theta_limits: expected shape (6, 2) with lower < upper [rad]")
    theta = np.full((A.size, 6), np.nan)
    feasible = np.zeros(A.size, dtype=bool)
    reasons: list[str] = []
    i0 = int(np.argmin(np.abs(A)))
    for order in (range(i0, A.size), range(i0 - 1, -1, -1)):
        seed = th0 if order.start == i0 else (theta[i0] if feasible[i0] else th0)
        for i in order:
            T = Tn.copy()
            T[:3, :3] = Tn[:3, :3] @ np.array(rot_z(math.radians(A[i])))
            try:
                th = arm.ik(T, seed)
            except (ConvergenceError, SingularConfigurationError) as exc:
                reasons.append(f"A = {A[i]:g} deg: {exc}")
                continue
            if lim is not None and np.any((th < lim[:, 0]) | (th > lim[:, 1])):
                reasons.append(f"A = {A[i]:g} deg: joint limits")
                seed = th
                continue
            theta[i], feasible[i], seed = th, True, th
    return theta, feasible, reasons


def optimise_spindle_angle(
    arm: SerialArm,
    T_nominal: Any,
    theta0: Any,
    process: MillingProcess,
    k_theta: Any,
    dynamics: DynamicStiffnessGP | Callable[[np.ndarray, np.ndarray, float], tuple[Any, Any, Any]] | None = None,
    A_deg: Any = None,
    R_workpiece: Any = None,
    theta_limits: Any = None,
    n_revolutions: float = 20.0,
    samples_per_revolution: int = 120,
    settle_time: float = 0.0,
) -> SpindleAngleResult:
    """Pose optimisation over the spindle angle, static (18) and dynamic (19) objectives.

    Cvitanic (2021), eqs. (12)-(19). For each grid angle ``A``: IK (continuation), the
    static deflection ``K_x(theta)^-1 [F_peak; 0]`` (eq. (7) with eq. (18)) and, if
    ``dynamics`` is given, the peak of the simulated per-direction single-mode response
    (eq. (8)) to the milling force over ``n_revolutions`` (eq. (19)).

    Parameters
    ----------
    arm : SerialArm
        The arm.
    T_nominal : array_like, shape (4, 4)
        TCP pose at ``A = 0`` (tool z = spindle axis) [m].
    theta0 : array_like, shape (6,)
        IK start near ``T_nominal`` [rad].
    process : MillingProcess
        Cutter, cutting conditions, force coefficients.
    k_theta : array_like, shape (6,)
        Joint stiffnesses [N m/rad].
    dynamics : DynamicStiffnessGP or callable, optional
        Per-direction modal parameters at a pose: a GP (input TCP position and ``A`` [rad])
        or ``f(theta, p_TCP, A_rad) -> (m, c, k)`` each shape (3,). Without it only eq. (18)
        is evaluated.
    A_deg : array_like, shape (n,), optional
        Grid of spindle angles [deg] (default -180 ... 179 in 1 deg steps).
    R_workpiece : array_like, shape (3, 3), optional
        Workpiece frame (x feed, z tool axis) in the base frame (default: the rotation of
        ``T_nominal``).
    theta_limits : array_like, shape (6, 2), optional
        Joint limits [rad].
    n_revolutions : float, optional
        Simulated duration of eq. (19) in spindle revolutions (default 20).
    samples_per_revolution : int, optional
        Time samples per revolution for eq. (19) (default 120).
    settle_time : float, optional
        Eq. (19) takes the maximum over ``t >= settle_time`` [s] only (>= 0, default 0:
        the entry transient from rest counts); the simulation is extended by this time.
        Use a few time constants ``1/(zeta omega_n)`` for the steady-state vibration.

    Returns
    -------
    SpindleAngleResult
        Objectives on the grid, best angles, status.

    Raises
    ------
    InputError
        Bad arguments.
    """
    if not isinstance(arm, SerialArm):
        raise InputError(f"arm: expected a SerialArm, got {type(arm).__name__}")
    if not isinstance(process, MillingProcess):
        raise InputError(f"process: expected a MillingProcess, got {type(process).__name__}")
    k = np.asarray(k_theta, dtype=float)
    if k.shape != (6,) or not np.all(np.isfinite(k)) or np.any(k <= 0):
        raise InputError(f"k_theta: expected 6 finite positive joint stiffnesses [N m/rad], got {np.asarray(k_theta).tolist()}")
    A = np.arange(-180.0, 180.0, 1.0) if A_deg is None else np.asarray(A_deg, dtype=float)
    Tn = SerialArm._transform(T_nominal, "T_nominal")
    if R_workpiece is None:
        Rw = Tn[:3, :3]
    else:
        Rw = np.asarray(R_workpiece, dtype=float)
        if Rw.shape != (3, 3) or not np.all(np.isfinite(Rw)) or not np.allclose(Rw.T @ Rw, np.eye(3), atol=1e-9) or np.linalg.det(Rw) < 0:
            raise InputError("R_workpiece: expected a 3x3 rotation matrix (orthonormal, det +1)")
    if dynamics is not None and not (isinstance(dynamics, DynamicStiffnessGP) or callable(dynamics)):
        raise InputError(f"dynamics: expected a DynamicStiffnessGP or a callable, got {type(dynamics).__name__}")

    if not np.isfinite(settle_time) or settle_time < 0:
        raise InputError(f"settle_time: expected a finite number >= 0 [s], got {settle_time!r}")
    theta, feasible, reasons = spindle_angle_poses(arm, Tn, theta0, A, theta_limits)
    t = process.time_grid(n_revolutions + settle_time / process.revolution_time, samples_per_revolution)
    after = t >= settle_time
    F_work = process.force(t)
    F_base = F_work @ Rw.T
    i_peak = int(np.argmax(np.linalg.norm(F_base, axis=1)))
    F_peak = F_base[i_peak]
    static = np.full(A.size, np.nan)
    dynamic = np.full(A.size, np.nan)
    p = Tn[:3, 3]
    if isinstance(dynamics, DynamicStiffnessGP) and np.any(feasible):
        # one GP call for all angles (sklearn's predict per sample dominates the run time otherwise)
        rows = np.flatnonzero(feasible)
        pred = dynamics.predict(np.column_stack([np.tile(p, (rows.size, 1)), np.radians(A[rows])]))
        gp_mck = {int(i): (pred["m"][j], pred["c"][j], pred["k"][j]) for j, i in enumerate(rows)}
    for i in np.flatnonzero(feasible):
        try:
            Kx = arm.cartesian_stiffness(theta[i], k)
        except SingularConfigurationError as exc:
            feasible[i] = False
            reasons.append(f"A = {A[i]:g} deg: {exc}")
            continue
        dX = np.linalg.solve(Kx, np.concatenate([F_peak, np.zeros(3)]))
        static[i] = float(np.linalg.norm(dX[:3]))
        if dynamics is not None:
            if isinstance(dynamics, DynamicStiffnessGP):
                mck = gp_mck[int(i)]
            else:
                mck = dynamics(theta[i], p, math.radians(A[i]))
            x = simulate_single_mode(*mck, t, F_base)
            dynamic[i] = float(np.max(np.linalg.norm(x[after], axis=1)))
    n_bad = int(np.sum(~feasible))
    ok = bool(np.any(feasible))
    best_s = float(A[np.nanargmin(static)]) if ok else math.nan
    best_d = float(A[np.nanargmin(dynamic)]) if ok and dynamics is not None else math.nan
    msg = f"{int(np.sum(feasible))} of {A.size} angles feasible"
    if reasons:
        msg += f"; {n_bad} infeasible, e.g. {reasons[0]}"
    return SpindleAngleResult(
        status=Status.OPTIMAL if ok else Status.INFEASIBLE,
        message=msg,
        A_deg=A,
        theta=theta,
        feasible=feasible,
        static_objective=static,
        dynamic_objective=dynamic,
        best_static_deg=best_s,
        best_dynamic_deg=best_d,
        F_peak=F_peak,
        extra={"t": t, "F_base": F_base},
    )
