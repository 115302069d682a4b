"""Measurement data for kinematic calibration: CSV files in, :class:`MeasurementSet` out.

Two small CSV formats are read and written here, both in the one table format of
:mod:`gtmodel._tables` (comments, header, numbers; read by :func:`gtmodel._tables.read_table`)
and strictly validated: every error is an :class:`~gtmodel.errors.InputError` naming the
file, the line (1-based line number in the file) and the column.

Pose measurements (:func:`read_measurements`, :meth:`MeasurementSet.to_csv`)
---------------------------------------------------------------------------
One row per measured pose: the actuator values commanded to the robot and the measured
TCP (target) position, optionally the measured orientation of the plate/target frame, the
known load on the plate and a weight. Example (3-DOF robot, laser tracker)::

    # robot: L1, device: Leica laser tracker, corner cube on the plate
    # date: 2011-05-03
    q1_m,q2_m,q3_m,Tx_m,Ty_m,Tz_m
    -0.25,0.10,0.35,-1.0723,2.9135,-0.6311
    ...

- Lines starting with ``#`` are comments. Those at the top, before the header
  (provenance: robot, device, date, frame), are kept in :attr:`MeasurementSet.comments`
  and written back by :meth:`MeasurementSet.to_csv`; those between rows are skipped.
- The header names the columns, each with its unit. Columns may come in any order; each
  may appear once. Accepted columns:

  ===================================  =======================================================
  ``q1_m, q2_m, q3_m``                 cart positions of the linear actuators [m] (required)
  ``q4_rad, q5_rad, q6_rad``           joint-plate angles of the F1-type 6-DOF robot [rad]
                                       (Dressler (2012), eqs. 4.20-4.24); all three or none
  ``Tx_m, Ty_m, Tz_m``                 measured TCP/target position [m] (required)
  ``qw, qx, qy, qz``                   measured orientation of the plate/target frame as a
                                       unit quaternion ``(w, x, y, z)`` (6-D target, e.g.
                                       Leica T-Mac); all four or none
  ``F_x_N, F_y_N, F_z_N``              known load on the plate/TCP during the measurement [N]
                                       (e.g. the weight of plate and payload; used by the
                                       elasto-geometric calibration); all three or none
  ``weight``                           positive weight of the pose in the calibration cost
                                       (optional; all poses weigh 1 without it)
  ===================================  =======================================================

- Every data row has exactly one value per header column: a decimal number
  (``[+-]digits[.digits][e[+-]digits]``); NaN, inf, empty fields, thousands separators
  and quotes are errors (:mod:`gtmodel._tables`). SI units as named in the header (a file
  in mm is converted before writing it in this format).
- A quaternion must have unit norm within :data:`QUATERNION_NORM_TOLERANCE`; weights
  must be positive; two identical rows are an error (a copy-paste slip); the file must
  hold at least ``min_poses`` rows (default :data:`MIN_POSES`). Empty lines are allowed
  only at the end of the file.

Cart measurements (:func:`read_cart_measurements`, :meth:`CartMeasurements.to_csv`)
-----------------------------------------------------------------------------------
Positions of a point on each cart measured along its guideway, the data of the
piecewise-linear actuator model (Dressler (2012), eq. 5.7; D1 range -0.650..0.700 m)::

    # D1 guideway survey, laser tracker, frame of the survey (not the TCP data frame)
    arm,q_m,x_m,y_m,z_m
    1,-0.650,0.12345,-0.00123,0.00045
    1,-0.600,0.17346,-0.00121,0.00047
    ...
    3,0.700,1.47311,0.00214,-0.00012

- ``arm`` is the arm (= actuator) number 1, 2, 3 written as an integer; ``q_m`` the
  actuator value [m]; ``x_m, y_m, z_m`` the measured cart point [m] in the frame of the
  guideway survey. The same comment/header/number rules as above apply; the header must
  hold exactly these five columns (any order).
- Every arm needs at least :data:`MIN_CART_POINTS` rows and a value of ``q_m`` may occur
  only once per arm (the interpolation needs strictly increasing nodes). Rows may come in
  any order; they are sorted by ``q`` per arm on reading.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Sequence

import numpy as np
import numpy.typing  # noqa: F401  (np.typing in annotations)

from gtmodel._tables import read_table, write_table
from gtmodel.errors import InputError
from gtmodel.robots.closure import quaternion_to_rotation

__all__ = [
    "MeasurementSet",
    "CartMeasurements",
    "read_measurements",
    "read_cart_measurements",
    "measurement_columns",
    "QUATERNION_NORM_TOLERANCE",
    "MIN_POSES",
    "MIN_CART_POINTS",
    "MAX_POSES",
    "MAX_POSE_FILE_BYTES",
    "MAX_CART_POINTS",
    "MAX_CART_FILE_BYTES",
    "CART_COLUMNS",
]

_log = logging.getLogger("gtmodel")

#: Largest accepted deviation of a measured quaternion's norm from 1 (dimensionless).
#: Device software writes unit quaternions rounded to ~8 digits; 1e-6 accepts that and
#: rejects a scaled or truncated 4-vector.
QUATERNION_NORM_TOLERANCE = 1e-6
#: Default smallest number of poses in a measurement file (2: one calibration and one
#: validation pose after :meth:`MeasurementSet.split_alternate`). Calibrations ask for
#: more through ``min_poses``.
MIN_POSES = 2
#: Smallest number of cart positions per arm in a cart-measurement file (one segment).
MIN_CART_POINTS = 2
#: Most poses in a measurement file (a laser-tracker campaign holds hundreds to a few thousand;
#: Dressler (2012), ch. 5) and the largest such file [bytes]: a larger file is refused before it is parsed.
MAX_POSES = 20_000
MAX_POSE_FILE_BYTES = 10_000_000
#: Most rows of a cart survey (all arms) and the largest such file [bytes].
MAX_CART_POINTS = 20_000
MAX_CART_FILE_BYTES = 5_000_000
#: Columns of the cart-measurement format, in the order written.
CART_COLUMNS = ("arm", "q_m", "x_m", "y_m", "z_m")

_Q_LINEAR = ("q1_m", "q2_m", "q3_m")
_Q_ROTARY = ("q4_rad", "q5_rad", "q6_rad")
_T_COLS = ("Tx_m", "Ty_m", "Tz_m")
_QUAT_COLS = ("qw", "qx", "qy", "qz")
_LOAD_COLS = ("F_x_N", "F_y_N", "F_z_N")
_WEIGHT_COL = "weight"


def measurement_columns(n_q: int = 3, orientation: bool = False, weights: bool = False, load: bool = False) -> tuple[str, ...]:
    """Header of a pose-measurement file, in the order :meth:`MeasurementSet.to_csv` writes.

    Parameters
    ----------
    n_q : {3, 6}, optional
        Actuator values per pose (3 for the 3-DOF Gantry-Tau, 6 for the F1).
    orientation : bool, optional
        Whether the quaternion columns ``qw, qx, qy, qz`` are included.
    weights : bool, optional
        Whether the ``weight`` column is included.
    load : bool, optional
        Whether the load columns ``F_x_N, F_y_N, F_z_N`` are included (after the
        quaternion, before the weight).

    Returns
    -------
    tuple of str
        Column names with units, e.g. ``("q1_m", "q2_m", "q3_m", "Tx_m", "Ty_m", "Tz_m")``.

    Raises
    ------
    InputError
        If ``n_q`` is not 3 or 6.
    """
    if n_q not in (3, 6):
        raise InputError(f"n_q: expected 3 or 6 actuator values per pose, got {n_q!r}")
    cols = list(_Q_LINEAR) + (list(_Q_ROTARY) if n_q == 6 else []) + list(_T_COLS)
    if orientation:
        cols += list(_QUAT_COLS)
    if load:
        cols += list(_LOAD_COLS)
    if weights:
        cols.append(_WEIGHT_COL)
    return tuple(cols)


# ----------------------------------------------------------------------------- data classes
@dataclass(frozen=True, eq=False)
class MeasurementSet:
    """Measured poses of a calibration experiment (rows are poses).

    Parameters
    ----------
    q : numpy.ndarray, shape (N, n_q)
        Actuator values [m] (``q1..q3``) and, for the F1, [rad] (``q4..q6``).
    T : numpy.ndarray, shape (N, 3)
        Measured TCP/target positions [m] in the measurement-device frame.
    quat : numpy.ndarray, shape (N, 4), or None
        Measured plate/target orientations as unit quaternions ``(w, x, y, z)``, or None
        for position-only data.
    weights : numpy.ndarray, shape (N,), or None
        Positive weights of the poses in the cost (None: all 1).
    source : str
        Where the data come from (file path, or a description of a synthetic set).
    comments : tuple of str, optional
        Provenance lines (without the leading ``#``), written back by :meth:`to_csv`.
    load : numpy.ndarray, shape (N, 3), or None, optional
        Known load on the plate/TCP of each pose [N] in the measurement frame (e.g. the
        weight of plate and payload, for the elasto-geometric calibration), or None.

    Raises
    ------
    InputError
        If shapes disagree, values are not finite, a quaternion is not of unit norm or a
        weight is not positive.
    """

    q: np.ndarray
    T: np.ndarray
    quat: np.ndarray | None = None
    weights: np.ndarray | None = None
    source: str = ""
    comments: tuple[str, ...] = field(default=(), compare=False)
    load: np.ndarray | None = None

    def __post_init__(self) -> None:
        q = np.array(self.q, dtype=float, ndmin=2)
        T = np.array(self.T, dtype=float, ndmin=2)
        if q.ndim != 2 or q.shape[1] not in (3, 6):
            raise InputError(f"MeasurementSet.q: expected shape (N, 3) or (N, 6), got {np.shape(self.q)}")
        N = q.shape[0]
        if T.shape != (N, 3):
            raise InputError(f"MeasurementSet.T: expected shape ({N}, 3) to match q, got {np.shape(self.T)}")
        for name, a in (("q", q), ("T", T)):
            if not np.all(np.isfinite(a)):
                raise InputError(f"MeasurementSet.{name}: non-finite value in row {int(np.argmax(~np.all(np.isfinite(a), axis=1)))}")
        object.__setattr__(self, "q", q)
        object.__setattr__(self, "T", T)
        if self.quat is not None:
            quat = np.array(self.quat, dtype=float, ndmin=2)
            if quat.shape != (N, 4):
                raise InputError(f"MeasurementSet.quat: expected shape ({N}, 4) or None, got {np.shape(self.quat)}")
            norm = np.linalg.norm(quat, axis=1)
            bad = ~(np.abs(norm - 1.0) <= QUATERNION_NORM_TOLERANCE)
            if np.any(bad):
                k = int(np.argmax(bad))
                raise InputError(
                    f"MeasurementSet.quat: row {k} has norm {float(norm[k])!r}, expected a unit quaternion "
                    f"(tolerance {QUATERNION_NORM_TOLERANCE:g})"
                )
            object.__setattr__(self, "quat", quat)
        if self.weights is not None:
            w = np.array(self.weights, dtype=float).reshape(-1)
            if w.shape != (N,):
                raise InputError(f"MeasurementSet.weights: expected shape ({N},) or None, got {np.shape(self.weights)}")
            bad = ~(w > 0) | ~np.isfinite(w)
            if np.any(bad):
                k = int(np.argmax(bad))
                raise InputError(f"MeasurementSet.weights: row {k} is {float(w[k])!r}, expected a positive finite weight")
            object.__setattr__(self, "weights", w)
        if self.load is not None:
            try:
                F = np.array(self.load, dtype=float, ndmin=2)
            except (TypeError, ValueError):
                raise InputError(f"MeasurementSet.load: expected numbers of shape ({N}, 3) [N] or None, got {self.load!r}") from None
            if F.shape != (N, 3):
                raise InputError(f"MeasurementSet.load: expected shape ({N}, 3) [N] or None, got {np.shape(self.load)}")
            bad = ~np.all(np.isfinite(F), axis=1)
            if np.any(bad):
                raise InputError(f"MeasurementSet.load: non-finite value in row {int(np.argmax(bad))}")
            object.__setattr__(self, "load", F)
        object.__setattr__(self, "comments", tuple(str(c) for c in self.comments))

    # ------------------------------------------------------------------ properties
    @property
    def n_poses(self) -> int:
        """Number of poses N."""
        return int(self.q.shape[0])

    @property
    def n_q(self) -> int:
        """Actuator values per pose (3 or 6)."""
        return int(self.q.shape[1])

    @property
    def has_orientation(self) -> bool:
        """Whether orientations were measured (``quat`` is not None)."""
        return self.quat is not None

    def rotations(self) -> np.ndarray:
        """Measured orientations as rotation matrices.

        Returns
        -------
        numpy.ndarray, shape (N, 3, 3)
            ``R_T`` of each pose, from :func:`gtmodel.robots.closure.quaternion_to_rotation`.

        Raises
        ------
        InputError
            If the set has no orientations.
        """
        if self.quat is None:
            raise InputError(f"measurements {self.source!r} hold no orientations (no qw, qx, qy, qz columns)")
        return np.array([quaternion_to_rotation(qk) for qk in self.quat])

    @property
    def has_load(self) -> bool:
        """Whether the poses carry a known plate load (``load`` is not None)."""
        return self.load is not None

    def weights_or_ones(self) -> np.ndarray:
        """The pose weights, ones where none were given.

        Returns
        -------
        numpy.ndarray, shape (N,)
        """
        return np.ones(self.n_poses) if self.weights is None else self.weights.copy()

    # ------------------------------------------------------------------ selections
    def subset(self, indices: Sequence[int] | np.ndarray) -> "MeasurementSet":
        """The poses at the given row indices (in that order).

        Parameters
        ----------
        indices : sequence of int or numpy.ndarray of int or bool
            Row indices (0-based) or a boolean mask of length N.

        Returns
        -------
        MeasurementSet
            The selected poses; ``source`` says it is a subset.

        Raises
        ------
        InputError
            If an index is out of range, the mask has the wrong length, or the selection
            is empty.
        """
        idx = np.asarray(indices)
        if idx.dtype == bool:
            if idx.shape != (self.n_poses,):
                raise InputError(f"indices: boolean mask of length {self.n_poses} expected, got shape {idx.shape}")
            idx = np.flatnonzero(idx)
        if idx.size == 0:
            raise InputError("indices: the selection is empty")
        if not np.issubdtype(idx.dtype, np.integer):
            raise InputError(f"indices: integer row indices expected, got dtype {idx.dtype}")
        idx = idx.reshape(-1)
        bad = (idx < 0) | (idx >= self.n_poses)
        if np.any(bad):
            raise InputError(f"indices: row {int(idx[np.argmax(bad)])} is out of range 0..{self.n_poses - 1}")
        return MeasurementSet(
            q=self.q[idx],
            T=self.T[idx],
            quat=None if self.quat is None else self.quat[idx],
            weights=None if self.weights is None else self.weights[idx],
            source=f"{self.source} [subset of {idx.size} of {self.n_poses} poses]",
            comments=self.comments,
            load=None if self.load is None else self.load[idx],
        )

    def split_alternate(self) -> tuple["MeasurementSet", "MeasurementSet"]:
        """Calibration and validation halves: every second pose (Dressler (2012), ch. 5.2).

        Returns
        -------
        calibration : MeasurementSet
            Rows 0, 2, 4, ...
        validation : MeasurementSet
            Rows 1, 3, 5, ...

        Raises
        ------
        InputError
            If the set has fewer than 2 poses.
        """
        if self.n_poses < 2:
            raise InputError(f"split_alternate: needs at least 2 poses, {self.source!r} has {self.n_poses}")
        idx = np.arange(self.n_poses)
        return self.subset(idx[0::2]), self.subset(idx[1::2])

    # ------------------------------------------------------------------ output
    def columns(self) -> tuple[str, ...]:
        """Header this set is written with (see :func:`measurement_columns`).

        Returns
        -------
        tuple of str
        """
        return measurement_columns(self.n_q, self.quat is not None, self.weights is not None, self.load is not None)

    def to_csv(self, path: str | Path) -> Path:
        """Write the set in the pose-measurement CSV format (module docstring).

        Numbers are written with 17 significant digits, so :func:`read_measurements`
        reads back the same floats. ``comments`` become ``#`` lines at the top, preceded
        by a ``# source:`` line.

        Parameters
        ----------
        path : str or pathlib.Path
            File to write (overwritten).

        Returns
        -------
        pathlib.Path
            The file written.

        Raises
        ------
        InputError
            If the file cannot be written.
        """
        blocks = [self.q, self.T]
        if self.quat is not None:
            blocks.append(self.quat)
        if self.load is not None:
            blocks.append(self.load)
        if self.weights is not None:
            blocks.append(self.weights[:, None])
        comments = list(self.comments) or ([f" source: {self.source}"] if self.source else [])
        return write_table(path, self.columns(), np.hstack(blocks), comments, what="measurement file")


@dataclass(frozen=True, eq=False)
class CartMeasurements:
    """Measured cart positions along each guideway (data of Dressler (2012), eq. 5.7).

    Parameters
    ----------
    q : tuple of numpy.ndarray
        Per arm, strictly increasing actuator values [m], shape (M_i,).
    positions : tuple of numpy.ndarray
        Per arm, the measured cart points [m], shape (M_i, 3), in the frame of the
        guideway survey.
    source : str
        Where the data come from.
    comments : tuple of str, optional
        Provenance lines (without the leading ``#``).

    Raises
    ------
    InputError
        If an arm has fewer than :data:`MIN_CART_POINTS` points, ``q`` is not strictly
        increasing, shapes disagree or values are not finite.
    """

    q: tuple[np.ndarray, ...]
    positions: tuple[np.ndarray, ...]
    source: str = ""
    comments: tuple[str, ...] = field(default=(), compare=False)

    def __post_init__(self) -> None:
        if len(self.q) != len(self.positions) or len(self.q) == 0:
            raise InputError(
                f"CartMeasurements: q and positions need one entry per arm, got {len(self.q)} and {len(self.positions)}"
            )
        qs, ps = [], []
        for i, (qi, pi) in enumerate(zip(self.q, self.positions)):
            qa = np.array(qi, dtype=float).reshape(-1)
            pa = np.array(pi, dtype=float, ndmin=2)
            if pa.shape != (qa.size, 3):
                raise InputError(f"CartMeasurements arm {i + 1}: positions must have shape ({qa.size}, 3), got {pa.shape}")
            if qa.size < MIN_CART_POINTS:
                raise InputError(f"CartMeasurements arm {i + 1}: needs at least {MIN_CART_POINTS} cart positions, got {qa.size}")
            if not (np.all(np.isfinite(qa)) and np.all(np.isfinite(pa))):
                raise InputError(f"CartMeasurements arm {i + 1}: non-finite value")
            if np.any(np.diff(qa) <= 0):
                raise InputError(f"CartMeasurements arm {i + 1}: q must be strictly increasing")
            qs.append(qa)
            ps.append(pa)
        object.__setattr__(self, "q", tuple(qs))
        object.__setattr__(self, "positions", tuple(ps))
        object.__setattr__(self, "comments", tuple(str(c) for c in self.comments))

    @property
    def n_arms(self) -> int:
        """Number of arms (guideways) measured."""
        return len(self.q)

    def q_range(self, arm: int) -> tuple[float, float]:
        """Range of the measured actuator values of one arm.

        Parameters
        ----------
        arm : int
            Arm index 0, 1, 2 (0-based, as in :class:`gtmodel.robots.closure.ClosureModel`).

        Returns
        -------
        tuple of float
            ``(q_min, q_max)`` [m].

        Raises
        ------
        InputError
            If ``arm`` is out of range.
        """
        self._check_arm(arm)
        return float(self.q[arm][0]), float(self.q[arm][-1])

    def _check_arm(self, arm: int) -> None:
        if not isinstance(arm, (int, np.integer)) or not 0 <= arm < self.n_arms:
            raise InputError(f"arm must be one of 0..{self.n_arms - 1}, got {arm!r}")

    def to_csv(self, path: str | Path) -> Path:
        """Write the cart positions in the cart-measurement CSV format (module docstring).

        Parameters
        ----------
        path : str or pathlib.Path
            File to write (overwritten).

        Returns
        -------
        pathlib.Path
            The file written.

        Raises
        ------
        InputError
            If the file cannot be written.
        """
        rows = [np.column_stack([np.full(qa.size, i + 1.0), qa, pa]) for i, (qa, pa) in enumerate(zip(self.q, self.positions))]
        comments = list(self.comments) or ([f" source: {self.source}"] if self.source else [])
        return write_table(path, CART_COLUMNS, np.vstack(rows), comments, integer_columns=(0,), what="measurement file")


# ----------------------------------------------------------------------------- checks
# ----------------------------------------------------------------------------- readers
def read_measurements(path: str | Path, n_q: int | None = None, min_poses: int = MIN_POSES) -> MeasurementSet:
    """Read a pose-measurement CSV file (format in the module docstring), strictly validated.

    Parameters
    ----------
    path : str or pathlib.Path
        The file.
    n_q : {3, 6} or None, optional
        Expected actuator values per pose; None infers it from the header (``q4_rad`` etc.
        present: 6).
    min_poses : int, optional
        Smallest accepted number of poses (default :data:`MIN_POSES`).

    Returns
    -------
    MeasurementSet
        ``source`` is the file path, ``comments`` the ``#`` lines at the top.

    Raises
    ------
    InputError
        Unreadable file, more than :data:`MAX_POSES` rows or :data:`MAX_POSE_FILE_BYTES`
        bytes; unknown, missing, incomplete (quaternion, F1 angles, load) or repeated columns; a row with the wrong number of values; a value that is not a finite
        decimal number; a non-unit quaternion (:data:`QUATERNION_NORM_TOLERANCE`); a
        non-positive weight; two identical rows; fewer than ``min_poses`` rows; or
        ``n_q`` disagreeing with the header. The message names the file, the line
        (1-based) and the column.
    """
    if n_q is not None and n_q not in (3, 6):
        raise InputError(f"n_q: expected 3, 6 or None, got {n_q!r}")
    table = read_table(path, "measurement file", max_rows=MAX_POSES, max_bytes=MAX_POSE_FILE_BYTES)
    origin, cols, hl = table.source, table.columns, table.header_line
    known = [*measurement_columns(6, True, True, True)]
    table.check_columns(allowed=known)
    rotary = [c for c in _Q_ROTARY if c in cols]
    if rotary and len(rotary) != 3:
        table.check_columns(_Q_ROTARY, note="the F1 angles q4..q6 come together")
    n_q_file = 6 if rotary else 3
    if n_q is not None and n_q != n_q_file:
        expected = ",".join(measurement_columns(n_q)[:n_q])
        raise InputError(f"{origin}: line {hl} (header): expected {n_q} actuator columns {expected}, the file has {n_q_file}")
    table.check_columns(list(_Q_LINEAR) + list(_T_COLS))
    quat_cols = [c for c in _QUAT_COLS if c in cols]
    if quat_cols:
        table.check_columns(_QUAT_COLS, note="a quaternion needs qw, qx, qy, qz")
    load_cols = [c for c in _LOAD_COLS if c in cols]
    if load_cols:
        table.check_columns(_LOAD_COLS, note="a load needs F_x_N, F_y_N, F_z_N")
    data = table.data
    if data.shape[0] < min_poses:
        raise InputError(f"{origin}: {data.shape[0]} data row(s), expected at least {min_poses} poses")
    ix = {c: j for j, c in enumerate(cols)}
    quat = None
    if quat_cols:
        quat = data[:, [ix[c] for c in _QUAT_COLS]]
        norm = np.linalg.norm(quat, axis=1)
        bad = ~(np.abs(norm - 1.0) <= QUATERNION_NORM_TOLERANCE)
        if np.any(bad):
            r = int(np.argmax(bad))
            raise table.error(
                f"quaternion norm {norm[r]:.9g}, expected a unit quaternion (|norm - 1| <= {QUATERNION_NORM_TOLERANCE:g})",
                row=r, column="qw,qx,qy,qz",
            )
    weights = None
    if _WEIGHT_COL in ix:
        weights = data[:, ix[_WEIGHT_COL]]
        bad = ~(weights > 0)
        if np.any(bad):
            r = int(np.argmax(bad))
            raise table.error(f"expected a positive weight, got {float(weights[r])!r}", row=r, column="weight")
    table.check_unique_rows()
    qcols = measurement_columns(n_q_file)[:n_q_file]
    ms = MeasurementSet(
        q=data[:, [ix[c] for c in qcols]],
        T=data[:, [ix[c] for c in _T_COLS]],
        quat=quat,
        weights=weights,
        source=origin,
        comments=tuple(table.comments),
        load=data[:, [ix[c] for c in _LOAD_COLS]] if load_cols else None,
    )
    _log.debug("read %d poses (n_q=%d, orientation=%s) from %s", ms.n_poses, ms.n_q, quat is not None, origin)
    return ms


def read_cart_measurements(path: str | Path, n_arms: int = 3) -> CartMeasurements:
    """Read a cart-measurement CSV file (format in the module docstring), strictly validated.

    Parameters
    ----------
    path : str or pathlib.Path
        The file.
    n_arms : int, optional
        Number of arms the file must cover (arms ``1..n_arms``; default 3).

    Returns
    -------
    CartMeasurements
        Per arm the positions sorted by ``q``.

    Raises
    ------
    InputError
        Unreadable file, more than :data:`MAX_CART_POINTS` rows or :data:`MAX_CART_FILE_BYTES` bytes; unknown, missing or repeated columns; a row with the wrong
        number of values; a value that is not a finite decimal number; an ``arm`` that is
        not an integer in ``1..n_arms``; an arm with fewer than :data:`MIN_CART_POINTS`
        rows; the same ``q_m`` twice for one arm. The message names the file, the line
        (1-based) and the column.
    """
    if not isinstance(n_arms, (int, np.integer)) or n_arms < 1:
        raise InputError(f"n_arms: expected a positive integer, got {n_arms!r}")
    table = read_table(path, "cart-measurement file", max_rows=MAX_CART_POINTS, max_bytes=MAX_CART_FILE_BYTES)
    origin = table.source
    table.check_columns(CART_COLUMNS, allowed=CART_COLUMNS)
    data = table.data
    ix = {c: j for j, c in enumerate(table.columns)}
    arm = data[:, ix["arm"]]
    for r, a in enumerate(arm):
        if not (a == math.floor(a) and 1 <= a <= n_arms):
            raise table.error(f"expected an integer arm number 1..{n_arms}, got '{a:g}'", row=r, column="arm")
    table.check_unique_rows(("arm", "q_m"), what="the same arm and q_m as")
    qs, ps = [], []
    pcols = [ix["x_m"], ix["y_m"], ix["z_m"]]
    for i in range(n_arms):
        rows = np.flatnonzero(arm == i + 1)
        if rows.size < MIN_CART_POINTS:
            raise InputError(f"{origin}: column 'arm': arm {i + 1} has {rows.size} row(s), expected at least {MIN_CART_POINTS}")
        order = rows[np.argsort(data[rows, ix["q_m"]], kind="stable")]
        qs.append(data[order, ix["q_m"]])
        ps.append(data[order][:, pcols])
    cm = CartMeasurements(q=tuple(qs), positions=tuple(ps), source=origin, comments=tuple(table.comments))
    _log.debug("read cart positions of %d arms (%s points) from %s", n_arms, [len(x) for x in qs], origin)
    return cm
