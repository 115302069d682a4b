"""Gantry-Tau parts on the 3-D frame connector: cart on a guideway, link, plate, and the 3-link robot.

The rigid-body model of Dressler (2012), ch. 6.2 (the point masses of eq. (6.7)), written
as acausal components on :class:`~gtmodel.modeling.components.connectors.Frame` (position ``r`` (3)
[m], cut force ``f`` (3) [N] acting on the component, world coordinates), named after their
counterparts in ``Modelica.Mechanics.MultiBody``:

* :class:`Fixed` — a frame fixed in the world;
* :class:`Cart` — a cart on a linear guideway: a prismatic joint along ``v`` from ``As``
  (``A = As + q v``, the actuator side of the closure equation (4.9)), a point mass ``m``
  and optional Coulomb (sign, tanh or piecewise-linear) + viscous friction (eq. (6.8)); the
  actuator force acts on a translational flange (connect a
  :class:`~gtmodel.modeling.library.translational.Force`, a drive axis or a friction element);
* :class:`Link` — a link cluster: a rod of fixed length ``L`` between two spherical joints
  with a point mass ``m`` at its midpoint (``Modelica.Mechanics.MultiBody.Joints.
  SphericalSpherical`` with its rod mass);
* :class:`Plate` — the end-effector plate: a point mass at the TCP, translation only
  (the parallelograms of the clusters keep the orientation constant), three link
  attachment frames at constant offsets;
* :class:`GantryTau3` — the three-link robot (three forces, carts, links and the plate,
  connected): a closed kinematic chain, index 3; ``Model.simulate`` reduces it
  (Pantelides + dummy derivatives, :mod:`gtmodel.modeling.structure.index_reduction`) and
  :func:`~gtmodel.modeling.simulation.inverse.inverse_model` gives its inverse dynamics::

      inv = inverse_model(GantryTau3(...).to_model(),
                          known=["plate.r", "plate.v", "der(plate.v)", "cart1.q", "cart2.q", "cart3.q"],
                          unknown=["force1.f", "force2.f", "force3.f"])
      tau1, tau2, tau3, closure = inv.function(T, T_dot, T_ddot, q1, q2, q3)

With the same masses these equations are Lagrange's equations of the point masses of
``gtmodel.robots.dynamics.GantryTau3Dynamics`` written in redundant coordinates with the
closure constraints: the cart's equation is the generalised-force balance along its
coordinate ``q``, the link's translational balance moves its midpoint mass, and its moment
balance (no inertia about the midpoint) leaves only the rod force along the link. The
modelling layer holds no robot data: the geometry, masses and friction are parameters,
set by modifiers (the test builds the L1 from ``gtmodel.robots.load_parameters("L1")``).
Gravity is a parameter vector ``g`` of each body (default ``(0, 0, -9.81)`` m/s^2, the
MultiBody ``world`` default).
"""

from __future__ import annotations

import casadi as ca

from gtmodel.modeling.components.component import Component, Parameter, State, Structural, Variable, connect
from gtmodel.modeling.components.connectors import Frame_a, Frame_b
from gtmodel.modeling.library import translational

__all__ = ["Fixed", "Cart", "Link", "Plate", "GantryTau3"]

#: Gravitational acceleration vector of the MultiBody ``world`` (m/s^2, along -z).
GRAVITY = (0.0, 0.0, -9.81)


class Fixed(Component):
    """Frame fixed in the world at ``r`` (``Modelica.Mechanics.MultiBody.Parts.Fixed``, translation only).

    Parameters
    ----------
    r : array_like, optional
        Position of the frame [m], shape (3,) (default the origin).
    **modifiers
        See :class:`~gtmodel.modeling.components.component.Component`.
    """

    r = Parameter([0.0, 0.0, 0.0], unit="m", description="position of the fixed frame")
    frame_b = Frame_b("the fixed frame")

    def equations(self) -> None:
        """``frame_b.r = r``."""
        self.equation(self.frame_b.r, self.r, name="position")


