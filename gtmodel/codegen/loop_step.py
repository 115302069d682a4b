"""The ONE C step interface of the loop controllers: a CasADi Function behind a memory struct.

Every controller that runs in the loop (the tracking controller of
:mod:`gtmodel.control.tracking`, a real-time MPC) is ONE CasADi Function of the form

``control(t (1,1), x (nx,1), u_last (nu,1)[, w (nw,1)]) -> (u (nu,1)[, w_next (nw,1)], ok (1,1))``

(``w`` an inner memory the step carries from one period to the next, e.g. an MPC's shifted
warm start, the C argument ``w_start`` of ``<prefix>_control``; ``ok`` 1 when the result is
valid, e.g. the QP solved), described by a
:class:`LoopStep`. :func:`generate_loop_step` writes it through the one codegen path
(:func:`gtmodel.codegen.writer.write_library`: CasADi's code generator, a plain-C wrapper
``<prefix>_control`` with argument checks and status codes) and adds, from
``harness/template_loop_step.h``/``.c``, the fixed interface of the loop::

    typedef struct PREFIX_memory { real u_last[NU]; real w[NW or 1]; long steps; int status; } PREFIX_memory;
    int PREFIX_init(PREFIX_memory *mem);
    int PREFIX_step(PREFIX_memory *mem, real t, const real *x, real *u);

No heap: the memory is the caller's, of static size. ``PREFIX_step`` returns ``GT_OK`` with
``u`` saturated at the input bounds; ``GT_BAD_ARGUMENT`` for a NULL pointer, a non-finite
``t`` or a non-finite or absurd ``x`` (outside :attr:`LoopStep.x_range`: the measurement is
rejected, the memory untouched; with a :attr:`LoopStep.predict`, generated as ``PREFIX_predict``,
the state the memory predicts replaces it instead and the step returns
``GT_MEASUREMENT_REJECTED`` with ``u`` computed from it); ``GT_NUMERIC_ERROR`` for a non-finite result; the
:attr:`LoopStep.fail_status` (e.g. ``GT_NOT_CONVERGED``) when ``ok`` is 0. On every failure it
writes the safe input: the last input, saturated. A memory that is non-finite or absurd
(``u_last`` outside :attr:`LoopStep.u_range`, ``w`` outside :attr:`LoopStep.w_range`: a glitch
that got into it, a write from outside) is reset before the step to the reference's at ``t``
(:attr:`LoopStep.reset`, generated as ``PREFIX_memory_reset``) and the step returns
``GT_MEMORY_RESET`` with ``u`` computed from it. :func:`check_loop_step` compiles it strictly,
compares ``<prefix>_control`` (and ``<prefix>_memory_reset``, ``<prefix>_predict``) with the
Functions evaluated from Python on random inputs and probes the step contract (it lives in the
check harness, :mod:`gtmodel.codegen.check.loop_step`, with the closed-loop check
:mod:`gtmodel.codegen.check.closed_loop`).

To reuse it (an MPC): build the Function above, wrap it in a :class:`LoopStep` (``w_init``
the first warm start, ``fail_status="GT_NOT_CONVERGED"``), call :func:`generate_loop_step`
and :func:`~gtmodel.codegen.check.loop_step.check_loop_step`; nothing else is C.
"""

from __future__ import annotations

import hashlib
import logging
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import casadi as ca
import numpy as np

import gtmodel
from gtmodel.codegen.build import CompiledLibrary, compile_shared
from gtmodel.codegen.code_source import CodeSource
from gtmodel.codegen.declarations import FLOAT_RELATIVE_TOLERANCE, STATUS_CODES, ArgSpec, FunctionSpec, OutputSpec, StatusCheck
from gtmodel.codegen.emit import fill, header_guard
from gtmodel.codegen.writer import REAL_TYPES, GeneratedCode, write_library
from gtmodel.codegen.hpipm_source import hpipm_libraries, patch_hpipm_memory, patch_hpipm_options
from gtmodel._escape import c_comment, check_c_identifier
from gtmodel.errors import CodegenError, InputError
from gtmodel.control.mpc import MPCController
from gtmodel.control.position_loop import PoseCorrection, ReferenceStreaming
from gtmodel.control.tracking import TrackingController
from gtmodel.control.reference import FLOAT_PERIOD_LIMIT

__all__ = ["LOOP_KIND", "LOOP_TOLERANCE", "SOLVER_LIBRARIES", "HEAP_ARENA_BYTES", "HEAP_WRAP_FLAGS", "uses_heap_arena", "LoopStep", "solver_libraries", "tracking_step", "mpc_step", "position_step", "generate_loop_step", "build_step", "load_loop_step"]

log = logging.getLogger("gtmodel")

#: ``GeneratedCode.kind`` of a loop controller.
LOOP_KIND = "loop_step"
#: Largest accepted ``|C - Python|`` of the inner step (absolute, or relative to ``|Python|``).
LOOP_TOLERANCE = 1e-12


