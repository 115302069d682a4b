"""Geometric paths: closed forms, derivatives, CasADi expressions, corners, workspace checks.

Independent references: the closed form of a straight line and of arc-length polylines,
central finite differences of ``T(s)`` for the derivatives of the spline, the given
points for interpolation, and the workspace test of :class:`GantryTau3Kinematics`
evaluated at the reported ``s``.
"""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

from gtmodel.errors import InputError, UnreachablePoseError
from gtmodel.robots.kinematics import GantryTau3Kinematics
from gtmodel.trajectory.path import Polyline, SplinePath, StraightLine

CLOSED_FORM_TOL = 1e-13  # double-precision evaluation of a polynomial of degree <= 3
FD_STEP = 1e-5  # central differences: truncation ~ h^2 |T'''| ~ 1e-9, rounding ~ eps/h ~ 1e-11
FD_TOL = 1e-7
START = np.array([-0.2, 2.75, -0.4])
END = np.array([0.2, 3.0, -0.6])
POINTS = np.array([[-0.2, 2.75, -0.4], [0.0, 2.9, -0.45], [0.1, 2.85, -0.55], [0.2, 3.0, -0.6]])


def test_straight_line_closed_form():
    line = StraightLine(START, END)
    s = np.linspace(0, 1, 11)
    T, dT, ddT = line.evaluate(s)
    np.testing.assert_allclose(T, START + np.outer(s, END - START), atol=CLOSED_FORM_TOL)
    np.testing.assert_allclose(dT, np.tile(END - START, (11, 1)), atol=CLOSED_FORM_TOL)
    np.testing.assert_allclose(ddT, 0.0, atol=CLOSED_FORM_TOL)
    assert line.corners.size == 0
    assert line.length == pytest.approx(np.linalg.norm(END - START), rel=1e-14)


def test_polyline_is_arc_length_and_has_corners():
    pts = np.array([[0, 0, 0], [0.5, 0, 0], [1.0, 0, 0], [1.0, 0.4, 0]], dtype=float)  # point 1 collinear
    poly = Polyline(pts)
    total = 1.4
    np.testing.assert_allclose(poly.corners, [1.0 / 1.4], atol=CLOSED_FORM_TOL)  # only the real turn
    np.testing.assert_allclose(poly(np.array([0.0, 0.5 / total, 1.0 / total, 1.0])), pts, atol=CLOSED_FORM_TOL)
    _, dT, ddT = poly.evaluate(np.linspace(0, 1, 57))
    np.testing.assert_allclose(np.linalg.norm(dT, axis=1), total, rtol=1e-13)  # |dT/ds| = length
    np.testing.assert_allclose(ddT, 0.0, atol=CLOSED_FORM_TOL)
    # right-continuous tangent: at the corner it is the outgoing segment's
    np.testing.assert_allclose(poly.evaluate([1.0 / total])[1][0], [0.0, total, 0.0], atol=1e-12)


def test_spline_interpolates_and_derivatives_match_finite_differences():
    sp = SplinePath(POINTS)
    np.testing.assert_allclose(sp(sp.breaks), POINTS, atol=CLOSED_FORM_TOL)
    s = np.linspace(0.05, 0.95, 19)
    T, dT, ddT = sp.evaluate(s)
    fd1 = (sp(s + FD_STEP) - sp(s - FD_STEP)) / (2 * FD_STEP)
    fd2 = (sp.evaluate(s + FD_STEP)[1] - sp.evaluate(s - FD_STEP)[1]) / (2 * FD_STEP)
    np.testing.assert_allclose(dT, fd1, atol=FD_TOL)
    np.testing.assert_allclose(ddT, fd2, atol=FD_TOL * 10)
    # C2 at the interior breaks
    for x in sp.breaks[1:-1]:
        left = sp.evaluate([x - 1e-12])
        right = sp.evaluate([x])
        np.testing.assert_allclose(left[2], right[2], atol=1e-8)
    # natural end conditions
    np.testing.assert_allclose(sp.evaluate([0.0, 1.0])[2], 0.0, atol=1e-9)


@pytest.mark.parametrize("path", [StraightLine(START, END), Polyline(POINTS), SplinePath(POINTS)], ids=["line", "polyline", "spline"])
def test_casadi_expression_equals_numpy(path):
    """Reference: the NumPy evaluation of the same piecewise polynomial."""
    s = ca.SX.sym("s")
    f = ca.Function("f", [s], list(path.casadi_expression(s)))
    for v in np.concatenate([np.linspace(0, 1, 23), path.breaks]):
        ref = path.evaluate([v])
        got = f(v)
        for a, b in zip(got, ref):
            np.testing.assert_allclose(np.asarray(a).ravel(), b[0], atol=1e-12)


def test_path_outside_workspace_names_s():
    """Reference: GantryTau3Kinematics.in_workspace at the reported s and just before it."""
    end = [0.2, 7.0, -0.6]
    with pytest.raises(UnreachablePoseError, match=r"leaves the workspace at s = ") as info:
        StraightLine(START, end, robot="L1")
    s_bad = float(str(info.value).split("s = ")[1].split(":")[0])
    kin = GantryTau3Kinematics("L1")
    line = StraightLine(START, end)
    assert not kin.in_workspace(line([s_bad])[0])
    assert kin.in_workspace(line([s_bad - 1.0 / 200])[0])


def test_path_inside_workspace_passes():
    StraightLine(START, END, robot="L1")
    SplinePath(POINTS, robot="L1")


@pytest.mark.parametrize(
    "make, match",
    [
        (lambda: StraightLine(START, START), "coincide"),
        (lambda: StraightLine([0, 0], END), "start: expected three finite numbers"),
        (lambda: Polyline([[0, 0, 0]]), r"K >= 2"),
        (lambda: Polyline([[0, 0, 0], [1, 0, np.nan]]), "finite"),
        (lambda: SplinePath(POINTS, bc_type="periodic"), "bc_type"),
        (lambda: StraightLine(START, END).evaluate([1.5]), r"s: expected finite values in \[0, 1\]"),
    ],
)
def test_bad_paths(make, match):
    with pytest.raises(InputError, match=match):
        make()
