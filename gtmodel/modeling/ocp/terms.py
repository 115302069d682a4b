"""The declared terms of an :class:`~gtmodel.modeling.Optimization`: constraints, timed variables, integrals.

:class:`Constraint` is a declared ``lb <= expr <= ub`` (path, at the start or final time,
or over timed variables and integrals); :class:`Timed` and :class:`Integral` are the
symbols standing for the value of an expression at a fixed time (Optimica's timed
variables) and for an integral over the horizon, given values by the transcriptions.
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np

__all__ = ["Constraint", "Timed", "Integral"]


@dataclass
class Constraint:
    """A declared constraint ``lb <= expr <= ub``.

    Parameters
    ----------
    name : str
        Label used in messages.
    expr : casadi.SX
        Column expression.
    lb, ub : numpy.ndarray
        Bounds, one per element of ``expr``.
    at : str or None
        ``None`` for a path constraint, ``"start"`` or ``"final"`` for a point constraint
        (model variables taken there), ``"timed"`` for a constraint on timed variables
        and integrals (:meth:`Optimization.timed`, :meth:`Optimization.integral`).
    """

    name: str
    expr: ca.SX
    lb: np.ndarray
    ub: np.ndarray
    at: str | None = None


@dataclass
class Timed:
    """A timed variable: an expression of the model's variables at one fixed time (Optimica's ``x(t)``).

    Parameters
    ----------
    symbol : casadi.SX
        Scalar symbol standing for the value in objectives and constraints.
    expr : casadi.SX
        Scalar expression of model variables, parameters and ``final_time``.
    time : float or str
        Absolute time [s] in the horizon, or ``"start"`` / ``"final"``; for a time at a
        fixed fraction of a free horizon, that time at the final time's guess (for
        messages only).
    fraction : float or None, optional
        ``s`` in ``(0, 1)`` for a time ``start_time + s (final_time - start_time)`` of a
        free final time (normalised time: the point moves with the final time); None
        otherwise.
    """

    symbol: ca.SX
    expr: ca.SX
    time: float | str
    fraction: float | None = None


@dataclass
class Integral:
    """An integral over the horizon standing as a symbol (isoperimetric constraints).

    Parameters
    ----------
    symbol : casadi.SX
        Scalar symbol standing for the value.
    expr : casadi.SX
        Scalar integrand over ``[start_time, final_time]``.
    """

    symbol: ca.SX
    expr: ca.SX
