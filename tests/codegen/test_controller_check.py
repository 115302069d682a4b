"""The controller's self-check over a whole run, and the 4 ms loop with the controller.

Independent references: the CasADi Functions evaluated from Python over the run
(``mapaccum``, the form the Python estimation uses); a deliberately different Function must
fail the check; ``nm`` and valgrind inspect the compiled loop.
"""

from __future__ import annotations

import contextlib
import dataclasses
import io
import re
import shutil
import subprocess

import numpy as np
import pytest

from gtmodel.cli import main
from gtmodel.codegen import Controller, check_controller, save_controller
from gtmodel.codegen.check.controller import ILC_MARGIN, RUN_CYCLES, python_run, run_inputs
from gtmodel.errors import InputError
from gtmodel.robots.kinematics import GantryTau3Kinematics
from gtmodel.trajectory.export import write_c_header

from .controller_functions import ilc_correction_function, kalman_step_function, learned_table
from .test_harness import HARNESS, REQUIRED_FLAGS

#: Flags the issue requires for the generated code (the harness's).
FLAGS = REQUIRED_FLAGS
needs_make = pytest.mark.skipif(shutil.which("make") is None or shutil.which("gcc") is None, reason="no make/gcc")
needs_valgrind = pytest.mark.skipif(shutil.which("valgrind") is None, reason="valgrind not on PATH")


@pytest.fixture(scope="module")
def report(controller_built, tmp_path_factory):
    gen, lib = controller_built
    return check_controller(gen, library=lib, build_dir=tmp_path_factory.mktemp("cc"), timing=True)


def test_check_passes_over_a_whole_run(report):
    assert report.passed, "\n".join(report.summary_lines())
    assert report.n == RUN_CYCLES


@pytest.mark.parametrize("name", ["kalman_step", "kalman_update", "ilc_correction"])
def test_every_cycle_equals_python_to_1e12(report, name):
    f = next(f for f in report.functions if f.name == name)
    assert f.passed and f.max_abs_diff <= 1e-12 and f.n_not_ok == 0
    assert f.n == (RUN_CYCLES if name != "ilc_correction" else 400 + 2 * ILC_MARGIN)
    assert f.ns_per_call is not None and f.ns_per_call > 0


@pytest.mark.parametrize("function, case", [
    ("kalman_step", "NaN in x"), ("kalman_step", "Inf in y"), ("kalman_step", "NULL x_next"),
    ("kalman_update", "NULL state"), ("kalman_update", "NaN in y"), ("kalman_update", "NaN in the state"),
    ("kalman_init", "NULL state"), ("ilc_correction", "k = N (after the table): zero"), ("ilc_correction", "NULL u"),
])
def test_status_probes_cover_null_and_non_finite_inputs(report, function, case):
    """GT_BAD_ARGUMENT with outputs and state untouched (GT_OK and zeros for the ILC outside its table)."""
    probe = next(p for p in report.probes if (p.function, p.case) == (function, case))
    assert probe.passed, probe


@pytest.mark.parametrize("name", ["kalman_step", "kalman_update", "ilc_correction"])
def test_summary_prints_error_and_time_per_function(report, name):
    text = "\n".join(report.summary_lines())
    assert re.search(r"^check of the controller of gt_L1 over a run of 400 cycles", text, re.M)
    assert re.search(rf"^{name}: max \|C - Python\| = \S+ .*\(tol 1e-12\), \d+ ns/call OK$", text, re.M), text


@pytest.mark.parametrize("seed", [1, 2])
def test_run_inputs_are_realistic(controller_built, seed):
    """A 10 mm motion, accelerometer within 1.5 g, the Python run's estimate near the position (same Functions)."""
    gen, _ = controller_built
    inp = run_inputs(gen.controller, 400, seed)
    assert inp["y"].shape == (400, 6)
    assert 0.009 < np.ptp(inp["y"][:, 0]) < 0.011
    assert np.abs(inp["y"][:, 3:]).max() <= 1.5 * 9.80665
    ref = python_run(gen.controller, inp["y"], inp["x0"], inp["k"])
    # the stationary filter leaves about 43 um RMS of accelerometer noise (crossover 4.5 Hz): max within 0.5 mm
    assert np.abs(ref["z_hat"][100:] - inp["y"][100:, :3]).max() < 5e-4


def test_a_replayed_measurement_sequence_is_checked(controller_built, tmp_path):
    gen, lib = controller_built
    y = np.tile(np.array([0.001, -0.002, 0.0005, 0.1, -0.2, 0.3]), (50, 1))
    r = check_controller(gen, library=lib, build_dir=tmp_path, y=y, x0=np.full(9, 1e-3))
    assert r.passed and r.n == 50


def test_a_c_function_that_differs_from_python_fails(controller_built, tmp_path):
    """The reference is the controller's Function: a gain 1 % off must be reported, not pass."""
    gen, lib = controller_built
    other = learned_table(400, 3, seed=5)
    wrong = Controller(kalman_step=kalman_step_function(dt=0.00404), ilc_correction=ilc_correction_function(other), ilc_table=other)
    r = check_controller(dataclasses.replace(gen, controller=wrong), library=lib, build_dir=tmp_path)
    assert not r.passed
    assert [f.passed for f in r.functions] == [False, False, False]
    assert r.summary_lines()[-1] == "FAILED"


@pytest.mark.parametrize("kwargs, match", [
    ({"cycles": 0}, r"cycles: expected a positive number of cycles, got 0"),
    ({"y": np.zeros((10, 5))}, r"y: expected finite measurements of shape \(N, 6\), got \(10, 5\)"),
    ({"y": np.full((10, 6), np.nan)}, r"y: expected finite measurements"),
    ({"x0": np.zeros(3)}, r"x0: expected a finite state of shape \(9,\), got \(3,\)"),
])
def test_bad_check_arguments(controller_built, kwargs, match):
    gen, lib = controller_built
    with pytest.raises(InputError, match=match):
        check_controller(gen, library=lib, **kwargs)


