"""A fine collocation mesh solved from the solution of a coarse one (the start of large meshes).

What a user does by hand: a fine mesh from the declared guess alone spends its iterations
where a coarse one spends them at a fraction of the cost. The coarse solution is
interpolated onto the fine mesh (:meth:`CollocationTranscription.solve` with a result as
``initial_guess``); fatrop, whose plugin takes no start multipliers, starts its barrier
parameter small from it (``warm_start``,
:data:`~gtmodel.modeling.ocp.collocation_stages.FATROP_WARM_START_OPTIONS`), IPOPT cold.
Which problems use it and from how many elements is the caller's choice
(:mod:`gtmodel.trajectory.model_ocp`, :mod:`gtmodel.trajectory.point_to_point`).
"""

from __future__ import annotations

from typing import Any, Callable

from gtmodel._timing import merge_phases
from gtmodel.modeling.ocp.result import OptimizationResult

__all__ = ["solve_from_coarse"]


def solve_from_coarse(transcription: Any, coarse: Callable[[], OptimizationResult] | None, initial_guess: Any = None,
                      **solve_kwargs: Any) -> OptimizationResult:
    """Solve ``transcription`` from the result of ``coarse()`` when it is optimal or acceptable.

    Parameters
    ----------
    transcription : CollocationTranscription
        The fine mesh.
    coarse : callable or None
        ``coarse() -> OptimizationResult``: the same problem solved on a coarser mesh
        (unverified); None: no coarse pass.
    initial_guess : optional
        The start when there is no coarse pass or it failed (as
        :meth:`~gtmodel.modeling.ocp.collocation.CollocationTranscription.solve`).
    **solve_kwargs
        Further arguments of :meth:`~gtmodel.modeling.ocp.collocation.CollocationTranscription.solve`
        (``parameters``, ...).

    Returns
    -------
    OptimizationResult
        The fine mesh's result; its ``solve_time`` includes the coarse pass's, its
        ``timing`` the coarse pass's phases (build, guess, solve: ``timing["solve"]`` is
        ``solve_time``), and
        ``stats["coarse_start"]`` records the pass (elements, status, iterations, solve
        time, CPU time, whether it was used).
    """
    first = coarse() if coarse is not None else None
    used = first is not None and str(first.status) in ("optimal", "acceptable")
    result = transcription.solve(initial_guess=first if used else initial_guess,
                                 warm_start=used and transcription.plugin == "fatrop", **solve_kwargs)
    if first is not None:  # the coarse pass is part of this solve's cost
        merge_phases(result.timing, first.timing)  # its build, guess and solve into the fine mesh's phases
        result.solve_time += first.solve_time
        result.stats["coarse_start"] = {"elements": first.collocation.elements, "status": str(first.status),
                                        "iterations": first.iterations, "solve_time": first.solve_time, "used": used,
                                        "t_proc_total": first.stats.get("t_proc_total")}
    return result
