"""Measurement files: CSV round trips and strict validation of malformed files.

Independent references: the round trip compares against the arrays written (exact
decimal representation, so the tolerance is far below any measurement resolution); the
malformed files are hand-written text whose faulty line and column are known.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from gtmodel.calibration.measurements import (
    CartMeasurements,
    MeasurementSet,
    QUATERNION_NORM_TOLERANCE,
    measurement_columns,
    read_cart_measurements,
    read_measurements,
)
from gtmodel.errors import InputError

#: Round trip CSV write/read [m, rad]: 17 significant digits reproduce the float exactly.
ROUND_TRIP_TOLERANCE = 1e-15


def _set(n_q: int, orientation: bool, weights: bool, n: int = 9, seed: int = 0, load: bool = False) -> MeasurementSet:
    rng = np.random.default_rng(seed)
    quat = Rotation.random(n, random_state=seed).as_quat(scalar_first=True) if orientation else None
    return MeasurementSet(
        q=rng.uniform(-1, 1, (n, n_q)),
        T=rng.uniform(-3, 3, (n, 3)),
        quat=quat,
        weights=rng.uniform(0.5, 2.0, n) if weights else None,
        source="test set",
        comments=(" robot: L1", " device: laser tracker"),
        load=rng.uniform(-500, 0, (n, 3)) if load else None,
    )


@pytest.mark.parametrize(
    "n_q, orientation, weights, load",
    [(3, False, False, False), (3, True, False, False), (3, False, True, False), (3, False, False, True), (6, True, True, True)],
    ids=["3dof-position", "3dof-quaternion", "3dof-weights", "3dof-load", "f1-all-columns"],
)
def test_csv_round_trip(tmp_path, n_q, orientation, weights, load):
    """write -> read gives the same arrays (to 1e-15; the load [N] to 1e-15 relative), the same
    comments, and the documented header."""
    ms = _set(n_q, orientation, weights, load=load)
    path = ms.to_csv(tmp_path / "m.csv")
    back = read_measurements(path)
    assert path.read_text().splitlines()[2] == ",".join(measurement_columns(n_q, orientation, weights, load))
    assert back.has_load == load
    if load:
        np.testing.assert_allclose(back.load, ms.load, rtol=ROUND_TRIP_TOLERANCE, atol=0)
    assert back.n_poses == ms.n_poses and back.n_q == n_q
    np.testing.assert_allclose(back.q, ms.q, rtol=0, atol=ROUND_TRIP_TOLERANCE)
    np.testing.assert_allclose(back.T, ms.T, rtol=0, atol=ROUND_TRIP_TOLERANCE)
    assert (back.quat is None, back.weights is None) == (ms.quat is None, ms.weights is None)
    if ms.quat is not None:
        np.testing.assert_allclose(back.quat, ms.quat, rtol=0, atol=ROUND_TRIP_TOLERANCE)
    if ms.weights is not None:
        np.testing.assert_allclose(back.weights, ms.weights, rtol=0, atol=ROUND_TRIP_TOLERANCE)
    assert back.comments == ms.comments
    assert back.source == str(path)


def test_columns_in_any_order(tmp_path):
    """A file with the columns permuted reads the same values into the same fields."""
    path = tmp_path / "m.csv"
    path.write_text("Tz_m,q3_m,Ty_m,q2_m,Tx_m,q1_m\n3,0.3,2,0.2,1,0.1\n6,0.6,5,0.5,4,0.4\n")
    ms = read_measurements(path)
    np.testing.assert_array_equal(ms.q, [[0.1, 0.2, 0.3], [0.4, 0.5, 0.6]])
    np.testing.assert_array_equal(ms.T, [[1, 2, 3], [4, 5, 6]])


def test_cart_round_trip(tmp_path):
    """Cart survey write -> read: same nodes and points per arm (to 1e-15), rows sorted by q."""
    rng = np.random.default_rng(1)
    qs = tuple(np.sort(rng.uniform(-0.65, 0.7, m)) for m in (5, 7, 4))
    ps = tuple(rng.normal(size=(len(q), 3)) for q in qs)
    cm = CartMeasurements(q=qs, positions=ps, source="survey")
    back = read_cart_measurements(cm.to_csv(tmp_path / "c.csv"))
    for i in range(3):
        np.testing.assert_allclose(back.q[i], qs[i], rtol=0, atol=ROUND_TRIP_TOLERANCE)
        np.testing.assert_allclose(back.positions[i], ps[i], rtol=0, atol=ROUND_TRIP_TOLERANCE)


def test_cart_rows_in_any_order_are_sorted(tmp_path):
    """Rows given out of order are sorted by q per arm (the interpolation needs increasing nodes)."""
    path = tmp_path / "c.csv"
    path.write_text("arm,q_m,x_m,y_m,z_m\n" + "\n".join(f"{a},{q},{q + a},0,0" for a in (3, 1, 2) for q in (0.5, -0.5, 0.0)) + "\n")
    cm = read_cart_measurements(path)
    for i in range(3):
        np.testing.assert_array_equal(cm.q[i], [-0.5, 0.0, 0.5])
        np.testing.assert_array_equal(cm.positions[i][:, 0], cm.q[i] + i + 1)


GOOD_HEADER = "q1_m,q2_m,q3_m,Tx_m,Ty_m,Tz_m"
ROW_A = "0.1,0.2,0.3,1.0,2.0,3.0"
ROW_B = "0.4,0.5,0.6,4.0,5.0,6.0"

# Every file starts with a comment line, so data line numbers differ from row indices.
MALFORMED = [
    ("unknown-column", f"# t\nq1_m,q2_m,q3_m,Tx_m,Ty_m,Tz_mm\n{ROW_A}\n{ROW_B}\n", r"line 2 \(header\): unknown column 'Tz_mm'"),
    ("missing-column", "# t\nq1_m,q2_m,q3_m,Tx_m,Ty_m\n0.1,0.2,0.3,1,2\n0.4,0.5,0.6,4,5\n", r"line 2 \(header\): missing column\(s\) Tz_m"),
    ("repeated-column", f"# t\n{GOOD_HEADER},Tx_m\n{ROW_A},1\n{ROW_B},4\n", r"line 2 \(header\): column 'Tx_m' appears twice"),
    ("incomplete-quaternion", f"# t\n{GOOD_HEADER},qw,qx,qy\n{ROW_A},1,0,0\n{ROW_B},1,0,0\n", r"line 2 \(header\): missing column\(s\) qz"),
    ("incomplete-f1-angles", "# t\nq1_m,q2_m,q3_m,q4_rad,Tx_m,Ty_m,Tz_m\n0,0,0,0,1,2,3\n", r"line 2 \(header\): missing column\(s\) q5_rad, q6_rad"),
    ("too-few-values", f"# t\n{GOOD_HEADER}\n{ROW_A}\n0.4,0.5,0.6,4.0,5.0\n", r"line 4: 5 values, expected 6"),
    ("too-many-values", f"# t\n{GOOD_HEADER}\n{ROW_A},7\n{ROW_B}\n", r"line 3: 7 values, expected 6"),
    ("non-numeric", f"# t\n{GOOD_HEADER}\n{ROW_A}\n0.4,0.5,0.6,4.0,abc,6.0\n", r"line 4, column 'Ty_m': expected a decimal number, got 3 characters of text"),
    ("empty-field", f"# t\n{GOOD_HEADER}\n0.1,,0.3,1,2,3\n{ROW_B}\n", r"line 3, column 'q2_m': expected a decimal number, got an empty field"),
    ("underscore-number", f"# t\n{GOOD_HEADER}\n0.1,0.2,0.3,1_0,2,3\n{ROW_B}\n", r"line 3, column 'Tx_m': expected a decimal number"),
    ("nan", f"# t\n{GOOD_HEADER}\n{ROW_A}\n0.4,0.5,0.6,4.0,5.0,nan\n", r"line 4, column 'Tz_m': NaN/inf is not allowed"),
    ("inf", f"# t\n{GOOD_HEADER}\n-inf,0.2,0.3,1,2,3\n{ROW_B}\n", r"line 3, column 'q1_m': NaN/inf is not allowed"),
    ("duplicated-row", f"# t\n{GOOD_HEADER}\n{ROW_A}\n{ROW_B}\n{ROW_A}\n", r"line 5: duplicated row, identical to line 3"),
    ("non-unit-quaternion", f"# t\n{GOOD_HEADER},qw,qx,qy,qz\n{ROW_A},1,0,0,0\n{ROW_B},0.99,0,0,0\n", r"line 4, columns 'qw,qx,qy,qz': quaternion norm 0\.99"),
    ("incomplete-load", f"# t\n{GOOD_HEADER},F_x_N,F_z_N\n{ROW_A},0,-90\n{ROW_B},0,-490\n", r"line 2 \(header\): missing column\(s\) F_y_N"),
    ("unitless-load", f"# t\n{GOOD_HEADER},F_x,F_y,F_z\n{ROW_A},0,0,-90\n{ROW_B},0,0,-490\n", r"line 2 \(header\): unknown column 'F_x'"),
    ("non-numeric-load", f"# t\n{GOOD_HEADER},F_x_N,F_y_N,F_z_N\n{ROW_A},0,0,-90\n{ROW_B},0,0,-4 90\n", r"line 4, column 'F_z_N': expected a decimal number"),
    ("nan-load", f"# t\n{GOOD_HEADER},F_x_N,F_y_N,F_z_N\n{ROW_A},0,NaN,-90\n{ROW_B},0,0,-490\n", r"line 3, column 'F_y_N': NaN/inf is not allowed"),
    ("zero-weight", f"# t\n{GOOD_HEADER},weight\n{ROW_A},1\n{ROW_B},0\n", r"line 4, column 'weight': expected a positive weight"),
    ("negative-weight", f"# t\n{GOOD_HEADER},weight\n{ROW_A},-2\n{ROW_B},1\n", r"line 3, column 'weight': expected a positive weight"),
    ("too-few-rows", f"# t\n{GOOD_HEADER}\n{ROW_A}\n", r"1 data row\(s\), expected at least 2 poses"),
    ("header-only", f"# t\n{GOOD_HEADER}\n", r"0 data row\(s\), expected at least 2 poses"),
    ("no-header", "# only comments\n# here\n", r"no header line"),
    ("empty-line-inside", f"# t\n{GOOD_HEADER}\n{ROW_A}\n\n{ROW_B}\n", r"line 4: empty line inside the data"),
]


@pytest.mark.parametrize("content, match", [c[1:] for c in MALFORMED], ids=[c[0] for c in MALFORMED])
def test_malformed_measurement_file(tmp_path, content, match):
    """Each malformed file raises InputError naming the file and the faulty line/column."""
    path = tmp_path / "bad.csv"
    path.write_text(content)
    with pytest.raises(InputError, match=match) as info:
        read_measurements(path)
    assert str(path) in str(info.value)


def test_comment_between_rows_is_skipped(tmp_path):
    """A '#' line between rows is a comment (gtmodel._tables format); only the top ones are kept."""
    path = tmp_path / "late.csv"
    path.write_text(f"# t\n{GOOD_HEADER}\n{ROW_A}\n# late comment\n{ROW_B}\n")
    ms = read_measurements(path)
    assert ms.n_poses == 2 and ms.comments == (" t",)


def test_quaternion_within_tolerance_is_accepted(tmp_path):
    """A quaternion rounded by device software (norm off by less than the tolerance) is valid."""
    w = 1.0 + 0.5 * QUATERNION_NORM_TOLERANCE
    path = tmp_path / "m.csv"
    path.write_text(f"{GOOD_HEADER},qw,qx,qy,qz\n{ROW_A},{w!r},0,0,0\n{ROW_B},1,0,0,0\n")
    assert read_measurements(path).quat[0, 0] == w


def test_trailing_empty_lines_are_allowed(tmp_path):
    """Empty lines at the end of the file (editors add them) are not data rows."""
    path = tmp_path / "m.csv"
    path.write_text(f"{GOOD_HEADER}\n{ROW_A}\n{ROW_B}\n\n\n")
    assert read_measurements(path).n_poses == 2


@pytest.mark.parametrize(
    "n_q, min_poses, match",
    [(6, 2, r"expected 6 actuator columns"), (4, 2, r"n_q: expected 3, 6 or None"), (3, 3, r"2 data row\(s\), expected at least 3")],
    ids=["n_q-mismatch", "n_q-invalid", "min_poses"],
)
def test_read_arguments(tmp_path, n_q, min_poses, match):
    """The caller's expectations (n_q, min_poses) are checked against the file."""
    path = tmp_path / "m.csv"
    path.write_text(f"{GOOD_HEADER}\n{ROW_A}\n{ROW_B}\n")
    with pytest.raises(InputError, match=match):
        read_measurements(path, n_q=n_q, min_poses=min_poses)


