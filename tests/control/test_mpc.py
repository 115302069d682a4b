"""Real-time nonlinear MPC (gtmodel.control.mpc) of the composed DC motor, evaluated from Python.

References: the same horizon problem solved to convergence by IPOPT (the SQP iterated at a
fixed state must reach IPOPT's first input); the feedforward alone on the same mismatched
plant (the MPC must halve its tracking error); the input bounds (never exceeded).
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from gtmodel.errors import InputError
from gtmodel.estimation.closed_loop.controller_loop import run_controller_loop
from gtmodel.control.mpc import mpc_controller
from gtmodel.control.reference import period_means
from gtmodel.modeling import explicit_ode
from gtmodel.problems.user_model import load_user_model

from ..conftest import REPO
from ..modeling._builders import double_integrator

DT = 0.004
#: The SQP iterated to convergence against IPOPT: first input, relative to 1 + |u_IPOPT|.
IPOPT_AGREEMENT = 1e-6


def _motor_motion(wave):
    """The DC motor along ``6 wave(2 pi t / 0.6)`` volts over 0.6 s, simulated by its own RK4: ``(ode, t, x, u)``."""
    ode = explicit_ode(load_user_model(REPO / "models" / "dc_motor.py", "DCMotorModel"))
    t = DT * np.arange(151)
    u = (6.0 * wave(2 * np.pi * t / 0.6))[:, None]
    x, _ = ode.simulate_steps(ode.step(DT, "rk4", substeps=4), u[:-1])
    return ode, t, x, u


@pytest.fixture(scope="module")
def motor():
    ode, t, x, u = _motor_motion(np.sin)
    c = mpc_controller(ode, t, x, u, horizon=20, Q=[1e-2, 100.0, 1e-2], R=[1e-3], u_lb=[-12.0], u_ub=[12.0], method="rk4", substeps=2)
    return ode, t, x, u, c


BAD = [
    ({"horizon": 0}, "horizon: expected a positive integer"),
    ({"horizon": 20, "blocks": 3}, "blocks: expected a divisor of the horizon 20"),
    ({"sqp_iterations": 0}, "sqp_iterations: expected a positive integer"),
    ({"dt": 0.0}, "dt: expected a positive loop period"),
    ({"method": "euler2"}, "method: expected one of"),
    ({"solver": "osqp"}, "solver: expected one of sqpmethod, fatrop, hpipm"),
    ({"solver": "fatrop", "horizon": 20, "blocks": 5}, "blocks: expected the horizon 20 with solver fatrop"),
    ({"R": [0.0]}, "R: expected a positive definite"),
]


@pytest.mark.parametrize("kwargs, match", BAD, ids=[str(b[0]) for b in BAD])
def test_bad_arguments_are_refused(motor, kwargs, match):
    ode, t, x, u, _ = motor
    with pytest.raises(InputError, match=match):
        mpc_controller(ode, t, x, u, **kwargs)


@pytest.mark.parametrize("k", [10, 60, 110])
def test_converged_sqp_agrees_with_ipopt(motor, k):
    # a perturbed state along the motion: 20 Gauss-Newton SQP iterations against IPOPT to 1e-10
    *_, c = motor
    xk = c.x_ref[k] + np.array([0.5, 0.02, 1.0])
    u_ip, _ = c.solve(c.t0 + k * DT, xk, plugin="ipopt")
    u_sqp, _ = c.solve(c.t0 + k * DT, xk, plugin="sqpmethod", iterations=20)
    assert np.max(np.abs(u_sqp - u_ip)) / (1 + np.max(np.abs(u_ip))) <= IPOPT_AGREEMENT


@pytest.mark.parametrize("plugin, iterations, status, message", [
    ("ipopt", None, "optimal", "Solve_Succeeded"),
    ("sqpmethod", 30, "completed", "30 SQP iterations, the count asked for (Maximum_Iterations_Exceeded)"),  # exactly 30
    ("sqpmethod", 1, "completed", "1 SQP iterations, the count asked for (Maximum_Iterations_Exceeded)"),
])
def test_solve_carries_the_solvers_verdict_and_unpacks_as_u_w(motor, plugin, iterations, status, message):
    """Independent: CasADi's own stats (return_status) of the solver, read through the result."""
    *_, c = motor
    sol = c.solve(c.t0 + 60 * DT, c.x_ref[60] + np.array([0.5, 0.02, 1.0]), plugin=plugin, iterations=iterations)
    u, w = sol
    assert (sol.status, sol.message, sol.plugin, sol.success) == (status, message, plugin, True)
    assert u is sol.u and w is sol[1] and len(sol) == 2 and u.shape == (c.nu,) and w.shape == (c.nw,) and np.all(np.isfinite(w))


