"""The model's fixed starts and initial equations as initial conditions of an optimisation.

A mass pushed by a force, composed from the standard library with ``Mass(s=3)``: move it to
``s = 4`` at rest in 1 s with least ``integral(F^2)``. The start position is the model's
fixed start (no start constraint in the problem); the start velocity is free (its start is
a library default, a guess). Reference: Pontryagin's conditions by hand (free ``v(0)``
gives ``lambda_v(0) = 0``, so ``F = a t``; ``v(1) = 0`` and ``s(1) = 4`` give ``a = -3``,
``v(0) = 1.5 m/s``, ``J = 3``), independent of the code.
"""

from __future__ import annotations

import numpy as np
import pytest

from gtmodel._tables import split_unit
from gtmodel.errors import ModelError
from gtmodel.modeling import Component, Optimization, connect, solve
from gtmodel.modeling.library import translational as tr
from gtmodel.modeling.ocp.initial import InitialConditionConflict
from gtmodel.problems import run_problem
from gtmodel.status import Status

from ...conftest import assert_bad_problem_through_cli


class Pushed(Component):
    push = tr.Force()
    mass = tr.Mass(m=1.0, s=3.0)

    def equations(self):
        connect(self.push.flange, self.mass.flange_a)


class PushedGuess(Pushed):
    mass = tr.Mass(m=1.0, s={"start": 3.0, "fixed": False})


def _problem(component: Component, **start) -> Optimization:
    m = component.to_model("pushed")
    states, force = m.variables("state"), m.variables("input")["push.f"]
    opt = Optimization(m, final_time=1.0)
    for name, (lb, ub) in start.items():
        opt.add_point_constraint(states[name], at="start", lb=lb, ub=ub, name=f"start of {name}")
    opt.add_point_constraint(states["mass.s"], at="final", lb=4.0, ub=4.0)
    opt.add_point_constraint(states["mass.v"], at="final", lb=0.0, ub=0.0)
    opt.set_objective(lagrange=force**2)
    return opt


def test_fixed_start_is_the_initial_condition():
    r = solve(_problem(Pushed()), elements=8, points=3)
    assert r.status == "optimal"
    assert r.states["mass.s"][0] == pytest.approx(3.0, abs=1e-9)
    assert r.states["mass.v"][0] == pytest.approx(1.5, abs=1e-6)  # free: Pontryagin by hand
    assert r.objective == pytest.approx(3.0, rel=1e-6)


@pytest.mark.parametrize("start, s0", [pytest.param((3.0, 3.0), 3.0, marks=pytest.mark.slow), ((2.0, 3.5), None)],
                         ids=["same_value", "inequality_frees"])
def test_problem_start_constraint_takes_the_place_of_the_fixed_start(start, s0):
    opt = _problem(Pushed(), **{"mass.s": start})
    assert not [c for c in opt.point_constraints if c.name.startswith("fixed start")]
    r = solve(opt, elements=8, points=3)
    assert r.status == "optimal"
    if s0 is not None:
        assert r.states["mass.s"][0] == pytest.approx(s0, abs=1e-9)
    else:  # freed within [2, 3.5]: the effort falls as the start nears the target, so it ends at 3.5
        assert r.states["mass.s"][0] == pytest.approx(3.5, abs=1e-6)


@pytest.mark.parametrize("start", [(0.0, 0.0), (3.5, 5.0)], ids=["other_value", "bounds_exclude_it"])
def test_conflicting_start_constraint_is_refused_naming_the_variable(start):
    opt = _problem(Pushed(), **{"mass.s": start})
    with pytest.raises(InitialConditionConflict, match=r"initial condition of 'mass\.s': the model's fixed start "
                       r"mass\.s = 3 contradicts the problem's start constraint 'start of mass\.s'"):
        opt.point_constraints
    with pytest.raises(ModelError, match=r"'mass\.s'"):
        solve(opt, elements=4, points=3)


def test_guess_is_no_initial_condition():
    opt = _problem(PushedGuess())
    assert [c.name for c in opt.point_constraints] == ["point0", "point1"]
    r = solve(opt, elements=8, points=3)
    # s(0) free too: the mass starts at the target at rest, no effort
    assert r.status == "optimal" and r.objective == pytest.approx(0.0, abs=1e-8)


class ReleasedMass(Component):  # the MSL tutorial's mass-spring-damper, pushed
    push = tr.Force()
    mass = tr.Mass(m=1.0, s=3.0, v=10.0)
    damper = tr.SpringDamper(c=10.0, d=1.0)
    wall = tr.Fixed()

    def equations(self):
        connect(self.push.flange, self.mass.flange_a)
        connect(self.mass.flange_b, self.damper.flange_a)
        connect(self.damper.flange_b, self.wall.flange)


