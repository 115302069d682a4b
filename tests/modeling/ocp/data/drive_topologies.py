"""Drive topologies the drive family does not have, composed by a user from the library (docs/verification.md).

* :class:`Arm`: a voltage command through an amplifier dead band (``DeadZone``), two gear stages with a backlash
  between them, a compliant shaft, an arm under gravity with Stribeck friction (swung up to inverted);
* :class:`Conveyor`: a voltage command through a saturating amplifier (``Limiter``), a pulley, a belt, a carriage and
  a tool holder with backlash against it, Stribeck friction on the tool;
* :class:`Table`: a rotary table behind a gear of 100 with backlash, bearing and Stribeck friction;
* :class:`Lift`: a cage lifted on an elastic rope from a drum, guide friction and gravity.

Problems: ``drive_topologies_*.toml`` beside this file (tests/trajectory/test_model_ocp_topologies.py).
"""
import casadi as ca
from gtmodel.modeling import Component, connect, structural_simplify
from gtmodel.modeling.components.component import Input, Parameter, Variable
from gtmodel.modeling.library import blocks
from gtmodel.modeling.library import electrical as el
from gtmodel.modeling.library import rotational as rot
from gtmodel.modeling.library import translational as tr


class CommandedVoltage(el.SignalVoltage):
    v = Variable(unit="V", description="voltage from a signal")


class _Armature(Component):
    """Voltage source, resistor, inductor and EMF on the rotor (each drive's own values below)."""
    src = el.SignalVoltage()
    gnd = el.Ground()
    r = el.Resistor(R=1.0)
    ind = el.Inductor(L=1e-3)
    emf = el.EMF(k=0.1)
    rotor = rot.Inertia(J=1e-4)

    def equations(self):
        connect(self.src.p, self.r.p)
        connect(self.r.n, self.ind.p)
        connect(self.ind.n, self.emf.p)
        connect(self.emf.n, self.src.n)
        connect(self.src.n, self.gnd.p)
        connect(self.emf.flange, self.rotor.flange_a)


class Gravity(Component):
    mgl = Parameter(2.0, unit="N.m")
    flange = rot.Flange_b("link")

    def equations(self):
        self.equation(self.flange.tau, self.mgl * ca.sin(self.flange.phi))


class DeadBandArm(_Armature):
    """Voltage command through an amplifier dead band, two gear stages with backlash between them, a compliant
    shaft, an arm under gravity with Stribeck friction."""
    u = Input(unit="V")
    band = blocks.DeadZone(uMax=0.5, uMin=-0.5, smoothing=0.02)
    src = CommandedVoltage()
    r = el.Resistor(R=0.8)
    ind = el.Inductor(L=1.2e-3)
    emf = el.EMF(k=0.08)
    rotor = rot.Inertia(J=3e-5)
    gear1 = rot.IdealGear(ratio=5.0)
    backlash = rot.ElastoBacklash(c=800.0, d=0.3, b=0.01, smoothing=5e-4)
    mid = rot.Inertia(J=1e-3)
    gear2 = rot.IdealGear(ratio=8.0)
    shaft = rot.SpringDamper(c=3000.0, d=2.0)
    arm = rot.Inertia(J=0.05)
    friction = rot.Friction(Fc=0.3, Fs=0.15, ws=0.1, dv=0.01, smoothing=0.01)
    fixed = rot.Fixed()
    gravity = Gravity(mgl=2.0)

    def equations(self):
        self.equation(self.band.u, self.u)
        self.equation(self.src.v, self.band.y)
        super().equations()
        connect(self.rotor.flange_b, self.gear1.flange_a)
        connect(self.gear1.flange_b, self.backlash.flange_a)
        connect(self.backlash.flange_b, self.mid.flange_a)
        connect(self.mid.flange_b, self.gear2.flange_a)
        connect(self.gear2.flange_b, self.shaft.flange_a)
        connect(self.shaft.flange_b, self.arm.flange_a)
        connect(self.arm.flange_b, self.friction.flange_b)
        connect(self.friction.flange_a, self.fixed.flange)
        connect(self.arm.flange_b, self.gravity.flange)


class Arm:
    def build(self):
        return structural_simplify(DeadBandArm().to_model("dead_band_arm"))


