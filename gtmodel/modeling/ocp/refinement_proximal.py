"""A refinement pass kept near the pass it refines: a proximal solve first, then the pass's own NLP warm from it.

A pass of the mesh refinement starts from the last pass's trajectories interpolated onto its mesh
(:func:`~gtmodel.modeling.ocp.refinement_guess.guess_from`). On the stiff drives of the drive family that start lies
among local optima within a few per cent of each other (the backlash's contact, the current's bound arcs), and
IPOPT's full Newton steps from it jump between them: ``drive0_04``'s pass-6 solution (0.174729 s), solved again on
its own mesh with IPOPT's defaults, ended at another optimum, 0.182214 s, after 674 iterations; with the passes'
warm settings, ``error`` at 0.212 s after 1,125 iterations and 115.7 CPU-s. Each pass then lands on another optimum,
so the next mesh is fitted to another trajectory, and the refinement saws.

:func:`proximal_start` solves the pass's NLP with the proximal term ``rho |w - w_0|^2`` added to its objective
(``w`` the NLP's variables scaled by their nominals, ``w_0`` the start; the proximal point method, Rockafellar 1976;
Nocedal and Wright, *Numerical Optimization*, 2006, section 17.1 on the quadratic penalty's conditioning), which
keeps IPOPT near the start, and returns its primal-dual point; the pass's own NLP (without the term) is then solved
from it with IPOPT's warm start (its multipliers), which removes the term's bias. ``rho`` is
:data:`PROXIMAL_WEIGHT` times the objective at the start per variable. Measured on that pass (the same mesh and the
next, 142 elements): 47 and 60 iterations in all (0.174666 and 0.174672 s) against 222 and 224 from the start alone.
The loop that uses it is :func:`gtmodel.modeling.ocp.refinement.solve_refined`.

The pass's own solve can still leave the proximal point's neighbourhood: ``drive4_07`` (a ball screw at minimum
copper loss, its table parked in the middle of its gap) at 553 elements, from a proximal point reached in 22
iterations, ran 2,342 iterations (115 CPU-s) to an optimum 1.6 % worse, its deviation 1.0 where its predecessor's was
0.043; at 251 elements it ended ``Restoration_Failed``, and the cold solve after it found another trajectory (deviation
2.1 after 0.025). The proximal point solves the pass's constraints, but its objective is pulled towards the start;
where the own solve ends without a solution or worse than it, :func:`kept_proximal` goes on by the proximal point
method itself (each solve centred on the last point, until a step no longer changes the objective) and returns its
last point, verified. The own solve is held to :data:`OWN_MAX_ITER` iterations.
"""

from __future__ import annotations

import dataclasses
import logging
import time as _time
from typing import Any, Mapping

import casadi as ca
import numpy as np

from gtmodel.modeling.ocp.collocation_function import nlp_solver
from gtmodel.modeling.ocp.collocation_nlp import merge_options
from gtmodel.modeling.ocp.result import OptimizationResult
from gtmodel.status import Status

__all__ = ["proximal_start", "kept_proximal", "PROXIMAL_WEIGHT", "PROXIMAL_CPU_SHARE", "OWN_MAX_ITER", "MAX_PROXIMAL_STEPS", "PROXIMAL_SETTLED"]

_log = logging.getLogger("gtmodel")

#: The proximal term's weight per variable, relative to the objective's magnitude at the start (``rho = PROXIMAL_WEIGHT
#: * max(|f(w_0)|, 1e-6) / n_w``). On ``drive0_04``'s pass the weights 1e-6 to 1e-4 absolute (0.02 to 2.4 relative)
#: gave the same optimum in 39 to 78 iterations.
PROXIMAL_WEIGHT = 0.1
#: The share of the CPU left of the refinement's budget that the proximal solve may take (IPOPT's ``max_cpu_time``):
#: the rest is the pass's own solve's (drive0_33's 2,170-element pass: its proximal solve took all that was left).
PROXIMAL_CPU_SHARE = 0.5

#: IPOPT's iteration limit for a pass's own solve from its proximal point (its own ``max_iter`` if smaller). The drive
#: family's seed 0: 265 such solves, the median 22 iterations, all but four within 205; those four, ``drive0_23``'s, ran
#: to 3,000 iterations (26 to 84 CPU-s each, 208 of its 290) and its proximal points were kept (measured 2026-11-28).
OWN_MAX_ITER = 500
#: The proximal point method's steps after a failed own solve (:func:`kept_proximal`): at most this many ...
MAX_PROXIMAL_STEPS = 10
#: ... until a step changes the objective by at most this (relative): then its point is taken as stationary.
PROXIMAL_SETTLED = 1e-4

_SOLVED = ("Solve_Succeeded", "Solved_To_Acceptable_Level")


