"""Tracking controller: feedforward + time-varying LQR of a model along a reference.

References: python-control's ``dlqr`` (time-invariant LQR), the stationary limit of the
backward Riccati recursion, a closed loop on the model's step with mismatched parameters
(the feedback must beat the feedforward alone), and the saturation bounds.
"""

from __future__ import annotations

import casadi as ca
import control
import numpy as np
import pytest

from gtmodel.errors import InputError
from gtmodel.control.reference import period_means
from gtmodel.control.tracking import limit_noise_gain, tracking_controller
from gtmodel.modeling import explicit_ode
from gtmodel.problems.user_model import load_user_model

from ..conftest import REPO
from .conftest import linearisation

DT = 0.004
#: Angle-tracking weights of the motor: the armature current is an internal state (weighting
#: it by its range, Bryson's default, fights the angle correction), the rotor angle is the task.
Q_ANGLE = [1e-2, 1.0, 1e-4]


def test_linear_motor_gains_are_the_stationary_ones(motor):
    # the motor is linear: A_k, B_k constant; with Qf the stationary P every K_k is dlqr's
    ode, t, x, u = motor
    c = tracking_controller(ode, t, x, u, u_lb=[-10.0], u_ub=[10.0])
    A, B = linearisation(ode, np.zeros(3), 0.0)
    K_ref, _, _ = control.dlqr(A, B, c.Q, c.R)
    assert c.K.shape == (251, 1, 3)
    np.testing.assert_allclose(c.K, np.broadcast_to(K_ref, c.K.shape), rtol=1e-8)


def _closed_loop(ode, c, p, feedback: bool) -> float:
    """RMS error of the load angle (rotor angle) over the reference, plant with parameters p."""
    step = ode.step(DT, "rk4", substeps=4)
    law = c.function()
    xk = c.x_ref[0].copy()
    err = []
    for k in range(c.length - 1):
        uk = np.asarray(law(k * DT, xk, c.u_initial)[0]).ravel() if feedback else c.u_ref[k]
        xk = np.asarray(step(xk, uk, p)[0]).ravel()
        err.append(xk[1] - c.x_ref[k + 1, 1])
    return float(np.sqrt(np.mean(np.square(err))))


def test_feedback_halves_the_error_of_the_feedforward_with_10_percent_mismatch(motor):
    ode, t, x, u = motor
    c = tracking_controller(ode, t, x, u, u_lb=[-24.0], u_ub=[24.0], Q=Q_ANGLE)
    p = ode.p_default.copy()
    for name in ("r.R", "emf.k", "friction.d", "load.J"):
        p[ode.p_names.index(name)] *= 1.1
    assert _closed_loop(ode, c, p, True) < 0.5 * _closed_loop(ode, c, p, False)


def test_input_is_saturated_at_the_bounds(motor):
    ode, t, x, u = motor
    c = tracking_controller(ode, t, x, u, u_lb=[-7.0], u_ub=[7.0], Q=Q_ANGLE)
    far = c.x_ref[100] + np.array([0.0, 50.0, 0.0])
    assert c(100 * DT, far) == pytest.approx([-7.0]) and c(100 * DT, c.x_ref[100] - [0.0, 50.0, 0.0]) == pytest.approx([7.0])
    # on the reference the input is the feedforward; before it the first sample, after it the held end
    assert c(100 * DT, c.x_ref[100]) == pytest.approx(c.u_ref[100], abs=1e-12)
    assert c(-1.0, c.x_ref[0]) == pytest.approx(c.u_ref[0], abs=1e-12)
    assert c(99.0, c.x_hold) == pytest.approx(c.u_hold, abs=1e-12)


def test_held_end_input_holds_the_final_state(motor):
    # reference: the model itself, f(x_end, u_hold) = 0 where the input can hold the state;
    # the motor's end state of this reference is at rest in current only if u_hold balances it
    ode, t, x, u = motor
    c = tracking_controller(ode, t, x, u)
    np.testing.assert_array_equal(c.x_hold, x[-1])
    rest = np.asarray(ode.f(c.x_hold, c.u_hold, ode.p_default)).ravel()
    # one input, three states: the current equation is balanced, the others are what they are
    assert abs(rest[0]) < 1e-9 * (1 + abs(c.u_hold[0]))


@pytest.mark.parametrize("t, x", [(np.nan, [0.0, 0.0, 0.0]), (0.1, [np.nan, 0.0, 0.0])], ids=["t_nan", "x_nan"])
def test_non_finite_input_is_not_ok(motor, t, x):
    ode, tt, xx, uu = motor
    c = tracking_controller(ode, tt, xx, uu, u_lb=[-np.inf], u_ub=[np.inf])
    assert float(c.function()(t, x, c.u_initial)[1]) == 0.0


