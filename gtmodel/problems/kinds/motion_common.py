"""What the motion kinds (``point_to_point``, ``path_constrained``) share.

The tables that read the same in both kinds (``[motion]``, ``[collocation]``,
``[solver]`` and the robot reference of ``[robot]``, defined in the light
:mod:`gtmodel.problems.kinds.schemas.motion` and re-exported here), the study-table columns
(Dressler (2012), Table 3.1) and the force statistics of ``summary.json``.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from gtmodel.problems.base import Column
from gtmodel.problems.kinds.schemas.motion import (
    MAX_TIME_S,
    CollocationSection,
    MotionSection,
    OcpSolverSection,
    RobotReference,
    SolverSection,
)

__all__ = [
    "MOTION_EXTRA_EMPTY_FIELDS",
    "AT_BOUND_RTOL",
    "MAX_TIME_S",
    "RobotReference",
    "MotionSection",
    "CollocationSection",
    "SolverSection",
    "OcpSolverSection",
    "trajectory_columns",
    "force_statistics",
]

#: Relative tolerance on force limits when reporting the fraction of time at a bound.
AT_BOUND_RTOL = 1e-3
#: Summary fields of the motion kinds, besides their columns, that are null when a run ends
#: before a solution.
MOTION_EXTRA_EMPTY_FIELDS = ("objective", "max_constraint_violation")


def trajectory_columns() -> tuple[Column, ...]:
    """Study-table columns of the motion kinds (Dressler (2012), Table 3.1).

    Returns
    -------
    tuple of Column
    """
    return (
        Column("final_time_s", "T_final [s]", "{:.4f}"),
        Column("energy", "energy [N^2 s]", "{:.6g}"),
        Column("iterations", "iterations", "{}"),
        Column("solve_time_s", "solve time [s]", "{:.3f}"),
    )


def force_statistics(traj: dict[str, Any], force_limit: Any) -> dict[str, Any]:
    """Force figures of a sampled trajectory for ``summary.json``.

    Parameters
    ----------
    traj : dict of str to numpy.ndarray
        Columns ``tau1, tau2, tau3`` [N], each (K,).
    force_limit : array_like, shape (3,)
        ``|tau_i| <= force_limit_i`` [N].

    Returns
    -------
    dict
        ``max_force_ratio`` (3,): ``max_t |tau_i| / force_limit_i``;
        ``fraction_at_force_bound`` (3,): fraction of samples with ``|tau_i|`` within
        :data:`AT_BOUND_RTOL` of the limit; ``bounds``: ``{"tau1": [-limit_1, limit_1], ...}``
        (the trajectory table's columns with their bounds, drawn by ``gtmodel report``).
    """
    limit = np.asarray(force_limit, dtype=float)
    tau = np.abs(np.column_stack([traj["tau1"], traj["tau2"], traj["tau3"]]))
    return {
        "max_force_ratio": (tau.max(axis=0) / limit).tolist(),
        "fraction_at_force_bound": (tau >= (1 - AT_BOUND_RTOL) * limit).mean(axis=0).tolist(),
        "bounds": {f"tau{i + 1}": [-float(f), float(f)] for i, f in enumerate(limit)},
    }
