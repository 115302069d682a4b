"""Optimal control of a user's model as one declaration: the problem, its method and solver settings.

:class:`OptimalControl` (what the ``optimal_control`` problem kind loads) holds the
:class:`~gtmodel.modeling.Optimization` declared on a user's model, the collocation
transcription (:class:`~gtmodel.trajectory.settings.Collocation`) and IPOPT's settings
(:class:`~gtmodel.trajectory.settings.SolverSettings`); :meth:`OptimalControl.solve`
transcribes and solves it.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from gtmodel._docstrings import SHARED_DOCS, fill_doc
from gtmodel.modeling import CollocationTranscription, Model, Optimization, OptimizationResult
from gtmodel.trajectory.settings import Collocation, SolverSettings

__all__ = ["OptimalControl"]


@dataclass
class OptimalControl:
    """The declaration of an ``optimal_control`` problem.

    Parameters
    ----------
    name : str
        Problem name.
    model_file : pathlib.Path
        The model's Python file.
    class_name : str
        The class in it.
    optimization : Optimization
        The declared problem (objective, constraints, bounds, boundary values, guesses).
    method : Collocation
        The transcription.
    solver : SolverSettings
        IPOPT's iteration limit and tolerance.
    nominal : dict of str to float
        Nominal magnitudes (scaling).
    objective : str
        The objective text.
    sense : {"minimize", "maximize"}
        Whether it is minimised or maximised.
    constraints : tuple of str
        The constraint texts.
    named_parameters : dict of str to float
        The ``[parameters]`` table.
    bounds : dict of str to tuple of float
        Bounds per scalar variable name (for the plots).
    """

    name: str
    model_file: Path
    class_name: str
    optimization: Optimization
    method: Collocation
    solver: SolverSettings
    nominal: dict[str, float] = field(default_factory=dict)
    objective: str = ""
    sense: str = "minimize"
    constraints: tuple[str, ...] = ()
    named_parameters: dict[str, float] = field(default_factory=dict)
    bounds: dict[str, tuple[float, float]] = field(default_factory=dict)

    @property
    def model(self) -> Model:
        """The user's model."""
        return self.optimization.model

    @fill_doc(**SHARED_DOCS)
    def solve(self, *, verbose: bool = False, previous: Any = None, warm_start: bool = False) -> OptimizationResult:
        """Transcribe by collocation and solve with IPOPT.

        Parameters
        ----------
        {solve_args}

        Returns
        -------
        OptimizationResult
        """
        d = self
        tr = CollocationTranscription(
            d.optimization, elements=d.method.elements, points=d.method.points, scheme=d.method.scheme, verbose=verbose,
            solver_options={"max_iter": d.solver.max_iter, "tol": d.solver.tol}, nominal=d.nominal,
        )
        guess = previous if warm_start and isinstance(previous, OptimizationResult) and previous.collocation is not None else None
        return tr.solve(initial_guess=guess)
