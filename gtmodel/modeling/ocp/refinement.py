"""Adaptive mesh refinement of a collocation solution (h-refinement, as GPOPS-II's and Dymos' grid refinement).

:func:`solve_refined` solves on a mesh, verifies the solution
(:mod:`gtmodel.modeling.ocp.verification`) and refines where it is least accurate, until
the verification tolerance is met or a limit on elements or passes is reached. Each pass
starts from the previous solution, interpolated onto the new mesh. Two error indicators
choose the elements to split:

* the *element defect*: the largest scaled deviation of an element's own simulation
  under the optimal inputs from its collocated start (``Verification.element_errors``).
  An element above the tolerance is split into 2, 3 or 4 equal parts (by how far it is
  above: below ``10 tol``, ``100 tol``, beyond). When every element is within the tolerance but
  the simulation over the horizon is not (the local errors add up), the elements are compared
  with ``ADD_UP * max(defect) * tol / deviation`` instead (:data:`~gtmodel.modeling.ocp.refinement_mesh.ADD_UP`),
  so that the contributors are split together. Where an input's polynomial exceeds its bound, the verification simulates the
  inputs clipped to their bounds (:func:`~gtmodel.modeling.ocp.verification.check_result`), and an element split
  for its defect is cut where its input's polynomial leaves and re-enters the bound too (the clipped input's
  kinks: :func:`~gtmodel.modeling.ocp.verification_bounds.input_bound_crossings`).
* a *switch*: an input that crosses most of its range within one element (a bang-bang
  switch, which no polynomial represents: the collocation smooths it, and a model that
  integrates the input, such as the double integrator, shows no defect while the
  optimum is missed by O(h)). Such an element, if longer than ``tol`` times the horizon,
  is split where the input's collocation polynomial crosses the middle of its range
  within the element, so that the switch moves onto an element boundary. Repeated, this
  locates the switch time to the width of the element that holds it. A switch estimated at
  an element's edge (:data:`SWITCH_EDGE`: the jump is on the boundary already) is not cut
  into a sliver; if the element's defect exceeds ``tol`` (a stiff state, such as a motor
  current against its limit, after the jump) the element is graded towards the jump
  (parts 0.15, 0.30, 0.55 of it), so that the transient after it is resolved.
* a *state bound* exceeded between the nodes: once nothing else is left to split, an element whose
  verifying simulation exceeds a state bound by more than the tolerance (scaled as the deviations;
  :mod:`~gtmodel.modeling.ocp.verification_bounds`) is cut where its state's polynomial first crosses
  the bound, at its input's switch, and into 2 to 4 parts (Betts, *Practical Methods*, ch. 4; GPOPS-II).
  From the pass after such an excess on, the state bounds also hold on the polynomial at
  :data:`~gtmodel.modeling.ocp.collocation_bounds.BOUND_POINTS` more points per element in the elements around
  where it was (IPOPT; not fatrop's stage structure; :mod:`~gtmodel.modeling.ocp.collocation_bounds`).
  A pass is verified only if it keeps the bounds too; if no pass does, the verified pass that keeps them
  best is returned, its ``verification.bounds`` holding a ``remedy`` (issue 49: the drives' motor current).

A pass whose deviation exceeds :data:`SPURIOUS` times the tolerance and
:data:`SPURIOUS_DEVIATION` has found a spurious
minimum of the NLP (the COPS hanging chain on 20 elements: its length shrinks inside the
first element): the next pass starts from a repaired guess instead of the spurious
trajectory (the inputs of the failing elements interpolated from their neighbours', the
states simulated under those inputs). Each pass starts from the previous solution interpolated onto its mesh, with IPOPT's barrier
parameter started at :data:`WARM_MU` and its start not pushed off its bounds (:data:`WARM_PUSH`)
so that it stays near it; IPOPT first solves the pass's NLP with a proximal term that keeps it near that start, then
the NLP itself warm from that point and its multipliers (:mod:`~gtmodel.modeling.ocp.refinement_proximal`: from the
start alone, IPOPT's steps jumped between neighbouring local optima of the stiff drives, hundreds of iterations a
pass); a proximal solve without a solution leaves the pass to start from the interpolation alone. A pass whose objective is
worse by more than :data:`WORSE` than an earlier pass feasible by simulation (its simulation
reaches its final state, :func:`end_deviation` within :data:`ANCHOR_END`: no spurious minimum,
and keeps the state bounds between the nodes within the tolerance) has left for another
local optimum: it is rejected and the earlier pass refined instead. The refinement stops at the
verification passing, at ``max_passes``, or at its CPU budget (``max_cpu_s``; each pass's IPOPT held to what is
left of it, ``max_cpu_time``). A pass that IPOPT stopped at its
acceptable level (``acceptable_iter`` iterations within ``acceptable_tol``) is continued in the same pass from
its primal-dual point (IPOPT's warm start: its multipliers and a small barrier parameter) with that early stop off,
within :data:`POLISH_CPU_S`: on the flexible-joint drive such stops were crawls (Newton steps regularised at every
iteration at a barrier parameter of 1e-9), not minima of the pass's NLP, 0.3 to 3 % above them, and the passes' objectives
jumped by percents between meshes; continued, each pass ends at its mesh's minimum (0.33272 to 0.33288 s) and the
refinement optimal and verified in 7 passes (issue 49). A pass that verifies with
nothing left to split but ended IPOPT's ``acceptable`` (IPOPT stopped after ``acceptable_iter``
iterations at its looser level, not at its tolerance: on the flexible-joint drive 1.6 % above
where the same start converges) is not where the refinement ends: the next pass re-solves its
mesh from it with that early stop off (``acceptable_iter = 0``; its own NLP warm from its multipliers where the pass
was solved here, not a ``start``), once per such pass, within what is left
of the CPU budget (IPOPT's ``max_cpu_time``). It returns the
verified and ``optimal`` pass with the best objective, else the verified ``acceptable`` pass with
the best objective, else the pass with the smallest deviation, with
``refinement`` (one dict per pass: elements, points, objective, status, largest element error,
deviation, end deviation, bound violation, CPU and wall time, what was done) and
``refinement_stop`` (why it ended, which pass it returned). ``start``: a single solve whose
verification failed, refined from without solving it again (``refine_on_failure``).

A verified ``optimal`` pass with nothing left to split is not yet where the refinement ends: its objective is
checked against the next pass, its mesh with every element halved (the element defects say how well the plan is
simulated, not whether a finer mesh finds a better plan: a held-out vertical ball screw with a 600 Hz compliant
coupling verified at 90 elements 0.45 % above its optimum, its coarse mesh unable to follow the coupling that the
optimum exploits, and its halved mesh gained 0.30 %). Where the halved pass improves the objective by more than
``objective_tolerance`` (relative; default :data:`OBJECTIVE_TOLERANCE`), the refinement goes on from it; else it
ends, "the objective converged" (or, where the halved pass is worse by more than the tolerance, "the objective did not
improve", with that change as the objective's uncertainty). The check is skipped, and the stop says so, where the element limit, the pass limit
or the CPU budget leaves no room for it. The mesh steps are :mod:`gtmodel.modeling.ocp.refinement_mesh`.

From its second pass on, the refinement regularises a minimum-time problem's inputs
(:mod:`~gtmodel.modeling.ocp.regularization`, weight ``defaults["ocp.input_regularization"]``, each input scaled by
its RMS in the pass refined from): on a bound arc the inputs between the points are otherwise free, ring
differently on every mesh, and the deviation saws (drive0_38: 21 passes unverified; regularised, verified).

Not done: the degree is the same in every element (the transcription takes one number of
points), so this is h-refinement; the p-part of hp/ph methods (Patterson, Hager and Rao 2015,
raising the degree of smooth elements) is not.
"""