def proximal_start(transcription: Any, guess: Mapping[str, Any], parameters: Mapping[str, Any] | None,
                   cpu_left: float) -> OptimizationResult | None:
    """The start of a refinement pass near its guess: its NLP solved with a proximal term added (see the module).

    Parameters
    ----------
    transcription : CollocationTranscription
        The pass's transcription (IPOPT; its solver options, e.g. the warm passes' small barrier, are used).
    guess : mapping
        Its guess, ``name -> (t, values)`` and ``"final_time"``
        (:func:`~gtmodel.modeling.ocp.refinement_guess.guess_from`).
    parameters : mapping or None
        Parameter values of the solve (:meth:`CollocationTranscription.solve`).
    cpu_left : float
        CPU seconds left of the refinement's budget: IPOPT's ``max_cpu_time`` is
        :data:`PROXIMAL_CPU_SHARE` of it.

    Returns
    -------
    OptimizationResult or None
        The proximal solve's point and multipliers as a result of ``transcription`` (unverified; for
        :meth:`CollocationTranscription.solve` with ``warm_start=True``), its ``stats["proximal"]`` the
        iterations, status, weight and CPU seconds; None without CPU left, for fatrop, or when IPOPT ends the
        proximal solve without a solution (the pass then starts from ``guess`` alone).
    """
    tr = transcription
    if tr.plugin != "ipopt" or not PROXIMAL_CPU_SHARE * cpu_left > 1.0:
        return None
    opt = tr.optimization
    pvec = tr.dae.parameter_vector({**opt.parameters, **(parameters or {})})
    guesses = {**opt.initial_guesses, **{k: v for k, v in guess.items() if k != "final_time"}}
    tf = float(np.clip(float(guess.get("final_time", opt.final_time_guess)), *opt.final_time_bounds))
    return _proximal_point(tr, np.asarray(tr._initial_w(guesses, tf, pvec), dtype=float), pvec, PROXIMAL_CPU_SHARE * cpu_left)


def _proximal_point(tr: Any, w0: np.ndarray, pvec: Any, cpu_limit: float) -> OptimizationResult | None:
    """The NLP of ``tr`` solved with the term ``rho |w - w0|^2`` added, as a result of ``tr`` (None without a solution)."""
    cpu0 = _time.process_time()
    nlp = tr.nlp
    f0 = float(ca.Function("f0", [nlp.w, nlp.p], [nlp.f])(w0, pvec))
    rho = PROXIMAL_WEIGHT * max(abs(f0), 1e-6) / max(w0.size, 1)
    options = merge_options(False, {**tr._solver_options, "max_cpu_time": float(cpu_limit)}, "ipopt")
    derivatives = dict(tr.derivative_functions)
    if "hess_lag" in derivatives:  # the pass's assembled Hessian of the Lagrangian plus the term's, 2 rho lam_f I
        x, p = ca.MX.sym("x", nlp.w.numel()), ca.MX.sym("p", nlp.p.numel())
        lam_f, lam_g = ca.MX.sym("lam_f"), ca.MX.sym("lam_g", nlp.g.numel())
        hess = derivatives["hess_lag"](x, p, lam_f, lam_g) + 2 * rho * lam_f * ca.MX.eye(int(nlp.w.numel()))
        derivatives["hess_lag"] = ca.Function("proximal_hess_lag", [x, p, lam_f, lam_g], [hess],
                                              ["x", "p", "lam_f", "lam_g"], ["triu_hess_gamma_x_x"])
    proximal = dataclasses.replace(nlp, f=nlp.f + rho * ca.sumsqr(nlp.w - ca.DM(w0)))
    solver, _ = nlp_solver(proximal, "ipopt", options, derivatives, "proximal")
    try:
        sol = solver(x0=w0, p=pvec, lbx=tr._lbw, ubx=tr._ubw, lbg=tr._lbg, ubg=tr._ubg)
    except RuntimeError as exc:  # an evaluation error inside: the pass starts from its guess alone
        _log.info("proximal start: %s", str(exc).strip().splitlines()[-1] if str(exc).strip() else repr(exc))
        return None
    stats = solver.stats()
    w = np.array(sol["x"], dtype=float).reshape(-1)
    record = {"status": str(stats.get("return_status")), "iterations": int(stats.get("iter_count", 0)), "weight": rho,
              "cpu_s": _time.process_time() - cpu0, "term": float(rho * np.sum((w - w0) ** 2))}
    if record["status"] not in _SOLVED or not np.all(np.isfinite(w)):
        _log.info("mesh refinement: the proximal solve ended %s", record["status"])
        return None
    start = tr._result(w, pvec, Status.OPTIMAL, record["status"], {"proximal": record}, 0.0)
    start.lam_w = np.array(sol["lam_x"], dtype=float).reshape(-1)
    start.lam_g = np.array(sol["lam_g"], dtype=float).reshape(-1)
    return start


