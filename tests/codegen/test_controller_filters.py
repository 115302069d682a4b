"""The KF/EKF steps of the tracker + IMU fusion as generated C (issue 14, item 6).

Independent references: the very CasADi step Functions of gtmodel.estimation.filters evaluated
from Python over the same measurement record (``mapaccum``, as ``KalmanFilter.run`` does); a
Function with other noise figures must fail the check; the stand-alone program (strict flags,
heap calls counted by ``-Wl,--wrap``) under valgrind's memcheck; ``nm`` on the objects.
The EKF library takes ~40 s to compile at -O2 (53k operations): its tests are marked slow.
"""

from __future__ import annotations

import contextlib
import dataclasses
import io
import re
import shutil
import subprocess

import casadi as ca
import numpy as np
import pytest

from gtmodel.cli import main
from gtmodel.codegen import Controller, check_controller, compile_shared, generate, load_controller, load_library, save_controller
from gtmodel.codegen.check.filter import (
    FILTER_CYCLES,
    QUATERNION_SLICE,
    STRICT_FLAGS,
    build_filter_program,
    filter_record,
    python_filter_run,
    run_filter_program,
)
from gtmodel.errors import InputError
from gtmodel.estimation.filters.end_effector import EndEffectorModel

from .controller_functions import FILTER_DT, fusion_filter

needs_valgrind = pytest.mark.skipif(shutil.which("valgrind") is None, reason="valgrind not on PATH")
SLOW_EKF = pytest.param("ekf_step", marks=pytest.mark.slow)
NAMES = ["kf_step", SLOW_EKF]
SIZES = {"kf_step": (9, 6), "ekf_step": (19, 13)}


@pytest.fixture(scope="module")
def built(tmp_path_factory):
    """``built(name) -> (GeneratedCode, CompiledLibrary, build dir)``: the filter alone, -Werror -pedantic."""
    cache = {}

    def get(name: str):
        if name not in cache:
            f = fusion_filter(name == "ekf_step").step_function()
            root = tmp_path_factory.mktemp(name)
            gen = generate("L1", root / "src", functions=(), prefix="gt_fusion", controller=Controller(dt=FILTER_DT, **{name: f}))
            lib = load_library(gen, compile_shared(gen, root / "build", werror=True, extra_flags=("-pedantic",)))
            cache[name] = (gen, lib, root / "build")
        return cache[name]

    return get


@pytest.fixture(scope="module")
def report(built):
    cache = {}

    def get(name: str):
        if name not in cache:
            gen, lib, build = built(name)
            cache[name] = check_controller(gen, library=lib, build_dir=build, timing=True)
        return cache[name]

    return get


# ----------------------------------------------------------------------------- declarations
@pytest.mark.parametrize("name", NAMES)
def test_header_declares_sizes_struct_init_update(built, name):
    gen, _, _ = built(name)
    nx, nz = SIZES[name]
    s, S = name[:-5], name[:-5].upper()
    header = gen.header.read_text()
    expected = [
        f"int gt_fusion_{name}(const double x[{nx}], const double P[{nx * nx}], const double z[{nz}], "
        f"double x_next[{nx}], double P_next[{nx * nx}]);",
        f"#define GT_FUSION_{S}_NX {nx}", f"#define GT_FUSION_{S}_NZ {nz}", f"#define GT_FUSION_{S}_NPIVOTS {nx + nz}",
        f"typedef struct gt_fusion_{s}_state {{", f"    double x[{nx}];", f"    double P[{nx * nx}];",
        f"int gt_fusion_{s}_init(gt_fusion_{s}_state *state, const double x0[{nx}], const double P0[{nx * nx}]);",
        f"int gt_fusion_{s}_update(gt_fusion_{s}_state *state, const double z[{nz}]);",
    ]
    missing = [line for line in expected if line not in header]
    assert not missing, missing
    assert gen.functions == (name,)  # the controller alone: no robot function


