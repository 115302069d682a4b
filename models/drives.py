"""A family of electric drives composed from the library, with the user's own components.

User models for the drive problems ``problems/drive_*.toml`` (kind ``optimal_control``,
minimum time with voltage and current limits) and their independent references
(``benchmarks/drive_references.py``: a direct multiple-shooting solve written with plain
CasADi, the same equations written out by hand). Each armature is a ``SignalVoltage``
(input ``src.v`` [V]) on a ``Resistor`` R, an ``Inductor`` L (state ``ind.i`` [A]) and an
``EMF`` k turning the current into torque on the rotor ``Inertia``; the electrical time
constant L/R is 1 to 2 ms, far below the motion's 0.1 to 0.4 s (stiff).

* :class:`MotorGearLoadModel`: motor, gear 50:1, rigid load with viscous friction (the
  shipped ``dc_motor.py`` motor, here with the armature current limited);
* :class:`TwoMassDriveModel`: motor, gear 20:1, a compliant shaft (``SpringDamper``) and a
  load with smooth Coulomb and viscous friction (:class:`SmoothFriction`, the user's own
  component: ``tau = Fc tanh(w / w_eps) + dv w``);
* :class:`FlexibleJointModel`: motor, gear 50:1, a torsional spring-damper (c = 200 N m/rad,
  d = 0.5 N m s/rad) and a link (0.5 kg m^2) under gravity (:class:`GravityTorque`, the
  user's own component: ``tau = m g l sin(phi)``, phi from the hanging position);
* :class:`BeltDriveModel`: motor, a pulley (``IdealRollingWheel``, radius 2 cm) driving a
  cart on a viscous rail and, through the belt's spring-damper (4000 N/m, 20 N s/m), a
  payload: rotational into translational (the belt cart of ``tests/fixtures/user_models``);
* :class:`BallScrewDriveModel`: motor, a compliant coupling (100 N m/rad), the screw's
  inertia and a ball screw of 10 mm lead (``IdealRollingWheel`` of radius lead / 2 pi, the
  MSL's ``IdealGearR2T`` with ratio 2 pi / lead) moving a 20 kg table against smooth Coulomb
  and viscous friction (:class:`SmoothLinearFriction`, the user's own component).

Each class builds the model reduced by :func:`gtmodel.modeling.structural_simplify` (the gear
ties two angles: index 2 before reduction).
"""

from __future__ import annotations

import math

import casadi as ca

from gtmodel.modeling import Component, Model, connect, structural_simplify
from gtmodel.modeling.components.component import Parameter
from gtmodel.modeling.library import electrical as el
from gtmodel.modeling.library import rotational as rot
from gtmodel.modeling.library import translational as tr


class SmoothFriction(rot.PartialCompliantWithRelativeStates):
    """Coulomb friction smoothed by tanh plus viscous friction: ``tau = Fc tanh(w_rel / w_eps) + dv w_rel``.

    Connected between the housing (``flange_a``) and a moving flange (``flange_b``), so that
    ``w_rel`` is the flange's speed [rad/s] and ``tau`` [N m] brakes it.
    """

    Fc = Parameter(1.0, unit="N.m", description="Coulomb friction torque", lb=0.0)
    w_eps = Parameter(0.05, unit="rad/s", description="speed of the tanh smoothing", lb=1e-9)
    dv = Parameter(0.0, unit="N.m.s/rad", description="viscous friction coefficient", lb=0.0)

    def equations(self) -> None:
        """The base's equations and the friction law."""
        super().equations()
        self.equation(self.tau, self.Fc * ca.tanh(self.w_rel / self.w_eps) + self.dv * self.w_rel, name="friction")


class SmoothLinearFriction(tr.PartialCompliantWithRelativeStates):
    """Coulomb friction smoothed by tanh plus viscous friction on a slide: ``f = Fc tanh(v_rel / v_eps) + dv v_rel``.

    Connected between the ground (``flange_a``) and a moving flange (``flange_b``): ``v_rel`` is its speed [m/s] and
    ``f`` [N] brakes it.
    """

    Fc = Parameter(1.0, unit="N", description="Coulomb friction force", lb=0.0)
    v_eps = Parameter(0.002, unit="m/s", description="speed of the tanh smoothing", lb=1e-9)
    dv = Parameter(0.0, unit="N.s/m", description="viscous friction coefficient", lb=0.0)

    def equations(self) -> None:
        """The base's equations and the friction law."""
        super().equations()
        self.equation(self.f, self.Fc * ca.tanh(self.v_rel / self.v_eps) + self.dv * self.v_rel, name="friction")