@dataclass(frozen=True)
class LoopStep(CodeSource):
    """A loop controller: its CasADi Function and what the memory functions need.

    Parameters
    ----------
    name : str
        Controller name (for the header).
    function : casadi.Function
        ``control(t, x, u_last[, w]) -> (u[, w_next], ok)``, inputs and outputs named so.
    dt : float
        Loop period [s] (``<PREFIX>_DT``).
    u_lb, u_ub : numpy.ndarray
        ``(nu,)`` input bounds of the saturation (``-inf``/``inf``: none).
    u_init : numpy.ndarray
        ``(nu,)`` the input before the first step (saturated by ``_init``).
    x_names, u_names : list of str
        Scalar names of states and inputs (for the header).
    w_init : numpy.ndarray
        ``(nw,)`` initial inner memory (empty: none).
    description : str
        Comment lines for the header (the law, its source).
    fail_status : str
        Status macro returned when ``ok`` is 0 (default ``GT_NUMERIC_ERROR``).
    t_range : tuple of float
        Times sampled by the check [s].
    x_samples : numpy.ndarray
        ``(M, nx)`` states about which the check samples (e.g. the reference).
    x_range : numpy.ndarray or None
        ``(2, nx)`` the plausible measurement, lowest and highest (``_step`` rejects one outside:
        ``GT_BAD_ARGUMENT``, or with :attr:`predict` ``GT_MEASUREMENT_REJECTED``); None: any finite one.
    u_range, w_range : numpy.ndarray or None
        ``(2, nu)``, ``(2, nw)`` the plausible memory ``u_last``, ``w`` (``_step`` resets a memory
        outside, or non-finite, and returns ``GT_MEMORY_RESET``); None: any finite one.
    reset : casadi.Function or None
        ``reset(t, x) -> (u_last[, w])``: the memory reset to the reference's at time ``t`` [s]
        (e.g. :meth:`gtmodel.control.mpc.MPCController.memory_reset`); None: the first memory
        (``u_init`` saturated, ``w_init``).
    predict : casadi.Function or None
        ``predict(u_last, w) -> x``: the state the memory predicts for now, which replaces a
        non-finite or absurd measurement (``_step`` returns ``GT_MEASUREMENT_REJECTED`` with ``u``
        computed from it; e.g. :meth:`gtmodel.control.mpc.MPCController.memory_predict`);
        None: such a measurement is refused (``GT_BAD_ARGUMENT``, the safe input).
    real : {"double", "float"} or None
        The real type :attr:`function` was built for (an MPC's QP tolerances, :func:`mpc_step`);
        generating in the other is refused. None: either.
    float_tolerance : float
        Single-precision check of ``control``: ``|C - Python| <= float_tolerance (1 + |Python|)``
        (default :data:`~gtmodel.codegen.declarations.FLOAT_RELATIVE_TOLERANCE`; an MPC's from its
        QP's conditioning, :meth:`~gtmodel.control.mpc.MPCController.float_tolerance`).
    """

    name: str
    function: ca.Function
    dt: float
    u_lb: np.ndarray
    u_ub: np.ndarray
    u_init: np.ndarray
    x_names: list[str]
    u_names: list[str]
    w_init: np.ndarray = field(default_factory=lambda: np.zeros(0))
    description: str = ""
    fail_status: str = "GT_NUMERIC_ERROR"
    t_range: tuple[float, float] = (0.0, 1.0)
    x_samples: np.ndarray = field(default_factory=lambda: np.zeros((1, 0)))
    x_range: np.ndarray | None = None
    u_range: np.ndarray | None = None
    w_range: np.ndarray | None = None
    reset: ca.Function | None = None
    predict: ca.Function | None = None
    real: str | None = None
    float_tolerance: float = FLOAT_RELATIVE_TOLERANCE

    #: The :class:`~gtmodel.codegen.sources.CodeSource` kind (``GeneratedCode.kind`` of its code).
    kind = LOOP_KIND

    def _summary(self) -> str:
        return f"the {self.dt:g} s loop step of {self.name} (<prefix>_init, <prefix>_step on a caller-owned memory)"

    def _specs(self) -> tuple[FunctionSpec, ...]:
        # control, then memory_reset and predict when given
        return (_spec(self),) + ((_reset_spec(self),) if self.reset is not None else ()) + ((_predict_spec(self),) if self.predict is not None else ())

    def _target(self, spec: FunctionSpec) -> ca.Function:
        return {"control": self.function, "memory_reset": self.reset, "predict": self.predict}[spec.name]

    def _evaluate(self, spec: FunctionSpec, inputs: Any) -> dict[str, np.ndarray]:
        # the Function mapped over the samples; control's rows NaN where ok is 0 or the evaluation fails
        f = self._target(spec)
        n = len(next(iter(inputs.values())))
        args = {a.casadi_input: np.asarray(inputs[a.name], dtype=float).reshape(n, -1).T for a in spec.args}
        failed = np.zeros(n, dtype=bool)
        try:
            res = f.map(n).call(args)
        except RuntimeError:  # a sample whose evaluation fails (an MPC's solver meeting NaN): NaN for it alone
            res = {out: np.zeros((f.numel_out(out), n)) for out in f.name_out()}
            for i in range(n):
                try:
                    one = f.call({k: v[:, i] for k, v in args.items()})
                except RuntimeError:
                    failed[i] = True
                    continue
                for out in res:
                    res[out][:, i] = np.asarray(one[out]).reshape(-1)
        if "ok" in f.name_out():
            failed |= np.asarray(res["ok"]).reshape(-1) <= 0.5
        return {o.name: np.where(failed[:, None], np.nan, np.asarray(res[o.casadi_output]).T) for o in spec.outputs}

    def _write(self, out_dir: str | Path, real: str, prefix: str | None) -> GeneratedCode:
        return generate_loop_step(self, out_dir, prefix=prefix or "gt_controller", real=real)

    @property
    def nx(self) -> int:
        """Number of states."""
        return int(self.function.numel_in("x"))

    @property
    def nu(self) -> int:
        """Number of inputs."""
        return int(self.function.numel_in("u_last"))

    @property
    def nw(self) -> int:
        """Length of the inner memory."""
        return int(self.function.numel_in("w")) if "w" in self.function.name_in() else 0

    def validate(self) -> None:
        """Check the Function's interface and the sizes.

        Raises
        ------
        InputError
            Inputs or outputs not named as the interface, sizes that disagree, a bad period
            or status.
        """
        f = self.function
        if not isinstance(f, ca.Function):
            raise InputError(f"function: expected a casadi.Function, got {type(f).__name__}")
        ins = ["t", "x", "u_last"] + (["w"] if "w" in f.name_in() else [])
        outs = ["u"] + (["w_next"] if "w" in f.name_in() else []) + ["ok"]
        if f.name_in() != ins or f.name_out() != outs:
            raise InputError(f"function: expected inputs {ins} and outputs {outs}, got {f.name_in()} and {f.name_out()}")
        if f.numel_in("t") != 1 or f.numel_out("u") != self.nu or f.numel_out("ok") != 1 or (self.nw and f.numel_out("w_next") != self.nw):
            raise InputError("function: t and ok must be scalars, u as long as u_last, w_next as long as w")
        if not (isinstance(self.dt, (int, float)) and math.isfinite(self.dt) and self.dt > 0):
            raise InputError(f"dt: expected a positive loop period in seconds, got {self.dt!r}")
        for label, v, n in (("u_lb", self.u_lb, self.nu), ("u_ub", self.u_ub, self.nu), ("u_init", self.u_init, self.nu), ("w_init", self.w_init, self.nw)):
            if np.size(v) != n or np.any(np.isnan(v)):
                raise InputError(f"{label}: expected {n} values, got {np.size(v)}")
        if not (np.all(np.isfinite(self.u_init)) and np.all(np.isfinite(self.w_init)) and np.all(np.asarray(self.u_lb) <= np.asarray(self.u_ub))):
            raise InputError("u_init, w_init: expected finite values; u_lb <= u_ub")
        for label, r, n in (("x_range", self.x_range, self.nx), ("u_range", self.u_range, self.nu), ("w_range", self.w_range, self.nw)):
            if r is not None and (np.shape(r) != (2, n) or np.any(np.isnan(r)) or np.any(np.asarray(r)[0] > np.asarray(r)[1])):
                raise InputError(f"{label}: expected a (2, {n}) array of the lowest and highest plausible values, got shape {np.shape(r)}")
        if not (self.u_range is None or np.all((self.u_range[0] <= self.u_init) & (self.u_init <= self.u_range[1]))) or not (
                self.w_range is None or np.all((self.w_range[0] <= self.w_init) & (self.w_init <= self.w_range[1]))):
            raise InputError("u_init, w_init: expected the first memory inside u_range, w_range")
        if self.reset is not None:
            outs = ["u_last"] + (["w"] if self.nw else [])
            if not isinstance(self.reset, ca.Function) or self.reset.name_in() != ["t", "x"] or self.reset.name_out() != outs:
                raise InputError(f"reset: expected a casadi.Function reset(t, x) -> ({', '.join(outs)})")
            if self.reset.numel_in("t") != 1 or self.reset.numel_in("x") != self.nx or self.reset.numel_out("u_last") != self.nu or (
                    self.nw and self.reset.numel_out("w") != self.nw):
                raise InputError("reset: t a scalar, x, u_last and w as long as the step's")
        if self.predict is not None and not (
                isinstance(self.predict, ca.Function) and self.nw and self.predict.name_in() == ["u_last", "w"]
                and self.predict.name_out() == ["x"] and self.predict.numel_in("u_last") == self.nu
                and self.predict.numel_in("w") == self.nw and self.predict.numel_out("x") == self.nx):
            raise InputError("predict: expected a casadi.Function predict(u_last, w) -> x of the step's sizes (with an inner memory)")
        if self.fail_status not in STATUS_CODES or self.fail_status == "GT_OK":
            raise InputError(f"fail_status: expected a failure status of {', '.join(STATUS_CODES)}, got {self.fail_status!r}")


