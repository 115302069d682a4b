"""What a problem file's user is told about a doubtful result: warnings, the benchmark check, the verification's settings.

Each test writes the user's mistake as a problem file on a double integrator ``x'' = u``
(its minimum-time optimum is the closed form ``T = 2 sqrt(d / u_max)``, Bryson and Ho
1975, sec. 7.3) and checks the exact message in ``summary.json`` and on the CLI.
"""

from __future__ import annotations

import json

import pytest

from gtmodel.cli import main
from gtmodel.problems import run_problem
from gtmodel.status import Status

from ...conftest import assert_bad_problem

MODEL = '''
from gtmodel.modeling import Model


class DoubleIntegrator(Model):
    def __init__(self):
        super().__init__("double_integrator")
        x, v, u = self.state("x"), self.state("v"), self.input("u")
        self.equation(self.der(x), v)
        self.equation(self.der(v), u)
'''

MIN_TIME = '''
name = "di"
kind = "optimal_control"

[model]
file = "di.py"
class = "DoubleIntegrator"

[optimization]
objective = "final_time"

[optimization.final_time]
free = true
bounds = [0.01, 10.0]
initial_guess = 2.0

[bounds]
u = [-1.0, 1.0]

[boundary.start]
x = 0.0
v = 0.0

[boundary.final]
x = 1.0
v = 0.0

[collocation]
elements = 11
'''


def _write(tmp_path, text: str):
    (tmp_path / "di.py").write_text(MODEL)
    f = tmp_path / "di.toml"
    f.write_text(text)
    return f


def _solve(tmp_path, text: str):
    outcome = run_problem(_write(tmp_path, text), tmp_path / "out", plots=False)
    return outcome, json.loads((tmp_path / "out" / "summary.json").read_text())


def test_unbounded_input_in_a_minimum_time_problem_is_warned(tmp_path, capsys):
    # the user's mistake: no [bounds] on the input; the "optimum" is the final time's lower bound
    text = MIN_TIME.replace("[bounds]\nu = [-1.0, 1.0]\n", "")
    code = main(["solve", str(_write(tmp_path, text)), "--no-plots", "--out", str(tmp_path / "out")])
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert summary["final_time_s"] == pytest.approx(0.01, rel=1e-6)
    (warning,) = summary["warnings"]
    assert warning.startswith("input 'u' has no bounds (or only one) in a minimum-time problem (free final time): the "
                              "optimum drives it as far as the final time's lower bound allows (|u| up to ")
    assert warning.endswith(", final time 0.01 s); give it [bounds]")
    assert f"warning      {warning}" in capsys.readouterr().out and code in (0, 1)


def test_a_solution_far_beyond_the_models_scale_is_warned(tmp_path):
    # the user's mistake: a target in mm on a model in m (start values 0, no bounds)
    text = MIN_TIME.replace("x = 1.0\nv = 0.0", "x = 5000.0\nv = 0.0").replace("bounds = [0.01, 10.0]", "bounds = [1.0, 1000.0]")
    text = text.replace("initial_guess = 2.0", "initial_guess = 150.0").replace("elements = 11", "elements = 20")
    outcome, summary = _solve(tmp_path, text)
    assert outcome.status in (Status.OPTIMAL, Status.CHECK_FAILED)
    assert summary["warnings"] == ["state 'x' reaches 5000 in the solution, 5e+03 times the model's scale of it (1: its "
                                   "start value and bounds): a missing bound or a wrong unit? bound it in [bounds] or "
                                   "check the model"]


def test_a_benchmark_value_beyond_its_tolerance_is_printed_and_flagged(tmp_path, capsys):
    # the user's mistake: a published value 10 % off (2.2 for the closed form 2)
    text = MIN_TIME + '\n[benchmark]\nsource = "a misprint"\npublished = 2.2\nquantity = "final time [s]"\n'
    main(["solve", str(_write(tmp_path, text)), "--no-plots", "--out", str(tmp_path / "out")])
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    bench = summary["benchmark"]
    assert not bench["within_tolerance"] and bench["tolerance"] == 1e-4
    assert bench["relative_error"] == pytest.approx(abs(summary["objective"] - 2.2) / 2.2)
    # beside it, the input's polynomial past |u| <= 1 in the switch's element and the clipped simulation's deviation
    # (verification_bounds, tested in tests/modeling/ocp/test_verification_bounds.py)
    (warning,) = [w for w in summary["warnings"] if w.startswith("benchmark:")]
    assert warning == (f"benchmark: final time [s] {summary['objective']:.7g} is {100 * bench['relative_error']:.3g} % away "
                       "from the published 2.2 (a misprint), beyond benchmark.tolerance 0.0001")
    out = capsys.readouterr().out
    assert "BEYOND tolerance 1e-04" in out and f"warning      {warning}" in out


