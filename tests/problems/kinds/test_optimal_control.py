"""Kind ``optimal_control``: the shipped cart-pendulum swing-up, its result folder and bad input.

The swing-up is checked against the model itself: the optimal force, replayed through
the model by IDAS (a second method, not the collocation polynomials), brings the pendulum
upright at rest. Bad input (model file missing, syntax error, class not defined, class
not a Model, unknown names) goes through the command line: exit 2, one message naming
the file and the field, no traceback.
"""

from __future__ import annotations

import json
import shutil

import numpy as np
import pytest
from scipy.linalg import expm as scipy_expm

from gtmodel._tables import read_table
from gtmodel.problems import load_problem, run_problem
from gtmodel.problems.kinds.optimal_control import OptimalControl, applied_inputs, scalar_signals
from gtmodel.status import Status

from ...conftest import PROBLEMS_DIR, REPO, assert_bad_problem_through_cli, replace_once as _edit

BASE = PROBLEMS_DIR / "cart_pendulum_swing_up.toml"
MODEL = REPO / "models" / "cart_pendulum.py"


def test_shipped_file_declares_its_model_and_settings():
    d = load_problem(BASE).declaration
    assert isinstance(d, OptimalControl)
    assert (d.class_name, d.model_file) == ("CartPendulum", MODEL.resolve())
    assert d.optimization.free_final_time and d.optimization.final_time_bounds == (0.5, 5.0)
    assert d.named_parameters == {"w": 0.001}
    assert d.bounds == {"F": (-20.0, 20.0), "s": (-1.0, 1.0)}
    assert {c.name for c in d.optimization.point_constraints} >= {"boundary.final.theta", "boundary.start.theta"}


@pytest.fixture(scope="module")
def solved(tmp_path_factory):
    out = tmp_path_factory.mktemp("cp") / "out"
    return run_problem(BASE, out, plots=True), out


def test_result_folder_of_the_swing_up(solved):
    outcome, out = solved
    assert outcome.status == Status.OPTIMAL
    files = {"summary.json", "trajectories.csv", "states.png", "inputs.png"}
    assert set(outcome.summary["files"]) == files == {p.name for p in out.iterdir()}
    summary = json.loads((out / "summary.json").read_text())
    assert summary["model"]["class"] == "CartPendulum" and summary["model_parameters"]["m_pole"] == 0.3
    # minimum time with |F| <= 20 N: about 1.09 s on this mesh (measured), between the bounds
    assert 0.9 < summary["final_time_s"] < 1.3


def test_force_within_bounds_and_rail_respected(solved):
    _, out = solved
    data = read_table(out / "trajectories.csv", text_columns=("point",))  # headers "F [N]" or "F" (before units)
    assert np.max(np.abs(data.column("F"))) <= 20.0 + 1e-6
    assert np.max(np.abs(data.column("s"))) <= 1.0 + 1e-6


def test_optimal_force_replayed_by_idas_swings_the_pendulum_up(solved):
    # second method: the model integrated by IDAS under the optimal force (sampled finely,
    # held piecewise constant) ends upright at rest, as the collocation solution does
    outcome, _ = solved
    r = outcome.solution
    t = np.linspace(0.0, r.final_time, 2001)
    force = r.sample(t)["inputs"]["F"]
    sim = load_problem(BASE).declaration.model.simulate(t, x0={"s": 0, "v": 0, "theta": 0, "omega": 0}, u=force)
    end = np.array([sim.x[k][-1] for k in ("s", "v", "theta", "omega")])
    np.testing.assert_allclose(end, [0.0, 0.0, np.pi, 0.0], atol=0.05)


