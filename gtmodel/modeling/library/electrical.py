"""Analog electrical components, named as ``Modelica.Electrical.Analog``.

Connector: :class:`Pin` (:class:`PositivePin`, :class:`NegativePin`) with the potential
``v`` [V] and the current ``i`` [A] flowing into the pin.

Components (Modelica Standard Library 4.0 names and equations): :class:`Resistor`,
:class:`Inductor`, :class:`Capacitor`, :class:`EMF` (electro-mechanical converter to a
rotational flange, support fixed), :class:`SignalVoltage`, :class:`ConstantVoltage`,
:class:`Ground`; the partial base :class:`OnePort`.
"""

from __future__ import annotations

from gtmodel.modeling.components.component import Component, Input, Parameter, State, Variable
from gtmodel.modeling.components.connectors import Connector, Flow, Potential
from gtmodel.modeling.library import rotational

__all__ = [
    "Pin",
    "PositivePin",
    "NegativePin",
    "OnePort",
    "Resistor",
    "Inductor",
    "Capacitor",
    "EMF",
    "SignalVoltage",
    "ConstantVoltage",
    "Ground",
]


class Pin(Connector):
    """Electrical pin: potential ``v`` [V], current ``i`` [A] into the pin (MSL ``Interfaces.Pin``).

    Parameters
    ----------
    description : str, optional
        Description of this connector instance.
    """

    v = Potential(unit="V", description="potential at the pin")
    i = Flow(unit="A", description="current flowing into the pin")


class PositivePin(Pin):
    """Positive pin (identical to :class:`Pin`, MSL naming).

    Parameters
    ----------
    description : str, optional
        Description of this connector instance.
    """


class NegativePin(Pin):
    """Negative pin (identical to :class:`Pin`, MSL naming).

    Parameters
    ----------
    description : str, optional
        Description of this connector instance.
    """


class OnePort(Component):
    """Two pins, one current (MSL ``Interfaces.OnePort``).

    ``v = p.v - n.v``, ``0 = p.i + n.i``, ``i = p.i``.

    Parameters
    ----------
    **modifiers
        See :class:`~gtmodel.modeling.components.component.Component`.
    """

    p = PositivePin("positive pin (current flows from p to n when i > 0)")
    n = NegativePin("negative pin")
    v = Variable(unit="V", description="voltage drop p.v - n.v")
    i = Variable(unit="A", description="current from p to n")

    def equations(self) -> None:
        """``v = p.v - n.v``, ``0 = p.i + n.i``, ``i = p.i``."""
        self.equation(self.v, self.p.v - self.n.v, name="voltage")
        self.equation(self.p.i + self.n.i, 0.0, name="current_balance")
        self.equation(self.i, self.p.i, name="current")


class Resistor(OnePort):
    """Ideal linear resistor: ``v = R i`` (MSL ``Basic.Resistor`` at the reference temperature).

    Parameters
    ----------
    R : float, optional
        Resistance [Ohm] (default 1).
    **modifiers
        Further modifiers (start values of variables, sub-components), see
        :class:`~gtmodel.modeling.components.component.Component`.
    """

    R = Parameter(1.0, unit="Ohm", description="resistance")

    def equations(self) -> None:
        """Ohm's law, plus :class:`OnePort`'s equations."""
        super().equations()
        self.equation(self.v, self.R * self.i, name="ohm")


class Inductor(OnePort):
    """Ideal linear inductor: ``L der(i) = v`` (MSL ``Basic.Inductor``); state ``i``.

    Parameters
    ----------
    L : float, optional
        Inductance [H], > 0 (default 1).
    **modifiers
        Further modifiers (start values of variables, sub-components), see
        :class:`~gtmodel.modeling.components.component.Component`.
    """

    L = Parameter(1.0, unit="H", description="inductance", lb=0.0)
    i = State(unit="A", description="current from p to n")

    def equations(self) -> None:
        """``L der(i) = v``, plus :class:`OnePort`'s equations."""
        super().equations()
        self.equation(self.L * self.der(self.i), self.v, name="induction")


class Capacitor(OnePort):
    """Ideal linear capacitor: ``C der(v) = i`` (MSL ``Basic.Capacitor``); state ``v``.

    Parameters
    ----------
    C : float, optional
        Capacitance [F], > 0 (default 1).
    **modifiers
        Further modifiers (start values of variables, sub-components), see
        :class:`~gtmodel.modeling.components.component.Component`.
    """

    C = Parameter(1.0, unit="F", description="capacitance", lb=0.0)
    v = State(unit="V", description="voltage drop p.v - n.v")

    def equations(self) -> None:
        """``C der(v) = i``, plus :class:`OnePort`'s equations."""
        super().equations()
        self.equation(self.C * self.der(self.v), self.i, name="charge")


class EMF(Component):
    """Electro-mechanical converter (MSL ``Basic.EMF``, support fixed): DC motor torque constant.

    ``v = p.v - n.v``, ``0 = p.i + n.i``, ``i = p.i``, ``phi = flange.phi``,
    ``w = der(phi)``, ``k w = v``, ``flange.tau = -k i``.

    Parameters
    ----------
    k : float, optional
        Transformation coefficient [N m/A] (= V s/rad) (default 1).
    **modifiers
        Further modifiers (start values of variables, sub-components), see
        :class:`~gtmodel.modeling.components.component.Component`.
    """

    k = Parameter(1.0, unit="N.m/A", description="transformation coefficient")
    p = PositivePin("positive pin")
    n = NegativePin("negative pin")
    flange = rotational.Flange_b("flange of the motor shaft")
    v = Variable(unit="V", description="voltage drop p.v - n.v")
    i = Variable(unit="A", description="current from p to n")
    phi = State(unit="rad", description="angle of the flange")
    w = Variable(unit="rad/s", description="angular velocity of the flange, der(phi)")

    def equations(self) -> None:
        """The electrical port, the back-EMF and the motor torque."""
        self.equation(self.v, self.p.v - self.n.v, name="voltage")
        self.equation(self.p.i + self.n.i, 0.0, name="current_balance")
        self.equation(self.i, self.p.i, name="current")
        self.equation(self.phi, self.flange.phi, name="angle")
        self.equation(self.w, self.der(self.phi), name="speed")
        self.equation(self.k * self.w, self.v, name="back_emf")
        self.equation(self.flange.tau, -self.k * self.i, name="torque")


class SignalVoltage(OnePort):
    """Voltage source from an input signal (MSL ``Sources.SignalVoltage``): ``p.v - n.v = v``.

    The voltage ``v`` [V] is an input of the model.

    Parameters
    ----------
    **modifiers
        ``v`` sets the input's nominal value.
    """

    v = Input(unit="V", description="voltage between pin p and pin n")


class ConstantVoltage(OnePort):
    """Constant voltage source: ``v = V`` (MSL ``Sources.ConstantVoltage``).

    Parameters
    ----------
    V : float, optional
        Voltage [V] (default 1).
    **modifiers
        Further modifiers (start values of variables, sub-components), see
        :class:`~gtmodel.modeling.components.component.Component`.
    """

    V = Parameter(1.0, unit="V", description="value of the constant voltage")

    def equations(self) -> None:
        """``v = V``, plus :class:`OnePort`'s equations."""
        super().equations()
        self.equation(self.v, self.V, name="source")


class Ground(Component):
    """Ground node: ``p.v = 0`` (MSL ``Basic.Ground``).

    Parameters
    ----------
    **modifiers
        None declared.
    """

    p = Pin("ground pin")

    def equations(self) -> None:
        """``p.v = 0``."""
        self.equation(self.p.v, 0.0, name="ground")
