"""Integral action of the tracking controller (``tracking_controller(..., integral_weights=...)``).

References: python-control's ``dlqr(..., integral_action=dt C)`` (the augmented gain at the
held end); the closed form of the steady state of a double integrator under a constant input
disturbance ``d``: with ``u = -K (x - x*)`` it rests at the position error ``d / K_x`` (the
acceleration ``u + d`` vanishes at rest), with the integral it rests at the reference; the
saturation (the integrator held, exactly, while the input saturates).
"""

from __future__ import annotations

import control
import numpy as np
import pytest
import scipy.linalg

from gtmodel.errors import InputError
from gtmodel.control.tracking import tracking_controller
from gtmodel.modeling import explicit_ode

from ..modeling._builders import double_integrator

DT = 0.004
N = 251
T = DT * np.arange(N)
X_REF = np.tile([1.0, 0.0], (N, 1))  # rest at x = 1
U_REF = np.zeros((N, 1))
Q, R = [1e4, 1.0], [1e-2]


@pytest.fixture(scope="module")
def ode():
    return explicit_ode(double_integrator()[0])


def _controller(ode, **kwargs):
    return tracking_controller(ode, T, X_REF, U_REF, dt=DT, Q=Q, R=R, u_lb=[-100.0], u_ub=[100.0], time_varying=False, **kwargs)


def test_augmented_gain_equals_python_control(ode):
    c = _controller(ode, integral_weights={"x": 1e6})
    A = np.array([[1.0, DT], [0.0, 1.0]])  # RK4 of the double integrator: exact
    B = np.array([[0.5 * DT**2], [DT]])
    K_ref, _, _ = control.dlqr(A, B, scipy.linalg.block_diag(np.diag(Q), [[1e6]]), np.diag(R), integral_action=DT * np.array([[1.0, 0.0]]))
    np.testing.assert_allclose(np.hstack([c.K_hold, c.Ki_hold]), K_ref, rtol=1e-8)
    np.testing.assert_allclose(c.Ki[0], c.Ki_hold, rtol=1e-12)  # time-invariant: one gain
    assert c.integral_states == (0,) and c.ni == 1


def _steady_state(ode, c, d, steps=6000):
    step = ode.step(DT, "rk4")
    f = c.function()
    x, w = np.array([1.0, 0.0]), np.zeros(c.ni)
    for k in range(steps):
        out = f(T[min(k, N - 1)], x, [0.0], *([w] if c.ni else []))
        u = float(out[0])
        if c.ni:
            w = np.asarray(out[1]).reshape(-1)
        x = np.asarray(step(x, [u + d], ode.p_default)[0]).reshape(-1)
    return x


@pytest.mark.parametrize("d", [0.5, -2.0])
def test_integral_action_removes_the_steady_state_error(ode, d):
    plain, integral = _controller(ode), _controller(ode, integral_weights={"x": 1e6})
    x_plain, x_int = _steady_state(ode, plain, d), _steady_state(ode, integral, d)
    assert x_plain[0] - 1.0 == pytest.approx(d / plain.K_hold[0, 0], rel=1e-6)  # closed form d / K_x
    assert abs(x_int[0] - 1.0) < 1e-9 and abs(x_int[1]) < 1e-9


def test_integrator_holds_while_the_input_saturates(ode):
    c = _controller(ode, integral_weights={"x": 1e6})
    f = c.function()
    u, w_next, ok = f(T[10], [0.0, 0.0], [0.0], [1e-5])  # 1 m off: the law asks for far more than 100
    assert float(u) == 100.0 and float(w_next) == 1e-5 and float(ok) == 1.0
    u, w_next, _ = f(T[10], [1.001, 0.0], [0.0], [0.0])  # 1 mm off: inside the bounds, integrates dt e
    assert abs(float(u)) < 100.0 and float(w_next) == pytest.approx(DT * 0.001, rel=1e-12)


@pytest.mark.parametrize("weights, match", [
    ({"y": 1.0}, "'y' is not a state"),
    ({"x": 0.0}, r"integral_weights\['x'\]: expected a finite weight > 0"),
    ({"x": float("nan")}, "expected a finite weight > 0"),
    ([("x", 1.0)], "expected a mapping"),
], ids=["unknown state", "zero", "nan", "not a mapping"])
def test_bad_integral_weights(ode, weights, match):
    with pytest.raises(InputError, match=match):
        _controller(ode, integral_weights=weights)
