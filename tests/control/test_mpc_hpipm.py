"""The MPC's real-time iteration by HPIPM on the multiple-shooting QP (gtmodel.control.mpc_hpipm).

References: IPOPT to convergence on the same horizon problem (the iteration repeated at a fixed
state must reach IPOPT's first input, 1e-6); the single-shooting SQP's one Gauss-Newton
iteration (the first multiple-shooting QP from the warm start's rollout has no gaps: it is the
same QP, so the same step, a second method); qpOASES and IPOPT on the step's own QP (``plugin``); HPIPM's
own verdict (``strict``) where it stops at its limit; the generated C against the Python Function (slow).
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from gtmodel.codegen.build import compile_shared
from gtmodel.codegen.loop_step import generate_loop_step, mpc_step, uses_heap_arena
from gtmodel.control.mpc import _sqrt_psd, mpc_controller
from gtmodel.control.mpc_hpipm import hpipm_rti
from gtmodel.errors import InputError
from gtmodel.modeling import explicit_ode
from gtmodel.problems.mpc_check import compiled_step
from gtmodel.problems.user_model import load_user_model

from ..conftest import REPO

DT = 0.004
#: The iteration repeated to convergence against IPOPT: first input, relative to 1 + |u_IPOPT|.
IPOPT_AGREEMENT = 1e-6


@pytest.fixture(scope="module")
def motor():
    ode = explicit_ode(load_user_model(REPO / "models" / "dc_motor.py", "DCMotorModel"))
    t = DT * np.arange(151)
    u = (6.0 * np.sin(2 * np.pi * t / 0.6))[:, None]
    x, _ = ode.simulate_steps(ode.step(DT, "rk4", substeps=4), u[:-1])
    c = mpc_controller(ode, t, x, u, horizon=20, Q=[1e-2, 100.0, 1e-2], R=[1e-3], u_lb=[-12.0], u_ub=[12.0], method="rk4",
                       substeps=2, solver="hpipm")
    return ode, t, x, u, c


@pytest.mark.parametrize("k, dx", [(10, [0.5, 0.02, 1.0]), (60, [0.5, 0.02, 1.0]), (110, [-2.0, -0.3, -20.0])],
                         ids=["early", "middle", "far-at-bounds"])
def test_converged_iteration_agrees_with_ipopt(motor, k, dx):
    *_, c = motor
    xk = c.x_ref[k] + np.array(dx)
    u_ip, _ = dataclasses.replace(c, solver="sqpmethod").solve(c.t0 + k * DT, xk, plugin="ipopt")
    u_hp, _ = c.solve(c.t0 + k * DT, xk, plugin="hpipm", iterations=20)
    assert np.max(np.abs(u_hp - u_ip)) / (1 + np.max(np.abs(u_ip))) <= IPOPT_AGREEMENT


def test_step_is_the_single_shooting_gauss_newton_step(motor):
    # the loop-step Function with hpipm against one sqpmethod (qrqp) iteration from the same warm start
    *_, c = motor
    ss = dataclasses.replace(c, solver="sqpmethod")
    xk, tk = c.x_ref[40] + np.array([0.1, 0.01, 0.5]), c.t0 + 40 * DT
    u, w_next, ok = c.function()(tk, xk, c.u_initial, c.w_initial)
    u_ss, w_ss, ok_ss = ss.function()(tk, xk, c.u_initial, c.w_initial)
    assert float(ok) == float(ok_ss) == 1.0
    np.testing.assert_allclose(np.asarray(u).ravel(), np.asarray(u_ss).ravel(), rtol=1e-8, atol=1e-8)
    np.testing.assert_allclose(np.asarray(w_next).ravel(), np.asarray(w_ss).ravel(), rtol=1e-8, atol=1e-8)


BAD = [
    ({"blocks": 5}, "blocks: expected the horizon 20 with solver hpipm"),
]


@pytest.mark.parametrize("kwargs, match", BAD, ids=["blocked"])
def test_unsupported_forms_are_refused(motor, kwargs, match):
    ode, t, x, u, _ = motor
    with pytest.raises(InputError, match=match):
        mpc_controller(ode, t, x, u, horizon=20, solver="hpipm", **kwargs)


@pytest.mark.slow
def test_generated_step_matches_the_function_without_heap(motor, tmp_path):
    # the generated C (CasADi's hpipm runtime, the wheel's libhpipm) against the Python Function it came from,
    # over a few periods of the motion; its per-QP allocations go to the arena (no heap call)
    *_, c = motor
    generated = generate_loop_step(mpc_step(c, "motor"), tmp_path, prefix="gt_hp")
    assert uses_heap_arena(generated.casadi_source)
    controller, _, _ = compiled_step(generated, compile_shared(generated, tmp_path / "build"))
    f = c.function()
    w, u_last = c.w_initial, c.u_initial
    got, want, statuses = [], [], []
    for k in range(30, 36):
        xk = c.x_ref[k] + np.array([0.2, 0.01, 0.3])
        status, u = controller(c.t0 + k * DT, xk)
        uf, w_next, _ = f(c.t0 + k * DT, xk, u_last, w)
        w, u_last = np.asarray(w_next).ravel(), np.asarray(uf).ravel()
        statuses.append(status)
        got.append(u)
        want.append(u_last)
    assert statuses == [0] * 6
    np.testing.assert_allclose(np.array(got), np.array(want), rtol=1e-9, atol=1e-9)


@pytest.fixture(scope="module")
def limited(motor):
    """The motor's hpipm MPC with a soft current row of +-2 A."""
    ode, t, x, u, _ = motor
    return mpc_controller(ode, t, x, u, horizon=20, Q=[1e-2, 100.0, 1e-2], R=[1e-3], u_lb=[-12.0], u_ub=[12.0], method="rk4",
                          substeps=2, solver="hpipm", x_lb={"ind.i": -2.0}, x_ub={"ind.i": 2.0})


