"""Self-check of the generated KF/EKF steps over a whole measurement record (Cvitanic (2021), ch. 4).

For each filter step of a :class:`~gtmodel.codegen.controller.Controller` (``kf_step``,
``ekf_step``) the C and Python are fed the SAME measurement record (default
:data:`FILTER_CYCLES` steps at the controller's sample time, :func:`filter_record`) from
the same prior, and every state and covariance is compared:

- ``<name>_update`` (the state struct) run in C over the whole record, its state fed
  back by the C code, against the Python run (the step Function's ``mapaccum``);
- ``<name>_step`` (the array function) on every ``(x_k, P_k, z_k)`` of the Python run;
- the quaternion of every C state of the 19-D EKF has unit norm (the renormalisation
  is in the graph): ``| |quat| - 1 | <= QUATERNION_NORM_TOLERANCE``;

then the status contract is probed: NULL pointers and NaN/Inf inputs give
``GT_BAD_ARGUMENT``, a covariance that is not positive definite ``GT_NUMERIC_ERROR``, the
outputs (and the state) untouched. :func:`build_filter_program` writes a stand-alone C
program running the record through ``_init``/``_update``, compiled with the strict flags
and linked with a heap-call counter, for valgrind (:func:`run_filter_program`).
"""

from __future__ import annotations

import subprocess
from dataclasses import dataclass
from pathlib import Path

import casadi as ca
import numpy as np

from gtmodel.codegen.build import CompiledLibrary
from gtmodel.codegen.check.report import FLOAT_RELATIVE_TOLERANCE, SENTINEL, FunctionCheck, StatusProbe, run_check, status_probe
from gtmodel.codegen.check.run import (HEAP_WRAP, STRICT_FLAGS, c_array, c_function, compile_program, pointer, run_record_program,
                                       strict_objects, time_program)
from gtmodel.codegen.controller import Controller
from gtmodel.codegen.declarations import STATUS_CODES
from gtmodel.codegen.emit import fill
from gtmodel.codegen.writer import GeneratedCode
from gtmodel.errors import InputError
from gtmodel.estimation.filters.end_effector import EndEffectorModel

__all__ = [
    "FILTER_CYCLES",
    "QUATERNION_SLICE",
    "QUATERNION_NORM_TOLERANCE",
    "STRICT_FLAGS",
    "TIMING_BLOCK",
    "FilterTrace",
    "filter_record",
    "python_filter_run",
    "c_filter_run",
    "filter_checks",
    "filter_probes",
    "time_filters",
    "build_filter_program",
    "run_filter_program",
]

#: Steps of the default record (3 s at 1 kHz).
FILTER_CYCLES = 3000
#: The quaternion of the 19-D state ``[p, v, a, quaternion, w, alpha]`` (scalar first).
QUATERNION_SLICE = slice(9, 13)
#: Largest accepted ``| |quaternion| - 1 |`` of a C state.
QUATERNION_NORM_TOLERANCE = 1e-14
#: Steps per timed block of :func:`time_filters` (its ``best`` figure).
TIMING_BLOCK = 100
#: Sensor figures of the record (Cvitanic (2021), Table 7 order of magnitude): tracker
#: position [m], tracker orientation (quaternion components), gyro [rad/s], accelerometer [m/s^2].
POSITION_NOISE, QUATERNION_NOISE, GYRO_NOISE, ACCELEROMETER_NOISE = 6.4e-6, 1e-5, 1e-3, 0.012

_OK = STATUS_CODES["GT_OK"][0]


@dataclass(frozen=True)
class FilterTrace:
    """States and covariances of a filter run: the prior and one posterior per measurement.

    Parameters
    ----------
    status : numpy.ndarray of int, shape (N + 1,)
        Status of ``_init`` then of every ``_update`` (zeros for the Python run).
    x : numpy.ndarray, shape (N + 1, nx)
        ``x_0`` (the prior) and the posterior means ``x_{k|k}``.
    P : numpy.ndarray, shape (N + 1, nx, nx)
        ``P_0`` and the posterior covariances.
    """

    status: np.ndarray
    x: np.ndarray
    P: np.ndarray


def _sizes(controller: Controller, name: str) -> tuple[int, int]:
    if name not in controller.filter_sizes:
        raise InputError(f"name: the controller has no {name!r} (has {', '.join(controller.filter_sizes) or 'no filter'})")
    return controller.filter_sizes[name]


