"""Declared state bounds held by a law without constraint rows (``gtmodel.control.state_limits``).

Independent checks: the largest voltage that keeps an RL circuit's current within its bound over one period, in
closed form (``i(h) = i0 e^{-h/tau} + v/R (1 - e^{-h/tau})``); the tracking law's input on a DC motor far off its
reference, integrated over the period by SciPy's adaptive RK45 (not the law's fixed step): the current stays within
its bound where the saturated law alone exceeds it.
"""

from __future__ import annotations

from dataclasses import replace

import casadi as ca
import numpy as np
import pytest
from scipy.integrate import solve_ivp

from gtmodel.control.bounds import TARGET_MARGIN
from gtmodel.control.state_limits import BACKOFF_GAIN, envelope, parameter_margin, state_limits
from gtmodel.control.state_limits import MARGIN_ERROR
from gtmodel.control.state_filter import NOISE_BAND, measurement_filter
from gtmodel.control.tracking import tracking_controller
from gtmodel.errors import InputError


R_OHM, TAU, DT = 2.0, 0.01, 0.004
AIM = 1 - TARGET_MARGIN  # the controllers aim inside each bound by the check's tolerance


def _rk4_substeps(f, x):
    """The states after each of 4 RK4 substeps of ``x' = f(x)`` over one period."""
    h, states, xi = DT / 4, [], x
    for _ in range(4):
        k1 = f(xi)
        k2 = f(xi + h / 2 * k1)
        k3 = f(xi + h / 2 * k2)
        k4 = f(xi + h * k3)
        xi = xi + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        states.append(xi)
    return states


def _rl_rows(n_circuits: int = 1):
    """``n`` RL circuits ``di/dt = (v - R i) / L`` as RK4 substeps over one period (1 ms steps: 1e-7 off the exponential)."""
    x, u = ca.SX.sym("x", n_circuits), ca.SX.sym("u", n_circuits)
    p = ca.SX.sym("p", 0)
    states = _rk4_substeps(lambda z: (u - R_OHM * z) / (R_OHM * TAU), x)
    return ca.Function("S", [x, u, p], [ca.horzcat(*states)])


def _project(limits, x, u0, lb, ub, margin=None):
    xs, us = ca.MX.sym("x", x.size), ca.MX.sym("u", u0.size)
    held = None if margin is None else ca.MX(ca.DM(margin))
    return np.asarray(ca.Function("f", [xs, us], [limits.project(xs, us, lb, ub, margin=held)])(x, u0)).ravel()


def _rl_p():
    """One RL circuit with its parameters free, ``p = (R, L)``: ``(substeps S(x, u, p), step F(x, u, p))``."""
    x, u, p = ca.SX.sym("x"), ca.SX.sym("u"), ca.SX.sym("p", 2)
    states = _rk4_substeps(lambda z: (u - p[0] * z) / p[1], x)
    return ca.Function("S", [x, u, p], [ca.horzcat(*states)]), ca.Function("F", [x, u, p], [states[-1]])


def _rl_current(i0, v, R, L, t):
    return i0 * np.exp(-t * R / L) + v / R * (1 - np.exp(-t * R / L))


def test_the_parameter_margin_is_the_closed_forms_change():
    """Independent: the closed-form current with R, then L, MARGIN_ERROR (10 %) off either way, the larger change, summed in squares."""
    S, F = _rl_p()
    p = np.array([R_OHM, R_OHM * TAU])
    limits = state_limits(S, ["i"], {"i": (-10.0, 10.0)}, p, np.array([-200.0]), np.array([200.0]), np.zeros((2, 1)))
    x_ref, u_ref = np.array([[3.0]]), np.array([[12.0]])
    got = parameter_margin(limits.rows_p, F, x_ref, u_ref, p)[0]
    t = DT * np.arange(1, 5) / 4
    nominal = _rl_current(3.0, 12.0, *p, t)
    change = [np.maximum(*(np.abs(_rl_current(3.0, 12.0, *(p + s * e), t) - nominal) for s in (-1, 1))) for e in np.diag(MARGIN_ERROR * p)]
    expected = np.sqrt(sum(c**2 for c in change))
    np.testing.assert_allclose(got, expected, rtol=1e-4)


def test_the_parameter_margin_fades_once_the_loop_has_measured():
    """Full over the lead and the delay's periods, then BACKOFF_GAIN smaller each period (a reference at rest: the same
    sensitivity every period)."""
    S, F = _rl_p()
    p = np.array([R_OHM, R_OHM * TAU])
    limits = state_limits(S, ["i"], {"i": (-10.0, 10.0)}, p, np.array([-200.0]), np.array([200.0]), np.zeros((2, 1)))
    x_ref, u_ref = np.full((6, 1), 3.0), np.full((6, 1), 3.0 * R_OHM)
    m = parameter_margin(limits.rows_p, F, x_ref, u_ref, p, delay=1, lead=1)
    fade = (1 - BACKOFF_GAIN) ** np.array([0, 0, 0, 1, 2, 3])
    np.testing.assert_allclose(m / m[0], np.broadcast_to(fade[:, None], m.shape), rtol=1e-9)


