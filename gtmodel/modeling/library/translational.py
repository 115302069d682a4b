"""1-D translational mechanics, named as ``Modelica.Mechanics.Translational``.

Connector: :class:`Flange_a` / :class:`Flange_b` with the position ``s`` [m], the
velocity ``v = der(s)`` [m/s], the acceleration ``a = der(v)`` [m/s^2] (potential
variables) and the cut force ``f`` [N] (flow, positive into the component). Velocity and
acceleration are carried in the connector (as ModelingToolkitStandardLibrary's
mechanical ports carry ``v``, and the MSL ``Move`` source ``s, v, a``) so that dampers
need no ``der()`` of an algebraic position and compliant chains flatten to index-1 DAEs
with today's :meth:`~gtmodel.modeling.Model.flatten`; unused ones are dropped (see
:mod:`gtmodel.modeling.components`).

Rigid couplings: a mass (or inertia) rigidly connected to another one that owns states
must be declared stateless, ``Mass(stateSelect="never")`` (Modelica ``StateSelect``):
it then takes ``s, v, a`` from its neighbour and the model stays index 1. Two
state-owning masses rigidly coupled are over-determined (the position, velocity and
acceleration constraints are all explicit), and index reduction does not repair that.

Components (Modelica Standard Library 4.0 names and equations):
:class:`Mass`, :class:`Spring`, :class:`Damper`, :class:`SpringDamper`, :class:`Force`,
:class:`Fixed`; the partial bases :class:`PartialTwoFlanges`, :class:`PartialCompliant`.
The optional ``support`` flanges of the MSL sources are omitted (support fixed).
"""

from __future__ import annotations

from gtmodel.modeling.components import Component, Input, Parameter, State, Structural, Variable
from gtmodel.modeling.connectors import Connector, Flow, Potential

__all__ = [
    "Flange",
    "Flange_a",
    "Flange_b",
    "PartialTwoFlanges",
    "PartialCompliant",
    "Mass",
    "Spring",
    "Damper",
    "SpringDamper",
    "Force",
    "Fixed",
]


class Flange(Connector):
    """Translational flange: position ``s`` [m], velocity ``v``, acceleration ``a``, cut force ``f`` [N].

    ``Modelica.Mechanics.Translational.Interfaces.Flange`` plus ``v = der(s)`` [m/s] and
    ``a = der(v)`` [m/s^2] (as the MSL ``Move`` source carries them).

    Parameters
    ----------
    description : str, optional
        Description of this connector instance.
    """

    s = Potential(unit="m", description="absolute position of the flange")
    v = Potential(unit="m/s", description="absolute velocity of the flange, der(s)")
    a = Potential(unit="m/s2", description="absolute acceleration of the flange, der(v)")
    f = Flow(unit="N", description="cut force directed into the flange")


class Flange_a(Flange):  # noqa: N801 - Modelica Standard Library name
    """Left translational flange (identical to :class:`Flange_b`, MSL naming).

    Parameters
    ----------
    description : str, optional
        Description of this connector instance.
    """


class Flange_b(Flange):  # noqa: N801 - Modelica Standard Library name
    """Right translational flange (identical to :class:`Flange_a`, MSL naming).

    Parameters
    ----------
    description : str, optional
        Description of this connector instance.
    """


class PartialTwoFlanges(Component):
    """Base of components with two translational flanges ``flange_a``, ``flange_b``.

    Parameters
    ----------
    **modifiers
        See :class:`~gtmodel.modeling.components.Component`.
    """

    flange_a = Flange_a("left flange")
    flange_b = Flange_b("right flange")


class PartialCompliant(PartialTwoFlanges):
    """Compliant connection of two flanges (no inertia): ``s_rel``, force ``f``.

    MSL ``PartialCompliant``: ``s_rel = flange_b.s - flange_a.s``, ``flange_b.f = f``,
    ``flange_a.f = -f``.

    Parameters
    ----------
    **modifiers
        See :class:`~gtmodel.modeling.components.Component`.
    """

    s_rel = Variable(unit="m", description="relative distance flange_b.s - flange_a.s")
    f = Variable(unit="N", description="force between the flanges, positive in the flange axis direction")

    def equations(self) -> None:
        """``s_rel = flange_b.s - flange_a.s``, ``flange_b.f = f``, ``flange_a.f = -f``."""
        self.equation(self.s_rel, self.flange_b.s - self.flange_a.s, name="s_rel")
        self.equation(self.flange_b.f, self.f, name="f_b")
        self.equation(self.flange_a.f, -self.f, name="f_a")


class Spring(PartialCompliant):
    """Linear spring: ``f = c (s_rel - s_rel0)`` (MSL ``Translational.Components.Spring``).

    Parameters
    ----------
    c : float, optional
        Spring constant [N/m], >= 0 (default 1).
    s_rel0 : float, optional
        Unstretched length [m] (default 0).
    **modifiers
        Further modifiers (start values of variables, sub-components), see
        :class:`~gtmodel.modeling.components.Component`.
    """

    c = Parameter(1.0, unit="N/m", description="spring constant", lb=0.0)
    s_rel0 = Parameter(0.0, unit="m", description="unstretched spring length")

    def equations(self) -> None:
        """Hooke's law, plus :class:`PartialCompliant`'s equations."""
        super().equations()
        self.equation(self.f, self.c * (self.s_rel - self.s_rel0), name="hooke")