def filter_record(controller: Controller, name: str, cycles: int = FILTER_CYCLES, seed: int = 0) -> dict[str, np.ndarray]:
    """A measurement record of an end effector on a sine path, with the prior of the filter.

    Parameters
    ----------
    controller : Controller
        The controller (sizes of ``name``; sample time ``dt``).
    name : {"kf_step", "ekf_step"}
        The filter.
    cycles : int, optional
        Measurements.
    seed : int, optional
        Seed of :func:`numpy.random.default_rng` (sensor noise).

    Returns
    -------
    dict of str to numpy.ndarray
        ``"z"`` ``(cycles, nz)``: the measurement Function of
        :class:`~gtmodel.estimation.filters.end_effector.EndEffectorModel` (``dt``, the default
        IMU-to-target transform; the one graph of the filters) of a true motion, plus noise:
        the target on ``p_j = 10 mm sin(2 pi f_j t)`` (``f_j`` = 1, 0.8, 0.6 Hz) and (19-D)
        rotating by ``0.1 sin(pi t)`` rad about ``(1, 1, 1)/sqrt 3``; noise 6.4 um on the
        tracker position, 1e-5 per quaternion component (then normalised), 1e-3 rad/s on the
        gyro, 0.012 m/s^2 on the accelerometer (Table 7 order of magnitude at 1 kHz).
        ``"x0"`` ``(nx,)`` the true state at ``t = 0``;
        ``"P0"`` ``(nx, nx)`` diagonal: (0.1 mm)^2, (10 mm/s)^2, (0.1 m/s^2)^2, then
        (1e-3)^2, (0.01 rad/s)^2, (0.1 rad/s^2)^2.

    Raises
    ------
    InputError
        The controller has no ``name``; ``cycles`` not a positive integer; a size other
        than (9, 6) or (19, 13).
    """
    nx, nz = _sizes(controller, name)
    if isinstance(cycles, bool) or not isinstance(cycles, (int, np.integer)) or cycles < 1:
        raise InputError(f"cycles: expected a positive number of measurements, got {cycles!r}")
    if (nx, nz) not in ((9, 6), (19, 13)):
        raise InputError(f"{name}: no default record for nx = {nx}, nz = {nz} (the 3-axis 9/6 or the 19-D 19/13 model); "
                         "pass a record (z, x0, P0)")
    rng = np.random.default_rng(seed)
    t = np.arange(cycles + 1)[:, None] * controller.dt
    w = 2 * np.pi * np.array([1.0, 0.8, 0.6])
    x = [0.01 * np.sin(w * t), 0.01 * w * np.cos(w * t), -0.01 * w**2 * np.sin(w * t)]
    if nx == 19:
        u = np.ones(3) / np.sqrt(3.0)  # a rotation about a fixed axis: body rate = world rate = u theta'
        th, thd, thdd = 0.1 * np.sin(np.pi * t), 0.1 * np.pi * np.cos(np.pi * t), -0.1 * np.pi**2 * np.sin(np.pi * t)
        x += [np.hstack([np.cos(th / 2), np.sin(th / 2) * u]), thd * u, thdd * u]
    x = np.hstack(x)
    model = EndEffectorModel(controller.dt, rotation=nx == 19)
    z = np.asarray(model.measurement.map(cycles)(x[1:].T)).T
    std = {"position": POSITION_NOISE, "quaternion": QUATERNION_NOISE, "gyro": GYRO_NOISE, "accelerometer": ACCELEROMETER_NOISE}
    for key, sl in model.measurement_slices.items():
        z[:, sl] += rng.normal(0.0, std[key], (cycles, sl.stop - sl.start))
    if "quaternion" in model.measurement_slices:  # the tracker reports a unit quaternion
        sl = model.measurement_slices["quaternion"]
        z[:, sl] /= np.linalg.norm(z[:, sl], axis=1, keepdims=True)
    var = [1e-4**2] * 3 + [1e-2**2] * 3 + [0.1**2] * 3 + ([1e-3**2] * 4 + [1e-2**2] * 3 + [0.1**2] * 3 if nx == 19 else [])
    return {"z": z, "x0": x[0], "P0": np.diag(var)}


