"""Pinhole cameras with Brown-Conrady lens distortion and the planar calibration pattern.

The projection of a point ``X_w`` (world frame, m) by a camera at centre ``c`` with
orientation ``R`` (rows: the camera axes in the world frame; x right, y down, z along the
optical axis) is OpenCV's model (Brown-Conrady, coefficients ``k1, k2, p1, p2, k3``)::

    X_c = R (X_w - c),             x = X_c[0] / X_c[2],   y = X_c[1] / X_c[2]
    r2 = x^2 + y^2,                radial = 1 + k1 r2 + k2 r2^2 + k3 r2^3
    x_d = x radial + 2 p1 x y + p2 (r2 + 2 x^2)
    y_d = y radial + p1 (r2 + 2 y^2) + 2 p2 x y
    u = fx x_d + cx,               v = fy y_d + cy          [pixels]

written once as a CasADi expression (:func:`projection_expression`); the numeric
projection (:meth:`Camera.project`), the synthetic images and the bundle adjustment
(:mod:`gtmodel.calibration.vision.reconstruction`) all evaluate that one graph.

The calibration pattern (:class:`Pattern`) is planar: by default five black squares in a
quincunx (the centre and the four diagonal neighbours of a 3x3 board), 20 corners, as the
pattern of Dressler (2012), ch. 5.5 (Figure 5.14; its dimensions are not given there, so
those of :meth:`Pattern.five_squares` are ASSUMED). The pattern frame has its origin at
the centre square's centre, z along the plate normal towards the cameras.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property

import casadi as ca
import numpy as np
import numpy.typing  # noqa: F401  (np.typing in annotations)

from gtmodel._arrays import as_rotation
from gtmodel.errors import InputError

__all__ = ["Camera", "Pattern", "projection_expression", "look_at", "N_INTRINSICS", "undistort"]

#: Number of camera constants of the projection: fx, fy, cx, cy, k1, k2, p1, p2, k3.
N_INTRINSICS = 9


def projection_expression(X_c: ca.SX | ca.MX, k: ca.SX | ca.MX) -> ca.SX | ca.MX:
    """Pixel coordinates of a point given in the camera frame (OpenCV's Brown-Conrady model).

    Parameters
    ----------
    X_c : casadi.SX or casadi.MX, shape (3, 1)
        Point in the camera frame [m] (z along the optical axis, in front: z > 0).
    k : casadi.SX or casadi.MX, shape (9, 1)
        ``fx, fy, cx, cy`` [px] and ``k1, k2, p1, p2, k3`` [-].

    Returns
    -------
    casadi.SX or casadi.MX, shape (2, 1)
        ``(u, v)`` [px]. Brown (1966); Bradski and Kaehler, *Learning OpenCV*, ch. 11.
    """
    x, y = X_c[0] / X_c[2], X_c[1] / X_c[2]
    fx, fy, cx, cy, k1, k2, p1, p2, k3 = (k[i] for i in range(N_INTRINSICS))
    r2 = x * x + y * y
    radial = 1 + k1 * r2 + k2 * r2 * r2 + k3 * r2 * r2 * r2
    xd = x * radial + 2 * p1 * x * y + p2 * (r2 + 2 * x * x)
    yd = y * radial + p1 * (r2 + 2 * y * y) + 2 * p2 * x * y
    return ca.vertcat(fx * xd + cx, fy * yd + cy)


def _projection_function() -> ca.Function:
    X, R, c, k = ca.SX.sym("X", 3), ca.SX.sym("R", 3, 3), ca.SX.sym("c", 3), ca.SX.sym("k", N_INTRINSICS)
    Xc = ca.mtimes(R, X - c)
    return ca.Function("project", [X, R, c, k], [projection_expression(Xc, k), Xc[2]], ["X", "R", "c", "k"], ["uv", "depth"])


_PROJECT = _projection_function()


def look_at(position: np.typing.ArrayLike, target: np.typing.ArrayLike, up: np.typing.ArrayLike = (0.0, 0.0, 1.0)) -> np.ndarray:
    """Orientation of a camera at ``position`` whose optical axis passes through ``target``.

    Parameters
    ----------
    position : array_like, shape (3,)
        Camera centre [m].
    target : array_like, shape (3,)
        A point on the optical axis [m].
    up : array_like, shape (3,), optional
        World direction that appears upwards in the image (default +z).

    Returns
    -------
    numpy.ndarray, shape (3, 3)
        ``R`` (rows: camera x right, y down, z forward in the world frame).

    Raises
    ------
    InputError
        ``target`` equals ``position`` or the axis is parallel to ``up``.
    """
    z = np.asarray(target, dtype=float) - np.asarray(position, dtype=float)
    u = np.asarray(up, dtype=float)
    if not np.all(np.isfinite(z)) or np.linalg.norm(z) < 1e-9:
        raise InputError(f"look_at: target {np.asarray(target).tolist()} must differ from position {np.asarray(position).tolist()}")
    z = z / np.linalg.norm(z)
    x = np.cross(z, u)
    if np.linalg.norm(x) < 1e-9:
        raise InputError("look_at: the optical axis is parallel to the up direction; give another up")
    x /= np.linalg.norm(x)
    return np.vstack([x, np.cross(z, x), z])


@dataclass(frozen=True)
class Camera:
    """A calibrated pinhole camera with lens distortion and its pose.

    Parameters
    ----------
    name : str
        Label (``"camera 1"``).
    width, height : int
        Image size [px].
    fx, fy : float
        Focal lengths [px].
    cx, cy : float
        Principal point [px].
    distortion : array_like, shape (5,)
        ``k1, k2, p1, p2, k3`` (OpenCV order).
    R : array_like, shape (3, 3)
        Orientation (rows: camera axes in the world frame).
    position : array_like, shape (3,)
        Camera centre in the world frame [m].

    Raises
    ------
    InputError
        Non-positive image size or focal length, a principal point outside the image,
        non-finite distortion, ``R`` not a rotation.
    """

    name: str
    width: int
    height: int
    fx: float
    fy: float
    cx: float
    cy: float
    distortion: np.ndarray = field(default_factory=lambda: np.zeros(5))
    R: np.ndarray = field(default_factory=lambda: np.eye(3))
    position: np.ndarray = field(default_factory=lambda: np.zeros(3))

    def __post_init__(self) -> None:
        if not (int(self.width) > 0 and int(self.height) > 0):
            raise InputError(f"{self.name}: image size must be positive, got {self.width} x {self.height}")
        for key in ("fx", "fy"):
            if not (np.isfinite(getattr(self, key)) and getattr(self, key) > 0):
                raise InputError(f"{self.name}: {key} must be a positive focal length [px], got {getattr(self, key)!r}")
        if not (0 <= self.cx <= self.width and 0 <= self.cy <= self.height):
            raise InputError(f"{self.name}: principal point ({self.cx}, {self.cy}) outside the {self.width} x {self.height} image")
        d = np.asarray(self.distortion, dtype=float).reshape(-1)
        if d.shape != (5,) or not np.all(np.isfinite(d)):
            raise InputError(f"{self.name}: distortion must be 5 finite values k1, k2, p1, p2, k3, got {np.asarray(self.distortion).tolist()}")
        pos = np.asarray(self.position, dtype=float).reshape(-1)
        if pos.shape != (3,) or not np.all(np.isfinite(pos)):
            raise InputError(f"{self.name}: position must be 3 finite values [m]")
        object.__setattr__(self, "distortion", d)
        object.__setattr__(self, "position", pos)
        object.__setattr__(self, "R", as_rotation(self.R, f"{self.name}: R", 1e-6))

    @property
    def constants(self) -> np.ndarray:
        """The 9 constants of :func:`projection_expression`: fx, fy, cx, cy, k1, k2, p1, p2, k3."""
        return np.concatenate([[self.fx, self.fy, self.cx, self.cy], self.distortion])

    def with_pose(self, R: np.typing.ArrayLike, position: np.typing.ArrayLike) -> "Camera":
        """The same camera at another pose.

        Parameters
        ----------
        R : array_like, shape (3, 3)
            Orientation.
        position : array_like, shape (3,)
            Centre [m].

        Returns
        -------
        Camera
        """
        return Camera(self.name, self.width, self.height, self.fx, self.fy, self.cx, self.cy, self.distortion, np.asarray(R), np.asarray(position))

    def with_distortion(self, distortion: np.typing.ArrayLike) -> "Camera":
        """The same camera with other distortion coefficients.

        Parameters
        ----------
        distortion : array_like, shape (5,)
            ``k1, k2, p1, p2, k3``.

        Returns
        -------
        Camera
        """
        return Camera(self.name, self.width, self.height, self.fx, self.fy, self.cx, self.cy, np.asarray(distortion), self.R, self.position)

    def project(self, X: np.typing.ArrayLike) -> tuple[np.ndarray, np.ndarray]:
        """Pixel coordinates and depths of world points (the graph of :func:`projection_expression`).

        Parameters
        ----------
        X : array_like, shape (M, 3)
            Points in the world frame [m].

        Returns
        -------
        uv : numpy.ndarray, shape (M, 2)
            Pixel coordinates [px].
        depth : numpy.ndarray, shape (M,)
            Distance along the optical axis [m] (negative: behind the camera).
        """
        Xa = np.atleast_2d(np.asarray(X, dtype=float))
        f = _PROJECT.map(Xa.shape[0])
        uv, depth = f(Xa.T, self.R, self.position, self.constants)
        return np.array(uv).T, np.array(depth).reshape(-1)

    def inside(self, uv: np.typing.ArrayLike, margin: float = 0.0) -> np.ndarray:
        """Whether pixel coordinates lie inside the image.

        Parameters
        ----------
        uv : array_like, shape (..., 2)
            Pixel coordinates [px].
        margin : float, optional
            Border kept free [px].

        Returns
        -------
        numpy.ndarray of bool, shape (...)
        """
        a = np.asarray(uv, dtype=float)
        return (a[..., 0] >= margin) & (a[..., 0] <= self.width - margin) & (a[..., 1] >= margin) & (a[..., 1] <= self.height - margin)


def undistort(camera: Camera, uv: np.typing.ArrayLike, iterations: int = 30) -> np.ndarray:
    """Normalised, undistorted image coordinates of pixels (fixed-point inversion, as OpenCV).

    Used only for start values (the homography of :mod:`~gtmodel.calibration.vision.reconstruction`).

    Parameters
    ----------
    camera : Camera
        Its intrinsics and distortion.
    uv : array_like, shape (M, 2)
        Pixel coordinates [px].
    iterations : int, optional
        Fixed-point iterations.

    Returns
    -------
    numpy.ndarray, shape (M, 2)
        ``(x, y) = (X_c[0] / X_c[2], X_c[1] / X_c[2])``.
    """
    a = np.atleast_2d(np.asarray(uv, dtype=float))
    xd = (a[:, 0] - camera.cx) / camera.fx
    yd = (a[:, 1] - camera.cy) / camera.fy
    k1, k2, p1, p2, k3 = camera.distortion
    x, y = xd.copy(), yd.copy()
    for _ in range(iterations):
        r2 = x * x + y * y
        radial = 1 + k1 * r2 + k2 * r2 * r2 + k3 * r2 ** 3
        x = (xd - (2 * p1 * x * y + p2 * (r2 + 2 * x * x))) / radial
        y = (yd - (p1 * (r2 + 2 * y * y) + 2 * p2 * x * y)) / radial
    return np.column_stack([x, y])


@dataclass(frozen=True)
class Pattern:
    """A planar calibration pattern: its corners in the pattern frame.

    Parameters
    ----------
    corners : array_like, shape (M, 2)
        Corner coordinates in the pattern plane [m] (z = 0), M >= 4, not collinear.
    name : str, optional
        Label.

    Raises
    ------
    InputError
        Fewer than 4 corners, repeated or collinear corners, non-finite values.
    """

    corners: np.ndarray
    name: str = "pattern"

    def __post_init__(self) -> None:
        c = np.asarray(self.corners, dtype=float)
        if c.ndim != 2 or c.shape[1] != 2 or c.shape[0] < 4 or not np.all(np.isfinite(c)):
            raise InputError(f"{self.name}: expected at least 4 finite corners of shape (M, 2), got shape {c.shape}")
        if np.linalg.matrix_rank(c - c.mean(axis=0), tol=1e-9) < 2:
            raise InputError(f"{self.name}: the corners are collinear")
        d = np.linalg.norm(c[:, None] - c[None], axis=-1) + np.eye(c.shape[0])
        if d.min() < 1e-9:
            raise InputError(f"{self.name}: two corners coincide")
        object.__setattr__(self, "corners", c)

    @classmethod
    def five_squares(cls, side: float = 0.06, pitch: float = 0.1) -> "Pattern":
        """Five squares in a quincunx, 20 corners (Dressler (2012), ch. 5.5, Figure 5.14; sizes ASSUMED).

        Parameters
        ----------
        side : float, optional
            Side of each square [m].
        pitch : float, optional
            Distance between the centre square's centre and the others' along x and y [m]
            (greater than ``side``, so the squares are apart and the 20 corners distinct).

        Returns
        -------
        Pattern
            Corners ordered square by square (centre, then (+,+), (-,+), (-,-), (+,-)),
            each counter-clockwise from its (-,-) corner.

        Raises
        ------
        InputError
            ``side`` not positive or ``pitch`` not above ``side``.
        """
        if not (np.isfinite(side) and side > 0 and np.isfinite(pitch) and pitch > side):
            raise InputError(f"pattern: expected side > 0 and pitch > side [m], got side={side!r}, pitch={pitch!r}")
        h = side / 2
        square = np.array([[-h, -h], [h, -h], [h, h], [-h, h]])
        centres = np.array([[0, 0], [pitch, pitch], [-pitch, pitch], [-pitch, -pitch], [pitch, -pitch]], dtype=float)
        return cls(np.concatenate([c + square for c in centres]), name="five squares")

    @property
    def n_corners(self) -> int:
        """Number of corners M."""
        return int(self.corners.shape[0])

    @cached_property
    def points(self) -> np.ndarray:
        """Corners as 3-D points of the pattern frame, shape (M, 3) [m]."""
        return np.column_stack([self.corners, np.zeros(self.n_corners)])