class Damper(PartialCompliant):
    """Linear damper: ``f = d v_rel`` (MSL ``Translational.Components.Damper``).

    Parameters
    ----------
    d : float, optional
        Damping constant [N s/m], >= 0 (default 0).
    **modifiers
        Further modifiers (start values of variables, sub-components), see
        :class:`~gtmodel.modeling.components.Component`.
    """

    d = Parameter(0.0, unit="N.s/m", description="damping constant", lb=0.0)
    v_rel = Variable(unit="m/s", description="relative velocity flange_b.v - flange_a.v")

    def equations(self) -> None:
        """``v_rel = flange_b.v - flange_a.v``, ``f = d v_rel``, plus the base's."""
        super().equations()
        self.equation(self.v_rel, self.flange_b.v - self.flange_a.v, name="v_rel")
        self.equation(self.f, self.d * self.v_rel, name="damping")


class SpringDamper(PartialCompliant):
    """Spring and damper in parallel: ``f = c (s_rel - s_rel0) + d v_rel`` (MSL ``SpringDamper``).

    Parameters
    ----------
    c : float, optional
        Spring constant [N/m], >= 0 (default 1).
    d : float, optional
        Damping constant [N s/m], >= 0 (default 1).
    s_rel0 : float, optional
        Unstretched length [m] (default 0).
    **modifiers
        Further modifiers (start values of variables, sub-components), see
        :class:`~gtmodel.modeling.components.Component`.
    """

    c = Parameter(1.0, unit="N/m", description="spring constant", lb=0.0)
    d = Parameter(1.0, unit="N.s/m", description="damping constant", lb=0.0)
    s_rel0 = Parameter(0.0, unit="m", description="unstretched spring length")
    v_rel = Variable(unit="m/s", description="relative velocity flange_b.v - flange_a.v")

    def equations(self) -> None:
        """``v_rel = flange_b.v - flange_a.v``, ``f = c (s_rel - s_rel0) + d v_rel``, plus the base's."""
        super().equations()
        self.equation(self.v_rel, self.flange_b.v - self.flange_a.v, name="v_rel")
        self.equation(self.f, self.c * (self.s_rel - self.s_rel0) + self.d * self.v_rel, name="force")


class Mass(PartialTwoFlanges):
    """Sliding mass with inertia (MSL ``Translational.Components.Mass``).

    ``flange_a.s = s - L/2``, ``flange_b.s = s + L/2`` (and the velocities and
    accelerations), ``v = der(s)``, ``a = der(v)``, ``m a = flange_a.f + flange_b.f``.
    States ``s``, ``v`` (modifiers set their start values: ``Mass(m=2, s=0.1, v=0)``);
    with ``stateSelect="never"`` the mass owns no states and takes its motion from what it
    is rigidly connected to (a rigid coupling of two masses is otherwise over-determined).

    Parameters
    ----------
    m : float, optional
        Mass [kg], >= 0 (default 1).
    L : float, optional
        Length [m] between the flanges (default 0).
    stateSelect : {"default", "never"}, optional
        ``"never"``: ``s`` and ``v`` are algebraic (Modelica ``StateSelect.never``).
    **modifiers
        Further modifiers (start values of variables, sub-components), see
        :class:`~gtmodel.modeling.components.Component`.
    """

    m = Parameter(1.0, unit="kg", description="mass of the sliding mass", lb=0.0)
    L = Parameter(0.0, unit="m", description="length of the component, flange_a to flange_b")
    stateSelect = Structural("default", choices=("default", "never"), description="never: no states (rigid coupling)")  # noqa: N815
    s = State(unit="m", description="absolute position of the centre of the component")
    v = State(unit="m/s", description="absolute velocity of the component")
    a = Variable(unit="m/s2", description="absolute acceleration of the component")

    def equations(self) -> None:
        """Rigid flanges, kinematics (unless stateless) and Newton's second law."""
        self.equation(self.flange_a.s, self.s - self.L / 2, name="s_a")
        self.equation(self.flange_b.s, self.s + self.L / 2, name="s_b")
        self.equation(self.flange_a.v, self.v, name="v_a")
        self.equation(self.flange_b.v, self.v, name="v_b")
        self.equation(self.flange_a.a, self.a, name="a_a")
        self.equation(self.flange_b.a, self.a, name="a_b")
        if self.stateSelect != "never":
            self.equation(self.der(self.s), self.v, name="velocity")
            self.equation(self.der(self.v), self.a, name="acceleration")
        self.equation(self.m * self.a, self.flange_a.f + self.flange_b.f, name="newton")


class Force(Component):
    """External force from an input signal (MSL ``Translational.Sources.Force``, support fixed).

    ``flange.f = -f``: ``f`` [N] (model input) accelerates the flange in its positive direction.

    Parameters
    ----------
    **modifiers
        ``f`` sets the input's nominal value.
    """

    flange = Flange_b("flange the force acts on")
    f = Input(unit="N", description="driving force, positive in the flange axis direction")

    def equations(self) -> None:
        """``flange.f = -f``."""
        self.equation(self.flange.f, -self.f, name="force")


class Fixed(Component):
    """Flange fixed in the housing at ``s0`` (MSL ``Translational.Components.Fixed``).

    Parameters
    ----------
    s0 : float, optional
        Fixed position [m] (default 0).
    **modifiers
        Further modifiers (start values of variables, sub-components), see
        :class:`~gtmodel.modeling.components.Component`.
    """

    s0 = Parameter(0.0, unit="m", description="fixed offset position of the housing")
    flange = Flange_b("fixed flange")

    def equations(self) -> None:
        """``flange.s = s0``, ``flange.v = 0``, ``flange.a = 0``."""
        self.equation(self.flange.s, self.s0, name="position")
        self.equation(self.flange.v, 0.0, name="velocity")
        self.equation(self.flange.a, 0.0, name="acceleration")