from __future__ import annotations

import copy
import dataclasses
import logging
import time as _time
from typing import Any

import numpy as np

from gtmodel.defaults import defaults
from gtmodel.errors import InputError
from gtmodel.modeling.ocp.coarse_start import WARM_MU, WARM_PUSH  # noqa: F401 - re-exported (refinement's warm passes)
from gtmodel.modeling.ocp.collocation import CollocationTranscription
from gtmodel.modeling.ocp.methods import VerificationSettings
from gtmodel.modeling.ocp.optimization import Optimization
from gtmodel.modeling.ocp.result import OptimizationResult, lagrange_basis
from gtmodel.modeling.ocp.verification import SPURIOUS_DEVIATION, SWITCH_FRACTION, refinement_passes, switch_elements
from gtmodel.modeling.ocp.verification_bounds import bounds_verdict, element_bound_violations
from gtmodel.modeling.ocp.refinement_remedy import refinement_remedy
from gtmodel.modeling.ocp.budget import ipopt_left, max_elements as memory_max_elements, stall_cap
from gtmodel.modeling.ocp.collocation_bounds import BOUND_POINTS, excess_spans, merged_spans
from gtmodel.modeling.ocp.refinement_mesh import SWITCH_EDGE, finer, halved, refine_mesh, switch_times
from gtmodel.modeling.ocp.regularization import input_scales, regularization_weight
from gtmodel.modeling.ocp.refinement_guess import guess_from, repaired_guess, solved_cold
from gtmodel.modeling.ocp.refinement_proximal import OWN_MAX_ITER, kept_proximal, proximal_start
from gtmodel.modeling.ocp.refinement_interrupt import keeps_verified_pass, recorded  # issue 67: Ctrl-C keeps a verified pass
from gtmodel.status import Status

__all__ = ["solve_refined", "start_cpu", "refine_mesh", "SWITCH_EDGE", "OBJECTIVE_TOLERANCE", "end_deviation", "WORSE", "ANCHOR_END", "WARM_MU", "WARM_PUSH", "POLISH_CPU_S", "switch_elements", "switch_times", "MAX_ELEMENTS", "MAX_PASSES", "SWITCH_FRACTION", "SPURIOUS", "SPURIOUS_DEVIATION"]

_log = logging.getLogger("gtmodel")

#: The element limit of a refined mesh that a problem file or caller sets no limit for is the memory estimate's
#: (:func:`gtmodel.modeling.ocp.budget.max_elements`: about 9,000 elements of a drive model in 24 GiB), not a
#: fixed number (issue 64: 400, whatever the model and machine); this is the limit of the schemas' examples.
MAX_ELEMENTS = 400
#: Default limit on refinement passes (solves).
MAX_PASSES = defaults["ocp.refine_max_passes"]
#: Passes compared to tell a stalled between-node bound excess (:func:`bound_remedy`).
STALL_PASSES = 4
#: A verification deviation this many times the tolerance, and above
#: :data:`SPURIOUS_DEVIATION`, marks a spurious minimum of the NLP rather than a
#: discretisation error: the next pass starts from a repaired guess.
SPURIOUS = 100.0


def end_deviation(result: OptimizationResult) -> float:
    """Scaled deviation of the simulated final state from the transcribed one (inf without a simulation).

    Parameters
    ----------
    result : OptimizationResult
        A verified collocation result.

    Returns
    -------
    float
        ``max_i |x_sim,i(t_f) - x_col,i(t_f)| / max(1, max |x_col,i|)``: small, the optimal
        inputs take the model where the solution says (its final conditions hold), even if it
        deviates on the way (a stiff current's transient inside an element).
    """
    v, col = result.verification, result.collocation
    if v is None or col is None or v.simulated.size == 0:
        return float("inf")
    end = lagrange_basis(col.tau_root, np.array([1.0])) @ col.xc[-1]  # (1, nx)
    scale = np.maximum(1.0, np.max(np.abs(col.xc), axis=(0, 1)))
    return float(np.max(np.abs(np.asarray(v.simulated)[-1] - end[0]) / scale))


