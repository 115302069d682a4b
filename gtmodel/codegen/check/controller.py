"""Self-check of the generated controller functions over a whole run of the 4 ms loop.

:func:`check_controller` compares the compiled Kalman step and ILC correction with the
Python evaluation of the very CasADi Functions they were generated from, over every cycle
of a run (default 400 cycles, 1.6 s):

- ``kalman_step`` (the array function) on every ``(x_k, y_k)`` of the Python run, and
  ``kalman_update`` (the state struct) run in C from ``x_0`` over the whole measurement
  sequence, its state fed back by the C code: every ``x_k`` and ``z_hat_k`` against the
  Python run ``kalman_step.mapaccum`` (the form the Python estimation uses);
- ``ilc_correction`` at every cycle ``k = -10 .. N + 9`` (the whole table and beyond
  both ends, where it must give 0 and ``GT_OK``);

then probes the status contract (NULL pointers, NaN/Inf inputs or state: ``GT_BAD_ARGUMENT``
with the outputs and the state untouched) and, with ``timing=True``, times each function
in a C loop over the run (ns per call). The KF/EKF steps of the tracker + IMU fusion
(``kf_step``, ``ekf_step``) are checked over a measurement record of a few thousand steps
by :mod:`gtmodel.codegen.check.filter` (every state and covariance; the quaternion norm;
a covariance that is not positive definite gives ``GT_NUMERIC_ERROR``).
"""

from __future__ import annotations

import logging
from dataclasses import dataclass
from pathlib import Path

import casadi as ca
import numpy as np

from gtmodel.codegen.build import CompiledLibrary, compile_shared, load_library
from gtmodel.codegen.check.filter import FILTER_CYCLES, filter_checks, filter_probes, filter_record, time_filters
from gtmodel.codegen.check.lead_through import check_record, lead_through_checks, lead_through_probes, lead_through_record, time_lead_through
from gtmodel.codegen.check.report import SENTINEL, CheckReport, FunctionCheck, StatusProbe, run_check, status_probe, with_timings
from gtmodel.codegen.check.run import c_array, c_function, pointer, time_program, timing_block
from gtmodel.codegen.controller import Controller
from gtmodel.codegen.declarations import STATUS_CODES
from gtmodel.codegen.generate import controller_part
from gtmodel.codegen.writer import GeneratedCode
from gtmodel.errors import InputError

__all__ = [
    "RUN_CYCLES",
    "ILC_MARGIN",
    "POSITION_AMPLITUDE",
    "ControllerCheckReport",
    "run_inputs",
    "python_run",
    "check_controller",
]

log = logging.getLogger("gtmodel")

#: Cycles of the default run (1.6 s at 4 ms).
RUN_CYCLES = 400
#: Cycles checked before and after the ILC table (the correction must be 0 there).
ILC_MARGIN = 10
#: Amplitude of the tool motion of the run [m] per direction (the 10 mm square of ch. 7.3).
POSITION_AMPLITUDE = 0.010
#: Structural ripple on the kinematic position [m] and its frequency [Hz] (the x resonance).
RIPPLE, RIPPLE_HZ = 20e-6, 7.4
#: Sensor figures of Dressler (2012), ch. 7.3: gauge-like position noise [m], accelerometer noise [m/s^2], range [m/s^2].
POSITION_NOISE, ACCELEROMETER_NOISE, ACCELEROMETER_RANGE = 1e-6, 0.07, 1.5 * 9.80665

_OK = STATUS_CODES["GT_OK"][0]
_BAD = STATUS_CODES["GT_BAD_ARGUMENT"][0]


