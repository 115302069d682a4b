"""The fixed-step integrators of a shooting interval on the explicit form (shooting_steps).

Independent references: the stability functions of the methods on ``x' = lambda x``
(closed forms: RK4 ``R(z) = 1 + z + z^2/2 + z^3/6 + z^4/24``; 2-stage Radau IIA
``R(z) = (1 + z/3) / (1 - 2z/3 + z^2/6)``, Hairer & Wanner, *Solving ODE II*, Table IV.5.5 and
sec. IV.3), the quadrature of ``x^2`` against its exact integral, and the elimination of an
algebraic variable (``w = u``, affine) against one only Newton solves (``w^3 + w = u``).
"""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

from gtmodel.modeling import Model
from gtmodel.modeling.ocp.shooting_steps import explicit_algebraics, fixed_steps


def _rk4(z):
    return 1 + z + z**2 / 2 + z**3 / 6 + z**4 / 24


def _radau(z):
    return (1 + z / 3) / (1 - 2 * z / 3 + z**2 / 6)


def _linear(lam):
    x, p, t = ca.SX.sym("x"), ca.SX.sym("p", 0), ca.SX.sym("t")
    return {"x": x, "p": p, "t": t, "ode": lam * x, "quad": x**2, "zout": ca.vertcat(2 * x)}


@pytest.mark.parametrize("method, stability, lam", [
    ("rk", _rk4, -1.0), ("rk", _rk4, -2.0), ("radau", _radau, -1.0), ("radau", _radau, -1000.0),
])
def test_one_step_is_the_methods_stability_function(method, stability, lam):
    F = fixed_steps(_linear(lam), 1, method)
    xf, zf, qf, xs, zs, ok = F(1.0, 0.0, ca.DM(0, 1))
    assert float(xf) == pytest.approx(stability(lam), rel=1e-12, abs=1e-14)
    assert float(zf) == pytest.approx(2 * float(xf), rel=1e-12, abs=1e-14) and float(ok) == 1.0


@pytest.mark.parametrize("method, order", [("rk", 4), ("radau", 3)])
def test_states_at_every_step_and_the_quadrature(method, order):
    # x' = -x from 1 over [0, 1] in 8 steps: x = exp(-t) at each step's end; int x^2 = (1 - e^-2) / 2
    F = fixed_steps(_linear(-1.0), 8, method)
    xf, zf, qf, xs, zs, ok = (np.array(v, dtype=float) for v in F(1.0, 0.0, ca.DM(0, 1)))
    t = np.arange(1, 9) / 8
    assert xs.shape == (1, 8) and zs.shape == (1, 8)
    assert np.max(np.abs(xs[0] - np.exp(-t))) < 10 * (1 / 8) ** order * 1e-1
    assert np.allclose(zs[0], 2 * xs[0], rtol=1e-14) and xf.item() == xs[0, -1]
    assert qf.item() == pytest.approx((1 - np.exp(-2)) / 2, rel=1e-3)


def _dae(cubic):
    m = Model("dae")
    x, w, u = m.state("x"), m.algebraic("w"), m.input("u")
    m.equation(m.der(x), w)
    m.equation((w**3 if cubic else 0) + w - u, 0)
    return m.flatten()


def test_affine_algebraics_are_eliminated():
    dae = _dae(cubic=False)
    e = explicit_algebraics(dae)
    assert e.reason == "" and float(ca.Function("z", [dae.t, dae.x, dae.u, dae.p], [e.z])(0.0, 1.0, 3.0, ca.DM(0, 1))) == 3.0


def test_newton_only_algebraics_are_named():
    e = explicit_algebraics(_dae(cubic=True))
    assert e.z is None and e.reason == "1 of its 1 algebraic variables are solved by a Newton iteration (equations not affine in them)"
