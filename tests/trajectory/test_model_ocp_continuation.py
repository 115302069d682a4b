"""Continuation over a model's smoothing widths on the default path of an ``optimal_control`` problem, and the solver named.

Independent check: the closed form of rest-to-rest minimum time of a mass ``m`` under a force ``|f| <= F``
against Coulomb friction ``Fc`` (bang-bang: accelerating at ``(F - Fc) / m``, braking at ``(F + Fc) / m``;
``v = sqrt(2 D a1 a2 / (a1 + a2))``, ``T = v / a1 + v / a2``), which the tanh-smoothed friction of width 1 mm/s
approaches to within 0.1 %.
"""

from __future__ import annotations

import json
import math
import textwrap

import pytest

from gtmodel.cli import main
from gtmodel.errors import GtModelError
from gtmodel.problems import load_problem

M, F, FC, D = 2.0, 20.0, 5.0, 1.0
A1, A2 = (F - FC) / M, (F + FC) / M
V = math.sqrt(2 * D * A1 * A2 / (A1 + A2))
T_CLOSED = V / A1 + V / A2  # 0.6532 s

MODEL = '''
from gtmodel.modeling import Component, Model, connect, structural_simplify
from gtmodel.modeling.library import translational as tr


class Slide(Component):
    force = tr.Force()
    mass = tr.Mass(m=2.0)
    friction = tr.Friction(Fc=5.0, dv=0.0, smoothing=1e-3)
    ground = tr.Fixed()

    def equations(self):
        connect(self.force.flange, self.mass.flange_a)
        connect(self.mass.flange_b, self.friction.flange_b)
        connect(self.friction.flange_a, self.ground.flange)


class SlideModel:
    def build(self) -> Model:
        return structural_simplify(Slide().to_model("slide"))
'''

PROBLEM = '''
name = "slide"
kind = "optimal_control"

[model]
file = "slide.py"
class = "SlideModel"

[optimization]
objective = "final_time"

[optimization.final_time]
free = true
initial_guess = 1.0
bounds = [0.05, 5.0]

[boundary.start]
"mass.v" = 0.0
"friction.s_rel" = 0.0

[boundary.final]
"mass.v" = 0.0
"friction.s_rel" = 1.0

[bounds]
"force.f" = [-20.0, 20.0]

[collocation]
elements = 30
'''


def problem(tmp_path, extra=""):
    (tmp_path / "slide.py").write_text(MODEL)
    path = tmp_path / "slide.toml"
    path.write_text(textwrap.dedent(PROBLEM) + textwrap.dedent(extra))
    return path


