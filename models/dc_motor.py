"""A DC motor with a gearbox driving a load, composed from the library's components.

A user model for ``gtmodel codegen --model models/dc_motor.py:DCMotorModel`` (the explicit
ODE, its fixed steps over the 4 ms loop), the tracking controller and MPC of an optimal
motion (``problems/dc_motor_move.toml``, ``codegen/mpc/dc_motor_mpc.toml``) and the
benchmark ``problems/benchmarks/dc_motor_min_energy.toml``.
Modelica Standard Library names: a :class:`~gtmodel.modeling.library.electrical.SignalVoltage`
(input ``src.v`` [V]) drives the armature (``Resistor`` R, ``Inductor`` L: the electrical
time constant L/R = 1.7 ms, shorter than the loop period), an ``EMF`` (k) turns the current
into torque on the rotor ``Inertia``; an ``IdealGear`` of ratio 50 drives the load
``Inertia`` with viscous friction (``Damper`` to the ``Fixed`` housing).

The component values below are the default parameter set (the 4 ms loop's motor); a problem
file sets another by its parameters' names in ``[model.parameters]``: the benchmark's smaller
motor, R = 2 Ohm, L = 3.4 mH (the same 1.7 ms), rotor 2e-5 kg m^2, gear 10:1, load
1e-3 kg m^2 on a bearing of 1e-3 N m s/rad, is
``{"r.R" = 2.0, "ind.L" = 3.4e-3, "rotor.J" = 2e-5, "gear.ratio" = 10.0, "load.J" = 1e-3, "friction.d" = 1e-3}``.

The composed model is of higher index (the gear ties the rotor and load angles), so the
class :class:`DCMotorModel` builds it reduced by
:func:`gtmodel.modeling.structural_simplify` (a model file's class must build a model that
flattens); its states are the armature current, the rotor angle and the rotor speed.
"""

from __future__ import annotations

from gtmodel.modeling import Component, Model, connect, structural_simplify
from gtmodel.modeling.library import electrical as el
from gtmodel.modeling.library import rotational as rot


class DCMotor(Component):
    """Armature (R = 0.5 Ohm, L = 0.85 mH), EMF (k = 0.05 N m/A), rotor, gear 50:1, load with friction."""

    src = el.SignalVoltage()
    gnd = el.Ground()
    r = el.Resistor(R=0.5)
    ind = el.Inductor(L=0.85e-3)
    emf = el.EMF(k=0.05)
    rotor = rot.Inertia(J=1e-4)
    gear = rot.IdealGear(ratio=50.0)
    load = rot.Inertia(J=0.01)
    friction = rot.Damper(d=0.02)
    fixed = rot.Fixed()

    def equations(self) -> None:
        """The armature circuit, the motor shaft, the gear and the load."""
        connect(self.src.p, self.r.p)
        connect(self.r.n, self.ind.p)
        connect(self.ind.n, self.emf.p)
        connect(self.emf.n, self.src.n)
        connect(self.src.n, self.gnd.p)
        connect(self.emf.flange, self.rotor.flange_a)
        connect(self.rotor.flange_b, self.gear.flange_a)
        connect(self.gear.flange_b, self.load.flange_a)
        connect(self.load.flange_b, self.friction.flange_b)
        connect(self.friction.flange_a, self.fixed.flange)


class DCMotorModel:
    """The DC motor's flat model, reduced to index 1 (alias elimination, index reduction)."""

    def build(self) -> Model:
        """The reduced model of :class:`DCMotor`.

        Returns
        -------
        Model
            Index 1; states ``ind.i`` [A], ``emf.phi`` [rad], ``rotor.w`` [rad/s]; input ``src.v`` [V].
        """
        return structural_simplify(DCMotor().to_model("dc_motor"))
