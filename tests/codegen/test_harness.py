"""The C harness in ``codegen/``: Makefile build, C unit tests, the 4 ms loop, memory guarantees.

Independent references: the C unit-test program checks model identities (FK(IK(T)) = T,
J J^-1 = I, inverse dynamics at rest = gravity); the loop compares its cart references
with the trajectory table's (the optimal-control solution); ``nm`` and valgrind inspect
the compiled code itself.
"""

from __future__ import annotations

import contextlib
import importlib
import io
import re
import shutil
import subprocess
import time
import tomllib
from pathlib import Path

import pytest

import gtmodel.codegen
from gtmodel.cli import main
from gtmodel.codegen import check_generated as check, generate
from gtmodel.codegen.check import HARNESS_FILES, harness_dir, run_harness_unit_tests

check_module = importlib.import_module("gtmodel.codegen.check.harness")
ROOT = Path(__file__).resolve().parents[2]
HARNESS = ROOT / "codegen"
PROBLEM = ROOT / "problems" / "l1_time_optimal.toml"
#: Flags the issue requires for the generated code.
REQUIRED_FLAGS = ("-std=c99", "-O2", "-Wall", "-Wextra", "-Werror")
#: Measure-only cycles of the acceptance run (the issue: 10^5).
MEASURE_CYCLES = 100_000
#: Real 4 ms periods of the short real-time run (1 s).
REALTIME_CYCLES = 250
#: Control period [s] of the loop example (Dressler (2012), ch. 3.2).
PERIOD_S = 0.004
#: Cycles under valgrind (about 50x slower).
VALGRIND_CYCLES = 2000
HEAP_FUNCTIONS = ("malloc", "calloc", "realloc", "free")

needs_make = pytest.mark.skipif(shutil.which("make") is None or shutil.which("gcc") is None, reason="no make/gcc")


@pytest.fixture(scope="session")
def harness(tmp_path_factory):
    """Generated L1 code, the shipped trajectory table and the harness built with make."""
    root = tmp_path_factory.mktemp("harness")
    generate("L1", root / "gen")
    assert main(["solve", str(PROBLEM), "--out", str(root / "traj"), "--no-plots", "-q"]) == 0
    build = root / "build"
    args = [f"BUILD={build}", f"GEN={root / 'gen'}", f"TRAJ={root / 'traj' / 'trajectory.h'}", "TRAJ_NAME=l1_time_optimal"]
    proc = subprocess.run(["make", "-C", str(HARNESS), *args, "all"], capture_output=True, text=True)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    return build, proc.stdout


def _run(cmd, timeout=300):
    return subprocess.run([str(c) for c in cmd], capture_output=True, text=True, timeout=timeout)


def _field(text: str, name: str) -> int:
    m = re.search(rf"^{name} (\d+)$", text, re.M)
    assert m, text
    return int(m.group(1))


@needs_make
def test_makefile_builds_static_and_shared_library_with_strict_flags(harness):
    build, log = harness
    assert (build / "libgt_L1.a").exists() and (build / "libgt_L1.so").exists()
    compile_lines = [l for l in log.splitlines() if " -c " in l]
    assert len(compile_lines) == 2  # CasADi part and wrapper
    missing = [(flag, line) for line in compile_lines for flag in REQUIRED_FLAGS if flag not in line.split()]
    assert not missing, missing


@needs_make
def test_c_unit_test_program_passes(harness):
    build, _ = harness
    proc = _run([build / "unit_test"])
    assert proc.returncode == 0, proc.stdout
    assert re.search(r"unit_test: \d+ checks, 0 failures", proc.stdout)


@needs_make
def test_loop_100000_cycles_measure_only_without_deadline_miss(harness):
    build, _ = harness
    proc = _run([build / "loop", "--mode", "measure", "--cycles", MEASURE_CYCLES])
    assert proc.returncode == 0, proc.stdout
    assert _field(proc.stdout, "cycles") == MEASURE_CYCLES
    assert _field(proc.stdout, "deadline misses") == 0
    assert _field(proc.stdout, "non-OK status") == 0
    assert _field(proc.stdout, "heap allocations in the loop") == 0
    # a miss is judged on the thread's CPU time; OS pre-emptions are reported apart
    assert re.search(r"^largest CPU time of a cycle \d+ ns; stalled cycles .* \d+$", proc.stdout, re.M), proc.stdout
    assert "max |q - q_table| 0 m" in proc.stdout or re.search(r"max \|q - q_table\| [0-9.e-]+ m", proc.stdout)