def _rti_args(c, k, xk):
    # the warm start: the input holding the start in every stage (from the reference's inputs, w_initial, HPIPM
    # converges at the strict test's state below)
    return (xk, np.tile(c.u_initial, c.horizon), c.parameters(c.t0 + k * DT, xk), np.tile(c.u_lb, c.horizon), np.tile(c.u_ub, c.horizon),
            np.zeros(c.constraint_rows))


@pytest.mark.parametrize("plugin", ["qpoases", "ipopt"])
def test_reference_qp_solvers_agree_with_hpipm_where_it_converges(limited, plugin):
    # the same QP by an active-set method and by IPOPT (a second method each) at a state near the reference: HPIPM converges there
    k, c = 40, limited
    args = _rti_args(c, k, c.x_ref[k] + np.array([0.1, 0.01, 0.5]))
    u = [np.asarray(hpipm_rti(c, _sqrt_psd, plugin=p, strict=True)(*args)[0]).ravel() for p in ("hpipm", plugin)]
    np.testing.assert_allclose(u[0], u[1], rtol=0, atol=1e-6 * 24.0)


def test_strict_raises_where_hpipm_stops_at_its_limit(limited):
    # a current 20x beyond the soft row: the row's multiplier is at least the penalty rho, and HPIPM's absolute
    # complementarity tolerance is out of reach (module docstring); the lenient Function returns the iterate
    c, k = limited, 40
    args = _rti_args(c, k, np.array([-40.0, c.x_ref[k][1], 100.0]))
    assert np.all(np.isfinite(np.asarray(hpipm_rti(c, _sqrt_psd)(*args)[0])))
    with pytest.raises(RuntimeError, match="mpc_hpipm"):
        hpipm_rti(c, _sqrt_psd, strict=True)(*args)


def test_solve_says_where_hpipm_stops_at_its_limit(limited, capfd):
    # the state of the test above: MPCController.solve returns HPIPM's last iterate with status error (HPIPM's own
    # verdict, strict), and CasADi's dump of the failed QP stays off the terminal; at a state where HPIPM converges,
    # completed
    c, k = limited, 40
    w0 = np.tile(c.u_initial, c.horizon)
    bad = c.solve(c.t0 + k * DT, np.array([-40.0, c.x_ref[k][1], 100.0]), w0=w0, plugin="hpipm")
    good = c.solve(c.t0 + k * DT, c.x_ref[k] + np.array([0.1, 0.01, 0.5]), w0=w0, plugin="hpipm")
    assert (bad.status, bad.success, good.status, good.success) == ("error", False, "completed", True)
    assert bad.message.startswith("HPIPM did not solve a QP of the 1 real-time iterations") and np.all(np.isfinite(bad.w))
    assert capfd.readouterr().err == ""


def test_unknown_reference_solver_is_refused(limited):
    with pytest.raises(InputError, match="plugin: expected 'hpipm', 'qpoases' or 'ipopt', got 'osqp'"):
        hpipm_rti(limited, _sqrt_psd, plugin="osqp")


def test_disturbance_estimate_and_delay_as_with_sqpmethod(motor):
    # the estimate shifts the input bounds and the delay moves the horizon's start; both are the step's, not the
    # solver's: with hpipm the step equals sqpmethod's (single shooting, one Gauss-Newton iteration) to 1e-8
    *_, c = motor
    hp = dataclasses.replace(c, disturbance_gain=0.3, delay=1)
    ss = dataclasses.replace(hp, solver="sqpmethod")
    mem = hp.memory_initial.copy()
    mem[hp.nw:hp.nw + hp.nu] = 0.5  # an estimate of 0.5 V
    mem[-1] = 1.0
    xk, tk, u_last = c.x_ref[40] + np.array([0.1, 0.01, 0.5]), c.t0 + 40 * DT, np.array([3.0])
    got = [np.asarray(v).ravel() for v in hp.function()(tk, xk, u_last, mem)]
    want = [np.asarray(v).ravel() for v in ss.function()(tk, xk, u_last, mem)]
    np.testing.assert_allclose(np.concatenate(got), np.concatenate(want), rtol=1e-8, atol=1e-8)
