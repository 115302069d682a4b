"""Pose accuracy analysis (Dressler (2012), App. A): geometric method, exact NLP, Monte-Carlo, inverse.

Independent references: the 3-link model's own forward kinematics with link lengths
``L_i +- r_i`` (A.3: the exact corners for spherical errors, computed without the A.2
iteration or the NLP); the second-order bound ``r^2 / L`` of the parallelepiped's error
(A.4's ``L >> r``); a Monte-Carlo sample can never exceed a true maximum; the inverse
answer's optimality (max sum log k: no factor can grow alone).
"""

from __future__ import annotations

import numpy as np
import pytest

from gtmodel.calibration.accuracy import (
    Tolerances,
    ellipsoid_corners,
    largest_tolerances,
    monte_carlo,
    nominal_pose,
    parallelepiped,
    sphere_corners,
    worst_case,
)
from gtmodel.calibration.accuracy.geometric import CORNER_SIGNS
from gtmodel.errors import InputError
from gtmodel.robots.kinematics import GantryTau3Kinematics

UM = 1e-6
#: Table 4.2 of Dressler (2012).
CASE_1 = Tolerances.spherical(np.array([32.0, 77.0, 54.0]) * UM)
CASE_2 = Tolerances(np.array([[11.0, 28.0, 28.0], [58.0, 38.0, 38.0], [19.0, 47.0, 47.0]]) * UM)
#: Poses of the D1 section x = -1.6 m: centre, near actuator 3, near actuator 1.
POSES = np.array([[-1.6, -4.4, 0.14], [-1.6, -4.78, -0.74], [-1.6, -5.2, 0.9]])


@pytest.fixture(scope="module")
def nominal():
    return nominal_pose(GantryTau3Kinematics("D1"), POSES)


def _rotated(tol: Tolerances) -> Tolerances:
    """The same semi-axes about rotated axes (the ellipsoids need not follow the base axes)."""
    c, s = np.cos(0.4), np.sin(0.4)
    R = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    return Tolerances(tol.semi_axes, np.repeat(R[None], 3, axis=0), link=[5 * UM, 0.0, 10 * UM])


def test_a2_iteration_equals_the_forward_kinematics_with_changed_link_lengths(nominal):
    """Spherical errors (A.3): the A.2 corners are the FK of L +- r, to round-off."""
    corners, iterations = ellipsoid_corners(nominal, CASE_1)
    fk = sphere_corners(nominal, CASE_1.semi_axes[:, 0])
    assert np.abs(corners - fk).max() < 1e-12
    assert iterations.max() <= 6


TOLERANCES = {"case_1": CASE_1, "case_2": CASE_2, "rotated_with_links": _rotated(CASE_2)}


@pytest.mark.parametrize("k", range(len(POSES)))
@pytest.mark.parametrize("name", list(TOLERANCES))
def test_exact_worst_case_is_the_parallelepiped_to_second_order(nominal, name, k):
    """A.4 is exact to first order: |parallelepiped - exact| <= 5 r_max^2 / L_min (nm here)."""
    tol = TOLERANCES[name]
    pp = parallelepiped(nominal, tol)
    bound = 5 * tol.scale**2 / nominal.L.min()
    wc = worst_case(nominal, k, tol, corner_starts_used=2, random_starts=1)
    assert wc.status == "optimal"
    assert abs(wc.error - pp.worst[k]) <= bound, (wc.error, pp.worst[k], bound)
    assert wc.error >= wc.best_corner * (1 - 1e-12)
    # the optimum lies on the ellipsoids' boundaries (a maximum of a near-linear map)
    M = tol.shape_matrices()
    radii = [d @ np.linalg.solve(Mi, d) for d, Mi in zip(wc.joint_offsets, M)]
    assert np.allclose(radii, 1.0, atol=1e-6)


@pytest.mark.parametrize("k", range(len(POSES)))
def test_exact_worst_case_of_spheres_is_the_farthest_fk_corner(nominal, k):
    """Spherical errors: the exact maximum is at a corner of the exact set (the FK of L +- r),
    or a picometre beyond it where the curved faces bulge."""
    fk = sphere_corners(nominal, CASE_1.semi_axes[:, 0])
    farthest = np.linalg.norm(fk[k] - POSES[k], axis=1).max()
    exact = worst_case(nominal, k, CASE_1).error
    assert farthest * (1 - 1e-12) <= exact <= farthest + 1e-11