class GravityTorque(Component):
    """Gravity on a link hinged at a horizontal axis: ``flange.tau = m g l sin(flange.phi)``.

    ``phi = 0`` hangs down; the torque pulls the link back towards it.
    """

    m = Parameter(1.0, unit="kg", description="link mass", lb=0.0)
    g = Parameter(9.81, unit="m/s2", description="gravitational acceleration")
    l = Parameter(0.2, unit="m", description="hinge to centre of mass", lb=0.0)  # noqa: E741 - the field's name
    flange = rot.Flange_b("flange of the link")

    def equations(self) -> None:
        """The gravity torque on the flange."""
        self.equation(self.flange.tau, self.m * self.g * self.l * ca.sin(self.flange.phi), name="gravity")


class _Armature(Component):
    """Voltage source, resistor, inductor and EMF on the rotor (the shared front of the drives)."""

    src = el.SignalVoltage()
    gnd = el.Ground()
    r = el.Resistor(R=1.0)
    ind = el.Inductor(L=1e-3)
    emf = el.EMF(k=0.05)
    rotor = rot.Inertia(J=1e-5)

    def equations(self) -> None:
        """The armature circuit and the motor shaft."""
        connect(self.src.p, self.r.p)
        connect(self.r.n, self.ind.p)
        connect(self.ind.n, self.emf.p)
        connect(self.emf.n, self.src.n)
        connect(self.src.n, self.gnd.p)
        connect(self.emf.flange, self.rotor.flange_a)


class MotorGearLoad(_Armature):
    """Motor (R = 0.5 Ohm, L = 0.85 mH, k = 0.05 N m/A, 1e-4 kg m^2), gear 50:1, load 0.01 kg m^2, friction 0.02 N m s/rad."""

    r = el.Resistor(R=0.5)
    ind = el.Inductor(L=0.85e-3)
    rotor = rot.Inertia(J=1e-4)
    gear = rot.IdealGear(ratio=50.0)
    load = rot.Inertia(J=0.01)
    friction = rot.Damper(d=0.02)
    fixed = rot.Fixed()

    def equations(self) -> None:
        """Armature, gear, load and its bearing."""
        super().equations()
        connect(self.rotor.flange_b, self.gear.flange_a)
        connect(self.gear.flange_b, self.load.flange_a)
        connect(self.load.flange_b, self.friction.flange_b)
        connect(self.friction.flange_a, self.fixed.flange)


class TwoMassDrive(_Armature):
    """Motor (R = 1 Ohm, L = 2 mH, k = 0.1 N m/A, 5e-5 kg m^2), gear 20:1, shaft 50 N m/rad and 0.2 N m s/rad,
    load 0.05 kg m^2 with Coulomb 0.3 N m (tanh, 0.05 rad/s) and viscous 0.05 N m s/rad friction."""

    r = el.Resistor(R=1.0)
    ind = el.Inductor(L=2e-3)
    emf = el.EMF(k=0.1)
    rotor = rot.Inertia(J=5e-5)
    gear = rot.IdealGear(ratio=20.0)
    shaft = rot.SpringDamper(c=50.0, d=0.2)
    load = rot.Inertia(J=0.05)
    friction = SmoothFriction(Fc=0.3, w_eps=0.05, dv=0.05)
    fixed = rot.Fixed()

    def equations(self) -> None:
        """Armature, gear, shaft, load and its friction."""
        super().equations()
        connect(self.rotor.flange_b, self.gear.flange_a)
        connect(self.gear.flange_b, self.shaft.flange_a)
        connect(self.shaft.flange_b, self.load.flange_a)
        connect(self.load.flange_b, self.friction.flange_b)
        connect(self.friction.flange_a, self.fixed.flange)


class FlexibleJoint(_Armature):
    """Motor (R = 1 Ohm, L = 1 mH, k = 0.05 N m/A, 1e-5 kg m^2), gear 50:1, spring-damper 200 N m/rad and
    0.5 N m s/rad, link 0.5 kg m^2 under gravity (m = 1 kg, l = 0.2 m)."""

    gear = rot.IdealGear(ratio=50.0)
    spring = rot.SpringDamper(c=200.0, d=0.5)
    link = rot.Inertia(J=0.5)
    gravity = GravityTorque(m=1.0, l=0.2)

    def equations(self) -> None:
        """Armature, gear, joint spring, link and gravity."""
        super().equations()
        connect(self.rotor.flange_b, self.gear.flange_a)
        connect(self.gear.flange_b, self.spring.flange_a)
        connect(self.spring.flange_b, self.link.flange_a)
        connect(self.link.flange_b, self.gravity.flange)


