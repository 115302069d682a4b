"""Geometric TCP paths ``T(s)`` for path-constrained motion (Dressler (2012), ch. 3.5).

A path maps the path coordinate ``s`` in ``[0, 1]`` to the TCP position ``T(s)`` [m]; the
motion along it is then a scalar problem in ``s(t)`` (Verscheure et al. (2009); TOPP-RA).
Every path gives ``T``, ``dT/ds`` and ``d2T/ds2`` for arrays of ``s`` (shape ``(N,)`` in,
``(N, 3)`` out) and as CasADi expressions of a symbolic ``s`` (for the collocation method
of :mod:`gtmodel.trajectory.path_constrained`).

Parametrisation
---------------
``s`` is dimensionless and runs from 0 (start) to 1 (end), for every path:

:class:`StraightLine`
    ``T(s) = start + s (end - start)``: ``s`` is the arc length divided by the length.
:class:`Polyline`
    Straight segments through the points, ``s`` proportional to arc length (the break
    ``s_j`` of point ``j`` is its cumulative length over the total). The tangent jumps at
    an interior point that is not collinear with its neighbours: a finite TCP
    acceleration can only turn there at rest, so such points are :attr:`Path.corners`
    and the path-constrained solvers put a grid point on each and force ``s_dot = 0``
    there (the segments are traversed as separate rest-to-rest motions). ``dT/ds`` is
    right-continuous: at a corner it is the tangent of the outgoing segment.
    No blending: a blended polyline is a :class:`SplinePath` through enough points,
    or a future path type.
:class:`SplinePath`
    A C2 cubic spline through the points (:class:`scipy.interpolate.CubicSpline`) in the
    normalised cumulative chord length; ``s`` is close to, but not exactly, the
    normalised arc length, so ``|dT/ds|`` varies slightly along the path.

Workspace: :meth:`Path.check_workspace` (also run by the constructors when a ``robot`` is
given) samples the path and raises :class:`~gtmodel.errors.UnreachablePoseError` naming the
first ``s`` outside the workspace of :meth:`GantryTau3Kinematics.in_workspace`.
"""

from __future__ import annotations

import logging
from typing import Any, Sequence

import casadi as ca
import numpy as np
import numpy.typing  # noqa: F401  (np.typing in annotations)

from gtmodel._lazy import lazy_module
from gtmodel.errors import InputError, UnreachablePoseError
from gtmodel.robots.dynamics import GantryTau3Dynamics
from gtmodel.robots.kinematics import GantryTau3Kinematics

#: Imported on first use (PEP 562 lazy module): the solve path of a problem file need not pay for it.
interpolate = lazy_module("scipy.interpolate")

__all__ = [
    "Path",
    "StraightLine",
    "Polyline",
    "SplinePath",
    "as_kinematics",
    "WORKSPACE_SAMPLES",
    "CORNER_ANGLE_TOLERANCE",
]

_log = logging.getLogger("gtmodel")

#: Number of uniformly spaced samples of ``s`` checked by :meth:`Path.check_workspace`
#: (the corners and both ends are always added).
WORKSPACE_SAMPLES = 201
#: Smallest turning angle [rad] at an interior polyline point that counts as a corner
#: (below it the neighbouring segments are taken as collinear).
CORNER_ANGLE_TOLERANCE = 1e-9
#: Tolerance on ``s`` outside ``[0, 1]`` accepted by :meth:`Path.evaluate` (rounding).
_S_TOLERANCE = 1e-12


def as_kinematics(robot: Any) -> GantryTau3Kinematics:
    """The kinematics of a robot given in any of the accepted forms.

    Parameters
    ----------
    robot : GantryTau3Kinematics or GantryTau3Dynamics or RobotParameters or str
        A kinematics or dynamics object, a parameter set, or its name/path.

    Returns
    -------
    GantryTau3Kinematics
        The kinematics (a new object unless one was given).

    Raises
    ------
    ParameterError
        Unknown parameter set name or invalid file.
    """
    if isinstance(robot, GantryTau3Kinematics):
        return robot
    if isinstance(robot, GantryTau3Dynamics):
        return robot.kinematics
    return GantryTau3Kinematics(robot)


def _point(x: Any, name: str) -> np.ndarray:
    try:
        arr = np.asarray(x, dtype=float)
    except (TypeError, ValueError):
        raise InputError(f"{name}: expected three finite numbers in m, got {x!r}") from None
    if arr.shape != (3,) or not np.all(np.isfinite(arr)):
        raise InputError(f"{name}: expected three finite numbers in m, got {x!r}")
    return arr


