"""Tracking-controller files (``gtmodel codegen --controller FILE.toml``): validation on load,
errors naming the file and the field, exit 2; the shipped DC motor file built and run in
closed loop with its generated C.

References: the declared contract of :mod:`gtmodel.problems.tracking_file` (a period > 0,
weights only of the model's variables, no unknown fields such as an MPC's horizon, a
``[reference]`` required); the closed loop of the compiled C step against the same loop
with the controller's CasADi Function called from Python (the same inputs to the last bit),
and against the feedforward alone on the same mismatched plant (the tracking controller must
cut its RMS error to below 5 %: measured 1.6 %).
"""

from __future__ import annotations

import re

import numpy as np
import pytest

from gtmodel.cli import main
from gtmodel.codegen.build import compile_shared
from gtmodel.codegen.loop_step import generate_loop_step, tracking_step
from gtmodel.errors import ProblemError
from gtmodel.estimation.closed_loop.controller_loop import run_controller_loop
from gtmodel.problems.loop_check import closed_loop_check, compiled_step
from gtmodel.problems.tracking_file import load_tracking_file

from ..conftest import REPO

CTRL_DIR = REPO / "codegen" / "controllers"
L1 = (CTRL_DIR / "l1_tracking.toml").read_text()
MOTOR = (CTRL_DIR / "dc_motor_tracking.toml").read_text()
_REFERENCE = MOTOR[MOTOR.index("\n[reference]"):MOTOR.index("\n[check]")]

#: (case, file text, original, replacement, field named in the error)
BAD = [
    ("period 0", L1, "period = 0.004 ", "period = 0.0 ", "controller.period"),
    ("period negative", MOTOR, "period = 0.004", "period = -0.004", "controller.period"),
    ("unknown state", L1, '"T[0]" = 1e8', '"T[9]" = 1e8', "controller.state_weights.T[9]"),
    ("unknown input", MOTOR, '"src.v" = 1e-3', '"src.u" = 1e-3', "controller.input_weights.src.u"),
    ("unknown terminal state", MOTOR, "input_weights =", 'terminal_weights = { "phi" = 1.0 }\ninput_weights =', "controller.terminal_weights.phi"),
    ("negative weight", MOTOR, '"src.v" = 1e-3', '"src.v" = -1.0', "controller.input_weights.src.v"),
    ("horizon-free", L1, "period = 0.004 ", "horizon = 20\nperiod = 0.004 ", "controller.horizon"),
    ("unknown field", MOTOR, "time_varying = true", "time_variant = true", "controller.time_variant"),
    ("time_varying not a bool", MOTOR, "time_varying = true", 'time_varying = "yes"', "controller.time_varying"),
    ("input delay 2", MOTOR, "input_delay = 1", "input_delay = 2", "controller.input_delay"),
    ("method unknown", MOTOR, 'method = "rk4"', 'method = "euler"', "controller.method"),
    ("missing reference", MOTOR, _REFERENCE, "", "reference"),
    ("bounds of another length", MOTOR, "period = 0.004", "period = 0.004\nu_lb = [-1.0, -2.0]\nu_ub = [1.0, 2.0]", "controller.u_lb"),
    ("unknown error state", MOTOR, 'error_states = ["emf.phi"]', 'error_states = ["phi"]', "check.error_states.phi"),
    ("integral of an unknown state", MOTOR, '"emf.phi" = 1e4 }', '"phi" = 1e4 }', "controller.integral_weights.phi"),
    ("integral weight 0", MOTOR, '"emf.phi" = 1e4 }', '"emf.phi" = 0.0 }', "controller.integral_weights.emf.phi"),
    ("measurement noise of another length", MOTOR, "time_varying = true", "time_varying = true\nmeasurement_noise = [1e-3, 1e-3]",
     "controller.measurement_noise"),
    ("measurement noise negative", MOTOR, "time_varying = true", "time_varying = true\nmeasurement_noise = [1e-3, -1e-3, 1e-2]",
     "controller.measurement_noise"),
    ("noise gain limit above 1", MOTOR, "time_varying = true", "time_varying = true\nnoise_gain_limit = 1.5", "controller.noise_gain_limit"),
    ("noise gain limit negative", MOTOR, "time_varying = true", "time_varying = true\nnoise_gain_limit = -0.1", "controller.noise_gain_limit"),
]


def _write(tmp_path, text, old, new):
    assert old in text
    path = CTRL_DIR / f"_test_{tmp_path.name}.toml"  # beside the shipped files: their relative references hold
    path.write_text(text.replace(old, new, 1))
    return path


