"""1-D translational mechanics, named as ``Modelica.Mechanics.Translational``.

Connector: :class:`Flange_a` / :class:`Flange_b` with the position ``s`` [m] (potential)
and the cut force ``f`` [N] (flow, positive into the component), as in the MSL.
Velocities are component-internal (``v = der(s)`` in :class:`Mass`, ``v_rel =
der(s_rel)`` with the relative states of :class:`Damper` and :class:`SpringDamper`, as
MSL's ``PartialCompliantWithRelativeStates``). A model with a damper or a rigid coupling
(two masses joined directly) is therefore of higher index; ``Model.simulate`` reduces it
(:func:`gtmodel.modeling.structure.index_reduction.structural_simplify`: alias elimination,
Pantelides, dummy derivatives). A chain of masses and springs only is index 1.

Components (Modelica Standard Library 4.0 names and equations):
:class:`Mass`, :class:`Spring`, :class:`Damper`, :class:`SpringDamper`, :class:`Force`,
:class:`Fixed`; the partial bases :class:`PartialTwoFlanges`, :class:`PartialCompliant`.
Non-smooth elements with a declared smoothing width (``Model.smoothing``; laws and
errors in each class): :class:`ElastoBacklash` (two-sided gap; MSL's one-sided analogue is
``ElastoGap``) and :class:`Friction` (Coulomb, viscous and Stribeck, smoothed).
The optional ``support`` flanges of the MSL sources are omitted (support fixed).
"""

from __future__ import annotations

import casadi as ca

from gtmodel.modeling.components.component import Component, Input, Parameter, State, Variable
from gtmodel.modeling.components.connectors import Connector, Flow, Potential
from gtmodel.modeling.library.blocks import _Positive, smooth_dead_zone, smooth_sign, smooth_step

__all__ = [
    "Flange",
    "Flange_a",
    "Flange_b",
    "PartialTwoFlanges",
    "PartialCompliant",
    "PartialCompliantWithRelativeStates",
    "Mass",
    "Spring",
    "Damper",
    "SpringDamper",
    "Force",
    "Fixed",
    "ElastoBacklash",
    "Friction",
]


class Flange(Connector):
    """Translational flange: position ``s`` [m], cut force ``f`` [N] (MSL ``Interfaces.Flange``).

    Parameters
    ----------
    description : str, optional
        Description of this connector instance.
    """

    s = Potential(unit="m", description="absolute position of the flange")
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
        See :class:`~gtmodel.modeling.components.component.Component`.
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
        See :class:`~gtmodel.modeling.components.component.Component`.
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
        :class:`~gtmodel.modeling.components.component.Component`.
    """

    c = Parameter(1.0, unit="N/m", description="spring constant", lb=0.0)
    s_rel0 = Parameter(0.0, unit="m", description="unstretched spring length")

    def equations(self) -> None:
        """Hooke's law, plus :class:`PartialCompliant`'s equations."""
        super().equations()
        self.equation(self.f, self.c * (self.s_rel - self.s_rel0), name="hooke")


class PartialCompliantWithRelativeStates(PartialCompliant):
    """Compliant connection with the relative position as a state (MSL base of dampers).

    MSL ``PartialCompliantWithRelativeStates``: :class:`PartialCompliant`'s equations with
    ``s_rel`` a state and ``v_rel = der(s_rel)``.

    Parameters
    ----------
    **modifiers
        Further modifiers (start values of variables, sub-components), see
        :class:`~gtmodel.modeling.components.component.Component`.
    """

    s_rel = State(unit="m", description="relative distance flange_b.s - flange_a.s")
    v_rel = Variable(unit="m/s", description="relative velocity der(s_rel)")

    def equations(self) -> None:
        """:class:`PartialCompliant`'s equations and ``v_rel = der(s_rel)``."""
        super().equations()
        self.equation(self.v_rel, self.der(self.s_rel), name="v_rel")


class Damper(PartialCompliantWithRelativeStates):
    """Linear damper: ``f = d v_rel`` (MSL ``Translational.Components.Damper``).

    Parameters
    ----------
    d : float, optional
        Damping constant [N s/m], >= 0 (default 0).
    **modifiers
        Further modifiers (start values of variables, sub-components), see
        :class:`~gtmodel.modeling.components.component.Component`.
    """

    d = Parameter(0.0, unit="N.s/m", description="damping constant", lb=0.0)

    def equations(self) -> None:
        """``f = d v_rel``, plus the base's equations."""
        super().equations()
        self.equation(self.f, self.d * self.v_rel, name="damping")