def test_the_projection_holds_the_margin_off_the_bound():
    """Closed form: the voltage whose current ends the period at the aimed 9.9 A less the last row's margin."""
    limits = state_limits(_rl_rows(), ["i"], {"i": (-10.0, 10.0)}, np.zeros(0), np.array([-200.0]), np.array([200.0]), np.zeros((2, 1)))
    decay = np.exp(-DT / TAU)
    margin = np.array([0.1, 0.2, 0.3, 0.5])
    v_max = R_OHM * (AIM * 10.0 - 0.5 - 3.0 * decay) / (1 - decay)
    got = _project(limits, np.array([3.0]), np.array([100.0]), np.array([-200.0]), np.array([200.0]), margin)
    assert got == pytest.approx([v_max], rel=1e-5)


@pytest.mark.parametrize("i0", [0.0, 3.0, 9.0], ids=["at_rest", "part_way", "near_the_bound"])
def test_one_input_reaches_the_closed_form_largest_voltage(i0):
    """The law asks 100 V; the projection gives the voltage whose current ends the period at 9.9 A (closed form: the
    10 A bound aimed at 1 % inside)."""
    limits = state_limits(_rl_rows(), ["i"], {"i": (-10.0, 10.0)}, np.zeros(0), np.array([-200.0]), np.array([200.0]), np.zeros((2, 1)))
    decay = np.exp(-DT / TAU)
    v_max = R_OHM * (AIM * 10.0 - i0 * decay) / (1 - decay)  # the bound aimed at: TARGET_MARGIN inside 10 A
    assert _project(limits, np.array([i0]), np.array([100.0]), np.array([-200.0]), np.array([200.0])) == pytest.approx([v_max], rel=1e-5)


def test_an_admissible_input_is_left_as_it_is():
    """Within every bound the law's input is the result (the saturated law's)."""
    limits = state_limits(_rl_rows(), ["i"], {"i": (-10.0, 10.0)}, np.zeros(0), np.array([-200.0]), np.array([200.0]), np.zeros((2, 1)))
    assert _project(limits, np.array([1.0]), np.array([5.0]), np.array([-200.0]), np.array([200.0])) == pytest.approx([5.0], abs=1e-12)


def test_the_input_bounds_come_last():
    """A bound the input box cannot reach: the box's side (never beyond the input bounds)."""
    limits = state_limits(_rl_rows(), ["i"], {"i": (-10.0, 10.0)}, np.zeros(0), np.array([-5.0]), np.array([5.0]), np.zeros((2, 1)))
    assert _project(limits, np.array([30.0]), np.array([5.0]), np.array([-5.0]), np.array([5.0])) == pytest.approx([-5.0])


def test_two_inputs_end_within_both_rows():
    """Two circuits, each asked 100 V: the alternating projections end at each one's closed-form largest voltage."""
    limits = state_limits(_rl_rows(2), ["a", "b"], {"a": (-10.0, 10.0), "b": (-4.0, 4.0)}, np.zeros(0), np.full(2, -200.0),
                          np.full(2, 200.0), np.zeros((2, 2)))
    decay = np.exp(-DT / TAU)
    expected = R_OHM * AIM * np.array([10.0, 4.0]) / (1 - decay)
    assert _project(limits, np.zeros(2), np.full(2, 100.0), np.full(2, -200.0), np.full(2, 200.0)) == pytest.approx(expected, rel=1e-5)


@pytest.mark.parametrize("bounds, match", [
    ({"i": (3.0, 1.0)}, r"'i': expected lb <= ub"),
    ({"i": ("a", 1.0)}, r"'i': expected \(lb, ub\) numbers"),
], ids=["crossed", "not_a_number"])
def test_bad_bounds_are_refused(bounds, match):
    with pytest.raises(InputError, match=match):
        state_limits(_rl_rows(), ["i"], bounds, np.zeros(0), np.array([-1.0]), np.array([1.0]), np.zeros((2, 1)))


def test_no_finite_bound_gives_none():
    assert state_limits(_rl_rows(), ["i"], {"i": (-np.inf, np.inf), "other": (0.0, 1.0)}, np.zeros(0), np.array([-1.0]),
                        np.array([1.0]), np.zeros((2, 1))) is None


def _peak_current(ode, x0, v):
    """The largest armature current over one period under ``v`` held, by SciPy's RK45 at 1e-10 (not the law's step)."""
    f = lambda _, z: np.asarray(ode.f(z, [v], ode.p_default)).ravel()  # noqa: E731
    sol = solve_ivp(f, (0.0, DT), x0, rtol=1e-10, atol=1e-12, dense_output=True)
    return float(np.max(sol.sol(np.linspace(0.0, DT, 401))[0]))


