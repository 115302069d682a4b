"""An optimal control problem over a component model as the user writes it (higher index).

The user's model: a DC motor (SignalVoltage, Resistor, Inductor, EMF, Ground), an IdealGear
of ratio 50 and a load (Inertia) with a Damper, composed from the library. ``flatten()``
refuses it (the gear ties the two inertias: index 2); ``Optimization`` reduces it as
``simulate()`` does. Conditions are written on variables of each kind the reduction leaves:
a state, an algebraic variable, an eliminated alias (an output of the reduced model) and a
declared output. Reference: the user's (unreduced) model simulated by ``simulate()`` from
the physical rest state under the optimal input (independent of the transcription), and
the gear's closed-form kinematics ``motor.w = ratio load.w`` at t = 0.
"""

from __future__ import annotations

import numpy as np
import pytest

from gtmodel.errors import ModelError
from gtmodel.modeling import Component, Optimization, connect, solve
from gtmodel.modeling.library import electrical as el
from gtmodel.modeling.library import rotational as rot

RATIO = 50.0
V_MAX = 24.0  # V, the bound of the source voltage
T_FINAL = 0.5  # s
SIM_TOL = 1e-2  # rad, the simulated final angle vs the condition (ZOH of the input on 200 steps: 4e-5 measured)


class DCMotorGearLoad(Component):
    source = el.SignalVoltage()
    resistor = el.Resistor(R=1.0)
    inductor = el.Inductor(L=0.02)
    emf = el.EMF(k=0.05)
    ground = el.Ground()
    motor = rot.Inertia(J=1e-5)
    gear = rot.IdealGear(ratio=RATIO)
    load = rot.Inertia(J=0.01)
    damper = rot.Damper(d=0.01)
    fixed = rot.Fixed()

    def equations(self):
        connect(self.source.p, self.resistor.p)
        connect(self.resistor.n, self.inductor.p)
        connect(self.inductor.n, self.emf.p)
        connect(self.emf.n, self.source.n)
        connect(self.source.n, self.ground.p)
        connect(self.emf.flange, self.motor.flange_a)
        connect(self.motor.flange_b, self.gear.flange_a)
        connect(self.gear.flange_b, self.load.flange_a)
        connect(self.load.flange_b, self.damper.flange_a)
        connect(self.damper.flange_b, self.fixed.flange)
        self.output("load_deg", self.load.phi * (180.0 / np.pi))


# kind of variable -> (start angle variable and value, final angle variable and value);
# after the reduction: emf.phi is a state, load.phi algebraic, motor.phi an eliminated
# alias (an output of the reduced model), load_deg a declared output
CASES = {
    "state": ("emf.phi", 0.0, "emf.phi", RATIO),
    "algebraic": ("load.phi", 0.0, "load.phi", 1.0),
    "alias": ("motor.phi", 0.0, "motor.phi", RATIO),
    "output": ("load_deg", 0.0, "load_deg", 180.0 / np.pi),
}


def _symbol(m, name):
    found = {**m.outputs, **{k: v for kind in ("state", "algebraic", "input") for k, v in m.variables(kind).items()}}
    return found[name]


@pytest.fixture(scope="module")
def user_model():
    return DCMotorGearLoad().to_model("dc_motor")


def _solve(m, start, final):
    opt = Optimization(m, final_time=T_FINAL)
    u = m.variables("input")["source.v"]
    for name, value in {start[0]: start[1], "load.w": 0.0, "inductor.i": 0.0}.items():
        opt.add_point_constraint(_symbol(m, name), at="start", lb=value, ub=value)
    for name, value in {final[0]: final[1], "load.w": 0.0}.items():
        opt.add_point_constraint(_symbol(m, name), at="final", lb=value, ub=value)
    opt.set_bounds(u, -V_MAX, V_MAX)
    opt.set_objective(lagrange=u**2)
    return opt, solve(opt, elements=40, points=3)


def test_the_model_as_written_does_not_flatten_and_is_reduced(user_model):
    with pytest.raises(ModelError, match="structural_simplify"):
        user_model.flatten()
    opt = Optimization(user_model, final_time=T_FINAL)
    assert opt.user_model is user_model and opt.model is not user_model
    flat = opt.model.flatten()
    assert flat.x_names == ["inductor.i", "emf.phi", "motor.w"]
    assert "load.phi" in flat.z_names and "motor.phi" in opt.model.outputs and "load_deg" in opt.model.outputs