def test_refinement_reports_the_final_mesh(tmp_path):
    # the switch of the bang-bang input at t = 1 s inside an element of 11: refinement adds elements
    text = MIN_TIME.replace("[collocation]", "[transcription]\nrefine = true\ntolerance = 1e-6\n\n[collocation]")
    outcome, summary = _solve(tmp_path, text)
    assert outcome.status == Status.OPTIMAL
    assert summary["transcription"]["declared_elements"] == 11
    (returned,) = [e for e in summary["refinement"] if e.get("returned")]  # the last pass: the objective's check
    assert summary["transcription"]["elements"] == returned["elements"] > 11
    assert summary["verification"]["time_s"] > 0 and summary["verification"]["status"] == "passed"


def test_a_skipped_verification_is_never_reported_verified(tmp_path, capsys):
    text = MIN_TIME + "\n[verification]\nenabled = false\n"
    main(["solve", str(_write(tmp_path, text)), "--no-plots", "--out", str(tmp_path / "out")])
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert summary["verification"] == {"status": "skipped", "passed": None,
                                       "message": "not verified: [verification] enabled = false"}
    assert "verified     skipped (not verified: [verification] enabled = false)" in capsys.readouterr().out


def test_the_verifying_integrator_is_chosen_in_the_file(tmp_path):
    text = MIN_TIME.replace("[collocation]", "[transcription]\ntolerance = 1e-6\nrefine_on_failure = false\n\n[collocation]")
    outcome, summary = _solve(tmp_path, text + '\n[verification]\nintegrator = "idas"\nrtol = 1e-9\n')
    assert outcome.status == Status.CHECK_FAILED  # the switch inside an element of 11 (2.00087 s)
    assert summary["verification"]["integrator"] == "idas (rtol 1e-09)"
    assert summary["verification"]["remedy"].startswith("an input jumps inside 1 element(s) (near t = 1")


BAD = [
    ("integrator", '[verification]\nintegrator = "rk"\n', r"field 'verification\.integrator'"),
    ("rtol", "[verification]\nrtol = 2.0\n", r"field 'verification\.rtol'"),
    ("refine_unverified", "[transcription]\nrefine = true\n\n[verification]\nenabled = false\n",
     r"field 'verification\.enabled': expected true with transcription\.refine = true"),
    ("benchmark_tolerance", '[benchmark]\nsource = "x"\npublished = 2.0\ntolerance = 0.0\n', r"field 'benchmark\.tolerance'"),
]


@pytest.mark.parametrize("case, extra, match", BAD, ids=[c[0] for c in BAD])
def test_bad_verification_and_benchmark_fields_name_the_field(tmp_path, case, extra, match):
    f = _write(tmp_path, MIN_TIME)
    assert_bad_problem(tmp_path, f, case, lambda text: text + "\n" + extra, match)


def test_a_failed_verification_is_refined_by_default(tmp_path):
    # refine_on_failure (default): the 11-element solve (2.00087 s, check_failed at 1e-6) is the first pass, the
    # refinement puts a boundary on the switch; the analytic minimum is 2 s (Bryson and Ho 1975, sec. 7.3)
    text = MIN_TIME.replace("[collocation]", "[transcription]\ntolerance = 1e-6\n\n[collocation]")
    outcome, summary = _solve(tmp_path, text)
    assert outcome.status == Status.OPTIMAL and summary["verification"]["passed"] is True
    first = summary["refinement"][0]
    assert first["elements"] == 11 and first["status"] == "check_failed"
    assert summary["objective"] == pytest.approx(2.0, abs=1e-6) and summary["objective"] <= first["objective"]
    assert "returned pass" in summary["refinement_stop"]
