"""1-D rotational mechanics, named as ``Modelica.Mechanics.Rotational``.

Connector: :class:`Flange_a` / :class:`Flange_b` with the angle ``phi`` [rad] (potential)
and the cut torque ``tau`` [N m] (flow, positive into the component), as in the MSL;
speeds are component-internal (``w = der(phi)``; see
:mod:`gtmodel.modeling.library.translational` for the index of the resulting models).

Components (Modelica Standard Library 4.0 names and equations, support flanges fixed):
:class:`Inertia`, :class:`IdealGear`, :class:`Spring`, :class:`Damper`,
:class:`SpringDamper`, :class:`Torque`, :class:`Fixed`, and :class:`IdealRollingWheel`
(rotation to translation, e.g. a belt pulley).
"""

from __future__ import annotations

from gtmodel.modeling.components.component import Component, Input, Parameter, State, Variable
from gtmodel.modeling.components.connectors import Connector, Flow, Potential
from gtmodel.modeling.library import translational

__all__ = [
    "Flange",
    "Flange_a",
    "Flange_b",
    "PartialTwoFlanges",
    "PartialCompliant",
    "PartialCompliantWithRelativeStates",
    "Inertia",
    "IdealGear",
    "Spring",
    "Damper",
    "SpringDamper",
    "Torque",
    "Fixed",
    "IdealRollingWheel",
]


class Flange(Connector):
    """Rotational flange: angle ``phi`` [rad], cut torque ``tau`` [N m] (MSL ``Interfaces.Flange``).

    Parameters
    ----------
    description : str, optional
        Description of this connector instance.
    """

    phi = Potential(unit="rad", description="absolute rotation angle of the flange")
    tau = Flow(unit="N.m", description="cut torque in the flange")


class Flange_a(Flange):  # noqa: N801 - Modelica Standard Library name
    """Rotational flange, "a" side (identical to :class:`Flange_b`, MSL naming).

    Parameters
    ----------
    description : str, optional
        Description of this connector instance.
    """


class Flange_b(Flange):  # noqa: N801 - Modelica Standard Library name
    """Rotational flange, "b" side (identical to :class:`Flange_a`, MSL naming).

    Parameters
    ----------
    description : str, optional
        Description of this connector instance.
    """


class PartialTwoFlanges(Component):
    """Base of components with two rotational flanges ``flange_a``, ``flange_b``.

    Parameters
    ----------
    **modifiers
        See :class:`~gtmodel.modeling.components.component.Component`.
    """

    flange_a = Flange_a("flange of the left shaft")
    flange_b = Flange_b("flange of the right shaft")


class PartialCompliant(PartialTwoFlanges):
    """Compliant connection of two flanges: ``phi_rel``, torque ``tau`` (MSL ``PartialCompliant``).

    ``phi_rel = flange_b.phi - flange_a.phi``, ``flange_b.tau = tau``, ``flange_a.tau = -tau``.

    Parameters
    ----------
    **modifiers
        See :class:`~gtmodel.modeling.components.component.Component`.
    """

    phi_rel = Variable(unit="rad", description="relative rotation angle flange_b.phi - flange_a.phi")
    tau = Variable(unit="N.m", description="torque between the flanges")

    def equations(self) -> None:
        """``phi_rel = flange_b.phi - flange_a.phi``, ``flange_b.tau = tau``, ``flange_a.tau = -tau``."""
        self.equation(self.phi_rel, self.flange_b.phi - self.flange_a.phi, name="phi_rel")
        self.equation(self.flange_b.tau, self.tau, name="tau_b")
        self.equation(self.flange_a.tau, -self.tau, name="tau_a")


