"""Tests of gtmodel.modeling.simulation.integration: piecewise-constant inputs that change on the grid.

A composed model with a ``translational.Force`` source has algebraic variables that
follow the input directly (the flange force); IDAS does not make them consistent again
where the input jumps, so the simulation restarts there (module docstring).

References: the closed form of two masses joined by a spring and pushed by a
piecewise-constant force (centre of mass and relative coordinate, exact per interval);
the same model written as a pure ODE; a direct single ``casadi.integrator`` run (the
behaviour before the restarts, for models that do not need them).
"""

from __future__ import annotations


import casadi as ca
import numpy as np
import pytest

from gtmodel.errors import ConvergenceError, InputError
from gtmodel.modeling import Component, Model, connect
from gtmodel.modeling.library import rotational as rot
from gtmodel.modeling.library import translational as tr
from gtmodel.modeling.simulation.integration import input_segments

M1, M2, C, D = 1.0, 2.0, 100.0, 3.0
SIM_TOL = 1e-7  # vs closed form at rtol = 1e-8 / atol = 1e-10 (positions of order 0.1 m)


class PushedTwoMass(Component):
    """Force -> m1 -- spring -- m2 (index 1: flattens as it is)."""

    push = tr.Force()
    m1 = tr.Mass(m=M1)
    spring = tr.Spring(c=C)
    m2 = tr.Mass(m=M2)

    def equations(self):
        connect(self.push.flange, self.m1.flange_a)
        connect(self.m1.flange_b, self.spring.flange_a)
        connect(self.spring.flange_b, self.m2.flange_a)


class PushedDampedTwoMass(PushedTwoMass):
    """A damper in parallel to the spring (higher index: the structured simulation)."""

    damper = tr.Damper(d=D)

    def equations(self):
        super().equations()
        connect(self.m1.flange_b, self.damper.flange_a)
        connect(self.damper.flange_b, self.m2.flange_a)


class PushedTwoMassWithStop(PushedTwoMass):
    """A when-clause (m2 bounces back at 5 cm): the event simulation."""

    def equations(self):
        super().equations()
        self.model_call("when", self.m2.s - 0.05, reinit=[(self.m2.v, -self.m2.v)], name="bounce")


def two_mass_closed_form(t, f):
    """Positions of m1, m2 for the force ``f[k]`` on ``[t_k, t_k+1)``, at rest at 0 at ``t_0``.

    Centre of mass ``xc'' = F / M``; relative coordinate ``r = s2 - s1`` with
    ``r'' + w^2 r = -F / m1``, ``w^2 = c M / (m1 m2)``: exact per interval.
    """
    mt = M1 + M2
    w = np.sqrt(C * mt / (M1 * M2))
    xc = vc = r = rd = 0.0
    s1, s2 = [0.0], [0.0]
    for h, fk in zip(np.diff(t), f):
        req = -fk * M2 / (C * mt)
        xc, vc = xc + vc * h + fk / (2.0 * mt) * h**2, vc + fk / mt * h
        r, rd = req + (r - req) * np.cos(w * h) + rd / w * np.sin(w * h), -(r - req) * w * np.sin(w * h) + rd * np.cos(w * h)
        s1.append(xc - M2 / mt * r)
        s2.append(xc + M1 / mt * r)
    return np.array(s1), np.array(s2)


def pure_ode(d=D):
    """:class:`PushedDampedTwoMass` (``d = 0``: :class:`PushedTwoMass`) by hand as an ODE."""
    m = Model("two_mass_ode")
    s1, v1, s2, v2 = (m.state(n) for n in ("m1.s", "m1.v", "m2.s", "m2.v"))
    f = m.input("push.f")
    fs = C * (s2 - s1) + d * (v2 - v1)  # spring-damper force on m1
    m.equation(m.der(s1), v1)
    m.equation(m.der(s2), v2)
    m.equation(M1 * m.der(v1), f + fs)
    m.equation(M2 * m.der(v2), -fs)
    return m


def _grid(n):
    return np.linspace(0.0, 1.0, n + 1)


