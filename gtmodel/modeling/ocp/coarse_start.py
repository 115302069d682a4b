"""A fine collocation mesh solved from the solution of a coarse one (the start of large meshes).

What a user does by hand: a fine mesh from the declared guess alone spends its iterations
where a coarse one spends them at a fraction of the cost. The coarse solution is
interpolated onto the fine mesh (:meth:`CollocationTranscription.solve` with a result as
``initial_guess``); fatrop, whose plugin takes no start multipliers, starts its barrier
parameter small from it (``warm_start``,
:data:`~gtmodel.modeling.ocp.collocation_stages.FATROP_WARM_START_OPTIONS`); IPOPT, whose start multipliers belong
to the coarse NLP, starts from the interpolated primal point with its barrier parameter small (:data:`WARM_MU`) and
its start not pushed off its bounds (:data:`WARM_PUSH`), as mesh refinement's passes do: with IPOPT's defaults
(barrier parameter 0.1, the start pushed 1 % inside its bounds) it left the coarse solution, and the L1's
minimum time on 800 elements stopped at 3,000 iterations, 0.7045 s against 0.6711 s (issue 64).
Which problems use it and from how many elements is the caller's choice
(:mod:`gtmodel.trajectory.model_ocp`, :mod:`gtmodel.trajectory.point_to_point`); a
linear-quadratic problem (:func:`linear_quadratic`) needs none: its NLP is a quadratic
program, which IPOPT solves in the same few iterations from any start
(``dc_motor_min_energy``: 6 iterations cold against 5 after a 50-element pass that cost
more than the difference, its build included).
"""

from __future__ import annotations

from typing import Any, Callable

import casadi as ca

from gtmodel._timing import merge_phases
from gtmodel.modeling.ocp.result import OptimizationResult

__all__ = ["solve_from_coarse", "linear_quadratic", "WARM_MU", "WARM_PUSH"]

#: IPOPT's initial barrier parameter in a solve started from a solution (a coarse mesh's, a refinement's previous pass).
WARM_MU = 1e-4

#: IPOPT's push of the start off its bounds in a solve started from a solution (relative and absolute, of the
#: variables and the slacks; IPOPT's defaults 1e-2).
WARM_PUSH = {"bound_push": 1e-8, "bound_frac": 1e-8, "slack_bound_push": 1e-8, "slack_bound_frac": 1e-8}

#: IPOPT's own defaults of the options above, restored after a solve from a coarse start.
_IPOPT_DEFAULTS = {"mu_init": 0.1, "bound_push": 1e-2, "bound_frac": 1e-2, "slack_bound_push": 1e-2, "slack_bound_frac": 1e-2}


def linear_quadratic(optimization: Any, dae: Any) -> bool:
    """Whether the problem is linear-quadratic: its collocation NLP a quadratic program.

    True when the final time is fixed, no parameter is free, no data table is fitted, the
    model's right-hand sides, the timed values and integrals and every path and point
    constraint are linear, and the Mayer and Lagrange terms quadratic, in the states, their
    derivatives, the algebraic variables, the inputs and the timed values
    (:func:`casadi.is_linear`, :func:`casadi.is_quadratic` on the symbolic expressions;
    time and the fixed parameters may enter in any way).

    Parameters
    ----------
    optimization : Optimization
        The problem.
    dae : FlatDAE
        Its flattened model (the transcription's).

    Returns
    -------
    bool
    """
    opt = optimization
    if opt.free_final_time or opt.free_parameters or opt.data_fits:
        return False
    specials = opt.special_symbols()
    v = ca.vertcat(dae.x, dae.xdot, dae.z, dae.u, *[s.symbol for s in specials])

    def linear(e: Any) -> bool:
        return e.numel() == 0 or bool(ca.is_linear(e, v))

    exprs = [dae.ode_expr, dae.alg_expr, *[s.expr for s in specials], *[c.expr for c in opt.path_constraints],
             *[c.expr for c in opt.point_constraints]]
    return all(linear(ca.SX(e)) for e in exprs) and all(bool(ca.is_quadratic(ca.SX(e), v)) for e in (opt.mayer, opt.lagrange))


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
    ipopt_warm = used and transcription.plugin == "ipopt"
    if ipopt_warm:  # near the coarse solution: a small barrier parameter, the start kept on its bounds
        own = dict(getattr(transcription, "_solver_options", {}) or {})
        transcription.set_solver_options({"mu_init": WARM_MU, **WARM_PUSH})
    try:
        result = transcription.solve(initial_guess=first if used else initial_guess,
                                     warm_start=used and transcription.plugin == "fatrop", **solve_kwargs)
    finally:
        if ipopt_warm:  # the transcription's own options again (a sweep re-solves it cold)
            transcription.set_solver_options({k: own.get(k, v) for k, v in _IPOPT_DEFAULTS.items()})
    if first is not None:  # the coarse pass is part of this solve's cost
        merge_phases(result.timing, first.timing)  # its build, guess and solve into the fine mesh's phases
        result.solve_time += first.solve_time
        result.stats["coarse_start"] = {"elements": first.collocation.elements, "status": str(first.status),
                                        "iterations": first.iterations, "solve_time": first.solve_time, "used": used,
                                        "t_proc_total": first.stats.get("t_proc_total")}
    return result
