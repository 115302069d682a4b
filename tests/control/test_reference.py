"""The reference of a loop controller (gtmodel.control.reference): the input that holds the end (and the start).

References: the L1's holding forces at rest, J^T G of the numeric inverse dynamics
(``GantryTau3Dynamics.gravity_forces``, Dressler (2012), Table 6.2; a second implementation
of eq. 6.7), against the least-squares equilibrium input of the symbolic model's explicit
ODE; a mass on a spring, whose holding force is c s in closed form.
"""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest
import scipy.integrate

from gtmodel.control.reference import FLOAT_PERIOD_LIMIT, PERIOD_EPS, delayed_start, hold_input, period_index, period_means, sample_reference, start_input
from gtmodel.errors import InputError
from gtmodel.modeling import explicit_ode
from gtmodel.robots.dynamics import GantryTau3Dynamics
from gtmodel.robots.model import gantry_tau_model


@pytest.mark.parametrize("T", [[-0.2, 2.75, -0.4], [0.3, 2.4, -0.6]])
def test_the_l1_held_at_rest_needs_its_gravity_forces(T):
    ode = explicit_ode(gantry_tau_model("L1"))
    u = hold_input(ode.f, np.r_[T, 0.0, 0.0, 0.0], np.zeros(3), ode.p_default)
    np.testing.assert_allclose(u, GantryTau3Dynamics("L1").gravity_forces(T), rtol=1e-8, atol=1e-8)


def test_a_mass_on_a_spring_is_held_by_c_s():
    # x = (s, v), xdot = (v, (u - c s) / m): held at s = 0.3 by u = c s, whatever the start guess
    x, u, p = ca.SX.sym("x", 2), ca.SX.sym("u"), ca.SX.sym("p", 2)  # p = (m, c)
    f = ca.Function("f", [x, u, p], [ca.vertcat(x[1], (u - p[1] * x[0]) / p[0])])
    assert hold_input(f, [0.3, 0.0], [-50.0], [2.0, 40.0]) == pytest.approx([12.0], rel=1e-12)


@pytest.mark.parametrize("x0, u0, expected", [
    ([0.3, 0.0], [-50.0], [12.0]),   # at rest on the spring: the holding force c s (closed form), not the plan's first input
    ([0.3, 1.0], [-50.0], [-50.0]),  # already moving (no input holds it): the plan's first input kept
])
def test_the_input_before_the_loop_holds_a_start_at_rest(x0, u0, expected):
    x, u, p = ca.SX.sym("x", 2), ca.SX.sym("u"), ca.SX.sym("p", 2)  # p = (m, c)
    f = ca.Function("f", [x, u, p], [ca.vertcat(x[1], (u - p[1] * x[0]) / p[0])])
    assert start_input(f, x0, u0, [2.0, 40.0]) == pytest.approx(expected, rel=1e-12)


def _spring():
    x, u, p = ca.SX.sym("x", 2), ca.SX.sym("u"), ca.SX.sym("p", 2)  # p = (m, c)
    return ca.Function("f", [x, u, p], [ca.vertcat(x[1], (u - p[1] * x[0]) / p[0])])


def test_a_delay_leads_a_start_at_rest_by_its_periods_held_by_c_s():
    # reference: the mass on a spring at rest at s = 0.3 (held by c s = 12, closed form) with a plan starting at -50:
    # one period of delay puts one period at rest before the plan, its mean input the holding force (period_means)
    t, x, u = np.array([0.0, 0.01, 0.02]), np.array([[0.3, 0.0], [0.29, -1.0], [0.27, -2.0]]), np.array([[-50.0], [-40.0], [-30.0]])
    tt, xx, uu, lead = delayed_start(_spring(), t, x, u, [2.0, 40.0], 0.004, 1)
    assert lead == 1 and tt[0] == pytest.approx(-0.004) and tt[1] < 0.0 and np.array_equal(tt[2:], t)
    np.testing.assert_allclose(xx[:2], [[0.3, 0.0], [0.3, 0.0]], rtol=1e-12)
    np.testing.assert_allclose(uu[:2, 0], [12.0, 12.0], rtol=1e-12)
    t0, xs, us = sample_reference(tt, xx, uu, 0.004)
    assert t0 == pytest.approx(-0.004) and us[0, 0] == pytest.approx(12.0, rel=1e-6)
    np.testing.assert_allclose(xs[1], [0.3, 0.0], atol=1e-9)  # the plan's first state at the plan's first time


@pytest.mark.parametrize("x0, u0, delay", [
    ([0.3, 1.0], -50.0, 1),  # a motion under way: no input holds it, the plan's first input acts
    ([0.3, 0.0], 12.0, 1),   # the plan starts with the holding force: nothing to lead
    ([0.3, 0.0], -50.0, 0),  # no delay
])
def test_no_lead_without_a_start_that_another_input_holds_or_without_delay(x0, u0, delay):
    t, x, u = np.array([0.0, 0.01]), np.array([x0, [0.29, 0.5]]), np.array([[u0], [0.0]])
    tt, xx, uu, lead = delayed_start(_spring(), t, x, u, [2.0, 40.0], 0.004, delay)
    assert lead == 0 and np.array_equal(tt, t) and np.array_equal(xx, x) and np.array_equal(uu, u)


