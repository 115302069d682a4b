"""Catalyst mixing of COPS 3.0 (Dolan, More, Munson 2004, problem 15; Gunn and Thomas 1965).

A tubular reactor with two catalysts; ``u`` is the fraction of the first one. Reactions
``A <-> B -> C``: ``x1' = u (10 x2 - x1)``, ``x2' = u (x1 - 10 x2) - (1 - u) x2``.
"""

from __future__ import annotations

from gtmodel.modeling import Model


class CatalystMixing(Model):
    """States x1, x2 (mole fractions of A and B); input u (fraction of the first catalyst); all unit "1"."""

    def __init__(self) -> None:
        super().__init__("catalyst_mixing")
        x1 = self.state("x1", unit="1", start=1.0)
        x2 = self.state("x2", unit="1")
        u = self.input("u", unit="1", start=0.5)
        self.equation(self.der(x1), u * (10 * x2 - x1), name="A")
        self.equation(self.der(x2), u * (x1 - 10 * x2) - (1 - u) * x2, name="B")
