"""Offset-free MPC: the input-disturbance estimate (``mpc_controller(..., disturbance_gain=...)``).

References: the disturbance the plant is given (a constant input offset ``d`` on the model's
own step: the estimate must converge to it, and the state to the reference, where the MPC
without the estimate rests off it, closed form ``d / K``-like: a non-zero offset); the step's
memory layout (warm start, estimate, last state, last input, flag) read back; the MPC without
the estimate unchanged (the same Function outputs as before the option existed: the estimate
off adds nothing to the memory).
"""

from __future__ import annotations

import numpy as np
import pytest

from gtmodel.errors import InputError
from gtmodel.control.mpc import mpc_controller
from gtmodel.modeling import explicit_ode

from ..modeling._builders import double_integrator

DT = 0.004
N = 251
T = DT * np.arange(N)
X_REF = np.tile([1.0, 0.0], (N, 1))
U_REF = np.zeros((N, 1))


@pytest.fixture(scope="module")
def ode():
    return explicit_ode(double_integrator()[0])


def _mpc(ode, gain, delay=0):
    return mpc_controller(ode, T, X_REF, U_REF, horizon=10, Q=[1e2, 1.0], R=[1e-4], u_lb=[-50.0], u_ub=[50.0],
                          method="rk4", delay=delay, disturbance_gain=gain)


def _run(ode, c, d_true, steps=1500):
    """The closed loop on the model's own step with the input offset d_true (and the delay the MPC compensates)."""
    f, step = c.function(), ode.step(DT, "rk4")
    x, mem, u_last = np.array([1.0, 0.0]), c.memory_initial.copy(), c.u_initial.copy()
    for k in range(steps):
        u, mem, ok = (np.asarray(v).reshape(-1) for v in f(T[min(k, N - 1)], x, u_last, mem))
        assert ok[0] == 1.0
        applied = u if c.delay == 0 else u_last  # with the delay, this period's input is the one computed a period ago
        x = np.asarray(step(x, applied + d_true, ode.p_default)[0]).reshape(-1)
        u_last = u
    return x, mem


@pytest.mark.parametrize("delay", [0, 1], ids=["no delay", "one period of delay"])
def test_estimate_converges_to_the_disturbance_and_the_offset_vanishes(ode, delay):
    d_true = 3.0
    plain = _mpc(ode, 0.0, delay)
    x_plain, _ = _run(ode, plain, d_true)
    assert abs(x_plain[0] - 1.0) > 1e-3  # without the estimate the MPC rests off the reference
    c = _mpc(ode, 0.5, delay)
    x, mem = _run(ode, c, d_true)
    d_hat = mem[c.nw:c.nw + c.nu]
    assert d_hat[0] == pytest.approx(d_true, abs=1e-6)
    assert abs(x[0] - 1.0) < 1e-6 and abs(x[1]) < 1e-6
    assert mem[-1] == 1.0  # the flag: a step ran


def test_memory_layout(ode):
    c = _mpc(ode, 0.5)
    assert c.n_memory == c.nw + 2 * c.nu + c.nx + 1
    np.testing.assert_array_equal(c.memory_initial, np.r_[c.w_initial, 0.0, X_REF[0], c.u_initial, 0.0])
    # the first step has no previous state: the estimate stays 0 whatever the memory's state slot holds
    mem = c.memory_initial.copy()
    mem[c.nw + c.nu:c.nw + c.nu + c.nx] = [np.nan, 5.0]  # not even a state
    out = c.function()(0.0, [1.0, 0.0], [0.0], mem)
    assert float(out[1][c.nw]) == 0.0
    np.testing.assert_array_equal(np.asarray(out[1][c.nw + c.nu:c.nw + c.nu + c.nx]).reshape(-1), [1.0, 0.0])  # this x kept


def test_without_the_estimate_the_memory_is_the_warm_start(ode):
    c = _mpc(ode, 0.0)
    assert c.n_memory == c.nw and c.function().numel_in("w") == c.nw
    np.testing.assert_array_equal(c.memory_initial, c.w_initial)


@pytest.mark.parametrize("kwargs, match", [
    ({"disturbance_gain": 1.5}, r"disturbance_gain: expected a number in \[0, 1\]"),
    ({"disturbance_gain": True}, "disturbance_gain: expected a number"),
    ({"disturbance_gain": 0.5, "solver": "fatrop"}, "give solver sqpmethod"),
], ids=["above 1", "a bool", "with fatrop"])
def test_bad_disturbance_gain(ode, kwargs, match):
    with pytest.raises(InputError, match=match):
        mpc_controller(ode, T, X_REF, U_REF, horizon=10, u_lb=[-50.0], u_ub=[50.0], **kwargs)
