"""The one-call collocation solve, ``gtmodel.modeling.solve``: transcribe an
:class:`~gtmodel.modeling.Optimization` by direct collocation
(:class:`~gtmodel.modeling.ocp.collocation.CollocationTranscription`) and solve it."""

from __future__ import annotations

from typing import Any, Mapping

from gtmodel.modeling.ocp.collocation import CollocationTranscription
from gtmodel.modeling.ocp.optimization import Optimization
from gtmodel.modeling.ocp.result import OptimizationResult

__all__ = ["solve"]


def solve(
    optimization: Optimization,
    elements: int = 50,
    points: int = 3,
    scheme: str = "radau",
    verbose: bool = False,
    solver_options: Mapping[str, Any] | None = None,
    initial_guess: OptimizationResult | Mapping[str, Any] | None = None,
) -> OptimizationResult:
    """Transcribe by direct collocation and solve with IPOPT.

    Parameters
    ----------
    optimization : Optimization
        The declared problem.
    elements : int, optional
        Number of uniform elements; default 50.
    points : int, optional
        Collocation points per element; default 3.
    scheme : {"radau", "legendre"}, optional
        Collocation scheme; default ``"radau"``.
    verbose : bool, optional
        Show IPOPT output; default False.
    solver_options : mapping, optional
        IPOPT/CasADi options merged over the defaults (see
        :class:`CollocationTranscription`).
    initial_guess : OptimizationResult or mapping, optional
        See :meth:`CollocationTranscription.solve`.

    Returns
    -------
    OptimizationResult
        The result; ``success`` is True only for status ``"optimal"``.

    Raises
    ------
    InputError
        On invalid transcription arguments or guesses.
    ModelError
        If the model cannot be flattened.
    SolverError
        If the NLP solver cannot be built.
    """
    tr = CollocationTranscription(
        optimization,
        elements=elements,
        points=points,
        scheme=scheme,
        verbose=verbose,
        solver_options=solver_options,
    )
    return tr.solve(initial_guess=initial_guess)