@pytest.mark.parametrize("case, text, old, new, field", BAD, ids=[b[0] for b in BAD])
def test_bad_tracking_file_names_file_and_field(tmp_path, case, text, old, new, field):
    path = _write(tmp_path, text, old, new)
    try:
        with pytest.raises(ProblemError, match=re.escape(str(path)) + r".*'?" + re.escape(field)):
            load_tracking_file(path)
    finally:
        path.unlink()


@pytest.mark.parametrize("case, text, old, new, field", [BAD[0], BAD[2], BAD[6], BAD[11]], ids=[BAD[i][0] for i in (0, 2, 6, 11)])
def test_bad_tracking_file_exits_2(tmp_path, capsys, case, text, old, new, field):
    path = _write(tmp_path, text, old, new)
    try:
        code = main(["codegen", "--controller", str(path), "--out", str(tmp_path / "out")])
    finally:
        path.unlink()
    err = capsys.readouterr().err
    assert code == 2
    assert str(path) in err and field in err and "Traceback" not in err
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("flags", [["--q", "1,1,1"], ["--period", "0.002"], ["--robot", "L1"], ["--mismatch", "1.1"]],
                         ids=["q", "period", "robot", "mismatch"])
def test_file_flags_of_other_routes_are_refused(tmp_path, capsys, flags):
    code = main(["codegen", "--controller", str(CTRL_DIR / "dc_motor_tracking.toml"), "--out", str(tmp_path / "out"), *flags])
    assert code == 2
    assert f"give it without {flags[0]}" in capsys.readouterr().err


@pytest.fixture(scope="module")
def motor():
    return load_tracking_file(CTRL_DIR / "dc_motor_tracking.toml")


def test_motor_file_builds_its_controller(motor):
    # the composed DC motor (models/dc_motor.py), bounds of problems/dc_motor_move.toml (not the 20 V override)
    c = motor.controller
    assert (c.dt, c.delay) == (0.004, 1)
    assert c.x_names == ["ind.i", "emf.phi", "rotor.w"] and c.u_names == ["src.v"]
    assert (c.u_lb.tolist(), c.u_ub.tolist()) == ([-24.0], [24.0])
    assert np.max(np.abs(c.u_ref)) <= 20.0 + 1e-6
    assert motor.loop["error_states"] == [1] and motor.loop["delay"] == 1


@pytest.fixture(scope="module")
def motor_loop(motor, tmp_path_factory):
    out = tmp_path_factory.mktemp("dc_motor_tracking")
    code = main(["codegen", "--controller", str(CTRL_DIR / "dc_motor_tracking.toml"), "--out", str(out), "--check", "-n", "200"])
    assert code == 0
    generated = generate_loop_step(tracking_step(motor.controller, motor.name), out / "again", prefix=f"gt_{motor.name}")
    return generated, compile_shared(generated, out / "again" / "build")


def test_motor_closed_loop_c_equals_python_and_beats_the_feedforward(motor, motor_loop):
    generated, library = motor_loop
    check = closed_loop_check(motor, generated, library, label="tracking controller")
    # the same loop (plant, noise, delay, disturbance) with the step's Function evaluated from Python, u_last and the
    # memory (the file's integral action on the angle, then the measurement filter of its [check] noise) carried as
    # the C memory does
    c = motor.controller
    step = tracking_step(c, motor.name)
    assert c.integral_states == (1,) and c.state_filter is not None
    law, memory = step.function, {"u": c.u_initial, "w": step.w_init}

    def python(t, x):
        out = law(t, x, memory["u"], memory["w"])
        memory["u"], memory["w"] = np.asarray(out[0]).ravel(), np.asarray(out[1]).ravel()
        return 0, memory["u"]

    ref = run_controller_loop(python, motor.plant_step, motor.plant_x0, motor.t, motor.x_ref, **dict(motor.loop, plant_p=motor.plant_p))
    np.testing.assert_array_equal(check.closed.u, ref.u)
    assert check.ratio_to_feedforward < 0.05
    assert check.closed.bound_violations == 0 and check.failed_steps == 0


def test_failed_step_returns_a_status_and_the_last_input_saturated(motor, motor_loop):
    controller, _, _ = compiled_step(*motor_loop)
    status, u_ok = controller(0.1, motor.x_ref[25])
    assert status == 0
    status, u = controller(0.104, np.r_[np.nan, 0.0, 0.0])
    assert status != 0
    np.testing.assert_array_equal(u, np.clip(u_ok, motor.controller.u_lb, motor.controller.u_ub))


