"""Friction from constant-velocity runs, separated from gravity (Dressler (2012), eq. 6.9, Table 6.1).

Constant-velocity experiment (6.9): ``tau = J^T G + f_c sign(q_dot) + f_v q_dot``; see
:func:`two_direction_friction` (gravity and friction separated by runs in both
directions) and :func:`subtract_gravity` (one-direction data: the model's ``J^T G`` with
the accumulated mass removed first; without it the gravity is absorbed into ``f_c``,
the ambiguity of the thesis' Fig. 6.2).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Sequence

import numpy as np
import numpy.typing  # noqa: F401  (np.typing in annotations)

from gtmodel._arrays import as_signal
from gtmodel.errors import InputError
from gtmodel.robots.dynamics import GantryTau3Dynamics
from gtmodel.robots.parameters import RobotParameters, load_parameters

__all__ = [
    "ConstantVelocityData",
    "FrictionFit",
    "accumulated_gravity_forces",
    "subtract_gravity",
    "fit_friction",
    "two_direction_friction",
    "SPEED_MATCH_TOLERANCE",
]

#: Largest relative speed difference of two runs paired by :func:`two_direction_friction`.
SPEED_MATCH_TOLERANCE = 0.05


@dataclass
class ConstantVelocityData:
    """Mean actuator forces of constant-velocity runs (Dressler (2012), eq. 6.9, Table 6.1).

    Parameters
    ----------
    T : numpy.ndarray, shape (N, 3)
        TCP position of each run (the pose at which the force is averaged) [m].
    q_dot : numpy.ndarray, shape (N, 3)
        Cart velocities [m/s] (constant during the run).
    tau : numpy.ndarray, shape (N, 3)
        Mean actuator forces [N].
    pose : numpy.ndarray, shape (N,)
        Integer pose index of each run (runs at the same pose share it).

    Raises
    ------
    InputError
        Shapes differ or values are not finite.
    """

    T: np.ndarray
    q_dot: np.ndarray
    tau: np.ndarray
    pose: np.ndarray

    def __post_init__(self) -> None:
        self.T = as_signal(self.T, "T", 3)
        n = self.T.shape[0]
        self.q_dot = as_signal(self.q_dot, "q_dot", 3, n, like="T")
        self.tau = as_signal(self.tau, "tau", 3, n, like="T")
        pose = np.asarray(self.pose).ravel()
        if pose.size != n:
            raise InputError(f"pose: expected {n} indices (one per run), got {pose.size}")
        self.pose = pose.astype(int)


@dataclass
class FrictionFit:
    """Coulomb and viscous friction from constant-velocity runs (Dressler (2012), Table 6.1).

    Parameters
    ----------
    f_c_plus, f_c_minus : numpy.ndarray, shape (3,)
        Coulomb friction [N] for positive / negative velocity (equal if symmetric).
    f_v_plus, f_v_minus : numpy.ndarray, shape (3,)
        Viscous friction [N s/m].
    std : dict of str to numpy.ndarray
        Standard deviations of the four, shape (3,) each.
    gravity : numpy.ndarray, shape (P, 3) or None
        Gravity force ``J^T G`` per pose [N] where estimated (two-direction runs).
    accumulated_mass : float or None
        ``m_p + sum m_a / 2`` [kg] estimated from the pose dependence of the gravity.
    accumulated_mass_std : float or None
        Its standard deviation [kg].
    method : str
        How the fit was made.
    """

    f_c_plus: np.ndarray
    f_c_minus: np.ndarray
    f_v_plus: np.ndarray
    f_v_minus: np.ndarray
    std: dict = field(default_factory=dict)
    gravity: np.ndarray | None = None
    accumulated_mass: float | None = None
    accumulated_mass_std: float | None = None
    method: str = ""

    @property
    def f_c(self) -> np.ndarray:
        """Symmetric Coulomb friction, the mean of both directions [N]."""
        return (self.f_c_plus + self.f_c_minus) / 2

    @property
    def f_v(self) -> np.ndarray:
        """Symmetric viscous friction, the mean of both directions [N s/m]."""
        return (self.f_v_plus + self.f_v_minus) / 2


def _gravity_model(parameters: RobotParameters, accumulated_mass: float) -> GantryTau3Dynamics:
    d = parameters.dynamics
    robot = dataclasses.replace(parameters, dynamics=dataclasses.replace(d, m_p=float(accumulated_mass), m_a=np.zeros(3)))
    return GantryTau3Dynamics(robot)


def accumulated_gravity_forces(T: np.typing.ArrayLike, parameters: RobotParameters | str | Path, accumulated_mass: float | None = None, configuration: int | Sequence[int] = 0) -> np.ndarray:
    """Gravity forces ``J^T G`` on the carts for the accumulated mass (Dressler (2012), eq. 6.9, Table 6.2).

    ``G = g (0, 0, m_acc)`` with ``m_acc = m_p + sum m_a/2`` carried by the plate (eq. 6.7),
    plus the carts' weight along their (nearly horizontal) guideways, evaluated by
    :meth:`gtmodel.robots.GantryTau3Dynamics.gravity_forces`.

    Parameters
    ----------
    T : array_like, shape (3,) or (N, 3)
        TCP positions [m].
    parameters : RobotParameters or str or pathlib.Path
        Parameter set (a name of :func:`gtmodel.robots.available_parameter_sets`, a TOML file or the parameters).
    accumulated_mass : float, optional
        ``m_acc`` [kg] (default: the parameter set's ``m_p + sum m_a/2``; the thesis'
        friction experiment used 22.38 kg).
    configuration : int or sequence of int, optional
        IK configuration (default 0).

    Returns
    -------
    numpy.ndarray, shape (3,) or (N, 3)
        ``J^T G`` [N].

    Raises
    ------
    InputError
        Non-positive mass or invalid ``T``.
    """
    robot = load_parameters(parameters)
    if accumulated_mass is None:
        accumulated_mass = float(robot.dynamics.m_p + np.sum(robot.dynamics.m_a) / 2)
    if not (isinstance(accumulated_mass, (int, float)) and math.isfinite(accumulated_mass) and accumulated_mass > 0):
        raise InputError(f"accumulated_mass: expected a positive mass in kg, got {accumulated_mass!r}")
    return _gravity_model(robot, accumulated_mass).gravity_forces(T, configuration)


def subtract_gravity(data: ConstantVelocityData, parameters: RobotParameters | str | Path, accumulated_mass: float | None = None, configuration: int | Sequence[int] = 0) -> ConstantVelocityData:
    """Remove the model's gravity ``J^T G`` from constant-velocity forces (eq. 6.9).

    With runs in one direction only, ``tau = J^T G + f_c + f_v v`` at one pose cannot tell
    the gravity from the Coulomb friction: a straight-line fit of ``tau`` over ``v`` puts
    ``J^T G`` into ``f_c`` (Dressler (2012), Fig. 6.2). Subtracting the model's gravity
    with the accumulated mass (22.38 kg in the thesis' experiment) first leaves friction
    only.

    Parameters
    ----------
    data : ConstantVelocityData
        The runs.
    parameters : RobotParameters or str or pathlib.Path
        Parameter set (a name of :func:`gtmodel.robots.available_parameter_sets`, a TOML file or the parameters): kinematics, gravity.
    accumulated_mass : float, optional
        ``m_p + sum m_a/2`` [kg] (default: the parameter set's; the thesis' experiment,
        ch. 6.2, used 22.38 kg).
    configuration : int or sequence of int, optional
        IK configuration (default 0).

    Returns
    -------
    ConstantVelocityData
        The same runs with ``tau - J^T G``.

    Raises
    ------
    InputError
        Invalid data or mass.
    """
    if not isinstance(data, ConstantVelocityData):
        raise InputError(f"data: expected ConstantVelocityData, got {type(data).__name__}")
    G = accumulated_gravity_forces(data.T, parameters, accumulated_mass, configuration)
    return ConstantVelocityData(data.T, data.q_dot, data.tau - G, data.pose)


def _line_fit(X: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    coef, *_ = np.linalg.lstsq(X, y, rcond=None)
    m, n = X.shape
    if m > n:
        r = y - X @ coef
        s2 = float(r @ r) / (m - n)
        cov = s2 * np.linalg.inv(X.T @ X)
        std = np.sqrt(np.diag(cov))
    else:
        std = np.full(n, math.nan)
    return coef, std


def fit_friction(data: ConstantVelocityData, asymmetric: bool = True, min_speed: float = 1e-3) -> FrictionFit:
    """Coulomb + viscous friction from gravity-free constant-velocity forces (eq. 6.8, Table 6.1).

    Per actuator a straight line ``tau = f_c + f_v v`` through the runs of each direction
    (asymmetric, Table 6.1) or ``tau = f_c sign(v) + f_v v`` through all (symmetric). The
    forces must not contain gravity: use :func:`subtract_gravity` or
    :func:`two_direction_friction`; otherwise ``J^T G`` ends up in ``f_c`` (Fig. 6.2).

    Parameters
    ----------
    data : ConstantVelocityData
        Runs (gravity removed).
    asymmetric : bool, optional
        Separate lines per direction (default True).
    min_speed : float, optional
        Runs with ``|q_dot_i|`` below this [m/s] are ignored (default 1 mm/s).

    Returns
    -------
    FrictionFit
        ``f_c_minus``/``f_v_minus`` are reported as positive numbers (force opposing the
        motion: ``tau = -f_c- + f_v- v`` for ``v < 0``). A direction without runs gives
        ``nan``.

    Raises
    ------
    InputError
        Invalid data, or fewer than two runs for a line.
    """
    if not isinstance(data, ConstantVelocityData):
        raise InputError(f"data: expected ConstantVelocityData, got {type(data).__name__}")
    out = {k: np.full(3, math.nan) for k in ("f_c_plus", "f_c_minus", "f_v_plus", "f_v_minus")}
    std = {k: np.full(3, math.nan) for k in out}
    for i in range(3):
        v, y = data.q_dot[:, i], data.tau[:, i]
        if asymmetric:
            for sgn, suffix in ((1, "plus"), (-1, "minus")):
                m = sgn * v >= min_speed
                if m.sum() < 2:
                    continue
                X = np.column_stack([np.full(m.sum(), float(sgn)), v[m]])
                c, s = _line_fit(X, y[m])
                out[f"f_c_{suffix}"][i], out[f"f_v_{suffix}"][i] = c
                std[f"f_c_{suffix}"][i], std[f"f_v_{suffix}"][i] = s
        else:
            m = np.abs(v) >= min_speed
            if m.sum() < 2:
                raise InputError(f"data: actuator {i + 1} has fewer than two runs with |q_dot| >= {min_speed} m/s")
            c, s = _line_fit(np.column_stack([np.sign(v[m]), v[m]]), y[m])
            for suffix in ("plus", "minus"):
                out[f"f_c_{suffix}"][i], out[f"f_v_{suffix}"][i] = c
                std[f"f_c_{suffix}"][i], std[f"f_v_{suffix}"][i] = s
    return FrictionFit(**out, std=std, method="asymmetric lines per direction" if asymmetric else "symmetric f_c sign(v) + f_v v")


def two_direction_friction(data: ConstantVelocityData, parameters: RobotParameters | str | Path | None, configuration: int | Sequence[int] = 0, min_speed: float = 1e-3) -> FrictionFit:
    """Gravity and friction separated by runs in both directions (Dressler (2012), eq. 6.9, Fig. 6.2).

    At one pose and speed ``|v|`` the runs in both directions give
    ``tau(+v) = J^T G + f_c+ + f_v+ |v|`` and ``tau(-v) = J^T G - f_c- - f_v- |v|``: the half
    difference ``f_c + f_v |v|`` (mean friction) no longer holds gravity, and the mean
    ``J^T G + (f_c+ - f_c-)/2 + (f_v+ - f_v-)/2 |v|`` holds gravity plus the friction
    asymmetry. At a single pose the two cannot be told apart (a constant either way);
    with several poses the gravity changes with the pose as ``m_acc J^T g e_z`` (the
    model's :func:`accumulated_gravity_forces` per kg) while the asymmetry does not, so
    ``m_acc`` and the asymmetry are estimated by least squares over all poses (if
    ``parameters`` is given and there are at least two poses). Otherwise the asymmetry is
    taken as zero and the mean is the gravity.

    Parameters
    ----------
    data : ConstantVelocityData
        Runs in both directions at the same poses, paired by ``pose`` and the closest
        ``|v|`` (within :data:`SPEED_MATCH_TOLERANCE`).
    parameters : RobotParameters or str or pathlib.Path or None
        Parameter set for the gravity direction ``J^T e_z`` (a name of :func:`gtmodel.robots.available_parameter_sets`, a TOML file or the parameters); None: symmetric
        friction assumed, no mass estimate.
    configuration : int or sequence of int, optional
        IK configuration (default 0).
    min_speed : float, optional
        Runs with ``|q_dot_i|`` below this [m/s] are ignored (default 1 mm/s).

    Returns
    -------
    FrictionFit
        Asymmetric friction, the per-pose gravity ``J^T G`` and, with several poses, the
        accumulated mass.

    Raises
    ------
    InputError
        A run without its opposite-direction partner, or too few runs.
    """
    if not isinstance(data, ConstantVelocityData):
        raise InputError(f"data: expected ConstantVelocityData, got {type(data).__name__}")
    poses = np.unique(data.pose)
    P = poses.size
    # mean of +- per (pose, |v|) and actuator; half difference
    rows = []  # (pose position, |v| (3,), mean (3,), half (3,))
    speed = np.abs(data.q_dot).mean(axis=1)
    direction = np.sign(data.q_dot.mean(axis=1))
    for pi, p in enumerate(poses):
        pos = np.flatnonzero((data.pose == p) & (direction > 0))
        neg = list(np.flatnonzero((data.pose == p) & (direction < 0)))
        for kp in pos:
            # the partner: the negative run at this pose with the closest speed
            if neg:
                kn = min(neg, key=lambda k: abs(speed[k] - speed[kp]))
            if not neg or abs(speed[kn] - speed[kp]) > SPEED_MATCH_TOLERANCE * speed[kp]:
                raise InputError(f"data: run {int(kp)} (pose {p}, speed {speed[kp]:.4g} m/s) needs a partner run in the opposite direction "
                                 f"at the same pose and speed (within {100 * SPEED_MATCH_TOLERANCE:g} %)")
            neg.remove(kn)
            vabs = (np.abs(data.q_dot[kp]) + np.abs(data.q_dot[kn])) / 2
            if np.any(vabs < min_speed):
                continue
            rows.append((pi, vabs, (data.tau[kp] + data.tau[kn]) / 2, (data.tau[kp] - data.tau[kn]) / 2))
        if neg:
            k = int(neg[0])
            raise InputError(f"data: run {k} (pose {p}, speed {speed[k]:.4g} m/s) needs a partner run in the opposite direction "
                             f"at the same pose and speed (within {100 * SPEED_MATCH_TOLERANCE:g} %)")
    if len(rows) < 2:
        raise InputError(f"data: {len(rows)} matched run pairs, expected at least 2")
    pidx = np.array([r[0] for r in rows])
    V = np.array([r[1] for r in rows])
    Mean = np.array([r[2] for r in rows])
    Half = np.array([r[3] for r in rows])
    out = {k: np.zeros(3) for k in ("f_c_plus", "f_c_minus", "f_v_plus", "f_v_minus")}
    std = {k: np.zeros(3) for k in out}
    fc, fv, fc_s, fv_s = np.zeros(3), np.zeros(3), np.zeros(3), np.zeros(3)
    for i in range(3):
        c, s = _line_fit(np.column_stack([np.ones(len(rows)), V[:, i]]), Half[:, i])
        fc[i], fv[i] = c
        fc_s[i], fv_s[i] = s
    gravity = np.zeros((P, 3))
    dfc, dfv, dfc_s, dfv_s = np.zeros(3), np.zeros(3), np.zeros(3), np.zeros(3)
    m_acc = m_std = None
    if parameters is not None and P >= 2:
        T_pose = np.array([data.T[data.pose == p][0] for p in poses])
        G1 = accumulated_gravity_forces(T_pose, parameters, 1.0, configuration)
        G2 = accumulated_gravity_forces(T_pose, parameters, 2.0, configuration)
        g1 = G2 - G1  # J^T G per kg of accumulated mass
        g0 = 2 * G1 - G2  # the carts' weight along their guideways
        # unknowns: m_acc, dfc_1..3, dfv_1..3; rows: (pair, actuator)
        n = len(rows)
        X = np.zeros((3 * n, 7))
        y = np.zeros(3 * n)
        for i in range(3):
            X[i * n:(i + 1) * n, 0] = g1[pidx, i]
            X[i * n:(i + 1) * n, 1 + i] = 1.0
            X[i * n:(i + 1) * n, 4 + i] = V[:, i]
            y[i * n:(i + 1) * n] = Mean[:, i] - g0[pidx, i]
        c, s = _line_fit(X, y)
        m_acc, m_std = float(c[0]), float(s[0])
        dfc, dfv = c[1:4], c[4:7]
        dfc_s, dfv_s = s[1:4], s[4:7]
        gravity = m_acc * g1 + g0
        method = "two directions, several poses: gravity m_acc J^T g e_z and friction asymmetry separated"
    else:
        for pi in range(P):
            sel = pidx == pi
            for i in range(3):
                gravity[pi, i] = float(np.mean(Mean[sel, i]))
        method = "two directions: gravity = mean of +- (friction asymmetry assumed zero)"
    out["f_c_plus"], out["f_c_minus"] = fc + dfc, fc - dfc
    out["f_v_plus"], out["f_v_minus"] = fv + dfv, fv - dfv
    # the mean and half-difference fits use independent combinations of the runs
    sc, sv = np.sqrt(fc_s**2 + dfc_s**2), np.sqrt(fv_s**2 + dfv_s**2)
    std = {"f_c_plus": sc, "f_c_minus": sc, "f_v_plus": sv, "f_v_minus": sv}
    return FrictionFit(**out, std=std, gravity=gravity, accumulated_mass=m_acc, accumulated_mass_std=m_std, method=method)
