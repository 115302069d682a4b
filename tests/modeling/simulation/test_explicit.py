"""explicit_ode: a model as xdot = f(x, u, p), its fixed steps, against independent references.

References: SciPy's ``solve_ivp`` (Radau) on the explicit right-hand side and IDAS on the
DAE (``Model.simulate``), the DC motor's closed-form steady state, and the orders of the
fixed-step methods.
"""

from __future__ import annotations

import importlib.util

import casadi as ca
import numpy as np
import pytest
from scipy.integrate import solve_ivp

from gtmodel.errors import InputError, ModelError
from gtmodel.exchange import ExplicitModel, explicit_model
from gtmodel.modeling import Model, explicit_ode
from gtmodel.problems.user_model import load_user_model

from ...conftest import REPO
from .._builders import nonlinear_loop

MOTOR = REPO / "models" / "dc_motor.py"
R, K, RATIO, D = 0.5, 0.05, 50.0, 0.02  # the model file's parameters


@pytest.fixture(scope="module")
def motor():
    model = load_user_model(MOTOR, "DCMotorModel")
    return model, explicit_ode(model)


def test_motor_is_eliminated_symbolically(motor):
    _, ode = motor
    assert (ode.symbolic, ode.newton, ode.x_names, ode.u_names) == (True, 0, ["ind.i", "emf.phi", "rotor.w"], ["src.v"])
    assert ode.algebraic == 29


def test_component_gives_units_and_the_same_ode(motor):
    # the component itself (reduced inside explicit_ode) and the model file's reduced model: one ODE
    spec = importlib.util.spec_from_file_location("dc_motor_file", MOTOR)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    ode = explicit_ode(module.DCMotor())
    assert (ode.units["ind.i"], ode.units["src.v"], ode.units["r.R"]) == ("A", "V", "Ohm")
    x = np.array([1.0, 0.2, 30.0])
    np.testing.assert_allclose(np.asarray(ode.f(x, 5.0, ode.p_default)), np.asarray(motor[1].f(x, 5.0, motor[1].p_default)), rtol=1e-14)


def test_motor_rest_point_is_the_closed_form_steady_state(motor):
    # V = R i + k w and k i = (d / ratio^2) w (the load's friction seen at the rotor)
    _, ode = motor
    V = 12.0
    w = K * V / (R * D / RATIO**2 + K**2)
    i = D / RATIO**2 * w / K
    xdot = np.asarray(ode.f([i, 0.0, w], V, ode.p_default)).ravel()
    assert xdot[1] == pytest.approx(w, rel=1e-12)
    np.testing.assert_allclose(xdot[[0, 2]], 0.0, atol=1e-9)


def test_motor_f_integrated_by_scipy_equals_simulate(motor):
    # peer: SciPy Radau on the explicit f; IDAS on the DAE (simulate)
    model, ode = motor
    t = np.linspace(0.0, 0.3, 31)
    f = ode.f
    sol = solve_ivp(lambda _t, x: np.asarray(f(x, 12.0, ode.p_default)).ravel(), (0.0, 0.3), ode.x0, t_eval=t,
                    method="Radau", rtol=1e-11, atol=1e-12)
    res = model.simulate(t, u=12.0, rtol=1e-10, atol=1e-12)
    got = np.column_stack([res.x[n] for n in ode.x_names])
    assert np.max(np.abs(sol.y.T - got) / np.abs(got).max(axis=0)) < 1e-7


def test_newton_loop_model_equals_simulate():
    # IDAS solves the same DAE with its own Newton; the explicit f carries an unrolled one
    m = nonlinear_loop()
    ode = explicit_ode(m)
    assert (ode.symbolic, ode.newton) == (False, 1)
    t = np.linspace(0.0, 2.0, 21)
    res = m.simulate(t, u=0.3, rtol=1e-10, atol=1e-12)
    x, ok = ode.simulate_steps(ode.step(0.01, "rk4"), np.full((200, 1), 0.3))
    assert ok.min() == 1.0
    np.testing.assert_allclose(x[::10, 0], res.x["x"], atol=1e-8)
    np.testing.assert_allclose(np.asarray(ode.h(x[-1], 0.3, [])).ravel(), res.outputs["zz"][-1], atol=1e-8)


