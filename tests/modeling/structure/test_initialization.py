"""Tests of initial equations and the consistent initialisation.

References: closed-form solutions (steady states, undamped oscillators) and the Cartesian
pendulum against the same pendulum in its minimal coordinate (a second formulation).
"""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest
from scipy.integrate import solve_ivp

from gtmodel.errors import ConvergenceError, InputError, ModelError
from gtmodel.modeling import Model

from ._dae_builders import angle_pendulum, cartesian_pendulum

SIM_TOL = 1e-6


def first_order():
    """x' = -a x + b, 0 = y - 2 x."""
    m = Model("first_order")
    a = m.parameter("a", 2.0)
    b = m.parameter("b", 3.0)
    x = m.state("x", start=10.0)
    y = m.algebraic("y")
    m.equation(m.der(x), -a * x + b)
    m.equation(y, 2 * x)
    return m, x, y


def oscillator():
    """x'' = -4 x as x' = v, v' = -4 x."""
    m = Model("oscillator")
    x = m.state("x", start=1.0)
    v = m.state("v", start=1.0)
    m.equation(m.der(x), v)
    m.equation(m.der(v), -4.0 * x)
    return m, x, v


def test_steady_state_initialisation():
    # reference: der(x) = 0 at t0  =>  x = b / a = 1.5 for all t, y = 3 (closed form)
    m, x, _ = first_order()
    m.initial_equation(m.der(x), 0.0, name="steady")
    res = m.simulate(np.linspace(0.0, 1.0, 11))
    np.testing.assert_allclose(res.x["x"], 1.5, atol=SIM_TOL)
    np.testing.assert_allclose(res.z["y"], 3.0, atol=SIM_TOL)


def test_initial_equations_on_algebraic_and_derivative():
    # reference: y(0) = 1 => x(0) = 0.5; v(0) from x'(0) = 0 => x = 0.5 cos(2 t) (closed form)
    m, x, v = oscillator()
    y = m.algebraic("y")
    m.equation(y, 2 * x)
    m.initial_equation(y, 1.0)
    m.initial_equation(m.der(x), 0.0)
    t = np.linspace(0.0, 2.0, 21)
    res = m.simulate(t)
    np.testing.assert_allclose(res.x["x"], 0.5 * np.cos(2 * t), atol=SIM_TOL)


def test_x0_mapping_fixes_a_state_next_to_initial_equations():
    # reference: x(0) = 0.3 from x0, v(0) = 0 from the initial equation => x = 0.3 cos(2 t)
    m, x, v = oscillator()
    m.initial_equation(v, 0.0)
    t = np.linspace(0.0, 2.0, 21)
    res = m.simulate(t, x0={"x": 0.3})
    np.testing.assert_allclose(res.x["x"], 0.3 * np.cos(2 * t), atol=SIM_TOL)