MODEL_LINE = 'file = "../models/cart_pendulum.py"'
BAD = [
    ("model_file_missing", MODEL_LINE, 'file = "../models/nope.py"', r"field 'model\.file': expected .*an existing file"),
    ("class_not_defined", 'class = "CartPendulum"', 'class = "CartPole"', r"field 'model\.class': .*cart_pendulum\.py: defines no class 'CartPole' \(classes in the file: CartPendulum"),
    ("class_not_a_model", 'class = "CartPendulum"', 'class = "NotAModel"', r"field 'model\.class': .*: NotAModel\(\) is a NotAModel, not a gtmodel\.modeling\.Model"),
    ("syntax_error", MODEL_LINE, 'file = "broken.py"', r"field 'model\.file': .*broken\.py: syntax error at line 2"),
    ("import_raises", MODEL_LINE, 'file = "raises.py"', r"field 'model\.file': .*raises\.py: importing it raised ZeroDivisionError"),
    ("unknown_variable_in_objective", 'objective = "final_time + w * integral(F^2)"', 'objective = "final_time + w * integral(force^2)"', r"field 'optimization\.objective': undefined name at column 27: 'force'; known names: F, d, energy"),
    ("unknown_variable_in_constraint", '"abs(tip_x) <= 1.5"', '"abs(tipx) <= 1.5"', r"field 'optimization\.constraints\[0\]': undefined name .*'tipx'"),
    ("unknown_parameter", "m_pole = 0.3 ", "m_poles = 0.3 ", r"field 'model\.parameters\.m_poles': expected one of the model's names"),
    ("unknown_boundary_name", "theta = 0.0\n", "angle = 0.0\n", r"field 'boundary\.start\.angle': expected one of the model's names"),
    ("unknown_bound_name", "F = [-20.0, 20.0]", "force = [-20.0, 20.0]", r"field 'bounds\.force': expected one of the model's names"),
    ("bounds_reversed", "F = [-20.0, 20.0]", "F = [20.0, -20.0]", r"field 'bounds\.F': expected \[lo, hi\] with lo <= hi"),
    ("free_time_without_bounds", "bounds = [0.5, 5.0]", "", r"field 'optimization\.final_time\.bounds': expected bounds"),
    ("parameter_huge", "m_pole = 0.3 ", "m_pole = 1e308 ", r"field 'model\.parameters\.m_pole': expected a number <= 1e\+09"),
    # the model's own range (Model.parameter(..., min=1e-3)): a massless cart is refused on load
    ("massless_cart", "m_cart = 1.0 ", "m_cart = 0.0 ", r"field 'model\.parameters\.m_cart': expected a value in the parameter's range \(parameter 'm_cart': 0 is outside its range \[0\.001, inf\]\)"),
    ("class_missing", 'class = "CartPendulum"', "", r"missing field 'model\.class'"),
    # the field is named once (an earlier version wrapped the final-time message twice)
    ("initial_guess_outside_bounds", "bounds = [0.5, 5.0]", "bounds = [0.5, 0.6]",
     r"^(?!.*field '[^']*': .*field ').*field 'optimization\.final_time\.initial_guess': expected a time within"),
    # a boundary value outside its own bound is refused on load, not left to the solver's "infeasible" (the rail is 1 m)
    ("boundary_outside_bounds", "s = [-1.0, 1.0] ", "s = [-1.0, -0.5] ",
     r"field 'boundary\.start\.s': expected a value within \[bounds\] s = \[-1, -0\.5\] \(the boundary value and the bound cannot both hold\), got 0\.0"),
    ("free_parameter_unknown", "[initial_guess]", "[free_parameters]\nlength = [0.3, 0.8]\n\n[initial_guess]", r"field 'free_parameters\.length': expected one of the model's names"),
]
HELPERS = {
    "broken.py": "from gtmodel.modeling import Model\nclass CartPendulum(Model:\n    pass\n",
    "raises.py": "x = 1 / 0\n",
}


@pytest.mark.parametrize("case, old, new, match", BAD, ids=[c[0] for c in BAD])
def test_bad_optimal_control_problem_through_cli(tmp_path, capsys, case, old, new, match):
    (tmp_path / "models").mkdir()
    model_text = MODEL.read_text() + "\n\nclass NotAModel:\n    pass\n"
    (tmp_path / "models" / "cart_pendulum.py").write_text(model_text)
    for name, text in HELPERS.items():
        (tmp_path / name).write_text(text)
    text = _edit(old, new)(BASE.read_text()).replace("../models/", "models/")
    assert_bad_problem_through_cli(tmp_path, capsys, text, match)


def test_free_parameter_from_the_problem_file(tmp_path):
    # the pole length free in [0.3, 0.8] m: a shorter pendulum is faster (natural frequency
    # sqrt(g / l)), so the minimum-time optimum is at the lower bound, faster than l = 0.5 m
    f = tmp_path / "free.toml"
    text = BASE.read_text().replace("../models/", str(MODEL.parent) + "/").replace("elements = 50", "elements = 20")
    f.write_text(text + "\n[free_parameters]\nl = [0.3, 0.8]\n")
    outcome = run_problem(f, tmp_path / "out", plots=False)
    assert outcome.status == Status.OPTIMAL
    assert outcome.summary["free_parameters"] == ["l"]
    assert outcome.summary["model_parameters"]["l"] == pytest.approx(0.3, abs=1e-6)
    assert outcome.summary["final_time_s"] < 1.09  # l = 0.5 m: 1.0929 s (test_result_folder_of_the_swing_up)


