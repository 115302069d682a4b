"""The MPC's constraint rows tightened by the prediction's error measured in the loop (``gtmodel.control.mpc_memory.row_backoff``).

References: the double integrator x'' = u under explicit Euler over 4 ms, whose one-period prediction is
``(x + dt v, v + dt u)`` by hand, so the rows' lower bounds are written out by hand from a measured error; and a
closed loop whose plant is pushed towards the bound by a force the model does not know (measured from the first
periods on): the soft-constrained MPC without the back-off passes its position bound, with it the bound holds.
"""

from __future__ import annotations

from dataclasses import replace

import casadi as ca
import numpy as np
import pytest

from gtmodel.control.bounds import TARGET_MARGIN
from gtmodel.control.mpc import mpc_controller
from gtmodel.control.mpc_memory import BACKOFF_CAP, backoff_error, backoff_rows, memory_estimates, row_backoff
from gtmodel.control.mpc_nlp import single_shooting_nlp
from gtmodel.control.problem import sqrt_psd
from gtmodel.control.state_limits import BACKOFF_GAIN
from gtmodel.errors import InputError
from gtmodel.modeling import explicit_ode

from ..modeling._builders import double_integrator

DT, H, BOUND = 0.004, 20, 0.5


@pytest.fixture(scope="module")
def integrator():
    ode = explicit_ode(double_integrator()[0])
    t = DT * np.arange(101)
    x_ref = np.column_stack([np.minimum(t / 0.2, 1.0), np.where(t < 0.2, 5.0, 0.0)])  # to 1 m: beyond the bound
    kw = dict(horizon=H, Q=[1.0, 0.0], R=[1e-4], u_lb=[-50.0], u_ub=[50.0], method="euler", x_ub={"x": BOUND})
    return ode, t, x_ref, {flag: mpc_controller(ode, t, x_ref, np.zeros((101, 1)), constraint_backoff=flag, **kw) for flag in (True, False)}


def _backoff(c, x, u_last, mem):
    """The rows' lower bounds with the horizon starting at the measured ``x`` (no delay) under the warm start."""
    xs, us, ms = ca.MX.sym("x", c.nx), ca.MX.sym("u", c.nu), ca.MX.sym("w", c.n_memory)
    rows, error = row_backoff(c, xs, xs, ms[:c.nw], us, ms)
    lbg, filtered = ca.Function("b", [xs, us, ms], [rows, error])(x, u_last, mem)
    return np.asarray(lbg).ravel(), np.asarray(filtered).ravel()


@pytest.mark.parametrize("error, ran", [
    ([0.01, 0.3], 1.0),    # position and speed under-predicted: every upper row tightened
    ([-0.05, 0.3], 1.0),   # the position over-predicted: the rows at the aim alone
    ([0.01, 0.3], 0.0),    # before a step ran: the envelope as it was
], ids=["under_predicted", "mixed", "first_step"])
def test_rows_are_tightened_by_the_recurring_error_by_hand(integrator, error, ran):
    """The errors' envelope ``f`` recurring over the horizon of explicit Euler, each period's share (1 - BACKOFF_GAIN)
    times the last's: the upper rows tightened by the position's shift where positive (never loosened), from the aim."""
    _, _, _, mpcs = integrator
    c = mpcs[True]
    x_prev, u_act, e = np.array([0.3, 2.0]), np.array([7.0]), np.asarray(error)
    predicted = np.array([x_prev[0] + DT * x_prev[1], x_prev[1] + DT * u_act[0]])  # explicit Euler, by hand
    kept = np.array([0.002, -0.1])  # the envelope so far
    mem = np.r_[c.w_initial, 0.0, x_prev, u_act, kept, ran]
    lbg, new = _backoff(c, predicted + e, u_act, mem)
    scale = c.plausible_ranges(c.u_lb, c.u_ub)[0]
    if ran:  # the envelope's step, by hand: a larger error (scaled norm) at once, else approached at BACKOFF_GAIN
        f = e if np.sum((e / scale) ** 2) > np.sum((kept / scale) ** 2) else kept + BACKOFF_GAIN * (e - kept)
    else:
        f = kept
    shift, dx, share = np.zeros(H), np.zeros(2), 1.0
    for j in range(H):  # explicit Euler, the error added after every period at a share falling by BACKOFF_GAIN, by hand
        dx = np.array([dx[0] + DT * dx[1], dx[1]]) + share * f
        shift[j], share = dx[0], share * (1 - BACKOFF_GAIN)
    assert c.constraint_rows == H and new == pytest.approx(f, rel=1e-12, abs=1e-15)
    margin = TARGET_MARGIN * BOUND  # the bound aimed at, 1 % inside the declared
    assert lbg == pytest.approx((np.maximum(shift, 0.0) + margin) / c.constraints.scale[0], rel=1e-9, abs=1e-15)


