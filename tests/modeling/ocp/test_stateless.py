"""Collocation of a problem without states: free parameters, algebraic variables and a path cost.

A stateless model has no continuity constraints and no final state; with one element the NLP's
variable vector can be a single free parameter (the algebraic variable eliminated), which failed
building the (empty) continuity constraints (``Dimension mismatch ... 1x0 vs 0x1``). The
references are closed forms whose cost is constant in time, so every mesh and scheme gets them
exactly.
"""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

from gtmodel.modeling import Model, Optimization, solve

TF = 2.0


def linear_static() -> tuple[Optimization, float, float]:
    """z = p - 2, min int_0^TF z^2 + (p - 3)^2 dt: p = 2.5, cost TF (0.25 + 0.25)."""
    m = Model("static_linear")
    p = m.parameter("p", 0.0)
    z = m.algebraic("z")
    m.equation(z, p - 2.0)
    opt = Optimization(m, final_time=TF)
    opt.free_parameter("p")
    opt.objective_integrand = z**2 + (p - 3.0) ** 2
    return opt, 2.5, 0.5 * TF


def nonlinear_static() -> tuple[Optimization, float, float]:
    """exp(z) = p, min int_0^TF (z - 1)^2 + (p - e)^2 dt: z = 1 and p = e, cost 0."""
    m = Model("static_nonlinear")
    p = m.parameter("p", 1.0)
    z = m.algebraic("z", start=0.5)
    m.equation(ca.exp(z), p)
    opt = Optimization(m, final_time=TF)
    opt.free_parameter("p", lb=0.1, ub=10.0, start=1.0)
    opt.objective_integrand = (z - 1.0) ** 2 + (p - np.e) ** 2
    return opt, np.e, 0.0


MESHES = [(1, 1), (1, 3), (2, 1), (3, 2)]


@pytest.mark.parametrize("scheme", ["radau", "legendre"])
@pytest.mark.parametrize(("elements", "points"), MESHES, ids=[f"{e}x{p}" for e, p in MESHES])
@pytest.mark.parametrize("problem", [linear_static, nonlinear_static], ids=["linear", "nonlinear"])
def test_stateless_problem_matches_closed_form(problem, elements, points, scheme):
    opt, p_star, cost = problem()
    res = solve(opt, elements=elements, points=points, scheme=scheme)
    assert res.status == "optimal"
    assert res.parameters["p"] == pytest.approx([p_star], abs=1e-7)
    assert res.objective == pytest.approx(cost, abs=1e-8)
