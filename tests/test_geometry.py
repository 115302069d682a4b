"""Quaternions of :mod:`gtmodel._geometry` (the one implementation) against SciPy's Rotation.

Independent reference: :class:`scipy.spatial.transform.Rotation` (scalar-last quaternions,
reordered here), for the rotation matrix (both the normalising and the unit form), the
Hamilton product, the conjugate and the exponential map on both sides of its series switch.
"""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from gtmodel._geometry import QUAT_EXP_SERIES_LIMIT, quat_conj, quat_exp, quat_mul, quaternion_to_rotation


def _scipy(quat):
    """Scalar-first ``(w, x, y, z)`` -> SciPy's Rotation."""
    q = np.asarray(quat, dtype=float).ravel()
    return Rotation.from_quat(np.r_[q[1:], q[0]])


def _first(rot):
    """SciPy's quaternion of ``rot``, scalar first."""
    q = rot.as_quat()
    return np.r_[q[3], q[:3]]


def _units(seed, n=5):
    v = np.random.default_rng(seed).normal(size=(n, 4))
    return v / np.linalg.norm(v, axis=1, keepdims=True)


@pytest.mark.parametrize("normalise", [True, False])
def test_rotation_matrix_against_scipy(normalise):
    for q in _units(0):
        np.testing.assert_allclose(quaternion_to_rotation(q, normalise=normalise), _scipy(q).as_matrix(), rtol=0, atol=1e-15)


def test_rotation_matrix_normalises_a_scaled_quaternion():
    q = _units(1)[0]
    np.testing.assert_allclose(quaternion_to_rotation(3.0 * q), _scipy(q).as_matrix(), rtol=0, atol=1e-15)


def test_rotation_matrix_symbolic_equals_numeric():
    s = ca.SX.sym("q", 4)
    f = ca.Function("R", [s], [quaternion_to_rotation(s)])
    q = _units(2)[0]
    np.testing.assert_allclose(np.asarray(f(q)), quaternion_to_rotation(q), rtol=0, atol=1e-15)


def test_product_and_conjugate_against_scipy():
    p, q = _units(3, 2)
    pq = np.asarray(quat_mul(p, q)).ravel()
    np.testing.assert_allclose(quaternion_to_rotation(pq), (_scipy(p) * _scipy(q)).as_matrix(), rtol=0, atol=1e-15)
    np.testing.assert_allclose(quaternion_to_rotation(np.asarray(quat_conj(q)).ravel()), _scipy(q).inv().as_matrix(), rtol=0, atol=1e-15)
    np.testing.assert_allclose(np.asarray(quat_mul(q, quat_conj(q))).ravel(), [1.0, 0.0, 0.0, 0.0], atol=1e-15)


# angles around the switch |r|/2 = sqrt(QUAT_EXP_SERIES_LIMIT) = 0.1 rad, far below and far above it
_SWITCH = 2.0 * np.sqrt(QUAT_EXP_SERIES_LIMIT)


@pytest.mark.parametrize("angle", [0.0, 1e-8, 1e-4, 0.05, _SWITCH * (1 - 1e-9), _SWITCH * (1 + 1e-9), 0.5, 3.0])
def test_exponential_map_against_scipy(angle):
    axis = np.array([1.0, -2.0, 0.5]) / np.linalg.norm([1.0, -2.0, 0.5])
    got = np.asarray(quat_exp(angle * axis)).ravel()
    np.testing.assert_allclose(got, _first(Rotation.from_rotvec(angle * axis)), rtol=0, atol=1e-15)


def test_exponential_map_derivative_is_smooth_across_the_switch():
    """The AD Jacobian of quat_exp is continuous at the series switch and finite at r = 0."""
    r = ca.SX.sym("r", 3)
    jac = ca.Function("J", [r], [ca.jacobian(quat_exp(r), r)])
    axis = np.array([0.3, 0.4, -0.2]) / np.linalg.norm([0.3, 0.4, -0.2])
    below, above = (np.asarray(jac(_SWITCH * f * axis)) for f in (1 - 1e-12, 1 + 1e-12))
    np.testing.assert_allclose(below, above, rtol=0, atol=1e-13)
    j0 = np.asarray(jac(np.zeros(3)))
    np.testing.assert_allclose(j0, np.vstack([np.zeros(3), 0.5 * np.eye(3)]), rtol=0, atol=1e-16)
