"""Tests of Pantelides' algorithm, dummy derivatives and structural_simplify.

References: energy conservation and the position constraint (exact invariants), the same
mechanisms in minimal coordinates (a second formulation, an ODE), closed forms.
"""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

from gtmodel.errors import InputError, ModelError
from gtmodel.modeling import Model, Optimization, solve, structural_simplify
from gtmodel.modeling.structure.index_reduction import pantelides, reduced_system, select_dummies
from gtmodel.modeling.structure.analysis import scalarize

from ._dae_builders import angle_pendulum, cartesian_pendulum, slider_crank, slider_crank_minimal

RTOL, ATOL = 1e-10, 1e-12  # IDAS tolerances for the invariants below


@pytest.fixture(scope="module")
def pendulum_run():
    t = np.linspace(0.0, 10.0, 501)
    return t, cartesian_pendulum(theta0=2.0).simulate(t, rtol=RTOL, atol=ATOL)


def test_pantelides_differentiates_the_length_constraint_twice():
    # reference: the index-3 pendulum (Hairer & Wanner): the constraint twice, the velocity
    # definitions once; 2 degrees of freedom remain (11 variables, 9 equations)
    aug = pantelides(scalarize(cartesian_pendulum()))
    assert aug.eq_names[5:] == ["der(length)", "der(vel_x)", "der(vel_y)", "der(der(length))"]
    assert len(aug.syms) - len(aug.res) == 2


@pytest.mark.parametrize(
    "theta0, states",
    [(2.0, ["y", "v"]), (0.1, ["x", "u"])],  # reference: the larger of |x|, |y| is the dummy
    ids=["x_large", "y_large"],
)
def test_dummy_selection_keeps_the_well_conditioned_states(theta0, states):
    m = cartesian_pendulum(theta0)
    s = scalarize(m)
    aug = pantelides(s)
    v = np.concatenate([s.start, np.zeros(len(aug.syms) - s.n_vars)])
    sel = select_dummies(aug, (0.0, v, np.zeros(0), s.p_value))
    assert [aug.names[k] for k in reduced_system(aug, sel)[0]] == states


def test_pendulum_keeps_length_and_energy_over_10_s(pendulum_run):
    # reference: the length constraint x^2 + y^2 = L^2 and energy conservation (exact invariants)
    t, res = pendulum_run
    radius = np.hypot(res.x["x"], res.x["y"])
    assert np.max(np.abs(radius - 1.0)) < 1e-8
    e = res.outputs["energy"]
    assert np.max(np.abs(e - e[0])) / abs(e[0]) < 1e-6
    assert np.any(res.x["x"] > 0.5) and np.any(res.x["x"] < -0.5)  # it swings over x = 0 (dummy switches)


def test_pendulum_switches_dummies_where_the_selection_turns_singular(caplog):
    # reference: from theta0 = 2 the first selection (x dummy, det ~ 2 x) is singular at x = 0,
    # which the pendulum crosses near t = 0.75 s (angle ODE); the switch must come before it
    caplog.set_level("DEBUG", logger="gtmodel")
    t = np.linspace(0.0, 1.2, 61)
    res = cartesian_pendulum(theta0=2.0).simulate(t, rtol=RTOL, atol=ATOL)
    msgs = [r.getMessage() for r in caplog.records if "switched at" in r.getMessage()]
    assert len(msgs) == 1
    first = float(msgs[0].split("[")[1].split(",")[0].rstrip("] s"))
    crossing = t[np.nonzero(np.diff(np.sign(res.x["x"])))[0][0]]
    assert 0.3 < first < crossing


def test_pendulum_matches_minimal_coordinates(pendulum_run):
    # reference: theta'' = -(g/L) sin(theta) integrated as an ODE (a second formulation)
    t, res = pendulum_run
    ref = angle_pendulum(theta0=2.0).simulate(t, rtol=RTOL, atol=ATOL)
    np.testing.assert_allclose(res.x["x"], ref.outputs["pos_x"], atol=1e-6)
    np.testing.assert_allclose(res.x["y"], ref.outputs["pos_y"], atol=1e-6)