class LimitedConveyor(_Armature):
    """Voltage command through a Limiter (amplifier saturation at +-20 V), pulley, a belt, a carriage, a tool holder
    with backlash against the carriage, Stribeck friction on the tool."""
    u = Input(unit="V")
    sat = blocks.Limiter(uMax=20.0, uMin=-20.0, smoothing=0.05)
    src = CommandedVoltage()
    r = el.Resistor(R=1.5)
    ind = el.Inductor(L=2e-3)
    emf = el.EMF(k=0.3)
    rotor = rot.Inertia(J=6e-5)
    pulley = rot.IdealRollingWheel(radius=0.02)
    belt = tr.SpringDamper(c=2e5, d=150.0)
    carriage = tr.Mass(m=4.0)
    backlash = tr.ElastoBacklash(c=5e6, d=800.0, b=2e-4, smoothing=5e-6)
    tool = tr.Mass(m=1.5)
    friction = tr.Friction(Fc=15.0, Fs=6.0, vs=0.02, dv=30.0, smoothing=2e-3)
    fixed = tr.Fixed()

    def equations(self):
        self.equation(self.sat.u, self.u)
        self.equation(self.src.v, self.sat.y)
        super().equations()
        connect(self.rotor.flange_b, self.pulley.flangeR)
        connect(self.pulley.flangeT, self.belt.flange_a)
        connect(self.belt.flange_b, self.carriage.flange_a)
        connect(self.carriage.flange_b, self.backlash.flange_a)
        connect(self.backlash.flange_b, self.tool.flange_a)
        connect(self.tool.flange_b, self.friction.flange_b)
        connect(self.friction.flange_a, self.fixed.flange)


class Conveyor:
    def build(self):
        return structural_simplify(LimitedConveyor().to_model("limited_conveyor"))


class Weight(Component):
    mg = Parameter(100.0, unit="N")
    flange = tr.Flange_b("load")

    def equations(self):
        self.equation(self.flange.f, self.mg)


class TableDrive(_Armature):
    """Rotary table: motor with its own bearing friction, gear 100 with backlash on its output, table inertia with
    Stribeck friction; the voltage is the input."""
    r = el.Resistor(R=2.0)
    ind = el.Inductor(L=3e-3)
    emf = el.EMF(k=0.15)
    rotor = rot.Inertia(J=2e-4)
    bearing = rot.Friction(Fc=0.02, Fs=0.0, ws=1.0, dv=1e-4, smoothing=0.5)
    fixed1 = rot.Fixed()
    gear = rot.IdealGear(ratio=100.0)
    backlash = rot.ElastoBacklash(c=5e4, d=20.0, b=2e-3, smoothing=1e-4)
    table = rot.Inertia(J=2.0)
    friction = rot.Friction(Fc=3.0, Fs=2.0, ws=0.02, dv=1.0, smoothing=2e-3)
    fixed2 = rot.Fixed()

    def equations(self):
        super().equations()
        connect(self.rotor.flange_b, self.bearing.flange_b)
        connect(self.bearing.flange_a, self.fixed1.flange)
        connect(self.rotor.flange_b, self.gear.flange_a)
        connect(self.gear.flange_b, self.backlash.flange_a)
        connect(self.backlash.flange_b, self.table.flange_a)
        connect(self.table.flange_b, self.friction.flange_b)
        connect(self.friction.flange_a, self.fixed2.flange)


class Table:
    def build(self):
        return structural_simplify(TableDrive().to_model("rotary_table"))


class LiftDrive(_Armature):
    """Vertical lift: motor, drum (radius 5 cm) winding a rope (a spring-damper) lifting a cage under gravity, with
    guide friction; the voltage is the input."""
    r = el.Resistor(R=0.5)
    ind = el.Inductor(L=1e-3)
    emf = el.EMF(k=0.5)
    rotor = rot.Inertia(J=5e-3)
    gear = rot.IdealGear(ratio=10.0)
    drum = rot.IdealRollingWheel(radius=0.05)
    rope = tr.SpringDamper(c=2e5, d=500.0)
    cage = tr.Mass(m=30.0)
    guide = tr.Friction(Fc=20.0, Fs=10.0, vs=0.01, dv=50.0, smoothing=1e-3)
    fixed = tr.Fixed()
    weight = Weight(mg=294.3)

    def equations(self):
        super().equations()
        connect(self.rotor.flange_b, self.gear.flange_a)
        connect(self.gear.flange_b, self.drum.flangeR)
        connect(self.drum.flangeT, self.rope.flange_a)
        connect(self.rope.flange_b, self.cage.flange_a)
        connect(self.cage.flange_b, self.guide.flange_b)
        connect(self.guide.flange_a, self.fixed.flange)
        connect(self.cage.flange_b, self.weight.flange)


class Lift:
    def build(self):
        return structural_simplify(LiftDrive().to_model("lift"))
