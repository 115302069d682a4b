"""The Bryson-Denham problem's plant: a double integrator ``x'' = u`` (Bryson and Ho 1975, sec. 3.11).

The source states the problem without units (``x <= l = 1/9``, final time 1): every
variable is dimensionless, unit ``"1"``.
"""

from __future__ import annotations

from gtmodel.modeling import Model


class BrysonDenham(Model):
    """States x, v; input u; all dimensionless (unit "1", as in the source)."""

    def __init__(self) -> None:
        super().__init__("bryson_denham")
        x = self.state("x", unit="1")
        v = self.state("v", unit="1", start=1.0)
        u = self.input("u", unit="1")
        self.equation(self.der(x), v, name="position")
        self.equation(self.der(v), u, name="velocity")
