"""An infeasible solve names its likely culprit (issue 67, item 5): the final time at a bound, or the worst rows by name.

Reference: the double integrator x'' = u, |u| <= 1, from rest at 0 to rest at 1 takes at least
2 s (bang-bang, switch at 1 s; Bryson and Ho 1975, sec. 7.3), so an upper bound of 1 s on the
final time, or a fixed final time of 1 s, leaves no feasible point.
"""

from __future__ import annotations

import json
from types import SimpleNamespace

import numpy as np
import pytest

from gtmodel.modeling import CollocationTranscription, Model, Optimization
from gtmodel.modeling.library.blocks import smooth_limit
from gtmodel.modeling.ocp.infeasibility import INERT_RATIO, inert_inputs, likely_culprit, with_culprit

from ...conftest import REPO


class DoubleIntegrator(Model):
    def __init__(self) -> None:
        super().__init__("double_integrator")
        x, v = self.state("x"), self.state("v")
        u = self.input("u")
        self.equation(self.der(x), v)
        self.equation(self.der(v), u)


def _problem(free: bool, tf: float, upper: float = 10.0) -> Optimization:
    m = DoubleIntegrator()
    opt = Optimization(m, final_time=tf, free_final_time=free, final_time_bounds=(0.1, upper) if free else None)
    s, u = m.variables("state"), m.variables("input")["u"]
    for name, at, value in (("x", "start", 0.0), ("v", "start", 0.0), ("x", "final", 1.0), ("v", "final", 0.0)):
        opt.add_point_constraint(s[name], at=at, lb=value, ub=value, name=None if name == "x" else f"{name}({at})")
    opt.set_bounds(u, -1.0, 1.0)
    opt.set_objective(mayer=opt.final_time if free else 0, lagrange=0 if free else u**2)
    return opt


def test_a_final_time_bound_below_the_minimum_time_is_named():
    res = CollocationTranscription(_problem(True, 0.5, upper=1.0), elements=20).solve()
    assert res.status == "infeasible" and res.last_iterate
    assert res.message.startswith("Infeasible_Problem_Detected; likely culprit: final_time at its upper bound 1 s at the last "
                                  "iterate: the minimum time may be above it (raise the final time's upper bound)")
    # the bang-bang input at its limits is the other remedy; the rows the last iterate misses are not listed then
    assert "bounds held over most of the horizon ('u' at its upper bound 1 at " in res.message
    assert "largest violations" not in res.message


def test_an_input_bound_that_forbids_the_motion_is_named_not_the_final_time():
    """u held to [-1, -0.5] cannot move x from 0 to 1 in any time: the last iterate sits at the shortest time allowed
    (the violations smallest there), and the bound that stops it is named (closed form: x(T) <= -T^2/4 < 0 for every T)."""
    opt = _problem(True, 3.0)
    opt.set_bounds(opt.model.variables("input")["u"], -1.0, -0.5)
    res = CollocationTranscription(opt, elements=20).solve()
    assert res.status == "infeasible"
    assert "final_time at its lower bound 0.1 s at the last iterate: a longer time does not meet the constraints" in res.message
    assert "lower the final time's lower bound" not in res.message
    assert "bounds held over most of the horizon ('u' at its upper bound -0.5 at 100 % of the samples)" in res.message
    assert "'point2' (x) at the final time by " in res.message


def test_otherwise_the_rows_violated_most_are_named():
    """A fixed final time too short: the final position is what the last iterate misses most (automatic names with their expression)."""
    res = CollocationTranscription(_problem(False, 1.0), elements=20).solve()
    assert res.status == "infeasible"
    prefix = "Infeasible_Problem_Detected; likely culprit: the largest violations at the last iterate: "
    assert res.message.startswith(prefix + "'point2' (x) at the final time by ")
    assert res.message.count(" by ") <= 3


def test_a_solution_keeps_its_message():
    res = CollocationTranscription(_problem(True, 3.0), elements=20).solve()
    assert res.status in ("optimal", "check_failed") and "likely culprit" not in res.message
    assert abs(res.final_time - 2.0) < 0.05


