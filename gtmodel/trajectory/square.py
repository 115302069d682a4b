"""The square of the ILC experiment (Dressler (2012), section 7.3), planned time-optimally.

:func:`plan_square`: a :class:`~gtmodel.trajectory.Polyline` through the corners of a
square in the xy plane, traversed at rest at each corner under a TCP speed and per-axis
acceleration limit (:func:`~gtmodel.trajectory.solve_path_convex`), sampled at the loop
period, mapped to actuator references by IK and framed by a lead-in and a lead-out.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from gtmodel.errors import InputError, SolverError
from gtmodel.trajectory.path import Polyline
from gtmodel.trajectory.path_constrained import PathConstraints, solve_path_convex

__all__ = ["plan_square"]


def plan_square(kinematics: Any, corner: Any, side: float, speed: float, acceleration: float, lead: int, grid: int,
                configuration: int, dt: float, rounds: int = 1) -> tuple[np.ndarray, np.ndarray, float]:
    """Time-optimal square in the xy plane, corners at rest, sampled at ``dt``, with lead-in/out.

    Dressler (2012), section 7.3: the path is a :class:`~gtmodel.trajectory.Polyline`
    through the corners, solved by :func:`~gtmodel.trajectory.solve_path_convex` under a TCP
    speed limit ``speed`` and a per-axis acceleration limit ``acceleration``; samples at
    ``k dt`` up to the final time, then the end pose held for ``lead`` samples (and the
    start pose for ``lead`` samples before).

    Parameters
    ----------
    kinematics : GantryTau3Kinematics
        The robot (workspace check and IK).
    corner : array_like, shape (3,)
        First corner [m].
    side : float
        Side [m].
    speed : float
        TCP speed limit [m/s].
    acceleration : float
        TCP acceleration limit per axis [m/s^2].
    lead : int
        Lead-in and lead-out [samples].
    grid : int
        Grid points of the solver.
    configuration : int
        IK configuration.
    dt : float
        Sample time [s] (the loop period).
    rounds : int, optional
        Consecutive rounds of the square (the thesis: 2, "to have the ILC algorithm cover
        the complete rectilinear figure", Dressler (2012), section 7.3); at rest at every
        corner of every round.

    Returns
    -------
    T : numpy.ndarray, shape (N, 3)
        Tool reference [m].
    q : numpy.ndarray, shape (N, 3)
        Actuator references [m].
    final_time : float
        Duration of the motion [s].

    Raises
    ------
    InputError
        ``rounds`` not a positive integer.
    UnreachablePoseError
        The square leaves the workspace.
    SolverError
        The planner found no motion.
    """
    c = np.asarray(corner, dtype=float)
    if int(rounds) != rounds or rounds < 1:
        raise InputError(f"rounds: expected a positive integer, got {rounds!r}")
    loop = np.array([[1, 0, 0], [1, 1, 0], [0, 1, 0], [0, 0, 0]], dtype=float)
    pts = c + side * np.vstack([np.zeros((1, 3)), np.tile(loop, (int(rounds), 1))])
    path = Polyline(pts, robot=kinematics, configuration=configuration)
    sol = solve_path_convex(path, PathConstraints(tcp_speed_limit=speed, tcp_acceleration_limit=acceleration), grid=grid)
    if not sol.success:
        raise SolverError(f"square: the path-constrained planner ended with status {sol.status} ({sol.message})")
    t = np.arange(0.0, sol.final_time, dt)
    T = sol.sample(t)["T"]
    T = np.vstack([np.repeat(pts[:1], lead, axis=0), T, np.repeat(pts[-1:], lead + 1, axis=0)])
    q = kinematics.ik(T, configuration)
    return T, q, float(sol.final_time)
