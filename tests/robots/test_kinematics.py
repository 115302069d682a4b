"""Kinematics of the 3-link Gantry-Tau (Dressler (2012), eqs. 4.9, 6.5, 6.6).

Independent references: FK and IK check each other (two different algorithms:
trilateration and per-arm quadratics); the analytic Jacobian (6.5) is compared with the
automatic-differentiation Jacobian of the closure equations via the implicit-function
theorem; the acceleration relation (6.6) with a finite difference of the velocity map.
"""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

from gtmodel.errors import InputError, SingularConfigurationError, UnreachablePoseError
from gtmodel.robots.kinematic_expressions import closure_residual, configuration_signs
from gtmodel.robots.kinematics import GantryTau3Kinematics

#: FK(IK(T)) round trip [m] (issue requirement).
ROUND_TRIP_TOL = 1e-12
#: Analytic vs AD Jacobian (dimensionless, relative to max |entry|).
JACOBIAN_TOL = 1e-12
#: Closure residual at IK solutions [m^2].
CLOSURE_TOL = 1e-12
#: Finite-difference check of eq. 6.6 (central differences, step 1e-6 s).
FD_TOL = 1e-6
#: Grid spacing filling the workspace [m].
GRID_STEP = 0.1
#: Poses closer than this to the FK singularity (TCP in the plane of the joint centres)
#: amplify rounding errors beyond ROUND_TRIP_TOL (error ~ eps * L / h); excluded [m].
FK_SINGULARITY_MARGIN = 0.01

ROBOTS = ["L1", "L1_ideal", "D1"]


@pytest.fixture(scope="module", params=ROBOTS)
def kin(request) -> GantryTau3Kinematics:
    return GantryTau3Kinematics(request.param)


_GRIDS: dict = {}


def _grid(kin, configuration):
    """Workspace grid for a configuration; for configurations that violate the joint
    limits everywhere, the reachable grid away from the FK singularity (cached)."""
    key = (kin.parameters.name, configuration)
    if key not in _GRIDS:
        _GRIDS[key] = _compute_grid(kin, configuration)
    return _GRIDS[key]


def _compute_grid(kin, configuration):
    G = kin.workspace_grid(GRID_STEP, configuration)
    if len(G) == 0:
        G = kin.workspace_grid(GRID_STEP, configuration, limits=False)
        q = kin.ik(G, configuration)
        _, h2, _ = kin.fk_function.map(len(G))(q.T, 1)
        G = G[np.asarray(h2).ravel() > FK_SINGULARITY_MARGIN**2]
    return G


def test_workspace_grid_is_large(kin):
    G = _grid(kin, 0)
    assert len(G) > 500
    assert kin.in_workspace(G).all()


@pytest.mark.parametrize("configuration", range(8))
def test_fk_of_ik_round_trip(kin, configuration):
    G = _grid(kin, configuration)
    assert len(G) > 100
    q = kin.ik(G, configuration)
    T_plus = kin.fk(q, 1)
    T_minus = kin.fk(q, -1)
    err = np.minimum(np.abs(T_plus - G).max(axis=1), np.abs(T_minus - G).max(axis=1))
    assert err.max() < ROUND_TRIP_TOL


def test_default_configurations_pair(kin):
    """Nominal IK configuration 0 pairs with FK solution +1 (and 7 with -1) on the whole workspace."""
    G = _grid(kin, 0)
    np.testing.assert_allclose(kin.fk(kin.ik(G, 0), 1), G, atol=ROUND_TRIP_TOL, rtol=0)
    G7 = _grid(kin, 7)
    np.testing.assert_allclose(kin.fk(kin.ik(G7, 7), -1), G7, atol=ROUND_TRIP_TOL, rtol=0)


@pytest.mark.parametrize("configuration", range(8))
def test_ik_satisfies_closure(kin, configuration):
    G = _grid(kin, configuration)
    q = kin.ik(G, configuration)
    T = ca.SX.sym("T", 3)
    qs = ca.SX.sym("q", 3)
    f = ca.Function("c", [T, qs], [closure_residual(T, qs, kin.L, kin.As, kin.v)]).map(len(G))
    assert np.abs(np.asarray(f(G.T, q.T))).max() < CLOSURE_TOL


def test_configuration_signs_select_roots(kin):
    T = _grid(kin, 0)[0]
    s = configuration_signs(5)
    np.testing.assert_array_equal(s, [1, -1, 1])
    q0, q5 = kin.ik(T, 0), kin.ik(T, 5)
    assert q0[1] == q5[1] and q0[0] != q5[0]
    # sign convention: configuration 0 has the TCP ahead of every cart along v_i
    ahead = np.array([(T - (kin.As[i] + q0[i] * kin.v[i])) @ kin.v[i] for i in range(3)])
    np.testing.assert_array_less(0, ahead)  # every arm


def test_single_and_batched_agree(kin):
    G = _grid(kin, 0)[:7]
    Q = kin.ik(G)
    for k in (0, 3, 6):
        np.testing.assert_array_equal(kin.ik(G[k]), Q[k])
    J = kin.jacobian(G)
    assert J.shape == (7, 3, 3)
    np.testing.assert_allclose(kin.jacobian(G[3]), J[3], rtol=0, atol=0)


def _ad_jacobian_inverse(kin, T, s):
    """dq/dT from the closure equations F(q, T) = 0 by AD and the implicit-function theorem."""
    Ts = ca.SX.sym("T", 3)
    qs = ca.SX.sym("q", 3)
    F = closure_residual(Ts, qs, kin.L, kin.As, kin.v)
    f = ca.Function("d", [Ts, qs], [ca.jacobian(F, qs), ca.jacobian(F, Ts)])
    q = kin.ik(T, s)
    Fq, FT = (np.asarray(m) for m in f(T, q))
    return -np.linalg.solve(Fq, FT)