def python_filter_run(f: ca.Function, z: np.ndarray, x0: np.ndarray, P0: np.ndarray) -> FilterTrace:
    """The Python run of a filter step Function over a record (``mapaccum``, as one evaluation).

    Parameters
    ----------
    f : casadi.Function
        ``(x, P, z) -> (x_next, P_next, pivots)``.
    z : numpy.ndarray, shape (N, nz)
        Measurements.
    x0 : numpy.ndarray, shape (nx,)
        Prior mean.
    P0 : numpy.ndarray, shape (nx, nx)
        Prior covariance.

    Returns
    -------
    FilterTrace
        ``x``, ``P`` of the prior and every posterior; ``status`` zeros.
    """
    n, nx = len(z), x0.size
    xs, Ps, _ = f.mapaccum("run", n, 2)(x0, P0, np.asarray(z, float).T)
    x = np.vstack([x0, np.asarray(ca.DM(xs)).T])
    P = np.concatenate([P0[None], np.asarray(ca.DM(Ps)).reshape(nx, n, nx).transpose(1, 0, 2)])
    return FilterTrace(np.zeros(n + 1, dtype=int), x, P)


def c_filter_run(library: CompiledLibrary, name: str, z: np.ndarray, x0: np.ndarray, P0: np.ndarray) -> FilterTrace:
    """The C run over a record through ``<prefix>_<stem>_init`` / ``_update`` (state in a struct).

    Parameters
    ----------
    library : CompiledLibrary
        The loaded library.
    name : {"kf_step", "ekf_step"}
        The filter.
    z : numpy.ndarray, shape (N, nz)
        Measurements.
    x0 : numpy.ndarray, shape (nx,)
        Prior mean.
    P0 : numpy.ndarray, shape (nx, nx)
        Prior covariance.

    Returns
    -------
    FilterTrace
        Statuses and the struct's state after ``_init`` and after every ``_update``.
    """
    stem = name[:-5]
    dt = library[name].dtype
    nx = x0.size
    init, update = c_function(library, f"{stem}_init", 3), c_function(library, f"{stem}_update", 2)
    state = np.full(nx + nx * nx, SENTINEL, dtype=dt)  # the struct: x[nx] then P[nx*nx], no padding
    zs = np.ascontiguousarray(z, dtype=dt)
    x0c, P0c = np.ascontiguousarray(x0, dtype=dt), np.ascontiguousarray(P0, dtype=dt)
    out = np.zeros((len(z) + 1, state.size))
    status = np.zeros(len(z) + 1, dtype=int)
    status[0] = init(pointer(state), pointer(x0c), pointer(P0c))
    out[0] = state
    for i in range(len(z)):
        status[i + 1] = update(pointer(state), pointer(zs[i]))
        out[i + 1] = state
    return FilterTrace(status, out[:, :nx], out[:, nx:].reshape(-1, nx, nx))


def filter_checks(library: CompiledLibrary, controller: Controller, name: str, record: dict[str, np.ndarray],
                  real: str = "double") -> tuple[list[FunctionCheck], FilterTrace, FilterTrace]:
    """Compare the C filter with Python over a record: update chain, step on every Python state, quaternion norm.

    Parameters
    ----------
    library : CompiledLibrary
        The loaded library.
    controller : Controller
        The controller (the Python Function).
    name : {"kf_step", "ekf_step"}
        The filter.
    record : dict
        ``z``, ``x0``, ``P0`` (:func:`filter_record`).
    real : {"double", "float"}, optional
        Floating-point type of the library.

    Returns
    -------
    checks : list of FunctionCheck
        ``<stem>_update`` (every state and covariance of the C run), ``<name>`` (each step
        from the Python states) and, for a 19-D state, ``<stem>_update quaternion norm``.
    c_run, python_run : FilterTrace
        The two runs.
    """
    f = getattr(controller, name)
    stem = name[:-5]
    cf = library[name]
    tol = cf.spec.tolerance
    z, x0, P0 = record["z"], record["x0"], record["P0"]
    ref = python_filter_run(f, z, x0, P0)
    run = c_filter_run(library, name, z, x0, P0)
    n = len(z)
    flat = lambda r: np.hstack([r.x, r.P.reshape(len(r.x), -1)])  # noqa: E731
    status, (xn, Pn) = cf.call_rows(ref.x[:-1], ref.P[:-1].reshape(n, -1), z, fill=SENTINEL)
    good = status == _OK
    unit = cf.spec.unit
    checks = [
        run_check(f"{stem}_update", n, [(flat(run), flat(ref))], real, tol, unit, int(np.sum(run.status != _OK))),
        run_check(name, n, [(np.hstack([xn, Pn])[good], flat(ref)[1:][good])], real, tol, unit, int(np.sum(~good))),
    ]
    if x0.size == 19:
        dev = np.abs(np.linalg.norm(run.x[1:, QUATERNION_SLICE], axis=1) - 1.0)
        worst = float(dev.max()) if np.all(np.isfinite(dev)) else float("inf")
        qtol = FLOAT_RELATIVE_TOLERANCE if real == "float" else QUATERNION_NORM_TOLERANCE
        checks.append(FunctionCheck(f"{stem}_update quaternion norm", n, worst, qtol, "| |quat| - 1 |", 0, worst <= qtol))
    return checks, run, ref