def test_rows_are_never_tightened_past_the_plans_room_or_the_cap(integrator):
    """A large recurring error would tighten the rows far beyond the plan's own distance to the bound (the rows then
    infeasible, the soft penalty steering): each row's lower bound is at most the larger of the reference's room there
    and BACKOFF_CAP of the bound (by hand: ``max(BOUND - x*_j, 0.2 BOUND) / scale``); without the reference the
    uncapped rows of the test above."""
    _, t, x_ref, mpcs = integrator
    c = mpcs[True]
    x_prev, u_act, e = np.array([0.0, 0.0]), np.array([0.0]), np.array([0.2, 5.0])  # 0.2 m a period: far beyond the room
    mem = np.r_[c.w_initial, 0.0, x_prev, u_act, np.zeros(2), 1.0]
    xr = [[ca.DM(v) for v in x_ref[j + 1]] for j in range(H)]  # the window at t = 0: rows k+1..k+H
    ur = [[ca.DM(0.0)] for _ in range(H)]
    xs, us, ms = ca.MX.sym("x", c.nx), ca.MX.sym("u", c.nu), ca.MX.sym("w", c.n_memory)
    capped, _ = row_backoff(c, xs, xs, ms[:c.nw], us, ms, xr, ur)
    free, _ = row_backoff(c, xs, xs, ms[:c.nw], us, ms)
    f = ca.Function("b", [xs, us, ms], [capped, free])
    lbg, uncapped = (np.asarray(v).ravel() for v in f(x_prev + e, u_act, mem))
    scale = c.constraints.scale[0]
    cap = np.maximum(BOUND - x_ref[1:H + 1, 0], BACKOFF_CAP * BOUND) / scale  # by hand: the plan's room, or 20 % of the bound
    assert np.count_nonzero(uncapped > cap) == H - 2  # the error alone would cut past both at all but the first two stages
    assert lbg == pytest.approx(np.minimum(uncapped, cap), rel=1e-12)


@pytest.mark.parametrize("slack", [0.0, 0.3], ids=["no_slack", "slack"])
def test_the_linearisations_rows_tighten_as_row_backoff(integrator, slack):
    """The sqpmethod step's back-off (backoff_rows) reads the nominal rows off the NLP's own rows at the warm start (less
    its slacks) instead of predicting them a second time: the same lower bounds as row_backoff's own prediction."""
    _, t, x_ref, mpcs = integrator
    c = mpcs[True]
    x_prev, u_act, e = np.array([0.1, 2.0]), np.array([7.0]), np.array([0.01, 0.3])
    w = np.linspace(-20.0, 30.0, c.nw)  # a warm start that moves the rows
    mem = np.r_[w, 0.0, x_prev, u_act, np.zeros(2), 1.0]
    x_start = x_prev + e
    xr = [[ca.DM(v) for v in x_ref[j + 1]] for j in range(H)]
    ur = [[ca.DM(0.0)] for _ in range(H)]
    xs, us, ms = ca.MX.sym("x", c.nx), ca.MX.sym("u", c.nu), ca.MX.sym("w", c.n_memory)
    expected, _ = row_backoff(c, xs, xs, ms[:c.nw], us, ms, xr, ur)
    error = backoff_error(c, xs, us, ms)
    nlp, _ = single_shooting_nlp(c, sqrt_psd)
    z = np.r_[w, np.full(c.n_slack, slack)]
    p = np.r_[x_start, x_ref[1:H + 1].ravel(), np.zeros(H)]
    g = ca.Function("g", [nlp["x"], nlp["p"]], [nlp["g"]])(z, p)
    rows, n_e = backoff_rows(c, False)
    got = rows(g[1:] - slack, ca.DM(z), ca.DM(p), error)
    f = ca.Function("b", [xs, us, ms], [expected, got])
    a, b = (np.asarray(v).ravel() for v in f(x_start, u_act, mem))
    assert n_e == c.nx and np.count_nonzero(a > a.min()) > 0 and b == pytest.approx(a, rel=1e-12, abs=1e-15)