@pytest.mark.parametrize("k", range(len(POSES)))
@pytest.mark.parametrize("name", ["case_1", "rotated_with_links"])
def test_monte_carlo_never_exceeds_the_exact_worst_case(nominal, name, k):
    tol = TOLERANCES[name]
    mc = monte_carlo(nominal, k, tol, samples=4000, seed=k)
    exact = worst_case(nominal, k, tol).error
    assert mc.max <= exact * (1 + 1e-9)
    assert mc.mean < mc.quantile(0.95) < mc.max


def test_a2_underestimates_anisotropic_ellipsoids_by_the_thesis_approximation(nominal):
    """A.2's shells have axes L +- r_j, not the support of E_i^A along the link: case 2 is a few um low."""
    corners, _ = ellipsoid_corners(nominal, CASE_2)
    geo = np.linalg.norm(corners - POSES[:, None], axis=2).max(axis=1)
    exact = np.array([worst_case(nominal, k, CASE_2).error for k in range(POSES.shape[0])])
    assert np.all(geo < exact) and np.all(exact - geo < 10 * UM)


def test_face_areas_and_diagonals_follow_the_corners(nominal):
    pp = parallelepiped(nominal, CASE_1)
    assert np.allclose(pp.diagonals, np.linalg.norm(pp.corners[:, :4] - pp.corners[:, 7 - np.arange(4)], axis=2))
    assert np.allclose(pp.worst, pp.diagonals.max(axis=1) / 2)
    # faces orthogonal to link i are at distance 2 r_i: area * 2 r_i = volume for every i
    edges = np.linalg.inv(nominal.u) * (2 * pp.half_widths[:, None, :])
    volume = np.abs(np.linalg.det(edges))
    heights = 2 * pp.half_widths
    assert np.allclose(pp.face_areas * heights, volume[:, None], rtol=1e-9)
    assert CORNER_SIGNS.shape == (8, 3)


def test_inverse_tolerances_are_feasible_and_largest(nominal):
    bound = 100 * UM
    inv = largest_tolerances(nominal, CASE_1, bound)
    assert inv.status == "optimal"
    assert inv.exact_worst <= bound * (1 + 1e-9)
    assert parallelepiped(nominal, inv.tolerances).worst.max() <= bound * (1 + 1e-6)
    # optimal volume: no factor can grow alone
    grown = [parallelepiped(nominal, CASE_1.scaled(inv.factors * np.where(np.arange(3) == i, 1.01, 1.0))).worst.max() for i in range(3)]
    assert min(grown) > bound, grown
    assert parallelepiped(nominal, CASE_1.scaled(inv.uniform_factor)).worst.max() == pytest.approx(bound, rel=1e-5)


@pytest.mark.parametrize(
    "kwargs, match",
    [
        ({"semi_axes": np.zeros((3, 3))}, r"semi_axes: arm 1: expected positive"),
        ({"semi_axes": [[1e-5] * 3, [1e-5, np.nan, 1e-5], [1e-5] * 3]}, r"semi_axes: expected finite"),
        ({"semi_axes": [[1e-5] * 3, [1e-5] * 3, [-1e-5] * 3]}, r"semi_axes: arm 3: expected positive"),
        ({"semi_axes": [[1.0] * 3] * 3}, r"semi_axes: arm 1: expected positive tolerances up to 0.05"),
        ({"semi_axes": [1e-5] * 3, "link": [0.0, -1e-6, 0.0]}, r"link: expected non-negative"),
        ({"semi_axes": [1e-5] * 3, "axes": np.ones((3, 3, 3))}, r"axes\[0\]: expected a rotation"),
    ],
)
def test_bad_tolerances_name_the_argument(kwargs, match):
    with pytest.raises(InputError, match=match):
        Tolerances(**kwargs)


def test_inverse_refuses_a_bad_bound(nominal):
    with pytest.raises(InputError, match="tcp_error"):
        largest_tolerances(nominal, CASE_1, float("nan"))