def not_positive_definite(P0: np.ndarray) -> np.ndarray:
    """A covariance that is not positive definite: ``P0`` with its first variance negated.

    Parameters
    ----------
    P0 : numpy.ndarray, shape (nx, nx)
        A valid covariance (the record's prior).

    Returns
    -------
    numpy.ndarray
        The same with ``P[0, 0] = -P0[0, 0]`` (symmetric, one negative pivot; the first
        state is the measured x position, so also the innovation covariance is not PD).
    """
    P = np.array(P0, dtype=float)
    P[0, 0] = -abs(P[0, 0]) - 1.0
    return P


def filter_probes(library: CompiledLibrary, name: str, record: dict[str, np.ndarray]) -> list[StatusProbe]:
    """Status probes of one filter: NULL, NaN/Inf (``GT_BAD_ARGUMENT``), not PD (``GT_NUMERIC_ERROR``), outputs untouched.

    Parameters
    ----------
    library : CompiledLibrary
        The loaded library.
    name : {"kf_step", "ekf_step"}
        The filter.
    record : dict
        ``z``, ``x0``, ``P0``: the valid inputs the probes start from.

    Returns
    -------
    list of StatusProbe
        For ``<name>``, ``<stem>_init`` and ``<stem>_update``.
    """
    stem = name[:-5]
    dt = library[name].dtype
    nx = record["x0"].size
    step = c_function(library, name, 5)
    init, update = c_function(library, f"{stem}_init", 3), c_function(library, f"{stem}_update", 2)
    good = {"x": np.ascontiguousarray(record["x0"], dt), "P": np.ascontiguousarray(record["P0"], dt),
            "z": np.ascontiguousarray(record["z"][0], dt)}
    sentinel = np.asarray(SENTINEL, dt)

    def fresh(n):
        return np.full(n, SENTINEL, dt)

    def clean(*arrays):
        return all(a is None or np.all(a == sentinel) for a in arrays)

    def run_step(inputs, null=None):
        xo, Po = fresh(nx), fresh(nx * nx)
        ptrs = [pointer(inputs["x"]), pointer(inputs["P"]), pointer(inputs["z"]), pointer(xo), pointer(Po)]
        if null is not None:
            ptrs[null] = None
        return step(*ptrs), clean(xo, Po)

    probes = []
    for what, bad in (("NaN", np.nan), ("Inf", np.inf)):
        for arg in ("x", "P", "z"):
            inputs = {k: v.copy() for k, v in good.items()}
            inputs[arg][-1] = bad
            s, ok = run_step(inputs)
            probes.append(status_probe(name, f"{what} in {arg}", "GT_BAD_ARGUMENT", s, ok))
    for i, arg in enumerate(("x", "P", "z", "x_next", "P_next")):
        s, ok = run_step(good, null=i)
        probes.append(status_probe(name, f"NULL {arg}", "GT_BAD_ARGUMENT", s, ok))
    bad_P = np.ascontiguousarray(not_positive_definite(record["P0"]), dt)
    s, ok = run_step(dict(good, P=bad_P))
    probes.append(status_probe(name, "P not positive definite", "GT_NUMERIC_ERROR", s, ok))
    s, ok = run_step(dict(good, P=np.ascontiguousarray(-record["P0"], dt)))
    probes.append(status_probe(name, "P negative definite", "GT_NUMERIC_ERROR", s, ok))

    st = fresh(nx + nx * nx)
    probes.append(status_probe(f"{stem}_init", "NULL state", "GT_BAD_ARGUMENT", init(None, pointer(good["x"]), pointer(good["P"])), True))
    for case, x0, P0 in (("NULL x0", None, good["P"]), ("NULL P0", good["x"], None),
                         ("NaN in P0", good["x"], np.where(np.eye(nx, dtype=bool), np.nan, good["P"]).astype(dt))):
        st = fresh(nx + nx * nx)
        probes.append(status_probe(f"{stem}_init", case, "GT_BAD_ARGUMENT", init(pointer(st), pointer(x0), pointer(P0)), clean(st)))

    def state_of(x, P):
        return np.ascontiguousarray(np.concatenate([x.ravel(), P.ravel()]), dt)

    for case, state, z, expected in (
        ("NaN in z", state_of(good["x"], good["P"]), np.full(good["z"].size, np.nan, dt), "GT_BAD_ARGUMENT"),
        ("NULL z", state_of(good["x"], good["P"]), None, "GT_BAD_ARGUMENT"),
        ("NaN in the state", state_of(np.full(nx, np.nan), good["P"]), good["z"], "GT_BAD_ARGUMENT"),
        ("covariance not positive definite", state_of(good["x"], bad_P), good["z"], "GT_NUMERIC_ERROR"),
    ):
        before = state.copy()
        s = update(pointer(state), pointer(z))
        probes.append(status_probe(f"{stem}_update", case, expected, s, bool(np.array_equal(state, before, equal_nan=True))))
    probes.append(status_probe(f"{stem}_update", "NULL state", "GT_BAD_ARGUMENT", update(None, pointer(good["z"])), True))
    return probes


