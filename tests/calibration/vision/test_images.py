"""Synthetic stereo images (detection failures) and the corner measurement file.

Independent references: the geometry of the test rig (a camera turned away sees nothing, a
pattern turned edge-on is oblique), and hand-written CSV files for the bad rows.
"""

from __future__ import annotations

import numpy as np
import pytest

from gtmodel.calibration.vision import PatternMount, StereoImages, look_at, read_stereo_corners, synthetic_stereo_images
from gtmodel.calibration.vision import images as images_module
from gtmodel.errors import InputError

from . import _rig

HEADER = "pose,corner,q1_m,q2_m,q3_m,u1_px,v1_px,u2_px,v2_px"


@pytest.fixture(scope="module")
def syn():
    return synthetic_stereo_images(_rig.model(), _rig.poses(), _rig.cameras(), _rig.pattern(), pixel_sigma=0.3, seed=1)


def test_csv_round_trip(syn, tmp_path):
    f = syn.images.to_csv(tmp_path / "corners.csv")
    back = read_stereo_corners(f, 20, _rig.cameras())
    np.testing.assert_array_equal(back.uv, syn.images.uv)
    np.testing.assert_array_equal(back.q, syn.images.q)
    np.testing.assert_array_equal(back.pose_ids, syn.images.pose_ids)


def test_rows_in_any_order(syn, tmp_path):
    f = syn.images.subset([0, 1]).to_csv(tmp_path / "c.csv")
    lines = f.read_text().splitlines()
    head = [ln for ln in lines if ln.startswith("#") or ln.startswith("pose")]
    rows = [ln for ln in lines if ln not in head]
    (tmp_path / "shuffled.csv").write_text("\n".join(head + rows[::-1]) + "\n")
    back = read_stereo_corners(tmp_path / "shuffled.csv", 20)
    np.testing.assert_array_equal(np.sort(back.pose_ids), np.sort(syn.images.pose_ids[:2]))


def test_a_camera_turned_away_sees_nothing():
    cams = _rig.cameras()
    away = cams[1].with_pose(look_at(cams[1].position, cams[1].position + np.array([0, 1.0, 0])), cams[1].position)
    s = synthetic_stereo_images(_rig.model(), _rig.poses(), (cams[0], away), _rig.pattern())
    assert not s.detected[:, 1].any() and s.detected[:, 0].all() and s.images.n_poses == 0
    assert set(s.reason[:, 1]) == {"behind camera"}


@pytest.mark.parametrize("normal, x_axis, limit_deg, seen", [
    ([0, -1.0, 0], [1.0, 0, 0], 89.0, False),   # facing away from the cameras (they are at +y)
    ([1.0, 0, 0], [0, 1.0, 0], 60.0, False),    # edge-on: normal along the guideways
    ([0, 1.0, 1.0], [1.0, 0, 0], 60.0, True),   # tilted 45 deg: still seen at 60 deg
    ([0, 1.0, 1.0], [1.0, 0, 0], 30.0, False),  # ... but not at 30 deg
])
def test_a_pattern_seen_too_obliquely_is_not_detected(normal, x_axis, limit_deg, seen):
    mount = PatternMount.facing(normal, x_axis)
    s = synthetic_stereo_images(_rig.model(), _rig.poses(), _rig.cameras(), _rig.pattern(), mount, max_obliquity_deg=limit_deg)
    assert (s.images.n_poses > 0) == seen
    if not seen:
        assert (s.reason == "oblique").any()


def test_a_narrow_camera_loses_the_border_poses():
    cams = _rig.cameras()
    tele = _rig.camera("tele", cams[0].position, f=2500.0)
    s = synthetic_stereo_images(_rig.model(), _rig.poses(), (tele, cams[1]), _rig.pattern())
    assert 0 < s.images.n_poses < _rig.poses().shape[0] and "outside image" in set(s.reason[:, 0])


def _write(tmp_path, body: str, header: str = HEADER):
    f = tmp_path / "c.csv"
    f.write_text(header + "\n" + body)
    return f


def _pose(p, q=(0.0, 0.1, 0.2), corners=range(1, 21), uv=(100.0, 200.0)):
    return "".join(f"{p},{c},{q[0]},{q[1]},{q[2]},{uv[0] + c},{uv[1]},{uv[0] + c},{uv[1]}\n" for c in corners)


@pytest.mark.parametrize("body, match", [
    (_pose(1, corners=range(1, 20)), r"line 2, column 'corner': pose 1 lacks corner\(s\) 20 of 20"),
    (_pose(1) + _pose(2, corners=[1, 2, 3]), r"line 22, column 'corner': pose 2 lacks corner\(s\) 4, 5, .*20 of 20"),
    (_pose(1) + "1,3,0.0,0.1,0.2,1,1,1,1\n", r"line 22, column 'corner': corner 3 of pose 1 repeats line 4"),
    (_pose(1, corners=[1]) + "1,2,0.0,0.1,0.3,1,1,1,1\n", r"line 3, columns 'q1_m,q2_m,q3_m': cart positions differ from those of pose 1 on line 2"),
    ("1,21,0,0,0,1,1,1,1\n", r"line 2, column 'corner': expected a corner number 1\.\.20"),
    ("1.5,1,0,0,0,1,1,1,1\n", r"line 2, column 'pose': expected a positive integer"),
    ("0,1,0,0,0,1,1,1,1\n", r"line 2, column 'pose': expected a positive integer"),
    ("1,1,0,0,0,1,1,1,nan\n", r"line 2, column 'v2_px': NaN/inf is not allowed"),
    ("1,1,0,0,0,1,1,2000,1\n", r"line 2, columns 'u2_px,v2_px': pixel \(2000, 1\) outside the 1024 x 768 image of camera 2"),
    ("", r"no data rows"),
])
def test_bad_rows_are_refused_naming_the_line(tmp_path, body, match):
    with pytest.raises(InputError, match=match):
        read_stereo_corners(_write(tmp_path, body), 20, _rig.cameras())


@pytest.mark.parametrize("header, match", [
    ("pose,corner,q1_m,q2_m,q3_m,u1_px,v1_px,u2_px", r"missing column\(s\) v2_px"),
    (HEADER + ",w", r"unknown column 'w'"),
])
def test_bad_header(tmp_path, header, match):
    with pytest.raises(InputError, match=match):
        read_stereo_corners(_write(tmp_path, "", header), 20)


def test_size_cap(tmp_path, monkeypatch):
    monkeypatch.setattr(images_module, "MAX_CORNER_FILE_BYTES", 100)
    with pytest.raises(InputError, match=r"bytes, expected at most 100 bytes"):
        read_stereo_corners(_write(tmp_path, _pose(1)), 20)


def test_bad_images_arrays():
    with pytest.raises(InputError, match=r"expected q \(N, 3\), uv \(N, 2, M, 2\)"):
        StereoImages(np.zeros((2, 3)), np.zeros((2, 1, 20, 2)), [1, 2])
