"""Optimal control, Optimica style: the problem, its transcription, its solution.

* :mod:`~gtmodel.modeling.ocp.optimization`: :class:`Optimization`, an optimal control
  problem declared over a model (no transcription);
* :mod:`~gtmodel.modeling.ocp.initial`: the model's fixed starts and initial equations as
  initial conditions of the problem (unless it states its own);
* :mod:`~gtmodel.modeling.ocp.expressions`: the restricted expression language of problem
  files (objectives, constraints) parsed into CasADi;
* :mod:`~gtmodel.modeling.ocp.declare`: the name table of an optimisation and the parsed
  objective and constraints declared on it (:func:`apply_to`);
* :mod:`~gtmodel.modeling.ocp.collocation`: :func:`solve` / :class:`CollocationTranscription`,
  direct collocation solved with IPOPT (or fatrop);
* :mod:`~gtmodel.modeling.ocp.collocation_nlp`: the collocation NLP (variables, constraints,
  layout); :mod:`~gtmodel.modeling.ocp.collocation_derivatives`: its Jacobian and Hessian
  assembled from per-point derivatives; :mod:`~gtmodel.modeling.ocp.collocation_function`:
  warm-started re-solves as one CasADi Function;
* :mod:`~gtmodel.modeling.ocp.methods`: how a problem is solved, apart from what it is:
  :class:`Collocation`, :class:`MultipleShooting`, :class:`SolverSettings`,
  :class:`Refinement` and the :class:`VerificationSettings` passed to a transcription;
* :mod:`~gtmodel.modeling.ocp.shooting`: :class:`ShootingTranscription`, direct multiple
  shooting (piecewise-constant or piecewise-linear inputs, a CasADi integrator per interval);
* :mod:`~gtmodel.modeling.ocp.timed`: the values of timed variables ``x(t)`` and integrals
  in a collocation NLP;
* :mod:`~gtmodel.modeling.ocp.guesses`: initial guesses from a table or a simulation;
* :mod:`~gtmodel.modeling.ocp.result`: :class:`OptimizationResult` and the collocation data;
* :mod:`~gtmodel.modeling.ocp.verification`: :func:`verify`, every solution simulated under
  its optimal inputs (``check_failed`` beyond the tolerance);
  :mod:`~gtmodel.modeling.ocp.refinement`: :func:`solve_refined`, adaptive mesh refinement.
"""

from __future__ import annotations

from gtmodel.modeling.ocp.optimization import Constraint, Optimization
from gtmodel.modeling.ocp.methods import Collocation, MultipleShooting, Refinement, SolverSettings, VerificationSettings
from gtmodel.modeling.ocp.declare import apply_to, optimization_names
from gtmodel.modeling.ocp.expressions import (
    Objective,
    ParsedConstraint,
    parse_constraint,
    parse_expression,
    parse_objective,
)
from gtmodel.modeling.ocp.collocation import CollocationTranscription, solve
from gtmodel.modeling.ocp.result import CollocationData, OptimizationResult
from gtmodel.modeling.ocp.shooting import ShootingTranscription
from gtmodel.modeling.ocp.guesses import guess_by_simulation, guess_from_table
from gtmodel.modeling.ocp.verification import Verification, verify
from gtmodel.modeling.ocp.refinement import solve_refined

__all__ = [
    "Optimization",
    "Constraint",
    "Objective",
    "ParsedConstraint",
    "parse_expression",
    "parse_objective",
    "parse_constraint",
    "optimization_names",
    "apply_to",
    "CollocationTranscription",
    "solve",
    "OptimizationResult",
    "CollocationData",
    "ShootingTranscription",
    "guess_by_simulation",
    "guess_from_table",
    "Verification",
    "verify",
    "solve_refined",
    "Collocation",
    "MultipleShooting",
    "SolverSettings",
    "Refinement",
    "VerificationSettings",
]