def test_a_library_without_controller_is_refused(built):
    gen, lib = built("L1")
    with pytest.raises(InputError, match=r"generated: the library has no controller functions"):
        check_controller(gen, library=lib)


# ----------------------------------------------------------------------------- the 4 ms loop
@pytest.fixture(scope="module")
def loop(controller_built, tmp_path_factory):
    """The harness loop built by make with CONTROLLER= (generated by the CLI), strict flags."""
    gen, _ = controller_built
    root = tmp_path_factory.mktemp("controller_loop")
    controller_file = save_controller(root / "controller.json", gen.controller)
    k = GantryTau3Kinematics("L1")
    t = np.arange(250) * 0.004
    s = (1 - np.cos(np.pi * t / t[-1])) / 2
    T = np.array([-0.2, 2.75, -0.4]) + np.outer(s, [0.05, -0.03, 0.02])
    Td = np.gradient(T, t, axis=0)
    q = np.reshape(k.ik(T, 0), (-1, 3))
    cols = {"t": t, "x": T[:, 0], "y": T[:, 1], "z": T[:, 2], "xd": Td[:, 0], "yd": Td[:, 1], "zd": Td[:, 2],
            "q1": q[:, 0], "q2": q[:, 1], "q3": q[:, 2]}
    write_c_header(cols, root / "trajectory.h", name="line")
    with contextlib.redirect_stdout(io.StringIO()):
        assert main(["codegen", "--robot", "L1", "--functions", "ik,jacobian,inverse_dynamics",
                     "--controller", str(controller_file), "--out", str(root / "gen")]) == 0
    build = root / "build"
    args = [f"BUILD={build}", f"GEN={root / 'gen'}", f"TRAJ={root / 'trajectory.h'}", "TRAJ_NAME=line", f"CONTROLLER={controller_file}"]
    proc = subprocess.run(["make", "-C", str(HARNESS), *args, str(build / "loop")], capture_output=True, text=True)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    return build, proc.stdout


def _run(cmd, timeout=300):
    return subprocess.run([str(c) for c in cmd], capture_output=True, text=True, timeout=timeout)


def _field(text: str, name: str) -> int:
    m = re.search(rf"^{name} (\d+)$", text, re.M)
    assert m, text
    return int(m.group(1))


@needs_make
def test_loop_with_controller_compiles_under_the_strict_flags(loop):
    _, log = loop
    commands = log.replace("\\\n", " ").splitlines()  # make echoes continued lines
    lines = [l for l in commands if " -c " in l or "loop.c" in l]
    assert len(lines) == 3, log  # CasADi part, wrapper, loop
    assert any("-DGT_CONTROLLER" in l and "-DGT_MACRO=GT_L1" in l for l in lines), log
    missing = [(f, l) for l in lines if (" -c " in l or "loop.c" in l) for f in FLAGS if f not in l.split()]
    assert not missing, missing


@needs_make
def test_loop_with_controller_100000_cycles(loop):
    build, _ = loop
    proc = _run([build / "loop", "--mode", "measure", "--cycles", 100_000])
    assert proc.returncode == 0, proc.stdout
    assert _field(proc.stdout, "deadline misses") == 0
    assert _field(proc.stdout, "non-OK status") == 0
    assert _field(proc.stdout, "heap allocations in the loop") == 0
    m = re.search(r"controller: ILC table 400 cycles, max \|u_k\| (\S+) m; Kalman max \|z_hat \+ T0 - T\| (\S+) m", proc.stdout)
    assert m, proc.stdout
    assert 0 < float(m.group(1)) < 1e-4 and float(m.group(2)) < 1e-3


@needs_make
@needs_valgrind
@pytest.mark.parametrize("cycles", [500, 1000])
def test_loop_with_controller_is_valgrind_clean(loop, cycles):
    build, _ = loop
    proc = _run(["valgrind", "--tool=memcheck", "--error-exitcode=99", "--leak-check=full", build / "loop",
                 "--mode", "measure", "--cycles", cycles])
    assert proc.returncode in (0, 1), proc.stderr[-2000:]
    assert "ERROR SUMMARY: 0 errors" in proc.stderr
    assert _field(proc.stdout, "heap allocations in the loop") == 0
    assert _field(proc.stdout, "non-OK status") == 0
    # the allocations of the whole program (stdio's buffer) do not depend on the cycles
    assert re.search(r"total heap usage: 1 allocs, 1 frees", proc.stderr), proc.stderr[-800:]


@needs_make
def test_controller_objects_call_no_heap_functions(loop):
    build, _ = loop
    objects = list(build.glob("gt_L1*.o"))
    assert len(objects) == 2
    undefined = set().union(*(_run(["nm", "-u", o]).stdout.split() for o in objects))
    assert not undefined & {"malloc", "calloc", "realloc", "free"}


def test_cli_check_runs_the_controller_check(controller_built, tmp_path):
    gen, _ = controller_built
    path = save_controller(tmp_path / "controller.npz", gen.controller)
    buffer = io.StringIO()
    with contextlib.redirect_stdout(buffer):
        code = main(["codegen", "--robot", "L1", "--functions", "ik", "--controller", str(path), "--out", str(tmp_path / "gen"),
                     "--check", "-n", "50"])
    out = buffer.getvalue()
    assert code == 0, out
    assert re.search(r"^check of the controller of gt_L1 over a run of 400 cycles", out, re.M), out
    assert out.rstrip().endswith("PASSED")