def test_pendulum_initial_equations_match_minimal_coordinates():
    # reference: x(0) = 0.6 on the lower branch, at rest => theta0 = asin(0.6); the angle ODE
    m = cartesian_pendulum(theta0=0.5)
    xs, us = m.variables("state")["x"], m.variables("state")["u"]
    m.initial_equation(xs, 0.6, name="x0")
    m.initial_equation(us, 0.0, name="u0")
    t = np.linspace(0.0, 2.0, 41)
    res = m.simulate(t, rtol=1e-10, atol=1e-12)
    assert res.x["y"][0] == pytest.approx(-0.8, abs=1e-10)
    assert res.x["v"][0] == pytest.approx(0.0, abs=1e-10)
    ref = angle_pendulum(theta0=float(np.arcsin(0.6))).simulate(t, rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(res.x["x"], ref.outputs["pos_x"], atol=SIM_TOL)


def _under_index1():
    m, x, _ = oscillator()
    m.initial_equation(x, 1.0, name="only_x")
    m.simulate([0.0, 1.0])


def _under_pendulum():
    m = cartesian_pendulum()
    m.initial_equation(m.variables("state")["x"], 0.6, name="x0")
    m.simulate([0.0, 1.0])


def _over():
    m, x, v = oscillator()
    m.initial_equation(x, 1.0, name="ix")
    m.initial_equation(v, 0.0, name="iv")
    m.initial_equation(m.der(v), 0.0, name="iacc")
    m.simulate([0.0, 1.0])


@pytest.mark.parametrize(
    "build, match",
    [
        (_under_index1, r"initialisation of model 'oscillator' is under-determined .* or x0 values for 1 of the states \['v'"),
        (_under_pendulum, r"initialisation of model 'pendulum' is under-determined .*1 of the states \["),
        (_over, r"initialisation of model 'oscillator' is over-determined .*remove 1 of the initial equations"),
    ],
    ids=["under_index1", "under_pendulum", "over"],
)
def test_initialisation_structure_errors(build, match):
    with pytest.raises(ModelError, match=match):
        build()


def _no_real_solution():
    m, x, _ = oscillator()
    m.initial_equation(x**2, -1.0, name="impossible")
    m.initial_equation(m.der(x), 0.0)
    m.simulate([0.0, 1.0])


def test_initialisation_without_solution_raises():
    # reference: x^2 = -1 has no real root
    with pytest.raises(ConvergenceError, match=r"initialisation of model 'oscillator' did not converge.*impossible"):
        _no_real_solution()


@pytest.mark.parametrize(
    "call, error, match",
    [
        (lambda m: m.initial_equation(ca.MX.sym("q"), 0.0), InputError, "MX"),
        (lambda m: m.initial_equation(ca.SX.sym("foo"), 0.0), ModelError, r"unknown symbol\(s\) \['foo'\]"),
        (lambda m: m.initial_equation(ca.SX.zeros(2), ca.SX.zeros(3), name="sz"), InputError, "'sz': lhs has 2"),
        (lambda m: m.initial_equation(ca.SX(0, 1), 0.0, name="e"), InputError, "'e' is empty"),
    ],
    ids=["mx", "unknown_symbol", "sizes", "empty"],
)
def test_initial_equation_bad_inputs(call, error, match):
    with pytest.raises(error, match=match):
        call(oscillator()[0])


# ---------------------------------------------------------------- start values (start, fixed)
# Held-out-style models built through the documented component API (the Modelica Standard
# Library's tutorial mechanics and a DC motor), checked against scipy's solve_ivp on the
# models' minimal ODEs (an independent integrator and formulation).


def _msd(mass_first: bool, **mods):
    """Mass -- SpringDamper(c=10, d=1) -- Fixed (the MSL tutorial), in either declaration order."""
    from gtmodel.modeling import Component, connect
    from gtmodel.modeling.library import translational as tr

    class MassFirst(Component):
        mass = tr.Mass(m=1.0, **mods)
        damper = tr.SpringDamper(c=10.0, d=1.0)
        wall = tr.Fixed()

        def equations(self):
            connect(self.mass.flange_b, self.damper.flange_a)
            connect(self.damper.flange_b, self.wall.flange)

    class WallFirst(Component):
        wall = tr.Fixed()
        damper = tr.SpringDamper(c=10.0, d=1.0)
        mass = tr.Mass(m=1.0, **mods)

        def equations(self):
            connect(self.wall.flange, self.damper.flange_a)
            connect(self.damper.flange_b, self.mass.flange_a)

    return (MassFirst if mass_first else WallFirst)().to_model("msd")


def _msd_reference(t, s0, v0):
    """s'' = -(c s + d s') / m with c = 10, d = 1, m = 1 (scipy, independent of gtmodel)."""
    sol = solve_ivp(lambda _, y: [y[1], -(10.0 * y[0] + y[1])], (t[0], t[-1]), [s0, v0], t_eval=t, rtol=1e-11, atol=1e-12)
    return sol.y[0]


SLOW = pytest.mark.slow  # the index-reduced simulation checks its dummy selection on 1000 points (~2.5 s)


@pytest.mark.parametrize(
    "how, mass_first",
    [("modifier", False), ("x0", True), pytest.param("modifier", True, marks=SLOW), pytest.param("x0", False, marks=SLOW)],
    ids=["modifier-wall_first", "x0-mass_first", "modifier-mass_first", "x0-wall_first"],
)
def test_mass_spring_damper_starts_at_the_users_position(how, mass_first):
    # reference: solve_ivp of the mass's ODE from s = 3 m, v = 10 m/s (the MSL tutorial data);
    # the index reduction keeps mass.s or damper.s_rel as the state depending on the order
    t = np.linspace(0.0, 2.0, 41)
    if how == "modifier":
        res = _msd(mass_first, s=3.0, v=10.0).simulate(t)
    else:
        res = _msd(mass_first).simulate(t, x0={"mass.s": 3.0, "mass.v": 10.0})
    assert res.x["mass.s"][0] == pytest.approx(3.0, abs=1e-12)
    assert res.x["mass.v"][0] == pytest.approx(10.0, abs=1e-12)
    np.testing.assert_allclose(res.x["mass.s"], _msd_reference(t, 3.0, 10.0), atol=SIM_TOL)
    rel = res.x["damper.s_rel"]
    np.testing.assert_allclose(rel, -res.x["mass.s"] if mass_first else res.x["mass.s"], atol=1e-9)


@SLOW
def test_x0_overrides_a_fixed_start():
    # reference: x0 of mass.s replaces the modifier's s = 3 for the run; v stays at its fixed 10
    t = np.linspace(0.0, 1.0, 11)
    res = _msd(True, s=3.0, v=10.0).simulate(t, x0={"mass.s": -1.0})
    np.testing.assert_allclose(res.x["mass.s"], _msd_reference(t, -1.0, 10.0), atol=SIM_TOL)


@pytest.mark.parametrize("mass_first", [True, False], ids=["mass_first", "wall_first"])
def test_structural_simplify_keeps_the_fixed_starts(mass_first):
    # reference: the reduced model (either state kept) starts where the declared one did
    from gtmodel.modeling import structural_simplify

    reduced = structural_simplify(_msd(mass_first, s=3.0, v=10.0))
    flat = reduced.flatten()  # its start values are consistent: mass.s = 3 whichever state was kept
    starts = dict(zip(flat.x_names + flat.z_names, np.concatenate([flat.x_start, flat.z_start])))
    assert starts["mass.s"] == pytest.approx(3.0, abs=1e-12)
    assert starts["damper.s_rel"] == pytest.approx(-3.0 if mass_first else 3.0, abs=1e-12)
    res = reduced.simulate(np.linspace(0.0, 1.0, 11))
    assert {**res.outputs, **res.x, **res.z}["mass.s"][0] == pytest.approx(3.0, abs=1e-12)


def _dc_motor(**mods):
    from gtmodel.modeling import Component, connect
    from gtmodel.modeling.library import electrical as el
    from gtmodel.modeling.library import rotational as rot

    class Motor(Component):
        src = el.ConstantVoltage(V=12.0)
        gnd = el.Ground()
        r = el.Resistor(R=1.0)
        ind = el.Inductor(L=0.05)
        emf = el.EMF(k=0.5)
        rotor = rot.Inertia(J=0.01, **mods)
        friction = rot.Damper(d=0.01)
        fixed = rot.Fixed()

        def equations(self):
            connect(self.src.p, self.r.p)
            connect(self.r.n, self.ind.p)
            connect(self.ind.n, self.emf.p)
            connect(self.emf.n, self.src.n)
            connect(self.src.n, self.gnd.p)
            connect(self.emf.flange, self.rotor.flange_a)
            connect(self.rotor.flange_b, self.friction.flange_b)
            connect(self.friction.flange_a, self.fixed.flange)

    return Motor().to_model("motor")


def test_dc_motor_inertia_starts_at_its_given_angle():
    # reference: solve_ivp of L i' = V - R i - k w, J w' = k i - d w, phi' = w from phi = 1 rad
    # (the EMF's angle is an alias of the rotor's: the rotor's fixed start must survive)
    t = np.linspace(0.0, 0.5, 51)
    res = _dc_motor(phi=1.0).simulate(t)

    def rhs(_, y):
        i, w, _phi = y
        return [(12.0 - 1.0 * i - 0.5 * w) / 0.05, (0.5 * i - 0.01 * w) / 0.01, w]

    ref = solve_ivp(rhs, (0.0, 0.5), [0.0, 0.0, 1.0], t_eval=t, rtol=1e-11, atol=1e-12)
    assert res.x["rotor.phi"][0] == pytest.approx(1.0, abs=1e-12)
    np.testing.assert_allclose(res.x["rotor.phi"], ref.y[2], atol=SIM_TOL)
    np.testing.assert_allclose(res.x["rotor.w"], ref.y[1], atol=1e-5)


def _fixed_angle_pendulum(theta0: float):
    """The Cartesian pendulum (index 3) with x fixed at L sin(theta0), at rest; y a guess below."""
    m = Model("pendulum")
    L, g = 1.0, 9.81
    x = m.state("x", start=L * np.sin(theta0), fixed=True)
    y = m.state("y", start=-0.5)  # a guess: the lower branch
    u = m.state("u", start=0.0, fixed=True)
    v = m.state("v")
    lam = m.algebraic("lam")
    m.equation(m.der(x), u)
    m.equation(m.der(y), v)
    m.equation(m.der(u), -lam * x)
    m.equation(m.der(v), -lam * y - g)
    m.equation(x**2 + y**2, L**2, name="length")
    return m


def test_index3_pendulum_starts_at_its_fixed_angle():
    # reference: solve_ivp of theta'' = -(g/L) sin(theta) from theta0 = 0.6 rad at rest
    theta0 = 0.6
    t = np.linspace(0.0, 2.0, 41)
    res = _fixed_angle_pendulum(theta0).simulate(t, rtol=1e-10, atol=1e-12)
    ref = solve_ivp(lambda _, y: [y[1], -9.81 * np.sin(y[0])], (0.0, 2.0), [theta0, 0.0], t_eval=t, rtol=1e-11, atol=1e-12)
    assert res.x["x"][0] == pytest.approx(np.sin(theta0), abs=1e-12)
    assert res.x["y"][0] == pytest.approx(-np.cos(theta0), abs=1e-10)
    np.testing.assert_allclose(res.x["x"], np.sin(ref.y[0]), atol=SIM_TOL)


def test_a_fixed_start_of_an_algebraic_variable_is_an_initial_condition():
    # reference: y = 2 x with y(0) = 1 fixed => x(0) = 0.5 (x's start 10 a guess); x' = -2 x + 3
    m = Model("first_order")
    x = m.state("x", start=10.0)
    y = m.algebraic("y", start=1.0, fixed=True)
    m.equation(m.der(x), -2.0 * x + 3.0)
    m.equation(y, 2 * x)
    t = np.linspace(0.0, 1.0, 11)
    res = m.simulate(t)
    np.testing.assert_allclose(res.x["x"], 1.5 + (0.5 - 1.5) * np.exp(-2.0 * t), atol=SIM_TOL)


def _inconsistent_starts():
    from gtmodel.modeling import Component, connect
    from gtmodel.modeling.library import translational as tr

    class Both(Component):
        mass = tr.Mass(m=1.0, s=3.0)
        damper = tr.SpringDamper(s_rel=1.0)
        wall = tr.Fixed()

        def equations(self):
            connect(self.mass.flange_b, self.damper.flange_a)
            connect(self.damper.flange_b, self.wall.flange)

    Both().to_model("msd").simulate([0.0, 1.0])


@pytest.mark.parametrize(
    "call, error, match",
    [
        (lambda: _msd(True).simulate([0.0, 1.0], x0={"mass.s": 3.0, "damper.s_rel": 1.0}), ModelError,
         r"over-determined and inconsistent: \['damper.s_rel = 1 \(x0\).*mass.s = 3 \(x0\)"),
        (_inconsistent_starts, ModelError, r"inconsistent: \['damper.s_rel = 1 \(fixed start\).*'mass.s = 3 \(fixed start\)'"),
        (lambda: _msd(True, s={"start": 1.0, "fixed": "yes"}), InputError, r"fixed of variable 's'.*True or False"),
        (lambda: _msd(True, s={"start": 1.0, "fixd": True}), ModelError, r"unknown attribute\(s\) \['fixd'\].*fixed"),
        (lambda: Model("m").state("x", fixed=[True, False]), InputError, r"state 'x' fixed: expected 1 or 1 flags"),
        (lambda: _input_fixed(), ModelError, "an input has no initial"),
        (lambda: _msd(True, s=3.0).simulate([0.0, 1.0], x0={"mass.s": 3.0, "damper.s_rel": 3.0}), ModelError,
         r"damper.s_rel = 3 \(x0\), but the others give -3"),
    ],
    ids=["x0_inconsistent", "starts_inconsistent", "fixed_not_bool", "attribute_typo", "fixed_size", "input_fixed",
         "x0_sign"],
)
def test_start_value_bad_inputs(call, error, match):
    with pytest.raises(error, match=match):
        call()


def _input_fixed():
    from gtmodel.modeling import Input

    Input(fixed=True)


def test_under_specified_initialisation_names_the_missing_state():
    # the pendulum with x fixed and an initial equation on y: u (nothing fixes it) is named
    m = Model("pendulum")
    x = m.state("x", start=0.5, fixed=True)
    y = m.state("y", start=-0.8)
    u = m.state("u")
    v = m.state("v")
    lam = m.algebraic("lam")
    m.equation(m.der(x), u)
    m.equation(m.der(y), v)
    m.equation(m.der(u), -lam * x)
    m.equation(m.der(v), -lam * y - 9.81)
    m.equation(x**2 + y**2, 1.0, name="length")
    m.initial_equation(y, -np.sqrt(0.75), name="y0")  # redundant with x (consistent); no filling from starts
    with pytest.raises(ModelError, match=r"under-determined.*x0 values for 1 of the states \[.*'u'"):
        m.simulate([0.0, 0.1])


def test_a_guess_the_initialisation_moves_is_reported(caplog):
    # x's start 10 is a guess (fixed=False): the steady state x = 1.5 replaces it, with a warning
    m, x, _ = first_order()
    m.initial_equation(m.der(x), 0.0, name="steady")
    with caplog.at_level("WARNING", logger="gtmodel"):
        res = m.simulate(np.linspace(0.0, 1.0, 3))
    assert res.x["x"][0] == pytest.approx(1.5)
    assert "did not keep the start values ['x (start 10, initial value 1.5)']" in caplog.text
