"""What the motion kinds (``point_to_point``, ``path_constrained``) share.

The tables that read the same in both kinds (``[motion]``, ``[collocation]``,
``[solver]`` and the robot reference of ``[robot]``), the study-table columns
(Dressler (2012), Table 3.1) and the force statistics of ``summary.json``.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from pydantic import Field

from gtmodel.problems.base import Column
from gtmodel.problems.schema import MAX_LENGTH_M, Flag, NonEmptyText, Section, choice, integer, number, vector

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
#: Longest final time accepted [s].
MAX_TIME_S = 1.0e4


class RobotReference(Section):
    """``[robot]``: the parameter set and the IK configuration (each kind adds its dynamics options).

    Parameters
    ----------
    parameters : str
        Shipped parameter set name or a TOML path relative to the problem file.
    configuration : int
        IK configuration, 0..7.
    """

    parameters: NonEmptyText = Field(description="shipped parameter set (L1, D1, L1_ideal) or a TOML path relative to the problem file")
    configuration: integer(0, 7, description="IK configuration") = 0


class MotionSection(Section):
    """``[motion]``: rest-to-rest between two TCP positions.

    Parameters
    ----------
    start, end : list of float, shape (3,)
        TCP positions at rest [m].
    """

    start: vector(3, bound=MAX_LENGTH_M, unit="m", description="TCP position at rest at the start")
    end: vector(3, bound=MAX_LENGTH_M, unit="m", description="TCP position at rest at the end")


class CollocationSection(Section):
    """``[collocation]``: the transcription.

    Parameters
    ----------
    elements : int
        Finite elements, 1..10000.
    points : int
        Collocation points per element, 1..9.
    scheme : str
        ``"radau"`` or ``"legendre"``.
    """

    elements: integer(1, 10000, description="finite elements") = 50
    points: integer(1, 9, description="collocation points per element") = 3
    scheme: choice("radau", "legendre") = "radau"


class SolverSection(Section):
    """``[solver]``: IPOPT settings.

    Parameters
    ----------
    max_iter : int
        IPOPT iteration limit.
    tol : float
        IPOPT tolerance.
    """

    max_iter: integer(1, 10**6, description="IPOPT iteration limit") = 3000
    tol: number(gt=0, le=1.0, description="IPOPT tolerance") = 1e-8


class OcpSolverSection(SolverSection):
    """``[solver]`` of a collocation OCP: the NLP solver and how its derivatives are evaluated.

    Parameters
    ----------
    max_iter : int
        IPOPT iteration limit.
    tol : float
        IPOPT tolerance.
    name : str
        The NLP solver: ``"ipopt"`` (IPOPT with MUMPS, the project's assembled
        derivatives). ``fatrop`` is not offered: CasADi's fatrop plugin differentiates
        the NLP itself and cannot take the compiled derivatives (issue 17).
    jit : bool
        Evaluate the constraint Jacobian and Lagrangian Hessian through C generated from
        their CasADi graph, compiled once with the system compiler and cached (the same
        values, about 5x faster per evaluation); the interpreter without a compiler.
    """

    name: choice("ipopt", description="NLP solver") = "ipopt"
    jit: Flag = Field(default=True, description="compiled (cached) C for the NLP derivatives")


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
        :data:`AT_BOUND_RTOL` of the limit.
    """
    limit = np.asarray(force_limit, dtype=float)
    tau = np.abs(np.column_stack([traj["tau1"], traj["tau2"], traj["tau3"]]))
    return {
        "max_force_ratio": (tau.max(axis=0) / limit).tolist(),
        "fraction_at_force_bound": (tau >= (1 - AT_BOUND_RTOL) * limit).mean(axis=0).tolist(),
    }