def tracking_step(controller: TrackingController, name: str = "tracking") -> LoopStep:
    """The loop step of a tracking controller (:func:`gtmodel.control.tracking.tracking_controller`).

    Parameters
    ----------
    controller : TrackingController
        Feedforward and time-varying LQR gains.
    name : str, optional
        Controller name for the header.

    Returns
    -------
    LoopStep
        Its :meth:`~gtmodel.control.tracking.TrackingController.function`, period,
        input bounds, first input ``u*_0`` and the reference as the check's samples.
    """
    c = controller
    text = (f"Tracking controller: u = sat(u*_k - K_k (x - x*_k)), k = floor((t - {c.t0!r}) / {c.dt!r}) held in 0..{c.length - 1}\n"
            + ("(feedforward u* and reference x* sampled at the period, time-varying LQR gains K_k from the\n"
               "backward discrete Riccati recursion on the model's fixed-step Jacobians; gtmodel.control.tracking).\n"
               if np.any(c.K != c.K[0]) else
               "(feedforward u* and reference x* sampled at the period, one time-invariant LQR gain K (the discrete\n"
               "Riccati equation at the held end, on the model's fixed-step Jacobians); gtmodel.control.tracking).\n")
            + ("One period of input delay compensated: x and t replaced by the state predicted at t + dt\n"
               "by the model's fixed step from u_last (the input acting until this one arrives).\n" if c.delay else "")
            + (f"Integral action on {', '.join(c.x_names[i] for i in c.integral_states)}: u -= Ki_k xi, the integrator state xi\n"
               "(memory w) += dt (x - x*_k) of those states, held while the input saturates.\n" if c.ni else "")
            + ("Declared state bounds held over the period the input acts (the input projected onto the linearised rows at\n"
               "every substep, backed off by the measured one-period prediction error; gtmodel.control.state_limits).\n"
               if c.state_limits is not None else "")
            + f"States x: {', '.join(c.x_names)}\nInputs u: {', '.join(c.u_names)}")
    return LoopStep(name=name, dt=c.dt, u_lb=c.u_lb.copy(), u_ub=c.u_ub.copy(), u_init=c.u_initial,
                    x_names=list(c.x_names), u_names=list(c.u_names), description=text + _filter_text(c),
                    t_range=(c.t0, c.t0 + c.dt * (c.length - 1)), x_samples=c.x_ref, **_guards(c, c.function, ()))