def time_filters(generated: GeneratedCode, library: Path, records: dict[str, dict[str, np.ndarray]], build_dir: str | Path,
                 budget_s: float = 0.1) -> dict[str, float]:
    """Time the filter steps in a C loop over their records (ns per step).

    Parameters
    ----------
    generated : GeneratedCode
        The library with the filters.
    library : pathlib.Path
        Its shared library.
    records : dict
        ``{name: record}`` (:func:`filter_record`): the measurements replayed from the prior
        (restarted at the end of the record).
    build_dir : str or pathlib.Path
        Folder for the timing program.
    budget_s : float, optional
        About this many seconds per function.

    Returns
    -------
    dict of str to float
        ``<name>`` (the array function, in place: ``x``, ``P`` fed back) and ``<stem>_update``
        (the state struct) -> ns per step, the mean over the loop; ``"<name> best"`` and
        ``"<stem>_update best"``: the fastest block of :data:`TIMING_BLOCK` consecutive steps
        (the step's own time, without the preemptions of a shared machine).

    Raises
    ------
    CodegenError
        The program failed to build or a timed step returned a non-OK status.
    """
    p, real = generated.prefix, generated.real
    tables, blocks = [], []
    for name, rec in records.items():
        stem, N = name[:-5], len(rec["z"])
        nx, nz = rec["x0"].size, rec["z"].shape[1]
        tables += [f"static const {real} Z_{stem}[{N}][{nz}] = {{{c_array(rec['z'], rows=True)}}};",
                   f"static const {real} X0_{stem}[{nx}] = {{{c_array(rec['x0'])}}};",
                   f"static const {real} P0_{stem}[{nx * nx}] = {{{c_array(rec['P0'])}}};"]
        for label, call in ((name, f"{p}_{name}(s.x, s.P, Z_{stem}[i % {N}], s.x, s.P)"), (f"{stem}_update", f"{p}_{stem}_update(&s, Z_{stem}[i % {N}])")):
            restart = f"if (i % {N} == 0) status |= {p}_{stem}_init(&s, X0_{stem}, P0_{stem});"
            block = (f"if (i % {TIMING_BLOCK} == 0) tb = now_ns(); status |= {call}; sink += s.x[0]; "
                     f"if (i % {TIMING_BLOCK} == {TIMING_BLOCK - 1}) {{ tb = (now_ns() - tb) / {TIMING_BLOCK}.0; if (tb < best) best = tb; }}")

            def loop(n: object, restart: str = restart, block: str = block) -> str:
                return f"for (i = 0; i < {n}; ++i) {{ {restart} {block} }}"
            blocks.append("\n".join([
                "    {",
                f"        {p}_{stem}_state s;",
                "        double tb = 0.0, best = 1e300;",
                f"        t0 = now_ns(); {loop(N)} t1 = now_ns();",
                f"        n = (long)({budget_s * 1e9} / ((t1 - t0) / {N}.0 + 1.0)); n = n < {N} ? {N} : (n / {N}) * {N};",
                "        best = 1e300;",
                f"        t0 = now_ns(); {loop('n')} t1 = now_ns();",
                f'        printf("{label}\\t%.3f\\t%.3f\\n", (t1 - t0) / (double)n, best);',
                "    }",
            ]))
    out = {}
    for label, mean, best in time_program(generated, library, f"{p}_filter_timing", blocks, build_dir, tables, "filter timing program"):
        out[label], out[f"{label} best"] = float(mean), float(best)
    return out


