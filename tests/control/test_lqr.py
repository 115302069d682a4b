"""The LQR designs (:mod:`gtmodel.control.lqr`) and the gain at rest a loop can trust around its rest point.

References: python-control's ``dlqr``; the stationary limit of the backward Riccati recursion; the closed form of a
scalar loop's pole, ``a - b k``, with and without the compensated delay; a closed loop simulated on the nonlinear
model (an RK4 step written here) from a state in the rest point's neighbourhood, independent of the eigenvalues
the design is chosen by.
"""

from __future__ import annotations

import casadi as ca
import control
import numpy as np
import pytest

from gtmodel.control.lqr import closed_loop_radius, dlqr, rest_groups, rest_linearization, riccati_gains
from gtmodel.control.tracking import tracking_controller
from gtmodel.defaults import REST_NEIGHBOURHOOD
from gtmodel.modeling import Model, explicit_ode

from .conftest import linearisation

DT = 0.004


def test_dlqr_equals_python_control(motor):
    ode, *_ = motor
    A, B = linearisation(ode, np.zeros(3), 0.0)
    Q, R = np.diag([1.0, 10.0, 0.01]), np.array([[0.1]])
    K, P = dlqr(A, B, Q, R)
    K_ref, P_ref, _ = control.dlqr(A, B, Q, R)
    np.testing.assert_allclose(K, K_ref, rtol=1e-9)
    np.testing.assert_allclose(P, P_ref, rtol=1e-9)


def test_riccati_recursion_converges_to_dlqr(motor):
    # a long horizon of constant A, B: the first gain is the stationary (dlqr) one
    ode, *_ = motor
    A, B = linearisation(ode, np.zeros(3), 0.0)
    Q, R = np.diag([1.0, 10.0, 0.01]), np.array([[0.1]])
    K, P = riccati_gains(np.tile(A, (2000, 1, 1)), np.tile(B, (2000, 1, 1)), Q, R, np.zeros((3, 3)))
    K_ref, P_ref, _ = control.dlqr(A, B, Q, R)
    np.testing.assert_allclose(K[0], K_ref, rtol=1e-8)
    np.testing.assert_allclose(P[0], P_ref, rtol=1e-8)


@pytest.mark.parametrize("delay", [0, 1])
@pytest.mark.parametrize("a, b, k", [(1.0, 0.5, 1.0), (1.2, 0.1, 1.0), (0.9, 1.0, -0.5)])
def test_a_scalar_loops_radius_is_its_pole_with_or_without_the_compensated_delay(a, b, k, delay):
    # closed form: u_k = -k (a x_k + b u_{k-1}) on x_{k+1} = a x_k + b u_{k-1}: det = lambda (lambda - (a - b k)), so the
    # compensated delay adds a pole at 0 and leaves a - b k
    assert closed_loop_radius(np.array([[k]]), np.array([[a]]), np.array([[b]]), delay) == pytest.approx(abs(a - b * k), abs=1e-12)


# a mass (1 kg) pushed by a force, with a Coulomb friction of 5 N smoothed over 10 mm/s (its slope at rest: 500 N s/m)
M, FC, DV = 1.0, 5.0, 0.01
Q_FRICTION, R_FRICTION = np.diag([1e6, 1.0]), np.array([[1e-4]])


def _friction(x, u):
    return ca.vertcat(x[1], (u - FC * ca.tanh(x[1] / DV)) / M)


def _rk4(x, u, substeps=4):
    h = DT / substeps
    for _ in range(substeps):
        k1 = _friction(x, u)
        k2 = _friction(x + h / 2 * k1, u)
        k3 = _friction(x + h / 2 * k2, u)
        k4 = _friction(x + h * k3, u)
        x = x + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
    return x


@pytest.fixture(scope="module")
def friction_mass():
    x, u = ca.SX.sym("x", 2), ca.SX.sym("u")
    xn = _rk4(x, u)
    step = ca.Function("F", [x, u], [xn])
    jac = ca.Function("J", [x, u], [ca.jacobian(xn, x), ca.jacobian(xn, u)])
    return step, lambda xx: tuple(np.asarray(m) for m in jac(xx, 0.0))


