"""Self-check of generated C: compiled functions against the Python evaluation.

:func:`check` compiles the generated code (unless given a loaded library), evaluates
every generated C function through ctypes on ``n`` random valid inputs and compares the
outputs with the Python evaluation of the same model (the NumPy methods of
``GantryTau3Kinematics``, ``GantryTau3Dynamics``, ``SixLinkClosure``, ``F1Closure``, or
the CasADi Function itself for a function without such a method). It probes the edge
cases: poses on the workspace boundary (an arm stretched to ``(1 - 1e-9) L``: OK for the
IK and equal to Python, singular for the Jacobian-based functions), just beyond it, far
unreachable poses, singular poses, non-finite inputs and invalid configurations must give
the stated non-zero status and leave the outputs untouched (so they stay finite). Finally
it times every function in a small C program linked against the library (ns/call).
"""

from __future__ import annotations

import logging
from pathlib import Path
from typing import Any, Mapping

import numpy as np

from gtmodel.codegen.build import CompiledLibrary, compile_shared, load_library
from gtmodel.codegen.check.compare import compare, edge_probes, row_args, sample_inputs
from gtmodel.codegen.check.harness import HARNESS_FUNCTIONS, run_harness_unit_tests
from gtmodel.codegen.check.report import CheckReport, StatusProbe, with_timings
from gtmodel.codegen.check.run import time_program, timing_block
from gtmodel.codegen.declarations import FunctionSpec
from gtmodel.codegen.generate import robot_part
from gtmodel.codegen.writer import GeneratedCode
from gtmodel.errors import InputError

__all__ = ["check", "timed_rows", "time_functions"]

log = logging.getLogger("gtmodel")


def _c_literal(values, real: str) -> str:
    return ", ".join(f"{float(v)!r}" + ("f" if real == "float" else "") for v in np.ravel(values))


def _c_call(generated: GeneratedCode, spec: FunctionSpec, args: list, indent: str = "        ") -> tuple[list[str], str]:
    """C declarations of the argument/output buffers of one call, and the call expression.

    Inputs become ``static const`` arrays ``a<k>`` (NULL for a None optional argument),
    outputs ``o<k>``; a Newton function also gets ``int it``.
    """
    real = generated.real
    sizes_in, sizes_out = generated.signatures[spec.name]
    lines, call = [], []
    for k, (v, n) in enumerate(zip(args, sizes_in)):
        if n == 0:
            call.append(str(int(v)))
        elif v is None:
            call.append("NULL")
        else:
            lines.append(f"{indent}static const {real} a{k}[{n}] = {{{_c_literal(v, real)}}};")
            call.append(f"a{k}")
    for k, n in enumerate(sizes_out):
        lines.append(f"{indent}{real} o{k}[{n}];")
        call.append(f"o{k}")
    if spec.newton is not None:
        lines.append(f"{indent}int it;")
        call.append("&it")
    return lines, f"{generated.prefix}_{spec.name}({', '.join(call)})"


def timed_rows(generated: GeneratedCode, samples: Mapping[str, Mapping[str, np.ndarray]]) -> dict[str, tuple[FunctionSpec, list]]:
    """The sample rows a timing uses, by label.

    Parameters
    ----------
    generated : GeneratedCode
        What was generated.
    samples : Mapping
        Inputs per function (as from :func:`sample_inputs`).

    Returns
    -------
    dict of str to tuple of (FunctionSpec, list)
        Per function the first row with a warm start (label = the function name) and, for
        Newton functions with an optional warm start, the first row without one (label
        ``"<name> (default start)"``); the list holds the C arguments (None = NULL).
    """
    out = {}
    for spec in generated.specs:
        inp = samples[spec.name]
        rows: dict[bool, list] = {}
        for i in range(len(inp[spec.args[0].name])):
            args = row_args(spec, inp, i)
            rows.setdefault(any(a.optional and v is None for a, v in zip(spec.args, args)), args)
            if len(rows) == 2:
                break
        if False in rows:
            out[spec.name] = (spec, rows[False])
        if True in rows:
            out[f"{spec.name} (default start)" if False in rows else spec.name] = (spec, rows[True])
    return out


