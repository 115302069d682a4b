"""Tests of components, connectors, connect(), modifiers, extends and flattening into a Model.

References: closed forms of small mechanical systems (stated per test), the Modelica
connection semantics (Modelica Language Specification 3.6, section 9.2), and the
minimum-energy double integrator (u(t) = 6 - 12 t for a unit move in 1 s).
"""

from __future__ import annotations

import casadi as ca
import numpy as np
import pandas as pd
import pytest

from gtmodel.errors import GtModelError, InputError, ModelError
from gtmodel.modeling import (
    Component,
    Connector,
    Flow,
    Input,
    Model,
    Optimization,
    Parameter,
    Potential,
    State,
    Variable,
    connect,
    solve,
)
from gtmodel.modeling.library import rotational as rot
from gtmodel.modeling.library import translational as tr

SIM_TOL = 1e-6  # absolute, IDAS at rtol 1e-8 / atol 1e-10 against a closed form


class Oscillator(Component):
    """Fixed -- spring -- mass."""

    fixed = tr.Fixed()
    spring = tr.Spring(c=4.0)
    mass = tr.Mass(m=1.0, s=0.1)

    def equations(self):
        connect(self.fixed.flange, self.spring.flange_a)
        connect(self.spring.flange_b, self.mass.flange_a)


class Axis(Component):
    """A composite with its own (outside) connector: spring -- mass -- flange."""

    ground = tr.Fixed()
    belt = tr.Spring(c=1e4)
    cart = tr.Mass(m=2.0)
    flange = tr.Flange_b("free side of the cart")

    def equations(self):
        connect(self.ground.flange, self.belt.flange_a)
        connect(self.belt.flange_b, self.cart.flange_a)
        connect(self.cart.flange_b, self.flange)


class Machine(Component):
    """Two axes, the first pushed by a force through its outside connector."""

    axis1 = Axis()
    axis2 = Axis(belt={"c": 4e4})
    push = tr.Force()

    def equations(self):
        connect(self.push.flange, self.axis1.flange)


# ---------------------------------------------------------------------- modifiers, extends, names
def test_modifier_sets_parameter_and_start_values():
    osc = Oscillator(spring={"c": 9.0}, mass={"m": 2.0, "s": {"start": 0.2, "lb": -1.0}})
    values = osc.parameter_values()
    assert values["spring.c"][0] == 9.0 and values["mass.m"][0] == 2.0
    dae = osc.to_model().flatten()
    assert dae.x_start[dae.x_vars["mass.s"]][0] == 0.2
    assert dae.x_lb[dae.x_vars["mass.s"]][0] == -1.0


def test_nested_modifiers_merge_with_the_class_ones():
    # Modelica: Machine(axis2(belt(d=...))) keeps the class modifier belt(c=4e4) of axis2
    values = Machine(axis2={"belt": {"s_rel0": 0.1}}, axis1={"cart": {"m": 5.0}}).parameter_values()
    assert values["axis2.belt.c"][0] == 4e4 and values["axis2.belt.s_rel0"][0] == 0.1
    assert values["axis1.cart.m"][0] == 5.0 and values["axis1.belt.c"][0] == 1e4


def test_describe_lists_the_declarations():
    table = Oscillator(spring={"c": 9.0}).describe()
    row = table.set_index("name").loc["spring.c"]
    assert (row["kind"], row["value"], row["unit"]) == ("parameter", 9.0, "N/m")
    assert table.set_index("name").loc["mass.s", "kind"] == "state"
    assert table.set_index("name").loc["mass.flange_a.f", "kind"] == "flow"
    assert table.set_index("name").loc["mass.a", "kind"] == "algebraic"


@pytest.mark.parametrize(
    "modifiers, start, fixed",
    [
        ({}, 0.1, True),  # Oscillator's class modifier mass = Mass(s=0.1): the user's value, fixed
        ({"mass": {"s": {"fixed": False}}}, 0.1, False),  # the start kept, as a guess (nested modifiers merge)
        ({"mass": {"s": 0.3}}, 0.3, True),
        ({"mass": {"s": {"start": 0.3, "fixed": False}}}, 0.3, False),
    ],
    ids=["class_modifier", "released", "outer_value", "outer_guess"],
)
def test_a_start_value_a_user_gives_is_fixed(modifiers, start, fixed):
    # Modelica's start/fixed; the library's own defaults (mass.v) stay guesses
    table = Oscillator(**modifiers).describe().set_index("name")
    assert (table.loc["mass.s", "value"], table.loc["mass.s", "fixed"]) == (start, fixed)
    assert not table.loc["mass.v", "fixed"]
    assert pd.isna(table.loc["spring.c", "fixed"])


