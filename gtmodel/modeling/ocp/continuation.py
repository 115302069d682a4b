"""Continuation over the smoothing of non-smooth model elements (backlash, friction, saturation).

A model's non-smooth elements (:mod:`gtmodel.modeling.library`: ``ElastoBacklash``, ``Friction``, ``Limiter``,
``DeadZone``, or a user's own parameter declared with ``smoothing=True``) are written with a smoothing width
``w`` whose limit ``w -> 0`` is the exact law. A small width makes the NLP hard: a backlash's dead zone, smoothed
over 1 um, switches the drive's stiffness by seven orders of magnitude within a micrometre, and IPOPT, started
from a guess that knows nothing of it, wanders (issue 64: a ball-screw axis with a 0.05 mm gap ended
``check_failed`` 33.8 % above its optimum). Continuation (homotopy) solves the problem with the widths
enlarged first, where it is smooth, then tightens them in steps, each solve started from the last (its primal and
dual point: IPOPT's warm start), down to the declared widths; the last solve is the problem as declared
(Allgower and Georg, *Introduction to Numerical Continuation Methods*, 2003, ch. 1; the smoothing continuation of
contact-implicit trajectory optimisation, e.g. Posa, Cantu and Tedrake 2014).

:func:`smoothing_widths` finds the widths and their declared values; :func:`schedule` gives the steps;
:func:`continue_smoothing` solves the steps before the last on one transcription (the parameters are NLP
parameters: one NLP, solved again for each width) and returns the start of the last solve and the record that
:func:`record_final` completes with the last solve (the widths each element ended at, the objective's change over
the last step). The problem layer's default path (:class:`gtmodel.trajectory.model_ocp.OptimalControl`) runs it
whenever a model declares smoothing widths.
"""

from __future__ import annotations

import logging
import time as _time
from dataclasses import dataclass
from typing import Any, Callable

import numpy as np

from gtmodel.errors import InputError
from gtmodel.modeling.ocp.result import OptimizationResult
from gtmodel.status import Status

__all__ = ["Continuation", "smoothing_widths", "schedule", "continue_smoothing", "record_final", "narrowed_steps",
           "solved_declared", "start_too_far", "FAR_START", "MAX_INSERTED_STEPS"]

_log = logging.getLogger("gtmodel")