@pytest.mark.parametrize(
    "kwargs, match",
    [
        ({"dt": 0.0}, r"dt: expected a positive loop period in seconds, got 0\.0"),
        ({"t": [0.0, 0.0]}, "t: expected at least two increasing finite reference times"),
        ({"t": [0.0, 0.001], "x_ref": np.zeros((2, 3)), "u_ref": np.zeros((2, 1))}, r"shorter than one period \(0\.004 s\)"),
        ({"x_ref": np.zeros((101, 2))}, "x_ref, u_ref: expected 3 state and 1"),
        ({"R": [0.0]}, "R: expected a positive definite input weight"),
        ({"Q": [[1.0, 2.0], [3.0, 4.0]]}, r"Q: expected 3 diagonal entries or a \(3, 3\) matrix"),
        ({"u_lb": [1.0], "u_ub": [0.0]}, "u_lb, u_ub: expected 1 bounds each with u_lb <= u_ub"),
    ],
    ids=["dt", "t", "short", "x_columns", "R", "Q", "bounds"],
)
def test_bad_arguments(motor, kwargs, match):
    ode, t, x, u = motor
    args = {"t": t, "x_ref": x, "u_ref": u, **kwargs}
    with pytest.raises(InputError, match=match):
        tracking_controller(ode, **args)


@pytest.fixture(scope="module")
def pendulum():
    # a nonlinear model: the cart pendulum swinging under a sine force (A_k, B_k vary along the motion)
    ode = explicit_ode(load_user_model(REPO / "models" / "cart_pendulum.py", "CartPendulum"))
    t = np.linspace(0.0, 0.5, 51)
    u = (2.0 * np.sin(2 * np.pi * t / 0.5))[:, None]
    x, _ = ode.simulate_steps(ode.step(0.01, "rk4", substeps=10), u[:-1])
    return ode, t, x, u


def test_time_invariant_gain_is_python_controls_dlqr_at_the_held_end(pendulum):
    # python-control's dlqr on the Jacobians of the same RK4 step at (x*_end, u_hold), independently formed here
    ode, t, x, u = pendulum
    c = tracking_controller(ode, t, x, u, u_lb=[-50.0], u_ub=[50.0], time_varying=False)
    xs, us = ca.SX.sym("x", ode.nx), ca.SX.sym("u", ode.nu)
    xn = ode.step(DT, "rk4")(xs, us, ode.p_default)[0]
    A, B = (np.asarray(m) for m in ca.Function("AB", [xs, us], [ca.jacobian(xn, xs), ca.jacobian(xn, us)])(c.x_hold, c.u_hold))
    K_ref, _, _ = control.dlqr(A, B, c.Q, c.R)
    np.testing.assert_allclose(c.K, np.broadcast_to(K_ref, c.K.shape), rtol=1e-8)
    varying = tracking_controller(ode, t, x, u, u_lb=[-50.0], u_ub=[50.0])
    assert np.max(np.abs(varying.K[0] - K_ref)) > 1e-3 * np.max(np.abs(K_ref))  # the recursion's gains differ along the swing


def test_compensated_delay_reproduces_the_undelayed_loop(pendulum):
    # reference: the same law without delay on the same plant. With the plant the prediction's own step and an
    # input acting one period late, the compensated law sees the true state at t_{k+1}: its inputs are the
    # undelayed loop's from the state x_1 on (identical up to round-off)
    ode, t, x, u = pendulum
    kw = dict(u_lb=[-50.0], u_ub=[50.0])
    plain, delayed = tracking_controller(ode, t, x, u, **kw), tracking_controller(ode, t, x, u, delay=1, **kw)
    step, p = ode.step(DT, "rk4"), ode.p_default
    f, g = plain.function(), delayed.function()
    x_true = x[0] + np.array([0.01, 0.02, 0.0, 0.0])
    u_now = delayed.u_initial
    x_next = np.asarray(step(x_true, u_now, p)[0]).ravel()  # the state when the first computed input starts to act
    got, want, xw = [], [], x_next.copy()
    for k in range(40):
        u_new = np.asarray(g(k * DT, x_true, u_now)[0]).ravel()
        want.append(np.asarray(f((k + 1) * DT, xw, plain.u_initial)[0]).ravel())
        got.append(u_new)
        x_true = np.asarray(step(x_true, u_now, p)[0]).ravel()
        xw = np.asarray(step(xw, want[-1], p)[0]).ravel()
        u_now = u_new
    np.testing.assert_allclose(np.array(got), np.array(want), rtol=1e-9, atol=1e-9)