def test_class_template_is_not_shared_between_instances():
    a, b = Oscillator(spring={"c": 9.0}), Oscillator()
    assert a.spring is not b.spring
    assert b.parameter_values()["spring.c"][0] == 4.0


def test_hierarchical_names_in_the_flat_model():
    model = Machine().to_model("machine")
    params = model.variables("parameter")
    assert {"axis1.belt.c", "axis2.belt.c", "axis1.cart.m"} <= set(params)
    assert "axis1.cart.s" in model.variables("state")
    assert "push.f" in model.variables("input")


def test_extends_inherits_declarations_and_equations():
    class StiffSpring(tr.Spring):
        c = Parameter(1e6, unit="N/m", description="stiffer default", lb=0.0)
        energy = Variable(unit="J")

        def equations(self):
            super().equations()
            self.equation(self.energy, 0.5 * self.c * self.s_rel**2)

    decl = StiffSpring.declarations()
    assert {"flange_a", "flange_b", "s_rel", "f", "c", "s_rel0", "energy"} <= set(decl)
    assert StiffSpring().parameter_values()["c"][0] == 1e6
    assert StiffSpring(c=5.0).parameter_values()["c"][0] == 5.0

    class Osc(Oscillator):
        spring = StiffSpring(c=9.0)

    # closed form: x = 0.1 cos(3 t) for c = 9, m = 1; energy = c x^2 / 2
    t = np.linspace(0.0, 2.0, 21)
    res = Osc().to_model().simulate(t)
    np.testing.assert_allclose(res.x["mass.s"], 0.1 * np.cos(3.0 * t), atol=SIM_TOL)
    np.testing.assert_allclose(res.z["spring.energy"], 4.5 * (0.1 * np.cos(3.0 * t)) ** 2, atol=SIM_TOL)


def test_parameter_bound_to_the_enclosing_component():
    # closed form: inertia J behind a gear n on a spring c: w = sqrt(c / (n^2 J))
    class Geared(Component):
        n = Parameter(5.0, unit="1", description="gear ratio")
        motor = rot.Inertia(J=0.01, phi=1.0)
        gear = rot.IdealGear(ratio=n)
        spring = rot.Spring(c=50.0)
        fixed = rot.Fixed()

        def equations(self):
            connect(self.motor.flange_b, self.gear.flange_a)
            connect(self.gear.flange_b, self.spring.flange_a)
            connect(self.spring.flange_b, self.fixed.flange)

    model = Geared(n=2.0).to_model()
    assert "n" in model.variables("parameter") and "gear.ratio" not in model.variables("parameter")
    assert Geared(n=2.0).parameter_values()["gear.ratio"][0] == 2.0
    t = np.linspace(0.0, 1.0, 11)
    res = model.simulate(t, p={"n": 4.0})
    np.testing.assert_allclose(res.x["motor.phi"], np.cos(np.sqrt(50.0 / (16.0 * 0.01)) * t), atol=SIM_TOL)


def test_replacing_a_sub_component():
    # closed form: a spring-damper instead of the spring, d = 0 gives the same cos(3 t)
    osc = Oscillator(spring=tr.SpringDamper(c=9.0, d=0.0))
    assert isinstance(osc.spring, tr.SpringDamper)
    t = np.linspace(0.0, 1.0, 11)
    np.testing.assert_allclose(osc.to_model().simulate(t).x["mass.s"], 0.1 * np.cos(3.0 * t), atol=SIM_TOL)


def test_flattened_model_is_a_plain_model():
    model = Oscillator().to_model("osc")
    assert isinstance(model, Model) and model.name == "osc"
    assert "mass.a" in model.variables("algebraic") and not model.outputs


