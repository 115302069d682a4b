"""Optimal control of a user's model as one declaration: the problem, its method and solver settings.

:class:`OptimalControl` (what the ``optimal_control`` problem kind loads) holds the
:class:`~gtmodel.modeling.Optimization` declared on a user's model, the collocation
transcription (:class:`~gtmodel.modeling.ocp.methods.Collocation` or
:class:`~gtmodel.modeling.ocp.methods.MultipleShooting`, re-exported here) and IPOPT's settings
(:class:`~gtmodel.modeling.ocp.methods.SolverSettings`); :meth:`OptimalControl.solve`
transcribes and solves it, passing the verification settings to the transcription (the
declared :class:`~gtmodel.modeling.Optimization` is not changed by a solve).
"""

from __future__ import annotations

import contextlib
import logging
import time
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from gtmodel._docstrings import SHARED_DOCS, fill_doc
from gtmodel._timing import add_phase, merge_phases, timed
from gtmodel.modeling import CollocationTranscription, Model, Optimization, OptimizationResult
from gtmodel.modeling.ocp.estimation import estimate_statistics
from gtmodel.modeling.ocp.budget import IPOPT_CPU_SHARE
from gtmodel.modeling.ocp.shooting import ShootingTranscription
from gtmodel.modeling.ocp.methods import Collocation, MultipleShooting, Refinement, SolverSettings
from gtmodel.modeling.ocp.coarse_start import linear_quadratic, solve_from_coarse
from gtmodel.modeling.ocp.continuation import (Continuation, continue_smoothing, narrowed_steps, record_final, smoothing_widths,
                                               solved_declared)
from gtmodel.modeling.ocp.diagnostics import without_inputs
from gtmodel.modeling.ocp.refinement import solve_refined
from gtmodel.modeling.ocp.refinement_guess import solved_cold
from gtmodel.modeling.ocp.verification_bounds import REFINING
from gtmodel.errors import InputError
from gtmodel.status import Status

_log = logging.getLogger("gtmodel")

__all__ = ["OptimalControl", "MultipleShooting", "COARSE_START_MIN_ELEMENTS", "COARSE_START_ELEMENTS"]

#: From this many elements a collocation solve without a given guess starts from a solve of
#: the same problem on :data:`COARSE_START_ELEMENTS` elements, interpolated onto the mesh
#: (what a user does by hand: a fine mesh from the declared guess alone spends its iterations
#: where a coarse one spends them at a fraction of the cost). Orbit raising of Bryson and Ho
#: (``problems/benchmarks/orbit_raising.toml`` with the redundant bounds ``|u1|, |u2| <= 1``
#: beside ``u1^2 + u2^2 = 1``, a degenerate NLP), 400 elements: 640 iterations and 29 s from
#: the linear guess, 33 iterations and 1.1 s (plus 2.8 s on 50 elements) from the coarse
#: solve (``benchmarks/bench_large_mesh.py``). A coarse solve that fails is not used.
COARSE_START_MIN_ELEMENTS = 200  # not for a linear-quadratic problem (coarse_start.linear_quadratic)
COARSE_START_ELEMENTS = 50


