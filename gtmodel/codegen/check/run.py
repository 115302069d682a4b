"""The one way the self-checks build and run a C program against a generated library.

:func:`compile_program` writes a C source, compiles it through
:func:`gtmodel._compiler.run_compiler` with the build flags of the library
(:data:`~gtmodel.codegen.build.COMMON_FLAGS` and the wrapper warnings, or the caller's
flags) and links it; :func:`run_program` runs it and parses its tab-separated output;
:func:`time_program` does both for a timing program from the template
``harness/template_timer.c`` whose blocks come from :func:`timing_block` (or the caller's
own). The checks of the robot functions, the controller and the KF/EKF steps all time
through here.
"""

from __future__ import annotations

import ctypes
import logging
import subprocess
from pathlib import Path
from typing import Sequence

import numpy as np

from gtmodel._compiler import find_compiler, run_child, run_compiler
from gtmodel.codegen.build import COMMON_FLAGS, WRAPPER_WARNINGS, CompiledLibrary
from gtmodel.codegen.emit import fill, harness_dir
from gtmodel.codegen.writer import GeneratedCode
from gtmodel.errors import CodegenError

__all__ = ["PROGRAM_FLAGS", "STRICT_FLAGS", "HEAP_WRAP", "compile_program", "strict_objects", "run_program", "run_record_program",
           "time_program", "timing_block", "c_function", "pointer", "c_array"]

log = logging.getLogger("gtmodel")

#: Flags of a check program: the library's own (:data:`~gtmodel.codegen.build.COMMON_FLAGS`) and its warnings.
PROGRAM_FLAGS = (*COMMON_FLAGS, *WRAPPER_WARNINGS)
#: Compiler flags of a stand-alone run program (the KF/EKF steps', the lead-through step's) and
#: of the library objects it links (:func:`strict_objects`).
STRICT_FLAGS = ("-std=c99", "-O2", "-Wall", "-Wextra", "-Werror", "-pedantic")
#: Link flag of a stand-alone run program: the heap calls go through the counter of ``harness/heap_watch.h``.
HEAP_WRAP = "-Wl,--wrap=malloc,--wrap=calloc,--wrap=realloc,--wrap=free"


def compile_program(generated: GeneratedCode, name: str, text: str, build_dir: str | Path, *, library: Path | None = None,
                    flags: Sequence[str] = PROGRAM_FLAGS, objects: Sequence[Path] = (), link_flags: Sequence[str] = ()) -> Path:
    """Write a C program and build it against the generated code.

    Parameters
    ----------
    generated : GeneratedCode
        The generated library (its folder is on the include path, with the harness folder).
    name : str
        File stem: the source is ``<build_dir>/<name>.c``, the program ``<build_dir>/<name>``.
    text : str
        The C source.
    build_dir : str or pathlib.Path
        Folder for the source, objects and program (created if missing).
    library : pathlib.Path or None, optional
        Shared library ``lib<prefix>.so`` to link (with an rpath to its folder); None:
        link ``objects`` instead.
    flags : sequence of str, optional
        Compiler flags (default :data:`PROGRAM_FLAGS`).
    objects : sequence of pathlib.Path, optional
        Objects linked into the program (with ``library`` None).
    link_flags : sequence of str, optional
        More flags of the link step (e.g. ``-Wl,--wrap=malloc``).

    Returns
    -------
    pathlib.Path
        The program.

    Raises
    ------
    CompilerNotFoundError
        No C compiler.
    CodegenError
        The program failed to compile or link (the message holds the compiler output).
    """
    build = Path(build_dir)
    build.mkdir(parents=True, exist_ok=True)
    src = build / f"{name}.c"
    src.write_text(text)
    exe = build / name
    inc = ["-I", str(generated.out_dir), "-I", str(harness_dir())]
    cc = find_compiler()
    if library is not None:
        run_compiler([*cc, *flags, *inc, str(src), "-o", str(exe), "-L", str(library.parent), f"-l{generated.prefix}",
                      f"-Wl,-rpath,{library.parent}", *link_flags, "-lm"], f"building {src.name}")
        return exe
    obj = build / (src.stem + ".strict.o")
    run_compiler([*cc, *flags, *inc, "-c", str(src), "-o", str(obj)], f"compiling {src.name} with {' '.join(flags)}")
    run_compiler([*cc, *map(str, objects), str(obj), *link_flags, "-lm", "-o", str(exe)], f"linking {exe.name}")
    return exe


