"""A double integrator ``x'' = u`` (a unit mass pushed by a bounded force): the textbook bang-bang problem.

Bryson and Ho (1975, sec. 7.3) state it without units (``|u| <= 1``, from 0 to 1): every
variable is dimensionless, unit ``"1"``.
"""

from __future__ import annotations

from gtmodel.modeling import Model


class DoubleIntegrator(Model):
    """States x (position), v (velocity); input u (acceleration); all dimensionless (unit "1")."""

    def __init__(self) -> None:
        super().__init__("double_integrator")
        x = self.state("x", unit="1")
        v = self.state("v", unit="1")
        u = self.input("u", unit="1")
        self.equation(self.der(x), v, name="position")
        self.equation(self.der(v), u, name="velocity")