class SpringDamper(PartialCompliantWithRelativeStates):
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
        :class:`~gtmodel.modeling.components.component.Component`.
    """

    c = Parameter(1.0, unit="N/m", description="spring constant", lb=0.0)
    d = Parameter(1.0, unit="N.s/m", description="damping constant", lb=0.0)
    s_rel0 = Parameter(0.0, unit="m", description="unstretched spring length")

    def equations(self) -> None:
        """``f = c (s_rel - s_rel0) + d v_rel``, plus the base's equations."""
        super().equations()
        self.equation(self.f, self.c * (self.s_rel - self.s_rel0) + self.d * self.v_rel, name="force")


class Mass(PartialTwoFlanges):
    """Sliding mass with inertia (MSL ``Translational.Components.Mass``).

    ``flange_a.s = s - L/2``, ``flange_b.s = s + L/2``, ``v = der(s)``, ``a = der(v)``,
    ``m a = flange_a.f + flange_b.f``. States ``s``, ``v`` (modifiers set their start
    values: ``Mass(m=2, s=0.1, v=0)``); rigidly coupled masses are reduced to one set of
    states by ``Model.simulate`` (index reduction).

    Parameters
    ----------
    m : float, optional
        Mass [kg], >= 0 (default 1).
    L : float, optional
        Length [m] between the flanges (default 0).
    **modifiers
        Further modifiers (start values of variables, sub-components), see
        :class:`~gtmodel.modeling.components.component.Component`.
    """

    m = Parameter(1.0, unit="kg", description="mass of the sliding mass", lb=0.0)
    L = Parameter(0.0, unit="m", description="length of the component, flange_a to flange_b")
    s = State(unit="m", description="absolute position of the centre of the component")
    v = State(unit="m/s", description="absolute velocity of the component")
    a = Variable(unit="m/s2", description="absolute acceleration of the component")

    def equations(self) -> None:
        """Rigid flanges, kinematics and Newton's second law."""
        self.equation(self.flange_a.s, self.s - self.L / 2, name="s_a")
        self.equation(self.flange_b.s, self.s + self.L / 2, name="s_b")
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
        :class:`~gtmodel.modeling.components.component.Component`.
    """

    s0 = Parameter(0.0, unit="m", description="fixed offset position of the housing")
    flange = Flange_b("fixed flange")

    def equations(self) -> None:
        """``flange.s = s0``."""
        self.equation(self.flange.s, self.s0, name="position")


class ElastoBacklash(PartialCompliantWithRelativeStates):
    """Backlash in series with a stiff, damped contact (translational ``ElastoBacklash``), smoothed.

    The translational counterpart of MSL ``Rotational.Components.ElastoBacklash`` (a
    nut in a screw with play, a rack and pinion): a spring-damper that acts only outside
    a total gap ``b`` (free play ``b/2`` to each side of ``s_rel0``). The MSL has no
    translational element of this name; its ``Translational.Components.ElastoGap`` is the
    one-sided contact (one wall), and this element is two such walls ``b`` apart. With
    ``x = s_rel - s_rel0``:

    * exact law: ``f = c dz(x) + d v_rel H(|x| - b/2)``, the dead zone
      ``dz(x) = x - min(max(x, -b/2), b/2)`` and the contact indicator ``H`` (1 in contact);
    * smooth law: ``f = c dz_eps(x) + d v_rel dz_eps'(x)`` with
      ``dz_eps(x) = softplus(x - b/2) - softplus(-x - b/2)``,
      ``softplus(y) = eps ln(1 + exp(y/eps))`` (:func:`~gtmodel.modeling.library.blocks.smooth_dead_zone`),
      and ``dz_eps'(x) = s(x - b/2) + s(-x - b/2)``, ``s`` the logistic
      (:func:`~gtmodel.modeling.library.blocks.smooth_step`), in ``(0, 1]``: the damping
      acts in contact only, smoothly;
    * worst-case error: spring force ``c eps ln 2`` (at a corner ``x = +-b/2``), below
      ``c eps exp(-delta/eps)`` at a distance ``delta`` from both corners; damping factor
      ``1/2`` at a corner, below ``2 exp(-delta/eps)`` away. The limit ``eps -> 0`` is the
      exact law; with ``b = 0`` the smooth law is the linear spring-damper exactly.

    As in the rotational element, MSL's clamp of the damping force (a contact that never
    pulls) is not modelled.

    Parameters
    ----------
    c : float, optional
        Contact (spring) stiffness [N/m], >= 0 (default 1e6).
    d : float, optional
        Contact damping [N s/m], >= 0 (default 0).
    b : float, optional
        Total backlash [m], >= 0 (default 0).
    s_rel0 : float, optional
        Relative position at the middle of the gap [m] (default 0).
    smoothing : float, optional
        Smoothing width ``eps`` [m], > 0 (default 1e-6); listed in ``Model.smoothing``.
    **modifiers
        Further modifiers (start values of ``s_rel``, ...), see
        :class:`~gtmodel.modeling.components.component.Component`.

    Raises
    ------
    InputError
        If ``c``, ``d`` or ``b`` is negative or ``smoothing <= 0``.
    """

    c = Parameter(1e6, unit="N/m", description="contact stiffness", lb=0.0)
    d = Parameter(0.0, unit="N.s/m", description="contact damping", lb=0.0)
    b = Parameter(0.0, unit="m", description="total backlash", lb=0.0)
    s_rel0 = Parameter(0.0, unit="m", description="relative position at the middle of the gap")
    smoothing = Parameter(1e-6, unit="m", description="smoothing width of the dead zone, > 0", smoothing=True)

    def equations(self) -> None:
        """``f = c dz_eps(x) + d v_rel dz_eps'(x)``, ``x = s_rel - s_rel0``, plus the base's equations."""
        super().equations()
        x, half, eps = self.s_rel - self.s_rel0, self.b / 2, self.smoothing
        contact = smooth_step(x - half, eps) + smooth_step(-x - half, eps)
        self.equation(self.f, self.c * smooth_dead_zone(x, -half, half, eps) + self.d * self.v_rel * contact,
                      name="backlash")


class Friction(PartialCompliantWithRelativeStates):
    """Coulomb, viscous and Stribeck friction force, smoothed (connected between support and flange).

    Connected between the support (``flange_a``, e.g. to :class:`Fixed`) and the moving
    flange (``flange_b``): ``v_rel`` is the flange's speed relative to the support [m/s]
    and ``f`` [N] brakes it. With ``v = v_rel``:

    * exact law: ``f = (Fc + Fs exp(-(v/vs)^2)) sign(v) + dv v`` for ``v != 0``, and any
      force in ``[-(Fc + Fs), Fc + Fs]`` at ``v = 0`` (stiction; breakaway force ``Fc + Fs``);
    * smooth law: ``f = (Fc + Fs exp(-(v/vs)^2)) tanh(v/eps) + dv v``
      (:func:`~gtmodel.modeling.library.blocks.smooth_sign`);
    * worst-case error: ``Fc + Fs`` as ``v -> 0`` (the smooth force passes through 0
      where the exact one jumps), below ``2 (Fc + Fs) exp(-2|v|/eps)`` at speed ``|v|``.
      The limit ``eps -> 0`` is the exact law for ``v != 0``. The smooth law cannot
      stick: under a force ``F`` below breakaway it creeps at about
      ``eps artanh(F / (Fc + Fs))``.

    ``Fs = 0`` is Coulomb and viscous friction without the Stribeck effect. The MSL's
    stick-slip friction with events is :mod:`gtmodel.modeling.library.friction`.

    Parameters
    ----------
    Fc : float, optional
        Coulomb friction force [N], >= 0 (default 1).
    Fs : float, optional
        Stribeck excess of the breakaway force over ``Fc`` [N], >= 0 (default 0).
    vs : float, optional
        Stribeck speed [m/s], > 0 (default 0.01).
    dv : float, optional
        Viscous friction coefficient [N s/m], >= 0 (default 0).
    smoothing : float, optional
        Smoothing width ``eps`` [m/s], > 0 (default 1e-3); listed in ``Model.smoothing``.
    **modifiers
        Further modifiers (start values of ``s_rel``, ...), see
        :class:`~gtmodel.modeling.components.component.Component`.

    Raises
    ------
    InputError
        If ``Fc``, ``Fs`` or ``dv`` is negative, or ``vs`` or ``smoothing`` is not > 0.
    """

    Fc = Parameter(1.0, unit="N", description="Coulomb friction force", lb=0.0)
    Fs = Parameter(0.0, unit="N", description="Stribeck excess of the breakaway force over Fc", lb=0.0)
    vs = _Positive(0.01, unit="m/s", description="Stribeck speed, > 0")
    dv = Parameter(0.0, unit="N.s/m", description="viscous friction coefficient", lb=0.0)
    smoothing = Parameter(1e-3, unit="m/s", description="smoothing width of sign(v), > 0", smoothing=True)

    def equations(self) -> None:
        """``f = (Fc + Fs exp(-(v_rel/vs)^2)) tanh(v_rel/eps) + dv v_rel``, plus the base's equations."""
        super().equations()
        v = self.v_rel
        level = self.Fc + self.Fs * ca.exp(-((v / self.vs) ** 2))
        self.equation(self.f, level * smooth_sign(v, self.smoothing) + self.dv * v, name="friction")