def test_delay_other_than_0_or_1_is_refused(pendulum):
    ode, t, x, u = pendulum
    with pytest.raises(InputError, match=r"delay: expected 0 or 1 period of input delay to compensate, got 2"):
        tracking_controller(ode, t, x, u, delay=2)


def test_a_delayed_law_computes_the_plans_first_input_from_the_rest_before_it(motor):
    # reference: the plan's own first-period input (period_means of the given one) and the law's closed form at zero
    # error. A plan starting at rest with 6 V (0 V holds the motor there) and one period of input delay: the reference
    # gets one period at rest (delayed_start); at the first measurement the plant rests under the held 0 V, the state
    # predicted one period on is the plan's first, and the input computed there, acting from the plan's first time on,
    # is the plan's first input
    ode, t, _, _ = motor
    u = (6.0 * np.cos(2 * np.pi * t))[:, None]
    x, _ = ode.simulate_steps(ode.step(0.01, "rk4", substeps=10), u[:-1])
    c = tracking_controller(ode, t, x, u, u_lb=[-24.0], u_ub=[24.0], Q=Q_ANGLE, delay=1)
    assert c.lead == 1 and c.t0 == pytest.approx(-DT) and c.u_initial == pytest.approx([0.0], abs=1e-9)
    first = np.asarray(c.function()(c.t0, x[0], c.u_initial)[0]).ravel()
    assert first == pytest.approx(period_means(t, u, np.array([0.0]), DT)[0], rel=1e-9)


def _response(K, sigma):
    return np.sqrt(np.sum((np.asarray(K) * sigma) ** 2, axis=-1))


def test_noise_gain_limit_scales_only_the_rows_above_it_to_it(pendulum):
    # reference: the one-sigma response sqrt(sum_j (K_ij sigma_j)^2) by hand; the rows above the limit (the median
    # response along the swing) end exactly there, the others are the Riccati gains untouched
    ode, t, x, u = pendulum
    c = tracking_controller(ode, t, x, u, u_lb=[-50.0], u_ub=[50.0], integral_weights={ode.x_names[0]: 1.0})
    sigma = np.full(ode.nx, 1e-2)
    before = _response(np.concatenate([c.K, c.K_hold[None]]), sigma)[:, 0]
    limit = float(np.median(before))
    assert np.any(before > limit * (1 + 1e-6)) and np.any(before < limit * (1 - 1e-6))  # the case tests both sides
    lim = limit_noise_gain(c, sigma, limit / 50.0)
    after = _response(np.concatenate([lim.K, lim.K_hold[None]]), sigma)[:, 0]
    np.testing.assert_allclose(after, np.minimum(before, limit), rtol=1e-12)
    np.testing.assert_allclose(lim.gain_scale[:, 0], np.minimum(1.0, limit / before), rtol=1e-12)
    np.testing.assert_allclose(lim.Ki, c.Ki * lim.gain_scale[:-1, :, None], rtol=1e-12)


def test_noise_gain_limit_leaves_a_law_below_it_as_it_is(motor):
    ode, t, x, u = motor
    c = tracking_controller(ode, t, x, u, u_lb=[-24.0], u_ub=[24.0], Q=Q_ANGLE)
    assert limit_noise_gain(c, [0.0, 1e-9, 1e-9]) is c and limit_noise_gain(c, [0.0, 0.0, 0.0]) is c


@pytest.mark.parametrize("sigma, fraction, match", [
    ([0.1, 0.1], 0.1, r"sigma: expected 3 finite standard deviations >= 0"),
    ([0.1, -0.1, 0.1], 0.1, r"sigma: expected 3 finite standard deviations >= 0"),
    ([0.1, np.nan, 0.1], 0.1, r"sigma: expected 3 finite standard deviations >= 0"),
    ([0.1, 0.1, 0.1], 0.0, r"fraction: expected a finite number > 0, got 0.0"),
    ([0.1, 0.1, 0.1], True, r"fraction: expected a finite number > 0, got True"),
])
def test_noise_gain_limit_refuses_bad_noise_or_fractions(motor, sigma, fraction, match):
    ode, t, x, u = motor
    c = tracking_controller(ode, t, x, u, u_lb=[-24.0], u_ub=[24.0], Q=Q_ANGLE)
    with pytest.raises(InputError, match=match):
        limit_noise_gain(c, sigma, fraction)