def start_cpu(start: OptimizationResult) -> float:
    """The CPU time [s] a solve at hand cost: its phases' CPU (build, guess, solve, verification), never its wall time.

    The single solve that refinement starts from (``refine_on_failure``) is charged to the CPU budget by this;
    charged with its wall time (``solve_time``), a loaded machine's first solve read 885.7 CPU-s for a 76.5 CPU-s
    solve (issue 64) and the budget left no pass for the refinement.

    Parameters
    ----------
    start : OptimizationResult
        A collocation result (its ``timing``: ``phase -> {"wall_s", "cpu_s"}``; its ``verification.cpu_s``).

    Returns
    -------
    float
        The sum of its phases' CPU seconds; without phases, the solver's own process time
        (``stats["t_proc_total"]``) and its verification's CPU time.
    """
    phases = start.timing or {}
    if phases:
        cpu = float(sum(float(e.get("cpu_s", 0.0)) for e in phases.values()))
        if "verification" not in phases and start.verification is not None:
            cpu += float(start.verification.cpu_s or 0.0)
        return cpu
    solver = float(start.stats.get("t_proc_total") or 0.0) if start.stats else 0.0
    return solver + (float(start.verification.cpu_s or 0.0) if start.verification is not None else 0.0)


def _feasible(entry: dict[str, Any], tolerance: float) -> bool:
    """A pass feasible by simulation: its simulation reaches its final state (within :data:`ANCHOR_END`), keeps
    the state bounds between the nodes (within ``tolerance``, scaled as the deviations) and follows its states (within
    :data:`ANCHOR_DEVIATION`); no later pass may be worse."""
    # a pass that keeps the current limit at its points only (the flexible joint's first pass: 2.8 A over it between
    # them) is faster than the bounds allow; anchored to it, refinement rejected the passes that kept the bound, and
    # stopped unverified ("left pass 3's optimum again"): now verified on its third pass
    # nor one whose states deviate from its simulation by more than a spurious minimum's (drive0_35, a ball screw at
    # minimum copper loss: its first pass's current 2.5 A off its simulation inside elements, scaled 0.89, so its
    # objective, the current's integral, is not the motion's; anchored to it, the finer passes were rejected as
    # "another local optimum" and the refinement stopped unverified on pass 1)
    return (entry["end_deviation"] <= ANCHOR_END and entry.get("max_bound_violation", 0.0) <= tolerance
            and entry.get("max_scaled_deviation", 0.0) <= ANCHOR_DEVIATION)


def _minimised(optimization: Optimization, result: OptimizationResult) -> float:
    """The objective as the NLP minimises it (``sign * objective``; inf without one)."""
    value = result.objective
    return float("inf") if value is None or not np.isfinite(value) else float(optimization.objective_sign * value)


def _pass_entry(n_pass: int, tr: CollocationTranscription, result: OptimizationResult, cpu: float, wall: float) -> dict[str, Any]:
    """One pass of the refinement as the summary and the log report it."""
    entry: dict[str, Any] = {
        "pass": n_pass, "elements": tr.elements, "points": tr.points, "status": str(result.status), "objective": result.objective,
        "final_time": result.final_time, "iterations": result.iterations, "solve_time": result.solve_time,
        "solve_cpu_time": (result.timing.get("solve") or {}).get("cpu_s"), "cpu_s": cpu, "wall_s": wall,
    }
    v = result.verification
    if v is not None:
        entry["verified"] = bool(v.passed)
        entry["max_scaled_deviation"] = v.max_scaled_deviation
        entry["verification_time"] = v.time_s
        entry["verification_cpu_time"] = v.cpu_s
        entry["max_element_error"] = float(np.max(v.element_errors)) if v.element_errors.size else 0.0
        entry["end_deviation"] = end_deviation(result)
        if "max_scaled_violation" in v.bounds:  # the states' (the inputs' under "inputs")
            entry["max_bound_violation"] = v.bounds["max_scaled_violation"]
    return entry


