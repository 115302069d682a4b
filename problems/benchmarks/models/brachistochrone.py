"""The brachistochrone: a bead sliding without friction under gravity along a wire of slope ``theta``."""

from __future__ import annotations

import casadi as ca

from gtmodel.modeling import Model


class Brachistochrone(Model):
    """States x, y (height), v (speed); input theta (angle of the wire from the downward vertical)."""

    def __init__(self) -> None:
        super().__init__("brachistochrone")
        g = self.parameter("g", 9.80665)
        x = self.state("x")
        y = self.state("y", start=10.0)
        v = self.state("v")
        theta = self.input("theta", start=1.0)
        self.equation(self.der(x), v * ca.sin(theta), name="x")
        self.equation(self.der(y), -v * ca.cos(theta), name="y")
        self.equation(self.der(v), g * ca.cos(theta), name="v")