def test_unreadable_file_names_it(tmp_path):
    """A missing file is an InputError naming the file, not an OSError traceback."""
    path = tmp_path / "nope.csv"
    with pytest.raises(InputError, match=r"nope\.csv: cannot read measurement file"):
        read_measurements(path)


CART_HEADER = "arm,q_m,x_m,y_m,z_m"
CART_OK = "\n".join(f"{a},{q},0,0,0" for a in (1, 2, 3) for q in (-0.5, 0.5))

MALFORMED_CART = [
    ("unknown-column", f"# t\narm,q_m,x_m,y_m,z\n{CART_OK}\n", r"line 2 \(header\): unknown column 'z'"),
    ("missing-column", "# t\narm,q_m,x_m,y_m\n1,0,0,0\n", r"line 2 \(header\): missing column\(s\) z_m"),
    ("non-integer-arm", f"# t\n{CART_HEADER}\n{CART_OK}\n1.5,0.1,0,0,0\n", r"line 9, column 'arm': expected an integer arm number 1\.\.3, got '1\.5'"),
    ("arm-out-of-range", f"# t\n{CART_HEADER}\n4,0.1,0,0,0\n{CART_OK}\n", r"line 3, column 'arm': expected an integer arm number 1\.\.3, got '4'"),
    ("same-q-twice", f"# t\n{CART_HEADER}\n{CART_OK}\n2,0.5,1,0,0\n", r"line 9: duplicated row, the same arm and q_m as line 6"),
    ("too-few-points", f"# t\n{CART_HEADER}\n1,0,0,0,0\n1,1,0,0,0\n2,0,0,0,0\n2,1,0,0,0\n3,0,0,0,0\n", r"arm 3 has 1 row\(s\), expected at least 2"),
    ("nan", f"# t\n{CART_HEADER}\n{CART_OK}\n3,0.9,0,NaN,0\n", r"line 9, column 'y_m': NaN/inf is not allowed"),
    ("wrong-count", f"# t\n{CART_HEADER}\n1,0.9,0,0\n{CART_OK}\n", r"line 3: 4 values, expected 5"),
]