@keeps_verified_pass  # issue 67: a signal returns the last verified pass (refinement_interrupt)
@refinement_passes
def solve_refined(
    optimization: Optimization,
    elements: int = 50,
    points: int = 3,
    scheme: str = "radau",
    max_elements: int | None = None,
    max_passes: int = MAX_PASSES,
    tolerance: float | None = None,
    initial_guess: OptimizationResult | dict[str, Any] | None = None,
    parameters: dict[str, Any] | None = None,
    max_cpu_s: float | None = None,
    start: OptimizationResult | None = None,
    verification: VerificationSettings | None = None,
    objective_tolerance: float | None = None,
    **transcription: Any,
) -> OptimizationResult:
    """Solve by collocation with adaptive h-refinement of the mesh (see the module docstring).

    Parameters
    ----------
    optimization : Optimization
        The declared problem.
    elements : int, optional
        Elements of the first, uniform mesh; default 50.
    points : int, optional
        Collocation points per element; default 3.
    scheme : {"radau", "legendre"}, optional
        Collocation points; default ``"radau"``.
    max_elements : int, optional
        Limit on the elements of a refined mesh; default (None) the most the memory estimate allows
        (:func:`gtmodel.modeling.ocp.budget.max_elements`, read at the first pass).
    max_passes : int, optional
        Limit on the solves (``start`` counted as one); default :data:`MAX_PASSES`.
    tolerance : float, optional
        Verification tolerance (over ``verification``'s); default the problem's
        :attr:`Optimization.verification_tolerance` (or ``defaults["ocp.verification_tolerance"]``).
        Passed to every pass's transcription, not written onto the problem.
    initial_guess : OptimizationResult or mapping, optional
        Guess of the first pass (see :meth:`CollocationTranscription.solve`).
    parameters : mapping of str to float or array_like, optional
        Parameter values of every pass (see :meth:`CollocationTranscription.solve`).
    max_cpu_s : float, optional
        Budget of CPU time [s] of the refinement (this process; the passes' solves and
        verifications): no pass starts once it is spent or the last pass's cost would
        overrun it. Default ``defaults["ocp.refine_max_cpu_s"]``.
    start : OptimizationResult, optional
        A verified solution of ``optimization`` already at hand (a single solve whose
        verification failed): the first pass, refined from, not solved again.
    verification : VerificationSettings, optional
        The verification's settings (tolerance, integrator, its rtol), each None field the
        problem's own (:meth:`~gtmodel.modeling.ocp.methods.VerificationSettings.over`).
    objective_tolerance : float, optional
        Relative change of the objective below which a verified pass's objective has converged with its
        mesh: a verified ``optimal`` pass with nothing left to split is followed by a pass on its mesh
        with every element halved, and the refinement goes on from that pass while it improves the
        objective by more than this fraction (see the module docstring); 0 ends at the first verified
        pass without the check. Default ``defaults["ocp.refine_objective_tolerance"]``
        (:data:`OBJECTIVE_TOLERANCE`).
    **transcription
        Further arguments of :class:`CollocationTranscription` (``solver_options``,
        ``nominal``, ``verbose``, ...); its ``regularization`` is the weight here (None:
        ``defaults["ocp.input_regularization"]``; 0 off), applied from the second pass on with each input
        scaled by its RMS in the pass refined from (:mod:`~gtmodel.modeling.ocp.regularization`).

    Returns
    -------
    OptimizationResult
        The verified ``optimal`` pass with the best objective if one passed, else the verified
        ``acceptable`` pass with the best objective, else the pass with the smallest verification
        deviation (``check_failed``); ``refinement`` holds one dict
        per pass (elements, points, status, objective, largest element error and deviation,
        the simulation's end deviation and bound violation, CPU and wall time, what was
        done next; ``check_next`` on a verified pass whose objective the next pass checks,
        ``objective_check`` (``{"pass", "relative_improvement"}``) on that next pass, ``regularization`` (the
        input regularisation's value in its NLP objective) on a regularised pass, ``returned``
        on the pass returned) and ``refinement_stop`` why it ended; ``solve_time`` is the sum over the
        passes.

    Raises
    ------
    InputError
        On invalid limits, tolerance, budget or transcription arguments.
    """
    for label, value, lo in (("max_elements", elements if max_elements is None else max_elements, elements), ("max_passes", max_passes, 1)):
        if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < lo:
            raise InputError(f"{label}: expected an integer >= {lo}, got {value!r}")
    budget = defaults["ocp.refine_max_cpu_s"] if max_cpu_s is None else max_cpu_s
    if isinstance(budget, bool) or not isinstance(budget, (int, float, np.integer, np.floating)) or not budget > 0:
        raise InputError(f"max_cpu_s: expected a positive number of seconds, got {budget!r}")
    settings = (verification or VerificationSettings()).over(optimization)
    if tolerance is not None:
        settings = dataclasses.replace(settings, tolerance=tolerance)
    tol = settings.tolerance
    try:
        tol = float(defaults["ocp.verification_tolerance"] if tol is None else tol)
    except (TypeError, ValueError):
        raise InputError(f"tolerance: expected a positive number, got {tol!r}") from None
    if not (np.isfinite(tol) and tol > 0):
        raise InputError(f"tolerance: expected a positive number, got {tol!r}")
    objective_tol = OBJECTIVE_TOLERANCE if objective_tolerance is None else objective_tolerance
    if isinstance(objective_tol, bool) or not isinstance(objective_tol, (int, float, np.integer, np.floating)) or not 0 <= objective_tol < 1:
        raise InputError(f"objective_tolerance: expected a number in [0, 1) (0: no objective check), got {objective_tolerance!r}")
    name = optimization.model.name
    reg_weight = regularization_weight(transcription.get("regularization"))[0]  # from the second pass on, by the last's RMS
    scales: dict[str, float] | None = None
    cpu0 = _time.process_time()
    state_bounds: tuple[np.ndarray, np.ndarray] | None = None
    input_bounds: tuple[np.ndarray, np.ndarray] | None = None
    mesh: np.ndarray | None = None
    guess: Any = initial_guess
    history: list[dict[str, Any]] = recorded("history")  # issue 67: read by keeps_verified_pass on a signal
    passes: list[OptimizationResult] = recorded("passes")
    anchor: OptimizationResult | None = None  # the best pass feasible by simulation (_feasible): no later pass may be worse
    stop = "the verification passed and no element is left to split"
    n_elements = elements
    warm = False
    polish = False  # the next pass re-solves the same mesh with IPOPT's acceptable termination off
    warm_from: CollocationTranscription | None = None  # the last pass's transcription (a polish re-solves its NLP)
    checking: OptimizationResult | None = None  # the verified pass whose objective this pass checks on its mesh halved
    bound_spans: list[tuple[float, float]] = []  # where state bounds were exceeded between the points (collocation_bounds)

    def state_bounds_of(r: OptimizationResult) -> tuple[np.ndarray, np.ndarray] | None:
        return optimization.bounds_vectors(r.dae, "x") if r.dae is not None and r.dae.nx and r.collocation is not None else None
    for n_pass in range(1, int(max_passes) + 1):
        c0, w0 = _time.process_time(), _time.perf_counter()
        if n_pass == 1 and start is not None:
            result, n_elements = start, start.collocation.elements if start.collocation is not None else elements
            tr_points, cpu, wall = points, start_cpu(start), float(start.solve_time or 0.0)
        else:
            options = {**transcription, "regularization": (reg_weight, scales) if scales is not None else 0.0}
            if warm and options.get("solver", "ipopt") == "ipopt":
                # started from the previous pass: a small barrier parameter keeps IPOPT near it (the default
                # 0.1 pushes the start off its active bounds, and a drive's NLP wandered 600 iterations into a
                # local optimum 38 % slower)
                # and its variables at their bounds are not pushed inside by IPOPT's default bound_push 1e-2 (the
                # voltage at 24 V moved to 23.76 V, the current at 8 A to 7.92 A: the flexible joint's warm passes left
                # for optima 2-3 % slower, and its refinement ended unverified; with WARM_PUSH, verified)
                options["solver_options"] = {"mu_init": WARM_MU, **WARM_PUSH, **dict(options.get("solver_options") or {})}
                if polish:
                    # without the early stop IPOPT may iterate long (the flexible joint under another BLAS kernel: 1608
                    # iterations, 99 CPU-s, past the budget): held to what is left of the budget
                    left = ipopt_left(budget, cpu0)
                    options["solver_options"].update(acceptable_iter=0, max_cpu_time=float(left))
            if options.get("solver", "ipopt") == "ipopt":  # every pass held to what is left of the budget: drive0_35's pass
                # 16 ran 3,000 iterations, several times its predecessor's cost, and the run ended at 368 CPU-s against 250
                left = ipopt_left(budget, cpu0)
                options["solver_options"] = {"max_cpu_time": float(left), **dict(options.get("solver_options") or {})}
            if polish and warm_from is not None and options.get("solver", "ipopt") == "ipopt":
                # the previous pass's own NLP re-solved from its primal-dual point (IPOPT's warm start: its multipliers,
                # a small barrier parameter): from the flexible joint's acceptable pass 9 (0.3347391), a start without
                # its multipliers left it at the first step (0.3372) and crawled, regularised at every iteration, into
                # the CPU limit (493 iterations, 34 CPU-s); warm, the same kind of pass ends optimal in 74 iterations, 1.2 CPU-s
                tr = warm_from
                tr.set_solver_options({k: options["solver_options"][k] for k in ("acceptable_iter", "max_cpu_time")})
                result = tr.solve(parameters=parameters, initial_guess=passes[-1], warm_start=True)
            else:
                tr = CollocationTranscription(optimization, elements=elements, points=points, scheme=scheme, mesh=mesh, verify=settings, **options)
                proximal = warm and options.get("solver", "ipopt") == "ipopt" and isinstance(guess, dict)
                begun = proximal_start(tr, guess, parameters, ipopt_left(budget, cpu0)) if proximal else None
                if proximal:  # the pass's own solve held to what the proximal one left (drive0_33's pass 26: the proximal
                    # solve ran to the CPU limit, then the pass's own as long again: 350 CPU-s, the run 478 against 290)
                    left = ipopt_left(budget, cpu0)
                    held = float(tr.options.get("ipopt", {}).get("max_cpu_time", left))  # its own limit, if smaller
                    iterations = int(tr.options.get("ipopt", {}).get("max_iter", 3000))  # from a proximal point: OWN_MAX_ITER
                    tr.set_solver_options({"max_cpu_time": min(held, left), **({"max_iter": min(iterations, OWN_MAX_ITER)} if begun else {})})
                cap = stall_cap(history, tr.elements) if warm and options.get("solver", "ipopt") == "ipopt" else None
                if cap is not None:  # a warm solve that stalls leaves the cold retry what is left (budget.stall_cap)
                    tr.set_solver_options({"max_cpu_time": min(float(tr.options.get("ipopt", {}).get("max_cpu_time", cap)), cap)})
                result = tr.solve(parameters=parameters, initial_guess=guess if begun is None else begun, warm_start=begun is not None)
                if begun is not None:
                    result.stats = {**(result.stats or {}), "proximal": begun.stats["proximal"]}
                    result = kept_proximal(tr, begun, result, parameters, objective_tol, ipopt_left(budget, cpu0))
                if warm and result.verification is None and options.get("solver", "ipopt") == "ipopt":  # no solution warm
                    result = solved_cold(tr, result, guess, parameters, ipopt_left(budget, cpu0))
            warm_from = tr if result.lam_g is not None else None
            if (not polish and warm_from is not None and options.get("solver", "ipopt") == "ipopt"
                    and result.stats.get("return_status") == "Solved_To_Acceptable_Level"):
                # IPOPT stopped at its acceptable level in a crawl (the flexible joint: regularised Newton steps at a
                # barrier parameter of 1e-9, 2e-5 s of objective per iteration), not at a minimum of this mesh's NLP:
                # continued from its primal-dual point (warm, the crawl left in 20 to 80 iterations) to IPOPT's tolerance
                left = ipopt_left(budget, cpu0)
                tr.set_solver_options({"acceptable_iter": 0, "max_cpu_time": float(min(left, POLISH_CPU_S))})
                polished = tr.solve(parameters=parameters, initial_guess=result, warm_start=True)
                continued = {"from": float(result.objective), "status": str(polished.status), "objective": polished.objective}
                if polished.verification is not None and polished.status in (Status.OPTIMAL, Status.CHECK_FAILED):
                    result = polished
                    result.stats = {**result.stats, "continued": continued}
            n_elements, tr_points = tr.elements, tr.points
            cpu, wall = _time.process_time() - c0, _time.perf_counter() - w0
        entry = _pass_entry(n_pass, _Mesh(n_elements, tr_points), result, cpu, wall)
        history.append(entry)
        passes.append(result)
        for key in ("continued", "cold_retry", "proximal", "proximal_kept"):  # the acceptable stop continued; a warm pass without a solution cold again
            if key in result.stats:
                entry[key] = result.stats[key]
        if polish:
            entry["polished"] = True  # IPOPT's acceptable stop off in this pass
        if (result.stats or {}).get("regularization"):  # the input regularisation's value in this pass's NLP objective
            entry["regularization"] = result.stats["regularization"]["value"]
        v = result.verification
        _log.info("mesh refinement of %s: pass %d, %d elements x %d points, %s, objective %.10g, largest element error %.3g, "
                  "deviation %.3g, %.1f CPU-s", name, n_pass, n_elements, tr_points, result.status, result.objective
                  if result.objective is not None else float("nan"), entry.get("max_element_error", float("nan")),
                  entry.get("max_scaled_deviation", float("nan")), cpu)
        if v is None:  # the solve failed: nothing to refine from
            stop = (f"the CPU budget ({budget:g} s; pass {n_pass} stopped at IPOPT's CPU limit, what was left of it)"
                    if "CpuTime" in str(result.message) else f"pass {n_pass} ended {result.status} without a solution to refine")
            break
        if entry.get("max_bound_violation", 0.0) > tol and transcription.get("solver", "ipopt") == "ipopt" and state_bounds_of(result):
            # a state bound exceeded between the points: from the next pass on imposed between them too, in the elements
            # around where it was (drive0_03: the current's polynomial 1.7 % over between points that kept it, splitting
            # alone stalled at 1.9 % for 16 passes); not everywhere: on a bound arc the rows and the points' bounds are
            # active together, dependent, and IPOPT's iterations grew (drive0_04: 444 to 729 a pass)
            col = result.collocation
            fractions = col.fractions if col.fractions is not None else np.full(col.elements, 1.0 / col.elements)
            # judged as refine_mesh judges it: by the elements' own simulations while the global one has drifted
            spans = excess_spans(fractions, element_bound_violations(result, *state_bounds_of(result), local=None), 0.5 * tol)
            bound_spans = merged_spans(bound_spans + spans)
            transcription = {**transcription, "bound_points": BOUND_POINTS, "bound_spans": bound_spans}
            entry["bound_points"] = {"points": BOUND_POINTS, "spans": len(bound_spans)}
            warm_from, polish = None, False
            _log.info("mesh refinement of %s: state bounds at %d more points per element in %d part(s) of the horizon "
                      "from pass %d on", name, BOUND_POINTS, len(bound_spans), n_pass + 1)
        if checking is not None:
            # this pass is the previous verified pass's mesh with every element halved: the objective's change with the
            # mesh (the compliant screw of the held-out drives, verified at 90 elements 0.45 % above its optimum, which a
            # finer mesh resolves: its 600 Hz coupling, smoothed by the coarse mesh, is exploited)
            k_checked = passes.index(checking) + 1
            gain = _objective_gain(optimization, checking, result)
            entry["objective_check"] = {"pass": k_checked, "relative_improvement": gain}
            checking = None
            if not gain > objective_tol:  # not better: converged, or worse by more than the tolerance, which is no
                # convergence (drive0_38: +0.44 %, another local optimum on the finer mesh): then said as its uncertainty
                stop = (f"the objective converged: pass {k_checked}'s mesh with every element halved changed it by "
                        f"{-gain:+.2g} (relative; tolerance {objective_tol:g})" if -objective_tol <= gain else
                        f"the objective did not improve: pass {k_checked}'s mesh with every element halved ended "
                        + (f"{-gain:+.2g} worse (relative; tolerance {objective_tol:g}; another local optimum or an "
                           f"unsettled switch), so pass {k_checked}'s objective is known to about {-gain:.2g}"
                           if np.isfinite(gain) else f"{result.status} without an objective to compare (unchecked)"))
                break
            _log.info("mesh refinement of %s: pass %d (pass %d's mesh halved) improves the objective by %.3g (relative, "
                      "tolerance %g): refined on from it", name, n_pass, k_checked, gain, objective_tol)
        base = result
        if anchor is not None and _minimised(optimization, result) > _minimised(optimization, anchor) + WORSE * abs(_minimised(optimization, anchor)):
            # refinement changes a feasible solution by the discretisation error only: a pass
            # this much worse has left for another local optimum; the next pass refines the anchor instead
            k = passes.index(anchor) + 1
            entry["rejected"] = (f"objective {result.objective:.10g} worse than pass {k}'s {anchor.objective:.10g}, which "
                                 "is feasible by simulation: another local optimum; pass {k} refined instead").replace("{k}", str(k))
            _log.warning("mesh refinement of %s: %s", name, entry["rejected"])
            base = anchor
        elif _feasible(entry, tol) and (anchor is None or _minimised(optimization, result) <= _minimised(optimization, anchor)
                                               or v.passed):
            anchor = result
        if state_bounds is None and result.dae is not None and result.dae.nx:
            state_bounds = optimization.bounds_vectors(result.dae, "x")
        if input_bounds is None and result.dae is not None and result.dae.nu:
            input_bounds = optimization.bounds_vectors(result.dae, "u")
        if max_elements is None:  # the memory estimate's cap, from the model's size
            dae = result.dae
            max_elements = max(elements, memory_max_elements(tr_points, dae.nx, dae.nz, dae.nu)) if dae is not None else MAX_ELEMENTS
            _log.info("mesh refinement of %s: at most %d elements (the memory estimate)", name, max_elements)
        persistent = len(history) > 1 and min(history[-2].get("max_bound_violation", 0.0), entry.get("max_bound_violation", 0.0)) > tol
        new, info = refine_mesh(base, tol, max_elements, bounds=state_bounds, input_bounds=input_bounds, persistent=persistent)
        if base is not result:  # at least as fine as the rejected pass's mesh
            new = finer(new, mesh if mesh is not None else np.full(n_elements, 1.0 / n_elements))
        entry["switches_s"] = info["switches"]
        if base is not result and history[-2].get("rejected") and len(new) == n_elements:
            stop = f"pass {n_pass} left pass {passes.index(anchor) + 1}'s optimum again on the same mesh"
            break
        if not info["split"] and base is result and v.passed and result.status == Status.ACCEPTABLE and not polish:
            # verified, but IPOPT stopped at its acceptable level, not at an optimum (the flexible joint's pass 4:
            # acceptable at 0.3358544, +0.6 % on the reference): its mesh re-solved from it to IPOPT's tolerance
            polish = True
            entry["polish"] = "ended acceptable: its mesh re-solved from it with IPOPT's acceptable stop off"
        elif not info["split"] and base is result:
            polish = False
            spent = _time.process_time() - cpu0
            unchecked = _objective_unchecked(optimization, result, objective_tol, n_elements, max_elements,
                                             max_passes - n_pass, budget - spent, cpu) if not info.get("limited") else "limit"
            if unchecked is None:  # verified with nothing to split: its objective checked on its mesh halved
                checking = result
                new = halved(result.collocation.fractions if result.collocation.fractions is not None else np.full(n_elements, 1.0 / n_elements))
                entry["check_next"] = "its objective, on its mesh with every element halved"
            else:
                # elements still to split (for a deviation, a switch or a state bound between the nodes) that the element
                # limit has no room for: the limit stopped it, not the mesh's convergence (said so, with its remedy)
                stop = (f"the element limit ({max_elements} elements)" if info.get("limited") else
                        "the verification passed and no element is left to split" if v.passed else
                        f"no element left to split within {max_elements} elements")
                stop += f" ({unchecked})" if unchecked else ""
                break
        entry["split"] = len(info["split"])
        spent = _time.process_time() - cpu0
        if n_pass == max_passes:
            stop = f"the pass limit ({max_passes})"
            break
        if spent + cpu > budget:
            stop = f"the CPU budget ({budget:g} s; {spent:.1f} s spent, the last pass took {cpu:.1f} s)"
            break
        polish = polish and "polish" in entry
        mesh = new
        if base is result and v.max_scaled_deviation > max(SPURIOUS * tol, SPURIOUS_DEVIATION) and entry["end_deviation"] > SPURIOUS_DEVIATION:
            # not a discretisation error but a spurious minimum of the NLP (its simulation does not reach its
            # end): start the next pass away from it (its own trajectory would lead back)
            entry["restart"] = "inputs of the failing elements interpolated, states simulated"
            guess, warm = repaired_guess(result, tol), False
        else:
            guess, warm = guess_from(base), True
        scales = input_scales(base) if reg_weight > 0 else None  # a minimum-time problem's inputs regularised from here on
    # verified: the deviations within the tolerance and the state bounds kept between the nodes (_kept); else a verified
    # pass at IPOPT's acceptable level: the best of them, not the smallest deviation (the flexible joint's pass 9,
    # 0.3347391, over its pass 4, 0.3358544, whose deviation was smaller by 3e-4); else, the bounds not kept by any
    # pass, the same choice among the passes whose deviations verified (its verification says that the bounds are not kept)
    verified: list[OptimizationResult] = []
    for kept in (True, False):
        for status in (Status.OPTIMAL, Status.ACCEPTABLE):
            verified = verified or [r for r in passes if r.verification is not None and r.verification.passed
                                    and r.status == status and (_kept(r) or not kept)]
    if verified and not _kept(verified[0]):  # the bounds kept by none: the pass that keeps them best
        best = min(verified, key=lambda r: r.verification.bounds["max_scaled_violation"])
    elif verified:
        best = min(verified, key=lambda r: _minimised(optimization, r))
    else:  # the smallest deviation, of the passes not rejected as another local optimum
        kept = [r for r, e in zip(passes, history) if "rejected" not in e]
        solved = [r for r in kept if r.verification is not None]
        best = min(solved, key=lambda r: r.verification.max_scaled_deviation) if solved else passes[-1]
    k = passes.index(best) + 1
    history[k - 1]["returned"] = True  # the pass the result is (the last may be an objective check, or rejected)
    if best is not passes[-1]:
        _log.warning("mesh refinement of %s: returning pass %d (%s, objective %s) rather than the last (%s)", name, k,
                     "verified" if verified else "the smallest deviation", best.objective, passes[-1].status)
    result = copy.copy(best)
    result.refinement = history
    result.refinement_stop = f"{stop}; returned pass {k} of {len(passes)}"
    _log.info("mesh refinement of %s ended: %s", name, result.refinement_stop)
    result.solve_time = float(sum(e["solve_time"] or 0.0 for e in history))  # every pass's solve, not the returned one's alone
    if result.verification is not None:  # and every pass's verification
        result.verification = copy.copy(result.verification)
        result.verification.time_s = float(sum(e.get("verification_time", 0.0) for e in history))
        result.verification.cpu_s = float(sum(e.get("verification_cpu_time", 0.0) for e in history))
    if not verified:
        # the pass's own "likely remedy" (refinement, more elements) is spent: the limit that stopped it, and by how much
        remedy = refinement_remedy(history, stop, tol, budget, max_passes, max_elements or MAX_ELEMENTS)
        head = str(result.message).split("; likely remedy: ")[0]
        result.message = f"{head}; mesh refinement stopped at {stop} before a pass verified; to finish: {remedy}"
        if result.verification is not None:
            result.verification.remedy = remedy
    elif not _kept(result):  # said in the verification (summary.json verification.bounds), not only the warnings
        result.verification.bounds = {**result.verification.bounds, "remedy": bound_remedy(
            history, stop, result.verification.bounds, budget, max_passes, max_elements or MAX_ELEMENTS)}
    return bounds_verdict(result)  # a bound exceeded between the points beyond the tolerance: check_failed, saying which


