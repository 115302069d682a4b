"""MPC files (``gtmodel codegen --mpc FILE``): validation on load, errors naming the file and the field, exit 2.

Reference: the declared contract of :mod:`gtmodel.problems.mpc_file` (a horizon >= 1, a period
> 0, weights only of the model's variables, blocks dividing the horizon, no unknown fields).
"""

from __future__ import annotations

import re

import numpy as np
import pytest

from gtmodel._tables import write_table

from gtmodel.cli import main
from gtmodel.errors import ProblemError
from gtmodel.problems.mpc_file import load_mpc_file

from ..conftest import REPO

MPC_DIR = REPO / "codegen" / "mpc"
L1 = (MPC_DIR / "l1_mpc.toml").read_text()
MOTOR = (MPC_DIR / "dc_motor_mpc.toml").read_text()

#: (case, file text, original, replacement, field named in the error)
BAD = [
    ("horizon 0", L1, "horizon = 20 ", "horizon = 0 ", "mpc.horizon"),
    ("period 0", L1, "period = 0.004 ", "period = 0.0 ", "mpc.period"),
    ("period negative", MOTOR, "period = 0.004", "period = -0.004", "mpc.period"),
    ("unknown state", L1, '"T[0]" = 1e8', '"T[9]" = 1e8', "mpc.state_weights.T[9]"),
    ("unknown input", MOTOR, '"src.v" = 1e-3', '"src.u" = 1e-3', "mpc.input_weights.src.u"),
    ("unknown field", L1, "sqp_iterations = 1 ", "sqp_iteration = 1 ", "mpc.sqp_iteration"),
    ("blocks not a divisor", L1, "blocks = 5 ", "blocks = 3 ", "mpc.blocks"),
    ("sqp iterations 0", MOTOR, "sqp_iterations = 1", "sqp_iterations = 0", "mpc.sqp_iterations"),
    ("solver unknown", MOTOR, 'solver = "sqpmethod"', 'solver = "osqp"', "mpc.solver"),
    ("unknown bounded state", MOTOR, 'input_weights = {', 'state_ub = { "rotor.x" = 80.0 }\ninput_weights = {', "mpc.state_ub.rotor.x"),
    ("crossed state bounds", MOTOR, 'input_weights = {', 'state_lb = { "rotor.w" = 9.0 }\nstate_ub = { "rotor.w" = 8.0 }\ninput_weights = {', "mpc.state_lb.rotor.w"),
    ("constraint_every 0", L1, "constraint_every = 4", "constraint_every = 0", "mpc.constraint_every"),
    ("plant method unknown", MOTOR, 'error_states = ["emf.phi"]', 'error_states = ["emf.phi"]\nplant_method = "rk5"', "check.plant_method"),
    ("plant method with compliance", L1, "compliance = true", 'compliance = true\nplant_method = "radau2"', "check.plant_method"),
    ("unknown error state", MOTOR, 'error_states = ["emf.phi"]', 'error_states = ["phi"]', "check.error_states.phi"),
    ("max_ratio above 1", MOTOR, "max_ratio = 0.5", "max_ratio = 1.5", "check.max_ratio"),
    ("disturbance gain above 1", MOTOR, "disturbance_gain = 0.3", "disturbance_gain = 1.5", "mpc.disturbance_gain"),
    ("disturbance gain with fatrop", MOTOR, 'solver = "sqpmethod"', 'solver = "fatrop"', "mpc.disturbance_gain"),
    ("unknown parameter factor", MOTOR, "parameter_factor = 1.1", 'parameter_factor = 1.1\nparameter_factors = { "r.X" = 1.0 }', "check.parameter_factors.r.X"),
    ("parameter factor 0", MOTOR, "parameter_factor = 1.1", 'parameter_factor = 1.1\nparameter_factors = { "r.R" = 0.0 }', "check.parameter_factors.r.R"),
    ("parameter factors of a robot", L1, "mass_factor = 1.1", 'mass_factor = 1.1\nparameter_factors = { "m" = 1.0 }', "check.parameter_factors"),
    ("max_step_time negative", MOTOR, 'error_states = ["emf.phi"]', 'error_states = ["emf.phi"]\nmax_step_time = -1e-3', "check.max_step_time"),
]