def mpc_step(controller: MPCController, name: str = "mpc", real: str = "double") -> LoopStep:
    """The loop step of a real-time MPC (:func:`gtmodel.control.mpc.mpc_controller`).

    Parameters
    ----------
    controller : MPCController
        The MPC (its solver is code-generated inside the step).
    name : str, optional
        Controller name for the header.
    real : {"double", "float"}, optional
        Real type the step is generated in: ``"float"`` relaxes ``qrqp``'s stopping tolerances
        to :data:`~gtmodel.control.mpc.QP_FLOAT_TOLERANCE` and compares the C with Python within
        :meth:`~gtmodel.control.mpc.MPCController.float_tolerance` (at least
        :data:`~gtmodel.codegen.declarations.FLOAT_RELATIVE_TOLERANCE`).

    Returns
    -------
    LoopStep
        Its :meth:`~gtmodel.control.mpc.MPCController.function`, period, input bounds,
        first input ``u*_0``, first warm start, ``GT_NOT_CONVERGED`` when the SQP result is
        not finite, and the reference as the check's samples.

    Raises
    ------
    InputError
        Another real type.
    """
    c = controller
    if real not in REAL_TYPES:
        raise InputError(f"real: expected 'double' or 'float', got {real!r}")
    text = (f"Real-time nonlinear MPC: horizon {c.horizon} periods of {c.dt!r} s, {c.blocks} input blocks, "
            f"{c.sqp_iterations} SQP iteration(s) per period\n"
            + {"sqpmethod": f"(single shooting, Gauss-Newton QPs by {c.qpsol}, full steps, warm start shifted by one period;\n",
               "hpipm": "(multiple shooting, Gauss-Newton QPs by HPIPM's Riccati recursion, full steps, warm start shifted by one period;\n",
               "fatrop": "(multiple shooting, fatrop's interior point, warm start shifted by one period;\n"}[c.solver] +
            "tracking of the reference x*, u* sampled at the period; gtmodel.control.mpc).\n"
            + (f"Offset-free: an input disturbance d estimated each period (gain {c.disturbance_gain:g}) from the\n"
               "one-period prediction error; the memory w holds the warm start, d, the last x and u_last, a flag.\n"
               if c.disturbance_gain else "")
            + ("Constraint rows tightened each period by the one-period prediction error measured in the loop (back-off;\n"
               "gtmodel.control.mpc_memory.row_backoff); the memory w holds the last x and u_last for it.\n"
               if c.estimates and c.constraint_backoff else "")
            + f"States x: {', '.join(c.x_names)}\nInputs u: {', '.join(c.u_names)}")
    ftol = max(FLOAT_RELATIVE_TOLERANCE, c.float_tolerance()) if real == "float" else FLOAT_RELATIVE_TOLERANCE
    return LoopStep(name=name, dt=c.dt, u_lb=c.u_lb.copy(), u_ub=c.u_ub.copy(), u_init=c.u_initial,
                    x_names=list(c.x_names), u_names=list(c.u_names), description=text + _filter_text(c), real=real, float_tolerance=ftol,
                    fail_status="GT_NOT_CONVERGED", t_range=(c.t0, c.t0 + c.dt * (c.length - 1)), x_samples=c.x_ref, **_guards(c, c.function, (real,)))