def test_fixed_start_of_a_dummy_derivative_holds_on_the_initial_state():
    # index reduction keeps damper.s_rel as the state and makes mass.s algebraic; its fixed
    # start still holds exactly (written in the state through the connection equations).
    # Reference: the free motion s'' + s' + 10 s = 0 from (3, 10) in closed form,
    # s = exp(-t/2) (3 cos(w t) + B sin(w t)), w = sqrt(39)/2, B = (10 + 3/2) / w.
    from gtmodel.modeling.structure import structural_simplify

    m = structural_simplify(ReleasedMass().to_model("msd"))
    states = m.variables("state")
    assert "mass.s" not in states and "damper.s_rel" in states
    opt = Optimization(m, final_time=1.0)
    opt.set_bounds(m.variables("input")["push.f"], 0.0, 0.0)  # released: the dynamics alone
    r = solve(opt, elements=20, points=3)
    assert r.status == "optimal"
    assert r.states["damper.s_rel"][0] == pytest.approx(-3.0, abs=1e-12) and r.states["mass.v"][0] == pytest.approx(10.0, abs=1e-12)
    w = np.sqrt(39.0) / 2.0
    s_ref = np.exp(-0.5) * (3.0 * np.cos(w) + (11.5 / w) * np.sin(w))
    assert -r.states["damper.s_rel"][-1] == pytest.approx(s_ref, abs=1e-5)


@pytest.mark.slow
def test_initial_equation_is_an_initial_condition():
    m = PushedGuess().to_model("pushed")
    states = m.variables("state")
    m.initial_equation(states["mass.s"] + states["mass.v"], 4.5, name="sum")  # with v(0) = 1.5: s(0) = 3
    opt = Optimization(m, final_time=1.0)
    opt.add_point_constraint(states["mass.v"], at="start", lb=1.5, ub=1.5)
    opt.add_point_constraint(states["mass.s"], at="final", lb=4.0, ub=4.0)
    opt.add_point_constraint(states["mass.v"], at="final", lb=0.0, ub=0.0)
    opt.set_objective(lagrange=m.variables("input")["push.f"] ** 2)
    r = solve(opt, elements=8, points=3)
    assert r.status == "optimal" and r.states["mass.s"][0] == pytest.approx(3.0, abs=1e-9)
    assert r.objective == pytest.approx(3.0, rel=1e-6)


MODEL = '''
from gtmodel.modeling import Component, connect
from gtmodel.modeling.library import translational as tr


class Pushed(Component):
    push = tr.Force()
    mass = tr.Mass(m=1.0, s=3.0)

    def equations(self):
        connect(self.push.flange, self.mass.flange_a)
'''
PROBLEM = '''
kind = "optimal_control"
[model]
file = "pushed.py"
class = "Pushed"
[optimization]
objective = "integral(push_f^2)"
[optimization.final_time]
free = false
value = 1.0
[boundary.final]
mass_s = 4.0
mass_v = 0.0
[collocation]
elements = 8
'''


@pytest.fixture
def folder(tmp_path):
    (tmp_path / "pushed.py").write_text(MODEL)
    return tmp_path


@pytest.mark.slow
def test_problem_file_starts_at_the_fixed_start(folder):
    (folder / "p.toml").write_text(PROBLEM)
    outcome = run_problem(folder / "p.toml", folder / "out", plots=False)
    assert outcome.status == Status.OPTIMAL
    assert outcome.summary["objective"] == pytest.approx(3.0, rel=1e-6)
    first = open(folder / "out" / "trajectories.csv").read().splitlines()
    header, values = [split_unit(h)[0] for h in first[0].split(",")], first[1].split(",")  # ("mass.s [m]"; a text column: the point)
    assert float(values[header.index("mass.s")]) == pytest.approx(3.0, abs=1e-9)


BAD = [
    ("boundary_contradicts_fixed_start", "[boundary.final]", "[boundary.start]\nmass_s = 0.0\n[boundary.final]",
     r"field 'boundary\.start\.mass_s': initial condition of 'mass\.s': the model's fixed start mass\.s = 3"),
    ("constraint_contradicts_fixed_start", 'objective = "integral(push_f^2)"',
     'objective = "integral(push_f^2)"\nconstraints = ["mass_s(start_time) >= 3.5"]',
     r"field 'optimization\.constraints\[0\]': initial condition of 'mass\.s'"),
]


@pytest.mark.parametrize("case, old, new, match", BAD, ids=[c[0] for c in BAD])
def test_bad_initial_condition_through_cli(folder, capsys, case, old, new, match):
    assert old in PROBLEM
    assert_bad_problem_through_cli(folder, capsys, PROBLEM.replace(old, new), match)
