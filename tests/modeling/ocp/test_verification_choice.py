"""The verification's integrator chosen by the model, and its relative test of the integrals.

Independent references: the eigenvalue of ``x' = -lam x + u`` is ``-lam`` (so an element of
length ``h`` holds ``h lam`` of its time constants: the stiffness the verifier reports);
the step response ``x = 1 - exp(-t)`` and its integrals in closed form; ``integral |f| dt``
of the cancelling integrand by scipy's adaptive quadrature (a second method).
"""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest
from scipy.integrate import quad

from gtmodel.modeling import CollocationTranscription, Model, Optimization
from gtmodel.modeling.ocp.verification import INTEGRAL_FLOOR, STIFF_STEPS, verify


class Decay(Model):
    """x' = -lam x + lam u (unit static gain)."""

    def __init__(self, lam: float) -> None:
        super().__init__("decay")
        x, u = self.state("x"), self.input("u")
        self.equation(self.der(x), -lam * x + lam * u)


def _step(lam: float, elements: int, lagrange_weight: float = 1.0):
    m = Decay(lam)
    opt = Optimization(m, final_time=2.0)
    x, u = m.variables("state")["x"], m.variables("input")["u"]
    opt.set_bounds(u, 1.0, 1.0)
    opt.add_point_constraint(x, at="start", lb=0.0, ub=0.0)
    opt.set_objective(lagrange=lagrange_weight * x**2)
    return opt


@pytest.mark.parametrize("lam, elements, method", [(1.0, 4, "Adams: non-stiff"), (1e3, 4, "BDF: stiff"), (1e3, 400, "Adams: non-stiff")])
def test_the_method_follows_the_stiffness_along_the_solution(lam, elements, method):
    # h |lambda| = (2 / elements) lam: 0.5, 500 (stiff: BDF) and 5 (a fine mesh of the same model)
    res = CollocationTranscription(_step(lam, elements), elements=elements, points=3).solve()
    rho = 2.0 / elements * lam
    assert (rho > STIFF_STEPS) == (method == "BDF: stiff")
    assert res.verification.integrator == f"cvodes, {method}, h |lambda| up to {rho:.3g} (rtol 1e-06)"


def test_a_small_objective_integral_is_held_to_a_relative_tolerance():
    # the energy 1e-3 integral x^2 of the step response (closed form), the NLP's value made 0.5 % too large:
    # absolute below 1 (the former test) it passed at tolerance 1e-3 (gap 6e-6 < 1e-3), relative it fails
    lam = 1.0
    res = CollocationTranscription(_step(lam, 20, 1e-3), elements=20, points=3, verify=False).solve()
    exact = 1e-3 * (2.0 - 2.0 * (1.0 - np.exp(-2.0)) + 0.5 * (1.0 - np.exp(-4.0)))
    x, t = ca.SX.sym("x"), ca.SX.sym("t")
    fn = ca.Function("f", [t, x, ca.SX(0, 1), ca.SX.sym("u"), ca.SX.sym("p", res.dae.p.numel())], [1e-3 * x**2])
    v = verify(res, 1e-3, integrals=(["energy"], fn, np.array([1.005 * exact])))
    c = v.integrals["energy"]
    assert c["simulated"] == pytest.approx(exact, rel=1e-5)  # the integrator at rtol 1e-6, atol 1e-8
    assert not c["passed"] and not v.passed and c["rel_deviation"] == pytest.approx(0.005 / 1.005, rel=1e-3)
    assert "relative 0.00498 > tolerance 0.001" in v.message
    assert verify(res, 1e-3, integrals=(["energy"], fn, np.array([1.0005 * exact]))).integrals["energy"]["passed"]


def test_an_integral_that_cancels_is_held_to_the_floor():
    # integral (x - mean x) dt = 0 exactly; the floor is INTEGRAL_FLOOR * integral |x - mean x| dt
    res = CollocationTranscription(_step(1.0, 40), elements=40, points=3, verify=False).solve()
    mean = (2.0 - (1.0 - np.exp(-2.0))) / 2.0
    x, t = ca.SX.sym("x"), ca.SX.sym("t")
    fn = ca.Function("f", [t, x, ca.SX(0, 1), ca.SX.sym("u"), ca.SX.sym("p", res.dae.p.numel())], [x - mean])
    v = verify(res, 1e-2, integrals=(["balance"], fn, np.array([0.0])))
    c = v.integrals["balance"]
    magnitude = quad(lambda s: abs(1.0 - np.exp(-s) - mean), 0.0, 2.0, points=[-np.log(1.0 - mean)])[0]
    assert c["passed"] and abs(c["simulated"]) < 1e-6
    # rel_deviation = gap / (INTEGRAL_FLOOR * A), A by the collocation quadrature (a kink: to 1e-3)
    assert c["abs_deviation"] / c["rel_deviation"] == pytest.approx(INTEGRAL_FLOOR * magnitude, rel=1e-3)
    shifted = verify(res, 1e-2, integrals=(["balance"], fn, np.array([0.02 * INTEGRAL_FLOOR * magnitude])))
    assert not shifted.integrals["balance"]["passed"]


def test_an_integral_below_the_simulations_accuracy_is_not_failed_for_its_noise():
    # 1e-12 integral x^2 = 7.6e-13: the NLP's value doubled differs by 7.6e-13, far below what the simulated
    # quadrature resolves (QUADRATURE_NOISE * atol * horizon = 10 * 1e-8 * 2 s); 1e-6 above it fails
    from gtmodel.modeling.ocp.verification import QUADRATURE_NOISE

    res = CollocationTranscription(_step(1.0, 20), elements=20, points=3, verify=False).solve()
    x, t = ca.SX.sym("x"), ca.SX.sym("t")
    fn = ca.Function("f", [t, x, ca.SX(0, 1), ca.SX.sym("u"), ca.SX.sym("p", res.dae.p.numel())], [1e-12 * x**2])
    exact = 1e-12 * (2.0 - 2.0 * (1.0 - np.exp(-2.0)) + 0.5 * (1.0 - np.exp(-4.0)))
    assert QUADRATURE_NOISE * 1e-8 * 2.0 == pytest.approx(2e-7)
    assert verify(res, 1e-2, integrals=(["tiny"], fn, np.array([2 * exact]))).integrals["tiny"]["passed"]
    assert not verify(res, 1e-2, integrals=(["tiny"], fn, np.array([exact + 1e-6]))).integrals["tiny"]["passed"]
