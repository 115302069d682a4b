"""The measurement filter in front of a loop controller (``gtmodel.control.state_filter``).

References: the Kalman filter's predict and update written out by hand in NumPy for a linear model (``x+ = A x + B u``,
exact for the filter's linearisation), and its gain iterated to the steady state compared with the one from SciPy's
discrete algebraic Riccati equation (``scipy.linalg.solve_discrete_are``, the dual of the LQR's); a double integrator
measured with noise, whose filtered position is closer to the truth than the measurement.
"""

from __future__ import annotations

import math

import casadi as ca
import numpy as np
import pytest
import scipy.linalg

from gtmodel.control.state_filter import INPUT_ERROR, NOISE_BAND, PARAMETER_ERROR, STATE_ERROR, measurement_filter, state_filter
from gtmodel.errors import InputError

DT = 0.004
A = np.array([[1.0, DT], [0.0, 0.98]])
B = np.array([[0.5 * DT**2], [DT]])
SIGMA = np.array([1e-3, 2e-2])
X_SCALE, U_SCALE = np.array([0.5, 2.0]), np.array([40.0])


def _linear_step() -> ca.Function:
    x, u = ca.MX.sym("x", 2), ca.MX.sym("u", 1)
    return ca.Function("F", [x, u], [ca.mtimes(ca.DM(A), x) + ca.mtimes(ca.DM(B), u)])


def _Q() -> np.ndarray:
    return B @ np.diag((INPUT_ERROR * U_SCALE) ** 2) @ B.T + np.diag((STATE_ERROR * X_SCALE) ** 2)


def _run(f, ys, us):
    """The filter's update over measurements ``ys`` with inputs ``us`` (no delay): the estimates and the last memory."""
    update, wf, out = f.update(), f.memory_initial(np.zeros(2), np.zeros(1)), []
    for y, u in zip(ys, us):
        x, wf = update(y, u, ca.DM(0, 1), wf)
        out.append(np.asarray(x, dtype=float).reshape(-1))
    return np.array(out), np.asarray(wf, dtype=float).reshape(-1)


def _rhs() -> ca.Function:
    """A right-hand side with a damping ``p`` of the speed: ``f = (v, -p v + u)``, ``df/dp = (0, -v)``."""
    x, u, p = ca.MX.sym("x", 2), ca.MX.sym("u", 1), ca.MX.sym("p", 1)
    return ca.Function("f", [x, u, p], [ca.vertcat(x[1], -p * x[1] + u)])


P_DAMPING = 5.0


@pytest.mark.parametrize("parametric", [False, True])
def test_the_update_is_the_kalman_filter_written_out_by_hand(parametric):
    extra = {"rhs": _rhs(), "p": [P_DAMPING], "dt": DT} if parametric else {}
    f = state_filter(_linear_step(), SIGMA, X_SCALE, U_SCALE, **extra)
    rng = np.random.default_rng(1)
    ys, us = rng.normal(size=(4, 2)) * [0.1, 1.0], rng.normal(size=(4, 1)) * 10
    got, _ = _run(f, ys, us)
    R = np.diag(SIGMA**2)
    x, P, expected = ys[0], R.copy(), [ys[0]]  # the first step takes the measurement, P = R
    for y, u_prev in zip(ys[1:], us[1:]):  # without a delay u_last (computed a period ago) acted over the last period
        # each parameter PARAMETER_ERROR off: J_p = Gamma df/dp, Gamma = DT (I + A) / 2, df/dp = (0, -v) at the estimate
        jp = DT / 2 * (np.eye(2) + A) @ [0.0, -x[1]]
        Qp = np.outer(jp, jp) * (PARAMETER_ERROR * P_DAMPING) ** 2 if parametric else 0.0
        xm, Pm = A @ x + B @ u_prev, A @ P @ A.T + _Q() + Qp
        L = Pm @ np.linalg.inv(Pm + R)
        x, P = xm + L @ (y - xm), (np.eye(2) - L) @ Pm
        expected.append(x)
    np.testing.assert_allclose(got, np.array(expected), rtol=1e-10, atol=1e-12)


