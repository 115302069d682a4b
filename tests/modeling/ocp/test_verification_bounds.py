"""The state bounds checked between the nodes, per element, and mesh refinement where they are exceeded.

Independent reference: the closed form ``x(t) = 1 - exp(-t)`` of ``x' = -x + 1``, ``x(0) = 0``, against an
upper bound of 0.8 (exceeded from ``t = ln 5`` on).
"""

from __future__ import annotations

import numpy as np
import pytest

from gtmodel.modeling import CollocationTranscription, Model, Optimization
from gtmodel.modeling.ocp.refinement import refine_mesh
from gtmodel.modeling.ocp.verification_bounds import bound_crossings, element_bound_violations

LOWER, UPPER = np.array([-np.inf]), np.array([0.8])


class Relaxation(Model):
    """x' = 1 - x (no input: no switch to refine for)."""

    def __init__(self) -> None:
        super().__init__("relaxation")
        x = self.state("x")
        self.equation(self.der(x), 1.0 - x)


@pytest.fixture(scope="module")
def step():
    """x(0) = 0 on [0, 2] s, 10 elements of 0.2 s, 3 Radau points (verified: deviation ~1e-6); bound not declared."""
    m = Relaxation()
    opt = Optimization(m, final_time=2.0)
    x = m.variables("state")["x"]
    opt.add_point_constraint(x, at="start", lb=0.0, ub=0.0)
    opt.set_objective(lagrange=x**2)
    return CollocationTranscription(opt, elements=10, points=3).solve()


@pytest.mark.parametrize("k", range(10))
def test_element_violation_is_the_closed_forms_at_the_elements_end(step, k):
    # x increases: its largest excess over 0.8 in element k is at the element's end, t = 0.2 (k + 1)
    expected = max(0.0, 1.0 - np.exp(-0.2 * (k + 1)) - 0.8)
    assert element_bound_violations(step, LOWER, UPPER)[k] == pytest.approx(expected, abs=1e-5)


def test_element_violations_are_zero_without_bounds(step):
    assert np.array_equal(element_bound_violations(step, np.array([-np.inf]), np.array([np.inf])), np.zeros(10))


def test_crossing_is_where_the_closed_form_reaches_the_bound(step):
    # 1 - exp(-t) = 0.8 at t = ln 5 = 1.6094 s: in element 8 (1.6 to 1.8 s) at tau = 0.047 (to the 1/400 grid);
    # element 9 starts above the bound (no crossing inside it)
    crossings = bound_crossings(step, LOWER, UPPER, [8, 9], 0.0)
    assert set(crossings) == {8}
    assert crossings[8] == pytest.approx((np.log(5.0) - 1.6) / 0.2, abs=1 / 400)


@pytest.mark.parametrize("with_bounds, split", [(False, []), (True, [8, 9])])
def test_refinement_splits_the_elements_that_exceed_a_bound(step, with_bounds, split):
    # closed form: the excess at an element's end exceeds the tolerance 0.01 where 1 - exp(-t) > 0.81, t > 1.661 s,
    # so elements 8 and 9 only; nothing else to split (the deviation ~1e-6, no input switch)
    mesh, info = refine_mesh(step, 1e-2, 400, bounds=(LOWER, UPPER) if with_bounds else None)
    assert info["split"] == split
    assert len(mesh) == 10 + (5 if with_bounds else 0) and mesh.sum() == pytest.approx(1.0)


def test_refinement_cuts_where_the_bound_is_crossed(step):
    # element 8's first cut where x exceeds the bound by a quarter of the tolerance: 1 - exp(-t) = 0.8025,
    # t = -ln(0.1975) = 1.6220 s (closed form), to the 1/400 grid of the element (0.5 ms)
    mesh, _ = refine_mesh(step, 1e-2, 400, bounds=(LOWER, UPPER))
    edges = 2.0 * np.cumsum(mesh)
    assert np.min(np.abs(edges - (-np.log(0.1975)))) <= 0.2 / 400 + 1e-9