def test_with_culprit_diagnoses_only_a_last_iterate():
    opt = _problem(True, 0.5, upper=1.0)
    at_bound = SimpleNamespace(last_iterate=True, final_time=1.0)
    assert with_culprit("Infeasible_Problem_Detected", at_bound, opt).endswith("final_time at its upper bound 1 s at the last "
                                                                             "iterate: the minimum time may be above it (raise the final time's upper bound)")
    assert with_culprit("Solve_Succeeded", SimpleNamespace(last_iterate=False, final_time=1.0), opt) == "Solve_Succeeded"
    low = SimpleNamespace(last_iterate=True, final_time=0.1)
    assert likely_culprit(low, opt).startswith("final_time at its lower bound 0.1 s")


def test_a_result_without_a_trajectory_gives_no_diagnosis_and_no_error():
    opt = _problem(False, 1.0)
    empty = SimpleNamespace(last_iterate=True, final_time=1.0, dae=None, t=np.zeros(0))
    assert likely_culprit(empty, opt) == ""
    broken = SimpleNamespace(last_iterate=True, final_time=1.0, dae=opt.flat(), t=np.zeros(3), states={"x": [1, 2]},
                             algebraics={}, inputs={}, parameters={})
    assert with_culprit("Infeasible_Problem_Detected", broken, opt) == "Infeasible_Problem_Detected"


def test_the_command_line_and_summary_name_the_bound(tmp_path, capsys):
    """The published double integrator (minimum time 2 s) with the final time bounded to 1.5 s, through `gtmodel solve`."""
    from gtmodel.cli import main

    text = (REPO / "problems" / "benchmarks" / "double_integrator_min_time.toml").read_text(encoding="utf-8")
    edits = (("bounds = [0.5, 10.0]", "bounds = [0.5, 1.5]"), ("initial_guess = 3.0", "initial_guess = 1.0"),
             ('file = "models/', f'file = "{(REPO / "problems" / "benchmarks").as_posix()}/models/'))
    assert [old for old, _ in edits if old not in text] == [], "test out of date: the file has changed"
    for old, new in edits:
        text = text.replace(old, new, 1)
    (tmp_path / "short.toml").write_text(text, encoding="utf-8")
    assert main(["solve", str(tmp_path / "short.toml"), "--out", str(tmp_path / "R"), "--no-plots", "--quiet"]) == 1
    culprit = "likely culprit: final_time at its upper bound 1.5 s at the last iterate: the minimum time may be above it"
    assert culprit in capsys.readouterr().out
    summary = json.loads((tmp_path / "R" / "summary.json").read_text())
    assert summary["status"] == "infeasible" and culprit in summary["message"]


@pytest.mark.parametrize("name, shown", [("point3", "'point3' (x)"), ("T(final)", "'T(final)'")])
def test_automatic_names_show_their_expression(name, shown):
    from gtmodel.modeling.ocp.infeasibility import _label

    assert _label(SimpleNamespace(name=name, expr="x")) == shown


def test_multiple_shooting_names_the_bound_too():
    from gtmodel.modeling.ocp.shooting import ShootingTranscription

    res = ShootingTranscription(_problem(True, 0.5, upper=1.0), intervals=20).solve()
    assert res.status == "infeasible"
    assert "likely culprit: final_time at its upper bound 1 s at the last iterate" in res.message


class SaturatedIntegrator(Model):
    """``x'' = sat(u)``: a double integrator whose input passes a smooth limiter at +-1 (width 1e-3), or none."""

    def __init__(self, limited: bool) -> None:
        super().__init__("saturated_integrator")
        x, v = self.state("x"), self.state("v")
        u = self.input("u")
        self.equation(self.der(x), v)
        self.equation(self.der(v), smooth_limit(u, -1.0, 1.0, 1e-3) if limited else u)


def _trajectory(limited: bool, u: np.ndarray) -> SimpleNamespace:
    opt = Optimization(SaturatedIntegrator(limited), final_time=1.0)
    n = u.size
    return SimpleNamespace(dae=opt.flat(), t=np.linspace(0.0, 1.0, n), states={"x": np.zeros(n), "v": np.zeros(n)},
                           algebraics={}, inputs={"u": u}, parameters={}, last_iterate=True, final_time=1.0), opt