class BeltDrive(_Armature):
    """Motor (R = 1.2 Ohm, L = 2 mH, k = 0.08 N m/A, 4e-5 kg m^2), pulley radius 0.02 m, cart 1.5 kg on a rail
    3 N s/m, belt 4000 N/m and 20 N s/m, payload 0.8 kg."""

    r = el.Resistor(R=1.2)
    ind = el.Inductor(L=2e-3)
    emf = el.EMF(k=0.08)
    rotor = rot.Inertia(J=4e-5)
    pulley = rot.IdealRollingWheel(radius=0.02)
    cart = tr.Mass(m=1.5)
    belt = tr.SpringDamper(c=4000.0, d=20.0)
    payload = tr.Mass(m=0.8)
    rail = tr.Damper(d=3.0)
    ground = tr.Fixed()

    def equations(self) -> None:
        """Armature, pulley, cart on its rail, belt and payload."""
        super().equations()
        connect(self.rotor.flange_b, self.pulley.flangeR)
        connect(self.pulley.flangeT, self.cart.flange_a)
        connect(self.cart.flange_b, self.belt.flange_a)
        connect(self.belt.flange_b, self.payload.flange_a)
        connect(self.cart.flange_a, self.rail.flange_b)
        connect(self.rail.flange_a, self.ground.flange)


class BallScrewDrive(_Armature):
    """Motor (R = 0.8 Ohm, L = 1.5 mH, k = 0.12 N m/A, 2e-4 kg m^2), coupling 100 N m/rad and 0.05 N m s/rad, screw
    1e-4 kg m^2 with a lead of 10 mm, table 20 kg with Coulomb 20 N (tanh, 2 mm/s) and viscous 50 N s/m friction."""

    r = el.Resistor(R=0.8)
    ind = el.Inductor(L=1.5e-3)
    emf = el.EMF(k=0.12)
    rotor = rot.Inertia(J=2e-4)
    coupling = rot.SpringDamper(c=100.0, d=0.05)
    screw_j = rot.Inertia(J=1e-4)
    screw = rot.IdealRollingWheel(radius=0.01 / (2.0 * math.pi))  # lead / 2 pi: 10 mm of travel per turn
    table = tr.Mass(m=20.0)
    friction = SmoothLinearFriction(Fc=20.0, v_eps=0.002, dv=50.0)
    ground = tr.Fixed()

    def equations(self) -> None:
        """Armature, coupling, screw, table and its friction."""
        super().equations()
        connect(self.rotor.flange_b, self.coupling.flange_a)
        connect(self.coupling.flange_b, self.screw_j.flange_a)
        connect(self.screw_j.flange_b, self.screw.flangeR)
        connect(self.screw.flangeT, self.table.flange_a)
        connect(self.table.flange_b, self.friction.flange_b)
        connect(self.friction.flange_a, self.ground.flange)


class MotorGearLoadModel:
    """:class:`MotorGearLoad`, reduced to index 1."""

    def build(self) -> Model:
        """The reduced model.

        Returns
        -------
        Model
            States ``ind.i`` [A], ``emf.phi`` [rad], ``rotor.w`` [rad/s]; input ``src.v`` [V].
        """
        return structural_simplify(MotorGearLoad().to_model("motor_gear_load"))


class TwoMassDriveModel:
    """:class:`TwoMassDrive`, reduced to index 1."""

    def build(self) -> Model:
        """The reduced model.

        Returns
        -------
        Model
            States: the current ``ind.i`` [A], the motor angle and speed, the shaft's twist and the load's
            angle and speed (their names as reduction keeps them); input ``src.v`` [V].
        """
        return structural_simplify(TwoMassDrive().to_model("two_mass_drive"))


class FlexibleJointModel:
    """:class:`FlexibleJoint`, reduced to index 1."""

    def build(self) -> Model:
        """The reduced model.

        Returns
        -------
        Model
            States: the current ``ind.i`` [A], the motor angle and speed, the spring's twist and the link's
            angle and speed (their names as reduction keeps them); input ``src.v`` [V].
        """
        return structural_simplify(FlexibleJoint().to_model("flexible_joint"))


class BeltDriveModel:
    """:class:`BeltDrive`, reduced to index 1."""

    def build(self) -> Model:
        """The reduced model.

        Returns
        -------
        Model
            States: the current ``ind.i`` [A], the motor angle and speed, the payload's position [m] and speed
            [m/s] (their names as reduction keeps them); input ``src.v`` [V].
        """
        return structural_simplify(BeltDrive().to_model("belt_drive"))


class BallScrewDriveModel:
    """:class:`BallScrewDrive`, reduced to index 1."""

    def build(self) -> Model:
        """The reduced model.

        Returns
        -------
        Model
            States: the current ``ind.i`` [A], the motor speed, the coupling's twist and the screw's angle and
            speed (their names as reduction keeps them); input ``src.v`` [V].
        """
        return structural_simplify(BallScrewDrive().to_model("ball_screw_drive"))
