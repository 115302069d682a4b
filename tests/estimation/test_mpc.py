"""Real-time nonlinear MPC (gtmodel.estimation.mpc) of the composed DC motor, evaluated from Python.

References: the same horizon problem solved to convergence by IPOPT (the SQP iterated at a
fixed state must reach IPOPT's first input); the feedforward alone on the same mismatched
plant (the MPC must halve its tracking error); the input bounds (never exceeded).
"""

from __future__ import annotations

import numpy as np
import pytest

from gtmodel.errors import InputError
from gtmodel.estimation.closed_loop.controller_loop import run_controller_loop
from gtmodel.estimation.mpc import mpc_controller
from gtmodel.modeling import explicit_ode
from gtmodel.problems.user_model import load_user_model

from ..conftest import REPO

DT = 0.004
#: The SQP iterated to convergence against IPOPT: first input, relative to 1 + |u_IPOPT|.
IPOPT_AGREEMENT = 1e-6


@pytest.fixture(scope="module")
def motor():
    ode = explicit_ode(load_user_model(REPO / "models" / "dc_motor.py", "DCMotorModel"))
    t = DT * np.arange(151)
    u = (6.0 * np.sin(2 * np.pi * t / 0.6))[:, None]
    x, _ = ode.simulate_steps(ode.step(DT, "rk4", substeps=4), u[:-1])
    c = mpc_controller(ode, t, x, u, horizon=20, Q=[1e-2, 100.0, 1e-2], R=[1e-3], u_lb=[-12.0], u_ub=[12.0], method="rk4", substeps=2)
    return ode, t, x, u, c


BAD = [
    ({"horizon": 0}, "horizon: expected an integer >= 1"),
    ({"horizon": 20, "blocks": 3}, "blocks: expected a divisor of the horizon 20"),
    ({"sqp_iterations": 0}, "sqp_iterations: expected an integer >= 1"),
    ({"dt": 0.0}, "dt: expected a positive loop period"),
    ({"method": "euler2"}, "method: expected one of"),
    ({"solver": "osqp"}, "solver: expected one of sqpmethod, fatrop"),
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