def test_a_filter_only_header_names_no_robot_and_carries_the_controller_hash(built):
    gen, _, _ = built("kf_step")
    header = gen.header.read_text()
    controller = Controller(dt=FILTER_DT, kf_step=fusion_filter(False).step_function())
    assert "L1" not in header and "_ROBOT" not in header and "SINGULARITY_TOLERANCE" not in header
    assert f'#define GT_FUSION_PARAMETER_HASH "{controller.content_hash()}"' in header
    assert gen.version.endswith(f"controller sha256:{controller.content_hash()}; real double")


# ----------------------------------------------------------------------------- whole run
@pytest.mark.parametrize("name", NAMES)
def test_check_passes_over_a_whole_record(report, name):
    r = report(name)
    assert r.passed, "\n".join(r.summary_lines())
    assert r.n == FILTER_CYCLES


@pytest.mark.parametrize("name, function", [
    ("kf_step", "kf_update"), ("kf_step", "kf_step"),
    pytest.param("ekf_step", "ekf_update", marks=pytest.mark.slow), pytest.param("ekf_step", "ekf_step", marks=pytest.mark.slow),
])
def test_every_state_and_covariance_equals_python_to_1e12(report, name, function):
    """Against the step Function's mapaccum from Python over 3000 steps (the same record)."""
    f = next(f for f in report(name).functions if f.name == function)
    assert f.n == FILTER_CYCLES and f.n_not_ok == 0
    assert f.max_abs_diff <= 1e-12 and f.passed
    assert f.ns_per_call is not None and f.ns_per_call > 0


@pytest.mark.slow
def test_quaternion_is_unit_in_every_c_state(report):
    """The renormalisation is in the graph: | |quat| - 1 | at rounding level in every C state."""
    f = next(f for f in report("ekf_step").functions if f.name == "ekf_update quaternion norm")
    assert f.passed and f.max_abs_diff <= 1e-14


@pytest.mark.parametrize("name", NAMES)
def test_the_record_is_realistic(built, name):
    """The record comes from the model's measurement Function; the Python filter tracks the true position within 0.1 mm."""
    gen, _, _ = built(name)
    rec = filter_record(gen.controller, name, 1000, seed=1)
    model = EndEffectorModel(FILTER_DT, rotation=name == "ekf_step")
    assert rec["z"].shape == (1000, model.nz) and rec["x0"].shape == (model.nx,)
    # the truth: p = 10 mm sin(2 pi f t) at t = k dt (closed form)
    t = np.arange(1, 1001)[:, None] * FILTER_DT
    p = 0.01 * np.sin(2 * np.pi * np.array([1.0, 0.8, 0.6]) * t)
    assert np.abs(rec["z"][:, :3] - p).max() < 5 * 6.4e-6
    run = python_filter_run(getattr(gen.controller, name), rec["z"], rec["x0"], rec["P0"])
    assert np.abs(run.x[1:, :3] - p).max() < 1e-4
    if name == "ekf_step":
        assert QUATERNION_SLICE == model.state_slices["quaternion"]


# ----------------------------------------------------------------------------- status contract
PROBES = [
    ("NaN in x", "{name}"), ("Inf in P", "{name}"), ("NaN in z", "{name}"), ("NULL P", "{name}"), ("NULL P_next", "{name}"),
    ("P not positive definite", "{name}"), ("P negative definite", "{name}"),
    ("NULL state", "{stem}_init"), ("NULL P0", "{stem}_init"), ("NaN in P0", "{stem}_init"),
    ("NaN in z", "{stem}_update"), ("NULL z", "{stem}_update"), ("NaN in the state", "{stem}_update"),
    ("covariance not positive definite", "{stem}_update"), ("NULL state", "{stem}_update"),
]


@pytest.mark.parametrize("name", NAMES)
@pytest.mark.parametrize("case, function", PROBES)
def test_status_with_outputs_untouched(report, name, case, function):
    """GT_BAD_ARGUMENT for NULL/NaN/Inf, GT_NUMERIC_ERROR for a covariance that is not PD; outputs and state untouched."""
    fn = function.format(name=name, stem=name[:-5])
    probe = next(p for p in report(name).probes if (p.function, p.case) == (fn, case))
    assert probe.passed, probe
    assert probe.expected == ("GT_NUMERIC_ERROR" if "definite" in case else "GT_BAD_ARGUMENT")


