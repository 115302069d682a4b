"""The self-check of a loop controller's generated C (:func:`check_loop_step`).

Compiles the code of :func:`gtmodel.codegen.loop_step.generate_loop_step` strictly, compares
``<prefix>_control`` (and ``<prefix>_memory_reset``, ``<prefix>_predict``) with the CasADi
Functions evaluated from Python on random inputs, and probes the step contract through the
memory interface (:meth:`gtmodel.codegen.build.CompiledLibrary.loop_interface`, the library's
real type, ``float`` included). The closed loop against a plant is
:mod:`gtmodel.codegen.check.closed_loop`.
"""

from __future__ import annotations

import contextlib
import ctypes
import io
import logging
import math
from pathlib import Path

import numpy as np

from gtmodel.codegen.build import CompiledLibrary, load_strict
from gtmodel.codegen.check.compare import compare, probe
from gtmodel.codegen.check.report import CheckReport, StatusProbe, with_timings
from gtmodel.codegen.check.robot import time_functions
from gtmodel.codegen.declarations import STATUS_CODES, FunctionSpec
from gtmodel.codegen.writer import GeneratedCode
from gtmodel.codegen.loop_step import LOOP_KIND, LoopStep
from gtmodel.errors import CodegenError, InputError

__all__ = ["check_loop_step", "loop_samples"]

log = logging.getLogger("gtmodel")


def loop_samples(step: LoopStep, n: int, rng: np.random.Generator) -> dict[str, np.ndarray]:
    """The random inputs of the inner step the check compares C with Python on.

    Parameters
    ----------
    step : LoopStep
        The loop controller's description.
    n : int
        Samples.
    rng : numpy.random.Generator
        The random generator.

    Returns
    -------
    dict
        ``"t"`` ``(n, 1)`` times in (and 5 % of the span beyond) ``t_range``; ``"x"`` ``(n, nx)`` rows of
        ``x_samples`` plus normal noise of 10 % of ``1 + max |x_samples|`` per state; ``"u_last"`` ``(n, nu)``
        uniform within the input bounds (``u_init +- 1`` where a bound is infinite); with a warm start,
        ``"w_start"`` ``(n, nw)`` its first value.
    """
    t0, t1 = step.t_range
    span = max(t1 - t0, step.dt)
    xs = step.x_samples if step.x_samples.size else np.zeros((1, step.nx))
    rows = xs[rng.integers(0, xs.shape[0], n)]
    scale = 0.1 * (1.0 + np.max(np.abs(xs), axis=0))
    lo = np.where(np.isfinite(step.u_lb), step.u_lb, step.u_init - 1.0)
    hi = np.where(np.isfinite(step.u_ub), step.u_ub, step.u_init + 1.0)
    out = {"t": rng.uniform(t0 - 0.05 * span, t1 + 0.05 * span, (n, 1)),
           "x": rows + scale * rng.standard_normal(rows.shape),
           "u_last": rng.uniform(lo, hi, (n, step.nu))}
    if step.nw:
        out["w_start"] = np.tile(step.w_init, (n, 1))  # the C argument's name (the Function's input: w)
    return out


