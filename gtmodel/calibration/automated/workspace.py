"""The calibration workspace of an automated calibration, Dressler (2012), ch. 5.6 (Figs. 5.22-5.24).

From the *a priori* parameters: the kinematic workspace by a grid search in the box that
contains it (every arm reaches, carts within their travel, every link within the
spherical-joint limit of its guideway), narrowed by a safety margin at its limit (a point
is kept when the points at the margin's distance along the 26 grid directions are in the
workspace too), by obstacle boxes grown by their safety zones, and intersected with what
the measuring device sees: a fixed pinhole camera of known pose (the whole calibration
pattern on the plate projects inside the image, in front of the camera) or a laser tracker
(the TCP within its range). The measurement poses are a regular grid over what remains,
its constant ``h = (V / n)^(1/3)`` from the estimated volume ``V`` and the desired
number ``n`` (thesis: 100 desired, 0.1367 m, 112 obtained).

The camera test here is a simple pinhole frustum of this module (no lens distortion); the
stereo camera model of the vision calibration is a separate piece.
"""

from __future__ import annotations

from dataclasses import dataclass
from itertools import product

import numpy as np

from gtmodel.calibration.vision.camera import Camera
from gtmodel.errors import InputError
from gtmodel.robots.kinematics import GantryTau3Kinematics
from gtmodel.robots.workspace import in_ranges

__all__ = ["Obstacle", "PinholeCamera", "Tracker", "CalibrationWorkspace", "grid_constant", "home_joint_axes"]

#: The 26 unit grid directions of the safety-margin test.
_DIRECTIONS = np.array([d for d in product((-1.0, 0.0, 1.0), repeat=3) if any(d)])
_DIRECTIONS = _DIRECTIONS / np.linalg.norm(_DIRECTIONS, axis=1, keepdims=True)
#: Most grid points of the workspace search.
MAX_GRID_POINTS = 2_000_000


@dataclass(frozen=True)
class Obstacle:
    """An axis-aligned obstacle box with its safety zone.

    Parameters
    ----------
    lo, hi : numpy.ndarray, shape (3,)
        Opposite corners [m], ``lo < hi``.
    safety : float
        Distance kept from the box [m].
    name : str
        For messages.
    """

    lo: np.ndarray
    hi: np.ndarray
    safety: float = 0.0
    name: str = ""

    def contains(self, P: np.ndarray) -> np.ndarray:
        """Whether points lie in the box grown by the safety zone.

        Parameters
        ----------
        P : numpy.ndarray, shape (N, 3)
            Points [m].

        Returns
        -------
        numpy.ndarray of bool, shape (N,)
        """
        return np.all((P >= self.lo - self.safety) & (P <= self.hi + self.safety), axis=1)


@dataclass(frozen=True)
class PinholeCamera:
    """A fixed pinhole camera of known pose that must see the whole calibration pattern.

    Parameters
    ----------
    position : numpy.ndarray, shape (3,)
        Optical centre in the base frame [m].
    rotation : numpy.ndarray, shape (3, 3)
        Columns: the camera axes (x right, y down, z optical axis) in the base frame.
    focal : float
        Focal length [px].
    image : tuple of int
        ``(width, height)`` [px]; the principal point is the image centre.
    pattern_corners : numpy.ndarray, shape (K, 3)
        Pattern points relative to the TCP in the base frame [m] (the plate keeps its
        orientation).
    """

    position: np.ndarray
    rotation: np.ndarray
    focal: float
    image: tuple[int, int]
    pattern_corners: np.ndarray

    def camera(self) -> Camera:
        """This camera as the one camera model of gtmodel (:class:`gtmodel.calibration.vision.Camera`, no distortion).

        Returns
        -------
        Camera
            Principal point at the image centre; ``R`` the transpose of :attr:`rotation`.
        """
        w, h = self.image
        return Camera("camera", int(w), int(h), float(self.focal), float(self.focal), w / 2, h / 2, np.zeros(5),
                      np.asarray(self.rotation, dtype=float).T, np.asarray(self.position, dtype=float))

    def sees(self, P: np.ndarray) -> np.ndarray:
        """Whether every pattern point projects inside the image, in front of the camera (pinhole model).

        Parameters
        ----------
        P : numpy.ndarray, shape (N, 3)
            TCP positions [m].

        Returns
        -------
        numpy.ndarray of bool, shape (N,)
        """
        camera = self.camera()
        P = np.asarray(P, dtype=float)
        ok = np.ones(P.shape[0], dtype=bool)
        for c in self.pattern_corners:
            uv, depth = camera.project(P + c)
            ok &= (depth > 0) & camera.inside(uv)
        return ok


