"""Re-solve a point-to-point problem for new boundary poses or weights without rebuilding it.

The NLP of :func:`gtmodel.trajectory.solve_point_to_point` takes the boundary poses
(:data:`~gtmodel.trajectory.point_to_point.START_POSE`, ``END_POSE``) and the named
parameters of the objective as NLP parameters, so a changed pose or weight is a new
parameter vector of the same NLP: nothing is transcribed or compiled again. A warm start
uses the previous solution's primal point and multipliers with a small barrier parameter
(:data:`gtmodel.modeling.ocp.collocation_function.WARM_START_OPTIONS`); the tests check that it
reaches the optimum of a cold start after a 1 cm change of the end pose. The same solve as
one CasADi Function of the parameter vector is :meth:`point_to_point_function`.
"""

from __future__ import annotations

import dataclasses
import logging
from typing import Any

import casadi as ca
import numpy as np

from gtmodel._arrays import as_finite
from gtmodel.errors import InputError
from gtmodel.trajectory.point_to_point import (
    END_POSE,
    START_POSE,
    PointToPointSolution,
    _energy,
)

__all__ = ["resolve_point_to_point", "point_to_point_function", "point_to_point_parameters"]

_log = logging.getLogger("gtmodel")


def _pose(value: Any, name: str) -> np.ndarray:
    arr = np.asarray(as_finite(value, name), dtype=float).reshape(-1)
    if arr.shape != (3,):
        raise InputError(f"{name}: expected three finite numbers [m], got {value!r}")
    return arr


def point_to_point_parameters(previous: PointToPointSolution, start: Any = None, end: Any = None, named_parameters: Any = None) -> dict:
    """The parameter values of a re-solve: poses and named parameters, the previous ones unless given.

    Parameters
    ----------
    previous : PointToPointSolution
        A solution of :func:`~gtmodel.trajectory.solve_point_to_point`.
    start, end : array_like, shape (3,), optional
        New boundary poses [m].
    named_parameters : mapping of str to float, optional
        New values of named parameters of the objective/constraints.

    Returns
    -------
    dict
        Model parameter name -> value (for ``CollocationTranscription.solve`` or
        ``FlatDAE.parameter_vector``).

    Raises
    ------
    InputError
        A malformed pose, or a name that is not a named parameter of the problem.
    """
    decl = previous.problem
    params = dict(decl.named_parameters)
    for k, v in dict(named_parameters or {}).items():
        if k not in params:
            raise InputError(f"named_parameters: {k!r} is not a named parameter of {decl.name!r} ({', '.join(params) or 'none'})")
        params[k] = float(v)
    params[START_POSE] = decl.start if start is None else _pose(start, "start")
    params[END_POSE] = decl.end if end is None else _pose(end, "end")
    return params


def resolve_point_to_point(
    previous: PointToPointSolution,
    start: Any = None,
    end: Any = None,
    named_parameters: Any = None,
    warm_start: bool = True,
) -> PointToPointSolution:
    """Solve ``previous``'s problem again for new poses or named parameters, reusing its NLP.

    Parameters
    ----------
    previous : PointToPointSolution
        A solution of :func:`~gtmodel.trajectory.solve_point_to_point` (it holds the NLP).
    start, end : array_like, shape (3,), optional
        New boundary poses [m]; default the previous ones.
    named_parameters : mapping of str to float, optional
        New values of named parameters (e.g. the energy weight ``w``).
    warm_start : bool, optional
        Start from ``previous``'s primal-dual point (True, default) or from the problem's
        initial guess with a cold barrier (False: the cold-start optimum, for comparison).

    Returns
    -------
    PointToPointSolution
        For the new declaration; always returned, its status says whether it is optimal.
        A warm start that does not converge is retried cold (logged).

    Raises
    ------
    InputError
        Malformed poses or unknown parameter names; ``previous`` has no NLP.
    UnreachablePoseError
        A pose outside the workspace.
    """
    tr = previous.transcription
    if tr is None:
        raise InputError("previous: the solution holds no NLP (solve it with solve_point_to_point)")
    params = point_to_point_parameters(previous, start, end, named_parameters)
    # the new declaration checks its poses (workspace) and force limits (holding forces) itself
    decl = dataclasses.replace(
        previous.problem,
        start=params[START_POSE],
        end=params[END_POSE],
        named_parameters={k: v for k, v in params.items() if k not in (START_POSE, END_POSE)},
    )
    warm = warm_start and previous.result.lam_g is not None and previous.result.transcription_key == tr.key
    result = tr.solve(parameters=params, initial_guess=previous.result if warm else None, warm_start=warm)
    if warm and not result.success:
        _log.warning("%s: the warm start ended with %s; solving cold", decl.name, result.status)
        result = tr.solve(parameters=params)
    return PointToPointSolution(problem=decl, result=result, energy=_energy(result), transcription=tr)


def point_to_point_function(previous: PointToPointSolution, warm_start: bool = True) -> ca.Function:
    """``previous``'s NLP solve as one CasADi Function (rockit's ``to_function``).

    Parameters
    ----------
    previous : PointToPointSolution
        A solution of :func:`~gtmodel.trajectory.solve_point_to_point`.
    warm_start : bool, optional
        Warm-start IPOPT options (see :func:`gtmodel.modeling.ocp.collocation_function.resolve_function`).

    Returns
    -------
    casadi.Function
        ``(p, w0, lam_w0, lam_g0) -> (w, lam_w, lam_g, objective, final_time)``; ``p`` is
        ``previous.transcription.dae.parameter_vector(point_to_point_parameters(previous, start, end))``
        and the start point ``previous.result.w, .lam_w, .lam_g``.

    Raises
    ------
    InputError
        ``previous`` holds no NLP.
    """
    if previous.transcription is None:
        raise InputError("previous: the solution holds no NLP (solve it with solve_point_to_point)")
    return previous.transcription.to_function(f"{previous.problem.name}_resolve".replace("-", "_"), warm_start)