def position_step(controller: PoseCorrection | ReferenceStreaming, name: str = "position") -> LoopStep:
    """The loop step of a controller behind a robot's position interface (:mod:`gtmodel.control.position_loop`).

    Parameters
    ----------
    controller : PoseCorrection or ReferenceStreaming
        Cvitanic's pose correction from a tracker, or a streamed reference with its ILC correction.
    name : str, optional
        Controller name for the header.

    Returns
    -------
    LoopStep
        Its Function, period, saturation bounds, first output, the plausible measurement and
        memory (:meth:`~gtmodel.control.position_loop.PoseCorrection.limits`) and sampled
        measurements for the check.

    Raises
    ------
    InputError
        Not one of the two controllers.
    """
    c = controller
    if not isinstance(c, (PoseCorrection, ReferenceStreaming)):
        raise InputError(f"controller: expected a PoseCorrection or a ReferenceStreaming, got {type(c).__name__}")
    lim = c.limits()
    t_end = c.dt * (c.length - 1) if isinstance(c, ReferenceStreaming) else 1.0
    return LoopStep(name=name, function=c.function(), dt=c.dt, u_lb=c.u_lb, u_ub=c.u_ub, u_init=c.u_initial,
                    x_names=list(c.x_names), u_names=list(c.u_names), description=c.description + "\nStates x: "
                    + ", ".join(c.x_names) + "\nInputs u: " + ", ".join(c.u_names), t_range=(0.0, t_end), x_samples=c.samples(),
                    x_range=lim["x"], u_range=lim["u_last"])


def _guards(controller: TrackingController | MPCController, build: Any, args: tuple) -> dict[str, Any]:
    """The step's Function (``build(*args[, filtered=True])``), first memory, plausible measurement and memory, memory
    reset and prediction (the LoopStep's fields), with the controller's
    :attr:`~gtmodel.control.mpc.MPCController.state_filter` in front when it has one."""
    c, lim = controller, controller.limits()
    f = c.state_filter
    fields = {"function": build(*args) if f is None else None, "w_init": c.memory_initial, "x_range": lim["x"], "u_range": lim["u_last"],
              "w_range": lim["memory"] if lim["memory"].shape[1] else None, "reset": c.memory_reset(),
              "predict": getattr(c, "memory_predict", lambda: None)()}
    if f is None:
        return fields
    control, reset, predict = f.wrap(build(*args, filtered=True), fields["reset"], c.n_memory)
    w_range = np.hstack([lim["memory"].reshape(2, -1), f.memory_range(lim["x"], lim["u_last"])])
    return {**fields, "function": control, "reset": reset, "predict": predict, "w_range": w_range,
            "w_init": np.concatenate([np.asarray(c.memory_initial, dtype=float).reshape(-1), f.memory_initial(c.x_ref[0], c.u_initial)])}


def _filter_text(controller: TrackingController | MPCController) -> str:
    """The header's line on the measurement filter (empty without one)."""
    f = controller.state_filter
    return "" if f is None else ("\nThe measurement filtered first: the extended Kalman filter of the controller's own step (noise per state "
                                 + ", ".join(f"{n} {s:.3g}" for n, s in zip(controller.x_names, f.sigma))
                                 + ";\ngtmodel.control.state_filter); the memory w ends with x^, P, u_last and a flag.")


def _c_array(values: Any) -> str:
    """C initialiser of a real array (infinite entries as ``INFINITY``; at least one entry)."""
    vals = np.asarray(values, dtype=float).reshape(-1)
    if vals.size == 0:
        return "0"
    return ", ".join("INFINITY" if v == math.inf else "-INFINITY" if v == -math.inf else repr(float(v)) for v in vals)


def _hash(step: LoopStep) -> str:
    """Short hash of the controller: its Functions' serialisations, bounds, plausible ranges and period."""
    ranges = [None if r is None else np.asarray(r).tolist() for r in (step.x_range, step.u_range, step.w_range)]
    text = (step.function.serialize() + "".join("" if f is None else f.serialize() for f in (step.reset, step.predict))
            + repr((step.dt, np.asarray(step.u_lb).tolist(), np.asarray(step.u_ub).tolist(), ranges)))
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def _reset_spec(step: LoopStep) -> FunctionSpec:
    """The memory reset's C function ``<prefix>_memory_reset(t, x, u_last[, w_reset])``."""
    outs = [OutputSpec("u_last", "u_last", "the last input of the reset memory")]
    if step.nw:
        outs.append(OutputSpec("w_reset", "w", "the inner memory reset"))  # not 'w': the wrapper's work array
    return FunctionSpec(
        "memory_reset", lambda source: source.reset,
        args=(ArgSpec("t", "vector", "t", "time [s]"), ArgSpec("x", "vector", "x", "measured state")),
        outputs=tuple(outs), tolerance=LOOP_TOLERANCE, relative_tolerance=LOOP_TOLERANCE, kind=LOOP_KIND,
        doc=f"The memory of the loop controller {step.name} reset to the reference's at t (called by _step on a "
            "non-finite or absurd memory).",
    )


