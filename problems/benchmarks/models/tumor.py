"""Tumour anti-angiogenesis (Ledzewicz and Schaettler 2008; a GPOPS-II and PSOPT example).

Gompertzian tumour growth ``p' = -xi p ln(p / q)`` of volume ``p`` under a carrying
capacity ``q`` of the vasculature, ``q' = q (b - (mu + d p^(2/3) + G u))``, reduced by
an anti-angiogenic agent at rate ``u``; ``y' = u`` is the agent given so far.
"""

from __future__ import annotations

import casadi as ca

from gtmodel.modeling import Model


class TumorAntiangiogenesis(Model):
    """States p, q (volumes), y (agent given); input u (dose rate)."""

    def __init__(self) -> None:
        super().__init__("tumor_antiangiogenesis")
        xi = self.parameter("xi", 0.084)
        b = self.parameter("b", 5.85)
        d = self.parameter("d", 0.00873)
        G = self.parameter("G", 0.15)
        mu = self.parameter("mu", 0.02)
        p = self.state("p", start=8000.0)
        q = self.state("q", start=8000.0)
        y = self.state("y")
        u = self.input("u", start=30.0)
        self.equation(self.der(p), -xi * p * ca.log(p / q), name="tumour")
        self.equation(self.der(q), q * (b - (mu + d * p ** (2 / 3) + G * u)), name="vasculature")
        self.equation(self.der(y), u, name="agent")