@pytest.mark.parametrize("decay, rel", [(10.0, 0.03), (100.0, 0.26)])
def test_the_parameter_term_is_the_steps_sensitivity_to_second_order(decay, rel):
    """``Q``'s parameter term ``Gamma df/dp`` against the exact sensitivity of the step of ``dx/dt = -a x``
    (closed form ``dF/da = -dt x e^(-a dt)``): 2 % apart at ``a dt = 0.04``, 25 % at ``a dt = 0.4`` (the held
    sensitivity over-states a fast state's, never under-states it)."""
    x0 = 2.0
    ad = math.exp(-decay * DT)
    x, u, p = ca.MX.sym("x", 1), ca.MX.sym("u", 1), ca.MX.sym("p", 1)
    step = ca.Function("F", [x, u], [ad * x + (1 - ad) / decay * u])
    rhs = ca.Function("f", [x, u, p], [-p * x + u])
    f = state_filter(step, [1e3], [1e-12], [1e-12], rhs=rhs, p=[decay], dt=DT)  # R huge: the update keeps P^- = Q
    wf = f.memory_initial([x0], [0.0])
    wf[1], wf[-1] = 0.0, 1.0  # P = 0, a step has run
    spread = math.sqrt(float(f.update()([x0], [0.0], ca.DM(0, 1), wf)[1][1]))  # |J_p| 0.2 a
    exact = PARAMETER_ERROR * decay * DT * x0 * ad
    assert spread == pytest.approx(exact, rel=rel)
    assert spread >= exact


@pytest.mark.parametrize("innovation, expected", [
    ([0.5 * SIGMA[0], -2.0 * SIGMA[1]], [0.0, 0.0]),                      # within the band: noise
    ([4.0 * SIGMA[0], -5.0 * SIGMA[1]], [1.0 * SIGMA[0], -2.0 * SIGMA[1]]),  # beyond it: the part beyond
], ids=["within", "beyond"])
def test_the_models_error_is_the_innovation_beyond_the_noise_band(innovation, expected):
    f = state_filter(_linear_step(), SIGMA, X_SCALE, U_SCALE)
    got = np.asarray(ca.evalf(f.model_error(ca.DM(innovation))), dtype=float).reshape(-1)
    assert NOISE_BAND == 3.0
    np.testing.assert_allclose(got, expected, rtol=1e-12, atol=1e-15)


def test_a_state_without_noise_keeps_its_innovation():
    f = state_filter(_linear_step(), [0.0, SIGMA[1]], X_SCALE, U_SCALE)
    got = np.asarray(ca.evalf(f.model_error(ca.DM([1e-9, SIGMA[1]]))), dtype=float).reshape(-1)
    np.testing.assert_allclose(got, [1e-9, 0.0], atol=1e-15)


def test_the_covariance_settles_at_the_riccati_equations_steady_state():
    f = state_filter(_linear_step(), SIGMA, X_SCALE, U_SCALE)
    _, wf = _run(f, np.zeros((600, 2)), np.zeros((600, 1)))
    P = wf[2:6].reshape(2, 2, order="F")
    Pm = scipy.linalg.solve_discrete_are(A.T, np.eye(2), _Q(), np.diag(SIGMA**2))  # the prior covariance's fixed point
    L = Pm @ np.linalg.inv(Pm + np.diag(SIGMA**2))
    np.testing.assert_allclose(P, (np.eye(2) - L) @ Pm, rtol=1e-6)