def strict_objects(generated: GeneratedCode, build_dir: str | Path) -> tuple[Path, ...]:
    """Compile the generated library's sources to objects with :data:`STRICT_FLAGS` (no ``-fPIC``).

    Parameters
    ----------
    generated : GeneratedCode
        The generated library.
    build_dir : str or pathlib.Path
        Folder for the objects ``<source stem>.strict.o`` (it must exist).

    Returns
    -------
    tuple of pathlib.Path
        The objects, in the order of ``generated.c_sources``.

    Raises
    ------
    CodegenError
        A compilation failed (the message holds the compiler output).
    """
    cc = find_compiler()
    objects = []
    for c_file in generated.c_sources:
        obj = Path(build_dir) / (c_file.stem + ".strict.o")
        run_compiler([*cc, *STRICT_FLAGS, "-I", str(generated.out_dir), "-c", str(c_file), "-o", str(obj)],
                     f"compiling {c_file.name} with {' '.join(STRICT_FLAGS)}")
        objects.append(obj)
    return tuple(objects)


def run_program(program: Path, what: str, timeout: float = 600) -> list[list[str]]:
    """Run a check program and parse its output.

    Parameters
    ----------
    program : pathlib.Path
        The program (:func:`compile_program`).
    what : str
        What it is, for the message of a failure.
    timeout : float, optional
        Seconds.

    Returns
    -------
    list of list of str
        Per output line its tab-separated fields.

    Raises
    ------
    CodegenError
        The program exited with a non-zero code (a call returned a non-OK status) or did
        not finish in time.
    """
    try:
        run = run_child([str(program)], timeout=timeout)
    except subprocess.TimeoutExpired:
        raise CodegenError(f"{what}: did not finish within {timeout:g} s") from None
    if run.returncode != 0:
        raise CodegenError(f"{what}: a timed call returned a non-OK status")
    return [line.split("\t") for line in run.stdout.strip().splitlines()]


def timing_block(label: str, decl: Sequence[str], call: str, budget_s: float, calibration: int = 100) -> str:
    """One block of a timing program: ``calibration`` calls, then about ``budget_s`` seconds of calls.

    Parameters
    ----------
    label : str
        First field of the printed line ``label<TAB>ns per call``.
    decl : sequence of str
        Declarations and set-up statements of the block (indented lines).
    call : str
        The statement(s) timed, e.g. ``"status |= gt_L1_ik(a0, 0, o0); sink += o0[0];"``.
    budget_s : float
        About this many seconds of calls.
    calibration : int, optional
        Calls of the first (calibrating) loop and the least number timed.

    Returns
    -------
    str
        C lines.
    """
    c = calibration
    return "\n".join([
        "    {",
        *decl,
        f"        t0 = now_ns(); for (i = 0; i < {c}; ++i) {{ {call} }} t1 = now_ns();",
        f"        n = (long)({budget_s * 1e9} / ((t1 - t0) / {c}.0 + 1.0)); if (n < {c}) n = {c};",
        f"        t0 = now_ns(); for (i = 0; i < n; ++i) {{ {call} }} t1 = now_ns();",
        f'        printf("{label}\\t%.3f\\n", (t1 - t0) / (double)n);',
        "    }",
    ])


