"""A double integrator ``x'' = u`` (a unit mass pushed by a bounded force): the textbook bang-bang problem."""

from __future__ import annotations

from gtmodel.modeling import Model


class DoubleIntegrator(Model):
    """States x (position), v (velocity); input u (acceleration)."""

    def __init__(self) -> None:
        super().__init__("double_integrator")
        x = self.state("x")
        v = self.state("v")
        u = self.input("u")
        self.equation(self.der(x), v, name="position")
        self.equation(self.der(v), u, name="velocity")