@dataclass(frozen=True)
class ControllerCheckReport(CheckReport):
    """Result of :func:`check_controller`: a :class:`~gtmodel.codegen.check.CheckReport` of the controller.

    Parameters
    ----------
    robot : str
        Robot of the library.
    prefix : str
        C prefix of the library.
    n : int
        Cycles of the run.
    seed : int
        Seed of the sensor noise of the run.
    functions : tuple of FunctionCheck
        ``kalman_step``, ``kalman_update``, ``ilc_correction``, ``kf_update``, ``kf_step``,
        ``ekf_update``, ``ekf_step``, ``ekf_update quaternion norm`` (those generated).
    probes : tuple of StatusProbe
        Status-code probes.
    version : str
        Version string reported by the compiled library.
    library : pathlib.Path
        The shared library checked.
    timings : dict
        Unused (the times are in ``functions``).
    harness : str
        Unused (empty).
    harness_passed : bool or None
        Unused (None).
    """

    def summary_lines(self) -> list[str]:
        """Printable lines: one per function, the status probes and the verdict.

        Returns
        -------
        list of str
            E.g. ``"kalman_update: max |C - Python| = 0.0e+00 m, m/s, m/s^2 (tol 1e-12), 60 ns/call OK"``.
        """
        lines = super().summary_lines()
        names = {f.name for f in self.functions}
        ilc = f"; ILC table +-{ILC_MARGIN} cycles" if "ilc_correction" in names else ""
        filters = ", filters over their whole record" if names & {"kf_update", "ekf_update"} else ""
        lines[0] = (f"check of the controller of {self.prefix} over a run of {self.n} cycles "
                    f"(every cycle{ilc}{filters}; seed {self.seed}):")
        return lines


def run_inputs(controller: Controller, cycles: int = RUN_CYCLES, seed: int = 0) -> dict[str, np.ndarray]:
    """A realistic input sequence of the loop for the controller functions.

    Parameters
    ----------
    controller : Controller
        The controller (sizes).
    cycles : int, optional
        Cycles of the run.
    seed : int, optional
        Seed of :func:`numpy.random.default_rng` (sensor noise).

    Returns
    -------
    dict of str to numpy.ndarray
        ``"y"`` ``(cycles, ny)``: when ``ny = 2 nz`` the measurements ``[z_kin; a_m]`` of a
        tool moving per direction ``j`` as ``p_j(t) = POSITION_AMPLITUDE (1 - cos(2 pi f_j t)) / 2``
        (``f_j`` = 1.25, 1.0, 0.75 Hz, ...) with a ``RIPPLE`` (20 um) structural ripple at 7.4 Hz
        and 1 um noise on ``z_kin``, the exact acceleration plus 0.07 m/s^2 noise, clipped to
        1.5 g, on ``a_m`` (Dressler (2012), ch. 7.3 sensors); other sizes: sinusoids of
        10 mm with the same noise; ``"x0"`` ``(nx,)`` zeros (the filter at rest);
        ``"k"`` ``(N + 2 ILC_MARGIN,)`` the cycles ``-ILC_MARGIN .. N + ILC_MARGIN - 1``.
        Missing functions give empty arrays.
    """
    rng = np.random.default_rng(seed)
    nx, ny, nz = controller.kalman_sizes
    t = np.arange(cycles) * controller.dt
    y = np.zeros((cycles, ny))
    if ny:
        half = ny // 2 if ny == 2 * nz else ny
        f = np.maximum(1.25 - 0.25 * np.arange(half), 0.25)
        w = 2 * np.pi * f
        p = POSITION_AMPLITUDE * (1 - np.cos(w * t[:, None])) / 2
        p += RIPPLE * np.sin(2 * np.pi * RIPPLE_HZ * t[:, None]) + rng.normal(0.0, POSITION_NOISE, p.shape)
        y[:, :half] = p
        if ny == 2 * nz:
            a = POSITION_AMPLITUDE * w**2 * np.cos(w * t[:, None]) / 2
            y[:, half:] = np.clip(a + rng.normal(0.0, ACCELEROMETER_NOISE, a.shape), -ACCELEROMETER_RANGE, ACCELEROMETER_RANGE)
    k = np.arange(-ILC_MARGIN, controller.ilc_length + ILC_MARGIN) if controller.ilc_correction is not None else np.zeros(0, int)
    return {"y": y, "x0": np.zeros(nx), "k": k}


def python_run(controller: Controller, y: np.ndarray, x0: np.ndarray, k: np.ndarray) -> dict[str, np.ndarray]:
    """The Python evaluation of a run: the given CasADi Functions called from Python.

    Parameters
    ----------
    controller : Controller
        The Functions.
    y : numpy.ndarray, shape (N, ny)
        Measurements per cycle.
    x0 : numpy.ndarray, shape (nx,)
        Initial filter state.
    k : numpy.ndarray, shape (M,)
        Cycle counts for the ILC correction.

    Returns
    -------
    dict of str to numpy.ndarray
        ``"x"`` ``(N + 1, nx)`` the states ``x_0 .. x_N`` (``kalman_step.mapaccum``),
        ``"z_hat"`` ``(N, nz)``, ``"u"`` ``(M, d)`` (``ilc_correction.map``).
    """
    out: dict[str, np.ndarray] = {}
    if controller.kalman_step is not None and len(y):
        run = controller.kalman_step.mapaccum("run", len(y))
        xs, zs = run(x0, y.T)
        out["x"] = np.vstack([x0, np.asarray(ca.DM(xs)).T])
        out["z_hat"] = np.asarray(ca.DM(zs)).T
    if controller.ilc_correction is not None and len(k):
        out["u"] = np.asarray(ca.DM(controller.ilc_correction.map(len(k))(np.asarray(k, float)[None, :]))).T
    return out


