"""A small standard library of components, named as the Modelica Standard Library.

* :mod:`~gtmodel.modeling.library.translational` (``Modelica.Mechanics.Translational``):
  Mass, Spring, Damper, SpringDamper, Force, Fixed, and the smoothed non-smooth
  ElastoBacklash and Friction;
* :mod:`~gtmodel.modeling.library.rotational` (``Modelica.Mechanics.Rotational``):
  Inertia, IdealGear, Spring, Damper, SpringDamper, Torque, Fixed, IdealRollingWheel, and
  the smoothed non-smooth ElastoBacklash and Friction;
* :mod:`~gtmodel.modeling.library.blocks` (``Modelica.Blocks.Nonlinear``): the smoothed
  Limiter and DeadZone, and the smooth laws (softplus, ...) of the non-smooth elements,
  each with a smoothing width listed in ``Model.smoothing``;
* :mod:`~gtmodel.modeling.library.electrical` (``Modelica.Electrical.Analog``):
  Resistor, Inductor, Capacitor, EMF, SignalVoltage, ConstantVoltage, Ground;
* :mod:`~gtmodel.modeling.library.drive`: a compliant drive axis (servo, motor, gear,
  belt, cart) composed from them;
* :mod:`~gtmodel.modeling.library.gantry_tau`: the Gantry-Tau parts on the 3-D frame
  (Fixed, Cart, Link, Plate) and the 3-link robot GantryTau3.

The domains share class names (``translational.Spring``, ``rotational.Spring``), as in
the MSL: import the domain module and qualify.
"""

from __future__ import annotations

from gtmodel.modeling.library import blocks, drive, electrical, gantry_tau, rotational, translational

__all__ = ["translational", "rotational", "blocks", "electrical", "drive", "gantry_tau"]