def test_a_noisy_measurement_is_filtered_towards_the_truth():
    f = state_filter(_linear_step(), SIGMA, X_SCALE, U_SCALE)
    rng = np.random.default_rng(0)
    n = 400
    us = np.sin(np.arange(n) * 0.05)[:, None] * 20
    x, truth = np.zeros(2), []
    for u in us:
        truth.append(x)
        x = A @ x + B @ u
    truth = np.array(truth)
    ys = truth + SIGMA * rng.standard_normal(truth.shape)
    est, _ = _run(f, ys, np.vstack([np.zeros((1, 1)), us[:-1]]))  # u_last at sample k: the input over the last period
    raw, filtered = np.sqrt(np.mean((ys - truth) ** 2, axis=0)), np.sqrt(np.mean((est - truth) ** 2, axis=0))
    assert np.all(filtered < 0.6 * raw)


def test_with_a_delay_the_prediction_takes_the_input_computed_a_period_earlier():
    f = state_filter(_linear_step(), SIGMA, X_SCALE, U_SCALE, delay=1)
    wf = f.memory_initial(np.array([0.1, 1.0]), np.array([3.0]))
    wf[-1] = 1.0
    x = np.asarray(f.prediction()(np.array([-7.0]), ca.DM(0, 1), wf), dtype=float).reshape(-1)
    np.testing.assert_allclose(x, A @ [0.1, 1.0] + B @ [3.0], rtol=1e-12)


def test_the_disturbance_estimate_is_added_to_the_predictions_input():
    f = state_filter(_linear_step(), SIGMA, X_SCALE, U_SCALE, disturbance=(2, 3))
    wf = f.memory_initial(np.array([0.1, 1.0]), np.array([3.0]))
    x = np.asarray(f.prediction()(np.array([3.0]), np.array([9.0, 9.0, 0.5]), wf), dtype=float).reshape(-1)
    np.testing.assert_allclose(x, A @ [0.1, 1.0] + B @ [3.5], rtol=1e-12)


def _inner():
    """A law with a memory of one entry, the count of its calls: ``u = -x_0``, ``w_next = w + 1``."""
    t, x, u_last, w = ca.MX.sym("t"), ca.MX.sym("x", 2), ca.MX.sym("u_last", 1), ca.MX.sym("w", 1)
    control = ca.Function("control", [t, x, u_last, w], [-x[0], w + 1, ca.DM(1)], ["t", "x", "u_last", "w"], ["u", "w_next", "ok"])
    tr, xr = ca.MX.sym("t"), ca.MX.sym("x", 2)
    return control, ca.Function("reset", [tr, xr], [ca.DM(0.0), ca.DM(5.0)], ["t", "x"], ["u_last", "w"])


def test_the_wrapped_step_gives_the_law_the_filtered_state_and_keeps_both_memories():
    f = state_filter(_linear_step(), SIGMA, X_SCALE, U_SCALE)
    control, reset, predict = f.wrap(*_inner(), 1)
    u0, w0 = reset(0.0, [0.2, 0.0])
    w0 = np.asarray(w0, dtype=float).reshape(-1)
    assert w0.size == 1 + f.n_memory and w0[0] == 5.0 and w0[-1] == 0.0
    u, w1, ok = control(0.0, [0.2, 0.0], u0, w0)  # first step: the measurement itself
    assert float(u) == pytest.approx(-0.2) and float(ok) == 1.0
    y = np.array([0.3, 0.0])
    u, w2, _ = control(DT, y, u, w1)
    xm = A @ [0.2, 0.0] + B @ [-0.2]
    x_hat = np.asarray(f.update()(y, np.array([-0.2]), ca.DM(0, 1), np.asarray(w1).reshape(-1)[1:])[0]).reshape(-1)
    assert float(u) == pytest.approx(-x_hat[0], rel=1e-12)
    assert xm[0] < x_hat[0] < y[0]  # between the prediction and the measurement
    assert float(np.asarray(w2).reshape(-1)[0]) == 7.0  # the law's own memory, counted twice from 5
    np.testing.assert_allclose(np.asarray(predict(u, w2), dtype=float).reshape(-1),
                               A @ x_hat + B @ np.asarray(u).reshape(-1), rtol=1e-12)


