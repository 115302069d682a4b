"""The MPC's constraint rows between the samples (gtmodel.control.mpc_nlp, ``constraint_substeps``).

The DC motor of ``models/dc_motor.py`` (L/R = 1.7 ms) asked to reach 400 rad/s in 20 ms from
rest under |v| <= 24 V, its current bounded to 10 A (hard rows), predicted by RK4 with four
1 ms substeps per 4 ms period. Reference: the horizon's inputs simulated again by SciPy's
``solve_ivp`` (RK45 at rtol 1e-10, a second integrator) on a fine grid inside every period.
With rows at the samples only the current passes the bound between them; with the rows at
the substeps it holds there, and within 1 % between those. The multiple shooting (fatrop)
solves the same NLP. The step's real-time iteration (``single_shooting_rti``): CasADi's ``sqpmethod``
with one iteration (a second implementation of the same step) and IPOPT to convergence (the
iterations repeated reach it).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from gtmodel.errors import InputError
from gtmodel.control.mpc import _sqrt_psd, mpc_controller
from gtmodel.control import mpc_nlp
from gtmodel.control.mpc_nlp import _single_shooting, single_shooting_rti
from gtmodel.modeling import explicit_ode
from gtmodel.problems.user_model import load_user_model

from ..conftest import REPO

DT, H, BOUND, SUBSTEPS, FINE = 0.004, 10, 10.0, 4, 400


@pytest.fixture(scope="module")
def motor():
    ode = explicit_ode(load_user_model(REPO / "models" / "dc_motor.py", "DCMotorModel"))
    t = DT * np.arange(101)
    x_ref = np.zeros((101, 3))
    x_ref[:, 2] = np.minimum(t / 0.02, 1.0) * 400.0
    x_ref[:, 1] = np.cumsum(x_ref[:, 2]) * DT
    kw = dict(horizon=H, Q=[0.0, 0.0, 1.0], R=[1e-6], u_lb=[-24.0], u_ub=[24.0], method="rk4", substeps=SUBSTEPS,
              x_lb={"ind.i": -BOUND}, x_ub={"ind.i": BOUND}, hard_constraints=True)
    return ode, {between: mpc_controller(ode, t, x_ref, np.zeros((101, 1)), constraint_substeps=between, **kw)
                 for between in (False, True)}


def _currents(ode, w):
    """The current on a grid of FINE + 1 points per period under the inputs ``w`` held, from rest (solve_ivp)."""
    x, out = np.zeros(3), []
    for u in w:
        r = solve_ivp(lambda _t, xx: np.asarray(ode.f(xx, [u], ode.p_default)).ravel(), (0.0, DT), x, rtol=1e-10, atol=1e-12,
                      dense_output=True)
        out.append(r.sol(np.linspace(0.0, DT, FINE + 1))[0])
        x = r.y[:, -1]
    return np.array(out)  # (H, FINE + 1)


def test_rows_counted_per_substep(motor):
    _, c = motor
    assert c[False].constraint_rows == 2 * H
    assert c[True].constraint_rows == 2 * H * SUBSTEPS
    assert c[False].substep_states is None


def test_samples_only_lets_the_current_pass_between(motor):
    ode, c = motor
    i = _currents(ode, c[False].solve(0.0, np.zeros(3))[1])
    assert np.max(np.abs(i[:, -1])) <= BOUND * (1 + 2e-3)  # held at the samples
    assert np.max(np.abs(i)) > 1.03 * BOUND  # 10.55 A between them


def test_substep_rows_hold_the_bound_between_the_samples(motor):
    ode, c = motor
    i = _currents(ode, c[True].solve(0.0, np.zeros(3))[1])
    at_substeps = i[:, FINE // SUBSTEPS::FINE // SUBSTEPS]
    assert np.max(np.abs(at_substeps)) <= BOUND * (1 + 2e-3)  # RK4's error against RK45 at 1e-10
    assert np.max(np.abs(i)) <= BOUND * 1.01  # 10.04 A between the substeps


def test_fatrop_solves_the_same_nlp(motor):
    _, c = motor
    ref = c[True].solve(0.0, np.zeros(3))[1]
    w = replace(c[True], solver="fatrop").solve(0.0, np.zeros(3), plugin="fatrop")[1]
    np.testing.assert_allclose(w, ref, atol=1e-6 * 24.0)


@pytest.mark.parametrize("value", ["yes", 1, None])
def test_flag_refused(motor, value):
    ode, c = motor
    with pytest.raises(InputError, match="constraint_substeps: expected true or false"):
        mpc_controller(ode, DT * np.arange(3), np.zeros((3, 3)), np.zeros((3, 1)), x_ub={"ind.i": BOUND}, constraint_substeps=value)


@pytest.mark.parametrize("method", ["euler", "rk4", "radau2"])
def test_soft_rows_inside_the_periods_agree_across_solvers(motor, method):
    # soft rows (slacks, fatrop's stage-0 slack of the states inside period 0): IPOPT's optimum (the exact penalty's hard
    # form), the converged SQP and fatrop's multiple shooting, each prediction step; measured 1e-12 (SQP), 1.4e-8 (fatrop)
    ode, _ = motor
    t = DT * np.arange(101)
    x_ref = np.zeros((101, 3))
    x_ref[:, 2] = np.minimum(t / 0.02, 1.0) * 400.0
    x_ref[:, 1] = np.cumsum(x_ref[:, 2]) * DT
    c = mpc_controller(ode, t, x_ref, np.zeros((101, 1)), horizon=H, Q=[0.0, 0.0, 1.0], R=[1e-6], u_lb=[-24.0], u_ub=[24.0],
                       method=method, substeps=SUBSTEPS, x_lb={"ind.i": -BOUND}, x_ub={"ind.i": BOUND})
    assert c.constraint_rows == 2 * H * SUBSTEPS and c.n_slack == 2
    ref = c.solve(0.0, np.zeros(3))[1]
    np.testing.assert_allclose(c.solve(0.0, np.zeros(3), plugin="sqpmethod", iterations=30)[1], ref, atol=1e-9 * 24.0)
    np.testing.assert_allclose(replace(c, solver="fatrop").solve(0.0, np.zeros(3), plugin="fatrop")[1], ref, atol=1e-6 * 24.0)


def _soft_or_hard(motor, hard):
    ode, c = motor
    return c[True] if hard else replace(c[True], constraints=replace(c[True].constraints, hard=False))


def _rti_first_input(c, k, x, iterations):
    b = c.bounds()
    rti = single_shooting_rti(c, _sqrt_psd, c._qp_options("double"), iterations)
    z, _ = rti(np.r_[c.w_initial, np.zeros(c.n_slack)], c.parameters(c.t0 + k * DT, x), b["lbx"], b["ubx"], b["lbg"], b["ubg"])
    return np.asarray(z).ravel()[: c.nu]


@pytest.mark.parametrize("hard", [True, False], ids=["hard rows", "soft rows"])
def test_real_time_iteration_is_sqpmethods_first_iteration(motor, hard):
    # a second implementation: CasADi's sqpmethod, one iteration with the same Gauss-Newton Hessian and QP solver, whose
    # line search takes the full step here; the same first input
    c = _soft_or_hard(motor, hard)
    k, x = 3, c.x_ref[3] + np.array([0.5, 0.0, 5.0])
    sol = c.nlp_solver("sqpmethod", 1)(x0=np.r_[c.w_initial, np.zeros(c.n_slack)], p=c.parameters(c.t0 + k * DT, x), **c.bounds())
    np.testing.assert_allclose(_rti_first_input(c, k, x, 1), np.asarray(sol["x"]).ravel()[: c.nu], rtol=0, atol=1e-9 * 24.0)


@pytest.mark.parametrize("hard", [True, False], ids=["hard rows", "soft rows"])
def test_real_time_iterations_converge_to_ipopt(motor, hard):
    # IPOPT to convergence on the same NLP (a second method): the iterations repeated reach its first input
    c = _soft_or_hard(motor, hard)
    k, x = 3, c.x_ref[3] + np.array([0.5, 0.0, 5.0])
    u_ip, _ = c.solve(c.t0 + k * DT, x, plugin="ipopt")
    np.testing.assert_allclose(_rti_first_input(c, k, x, 30), u_ip, rtol=0, atol=1e-6 * 24.0)


@pytest.fixture(scope="module")
def sine_drive():
    """x' = 50 sin(u): far enough up the sine the Gauss-Newton step overshoots and sqpmethod's line search backs off."""
    import casadi as ca

    from gtmodel.modeling import Model

    m = Model("sine_drive")
    x, u = m.state("x"), m.input("u")
    m.equation(m.der(x), 50 * ca.sin(u))
    t = DT * np.arange(101)
    return mpc_controller(explicit_ode(m), t, np.minimum(t / 0.1, 1.0)[:, None] * 5.0, np.zeros((101, 1)), horizon=10, Q=[1.0],
                          R=[1e-4], u_lb=[-3.0], u_ub=[3.0], method="rk4")


@pytest.mark.parametrize("w0, trials", [(1.40, 1), (1.482, 2), (1.55, 3)], ids=["full step", "second trial", "last trial"])
def test_the_line_search_is_sqpmethods(sine_drive, w0, trials):
    # a second implementation: CasADi's sqpmethod (one iteration, its default line search); its count of predictions
    # (n_call_nlp_fg) shows which trial step it took; the written-out iteration lands on the same point
    c, b = sine_drive, sine_drive.bounds()
    solver = c.nlp_solver("sqpmethod", 1)
    p = c.parameters(0.0, [0.0])
    sol = solver(x0=np.full(c.nw, w0), p=p, **b)
    z, _ = single_shooting_rti(c, _sqrt_psd, c._qp_options("double"), 1)(np.full(c.nw, w0), p, b["lbx"], b["ubx"], b["lbg"], b["ubg"])
    assert solver.stats()["n_call_nlp_fg"] == trials
    np.testing.assert_allclose(np.asarray(z).ravel(), np.asarray(sol["x"]).ravel(), rtol=0, atol=1e-12)


@pytest.mark.parametrize("between, hard, blocks, rate, unrolled", [(True, True, H, None, True), (True, False, H, None, True),
                                                                   (False, False, 5, None, True), (True, False, 5, [1e-3], True),
                                                                   (True, False, H, [1e-3], False)],
                         ids=["substep rows hard", "substep rows soft", "sample rows blocked", "blocked with rate", "one product"])
def test_chain_rule_sensitivities_are_casadis_jacobian(motor, monkeypatch, between, hard, blocks, rate, unrolled):
    # a second method: CasADi's jacobian() of the whole prediction (one forward sweep through the chained steps); the
    # step's Jacobians by the chain rule of the stages' own, the same values; the Gauss-Newton J_r' J_r and J_r' r the
    # stages accumulate (or, "one product", J_r' J_r of the states' share in one MX product: UNROLLED_HESSIAN_MAX),
    # those of jacobian()'s J_r
    import casadi as ca

    if not unrolled:
        monkeypatch.setattr(mpc_nlp, "UNROLLED_HESSIAN_MAX", 0)

    c = _soft_or_hard(motor, hard) if between else replace(motor[1][False], constraints=replace(motor[1][False].constraints, hard=False))
    c = replace(c, blocks=blocks, R_rate=None if rate is None else np.diag(rate))
    w, p, r, g, _, _, sens = _single_shooting(c, _sqrt_psd, sensitivities=True)
    mine = ca.Function("mine", [w, p], [sens["J_r"], sens["J_g"], sens["JtJ"], sens["Jtr"]])
    jr = ca.jacobian(r, w)
    theirs = ca.Function("theirs", [w, p], [jr, ca.jacobian(g, w), ca.mtimes(jr.T, jr), ca.mtimes(jr.T, r)])
    rng = np.random.default_rng(1)
    wv = np.r_[rng.uniform(-24.0, 24.0, c.nw), rng.uniform(0.0, 1.0, c.n_slack)]
    pv = c.parameters(c.t0 + 3 * DT, c.x_ref[3] + np.array([0.5, 0.0, 5.0]))
    got, want = mine(wv, pv), theirs(wv, pv)
    scale = [max(1.0, float(np.max(np.abs(t.full())))) for t in want]
    np.testing.assert_allclose([float(np.max(np.abs(m.full() - t.full()))) / s for m, t, s in zip(got, want, scale)], 0.0, atol=1e-13)
