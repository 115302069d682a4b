"""Kind ``optimal_control`` over a user's component model as written (higher index, not reduced by hand).

The user's file composes a DC motor, a gear (ratio 50) and a load from library components
and has no ``build()``: the problem file names the class, the kind reduces it as
``simulate()`` does, names the states chosen (log and summary), and the conditions on the
load (algebraic after the reduction) hold at t = 0. References: the gear's kinematics
(``motor.w = 50 load.w``, ``motor.phi = 50 load.phi``) in the written table, the input's
bound, and the same problem solved from Python (``Optimization`` over the model, a second
path through the declarations).
"""

from __future__ import annotations

import csv
import json
import logging
import shutil

import numpy as np
import pytest

from gtmodel._tables import split_unit
from gtmodel.cli import main
from gtmodel.problems import run_problem
from gtmodel.status import Status

MODEL = '''
from gtmodel.modeling import Component, connect
from gtmodel.modeling.library import electrical as el
from gtmodel.modeling.library import rotational as rot


class DCMotorGearLoad(Component):
    source = el.SignalVoltage()
    resistor = el.Resistor(R=1.0)
    inductor = el.Inductor(L=0.02)
    emf = el.EMF(k=0.05)
    ground = el.Ground()
    motor = rot.Inertia(J=1e-5)
    gear = rot.IdealGear(ratio=50.0)
    load = rot.Inertia(J=0.01)
    damper = rot.Damper(d=0.01)
    fixed = rot.Fixed()

    def equations(self):
        connect(self.source.p, self.resistor.p)
        connect(self.resistor.n, self.inductor.p)
        connect(self.inductor.n, self.emf.p)
        connect(self.emf.n, self.source.n)
        connect(self.source.n, self.ground.p)
        connect(self.emf.flange, self.motor.flange_a)
        connect(self.motor.flange_b, self.gear.flange_a)
        connect(self.gear.flange_b, self.load.flange_a)
        connect(self.load.flange_b, self.damper.flange_a)
        connect(self.damper.flange_b, self.fixed.flange)
        self.output("power", self.source.v * self.source.i)
'''

PROBLEM = '''name = "dc_move"
kind = "optimal_control"

[model]
file = "dc_motor.py"
class = "DCMotorGearLoad"

[optimization]
objective = "integral(source_v^2)"
constraints = ["motor_phi <= 60"]

[optimization.final_time]
free = false
value = 0.5

[boundary.start]
"load.phi" = 0.0
"load.w" = 0.0
"inductor.i" = 0.0

[boundary.final]
"load.phi" = 1.0
"load.w" = 0.0

[bounds]
"source.v" = [-24.0, 24.0]

[initial_guess.values]
"motor.phi" = "100 * time"

[collocation]
elements = 40
'''
RATIO = 50.0
GUESS = '"motor.phi" = "100 * time"\n'


@pytest.fixture(scope="module")
def solved(tmp_path_factory):
    folder = tmp_path_factory.mktemp("dc")
    (folder / "dc_motor.py").write_text(MODEL)
    (folder / "dc_move.toml").write_text(PROBLEM)
    logger = logging.getLogger("gtmodel")
    records: list[str] = []
    handler = logging.Handler()
    handler.emit = lambda rec: records.append(rec.getMessage())
    logger.addHandler(handler)
    level = logger.level
    logger.setLevel(logging.INFO)
    try:
        outcome = run_problem(folder / "dc_move.toml", folder / "out", plots=True)
    finally:
        logger.removeHandler(handler)
        logger.setLevel(level)
    return outcome, folder, records


def test_the_class_as_written_solves_and_the_states_chosen_are_named(solved):
    outcome, folder, records = solved
    assert outcome.status == Status.OPTIMAL
    summary = json.loads((folder / "out" / "summary.json").read_text())
    states = summary["model"]["states"]
    assert states == ["inductor.i", "emf.phi", "motor.w"]
    assert any("reduced to index 1" in r and "inductor.i, emf.phi, motor.w" in r for r in records)
    # the library components' units (MSL declarations) carried to the summary and the report's unit column
    assert {n: summary["units"][n] for n in (*states, "source.v")} == {"inductor.i": "A", "emf.phi": "rad", "motor.w": "rad/s",
                                                                      "source.v": "V"}
    from gtmodel.problems.run import add_report

    assert "<tr><td>inductor.i</td><td>states</td><td>A</td>" in add_report(folder / "out").read_text()


def test_variables_plot_shows_the_states_as_written_by_default(solved):
    # [output] variables defaults, for a reduced model, to the states of the model as written
    outcome, folder, _ = solved
    assert outcome.problem.declaration.variables[:3] == ("inductor.i", "emf.phi", "motor.phi")
    assert {"load.phi", "load.w"} <= set(outcome.problem.declaration.variables)
    assert "variables.png" in outcome.summary["files"] and (folder / "out" / "variables.png").stat().st_size > 0


def test_output_variables_named_in_the_file(tmp_path):
    (tmp_path / "dc_motor.py").write_text(MODEL)
    (tmp_path / "p.toml").write_text(PROBLEM + '[output]\nvariables = ["load.phi", "motor.phi"]\n')
    from gtmodel.problems import load_problem

    assert load_problem(tmp_path / "p.toml").declaration.variables == ("load.phi", "motor.phi")
    (tmp_path / "q.toml").write_text(PROBLEM + '[output]\nvariables = ["load.phy"]\n')
    from gtmodel.errors import ProblemError

    with pytest.raises(ProblemError, match=r"field 'output.variables\[0\]': expected one of the model's names: did you mean 'load.phi'.*\? \(all: .*load\.phi, load\.w, .*\), got 'load.phy'"):
        load_problem(tmp_path / "q.toml")