@pytest.mark.parametrize("x, converged", [(1.0, 1.0), (50.0, 1.0), (np.nan, 0.0), (1e308, 0.0)])
def test_newton_converged_flag(x, converged):
    # z + 0.5 sin z = x has one root for every finite x; NaN and an overflow are flagged
    ode = explicit_ode(nonlinear_loop())
    assert float(ode.converged(x, 0.0, [])) == converged


@pytest.mark.parametrize("method, substeps, tolerance", [("rk4", 4, 1e-4), ("radau2", 4, 1e-3), ("implicit_euler", 16, 2e-2)])
def test_motor_steps_follow_simulate(motor, method, substeps, tolerance):
    # reference: IDAS on the DAE with the same piecewise-constant input, at the period boundaries
    model, ode = motor
    n, dt = 100, 0.004
    u = (6.0 * np.sin(2 * np.pi * np.arange(n) / n))[:, None]
    res = model.simulate(dt * np.arange(n + 1), u=u, rtol=1e-10, atol=1e-12)
    ref = np.column_stack([res.x[k] for k in ode.x_names])
    x, ok = ode.simulate_steps(ode.step(dt, method, substeps=substeps), u)
    assert ok.min() == 1.0
    assert np.max(np.abs(x - ref) / (1.0 + np.abs(ref).max(axis=0))) < tolerance


def test_radau_is_stable_where_rk4_is_not(motor):
    # the electrical pole (about -535 1/s) times 8 ms leaves RK4's stability region (-2.79);
    # Radau IIA is L-stable
    model, ode = motor
    n, dt = 50, 0.008
    u = np.full((n, 1), 6.0)
    ref = model.simulate(dt * np.arange(n + 1), u=u).x["rotor.w"]
    rk4, _ = ode.simulate_steps(ode.step(dt, "rk4"), u)
    radau, ok = ode.simulate_steps(ode.step(dt, "radau2"), u)
    assert np.max(np.abs(rk4[:, 2])) > 1e3 * np.max(np.abs(ref))
    assert ok.min() == 1.0 and np.max(np.abs(radau[:, 2] - ref)) < 0.02 * np.max(np.abs(ref))


def test_time_dependent_model_refuses_f():
    m = Model("forced")
    x = m.state("x")
    m.equation(m.der(x), ca.sin(m.time) - x)
    ode = explicit_ode(m)
    assert ode.time_dependent
    assert float(ode.full(t=np.pi / 2, x=0.0, u=ca.DM(0, 1), p=ca.DM(0, 1))["xdot"]) == pytest.approx(1.0)
    with pytest.raises(ModelError, match="'forced' depends on time explicitly"):
        ode.f


def _no_state() -> Model:
    m = Model("static")
    y = m.algebraic("y")
    m.equation(y, 1.0)
    return m


@pytest.mark.parametrize(
    "call, error, match",
    [
        (lambda ode: explicit_ode("motor"), InputError, "model: expected a gtmodel Model or Component, got str"),
        (lambda ode: explicit_ode(_no_state()), ModelError, "'static' has no state"),
        (lambda ode: explicit_ode(nonlinear_loop(), iterations=0), InputError, "iterations: expected a positive"),
        (lambda ode: ode.step(0.0), InputError, r"dt: expected a positive step length in seconds, got 0\.0"),
        (lambda ode: ode.step(float("nan")), InputError, "dt: expected a positive step length"),
        (lambda ode: ode.step(0.004, "euler"), InputError, "method: expected one of rk4, implicit_euler, radau2, got 'euler'"),
        (lambda ode: ode.step(0.004, "radau2", iterations=0), InputError, "iterations: expected a positive number"),
        (lambda ode: ode.step(0.004, substeps=0), InputError, "substeps: expected a positive number"),
        (lambda ode: ode.simulate_steps(ode.step(), np.zeros((3, 1)), p=[1.0]), InputError, "p, x0: expected lengths 8 and 3"),
    ],
    ids=["not_a_model", "no_state", "iterations", "dt_zero", "dt_nan", "method", "step_iterations", "substeps", "p_length"],
)
def test_bad_arguments(motor, call, error, match):
    with pytest.raises(error, match=match):
        call(motor[1])