def test_model_file_relative_to_the_problem_file(tmp_path):
    # the [model] file is found next to a copied problem file, wherever the command runs
    (tmp_path / "sub").mkdir()
    shutil.copy(MODEL, tmp_path / "sub" / "pendulum.py")
    f = tmp_path / "sub" / "p.toml"
    f.write_text(BASE.read_text().replace("../models/cart_pendulum.py", "pendulum.py"))
    assert load_problem(f).declaration.model_file == (tmp_path / "sub" / "pendulum.py").resolve()


COMPOSED = '''
from gtmodel.modeling.components.component import Component, connect
from gtmodel.modeling.library.translational import Fixed, Force, Mass, Spring


class Oscillator(Component):
    fixed = Fixed()
    spring = Spring(c=4.0)
    mass = Mass(m=1.0, s=0.1)
    force = Force()

    def equations(self):
        connect(self.fixed.flange, self.spring.flange_a)
        connect(self.spring.flange_b, self.mass.flange_a)
        connect(self.force.flange, self.mass.flange_b)
'''
COMPOSED_PROBLEM = '''
kind = "optimal_control"
[model]
file = "osc.py"
class = "Oscillator"
[model.parameters]
"spring.c" = 4.0
mass_m = 1.0
[optimization]
objective = "integral(force_f^2)"
[optimization.final_time]
free = false
value = 2.0
[boundary.start]
"mass.s" = 0.1
mass_v = 0.0
[boundary.final]
mass_s = 0.5
mass_v = 0.0
'''


def test_composed_model_with_hierarchical_names(tmp_path):
    # a component model (to_model()); hierarchical names as quoted keys or with _ for .;
    # checked against the closed form: minimum-energy transfer of x'' + 4 x = f over 2 s
    # (the Gramian solution), objective = d^T W^-1 d
    pytest.importorskip("gtmodel.modeling.components.component")
    (tmp_path / "osc.py").write_text(COMPOSED)
    (tmp_path / "osc.toml").write_text(COMPOSED_PROBLEM)
    outcome = run_problem(tmp_path / "osc.toml", tmp_path / "out", plots=False)
    assert outcome.status == Status.OPTIMAL
    A, B, T = np.array([[0.0, 1.0], [-4.0, 0.0]]), np.array([0.0, 1.0]), 2.0
    tau = np.linspace(0.0, T, 4001)
    expm = [scipy_expm(A * (T - s)) @ B for s in tau]
    W = np.trapezoid([np.outer(e, e) for e in expm], tau, axis=0)
    d = np.array([0.5, 0.0]) - scipy_expm(A * T) @ np.array([0.1, 0.0])
    assert outcome.summary["objective"] == pytest.approx(d @ np.linalg.solve(W, d), rel=1e-5)


def test_inputs_plot_draws_the_inputs_as_verified():
    # independent: the result's own polynomials (OptimizationResult.sample) and numpy.clip with the problem's
    # bound |F| <= 20 N; the plot's samples include every written time
    d = load_problem(BASE).declaration
    result = d.solve()
    t, inputs = applied_inputs(result, d.optimization)
    assert set(inputs) == {"F"} and np.isin(result.t, t).all()
    np.testing.assert_allclose(inputs["F"], np.clip(result.sample(t)["inputs"]["F"], -20.0, 20.0), rtol=0, atol=1e-12)
    assert t.size == 10 * (result.t.size - 1) + 1 and np.all(np.diff(t) > 0)


# the plots of a model with array variables (the Optimica robot's tcp[3], tau[3]): each element its own signal, as
# trajectories.csv names them (before, every array variable was left out: opt_robot's plots showed only its cost)
@pytest.mark.parametrize(("values", "expected"), [
    ({"x": np.arange(3.0)}, {"x": [0.0, 1.0, 2.0]}),
    ({"q": np.array([[1.0, 2.0], [3.0, 4.0]])}, {"q[0]": [1.0, 3.0], "q[1]": [2.0, 4.0]}),
    ({"s": np.zeros((2, 2, 2))}, {}),
])
def test_scalar_signals_split_array_variables_into_their_elements(values, expected):
    got = scalar_signals(values)
    assert {k: v.tolist() for k, v in got.items()} == expected