def test_a_c_function_that_differs_from_python_fails(built, tmp_path):
    """The reference is the controller's Function: other noise figures must be reported, not pass."""
    gen, lib, _ = built("kf_step")
    other = Controller(kf_step=fusion_filter(False, jerk=5.5).step_function(), dt=FILTER_DT)
    r = check_controller(dataclasses.replace(gen, controller=other), library=lib, build_dir=tmp_path, filter_cycles=200)
    assert not r.passed
    assert [f.passed for f in r.functions] == [False, False]


# ----------------------------------------------------------------------------- strict program, valgrind, heap
@pytest.fixture(scope="module")
def program(built):
    cache = {}

    def get(name: str):
        if name not in cache:
            gen, _, build = built(name)
            rec = filter_record(gen.controller, name, FILTER_CYCLES)
            # KF: every source compiled here with STRICT_FLAGS; EKF (40 s to compile): the library's objects,
            # compiled by the fixture with the same flags (-Werror -pedantic) plus -fPIC
            objects = tuple(build / f"{gen.prefix}{s}.o" for s in ("_casadi", "")) if name == "ekf_step" else None
            exe = build_filter_program(gen, name, rec, build / "program", objects=objects)
            cache[name] = (gen, rec, exe)
        return cache[name]

    return get


@needs_valgrind
@pytest.mark.parametrize("name", NAMES)
def test_stand_alone_run_is_valgrind_clean_without_heap_calls_and_equals_python(program, name, tmp_path):
    gen, rec, exe = program(name)
    proc, run = run_filter_program(exe, tmp_path / "run.bin", rec["x0"].size, valgrind=True)
    assert proc.returncode == 0, proc.stdout + proc.stderr[-2000:]
    assert "ERROR SUMMARY: 0 errors" in proc.stderr
    assert re.search(r"^heap calls in the filter 0$", proc.stdout, re.M), proc.stdout
    assert re.search(r"^non-OK status 0$", proc.stdout, re.M), proc.stdout
    ref = python_filter_run(getattr(gen.controller, name), rec["z"], rec["x0"], rec["P0"])
    assert run.x.shape == ref.x.shape == (FILTER_CYCLES + 1, rec["x0"].size)
    # every state and covariance of the stand-alone C run against Python
    assert np.abs(run.x - ref.x).max() <= 1e-12 and np.abs(run.P - ref.P).max() <= 1e-12


@pytest.mark.parametrize("name", NAMES)
def test_objects_and_program_are_built_with_the_strict_flags_and_call_no_heap_function(program, built, name):
    gen, _, build = built(name)
    program(name)
    assert STRICT_FLAGS == ("-std=c99", "-O2", "-Wall", "-Wextra", "-Werror", "-pedantic")
    objects = list(build.glob(f"{gen.prefix}*.o")) + list((build / "program").glob("*.strict.o"))
    assert len(objects) == (5 if name == "kf_step" else 3)  # 2 of the library, the program's (+ the KF sources' strict ones)
    undefined = set().union(*(subprocess.run(["nm", "-u", str(o)], capture_output=True, text=True).stdout.split() for o in objects))
    assert not undefined & {"malloc", "calloc", "realloc", "free"}


# ----------------------------------------------------------------------------- file and CLI
@pytest.mark.parametrize("suffix", [".json", ".npz"])
def test_controller_file_carries_the_filter_steps(tmp_path, suffix):
    """Round trip: the loaded Functions give the same step as the saved ones (same graph)."""
    kf, ekf = fusion_filter(False).step_function(), fusion_filter(True).step_function()
    path = save_controller(tmp_path / f"fusion{suffix}", Controller(kf_step=kf, ekf_step=ekf, dt=FILTER_DT))
    c = load_controller(path)
    assert c.filter_sizes == {"kf_step": (9, 6), "ekf_step": (19, 13)} and c.dt == FILTER_DT
    rec = filter_record(c, "ekf_step", 5)
    a = python_filter_run(ekf, rec["z"], rec["x0"], rec["P0"])
    b = python_filter_run(c.ekf_step, rec["z"], rec["x0"], rec["P0"])
    assert np.array_equal(a.x, b.x) and np.array_equal(a.P, b.P)