class Cart(Component):
    """Cart on a linear guideway: prismatic joint along ``v`` from ``As``, point mass, friction.

    The spherical-joint point ``frame_b.r = As + q v`` (the actuator side of the closure
    equation, Dressler (2012), eq. (4.9)); ``der(q) = q_dot``; the balance of generalised
    forces along ``q`` (the guideway takes the force normal to it)::

        m |v|^2 der(q_dot) = flange.f + v . frame_b.f + m v . g - f_fric
        f_fric = f_c sigma(q_dot) + f_v q_dot                                (eq. (6.8))

    ``flange`` (a translational flange, ``s = q``) takes the actuator force ``flange.f`` [N]
    (generalised force along ``q``; with ``|v| != 1`` the gear-ratio correction of the
    modified nominal model). Friction is off by default
    (``f_c = f_v = 0``); ``sigma`` is the sign in the form ``friction`` of
    ``gtmodel.robots.friction``: ``"tanh"`` (default, ``tanh(q_dot / friction_width)``),
    ``"piecewise"`` (linear on ``|q_dot| < friction_width``) or ``"exact"`` (``sign``: for
    inverse dynamics; a simulation needs events). Coulomb friction with stiction: leave
    ``f_c = 0`` and connect an event-driven friction element to ``flange``.

    Parameters
    ----------
    As : array_like, optional
        Joint point at ``q = 0`` [m], shape (3,) (default the origin).
    v : array_like, optional
        Guideway direction, shape (3,) (default ``e_x``; ``|v|`` need not be 1).
    m : float, optional
        Cart mass [kg], >= 0 (default 1).
    g : array_like, optional
        Gravitational acceleration vector [m/s^2], shape (3,) (default ``(0, 0, -9.81)``).
    f_c : float, optional
        Coulomb friction [N], >= 0 (default 0).
    f_v : float, optional
        Viscous friction [N s/m], >= 0 (default 0).
    friction_width : float, optional
        Velocity width of the smooth forms of the sign [m/s], > 0 (default 0.01).
    friction : {"tanh", "piecewise", "exact"}, optional
        Form of the sign in the Coulomb term (structural, default ``"tanh"``).
    **modifiers
        Start values of the states ``q`` [m] and ``q_dot`` [m/s], see
        :class:`~gtmodel.modeling.components.component.Component`.
    """

    As = Parameter([0.0, 0.0, 0.0], unit="m", description="spherical-joint point at q = 0")
    v = Parameter([1.0, 0.0, 0.0], unit="1", description="guideway direction (|v| != 1: gear-ratio correction)")
    m = Parameter(1.0, unit="kg", description="cart mass", lb=0.0)
    g = Parameter(list(GRAVITY), unit="m/s2", description="gravitational acceleration vector")
    f_c = Parameter(0.0, unit="N", description="Coulomb friction", lb=0.0)
    f_v = Parameter(0.0, unit="N.s/m", description="viscous friction", lb=0.0)
    friction_width = Parameter(0.01, unit="m/s", description="velocity width of the smooth sign", lb=1e-12)
    friction = Structural("tanh", choices=("tanh", "piecewise", "exact"), description="form of the Coulomb sign")
    q = State(unit="m", description="cart position along the guideway")
    q_dot = State(unit="m/s", description="cart velocity")
    frame_b = Frame_b("spherical-joint point A = As + q v")
    flange = translational.Flange_a("actuator flange: s = q, f = actuator force along the guideway")

    def equations(self) -> None:
        """Prismatic joint, kinematics and the force balance along the guideway (eqs. (4.9), (6.8))."""
        v = self.v
        x = self.q_dot / self.friction_width
        sigma = {"tanh": ca.tanh(x), "piecewise": ca.fmin(ca.fmax(x, -1), 1), "exact": ca.sign(self.q_dot)}[self.friction]
        f_fric = self.f_c * sigma + self.f_v * self.q_dot
        self.equation(self.frame_b.r, self.As + self.q * v, name="prismatic")
        self.equation(self.flange.s, self.q, name="flange_s")
        self.equation(self.der(self.q), self.q_dot, name="kinematics")
        self.equation(
            self.m * ca.dot(v, v) * self.der(self.q_dot),
            self.flange.f + ca.dot(v, self.frame_b.f) + self.m * ca.dot(v, self.g) - f_fric,
            name="newton",
        )
        self.output("f_friction", f_fric, unit="N")