def _reference(step: LoopStep, inputs: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    """Python's inner step on the samples (NaN rows where ``ok`` is 0 or the evaluation failed).

    CasADi's warnings of a sample its solver cannot evaluate (``NaN detected``: a random state
    the MPC's SQP meets NaN at) are kept off the terminal (logged at debug level): the report
    counts those samples as "refused by Python, skipped".
    """
    buf = io.StringIO()
    with contextlib.redirect_stdout(buf), contextlib.redirect_stderr(buf):
        out = step.reference("control", inputs)
    if buf.getvalue():
        log.debug("Python reference of %s: %s", step.name, buf.getvalue().strip())
    return out


def _reset_memory(step: LoopStep, t: float, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The memory ``_step`` resets to at ``(t, x)``: :attr:`LoopStep.reset` (or the first memory), ``u_last`` saturated."""
    if step.reset is None:
        u, w = step.u_init, step.w_init
    else:
        res = step.reset.call({"t": t, "x": x})
        u, w = np.asarray(res["u_last"]).reshape(-1), (np.asarray(res["w"]).reshape(-1) if step.nw else np.zeros(0))
    return np.clip(u, step.u_lb, step.u_ub), w


def _contract_probes(generated: GeneratedCode, library: CompiledLibrary, samples: dict[str, np.ndarray]) -> list[StatusProbe]:
    """The step contract through the memory functions: NULLs, non-finite input, the safe input, equality with Python."""
    step: LoopStep = generated.parameters
    memory, init, fstep = library.loop_interface()
    real = library.real_type
    safe = np.clip(step.u_init, step.u_lb, step.u_ub)
    ftol = generated.specs[0].float_tolerance
    rtol, atol = (ftol, ftol) if generated.real == "float" else (1e-9, 1e-12)  # as the comparison
    probes = []

    def run(case: str, expected: str, t: float, x: np.ndarray | None, want: np.ndarray | None, null_mem: bool = False,
            poison: bool = False) -> None:
        mem = memory()
        init(ctypes.byref(mem))
        if poison:  # NaN written into the memory
            mem.u_last[0] = math.nan
            mem.w[0] = math.nan
        u = (real * step.nu)(*([12345.0] * step.nu))
        xa = None if x is None else (real * step.nx)(*x.tolist())
        status = fstep(None if null_mem else ctypes.byref(mem), t, xa, u)
        got = np.array(u[:], dtype=float)
        untouched = bool(np.all(got == 12345.0)) if want is None else bool(np.allclose(got, want, rtol=rtol, atol=atol))
        probes.append(StatusProbe("step", case, expected, int(status), untouched, int(status) == STATUS_CODES[expected][0] and untouched))

    x0 = np.asarray(samples["x"][0], dtype=float)
    t0 = float(samples["t"][0, 0])
    ref = _reference(step, {"t": np.array([[t0]]), "x": x0[None, :], "u_last": safe[None, :],
                            **({"w_start": step.w_init[None, :]} if step.nw else {})})["u"][0]
    run("valid state after init (u equals Python)", "GT_OK", t0, x0, ref)
    if step.predict is None:  # a rejected measurement: the safe input
        rejected, want, how = "GT_BAD_ARGUMENT", safe, "u = the last input, saturated"
    else:  # the state the memory predicts in its place
        x_hat = np.asarray(step.predict(safe, step.w_init)).reshape(-1)
        rejected, how = "GT_MEASUREMENT_REJECTED", "u equals Python at the state the memory predicts"
        want = _reference(step, {"t": np.array([[t0]]), "x": x_hat[None, :], "u_last": safe[None, :], "w_start": step.w_init[None, :]})["u"][0]
    bad = x0.copy()
    bad[0] = math.nan
    run(f"x[0] = nan ({how})", rejected, t0, bad, want)
    run("t = nan (u = the last input, saturated)", "GT_BAD_ARGUMENT", math.nan, x0, safe)
    run("x NULL (u = the last input, saturated)", "GT_BAD_ARGUMENT", t0, None, safe)
    run("mem NULL (u untouched)", "GT_BAD_ARGUMENT", t0, x0, None, null_mem=True)
    if step.x_range is not None and np.isfinite(step.x_range[1, 0]):
        far = x0.copy()
        far[0] = 10.0 * abs(step.x_range[1, 0]) + 1.0
        run(f"x[0] beyond x_range ({how})", rejected, t0, far, want)
    u_r, w_r = _reset_memory(step, t0, x0)
    again = _reference(step, {"t": np.array([[t0]]), "x": x0[None, :], "u_last": u_r[None, :], **({"w_start": w_r[None, :]} if step.nw else {})})
    run("NaN in the memory (reset: u equals Python from the reset memory)", "GT_MEMORY_RESET", t0, x0, again["u"][0], poison=True)
    init_null = init(None)
    probes.append(StatusProbe("init", "mem NULL", "GT_BAD_ARGUMENT", int(init_null), True, int(init_null) == STATUS_CODES["GT_BAD_ARGUMENT"][0]))
    return probes


def check_loop_step(generated: GeneratedCode, n: int = 500, seed: int = 0, build_dir: str | Path | None = None,
                    timing: bool = False) -> CheckReport:
    """Compile a loop controller strictly and compare it with Python; probe the step contract.

    Parameters
    ----------
    generated : GeneratedCode
        From :func:`generate_loop_step`.
    n : int, optional
        Random inputs of the inner step (default 500).
    seed : int, optional
        Seed of the random generator.
    build_dir : str or pathlib.Path, optional
        Build folder (default ``<out_dir>/build``).
    timing : bool, optional
        Also time ``<prefix>_control`` in a C loop (ns/call).

    Returns
    -------
    CheckReport
        ``control`` (and ``memory_reset``, ``predict``): the largest ``|C - Python|`` (:data:`LOOP_TOLERANCE`,
        absolute or relative) on random times, states about the reference and last inputs;
        probes: non-finite inputs of ``control``, and of ``_step``: ``GT_OK`` with ``u`` equal
        to Python after ``_init``, ``GT_BAD_ARGUMENT`` with the safe input for a NaN time and a
        NULL state, for a NaN state and one beyond :attr:`LoopStep.x_range` the same or, with a
        :attr:`LoopStep.predict`, ``GT_MEASUREMENT_REJECTED`` with ``u`` equal to Python at the
        predicted state, a NULL memory (``u`` untouched), ``GT_MEMORY_RESET`` with ``u`` equal to Python from the reset memory for NaN
        written into the memory, and ``_init(NULL)``.

    Raises
    ------
    InputError
        Not a loop controller's code, ``n`` not positive.
    CompilerNotFoundError
        No C compiler.
    CodegenError
        Compilation failed.
    """
    if generated.kind != LOOP_KIND or not isinstance(generated.parameters, LoopStep):
        raise InputError("generated: expected the code of a loop controller (from generate_loop_step)")
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 1:
        raise InputError(f"n: expected a positive number of samples, got {n!r}")
    build = Path(build_dir) if build_dir is not None else generated.out_dir / "build"
    library = load_strict(generated, build)
    step: LoopStep = generated.parameters
    samples = loop_samples(step, int(n), np.random.default_rng(seed))
    spec = generated.specs[0]
    spec = FunctionSpec(**{**spec.__dict__, "reference": lambda source, inputs: _reference(source, inputs)})
    cf = library["control"]
    results = (compare(spec, cf, step, samples, generated.real),) + tuple(
        compare(s, library[s.name], step, samples, generated.real) for s in generated.specs[1:])
    if timing:
        times = time_functions(generated, library.path, {s.name: samples for s in generated.specs}, build)
        results = tuple(with_timings(results, times))
    probes = []
    for a in spec.args:
        row = np.array(samples[a.name][0], dtype=float)
        row[0] = np.nan
        probes.append(probe(cf, spec, samples, f"{a.name}[0] = nan", "GT_BAD_ARGUMENT", {a.name: row}))
    try:
        probes += _contract_probes(generated, library, samples)
    except (OSError, AttributeError) as exc:
        raise CodegenError(f"loop controller {generated.prefix}: cannot load _init/_step: {exc}") from None
    report = CheckReport(robot=step.name, prefix=generated.prefix, n=int(n), seed=seed, functions=results, probes=tuple(probes),
                         version=library.version(), library=library.path)
    log.info("codegen check of loop controller %s: %s", generated.prefix, "passed" if report.passed else "FAILED")
    return report
