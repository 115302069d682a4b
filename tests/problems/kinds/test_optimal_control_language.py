"""Kind ``optimal_control``: the Optimica-complete problem language in problem files.

A double integrator ``x'' = u`` declared in a file with: ``maximize``, an isoperimetric
constraint ``integral(u^2) <= E``, a variable at an interior time ``x(1.0)``, one-sided
and infinite bounds (``inf``, ``"-inf"``) and a bound that is an expression of a model
parameter. Reference: the closed form ``max x(T) = sqrt(E T^3 / 3)`` (Cauchy-Schwarz on
``x(T) = int (T - s) u ds``). Bad input of each new field: exit 2 naming the file and field.
"""

from __future__ import annotations

import numpy as np
import pytest

from gtmodel.problems import run_problem
from gtmodel.status import Status

from ...conftest import assert_bad_problem_through_cli

MODEL = '''
from gtmodel.modeling import Model


class DoubleIntegrator:
    def build(self):
        m = Model("di")
        x, v, u = m.state("x"), m.state("v"), m.input("u")
        m.parameter("umax", 1.0)
        m.equation(m.der(x), v)
        m.equation(m.der(v), u)
        m.output("speed", v)
        return m
'''
PROBLEM = '''
kind = "optimal_control"
[model]
file = "di.py"
class = "DoubleIntegrator"
[parameters]
E = 0.5
[optimization]
maximize = "x(final_time)"
constraints = ["integral(u^2) <= E", "x(1.0) >= 0.1 * speed(final_time)"]
[optimization.final_time]
free = false
value = 2.0
[boundary.start]
x = 0.0
v = 0.0
[bounds]
u = ["-umax", inf]
v = ["-inf", 10.0]
x = [-1e20, 100.0]
[collocation]
elements = 10
'''


@pytest.fixture
def folder(tmp_path):
    (tmp_path / "di.py").write_text(MODEL)
    return tmp_path


def test_maximize_isoperimetric_timed_and_open_bounds(folder):
    (folder / "p.toml").write_text(PROBLEM)
    outcome = run_problem(folder / "p.toml", folder / "out", plots=False)
    assert outcome.status == Status.OPTIMAL
    s = outcome.summary
    assert s["objective_sense"] == "maximize"
    assert s["objective"] == pytest.approx(np.sqrt(0.5 * 2.0**3 / 3.0), rel=1e-7)


def test_bound_expression_of_a_parameter_is_active(folder):
    # minimising x(T) (with a large energy budget) drives u onto its lower bound -umax, a
    # model parameter set to 0.25 in the file; imposed at the collocation points
    text = PROBLEM.replace('maximize = "x(final_time)"', 'minimize = "x(final_time)"').replace(
        '"x(1.0) >= 0.1 * speed(final_time)"', '"x(1.0) <= 0"').replace("E = 0.5", "E = 100.0")
    text = text.replace("[collocation]", "[model.parameters]\numax = 0.25\n[collocation]")
    (folder / "p.toml").write_text(text)
    outcome = run_problem(folder / "p.toml", folder / "out", plots=False)
    # u = -umax throughout: x(T) = -umax T^2 / 2
    assert outcome.summary["objective"] == pytest.approx(-0.25 * 2.0**2 / 2, rel=1e-6)


