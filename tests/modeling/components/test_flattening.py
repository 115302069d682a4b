"""Flattening names what a user left open: connectors with no connect() (their flow is zero, silently), floating subsystems.

Reference: the Modelica Language Specification 3.6, sec. 9.2 (an unconnected connector's
flow variables are set to zero), and a DC motor whose circuit is broken at one pin: no
current flows, so the motor never turns.
"""

from __future__ import annotations

import logging

import numpy as np
import pytest

from gtmodel.modeling import Component, connect
from gtmodel.modeling.library import electrical as el
from gtmodel.modeling.library import rotational as rot


def _motor(broken: bool):
    class Motor(Component):
        source = el.ConstantVoltage(V=12.0)
        ground = el.Ground()
        r = el.Resistor(R=1.0)
        ind = el.Inductor(L=0.05)
        emf = el.EMF(k=0.5)
        rotor = rot.Inertia(J=0.01)
        friction = rot.Damper(d=0.01)
        fixed = rot.Fixed()

        def equations(self):
            connect(self.source.p, self.r.p)
            if not broken:  # the user's mistake: this line forgotten
                connect(self.r.n, self.ind.p)
            connect(self.ind.n, self.emf.p)
            connect(self.emf.n, self.source.n)
            connect(self.source.n, self.ground.p)
            connect(self.emf.flange, self.rotor.flange_a)
            connect(self.rotor.flange_b, self.friction.flange_b)
            connect(self.friction.flange_a, self.fixed.flange)

    return Motor().to_model("motor")


@pytest.mark.parametrize("broken, expected", [
    (True, ["component motor: connector(s) left open (no connect(), so their flow is zero, as if nothing were attached): "
            "r.n (i = 0), ind.p (i = 0)"]),
    (False, []),
])
def test_a_connector_left_open_is_named_at_flatten(caplog, broken, expected):
    with caplog.at_level(logging.WARNING, logger="gtmodel"):
        model = _motor(broken)
    assert model.warnings == expected
    assert [r.getMessage() for r in caplog.records if "left open" in r.getMessage()] == expected


def test_the_broken_motor_indeed_never_moves():
    # the reason for the warning: with the circuit open no current flows and the rotor stays at rest
    from gtmodel.modeling.structure.index_reduction import structural_simplify

    res = structural_simplify(_motor(True)).simulate(np.linspace(0.0, 0.5, 11))
    assert np.max(np.abs(res.x["rotor.w"] if "rotor.w" in res.x else res.z["rotor.w"])) < 1e-9


def test_a_subsystem_that_floats_is_named_at_flatten(caplog):
    # the user's mistake: the load (gear and inertia) never connected to the motor's shaft
    class Drive(Component):
        source = el.ConstantVoltage(V=12.0)
        ground = el.Ground()
        emf = el.EMF(k=0.5)
        rotor = rot.Inertia(J=0.01)
        gear = rot.IdealGear(ratio=10.0)
        load = rot.Inertia(J=1.0)

        def equations(self):
            connect(self.source.p, self.emf.p)
            connect(self.emf.n, self.source.n)
            connect(self.source.n, self.ground.p)
            connect(self.emf.flange, self.rotor.flange_a)
            connect(self.gear.flange_b, self.load.flange_a)

    with caplog.at_level(logging.WARNING, logger="gtmodel"):
        model = Drive().to_model("drive")
    assert model.warnings == [
        "component drive: subsystem(s) that float (no connect() joins them to the rest, and none of their components "
        "fixes a potential as Ground or Fixed do): {gear, load}",
        "component drive: connector(s) left open (no connect(), so their flow is zero, as if nothing were attached): "
        "gear.flange_a (tau = 0)",
    ]
    assert [r.getMessage() for r in caplog.records if r.getMessage().startswith("component drive")] == model.warnings


class _Loaded(Component):
    """An inertia driven by a torque, with an output of the user's own declared in N.m.s (an angular momentum)."""

    torque = rot.Torque()
    body = rot.Inertia(J=0.5)

    def equations(self):
        connect(self.torque.flange, self.body.flange_a)
        self.output("momentum", self.body.J * self.body.w, unit="N.m.s")


def test_the_declared_units_reach_the_flat_model():
    # the library's declarations (MSL units: rad, rad/s, N.m), a connector's, and the user's output
    m = _Loaded().to_model("loaded")
    assert {k: m.units[k] for k in ("torque.tau", "body.phi", "body.w", "body.a", "body.flange_a.tau", "momentum")} == {
        "torque.tau": "N.m", "body.phi": "rad", "body.w": "rad/s", "body.a": "rad/s2", "body.flange_a.tau": "N.m",
        "momentum": "N.m.s"}


def test_a_unit_that_is_no_string_is_refused_naming_the_output():
    class Bad(Component):
        body = rot.Inertia()

        def equations(self):
            self.output("momentum", self.body.w, unit=3)

    from gtmodel.errors import InputError

    with pytest.raises(InputError, match=r"output 'momentum' unit: expected a string such as 'N', got 3"):
        Bad().to_model("bad")
