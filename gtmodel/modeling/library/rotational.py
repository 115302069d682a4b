"""1-D rotational mechanics, named as ``Modelica.Mechanics.Rotational``.

Connector: :class:`Flange_a` / :class:`Flange_b` with the angle ``phi`` [rad] (potential)
and the cut torque ``tau`` [N m] (flow, positive into the component), as in the MSL;
speeds are component-internal (``w = der(phi)``; see
:mod:`gtmodel.modeling.library.translational` for the index of the resulting models).

Components (Modelica Standard Library 4.0 names and equations, support flanges fixed):
:class:`Inertia`, :class:`IdealGear`, :class:`Spring`, :class:`Damper`,
:class:`SpringDamper`, :class:`Torque`, :class:`Fixed`, and :class:`IdealRollingWheel`
(rotation to translation, e.g. a belt pulley). Non-smooth elements with a declared
smoothing width (``Model.smoothing``; the laws and their errors in each class):
:class:`ElastoBacklash` (MSL ``ElastoBacklash``) and :class:`Friction` (Coulomb, viscous
and Stribeck, smoothed; the event-based MSL friction is :mod:`gtmodel.modeling.library.friction`).
"""

from __future__ import annotations

import casadi as ca

from gtmodel.modeling.components.component import Component, Input, Parameter, State, Variable
from gtmodel.modeling.components.connectors import Connector, Flow, Potential
from gtmodel.modeling.library import translational
from gtmodel.modeling.library.blocks import _Positive, smooth_dead_zone, smooth_sign, smooth_step

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
    "ElastoBacklash",
    "Friction",
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


class ElastoBacklash(PartialCompliantWithRelativeStates):
    """Backlash in series with a stiff, damped contact (MSL ``Rotational.Components.ElastoBacklash``), smoothed.

    A spring-damper that acts only outside a total gap ``b`` (free play ``b/2`` to each
    side of ``phi_rel0``). With ``x = phi_rel - phi_rel0``:

    * exact law: ``tau = c dz(x) + d w_rel H(|x| - b/2)``, the dead zone
      ``dz(x) = x - min(max(x, -b/2), b/2)`` and the contact indicator ``H`` (1 in contact);
    * smooth law: ``tau = c dz_eps(x) + d w_rel dz_eps'(x)`` with
      ``dz_eps(x) = softplus(x - b/2) - softplus(-x - b/2)``,
      ``softplus(y) = eps ln(1 + exp(y/eps))`` (:func:`~gtmodel.modeling.library.blocks.smooth_dead_zone`),
      and its derivative ``dz_eps'(x) = s(x - b/2) + s(-x - b/2)``, ``s`` the logistic
      (:func:`~gtmodel.modeling.library.blocks.smooth_step`), in ``(0, 1]``: the damping
      acts in contact only, smoothly;
    * worst-case error: spring torque ``c eps ln 2`` (at a corner ``x = +-b/2``), below
      ``c eps exp(-delta/eps)`` at a distance ``delta`` from both corners; damping factor
      ``1/2`` at a corner, below ``2 exp(-delta/eps)`` away. The limit ``eps -> 0`` is the
      exact law; with ``b = 0`` the smooth law is the linear spring-damper exactly.

    The MSL element also limits the damping torque so that the contact never pulls
    (``tau = c dz + min(tau_c, tau_d)`` in contact, 0 if that changes sign); that clamp is
    not modelled: here the damping acts in full while in contact.

    Parameters
    ----------
    c : float, optional
        Contact (spring) stiffness [N m/rad], >= 0 (default 1e5).
    d : float, optional
        Contact damping [N m s/rad], >= 0 (default 0).
    b : float, optional
        Total backlash [rad], >= 0 (default 0).
    phi_rel0 : float, optional
        Relative angle at the middle of the gap [rad] (default 0).
    smoothing : float, optional
        Smoothing width ``eps`` [rad], > 0 (default 1e-5); listed in ``Model.smoothing``.
    **modifiers
        Further modifiers (start values of ``phi_rel``, ...), see
        :class:`~gtmodel.modeling.components.component.Component`.

    Raises
    ------
    InputError
        If ``c``, ``d`` or ``b`` is negative or ``smoothing <= 0``.
    """

    c = Parameter(1e5, unit="N.m/rad", description="contact stiffness", lb=0.0)
    d = Parameter(0.0, unit="N.m.s/rad", description="contact damping", lb=0.0)
    b = Parameter(0.0, unit="rad", description="total backlash", lb=0.0)
    phi_rel0 = Parameter(0.0, unit="rad", description="relative angle at the middle of the gap")
    smoothing = Parameter(1e-5, unit="rad", description="smoothing width of the dead zone, > 0", smoothing=True)

    def equations(self) -> None:
        """``tau = c dz_eps(x) + d w_rel dz_eps'(x)``, ``x = phi_rel - phi_rel0``, plus the base's equations."""
        super().equations()
        x, half, eps = self.phi_rel - self.phi_rel0, self.b / 2, self.smoothing
        contact = smooth_step(x - half, eps) + smooth_step(-x - half, eps)
        self.equation(self.tau, self.c * smooth_dead_zone(x, -half, half, eps) + self.d * self.w_rel * contact,
                      name="backlash")