def test_model_call_reaches_the_flattened_model():
    # a component declares an extra algebraic variable and an output through the Model API;
    # closed form: the spring force of the oscillator, -c x = -4 * 0.1 cos(2 t)
    class Probe(Component):
        osc = Oscillator()

        def equations(self):
            force = self.model_call("algebraic", "probe_force")
            self.equation(force, -self.osc.spring.f)
            self.model_call("output", "probe_double", 2.0 * force)

    model = Probe().to_model()
    assert "probe_force" in model.variables("algebraic")
    t = np.linspace(0.0, 1.0, 11)
    res = model.simulate(t)
    np.testing.assert_allclose(res.z["probe_force"], -0.4 * np.cos(2.0 * t), atol=SIM_TOL)
    np.testing.assert_allclose(res.outputs["probe_double"], -0.8 * np.cos(2.0 * t), atol=SIM_TOL)


class RigidGear(Component):
    """Torque -- inertia -- gear -- inertia: a rigid coupling of two inertias with states."""

    torque = rot.Torque()
    motor = rot.Inertia(J=1.0)
    gear = rot.IdealGear(ratio=4.0)
    load = rot.Inertia(J=32.0)

    def equations(self):
        connect(self.torque.flange, self.motor.flange_a)
        connect(self.motor.flange_b, self.gear.flange_a)
        connect(self.gear.flange_b, self.load.flange_a)


def _value(res, name):
    """A trajectory by name: state, algebraic variable or output (eliminated alias)."""
    for group in (res.x, res.z, res.outputs):
        if name in group:
            return group[name]
    raise KeyError(name)


def test_rigid_gear_between_two_inertias_simulates_after_index_reduction():
    # closed form: the load reflected to the motor is J2 / ratio^2 = 2: w1 = tau t / (J1 + 2);
    # the composed model is of index 2 (phi_motor = 4 phi_load between two states)
    model = RigidGear().to_model()
    res = model.simulate(np.linspace(0.0, 1.0, 5), u=3.0)
    np.testing.assert_allclose(_value(res, "motor.w"), 3.0 * res.t / 3.0, atol=SIM_TOL)
    np.testing.assert_allclose(_value(res, "load.w"), res.t / 4.0, atol=SIM_TOL)
    np.testing.assert_allclose(_value(res, "load.phi"), res.t**2 / 8.0, atol=SIM_TOL)


def test_rigid_masses_simulate_after_index_reduction():
    # closed form: two masses joined directly and pushed by F: a = F / (m1 + m2)
    class Rigid(Component):
        push = tr.Force()
        m1 = tr.Mass(m=1.0, L=0.2)
        m2 = tr.Mass(m=3.0, L=0.2, s=0.2)

        def equations(self):
            connect(self.push.flange, self.m1.flange_a)
            connect(self.m1.flange_b, self.m2.flange_a)

    res = Rigid().to_model().simulate(np.linspace(0.0, 1.0, 5), u=2.0)
    np.testing.assert_allclose(_value(res, "m1.s"), 0.5 * 0.5 * res.t**2, atol=SIM_TOL)
    np.testing.assert_allclose(_value(res, "m2.s"), 0.2 + 0.5 * 0.5 * res.t**2, atol=SIM_TOL)
    np.testing.assert_allclose(_value(res, "m2.flange_a.f"), 1.5, atol=SIM_TOL)


# ---------------------------------------------------------------------- connection semantics
def _residuals(model: Model) -> dict[str, ca.SX]:
    return {label: res for label, res in model._equations}


def test_connection_set_of_three_gives_one_flow_sum():
    class Three(Component):
        fixed = tr.Fixed()
        s1 = tr.Spring(c=1.0)
        s2 = tr.Spring(c=2.0)
        mass = tr.Mass()

        def equations(self):
            connect(self.fixed.flange, self.s1.flange_a)
            connect(self.s1.flange_a, self.s2.flange_a)  # set {fixed, s1.a, s2.a}
            connect(self.s1.flange_b, self.mass.flange_a)
            connect(self.s2.flange_b, self.mass.flange_a)

    eqs = _residuals(Three().to_model())
    flow = [k for k in eqs if k.startswith("connect(fixed.flange") and k.endswith(".f")]
    assert len(flow) == 1
    names = {str(s) for s in ca.symvar(eqs[flow[0]])}
    assert names == {"fixed.flange.f", "s1.flange_a.f", "s2.flange_a.f"}
    # closed form: springs in parallel, frequency sqrt(3 / 1)
    res = Three(mass={"s": 0.1}).to_model().simulate(np.linspace(0.0, 1.0, 11))
    np.testing.assert_allclose(res.x["mass.s"], 0.1 * np.cos(np.sqrt(3.0) * res.t), atol=SIM_TOL)


