"""The loop-step C interface (``<prefix>_init``/``<prefix>_step``) of generated controllers.

References: the controller's CasADi Function evaluated from Python (C equal to 1e-12), the
status contract (GT_BAD_ARGUMENT on NULL/non-finite input, the safe input = the last input
saturated on every failure), and ``gtmodel codegen --controller RESULT_DIR`` on a result
folder written here from a simulated motion of the DC motor of ``models/dc_motor.py``.
"""

from __future__ import annotations

import csv
import ctypes
import dataclasses
import json
import re
import subprocess

import casadi as ca
import numpy as np
import pytest

from gtmodel.cli import EXIT_BAD_INPUT, EXIT_OK, main
from gtmodel.codegen.build import compile_shared, load_library
from gtmodel.codegen.declarations import STATUS_CODES
from gtmodel.codegen.check.loop_step import check_loop_step
from gtmodel.codegen.loop_step import LoopStep, generate_loop_step, load_loop_step, mpc_step, tracking_step
from gtmodel.errors import InputError
from gtmodel.control.mpc import mpc_controller
from gtmodel.control.reference import FLOAT_PERIOD_LIMIT, period_index
from gtmodel.control.tracking import tracking_controller
from gtmodel.modeling import explicit_ode
from gtmodel.problems.user_model import load_user_model

from ..conftest import REPO
from ..modeling._builders import double_integrator

MOTOR = REPO / "models" / "dc_motor.py"
OK, BAD, NUMERIC, NOT_CONVERGED = (STATUS_CODES[k][0] for k in ("GT_OK", "GT_BAD_ARGUMENT", "GT_NUMERIC_ERROR", "GT_NOT_CONVERGED"))
MEMORY_RESET, REJECTED = (STATUS_CODES[k][0] for k in ("GT_MEMORY_RESET", "GT_MEASUREMENT_REJECTED"))


@pytest.fixture(scope="module")
def motion():
    ode = explicit_ode(load_user_model(MOTOR, "DCMotorModel"))
    t = np.linspace(0.0, 0.4, 41)
    u = (6.0 * np.sin(2 * np.pi * t / 0.4))[:, None]
    x, _ = ode.simulate_steps(ode.step(0.01, "rk4", substeps=10), u[:-1])
    return ode, t, x, u


def _compiled(step: LoopStep, folder, prefix):
    gen = generate_loop_step(step, folder, prefix=prefix)
    lib = load_library(gen, compile_shared(gen, folder / "build", werror=True))
    return gen, lib


def test_tracking_controller_c_equals_python_and_keeps_the_contract(tmp_path, motion):
    ode, t, x, u = motion
    c = tracking_controller(ode, t, x, u, u_lb=[-10.0], u_ub=[10.0], Q=[1e-2, 1.0, 1e-4])
    gen = generate_loop_step(tracking_step(c), tmp_path / "src", prefix="gt_tracking")
    report = check_loop_step(gen, n=300)
    assert report.passed, "\n".join(report.summary_lines())
    assert report.functions[0].max_abs_diff <= 1e-12 and len(report.probes) == 11
    assert [f.name for f in report.functions] == ["control", "memory_reset"] and report.functions[1].max_abs_diff <= 1e-12
    text = gen.header.read_text()
    assert "int gt_tracking_step(gt_tracking_memory *mem, double t, const double *x, double *u);" in text
    assert "#define GT_TRACKING_DT 0.004" in text and "malloc" not in gen.source.read_text()


def _call(init, step, memory, t, x, nu, real=ctypes.c_double):
    mem = memory()
    assert init(ctypes.byref(mem)) == OK
    u = (real * nu)()
    status = step(ctypes.byref(mem), t, (real * len(x))(*x), u)
    return status, np.array(u[:]), mem


@pytest.mark.parametrize("plausible, expected", [(False, NUMERIC), (True, BAD)], ids=["any finite state", "plausible states"])
def test_overflow_gives_a_status_and_the_safe_input(tmp_path, motion, plausible, expected):
    # no bounds: a state of 1e308 overflows the law to inf; the step must not hand it out. With the
    # controller's plausible measurement (1e6 state scales beyond the reference) it is rejected before
    ode, t, x, u = motion
    c = tracking_controller(ode, t, x, u, u_lb=[-np.inf], u_ub=[np.inf], Q=[1e-2, 1.0, 1e-4])
    loop = tracking_step(c)
    gen, lib = _compiled(loop if plausible else dataclasses.replace(loop, x_range=None), tmp_path / "src", "gt_t")
    memory, init, step = load_loop_step(gen, lib)
    status, got, mem = _call(init, step, memory, 0.1, [0.0, 1e308, 0.0], 1)
    assert status == expected and got == pytest.approx(c.u_initial) and mem.status == expected and mem.steps == 1