@pytest.mark.parametrize("delay", [-1, 1.5, True, "1"])
def test_a_delay_that_is_not_a_count_of_periods_is_refused(delay):
    with pytest.raises(InputError, match=r"delay: expected a number of periods >= 0"):
        delayed_start(_spring(), [0.0, 0.01], [[0.3, 0.0], [0.3, 0.0]], [[1.0], [1.0]], [2.0, 40.0], 0.004, delay)


@pytest.mark.parametrize("dt", [0.004, 0.001, 0.0125])
def test_float32_grid_times_read_their_own_period(dt):
    """Every grid time t = k dt, rounded to float32 and divided in float32 as the float C does,
    reads row k under the period slack, up to the float limit (independent check: integer k)."""
    k = np.arange(0, FLOAT_PERIOD_LIMIT + 1)
    t, step = (k * dt).astype(np.float32), np.float32(dt)
    rows = np.floor(t / step + np.float32(PERIOD_EPS)).astype(np.int64)
    np.testing.assert_array_equal(rows, k)


@pytest.mark.parametrize("k", [0, 1, 7, 250, 1999])
def test_period_index_reads_the_row_of_a_grid_time_and_of_a_time_just_before(k):
    dt = 0.004
    assert period_index(k * dt, 0.0, dt, 10_000) == k
    assert period_index(k * dt - 0.5 * PERIOD_EPS * dt, 0.0, dt, 10_000) == k  # within the slack: jitter
    assert period_index(k * dt - 2 * PERIOD_EPS * dt, 0.0, dt, 10_000) == max(k - 1, 0)


# period_means: what a zero-order hold applies, against closed forms and SciPy's quadrature of the same interpolant
@pytest.mark.parametrize(("t", "u", "grid", "dt", "expected"), [
    ([0.0, 1.0], [0.0, 1.0], [0.0, 0.5], 0.5, [0.25, 0.75]),            # a ramp: its value at each period's middle
    ([0.0, 0.3, 0.3 + 1e-12, 1.0], [40.0, 40.0, -40.0, -40.0], [0.0], 0.5, [40.0 * 0.3 / 0.5 - 40.0 * 0.2 / 0.5]),  # a switch inside: duty-weighted
    ([0.0, 1.0], [2.0, 4.0], [0.8], 0.4, [(0.2 * 3.8 + 0.2 * 4.0) / 0.4]),  # past the last time: the last value held
])
def test_period_means_are_what_a_zero_order_hold_applies(t, u, grid, dt, expected):
    got = period_means(np.asarray(t), np.asarray(u, dtype=float)[:, None], np.asarray(grid), dt)
    np.testing.assert_allclose(got[:, 0], expected, rtol=1e-9)


def test_period_means_of_a_bang_bang_plan_match_scipy_quad():
    rng = np.random.default_rng(0)
    t = np.sort(np.r_[0.0, rng.uniform(0.0, 0.1, 60), 0.1])
    u = np.sign(np.sin(200.0 * t)) * 40.0 + rng.normal(0.0, 1.0, t.size)
    grid = 0.004 * np.arange(26)
    quad = [scipy.integrate.quad(lambda s: np.interp(s, t, u), g, g + 0.004, points=t[(t > g) & (t < g + 0.004)], limit=200)[0] / 0.004
            for g in grid]
    np.testing.assert_allclose(period_means(t, u[:, None], grid, 0.004)[:, 0], quad, rtol=1e-7, atol=1e-9)


def test_sample_reference_holds_each_period_the_plans_mean_input():
    # a minimum-time plan's voltage switching inside a 4 ms period (the ball-screw drive's last 2 ms) held at its value at
    # the period's start drove the plant's current to 40 A of 10: the loop holds the period's mean
    t = np.array([0.0, 0.001, 0.001 + 1e-9, 0.008])
    t0, xs, us = sample_reference(t, np.zeros((4, 1)), np.array([[40.0], [40.0], [-40.0], [-40.0]]), 0.004)
    np.testing.assert_allclose(us[:, 0], [(40.0 * 0.001 - 40.0 * 0.003) / 0.004, -40.0, -40.0], rtol=1e-6)


@pytest.mark.parametrize(("values", "match"), [(np.array([[1.0], [np.nan]]), "u_ref: expected a finite"),
                                              (np.ones((3, 1)), r"u_ref: expected a finite \(2, n\) array")])
def test_period_means_refuses_bad_values(values, match):
    with pytest.raises(InputError, match=match):
        period_means(np.array([0.0, 1.0]), values, np.array([0.0]), 0.5)
