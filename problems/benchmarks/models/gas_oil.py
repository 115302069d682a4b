"""Catalytic cracking of gas oil, COPS 3.0 (Dolan, More, Munson 2004, problem 13; Tjoa and Biegler 1991).

Gas oil ``y1`` cracks to gasoline ``y2`` and other products::

    y1' = -(theta1 + theta3) y1^2,   y2' = theta1 y1^2 - theta2 y2,   y(0) = (1, 0)

The rate constants ``theta`` are estimated from the 21 measurements of ``y1, y2`` in
``../data/gas_oil.csv`` (least squares). :class:`GasOilODE` is the model the problem file
fits with a ``[[data]]`` table; :class:`GasOil` is the same fit written without data tables:
one copy of the ODE per measurement time ``t_j``, in the scaled time ``s = t / t_j`` on
``[0, 1]`` (copy ``j`` at ``s = 1`` is the state at ``t_j``, exactly), and the output
``sse`` is the sum of squared residuals at the final time. ``y1``, ``y2`` are fractions
(``y(0) = (1, 0)``), unit ``"1"``.
"""

from __future__ import annotations

from pathlib import Path

import casadi as ca
import numpy as np

from gtmodel.modeling import Model

DATA = Path(__file__).resolve().parent.parent / "data" / "gas_oil.csv"


class GasOilODE(Model):
    """States y1 (gas oil), y2 (gasoline); parameters theta1..3 (rate constants)."""

    def __init__(self) -> None:
        super().__init__("gas_oil_ode")
        theta = [self.parameter(f"theta{i}", 1.0) for i in (1, 2, 3)]
        y1 = self.state("y1", unit="1", start=1.0)
        y2 = self.state("y2", unit="1", start=0.0)
        self.equation(self.der(y1), -(theta[0] + theta[2]) * y1**2, name="gas_oil")
        self.equation(self.der(y2), theta[0] * y1**2 - theta[1] * y2, name="gasoline")


class GasOil(Model):
    """States y1_j, y2_j per measurement time; parameters theta1..3; output sse."""

    def __init__(self) -> None:
        super().__init__("gas_oil")
        data = np.loadtxt(DATA, delimiter=",", skiprows=1)
        theta = [self.parameter(f"theta{i}", 1.0) for i in (1, 2, 3)]
        sse = ca.SX(0)
        for j, (tj, z1, z2) in enumerate(data):
            if tj == 0.0:
                continue  # the initial state is given: no residual to fit
            y1 = self.state(f"y1_{j}", unit="1", start=1.0)
            y2 = self.state(f"y2_{j}", unit="1", start=0.0)
            self.equation(self.der(y1), tj * (-(theta[0] + theta[2]) * y1**2), name=f"gas_oil_{j}")
            self.equation(self.der(y2), tj * (theta[0] * y1**2 - theta[1] * y2), name=f"gasoline_{j}")
            sse = sse + (y1 - z1) ** 2 + (y2 - z2) ** 2
        self.output("sse", sse, unit="1")