BAD = [
    ("unknown_variable_in_timed", '"x(1.0) >= 0.1', '"y(1.0) >= 0.1', r"field 'optimization\.constraints\[1\]': undefined name at column 1: 'y'"),
    ("time_outside_horizon", '"x(1.0) >= 0.1', '"x(2.5) >= 0.1', r"field 'optimization\.constraints\[1\]': timed variable at t = 2\.5 s: outside the horizon \[0, 2\] s"),
    ("time_not_a_number", '"x(1.0) >= 0.1', '"x(v) >= 0.1', r"field 'optimization\.constraints\[1\]': the time of a time point must be constant .* at column 3: 'v'"),
    ("bare_variable_with_timed", '"x(1.0) >= 0.1 * speed(final_time)"', '"x(1.0) >= v"', r"field 'optimization\.constraints\[1\]': 'v' is not evaluated at a time point"),
    ("inf_both_sides", 'u = ["-umax", inf]', "u = [-inf, inf]", r"field 'bounds\.u': expected a bound on at least one side"),
    ("inf_strings_both_sides", 'u = ["-umax", inf]', 'u = ["-inf", "inf"]', r"field 'bounds\.u': expected a bound on at least one side"),
    ("inf_by_1e20_both_sides", 'u = ["-umax", inf]', "u = [-1e20, 1e20]", r"field 'bounds\.u': expected a bound on at least one side"),
    ("bound_between_finite_and_infinite", 'u = ["-umax", inf]', "u = [-1e12, 1.0]", r"field 'bounds\.u': expected a list \[lo, hi\] of numbers \(\|x\| <= 1e\+09"),
    ("lower_bound_inf", 'u = ["-umax", inf]', 'u = [inf, 1.0]', r"field 'bounds\.u': expected lo < inf and hi > -inf"),
    ("bound_nan", 'u = ["-umax", inf]', "u = [nan, 1.0]", r"field 'bounds\.u': expected a list \[lo, hi\]"),
    ("bound_unknown_name", 'u = ["-umax", inf]', 'u = ["-umx", inf]', r"field 'bounds\.u': undefined name at column 2: 'umx'"),
    ("bound_of_a_variable", 'u = ["-umax", inf]', 'u = ["-x", inf]', r"field 'bounds\.u': .*parameters and final_time only"),
    ("two_objectives", 'maximize = "x(final_time)"', 'maximize = "x(final_time)"\nobjective = "x(final_time)"', r"field 'optimization\.maximize': expected one objective \(optimization\.objective is given too\)"),
    ("no_objective", 'maximize = "x(final_time)"', "", r"field 'optimization\.objective': expected an objective"),
    ("integral_nested_in_constraint", '"integral(u^2) <= E"', '"sqrt(integral(u^2)) <= E"', r"field 'optimization\.constraints\[0\]': integral\(\) inside sqrt\(\) is not allowed"),
    ("maximize_bad_name", 'maximize = "x(final_time)"', 'maximize = "z(final_time)"', r"field 'optimization\.maximize': undefined name at column 1: 'z'"),
    ("interior_time_with_free_final_time", "free = false\nvalue = 2.0", "free = true\nbounds = [1.0, 3.0]", r"field 'optimization\.constraints\[1\]': timed variable at t = 1 s: with a free final time only the start and the final time or a fixed fraction s of the horizon .* write the time as start_time \+ s \* \(final_time - start_time\)"),
    ("time_not_a_fraction_of_the_horizon", '"x(1.0) >= 0.1 * speed(final_time)"]\n[optimization.final_time]\nfree = false\nvalue = 2.0',
     '"x(1.0 + 0.5 * final_time) >= 0"]\n[optimization.final_time]\nfree = true\nbounds = [1.0, 3.0]', r"field 'optimization\.constraints\[1\]': timed variable at 1 \+ 0\.5 \* final_time s: with a free final time an interior time must be a fixed fraction s of the horizon"),
    ("free_parameter_of_a_model_parameter", "[collocation]", '[free_parameters]\numax = ["-umax", 2.0]\n[collocation]', r"field 'free_parameters\.umax': expected numbers or expressions of \[parameters\] names"),
]


@pytest.mark.parametrize("case, old, new, match", BAD, ids=[c[0] for c in BAD])
def test_bad_language_through_cli(folder, capsys, case, old, new, match):
    assert old in PROBLEM
    assert_bad_problem_through_cli(folder, capsys, PROBLEM.replace(old, new), match)


@pytest.mark.slow
def test_interior_time_of_a_free_horizon_as_a_fraction(folder):
    # minimum time with v(0.5 * final_time) <= 0.1: T = 2 (2 sqrt(0.505) - 0.1) by hand
    # (tests/modeling/ocp/test_timed.py), here written in the file
    text = PROBLEM.replace('maximize = "x(final_time)"', 'minimize = "final_time"')
    text = text.replace('"integral(u^2) <= E", "x(1.0) >= 0.1 * speed(final_time)"', '"v(0.5 * final_time) <= 0.1"')
    text = text.replace("free = false\nvalue = 2.0", "free = true\nbounds = [0.5, 5.0]\ninitial_guess = 3.0")
    text = text.replace("[bounds]", "[boundary.final]\nx = 1.0\nv = 0.0\n[bounds]").replace("elements = 10", "elements = 20")
    (folder / "half.toml").write_text(text.replace('u = ["-umax", inf]', 'u = ["-umax", "umax"]'))
    outcome = run_problem(folder / "half.toml", folder / "half", plots=False)
    assert outcome.status == Status.OPTIMAL
    assert outcome.summary["final_time_s"] == pytest.approx(2.0 * (2.0 * np.sqrt(0.505) - 0.1), rel=5e-4)


def test_guess_from_an_earlier_result_folder_and_by_simulation(folder):
    # the same problem restarted from its own result converges at once to the same optimum;
    # a simulation guess (JModelica's default) and a per-variable expression also solve it
    (folder / "p.toml").write_text(PROBLEM)
    first = run_problem(folder / "p.toml", folder / "first", plots=False)
    again = PROBLEM + '[initial_guess]\nmethod = "file"\nfile = "first"\n'
    (folder / "again.toml").write_text(again)
    second = run_problem(folder / "again.toml", folder / "second", plots=False)
    assert second.summary["objective"] == pytest.approx(first.summary["objective"], rel=1e-8)
    assert second.summary["iterations"] < first.summary["iterations"]
    sim = PROBLEM + '[initial_guess]\nmethod = "simulation"\n[initial_guess.inputs]\nu = "0.5 * (2 - time)"\n[initial_guess.values]\nv = "0.1 * time"\n'
    (folder / "sim.toml").write_text(sim)
    third = run_problem(folder / "sim.toml", folder / "third", plots=False)
    assert third.summary["objective"] == pytest.approx(first.summary["objective"], rel=1e-8)