@dataclass(frozen=True)
class Continuation:
    """How the smoothing widths are continued (:func:`continue_smoothing`).

    Parameters
    ----------
    enabled : bool
        Continue over the widths when the model declares any (default); False solves at the declared widths alone.
    start_factor : float
        The first solve's widths are the declared ones times this (> 1; default 100).
    step : float
        Each solve divides the widths by this (> 1; default 10), down to the declared ones.

    Raises
    ------
    InputError
        A factor not above 1, naming it.
    """

    enabled: bool = True
    start_factor: float = 100.0
    step: float = 10.0

    def __post_init__(self) -> None:
        for name in ("start_factor", "step"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not (np.isfinite(value) and value > 1):
                raise InputError(f"continuation.{name}: expected a number > 1, got {value!r}")
        if self.step > self.start_factor:
            raise InputError(f"continuation.step: expected at most start_factor ({self.start_factor:g}), got {self.step!r}")


def smoothing_widths(optimization: Any) -> dict[str, float]:
    """The smoothing widths of a problem's model and their values in the problem.

    Parameters
    ----------
    optimization : Optimization
        The problem: its model's ``smoothing`` (the parameters declared with ``smoothing=True``, name -> default),
        each overridden by the problem's own value (:meth:`~gtmodel.modeling.Optimization.set_parameter`).

    Returns
    -------
    dict of str to float
        Name -> width (in the element's units), in declaration order; empty without smoothing widths. A free
        parameter is left out (the NLP chooses it).
    """
    declared = dict(getattr(optimization.model, "smoothing", None) or {})
    free = set(getattr(optimization, "free_parameters", {}) or {})
    out: dict[str, float] = {}
    for name, value in declared.items():
        if name in free:
            continue
        value = optimization.parameters.get(name, value)
        out[name] = float(np.ravel(value)[0])
    return out


def schedule(widths: dict[str, float], settings: Continuation) -> list[float]:
    """The factors on the declared widths, one per solve, the last 1 (the problem as declared).

    Parameters
    ----------
    widths : dict of str to float
        The declared widths (:func:`smoothing_widths`).
    settings : Continuation
        The start factor and the step.

    Returns
    -------
    list of float
        ``[start_factor, start_factor / step, ..., 1]`` (decreasing; the last step may be smaller than ``step``);
        ``[1.0]`` without widths or with continuation off.
    """
    if not widths or not settings.enabled:
        return [1.0]
    factors = [float(settings.start_factor)]
    while factors[-1] / settings.step > 1.0 + 1e-12:
        factors.append(factors[-1] / settings.step)
    return factors + [1.0]


def continue_smoothing(optimization: Any, solve: Callable[[dict[str, float], OptimizationResult | None], OptimizationResult],
                       settings: Continuation | None = None) -> tuple[OptimizationResult | None, dict[str, Any]]:
    """Solve the steps of the continuation before the last, each from the one before.

    Parameters
    ----------
    optimization : Optimization
        The problem (:func:`smoothing_widths`).
    solve : callable
        ``solve(parameters, start) -> OptimizationResult``: the problem solved with the widths given in
        ``parameters`` (name -> width), started from ``start`` (None: the declared guess), unverified (the
        intermediate problems are not the user's).
    settings : Continuation, optional
        Default :class:`Continuation` ().

    Returns
    -------
    tuple
        ``(start, record)``: the last step's result that solved (``optimal`` or ``acceptable``), the start of the
        solve at the declared widths (None without widths, or when the first step failed), and the record
        ``{"declared": {name: width}, "steps": [{"factor", "status", "objective", "iterations", "cpu_s"}]}``
        (empty without widths) that :func:`record_final` completes.
    """
    settings = settings or Continuation()
    widths = smoothing_widths(optimization)
    factors = schedule(widths, settings)
    if len(factors) == 1:
        return None, {}
    record: dict[str, Any] = {"declared": dict(widths), "steps": []}
    start: OptimizationResult | None = None
    name = optimization.model.name
    for factor in factors[:-1]:
        cpu0 = _time.process_time()
        result = solve({k: w * factor for k, w in widths.items()}, start)
        ok = result.status in (Status.OPTIMAL, Status.ACCEPTABLE)
        step = {"factor": factor, "status": str(result.status), "objective": _number(result.objective),
                "iterations": int(result.iterations), "cpu_s": _time.process_time() - cpu0}
        record["steps"].append(step)
        _log.info("continuation of %s: widths x %g, %s, objective %s, %d iterations, %.2f CPU-s", name, factor,
                  result.status, step["objective"], result.iterations, step["cpu_s"])
        if not ok:  # the step failed: the next starts from the last that solved (or the declared guess)
            _log.info("continuation of %s: the step at widths x %g ended %s; the next step starts from the last solved",
                      name, factor, result.status)
            continue
        start = result
    return start, record


#: The most steps :func:`narrowed_steps` inserts between the last width that solved and the declared one.
MAX_INSERTED_STEPS = 3


def narrowed_steps(optimization: Any, solve: Callable[[dict[str, float], OptimizationResult | None], OptimizationResult],
                   declared: Callable[[OptimizationResult], OptimizationResult], start: OptimizationResult | None,
                   record: dict[str, Any], failed: OptimizationResult) -> tuple[OptimizationResult | None, OptimizationResult]:
    """Steps inserted where the solve at the declared widths failed from the last step: the continuation's step halved.

    Only where the failure says the start was outside the declared problem's basin (:func:`start_too_far`).

    The step from the last width that solved to the declared one was too long (its start outside the declared
    problem's basin): a step at the geometric middle of the two factors is solved from the last, and the declared
    widths again from it; a middle step that fails halves the step towards the last that solved instead (step-length
    control of a continuation, Allgower and Georg 2003, sec. 6.1). At most :data:`MAX_INSERTED_STEPS` steps. A held-out
    arm swung up through two gear stages with a 0.01 rad backlash smoothed over 5e-4 rad (steps x100, x10, x1):
    ``Restoration_Failed`` at x1 from x10, then ``Infeasible_Problem_Detected`` solved again cold; the steps x100 /
    3 ... x1.23, x1: optimal, verified after refinement.

    Parameters
    ----------
    optimization : Optimization
        The problem (:func:`smoothing_widths`).
    solve : callable
        As :func:`continue_smoothing`'s: an intermediate step, unverified.
    declared : callable
        ``declared(start) -> OptimizationResult``: the solve at the declared widths from ``start`` (verified; without
        a solution its status is none of :func:`solved_declared`'s).
    start : OptimizationResult or None
        The last step that solved (None: nothing to insert from).
    record : dict
        :func:`continue_smoothing`'s record; each inserted step is added to its ``steps`` with ``"inserted": True``.
    failed : OptimizationResult
        The declared solve that failed from ``start``.

    Returns
    -------
    tuple
        ``(start, result)``: the last step that solved and the declared solve from it (``failed`` when no inserted
        step led to a solution).
    """
    done = [s for s in record.get("steps", []) if s["status"] in ("optimal", "acceptable")]
    if start is None or not done or solved_declared(failed) or not start_too_far(failed):
        return start, failed
    widths, name = smoothing_widths(optimization), optimization.model.name
    solved, target, result = float(done[-1]["factor"]), 1.0, failed
    for _ in range(MAX_INSERTED_STEPS):
        factor = float(np.sqrt(solved * target))
        if not solved > factor * (1.0 + 1e-9) > 1.0:
            break
        cpu0 = _time.process_time()
        step_result = solve({k: w * factor for k, w in widths.items()}, start)
        ok = step_result.status in (Status.OPTIMAL, Status.ACCEPTABLE)
        record["steps"].append({"factor": factor, "status": str(step_result.status), "objective": _number(step_result.objective),
                                "iterations": int(step_result.iterations), "cpu_s": _time.process_time() - cpu0, "inserted": True})
        _log.info("continuation of %s: a step inserted at widths x %g (the declared solve failed from x %g): %s", name,
                  factor, solved, step_result.status)
        if not ok:  # still too long: halve towards the last that solved
            target = factor
            continue
        start, solved, target = step_result, factor, 1.0
        result = declared(start)
        if solved_declared(result) or not start_too_far(result):
            break
    return start, result


#: IPOPT's messages of a start outside the problem's basin, the failures a shorter continuation step can cure.
FAR_START = ("Infeasible_Problem_Detected", "Restoration_Failed")


def start_too_far(result: OptimizationResult) -> bool:
    """True when a failed solve says its start was too far from the problem's feasible points (:data:`FAR_START`).

    Its status ``infeasible``, its message (or its cold retry's status) one of IPOPT's restoration failures. A singular
    NLP (``Error_In_Step_Computation``: a servo commanded beyond its Limiter's saturation, its input inert) or an
    iteration limit is no matter of the step: narrowing the servo's step three times cost 127 CPU-s and ended
    ``max_iterations`` where it had ended ``error`` with its culprit named in 50 s.

    Parameters
    ----------
    result : OptimizationResult
        A solve that ended without a solution.

    Returns
    -------
    bool
    """
    retry = (getattr(result, "stats", None) or {}).get("cold_retry") or {}
    return (result.status == Status.INFEASIBLE or str(result.message).startswith(FAR_START)
            or retry.get("status") == "infeasible" or str(retry.get("warm_message", "")).startswith(FAR_START))

def solved_declared(result: OptimizationResult) -> bool:
    """True when a solve ended with a solution, verified or not (``optimal``, ``acceptable`` or ``check_failed``).

    Parameters
    ----------
    result : OptimizationResult
        A solve's result.

    Returns
    -------
    bool
    """
    return result.status in (Status.OPTIMAL, Status.ACCEPTABLE, Status.CHECK_FAILED)


def record_final(record: dict[str, Any], start: OptimizationResult | None, final: OptimizationResult) -> dict[str, Any]:
    """The continuation's record completed with the solve at the declared widths.

    Parameters
    ----------
    record : dict
        :func:`continue_smoothing`'s record (empty: no continuation).
    start : OptimizationResult or None
        The last step's result that the declared solve started from.
    final : OptimizationResult
        The declared solve's result.

    Returns
    -------
    dict
        ``record`` with ``"final_widths"`` (name -> the width each element ended at: the declared one),
        ``"final_factor"`` 1, ``"last_step_relative_change"`` (the objective's relative change from the last
        step's to the declared solve's; None where either has none) and ``"started_from_factor"`` (the step the
        declared solve started from; None: the declared guess). Empty for an empty ``record``.
    """
    if not record:
        return {}
    out = dict(record)
    out["final_widths"] = dict(record["declared"])
    out["final_factor"] = 1.0
    done = [s for s in record["steps"] if s["status"] in ("optimal", "acceptable")]
    out["started_from_factor"] = done[-1]["factor"] if start is not None and done else None
    a, b = (done[-1]["objective"] if done else None), _number(final.objective)
    out["last_step_relative_change"] = (None if a is None or b is None else (b - a) / max(abs(a), 1e-12))
    return out


def _number(value: Any) -> float | None:
    """A finite float, or None."""
    try:
        v = float(value)
    except (TypeError, ValueError):
        return None
    return v if np.isfinite(v) else None