@pytest.mark.parametrize("content, match", [c[1:] for c in MALFORMED_CART], ids=[c[0] for c in MALFORMED_CART])
def test_malformed_cart_file(tmp_path, content, match):
    """Each malformed cart survey raises InputError naming the file and the faulty line/column."""
    path = tmp_path / "bad_cart.csv"
    path.write_text(content)
    with pytest.raises(InputError, match=match) as info:
        read_cart_measurements(path)
    assert str(path) in str(info.value)


def test_split_alternate_every_second_pose():
    """Calibration = rows 0, 2, 4, ...; validation = rows 1, 3, 5, ... (Dressler (2012), ch. 5.2)."""
    ms = _set(3, True, True, n=7, load=True)
    cal, val = ms.split_alternate()
    np.testing.assert_array_equal(val.load, ms.load[[1, 3, 5]])
    np.testing.assert_array_equal(cal.q, ms.q[[0, 2, 4, 6]])
    np.testing.assert_array_equal(val.T, ms.T[[1, 3, 5]])
    np.testing.assert_array_equal(val.quat, ms.quat[[1, 3, 5]])
    np.testing.assert_array_equal(cal.weights, ms.weights[[0, 2, 4, 6]])


@pytest.mark.parametrize(
    "indices, match",
    [([0, 9], r"row 9 is out of range 0\.\.8"), ([], r"selection is empty"), (np.ones(3, dtype=bool), r"boolean mask of length 9")],
    ids=["out-of-range", "empty", "mask-length"],
)
def test_subset_rejects_bad_indices(indices, match):
    """subset names the offending index."""
    with pytest.raises(InputError, match=match):
        _set(3, False, False).subset(indices)