def _predict_spec(step: LoopStep) -> FunctionSpec:
    """The prediction's C function ``<prefix>_predict(u_last, w_start, x_hat)``."""
    return FunctionSpec(
        "predict", lambda source: source.predict,
        args=(ArgSpec("u_last", "vector", "u_last", "the last input"), ArgSpec("w_start", "vector", "w", "inner memory")),
        outputs=(OutputSpec("x_hat", "x", "the state the memory predicts for now"),), tolerance=LOOP_TOLERANCE,
        relative_tolerance=LOOP_TOLERANCE, kind=LOOP_KIND,
        doc=f"The state the memory of the loop controller {step.name} predicts (called by _step in place of a "
            "non-finite or absurd measurement).",
    )


def _spec(step: LoopStep) -> FunctionSpec:
    args = [ArgSpec("t", "vector", "t", "time [s]"), ArgSpec("x", "vector", "x", f"measured state ({', '.join(step.x_names[:12])})"),
            ArgSpec("u_last", "vector", "u_last", "the last input")]
    outs = [OutputSpec("u", "u", f"input ({', '.join(step.u_names[:12])}), saturated")]
    if step.nw:
        args.append(ArgSpec("w_start", "vector", "w", "inner memory (warm start)"))  # not 'w': the wrapper's work array
        outs.append(OutputSpec("w_next", "w_next", "inner memory of the next period"))
    return FunctionSpec(
        "control", lambda source: source.function, args=tuple(args), outputs=tuple(outs),
        checks=(StatusCheck("ok", ">", "0.5", step.fail_status),), tolerance=LOOP_TOLERANCE,
        relative_tolerance=LOOP_TOLERANCE, kind=LOOP_KIND, float_tolerance=step.float_tolerance,
        doc=f"The inner step of the loop controller {step.name} (called by _step; the memory functions are the interface).",
    )


#: Solver libraries of the casadi wheel that CasADi's generated C may include: the header it
#: includes -> the linker arguments (``{lib}``: the wheel's folder). DAQP statically (its
#: ``libdaqpstat.a``), fatrop and BLASFEO as the wheel's shared libraries (found by rpath).
SOLVER_LIBRARIES = {
    "daqp/api.h": ("{lib}/libdaqpstat.a",),
    "fatrop/ocp/OCPCInterface.h": ("-L{lib}", "-lfatrop", "-lblasfeo", "-Wl,-rpath,{lib}"),
    "hpipm_d_ocp_qp_ipm.h": ("-L{lib}", "-lhpipm", "-lblasfeo", "-Wl,-rpath,{lib}"),
}
#: Headers of the solver libraries whose generated call allocates its work in every QP (DAQP's setup;
#: HPIPM's dimensions, QP, solution and workspace in CasADi's runtime): the step's heap arena takes them.
ARENA_HEADERS = ("daqp/api.h", "hpipm_d_ocp_qp_ipm.h")


#: Bytes of the per-thread static arena that takes the allocations of a QP solver that allocates its work
#: in every QP (DAQP, whose setup mallocs; :data:`SOLVER_LIBRARIES`): the library is linked with
#: :data:`HEAP_WRAP_FLAGS`, so the step makes no heap call (``<prefix>_heap_stats`` counts those that did
#: not fit; the closed-loop check fails on any). The L1 MPC's QP (15 variables, 60 rows) peaks at a few
#: kB; a compile-time ``-DGT_HEAP_ARENA_BYTES=...`` changes it.
HEAP_ARENA_BYTES = 262144
#: Linker arguments that send the allocator calls of the library's objects to the arena.
HEAP_WRAP_FLAGS = ("-Wl,--wrap=malloc,--wrap=calloc,--wrap=realloc,--wrap=free",)
#: The header's declaration of ``<prefix>_heap_stats`` (with the arena).
_HEAP_DOC = """/*
 * The QP solver's allocations (DAQP sets up its work in every QP; HPIPM's memory is made at the
 * calling thread's first QP and kept for its later ones) go to a per-thread static arena of GT_HEAP_ARENA_BYTES ({arena} unless defined at compile time), not to the heap: link
 * the library with -Wl,--wrap=malloc,--wrap=calloc,--wrap=realloc,--wrap=free (gtmodel's build
 * does). Writes the arena's peak use [bytes], the allocations that did not fit and went to the
 * heap (0 expected) and the arena's size [bytes], of the calling thread.
 * Returns GT_OK, or GT_BAD_ARGUMENT (a NULL pointer).
 */
int {prefix}_heap_stats(unsigned long *peak_bytes, unsigned long *heap_calls, unsigned long *arena_bytes);"""


def uses_heap_arena(casadi_source: str | Path) -> bool:
    """Whether a loop step's CasADi source calls a QP solver that allocates (DAQP, HPIPM), so that its
    library carries the heap arena (:data:`HEAP_ARENA_BYTES`).

    Parameters
    ----------
    casadi_source : str or pathlib.Path
        The generated ``<prefix>_casadi.c``.

    Returns
    -------
    bool
    """
    text = Path(casadi_source).read_text()
    return any(f"#include <{h}>" in text for h in ARENA_HEADERS)


