"""The robot model projected onto a path: the row coefficients of :func:`path_rows_function`.

Independent reference: the inverse dynamics of :class:`GantryTau3Dynamics` (exact friction)
and the cart kinematics evaluated directly at ``T_dot = T' s_dot``, ``T_ddot = T'' s_dot^2 +
T' s_ddot``; the closed forms of the TCP rows.
"""

from __future__ import annotations

import numpy as np
import pytest

from gtmodel.errors import InputError
from gtmodel.robots.dynamics import GantryTau3Dynamics
from gtmodel.robots.kinematic_expressions import configuration_signs
from gtmodel.robots.kinematics import GantryTau3Kinematics
from gtmodel.robots.path_projection import PATH_LIMIT_KINDS, PATH_ROW_COUNTS, path_rows_function

#: Coefficient form against the direct evaluation (same model, rounding) [relative].
RTOL = 1e-9
T0 = np.array([-0.1, 2.8, -0.45])
DT = np.array([0.4, 0.25, -0.2])
DDT = np.array([0.3, -0.5, 0.2])


@pytest.fixture(scope="module")
def rows():
    dyn = GantryTau3Dynamics("L1", friction="exact")
    f = path_rows_function(dyn, PATH_LIMIT_KINDS)
    return dyn, {k: np.asarray(v).ravel() for k, v in f.call({"T": T0, "dT": DT, "ddT": DDT, "sg": configuration_signs(0)}).items()}


@pytest.mark.parametrize("sd, sdd", [(0.7, 0.0), (1.3, -2.0), (0.2, 5.0)])
def test_rows_reproduce_forces_cart_and_tcp_quantities(rows, sd, sdd):
    """m a + c b + d sqrt(b) + g, row by row, against the quantities evaluated directly."""
    dyn, r = rows
    T_dot, T_ddot = DT * sd, DDT * sd**2 + DT * sdd
    tau = dyn.inverse_dynamics(T0, T_dot, T_ddot, 0)
    _, q_dot, q_ddot = GantryTau3Kinematics("L1").cart_motion(T0, T_dot, T_ddot, 0)
    direct = np.concatenate([tau, q_dot**2, q_ddot, T_dot**2, [T_dot @ T_dot], T_ddot])
    value = r["m"] * sdd + r["c"] * sd**2 + r["d"] * sd + r["g"]
    assert value.size == sum(PATH_ROW_COUNTS.values())
    np.testing.assert_allclose(value, direct, rtol=RTOL, atol=RTOL * np.max(np.abs(direct)))


def test_without_viscous_friction_d_is_zero():
    f = path_rows_function(GantryTau3Dynamics("L1", friction="exact"), ("force_limit",), viscous=False)
    d = np.asarray(f(T0, DT, DDT, configuration_signs(0))[2])
    assert np.all(d == 0.0)


@pytest.mark.parametrize(
    "dynamics, kinds, match",
    [
        (None, ("force_limit",), "need a robot model"),
        (None, ("cart_velocity_limit",), "need a robot model"),
        (None, ("speed",), "unknown limit kinds"),
    ],
)
def test_bad_arguments(dynamics, kinds, match):
    with pytest.raises(InputError, match=match):
        path_rows_function(dynamics, kinds)


def test_tcp_rows_without_robot():
    """Closed forms: |T' s_dot|^2 = |T'|^2 b."""
    f = path_rows_function(None, ("tcp_speed_limit",))
    c = float(f(T0, DT, DDT, configuration_signs(0))[1])
    assert c == pytest.approx(DT @ DT, rel=1e-15)