@pytest.mark.parametrize("configuration", [0, 7])
def test_analytic_jacobian_equals_ad_jacobian(kin, configuration):
    G = kin.workspace_grid(GRID_STEP * 3, configuration)
    Jinv = kin.jacobian_inverse(G, configuration)
    J = kin.jacobian(G, configuration)
    ks = list(range(0, len(G), max(1, len(G) // 25)))
    ref = np.array([_ad_jacobian_inverse(kin, G[k], configuration) for k in ks])  # (sample, 3, 3)
    scale = np.abs(ref).max(axis=(1, 2))
    np.testing.assert_array_less(np.abs(Jinv[ks] - ref).max(axis=(1, 2)), JACOBIAN_TOL * scale)
    np.testing.assert_array_less(
        np.abs(J[ks] @ ref - np.eye(3)).max(axis=(1, 2)), JACOBIAN_TOL * np.linalg.cond(ref)
    )


def test_acceleration_relation_matches_finite_difference(kin):
    """Eq. 6.6: along T(t) = T0 + t a + t^2 b, d/dt(q_dot) by central differences equals
    the q_ddot of cart_motion, and acceleration() maps it back to T_ddot."""
    G = _grid(kin, 0)
    T0 = G[len(G) // 2]
    a = np.array([0.3, -0.2, 0.1])
    b = np.array([0.5, 0.4, -0.3])
    h = 1e-6

    def qdot(t):
        T = T0 + t * a + t**2 * b
        return kin.jacobian_inverse(T) @ (a + 2 * t * b)

    q, q_dot, q_ddot = kin.cart_motion(T0, a, 2 * b)
    np.testing.assert_allclose(q_dot, qdot(0.0), rtol=1e-13, atol=1e-13)
    fd = (qdot(h) - qdot(-h)) / (2 * h)
    np.testing.assert_allclose(q_ddot, fd, rtol=FD_TOL, atol=FD_TOL)
    np.testing.assert_allclose(kin.acceleration(T0, a, q_ddot), 2 * b, rtol=1e-12, atol=1e-12)


UNREACHABLE = [
    ("far_away", [5.0, 5.0, 5.0], r"arm 1 .*arm 2 .*arm 3"),
]


def test_unreachable_pose_names_arm():
    kin = GantryTau3Kinematics("L1")
    # move along the normal away from guideway 3 only until just arm 3 is out of reach
    T = np.array([0.0, 2.9, -0.5])
    d = T - kin.As[2]
    v = kin.v[2] / np.linalg.norm(kin.v[2])
    perp = d - (d @ v) * v
    T_far = kin.As[2] + (d @ v) * v + perp / np.linalg.norm(perp) * (kin.L[2] + 0.01)
    with pytest.raises(UnreachablePoseError, match=r"unreachable: arm 3 \(distance to guideway"):
        kin.ik(T_far)


@pytest.mark.parametrize("pose, match", [(p, m) for _, p, m in UNREACHABLE], ids=[u[0] for u in UNREACHABLE])
def test_unreachable_far_pose(pose, match):
    with pytest.raises(UnreachablePoseError, match=match):
        GantryTau3Kinematics("L1").ik(pose)


def test_unreachable_row_is_named_in_batch():
    kin = GantryTau3Kinematics("L1")
    G = kin.workspace_grid(GRID_STEP)[:3].copy()
    G[2] = [5.0, 5.0, 5.0]
    with pytest.raises(UnreachablePoseError, match=r"\(row 2\)"):
        kin.ik(G)


def test_non_intersecting_spheres_raise():
    kin = GantryTau3Kinematics("L1")
    with pytest.raises(UnreachablePoseError, match="do not intersect"):
        kin.fk([0.0, 3.0, -3.0])


def test_singular_jacobian_raises():
    """A pose with link 1 perpendicular to its guideway (dP_1 . v_1 = 0, eq. 6.5)."""
    kin = GantryTau3Kinematics("L1")
    v = kin.v[0] / np.linalg.norm(kin.v[0])
    toward = (kin.As[1] + kin.As[2]) / 2 - kin.As[0]
    n = toward - (toward @ v) * v
    n /= np.linalg.norm(n)
    inward = 1e-13  # stay inside the reach of arm 1 despite rounding [m]
    T = kin.As[0] + (kin.L[0] - inward) * n
    assert kin.in_workspace(T, limits=False)
    with pytest.raises(SingularConfigurationError, match="singular"):
        kin.jacobian(T)


BAD_ARGS = [
    ("wrong_shape", dict(T=[1.0, 2.0]), InputError, r"T: expected shape \(3,\) or \(N, 3\)"),
    ("nan", dict(T=[np.nan, 2.9, -0.5]), InputError, r"T: row 0 is not finite"),
    ("config_9", dict(T=[0.0, 2.9, -0.5], configuration=9), InputError, r"configuration: expected an integer 0-7"),
    ("config_signs", dict(T=[0.0, 2.9, -0.5], configuration=(1, 0, 1)), InputError, r"three signs"),
    ("text", dict(T="abc"), InputError, r"T: expected"),
]


@pytest.mark.parametrize("case, kwargs, exc, match", BAD_ARGS, ids=[b[0] for b in BAD_ARGS])
def test_bad_arguments(case, kwargs, exc, match):
    with pytest.raises(exc, match=match) as info:
        GantryTau3Kinematics("L1").ik(**kwargs)
    # the message starts with the name of the offending argument
    assert str(info.value).split(":")[0] in kwargs


def test_bad_fk_solution():
    with pytest.raises(InputError, match=r"solution: expected \+1 or -1"):
        GantryTau3Kinematics("L1").fk([0.0, 0.0, 0.0], solution=0)