def kept_proximal(transcription: Any, start: OptimizationResult | None, result: OptimizationResult,
                  parameters: Mapping[str, Any] | None, objective_tolerance: float,
                  cpu_left: float = float("inf")) -> OptimizationResult:
    """The pass's result, or the proximal point method from its start where the own solve from it did worse.

    Where the own solve ends without a solution, or worse than ``start``, the proximal solve is repeated, each
    centred on the last point (the proximal point method, Rockafellar 1976: each step's objective no higher than
    the last, their fixed point a stationary point of the pass's NLP), until a step changes the objective by at
    most :data:`PROXIMAL_SETTLED` (relative), at most :data:`MAX_PROXIMAL_STEPS` steps. The last point is a KKT
    point of the pass's NLP but for the term's gradient, ``2 rho (w - w0)``: its norm (the NLP's scaled units) is
    recorded as ``stationarity``.

    Parameters
    ----------
    transcription : CollocationTranscription
        The pass's transcription (both points are its NLP's).
    start : OptimizationResult or None
        The proximal start (:func:`proximal_start`), or None (then ``result`` is returned).
    result : OptimizationResult
        The pass's own solve from ``start``.
    parameters : mapping or None
        Parameter values of the solve (:meth:`CollocationTranscription.solve`).
    objective_tolerance : float
        Relative: the own solve is worse where its minimised objective exceeds the start's by more than this
        times the start's magnitude.
    cpu_left : float, optional
        CPU seconds left of the refinement's budget: each proximal step's IPOPT is held to
        :data:`PROXIMAL_CPU_SHARE` of what is left of it (default: no limit).

    Returns
    -------
    OptimizationResult
        ``result`` where it holds a solution (verified or not) no worse than ``start``, or where ``start`` is
        None; else the last proximal point, verified by :meth:`CollocationTranscription.check` (``check_failed``
        if it fails), ``max_iterations`` if its steps had not settled; its message names the proximal steps and
        the own solve's outcome, ``stats["proximal_kept"]`` the own solve's status, iterations and objective, the
        steps, whether they settled, the last step's relative change and ``stationarity``.
    """
    if start is None or start.objective is None or not np.isfinite(start.objective):
        return result
    sign = transcription.optimization.objective_sign
    own = float("inf") if result.verification is None or result.objective is None or not np.isfinite(result.objective) \
        else sign * float(result.objective)
    if own <= sign * float(start.objective) + objective_tolerance * max(abs(float(start.objective)), 1e-12):
        return result
    tr, opt, cpu0 = transcription, transcription.optimization, _time.process_time()
    pvec = tr.dae.parameter_vector({**opt.parameters, **(parameters or {})})
    point, steps, change = start, 0, float("nan")
    while steps < MAX_PROXIMAL_STEPS and not change <= PROXIMAL_SETTLED:
        left = PROXIMAL_CPU_SHARE * (cpu_left - (_time.process_time() - cpu0))
        nxt = _proximal_point(tr, np.asarray(point.w, dtype=float), pvec, left) if left > 1.0 else None
        if nxt is None:
            break
        steps, change = steps + 1, abs(nxt.objective - point.objective) / max(abs(float(point.objective)), 1e-12)
        point = nxt
    last = point.stats["proximal"]  # the term's gradient norm 2 rho |w - w0| = 2 sqrt(rho * rho |w - w0|^2)
    settled = bool(change <= PROXIMAL_SETTLED)
    record = {"status": str(result.status), "iterations": result.iterations, "steps": steps, "settled": settled,
              "last_change": change, "stationarity": 2.0 * float(np.sqrt(last["weight"] * last["term"])), "cpu_s": _time.process_time() - cpu0,
              "objective": None if result.objective is None or not np.isfinite(result.objective) else float(result.objective)}
    point.stats = {**point.stats, "proximal": start.stats["proximal"], "proximal_kept": record}
    if not settled:
        point.status = Status.MAX_ITERATIONS
    tr.check(point, special=np.array(tr.special_function(point.w, pvec), dtype=float).reshape(-1),
             lagrange=float(tr.lagrange_function(point.w, pvec)))
    own_text = (f"the pass's own solve from its proximal start ended {result.status} after {result.iterations} iterations"
                + ("" if record["objective"] is None else f" at {record['objective']:.10g}"))
    steps_text = (f"{steps} further proximal step(s), the last changing the objective by {change:.2g} (relative), "
                  + ("settled" if settled else f"not settled (more than {PROXIMAL_SETTLED:g})"))
    point.message = (f"{start.stats['proximal']['status']}, a proximal point kept: {own_text}; {steps_text}"
                     + ("" if point.status in (Status.OPTIMAL, Status.MAX_ITERATIONS) else f"; {point.message}"))
    point.solve_time = float(result.solve_time or 0.0)
    _log.info("mesh refinement: %s; the proximal point (%.10g) kept", own_text, point.objective)
    return point