def test_unconnected_flow_is_zero():
    eqs = _residuals(Oscillator().to_model())
    assert "mass.flange_b.f (unconnected)" in eqs
    assert str(eqs["mass.flange_b.f (unconnected)"]) == "mass.flange_b.f"


def test_outside_connector_flow_enters_with_minus_sign():
    # Modelica: connect(cart.flange_b, flange) inside Axis gives cart.flange_b.f - flange.f = 0
    eqs = _residuals(Machine().to_model())
    res = eqs["connect(axis1.cart.flange_b, axis1.flange).f"]
    jac = ca.jacobian(res, ca.vertcat(*ca.symvar(res)))
    coeff = {str(s): float(ca.DM(jac[0, i])) for i, s in enumerate(ca.symvar(res))}
    assert coeff == {"axis1.cart.flange_b.f": 1.0, "axis1.flange.f": -1.0}


def test_force_through_hierarchy_matches_closed_form():
    # closed form: constant force F on the cart (m = 2) held by the belt (c = 1e4):
    # s(t) = F / c (1 - cos(w t)), w = sqrt(c / m); the second axis stays at rest
    t = np.linspace(0.0, 0.2, 41)
    res = Machine().to_model().simulate(t, u=50.0)
    w = np.sqrt(1e4 / 2.0)
    np.testing.assert_allclose(res.x["axis1.cart.s"], 50.0 / 1e4 * (1.0 - np.cos(w * t)), atol=SIM_TOL)
    np.testing.assert_allclose(res.x["axis2.cart.s"], 0.0, atol=SIM_TOL)


def test_springs_in_series_have_an_algebraic_node():
    # the node between two springs is an algebraic position (force balance); closed form:
    # c = c1 c2 / (c1 + c2) = 2, x = 0.1 cos(sqrt(2) t)
    class Series(Component):
        fixed = tr.Fixed()
        s1 = tr.Spring(c=4.0)
        s2 = tr.Spring(c=4.0)
        mass = tr.Mass(s=0.1)

        def equations(self):
            connect(self.fixed.flange, self.s1.flange_a)
            connect(self.s1.flange_b, self.s2.flange_a)
            connect(self.s2.flange_b, self.mass.flange_a)

    model = Series().to_model()
    assert "s1.flange_b.s" in model.variables("algebraic")
    res = model.simulate(np.linspace(0.0, 2.0, 21))
    np.testing.assert_allclose(res.x["mass.s"], 0.1 * np.cos(np.sqrt(2.0) * res.t), atol=SIM_TOL)
    np.testing.assert_allclose(res.z["s1.flange_b.s"], 0.5 * res.x["mass.s"], atol=SIM_TOL)


def test_unused_potential_is_dropped():
    # a potential that no equation uses (here p) is no variable of the model; closed form:
    # the sink integrates the flow it receives: q_sink = -q_source = 2, x' = -q_sink = -2
    class Port(Connector):
        p = Potential(unit="m")
        q = Flow(unit="N")

    class Source(Component):
        port = Port()

        def equations(self):
            self.equation(self.port.q, -2.0)

    class Sink(Component):
        port = Port()
        x = State()

        def equations(self):
            self.equation(self.der(self.x), -self.port.q)

    class Pair(Component):
        src = Source()
        snk = Sink()

        def equations(self):
            connect(self.src.port, self.snk.port)

    model = Pair().to_model()
    assert not {"src.port.p", "snk.port.p"} & set(model.variables("algebraic"))
    res = model.simulate(np.linspace(0.0, 1.0, 3))
    np.testing.assert_allclose(res.x["snk.x"], -2.0 * res.t, atol=SIM_TOL)