def test_step_function_is_the_rti_with_a_shifted_warm_start(motor):
    # the loop-step Function's u equals one SQP iteration of the same NLP from the same warm start
    *_, c = motor
    f = c.function()
    xk, tk = c.x_ref[40] + np.array([0.1, 0.01, 0.5]), c.t0 + 40 * DT
    u, w_next, ok = f(tk, xk, c.u_initial, c.w_initial)
    u_one, w_one = c.solve(tk, xk, w0=c.w_initial, plugin="sqpmethod", iterations=1)
    assert float(ok) == 1.0
    np.testing.assert_allclose(np.asarray(u).ravel(), np.clip(u_one, -12, 12), rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(np.asarray(w_next).ravel(), np.r_[np.clip(w_one, -12, 12)[1:], np.clip(w_one, -12, 12)[-1]], atol=1e-12)


def test_closed_loop_halves_the_feedforward_error_within_bounds(motor):
    ode, t, x, u, c = motor
    plant = ode.step(DT, "rk4", substeps=4)
    f = c.function()
    mem = {"w": c.w_initial}

    def controller(tk, y):
        uk, w_next, ok = f(tk, y, c.u_initial, mem["w"])
        mem["w"] = np.asarray(w_next).ravel()
        return (0 if float(ok) else 6), np.asarray(uk).ravel()

    kw = dict(u_lb=c.u_lb, u_ub=c.u_ub, plant_p=ode.p_default * 1.1, noise_std=[1e-3, 1e-3, 1e-2], disturbance=[-1.0],
              disturbance_time=0.3, delay=1, error_states=[1])
    mpc = run_controller_loop(controller, plant, x[0], c.t0 + DT * np.arange(c.length), c.x_ref, **kw)
    ff = run_controller_loop(lambda tk, y: (0, np.clip(c.u_ref[int(round(tk / DT))], -12, 12)), plant, x[0],
                             c.t0 + DT * np.arange(c.length), c.x_ref, **kw)
    assert mpc.rms_error <= 0.5 * ff.rms_error
    assert mpc.bound_violations == 0
    assert mpc.status_counts == {"0": c.length}


def test_delay_compensation_is_the_step_from_the_predicted_state(motor):
    # by construction (the tracking controller's rule): with delay 1 the step at (t, x, u_last) is the
    # undelayed step at (t + dt, F(x, u_last)), F the prediction over one period
    *_, c = motor
    late = dataclasses.replace(c, delay=1)
    x0, u_last = c.x_ref[40] + np.array([0.3, 0.01, 0.5]), np.array([4.0])
    got = late.function()(c.t0 + 40 * DT, x0, u_last, c.w_initial)
    want = c.function()(c.t0 + 41 * DT, c.step(x0, u_last), u_last, c.w_initial)
    np.testing.assert_allclose(np.asarray(got[0]), np.asarray(want[0]), rtol=1e-12, atol=1e-12)


@pytest.mark.parametrize("delay, chatter", [(0, True), (1, False)], ids=["uncompensated", "compensated"])
def test_delay_compensation_stops_the_input_chattering(motor, delay, chatter):
    # the loop's one-period input delay: an MPC blind to it ends the motion in a limit cycle between its
    # bounds (measured 15 V per period on the shipped motor file), the compensated one holds smoothly
    ode, t, x, u, c = motor
    c = dataclasses.replace(c, delay=delay)
    f = c.function()
    mem = {"w": c.w_initial, "u": c.u_initial}

    def controller(tk, y):
        uk, w_next, ok = f(tk, y, mem["u"], mem["w"])
        mem["w"], mem["u"] = np.asarray(w_next).ravel(), np.asarray(uk).ravel()
        return (0 if float(ok) else 6), mem["u"]

    kw = dict(u_lb=c.u_lb, u_ub=c.u_ub, plant_p=ode.p_default * 1.1, noise_std=[1e-3, 1e-3, 1e-2], delay=1, error_states=[1])
    run = run_controller_loop(controller, ode.step(DT, "rk4", substeps=4), x[0], c.t0 + DT * np.arange(c.length), c.x_ref, **kw)
    change = np.mean(np.abs(np.diff(run.u[run.t > 0.4], axis=0)))  # V per period over the last third
    assert bool(change > 1.0) == chatter  # measured 4.9 and 0.19 V per period


@pytest.mark.parametrize("blocks", [20, 5])
@pytest.mark.parametrize("x0, at_bound", [([0.0, 0.0], False), ([-0.5, -12.0], True)], ids=["inside", "at-bound"])
def test_one_real_time_iteration_is_the_full_gauss_newton_step(blocks, x0, at_bound):
    # issue 46: on a linear model with a quadratic cost the Gauss-Newton QP IS the horizon problem, so one
    # SQP iteration from any warm start must land on IPOPT's optimum: the step is taken whole (no line
    # search cut, no regularisation) and qrqp solves the QP to its optimum, with and without active bounds
    # (a second method: IPOPT to 1e-10). acados' SQP-RTI from the same rollout gives the same first input
    # on the L1 (1e-8, benchmarks/bench_mpc.py), so the RTI itself does not make gtmodel track worse.
    ode = explicit_ode(double_integrator()[0])
    t = DT * np.arange(101)
    x_ref = np.column_stack([np.minimum(t / 0.2, 1.0), np.where(t < 0.2, 5.0, 0.0)])
    c = mpc_controller(ode, t, x_ref, np.zeros((101, 1)), horizon=20, blocks=blocks, Q=[1.0, 1e-3], R=[1e-4],
                       u_lb=[-50.0], u_ub=[50.0], method="euler")
    w0 = np.full(c.nw, 37.0)  # far from the optimum
    u_one, w_one = c.solve(0.02, x0, w0=w0, plugin="sqpmethod", iterations=1)
    u_ip, w_ip = c.solve(0.02, x0, plugin="ipopt")
    assert np.any(np.isclose(np.abs(w_ip), 50.0, atol=1e-6)) == at_bound
    assert np.max(np.abs(w_one - w_ip)) <= IPOPT_AGREEMENT * (1 + np.max(np.abs(w_ip)))


def _linear_mpc(blocks: int = 4):
    """An MPC of the double integrator (Euler step): its horizon cost is quadratic in the inputs."""
    ode = explicit_ode(double_integrator()[0])
    t = DT * np.arange(101)
    x_ref = np.column_stack([np.minimum(t / 0.2, 1.0), np.where(t < 0.2, 5.0, 0.0)])
    return mpc_controller(ode, t, x_ref, np.zeros((101, 1)), horizon=8, blocks=blocks, Q=[1.0, 0.01], R=[1e-4],
                          u_lb=[-50.0], u_ub=[50.0], method="euler")


def test_float_tolerance_from_the_exact_hessian():
    """Reference: the exact Hessian of the NLP's objective (CasADi's second derivative, not the
    Gauss-Newton product the solver uses; equal for this linear model), its eigenvalues by NumPy:
    2 tau / lambda_min + eps32 cond."""
    import casadi as ca

    from gtmodel.control.mpc import QP_FLOAT_TOLERANCE

    c = _linear_mpc()
    nlp, _ = c._nlp()
    hess = ca.Function("h", [nlp["x"], nlp["p"]], [ca.hessian(nlp["f"], nlp["x"])[0]])
    h = np.array(hess(np.r_[c.w_initial, np.zeros(c.n_slack)], c.parameters(c.t0, c.x_ref[0])))[: c.nw, : c.nw]
    lam = np.linalg.eigvalsh(h)
    expected = 2 * QP_FLOAT_TOLERANCE / lam[0] + np.finfo(np.float32).eps * lam[-1] / lam[0]
    assert c.float_tolerance() == pytest.approx(expected, rel=1e-6)
    assert c.float_tolerance(rows=1) == pytest.approx(expected, rel=1e-6)  # linear: the same Hessian on every row


@pytest.mark.parametrize("rows", [0, -1, 2.5, True])
def test_float_tolerance_refuses_bad_rows(rows):
    with pytest.raises(InputError, match="rows: expected a positive number of reference rows"):
        _linear_mpc().float_tolerance(rows=rows)


@pytest.mark.parametrize("plugin, real, match", [("sqpmethod", "half", "real: expected one of"), ("qpoases", "double", "plugin: expected")])
def test_nlp_solver_refuses_bad_options(motor, plugin, real, match):
    with pytest.raises(InputError, match=match):
        motor[-1].nlp_solver(plugin, real=real)


def test_a_delayed_mpc_computes_the_plans_first_input_from_the_rest_before_it():
    # reference: the plan's own first-period input (period_means of the given one). A plan starting at rest with 6 V
    # (0 V holds the motor there) and one period of input delay: the reference gets one period at rest
    # (delayed_start), and the first real-time iteration, from the plant at rest under the held 0 V, computes the
    # plan's first input (within 2 %: one Gauss-Newton step on the reference the model's own RK4 made) instead of
    # catching up a period late
    ode, t, x, u = _motor_motion(np.cos)
    c = mpc_controller(ode, t, x, u, horizon=20, Q=[1e-2, 100.0, 1e-2], R=[1e-3], u_lb=[-12.0], u_ub=[12.0], method="rk4",
                       substeps=2, delay=1)
    assert c.lead == 1 and c.t0 == pytest.approx(-DT) and c.u_initial == pytest.approx([0.0], abs=1e-9)
    first = np.asarray(c.function()(c.t0, x[0], c.u_initial, c.memory_initial)[0]).ravel()
    assert first == pytest.approx(period_means(t, u, np.array([0.0]), DT)[0], rel=0.02)


@pytest.mark.parametrize("blocks, delay, rows", [(20, 0, list(range(20))), (4, 1, [1, 6, 11, 16])])
def test_the_first_warm_start_is_the_reference_input_where_each_block_acts(motor, blocks, delay, rows):
    # reference: the reference's rows read by hand (delay + j H / blocks), saturated at 5 V
    ode, t, x, u, _ = motor
    c = mpc_controller(ode, t, x, u, horizon=20, blocks=blocks, Q=[1e-2, 100.0, 1e-2], R=[1e-3], u_lb=[-5.0], u_ub=[5.0],
                       method="rk4", substeps=2, delay=delay)
    np.testing.assert_array_equal(c.w_initial, np.clip(c.u_ref[rows, 0], -5.0, 5.0))
    assert np.ptp(c.w_initial) > 0  # the case tests the rows, not a constant