def test_cli_generates_and_checks_the_filter_without_a_robot(tmp_path):
    path = save_controller(tmp_path / "kf.json", Controller(kf_step=fusion_filter(False).step_function(), dt=FILTER_DT))
    buffer = io.StringIO()
    with contextlib.redirect_stdout(buffer):
        code = main(["codegen", "--controller", str(path), "--out", str(tmp_path / "gen"), "--check"])
    out = buffer.getvalue()
    assert code == 0, out
    assert (tmp_path / "gen" / "gt_fusion.h").is_file()
    assert "gt_fusion_ik" not in (tmp_path / "gen" / "gt_fusion.h").read_text()
    assert re.search(r"^kf_update: max \|C - Python\| = 0\.0e\+00 .*\(tol 1e-12\), \d+ ns/call OK$", out, re.M), out
    assert out.rstrip().endswith("PASSED")


def _renamed(f, ins=("x", "P", "z"), outs=("x_next", "P_next", "pivots")):
    return ca.Function("f", f.sx_in(), f.call(f.sx_in()), list(ins), list(outs))


def _sliced_output(f, k):
    outs = f.call(f.sx_in())
    outs[k] = outs[k][:-1]
    return ca.Function("f", f.sx_in(), outs, f.name_in(), f.name_out())


KF = fusion_filter(False).step_function()
BAD_FILTERS = [
    ({"kf_step": "kf"}, r"kf_step: expected a casadi.Function, got str"),
    ({"kf_step": _renamed(KF, ins=("x", "P", "y"))}, r"kf_step: expected a casadi.Function \(x, P, z\) -> \(x_next, P_next, pivots\), got \(x, P, y\)"),
    ({"ekf_step": _sliced_output(KF, 2)}, r"ekf_step: output 'pivots' must be a dense 15x1 matrix \(nx = 9, nz = 6\), is 14x1"),
    ({"kf_step": _sliced_output(KF, 0)}, r"kf_step: output 'x_next' must be a dense 9x1 matrix"),
]


@pytest.mark.parametrize("kwargs, match", BAD_FILTERS, ids=[m[:40] for _, m in BAD_FILTERS])
def test_bad_filter_function_is_refused_naming_it(kwargs, match):
    with pytest.raises(InputError, match=match):
        Controller(**kwargs)


@pytest.mark.parametrize("kwargs, match", [
    ({"filter_cycles": 0}, r"filter_cycles: expected a positive number of measurements, got 0"),
    ({"records": {"ekf_step": {}}}, r"records: 'ekf_step' is not a filter of the controller \(kf_step\)"),
    ({"records": {"kf_step": {"z": np.zeros((5, 13)), "x0": np.zeros(9), "P0": np.eye(9)}}}, r"records\['kf_step'\]\['z'\]: expected finite values of shape \(N, 6\), got \(5, 13\)"),
    ({"records": {"kf_step": {"z": np.zeros((5, 6)), "x0": np.zeros(9), "P0": np.full((9, 9), np.nan)}}}, r"records\['kf_step'\]\['P0'\]: expected finite values of shape \(9, 9\)"),
])
def test_bad_check_arguments(built, kwargs, match):
    gen, lib, _ = built("kf_step")
    with pytest.raises(InputError, match=match):
        check_controller(gen, library=lib, **kwargs)


def test_a_given_record_is_replayed(built, tmp_path):
    gen, lib, _ = built("kf_step")
    rec = filter_record(gen.controller, "kf_step", 50, seed=4)
    r = check_controller(gen, library=lib, build_dir=tmp_path, records={"kf_step": rec})
    assert r.passed and r.n == 50