# the input at 0 (effect 1: the limiter's slope sigma((u+1)/eps) - sigma((u-1)/eps)) at 2 samples in 5, and at 1.005,
# 5 widths past the corner (slope sigma(-5) = 6.7e-3 < INERT_RATIO) at 3 in 5: inert at 60 % of the samples;
# without the limiter the same input acts equally everywhere
@pytest.mark.parametrize(("limited", "expected"), [(True, [("u", 0.6)]), (False, [])])
def test_an_input_saturated_inside_the_model_is_named_inert(limited, expected):
    u = np.array([0.0, 1.005, 1.005, 0.0, 1.005] * 4)
    result, opt = _trajectory(limited, u)
    assert 1 / (1 + np.exp(5.0)) < INERT_RATIO
    assert dict(inert_inputs(result, opt)) == pytest.approx(dict(expected))


def test_a_failed_solve_names_the_saturated_input_and_the_remedy():
    result, opt = _trajectory(True, np.array([0.0, 1.005, 1.005, 0.0, 1.005] * 4))
    message = with_culprit("Error_In_Step_Computation", result, opt)
    assert message.startswith("Error_In_Step_Computation; likely culprit: an input with almost no effect on the states "
                              "over much of the horizon ('u' at 60 % of the samples")
    assert message.endswith("bound the input within the saturation in [bounds]")


@pytest.mark.slow  # two solves of a servo with backlash and friction: about a minute of CPU
def test_a_servo_commanded_through_a_limiter_is_diagnosed_and_the_remedy_solves(tmp_path, capsys):
    """A model nobody tuned for: the torque command passes a smooth Limiter (0.5 N m, width 1e-3) inside the model.

    Commanded up to 0.6 N m, the solve ends ``error`` with every constraint met: the message names the command as
    saturated. Bounded within the saturation, as the message says, it ends optimal and verified, above the closed-form
    bang-bang minimum time without friction or play, 2 sqrt(1 rad / (0.5 N m / 0.06 kg m^2)) = 0.6928 s.
    """
    from gtmodel.cli import main

    for name in ("servo_limited.py", "servo_limited.toml"):
        (tmp_path / name).write_text((REPO / "tests" / "modeling" / "ocp" / "data" / name).read_text(encoding="utf-8"))
    problem = tmp_path / "servo_limited.toml"
    assert main(["solve", str(problem), "--out", str(tmp_path / "A"), "--no-plots", "--quiet"]) == 1
    summary = json.loads((tmp_path / "A" / "summary.json").read_text())
    assert summary["status"] == "error" and "('cmd' at " in summary["message"]
    assert "bound the input within the saturation in [bounds]" in summary["message"]
    problem.write_text(problem.read_text().replace('"cmd" = [-0.6, 0.6]', '"cmd" = [-0.5, 0.5]'))
    assert main(["solve", str(problem), "--out", str(tmp_path / "B"), "--no-plots", "--quiet"]) == 0
    summary = json.loads((tmp_path / "B" / "summary.json").read_text())
    assert summary["status"] == "optimal" and summary["verification"]["passed"]
    assert 2 * np.sqrt(1.0 / (0.5 / 0.06)) < summary["final_time_s"] < 0.8
    assert summary["final_time_s"] == pytest.approx(0.736, abs=1e-3)  # docs/own_model.md, section 6, quotes it


@pytest.mark.slow  # a continued multiple-shooting solve of the servo: about 30 CPU-s
def test_the_servo_within_its_saturation_solves_by_multiple_shooting_too(tmp_path):
    """Continued over the smoothing widths (docs/verification.md): infeasible from the declared guess without it."""
    from gtmodel.cli import main

    for name in ("servo_limited.py", "servo_limited.toml"):
        (tmp_path / name).write_text((REPO / "tests" / "modeling" / "ocp" / "data" / name).read_text(encoding="utf-8"))
    problem = tmp_path / "servo_limited.toml"
    problem.write_text(problem.read_text().replace('"cmd" = [-0.6, 0.6]', '"cmd" = [-0.5, 0.5]')
                       + '\n[transcription]\nmethod = "multiple_shooting"\n')
    assert main(["solve", str(problem), "--out", str(tmp_path / "S"), "--no-plots", "--quiet"]) == 0
    summary = json.loads((tmp_path / "S" / "summary.json").read_text())
    assert summary["status"] == "optimal" and summary["verification"]["passed"]
    assert [s["factor"] for s in summary["continuation"]["steps"]] == [100.0, 10.0]
    # piecewise-constant torque on 50 intervals: above the collocation optimum (0.736 s) by the O(h) of its switches
    assert 0.736 < summary["final_time_s"] < 0.76