def test_the_memory_range_holds_the_first_memory_and_bounds_the_covariance():
    f = state_filter(_linear_step(), SIGMA, X_SCALE, U_SCALE)
    r = f.memory_range(np.array([[-1.0, -5.0], [1.0, 5.0]]), np.array([[-40.0], [40.0]]))
    w = f.memory_initial(np.zeros(2), np.zeros(1))
    assert r.shape == (2, f.n_memory) and np.all((r[0] <= w) & (w <= r[1]))
    np.testing.assert_array_equal(r[:, 2:6], [[0.0, -20.0, -20.0, 0.0], [4.0, 20.0, 20.0, 100.0]])


def test_no_noise_builds_no_filter():
    assert state_filter(_linear_step(), [0.0, 0.0], X_SCALE, U_SCALE) is None


@pytest.mark.parametrize("kwargs, match", [
    ({"sigma": [1e-3]}, "step: expected"),
    ({"sigma": [1e-3, -1.0]}, "sigma: expected 2 finite"),
    ({"sigma": [1e-3, np.nan]}, "sigma: expected 2 finite"),
    ({"x_scale": [0.0, 1.0]}, "x_scale, u_scale: expected finite scales > 0"),
    ({"u_scale": [np.inf]}, "x_scale, u_scale: expected finite scales > 0"),
    ({"delay": 2}, "delay: expected 0 or 1"),
    ({"delay": True}, "delay: expected 0 or 1"),
    ({"rhs": "f", "p": [1.0], "dt": DT}, "rhs, p, dt: expected f"),
    ({"rhs": _rhs(), "p": [np.inf], "dt": DT}, "rhs, p, dt: expected f"),
    ({"rhs": _rhs(), "p": [1.0, 2.0], "dt": DT}, "rhs, p, dt: expected f"),
    ({"rhs": _rhs(), "p": [1.0]}, "rhs, p, dt: expected f"),
    ({"rhs": _rhs(), "p": [1.0], "dt": -DT}, "rhs, p, dt: expected f"),
])
def test_bad_arguments_are_refused(kwargs, match):
    args = {"step": _linear_step(), "sigma": SIGMA, "x_scale": X_SCALE, "u_scale": U_SCALE, **kwargs}
    with pytest.raises(InputError, match=match):
        state_filter(**args)


def test_a_controller_without_a_step_is_refused():
    with pytest.raises(InputError, match="controller: expected a loop controller with its one-period step"):
        measurement_filter(object(), SIGMA)


def test_a_law_that_takes_x_hat_gets_the_measurement_and_the_filtered_state_apart():
    # its own estimators measure the innovation from the measurement; it acts on the filtered state
    t, x, u_last, w, x_hat = ca.MX.sym("t"), ca.MX.sym("x", 2), ca.MX.sym("u_last", 1), ca.MX.sym("w", 1), ca.MX.sym("x_hat", 2)
    inner = ca.Function("control", [t, x, u_last, w, x_hat], [-x_hat[0], x[0], ca.DM(1)], ["t", "x", "u_last", "w", "x_hat"],
                        ["u", "w_next", "ok"])
    f = state_filter(_linear_step(), SIGMA, X_SCALE, U_SCALE)
    control, reset, _ = f.wrap(inner, _inner()[1], 1)
    _, w0 = reset(0.0, [0.2, 0.0])
    u, w1, _ = control(0.0, [0.2, 0.0], 0.0, w0)
    y = np.array([0.3, 0.0])
    u, w2, _ = control(DT, y, u, w1)
    x_hat_ = np.asarray(f.update()(y, np.array([-0.2]), ca.DM(0, 1), np.asarray(w1).reshape(-1)[1:])[0]).reshape(-1)
    assert float(np.asarray(w2).reshape(-1)[0]) == 0.3  # the law's memory: the measurement it was given as x
    assert float(u) == pytest.approx(-x_hat_[0], rel=1e-12) and x_hat_[0] < 0.3