def _peak(c, push):
    """The largest position of a closed loop whose plant is pushed towards the bound by ``push`` [m/s^2] the model does
    not know (explicit Euler by hand)."""
    f = c.function()
    w, u_last, x, peak = c.memory_initial, c.u_initial, c.x_ref[0].copy(), -np.inf
    for k in range(c.length - 1):
        u, w, ok = f(c.t0 + k * DT, x, u_last, w)
        assert float(ok) == 1.0
        u_last = np.asarray(u).ravel()
        x = np.array([x[0] + DT * x[1], x[1] + DT * (u_last[0] + push)])
        peak = max(peak, x[0])
    return peak


@pytest.mark.parametrize("solver, beyond", [("sqpmethod", 1.04), ("hpipm", 1.02)])
def test_the_back_off_holds_the_bound_on_a_plant_pushed_towards_it(integrator, solver, beyond):
    # the same tightening for both QP forms (single shooting with DAQP; multiple shooting with HPIPM's stage rows, whose
    # slack per stage penalises an excess at every stage: 0.514 without the back-off where the single shooting's 0.524)
    _, _, _, mpcs = integrator
    without, with_backoff = (_peak(replace(mpcs[flag], solver=solver), 10.0) for flag in (False, True))  # the plant pushed on at 10 m/s^2
    assert without > BOUND * beyond and with_backoff <= BOUND * 1.01


@pytest.mark.parametrize("kwargs", [{}, {"x_ub": {"x": BOUND}, "solver": "fatrop"}], ids=["no rows", "fatrop"])
def test_the_back_off_needs_rows_of_sqpmethod_or_hpipm(integrator, kwargs):
    ode, t, x_ref, _ = integrator
    with pytest.raises(InputError, match="constraint_backoff: tightens the constraint rows of solver sqpmethod or hpipm"):
        mpc_controller(ode, t, x_ref, np.zeros((101, 1)), horizon=H, constraint_backoff=True, **kwargs)


def test_memory_estimates_read_the_estimator_by_hand(integrator):
    # the memory after three periods written by hand (layout of memory_layout: w, d, x, u, error, ran): the figures are
    # the entries of largest magnitude, their times, the last values, over the input's range and the states' scales
    ode, t, x_ref, mpcs = integrator
    c = replace(mpcs[True], disturbance_gain=0.3)
    d, err = np.array([0.5, -2.0, 1.0]), np.array([[0.001, 0.0], [-0.004, 0.2], [0.002, -0.3]])
    rows = np.array([np.r_[c.w_initial, d[k], 0.1, 0.2, 3.0, err[k], 1.0] for k in range(3)])
    got = {(e["kind"], e["name"]): e for e in memory_estimates(c, t[:3], rows)}
    scale = c.plausible_ranges(c.u_lb, c.u_ub)[0]
    assert got["input disturbance", "u"] == {"kind": "input disturbance", "name": "u", "largest": -2.0, "time": t[1], "last": 1.0,
                                              "relative": 2.0 / 100.0}  # the bounds' span, 100 m/s^2
    assert got["prediction error envelope", "v"]["largest"] == -0.3 and got["prediction error envelope", "v"]["time"] == t[2]
    assert got["prediction error envelope", "x"]["relative"] == pytest.approx(0.004 / scale[0])


@pytest.mark.parametrize("rows, match", [(np.zeros((2, 5)), r"memories: expected \(3, ")], ids=["short"])
def test_memory_estimates_refuse_a_memory_of_another_shape(integrator, rows, match):
    *_, mpcs = integrator
    with pytest.raises(ValueError, match=match):
        memory_estimates(mpcs[True], np.zeros(3), rows)


def test_no_estimator_no_estimates(integrator):
    *_, mpcs = integrator
    assert memory_estimates(mpcs[False], np.zeros(3), np.zeros((3, mpcs[False].n_memory))) == []


def test_without_a_gain_only_the_envelope_is_reported(integrator):
    *_, mpcs = integrator
    c = mpcs[True]  # the back-off's memory, no disturbance gain: its d stays 0 and is not reported
    kinds = {e["kind"] for e in memory_estimates(c, np.zeros(2), np.zeros((2, c.n_memory)))}
    assert kinds == {"prediction error envelope"}
