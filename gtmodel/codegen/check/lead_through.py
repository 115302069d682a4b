"""Self-check of the generated lead-through controller step over a whole recorded run (Dressler (2012), ch. 8).

The C and Python are fed the SAME record of handle and tool wrenches and nominal normals
(default: :func:`lead_through_record`, a scripted lead-through session; or the inputs of a
simulated run, ``surface_tracking.csv`` of the ``lead_through`` kind) and compared on
every sample:

- ``lead_through_update`` (the state struct) run in C over the whole record, its state fed
  back by the C code, against the Python run (the step Function's ``mapaccum``): every
  state, ``V_tool`` and ``n``;
- ``lead_through_step`` (the array function) on every Python state;

then the status contract is probed (NULL pointers, NaN/Inf wrenches or state, a nominal
normal that is not of unit norm: ``GT_BAD_ARGUMENT``, outputs and state untouched).
:func:`build_lead_through_program` writes a stand-alone C program running the record
through ``_init``/``_update`` with the strict flags and a heap-call counter, for valgrind.
"""

from __future__ import annotations

import subprocess
from pathlib import Path

import casadi as ca
import numpy as np

from gtmodel.codegen.build import CompiledLibrary
from gtmodel.codegen.check.filter import TIMING_BLOCK
from gtmodel.codegen.check.report import SENTINEL, FunctionCheck, StatusProbe, run_check, status_probe
from gtmodel.codegen.check.run import (HEAP_WRAP, STRICT_FLAGS, c_array, c_function, compile_program, pointer, run_record_program,
                                       strict_objects, time_program)
from gtmodel.codegen.controller import Controller
from gtmodel.codegen.declarations import STATUS_CODES
from gtmodel.codegen.emit import fill
from gtmodel.codegen.writer import GeneratedCode
from gtmodel.errors import InputError

__all__ = ["LEAD_THROUGH_CYCLES", "lead_through_record", "check_record", "python_lead_through_run", "c_lead_through_run",
           "lead_through_checks", "lead_through_probes", "time_lead_through", "build_lead_through_program",
           "run_lead_through_program"]

#: Samples of the default record (8 s at 4 ms).
LEAD_THROUGH_CYCLES = 2000

_OK = STATUS_CODES["GT_OK"][0]


def lead_through_record(cycles: int = LEAD_THROUGH_CYCLES, seed: int = 0, normal=(0.0, 0.0, -1.0)) -> dict[str, np.ndarray]:
    """A scripted lead-through session: approach, contact, guided motion, tilted contact, release.

    Per sample, the operator's handle force pushes along the normal (first tenth), then
    along the surface; the tool force rises to 2 N along the normal once in contact, with
    the force direction tilted by up to 8 degrees (the normal estimate of eq. 8.10 then
    switches), a pull of 15 N off the surface in the eighth tenth, and free space at the
    end; 0.05 N (0.5 mN m) noise on every component.

    Parameters
    ----------
    cycles : int, optional
        Samples.
    seed : int, optional
        Noise seed.
    normal : array_like, shape (3,), optional
        Nominal normal (unit) given to every step.

    Returns
    -------
    dict of str to numpy.ndarray
        ``"F_h"``, ``"F_t"`` ``(cycles, 6)``, ``"n_n"`` ``(cycles, 3)``, ``"x0"`` ``(8,)`` zeros.

    Raises
    ------
    InputError
        ``cycles`` below 10.
    """
    if isinstance(cycles, bool) or not isinstance(cycles, (int, np.integer)) or cycles < 10:
        raise InputError(f"cycles: expected at least 10 samples, got {cycles!r}")
    rng = np.random.default_rng(seed)
    n = np.asarray(normal, dtype=float)
    t = np.linspace(0.0, 1.0, cycles)
    tangent = np.array([1.0, 0.0, 0.0]) - n[0] * n
    tangent /= np.linalg.norm(tangent)
    side = np.cross(n, tangent)
    F_h = np.zeros((cycles, 6))
    F_t = np.zeros((cycles, 6))
    F_h[:, :3] = np.where((t < 0.1)[:, None], 3.0 * n, 2.0 * tangent + 0.5 * np.sin(9 * t)[:, None] * side)
    F_h[(t >= 0.7) & (t < 0.8), :3] = -15.0 * n
    contact = (t >= 0.08) & (t < 0.75)
    tilt = np.radians(8.0) * np.sin(2 * np.pi * 3 * t)
    direction = np.cos(tilt)[:, None] * n + np.sin(tilt)[:, None] * tangent
    magnitude = np.where(contact, 2.0 * np.clip((t - 0.08) / 0.02, 0.0, 1.0), 0.0)
    F_t[:, :3] = magnitude[:, None] * direction
    F_t[:, 3:] = 0.02 * np.sin(5 * t)[:, None] * contact[:, None]
    scale = np.array([1, 1, 1, 0.01, 0.01, 0.01])
    F_h += 0.05 * scale * rng.standard_normal(F_h.shape)
    F_t += 0.05 * scale * rng.standard_normal(F_t.shape)
    return {"F_h": F_h, "F_t": F_t, "n_n": np.tile(n, (cycles, 1)), "x0": np.zeros(8)}