class Friction(PartialCompliantWithRelativeStates):
    """Coulomb, viscous and Stribeck friction torque, smoothed (connected between support and flange).

    Connected between the support (``flange_a``, e.g. to :class:`Fixed`) and the moving
    flange (``flange_b``): ``w_rel`` is the flange's speed relative to the support [rad/s]
    and ``tau`` [N m] brakes it. With ``w = w_rel``:

    * exact law: ``tau = (Fc + Fs exp(-(w/ws)^2)) sign(w) + dv w`` for ``w != 0``, and any
      torque in ``[-(Fc + Fs), Fc + Fs]`` at ``w = 0`` (stiction; breakaway torque
      ``Fc + Fs``);
    * smooth law: ``tau = (Fc + Fs exp(-(w/ws)^2)) tanh(w/eps) + dv w``
      (:func:`~gtmodel.modeling.library.blocks.smooth_sign`);
    * worst-case error: ``Fc + Fs`` as ``w -> 0`` (the smooth torque passes through 0
      where the exact one jumps), below ``2 (Fc + Fs) exp(-2|w|/eps)`` at speed ``|w|``.
      The limit ``eps -> 0`` is the exact law for ``w != 0``. The smooth law cannot
      stick: under a torque ``T`` below breakaway it creeps at about
      ``eps artanh(T / (Fc + Fs))``.

    ``Fs = 0`` is Coulomb and viscous friction without the Stribeck effect. MSL's
    ``BearingFriction`` (a stick-slip state machine with events) is
    :mod:`gtmodel.modeling.library.friction`.

    Parameters
    ----------
    Fc : float, optional
        Coulomb friction torque [N m], >= 0 (default 1).
    Fs : float, optional
        Stribeck excess of the breakaway torque over ``Fc`` [N m], >= 0 (default 0).
    ws : float, optional
        Stribeck speed [rad/s], > 0 (default 0.1).
    dv : float, optional
        Viscous friction coefficient [N m s/rad], >= 0 (default 0).
    smoothing : float, optional
        Smoothing width ``eps`` [rad/s], > 0 (default 1e-2); listed in ``Model.smoothing``.
    **modifiers
        Further modifiers (start values of ``phi_rel``, ...), see
        :class:`~gtmodel.modeling.components.component.Component`.

    Raises
    ------
    InputError
        If ``Fc``, ``Fs`` or ``dv`` is negative, or ``ws`` or ``smoothing`` is not > 0.
    """

    Fc = Parameter(1.0, unit="N.m", description="Coulomb friction torque", lb=0.0)
    Fs = Parameter(0.0, unit="N.m", description="Stribeck excess of the breakaway torque over Fc", lb=0.0)
    ws = _Positive(0.1, unit="rad/s", description="Stribeck speed, > 0")
    dv = Parameter(0.0, unit="N.m.s/rad", description="viscous friction coefficient", lb=0.0)
    smoothing = Parameter(1e-2, unit="rad/s", description="smoothing width of sign(w), > 0", smoothing=True)

    def equations(self) -> None:
        """``tau = (Fc + Fs exp(-(w_rel/ws)^2)) tanh(w_rel/eps) + dv w_rel``, plus the base's equations."""
        super().equations()
        w = self.w_rel
        level = self.Fc + self.Fs * ca.exp(-((w / self.ws) ** 2))
        self.equation(self.tau, level * smooth_sign(w, self.smoothing) + self.dv * w, name="friction")
