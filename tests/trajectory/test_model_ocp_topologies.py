"""Drive topologies the drive family does not have (tests/modeling/ocp/data/drive_topologies.py), solved by default.

Independent checks: the rotary table's minimum time against the closed form of its rigid, frictionless bound
(bang-coast-bang at the current limit's acceleration up to the motor's speed limit: ``T >= theta / w + w / a``), and
the lift's copper loss against the loss of holding the cage alone (``R i_hold^2 T``, ``i_hold = m g r / (n k)``): each
a lower bound the verified optimum must respect and, for the table, come within 1 % of.
"""

from __future__ import annotations

import pytest

from gtmodel.problems import load_problem

from ..conftest import REPO

DATA = REPO / "tests" / "modeling" / "ocp" / "data"

# the table: k 0.15 N m/A, |i| <= 8 A, gear 100, J 2 + 2e-4 * 100^2 kg m^2 at the table, |w_motor| <= 250 rad/s, 90 degrees
A_MAX = 0.15 * 8.0 * 100.0 / (2.0 + 2e-4 * 100.0**2)
W_MAX = 250.0 / 100.0
T_BOUND = (3.141592653589793 / 2) / W_MAX + W_MAX / A_MAX  # 0.7117 s
# the lift: R 0.5 Ohm, cage 294.3 N on a drum of 5 cm behind a gear of 10, k 0.5 N m/A, 2 s
I_HOLD = 294.3 * 0.05 / (10.0 * 0.5)
HOLD_LOSS = 0.5 * I_HOLD**2 * 2.0  # 8.66 J


@pytest.fixture(scope="module")
def table():
    return load_problem(DATA / "drive_topologies_table.toml").declaration.solve()


@pytest.fixture(scope="module")
def lift():
    return load_problem(DATA / "drive_topologies_lift.toml").declaration.solve()


@pytest.mark.slow
def test_rotary_table_is_optimal_and_verified_near_its_rigid_bound(table):
    assert str(table.status) == "optimal" and table.verification.passed
    assert T_BOUND <= table.final_time <= 1.01 * T_BOUND


@pytest.mark.slow
def test_lift_is_optimal_and_verified_above_its_holding_loss(lift):
    assert str(lift.status) == "optimal" and lift.verification.passed
    assert lift.objective > HOLD_LOSS
