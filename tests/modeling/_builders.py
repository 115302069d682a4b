"""Builders of small reference problems shared by the modelling-layer tests."""

from __future__ import annotations

import casadi as ca

from gtmodel.modeling import Model, Optimization


def double_integrator():
    """Double integrator x'' = u as a two-state model; returns (model, x, v, u)."""
    m = Model("double_integrator")
    x = m.state("x")
    v = m.state("v")
    u = m.input("u")
    m.equation(m.der(x), v)
    m.equation(m.der(v), u)
    m.output("kinetic", 0.5 * v**2)
    return m, x, v, u


def rest_to_rest(opt: Optimization, x, v, distance=1.0) -> None:
    """x(t0) = v(t0) = 0, x(tf) = distance, v(tf) = 0."""
    opt.add_point_constraint(x, at="start", lb=0.0, ub=0.0, name="x_start")
    opt.add_point_constraint(v, at="start", lb=0.0, ub=0.0, name="v_start")
    opt.add_point_constraint(x, at="final", lb=distance, ub=distance, name="x_final")
    opt.add_point_constraint(v, at="final", lb=0.0, ub=0.0, name="v_final")


def min_energy_problem():
    """Fixed-time (1 s) minimum-energy rest-to-rest transfer over distance 1."""
    m, x, v, u = double_integrator()
    opt = Optimization(m, start_time=0.0, final_time=1.0)
    opt.set_objective(lagrange=u**2)
    rest_to_rest(opt, x, v)
    return opt




def min_energy_over_distance_parameter():
    """The minimum-energy transfer with the distance as model parameter ``D`` (default 1):
    ``min int u^2`` over 1 s, rest to rest over ``D``; closed-form cost ``12 D^2``."""
    m = Model("di_param")
    dist = m.parameter("D", 1.0)
    x, v, u = m.state("x"), m.state("v"), m.input("u")
    m.equation(m.der(x), v)
    m.equation(m.der(v), u)
    opt = Optimization(m, final_time=1.0)
    opt.set_objective(lagrange=u**2)
    opt.add_point_constraint(x, at="start", lb=0.0, ub=0.0)
    opt.add_point_constraint(v, at="start", lb=0.0, ub=0.0)
    opt.add_point_constraint(x - dist, at="final", lb=0.0, ub=0.0)
    opt.add_point_constraint(v, at="final", lb=0.0, ub=0.0)
    return opt


def nonlinear_loop(name="loop", output=True):
    """An algebraic loop through a nonlinear equation, z + 0.5 sin(z) = x, xdot = u - z (output zz = z if ``output``)."""
    m = Model(name)
    x = m.state("x", start=1.0)
    z = m.algebraic("z", start=0.5)
    u = m.input("u")
    m.equation(m.der(x), u - z)
    m.equation(z + 0.5 * ca.sin(z), x)
    if output:
        m.output("zz", z)
    return m
