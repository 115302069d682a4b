"""Inverse models (Modelica's inverse-model idea) of index-1 and index-3 models."""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

from gtmodel.errors import InputError, ModelError
from gtmodel.modeling import Component, Input, Model, Parameter, State, connect, inverse_model
from gtmodel.modeling.library import translational as tr

G = 9.81
TOL = 1e-12


def forced_pendulum(length: float = 1.5, mass: float = 2.0) -> Model:
    """Cartesian pendulum (index 3) with a horizontal force input F on the bob."""
    m = Model("forced_pendulum")
    L = m.parameter("L", length)
    mm = m.parameter("m", mass)
    x, y, u, v = (m.state(n) for n in ("x", "y", "u", "v"))
    lam = m.algebraic("lam")
    F = m.input("F")
    m.equation(m.der(x), u, name="vel_x")
    m.equation(m.der(y), v, name="vel_y")
    m.equation(mm * m.der(u), -lam * x + F, name="force_x")
    m.equation(mm * m.der(v), -lam * y - mm * G, name="force_y")
    m.equation(x**2 + y**2, L**2, name="length")
    return m


def singular() -> Model:
    """x determined twice, y not at all: structurally singular."""
    m = Model("singular")
    x = m.state("x")
    m.algebraic("y")
    f = m.input("F")
    m.equation(m.der(x), f, name="a")
    m.equation(x, 1.0, name="b")
    return m


class Oscillator(Component):
    """Force -> mass -- spring-damper -- fixed (an ODE after flattening)."""

    force = tr.Force()
    mass = tr.Mass(m=3.0)
    spring = tr.SpringDamper(c=50.0, d=4.0)
    fixed = tr.Fixed()

    def equations(self):
        connect(self.force.flange, self.mass.flange_b)
        connect(self.mass.flange_a, self.spring.flange_b)
        connect(self.spring.flange_a, self.fixed.flange)


def pendulum_motion(theta, dtheta, ddtheta, length=1.5):
    """x, y, u, der(u) of the pendulum at angle theta from the downward vertical."""
    s, c = np.sin(theta), np.cos(theta)
    return length * s, -length * c, length * c * dtheta, length * (c * ddtheta - s * dtheta**2)


def test_pendulum_force_matches_lagrange():
    # closed form: m L^2 theta'' = -m g L sin(theta) + F L cos(theta) (Lagrange in the angle)
    inv = inverse_model(forced_pendulum(), known=["x", "y", "u", "der(u)"], unknown=["F", "lam"])
    rng = np.random.default_rng(3)
    th, dth, ddth = rng.uniform(-1.2, 1.2, 200), rng.normal(0, 2, 200), rng.normal(0, 5, 200)
    x, y, u, du = pendulum_motion(th, dth, ddth)
    F, lam, residual = inv.function.map(200)(x, y, u, du)
    expected = 2.0 * (1.5 * ddth + G * np.sin(th)) / np.cos(th)
    np.testing.assert_allclose(np.array(F).ravel(), expected, rtol=1e-11, atol=TOL)
    # closed form from force_y: lam = m (y'' + g) / (-y), y'' = L (cos(theta) theta'^2 + sin(theta) theta'')
    lam_expected = 2.0 * (1.5 * (np.cos(th) * dth**2 + np.sin(th) * ddth) + G) / (1.5 * np.cos(th))
    np.testing.assert_allclose(np.array(lam).ravel(), lam_expected, rtol=1e-10, atol=1e-10)
    assert inv.residual_names == ["length"]
    assert np.max(np.abs(np.array(residual))) < 1e-12


def test_inconsistent_motion_shows_in_the_residual():
    # closed form: the length constraint x^2 + y^2 - L^2 at a point off the circle
    inv = inverse_model(forced_pendulum(), known=["x", "y", "u", "der(u)"], unknown=["F"])
    _, residual = inv.function(1.0, -1.0, 0.0, 0.0)
    assert float(residual) == pytest.approx(2.0 - 1.5**2, abs=TOL)


def test_velocity_and_acceleration_from_the_differentiated_constraint():
    # closed form: v = -x u / y (first derivative of the constraint), der(v) from the second
    inv = inverse_model(forced_pendulum(), known=["x", "y", "u", "der(u)"], unknown=["v", "der(v)", "F"])
    x, y, u, du = pendulum_motion(0.4, 1.3, -0.7)
    v, dv, _, _ = inv.function(x, y, u, du)
    dv_expected = 1.5 * (np.cos(0.4) * 1.3**2 + np.sin(0.4) * -0.7)  # y'' of y = -L cos(theta)
    assert float(v) == pytest.approx(-x * u / y, abs=TOL)
    assert float(dv) == pytest.approx(dv_expected, abs=1e-10)


@pytest.mark.parametrize("accel_name", ["der(mass.v)", "der(der(mass.s))"])
def test_oscillator_force_matches_newton(accel_name):
    # closed form: f = m a + d v + c s (Newton with the spring-damper to the fixed point s = 0)
    model = Oscillator().to_model()
    inv = inverse_model(model, known=["mass.s", "mass.v", accel_name], unknown=["force.f"])
    f, residual = inv.function(0.2, -0.5, 1.5)
    assert float(f) == pytest.approx(3.0 * 1.5 + 4.0 * -0.5 + 50.0 * 0.2, abs=TOL)
    assert residual.numel() == 0 or np.max(np.abs(np.array(residual))) < TOL