class Link(Component):
    """Link cluster: rigid rod of length ``L`` between two spherical joints, point mass at its midpoint.

    ``Modelica.Mechanics.MultiBody.Joints.SphericalSpherical`` with a rod mass, as the
    link clusters of Dressler (2012), ch. 6.2 (``m_a,i`` at the link midpoint)::

        r_mid = (frame_a.r + frame_b.r) / 2,   der(r_mid) = v_mid
        m der(v_mid) = frame_a.f + frame_b.f + m g                   (translational balance)
        frame_b.f - frame_a.f = 2 f_rod (frame_b.r - frame_a.r) / L   (moment balance)
        |frame_b.r - frame_a.r|^2 = L^2                               (length, eq. (4.9))

    The moment balance about the midpoint of a rod without inertia there,
    ``(r_b - r_a)/2 x f_b - (r_b - r_a)/2 x f_a = 0``, has rank 2; its solutions are written
    with the rod force ``f_rod`` [N] (tension positive), the unknown that the length
    constraint determines (as ``f_rod`` of the MSL component).

    Parameters
    ----------
    L : float, optional
        Rod length [m], > 0 (default 1).
    m : float, optional
        Mass at the rod midpoint [kg], >= 0 (default 0).
    g : array_like, optional
        Gravitational acceleration vector [m/s^2], shape (3,) (default ``(0, 0, -9.81)``).
    **modifiers
        Start values of ``r_mid`` [m], ``v_mid`` [m/s] and ``f_rod`` [N], see
        :class:`~gtmodel.modeling.components.component.Component`.
    """

    L = Parameter(1.0, unit="m", description="rod length, joint centre to joint centre", lb=1e-12)
    m = Parameter(0.0, unit="kg", description="point mass at the rod midpoint", lb=0.0)
    g = Parameter(list(GRAVITY), unit="m/s2", description="gravitational acceleration vector")
    r_mid = State(unit="m", shape=3, description="position of the rod midpoint")
    v_mid = State(unit="m/s", shape=3, description="velocity of the rod midpoint")
    f_rod = Variable(unit="N", description="rod force along the rod, tension positive")
    frame_a = Frame_a("spherical joint a (cart side)")
    frame_b = Frame_b("spherical joint b (plate side)")

    def equations(self) -> None:
        """Midpoint kinematics, translational and moment balance, length constraint."""
        ra, rb = self.frame_a.r, self.frame_b.r
        d = rb - ra
        self.equation(self.r_mid, (ra + rb) / 2, name="midpoint")
        self.equation(self.der(self.r_mid), self.v_mid, name="kinematics")
        self.equation(self.m * self.der(self.v_mid), self.frame_a.f + self.frame_b.f + self.m * self.g, name="newton")
        self.equation(self.frame_b.f - self.frame_a.f, 2 * self.f_rod * d / self.L, name="moment")
        self.equation(ca.dot(d, d), self.L**2, name="length")
        self.output("length_error", ca.sqrt(ca.dot(d, d)) - self.L, unit="m")