def test_start_conditions_on_algebraic_variables_hold_at_t0(user_model):
    # the case: start and end conditions on load.phi and load.w (algebraic after the
    # reduction). Reference: the gear's kinematics motor.w = ratio load.w at t = 0, the bound
    # of the input, and the verification by simulation of the transcription's result
    opt, res = _solve(user_model, ("load.phi", 0.0), ("load.phi", 1.0))
    assert res.status == "optimal" and res.verification.passed
    assert abs(res.states["motor.w"][0]) < 1e-9 and abs(res.algebraics["load.w"][0]) < 1e-9
    assert abs(res.algebraics["load.w"][1] * RATIO - res.states["motor.w"][1]) < 1e-9
    assert np.max(np.abs(res.inputs["source.v"])) <= V_MAX + 1e-7
    assert res.collocation.point_kinds()[0] == "start"


@pytest.mark.slow
@pytest.mark.parametrize("kind", CASES)
def test_conditions_on_each_kind_of_variable_hold_in_a_simulation(user_model, kind):
    # reference: simulate() of the user's model from rest (load.phi = load.w = 0, no current)
    # under the optimal input; and the gear's kinematics at t = 0
    s_name, s_val, f_name, f_val = CASES[kind]
    opt, res = _solve(user_model, (s_name, s_val), (f_name, f_val))
    assert res.status == "optimal"
    table = {**res.states, **res.algebraics, **res.outputs, **res.inputs}
    # at t = 0 the motor does not already move (the 4.81 rad/s): motor.w = ratio load.w = 0
    assert abs(table["motor.w"][0]) < 1e-9 and abs(table["load.w"][0]) < 1e-9
    assert abs(table[f_name][-1] - f_val) < 1e-7
    # no written input outside the bound the NLP respects (the 29.7 V at t = 0)
    assert np.max(np.abs(res.inputs["source.v"])) <= V_MAX + 1e-7
    t = np.linspace(0.0, T_FINAL, 201)
    u = res.sample(0.5 * (t[1:] + t[:-1]))["inputs"]["source.v"]  # midpoint of each hold interval
    sim = user_model.simulate(t, x0={"load.phi": 0.0, "load.w": 0.0, "inductor.i": 0.0}, u=np.append(u, u[-1]))
    assert abs(sim.x["load.phi"][-1] - 1.0) < SIM_TOL
    assert abs(sim.x["load.w"][-1]) < 20 * SIM_TOL


def test_user_symbols_and_reduced_symbols_mean_the_same(user_model):
    # reference: the same problem declared through the reduced model's own symbols
    _, a = _solve(user_model, ("load.phi", 0.0), ("load.phi", 1.0))
    opt = Optimization(user_model, final_time=T_FINAL)
    r = opt.model
    u = r.variables("input")["source.v"]
    for name, value in {"load.phi": 0.0, "load.w": 0.0, "inductor.i": 0.0}.items():
        opt.add_point_constraint(_symbol(r, name), at="start", lb=value, ub=value)
    for name, value in {"load.phi": 1.0, "load.w": 0.0}.items():
        opt.add_point_constraint(_symbol(r, name), at="final", lb=value, ub=value)
    opt.set_bounds(u, -V_MAX, V_MAX)
    opt.set_objective(lagrange=u**2)
    b = solve(opt, elements=40, points=3)
    assert a.objective == pytest.approx(b.objective, rel=1e-9)


def test_bounds_and_guesses_on_an_output(user_model):
    # reference: load_deg = 180 / pi load.phi (declared output): a bound on it is a path
    # constraint; a guess on it is the guess of load.phi it is affine in (pi / 180 per degree)
    opt = Optimization(user_model, final_time=T_FINAL)
    out = user_model.outputs["load_deg"]
    opt.set_bounds(out, -1.0, 30.0)
    assert opt.path_constraints[-1].name.startswith("bounds of")
    assert float(opt.path_constraints[-1].ub[0]) == 30.0
    opt.set_initial_guess(out, 90.0)
    assert float(np.ravel(opt.initial_guesses["load.phi"])[0]) == pytest.approx(np.pi / 2, rel=1e-12)


def test_path_bounds_on_algebraic_variables_hold_at_t0_too(user_model):
    # reference: the bound itself, at every written time (t0 is no collocation point: the
    # bound is imposed on the algebraic variables consistent with the start there)
    opt = Optimization(user_model, final_time=T_FINAL)
    m = opt.model
    u, z = m.variables("input")["source.v"], m.variables("algebraic")
    for name, value in {"load.phi": 0.0, "load.w": 0.0}.items():
        opt.add_point_constraint(z[name], at="start", lb=value, ub=value)
    opt.add_point_constraint(z["load.phi"], at="final", lb=1.0, ub=1.0)
    opt.set_bounds(z["resistor.v"], -5.0, 5.0)  # the voltage over the resistor: |i| <= 5 A
    opt.set_bounds(u, -V_MAX, V_MAX)
    opt.set_objective(lagrange=u**2)
    res = solve(opt, elements=40, points=3)
    assert res.status == "optimal"
    assert np.max(np.abs(res.algebraics["resistor.v"])) <= 5.0 + 1e-7