class Spring(PartialCompliant):
    """Linear torsional spring: ``tau = c (phi_rel - phi_rel0)`` (MSL ``Rotational.Components.Spring``).

    Parameters
    ----------
    c : float, optional
        Spring constant [N m/rad], >= 0 (default 1e5).
    phi_rel0 : float, optional
        Unstretched angle [rad] (default 0).
    **modifiers
        Further modifiers (start values of variables, sub-components), see
        :class:`~gtmodel.modeling.components.component.Component`.
    """

    c = Parameter(1e5, unit="N.m/rad", description="spring constant", lb=0.0)
    phi_rel0 = Parameter(0.0, unit="rad", description="unstretched spring angle")

    def equations(self) -> None:
        """Hooke's law, plus :class:`PartialCompliant`'s equations."""
        super().equations()
        self.equation(self.tau, self.c * (self.phi_rel - self.phi_rel0), name="hooke")


class PartialCompliantWithRelativeStates(PartialCompliant):
    """Compliant connection with the relative angle as a state (MSL base of dampers).

    :class:`PartialCompliant`'s equations with ``phi_rel`` a state and ``w_rel = der(phi_rel)``.

    Parameters
    ----------
    **modifiers
        Further modifiers (start values of variables, sub-components), see
        :class:`~gtmodel.modeling.components.component.Component`.
    """

    phi_rel = State(unit="rad", description="relative rotation angle flange_b.phi - flange_a.phi")
    w_rel = Variable(unit="rad/s", description="relative angular velocity der(phi_rel)")

    def equations(self) -> None:
        """:class:`PartialCompliant`'s equations and ``w_rel = der(phi_rel)``."""
        super().equations()
        self.equation(self.w_rel, self.der(self.phi_rel), name="w_rel")


class Damper(PartialCompliantWithRelativeStates):
    """Linear torsional damper: ``tau = d w_rel`` (MSL ``Rotational.Components.Damper``).

    Parameters
    ----------
    d : float, optional
        Damping constant [N m s/rad], >= 0 (default 0).
    **modifiers
        Further modifiers (start values of variables, sub-components), see
        :class:`~gtmodel.modeling.components.component.Component`.
    """

    d = Parameter(0.0, unit="N.m.s/rad", description="damping constant", lb=0.0)

    def equations(self) -> None:
        """``tau = d w_rel``, plus the base's equations."""
        super().equations()
        self.equation(self.tau, self.d * self.w_rel, name="damping")


class SpringDamper(PartialCompliantWithRelativeStates):
    """Torsional spring and damper in parallel (MSL ``Rotational.Components.SpringDamper``).

    ``tau = c (phi_rel - phi_rel0) + d w_rel``.

    Parameters
    ----------
    c : float, optional
        Spring constant [N m/rad], >= 0 (default 1e5).
    d : float, optional
        Damping constant [N m s/rad], >= 0 (default 0).
    phi_rel0 : float, optional
        Unstretched angle [rad] (default 0).
    **modifiers
        Further modifiers (start values of variables, sub-components), see
        :class:`~gtmodel.modeling.components.component.Component`.
    """

    c = Parameter(1e5, unit="N.m/rad", description="spring constant", lb=0.0)
    d = Parameter(0.0, unit="N.m.s/rad", description="damping constant", lb=0.0)
    phi_rel0 = Parameter(0.0, unit="rad", description="unstretched spring angle")

    def equations(self) -> None:
        """``tau = c (phi_rel - phi_rel0) + d w_rel``, plus the base's equations."""
        super().equations()
        self.equation(self.tau, self.c * (self.phi_rel - self.phi_rel0) + self.d * self.w_rel, name="torque")


