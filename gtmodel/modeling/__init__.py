"""Modelica-inspired modelling layer: equation-based models, Optimica-style problems.

Rooms by job (lower rooms never import higher ones; an import-linter contract checks it):
``library`` (MSL-named components) -> ``components`` (Component, connectors, connect())
and ``ocp`` (Optimization, expressions, collocation, results) -> ``simulation`` (Model,
flattening to a CasADi DAE, simulators, linearisation, inverse model) -> ``structure``
(incidence, matching, alias elimination, index reduction, initialisation, events) ->
:mod:`~gtmodel.modeling.dae` (the flat DAE and the symbol helpers every room shares).

* :class:`Model` declares parameters, states, algebraic variables, inputs, ``der()``
  equations and outputs (CasADi SX), flattens to a :class:`FlatDAE` and simulates.
* :class:`Optimization` declares an optimal control problem over a model.
* :class:`Component`, :func:`connect` and :mod:`gtmodel.modeling.library`: acausal
  components with connectors (Modelica style), flattened into a :class:`Model`.
* :func:`solve` / :class:`CollocationTranscription` transcribe it by direct collocation
  and solve it with IPOPT, giving an :class:`OptimizationResult`.
* :func:`structural_simplify` / :func:`check_structure`: alias elimination, structural check
  and index reduction (Pantelides, dummy derivatives) to an index-1 model;
  ``Model.initial_equation`` for a consistent initialisation.
* ``Model.when`` / ``Model.mode``: zero-crossing state events (``sign()`` becomes
  event-switched modes); the event times are in ``SimulationResult.events``.
* :func:`explicit_ode`: the model as an explicit ODE ``xdot = f(x, u, p)``, ``y = h(x, u, p)``
  (algebraic variables eliminated symbolically, or by Newton inside the graph) and its
  fixed-step integrators (:meth:`ExplicitODE.step`: RK4, implicit Euler, Radau IIA);
* :func:`inverse_model`: forces from a prescribed motion (Modelica's inverse model);
  :func:`gtmodel.modeling.simulation.linear.linearize`: the linearisation of a model.
"""

from __future__ import annotations

import sys

from gtmodel._lazy import lazy_exports
from gtmodel.modeling.dae import FlatDAE, SimulationResult
from gtmodel.modeling.structure import discontinuities as _discontinuities
from gtmodel.modeling.structure.analysis import check_structure
from gtmodel.modeling.structure.index_reduction import structural_simplify
from gtmodel.modeling.simulation import linear as _linear
from gtmodel.modeling.simulation.model import Model
from gtmodel.modeling.simulation.explicit import ExplicitODE, explicit_ode
from gtmodel.modeling.ocp import collocation as _collocation
from gtmodel.modeling.ocp import expressions as _expressions
from gtmodel.modeling.ocp.collocation import CollocationTranscription, solve
from gtmodel.modeling.ocp.optimization import Optimization
from gtmodel.modeling.ocp.result import OptimizationResult
from gtmodel.modeling.ocp.declare import apply_to, optimization_names
from gtmodel.modeling.ocp.expressions import (
    Objective,
    ParsedConstraint,
    parse_constraint,
    parse_expression,
    parse_objective,
)

#: Module paths the docs name, kept importable after the move into rooms (the same module
#: objects under their old names: ``from gtmodel.modeling.linear import linearize`` works).
_DOC_PATHS = {
    "linear": _linear,
    "expressions": _expressions,
    "collocation": _collocation,
    "discontinuities": _discontinuities,
}
for _name, _module in _DOC_PATHS.items():
    sys.modules.setdefault(f"{__name__}.{_name}", _module)

__all__ = [
    "Model",
    "FlatDAE",
    "SimulationResult",
    "Optimization",
    "structural_simplify",
    "ExplicitODE",
    "explicit_ode",
    "check_structure",
    "inverse_model",
    "InverseModel",
    "OptimizationResult",
    "CollocationTranscription",
    "solve",
    "Objective",
    "ParsedConstraint",
    "parse_expression",
    "parse_objective",
    "parse_constraint",
    "optimization_names",
    "apply_to",
    "Component",
    "Parameter",
    "Variable",
    "State",
    "Input",
    "Structural",
    "connect",
    "Connector",
    "Potential",
    "Flow",
]

#: Imported on first use (:mod:`gtmodel._lazy`): the inverse model and the acausal components,
#: which a problem file on an equation-based model (``gtmodel solve``) does not need.
__getattr__, __dir__ = lazy_exports(__name__, {
    "InverseModel": "simulation.inverse",
    "inverse_model": "simulation.inverse",
    "Component": "components.component",
    "Input": "components.component",
    "Parameter": "components.component",
    "State": "components.component",
    "Structural": "components.component",
    "Variable": "components.component",
    "connect": "components.component",
    "Connector": "components.connectors",
    "Flow": "components.connectors",
    "Potential": "components.connectors",
})