def _counting_step():
    """A step with an inner memory (a counter, as an MPC's warm start) that fails for x[0] > 5."""
    t, x, u_last, w = ca.MX.sym("t"), ca.MX.sym("x", 2), ca.MX.sym("u_last", 1), ca.MX.sym("w", 1)
    f = ca.Function("control", [t, x, u_last, w], [3.0 * x[0] + w, w + 1, x[0] <= 5], ["t", "x", "u_last", "w"], ["u", "w_next", "ok"])
    return LoopStep(name="counter", function=f, dt=0.004, u_lb=np.array([-4.0]), u_ub=np.array([4.0]), u_init=np.array([9.0]),
                    x_names=["a", "b"], u_names=["v"], w_init=np.array([0.5]), fail_status="GT_NOT_CONVERGED",
                    x_samples=np.zeros((1, 2)))


def test_inner_memory_and_failure_status(tmp_path):
    gen, lib = _compiled(_counting_step(), tmp_path / "src", "gt_count")
    memory, init, step = load_loop_step(gen, lib)
    mem = memory()
    init(ctypes.byref(mem))
    u = (ctypes.c_double * 1)()
    results = [(step(ctypes.byref(mem), 0.0, (ctypes.c_double * 2)(*xs), u), u[0], mem.w[0]) for xs in ([1.0, 0.0], [0.2, 0.0], [6.0, 0.0])]
    # 3*1 + 0.5 = 3.5; 3*0.2 + 1.5 = 2.1; x[0] = 6 fails: the last input 2.1 (saturated), memory kept
    assert results == [(OK, 3.5, 1.5), (OK, pytest.approx(2.1), 2.5), (NOT_CONVERGED, pytest.approx(2.1), 2.5)]
    assert mem.steps == 3 and mem.status == NOT_CONVERGED
    assert mem.u_last[0] == pytest.approx(2.1)
    report = check_loop_step(gen, n=50)
    assert report.passed, "\n".join(report.summary_lines())


def test_initial_input_is_saturated(tmp_path):
    gen, lib = _compiled(_counting_step(), tmp_path / "src", "gt_count")
    memory, init, step = load_loop_step(gen, lib)
    status, got, _ = _call(init, step, memory, np.nan, [0.0, 0.0], 1)
    assert status == BAD and got[0] == 4.0  # u_init 9 saturated at 4


@pytest.mark.parametrize(
    "change, match",
    [
        ({"dt": 0.0}, r"dt: expected a positive loop period in seconds, got 0\.0"),
        ({"u_lb": np.array([5.0])}, "u_lb <= u_ub"),
        ({"u_init": np.array([1.0, 2.0])}, "u_init: expected 1 values, got 2"),
        ({"fail_status": "GT_OK"}, "fail_status: expected a failure status"),
        ({"function": ca.Function("f", [T := ca.MX.sym("t")], [2 * T])}, r"function: expected inputs \['t', 'x', 'u_last'\]"),
        ({"x_range": np.zeros((2, 3))}, r"x_range: expected a \(2, 2\) array of the lowest and highest plausible values, got shape \(2, 3\)"),
        ({"w_range": np.array([[1.0], [2.0]])}, "u_init, w_init: expected the first memory inside u_range, w_range"),
        ({"reset": ca.Function("reset", [T], [T], ["t"], ["u_last"])}, r"reset: expected a casadi.Function reset\(t, x\) -> \(u_last, w\)"),
        ({"predict": ca.Function("predict", [T], [T], ["w"], ["x"])}, r"predict: expected a casadi.Function predict\(u_last, w\) -> x"),
    ],
    ids=["dt", "bounds", "u_init", "status", "interface", "x_range", "w_range", "reset", "predict"],
)
def test_bad_loop_step(tmp_path, change, match):
    step = LoopStep(**{**_counting_step().__dict__, **change})
    with pytest.raises(InputError, match=match):
        generate_loop_step(step, tmp_path)