@needs_make
def test_loop_short_realtime_run(harness):
    """Real 4 ms periods (clock_nanosleep to absolute deadlines): the run lasts the
    planned time, every call is OK and the misses are reported honestly (exit code 1 if
    any) and counted, never more than the cycles run. The test machines are shared
    containers where SCHED_FIFO is granted but not honoured (a CI run saw one 16 ms stall
    make 21 of 250 cycles late), so the number of misses is not asserted here: wall-clock
    deadlines measure the machine, not the code. The zero-miss requirement is checked on
    the compute time of 10^5 cycles by
    ``test_loop_100000_cycles_measure_only_without_deadline_miss``."""
    build, _ = harness
    start = time.perf_counter()
    proc = _run([build / "loop", "--mode", "realtime", "--cycles", REALTIME_CYCLES])
    elapsed = time.perf_counter() - start
    misses = _field(proc.stdout, "deadline misses")
    assert _field(proc.stdout, "non-OK status") == 0, proc.stdout
    assert _field(proc.stdout, "heap allocations in the loop") == 0, proc.stdout
    assert proc.returncode == (0 if misses == 0 else 1), proc.stdout
    assert 0 <= misses <= int(REALTIME_CYCLES), proc.stdout
    assert elapsed >= 0.9 * int(REALTIME_CYCLES) * PERIOD_S, f"run took {elapsed:.3f} s: not paced at 4 ms"


@needs_make
def test_generated_objects_call_no_heap_functions(harness, built):
    """``nm -u``: neither the L1 objects nor the six-link / F1 ones reference malloc & co."""
    build, _ = harness
    objects = list(build.glob("*.o")) + list(built("D1_six_link")[1].path.parent.glob("*.o"))
    assert len(objects) >= 4
    undefined = {obj: set(_run(["nm", "-u", obj]).stdout.split()) for obj in objects}
    heap = {obj: sorted(u & set(HEAP_FUNCTIONS)) for obj, u in undefined.items() if u & set(HEAP_FUNCTIONS)}
    assert not heap, heap


@needs_make
def test_generated_objects_have_no_mutable_global_state(harness, built):
    """``nm``: no data/bss symbols (B, D, C): only code and read-only constants."""
    build, _ = harness
    objects = list(build.glob("gt_*.o")) + list(built("D1_six_link")[1].path.parent.glob("*.o"))
    symbols = {obj: _run(["nm", obj]).stdout.splitlines() for obj in objects}
    mutable = {obj: [l for l in lines if re.search(r" [BbDdC] ", l)] for obj, lines in symbols.items()}
    mutable = {obj: m for obj, m in mutable.items() if m}
    assert not mutable, mutable


needs_valgrind = pytest.mark.skipif(shutil.which("valgrind") is None, reason="valgrind not on PATH")
#: The two valgrind runs (half and full length): their heap allocations must be equal.
VALGRIND_RUNS = (VALGRIND_CYCLES // 2, VALGRIND_CYCLES)


@pytest.fixture(scope="module")
def valgrind_runs(harness):
    """The loop under memcheck, once per length of ``VALGRIND_RUNS``: ``{cycles: process}``."""
    build, _ = harness
    return {
        cycles: _run(["valgrind", "--tool=memcheck", "--error-exitcode=99", "--leak-check=full",
                      build / "loop", "--mode", "measure", "--cycles", cycles])
        for cycles in VALGRIND_RUNS
    }


def _heap_allocs(proc) -> int:
    m = re.search(r"total heap usage: ([\d,]+) allocs", proc.stderr)
    assert m, proc.stderr[-2000:]
    return int(m.group(1).replace(",", ""))


@needs_make
@needs_valgrind
@pytest.mark.parametrize("cycles", VALGRIND_RUNS, ids=lambda c: f"{c}_cycles")
def test_valgrind_memcheck_clean(valgrind_runs, cycles):
    """memcheck: no errors, every call OK, no allocation counted inside the loop."""
    proc = valgrind_runs[cycles]
    # exit 99 = memcheck errors; a deadline miss under valgrind's ~50x slow-down is no error here
    assert proc.returncode in (0, 1), proc.stderr[-2000:]
    assert "ERROR SUMMARY: 0 errors" in proc.stderr
    assert _field(proc.stdout, "heap allocations in the loop") == 0
    assert _field(proc.stdout, "non-OK status") == 0
    _heap_allocs(proc)


@needs_make
@needs_valgrind
def test_valgrind_no_allocation_in_the_loop(valgrind_runs):
    """The number of heap allocations does not grow with the cycles."""
    allocs = [_heap_allocs(valgrind_runs[cycles]) for cycles in VALGRIND_RUNS]
    assert allocs[0] == allocs[1], dict(zip(VALGRIND_RUNS, allocs))


@pytest.fixture(scope="module")
def cli_check_output(tmp_path_factory):
    """Exit code and printed output of ``gtmodel codegen --robot L1 --check``."""
    out_dir = tmp_path_factory.mktemp("cli_check") / "gen"
    buffer = io.StringIO()
    with contextlib.redirect_stdout(buffer):
        code = main(["codegen", "--robot", "L1", "--out", str(out_dir), "--check", "-n", "300"])
    return code, buffer.getvalue()


@pytest.mark.parametrize("name", ["ik", "fk", "jacobian", "jacobian_inverse", "acceleration", "inverse_dynamics", "gravity"])
def test_cli_check_prints_error_and_time_per_function(cli_check_output, name):
    code, out = cli_check_output
    assert code == 0, out
    assert re.search(rf"^{name}: max \|C - Python\| = \S+ .*\d+ ns/call .*OK$", out, re.M), out


def test_cli_check_runs_the_packaged_c_unit_tests(cli_check_output):
    code, out = cli_check_output
    assert code == 0, out
    unit_test = re.escape(str(harness_dir() / "unit_test.c"))
    assert re.search(rf"^C unit tests: ran {unit_test}: unit_test: \d+ checks, 0 failures$", out, re.M), out
    assert out.rstrip().endswith("PASSED")


def test_the_harness_ships_with_the_package():
    """The harness sources are package data of gtmodel.codegen (found after ``pip install .``)."""
    folder = harness_dir()
    assert folder == Path(gtmodel.codegen.__file__).resolve().parent / "harness"
    assert all((folder / name).is_file() for name in HARNESS_FILES)
    package_data = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]["package-data"]
    assert package_data["gtmodel.codegen"][:3] == ["harness/Makefile", "harness/*.c", "harness/*.h"]
    # the robot runtime (gtmodel.codegen.robot_runtime): its C, ABB's egm.proto with its nanopb options, the vendored nanopb
    assert set(package_data["gtmodel.codegen"][3:]) == {"harness/runtime/*.c", "harness/runtime/*.h", "harness/runtime/egm.proto",
                                                         "harness/runtime/egm.options", "harness/runtime/nanopb/*"}
    assert "include ../gtmodel/codegen/harness/Makefile" in (HARNESS / "Makefile").read_text()