def _write(tmp_path, text, old, new):
    assert old in text
    path = MPC_DIR / f"_test_{tmp_path.name}.toml"  # beside the shipped files: their relative references hold
    path.write_text(text.replace(old, new, 1))
    return path


@pytest.mark.parametrize("case, text, old, new, field", BAD, ids=[b[0] for b in BAD])
def test_bad_mpc_file_names_file_and_field(tmp_path, case, text, old, new, field):
    path = _write(tmp_path, text, old, new)
    try:
        with pytest.raises(ProblemError, match=re.escape(str(path)) + r".*" + re.escape(field)):
            load_mpc_file(path)
    finally:
        path.unlink()


@pytest.mark.parametrize("case, text, old, new, field", BAD[:4], ids=[b[0] for b in BAD[:4]])
def test_bad_mpc_file_exits_2(tmp_path, capsys, case, text, old, new, field):
    path = _write(tmp_path, text, old, new)
    try:
        code = main(["codegen", "--mpc", str(path), "--out", str(tmp_path / "out")])
    finally:
        path.unlink()
    assert code == 2
    assert field in capsys.readouterr().err
    assert not (tmp_path / "out").exists()


def test_motor_file_builds_its_controller():
    # the composed DC motor (models/dc_motor.py) reduced to its explicit ODE, bounds from the file
    setup = load_mpc_file(MPC_DIR / "dc_motor_mpc.toml")
    c = setup.controller
    assert (c.horizon, c.blocks, c.sqp_iterations, c.dt) == (20, 20, 1, 0.004)
    assert c.x_names == ["ind.i", "emf.phi", "rotor.w"] and c.u_names == ["src.v"]
    assert (c.u_lb.tolist(), c.u_ub.tolist()) == ([-24.0], [24.0])  # problems/dc_motor_move.toml's bounds, not the override
    assert np.max(np.abs(c.u_ref)) <= 20.0 + 1e-6  # planned with the override's 20 V
    assert setup.loop["error_states"] == [1] and setup.loop["delay"] == 1


def test_reference_table_of_a_user_model(tmp_path):
    # [reference] file: a CSV of t and the model's variables, sampled onto the period
    t = np.linspace(0.0, 0.2, 11)
    write_table(tmp_path / "ref.csv", ["t", "ind.i", "emf.phi", "rotor.w", "src.v"], np.column_stack([t, 0 * t, t, 1 + 0 * t, 2 + 0 * t]))
    text = MOTOR.replace('problem = "../../problems/dc_motor_move.toml"', 'file = "ref.csv"').replace('model = "../../models/', f'model = "{REPO}/models/')
    text = "\n".join(line for line in text.splitlines() if not line.startswith("overrides"))
    (tmp_path / "m.toml").write_text(text + '\n')
    c = load_mpc_file(tmp_path / "m.toml").controller
    assert c.length == 51 + int(round(0.3 / 0.004))  # 0.2 s at 4 ms, then the settling hold
    np.testing.assert_allclose(c.x_ref[:51, 1], np.arange(51) * 0.004, atol=1e-12)  # linear in t: sampled exactly
    assert np.isinf(c.u_ub[0])  # no bounds declared: the model's (none)


def test_parameter_factors_replace_the_common_factor(tmp_path):
    # the plant's parameters: every one 1.1 times the model's, the gear ratio (a geometry known exactly) 1.0 times
    path = _write(tmp_path, MOTOR, "parameter_factor = 1.1", 'parameter_factor = 1.1\nparameter_factors = { "gear.ratio" = 1.0 }')
    try:
        setup = load_mpc_file(path)
    finally:
        path.unlink()
    shipped = load_mpc_file(MPC_DIR / "dc_motor_mpc.toml")
    ratio = setup.plant_p[:7] / shipped.plant_p[:7]  # fixed.phi0 (the 8th) is 0
    names = ["r.R", "ind.L", "emf.k", "rotor.J", "gear.ratio", "load.J", "friction.d"]
    np.testing.assert_allclose(ratio, [1.0, 1.0, 1.0, 1.0, 1 / 1.1, 1.0, 1.0], rtol=1e-12, err_msg=str(names))