def test_slider_crank_matches_minimal_coordinates_and_conserves_energy():
    # reference: Lagrange's equation in the crank angle (slider_crank_minimal) and energy conservation
    t = np.linspace(0.0, 2.0, 201)
    res = slider_crank().simulate(t, rtol=RTOL, atol=ATOL)
    ref = slider_crank_minimal().simulate(t, rtol=RTOL, atol=ATOL)
    np.testing.assert_allclose(res.x["theta"], ref.x["theta"], atol=1e-7)
    np.testing.assert_allclose(res.x["s"], ref.outputs["s"], atol=1e-7)
    e = res.outputs["energy"]
    assert np.max(np.abs(e - e[0])) / e[0] < 1e-6


def test_slider_crank_driven_by_an_input_torque():
    # reference: the work-energy theorem, E(t) - E(0) = tau (theta(t) - theta(0)) for a constant tau
    t = np.linspace(0.0, 1.0, 101)
    res = slider_crank(torque=True).simulate(t, u=0.05, rtol=RTOL, atol=ATOL)
    e, th = res.outputs["energy"], res.x["theta"]
    np.testing.assert_allclose(e - e[0], 0.05 * (th - th[0]), atol=1e-8)
    np.testing.assert_allclose(res.u["tau"], 0.05)


def test_structural_simplify_gives_an_index1_model():
    # reference: the pendulum's own invariants over 0.5 s (no dummy switch needed from theta0 = 2)
    red = structural_simplify(cartesian_pendulum(theta0=2.0))
    flat = red.flatten()
    assert flat.x_names == ["y", "v"]
    assert {"x", "u", "lam", "der_x", "der2_x"} <= set(flat.z_names)
    res = red.simulate(np.linspace(0.0, 0.3, 31), rtol=RTOL, atol=ATOL)
    assert np.max(np.abs(res.z["x"] ** 2 + res.x["y"] ** 2 - 1.0)) < 1e-9


def test_simplified_model_feeds_the_collocation():
    # reference: the angle ODE theta'' = -(g/L) sin(theta) from rest at theta0 = 0.5 (second
    # formulation); Radau collocation with 40 elements is accurate to ~1e-5 here
    red = structural_simplify(cartesian_pendulum(theta0=0.5))
    states = red.variables("state")
    assert list(states) == ["x", "u"]
    opt = Optimization(red, start_time=0.0, final_time=1.0)
    opt.add_point_constraint(states["x"], at="start", lb=np.sin(0.5), ub=np.sin(0.5))
    opt.add_point_constraint(states["u"], at="start", lb=0.0, ub=0.0)
    opt.set_objective(mayer=0 * states["x"])
    res = solve(opt, elements=40, points=3, scheme="radau")
    assert res.status.name.lower() == "optimal"
    ref = angle_pendulum(theta0=0.5).simulate(res.t, rtol=RTOL, atol=ATOL)
    np.testing.assert_allclose(res.states["x"], ref.outputs["pos_x"], atol=1e-4)


def test_index1_model_is_returned_unchanged():
    m = angle_pendulum()
    assert structural_simplify(m) is m


def test_constraint_on_a_state_is_differentiated():
    # reference: x' = z, x = 1 + t^2 / 2  =>  z = t (closed form)
    m = Model("prescribed")
    x = m.state("x", start=1.0)
    z = m.algebraic("z")
    m.equation(m.der(x), z)
    m.equation(x, 1.0 + 0.5 * m.time**2)
    t = np.linspace(0.0, 1.0, 11)
    res = m.simulate(t)
    np.testing.assert_allclose(res.z["z"], t, atol=1e-8)
    np.testing.assert_allclose(res.x["x"], 1.0 + 0.5 * t**2, atol=1e-8)


def _input_in_constraint():
    m = Model("m")
    x = m.state("x")
    z = m.algebraic("z")
    f = m.input("f")
    m.equation(m.der(x), z)
    m.equation(x, f, name="follow")
    m.simulate([0.0, 1.0])


def _singular():
    m = Model("m")
    x = m.state("x")
    y = m.algebraic("y")
    m.algebraic("z")  # in no equation
    m.equation(m.der(x), y)
    m.equation(y, ca.sin(x), name="e1")
    m.equation(2 * y, x, name="e2")
    structural_simplify(m)


