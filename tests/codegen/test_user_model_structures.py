"""Users' models no one here wrote, through explicit C, the tracking controller and the MPC (issue 36).

The models in ``tests/fixtures/user_models/`` (see its README) are structures a control engineer
brings: a two-mass flexible drive with tanh Coulomb friction, inertias rigidly coupled behind a
gearbox (index reduction), a cart with the force's bounds on the model, a motor behind a cubic
resistor and one behind a diode (the algebraic voltage by Newton inside the generated code), a
model written by equations whose names are C keywords and macros, a pendulum heating a thermal
capacity through a connector of the user's own. Each one's C steps are iterated over 250 periods
against ``simulate()`` (IDAS, an independent variable-step integrator of the same equations)
and its functions compared with the CasADi Functions evaluated from Python to 1e-12.
"""

from __future__ import annotations

import numpy as np
import pytest

from gtmodel.cli import EXIT_OK, main
from gtmodel.codegen.model_code import MODEL_TOLERANCE, _c_names, check_model, generate_model
from gtmodel.modeling import Model
from gtmodel.problems.user_model import load_user_model

from ..conftest import REPO

USER_MODELS = REPO / "tests" / "fixtures" / "user_models"

#: (file, class, structure): each a structure of its own.
STRUCTURES = [
    ("two_mass_drive.py", "TwoMass2Drive", "two_mass_drive"),
    ("rigid_gearbox.py", "Rigid3Gearbox", "rigid_coupling_gearbox"),
    ("cart_spring.py", "Cart_1", "cart_with_model_bounds"),
    pytest.param("cubic_motor.py", "Cubic4Motor", "cubic_resistor_newton", marks=pytest.mark.slow),  # ~6 s: the Newton's code
    ("keyword_names.py", "Plant2In3Out", "c_keyword_names"),
    ("pendulum_thermal.py", "PendulumHeat6", "pendulum_thermal_own_connector"),
    ("belt_cart.py", "BeltCart", "electrical_rotational_translational"),
]


@pytest.mark.parametrize("file, cls, structure", STRUCTURES)
def test_user_model_explicit_c_matches_simulate(tmp_path, file, cls, structure):
    # references: the CasADi Function from Python (1e-12) and simulate() (IDAS) over 250 periods
    model = load_user_model(USER_MODELS / file, cls)
    gen = generate_model(model, tmp_path / "src", functions=["ode", "outputs", "step_rk4"] if model.outputs else ["ode", "step_rk4"])
    report = check_model(gen, n=200, build_dir=tmp_path / "build")
    assert report.passed, "\n".join(report.summary_lines())
    horizon = next(f for f in report.functions if "periods" in f.name)
    assert horizon.max_ratio < 0.5  # the RK4 step 4 x 1 ms within half the 1e-3 (1 + |x|) tolerance
    assert max(f.max_abs_diff for f in report.functions if "periods" not in f.name) <= MODEL_TOLERANCE


@pytest.mark.slow
def test_diode_motor_explicit_c_matches_simulate(tmp_path):
    # the diode's voltage by the damped Newton from v = 0 (plain Newton overflowed exp: NaN, GT_NOT_CONVERGED);
    # reference: simulate() (IDAS, its own Newton from the last step's values) over 250 periods
    model = load_user_model(USER_MODELS / "diode_motor.py", "Diode2Motor")
    gen = generate_model(model, tmp_path / "src", functions=["ode", "step_rk4"])
    report = check_model(gen, n=200, build_dir=tmp_path / "build")
    assert report.passed, "\n".join(report.summary_lines())
    assert report.functions[0].n == 200  # Python converged on every random sample of the ODE


def test_output_names_like_macros_get_a_prefix():
    # the C parameter of an output named like a macro of the included headers or the generated code's
    names = _c_names(["NULL", "GT_OK", "casadi_f0", "gt_x", "errno", "main", "speed", "y.c", "y_c"])
    assert list(names.values()) == ["y_NULL", "y_GT_OK", "y_casadi_f0", "y_gt_x", "y_errno", "y_main", "speed", "y_c", "y_c_1"]


def test_check_reports_a_model_python_refuses_everywhere(tmp_path):
    # z^2 + 1 + x^2 = 0 has no real root: Python refuses every sample, the C says GT_NOT_CONVERGED;
    # the check fails and says so (it crashed on an empty array, then in the timing program)
    m = Model("no_root")
    x = m.state("x")
    z = m.algebraic("z", start=0.5)
    m.equation(m.der(x), -x + z)
    m.equation(z**2 + 1.0 + x**2, 0.0)
    gen = generate_model(m, tmp_path / "src", functions=["ode"])
    report = check_model(gen, n=20, build_dir=tmp_path / "build", timing=True, horizon=0)
    assert not report.passed
    assert (report.functions[0].n, report.functions[0].n_refused) == (0, 20)


@pytest.mark.slow
@pytest.mark.parametrize("stem, model, problem", [
    ("two_mass", "two_mass_drive.py:TwoMass2Drive", "two_mass_move.toml"),
    ("keyword", "keyword_names.py:Plant2In3Out", "keyword_move.toml"),
    ("belt", "belt_cart.py:BeltCart", "belt_move.toml"),
])
def test_user_model_full_path_to_the_loop(tmp_path, capsys, stem, model, problem):
    # the user's path of docs/model_in_the_loop.md, no C by hand: explicit C, solve, tracking C, MPC C;
    # references: simulate() (the model's C), the Python Functions (the controllers' C), the
    # feedforward alone on the mismatched plant (the MPC's closed loop must beat it)
    assert main(["codegen", "--model", str(USER_MODELS / model.split(":")[0]) + ":" + model.split(":")[1],
                 "--out", str(tmp_path / "c"), "--check", "-n", "200"]) == EXIT_OK
    assert main(["solve", str(USER_MODELS / problem), "--out", str(tmp_path / "r"), "--no-plots"]) == EXIT_OK
    assert main(["codegen", "--controller", str(tmp_path / "r"), "--out", str(tmp_path / "t"), "--check", "-n", "200"]) == EXIT_OK
    assert main(["codegen", "--mpc", str(USER_MODELS / f"{stem}_mpc.toml"), "--out", str(tmp_path / "m"), "--check", "-n", "50"]) == EXIT_OK
    out = capsys.readouterr().out
    assert "input bound violations: 0" in out and "RMS ratio MPC / feedforward" in out