class Inertia(PartialTwoFlanges):
    """Rotational inertia (MSL ``Rotational.Components.Inertia``).

    ``phi = flange_a.phi = flange_b.phi``, ``w = der(phi)``, ``a = der(w)``,
    ``J a = flange_a.tau + flange_b.tau``. States ``phi``, ``w``.

    Parameters
    ----------
    J : float, optional
        Moment of inertia [kg m^2], >= 0 (default 1).
    **modifiers
        Further modifiers (start values of variables, sub-components), see
        :class:`~gtmodel.modeling.components.component.Component`.
    """

    J = Parameter(1.0, unit="kg.m2", description="moment of inertia", lb=0.0)
    phi = State(unit="rad", description="absolute rotation angle of the component")
    w = State(unit="rad/s", description="absolute angular velocity of the component")
    a = Variable(unit="rad/s2", description="absolute angular acceleration of the component")

    def equations(self) -> None:
        """Rigid flanges, kinematics and Euler's law."""
        self.equation(self.flange_a.phi, self.phi, name="phi_a")
        self.equation(self.flange_b.phi, self.phi, name="phi_b")
        self.equation(self.der(self.phi), self.w, name="velocity")
        self.equation(self.der(self.w), self.a, name="acceleration")
        self.equation(self.J * self.a, self.flange_a.tau + self.flange_b.tau, name="euler")


class IdealGear(PartialTwoFlanges):
    """Ideal gear without inertia (MSL ``Rotational.Components.IdealGear``, support fixed).

    ``flange_a.phi = ratio flange_b.phi``,
    ``0 = ratio flange_a.tau + flange_b.tau``.

    Parameters
    ----------
    ratio : float, optional
        Transmission ratio ``flange_a.phi / flange_b.phi`` [1], non-zero (default 1).
    **modifiers
        Further modifiers (start values of variables, sub-components), see
        :class:`~gtmodel.modeling.components.component.Component`.
    """

    ratio = Parameter(1.0, unit="1", description="transmission ratio flange_a.phi / flange_b.phi")

    def equations(self) -> None:
        """Kinematic and torque relations of the gear."""
        self.equation(self.flange_a.phi, self.ratio * self.flange_b.phi, name="angle")
        self.equation(self.ratio * self.flange_a.tau + self.flange_b.tau, 0.0, name="torque")


class Torque(Component):
    """External torque from an input signal (MSL ``Rotational.Sources.Torque``, support fixed).

    ``flange.tau = -tau``: ``tau`` [N m] (model input) accelerates the flange positively.

    Parameters
    ----------
    **modifiers
        ``tau`` sets the input's nominal value.
    """

    flange = Flange_b("flange the torque acts on")
    tau = Input(unit="N.m", description="accelerating torque")

    def equations(self) -> None:
        """``flange.tau = -tau``."""
        self.equation(self.flange.tau, -self.tau, name="torque")


class Fixed(Component):
    """Flange fixed in the housing at ``phi0`` (MSL ``Rotational.Components.Fixed``).

    Parameters
    ----------
    phi0 : float, optional
        Fixed angle [rad] (default 0).
    **modifiers
        Further modifiers (start values of variables, sub-components), see
        :class:`~gtmodel.modeling.components.component.Component`.
    """

    phi0 = Parameter(0.0, unit="rad", description="fixed offset angle of the housing")
    flange = Flange_b("fixed flange")

    def equations(self) -> None:
        """``flange.phi = phi0``."""
        self.equation(self.flange.phi, self.phi0, name="angle")


class IdealRollingWheel(Component):
    """Rotation to translation without slip (MSL ``Rotational.Components.IdealRollingWheel``).

    ``flangeR.phi radius = flangeT.s``, ``0 = radius flangeT.f + flangeR.tau``:
    a belt pulley or pinion of radius ``radius``.

    Parameters
    ----------
    radius : float, optional
        Wheel (pulley) radius [m], > 0 (default 0.3).
    **modifiers
        Further modifiers (start values of variables, sub-components), see
        :class:`~gtmodel.modeling.components.component.Component`.
    """

    radius = Parameter(0.3, unit="m", description="radius of the wheel", lb=0.0)
    flangeR = Flange_a("rotational flange (shaft)")  # noqa: N815 - MSL name
    flangeT = translational.Flange_b("translational flange (rim)")  # noqa: N815 - MSL name

    def equations(self) -> None:
        """Rolling without slip and the force/torque balance."""
        self.equation(self.flangeR.phi * self.radius, self.flangeT.s, name="position")
        self.equation(self.radius * self.flangeT.f + self.flangeR.tau, 0.0, name="force")