def _result_folder(root, ode, t, x, u, kind="optimal_control"):
    root.mkdir()
    with open(root / "trajectories.csv", "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["t", *ode.x_names, *ode.u_names])
        w.writerows([[t[k], *x[k], *u[k]] for k in range(t.size)])
    (root / "problem.toml").write_text('[bounds]\n"src.v" = [-10.0, 10.0]\n')
    (root / "summary.json").write_text(json.dumps({
        "kind": kind, "status": "optimal", "problem": str(root / "problem.toml"),
        "model": {"file": str(MOTOR), "class": "DCMotorModel"}, "model_parameters": {"r.R": 0.5},
        # as gtmodel solve writes them: the verification (a result is tracked verified) and the NLP's bounds
        "verification": {"passed": True, "status": "passed"}, "bounds": {"src.v": [-10.0, 10.0]}}))
    return root


def test_cli_codegen_controller_result_folder(tmp_path, capsys, motion):
    folder = _result_folder(tmp_path / "result", *motion)
    code = main(["codegen", "--controller", str(folder), "--out", str(tmp_path / "c"), "--check", "-n", "200", "--q", "0.01,1,1e-4"])
    out = capsys.readouterr().out
    assert code == EXIT_OK, out
    assert "PASSED" in out and "101 samples at 0.004 s" in out and "input bounds [-10.0] .. [10.0]" in out
    # the closed loop of the file route on the nominal plant (one-sample delay): the figures and the verdict
    assert "RMS ratio tracking controller / feedforward" in out and "closed-loop check: PASSED" in out


def test_delay_compensating_controller_c_equals_python(tmp_path, motion):
    # the predicted state (the model's RK4 step from u_last) is in the generated C too
    ode, t, x, u = motion
    c = tracking_controller(ode, t, x, u, u_lb=[-10.0], u_ub=[10.0], Q=[1e-2, 1.0, 1e-4], delay=1)
    gen = generate_loop_step(tracking_step(c), tmp_path / "src", prefix="gt_tracking")
    report = check_loop_step(gen, n=300)
    assert report.passed, "\n".join(report.summary_lines())
    assert report.functions[0].max_abs_diff <= 1e-12 and "One period of input delay compensated" in gen.header.read_text()


@pytest.mark.parametrize(
    "kind, args, match",
    [
        ("point_to_point", [], r"summary\.json: kind: expected an optimal_control \(or optimica\) result, got 'point_to_point'"),
        ("optimal_control", ["--q", "1,x"], r"--q: expected comma-separated numbers, got '1,x'"),
        ("optimal_control", ["--robot", "L1"], r"--controller RESULT_DIR generates the tracking controller alone"),
        ("optimal_control", ["--mismatch", "0"], r"--mismatch: expected a factor in \(0, 10\] on the plant's parameters, got 0\.0"),
    ],
    ids=["kind", "weights", "robot", "mismatch"],
)
def test_cli_codegen_controller_bad_result(tmp_path, capsys, motion, kind, args, match):
    folder = _result_folder(tmp_path / "result", *motion, kind=kind)
    code = main(["codegen", "--controller", str(folder), "--out", str(tmp_path / "c"), *args])
    err = capsys.readouterr().err
    assert code == EXIT_BAD_INPUT and "Traceback" not in err and re.search(match, err), err


def _memory_step(memory, init, step, nx, nu):
    """A call ``(t, x) -> (status, u)`` on one memory after ``_init``, and the memory."""
    mem = memory()
    assert init(ctypes.byref(mem)) == OK
    u = (ctypes.c_double * nu)()

    def call(t, x):
        return step(ctypes.byref(mem), t, (ctypes.c_double * nx)(*x), u), np.array(u[:])

    return call, mem


@pytest.mark.parametrize("value", [np.nan, 1e150], ids=["nan", "1e150"])
def test_tracking_integrator_poisoned_is_reset(tmp_path, motion, value):
    # reference: the law from Python with the reset memory (u_last = u*_k saturated, integrator 0)
    ode, t, x, u = motion
    c = tracking_controller(ode, t, x, u, u_lb=[-10.0], u_ub=[10.0], Q=[1e-2, 1.0, 1e-4], integral_weights={"emf.phi": 1e3})
    gen, lib = _compiled(tracking_step(c), tmp_path / "src", "gt_ti")
    call, mem = _memory_step(*load_loop_step(gen, lib), 3, 1)
    assert call(0.1, x[10])[0] == OK
    mem.w[0] = value
    status, got = call(0.104, x[10])
    u_reset = np.clip(u[period_index(0.104, 0.0, 0.004, c.length - 1)], -10, 10)
    want = c(0.104, x[10], u_reset, np.zeros(1))
    assert status == MEMORY_RESET and got == pytest.approx(want, rel=1e-12, abs=1e-12) and mem.status == MEMORY_RESET
    assert call(0.108, x[10])[0] == OK


def test_tracking_absurd_measurement_keeps_the_integrator(tmp_path, motion):
    ode, t, x, u = motion
    c = tracking_controller(ode, t, x, u, u_lb=[-10.0], u_ub=[10.0], Q=[1e-2, 1.0, 1e-4], integral_weights={"emf.phi": 1e3})
    gen, lib = _compiled(tracking_step(c), tmp_path / "src", "gt_ti")
    call, mem = _memory_step(*load_loop_step(gen, lib), 3, 1)
    _, u_ok = call(0.1, x[10] + np.array([0.0, 0.01, 0.0]))
    xi = mem.w[0]
    status, got = call(0.104, [1e150, 0.0, 0.0])  # beyond 1e6 state scales: rejected, no prediction (no state in the memory)
    assert status == BAD and got == pytest.approx(u_ok) and mem.w[0] == xi


def _glitch_mpc_controller():
    """A small offset-free MPC (double integrator, horizon 4): quick to build; with its time and reference."""
    ode = explicit_ode(double_integrator()[0])
    t = 0.004 * np.arange(101)
    x_ref = np.column_stack([np.minimum(t / 0.2, 1.0), np.where(t < 0.2, 5.0, 0.0)])
    c = mpc_controller(ode, t, x_ref, np.zeros((101, 1)), horizon=4, Q=[1.0, 0.01], R=[1e-4], u_lb=[-50.0], u_ub=[50.0],
                       method="euler", disturbance_gain=0.5)
    return c, t, x_ref


def _glitch_mpc(folder):
    """The MPC of :func:`_glitch_mpc_controller` as C, checked."""
    c, _, _ = _glitch_mpc_controller()
    gen = generate_loop_step(mpc_step(c, "di"), folder, prefix="gt_di")
    report = check_loop_step(gen, n=50)  # its strict build is the library of the test
    return c, gen, report


def _mpc_loop(c, call, glitch=None, n=60):
    """The MPC against its own model (a plant 1 m/s^2 off, its estimate takes it): the inputs and statuses."""
    x, us, statuses = np.zeros(2), [], []
    for k in range(n):
        status, u = call(0.004 * k, x if glitch is None else glitch(k, x.copy()))
        us.append(u[0])
        statuses.append(status)
        x = np.asarray(c.step(x, u + 1.0)).reshape(-1)
    return np.array(statuses), np.array(us)


def test_mpc_spike_and_poisoned_memory_recover(tmp_path):
    # fast variant of tests/codegen/test_loop_step_glitch.py. References: the spike-free run of the
    # same step; the contract probes of check_loop_step (C equal to the Functions from Python)
    c, gen, report = _glitch_mpc(tmp_path / "src")
    assert report.passed, "\n".join(report.summary_lines())
    assert [f.name for f in report.functions] == ["control", "memory_reset", "predict"]
    assert {p.expected for p in report.probes} >= {"GT_MEASUREMENT_REJECTED", "GT_MEMORY_RESET"}
    loaded = load_loop_step(gen, load_library(gen, report.library))
    call, mem = _memory_step(*loaded, 2, 1)
    free_status, free = _mpc_loop(c, call)
    assert np.all(free_status == OK)

    def spike(k, x):
        if k == 20:
            x[0] = 1e150
        if k == 30:
            x[1] = 1e3  # inside the measurement limit, but it drives the estimate beyond its range (1.25e5 > 500 N)
        return x

    call, mem = _memory_step(*loaded, 2, 1)
    status, got = _mpc_loop(c, call, spike)
    assert status[20] == REJECTED and status[30] == REJECTED and np.all(np.delete(status, [20, 30]) == OK)
    assert np.max(np.abs(got - free)[25:]) <= 0.01 * 50.0

    def poison(k, x):
        if k == 20:
            mem.w[4] = np.nan  # the disturbance estimate
        return x

    call, mem = _memory_step(*loaded, 2, 1)
    status, got = _mpc_loop(c, call, poison)
    assert status[20] == MEMORY_RESET and np.all(np.delete(status, 20) == OK) and np.all(np.abs(got) <= 50.0)
    assert np.max(np.abs(got - free)[25:]) <= 0.01 * 50.0  # the estimate, reset to zero, converges again (gain 0.5)


def test_single_precision_step_keeps_the_contract(tmp_path, motion):
    # float: the plausible ranges as float constants (beyond FLT_MAX: none), the probes at the float tolerance (1e-4)
    ode, t, x, u = motion
    c = tracking_controller(ode, t, x, u, u_lb=[-np.inf], u_ub=[np.inf], Q=[1e-2, 1.0, 1e-4], integral_weights={"emf.phi": 1e3})
    report = check_loop_step(generate_loop_step(tracking_step(c), tmp_path / "src", prefix="gt_f", real="float"), n=50)
    assert report.passed, "\n".join(report.summary_lines())
    assert {p.expected for p in report.probes} >= {"GT_MEMORY_RESET"}

def test_a_float_mpc_step_passes_within_its_derived_tolerance(tmp_path):
    """The float step of an MPC: qrqp stops at QP_FLOAT_TOLERANCE, the check compares within
    MPCController.float_tolerance (>= 1e-4); its declaration carries that tolerance."""
    c, _, _ = _glitch_mpc_controller()
    step = mpc_step(c, "di", real="float")
    assert step.real == "float" and step.float_tolerance == pytest.approx(max(1e-4, c.float_tolerance()))
    gen = generate_loop_step(step, tmp_path / "src", prefix="gt_df", real="float")
    assert gen.specs[0].float_tolerance == step.float_tolerance
    report = check_loop_step(gen, n=50)
    assert report.passed, "\n".join(report.summary_lines())


@pytest.mark.parametrize("built, asked", [("double", "float"), ("float", "double")])
def test_an_mpc_step_is_generated_only_in_its_own_real_type(tmp_path, built, asked):
    c, _, _ = _glitch_mpc_controller()
    with pytest.raises(InputError, match=f"real: the step of di was built for real = '{built}'"):
        generate_loop_step(mpc_step(c, "di", real=built), tmp_path / "src", prefix="gt_di", real=asked)


def test_mpc_step_refuses_another_real_type():
    c, _, _ = _glitch_mpc_controller()
    with pytest.raises(InputError, match="real: expected 'double' or 'float', got 'half'"):
        mpc_step(c, "di", real="half")


def test_a_float_step_refuses_a_reference_longer_than_float32_can_index(tmp_path, motion):
    """Beyond FLOAT_PERIOD_LIMIT periods float32's round-off of (t - t0) / dt exceeds the period
    slack (a grid time would read the row before it): refused before anything is written."""
    ode, t, x, u = motion
    step = tracking_step(tracking_controller(ode, t, x, u, u_lb=[-10.0], u_ub=[10.0], Q=[1e-2, 1.0, 1e-4]))
    long_step = dataclasses.replace(step, t_range=(0.0, step.dt * (FLOAT_PERIOD_LIMIT + 10)))
    with pytest.raises(InputError, match="real: 'float' cannot index .* periods .* use real = 'double'"):
        generate_loop_step(long_step, tmp_path / "src", prefix="gt_f", real="float")
    assert not (tmp_path / "src").exists()


HOSTILE_NAME = ('p"; } int system(const char *); __attribute__((constructor)) static void pwn(void) '
                '{ system("touch PWNED"); } const char *gt_q(void) { return "')


def _exported(library) -> list[str]:
    out = subprocess.run(["nm", "-D", "--defined-only", str(library)], check=True, capture_output=True, text=True).stdout
    return sorted(line.split()[-1] for line in out.splitlines() if line.strip())


def test_a_hostile_controller_name_and_description_stay_text(tmp_path, monkeypatch):
    """The issue's name as the controller's name, a description breaking comments and lines: the C
    builds with -Werror, exports what a plain name's does (nm), behaves alike (the step of
    test_inner_memory_and_failure_status), holds the name byte for byte in its version, creates no file."""
    monkeypatch.chdir(tmp_path)
    plain = _counting_step()
    hostile = dataclasses.replace(plain, name=HOSTILE_NAME, description=f"{HOSTILE_NAME}\n*/ #include </etc/passwd>\n??/\n\\")
    runs = []
    for step, folder in ((plain, "plain"), (hostile, "hostile")):
        gen, lib = _compiled(step, tmp_path / folder, "gt_count")
        memory, init, call = load_loop_step(gen, lib)
        mem = memory()
        init(ctypes.byref(mem))
        u = (ctypes.c_double * 1)()
        outs = [(call(ctypes.byref(mem), 0.0, (ctypes.c_double * 2)(*xs), u), u[0]) for xs in ([1.0, 0.0], [6.0, 0.0])]
        runs.append((_exported(lib.path), outs, lib.version()))
    assert runs[0][:2] == runs[1][:2]
    assert f"controller {HOSTILE_NAME} sha256:" in runs[1][2]
    assert not list(tmp_path.rglob("PWNED"))