def build_filter_program(generated: GeneratedCode, name: str, record: dict[str, np.ndarray], build_dir: str | Path,
                         objects: tuple[Path, ...] | None = None) -> Path:
    """Build the stand-alone filter run program with :data:`STRICT_FLAGS` (library objects included).

    Parameters
    ----------
    generated : GeneratedCode
        The library with the filter.
    name : {"kf_step", "ekf_step"}
        The filter.
    record : dict
        ``z``, ``x0``, ``P0``, compiled into the program as constant tables.
    build_dir : str or pathlib.Path
        Folder for the objects and the program.
    objects : tuple of pathlib.Path or None, optional
        Objects of the generated sources already compiled (e.g. by
        :func:`~gtmodel.codegen.build.compile_shared` with ``werror=True,
        extra_flags=("-pedantic",)``: the same flags plus ``-fPIC``); None: compile them
        here with :data:`STRICT_FLAGS`.

    Returns
    -------
    pathlib.Path
        The executable: ``PROGRAM OUT.bin`` writes the run (``(N + 1) x (1 + nx + nx^2)``
        doubles: status, x, P row-major) and prints ``steps``, ``non-OK status``,
        ``heap calls in the filter``; exit 0 when every status is OK and no heap call happened.

    Raises
    ------
    CodegenError
        A compilation failed (the message holds the compiler output).
    """
    p, stem = generated.prefix, name[:-5]
    nx, nz = record["x0"].size, record["z"].shape[1]
    build = Path(build_dir)
    build.mkdir(parents=True, exist_ok=True)
    text = fill("template_filter_run.c", PREFIX=p, STEM=stem, HEADER=generated.header.name, N=len(record["z"]), REAL=generated.real,
                NX=nx, NZ=nz, NX2=nx * nx, Z=c_array(record["z"], rows=True), X0=c_array(record["x0"]), P0=c_array(record["P0"]))
    if objects is None:  # the library's sources, compiled here with the strict flags
        objects = strict_objects(generated, build)
    return compile_program(generated, f"{p}_{stem}_run", text, build, flags=STRICT_FLAGS, objects=tuple(objects), link_flags=(HEAP_WRAP,))


def run_filter_program(program: str | Path, out_file: str | Path, nx: int, valgrind: bool = False,
                       timeout: float = 600) -> tuple[subprocess.CompletedProcess, FilterTrace]:
    """Run the program of :func:`build_filter_program` (optionally under valgrind's memcheck) and read its run.

    Parameters
    ----------
    program : str or pathlib.Path
        The executable.
    out_file : str or pathlib.Path
        Binary file it writes.
    nx : int
        State size.
    valgrind : bool, optional
        Run under ``valgrind --tool=memcheck --error-exitcode=99 --leak-check=full``.
    timeout : float, optional
        Seconds.

    Returns
    -------
    proc : subprocess.CompletedProcess
        Exit code, stdout (the counts) and stderr (valgrind's report).
    run : FilterTrace
        Statuses, states and covariances written by the program (empty if none).
    """
    proc, data = run_record_program(program, out_file, 1 + nx + nx * nx, valgrind, timeout)
    return proc, FilterTrace(data[:, 0].astype(int), data[:, 1:1 + nx], data[:, 1 + nx:].reshape(-1, nx, nx))
