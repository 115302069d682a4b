"""A cart-pendulum: a cart on a horizontal rail pushed by a force, a pendulum hinged on it.

A user model for ``problems/cart_pendulum_swing_up.toml`` (kind ``optimal_control``)
and ``gtmodel codegen --model models/cart_pendulum.py:CartPendulum``. The pendulum is a
point mass ``m_pole`` at distance ``l`` from the hinge on a massless rod; ``theta = 0``
hangs down, ``theta = pi`` is upright. Lagrange's equations (e.g. Tedrake, *Underactuated
Robotics*, ch. 3, the cart-pole with ``theta`` from the downward vertical)::

    (m_cart + m_pole) s'' + m_pole l (theta'' cos(theta) - theta'^2 sin(theta)) = F - d s'
    l theta'' + s'' cos(theta) + g sin(theta) = 0

The equations are linear in the derivatives, as gtmodel's ``Model`` needs; it solves
them for ``der(v)`` and ``der(omega)`` when it flattens.
"""

from __future__ import annotations

import casadi as ca

from gtmodel.modeling import Model


class CartPendulum(Model):
    """Cart-pendulum with states s [m], v [m/s], theta [rad], omega [rad/s] and input F [N]."""

    def __init__(self) -> None:
        super().__init__("cart_pendulum")
        m_cart = self.parameter("m_cart", 1.0, min=1e-3)  # kg (a massless cart has no dynamics)
        m_pole = self.parameter("m_pole", 0.3, min=0.0)  # kg
        l = self.parameter("l", 0.5, min=1e-3)  # m, hinge to pole mass
        g = self.parameter("g", 9.81)  # m/s^2
        d = self.parameter("d", 0.0)  # N s/m, viscous friction of the cart
        s = self.state("s", unit="m")
        v = self.state("v", unit="m/s")
        theta = self.state("theta", unit="rad")
        omega = self.state("omega", unit="rad/s")
        F = self.input("F", unit="N")
        self.equation(self.der(s), v, name="cart_kinematics")
        self.equation(self.der(theta), omega, name="pole_kinematics")
        self.equation(
            (m_cart + m_pole) * self.der(v) + m_pole * l * (self.der(omega) * ca.cos(theta) - omega**2 * ca.sin(theta)),
            F - d * v,
            name="cart_momentum",
        )
        self.equation(l * self.der(omega) + self.der(v) * ca.cos(theta) + g * ca.sin(theta), 0, name="pole_moment")
        self.output("tip_x", s + l * ca.sin(theta), unit="m")
        self.output("tip_y", -l * ca.cos(theta), unit="m")  # hinge height 0
        kinetic = 0.5 * m_cart * v**2 + 0.5 * m_pole * ((v + l * omega * ca.cos(theta)) ** 2 + (l * omega * ca.sin(theta)) ** 2)
        self.output("energy", kinetic - m_pole * g * l * ca.cos(theta), unit="J")  # potential zero at the hinge height
