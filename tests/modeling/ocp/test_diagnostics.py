"""A failed solve of a model without inputs names the cause (IPOPT says only Not_Enough_Degrees_Of_Freedom).

Reference: the harmonic oscillator x'' = -x from rest at x = 0 stays at rest (closed form
x = 0), so no final time reaches x = 1: with no input nothing can be chosen.
"""

from __future__ import annotations

from types import SimpleNamespace

import pytest

from gtmodel.modeling import CollocationTranscription, Model, Optimization
from gtmodel.modeling.ocp.diagnostics import without_inputs


class Oscillator(Model):
    def __init__(self) -> None:
        super().__init__("oscillator")
        x, v = self.state("x"), self.state("v")
        self.equation(self.der(x), v)
        self.equation(self.der(v), -x)


def test_a_minimum_time_problem_without_inputs_names_the_missing_input():
    m = Oscillator()
    opt = Optimization(m, final_time=2.0, free_final_time=True, final_time_bounds=(0.1, 10.0))
    x, v = m.variables("state")["x"], m.variables("state")["v"]
    for sym, at, value in ((x, "start", 0.0), (v, "start", 0.0), (x, "final", 1.0), (v, "final", 0.0)):
        opt.add_point_constraint(sym, at=at, lb=value, ub=value)
    opt.set_objective(mayer=opt.final_time)
    res = CollocationTranscription(opt, elements=10).solve()
    assert res.status == "error"
    assert res.message.startswith("Not_Enough_Degrees_Of_Freedom: the model 'oscillator' has no inputs, so in a "
                                  "minimum-time problem (free final time) nothing but the final time and the start values")
    assert "declare the input that drives it" in res.message


@pytest.mark.parametrize("nu, message, named", [
    (0, "Not_Enough_Degrees_Of_Freedom", True),
    (0, "Infeasible_Problem_Detected", True),
    (0, "Solve_Succeeded", False),  # nothing failed
    (1, "Not_Enough_Degrees_Of_Freedom", False),  # it has an input: another cause
])
def test_the_cause_is_named_only_for_a_failure_of_a_model_without_inputs(nu, message, named):
    opt = SimpleNamespace(free_final_time=False, free_parameters={})
    out = without_inputs(opt, SimpleNamespace(nu=nu, name="m"), message)
    assert ("has no inputs" in out) == named and out.startswith(message)
    assert without_inputs(opt, SimpleNamespace(nu=nu, name="m"), out) == out  # named once
