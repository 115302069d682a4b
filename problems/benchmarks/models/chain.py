"""The hanging chain of COPS 3.0 (Dolan, More, Munson 2004, problem 4), as an optimal control problem.

A chain of length ``L`` hangs between ``x(0) = a`` and ``x(1) = b``; its potential energy
``integral(x sqrt(1 + u^2))`` is minimised with ``x' = u``. The length constraint
``integral(sqrt(1 + u^2)) = L`` (isoperimetric) is an ``integral()`` constraint of the
problem file on :class:`Chain`; :class:`HangingChain` carries it as the state ``length``,
``length' = sqrt(1 + u^2)``, with ``length(0) = 0`` and ``length(1) = L`` (the same problem
written without integral constraints). COPS states the problem without units: every
variable is dimensionless, unit ``"1"``.
"""

from __future__ import annotations

import casadi as ca

from gtmodel.modeling import Model


class HangingChain(Model):
    """States x (height), length (arc length so far); input u = dx/dt."""

    def __init__(self) -> None:
        super().__init__("hanging_chain")
        x = self.state("x", unit="1")
        length = self.state("length", unit="1")
        u = self.input("u", unit="1")
        self.equation(self.der(x), u, name="slope")
        self.equation(self.der(length), ca.sqrt(1 + u**2), name="arc_length")


class Chain(Model):
    """State x (height); input u = dx/dt (the length constraint is an integral() of the problem)."""

    def __init__(self) -> None:
        super().__init__("chain")
        x = self.state("x", unit="1")
        u = self.input("u", unit="1")
        self.equation(self.der(x), u, name="slope")
