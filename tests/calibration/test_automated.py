"""Automated calibration pieces (Dressler (2012), ch. 5.6): workspace tests, grid constant, program files.

Independent references: hand-computed pinhole projections and tracker distances; the
inverse kinematics' own reach test (a kept point must be admissible at its margin's distance
in every grid direction); the CSV reader of the project reading back the written program.
"""

from __future__ import annotations

import re

import numpy as np
import pytest

from gtmodel._tables import read_table
from gtmodel.calibration.automated import (
    CalibrationWorkspace,
    Obstacle,
    PinholeCamera,
    Tracker,
    grid_constant,
    home_joint_axes,
    rapid_module,
    write_pose_csv,
)
from gtmodel.errors import InputError
from gtmodel.robots.kinematics import GantryTau3Kinematics
from gtmodel.robots.parameters import KinematicParameters

#: Table 5.7's a priori (manually measured) L1 parameters.
APRIORI = KinematicParameters(L=np.array([2.05, 1.82, 1.81]), As=np.array([[0.04, 0.0, 1.44], [0.25, -1.31, 1.46], [0.0, 0.0, 0.0]]),
                              v=np.array([[1.0, 0.0, 0.0]] * 3))
TRAVEL = np.array([[-1.0, 1.0]] * 3)


@pytest.fixture(scope="module")
def kin():
    return GantryTau3Kinematics(APRIORI)


def test_grid_constant_fills_the_volume():
    assert grid_constant(0.1367**3 * 100, 100) == pytest.approx(0.1367)
    with pytest.raises(InputError, match="grid_constant"):
        grid_constant(0.0, 100)


def test_pinhole_camera_sees_the_pattern_in_front_inside_the_image():
    # camera at the origin looking along +x: image x = -y (right), image y = -z (down)
    R = np.column_stack([[0.0, -1.0, 0.0], [0.0, 0.0, -1.0], [1.0, 0.0, 0.0]])
    pattern = np.array([[0.0, 0.1, 0.1], [0.0, -0.1, -0.1]])
    cam = PinholeCamera(np.zeros(3), R, focal=1000.0, image=(1000, 800), pattern_corners=pattern)
    P = np.array([[2.0, 0.0, 0.0],      # centre: seen
                  [-2.0, 0.0, 0.0],     # behind the camera
                  [2.0, 0.85, 0.0],     # corner at y = 0.95: u = 1000 * -0.95 / 2 + 500 = 25 -> seen
                  [2.0, 0.95, 0.0],     # corner at y = 1.05: u = -25 -> outside
                  [2.0, 0.0, 0.75]])    # corner at z = 0.85: v = 1000 * -0.85 / 2 + 400 = -25 -> outside
    assert cam.sees(P).tolist() == [True, False, True, False, False]


def test_tracker_range():
    tr = Tracker(np.zeros(3), 1.0, 5.0)
    assert tr.sees(np.array([[0.5, 0, 0], [3.0, 0, 0], [0, 0, 5.5]])).tolist() == [False, True, False]


def test_home_joint_axes_are_the_link_directions_at_q0(kin):
    axes = home_joint_axes(kin)
    T = kin.fk(np.zeros(3))
    assert np.allclose(np.linalg.norm(axes, axis=1), 1.0)
    assert np.allclose(T - axes * kin.L[:, None], kin.As)  # joint point + L * direction = TCP


def test_margin_keeps_only_points_whose_neighbourhood_is_in_the_workspace(kin):
    ws0 = CalibrationWorkspace(kin, TRAVEL, np.radians(30), 0.0, joint_axes=home_joint_axes(kin))
    ws = CalibrationWorkspace(kin, TRAVEL, np.radians(30), 0.1, joint_axes=home_joint_axes(kin))
    P = ws.grid(0.2)
    kinematic = ws0.kinematic(P)
    ok, removed = ws.admissible(P)
    assert ok.sum() < kinematic.sum() and not np.any(ok & ~kinematic)
    assert removed["margin"] == kinematic.sum() - ok.sum()
    rng = np.random.default_rng(0)
    d = rng.normal(size=(len(P[ok]), 3))
    d *= 0.099 / np.linalg.norm(d, axis=1, keepdims=True)
    # within the margin of a kept point the kinematic tests hold along the grid directions
    # (random directions: nearly always; the test uses the 26 directions, so allow a few)
    assert ws0.kinematic(P[ok] + d).mean() > 0.97


def test_obstacles_and_their_safety_zones_remove_points(kin):
    box = Obstacle(np.array([1.0, -1.0, 0.3]), np.array([2.0, -0.5, 0.8]), 0.1, "table")
    ws = CalibrationWorkspace(kin, TRAVEL, np.radians(30), 0.0, (box,), joint_axes=home_joint_axes(kin))
    P = ws.grid(0.1)
    ok, removed = ws.admissible(P)
    inside = np.all((P >= box.lo - 0.1) & (P <= box.hi + 0.1), axis=1)
    assert removed["obstacles"] > 0 and not np.any(ok & inside)


def test_grid_refuses_a_bad_step(kin):
    ws = CalibrationWorkspace(kin, TRAVEL, np.radians(30))
    with pytest.raises(InputError, match="step: expected a positive"):
        ws.grid(0.0)
    with pytest.raises(InputError, match="step: expected a grid step giving at most"):
        ws.grid(1e-3)


def test_pose_program_round_trips_and_rapid_moves_through_every_pose(tmp_path):
    q = np.array([[0.1, -0.2, 0.3], [0.0, 0.5, -0.25]])
    T = np.array([[1.0, -0.5, 0.4], [1.2, -0.6, 0.5]])
    table = read_table(write_pose_csv(tmp_path / "poses.csv", q, T, "two poses"), what="poses")
    assert table.columns == ("pose", "q1_m", "q2_m", "q3_m", "x_m", "y_m", "z_m") and table.comments == ("two poses",)
    assert np.array_equal(table.data[:, 1:4], q) and np.array_equal(table.data[:, 4:], T)
    text = rapid_module(q)
    assert text.count("MoveAbsJ") == 2 and text.startswith("MODULE CalibPoses") and "ENDMODULE" in text
    first = re.search(r"p1 := \[\[([^\]]*)\]", text).group(1)
    assert [float(x) for x in first.split(",")[:3]] == [100.0, -200.0, 300.0]  # mm
