"""CasADi graphs of calibration problems shared between problems of the same structure.

Building the residual/Jacobian graphs of a :class:`~gtmodel.calibration.kinematic.problem.CalibrationProblem`
(closure expressions, their Jacobian, ``map`` + ``expand``) and reading which parameters
enter which arm (Jacobian sparsity) costs ~25 ms for the L1 model, more than the solve.
For model types whose closure equations depend on an instance only through its parameter
vector and the parameter names (``_SHARED_GRAPH_TYPES``), they are built once per
structure and selection and re-used by every later problem, e.g. the problem kind's
``CalibrationProblem(model, selection).solve(...)`` per model.
"""

from __future__ import annotations

from collections import OrderedDict
from typing import Any

import numpy as np

from gtmodel.calibration.kinematic.residuals import _Group
from gtmodel.calibration.kinematic.selection import ParameterSelection, _Resolution
from gtmodel.robots.closure import ClosureModel, ThreeLinkClosure

__all__ = ["GRAPH_CACHE_SIZE", "shared_groups"]

#: Residual/Jacobian graphs (one :class:`_Group` list per model structure and selection)
#: shared by all problems of models whose closure equations are known to depend on the
#: instance only through the parameter vector and its names (``ThreeLinkClosure``); least
#: recently used dropped first.
GRAPH_CACHE_SIZE = 16
_SHARED_GRAPH_TYPES = (ThreeLinkClosure,)
_GRAPHS: "OrderedDict[tuple[Any, ...], list[_Group]]" = OrderedDict()


_ARM_PARAMETERS: dict[tuple[Any, ...], np.ndarray] = {}


def _arm_parameter_indices(model: ClosureModel, arm: int) -> np.ndarray:
    """``model.arm_parameter_indices(arm)`` (Jacobian sparsity), kept per structure for the
    model types of ``_SHARED_GRAPH_TYPES``."""
    if type(model) not in _SHARED_GRAPH_TYPES:
        return model.arm_parameter_indices(arm)
    key = (type(model), tuple(model.parameter_names()), model.n_q, arm)
    if key not in _ARM_PARAMETERS:
        if len(_ARM_PARAMETERS) >= 8 * GRAPH_CACHE_SIZE:
            _ARM_PARAMETERS.clear()
        _ARM_PARAMETERS[key] = np.array(model.arm_parameter_indices(arm))
    return _ARM_PARAMETERS[key].copy()


def _bounded_add(cache: set[Any], key: Any, size: int = 64) -> None:
    """Add ``key`` to a set used as a cache, emptying it first when it is full."""
    if len(cache) >= size:
        cache.clear()
    cache.add(key)


def shared_groups(
    model: ClosureModel,
    resolution: _Resolution,
    selection: ParameterSelection,
    arm_groups: tuple[tuple[int, ...], ...],
    group_vars: list[list[int]],
) -> list[_Group]:
    """The residual/Jacobian graphs of a problem's arm groups, shared between problems.

    Shared only for the model types of ``_SHARED_GRAPH_TYPES`` (exact type), keyed by the
    parameter names, the number of actuators, the links per arm and the selection; other
    models get graphs of their own.

    Parameters
    ----------
    model : ClosureModel
        The problem's model.
    resolution : _Resolution
        The selection resolved against ``model`` (variables, quaternions, ties).
    selection : ParameterSelection
        The selection (part of the key).
    arm_groups : tuple of tuple of int
        Arms per group (connected over shared variables).
    group_vars : list of list of int
        Variable indices per group.

    Returns
    -------
    list of _Group
        One per arm group, in the order of ``arm_groups``.
    """
    def build() -> list[_Group]:
        return [_Group(model, resolution, a, v) for a, v in zip(arm_groups, group_vars)]

    if type(model) not in _SHARED_GRAPH_TYPES:
        return build()
    key = (
        type(model), resolution.names, model.n_q, tuple(len(l) for l in model.links),
        (selection.free, selection.fixed, selection.ties),
    )
    groups = _GRAPHS.get(key)
    if groups is None:
        groups = _GRAPHS[key] = build()
        while len(_GRAPHS) > GRAPH_CACHE_SIZE:
            _GRAPHS.popitem(last=False)
    _GRAPHS.move_to_end(key)
    return groups