class Plate(Component):
    """End-effector plate: point mass at the TCP, translation only, three link attachment frames.

    ``frame_i.r = r + b_i`` (the plate-side joint points of the links at constant offsets
    ``b_i`` from the TCP; the 3-link model of Dressler (2012), eqs. (4.7)-(4.9), has
    ``b_i = 0``: all links meet at the TCP), ``der(r) = v``,
    ``m der(v) = frame_1.f + frame_2.f + frame_3.f + m g``. The moments of the link forces
    are not balanced: the parallelograms of the link clusters hold the orientation.

    Parameters
    ----------
    m : float, optional
        Plate mass [kg], >= 0 (default 1).
    g : array_like, optional
        Gravitational acceleration vector [m/s^2], shape (3,) (default ``(0, 0, -9.81)``).
    b_1, b_2, b_3 : array_like, optional
        Offsets of the link attachment points from the TCP [m], shape (3,), world
        coordinates (default 0).
    **modifiers
        Start values of the TCP position ``r`` [m] and velocity ``v`` [m/s], see
        :class:`~gtmodel.modeling.components.component.Component`.
    """

    m = Parameter(1.0, unit="kg", description="plate mass at the TCP", lb=0.0)
    g = Parameter(list(GRAVITY), unit="m/s2", description="gravitational acceleration vector")
    b_1 = Parameter([0.0, 0.0, 0.0], unit="m", description="offset of the attachment of link 1 from the TCP")
    b_2 = Parameter([0.0, 0.0, 0.0], unit="m", description="offset of the attachment of link 2 from the TCP")
    b_3 = Parameter([0.0, 0.0, 0.0], unit="m", description="offset of the attachment of link 3 from the TCP")
    r = State(unit="m", shape=3, description="TCP position T")
    v = State(unit="m/s", shape=3, description="TCP velocity")
    frame_1 = Frame_a("attachment of link 1, r + b_1")
    frame_2 = Frame_a("attachment of link 2, r + b_2")
    frame_3 = Frame_a("attachment of link 3, r + b_3")

    def equations(self) -> None:
        """Attachment points, kinematics and Newton's second law of the plate."""
        frames = (self.frame_1, self.frame_2, self.frame_3)
        for k, (frame, b) in enumerate(zip(frames, (self.b_1, self.b_2, self.b_3)), 1):
            self.equation(frame.r, self.r + b, name=f"attachment_{k}")
        self.equation(self.der(self.r), self.v, name="kinematics")
        self.equation(self.m * self.der(self.v), sum((f.f for f in frames), self.m * self.g), name="newton")


class GantryTau3(Component):
    """The 3-link Gantry-Tau (Dressler (2012), eqs. (4.9), (6.7), (6.8)) assembled from its parts.

    ``force_i`` (:class:`~gtmodel.modeling.library.translational.Force`, input ``f`` [N])
    drives ``cart_i``; ``cart_i.frame_b`` -- ``link_i.frame_a``; ``link_i.frame_b`` --
    ``plate.frame_i``. Three closure constraints (the links' lengths) make it an index-3
    DAE with 3 degrees of freedom. The defaults are placeholders (unit geometry): give the
    robot's numbers as modifiers, e.g.
    ``GantryTau3(cart1={"As": As[0], "v": v[0], "m": m_c[0], "q": q0[0]}, link1={"L": L[0]},
    plate={"m": m_p, "r": T0})``, and consistent start values (positions from the inverse
    kinematics) for simulation.

    Parameters
    ----------
    **modifiers
        Sub-component modifiers: ``cart1``..``cart3`` (:class:`Cart`), ``link1``..``link3``
        (:class:`Link`), ``plate`` (:class:`Plate`), ``force1``..``force3``
        (:class:`~gtmodel.modeling.library.translational.Force`).
    """

    force1 = translational.Force()
    force2 = translational.Force()
    force3 = translational.Force()
    cart1 = Cart()
    cart2 = Cart()
    cart3 = Cart()
    link1 = Link()
    link2 = Link()
    link3 = Link()
    plate = Plate()

    def equations(self) -> None:
        """Actuator, cart-link and link-plate connections of the three arms."""
        plate_frames = (self.plate.frame_1, self.plate.frame_2, self.plate.frame_3)
        for i, frame in enumerate(plate_frames, 1):
            force, cart, link = (getattr(self, f"{k}{i}") for k in ("force", "cart", "link"))
            connect(force.flange, cart.flange)
            connect(cart.frame_b, link.frame_a)
            connect(link.frame_b, frame)
