"""A DC motor, gearbox and load from library components: a stiff plant (electrical time constant L / R = 1.7 ms).

The component model (:class:`DCMotorDrive`) is of higher index (the gear ties two
inertias); :class:`DCMotor` gives it reduced (:func:`~gtmodel.modeling.structure.index_reduction.structural_simplify`):
states ``inductor.i``, ``emf.phi``, ``motor.w``, input ``source.v``.
"""

from __future__ import annotations

from gtmodel.modeling import Component, Model, connect
from gtmodel.modeling.library import electrical as el
from gtmodel.modeling.library import rotational as rot
from gtmodel.modeling.structure.index_reduction import structural_simplify


class DCMotorDrive(Component):
    """Voltage source, armature resistance and inductance, EMF, rotor, gear 10:1, load on a bearing."""

    source = el.SignalVoltage()
    ground = el.Ground()
    resistor = el.Resistor(R=2.0)
    inductor = el.Inductor(L=3.4e-3)
    emf = el.EMF(k=0.05)
    motor = rot.Inertia(J=2e-5)
    gear = rot.IdealGear(ratio=10.0)
    load = rot.Inertia(J=1e-3)
    bearing = rot.Damper(d=1e-3)
    fixed = rot.Fixed()

    def equations(self) -> None:
        """The circuit, the motor shaft, the gear and the load."""
        connect(self.source.p, self.resistor.p)
        connect(self.resistor.n, self.inductor.p)
        connect(self.inductor.n, self.emf.p)
        connect(self.emf.n, self.source.n)
        connect(self.source.n, self.ground.p)
        connect(self.emf.flange, self.motor.flange_a)
        connect(self.motor.flange_b, self.gear.flange_a)
        connect(self.gear.flange_b, self.load.flange_a)
        connect(self.load.flange_b, self.bearing.flange_a)
        connect(self.bearing.flange_b, self.fixed.flange)


class DCMotor:
    """The drive, reduced to index 1."""

    def build(self) -> Model:
        """The reduced model.

        Returns
        -------
        Model
            States ``inductor.i``, ``emf.phi``, ``motor.w``; input ``source.v``.
        """
        return structural_simplify(DCMotorDrive().to_model("dc_motor"))