def check_record(record: dict) -> dict[str, np.ndarray]:
    """Validate a record: ``F_h``, ``F_t`` ``(N, 6)``, ``n_n`` ``(N, 3)`` unit rows, ``x0`` ``(8,)``, finite.

    Parameters
    ----------
    record : dict
        The record.

    Returns
    -------
    dict of str to numpy.ndarray
        The arrays as floats.

    Raises
    ------
    InputError
        A missing key, a wrong shape, a non-finite value, a normal not of unit norm.
    """
    if not isinstance(record, dict):
        raise InputError(f"record: expected a dict with F_h, F_t, n_n, x0, got {type(record).__name__}")
    out = {}
    n = None
    for key, width in (("F_h", 6), ("F_t", 6), ("n_n", 3), ("x0", None)):
        if key not in record:
            raise InputError(f"record: missing {key!r}")
        v = np.asarray(record[key], dtype=float)
        ok = v.shape == (8,) if width is None else (v.ndim == 2 and v.shape[1] == width and len(v) > 0 and (n is None or len(v) == n))
        if not ok or not np.all(np.isfinite(v)):
            raise InputError(f"record[{key!r}]: expected finite values of shape {'(8,)' if width is None else f'(N, {width})'}, got {v.shape}")
        if width is not None:
            n = len(v)
        out[key] = v
    if np.any(np.abs(np.linalg.norm(out["n_n"], axis=1) - 1.0) > 1e-6):
        raise InputError("record['n_n']: expected unit normals")
    return out


