"""What a rest-to-rest motion between two TCP positions needs besides its optimisation.

- :func:`check_holding_forces`: the force limits must hold the robot at rest at both ends
  (Dressler (2012), eq. 6.7 with zero velocity and acceleration), or the problem is
  infeasible whatever the solver does;
- :func:`trapezoid_profile`: the straight line with a trapezoidal velocity profile (the
  thesis' initial guess);
- :func:`bang_bang_duration`: a rough minimum duration from the force limits.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from gtmodel.errors import InputError
from gtmodel.robots.dynamics import GantryTau3Dynamics

__all__ = ["check_holding_forces", "trapezoid_profile", "bang_bang_duration"]


def check_holding_forces(problem: Any, dynamics: GantryTau3Dynamics | None = None) -> None:
    """Check that the force limits can hold the robot at rest at both end poses.

    At rest friction is zero in every form, so the actuators must supply exactly
    ``J^T G`` (Dressler (2012), eq. 6.7 with ``T_dot = T_ddot = 0``); if that exceeds a
    limit, the rest-to-rest problem is infeasible whatever the solver does.

    Parameters
    ----------
    problem : gtmodel.trajectory.PointToPoint
        The declaration.
    dynamics : GantryTau3Dynamics, optional
        The dynamics to use (default: built from the problem's parameter set).

    Raises
    ------
    InputError
        A holding force exceeds its limit; the message gives both.
    """
    dyn = dynamics or GantryTau3Dynamics(problem.parameters, friction=problem.friction, friction_width=problem.friction_width)
    for label, pose in (("start", problem.start), ("end", problem.end)):
        hold = dyn.gravity_forces(pose, problem.configuration)
        if np.any(np.abs(hold) > problem.force_limit):
            raise InputError(
                f"force_limit: {problem.force_limit.tolist()} N cannot hold the robot at rest at the {label} pose "
                f"{pose.tolist()}, which needs {np.round(hold, 2).tolist()} N (gravity, eq. 6.7)"
            )


def trapezoid_profile(start, end, duration: float, t, ramp: float = 1.0 / 3.0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Straight line with a trapezoidal velocity profile.

    Parameters
    ----------
    start, end : array_like, shape (3,)
        End points [m].
    duration : float
        Duration [s].
    t : array_like, shape (K,)
        Times in ``[0, duration]`` [s].
    ramp : float, optional
        Fraction of the duration spent accelerating (and decelerating); default 1/3.

    Returns
    -------
    T, T_dot, T_ddot : numpy.ndarray, each shape (K, 3)
        Position [m], velocity [m/s] and acceleration [m/s^2].

    Raises
    ------
    InputError
        Non-positive duration or ``ramp`` outside (0, 0.5].
    """
    if not duration > 0:
        raise InputError(f"duration: expected a positive time in s, got {duration!r}")
    if not 0 < ramp <= 0.5:
        raise InputError(f"ramp: expected a fraction in (0, 0.5], got {ramp!r}")
    start = np.asarray(start, dtype=float)
    delta = np.asarray(end, dtype=float) - start
    t = np.clip(np.asarray(t, dtype=float).reshape(-1), 0.0, duration)
    ta = ramp * duration
    a = 1.0 / (ta * (duration - ta))  # peak path acceleration for unit length
    s = np.where(t < ta, 0.5 * a * t**2, np.where(t <= duration - ta, a * ta * (t - ta / 2), 1 - 0.5 * a * (duration - t) ** 2))
    sd = np.where(t < ta, a * t, np.where(t <= duration - ta, a * ta, a * (duration - t)))
    sdd = np.where(t < ta, a, np.where(t <= duration - ta, 0.0, -a))
    return start + np.outer(s, delta), np.outer(sd, delta), np.outer(sdd, delta)


def bang_bang_duration(problem: Any, dynamics: GantryTau3Dynamics | None = None) -> float:
    """Rough minimum duration from the force limits, for the initial guess.

    Each cart is treated as a double integrator with the force left after gravity and
    Coulomb friction at the start pose, driving its own mass plus a third of the plate,
    over its IK displacement (bang-bang: ``t_i = 2 sqrt(|dq_i| / a_i)``).

    Parameters
    ----------
    problem : gtmodel.trajectory.PointToPoint
        The declaration.
    dynamics : GantryTau3Dynamics, optional
        Dynamics to use (built from the problem if omitted).

    Returns
    -------
    float
        The largest ``t_i`` [s].
    """
    dyn = dynamics or GantryTau3Dynamics(problem.parameters, friction=problem.friction, friction_width=problem.friction_width)
    kin = dyn.kinematics
    dq = np.abs(kin.ik(problem.end, problem.configuration) - kin.ik(problem.start, problem.configuration))
    d = problem.parameters.dynamics
    hold = np.abs(dyn.gravity_forces(problem.start, problem.configuration)) + np.asarray(d.f_c)
    spare = np.maximum(problem.force_limit - hold, 0.05 * problem.force_limit)
    mass = np.asarray(d.m_c) + np.asarray(d.m_a) + d.m_p / 3.0
    return float(np.max(2.0 * np.sqrt(dq / (spare / mass))))
