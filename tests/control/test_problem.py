"""The tracking problem the TV-LQR and the MPC share (gtmodel.control.problem).

Independent checks: python-control's ``dlqr`` on the problem's own linearisation (the
time-invariant tracking controller's gain), Bryson's rule written out from the reference's
ranges (closed form), explicit Euler written out by hand (closed form), and the identity of
what both controllers carry with what the problem built.
"""

from __future__ import annotations

import casadi as ca
import control
import numpy as np
import pytest

from gtmodel.control.mpc import mpc_controller
from gtmodel.control.problem import TrackingProblem, tracking_problem
from gtmodel.control.tracking import tracking_controller
from gtmodel.errors import InputError

DT = 0.004


@pytest.fixture(scope="module")
def problem(motor):
    ode, t, x, u = motor
    return tracking_problem(ode, t, x, u, DT)


def test_problem_is_sampled_at_the_period(motor, problem):
    ode, t, x, u = motor
    assert isinstance(problem, TrackingProblem)
    assert problem.x_ref.shape == (251, ode.nx) and problem.u_ref.shape == (251, ode.nu)
    np.testing.assert_allclose(problem.x_ref[::25], np.column_stack([np.interp(t[::10], t, x[:, j]) for j in range(ode.nx)]), atol=1e-12)


def test_default_weights_are_brysons_rule(motor, problem):
    # closed form: Q = diag(1 / range(x*)^2) with the floor 1e-3 (1 + max|x*|); R = diag(1 / (half the bound range)^2)
    xs = problem.x_ref
    scale = np.maximum(np.ptp(xs, axis=0), 1e-3 * (1.0 + np.max(np.abs(xs), axis=0)))
    np.testing.assert_allclose(np.diag(problem.Q), 1.0 / scale**2, rtol=1e-12)
    lb, ub = problem.u_lb, problem.u_ub
    expected_r = 1.0 / (0.5 * (ub - lb)) ** 2 if np.all(np.isfinite([lb, ub])) else 1.0 / problem.u_scale**2
    np.testing.assert_allclose(np.diag(problem.R), expected_r, rtol=1e-12)


def test_both_controllers_carry_the_problems_weights_and_bounds(motor, problem):
    ode, t, x, u = motor
    lqr = tracking_controller(ode, t, x, u, dt=DT)
    mpc = mpc_controller(ode, t, x, u, horizon=5, dt=DT)
    for c in (lqr, mpc):
        np.testing.assert_array_equal(c.Q, problem.Q)
        np.testing.assert_array_equal(c.R, problem.R)
        np.testing.assert_array_equal(c.u_lb, problem.u_lb)
        np.testing.assert_array_equal(c.x_ref, problem.x_ref)
    np.testing.assert_array_equal(mpc.Qf, problem.Q)  # the MPC's terminal weight defaults to Q


def test_time_invariant_gain_is_python_controls_dlqr(motor, problem):
    # the held end's linearisation of the problem's own step, solved by python-control
    ode, t, x, u = motor
    lqr = tracking_controller(ode, t, x, u, dt=DT, time_varying=False)
    xs, us = ca.SX.sym("x", ode.nx), ca.SX.sym("u", ode.nu)
    xn = problem.prediction("rk4")(xs, us)
    A, B = (np.asarray(m) for m in ca.Function("AB", [xs, us], [ca.jacobian(xn, xs), ca.jacobian(xn, us)])(lqr.x_hold, lqr.u_hold))
    K_ref, _, _ = control.dlqr(A, B, problem.Q, problem.R)
    np.testing.assert_allclose(lqr.K_hold, K_ref, rtol=1e-8)


def test_euler_prediction_is_written_out(motor, problem):
    ode, *_ = motor
    x0, u0 = np.array([0.1, -0.2, 0.3]), np.array([2.0])
    f = lambda x: np.asarray(ode.f(x, u0, problem.p)).reshape(-1)  # noqa: E731
    h = DT / 2
    x1 = x0 + h * f(x0)
    np.testing.assert_allclose(np.asarray(problem.prediction("euler", 2)(ca.DM(x0), ca.DM(u0))).reshape(-1), x1 + h * f(x1), rtol=1e-12)


def test_terminal_weight(problem):
    np.testing.assert_array_equal(problem.terminal_weight(None, problem.Q), problem.Q)
    np.testing.assert_array_equal(problem.terminal_weight([1.0, 2.0, 3.0], problem.Q), np.diag([1.0, 2.0, 3.0]))


@pytest.mark.parametrize("kwargs, match", [
    (dict(u_lb=[1.0], u_ub=[0.0]), "u_lb, u_ub: expected 1 bounds each with u_lb <= u_ub"),
    (dict(p=[1.0]), "p: expected .* parameter values, got 1"),
    (dict(Q=[1.0, 2.0]), r"Q: expected 3 diagonal entries or a \(3, 3\) matrix"),
    (dict(R=[0.0]), "R: expected a positive definite input weight"),
    (dict(R=[[-1.0]]), "R: expected a symmetric positive semi-definite weight"),
    (dict(dt=0.0), "dt: expected a positive loop period"),
])
def test_bad_input(motor, kwargs, match):
    ode, t, x, u = motor
    args = dict(dt=DT) | kwargs
    with pytest.raises(InputError, match=match):
        tracking_problem(ode, t, x, u, **args)


def test_wrong_columns_are_refused(motor):
    ode, t, x, u = motor
    with pytest.raises(InputError, match=r"x_ref, u_ref: expected 3 state and 1 \(>= 1\) input columns, got 2 and 1"):
        tracking_problem(ode, t, x[:, :2], u, DT)