def _objective_gain(optimization: Optimization, before: OptimizationResult, after: OptimizationResult) -> float:
    """The relative improvement of the minimised objective from ``before`` to ``after`` (negative: worse; -inf: none)."""
    a, b = _minimised(optimization, before), _minimised(optimization, after)
    if not (np.isfinite(a) and np.isfinite(b)):
        return float("-inf")
    return (a - b) / max(abs(a), 1e-12)


def _objective_unchecked(optimization: Optimization, result: OptimizationResult, objective_tol: float, elements: int,
                         max_elements: int, passes_left: int, cpu_left: float, cpu: float) -> str | None:
    """None where a verified pass with nothing left to split is to be followed by its objective's check on its mesh
    halved; else why not ("" where no check applies: not verified and optimal, no objective, the check off)."""
    v = result.verification
    if (objective_tol <= 0 or v is None or not v.passed or not _kept(result) or result.status != Status.OPTIMAL
            or not np.isfinite(_minimised(optimization, result))):
        return ""
    why = ("the element limit leaves no room for it" if 2 * elements > max_elements else
           "the pass limit leaves no pass for it" if passes_left < 1 else
           "the CPU budget leaves no room for it" if 2 * cpu > cpu_left else None)
    return None if why is None else f"its objective not checked on the mesh halved: {why}"