@contextlib.contextmanager
def _quiet_if_refined(refined: bool) -> Iterator[None]:
    """A single solve that refinement will start from if it fails logs its failed checks as a pass does (INFO).

    Its "likely remedy: refine = true" as a warning told a user whose run then refined by itself, and ended
    ``optimal``, that it had failed (issue 67: 16 lines of stderr for a verified first solve); the stop of the
    refinement, or its result, says what came of it.
    """
    token = REFINING.set(True) if refined else None
    try:
        yield
    finally:
        if token is not None:
            REFINING.reset(token)


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
    method : Collocation or MultipleShooting
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
    refinement : Refinement
        Verification tolerance and mesh refinement.
    benchmark : dict or None
        A published optimum to compare with: ``{"source", "published", "quantity",
        "sign"}`` (``objective = sign * published``).
    estimation : dict or None
        After :meth:`solve` of a problem with data fits: the residual statistics and the
        estimates with standard deviations
        (:func:`gtmodel.modeling.ocp.estimation.estimate_statistics`).
    variables : tuple of str
        The variables plotted in ``variables.png`` (``[output] variables``).
    continuation : Continuation
        The continuation over the model's smoothing widths
        (:mod:`gtmodel.modeling.ocp.continuation`; applied when the model declares any).
    """

    name: str
    model_file: Path
    class_name: str
    optimization: Optimization
    method: Collocation | MultipleShooting
    solver: SolverSettings
    nominal: dict[str, float] = field(default_factory=dict)
    objective: str = ""
    sense: str = "minimize"
    constraints: tuple[str, ...] = ()
    named_parameters: dict[str, float] = field(default_factory=dict)
    bounds: dict[str, tuple[float, float]] = field(default_factory=dict)
    refinement: Refinement = field(default_factory=Refinement)
    benchmark: dict[str, Any] | None = None
    estimation: dict[str, Any] | None = None
    variables: tuple[str, ...] = ()
    continuation: Continuation = field(default_factory=Continuation)

    @property
    def model(self) -> Model:
        """The user's model (reduced to index 1 if it was written of higher index)."""
        return self.optimization.model

    @fill_doc(**SHARED_DOCS)
    def solve(self, *, verbose: bool = False, previous: Any = None, warm_start: bool = False) -> OptimizationResult:
        """Transcribe (collocation or multiple shooting) and solve with IPOPT (refining a collocation mesh if :attr:`refinement` says so).

        Parameters
        ----------
        {solve_args}

        Returns
        -------
        OptimizationResult
        """
        d = self
        check = d.refinement.verification if d.refinement.verify else False  # passed down, never set on the declaration
        options = {"max_iter": d.solver.max_iter, "tol": d.solver.tol}
        if isinstance(d.method, MultipleShooting):
            return self._shot(check, options, verbose, previous if warm_start else None)
        kwargs = {"verbose": verbose, "solver_options": options, "nominal": d.nominal, "eliminate_algebraics": d.method.eliminate_algebraics,
                  "solver": d.solver.name, "compile": d.solver.jit}
        single = {**kwargs, "verify": check}
        guess = previous if warm_start and isinstance(previous, OptimizationResult) and previous.collocation is not None else None
        if d.continuation.enabled and smoothing_widths(d.optimization):
            return self._estimated_final(self._continued(kwargs, check, guess), kwargs)
        if d.refinement.refine:
            phases = {}
            with timed(phases, "refinement"):  # every pass: its build, guess, solve and verification
                result = solve_refined(
                    d.optimization, elements=d.method.elements, points=d.method.points, scheme=d.method.scheme,
                    max_elements=None if d.refinement.max_elements is None else max(d.refinement.max_elements, d.method.elements), max_passes=d.refinement.max_passes,
                    initial_guess=guess, max_cpu_s=d.refinement.max_cpu_s, verification=d.refinement.verification,
                    objective_tolerance=d.refinement.objective_tolerance, regularization=d.refinement.regularization, **kwargs,
                )
            result.timing = phases
            return self._estimated_final(result, kwargs)
        tr = CollocationTranscription(d.optimization, elements=d.method.elements, points=d.method.points, scheme=d.method.scheme, **single)
        coarse = (lambda: self.coarse_solve(kwargs)) if (guess is None and d.method.elements >= COARSE_START_MIN_ELEMENTS
                                                         and not linear_quadratic(d.optimization, tr.dae)) else None
        with _quiet_if_refined(d.refinement.on_failure and bool(check) and not d.optimization.data_fits):
            result = solve_from_coarse(tr, coarse, initial_guess=guess)
        bounds = getattr(result.verification, "bounds", None) or {}
        # a state bound exceeded between the nodes beyond the tolerance fails as the deviations do: refinement splits there
        exceeded = result.status in (Status.OPTIMAL, Status.ACCEPTABLE) and not bounds.get("within_tolerance", True)
        if d.refinement.on_failure and check and (result.status == Status.CHECK_FAILED or exceeded) and not d.optimization.data_fits:
            # the verification failed: refined from this solution within the budget (refine_on_failure)
            _log.warning("%s: the verification %s; refining the mesh from this solution (refine_on_failure; "
                         "at most %d passes, %s CPU-s)", d.optimization.model.name,
                         "failed" if result.status == Status.CHECK_FAILED else "found a state bound exceeded between the nodes",
                         d.refinement.max_passes, "the default" if d.refinement.max_cpu_s is None else f"{d.refinement.max_cpu_s:g}")
            phases = {k: dict(v) for k, v in result.timing.items()}  # the single solve's, then every pass's
            with timed(phases, "refinement"):
                result = self._refined_from(result, kwargs)
            result.timing = phases
        return self._estimated(tr, result)

    def _estimated_final(self, result: OptimizationResult, kwargs: dict[str, Any]) -> OptimizationResult:
        """A data fit's statistics on the mesh of a refined result (its transcription rebuilt, not solved)."""
        self.estimation = None
        col = result.collocation
        if not self.optimization.data_fits or col is None:
            return result
        # refinement only splits elements, so data times that were mesh points stay mesh points
        final = CollocationTranscription(self.optimization, elements=col.elements, points=col.points, scheme=col.scheme,
                                         mesh=col.fractions, **kwargs)
        return self._estimated(final, result)

    def _shot(self, check: Any, options: dict[str, Any], verbose: bool, previous: Any) -> OptimizationResult:
        """The multiple-shooting solve: continued over the smoothing widths where the model declares any.

        A declared ``max_cpu_s`` (:attr:`Refinement.max_cpu_s`) bounds the whole of it, the continuation's steps
        included: each solve gets what is left as IPOPT's ``max_cpu_time``, and a solve it stopped says so, naming
        the knob. Undeclared, IPOPT's ``max_iter`` alone bounds each solve (shooting is not refined).
        """
        d = self
        if d.solver.name != "ipopt":  # the solver named is the one that runs, or the call says why not
            raise InputError(f"solver {d.solver.name!r}: multiple shooting is solved by IPOPT only (its NLP has no stage "
                             "structure for fatrop); solver = \"ipopt\", or method = \"collocation\" for fatrop")
        m, budget, cpu0 = d.method, d.refinement.max_cpu_s, time.process_time()
        phases: dict[str, dict[str, float]] = {}
        with timed(phases, "build"):
            shooting = ShootingTranscription(d.optimization, intervals=m.intervals, controls=m.controls, integrator=m.integrator,
                                             steps=m.steps, verbose=verbose, solver_options=options, verify=check)
        guess = previous if isinstance(previous, OptimizationResult) and previous.collocation is not None else None

        def solve(parameters: dict[str, float] | None, begin: OptimizationResult | None) -> OptimizationResult:
            if budget is not None:  # IPOPT's share of what is left, at least a token (IPOPT then stops at once): IPOPT
                # counts less than the process (budget.ipopt_left; drive0_03 by shooting, 300 CPU-s declared: its
                # declared solve given the 172 s left took 215, the run 343)
                left = budget - (time.process_time() - cpu0)
                shooting.set_solver_options({"max_cpu_time": max(IPOPT_CPU_SHARE * left, 1e-2)})
            return shooting.solve(parameters=parameters, initial_guess=begin if begin is not None else guess)

        start, record = None, {}
        if d.continuation.enabled and smoothing_widths(d.optimization):
            # the smoothing widths continued as on the collocation path, each step started from the last's primal
            # point (a servo with a torque limiter, backlash and friction: infeasible from the declared guess)
            with timed(phases, "continuation"):
                shooting.verify = False  # the intermediate problems are not the user's: solved, not verified
                try:
                    start, record = continue_smoothing(d.optimization, solve, d.continuation)
                finally:
                    shooting.verify = bool(check)
        with timed(phases, "solve"):  # its guess and verification included, the verification moved out below
            result = solve(None, start)
            if not solved_declared(result) and start is not None:  # the last step too long: steps inserted before it

                def step(parameters: dict[str, float] | None, begin: OptimizationResult | None) -> OptimizationResult:
                    shooting.verify = False
                    try:
                        return solve(parameters, begin)
                    finally:
                        shooting.verify = bool(check)

                start, result = narrowed_steps(d.optimization, step, lambda begin: solve(None, begin), start, record, result)
        result.continuation = record_final(record, start, result)
        ver = result.verification
        if getattr(ver, "cpu_s", None) is not None:
            add_phase(phases, "solve", -ver.time_s, -ver.cpu_s)
            add_phase(phases, "verification", ver.time_s, ver.cpu_s)
        result.timing = phases
        if result.dae is not None:
            result.message = without_inputs(d.optimization, result.dae, result.message)
        if budget is not None and str(result.message).startswith("Maximum_CpuTime_Exceeded"):
            spent = time.process_time() - cpu0
            head, _, rest = str(result.message).partition(";")  # the knob that stopped it first, then any culprit
            result.message = (f"{head}; the CPU budget max_cpu_s = {budget:g} in [transcription] is spent ({spent:.3g} "
                              f"CPU-s, {phases.get('continuation', {}).get('cpu_s', 0.0):.3g} of them in the continuation "
                              "over the smoothing widths): raise max_cpu_s, or solve by collocation" + (f";{rest}" if rest else ""))
        return self._estimated(shooting, result)

    def _continued(self, kwargs: dict[str, Any], check: Any, guess: OptimizationResult | None) -> OptimizationResult:
        """The collocation solve of a model with smoothing widths: continued over them, then refined as declared.

        The steps (:func:`~gtmodel.modeling.ocp.continuation.continue_smoothing`) on the declared mesh, one NLP whose
        parameters are the widths, each solve warm from the last (its multipliers); then the declared widths from
        the last step, verified (solved again cold from the last step's primal point where IPOPT ends it warm without a
        solution: ``continuation["cold_retry"]``); then mesh refinement from it where ``refine`` or ``refine_on_failure`` asks.
        """
        d = self
        phases: dict[str, dict[str, float]] = {}
        with timed(phases, "build"):
            tr = CollocationTranscription(d.optimization, elements=d.method.elements, points=d.method.points,
                                          scheme=d.method.scheme, **kwargs, verify=check)
        verify = tr.verify

        def solve(parameters: dict[str, float] | None, start: OptimizationResult | None) -> OptimizationResult:
            warm = start is not None and start.lam_g is not None and start.transcription_key == tr.key
            return tr.solve(parameters=parameters, initial_guess=start if start is not None else guess, warm_start=warm)

        with timed(phases, "continuation"):
            tr.verify = False  # the intermediate problems are not the user's: solved, not verified
            try:
                start, record = continue_smoothing(d.optimization, solve, d.continuation)
            finally:
                tr.verify = verify
        def declared(begin: OptimizationResult | None) -> OptimizationResult:
            out = solve(None, begin)
            if out.verification is None and begin is not None and begin.lam_g is not None:
                # warm from the last step (its multipliers, a small barrier) IPOPT found no solution at the declared
                # widths (drive2_12: Restoration_Failed after 1,151 iterations, the last iterate feasible to 7e-8):
                # solved again from the same primal point with IPOPT's own barrier and bound push (no budget here:
                # IPOPT's default max_cpu_time)
                out = solved_cold(tr, out, begin, None, 1e20)
            return out

        def step(parameters: dict[str, float] | None, begin: OptimizationResult | None) -> OptimizationResult:
            tr.verify = False
            try:
                return solve(parameters, begin)
            finally:
                tr.verify = verify

        wall0, cpu0 = time.perf_counter(), time.process_time()
        with _quiet_if_refined(d.refinement.on_failure and bool(check) and not d.optimization.data_fits):
            result = declared(start)
            if not solved_declared(result) and start is not None:  # the last step too long: steps inserted before it
                # (their CPU in the record's steps; the declared solve's in the phases below, from its result)
                start, result = narrowed_steps(d.optimization, step, declared, start, record, result)
            retried = result.stats.get("cold_retry")
        # the solves that failed on the way to the declared one (a warm attempt, inserted steps) are the continuation's;
        # the declared solve's own phases follow from its result
        own = [v for k, v in (result.timing or {}).items() if k != "total"]
        failed_wall = time.perf_counter() - wall0 - sum(v.get("wall_s", 0.0) for v in own)
        failed_cpu = time.process_time() - cpu0 - sum(v.get("cpu_s", 0.0) for v in own)
        if failed_cpu > 1e-3:
            add_phase(phases, "continuation", max(failed_wall, 0.0), failed_cpu)
        merge_phases(phases, result.timing)
        result.continuation = record_final(record, start, result)
        if retried is not None:
            result.continuation["cold_retry"] = retried
        failed = result.status == Status.CHECK_FAILED or (result.status in (Status.OPTIMAL, Status.ACCEPTABLE)
                                                          and not (getattr(result.verification, "bounds", None) or {}).get("within_tolerance", True))
        if check and result.verification is not None and (d.refinement.refine or (d.refinement.on_failure and failed
                                                                                   and not d.optimization.data_fits)):
            if not d.refinement.refine:
                _log.info("%s: the verification at the declared smoothing failed; refining the mesh from this solution "
                          "(refine_on_failure)", d.optimization.model.name)
            continued = result.continuation
            with timed(phases, "refinement"):
                result = self._refined_from(result, kwargs)
            result.continuation = continued
        result.timing = phases
        return result

    def _refined_from(self, start: OptimizationResult, kwargs: dict[str, Any]) -> OptimizationResult:
        """Mesh refinement from a verified solve at hand (``refine_on_failure``, or after a continuation)."""
        d = self
        return solve_refined(
            d.optimization, elements=d.method.elements, points=d.method.points, scheme=d.method.scheme,
            max_elements=None if d.refinement.max_elements is None else max(d.refinement.max_elements, d.method.elements),
            max_passes=d.refinement.max_passes, max_cpu_s=d.refinement.max_cpu_s, start=start,
            verification=d.refinement.verification, objective_tolerance=d.refinement.objective_tolerance,
            regularization=d.refinement.regularization, **kwargs,
        )

    def coarse_solve(self, kwargs: dict[str, Any]) -> OptimizationResult:
        """The problem solved on :data:`COARSE_START_ELEMENTS` elements (unverified), the start of a fine mesh.

        Parameters
        ----------
        kwargs : dict
            Further arguments of :class:`~gtmodel.modeling.CollocationTranscription`
            (``verbose``, ``solver_options``, ``nominal``).

        Returns
        -------
        OptimizationResult
            Its result (any status; the caller uses it only when optimal or acceptable).
        """
        m = self.method
        coarse = CollocationTranscription(self.optimization, elements=min(COARSE_START_ELEMENTS, m.elements), points=m.points,
                                          scheme=m.scheme, verify=False, **kwargs)
        return coarse.solve()

    def _estimated(self, transcription: Any, result: OptimizationResult) -> OptimizationResult:
        """Keep the statistics of a data fit (:attr:`estimation`) of a solved problem."""
        self.estimation = None
        if self.optimization.data_fits and result.status in ("optimal", "acceptable"):
            with timed(result.timing, "estimation"):
                self.estimation = estimate_statistics(transcription, result)
        return result