def _settles(step, K, delay, x0, periods=1000):
    """The nonlinear loop from x0 (no input bounds): the largest |position| over its last 200 periods."""
    x, u_last, s = np.asarray(x0, float), 0.0, []
    for _ in range(periods):
        seen = np.asarray(step(x, u_last)).ravel() if delay else x
        u = float((-K @ seen)[0])
        x = np.asarray(step(x, u_last if delay else u)).ravel()
        u_last = u
        s.append(abs(x[0]))
    return max(s[-200:])


@pytest.mark.parametrize("delay", [0, 1])
def test_the_gain_at_rest_holds_where_a_friction_leaves_its_band(friction_mass, delay):
    # the rest point's own Jacobian reads the friction's 500 N s/m as damping: its gain is unstable 0.1 m/s away (where the
    # friction's slope is gone), and simulated from 10 mm off, the loop runs away; the chosen design settles it
    step, jac = friction_mass
    r = rest_linearization(jac, np.zeros(2), np.array([0.1, 1.0]), Q_FRICTION, R_FRICTION, delay, ["s", "v"])
    own, chosen = (dlqr(*p, Q_FRICTION, R_FRICTION)[0] for p in (jac(np.zeros(2)), (r.A, r.B)))
    ran, settled = (_settles(step, K, delay, [0.01, 0.0]) for K in (own, chosen))
    assert (r.moved.startswith("v "), r.radius_own > 1.0, r.radius < 1.0, ran > 1.0, settled < 1e-9) == (True,) * 5, (r, ran, settled)


def test_a_linear_model_keeps_the_rest_points_ownlinearisation(motor):
    ode, *_ = motor
    A, B = linearisation(ode, np.zeros(3), 0.0)
    r = rest_linearization(lambda x: (A, B), np.zeros(3), np.ones(3), np.diag([1.0, 10.0, 0.01]), np.array([[0.1]]))
    assert (r.moved, r.radius == r.radius_own, r.radius < 1.0, np.array_equal(r.A, A)) == ("", True, True, True)


class _FrictionMass(Model):
    def __init__(self):
        super().__init__("friction_mass")
        s, v, F = self.state("s", unit="m"), self.state("v", unit="m/s"), self.input("F", unit="N")
        self.equation(self.der(s), v)
        self.equation(M * self.der(v), F - FC * ca.tanh(v / DV))


def test_a_tracking_laws_held_end_is_designed_on_the_neighbour_its_own_gain_fails():
    # independent: python-control's dlqr on the Jacobians of the same RK4 step at the end moved by the neighbourhood in v
    ode = explicit_ode(_FrictionMass())
    t = np.linspace(0.0, 0.4, 101)
    v = np.where(t < 0.2, np.sin(np.pi * t / 0.2), 0.0)
    s = np.concatenate([[0.0], np.cumsum(0.5 * (v[1:] + v[:-1]) * np.diff(t))])
    x = np.column_stack([s, v])
    u = (FC * np.tanh(v / DV) + M * np.gradient(v, t))[:, None]
    c = tracking_controller(ode, t, x, u, Q=np.diag([1e6, 1.0]), R=[1e-4], u_lb=[-1e3], u_ub=[1e3])
    d = REST_NEIGHBOURHOOD * (v.max() - v.min())
    sign = -1.0 if "v - " in c.rest.moved else 1.0
    A, B = linearisation(ode, c.x_hold + [0.0, sign * d], c.u_hold)
    K_ref = control.dlqr(A, B, c.Q, c.R)[0]
    np.testing.assert_allclose(c.K_hold, K_ref, rtol=1e-8)
    assert (c.rest.moved.startswith("v "), c.rest.radius_own > 1.0, c.rest.radius < 1.0) == (True, True, True), c.rest


REST_RUNS = [
    ([0, 0, 0, 1, 2, 2], [(0, 3), (4, 6)]),
    ([0, 1, 2, 3], []),
    ([5, 5], [(0, 2)]),
    ([0, 1, 1, 1, 2], [(1, 4)]),
]


@pytest.mark.parametrize("x, runs", REST_RUNS, ids=[str(x) for x, _ in REST_RUNS])
def test_rest_runs_are_the_repeated_states(x, runs):
    assert rest_groups(np.asarray(x, float)[:, None], np.ones(1)) == runs