def _points(points: Any, name: str, minimum: int = 2) -> np.ndarray:
    try:
        arr = np.asarray(points, dtype=float)
    except (TypeError, ValueError):
        raise InputError(f"{name}: expected an array of shape (K, 3), got {points!r}") from None
    if arr.ndim != 2 or arr.shape[1] != 3 or arr.shape[0] < minimum:
        raise InputError(f"{name}: expected shape (K, 3) with K >= {minimum}, got {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise InputError(f"{name}: points must be finite")
    seg = np.linalg.norm(np.diff(arr, axis=0), axis=1)
    if np.any(seg < 1e-12):
        k = int(np.argmin(seg))
        raise InputError(f"{name}: points {k} and {k + 1} coincide; a path needs distinct consecutive points")
    return arr


class Path:
    """A geometric TCP path ``T(s)``, ``s`` in ``[0, 1]``, as a piecewise polynomial.

    Subclasses set the breaks ``x`` (K + 1,) and the coefficients ``c`` (d + 1, K, 3) of
    the local polynomials ``T(s) = sum_m c[m, k] (s - x_k)^(d - m)`` on ``[x_k, x_{k+1})``
    (SciPy's ``PPoly`` layout).

    Parameters
    ----------
    breaks : array_like, shape (K + 1,)
        Increasing breaks, ``breaks[0] = 0`` and ``breaks[-1] = 1``.
    coefficients : array_like, shape (d + 1, K, 3)
        Polynomial coefficients per piece and axis [m].
    corners : array_like, shape (C,), optional
        Interior breaks where the tangent is discontinuous (rest required there).
    robot : GantryTau3Kinematics or GantryTau3Dynamics or RobotParameters or str, optional
        If given, the path is checked to lie in the robot's workspace.
    configuration : int or sequence of int, optional
        IK configuration for the workspace check (default 0).

    Raises
    ------
    InputError
        Malformed breaks or coefficients.
    UnreachablePoseError
        A robot is given and the path leaves its workspace (names the first ``s``).
    """

    def __init__(
        self,
        breaks: np.typing.ArrayLike,
        coefficients: np.typing.ArrayLike,
        corners: np.typing.ArrayLike = (),
        robot: Any = None,
        configuration: int | Sequence[int] = 0,
    ) -> None:
        x = np.asarray(breaks, dtype=float).reshape(-1)
        c = np.asarray(coefficients, dtype=float)
        if x.size < 2 or abs(x[0]) > 0 or abs(x[-1] - 1.0) > 0 or np.any(np.diff(x) <= 0):
            raise InputError(f"breaks: expected increasing values from 0 to 1, got {x.tolist()}")
        if c.ndim != 3 or c.shape[1] != x.size - 1 or c.shape[2] != 3 or not np.all(np.isfinite(c)):
            raise InputError(f"coefficients: expected finite shape (d + 1, {x.size - 1}, 3), got {c.shape}")
        self.breaks = x
        self.coefficients = c
        self.degree = c.shape[0] - 1
        self.corners = np.asarray(corners, dtype=float).reshape(-1)
        # derivative coefficients, same layout
        d = self.degree
        powers = np.arange(d, -1, -1, dtype=float)  # exponent of each row
        c1 = (c * powers[:, None, None])[:-1] if d >= 1 else np.zeros((1,) + c.shape[1:])
        p1 = powers[:-1] - 1 if d >= 1 else np.zeros(1)
        c2 = (c1 * p1[:, None, None])[:-1] if d >= 2 else np.zeros((1,) + c.shape[1:])
        self._c1 = c1
        self._c2 = c2
        if robot is not None:
            self.check_workspace(robot, configuration)

    # ------------------------------------------------------------------ properties
    @property
    def start(self) -> np.ndarray:
        """TCP position at ``s = 0`` [m], shape (3,)."""
        return self.evaluate(np.array([0.0]))[0][0]

    @property
    def end(self) -> np.ndarray:
        """TCP position at ``s = 1`` [m], shape (3,)."""
        return self.evaluate(np.array([1.0]))[0][0]

    @property
    def length(self) -> float:
        """Arc length [m] (Gauss-Legendre quadrature, 8 points per piece)."""
        nodes, weights = np.polynomial.legendre.leggauss(8)
        total = 0.0
        for k in range(self.breaks.size - 1):
            a, b = self.breaks[k], self.breaks[k + 1]
            s = (a + b) / 2 + (b - a) / 2 * nodes
            _, dT, _ = self.evaluate(s)
            total += (b - a) / 2 * float(np.sum(weights * np.linalg.norm(dT, axis=1)))
        return total

    # ------------------------------------------------------------------ evaluation
    def _check_s(self, s: Any) -> np.ndarray:
        try:
            arr = np.asarray(s, dtype=float).reshape(-1)
        except (TypeError, ValueError):
            raise InputError(f"s: expected numbers in [0, 1], got {s!r}") from None
        if not np.all(np.isfinite(arr)) or np.any(arr < -_S_TOLERANCE) or np.any(arr > 1 + _S_TOLERANCE):
            raise InputError("s: expected finite values in [0, 1]")
        return np.clip(arr, 0.0, 1.0)

    def evaluate(self, s: np.typing.ArrayLike) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Position and its first two derivatives along the path.

        Parameters
        ----------
        s : array_like, shape (N,)
            Path coordinates in ``[0, 1]``.

        Returns
        -------
        T : numpy.ndarray, shape (N, 3)
            TCP position [m].
        dT : numpy.ndarray, shape (N, 3)
            ``dT/ds`` [m] (right-continuous at breaks).
        ddT : numpy.ndarray, shape (N, 3)
            ``d2T/ds2`` [m].

        Raises
        ------
        InputError
            ``s`` outside ``[0, 1]`` or not finite.
        """
        s = self._check_s(s)
        k = np.clip(np.searchsorted(self.breaks, s, side="right") - 1, 0, self.breaks.size - 2)
        h = (s - self.breaks[k])[:, None]
        out = []
        for c in (self.coefficients, self._c1, self._c2):
            v = np.zeros((s.size, 3))
            for m in range(c.shape[0]):
                v = v * h + c[m, k]
            out.append(v)
        return out[0], out[1], out[2]

    def __call__(self, s: np.typing.ArrayLike) -> np.ndarray:
        """TCP positions along the path.

        Parameters
        ----------
        s : array_like, shape (N,)
            Path coordinates in ``[0, 1]``.

        Returns
        -------
        numpy.ndarray, shape (N, 3)
            ``T(s)`` [m].
        """
        return self.evaluate(s)[0]

    def casadi_expression(self, s: ca.SX | ca.MX) -> tuple[ca.SX | ca.MX, ca.SX | ca.MX, ca.SX | ca.MX]:
        """``T``, ``dT/ds`` and ``d2T/ds2`` as CasADi expressions of a symbolic ``s``.

        Pieces are selected by ``if_else`` on the breaks (right-continuous, as
        :meth:`evaluate`); outside ``[0, 1]`` the first/last piece is extrapolated.

        Parameters
        ----------
        s : casadi.SX or casadi.MX, scalar
            Path coordinate.

        Returns
        -------
        T, dT, ddT : casadi.SX or casadi.MX, each shape (3, 1)
            Position [m] and its first and second derivatives with respect to ``s``.
        """
        out = []
        for c in (self.coefficients, self._c1, self._c2):
            expr = None
            for k in range(self.breaks.size - 2, -1, -1):  # last piece first, then wrap
                h = s - float(self.breaks[k])
                v = ca.DM(c[0, k])
                for m in range(1, c.shape[0]):
                    v = v * h + ca.DM(c[m, k])
                if not isinstance(v, (ca.SX, ca.MX)):
                    v = v + 0 * s
                expr = v if expr is None else ca.if_else(s < float(self.breaks[k + 1]), v, expr)
            out.append(expr)
        return out[0], out[1], out[2]

    # ------------------------------------------------------------------ workspace
    def check_workspace(self, robot: Any, configuration: int | Sequence[int] = 0, s: np.typing.ArrayLike | None = None) -> None:
        """Check that the path lies in the robot's workspace.

        Parameters
        ----------
        robot : GantryTau3Kinematics or GantryTau3Dynamics or RobotParameters or str
            The robot (its kinematics and limits are used).
        configuration : int or sequence of int, optional
            IK configuration (see :meth:`GantryTau3Kinematics.ik`).
        s : array_like, shape (M,), optional
            Path coordinates to check; default :data:`WORKSPACE_SAMPLES` uniform samples,
            the breaks and the corners.

        Raises
        ------
        UnreachablePoseError
            At the first (smallest) ``s`` outside the workspace: the message gives ``s``,
            the pose and why (unreachable arm, cart travel or joint angle limit).
        InputError
            ``s`` outside ``[0, 1]`` or a parameter set without limits.
        """
        kin = as_kinematics(robot)
        if s is None:
            s = np.unique(np.concatenate([np.linspace(0.0, 1.0, WORKSPACE_SAMPLES), self.breaks, self.corners]))
        s = self._check_s(s)
        T = self(s)
        ok = kin.in_workspace(T, configuration)
        ok = np.atleast_1d(ok)
        if np.all(ok):
            return
        k = int(np.argmin(ok))
        try:
            kin.require_in_workspace(T[k], configuration)
        except UnreachablePoseError as exc:
            raise UnreachablePoseError(f"the path leaves the workspace at s = {s[k]:.6g}: {exc}") from None
        raise UnreachablePoseError(f"the path leaves the workspace at s = {s[k]:.6g} (T = {T[k].tolist()})")  # pragma: no cover


class StraightLine(Path):
    """Straight line ``T(s) = start + s (end - start)``, ``s`` in ``[0, 1]``.

    Parameters
    ----------
    start, end : array_like, shape (3,)
        End points [m]; must differ.
    robot : GantryTau3Kinematics or GantryTau3Dynamics or RobotParameters or str, optional
        If given, the line is checked to lie in the workspace.
    configuration : int or sequence of int, optional
        IK configuration for the workspace check (default 0).

    Raises
    ------
    InputError
        Malformed or coinciding end points.
    UnreachablePoseError
        A robot is given and the line leaves its workspace (names the first ``s``).
    """

    def __init__(self, start: np.typing.ArrayLike, end: np.typing.ArrayLike, robot: Any = None, configuration: int | Sequence[int] = 0) -> None:
        pts = _points(np.vstack([_point(start, "start"), _point(end, "end")]), "start, end")
        c = np.stack([pts[1] - pts[0], pts[0]])[:, None, :]
        super().__init__([0.0, 1.0], c, (), robot, configuration)


class Polyline(Path):
    """Straight segments through points, ``s`` proportional to arc length.

    The tangent is discontinuous at interior points where the path turns
    (:attr:`Path.corners`): the TCP must be at rest there (see the module docstring).

    Parameters
    ----------
    points : array_like, shape (K, 3)
        Points [m], ``K >= 2``, consecutive points distinct.
    robot : GantryTau3Kinematics or GantryTau3Dynamics or RobotParameters or str, optional
        If given, the path is checked to lie in the workspace.
    configuration : int or sequence of int, optional
        IK configuration for the workspace check (default 0).

    Raises
    ------
    InputError
        Malformed points or coinciding consecutive points.
    UnreachablePoseError
        A robot is given and the path leaves its workspace (names the first ``s``).
    """

    def __init__(self, points: np.typing.ArrayLike, robot: Any = None, configuration: int | Sequence[int] = 0) -> None:
        pts = _points(points, "points")
        seg = np.diff(pts, axis=0)
        lengths = np.linalg.norm(seg, axis=1)
        x = np.concatenate([[0.0], np.cumsum(lengths) / lengths.sum()])
        x[-1] = 1.0
        slope = seg / np.diff(x)[:, None]
        c = np.stack([slope, pts[:-1]])
        u = seg / lengths[:, None]
        cosang = np.clip(np.sum(u[:-1] * u[1:], axis=1), -1.0, 1.0)
        corners = x[1:-1][np.arccos(cosang) > CORNER_ANGLE_TOLERANCE]
        self.points = pts
        super().__init__(x, c, corners, robot, configuration)


class SplinePath(Path):
    """C2 cubic spline through points, in the normalised cumulative chord length.

    Parameters
    ----------
    points : array_like, shape (K, 3)
        Points [m], ``K >= 2``, consecutive points distinct.
    bc_type : str, optional
        End conditions of :class:`scipy.interpolate.CubicSpline`: ``"natural"`` (default,
        zero curvature at the ends), ``"not-a-knot"`` or ``"clamped"``.
    robot : GantryTau3Kinematics or GantryTau3Dynamics or RobotParameters or str, optional
        If given, the path is checked to lie in the workspace.
    configuration : int or sequence of int, optional
        IK configuration for the workspace check (default 0).

    Raises
    ------
    InputError
        Malformed points, coinciding consecutive points or an unknown ``bc_type``.
    UnreachablePoseError
        A robot is given and the path leaves its workspace (names the first ``s``).
    """

    def __init__(self, points: np.typing.ArrayLike, bc_type: str = "natural", robot: Any = None, configuration: int | Sequence[int] = 0) -> None:
        pts = _points(points, "points")
        if bc_type not in ("natural", "not-a-knot", "clamped"):
            raise InputError(f"bc_type: expected 'natural', 'not-a-knot' or 'clamped', got {bc_type!r}")
        chord = np.linalg.norm(np.diff(pts, axis=0), axis=1)
        x = np.concatenate([[0.0], np.cumsum(chord) / chord.sum()])
        x[-1] = 1.0
        spline = interpolate.CubicSpline(x, pts, bc_type=bc_type, axis=0)
        c = np.asarray(spline.c, dtype=float)
        if c.shape[0] < 4:  # CubicSpline lowers the degree for 2 or 3 points: pad to cubic
            c = np.concatenate([np.zeros((4 - c.shape[0],) + c.shape[1:]), c])
        self.points = pts
        super().__init__(x, c, (), robot, configuration)