GUESS = '[initial_guess]\nmethod = "file"\nfile = "guess.csv"\n'
BAD_GUESS = [
    ("guess_of_another_problem", "t,theta,omega\n0,0,0\n2,1,1\n", GUESS, r"field 'initial_guess\.file': .*columns theta, omega name no state, input or algebraic variable of model 'di'"),
    ("guess_with_nan", "t,x\n0,0\n2,nan\n", GUESS, r"field 'initial_guess\.file': .*guess\.csv.*line 3"),
    ("guess_without_time_column", "time,x\n0,0\n2,1\n", GUESS, r"field 'initial_guess\.file': no time column 't'"),
    ("guess_file_missing", None, GUESS, r"field 'initial_guess\.file': expected an existing CSV file or result folder"),
    ("guess_file_without_method", "t,x\n0,0\n2,1\n", '[initial_guess]\nfile = "guess.csv"\n', r"field 'initial_guess\.file': expected method = \"file\""),
    ("guess_value_of_a_state", None, '[initial_guess.values]\nx = "v * time"\n', r"field 'initial_guess\.values\.x': expected an expression of time, final_time and parameters"),
    ("guess_value_unknown_name", None, "[initial_guess.values]\nq = 1.0\n", r"field 'initial_guess\.values\.q': expected one of the model's variables"),
    ("simulation_input_unknown", None, '[initial_guess]\nmethod = "simulation"\n[initial_guess.inputs]\nF = 1.0\n', r"field 'initial_guess\.inputs\.F': expected an input of the model \(u\)"),
]


@pytest.mark.parametrize("case, csv, extra, match", BAD_GUESS, ids=[c[0] for c in BAD_GUESS])
def test_bad_initial_guess_through_cli(folder, capsys, case, csv, extra, match):
    if csv is not None:
        (folder / "guess.csv").write_text(csv)
    assert_bad_problem_through_cli(folder, capsys, PROBLEM + extra, match)


def test_multiple_shooting_from_the_file(folder):
    # the same problem by direct multiple shooting with piecewise-linear inputs (the optimal
    # u ~ T - t is representable): the same closed-form optimum
    text = PROBLEM + '[transcription]\nmethod = "multiple_shooting"\nintervals = 8\ncontrols = "linear"\n'
    (folder / "ms.toml").write_text(text)
    outcome = run_problem(folder / "ms.toml", folder / "out", plots=False)
    assert outcome.status == Status.OPTIMAL
    assert outcome.summary["transcription"] == {"method": "multiple_shooting", "intervals": 8, "controls": "linear",
                                                "integrator": "rk", "steps": 4}
    assert outcome.summary["objective"] == pytest.approx(np.sqrt(0.5 * 2.0**3 / 3.0), rel=1e-7)
    check = outcome.summary["verification"]  # CVODES under the piecewise-linear inputs, integral included
    assert check["passed"] and "piecewise linear" in check["method"] and check["max_abs_deviation"] < 1e-6
    assert check["integrals"]["sq(u)"]["passed"]


BAD_TRANSCRIPTION = [
    ("unknown_method", '[transcription]\nmethod = "single_shooting"\n', r"field 'transcription\.method': expected one of collocation, multiple_shooting"),
    ("nominal_with_shooting", '[transcription]\nmethod = "multiple_shooting"\n[nominal]\nu = 2.0\n', r"field 'nominal': expected no nominal values"),
    ("integrator_unknown", '[transcription]\nmethod = "multiple_shooting"\nintegrator = "euler"\n', r"field 'transcription\.integrator': expected one of rk, radau, collocation, cvodes, idas"),
    ("shooting_too_large", '[transcription]\nmethod = "multiple_shooting"\nintervals = 10000\nsteps = 1000\n',
     r"transcription\.intervals.*intervals = 10000, steps = 1000: the multiple-shooting NLP would integrate 10000000 steps .*"
     r"use fewer intervals or steps \(transcription\.intervals, transcription\.steps"),
    ("intervals_zero", '[transcription]\nmethod = "multiple_shooting"\nintervals = 0\n', r"field 'transcription\.intervals': expected an integer in 1\.\.10000"),
    ("steps_zero", '[transcription]\nmethod = "multiple_shooting"\nsteps = 0\n', r"field 'transcription\.steps': expected an integer in 1\.\.1000"),
    ("refine_with_shooting", '[transcription]\nmethod = "multiple_shooting"\nrefine = true\n', r"field 'transcription\.refine': expected false with method = \"multiple_shooting\" \(mesh refinement splits collocation elements; shooting is verified as it is: raise transcription\.intervals"),
    ("controls_unknown", '[transcription]\nmethod = "multiple_shooting"\ncontrols = "cubic"\n', r"field 'transcription\.controls': expected one of constant, linear"),
]


@pytest.mark.parametrize("case, extra, match", BAD_TRANSCRIPTION, ids=[c[0] for c in BAD_TRANSCRIPTION])
def test_bad_transcription_through_cli(folder, capsys, case, extra, match):
    assert_bad_problem_through_cli(folder, capsys, PROBLEM + extra, match)