def run_record_program(program: str | Path, out_file: str | Path, width: int, valgrind: bool = False,
                       timeout: float = 600) -> tuple[subprocess.CompletedProcess, np.ndarray]:
    """Run a stand-alone run program (optionally under valgrind's memcheck) and read the rows it writes.

    Parameters
    ----------
    program : str or pathlib.Path
        The executable, called as ``PROGRAM OUT_FILE``.
    out_file : str or pathlib.Path
        Binary file of float64 rows it writes.
    width : int
        Doubles per row.
    valgrind : bool, optional
        Run under ``valgrind --tool=memcheck --error-exitcode=99 --leak-check=full``.
    timeout : float, optional
        Seconds.

    Returns
    -------
    proc : subprocess.CompletedProcess
        Exit code, stdout and stderr (valgrind's report).
    rows : numpy.ndarray, shape (N, width)
        The complete rows written (none if the file is missing).
    """
    cmd = [str(program), str(out_file)]
    if valgrind:
        cmd = ["valgrind", "--tool=memcheck", "--error-exitcode=99", "--leak-check=full", *cmd]
    proc = run_child(cmd, timeout=timeout)
    data = np.fromfile(out_file, dtype=np.float64) if Path(out_file).is_file() else np.zeros(0)
    return proc, data[: data.size // width * width].reshape(-1, width)


def time_program(generated: GeneratedCode, library: Path, name: str, blocks: Sequence[str], build_dir: str | Path,
                 tables: Sequence[str] = (), what: str = "timing program") -> list[list[str]]:
    """Build the timing program of ``blocks`` against the shared library, run it and parse its output.

    Parameters
    ----------
    generated : GeneratedCode
        The generated library.
    library : pathlib.Path
        Its shared library.
    name : str
        Program name (file stem), e.g. ``"gt_L1_timing"``.
    blocks : sequence of str
        Timed blocks (:func:`timing_block`), each printing a line ``label<TAB>value...``.
    build_dir : str or pathlib.Path
        Folder for the program.
    tables : sequence of str, optional
        Lines before ``main``: constant input tables.
    what : str, optional
        What it is, for the messages.

    Returns
    -------
    list of list of str
        Per printed line its tab-separated fields.

    Raises
    ------
    CodegenError
        The program failed to build, or a timed call returned a non-OK status.
    """
    text = fill("template_timer.c", HEADER=generated.header.name, TABLES="\n".join(tables), BLOCKS="\n".join(blocks))
    try:
        exe = compile_program(generated, name, text, build_dir, library=library)
    except CodegenError as exc:
        raise CodegenError(f"{what} failed to build:\n{exc}") from None
    log.debug("codegen: running %s", exe)
    return run_program(exe, what)


def c_function(library: CompiledLibrary, name: str, nargs: int, int_first: bool = False):
    """A raw ctypes function ``<prefix>_<name>`` of a library: pointer arguments, ``int`` result.

    Parameters
    ----------
    library : CompiledLibrary
        The loaded library.
    name : str
        Function name without the prefix, e.g. ``"kalman_update"``.
    nargs : int
        Number of arguments.
    int_first : bool, optional
        The first argument is an ``int`` (e.g. the cycle of ``ilc_correction``).

    Returns
    -------
    ctypes function
        Called with :func:`pointer` values (None for NULL).

    Raises
    ------
    CodegenError
        The library does not export ``<prefix>_<name>``.
    """
    return library.bind(name, ctypes.c_int, ([ctypes.c_int] if int_first else [ctypes.c_void_p]) + [ctypes.c_void_p] * (nargs - 1))


def pointer(a: np.ndarray | None) -> int | None:
    """The data address of a contiguous array for a :func:`c_function` call (None: NULL).

    Parameters
    ----------
    a : numpy.ndarray or None
        A C-contiguous array of the library's floating-point type.

    Returns
    -------
    int or None
        Its address.
    """
    return None if a is None else a.ctypes.data


def c_array(values: np.ndarray, rows: bool = False) -> str:
    """C initialiser of a table of a check program: the values flattened, or with ``rows`` a brace per row.

    Parameters
    ----------
    values : numpy.ndarray
        The values (2-D with ``rows``).
    rows : bool, optional
        One ``{...}`` per row, rows separated by ``,\\n``.

    Returns
    -------
    str
        The values as ``repr(float(v))`` (they read back exactly), comma-separated.
    """
    values = np.asarray(values, dtype=float)
    if rows:
        return ",\n".join("{" + ", ".join(f"{float(v)!r}" for v in row) + "}" for row in values)
    return ", ".join(f"{float(v)!r}" for v in np.ravel(values))