@dataclass(frozen=True)
class Tracker:
    """A laser tracker: the TCP within ``[min_range, max_range]`` of its position.

    Parameters
    ----------
    position : numpy.ndarray, shape (3,)
        [m].
    min_range, max_range : float
        [m].
    """

    position: np.ndarray
    min_range: float
    max_range: float

    def sees(self, P: np.ndarray) -> np.ndarray:
        """Whether the TCP positions lie in the tracker's range.

        Parameters
        ----------
        P : numpy.ndarray, shape (N, 3)
            TCP positions [m].

        Returns
        -------
        numpy.ndarray of bool, shape (N,)
        """
        d = np.linalg.norm(P - self.position, axis=1)
        return (d >= self.min_range) & (d <= self.max_range)


def home_joint_axes(kinematics: GantryTau3Kinematics, q_home: np.ndarray | None = None) -> np.ndarray:
    """The link directions at the home pose (carts at ``q_home``, default 0): the joints' neutral axes.

    Parameters
    ----------
    kinematics : GantryTau3Kinematics
        The *a priori* model.
    q_home : numpy.ndarray, shape (3,), optional
        Home cart positions [m].

    Returns
    -------
    numpy.ndarray, shape (3, 3)
        Row i: unit direction from joint point i to the TCP.

    Raises
    ------
    UnreachablePoseError
        No pose at the home cart positions.
    """
    q = np.zeros(3) if q_home is None else np.asarray(q_home, dtype=float)
    T = kinematics.fk(q)
    d = T[None] - (kinematics.As + q[:, None] * kinematics.v)
    return d / np.linalg.norm(d, axis=1, keepdims=True)


def grid_constant(volume: float, n: int) -> float:
    """The grid constant that puts about ``n`` points in a volume: ``(V / n)^(1/3)`` [m].

    Parameters
    ----------
    volume : float
        [m^3], positive.
    n : int
        Desired number of points, positive.

    Returns
    -------
    float

    Raises
    ------
    InputError
        A non-positive volume or count.
    """
    if not (volume > 0 and n > 0):
        raise InputError(f"grid_constant: expected a positive volume and count, got {volume!r}, {n!r}")
    return float((volume / n) ** (1.0 / 3.0))


