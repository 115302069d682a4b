"""Modelica-inspired modelling layer: equation-based models, Optimica-style problems.

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
* :func:`inverse_model`: forces from a prescribed motion (Modelica's inverse model);
  :func:`gtmodel.modeling.linear.linearize`: the linearisation of a model.
"""

from __future__ import annotations

from gtmodel.modeling.collocation import CollocationTranscription, solve
from gtmodel.modeling.components import Component, Input, Parameter, State, Structural, Variable, connect
from gtmodel.modeling.connectors import Connector, Flow, Potential
from gtmodel.modeling.dae import FlatDAE, SimulationResult
from gtmodel.modeling.model import Model
from gtmodel.modeling.optimization import Optimization
from gtmodel.modeling.index_reduction import structural_simplify
from gtmodel.modeling.inverse import InverseModel, inverse_model
from gtmodel.modeling.structure import check_structure
from gtmodel.modeling.result import OptimizationResult
from gtmodel.modeling.expressions import (
    Objective,
    ParsedConstraint,
    apply_to,
    optimization_names,
    parse_constraint,
    parse_expression,
    parse_objective,
)

__all__ = [
    "Model",
    "FlatDAE",
    "SimulationResult",
    "Optimization",
    "structural_simplify",
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