@pytest.mark.slow  # tens of seconds of the default run's budget (measured 2026-11-28)
def test_l1_tracking_file_halves_the_feedforward_error_in_closed_loop(tmp_path):
    # the L1 plant 10 % off in masses and friction, with the tool structure of eq. 6.14, noise, a 20 N step and one
    # sample of delay: the MPC's bar (half the feedforward's RMS error; measured 0.0096), no bound violated, no step failed
    setup = load_tracking_file(CTRL_DIR / "l1_tracking.toml")
    generated = generate_loop_step(tracking_step(setup.controller, setup.name), tmp_path, prefix=f"gt_{setup.name}")
    check = closed_loop_check(setup, generated, compile_shared(generated, tmp_path / "build"), label="tracking controller")
    assert check.ratio_to_feedforward < 0.5
    assert check.closed.bound_violations == 0 and check.closed.status_counts == {"GT_OK": setup.t.size}


@pytest.mark.parametrize("changes, field, match", [
    # one 10 ms RK4 step against the motor's electrical pole (L/R = 1.7 ms: |lambda h| = 5.9 > 2.785)
    ({"period = 0.004": "period = 0.02"}, "controller", r"rk4 with 2 substep\(s\) of 0.01 s meets the eigenvalue -5\d\d"),
    # the controller implicit, the check's plant one RK4 step of 20 ms
    ({"period = 0.004": "period = 0.02", 'method = "rk4"': 'method = "radau2"', "max_ratio = 0.5": "plant_substeps = 1\nmax_ratio = 0.5"},
     "check.plant_substeps", r"a stable plant step: the check's plant step .* give plant_substeps = \d+ .*got 1"),
], ids=["controller", "plant"])
def test_an_unstable_explicit_step_is_refused_with_the_substeps_it_needs(tmp_path, changes, field, match):
    # independent check of the deciding number: tests/modeling/simulation/test_step_stability.py (the step's own growth)
    assert [MOTOR.count(old) for old in changes] == [1] * len(changes)
    text = MOTOR
    for old, new in changes.items():
        text = text.replace(old, new)
    path = _write(tmp_path, text, "[check]", "[check]")
    try:
        with pytest.raises(ProblemError, match=re.escape(str(path)) + f".*'{re.escape(field)}'.*" + match):
            load_tracking_file(path)
    finally:
        path.unlink()


def _motor_controller(tmp_path, extra: str):
    """The shipped motor file's controller with ``extra`` lines after its ``time_varying``."""
    path = _write(tmp_path, MOTOR, "time_varying = true", "time_varying = true" + extra)
    try:
        return load_tracking_file(path).controller
    finally:
        path.unlink()


@pytest.mark.parametrize("declared, filtered", [(None, True), ("[0.0, 0.0, 0.0]", False), ("[]", False), ("[1e-3, 1e-3, 1e-2]", True)])
def test_the_measurement_filter_follows_the_declared_noise(tmp_path, declared, filtered):
    # default: [check] noise (the shipped file's); zeros or an empty list: none
    c = _motor_controller(tmp_path, "" if declared is None else f"\nmeasurement_noise = {declared}")
    assert (c.state_filter is not None) is filtered
    if filtered:
        np.testing.assert_array_equal(c.state_filter.sigma, [1e-3, 1e-3, 1e-2])
        assert c.state_filter.p is not None and c.state_filter.p.size > 0


@pytest.mark.parametrize("limit, noise, limited", [
    (None, "[1e-3, 1e-3, 1e-2]", False),   # the shipped motor's gains: a one-sigma error moves its 20 V by far less than 10 %
    ("1e-4", "[1e-3, 1e-3, 1e-2]", True),  # a limit of 1e-4 of the half range: every row scaled down to it
    ("0.0", "[1e-3, 1e-3, 1e-2]", False),  # no limit
    ("1e-4", "[]", False),                 # no filter, no noise assumed: no limit
])
def test_the_noise_gain_limit_scales_the_gains_the_filters_noise_would_carry_too_far(tmp_path, limit, noise, limited):
    # reference: limit_noise_gain (tests/control/test_tracking.py): the limited rows' one-sigma response equals the limit
    c = _motor_controller(tmp_path, f"\nmeasurement_noise = {noise}" + ("" if limit is None else f"\nnoise_gain_limit = {limit}"))
    assert (c.gain_scale is not None) is limited
    if limited:
        sigma, half = c.state_filter.sigma, (c.u_ub - c.u_lb) / 2
        np.testing.assert_allclose(np.sqrt(np.sum((c.K * sigma) ** 2, axis=2))[:, 0], 1e-4 * half[0], rtol=1e-9)
