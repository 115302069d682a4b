"""Modelica-inspired modelling layer: equation-based models, Optimica-style problems.

* :class:`Model` declares parameters, states, algebraic variables, inputs, ``der()``
  equations and outputs (CasADi SX), flattens to a :class:`FlatDAE` and simulates.
* :class:`Optimization` declares an optimal control problem over a model.
* :func:`solve` / :class:`CollocationTranscription` transcribe it by direct collocation
  and solve it with IPOPT, giving an :class:`OptimizationResult`.
"""

from __future__ import annotations

from gtmodel.modeling.collocation import CollocationTranscription, solve
from gtmodel.modeling.model import FlatDAE, Model, SimulationResult
from gtmodel.modeling.optimization import Optimization
from gtmodel.modeling.result import OptimizationResult

__all__ = [
    "Model",
    "FlatDAE",
    "SimulationResult",
    "Optimization",
    "OptimizationResult",
    "CollocationTranscription",
    "solve",
]