@pytest.mark.parametrize(
    "kwargs, match",
    [
        (dict(q=np.zeros((2, 4)), T=np.zeros((2, 3))), r"MeasurementSet\.q: expected shape \(N, 3\) or \(N, 6\)"),
        (dict(q=np.zeros((2, 3)), T=np.zeros((3, 3))), r"MeasurementSet\.T: expected shape \(2, 3\)"),
        (dict(q=np.zeros((2, 3)), T=np.zeros((2, 3)), quat=np.zeros((2, 4))), r"MeasurementSet\.quat: row 0 has norm 0\.0"),
        (dict(q=np.zeros((2, 3)), T=np.zeros((2, 3)), weights=[1.0, -1.0]), r"MeasurementSet\.weights: row 1"),
        (dict(q=[[0, 0, np.nan]] * 2, T=np.zeros((2, 3))), r"MeasurementSet\.q: non-finite value in row 0"),
        (dict(q=np.zeros((2, 3)), T=np.zeros((2, 3)), load=np.zeros((2, 2))), r"MeasurementSet\.load: expected shape \(2, 3\)"),
        (dict(q=np.zeros((2, 3)), T=np.zeros((2, 3)), load=np.zeros((3, 3))), r"MeasurementSet\.load: expected shape \(2, 3\)"),
        (dict(q=np.zeros((2, 3)), T=np.zeros((2, 3)), load=[[0, 0, -90], [0, np.inf, 0]]), r"MeasurementSet\.load: non-finite value in row 1"),
        (dict(q=np.zeros((2, 3)), T=np.zeros((2, 3)), load=[["a", 0, 0], [0, 0, 0]]), r"MeasurementSet\.load: expected numbers"),
    ],
    ids=["q-columns", "T-rows", "quaternion-norm", "weight", "nan", "load-columns", "load-rows", "load-inf", "load-text"],
)
def test_measurement_set_validates(kwargs, match):
    """The dataclass checks shapes and values as the reader does."""
    with pytest.raises(InputError, match=match):
        MeasurementSet(**kwargs)