def bound_remedy(history: list[dict], stop: str, bounds: dict, budget: float, max_passes: int, max_elements: int) -> str:
    """What to do when mesh refinement stopped before a pass kept the state bounds between the points.

    A larger limit (the one that stopped it) where the passes' between-node excess still falls; where it has
    stalled (the least excess of the last :data:`STALL_PASSES` passes above half that of the passes before
    them: the held-out drives' current at its junction with its bound arc, 0.017-0.023 scaled after 16 to 40
    passes, issue 49), more passes do not help, and the remedy is a margin on the declared bound.

    Parameters
    ----------
    history : list of dict
        The passes' entries (``max_bound_violation``: the scaled between-node excess of a verified pass).
    stop : str
        Why refinement stopped (``"the element limit (...)"``, ``"the pass limit (...)"``, ...).
    bounds : dict
        The returned pass's ``verification.bounds`` (``variable``, ``value``, ``bound``, ``max_scaled_violation``).
    budget : float
        The CPU budget [s].
    max_passes, max_elements : int
        The pass and element limits.

    Returns
    -------
    str
        The remedy, one sentence.
    """
    head = f"mesh refinement stopped at {stop} before a pass kept the bound between the points: "
    excess = [float(e["max_bound_violation"]) for e in history if e.get("max_bound_violation") is not None]
    last, before = excess[-STALL_PASSES:], excess[-2 * STALL_PASSES:-STALL_PASSES]
    if len(before) == STALL_PASSES and min(last) > 0.5 * min(before):
        name, value, bound = bounds.get("variable"), bounds.get("value"), bounds.get("bound")
        margin = (f" (e.g. {name!r} to {2 * bound - value:.6g} instead of {bound:.6g})"
                  if isinstance(value, (int, float)) and isinstance(bound, (int, float)) else "")
        return (head + f"the excess has stalled ({min(last):.3g} scaled over the last {STALL_PASSES} passes against "
                f"{min(before):.3g} over the {STALL_PASSES} before), so more passes or elements will not settle it; "
                f"declare the bound with a margin of the excess{margin}, or accept the plan, which keeps it at its points")
    if stop.startswith("the element limit"):
        return head + f"a larger max_elements in [transcription] (now {max_elements})"
    return head + f"a larger max_cpu_s or max_passes in [transcription] (now {budget:g} CPU-s, {max_passes} passes)"