def time_functions(generated: GeneratedCode, library: Path, samples: Mapping[str, Mapping[str, np.ndarray]], build_dir: Path, budget_s: float = 0.05) -> dict[str, float]:
    """Time every generated function in a C loop linked against the shared library.

    Parameters
    ----------
    generated : GeneratedCode
        What was generated.
    library : pathlib.Path
        The shared library (``lib<prefix>.so``).
    samples : Mapping
        Inputs per function (as from :func:`sample_inputs`); the first row with a warm
        start (if any) is timed, and for Newton functions with a warm start also the
        first row without one (label ``"<name> (default start)"``).
    build_dir : pathlib.Path
        Folder for the timing program.
    budget_s : float, optional
        About this many seconds of calls per function.

    Returns
    -------
    dict of str to float
        Label -> mean time per call [ns].

    Raises
    ------
    CodegenError
        The timing program failed to build or a timed call returned a non-OK status.
    """
    blocks = []
    for label, (spec, args) in timed_rows(generated, samples).items():
        decl, c = _c_call(generated, spec, args)
        blocks.append(timing_block(label, decl, f"status |= {c}; sink += o0[0];", budget_s, calibration=100))
    rows = time_program(generated, library, f"{generated.prefix}_timing", blocks, build_dir)
    return {k: float(v) for k, v in rows}


# ----------------------------------------------------------------------------- API
def check(
    generated: GeneratedCode,
    n: int = 1000,
    seed: int = 0,
    library: CompiledLibrary | None = None,
    build_dir: str | Path | None = None,
    timing: bool = False,
) -> CheckReport:
    """Compile the generated C and compare it with the Python evaluation of the model.

    Parameters
    ----------
    generated : GeneratedCode
        Result of :func:`gtmodel.codegen.generate`.
    n : int, optional
        Number of random valid inputs per function (default 1000); see :func:`sample_inputs`.
    seed : int, optional
        Seed of the random generator (default 0).
    library : CompiledLibrary or None, optional
        An already loaded library; compiled with :func:`compile_shared` if None.
    build_dir : str or pathlib.Path or None, optional
        Build folder when compiling or timing (default ``<out_dir>/build``).
    timing : bool, optional
        Also time every function in a C loop (ns/call, :func:`time_functions`) and build
        and run the C unit-test program of the harness shipped with the package
        (:func:`run_harness_unit_tests`; a harness that applies but cannot run fails the
        check).

    Returns
    -------
    CheckReport
        Per robot-model function (the controller functions of a library generated with
        ``controller=`` are checked by
        :func:`~gtmodel.codegen.check.controller.check_controller`) the largest ``|C - Python|`` against its tolerance (``IK_TOLERANCE``,
        ``FK_TOLERANCE`` = 1e-12 m, ``JACOBIAN_TOLERANCE`` = 1e-12,
        ``INVERSE_DYNAMICS_TOLERANCE`` = 1e-9 N or 1e-9 relative; single precision:
        ``FLOAT_RELATIVE_TOLERANCE``), the edge-case probes and the timings. A failed
        check is a report with ``passed == False``, not an exception.

    Raises
    ------
    InputError
        ``n`` is not a positive integer.
    CompilerNotFoundError
        No C compiler.
    CodegenError
        Compilation failed, or no valid inputs could be sampled.
    """
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 1:
        raise InputError(f"n: expected a positive number of poses, got {n!r}")
    build = Path(build_dir) if build_dir is not None else generated.out_dir / "build"
    generated = robot_part(generated)  # the controller functions: check.controller.check_controller
    if library is None:
        library = load_library(generated, compile_shared(generated, build))
    model = generated.model()
    data = sample_inputs(generated, int(n), seed, model)
    results = []
    probes: list[StatusProbe] = []
    cache: dict[str, Any] = {}
    for spec in generated.specs:
        cf = library[spec.name]
        inputs = data[spec.name]
        results.append(compare(spec, cf, model, inputs, generated.real))
        log.debug("codegen check: %s", results[-1])
        probes += edge_probes(generated, spec, cf, model, inputs, cache)
    extra: dict[str, float] = {}
    if timing:
        times = time_functions(generated, library.path, data, build)
        results = with_timings(results, times)
        extra = {k: v for k, v in times.items() if k not in generated.functions}
    harness = run_harness_unit_tests(generated, build / "harness") if timing else None
    if timing and harness is None:
        harness = (None, "not applicable (the harness tests a 3-link library in double precision with all of "
                   + ", ".join(HARNESS_FUNCTIONS) + ")")
    report = CheckReport(
        robot=generated.robot_name,
        prefix=generated.prefix,
        n=int(n),
        seed=seed,
        functions=tuple(results),
        probes=tuple(probes),
        version=library.version(),
        library=library.path,
        timings=extra,
        harness=harness[1] if harness else "",
        harness_passed=harness[0] if harness else None,
    )
    log.info("codegen check of %s: %s", generated.prefix, "passed" if report.passed else "FAILED")
    return report