def test_parameters_as_input_and_overrides():
    # closed form: f = m a + d v + c s with the overridden / passed mass
    model = Oscillator().to_model()
    inv = inverse_model(model, known=["mass.s", "mass.v", "der(mass.v)"], unknown=["force.f"], parameter_input=True)
    p = inv.p_value.copy()
    p[inv.p_names.index("mass.m")] = 7.0
    f, _ = inv.function(0.2, -0.5, 1.5, p)
    assert float(f) == pytest.approx(7.0 * 1.5 + 4.0 * -0.5 + 50.0 * 0.2, abs=TOL)
    inv2 = inverse_model(model, known=["mass.s", "mass.v", "der(mass.v)"], unknown=["force.f"], p={"mass.m": 7.0})
    assert float(inv2.function(0.2, -0.5, 1.5)[0]) == pytest.approx(float(f), abs=TOL)


def test_function_is_differentiable_and_mappable():
    # second method: the CasADi Jacobian of the force w.r.t. the acceleration is the mass (3 kg)
    inv = inverse_model(Oscillator().to_model(), known=["mass.s", "mass.v", "der(mass.v)"], unknown=["force.f"])
    a = ca.SX.sym("a")
    f = inv.function(0.0, 0.0, a)[0]
    assert float(ca.DM(ca.jacobian(f, a))) == pytest.approx(3.0, abs=TOL)
    out = inv.function.map(5)(np.zeros(5), np.zeros(5), np.arange(5.0))[0]
    np.testing.assert_allclose(np.array(out).ravel(), 3.0 * np.arange(5.0), atol=TOL)


@pytest.mark.parametrize(
    "build, known, unknown, kw, error, match",
    [
        (forced_pendulum, ["x", "y"], ["F"], {}, ModelError, r"not determined.*'u'|not determined"),
        (forced_pendulum, ["x", "u", "der(u)"], ["F"], {}, ModelError, r"not linear in the variables \['y'\]"),
        (forced_pendulum, ["x", "y", "u", "der(u)"], ["G"], {}, ModelError, r"'G' names no state"),
        (forced_pendulum, ["x", "y", "u", "der(u)"], ["F", "lam[0]"], {}, ModelError, r"'lam\[0\]' is not a variable"),
        (forced_pendulum, ["x", "y", "u", "der(u)"], ["lam"], {}, ModelError, r"input\(s\) \['F'\] are neither known nor unknown"),
        (forced_pendulum, ["x", "y", "u", "der(u)", "der(F)"], ["lam"], {}, ModelError, r"derivatives of the input 'F'"),
        (forced_pendulum, ["x", "y", "u", "der(u)"], [], {}, InputError, "at least one variable"),
        (singular, ["x"], ["F"], {}, ModelError, r"model 'singular' is structurally singular.*\['y'\]"),
        (forced_pendulum, ["x", "y", "u", "der(u)"], ["x"], {}, InputError, r"overlap: \['x'\]"),
        (forced_pendulum, ["x", "x"], ["F"], {}, InputError, "listed twice"),
        (forced_pendulum, "x", ["F"], {}, InputError, "list of variable names"),
        (forced_pendulum, ["x", "y", "u", "der(u)"], ["F"], {"p": {"mass": 1.0}}, InputError, "has no parameter 'mass'"),
        (forced_pendulum, ["x", "y", "u", "der(u)"], ["F"], {"p": {"m": np.nan}}, InputError, "finite"),
    ],
)
def test_bad_input(build, known, unknown, kw, error, match):
    with pytest.raises(error, match=match):
        inverse_model(build(), known=known, unknown=unknown, **kw)


def test_time_must_be_known_when_the_equations_use_it():
    m = Model("driven")
    x = m.state("x")
    f = m.input("f")
    m.equation(m.der(x), f + ca.sin(m.time))
    with pytest.raises(ModelError, match="name 'time' in known"):
        inverse_model(m, known=["x", "der(x)"], unknown=["f"])
    inv = inverse_model(m, known=["x", "der(x)", "time"], unknown=["f"])
    # closed form: f = der(x) - sin(t)
    assert float(inv.function(0.0, 1.0, 0.5)[0]) == pytest.approx(1.0 - np.sin(0.5), abs=TOL)


class Point(Component):
    """A point mass in the plane driven by a force input (an ODE)."""

    m = Parameter(2.0)
    r = State(shape=2)
    v = State(shape=2)
    f = Input(shape=2)

    def equations(self):
        self.equation(self.der(self.r), self.v)
        self.equation(self.m * self.der(self.v), self.f)


@pytest.mark.parametrize("accel_name", ["der(v)", "der(der(r))"])
def test_second_derivative_of_a_vector_state_by_name(accel_name):
    # closed form: f = m a; der(der(r)) is der(v) through the equation der(r) = v
    inv = inverse_model(Point().to_model(), known=["r", "v", accel_name], unknown=["f"])
    f, _ = inv.function([0.0, 0.0], [0.0, 0.0], [1.0, -3.0])
    np.testing.assert_allclose(np.array(f).ravel(), [2.0, -6.0], atol=TOL)


def test_single_elements_by_name():
    # closed form: f[1] = m a[1], with r[1] and v[1] known by element
    inv = inverse_model(Point().to_model(), known=["r", "v", "der(v[0])", "der(v[1])"], unknown=["f[1]", "f[0]"])
    f1, f0, _ = inv.function([0.0, 0.0], [0.0, 0.0], 1.0, -3.0)
    assert (float(f1), float(f0)) == pytest.approx((-6.0, 2.0), abs=TOL)