def solver_libraries(source: str | Path) -> tuple[tuple[str, ...], tuple[str, ...]]:
    """Include folders and linker arguments of the solver libraries a CasADi-generated C file includes.

    Parameters
    ----------
    source : str or pathlib.Path
        The generated C file.

    Returns
    -------
    include_dirs : tuple of str
        The casadi wheel's ``include`` folder when a library of :data:`SOLVER_LIBRARIES` is included.
    link_flags : tuple of str
        Their linker arguments (empty: plain C); for HPIPM the static libraries of
        :data:`~gtmodel.codegen.hpipm_source.HPIPM_ENV` when it is set.

    Raises
    ------
    CodegenError
        :data:`~gtmodel.codegen.hpipm_source.HPIPM_ENV` names a folder without them.
    """
    text = Path(source).read_text()
    lib = Path(ca.__file__).resolve().parent
    static = hpipm_libraries() if "#include <hpipm_d_ocp_qp_ipm.h>" in text else None
    # with HPIPM_ENV: HPIPM and BLASFEO linked into the step, hidden (the process's other HPIPM does not bind them)
    libraries = {**SOLVER_LIBRARIES, "hpipm_d_ocp_qp_ipm.h": (*map(str, static), "-Wl,--exclude-libs,ALL")} if static else SOLVER_LIBRARIES
    flags = [a.format(lib=lib) for header, args in libraries.items() if f"#include <{header}>" in text for a in args]
    return ((str(lib / "include"),) if flags else ()), tuple(flags)


def generate_loop_step(step: LoopStep, out_dir: str | Path, prefix: str = "gt_controller", real: str = "double") -> GeneratedCode:
    """Generate C for a loop controller: the inner step and the memory interface.

    Parameters
    ----------
    step : LoopStep
        The controller.
    out_dir : str or pathlib.Path
        Folder to write into (created if missing).
    prefix : str, optional
        C symbol prefix (``<prefix>_step``, ``<prefix>_init``, ``<prefix>_memory``).
    real : {"double", "float"}, optional
        Floating-point type.

    Returns
    -------
    GeneratedCode
        ``kind = "loop_step"``, ``parameters`` the :class:`LoopStep`, ``functions``
        ``("control",)``, then ``"memory_reset"`` and ``"predict"`` with a :attr:`LoopStep.reset`, :attr:`LoopStep.predict`.

    Raises
    ------
    InputError
        A bad step (:meth:`LoopStep.validate`), prefix or real type (or not the one :attr:`LoopStep.real` was built for); ``real = "float"`` for a
        reference reaching beyond :data:`~gtmodel.control.reference.FLOAT_PERIOD_LIMIT` periods.
    CodegenError
        CasADi's code generation or writing the files failed.
    """
    if not isinstance(step, LoopStep):
        raise InputError(f"step: expected a LoopStep, got {type(step).__name__}")
    step.validate()
    if real not in REAL_TYPES:
        raise InputError(f"real: expected 'double' or 'float', got {real!r}")
    if step.real is not None and step.real != real:
        raise InputError(f"real: the step of {step.name} was built for real = {step.real!r} (its QP tolerances), got {real!r}; "
                         f"build it with mpc_step(controller, real={real!r})")
    periods = max(abs(step.t_range[0]), abs(step.t_range[1])) / step.dt
    if real == "float" and periods > FLOAT_PERIOD_LIMIT:
        raise InputError(f"real: 'float' cannot index {periods:.0f} periods of {step.dt:g} s (times up to {max(map(abs, step.t_range)):g} s): "
                         f"float32 round-off of (t - t0) / dt exceeds the period slack beyond {FLOAT_PERIOD_LIMIT} periods; use real = 'double'")
    check_c_identifier(prefix, "prefix", "gt_tracking")
    spec = _spec(step)
    specs = (spec,) + ((_reset_spec(step),) if step.reset is not None else ()) + ((_predict_spec(step),) if step.predict is not None else ())
    phash = _hash(step)
    version = f"gtmodel {gtmodel.__version__}; casadi {ca.__version__}; controller {step.name} sha256:{phash}; real {real}"
    P = prefix.upper()
    ins = {"t": "tt", "x": "x", "u_last": "mem->u_last", "w_start": "mem->w"}
    outs = {"u": "u_new", "w_next": "w_new"}
    call = f"{prefix}_control(" + ", ".join([ins[a.name] for a in spec.args] + [outs[o.name] for o in spec.outputs]) + ")"
    reset = ("GT_NUMERIC_ERROR /* no reset function: the first memory */" if step.reset is None else
             f"{prefix}_memory_reset(tt, x, mem->u_last" + (", mem->w)" if step.nw else ")"))
    predict = "GT_BAD_ARGUMENT /* no prediction */" if step.predict is None else f"{prefix}_predict(mem->u_last, mem->w, x_hat)"
    inf = math.inf

    def bounds(r: np.ndarray | None, n: int, row: int) -> str:
        v = np.full(n, -inf if row == 0 else inf) if r is None else np.asarray(r, dtype=float)[row]
        return _c_array(np.where(np.abs(v) > 3.0e38, np.copysign(inf, v), v) if real == "float" else v)  # beyond FLT_MAX: none
    names = dict(NAME=step.name, VERSION=version)
    values = dict(
        GP=prefix, P=P, REAL=real, NX=step.nx, NU=step.nu, NW=step.nw, NW1=max(step.nw, 1),
        DT=repr(float(step.dt)), OPEN=header_guard(P)[0], CLOSE=header_guard(P)[1],
        DESCRIPTION="\n".join(f" * {c_comment(line)}".rstrip() for line in (step.description or step.name).splitlines()),
        ULB=_c_array(step.u_lb), UUB=_c_array(step.u_ub), U0=_c_array(step.u_init), W0=_c_array(step.w_init), CALL=call,
        RESET=reset, PREDICT=predict, XLO=bounds(step.x_range, step.nx, 0), XHI=bounds(step.x_range, step.nx, 1),
        ULO=bounds(step.u_range, step.nu, 0), UHI=bounds(step.u_range, step.nu, 1),
        WLO=bounds(step.w_range, step.nw, 0), WHI=bounds(step.w_range, step.nw, 1),
    )
    memory = "\n" + fill("template_loop_step.c", names, **values)

    def header(wrapped: Any) -> str:
        arena = uses_heap_arena(Path(out_dir) / f"{prefix}_casadi.c")  # written before the header
        return fill("template_loop_step.h", names, **values, PROTOTYPES="\n".join(wrapped.header),
                    HEAP=_HEAP_DOC.format(arena=HEAP_ARENA_BYTES, prefix=prefix) if arena else "")

    out, _, sizes, signatures = write_library(prefix, specs, step, out_dir, real, header, extra_source=memory)
    patch_hpipm_options(out / f"{prefix}_casadi.c")
    patch_hpipm_memory(out / f"{prefix}_casadi.c")
    log.info("codegen: wrote %s for loop controller %s", out / f"{prefix}.c", step.name)
    include_dirs, link_flags = solver_libraries(out / f"{prefix}_casadi.c")
    if uses_heap_arena(out / f"{prefix}_casadi.c"):
        try:
            with open(out / f"{prefix}.c", "a") as f:
                f.write("\n" + fill("template_heap_arena.c", GP=prefix, ARENA=HEAP_ARENA_BYTES))
        except OSError as exc:
            raise CodegenError(f"cannot write generated code to {out}: {exc.strerror}") from None
        link_flags = (*link_flags, *HEAP_WRAP_FLAGS)
    return GeneratedCode(
        out_dir=out, prefix=prefix, functions=tuple(s.name for s in specs), source=out / f"{prefix}.c", header=out / f"{prefix}.h",
        casadi_source=out / f"{prefix}_casadi.c", casadi_header=out / f"{prefix}_casadi.h", parameters=step, friction="",
        parameter_hash=phash, version=version, specs=specs, work_sizes=sizes, signatures=signatures, real=real, kind=LOOP_KIND,
        include_dirs=include_dirs, link_flags=link_flags,
    )


