"""Particle steering of COPS 3.0 (Dolan, More, Munson 2004, problem 10; linear tangent steering).

A particle accelerated by a thrust of constant magnitude ``a`` whose direction ``u`` is
the control: ``y1'' = a cos(u)``, ``y2'' = a sin(u)``. COPS states the problem without units
(``a = 100``, height 5, speed 45): positions and velocities are scaled (unit ``"1"``), the
thrust angle ``u`` is in ``rad``.
"""

from __future__ import annotations

import casadi as ca

from gtmodel.modeling import Model


class ParticleSteering(Model):
    """States y1, y2 (position), y3, y4 (velocity); input u (thrust angle)."""

    def __init__(self) -> None:
        super().__init__("particle_steering")
        a = self.parameter("a", 100.0)
        y1, y2 = self.state("y1", unit="1"), self.state("y2", unit="1")
        y3, y4 = self.state("y3", unit="1"), self.state("y4", unit="1")
        u = self.input("u", unit="rad", start=0.5)
        self.equation(self.der(y1), y3, name="y1")
        self.equation(self.der(y2), y4, name="y2")
        self.equation(self.der(y3), a * ca.cos(u), name="y3")
        self.equation(self.der(y4), a * ca.sin(u), name="y4")
