"""The Goddard rocket of COPS 3.0 (Dolan, More, Munson 2004, problem 11), in its scaled units.

Vertical ascent with drag ``D = Dc v^2 exp(-hc (h - h0) / h0)`` and gravity
``g = g0 (h0 / h)^2``; thrust ``T`` burns fuel at ``T / c``. The data of COPS: ``h0 = m0 =
g0 = 1``, ``Tc = 3.5``, ``hc = 500``, ``vc = 620``, ``mc = 0.6``; ``c = 0.5 sqrt(g0 h0)``,
``Dc = 0.5 vc m0 / g0``, ``T_max = Tc g0 m0``.
"""

from __future__ import annotations

import casadi as ca

from gtmodel.modeling import Model


class GoddardRocket(Model):
    """States h (height), v (velocity), m (mass); input T (thrust); all in COPS' scaled units (unit "1": h0 = m0 = g0 = 1)."""

    def __init__(self) -> None:
        super().__init__("goddard_rocket")
        h0, g0, m0 = 1.0, 1.0, 1.0
        hc = self.parameter("hc", 500.0)
        vc = self.parameter("vc", 620.0)
        c = 0.5 * (g0 * h0) ** 0.5
        Dc = 0.5 * vc * m0 / g0
        h = self.state("h", unit="1", start=1.0)
        v = self.state("v", unit="1", start=0.0)
        m = self.state("m", unit="1", start=1.0)
        T = self.input("T", unit="1", start=1.75)
        drag = Dc * v**2 * ca.exp(-hc * (h - h0) / h0)
        self.equation(self.der(h), v, name="height")
        self.equation(self.der(v), (T - drag) / m - g0 * (h0 / h) ** 2, name="momentum")
        self.equation(self.der(m), -T / c, name="fuel")