def _square(n, period):
    """+-5 N square wave switching every ``period`` samples, ``(n,)``."""
    return np.where((np.arange(n) // period) % 2 == 0, 5.0, -5.0)


@pytest.mark.parametrize(
    "u",
    [
        np.where(_grid(100)[:-1] < 0.5, 5.0, -5.0),  # the step 5 N -> -5 N at 0.5 s
        _square(100, 7),  # square wave, segments of 7 samples
        _square(100, 1),  # a change at every sample
    ],
    ids=["step", "square7", "every_sample"],
)
def test_force_jumps_match_closed_form(u):
    # reference: two_mass_closed_form (exact per interval)
    t = _grid(100)
    res = PushedTwoMass().to_model("two").simulate(t, u=u)
    s1, s2 = two_mass_closed_form(t, u)
    np.testing.assert_allclose(res.x["m1.s"], s1, atol=SIM_TOL)
    np.testing.assert_allclose(res.x["m2.s"], s2, atol=SIM_TOL)
    # the algebraic variables follow the input (flange force) and the spring at every point
    np.testing.assert_allclose(res.z["push.flange.f"], -np.append(u, u[-1]), atol=1e-9)
    np.testing.assert_allclose(res.z["spring.f"], C * (s2 - s1), atol=1e2 * SIM_TOL)


def test_callable_input_with_jump():
    # reference: two_mass_closed_form with the zero-order hold of u(t)
    t = _grid(50)
    res = PushedTwoMass().to_model("two").simulate(t, u=lambda tk: 5.0 if tk < 0.3 else -2.0)
    s1, s2 = two_mass_closed_form(t, np.where(t[:-1] < 0.3, 5.0, -2.0))
    np.testing.assert_allclose(res.x["m1.s"], s1, atol=SIM_TOL)
    np.testing.assert_allclose(res.x["m2.s"], s2, atol=SIM_TOL)


def test_time_in_the_algebraic_equation_is_shifted_per_segment():
    # reference: z = u + sin(t), x' = z, x(0) = 0  =>  x = int u + 1 - cos(t) (exact)
    m = Model("timed")
    x = m.state("x")
    z = m.algebraic("z")
    u = m.input("u")
    m.equation(m.der(x), z)
    m.equation(z, u + ca.sin(m.time))
    t = np.linspace(0.5, 3.5, 31)  # t0 != 0: the segments start at their own times
    uk = np.where(np.arange(30) % 4 < 2, 1.0, -1.0)
    res = m.simulate(t, u=uk)
    x_ref = np.concatenate([[0.0], np.cumsum(uk * np.diff(t))]) + np.cos(t[0]) - np.cos(t)
    np.testing.assert_allclose(res.x["x"], x_ref, atol=SIM_TOL)
    np.testing.assert_allclose(res.z["z"], np.append(uk, uk[-1]) + np.sin(t), atol=1e-9)


@pytest.mark.parametrize(
    "cls, name",
    [(PushedDampedTwoMass, "structured"), (PushedTwoMassWithStop, "events")],
)
def test_force_square_wave_in_the_structured_and_event_simulations(cls, name):
    # reference: the same model as a pure ODE (structured); two_mass_closed_form up to the
    # first bounce (events)
    t = _grid(100)
    u = _square(100, 5) + (5.0 if name == "events" else 0.0)  # 10 N / 0 N: m2 reaches the stop
    res = cls().to_model(name).simulate(t, u=u)
    if name == "structured":
        ref = pure_ode().simulate(t, u=u)
        s1, s2 = ref.x["m1.s"], ref.x["m2.s"]
        before = np.ones(t.size, bool)
    else:
        s1, s2 = two_mass_closed_form(t, u)
        assert len(res.events) >= 1 and res.events[0].t > 0.1  # m2 reaches 5 cm after 2 changes
        before = t < res.events[0].t
    np.testing.assert_allclose(res.x["m1.s"][before], s1[before], atol=SIM_TOL)
    np.testing.assert_allclose(res.x["m2.s"][before], s2[before], atol=SIM_TOL)
    # at each change the values consistent with the new input are reported (right limit)
    np.testing.assert_allclose(res.z["push.flange.f"], -np.append(u, u[-1]), atol=1e-9)


def _single_run(model, t, u, plugin):
    """The single ``casadi.integrator`` run that simulate_model made before the restarts."""
    dae = model.flatten()
    dd = {"t": dae.t, "x": dae.x, "u": dae.u, "p": dae.p, "ode": dae.ode_expr}
    if dae.nz:
        dd.update(z=dae.z, alg=dae.alg_expr)
    opts = {"reltol": 1e-8, "abstol": 1e-10, "show_eval_warnings": False, "disable_internal_warnings": True}
    F = ca.integrator("ref", plugin, dd, float(t[0]), list(t), opts)
    u_int = np.broadcast_to(np.asarray(u, float).reshape(-1, 1), (t.size - 1, 1))
    res = F(x0=dae.x_start, z0=dae.z_start, p=dae.parameter_vector(None), u=np.vstack([u_int[:1], u_int]).T)
    return np.array(res["xf"]).T


@pytest.mark.parametrize(
    "model, u, plugin",
    [
        (PushedTwoMass().to_model("two"), 5.0, "idas"),  # DAE, constant input: one run
        (pure_ode(), _square(100, 7), "idas"),  # ODE, changing input: one run
        (pure_ode(), _square(100, 50), "cvodes"),
    ],
    ids=["dae_constant", "ode_idas", "ode_cvodes"],
)
def test_models_without_restarts_are_unchanged(model, u, plugin):
    # reference: the direct single integrator run (bit-identical)
    t = _grid(100)
    res = model.simulate(t, u=u, integrator=plugin)
    x = np.column_stack([res.x[k] for k in model.flatten().x_vars])
    np.testing.assert_array_equal(x, _single_run(model, t, u, plugin))


@pytest.mark.parametrize("integrator", ["cvodes", "idas"])
def test_ode_square_wave_restarts_where_one_run_fails(integrator):
    # reference: two_mass_closed_form (the pure ODE, no damper). One CVODES run over the
    # 5-sample square wave stops with CV_ERR_FAILURE; the simulation then restarts at each change
    t = _grid(100)
    u = _square(100, 5)
    res = pure_ode(0.0).simulate(t, u=u, integrator=integrator)
    s1, s2 = two_mass_closed_form(t, u)
    np.testing.assert_allclose(res.x["m1.s"], s1, atol=SIM_TOL)
    np.testing.assert_allclose(res.x["m2.s"], s2, atol=SIM_TOL)


@pytest.mark.parametrize(
    "u, expected",
    [
        (np.zeros((5, 0)), [0]),
        (np.array([[1.0], [1.0], [2.0], [2.0], [1.0]]), [0, 2, 4]),
        (np.array([[1.0, 0.0], [1.0, 1.0], [1.0, 1.0]]), [0, 1]),
    ],
    ids=["no_inputs", "scalar", "vector"],
)
def test_input_segments(u, expected):
    # reference: the changes counted by hand
    np.testing.assert_array_equal(input_segments(u), expected)


def test_input_changing_every_sample_on_1000_samples_builds_one_integrator(monkeypatch):
    """1000 input segments of one length share one integrator (its cache), not one each.

    Reference: the closed form at the end. The cost that matters (building a SUNDIALS
    integrator per segment) is counted, not timed: speed belongs in the benchmarks.
    """
    built = []
    real = ca.integrator

    def counting(*args, **kwargs):
        built.append(args[0])
        return real(*args, **kwargs)

    monkeypatch.setattr(ca, "integrator", counting)
    t = _grid(1000)
    u = _square(1000, 1)
    res = PushedTwoMass().to_model("two").simulate(t, u=u)
    s1, _ = two_mass_closed_form(t, u)
    np.testing.assert_allclose(res.x["m1.s"], s1, atol=SIM_TOL)
    assert len(built) == 1, built


# ---------------------------------------------------------------- integrator options


class TwoInertiaDrive(Component):
    """Torque -> motor inertia -- shaft spring -- load inertia (index 1), J = 1 kg m^2, c = 1e4 N m/rad."""

    torque = rot.Torque()
    motor = rot.Inertia(J=1.0)
    shaft = rot.Spring(c=1e4)
    load = rot.Inertia(J=1.0)

    def equations(self):
        connect(self.torque.flange, self.motor.flange_a)
        connect(self.motor.flange_b, self.shaft.flange_a)
        connect(self.shaft.flange_b, self.load.flange_a)


def test_two_inertia_drive_at_rtol_1e_10_needs_and_takes_a_higher_step_limit():
    # reference: closed form from rest under 1 N m: centre phi_c = t^2 / 4, relative angle
    # r = -(1 - cos(w t)) / (J w^2), w = sqrt(2 c / J); motor phi_c - r / 2, load phi_c + r / 2
    model = TwoInertiaDrive().to_model("drive")
    t = np.array([0.0, 10.0])  # one output interval: about 14,000 steps at rtol 1e-10
    tight = dict(u=1.0, rtol=1e-10, atol=1e-12)
    with pytest.raises(ConvergenceError, match="TOO_MUCH_WORK"):
        model.simulate(t, **tight, options={"suppress_algebraic": True})
    res = model.simulate(t, **tight, options={"suppress_algebraic": True, "max_num_steps": 100_000})
    w = np.sqrt(2e4)
    rel = -(1.0 - np.cos(w * t)) / w**2
    np.testing.assert_allclose(res.x["motor.phi"], t**2 / 4 - rel / 2, rtol=0, atol=1e-6)
    np.testing.assert_allclose(res.x["load.phi"], t**2 / 4 + rel / 2, rtol=0, atol=1e-6)


@pytest.mark.parametrize("integrator", ["idas", "cvodes"])
def test_max_step_size_does_not_step_over_a_short_pulse(integrator):
    # reference: x' = exp(-((t - 0.5) / 1e-3)^2) from 0: x(1) = 1e-3 sqrt(pi) (a Gaussian's
    # integral); one output interval, so without a step limit the integrator may not see it
    m = Model("pulse")
    x = m.state("x")
    m.equation(m.der(x), ca.exp(-(((m.time - 0.5) / 1e-3) ** 2)))
    res = m.simulate([0.0, 1.0], integrator=integrator, options={"max_step_size": 1e-4, "max_num_steps": 100_000})
    assert res.x["x"][-1] == pytest.approx(1e-3 * np.sqrt(np.pi), rel=1e-5)


@pytest.mark.parametrize(
    "options, integrator, match",
    [
        ({"max_steps": 10}, "idas", r"unknown integrator option\(s\) \['max_steps'\]; allowed: .*'max_num_steps'"),
        ({"max_num_steps": 0}, "idas", r"options\['max_num_steps'\]: expected a positive integer, got 0"),
        ({"max_num_steps": 1.5}, "idas", r"options\['max_num_steps'\]: expected a positive integer"),
        ({"max_num_steps": True}, "idas", r"options\['max_num_steps'\]: expected a positive integer"),
        ({"rtol": -1e-8}, "idas", r"options\['rtol'\]: expected a positive finite number"),
        ({"max_step_size": float("nan")}, "idas", r"options\['max_step_size'\]: expected a positive finite"),
        ({"max_order": 6}, "idas", r"options\['max_order'\]: expected an integer from 1 to 5"),
        ({"min_step_size": 1e-9}, "idas", r"'min_step_size' is an option of cvodes only, not of 'idas'"),
        ({"suppress_algebraic": True}, "cvodes", r"'suppress_algebraic' is an option of idas only"),
        ({"suppress_algebraic": 1}, "idas", r"options\['suppress_algebraic'\]: expected True or False"),
        ([("rtol", 1e-6)], "idas", r"options: expected a mapping"),
    ],
    ids=["unknown", "zero_steps", "float_steps", "bool_steps", "negative_rtol", "nan_step", "order_6",
         "min_step_idas", "suppress_cvodes", "suppress_int", "not_mapping"],
)
def test_bad_integrator_options_are_refused_by_name(options, integrator, match):
    m = Model("decay")
    x = m.state("x", start=1.0)
    m.equation(m.der(x), -x)
    with pytest.raises(InputError, match=match):
        m.simulate([0.0, 1.0], integrator=integrator, options=options)