def load_loop_step(generated: GeneratedCode, library: CompiledLibrary) -> tuple[type, Any, Any]:
    """The memory struct type and the ``_init`` / ``_step`` functions of a compiled loop controller (ctypes).

    A thin wrapper of :meth:`gtmodel.codegen.build.CompiledLibrary.loop_interface` (the one owner of
    a built library's ctypes interface; the reals of the library's type, ``float`` included).

    Parameters
    ----------
    generated : GeneratedCode
        From :func:`generate_loop_step`.
    library : CompiledLibrary
        Its compiled library.

    Returns
    -------
    memory : type
        A ``ctypes.Structure`` of the layout of ``<prefix>_memory``.
    init : callable
        ``init(ctypes.byref(mem)) -> int``.
    step : callable
        ``step(ctypes.byref(mem), t, x_ptr, u_ptr) -> int`` (``x_ptr``, ``u_ptr`` pointers
        to the real type, or None).

    Raises
    ------
    InputError
        Not a loop controller's code.
    """
    if generated.kind != LOOP_KIND or not isinstance(generated.parameters, LoopStep):
        raise InputError("generated: expected the code of a loop controller (from generate_loop_step)")
    return library.loop_interface()


def build_step(step: LoopStep, out_dir: str | Path, prefix: str, real: str = "double") -> tuple[GeneratedCode, Path]:
    """Generate and compile a loop step.

    Parameters
    ----------
    step : LoopStep
        The controller (:func:`tracking_step`, :func:`mpc_step`).
    out_dir : str or pathlib.Path
        Folder of the C files (the shared library in ``out_dir/build``).
    prefix : str
        C prefix.
    real : {"double", "float"}, optional
        Floating-point type.

    Returns
    -------
    generated : GeneratedCode
    library : pathlib.Path
        The compiled shared library.

    Raises
    ------
    CompilerNotFoundError
        No C compiler.
    CodegenError
        Generation or compilation failed.
    """
    generated = generate_loop_step(step, out_dir, prefix=prefix, real=real)
    return generated, compile_shared(generated, Path(out_dir) / "build")