@pytest.fixture(scope="module")
def continued(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("slide")
    return load_problem(problem(tmp)).declaration.solve()


def test_continued_solve_reaches_the_closed_form(continued):
    assert str(continued.status) == "optimal" and continued.verification.passed
    assert continued.final_time == pytest.approx(T_CLOSED, rel=5e-3)


def test_continuation_record_reports_its_steps_and_final_widths(continued):
    c = continued.continuation
    assert [s["factor"] for s in c["steps"]] == [100.0, 10.0]
    assert all(s["status"] == "optimal" for s in c["steps"])
    assert c["final_widths"] == {"friction.smoothing": 1e-3} and c["started_from_factor"] == 10.0
    # the widest step's optimum is further from the closed form than the declared one: the friction smoothed over
    # 0.1 m/s brakes less near rest
    assert abs(c["last_step_relative_change"]) < 0.05


def test_continuation_off_reaches_the_same_optimum(tmp_path, continued):
    off = load_problem(problem(tmp_path, "\n[continuation]\nenabled = false\n")).declaration.solve()
    assert not off.continuation and str(off.status) == "optimal"
    assert off.final_time == pytest.approx(continued.final_time, rel=1e-4)


def test_summary_holds_the_continuation(tmp_path):
    out = tmp_path / "out"
    assert main(["solve", str(problem(tmp_path)), "--out", str(out), "--no-plots"]) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["continuation"]["final_widths"] == {"friction.smoothing": 0.001}


def test_fatrop_named_in_the_file_is_the_solver_that_runs(tmp_path):
    result = load_problem(problem(tmp_path, '\n[solver]\nname = "fatrop"\n\n[continuation]\nenabled = false\n')).declaration.solve()
    assert result.message.startswith("fatrop:") and result.final_time == pytest.approx(T_CLOSED, rel=5e-3)


@pytest.mark.parametrize("extra, match", [
    ("\n[continuation]\nstart_factor = 10.0\nstep = 100.0\n", r"continuation\.step"),
    ("\n[continuation]\nstart_factor = 1.0\n", r"continuation\.start_factor"),
    ('\n[solver]\nname = "fatrop"\n\n[transcription]\nmethod = "multiple_shooting"\n', r"solver\.name.*multiple_shooting"),
])
def test_bad_continuation_or_solver_is_refused_naming_the_field(tmp_path, extra, match):
    with pytest.raises(GtModelError, match=match):
        load_problem(problem(tmp_path, extra))


SHOOTING = '\n[transcription]\nmethod = "multiple_shooting"\n'


@pytest.fixture(scope="module")
def shooting(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("slide_shooting")
    return load_problem(problem(tmp, SHOOTING)).declaration.solve()


def test_multiple_shooting_is_continued_too(shooting):
    # the same steps as collocation's, each from the last's primal point; the declared solve verified, and the closed
    # form met to the O(h) of a piecewise-constant force (the switch inside one of 50 intervals)
    c = shooting.continuation
    assert [s["factor"] for s in c["steps"]] == [100.0, 10.0] and c["started_from_factor"] == 10.0
    assert str(shooting.status) == "optimal" and shooting.verification.passed
    assert shooting.final_time == pytest.approx(T_CLOSED, rel=2e-2)


def test_multiple_shooting_keeps_a_declared_cpu_budget_and_names_it(tmp_path):
    # the budget bounds the whole solve, the continuation's steps included (IPOPT's max_cpu_time: what is left of it)
    spent = load_problem(problem(tmp_path, SHOOTING + "max_cpu_s = 0.05\n")).declaration.solve()
    assert str(spent.status) == "max_iterations"
    assert all(s["status"] == "max_iterations" for s in spent.continuation["steps"])
    assert "Maximum_CpuTime_Exceeded; the CPU budget max_cpu_s = 0.05 in [transcription] is spent" in spent.message
    assert "raise max_cpu_s, or solve by collocation" in spent.message


@pytest.mark.slow  # tens of seconds of the default run's budget (measured 2026-11-28)
def test_a_generous_cpu_budget_changes_nothing(tmp_path, shooting):
    kept = load_problem(problem(tmp_path, SHOOTING + "max_cpu_s = 600\n")).declaration.solve()
    assert str(kept.status) == "optimal" and kept.final_time == pytest.approx(shooting.final_time, rel=1e-9)


def test_declared_widths_that_fail_warm_are_solved_again_cold(tmp_path, monkeypatch):
    # every warm solve held to 2 iterations (drive2_12 of the drive family's seed 2 ended Restoration_Failed warm from
    # its last step): the steps after the first and the declared widths fail warm; solved again cold from the last
    # step's primal point, the declared widths reach the closed form
    import gtmodel.modeling.ocp.collocation as collocation

    monkeypatch.setattr(collocation, "WARM_START_OPTIONS", {**collocation.WARM_START_OPTIONS, "max_iter": 2})
    res = load_problem(problem(tmp_path)).declaration.solve()
    retry = res.continuation["cold_retry"]
    assert retry["warm_status"] == "max_iterations" and retry["warm_iterations"] == 2 and retry["status"] == "optimal"
    assert str(res.status) == "optimal" and res.final_time == pytest.approx(T_CLOSED, rel=5e-3)