@dataclass(frozen=True)
class CalibrationWorkspace:
    """The tests a calibration pose must pass, from the *a priori* parameters.

    Parameters
    ----------
    kinematics : GantryTau3Kinematics
        The *a priori* 3-link model.
    cart_travel : numpy.ndarray, shape (3, 2)
        ``(q_min, q_max)`` per cart [m].
    joint_angle_max : float
        Largest link-guideway angle [rad].
    margin : float
        Safety distance from the limit of the kinematic workspace [m].
    obstacles : tuple of Obstacle
        Obstacle boxes with their safety zones.
    device : PinholeCamera or Tracker or None
        What measures (None: everything is measurable).
    joint_axes : numpy.ndarray, shape (3, 3), optional
        Row i: the neutral axis of arm i's spherical joint (unit); the joint angle is the
        link's angle to it. None: the angle to the guideway.
    """

    kinematics: GantryTau3Kinematics
    cart_travel: np.ndarray
    joint_angle_max: float
    margin: float = 0.0
    obstacles: tuple[Obstacle, ...] = ()
    device: PinholeCamera | Tracker | None = None
    joint_axes: np.ndarray | None = None

    def joint_angles(self, P: np.ndarray) -> np.ndarray:
        """Joint angles at reachable TCP positions (see ``joint_axes``).

        Parameters
        ----------
        P : numpy.ndarray, shape (N, 3)
            TCP positions [m], every one reachable.

        Returns
        -------
        numpy.ndarray, shape (N, 3)
            Angle of each link to its joint's neutral axis [rad].
        """
        kin = self.kinematics
        if self.joint_axes is None:
            return kin.link_angles(P)
        q = kin.ik(P)
        d = P[:, None, :] - (kin.As[None] + q[:, :, None] * kin.v[None])
        d /= np.linalg.norm(d, axis=2, keepdims=True)
        return np.arccos(np.clip(np.einsum("nix,ix->ni", d, self.joint_axes), -1.0, 1.0))

    def kinematic(self, P: np.ndarray) -> np.ndarray:
        """Reach, cart travel and joint-angle limit at TCP positions (the kinematic workspace).

        Parameters
        ----------
        P : numpy.ndarray, shape (N, 3)
            TCP positions [m].

        Returns
        -------
        numpy.ndarray of bool, shape (N,)
        """
        kin = self.kinematics
        ok = kin.in_workspace(P, limits=False)
        if ok.any():
            R = P[ok]
            ok[ok] = in_ranges(kin.ik(R), self.cart_travel) & (self.joint_angles(R).max(axis=1) <= self.joint_angle_max)
        return ok

    def admissible(self, P: np.ndarray) -> tuple[np.ndarray, dict[str, int]]:
        """Every test at TCP positions, and how many points each step removed.

        Parameters
        ----------
        P : numpy.ndarray, shape (N, 3)
            TCP positions [m].

        Returns
        -------
        ok : numpy.ndarray of bool, shape (N,)
        removed : dict of str to int
            Points removed by ``"kinematic"``, ``"margin"``, ``"obstacles"``, ``"device"``.
        """
        ok = self.kinematic(P)
        removed = {"kinematic": int((~ok).sum())}
        if self.margin > 0:
            before = int(ok.sum())
            for d in _DIRECTIONS:
                if ok.any():
                    ok[ok] = self.kinematic(P[ok] + self.margin * d)
            removed["margin"] = before - int(ok.sum())
        before = int(ok.sum())
        for obstacle in self.obstacles:
            ok &= ~obstacle.contains(P)
        removed["obstacles"] = before - int(ok.sum())
        before = int(ok.sum())
        if self.device is not None and ok.any():
            ok[ok] = self.device.sees(P[ok])
        removed["device"] = before - int(ok.sum())
        return ok, removed

    def search_box(self) -> np.ndarray:
        """The box that contains the workspace: per arm, its guideway segment grown by its link, intersected.

        Returns
        -------
        numpy.ndarray, shape (3, 2)
            ``(min, max)`` per coordinate [m].
        """
        kin = self.kinematics
        lo = np.full(3, -np.inf)
        hi = np.full(3, np.inf)
        for i in range(3):
            ends = np.array([kin.As[i] + self.cart_travel[i, k] * kin.v[i] for k in range(2)])
            lo = np.maximum(lo, ends.min(axis=0) - kin.L[i])
            hi = np.minimum(hi, ends.max(axis=0) + kin.L[i])
        return np.column_stack([lo, hi])

    def grid(self, step: float, box: np.ndarray | None = None) -> np.ndarray:
        """A regular grid in the search box (or ``box``) [m], shape (N, 3).

        Parameters
        ----------
        step : float
            Spacing [m].
        box : numpy.ndarray, shape (3, 2), optional
            The box gridded, centred (default :meth:`search_box`).

        Returns
        -------
        numpy.ndarray

        Raises
        ------
        InputError
            A step that is not positive or gives more than :data:`MAX_GRID_POINTS` points.
        """
        box = self.search_box() if box is None else box
        if not step > 0:
            raise InputError(f"step: expected a positive grid step in m, got {step!r}")
        counts = np.floor((box[:, 1] - box[:, 0]) / step).astype(int) + 1
        if np.prod(counts.astype(float)) > MAX_GRID_POINTS:
            raise InputError(f"step: expected a grid step giving at most {MAX_GRID_POINTS} points, got {np.prod(counts.astype(float)):.3g}")
        mid = box.mean(axis=1)
        axes = [mid[k] + (np.arange(counts[k]) - (counts[k] - 1) / 2) * step for k in range(3)]
        return np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
