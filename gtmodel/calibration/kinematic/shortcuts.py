"""Calibrate in one call: :func:`calibrate` and :func:`analyze_identifiability`, with a
bounded cache of :class:`~gtmodel.calibration.kinematic.problem.CalibrationProblem`s."""

from __future__ import annotations

from collections import OrderedDict
from typing import Any, Mapping, Sequence

import numpy as np

from gtmodel.calibration.identifiability import IdentifiabilityReport, analyze_jacobian
from gtmodel.calibration.kinematic.data import _unpack_measurements
from gtmodel.calibration.kinematic.problem import DEFAULT_SOLVER, MAX_ITER, CalibrationProblem
from gtmodel.calibration.kinematic.result import CalibrationResult
from gtmodel.calibration.kinematic.selection import ParameterSelection
from gtmodel.errors import InputError
from gtmodel.robots.closure import ClosureModel

__all__ = ["calibrate", "analyze_identifiability", "PROBLEM_CACHE_SIZE"]


#: Problems kept by :func:`calibrate` (least recently used dropped first); each holds its
#: model, so the cache is bounded rather than weak.
PROBLEM_CACHE_SIZE = 16
_PROBLEMS: "OrderedDict[tuple[int, Any], CalibrationProblem]" = OrderedDict()


def _selection_of(selection: Any, free: Any, fixed: Any, ties: Any) -> ParameterSelection:
    if selection is not None:
        if free is not None or fixed is not None or ties is not None:
            raise InputError("give either selection or free/fixed/ties, not both")
        if not isinstance(selection, ParameterSelection):
            raise InputError(f"selection: expected a ParameterSelection, got {type(selection).__name__}")
        return selection
    return ParameterSelection(free=free, fixed=fixed or (), ties=ties or ())


def _problem(model: ClosureModel, sel: ParameterSelection) -> CalibrationProblem:
    if not isinstance(model, ClosureModel):
        raise InputError(f"model: expected a ClosureModel, got {type(model).__name__}")
    key = (id(model), (sel.free, sel.fixed, sel.ties))
    problem = _PROBLEMS.get(key)
    if problem is None or problem.model is not model:
        problem = CalibrationProblem(model, sel)
        _PROBLEMS[key] = problem
        while len(_PROBLEMS) > PROBLEM_CACHE_SIZE:
            _PROBLEMS.popitem(last=False)
    _PROBLEMS.move_to_end(key)
    return problem


def calibrate(
    model: ClosureModel,
    q: Any,
    T: np.typing.ArrayLike | None = None,
    quat: np.typing.ArrayLike | None = None,
    weights: np.typing.ArrayLike | None = None,
    *,
    selection: ParameterSelection | None = None,
    free: str | Sequence[str] | None = None,
    fixed: str | Sequence[str] | None = None,
    ties: str | Sequence[Any] | Mapping[str, str] | None = None,
    solver: str = DEFAULT_SOLVER,
    align: bool = True,
    max_iter: int = MAX_ITER,
) -> CalibrationResult:
    """Calibrate a kinematic model from measured poses (Dressler (2012), eqs. 5.1-5.4).

    Builds (or re-uses, per model instance and selection) a :class:`CalibrationProblem`
    and solves it; see the module docstring for the method.

    Parameters
    ----------
    model : ClosureModel
        Nominal model (start values; moved into the measurement frame if ``align``).
    q : array_like, shape (N, n_q), or MeasurementSet
        Actuator values [m, rad] (or a measurement set with ``q, T, quat, weights``).
    T : array_like, shape (N, 3)
        Measured TCP positions [m].
    quat : array_like, shape (N, 4), optional
        Measured orientations ``(w, x, y, z)`` (models with orientation).
    weights : array_like, shape (N,), optional
        Non-negative pose weights (residuals multiplied by ``sqrt(w)``).
    selection : ParameterSelection, optional
        Free/fixed/tied parameters (alternative to ``free``, ``fixed``, ``ties``).
    free : str or sequence of str, optional
        Free parameter names or patterns (default: all not fixed or tied).
    fixed : str or sequence of str, optional
        Fixed parameter names or patterns.
    ties : str or sequence or mapping, optional
        ``"target = source"`` ties.
    solver : {"lm", "trf", "ipopt", "ipopt-gn"}, optional
        Solver (default :data:`DEFAULT_SOLVER`).
    align : bool, optional
        Fit the base transform first (default True).
    max_iter : int, optional
        Iteration limit per group.

    Returns
    -------
    CalibrationResult

    Raises
    ------
    InputError
        Bad shapes or values, unknown parameter names (with close matches), too few poses
        for an arm group.
    ModelError
        Singular problem at the start (non-identifiable parameters listed with their
        dependencies; ``report`` attribute), or a free parameter in no closure equation.
    """
    sel = _selection_of(selection, free, fixed, ties)
    problem = _problem(model, sel)
    return problem.solve(q, T, quat, weights, solver=solver, align=align, max_iter=max_iter)


def analyze_identifiability(
    model: ClosureModel,
    q: Any,
    T: np.typing.ArrayLike | None = None,
    quat: np.typing.ArrayLike | None = None,
    weights: np.typing.ArrayLike | None = None,
    *,
    selection: ParameterSelection | None = None,
    free: str | Sequence[str] | None = None,
    fixed: str | Sequence[str] | None = None,
    ties: str | Sequence[Any] | Mapping[str, str] | None = None,
) -> IdentifiabilityReport:
    """Identifiability of a model's free parameters from a pose set, at the model's values.

    The Jacobian of all closure residuals (eqs. 5.1-5.2) with respect to the free
    variables is analysed by :func:`~gtmodel.calibration.identifiability.analyze_jacobian`
    (column-pivoted QR, Dressler (2012), Table 5.4). No frame alignment: ``T`` must be in
    the model's frame (e.g. its own FK for a planned pose set).

    Parameters
    ----------
    model : ClosureModel
        The model (its parameter values are the linearisation point).
    q : array_like, shape (N, n_q), or MeasurementSet
        Actuator values [m, rad].
    T : array_like, shape (N, 3)
        TCP positions [m].
    quat : array_like, shape (N, 4), optional
        Plate orientations (models with orientation).
    weights : array_like, shape (N,), optional
        Pose weights.
    selection : ParameterSelection, optional
        Free/fixed/tied parameters.
    free : str or sequence of str, optional
        Free parameter names or patterns.
    fixed : str or sequence of str, optional
        Fixed parameter names or patterns.
    ties : str or sequence or mapping, optional
        ``"target = source"`` ties.

    Returns
    -------
    IdentifiabilityReport
        With standard deviations from the residuals at the model's values if there are
        more residuals than variables.

    Raises
    ------
    InputError
        Bad shapes, values or names.
    ModelError
        A free parameter enters no closure equation.
    """
    sel = _selection_of(selection, free, fixed, ties)
    problem = _problem(model, sel)
    q, T, quat, weights = _unpack_measurements(q, T, quat, weights, model)
    r, J, names = problem.jacobian(model.parameter_vector(), q, T, quat, weights)
    w = np.ones(r.shape[0]) if weights is None else np.asarray(weights, dtype=float).ravel()
    keep = w > 0
    Jm = J[keep].reshape(-1, len(names))
    rm = r[keep].ravel()
    return analyze_jacobian(Jm, names, residuals=rm if rm.size > len(names) else None)