@pytest.mark.parametrize("current", [1e-3, 1e-1, 1.0, 10.0, 1e3, -1.0])
def test_diode_voltage_by_the_damped_newton_from_zero(current):
    # a Shockley diode (I_s 1e-9 A, V_t 26 mV, leakage 1e4 Ohm) in series with a motor, v from v = 0:
    # the plain Newton step from 0 is about i x 1e4 V, where exp overflows (NaN before the damping);
    # reference: the root of the same equation by SciPy's brentq
    from scipy.optimize import brentq

    model = load_user_model(REPO / "tests" / "fixtures" / "user_models" / "diode_motor.py", "Diode2Motor")
    ode = explicit_ode(model)
    u, R, L = 6.0, 1.0, 2e-3
    out = ode.full(t=0.0, x=[current, 0.0, 0.0], u=u, p=ode.p_default)
    assert float(out["converged"]) == 1.0
    v_diode = u - R * current - L * float(out["xdot"][0])  # emf.v = 0 at rest: L di/dt = u - v_d - R i
    root = brentq(lambda v: 1e-9 * np.expm1(v / 0.026) + v / 1e4 - current, -1e8, 2.0, xtol=1e-14)
    assert v_diode == pytest.approx(root, rel=1e-8, abs=1e-9)


def test_model_subclass_without_a_name_argument_reduces():
    # a higher-index model written by equations in a subclass whose __init__ takes no name (the
    # Cartesian pendulum, index 3): structural_simplify made type(model)(name) and raised TypeError;
    # reference: the dummy-derivative state count of the pendulum, 2 (Mattsson & Soederlind 1993)
    class CartesianPendulum2(Model):
        def __init__(self):
            super().__init__("cartesian pendulum")  # no CasADi name either: the integrators' names are made valid
            x, y = self.state("x", start=1.0), self.state("y", start=0.0)
            vx, vy = self.state("vx"), self.state("vy")
            lam = self.algebraic("lam")
            self.equation(self.der(x), vx)
            self.equation(self.der(y), vy)
            self.equation(self.der(vx), -lam * x)
            self.equation(self.der(vy), -lam * y - 9.81)
            self.equation(x**2 + y**2, 1.0)

    ode = explicit_ode(CartesianPendulum2())
    assert ode.nx == 2
    res = CartesianPendulum2().simulate(np.linspace(0.0, 0.2, 11))
    assert res.x["x"][-1] ** 2 + res.x["y"][-1] ** 2 == pytest.approx(1.0, abs=1e-6)


def test_one_explicit_model_class_for_the_loop_and_the_fmu(motor):
    """The FMU's explicit model is this class (exchange.ExplicitModel an alias), with the same equations."""
    model, ode = motor
    em = explicit_model(model)
    x, u = np.array([0.3, 0.1, 2.0]), np.array([4.0])
    assert ExplicitModel is type(ode) is type(em)
    assert np.allclose(np.array(em.rhs(0.0, x, u, em.p_default)[0], float).ravel(),
                       np.array(ode.f(x, u, ode.p_default), float).ravel(), rtol=1e-14, atol=0)


def test_from_function_steps_like_the_reduced_model(motor):
    """An ODE given as a Function (an FMU, a connection) steps as the one reduced from the model (second path)."""
    _, ode = motor
    given = type(ode).from_function("given", ode.rhs, ode.x_names, ode.u_names, ode.p_names, ode.y_names,
                                    ode.x0, ode.u0, ode.p_default)
    x, u = np.array([0.3, 0.1, 2.0]), np.array([4.0])
    same = [np.array(o.step(1e-3)(x, u, o.p_default)[0], float).ravel() for o in (ode, given)]
    assert given.dae is None and not given.time_dependent and np.all(np.isinf(given.x_ub))
    assert np.allclose(same[0], same[1], rtol=1e-13, atol=0)
