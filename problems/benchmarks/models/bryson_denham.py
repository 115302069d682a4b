"""The Bryson-Denham problem's plant: a double integrator ``x'' = u`` (Bryson and Ho 1975, sec. 3.11)."""

from __future__ import annotations

from gtmodel.modeling import Model


class BrysonDenham(Model):
    """States x, v; input u; output energy rate u^2 / 2."""

    def __init__(self) -> None:
        super().__init__("bryson_denham")
        x = self.state("x")
        v = self.state("v", start=1.0)
        u = self.input("u")
        self.equation(self.der(x), v, name="position")
        self.equation(self.der(v), u, name="velocity")