def python_lead_through_run(f: ca.Function, record: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    """The Python run of the step Function over a record (``mapaccum``, one evaluation).

    Parameters
    ----------
    f : casadi.Function
        The lead-through step.
    record : dict
        ``F_h``, ``F_t``, ``n_n``, ``x0``.

    Returns
    -------
    dict of str to numpy.ndarray
        ``"x"`` ``(N + 1, 8)`` (the initial state first), ``"V_tool"`` ``(N, 6)``, ``"n"`` ``(N, 3)``.
    """
    N = len(record["F_h"])
    xs, v, n, _ = f.mapaccum("run", N)(record["x0"], record["F_h"].T, record["F_t"].T, record["n_n"].T)
    return {"x": np.vstack([record["x0"], np.asarray(ca.DM(xs)).T]), "V_tool": np.asarray(ca.DM(v)).T, "n": np.asarray(ca.DM(n)).T}


def c_lead_through_run(library: CompiledLibrary, record: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    """The C run over a record through ``<prefix>_lead_through_init`` / ``_update`` (state in a struct).

    Parameters
    ----------
    library : CompiledLibrary
        The loaded library.
    record : dict
        ``F_h``, ``F_t``, ``n_n`` (``x0`` must be zeros: ``_init`` starts at rest).

    Returns
    -------
    dict of str to numpy.ndarray
        ``"status"`` ``(N + 1,)`` (``_init`` then every ``_update``), ``"x"``, ``"V_tool"``, ``"n"``.
    """
    dt = library["lead_through_step"].dtype
    init, update = c_function(library, "lead_through_init", 1), c_function(library, "lead_through_update", 6)
    state = np.full(8, SENTINEL, dtype=dt)
    arrays = {k: np.ascontiguousarray(record[k], dtype=dt) for k in ("F_h", "F_t", "n_n")}
    N = len(arrays["F_h"])
    v, n = np.zeros(6, dtype=dt), np.zeros(3, dtype=dt)
    out = {"status": np.zeros(N + 1, dtype=int), "x": np.zeros((N + 1, 8)), "V_tool": np.zeros((N, 6)), "n": np.zeros((N, 3))}
    out["status"][0] = init(pointer(state))
    out["x"][0] = state
    for i in range(N):
        out["status"][i + 1] = update(pointer(state), pointer(arrays["F_h"][i]), pointer(arrays["F_t"][i]), pointer(arrays["n_n"][i]),
                                      pointer(v), pointer(n))
        out["x"][i + 1], out["V_tool"][i], out["n"][i] = state, v, n
    return out


def lead_through_checks(library: CompiledLibrary, controller: Controller, record: dict[str, np.ndarray],
                        real: str = "double") -> list[FunctionCheck]:
    """Compare the C step with Python over a record: the update chain and the step on every Python state.

    Parameters
    ----------
    library : CompiledLibrary
        The loaded library.
    controller : Controller
        The controller (the Python Function).
    record : dict
        ``F_h``, ``F_t``, ``n_n``, ``x0`` (:func:`check_record`; ``x0`` zeros).
    real : {"double", "float"}, optional
        Floating-point type of the library.

    Returns
    -------
    list of FunctionCheck
        ``lead_through_update`` (every state, ``V_tool`` and ``n`` of the C run) and
        ``lead_through_step`` (each step from the Python states).
    """
    cf = library["lead_through_step"]
    tol, unit = cf.spec.tolerance, cf.spec.unit
    ref = python_lead_through_run(controller.lead_through_step, record)
    run = c_lead_through_run(library, record)
    N = len(record["F_h"])
    flat = lambda r: np.hstack([r["x"][1:], r["V_tool"], r["n"]])  # noqa: E731
    status, (xn, v, n) = cf.call_rows(ref["x"][:-1], record["F_h"], record["F_t"], record["n_n"], fill=SENTINEL)
    good = status == _OK
    return [
        run_check("lead_through_update", N, [(flat(run), flat(ref)), (run["x"][0], ref["x"][0])], real, tol, unit,
                  int(np.sum(run["status"] != _OK))),
        run_check("lead_through_step", N, [(np.hstack([xn, v, n])[good], flat(ref)[good])], real, tol, unit, int(np.sum(~good))),
    ]


def lead_through_probes(library: CompiledLibrary, record: dict[str, np.ndarray]) -> list[StatusProbe]:
    """Status probes: NULL, NaN/Inf wrenches and state, a non-unit or zero normal (``GT_BAD_ARGUMENT``), outputs untouched.

    Parameters
    ----------
    library : CompiledLibrary
        The loaded library.
    record : dict
        The valid inputs the probes start from (its first sample).

    Returns
    -------
    list of StatusProbe
        For ``lead_through_step``, ``lead_through_init`` and ``lead_through_update``.
    """
    dt = library["lead_through_step"].dtype
    step = c_function(library, "lead_through_step", 7)
    init, update = c_function(library, "lead_through_init", 1), c_function(library, "lead_through_update", 6)
    good = {"x": np.ascontiguousarray(record["x0"], dt), "F_h": np.ascontiguousarray(record["F_h"][0], dt),
            "F_t": np.ascontiguousarray(record["F_t"][0], dt), "n_n": np.ascontiguousarray(record["n_n"][0], dt)}
    sentinel = np.asarray(SENTINEL, dt)

    def clean(*arrays):
        return all(a is None or np.all(a == sentinel) for a in arrays)

    def run_step(inputs, null=None):
        outs = [np.full(k, SENTINEL, dt) for k in (8, 6, 3)]
        ptrs = [pointer(inputs[k]) for k in ("x", "F_h", "F_t", "n_n")] + [pointer(o) for o in outs]
        if null is not None:
            ptrs[null] = None
        return step(*ptrs), clean(*[o for i, o in enumerate(outs) if null != 4 + i])

    probes = []
    bad_inputs = [(f"{what} in {arg}", arg, value) for what, value in (("NaN", np.nan), ("Inf", np.inf)) for arg in ("x", "F_h", "F_t")]
    bad_inputs += [("n_n of norm 1.01", "n_n", None), ("zero n_n", "n_n", 0.0)]
    for case, arg, value in bad_inputs:
        inputs = {k: v.copy() for k, v in good.items()}
        if case.startswith("n_n of norm"):
            inputs["n_n"] = (inputs["n_n"] * 1.01).astype(dt)
        elif arg == "n_n":
            inputs["n_n"][:] = 0.0
        else:
            inputs[arg][-1] = value
        s, ok = run_step(inputs)
        probes.append(status_probe("lead_through_step", case, "GT_BAD_ARGUMENT", s, ok))
    for i, arg in enumerate(("x", "F_h", "F_t", "n_n", "x_next", "V_tool", "n")):
        s, ok = run_step(good, null=i)
        probes.append(status_probe("lead_through_step", f"NULL {arg}", "GT_BAD_ARGUMENT", s, ok))
    probes.append(status_probe("lead_through_init", "NULL state", "GT_BAD_ARGUMENT", init(None), True))
    for case, state, F_t, n_n in (("NaN in F_t", good["x"], np.full(6, np.nan, dt), good["n_n"]),
                                  ("n_n not unit", good["x"], good["F_t"], (good["n_n"] * 2).astype(dt)),
                                  ("NaN in the state", np.full(8, np.nan, dt), good["F_t"], good["n_n"])):
        st = np.ascontiguousarray(state, dt).copy()
        before = st.copy()
        v, n = np.full(6, SENTINEL, dt), np.full(3, SENTINEL, dt)
        s = update(pointer(st), pointer(good["F_h"]), pointer(F_t), pointer(n_n), pointer(v), pointer(n))
        probes.append(status_probe("lead_through_update", case, "GT_BAD_ARGUMENT", s,
                                   bool(np.array_equal(st, before, equal_nan=True)) and clean(v, n)))
    return probes


def _tables(record: dict[str, np.ndarray], real: str) -> list[str]:
    N = len(record["F_h"])
    return [f"#define LT_N {N}",
            f"static const {real} FH[{N}][6] = {{{c_array(record['F_h'], rows=True)}}};",
            f"static const {real} FT[{N}][6] = {{{c_array(record['F_t'], rows=True)}}};",
            f"static const {real} NN[{N}][3] = {{{c_array(record['n_n'], rows=True)}}};"]


def time_lead_through(generated: GeneratedCode, library: Path, record: dict[str, np.ndarray], build_dir: str | Path,
                      budget_s: float = 0.1) -> dict[str, float]:
    """Time ``lead_through_update`` in a C loop over the record (ns per step).

    Parameters
    ----------
    generated : GeneratedCode
        The library with the step.
    library : pathlib.Path
        Its shared library.
    record : dict
        The inputs replayed (restarted from rest at the end of the record).
    build_dir : str or pathlib.Path
        Folder for the timing program.
    budget_s : float, optional
        About this many seconds.

    Returns
    -------
    dict of str to float
        ``"lead_through_update"``: mean ns per step; ``"lead_through_update best"``: the
        fastest block of :data:`TIMING_BLOCK` consecutive steps.

    Raises
    ------
    CodegenError
        The program failed to build or a timed step returned a non-OK status.
    """
    p = generated.prefix
    N = len(record["F_h"])
    restart = f"if (i % {N} == 0) status |= {p}_lead_through_init(&s);"
    call = f"{p}_lead_through_update(&s, FH[i % {N}], FT[i % {N}], NN[i % {N}], v, nv)"
    block = (f"if (i % {TIMING_BLOCK} == 0) tb = now_ns(); status |= {call}; sink += v[0]; "
             f"if (i % {TIMING_BLOCK} == {TIMING_BLOCK - 1}) {{ tb = (now_ns() - tb) / {TIMING_BLOCK}.0; if (tb < best) best = tb; }}")

    def loop(n: object) -> str:
        return f"for (i = 0; i < {n}; ++i) {{ {restart} {block} }}"

    text = "\n".join([
        "    {",
        f"        {p}_lead_through_state s;",
        f"        {generated.real} v[6], nv[3];",
        "        double tb = 0.0, best = 1e300;",
        f"        t0 = now_ns(); {loop(N)} t1 = now_ns();",
        f"        n = (long)({budget_s * 1e9} / ((t1 - t0) / {N}.0 + 1.0)); n = n < {N} ? {N} : (n / {N}) * {N};",
        "        best = 1e300;",
        f"        t0 = now_ns(); {loop('n')} t1 = now_ns();",
        '        printf("lead_through_update\\t%.3f\\t%.3f\\n", (t1 - t0) / (double)n, best);',
        "    }",
    ])
    out = {}
    for label, mean, best in time_program(generated, library, f"{p}_lead_through_timing", [text], build_dir,
                                          _tables(record, generated.real), "lead-through timing program"):
        out[label], out[f"{label} best"] = float(mean), float(best)
    return out


def build_lead_through_program(generated: GeneratedCode, record: dict[str, np.ndarray], build_dir: str | Path) -> Path:
    """Build the stand-alone run of the record through ``_init``/``_update`` with :data:`STRICT_FLAGS`.

    Parameters
    ----------
    generated : GeneratedCode
        The library with the step.
    record : dict
        ``F_h``, ``F_t``, ``n_n``, compiled into the program as constant tables.
    build_dir : str or pathlib.Path
        Folder for the objects and the program.

    Returns
    -------
    pathlib.Path
        The executable: ``PROGRAM OUT.bin`` writes per step the status, the state, ``V_tool``
        and ``n`` (18 doubles) and prints ``steps``, ``non-OK status``, ``heap calls in the
        controller``; exit 0 when every status is OK and no heap call happened.

    Raises
    ------
    CodegenError
        A compilation failed.
    """
    p = generated.prefix
    build = Path(build_dir)
    build.mkdir(parents=True, exist_ok=True)
    text = fill("template_lead_through_run.c", PREFIX=p, HEADER=generated.header.name, REAL=generated.real,
                TABLES="\n".join(_tables(record, generated.real)))
    return compile_program(generated, f"{p}_lead_through_run", text, build, flags=STRICT_FLAGS,
                           objects=strict_objects(generated, build), link_flags=(HEAP_WRAP,))


def run_lead_through_program(program: str | Path, out_file: str | Path, valgrind: bool = False,
                             timeout: float = 600) -> tuple[subprocess.CompletedProcess, np.ndarray]:
    """Run the program of :func:`build_lead_through_program` (optionally under valgrind's memcheck).

    Parameters
    ----------
    program : str or pathlib.Path
        The executable.
    out_file : str or pathlib.Path
        Binary file it writes.
    valgrind : bool, optional
        Run under ``valgrind --tool=memcheck --error-exitcode=99 --leak-check=full``.
    timeout : float, optional
        Seconds.

    Returns
    -------
    proc : subprocess.CompletedProcess
        Exit code, stdout (the counts) and stderr (valgrind's report).
    rows : numpy.ndarray, shape (N, 18)
        Per step: status, state (8), ``V_tool`` (6), ``n`` (3).
    """
    return run_record_program(program, out_file, 18, valgrind, timeout)