def _c_kalman_run(library: CompiledLibrary, y: np.ndarray, x0: np.ndarray, dtype) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The whole run in C through ``kalman_init``/``kalman_update``: statuses, states, estimates."""
    init, update = c_function(library, "kalman_init", 2), c_function(library, "kalman_update", 3)
    state = np.full(x0.size, SENTINEL, dtype=dtype)
    x0c = np.ascontiguousarray(x0, dtype=dtype)
    ys = np.ascontiguousarray(y, dtype=dtype)
    xs = np.zeros((len(y) + 1, x0.size))
    zs = np.zeros((len(y), library["kalman_step"].sizes_out[1]))
    z = np.zeros(zs.shape[1], dtype=dtype)
    status = np.zeros(len(y) + 1, dtype=int)
    status[0] = init(pointer(state), pointer(x0c))
    xs[0] = state
    for i in range(len(y)):
        status[i + 1] = update(pointer(state), pointer(ys[i]), pointer(z))
        xs[i + 1], zs[i] = state, z
    return status, xs, zs


def _kalman_checks(library: CompiledLibrary, controller: Controller, ref: dict, y: np.ndarray, x0: np.ndarray, real: str) -> list[FunctionCheck]:
    cf = library["kalman_step"]
    spec = cf.spec
    status, (xn, zh) = cf.call_rows(ref["x"][:-1], y, fill=SENTINEL)
    good = status == _OK
    st, xs, zs = _c_kalman_run(library, y, x0, cf.dtype)
    ref_next = np.hstack([ref["x"][1:], ref["z_hat"]])
    n = len(y)
    return [
        run_check("kalman_step", n, [(np.hstack([xn, zh])[good], ref_next[good])], real, spec.tolerance, spec.unit, int(np.sum(~good))),
        run_check("kalman_update", n, [(np.hstack([xs[1:], zs]), ref_next), (xs[0], ref["x"][0])], real, spec.tolerance, spec.unit,
                  int(np.sum(st != _OK))),
    ]


def _kalman_probes(library: CompiledLibrary, y: np.ndarray, x0: np.ndarray) -> list[StatusProbe]:
    cf = library["kalman_step"]
    dt = cf.dtype
    nx, ny = cf.sizes_in
    nz = cf.sizes_out[1]
    step = c_function(library, "kalman_step", 4)
    init, update = c_function(library, "kalman_init", 2), c_function(library, "kalman_update", 3)
    good_x, good_y = np.ascontiguousarray(x0, dt), np.ascontiguousarray(y[0], dt)
    probes = []

    def fresh():
        return np.full(nx, SENTINEL, dt), np.full(nz, SENTINEL, dt)

    def clean(*arrays):
        return all(a is None or np.all(a == np.asarray(SENTINEL, dt)) for a in arrays)

    for what, bad in (("NaN", np.nan), ("Inf", np.inf)):
        for arg in ("x", "y"):
            x_in, y_in = good_x.copy(), good_y.copy()
            (x_in if arg == "x" else y_in)[0] = bad
            xo, zo = fresh()
            s = step(pointer(x_in), pointer(y_in), pointer(xo), pointer(zo))
            probes.append(status_probe("kalman_step", f"{what} in {arg}", "GT_BAD_ARGUMENT", s, clean(xo, zo)))
    for i, arg in enumerate(("x", "y", "x_next", "z_hat")):
        xo, zo = fresh()
        ptrs = [pointer(good_x), pointer(good_y), pointer(xo), pointer(zo)]
        ptrs[i] = None
        s = step(*ptrs)
        probes.append(status_probe("kalman_step", f"NULL {arg}", "GT_BAD_ARGUMENT", s, clean(xo if i != 2 else None, zo if i != 3 else None)))
    state, zo = fresh()
    probes.append(status_probe("kalman_init", "NULL state", "GT_BAD_ARGUMENT", init(None, pointer(good_x)), True))
    bad_x = good_x.copy()
    bad_x[-1] = np.nan
    probes.append(status_probe("kalman_init", "NaN in x0", "GT_BAD_ARGUMENT", init(pointer(state), pointer(bad_x)), clean(state)))
    s = init(pointer(state), None)
    probes.append(status_probe("kalman_init", "x0 NULL (zeros)", "GT_OK", s, bool(np.all(state == 0))))
    for case, y_in, z_ptr in (("NULL y", None, zo), ("NULL z_hat", good_y, None), ("NaN in y", np.full(ny, np.nan, dt), zo)):
        st = np.full(nx, SENTINEL, dt)
        s = update(pointer(st), pointer(y_in), pointer(z_ptr))
        probes.append(status_probe("kalman_update", case, "GT_BAD_ARGUMENT", s, clean(st, z_ptr)))
    probes.append(status_probe("kalman_update", "NULL state", "GT_BAD_ARGUMENT", update(None, pointer(good_y), pointer(zo)), clean(zo)))
    st = np.full(nx, np.nan, dt)
    s = update(pointer(st), pointer(good_y), pointer(zo))
    probes.append(status_probe("kalman_update", "NaN in the state", "GT_BAD_ARGUMENT", s, bool(np.all(np.isnan(st))) and clean(zo)))
    return probes


def _ilc(library: CompiledLibrary, controller: Controller, ref: dict, k: np.ndarray, real: str) -> tuple[FunctionCheck, list[StatusProbe]]:
    cf = library["ilc_correction"]
    status, (u,) = cf.call_rows(k, fill=SENTINEL)
    good = status == _OK
    check = run_check("ilc_correction", len(k), [(u[good], ref["u"][good])], real, cf.spec.tolerance, cf.spec.unit, int(np.sum(~good)))
    raw = c_function(library, "ilc_correction", 2, int_first=True)
    probes = []
    n = controller.ilc_length
    for case, kk in (("k = -1 (before the table)", -1), ("k = N (after the table)", n), ("k = INT_MIN", -(2**31)), ("k = INT_MAX", 2**31 - 1)):
        out = np.full(cf.sizes_out[0], SENTINEL, cf.dtype)
        s = raw(kk, pointer(out))
        probes.append(status_probe("ilc_correction", case + ": zero", "GT_OK", s, bool(np.all(out == 0))))
    probes.append(status_probe("ilc_correction", "NULL u", "GT_BAD_ARGUMENT", raw(0, None), True))
    return check, probes


def _timing_block(label: str, init: str, call: str, budget_s: float) -> str:
    return timing_block(label, [f"        {init}"], f"status |= {call};", budget_s, calibration=1000)


def time_controller(generated: GeneratedCode, library: Path, inputs: dict[str, np.ndarray], build_dir: str | Path, budget_s: float = 0.05) -> dict[str, float]:
    """Time the controller functions in a C loop over the run (ns per call).

    Parameters
    ----------
    generated : GeneratedCode
        A library generated with ``controller=``.
    library : pathlib.Path
        Its shared library.
    inputs : dict
        The run (:func:`run_inputs`): ``y`` replayed cyclically, ``k`` swept.
    build_dir : str or pathlib.Path
        Folder for the timing program.
    budget_s : float, optional
        About this many seconds per function.

    Returns
    -------
    dict of str to float
        ``kalman_step`` (state fed back in place), ``kalman_update`` (the state struct),
        ``ilc_correction`` -> ns per call.

    Raises
    ------
    CodegenError
        The program failed to build or a call returned a non-OK status.
    """
    c = generated.controller
    p, real = generated.prefix, generated.real
    nx, ny, nz = c.kalman_sizes
    y = inputs["y"] if c.kalman_step is not None else np.zeros((1, 1))
    ytext = c_array(y, rows=True)
    blocks = []
    if c.kalman_step is not None:
        blocks.append(_timing_block("kalman_step", f"{real} x[{nx}] = {{0}}, z[{nz}];",
                                    f"{p}_kalman_step(x, Y[i % CYCLES], x, z); sink += z[0]", budget_s))
        blocks.append(_timing_block("kalman_update", f"{p}_kalman_state s; {real} z[{nz}]; status |= {p}_kalman_init(&s, NULL);",
                                    f"{p}_kalman_update(&s, Y[i % CYCLES], z); sink += z[0]", budget_s))
    if c.ilc_correction is not None:
        m = c.ilc_length + 2 * ILC_MARGIN
        blocks.append(_timing_block("ilc_correction", f"{real} u[{c.ilc_d}];",
                                    f"{p}_ilc_correction((int)(i % {m}) - {ILC_MARGIN}, u); sink += u[0]", budget_s))
    tables = ["", f"#define CYCLES {len(y)}", f"static const {real} Y[CYCLES > 0 ? CYCLES : 1][{y.shape[1]}] = {{{ytext}}};", ""]
    rows = time_program(generated, library, f"{p}_controller_timing", blocks, build_dir, tables, "controller timing program")
    return {k: float(v) for k, v in rows}


def _records(c: Controller, cycles: int, seed: int, given: dict | None) -> dict[str, dict[str, np.ndarray]]:
    """The measurement record and prior of every filter step: ``given`` ones validated, else :func:`filter_record`."""
    given = {} if given is None else dict(given)
    lead = given.pop("lead_through_step", None)
    unknown = [k for k in given if k not in c.filter_sizes]
    if unknown:
        raise InputError(f"records: {unknown[0]!r} is not a filter of the controller ({', '.join(c.filter_sizes) or 'none'})")
    out = {}
    for name, (nx, nz) in c.filter_sizes.items():
        if name not in given:
            out[name] = filter_record(c, name, cycles, seed)
            continue
        r = given[name]
        shapes = {"z": (None, nz), "x0": (nx,), "P0": (nx, nx)}
        rec = {}
        for key, shape in shapes.items():
            v = np.asarray(r.get(key, np.zeros(0)) if isinstance(r, dict) else np.zeros(0), dtype=float)
            if v.ndim != len(shape) or any(a is not None and a != b for a, b in zip(shape, v.shape)) or v.size == 0 or not np.all(np.isfinite(v)):
                want = "(N, %d)" % nz if key == "z" else str(shape)
                raise InputError(f"records[{name!r}][{key!r}]: expected finite values of shape {want}, got {v.shape}")
            rec[key] = v
        out[name] = rec
    if lead is not None and c.lead_through_step is None:
        raise InputError("records: 'lead_through_step' given but the controller has no lead_through_step")
    if c.lead_through_step is not None:
        try:
            out["lead_through_step"] = lead_through_record(seed=seed) if lead is None else check_record(lead)
        except InputError as exc:
            raise InputError(f"records['lead_through_step']: {exc}") from None
        if np.any(out["lead_through_step"]["x0"] != 0):
            raise InputError("records['lead_through_step']['x0']: expected zeros (the C run starts from _init: at rest)")
    return out


def check_controller(
    generated: GeneratedCode,
    cycles: int = RUN_CYCLES,
    seed: int = 0,
    library: CompiledLibrary | None = None,
    build_dir: str | Path | None = None,
    timing: bool = False,
    y: np.ndarray | None = None,
    x0: np.ndarray | None = None,
    filter_cycles: int = FILTER_CYCLES,
    records: dict[str, dict[str, np.ndarray]] | None = None,
) -> ControllerCheckReport:
    """Compare the generated controller functions with Python over every cycle of a run.

    Parameters
    ----------
    generated : GeneratedCode
        A library generated with ``controller=`` (:func:`gtmodel.codegen.generate`).
    cycles : int, optional
        Cycles of the run (default 400); ignored when ``y`` is given.
    seed : int, optional
        Seed of the sensor noise of :func:`run_inputs`.
    library : CompiledLibrary or None, optional
        An already loaded library; compiled with :func:`compile_shared` if None.
    build_dir : str or pathlib.Path or None, optional
        Build folder (default ``<out_dir>/build``).
    timing : bool, optional
        Also time each function in a C loop over the run (:func:`time_controller`).
    y : numpy.ndarray or None, optional
        Measurements ``(N, ny)`` of a run to replay instead of :func:`run_inputs`' (e.g.
        the logged ``[z_kin, a_m]`` of an ILC trial).
    x0 : numpy.ndarray or None, optional
        Initial filter state ``(nx,)`` (default zeros).
    filter_cycles : int, optional
        Measurements of the default record of each KF/EKF step
        (:func:`~gtmodel.codegen.check.filter.filter_record`; default 3000).
    records : dict or None, optional
        ``{"kf_step" | "ekf_step": {"z": (N, nz), "x0": (nx,), "P0": (nx, nx)}}``: a
        measurement record and prior to replay instead of the default one (e.g. a
        simulated tracker + IMU run of the fusion study); ``{"lead_through_step": {"F_h":
        (N, 6), "F_t": (N, 6), "n_n": (N, 3), "x0": zeros (8,)}}``: a recorded lead-through
        session (default :func:`~gtmodel.codegen.check.lead_through.lead_through_record`).

    Returns
    -------
    ControllerCheckReport
        ``kalman_step``, ``kalman_update`` and ``ilc_correction`` each with the largest
        ``|C - Python|`` over the run against 1e-12 (single precision:
        ``FLOAT_RELATIVE_TOLERANCE``), the status probes and the timings. A failed check
        is a report with ``passed == False``, not an exception.

    Raises
    ------
    InputError
        No controller in ``generated``; ``cycles`` or ``filter_cycles`` not a positive
        integer; ``y``, ``x0`` or a record of the wrong shape or not finite.
    CompilerNotFoundError
        No C compiler.
    CodegenError
        Compilation failed.
    """
    c = generated.controller
    if c is None:
        raise InputError("generated: the library has no controller functions (generate(..., controller=...))")
    if isinstance(cycles, bool) or not isinstance(cycles, (int, np.integer)) or cycles < 1:
        raise InputError(f"cycles: expected a positive number of cycles, got {cycles!r}")
    if isinstance(filter_cycles, bool) or not isinstance(filter_cycles, (int, np.integer)) or filter_cycles < 1:
        raise InputError(f"filter_cycles: expected a positive number of measurements, got {filter_cycles!r}")
    inputs = run_inputs(c, int(cycles), seed)
    nx, ny, _ = c.kalman_sizes
    if y is not None:
        y = np.asarray(y, dtype=float)
        if y.ndim != 2 or y.shape[1] != ny or len(y) < 1 or not np.all(np.isfinite(y)):
            raise InputError(f"y: expected finite measurements of shape (N, {ny}), got {y.shape}")
        inputs["y"] = y
    if x0 is not None:
        x0 = np.asarray(x0, dtype=float)
        if x0.shape != (nx,) or not np.all(np.isfinite(x0)):
            raise InputError(f"x0: expected a finite state of shape ({nx},), got {x0.shape}")
        inputs["x0"] = x0
    build = Path(build_dir) if build_dir is not None else generated.out_dir / "build"
    if library is None:
        library = load_library(generated, compile_shared(generated, build))
    ref = python_run(c, inputs["y"], inputs["x0"], inputs["k"])
    results: list[FunctionCheck] = []
    probes: list[StatusProbe] = []
    if c.kalman_step is not None:
        results += _kalman_checks(library, c, ref, inputs["y"], inputs["x0"], generated.real)
        probes += _kalman_probes(library, inputs["y"], inputs["x0"])
    if c.ilc_correction is not None:
        check, p = _ilc(library, c, ref, inputs["k"], generated.real)
        results.append(check)
        probes += p
    recs = _records(c, filter_cycles, seed, records)
    lead = recs.pop("lead_through_step", None)
    for name, rec in recs.items():
        results += filter_checks(library, c, name, rec, generated.real)[0]
        probes += filter_probes(library, name, rec)
    if lead is not None:
        results += lead_through_checks(library, c, lead, generated.real)
        probes += lead_through_probes(library, lead)
    if timing:
        times = time_controller(controller_part(generated), library.path, inputs, build) if c.kalman_step or c.ilc_correction else {}
        if recs:
            times.update(time_filters(controller_part(generated), library.path, recs, build))
        if lead is not None:
            times.update(time_lead_through(controller_part(generated), library.path, lead, build))
        results = with_timings(results, times)
    lengths = [len(r["z"]) for r in recs.values()] + ([len(lead["F_h"])] if lead is not None else [])
    n = len(inputs["y"]) if c.kalman_step is not None else (len(inputs["k"]) if c.ilc_correction is not None else max(lengths))
    report = ControllerCheckReport(
        robot=generated.robot_name, prefix=generated.prefix, n=n,
        seed=seed, functions=tuple(results), probes=tuple(probes), version=library.version(), library=library.path,
    )
    log.info("codegen controller check of %s: %s", generated.prefix, "passed" if report.passed else "FAILED")
    return report
