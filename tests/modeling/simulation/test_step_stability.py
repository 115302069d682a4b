"""The linear stability of the loop's fixed explicit steps along a trajectory (issue 49's held-out loop trial).

Independent checks: the step's own one-period growth, measured by running the RK4 / Euler step Functions of
:meth:`ExplicitODE.step` on ``x' = -a x`` (not the stability polynomial the module evaluates); RK4's real-axis
stability limit 2.785 (Hairer & Wanner, *Solving ODE II*, Table IV.2.1 region) giving the substeps by hand;
explicit Euler's ``|1 + i omega h|`` on an undamped oscillator.
"""

from __future__ import annotations

import math

import casadi as ca
import numpy as np
import pytest

from gtmodel.control.tracking import tracking_controller
from gtmodel.errors import InputError
from gtmodel.modeling import Model, explicit_ode
from gtmodel.modeling.simulation.step_stability import GROWTH_PER_PERIOD, step_stability
from gtmodel.problems.user_model import load_user_model

from ...conftest import REPO

DT = 0.004


class Decay(Model):
    """x' = -a x + u (a > 0 decays; a < 0 grows)."""

    def __init__(self, a: float) -> None:
        super().__init__("decay")
        x, u, a_ = self.state("x"), self.input("u"), self.parameter("a", a)
        self.equation(self.der(x), -a_ * x + u)


class Oscillator(Model):
    """x'' = -omega^2 x + u, undamped."""

    def __init__(self, omega: float) -> None:
        super().__init__("oscillator")
        x, v, u = self.state("x"), self.state("v"), self.input("u")
        self.equation(self.der(x), v)
        self.equation(self.der(v), -omega**2 * x + u)


def _stability(ode, method, substeps, n=5):
    return step_stability(ode.f, DT, method, substeps, np.zeros((n, ode.nx)), np.zeros((n, ode.nu)), ode.p_default)


def _measured_growth(ode, method, substeps):
    step = ode.step(DT, method, substeps=substeps) if method == "rk4" else None
    if step is None:  # explicit Euler, as the MPC's prediction writes it
        x, u, p = ca.SX.sym("x", ode.nx), ca.SX.sym("u", ode.nu), ca.SX.sym("p", ode.np)
        xn = x
        for _ in range(substeps):
            xn = xn + DT / substeps * ode.f(xn, u, p)
        step = ca.Function("euler", [x, u, p], [xn])
    return abs(float(step(np.ones(ode.nx), np.zeros(ode.nu), ode.p_default)[0][0]))


@pytest.mark.parametrize("method, limit", [("rk4", 2.785), ("euler", 2.0)])
def test_a_stiff_decay_needs_the_substeps_of_the_real_axis_limit(method, limit):
    # a = 5000 1/s (a motor's L/R = 0.2 ms): RK4 needs |a h| <= 2.785, explicit Euler |a h| <= 2 (a bit less for 1 % growth)
    ode = explicit_ode(Decay(5000.0))
    s = _stability(ode, method, 4)
    assert not s.stable and s.eigenvalue == pytest.approx(-5000.0)
    assert s.growth == pytest.approx(_measured_growth(ode, method, 4), rel=1e-9)  # the step's own growth per period
    n = s.substeps_needed
    assert math.ceil(5000.0 * DT / limit) <= n <= math.ceil(5000.0 * DT / limit) + 1
    assert _measured_growth(ode, method, n) <= GROWTH_PER_PERIOD < _measured_growth(ode, method, n - 1)
    assert _stability(ode, method, n).stable


class TanhFriction(Model):
    """v' = -c tanh(v / w) + u: a smooth Coulomb friction, stiff only within |v| < w (slope c / w at rest)."""

    def __init__(self, c: float, w: float) -> None:
        super().__init__("tanh_friction")
        v, u = self.state("v"), self.input("u")
        self.equation(self.der(v), -c * ca.tanh(v / w) + u)


def test_a_mode_bounded_by_the_model_s_nonlinearity_is_not_refused():
    # at rest c / w = 750 1/s (the L1's friction: -749 1/s) under one 4 ms Euler step: |1 + z| = 2 linearly, but a
    # perturbation stops growing where the tanh saturates (|v| ~ w): the step chatters within the band, it does not diverge
    ode = explicit_ode(TanhFriction(7.5, 0.01))
    assert _stability(ode, "euler", 1).stable
    # the same slope from a linear damper diverges: refused
    assert not _stability(explicit_ode(Decay(750.0)), "euler", 1).stable


def test_a_growing_mode_of_the_model_itself_is_not_the_step_s():
    # x' = +5000 x grows in the model too: the step follows it, nothing to refuse
    assert _stability(explicit_ode(Decay(-5000.0)), "rk4", 1).stable


@pytest.mark.parametrize("omega, stable", [(10.0, True), (1000.0, False)])
def test_explicit_euler_on_an_undamped_oscillator(omega, stable):
    # |1 + i omega h| per step: 1.0008 at 10 rad/s (harmless), 4.1 at 1000 rad/s
    s = _stability(explicit_ode(Oscillator(omega)), "euler", 1)
    assert s.stable is stable and s.growth == pytest.approx(abs(1 + 1j * omega * DT), rel=1e-9)


@pytest.mark.parametrize("method", ["radau2", "implicit_euler"])
def test_implicit_methods_are_not_checked(method):
    assert _stability(explicit_ode(Decay(5000.0)), method, 1) is None


def test_shapes_are_checked():
    ode = explicit_ode(Decay(1.0))
    with pytest.raises(InputError, match=r"expected states \(N, 1\) and inputs \(N, 1\)"):
        step_stability(ode.f, DT, "rk4", 1, np.zeros((3, 2)), np.zeros((3, 1)), ode.p_default)


def test_the_tracking_controller_refuses_an_unstable_step_and_names_the_substeps():
    # the shipped DC motor with its inductance 10x smaller (L/R 0.17 ms): one 4 ms RK4 step per period diverges
    ode = explicit_ode(load_user_model(REPO / "models" / "dc_motor.py", "DCMotorModel"))
    p = ode.p_default.copy()
    p[list(ode.p_names).index("ind.L")] /= 10.0
    t = np.linspace(0.0, 0.2, 51)
    x, u = np.zeros((51, ode.nx)), np.ones((51, ode.nu))
    with pytest.raises(InputError, match=r"the tracking controller's step \(method, substeps\) is unstable for this model: "
                                         r"rk4 with 1 substep\(s\).*give substeps = \d+"):
        tracking_controller(ode, t, x, u, p=p, method="rk4", substeps=1)