def test_table_holds_every_variable_and_the_conditions_at_t0(solved):
    # reference: the gear's kinematics at t = 0 (the motor does not start moving: the issue's
    # 4.81 rad/s), the bound of the input at every written time (the 29.7 V)
    _, folder, _ = solved
    raw = list(csv.DictReader(open(folder / "out" / "trajectories.csv")))
    assert {"t [s]", "load.phi [rad]", "load.w [rad/s]", "source.v [V]"} <= set(raw[0])  # units in the header
    rows = [{split_unit(k)[0]: v for k, v in r.items()} for r in raw]
    first = rows[0]
    assert first["point"] == "start" and {r["point"] for r in rows[1:]} == {"collocation", "collocation_boundary"}
    assert {"load.phi", "load.w", "motor.phi", "motor.w", "emf.phi", "source.v"} <= set(first)
    assert abs(float(first["motor.w"])) < 1e-9 and abs(float(first["load.w"])) < 1e-9
    col = {k: np.array([float(r[k]) for r in rows]) for k in ("motor.phi", "load.phi", "source.v")}
    np.testing.assert_allclose(col["motor.phi"], RATIO * col["load.phi"], atol=1e-9)
    assert np.max(np.abs(col["source.v"])) <= 24.0 + 1e-7
    assert np.max(col["motor.phi"]) <= 60.0 + 1e-6  # the constraint on the eliminated alias


def test_same_optimum_as_optimization_over_the_model_from_python(solved, tmp_path):
    # second path: the model as written given to Optimization (reduced there), the same problem
    import sys

    from gtmodel.modeling import Optimization, solve

    outcome, folder, _ = solved
    sys.path.insert(0, str(folder))
    try:
        from dc_motor import DCMotorGearLoad  # noqa: PLC0415 - the file written by the fixture
    finally:
        sys.path.remove(str(folder))
    m = DCMotorGearLoad().to_model()
    opt = Optimization(m, final_time=0.5)
    s, a, u = m.variables("state"), m.variables("algebraic"), m.variables("input")["source.v"]
    for name, value in {"load.phi": 0.0, "load.w": 0.0, "inductor.i": 0.0}.items():
        opt.add_point_constraint(s[name], at="start", lb=value, ub=value)
    for name, value in {"load.phi": 1.0, "load.w": 0.0}.items():
        opt.add_point_constraint(s[name], at="final", lb=value, ub=value)
    opt.add_path_constraint(s["motor.phi"], ub=60.0)
    opt.set_bounds(u, -24.0, 24.0)
    opt.set_objective(lagrange=u**2)
    res = solve(opt, elements=40, points=3)
    assert res.objective == pytest.approx(outcome.summary["objective"], rel=1e-7)


@pytest.mark.slow  # generating the code takes ~5 s, compiling and checking it ~4 s more
@pytest.mark.parametrize("check", [False, True])
def test_codegen_of_the_class_as_written(solved, tmp_path, check):
    # the C generator takes the same class: the header names the states the reduction chose;
    # --check compiles it and compares every function with the reduced model from Python
    _, folder, _ = solved
    if check and not shutil.which("gcc"):
        pytest.skip("--check needs gcc")
    args = ["codegen", "--model", f"{folder / 'dc_motor.py'}:DCMotorGearLoad", "--out", str(tmp_path)]
    assert main(args + (["--check"] if check else [])) == 0
    header = next(tmp_path.glob("*.h")).read_text()
    assert "States x: inductor.i [A], emf.phi [rad], motor.w [rad/s]" in header and "Inputs u: source.v [V]" in header


def test_a_guess_on_an_output_that_is_no_affine_function_of_one_variable_is_refused(tmp_path):
    # source.i = -inductor.i (an eliminated alias): a guess of it guesses inductor.i; the
    # declared output power = source.v source.i is a product: refused, naming the field
    from gtmodel.errors import ProblemError
    from gtmodel.problems import load_problem

    (tmp_path / "dc_motor.py").write_text(MODEL)
    (tmp_path / "p.toml").write_text(PROBLEM.replace(GUESS, GUESS + '"source.i" = "0.1"\n'))
    guess = load_problem(tmp_path / "p.toml").declaration.optimization.initial_guesses["inductor.i"]
    assert float(np.ravel(guess(0.2) if callable(guess) else guess)[0]) == pytest.approx(-0.1, rel=1e-12)
    (tmp_path / "q.toml").write_text(PROBLEM.replace(GUESS, GUESS + '"power" = "0.1"\n'))
    with pytest.raises(ProblemError, match=r"field 'initial_guess.values.power': .*not a variable of the model nor affine in one"):
        load_problem(tmp_path / "q.toml")


@pytest.mark.parametrize("wrong, suggested", [
    ("load.omega", r"did you mean 'load\.w'.*\? \(the Modelica Standard Library's name of omega is w\)"),
    ("load.theta", r"did you mean 'load\.phi'.*\? \(the Modelica Standard Library's name of theta is phi\)"),
    ("load.ww", r"did you mean 'load\.w'.*\? \(all: "),
])
def test_an_unknown_name_suggests_the_models_close_and_msl_names(tmp_path, wrong, suggested):
    # the user's mistake: another library's name (omega, theta) or a typo for a library component's variable
    from gtmodel.errors import ProblemError
    from gtmodel.problems import load_problem

    (tmp_path / "dc_motor.py").write_text(MODEL)
    (tmp_path / "p.toml").write_text(PROBLEM.replace('"load.w" = 0.0\n\n[bounds]', f'"{wrong}" = 0.0\n\n[bounds]'))
    with pytest.raises(ProblemError, match=rf"field 'boundary\.final\.{wrong}': expected one of the model's names: {suggested}"):
        load_problem(tmp_path / "p.toml")
