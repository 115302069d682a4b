"""The brachistochrone: a bead sliding without friction under gravity along a wire of slope ``theta``.

SI units, as the problem is stated (Bryson and Ho 1975, sec. 2.7; the problem file: from
(0, 10) m to (10, 5) m under g = 9.80665 m/s^2).
"""

from __future__ import annotations

import casadi as ca

from gtmodel.modeling import Model


class Brachistochrone(Model):
    """States x, y (height), v (speed); input theta (angle of the wire from the downward vertical)."""

    def __init__(self) -> None:
        super().__init__("brachistochrone")
        g = self.parameter("g", 9.80665)
        x = self.state("x", unit="m")
        y = self.state("y", unit="m", start=10.0)
        v = self.state("v", unit="m/s")
        theta = self.input("theta", unit="rad", start=1.0)
        self.equation(self.der(x), v * ca.sin(theta), name="x")
        self.equation(self.der(y), -v * ca.cos(theta), name="y")
        self.equation(self.der(v), g * ca.cos(theta), name="v")
