"""Tumour anti-angiogenesis (Ledzewicz and Schaettler 2008; a GPOPS-II and PSOPT example).

Gompertzian tumour growth ``p' = -xi p ln(p / q)`` of volume ``p`` under a carrying
capacity ``q`` of the vasculature, ``q' = q (b - (mu + d p^(2/3) + G u))``, reduced by
an anti-angiogenic agent at rate ``u``; ``y' = u`` is the agent given so far.

Units of the source (Hahnfeldt et al. 1999 via Ledzewicz and Schaettler; Betts 2010, example
6.17): time in days, ``xi``, ``b``, ``mu`` per day, ``d`` per mm^2 per day, ``G`` kg per mg
per day. So ``p``, ``q`` are in ``mm3`` (``d p^(2/3)`` per day), ``u`` in ``mg/kg`` (``G u``
per day) and ``y``, its integral over days, in ``mg.d/kg``.
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
        p = self.state("p", unit="mm3", start=8000.0)
        q = self.state("q", unit="mm3", start=8000.0)
        y = self.state("y", unit="mg.d/kg")
        u = self.input("u", unit="mg/kg", start=30.0)
        self.equation(self.der(p), -xi * p * ca.log(p / q), name="tumour")
        self.equation(self.der(q), q * (b - (mu + d * p ** (2 / 3) + G * u)), name="vasculature")
        self.equation(self.der(y), u, name="agent")
