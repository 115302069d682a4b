"""Stereo corner measurements: synthetic images of the pattern, and the CSV file of real ones.

Synthetic images (:func:`synthetic_stereo_images`): the pattern on the end-effector plate
of a true robot is projected by the true cameras (:mod:`~gtmodel.calibration.vision.camera`)
at each pose; a camera detects the pattern only when every corner is in front of it and
inside its image (less a margin) and the pattern is not seen too obliquely (angle between
the plate normal and the line of sight to the pattern centre at most ``max_obliquity_deg``);
detected corners get Gaussian pixel noise. A pose is a stereo measurement when both
cameras detect the pattern (Dressler (2012), ch. 5.5: 125 of 282 images detected).

Measurement file (:func:`read_stereo_corners`, :meth:`StereoImages.to_csv`)
-------------------------------------------------------------------------
One row per pose and corner, in the table format of :mod:`gtmodel._tables`::

    # rig: two firewire cameras, five-square pattern; corners by our detector
    pose,corner,q1_m,q2_m,q3_m,u1_px,v1_px,u2_px,v2_px
    1,1,-0.2,0.1,0.3,512.31,388.02,498.77,391.45
    1,2,-0.2,0.1,0.3,530.12,388.35,516.40,391.80
    ...

- ``pose``: a positive integer naming the pose; ``corner``: 1..M, the corner's index in
  the declared pattern (:class:`~gtmodel.calibration.vision.camera.Pattern` order).
- ``q1_m, q2_m, q3_m``: the cart positions of the pose [m], the same on each of its rows.
- ``u1_px, v1_px`` and ``u2_px, v2_px``: the corner's pixel coordinates in camera 1 and 2
  (origin at the top-left pixel corner, u right, v down), inside each image.
- Every pose has every corner exactly once (a pose seen by only one camera, or with a
  corner not detected, is left out of the file). Rows may come in any order.

Every error is an :class:`~gtmodel.errors.InputError` naming the file, the line and the column.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Sequence

import numpy as np
import numpy.typing  # noqa: F401  (np.typing in annotations)

from gtmodel._arrays import as_rotation
from gtmodel._tables import read_table, write_table
from gtmodel.calibration.poses import _fk_filter, _model_limits, _q_box
from gtmodel.calibration.vision.camera import Camera, Pattern
from gtmodel.errors import InputError
from gtmodel.robots.closure import ClosureModel

__all__ = [
    "StereoImages", "PatternMount", "SyntheticStereo", "synthetic_stereo_images", "read_stereo_corners",
    "actuator_grid_poses", "CORNER_COLUMNS", "MAX_CORNER_ROWS", "MAX_CORNER_FILE_BYTES", "MAX_OBLIQUITY_DEG",
]

#: Columns of the measurement file, in the order written.
CORNER_COLUMNS = ("pose", "corner", "q1_m", "q2_m", "q3_m", "u1_px", "v1_px", "u2_px", "v2_px")
#: Most data rows of a measurement file (5000 poses of 20 corners).
MAX_CORNER_ROWS = 100_000
#: Largest measurement file [bytes].
MAX_CORNER_FILE_BYTES = 20_000_000
#: Default largest angle between the plate normal and the line of sight [deg] at which a
#: pattern is still detected (ASSUMED; the thesis gives no figure).
MAX_OBLIQUITY_DEG = 60.0


@dataclass(frozen=True)
class StereoImages:
    """Corners of the pattern seen by two cameras at N poses.

    Parameters
    ----------
    q : numpy.ndarray, shape (N, 3)
        Cart positions [m].
    uv : numpy.ndarray, shape (N, 2, M, 2)
        Pixel coordinates [px] per pose, camera, corner.
    pose_ids : numpy.ndarray of int, shape (N,)
        Pose numbers (the file's ``pose`` column).
    source : str, optional
        Where the data come from.
    comments : tuple of str, optional
        Provenance lines of the file.

    Raises
    ------
    InputError
        Shapes disagree or values are not finite.
    """

    q: np.ndarray
    uv: np.ndarray
    pose_ids: np.ndarray
    source: str = ""
    comments: tuple[str, ...] = field(default=(), compare=False)

    def __post_init__(self) -> None:
        q = np.asarray(self.q, dtype=float).reshape(-1, 3)
        uv = np.asarray(self.uv, dtype=float)
        ids = np.asarray(self.pose_ids, dtype=int).reshape(-1)
        if uv.ndim != 4 or uv.shape[0] != q.shape[0] or uv.shape[1] != 2 or uv.shape[3] != 2 or ids.shape[0] != q.shape[0]:
            raise InputError(f"stereo images: expected q (N, 3), uv (N, 2, M, 2), pose_ids (N,), got {q.shape}, {uv.shape}, {ids.shape}")
        if not (np.all(np.isfinite(q)) and np.all(np.isfinite(uv))):
            raise InputError("stereo images: q and uv must be finite")
        object.__setattr__(self, "q", q)
        object.__setattr__(self, "uv", uv)
        object.__setattr__(self, "pose_ids", ids)

    @property
    def n_poses(self) -> int:
        """Number of poses N."""
        return int(self.q.shape[0])

    @property
    def n_corners(self) -> int:
        """Corners per pose M."""
        return int(self.uv.shape[2])

    def subset(self, rows: np.typing.ArrayLike) -> "StereoImages":
        """The poses ``rows``.

        Parameters
        ----------
        rows : array_like of int or bool
            Rows to keep.

        Returns
        -------
        StereoImages
        """
        r = np.asarray(rows)
        return StereoImages(self.q[r], self.uv[r], self.pose_ids[r], self.source, self.comments)

    def to_csv(self, path: str | Path) -> Path:
        """Write the measurement file (format in the module docstring).

        Parameters
        ----------
        path : str or pathlib.Path
            File to write.

        Returns
        -------
        pathlib.Path

        Raises
        ------
        InputError
            The file cannot be written.
        """
        N, M = self.n_poses, self.n_corners
        rows = np.column_stack([
            np.repeat(self.pose_ids, M), np.tile(np.arange(1, M + 1), N), np.repeat(self.q, M, axis=0),
            self.uv[:, 0].reshape(-1, 2), self.uv[:, 1].reshape(-1, 2),
        ])
        comments = self.comments or ((" " + self.source,) if self.source else ())
        return write_table(path, CORNER_COLUMNS, rows, comments, integer_columns=(0, 1), what="stereo corner measurements")


def read_stereo_corners(path: str | Path, n_corners: int, cameras: Sequence[Camera] | None = None) -> StereoImages:
    """Read a stereo corner measurement file (format in the module docstring).

    Parameters
    ----------
    path : str or pathlib.Path
        The CSV file (at most :data:`MAX_CORNER_FILE_BYTES` bytes, :data:`MAX_CORNER_ROWS` rows).
    n_corners : int
        Corners of the declared pattern M.
    cameras : sequence of 2 Camera, optional
        When given, every pixel coordinate must lie inside its camera's image.

    Returns
    -------
    StereoImages
        Poses in the order of their first row, corners in pattern order.

    Raises
    ------
    InputError
        A malformed table (see :func:`gtmodel._tables.read_table`), a missing or unknown
        column, a pose or corner number that is not a positive integer (or a corner above
        M), a repeated corner of a pose, cart positions that differ between the rows of a
        pose, a pixel outside the image, a pose with missing corners (its first row and the
        missing corner numbers named), no pose at all. Each names the file, line and column.
    """
    t = read_table(path, "stereo corner measurements", max_rows=MAX_CORNER_ROWS, max_bytes=MAX_CORNER_FILE_BYTES)
    t.check_columns(CORNER_COLUMNS, CORNER_COLUMNS)
    if t.n_rows == 0:
        raise t.error("no data rows (expected one row per pose and corner)")
    pose, corner = t.column("pose"), t.column("corner")
    q = t.columns_of(("q1_m", "q2_m", "q3_m"))
    uv = np.stack([t.columns_of(("u1_px", "v1_px")), t.columns_of(("u2_px", "v2_px"))], axis=1)
    order: dict[int, int] = {}
    first: list[int] = []
    seen: dict[tuple[int, int], int] = {}
    for i in range(t.n_rows):
        if pose[i] != np.round(pose[i]) or pose[i] < 1:
            raise t.error(f"expected a positive integer pose number, got {pose[i]!r}", row=i, column="pose")
        if corner[i] != np.round(corner[i]) or not 1 <= corner[i] <= n_corners:
            raise t.error(f"expected a corner number 1..{n_corners} (the pattern's corners), got {corner[i]!r}", row=i, column="corner")
        p, c = int(pose[i]), int(corner[i])
        if p not in order:
            order[p] = len(order)
            first.append(i)
        elif not np.array_equal(q[i], q[first[order[p]]]):
            raise t.error(f"cart positions differ from those of pose {p} on line {int(t.lines[first[order[p]]])}", row=i, column="q1_m,q2_m,q3_m")
        if (p, c) in seen:
            raise t.error(f"corner {c} of pose {p} repeats line {int(t.lines[seen[(p, c)]])}", row=i, column="corner")
        seen[(p, c)] = i
        if cameras is not None:
            for j, cam in enumerate(cameras):
                if not cam.inside(uv[i, j]):
                    raise t.error(f"pixel ({uv[i, j, 0]:g}, {uv[i, j, 1]:g}) outside the {cam.width} x {cam.height} image of camera {j + 1}",
                                  row=i, column=f"u{j + 1}_px,v{j + 1}_px")
    N = len(order)
    out = np.empty((N, 2, n_corners, 2))
    ids = np.array(list(order), dtype=int)
    for k, p in enumerate(ids):
        missing = [c for c in range(1, n_corners + 1) if (int(p), c) not in seen]
        if missing:
            raise t.error(f"pose {p} lacks corner(s) {', '.join(map(str, missing))} of {n_corners} (a pose must have every corner in both images)",
                          row=first[k], column="corner")
        for c in range(1, n_corners + 1):
            out[k, :, c - 1] = uv[seen[(int(p), c)]]
    return StereoImages(q[first], out, ids, source=f"stereo corners from {path}", comments=t.comments)


@dataclass(frozen=True)
class PatternMount:
    """How the pattern sits on the end-effector plate.

    Parameters
    ----------
    R : array_like, shape (3, 3)
        Pattern axes in the plate frame (columns: pattern x, y, normal z).
    offset : array_like, shape (3,)
        Pattern origin (centre square's centre) in the plate frame, from the TCP [m].

    Raises
    ------
    InputError
        ``R`` not a rotation or a non-finite offset.
    """

    R: np.ndarray = field(default_factory=lambda: np.array([[1.0, 0, 0], [0, 0, 1], [0, -1, 0]]))
    offset: np.ndarray = field(default_factory=lambda: np.zeros(3))

    def __post_init__(self) -> None:
        object.__setattr__(self, "R", as_rotation(self.R, "pattern mount R", 1e-6))
        o = np.asarray(self.offset, dtype=float).reshape(-1)
        if o.shape != (3,) or not np.all(np.isfinite(o)):
            raise InputError(f"pattern offset: expected 3 finite values [m], got {np.asarray(self.offset).tolist()}")
        object.__setattr__(self, "offset", o)

    @classmethod
    def facing(cls, normal: np.typing.ArrayLike, x_axis: np.typing.ArrayLike, offset: np.typing.ArrayLike = (0.0, 0.0, 0.0)) -> "PatternMount":
        """A mount from the plate normal and the pattern's x direction (plate frame).

        Parameters
        ----------
        normal : array_like, shape (3,)
            Pattern normal (towards the cameras).
        x_axis : array_like, shape (3,)
            Pattern x direction (made orthogonal to ``normal``).
        offset : array_like, shape (3,), optional
            Pattern origin from the TCP [m].

        Returns
        -------
        PatternMount

        Raises
        ------
        InputError
            Zero or parallel directions.
        """
        n = np.asarray(normal, dtype=float)
        x = np.asarray(x_axis, dtype=float)
        if not (np.linalg.norm(n) > 0 and np.all(np.isfinite(n)) and np.all(np.isfinite(x))):
            raise InputError(f"pattern normal: expected a non-zero direction, got {n.tolist()}")
        n = n / np.linalg.norm(n)
        x = x - (x @ n) * n
        if np.linalg.norm(x) < 1e-9:
            raise InputError(f"pattern x_axis: must not be parallel to the normal, got {np.asarray(x_axis).tolist()}")
        x /= np.linalg.norm(x)
        return cls(np.column_stack([x, np.cross(n, x), n]), offset)

    @property
    def tcp_in_pattern(self) -> np.ndarray:
        """The TCP in the pattern frame [m], shape (3,)."""
        return -self.R.T @ self.offset

    def corners_world(self, pattern: Pattern, T: np.ndarray, R_T: np.ndarray) -> np.ndarray:
        """Pattern corners in the world frame at plate poses.

        Parameters
        ----------
        pattern : Pattern
            The pattern.
        T : numpy.ndarray, shape (N, 3)
            TCP positions [m].
        R_T : numpy.ndarray, shape (N, 3, 3)
            Plate orientations.

        Returns
        -------
        numpy.ndarray, shape (N, M, 3)
        """
        local = self.offset[None, :] + pattern.points @ self.R.T  # (M, 3) in the plate frame
        return T[:, None, :] + np.einsum("nij,mj->nmi", R_T, local)


@dataclass(frozen=True)
class SyntheticStereo:
    """Synthetic stereo images and the truth behind them.

    Parameters
    ----------
    images : StereoImages
        The detected poses (seen by both cameras), noisy corners.
    q : numpy.ndarray, shape (N, 3)
        Every commanded pose [m].
    T : numpy.ndarray, shape (N, 3)
        True TCP positions of every pose [m] (world frame).
    detected : numpy.ndarray of bool, shape (N, 2)
        Whether each camera detected the pattern.
    reason : numpy.ndarray of str, shape (N, 2)
        ``"ok"``, ``"outside image"``, ``"behind camera"`` or ``"oblique"``.
    rows : numpy.ndarray of int, shape (n,)
        Rows of ``q`` in ``images`` (seen by both).
    """

    images: StereoImages
    q: np.ndarray
    T: np.ndarray
    detected: np.ndarray
    reason: np.ndarray
    rows: np.ndarray


def synthetic_stereo_images(
    true_model: ClosureModel,
    q: np.typing.ArrayLike,
    cameras: Sequence[Camera],
    pattern: Pattern,
    mount: PatternMount | None = None,
    pixel_sigma: float = 0.0,
    seed: int | None = 0,
    max_obliquity_deg: float = MAX_OBLIQUITY_DEG,
    margin_px: float = 0.0,
    plate_poses: tuple[np.ndarray, np.ndarray] | None = None,
) -> SyntheticStereo:
    """Simulated corner detections of two cameras at given actuator values.

    Parameters
    ----------
    true_model : ClosureModel
        The true robot (its FK gives the plate poses).
    q : array_like, shape (N, 3)
        Actuator values [m].
    cameras : sequence of 2 Camera
        The true cameras (true pose, intrinsics and distortion).
    pattern : Pattern
        The pattern.
    mount : PatternMount, optional
        Pattern on the plate (default: facing +y, centred on the TCP).
    pixel_sigma : float, optional
        Standard deviation of the corner noise per pixel coordinate [px] (0: exact).
    seed : int or None, optional
        Seed of the noise.
    max_obliquity_deg : float, optional
        Largest detection angle [deg] (default :data:`MAX_OBLIQUITY_DEG`).
    margin_px : float, optional
        Image border where corners are not detected [px].
    plate_poses : tuple of numpy.ndarray, optional
        ``(T (N, 3), R (N, 3, 3))``: the true plate poses, when they are not
        ``true_model.fk(q)`` (e.g. with actuator errors,
        :func:`~gtmodel.calibration.synthetic.synthetic_measurements`).

    Returns
    -------
    SyntheticStereo

    Raises
    ------
    InputError
        Not two cameras, a negative or non-finite noise, a bad angle.
    """
    if len(cameras) != 2:
        raise InputError(f"cameras: expected 2 cameras, got {len(cameras)}")
    if not (np.isfinite(pixel_sigma) and pixel_sigma >= 0):
        raise InputError(f"pixel_sigma: expected a finite value >= 0 [px], got {pixel_sigma!r}")
    if not (0 < max_obliquity_deg <= 90):
        raise InputError(f"max_obliquity_deg: expected (0, 90], got {max_obliquity_deg!r}")
    mount = PatternMount() if mount is None else mount
    qa = np.atleast_2d(np.asarray(q, dtype=float))
    T, R = true_model.fk(qa) if plate_poses is None else (np.asarray(plate_poses[0], dtype=float), np.asarray(plate_poses[1], dtype=float))
    if T.shape != (qa.shape[0], 3) or R.shape != (qa.shape[0], 3, 3):
        raise InputError(f"plate_poses: expected T ({qa.shape[0]}, 3) and R ({qa.shape[0]}, 3, 3), got {T.shape} and {R.shape}")
    N, M = qa.shape[0], pattern.n_corners
    X = mount.corners_world(pattern, T, R)
    centre = T + R @ mount.offset
    normal = np.einsum("nij,j->ni", R, mount.R[:, 2])
    uv = np.empty((N, 2, M, 2))
    detected = np.zeros((N, 2), dtype=bool)
    reason = np.full((N, 2), "ok", dtype=object)
    cos_max = np.cos(np.radians(max_obliquity_deg))
    for j, cam in enumerate(cameras):
        p, depth = cam.project(X.reshape(-1, 3))
        uv[:, j] = p.reshape(N, M, 2)
        depth = depth.reshape(N, M)
        sight = cam.position[None, :] - centre
        cos = np.einsum("ni,ni->n", sight, normal) / np.linalg.norm(sight, axis=1)
        front = np.all(depth > 0, axis=1)
        inside = np.all(cam.inside(uv[:, j], margin_px), axis=1)
        straight = cos >= cos_max
        detected[:, j] = front & inside & straight
        reason[~straight, j] = "oblique"
        reason[~inside, j] = "outside image"
        reason[~front, j] = "behind camera"
    rng = np.random.default_rng(seed)
    noisy = uv + rng.standard_normal(uv.shape) * pixel_sigma
    rows = np.flatnonzero(detected.all(axis=1))
    src = f"synthetic stereo images: {true_model.name}, {N} poses, {rows.size} seen by both cameras, pixel noise {pixel_sigma:g} px, seed {seed}"
    images = StereoImages(qa[rows], noisy[rows], rows + 1, source=src, comments=(" " + src,))
    return SyntheticStereo(images, qa, T, detected, reason.astype(str), rows)


def actuator_grid_poses(model: ClosureModel, step: float) -> np.ndarray:
    """A regular grid in the cart positions, kept inside the workspace (Dressler (2012), ch. 5.5).

    Every pose ``q + step (1, 1, 1)`` of the grid is a known cart displacement of ``q``:
    the TCP moves by ``step`` along the (parallel) guideways, which gives the metric scale
    of the stereo reconstruction (:func:`~gtmodel.calibration.vision.reconstruction.scale_from_carts`).

    Parameters
    ----------
    model : ClosureModel
        The (nominal) 3-actuator model; its limits give cart travel and joint angles.
    step : float
        Grid spacing [m].

    Returns
    -------
    numpy.ndarray, shape (N, 3)
        Actuator values [m].

    Raises
    ------
    InputError
        Non-positive step, no limits, or no grid pose in the workspace.
    """
    if not (np.isfinite(step) and step > 0):
        raise InputError(f"step: expected a positive grid spacing [m], got {step!r}")
    lim = _model_limits(model, None)
    box = _q_box(model, lim, None)
    axes = [np.arange(lo, hi + step / 2, step) for lo, hi in box]
    q = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
    q = q[np.all(q <= box[:, 1] + 1e-12, axis=1)]
    ok = _fk_filter(model, q, lim, box.mean(axis=1))
    if not np.any(ok):
        raise InputError(f"{model.name}: no cart grid pose with step {step} m lies in the workspace")
    return q[ok]