def test_user_connector_and_vector_variables():
    class Port(Connector):
        p = Potential(unit="m", shape=2)
        q = Flow(unit="N", shape=2)

    class Anchor(Component):
        port = Port()
        where = Parameter([1.0, 2.0], unit="m")

        def equations(self):
            self.equation(self.port.p, self.where)

    class Body(Component):
        port = Port()
        k = Parameter(3.0, unit="N/m")
        x = State(unit="m", shape=2)

        def equations(self):
            self.equation(self.der(self.x), self.port.q / self.k)
            self.equation(self.port.q, self.k * (self.port.p - self.x))

    class Pair(Component):
        anchor = Anchor()
        body = Body()

        def equations(self):
            connect(self.anchor.port, self.body.port)

    # closed form: x' = p - x from x(0) = 0: x = p (1 - exp(-t))
    t = np.linspace(0.0, 1.0, 11)
    res = Pair().to_model().simulate(t)
    np.testing.assert_allclose(res.x["body.x"], np.outer(1.0 - np.exp(-t), [1.0, 2.0]), atol=SIM_TOL)


# ---------------------------------------------------------------------- downstream: optimisation
def test_optimization_on_a_composed_model():
    # closed form: minimum-energy unit move of a unit mass in 1 s, F(t) = 6 - 12 t
    class Slider(Component):
        push = tr.Force()
        body = tr.Mass(m=1.0)

        def equations(self):
            connect(self.push.flange, self.body.flange_a)

    model = Slider().to_model()
    s, v = model.variables("state")["body.s"], model.variables("state")["body.v"]
    f = model.variables("input")["push.f"]
    opt = Optimization(model, final_time=1.0)
    opt.set_objective(lagrange=f**2)
    for expr, at, value in ((s, "start", 0.0), (v, "start", 0.0), (s, "final", 1.0), (v, "final", 0.0)):
        opt.add_point_constraint(expr, at=at, lb=value, ub=value)
    result = solve(opt, elements=10, points=3, scheme="radau")
    assert result.status == "optimal"
    assert result.objective == pytest.approx(12.0, abs=1e-6)
    np.testing.assert_allclose(result.inputs["push.f"], 6.0 - 12.0 * result.t, atol=1e-5)


# ---------------------------------------------------------------------- bad input
class _Bad(Component):
    """Helper composite whose equations() runs a given callable."""

    fixed = tr.Fixed()
    mass = tr.Mass()
    shaft = rot.Inertia()

    action = None

    def equations(self):
        type(self).action(self)


def _flatten_with(action):
    cls = type("BadCase", (_Bad,), {"action": staticmethod(action)})
    return cls().to_model()


def _composite_without_inner_connection():
    class Hollow(Component):
        mass = tr.Mass()
        flange = tr.Flange_b()

    class Outer(Component):
        h = Hollow()
        fixed = tr.Fixed()

        def equations(self):
            connect(self.fixed.flange, self.h.flange)

    return Outer().to_model()