def test_the_tracking_law_holds_the_current_where_the_saturated_law_exceeds_it(motor):
    """The motor far behind its reference: the LQR asks the full 24 V; held at 5 A, its input keeps the current there."""
    ode, t, x, u = motor
    i = ode.x_names.index("ind.i")
    kwargs = dict(u_lb=[-24.0], u_ub=[24.0], Q=[1e-2, 1.0, 1e-4], method="rk4", substeps=4)
    free = tracking_controller(ode, t, x, u, **kwargs)
    held = tracking_controller(ode, t, x, u, state_bounds={"ind.i": (-5.0, 5.0), "not_a_state": (0.0, 1.0)}, **kwargs)
    state = free.x_ref[50] - np.array([0.0, 5.0, 0.0])
    v_free, v_held = float(free(50 * DT, state)[0]), float(held(50 * DT, state)[0])
    assert v_free == pytest.approx(24.0) and _peak_current(ode, state, v_free) > 5.5
    assert -24.0 <= v_held < v_free and _peak_current(ode, state, v_held) == pytest.approx(AIM * 5.0, rel=2e-3)
    assert held.state_limits.names == ["ind.i@1", "ind.i@2", "ind.i@3", "ind.i@4"] and i == 0


def test_the_measured_prediction_error_backs_the_bound_off(motor):
    """The last period's current came out 0.2 A above the model's prediction: the law holds it 0.2 A below its aim (SciPy)."""
    ode, t, x, u = motor
    held = tracking_controller(ode, t, x, u, u_lb=[-24.0], u_ub=[24.0], Q=[1e-2, 1.0, 1e-4], method="rk4", substeps=4,
                               state_bounds={"ind.i": (-5.0, 5.0)})
    before, acted = held.x_ref[49], np.array([3.0])
    state = np.asarray(held.predict(before, acted)).ravel() + np.array([0.2, 0.0, 0.0])  # the plant's current 0.2 A higher
    state[1] -= 5.0  # far behind the reference: the LQR asks the full 24 V
    kept = np.array([0.2, -5.0, 0.0])  # the envelope: as this period's error, so it stays (the angle's reaches no current row)
    memory = np.r_[before, acted, kept, 1.0]  # the last measured state, the input that acted since, the envelope, a step ran
    fresh = np.r_[before, acted, np.zeros(3), 0.0]  # no step ran yet: nothing measured
    v_backed, v_plain = float(held(50 * DT, state, acted, memory)[0]), float(held(50 * DT, state, acted, fresh)[0])
    assert held.n_memory == 3 + 1 + 3 + 1 and v_backed < v_plain
    assert _peak_current(ode, state, v_plain) == pytest.approx(AIM * 5.0, rel=2e-3)
    assert _peak_current(ode, state, v_backed) == pytest.approx(AIM * 5.0 - 0.2, rel=2e-3)


@pytest.mark.parametrize("excess, backed_off", [(0.2, 0.0), (0.5, 0.2)], ids=["within_the_noise_band", "beyond_it"])
def test_with_a_filter_the_back_off_takes_the_innovation_beyond_the_noise_band(motor, excess, backed_off):
    """The current 0.2 A above the prediction, within 3 standard deviations (0.1 A) of its sensor: noise, no back-off;
    0.5 A above: 0.2 A of it the model's error, held 0.2 A below the aim (SciPy, as above)."""
    ode, t, x, u = motor
    held = tracking_controller(ode, t, x, u, u_lb=[-24.0], u_ub=[24.0], Q=[1e-2, 1.0, 1e-4], method="rk4", substeps=4,
                               state_bounds={"ind.i": (-5.0, 5.0)})
    held = replace(held, state_filter=measurement_filter(held, [0.1, 1e-3, 1e-2]))
    before, acted = held.x_ref[49], np.array([3.0])
    state = np.asarray(held.predict(before, acted)).ravel() + np.array([excess, -5.0, 0.0])  # far behind, the current higher
    memory = np.r_[before, acted, np.zeros(3), 1.0]
    v = float(held.function(filtered=True)(50 * DT, state, acted, memory, state)[0])  # measured and filtered alike
    assert NOISE_BAND == 3.0
    assert _peak_current(ode, state, v) == pytest.approx(AIM * 5.0 - backed_off, rel=2e-3)


@pytest.mark.parametrize("kept, measured, expected", [
    ([0.0, 0.0], [0.4, -1.0], [0.4, -1.0]),                               # from zero: at once
    ([0.2, 0.0], [0.1, 3.0], [0.1, 3.0]),                                 # larger in the scaled norm: at once, the whole vector
    ([0.5, 0.0], [0.2, 0.0], [0.5 + BACKOFF_GAIN * (0.2 - 0.5), 0.0]),    # smaller: approached slowly
    ([0.5, 0.0], [-0.5, 0.0], [0.5 * (1 - 2 * BACKOFF_GAIN), 0.0]),       # as large, opposite (an input's swing): approached
], ids=["from_zero", "growing", "smaller", "opposite"])
def test_the_back_offs_error_is_the_envelope_of_the_measured_ones(kept, measured, expected):
    """Fast attack, slow release, written out by hand (scales 1 and 10: the second entry's 3.0 is 0.3 scaled)."""
    k, m = ca.MX.sym("k", 2), ca.MX.sym("m", 2)
    got = ca.Function("e", [k, m], [envelope(k, m, np.array([1.0, 10.0]))])(kept, measured)
    assert np.asarray(got).ravel() == pytest.approx(expected, abs=1e-15)
