"""Excitation trajectories (Swevers et al. 1997) for the identification of Dressler (2012), ch. 6.2."""

from __future__ import annotations

import numpy as np
import pytest

from gtmodel.calibration.identification import DynamicRegressor, FourierTrajectory, design_excitation, regressor_condition
from gtmodel.errors import GtModelError, InputError
from gtmodel.robots.kinematics import GantryTau3Kinematics
from gtmodel.robots.parameters import load_parameters

#: Central differences on a 1 ms grid against the closed-form derivatives [m/s, m/s^2].
DERIVATIVE_TOLERANCE = 1e-4
#: The optimised design must at least halve the condition number of the random start.
CONDITION_IMPROVEMENT = 2.0
#: Limits checked on a 10x finer grid than the NLP's: allowed violation (m, m/s, m/s^2, cos).
VIOLATION_TOLERANCE = 0.02
#: TCP position in the L1 workspace about which the excitation is designed [m].
T_CENTER_L1 = (0.0, 2.9, -0.5)


@pytest.fixture(scope="module")
def design():
    return design_excitation("L1", "model_2", T_center=T_CENTER_L1, harmonics=3, period=8.0, n_grid=40, seed=0, max_iter=80)


def test_fourier_derivatives_match_finite_differences():
    """q_dot and q_ddot of the series equal central differences of q (second method) and the
    motion is periodic."""
    rng = np.random.default_rng(0)
    tr = FourierTrajectory([0.1, 0.2, 0.3], 0.1 * rng.standard_normal((3, 4)), 0.1 * rng.standard_normal((3, 4)), 5.0)
    t = np.arange(0, 5.0, 1e-3)
    q, qd, qdd = tr.evaluate(t)
    np.testing.assert_allclose(np.gradient(q, t, axis=0)[1:-1], qd[1:-1], atol=DERIVATIVE_TOLERANCE)
    np.testing.assert_allclose(np.gradient(qd, t, axis=0)[1:-1], qdd[1:-1], atol=DERIVATIVE_TOLERANCE)
    q_end, qd_end, _ = tr.evaluate(np.array([0.0, 5.0]))
    np.testing.assert_allclose(q_end[0], q_end[1], atol=1e-12)
    np.testing.assert_allclose(qd_end[0], qd_end[1], atol=1e-12)


def test_coefficient_round_trip():
    """from_coefficients inverts coefficients."""
    rng = np.random.default_rng(1)
    tr = FourierTrajectory(rng.standard_normal(3), rng.standard_normal((3, 2)), rng.standard_normal((3, 2)), 3.0)
    back = FourierTrajectory.from_coefficients(tr.coefficients, 2, 3.0)
    np.testing.assert_array_equal(back.a, tr.a)
    np.testing.assert_array_equal(back.b, tr.b)
    np.testing.assert_array_equal(back.q0, tr.q0)


def test_design_lowers_the_condition_number_within_limits(design):
    """IPOPT design: the condition number of the column-scaled regressor (exact sign) drops
    at least by half against the random start, and cart travel, speed, acceleration and
    workspace limits hold on a 10x finer grid (checked again here with the kinematics)."""
    assert design.success, design.message
    assert design.condition_after * CONDITION_IMPROVEMENT < design.condition_before
    assert design.max_violation < VIOLATION_TOLERANCE
    robot = load_parameters("L1")
    t = np.linspace(0, design.trajectory.period, 400, endpoint=False)
    q, qd, qdd = design.trajectory.evaluate(t)
    assert np.all(q >= robot.limits.cart_travel[:, 0]) and np.all(q <= robot.limits.cart_travel[:, 1])
    assert np.abs(qd).max() <= 0.5 + VIOLATION_TOLERANCE and np.abs(qdd).max() <= 3.0 + VIOLATION_TOLERANCE
    kin = GantryTau3Kinematics(robot)
    T = kin.fk(q)
    assert np.all(kin.in_workspace(T))
    cond = regressor_condition(DynamicRegressor("L1", "model_2"), design.trajectory, min_speed=0.05)
    assert cond == pytest.approx(design.condition_after, rel=0.2)


BAD = [
    ("zero_harmonics", dict(harmonics=0), InputError, r"harmonics: expected an integer >= 1"),
    ("coarse_grid", dict(harmonics=4, n_grid=10), InputError, r"n_grid: expected at least 4 points per period"),
    ("negative_speed_limit", dict(max_velocity=-1.0), InputError, r"max_velocity: expected a positive number"),
    ("unknown_variant", dict(variant="model_7"), InputError, r"variant: expected one of"),
    ("centre_outside_workspace", dict(T_center=(0.0, 10.0, 0.0)), GtModelError, r"unreachable|outside the workspace"),
]


@pytest.mark.parametrize("case, kwargs, err, match", BAD, ids=[c[0] for c in BAD])
def test_bad_design_input(case, kwargs, err, match):
    """Invalid design options give an error naming the argument before any solve."""
    with pytest.raises(err, match=match):
        design_excitation(**{"parameters": "L1", "T_center": T_CENTER_L1, **kwargs})


@pytest.mark.parametrize("args, match", [
    (dict(q0=[0, 0], a=np.zeros((3, 2)), b=np.zeros((3, 2)), period=1.0), r"expected q0 \(3,\)"),
    (dict(q0=[0, 0, 0], a=np.zeros((3, 2)), b=np.zeros((3, 3)), period=1.0), r"a and b \(3, K\)"),
    (dict(q0=[0, 0, 0], a=np.zeros((3, 2)), b=np.zeros((3, 2)), period=0.0), r"period: expected a positive time"),
    (dict(q0=[0, 0, np.nan], a=np.zeros((3, 2)), b=np.zeros((3, 2)), period=1.0), r"must be finite"),
], ids=["q0_shape", "b_shape", "period", "nan"])
def test_bad_fourier_trajectory(args, match):
    """Invalid coefficients: InputError naming the field."""
    with pytest.raises(InputError, match=match):
        FourierTrajectory(**args)