BAD = [
    ("incompatible", lambda: _flatten_with(lambda c: connect(c.mass.flange_a, c.shaft.flange_a)), ModelError,
     r"incompatible connectors mass\.flange_a \(Flange_a: s, f\) and shaft\.flange_a \(Flange_a: phi, tau\)"),
    ("self", lambda: _flatten_with(lambda c: connect(c.mass.flange_a, c.mass.flange_a)), ModelError,
     r"connect\(mass\.flange_a, mass\.flange_a\): a connector cannot be connected to itself"),
    ("not a connector", lambda: _flatten_with(lambda c: connect(c.mass, c.fixed.flange)), ModelError,
     r"is not a connector \(got Mass\)"),
    ("foreign", lambda: _flatten_with(lambda c: connect(tr.Mass().flange_a, c.fixed.flange)), ModelError,
     r"belongs neither to <root> nor to one of its direct sub-components"),
    ("outside equations", lambda: connect(tr.Mass().flange_a, tr.Mass().flange_b), ModelError,
     r"must be called inside a component's equations\(\)"),
    ("unknown modifier", lambda: tr.Spring(k=2e5), ModelError,
     r"Spring: unknown modifier\(s\) \['k'\]; allowed: \['c', 'f', 's_rel', 's_rel0'\]"),
    ("modifier of a connector", lambda: tr.Spring(flange_a=1.0), ModelError, r"Spring: unknown modifier\(s\) \['flange_a'\]"),
    ("wrong type", lambda: tr.Spring(c="stiff"), InputError, r"Spring\.c: expected a real number, got str 'stiff'"),
    ("bool parameter", lambda: tr.Mass(m=True), InputError, r"Mass\.m: expected a real number, got bool"),
    ("out of bounds", lambda: tr.Spring(c=-1.0), InputError, r"Spring\.c: must be >= 0\.0"),
    ("wrong size", lambda: tr.Spring(c=[1.0, 2.0]), InputError, r"Spring\.c: expected 1 value\(s\), got 2"),
    ("not finite", lambda: rot.Inertia(J=float("nan")), InputError, r"Inertia\.J: expected finite numbers"),
    ("start attribute", lambda: tr.Mass(s={"begin": 1.0}), ModelError, r"Mass\.s: unknown attribute\(s\) \['begin'\]"),
    ("start type", lambda: tr.Mass(s="up"), InputError, r"Mass\.s: start of variable 's' must be numbers"),
    ("nested unknown", lambda: Oscillator(spring={"k": 1.0}), ModelError, r"Spring: unknown modifier\(s\) \['k'\]"),
    ("sub-component value", lambda: Oscillator(spring=5.0), InputError,
     r"Oscillator\.spring: a sub-component modifier must be a dict of modifiers or a Component"),
    ("replacement", lambda: Oscillator(spring=rot.Spring()), ModelError,
     r"Oscillator\.spring: replacement Spring lacks connector\(s\) \['flange_a', 'flange_b'\]"),
    ("symbol outside", lambda: tr.Spring().c, ModelError, r"'c' has a symbol only while the component is flattened"),
    ("equation outside", lambda: tr.Spring().equation(1.0, 2.0), ModelError, r"work only inside equations\(\)"),
    ("der of non-state", lambda: _flatten_with(lambda c: c.equation(c.der(c.mass.flange_a.s), 0.0)), ModelError,
     r"component <root> \(BadCase\): .*der\(\) needs a declared state, got mass\.flange_a\.s"),
    ("size mismatch", lambda: _flatten_with(lambda c: c.equation(ca.vertcat(c.mass.s, c.mass.v), ca.DM([1, 2, 3]))),
     InputError, r"component <root> \(BadCase\): equation 'eq0': lhs has 2 elements but rhs has 3"),
    ("casadi error", lambda: _flatten_with(lambda c: c.equation(ca.mtimes(ca.DM.ones(2, 3), ca.vertcat(c.mass.s, c.mass.v)), 0.0)), ModelError,
     r"component <root> \(BadCase\): error in equations\(\): Matrix product with incompatible dimensions"),
    ("python error", lambda: _flatten_with(lambda c: c.equation(c.mass.nothing, 0.0)), ModelError,
     r"component <root> \(BadCase\): error in equations\(\): 'Mass' object has no attribute 'nothing'"),
    ("foreign binding", lambda: type("Loose", (Component,), {"gear": rot.IdealGear(ratio=Parameter(2.0))})().to_model(),
     ModelError, r"component gear \(IdealGear\): parameter 'ratio' is bound to a Parameter \(unnamed\) that is not declared"),
    ("binding size", lambda: rot.IdealGear(ratio=Parameter([1.0, 2.0])), InputError,
     r"IdealGear\.ratio: bound to a parameter of 2 value\(s\), expected 1"),
    ("model_call", lambda: _flatten_with(lambda c: c.model_call("_vars")), ModelError,
     r"model_call: '_vars' is not a public method of Model"),
    ("inner connection", _composite_without_inner_connection, ModelError,
     r"component h \(Hollow\): its connector h\.flange is connected to nothing inside it"),
    ("unbalanced", lambda: _flatten_with(lambda c: c.equation(c.mass.s, 1.0)).flatten(), ModelError,
     r"scalar equations but .* unknowns"),
]


@pytest.mark.parametrize("make, error, match", [b[1:] for b in BAD], ids=[b[0] for b in BAD])
def test_bad_input_gives_one_named_error(make, error, match):
    with pytest.raises(error, match=match) as info:
        make()
    assert isinstance(info.value, GtModelError)
    # no CasADi traceback chained to the message
    assert not isinstance(info.value.__cause__, RuntimeError)


def test_a_component_may_use_time_in_its_equations():
    # closed form: x' = cos(t), x(0) = 0 gives x = sin(t)
    class Driven(Component):
        x = State(start=0.0, unit="m", description="position")

        def equations(self) -> None:
            self.equation(self.der(self.x), ca.cos(self.time))

    t = np.linspace(0.0, 2.0, 21)
    res = Driven().to_model("driven").simulate(t)
    np.testing.assert_allclose(res.x["x"], np.sin(t), atol=1e-7)
