"""Shared fixtures of the control tests; tests marked ``realtime`` skip on a busy machine, saying why (:mod:`tests.robot_sim.realtime`)."""

from __future__ import annotations

import numpy as np
import pytest

from gtmodel.modeling import explicit_ode
from gtmodel.problems.user_model import load_user_model

from ..conftest import REPO
from ..robot_sim.realtime import skip_when_busy


@pytest.fixture(autouse=True)
def _realtime_needs_a_quiet_machine(request):
    skip_when_busy(request.node)


@pytest.fixture(scope="module")
def motor():
    """The DC motor of ``models/dc_motor.py`` along a 6 V sine over 1 s, simulated by its own RK4 (10 substeps of 10 ms):
    ``(ode, t (101,), x (101, 3), u (101, 1))``."""
    ode = explicit_ode(load_user_model(REPO / "models" / "dc_motor.py", "DCMotorModel"))
    t = np.linspace(0.0, 1.0, 101)
    u = (6.0 * np.sin(2 * np.pi * t))[:, None]
    x, _ = ode.simulate_steps(ode.step(0.01, "rk4", substeps=10), u[:-1])
    return ode, t, x, u


def linearisation(ode, x, u, dt=0.004):
    """``(A, B)``: the Jacobians of the model's RK4 step over ``dt`` at ``(x, u)`` (CasADi AD), formed in the tests."""
    import casadi as ca

    xs, us = ca.SX.sym("x", ode.nx), ca.SX.sym("u", ode.nu)
    xn = ode.step(dt, "rk4")(xs, us, ode.p_default)[0]
    f = ca.Function("AB", [xs, us], [ca.jacobian(xn, xs), ca.jacobian(xn, us)])
    return (np.asarray(m) for m in f(x, u))