def _kept(result: OptimizationResult) -> bool:
    """The verifying simulation keeps the state bounds between the nodes within the tolerance (or none are checked)."""
    v = result.verification
    return v is not None and bool(v.bounds.get("within_tolerance", True))


#: Default relative change of the objective below which a verified pass's objective has converged with its mesh
#: (``defaults["ocp.refine_objective_tolerance"]``; :func:`solve_refined`'s ``objective_tolerance``).
OBJECTIVE_TOLERANCE = defaults["ocp.refine_objective_tolerance"]

#: CPU limit [s] of the continuation of a pass that IPOPT stopped at its acceptable level.
POLISH_CPU_S = 20.0


#: A pass whose minimised objective exceeds that of an earlier pass feasible by simulation (its end
#: reached, its state bounds kept between the nodes) by more than this fraction of it has left for another local optimum.
#: Relative, and above the discretisation error of the coarse meshes it compares (a servo with a dead zone on its
#: command: its anchor, 84 elements and deviating 4 % from its simulation, rejected two finer passes 0.3 % and 0.4 %
#: slower under the former 0.002 (absolute below 1), and the refinement ended unverified; at 1 % it verifies), and below
#: the flexible-joint drive's other optima (2-3 % slower).
WORSE = 1e-2
#: A pass whose simulation ends within this scaled deviation of its final state is no spurious
#: minimum: if it keeps its state bounds between the nodes too, later passes, which change it by
#: the discretisation error, may not be worse than it by more than :data:`WORSE` (the flexible-joint drive's first pass: 0.063, its current off by 2 A
#: inside elements; the hanging chain's spurious minimum misses its end).
ANCHOR_END = SPURIOUS_DEVIATION
#: ... and whose states deviate from its simulation by at most this scaled deviation (above it, its objective, computed
#: on its own states, is not that of the motion its inputs make).
ANCHOR_DEVIATION = SPURIOUS_DEVIATION


@dataclasses.dataclass
class _Mesh:
    """What :func:`_pass_entry` reads of a transcription."""

    elements: int
    points: int