@pytest.mark.parametrize(
    "build, match",
    [
        (_input_in_constraint, r"equation 'follow' must be differentiated .* input\(s\) \['f'\]"),
        (_singular, r"structurally singular .* over-determine variables \['x', 'y'\].*\['z'\] are under-determined"),
    ],
    ids=["input_in_constraint", "singular"],
)
def test_reduction_errors(build, match):
    with pytest.raises(ModelError, match=match):
        build()


@pytest.mark.parametrize(
    "call, match",
    [
        (lambda: cartesian_pendulum().simulate([0.0, 1.0], integrator="cvodes"), "use integrator 'idas'"),
        (lambda: cartesian_pendulum().simulate([0.0, 1.0], x0={"lam": 1.0}), "'lam' is not a state"),
        (lambda: cartesian_pendulum().simulate([0.0, 1.0], p={"mass": 1.0}), "no parameter 'mass'"),
        (lambda: cartesian_pendulum().simulate([1.0, 0.0]), "strictly increasing"),
    ],
    ids=["cvodes", "x0_not_state", "parameter_name", "grid"],
)
def test_reduced_simulation_bad_arguments(call, match):
    with pytest.raises(InputError, match=match):
        call()


def _reduced_motor():
    """The DC motor of models/dc_motor.py without its friction (index 2 through its gear), reduced."""
    from gtmodel.modeling.library import electrical as el
    from gtmodel.modeling.library import rotational as rot
    from gtmodel.modeling import Component, connect

    class Motor(Component):
        src, gnd, r, ind, emf = el.SignalVoltage(), el.Ground(), el.Resistor(R=0.5), el.Inductor(L=1e-3), el.EMF(k=0.05)
        rotor, gear, load = rot.Inertia(J=1e-4), rot.IdealGear(ratio=10.0), rot.Inertia(J=0.01)

        def equations(self):
            connect(self.src.p, self.r.p)
            connect(self.r.n, self.ind.p)
            connect(self.ind.n, self.emf.p)
            connect(self.emf.n, self.src.n)
            connect(self.src.n, self.gnd.p)
            connect(self.emf.flange, self.rotor.flange_a)
            connect(self.rotor.flange_b, self.gear.flange_a)
            connect(self.gear.flange_b, self.load.flange_a)

    return structural_simplify(Motor().to_model("motor"))


def test_the_reduction_keeps_the_declared_units():
    # the states the reduction chose, the input, an algebraic variable kept and an alias that
    # became an output keep the library's units
    reduced = _reduced_motor()
    units = reduced.units
    assert all(units[n] == u for n, u in {"ind.i": "A", "src.v": "V", "load.phi": "rad"}.items())
    states = reduced.flatten().x_names
    assert {units.get(s) for s in states} <= {"A", "rad", "rad/s"} and all(s in units for s in states)
    assert units["rotor.phi"] == "rad" and "rotor.phi" in reduced.outputs  # an alias kept as an output


#: The derivatives the reduction of the DC motor keeps as variables and their units by hand:
#: the physical quantity each one is (MSL units: di/dt in A/s, angular acceleration in rad/s2).
MOTOR_DERIVATIVE_UNITS = {
    "der_ind_i": "A/s",  # rate of the armature current
    "der_emf_phi": "rad/s",  # rotor angular velocity
    "der2_emf_phi": "rad/s2",  # rotor angular acceleration
    "der_rotor_w": "rad/s2",
    "der_load_phi": "rad/s",
    "der2_load_phi": "rad/s2",
    "der_load_w": "rad/s2",
}


@pytest.fixture(scope="module")
def motor_units():
    reduced = _reduced_motor()
    return {n for n, v in reduced._vars.items() if v.kind == "algebraic" and n.startswith("der")}, reduced.units


@pytest.mark.parametrize("name, unit", MOTOR_DERIVATIVE_UNITS.items())
def test_a_derivative_the_reduction_keeps_has_the_unit_of_its_variable_per_second(motor_units, name, unit):
    # a dummy derivative der(x) is x's unit / s (der2: / s2), not a variable without a unit
    kept, units = motor_units
    assert name in kept
    assert units.get(name) == unit


def test_every_derivative_the_reduction_keeps_has_a_unit(motor_units):
    kept, units = motor_units
    assert sorted(n for n in kept if not units.get(n)) == []
    assert kept == set(MOTOR_DERIVATIVE_UNITS)  # the table above is the whole list
