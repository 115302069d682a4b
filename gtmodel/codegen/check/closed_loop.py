"""A loop controller's generated C checked in closed loop (``gtmodel codegen mpc | tracking ... --check``).

:func:`~gtmodel.codegen.loop_step.build_step` generates a loop step and compiles it;
:func:`compiled_step` loads it through the library's one ctypes owner
(:meth:`gtmodel.codegen.build.CompiledLibrary.loop_runner`: ``<prefix>_init`` /
``<prefix>_step`` with the caller's memory, in the library's real type); :func:`closed_loop_check`
runs it against the plant of a loop-controller file's ``[check]`` (a
:class:`gtmodel.problems.loop_file.LoopSetup`, used through its attributes: this layer is
below the problem files; :func:`gtmodel.estimation.closed_loop.controller_loop.run_controller_loop`),
beside the feedforward alone (``u*`` of the reference, saturated) on the same plant, noise and
disturbance. The same check serves the MPC (:mod:`gtmodel.codegen.check.mpc`) and the
tracking controller, in ``double`` and in ``float``: the criteria (plant diverged, input and
declared bounds within :data:`~gtmodel.control.bounds.EXCESS_TOLERANCE`, failed steps, RMS
ratio to the feedforward, step time) are about the loop, not about rounding, and hold as
they are for a float32 step (its state rounded once, relative 6e-8, far below the loop's
errors); the summary states the real type. Its :attr:`LoopCheck.status` is the shared
:class:`~gtmodel.status.Status`.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from gtmodel.codegen.build import CompiledLibrary, load_library
from gtmodel.codegen.declarations import STATUS_CODES
from gtmodel.codegen.writer import GeneratedCode
from gtmodel.codegen.loop_step import build_step
from gtmodel.codegen.check.loop_causes import excess_predictions, noise_gain, noise_gain_text, prediction_text
from gtmodel.control.bounds import EXCESS_TOLERANCE, BoundExcess, bound_report
from gtmodel.control.mpc_memory import ESTIMATES, memory_estimates
from gtmodel.control.reference import period_index
from gtmodel.estimation.closed_loop.controller_loop import LoopSummary, run_controller_loop
from gtmodel.status import Status

#: A loop-controller file's setup (:class:`gtmodel.problems.loop_file.LoopSetup`, :class:`~gtmodel.problems.mpc_file.MPCSetup`),
#: used through its attributes (``controller``, ``plant_step``, ``plant_x0``, ``plant_p``, ``t``, ``x_ref``, ``u_ref``, ``loop``,
#: ``bounds``, ``names``, ``outputs``, ``max_ratio``, ``max_step_time``, ``notes``).
LoopSetup = Any

__all__ = ["AUTHORITY_WARNING", "STATE_AUTHORITY_WARNING", "reference_states_at_bounds", "STATUS_NAMES", "PROGRESS_INTERVAL_S", "LoopCheck", "plant_bounds", "reference_at_bounds", "build_step", "compiled_step", "heap_stats", "closed_loop_check", "feedforward_law"]

#: Fraction of the reference's samples at an input bound above which the check's summary notes the
#: feedback's lack of authority (a minimum-time plan at the bounds: bang-bang).
AUTHORITY_WARNING = 0.2
#: Fraction of the reference's samples at a declared state bound above which the summary notes it: a plan riding
#: its current limit leaves the feedback no room on that state (a held-out drive's MPC at 0.91 of the feedforward,
#: 0.021 with the limit planned 20 % lower; issue 49).
STATE_AUTHORITY_WARNING = 0.05
#: Status names by code.
STATUS_NAMES = {code: name for name, (code, _) in STATUS_CODES.items()}
#: What to change when a declared bound is exceeded between the samples, by controller (:attr:`LoopCheck.label`).
BETWEEN_REMEDY = {
    "mpc": ("the MPC's rows act at its prediction's substeps with [mpc] substeps as fine as the plant's and constraint_substeps = "
            "true; where they do, the plant needs more than the bound to follow the plan: plan with margin below it ([reference] overrides)"),
    "state_limits": ("the controller holds the declared state bounds on its linearised rows at its substeps, backed off by its "
                     "measured one-period prediction error, which it measures only at the samples; a larger error inside the period "
                     "(the model's error on this plant) is beyond it: plan with margin below the bound ([reference] overrides)"),
    "": "the controller has no constraint rows: plan with margin below the bound ([reference] overrides) or weight the variable more",
}

#: An input step larger than this fraction of the input's range counts towards :attr:`LoopCheck.alternation`.
SWING = 0.05
#: :attr:`LoopCheck.alternation` above which a failure says the loop cycles at half the sampling frequency.
ALTERNATION_NOTE = 0.2
#: A declared bound the controller came within this fraction of (relative to its size) counts as binding in the ratio's failure.
BINDING = 0.02
#: Seconds between the closed loop's progress lines (``progress`` of :func:`closed_loop_check`).
PROGRESS_INTERVAL_S = 2.0


@dataclass
class LoopCheck:
    """Closed-loop figures of a generated loop controller.

    Parameters
    ----------
    closed : LoopSummary
        The generated C step in the loop.
    feedforward : LoopSummary
        The feedforward alone on the same plant.
    memory_bytes : int
        ``sizeof(<prefix>_memory)`` (the caller's static memory).
    work_bytes : int
        Stack work arrays of one step (CasADi's ``sz_arg``, ``sz_res`` pointers, ``sz_iw``
        integers, ``sz_w`` reals).
    label : str
        What the controller is, for the summary (e.g. ``"MPC"``).
    state_limits : bool
        Whether the controller (a tracking controller) holds the declared state bounds itself
        (:mod:`gtmodel.control.state_limits`): a failure's remedy says so (:data:`BETWEEN_REMEDY`).
    max_ratio : float
        The largest RMS ratio to the feedforward that passes (exclusive; default 1).
    step_budget_s : float
        The largest 99th-percentile step time that passes [s] (default no limit).
    heap : tuple of int or None
        ``(peak bytes, heap calls, arena bytes)`` of the QP solver's arena (:func:`heap_stats`);
        None: the step has none (no allocating solver).
    clock : str
        Name of the clock of the step times (``"thread_time"``: thread CPU time,
        ``"perf_counter"``: wall time).
    reference_at_bounds : float
        Fraction of the reference's samples whose feedforward input is at an input bound
        (:func:`reference_at_bounds`); above :data:`AUTHORITY_WARNING` the summary says that
        the feedback has little authority left.
    bounds : list of BoundExcess
        Every declared bound on the plant under the controller (states, inputs, algebraic
        variables and outputs; :func:`~gtmodel.control.bounds.bound_report`):
        one beyond :data:`~gtmodel.control.bounds.EXCESS_TOLERANCE` fails the check.
    bounds_feedforward : list of BoundExcess
        The same under the feedforward alone (for comparison; not a failure).
    bounds_between : list of BoundExcess
        The declared state bounds under the controller counted between the samples, at the plant step's
        substeps (:func:`plant_bounds` with ``between``): judged as :attr:`bounds` (an MPC's rows act at its
        prediction's substeps too: ``constraint_substeps``).
    notes : list of str
        What the summary and the verdict repeat (an unverified reference accepted, unknown bounds).
    real : str
        The step's real type (``"double"`` or ``"float"``), for the summary.
    states_at_bounds : dict of str to float
        Per declared state bound the reference rides, the fraction of its samples there
        (:func:`reference_states_at_bounds`); above :data:`STATE_AUTHORITY_WARNING` the summary notes it.
    estimates : list of dict
        The MPC's estimator read from the step's memory along the run (:func:`~gtmodel.control.mpc_memory.memory_estimates`:
        the input disturbance it compensated, the back-off's error envelope); printed, and named where the ratio fails.
    predictions : list of dict
        Per state bound beyond the tolerance at the samples, what the controller's own model predicted there
        (:func:`~gtmodel.codegen.check.loop_causes.excess_predictions`): printed, and named in that bound's failure.
    noise_gain : dict or None
        A tracking law's largest input response to a one-sigma state error
        (:func:`~gtmodel.codegen.check.loop_causes.noise_gain`): named where the check fails, when above its note.
    """

    closed: LoopSummary
    feedforward: LoopSummary
    memory_bytes: int
    work_bytes: int
    label: str = "controller"
    state_limits: bool = False
    max_ratio: float = 1.0
    step_budget_s: float = float("inf")
    heap: tuple[int, int, int] | None = None
    clock: str = "perf_counter"
    reference_at_bounds: float = 0.0
    bounds: list[BoundExcess] = field(default_factory=list)
    bounds_feedforward: list[BoundExcess] = field(default_factory=list)
    bounds_between: list[BoundExcess] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)
    real: str = "double"
    states_at_bounds: dict[str, float] = field(default_factory=dict)
    estimates: list[dict[str, Any]] = field(default_factory=list)
    predictions: list[dict[str, Any]] = field(default_factory=list)
    noise_gain: dict[str, Any] | None = None

    @property
    def status(self) -> Status:
        """The shared status: ``converged`` when the closed loop passes, ``check_failed`` when it fails (:meth:`failures`)."""
        return Status.CHECK_FAILED if self.failures() else Status.CONVERGED

    @property
    def ratio_to_feedforward(self) -> float:
        """RMS tracking error of the controller over that of the feedforward alone."""
        return self.closed.rms_error / self.feedforward.rms_error

    @property
    def plant_diverged(self) -> bool:
        """Whether the plant diverged under the controller or under the feedforward (then the ratio means nothing)."""
        return self.closed.diverged or self.feedforward.diverged

    def failures(self) -> list[str]:
        """Why the closed loop fails the check (empty: it passes): a diverged plant, input bound violations,
        a declared bound exceeded beyond the tolerance at the samples or between them, failed steps, an RMS error not below :attr:`max_ratio` times the feedforward's, a
        99th-percentile step time above :attr:`step_budget_s`, or a QP solver's allocation
        that went to the heap (:attr:`heap`).

        Returns
        -------
        list of str
        """
        diverged = self.plant_diverged
        return [why for why, bad in (
            ("the plant diverged (a stiff model's explicit plant step? [check] plant_method = \"radau2\"; the RMS errors "
             "of a runaway run say nothing)", diverged),
            (f"{self.closed.bound_violations} input bound violations", self.closed.bound_violations > 0),
            *[(f"{b.name} beyond its bound by {b.excess:.4g} ({100 * b.relative:.3g} % > {100 * EXCESS_TOLERANCE:g} %)" + self._predicted(b.name)
               + self._cycling() + self._gain(), True)
              for b in self.bounds if b.beyond_tolerance and not diverged],
            *[(f"{b.name} beyond its bound between the samples by {b.excess:.4g} ({100 * b.relative:.3g} % > {100 * EXCESS_TOLERANCE:g} %; "
               f"{BETWEEN_REMEDY.get(self.label.lower(), BETWEEN_REMEDY['state_limits' if self.state_limits else ''])})"
               + self._cycling() + self._gain(), True)
              for b in self.bounds_between if b.beyond_tolerance and not diverged],
            (f"{self.failed_steps} failed steps", self.failed_steps > 0),
            (f"RMS ratio to the feedforward {self.ratio_to_feedforward:.4g} not below {self.max_ratio:g} ([check] max_ratio)"
             + self._binding() + self._estimated() + self._cycling() + self._gain(), not diverged and not self.ratio_to_feedforward < self.max_ratio),
            (f"99th-percentile step time {self.step_p99_s * 1e6:.1f} us above the budget {self.step_budget_s * 1e6:.1f} us "
             "([check] max_step_time, default the period)", not self.step_p99_s <= self.step_budget_s),
            (f"{self.heap[1] if self.heap else 0} allocations of the QP solver on the heap (its arena of "
             f"{self.heap[2] if self.heap else 0} bytes too small)", bool(self.heap and self.heap[1] > 0))) if bad]

    @property
    def alternation(self) -> float:
        """Fraction of the periods whose applied input turns back by more than :data:`SWING` of its range each period
        (``(u_k - u_{k-1}) (u_{k+1} - u_k) < 0`` with both steps that large, in any input): above
        :data:`ALTERNATION_NOTE` the summary and a failure say the loop cycles at half the sampling frequency."""
        u = np.asarray(self.closed.u, dtype=float)
        if u.shape[0] < 3:
            return 0.0
        lb, ub = np.asarray(self.closed.u_lb, dtype=float), np.asarray(self.closed.u_ub, dtype=float)
        span = np.where(np.isfinite(ub - lb), ub - lb, np.ptp(u, axis=0) + 1e-300)
        du = np.diff(u, axis=0)
        big = np.abs(du) > SWING * span
        turns = (du[:-1] * du[1:] < 0) & big[:-1] & big[1:]
        return float(np.mean(np.any(turns, axis=1)))

    def _cycling(self) -> str:
        """Why a bound or the ratio failed when the loop cycles at half the sampling frequency (empty otherwise)."""
        a = self.alternation
        return (f"; the applied input turns back every period in {100 * a:.0f} % of the periods: a limit cycle at half the "
                "sampling frequency (a mode the period and the input delay leave no phase margin for; weight the input more, "
                "or the states of that mode less)") if a > ALTERNATION_NOTE else ""

    def _gain(self) -> str:
        """The law's gain on the noise, for a failure (empty below its note)."""
        text = noise_gain_text(self.noise_gain)
        return "; " + text if text else ""

    def _binding(self) -> str:
        """The declared bounds the controller reached (within :data:`BINDING` of the limit): why it could not track better."""
        near = [b for b in self.bounds + self.bounds_between if math.isfinite(b.signed) and b.signed >= -BINDING]
        return ("; the bounds it rode: " + ", ".join(f"{b.name} {b.value:.4g} of {b.limit:g} ({100 * b.signed:+.2g} %) at t = {b.time:.4g} s"
                                                      for b in near)) if near else ""

    def _predicted(self, name: str) -> str:
        """What the controller's model predicted where ``name`` went furthest beyond its bound (:attr:`predictions`; empty without)."""
        return "".join("; " + prediction_text(e) for e in self.predictions if e["name"] == name)

    def _estimated(self) -> str:
        """The estimates the controller worked with (:attr:`estimates`), for the ratio's failure (empty without)."""
        return ("; its estimates: " + "; ".join(_estimate_text(e) for e in self.estimates)) if self.estimates else ""

    @property
    def step_p99_s(self) -> float:
        """99th percentile of the step times after the first [s] (:meth:`LoopSummary.step_times`)."""
        return self.closed.step_times()["p99"]

    @property
    def failed_steps(self) -> int:
        """Calls of the step that did not return ``GT_OK``."""
        return int(np.count_nonzero(self.closed.status != STATUS_CODES["GT_OK"][0]))

    def to_dict(self) -> dict[str, Any]:
        """The figures of :meth:`summary_lines` as JSON-able values (``DIR/summary.json`` of ``gtmodel codegen ... --check``).

        Returns
        -------
        dict
            ``status`` (the shared :class:`~gtmodel.status.Status`), ``failures``, ``label``, ``real``,
            ``ratio_to_feedforward`` (None when the plant diverged) and ``max_ratio``, ``rms_error`` and ``max_error`` of
            the controller and of the feedforward, ``bounds`` and ``bounds_between`` (the controller's, per bound:
            :meth:`~gtmodel.control.bounds.BoundExcess.to_dict`), ``bounds_feedforward``, ``step_time_s`` (``median``,
            ``p99``, ``max``, ``first``, ``budget``, ``clock``), ``failed_steps``, ``alternation`` (:attr:`alternation`), ``input_bound_violations``,
            ``memory_bytes``, ``work_bytes``, ``notes``, ``estimates`` (:attr:`estimates`), ``predictions`` (:attr:`predictions`),
            ``noise_gain`` (:attr:`noise_gain`, its infinite time, the held end's, as null).
        """
        times = self.closed.step_times()
        return {"status": str(self.status), "failures": self.failures(), "label": self.label, "real": self.real,
                "ratio_to_feedforward": None if self.plant_diverged else float(self.ratio_to_feedforward),
                "max_ratio": float(self.max_ratio),
                "controller": {"rms_error": float(self.closed.rms_error), "max_error": float(self.closed.max_error), "diverged": bool(self.closed.diverged)},
                "feedforward": {"rms_error": float(self.feedforward.rms_error), "max_error": float(self.feedforward.max_error),
                                "diverged": bool(self.feedforward.diverged)},
                "bounds": [b.to_dict() for b in self.bounds], "bounds_between": [b.to_dict() for b in self.bounds_between],
                "bounds_feedforward": [b.to_dict() for b in self.bounds_feedforward],
                "step_time_s": {**{k: float(v) for k, v in times.items()}, "budget": float(self.step_budget_s), "clock": self.clock},
                "failed_steps": self.failed_steps, "alternation": self.alternation, "input_bound_violations": int(self.closed.bound_violations),
                "memory_bytes": int(self.memory_bytes), "work_bytes": int(self.work_bytes), "notes": list(self.notes),
                "estimates": [dict(e) for e in self.estimates], "predictions": [dict(e) for e in self.predictions],
                "noise_gain": None if self.noise_gain is None else {k: (None if isinstance(v, float) and not math.isfinite(v) else v)
                                                                    for k, v in self.noise_gain.items()}}

    def summary_lines(self) -> list[str]:
        """Human-readable summary.

        Returns
        -------
        list of str
        """
        if self.plant_diverged:
            runaway = [name for name, run in (("controller", self.closed), ("feedforward", self.feedforward)) if run.diverged]
            ratio = (f"RMS ratio {self.label} / feedforward: none (the plant diverged under the {' and the '.join(runaway)}: "
                     f"no figure of a runaway run counts; limit {self.max_ratio:g})")
        else:
            r = self.ratio_to_feedforward
            ratio = f"RMS ratio {self.label} / feedforward: {r:.4g} ({'below' if r < self.max_ratio else 'NOT below'} the limit {self.max_ratio:g})"
        held = [f"  {b.line()}" for b in self.bounds]
        held += [f"  between the samples (the plant step's substeps): {b.line()}" for b in self.bounds_between]
        ff_beyond = [b.name for b in self.bounds_feedforward if b.beyond_tolerance]
        return ([f"notes: {n}" for n in self.notes]
                + [f"closed loop, generated C {self.label}" + (" (real float: float32 step, double plant; the same criteria)" if self.real == "float" else "") + ":"] + ["  " + line for line in self.closed.summary_lines()]
                + ([f"declared bounds on the plant under the {self.label} (tolerance {100 * EXCESS_TOLERANCE:g} %):"] + held if held
                   else ["declared bounds on the plant: none"])
                + ([f"the {self.label}'s estimates (its memory after each period):"] + [f"  {_estimate_text(e)}" for e in self.estimates]
                   if self.estimates else [])
                + ([f"note: {noise_gain_text(self.noise_gain)}"] if noise_gain_text(self.noise_gain) else [])
                + ([f"where a bound was exceeded, the {self.label}'s model:"] + [f"  {prediction_text(e)}" for e in self.predictions]
                   if self.predictions else [])
                + ["feedforward alone:", f"  tracking error: RMS {self.feedforward.rms_error:.4g}, max {self.feedforward.max_error:.4g}"]
                + ([f"  beyond a declared bound by more than {100 * EXCESS_TOLERANCE:g} %: {', '.join(ff_beyond)}"] if ff_beyond else [])
                + [ratio,
                   f"step time budget (99th percentile): {self.step_budget_s * 1e6:.1f} us; step times by time.{self.clock}"
                   + (" (the thread's CPU time)" if self.clock == "thread_time" else ""),
                   f"static memory: {self.memory_bytes} bytes (memory struct) + {self.work_bytes} bytes of stack work arrays"]
                + ([f"QP solver's allocations: arena peak {self.heap[0]} of {self.heap[2]} bytes (per thread), {self.heap[1]} on the heap"]
                   if self.heap else [])
                + ([f"note: the feedforward is at an input bound in {100 * self.reference_at_bounds:.0f} % of the samples: the feedback has "
                    "little authority there (plan with margin below the bounds: a controller or MPC file's [reference] overrides, docs/model_in_the_loop.md)"]
                   if self.reference_at_bounds > AUTHORITY_WARNING else [])
                + [f"note: the reference rides the declared bound of {name} in {100 * share:.0f} % of the samples: the feedback has no "
                   "room there on a plant unlike the model (plan that state with margin below its bound: a controller or MPC file's "
                   "[reference] overrides, docs/model_in_the_loop.md)"
                   for name, share in self.states_at_bounds.items() if share > STATE_AUTHORITY_WARNING])


def _estimate_text(e: dict[str, Any]) -> str:
    """One estimate of :attr:`LoopCheck.estimates` as a line."""
    return (f"{e['kind']} {e['name']}: largest {e['largest']:.4g} at t = {e['time']:.4g} s ({100 * e['relative']:.3g} % of its "
            f"{'range' if e['kind'] == ESTIMATES['d'][0] else 'scale'}), last {e['last']:.4g}")


def compiled_step(generated: GeneratedCode, library: Path | CompiledLibrary) -> tuple[Any, Any, int]:
    """The compiled step as ``controller(t, x) -> (status, u)`` with its own memory, and a reset.

    A thin wrapper of :meth:`gtmodel.codegen.build.CompiledLibrary.loop_runner` (the reals of the
    library's type: ``float`` included).

    Parameters
    ----------
    generated : GeneratedCode
        From :func:`~gtmodel.codegen.loop_step.build_step`.
    library : pathlib.Path or CompiledLibrary
        The compiled library.

    Returns
    -------
    controller : callable
        ``controller(t, x) -> (status, u)`` calling ``<prefix>_step`` through ctypes.
    reset : callable
        ``reset()`` calls ``<prefix>_init`` (returns its status).
    memory_bytes : int
        ``sizeof(<prefix>_memory)``.
    """
    runner = _library(generated, library).loop_runner()
    return runner, runner.reset, runner.memory_bytes


def _library(generated: GeneratedCode, library: Path | CompiledLibrary) -> CompiledLibrary:
    return library if isinstance(library, CompiledLibrary) else load_library(generated, library)


def heap_stats(generated: GeneratedCode, library: Path | CompiledLibrary) -> tuple[int, int, int] | None:
    """The heap arena's figures of a compiled loop step whose QP solver allocates (:meth:`CompiledLibrary.heap_stats`).

    Parameters
    ----------
    generated : GeneratedCode
        From :func:`~gtmodel.codegen.loop_step.build_step`.
    library : pathlib.Path or CompiledLibrary
        The compiled library.

    Returns
    -------
    tuple of int or None
        ``(peak bytes, heap calls, arena bytes)``; None when the step has no arena (its solver
        does not allocate).
    """
    return _library(generated, library).heap_stats()


def reference_at_bounds(u_ref: np.ndarray, u_lb: np.ndarray, u_ub: np.ndarray, rtol: float = 1e-3) -> float:
    """Fraction of the samples whose feedforward input is at a bound (within ``rtol`` of the bound range,
    or of ``1 + |bound|`` for a one-sided one), in any component.

    Parameters
    ----------
    u_ref : numpy.ndarray
        ``(N, nu)`` the feedforward.
    u_lb, u_ub : numpy.ndarray
        ``(nu,)`` the input bounds (infinite: none).
    rtol : float, optional
        Closeness to a bound, relative (default 1e-3).

    Returns
    -------
    float
        In ``[0, 1]``.
    """
    u = np.atleast_2d(np.asarray(u_ref, dtype=float))
    lb, ub = np.asarray(u_lb, dtype=float), np.asarray(u_ub, dtype=float)
    finite = np.isfinite(lb) & np.isfinite(ub)
    one_sided = 1.0 + np.abs(np.where(np.isfinite(lb), lb, np.where(np.isfinite(ub), ub, 0.0)))
    scale = np.where(finite, ub - lb, one_sided)  # ub - lb is inf, not NaN, where a bound is infinite
    at = (u <= lb + rtol * scale) | (u >= ub - rtol * scale)
    return float(np.mean(np.any(at, axis=1))) if u.size else 0.0


def reference_states_at_bounds(setup: LoopSetup, rtol: float = 1e-3) -> dict[str, float]:
    """Per declared state bound, the fraction of the reference's samples at it (within ``rtol`` of ``max(1, |bound|)``).

    Parameters
    ----------
    setup : LoopSetup
        The file's reference (``x_ref``), state names and declared bounds.
    rtol : float, optional
        Closeness to a bound, relative (default 1e-3).

    Returns
    -------
    dict of str to float
        State name to a fraction in ``(0, 1]``; the states never at a bound left out.
    """
    if setup.bounds is None or not setup.names:
        return {}
    out = {}
    for j, name in enumerate(setup.names[0]):
        if name not in setup.bounds.lb or j >= setup.x_ref.shape[1]:
            continue
        x = setup.x_ref[:, j]
        lo, hi = float(setup.bounds.lb[name]), float(setup.bounds.ub.get(name, np.inf))
        at = np.zeros(x.shape, dtype=bool)
        for bound in (lo, hi):
            if np.isfinite(bound):
                at |= np.abs(x - bound) <= rtol * max(1.0, abs(bound))
        if at.any():
            out[name] = float(np.mean(at))
    return out


def feedforward_law(controller: Any) -> Any:
    """The feedforward alone of a loop controller: ``u*_k`` of its reference at time ``t``, saturated.

    Parameters
    ----------
    controller : Any
        ``t0``, ``dt``, ``length``, ``u_ref`` ``(N, nu)``, ``u_lb``, ``u_ub``.

    Returns
    -------
    callable
        ``law(t, x) -> (0, u)`` (the state is not used).
    """
    c = controller
    return lambda t, x: (0, np.clip(c.u_ref[period_index(t, c.t0, c.dt, c.length - 1)], c.u_lb, c.u_ub))


def plant_bounds(setup: LoopSetup, run: LoopSummary, between: bool = False) -> list[BoundExcess]:
    """The declared bounds of a loop-controller file on the plant of one run, per variable.

    The states (the run's plant states, when they are the model's: not the tool coordinates
    of a compliant robot plant), the applied inputs and the plant's algebraic variables and
    outputs ``h(x, u, p)`` (with the plant's parameters), against :attr:`LoopSetup.bounds`.

    Parameters
    ----------
    setup : LoopSetup
        The file's bounds, names and plant.
    run : LoopSummary
        A closed-loop run.
    between : bool, optional
        The states between the samples instead: at the plant step's substeps (:attr:`LoopSummary.x_interior`;
        empty where the run recorded none). A held-out drive's MPC kept 5.028 A of 5 at the 4 ms samples and
        reached 5.087 A between them; the shipped drives' MPCs, their current rows at the samples only,
        overshot there by up to 41 % (the flexible joint: 9.98 A at the samples, 13.23 A inside its second period).

    Returns
    -------
    list of BoundExcess
        :func:`~gtmodel.control.bounds.bound_report`; empty without bounds.
    """
    if setup.bounds is None:
        return []
    x_names, u_names, y_names = setup.names
    values = {n: run.u[:, j] for j, n in enumerate(u_names) if j < run.u.shape[1]}
    if between:  # the states at the plant step's substeps alone, where recorded
        inner = run.x_interior if run.x_interior is not None and run.x_interior.ndim == 3 else None
        if inner is None or "output" in setup.loop or len(x_names) != inner.shape[2]:
            return []
        t = np.asarray(run.t, dtype=float).reshape(-1)
        period = np.diff(t, append=t[-1] + (t[-1] - t[-2] if t.size > 1 else 0.0))
        when = t[:, None] + period[:, None] * np.arange(1, inner.shape[1] + 1) / (inner.shape[1] + 1)  # the substeps' times
        return bound_report({n: inner[:, :, j].ravel() for j, n in enumerate(x_names)}, setup.bounds.lb, setup.bounds.ub, times=when.ravel())
    if "output" not in setup.loop and len(x_names) == run.x.shape[1]:
        values.update({n: run.x[:, j] for j, n in enumerate(x_names)})
        if setup.outputs is not None and y_names and np.all(np.isfinite(run.x)):
            y = np.asarray(setup.outputs.map(run.t.size)(run.x.T, run.u.T, setup.plant_p), dtype=float).T
            values.update({n: y[:, j] for j, n in enumerate(y_names)})
    return bound_report(values, setup.bounds.lb, setup.bounds.ub, times=np.asarray(run.t, dtype=float))


def closed_loop_check(setup: LoopSetup, generated: GeneratedCode, library: Path | CompiledLibrary, repeat: int = 1,
                      clock: Any = time.thread_time, label: str = "controller", progress: Any = None) -> LoopCheck:
    """Run the generated controller and the feedforward alone against the file's plant.

    Parameters
    ----------
    setup : LoopSetup
        The file's controller, plant and loop options.
    generated : GeneratedCode
        From :func:`build_step`.
    library : pathlib.Path or CompiledLibrary
        The compiled library (any real type: a ``float`` build is called with float32 arrays).
    repeat : int, optional
        Runs of the whole motion (``_init`` before each; the step times and statuses of
        all runs are kept, the tracking figures are those of the first run).
    clock : callable, optional
        Clock of the step times (see :func:`run_controller_loop`); default the calling
        thread's CPU time (``time.thread_time``): the step's own computation, which the
        period budget (``[check] max_step_time``) is about, without the preemptions of a
        shared machine (``time.perf_counter`` for wall time).
    label : str, optional
        What the controller is, for the summary.
    progress : callable, optional
        ``progress(line)`` called with a line at most every :data:`PROGRESS_INTERVAL_S` seconds
        while the loop runs (``"closed loop, generated C MPC: 120 of 250 periods, 2.1 s"``); None: quiet.

    Returns
    -------
    LoopCheck
    """
    lib = _library(generated, library)
    runner = lib.loop_runner()
    args = (setup.plant_step, setup.plant_x0, setup.t, setup.x_ref)
    kw = dict(setup.loop, plant_p=setup.plant_p, status_names=STATUS_NAMES, clock=clock)
    n = int(np.size(setup.t))
    memories: list[np.ndarray] = []

    def recording(t: float, x: np.ndarray) -> tuple[int, np.ndarray]:  # the first run's memory after each period
        out = runner(t, x)
        if len(memories) < n:
            memories.append(runner.memory())
        return out

    controller = recording if progress is None else _reporting(recording, f"closed loop, generated C {label}", n, progress)
    first = run_controller_loop(controller, *args, **kw)
    own = getattr(setup.controller, "n_memory", 0)  # the controller's own memory (a measurement filter's follows it)
    estimates = memory_estimates(setup.controller, first.t[:len(memories)], np.array(memories)[:, :own]) if memories else []
    times, statuses = [first.step_s], [first.status]
    for _ in range(max(int(repeat), 1) - 1):
        runner.reset()
        again = run_controller_loop(controller, *args, **kw)
        times.append(again.step_s)
        statuses.append(again.status)
    first.step_s, first.status = np.concatenate(times), np.concatenate(statuses)
    law = feedforward_law(setup.controller)
    ff = run_controller_loop(law if progress is None else _reporting(law, "feedforward alone", n, progress), *args, **kw)
    budget = setup.max_step_time if setup.max_step_time is not None else float(setup.controller.dt)
    bounds = plant_bounds(setup, first)
    return LoopCheck(closed=first, feedforward=ff, memory_bytes=runner.memory_bytes, work_bytes=lib.work_bytes("control"), label=label,
                     state_limits=getattr(setup.controller, "state_limits", None) is not None,
                     real=getattr(generated, "real", "double"),
                     max_ratio=float(setup.max_ratio), step_budget_s=float(budget), heap=lib.heap_stats(),
                     clock=getattr(clock, "__name__", str(clock)),
                     reference_at_bounds=reference_at_bounds(setup.u_ref, setup.controller.u_lb, setup.controller.u_ub),
                     bounds=bounds, bounds_feedforward=plant_bounds(setup, ff), notes=list(setup.notes),
                     states_at_bounds=reference_states_at_bounds(setup), bounds_between=plant_bounds(setup, first, between=True),
                     estimates=estimates, predictions=excess_predictions(setup, first, bounds, label, x_hat=_filter_estimates(setup, memories)),
                     noise_gain=noise_gain(setup.controller, setup.loop.get("noise_std", 0.0), *setup.names[:2]))


def _filter_estimates(setup: LoopSetup, memories: list[np.ndarray]) -> np.ndarray | None:
    """``(n, nx)`` the measurement filter's estimate after each period (its memory's ``x^``), or None without a filter."""
    f = getattr(setup.controller, "state_filter", None)
    if f is None or not memories:
        return None
    own = getattr(setup.controller, "n_memory", 0)
    return np.array(memories, dtype=float)[:, own:own + f.nx]


def _reporting(law: Any, what: str, n: int, progress: Any) -> Any:
    """``law`` that also calls ``progress(line)`` at most every :data:`PROGRESS_INTERVAL_S` seconds (wall time)."""
    start = time.perf_counter()
    state = {"calls": 0, "next": start + PROGRESS_INTERVAL_S}

    def wrapped(t: float, x: np.ndarray) -> Any:
        state["calls"] += 1
        now = time.perf_counter()
        if now >= state["next"]:
            state["next"] = now + PROGRESS_INTERVAL_S
            progress(f"{what}: {min(state['calls'], n)} of {n} periods, {now - start:.0f} s")
        return law(t, x)

    return wrapped