@pytest.mark.parametrize("missing", ["folder", "unit_test.c"])
def test_a_missing_harness_fails_the_check(tmp_path, monkeypatch, missing):
    """A harness that applies but cannot run makes the check FAIL and says why (never PASSED)."""
    broken = tmp_path / "harness"
    if missing != "folder":
        shutil.copytree(harness_dir(), broken)
        (broken / missing).unlink()
    monkeypatch.setattr(check_module, "harness_dir", lambda: broken)
    gen = generate("L1", tmp_path / "gen")
    report = check(gen, n=20, build_dir=tmp_path / "build", timing=True)
    assert report.harness_passed is False
    assert not report.passed
    lines = report.summary_lines()
    assert re.fullmatch(r"C unit tests: not run: harness files \[.*'unit_test.c'.*\] missing in .*", lines[-2]), lines
    assert lines[-1] == "FAILED"


def test_no_make_fails_the_check(tmp_path, monkeypatch):
    """Without ``make`` the C unit tests cannot run: the verdict says so and is a failure."""
    gen = generate("L1", tmp_path / "gen")
    monkeypatch.setattr(check_module.shutil, "which", lambda name: None)
    assert run_harness_unit_tests(gen, tmp_path / "build") == (False, "not run: no 'make' program on PATH")


def test_single_precision_code_compiles_strictly_and_matches(tmp_path):
    """``real="float"``: float API, compiled with -Werror, within FLOAT_RELATIVE_TOLERANCE of Python."""
    gen = generate("L1", tmp_path / "gen", real="float", functions=("ik", "jacobian", "inverse_dynamics"))
    assert "int gt_L1_ik(const float T[3], int configuration, float q[3]);" in gen.header.read_text()
    report = check(gen, n=300, build_dir=tmp_path / "build")
    assert report.passed, "\n".join(report.summary_lines())


REENTRANCY_PROGRAM = r"""
#define _POSIX_C_SOURCE 200112L
#include <pthread.h>
#include <stdio.h>
#include <string.h>
#include "gt_L1.h"
#define N 20000
static double base[N][3];
static void run(double (*out)[3])
{
    long i;
    for (i = 0; i < N; ++i) {
        const double T[3] = {-0.2 + 1e-5 * (double)(i % 1000), 2.75, -0.4 - 1e-6 * (double)(i % 700)};
        const double Td[3] = {0.1, 0.2, -0.3}, Tdd[3] = {1.0, -2.0, 0.5};
        if (gt_L1_inverse_dynamics(T, Td, Tdd, 0, out[i]) != GT_OK) out[i][0] = -1.0;
    }
}
static double res[2][N][3];
static void *worker(void *arg) { run(res[*(int *)arg]); return NULL; }
int main(void)
{
    pthread_t t[2];
    int id[2] = {0, 1}, k;
    run(base);
    for (k = 0; k < 2; ++k) pthread_create(&t[k], NULL, worker, &id[k]);
    for (k = 0; k < 2; ++k) pthread_join(t[k], NULL);
    printf("%d %d\n", memcmp(base, res[0], sizeof base) == 0, memcmp(base, res[1], sizeof base) == 0);
    return 0;
}
"""


@needs_make
def test_functions_are_reentrant_across_threads(harness, tmp_path):
    """Two threads calling the same function concurrently get bit-identical results (no shared state)."""
    build, _ = harness
    src = tmp_path / "reentrant.c"
    src.write_text(REENTRANCY_PROGRAM)
    exe = tmp_path / "reentrant"
    proc = _run(["gcc", "-std=c99", "-O2", "-Wall", "-Wextra", "-Werror", "-pthread", f"-I{build.parent / 'gen'}", src,
                 build / "libgt_L1.a", "-lm", "-o", exe])
    assert proc.returncode == 0, proc.stderr
    assert _run([exe]).stdout.split() == ["1", "1"]
