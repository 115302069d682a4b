"""The hand-written C unit tests of the harness, run against a generated library by the self-check.

``gtmodel/codegen/harness/`` (package data) holds the Makefile rules, ``unit_test.c`` and the
4 ms loop; :func:`run_harness_unit_tests` builds the unit-test program with ``make``
against a generated 3-link library and runs it.
"""

from __future__ import annotations

import shutil
from pathlib import Path

from gtmodel._compiler import run_child
from gtmodel.codegen.emit import harness_dir
from gtmodel.codegen.writer import GeneratedCode

__all__ = ["HARNESS_FUNCTIONS", "HARNESS_FILES", "harness_dir", "harness_applies", "run_harness_unit_tests"]


#: Functions the C unit-test program calls.
HARNESS_FUNCTIONS = ("ik", "fk", "jacobian", "jacobian_inverse", "acceleration", "inverse_dynamics", "gravity")
#: Files of the hand-written harness shipped as package data in ``gtmodel/codegen/harness/``.
HARNESS_FILES = ("Makefile", "unit_test.c", "loop.c", "heap_watch.h")


def harness_applies(generated: GeneratedCode) -> bool:
    """Whether the C unit-test program applies to a generated library.

    Parameters
    ----------
    generated : GeneratedCode
        The generated code.

    Returns
    -------
    bool
        True for a 3-link library in double precision with every function of
        :data:`HARNESS_FUNCTIONS` (the program calls them all).
    """
    return (
        generated.kind == "three_link" and generated.real == "double"
        and set(HARNESS_FUNCTIONS) <= set(generated.functions)
    )


def run_harness_unit_tests(generated: GeneratedCode, build_dir: str | Path, harness: str | Path | None = None) -> tuple[bool, str] | None:
    """Build and run the C unit-test program of the harness against the generated code.

    Parameters
    ----------
    generated : GeneratedCode
        A 3-link library with every function of :data:`HARNESS_FUNCTIONS` in double
        precision (:func:`harness_applies`).
    build_dir : str or pathlib.Path
        Build folder of the harness (``make BUILD=...``).
    harness : str or pathlib.Path or None, optional
        Folder of the harness sources; default :func:`harness_dir`.

    Returns
    -------
    tuple of (bool, str) or None
        Verdict and a line saying what ran (the program's last output line) or why the
        tests could not run (harness files missing, no ``make``, build failure): then the
        verdict is False. None if the tests do not apply to this library
        (:func:`harness_applies`).
    """
    if not harness_applies(generated):
        return None
    folder = Path(harness) if harness is not None else harness_dir()
    missing = [f for f in HARNESS_FILES if not (folder / f).is_file()]
    if missing:
        return False, f"not run: harness files {missing} missing in {folder} (broken installation)"
    if shutil.which("make") is None:
        return False, "not run: no 'make' program on PATH"
    model = generated.model()
    grid = model.kinematics.workspace_grid(0.1)
    T = grid[len(grid) // 2]
    build = Path(build_dir).resolve()
    target = build / "unit_test"
    cmd = [
        "make", "-s", "-C", str(folder), f"BUILD={build}", f"GEN={generated.out_dir.resolve()}",
        f"PREFIX={generated.prefix}", f"TEST_T={{{', '.join(repr(float(x)) for x in T)}}}", str(target),
    ]
    proc = run_child(cmd)
    if proc.returncode != 0:
        return False, f"build failed: {(proc.stderr or proc.stdout).strip().splitlines()[-1:]}"
    run = run_child([str(target)], timeout=120)
    last = run.stdout.strip().splitlines()[-1] if run.stdout.strip() else f"exit {run.returncode}"
    return run.returncode == 0, f"ran {folder / 'unit_test.c'}: {last}"
