"""Time-optimal motion along a given TCP path (Dressler (2012), ch. 3.5; Verscheure et al. (2009)).

The TCP follows a geometric path ``T(s)``, ``s`` in ``[0, 1]`` (:mod:`gtmodel.trajectory.path`),
from rest to rest. With ``T_dot = T'(s) s_dot`` and ``T_ddot = T''(s) s_dot^2 + T'(s) s_ddot``
every quantity of the robot becomes a function of the path state; the inverse dynamics of
the CasADi model (:class:`~gtmodel.robots.dynamics.GantryTau3Dynamics`, eqs. 6.7, 6.8) gives::

    tau(s) = m(s) s_ddot + c(s) s_dot^2 + d(s) s_dot + g(s)

where ``g`` holds gravity and Coulomb friction ``f_c sign(q'(s))`` (exact: ``s_dot >= 0`` so
the sign of ``q_dot = q'(s) s_dot`` is that of ``q'(s)``; it is 0 where ``q'(s) = 0``) and
``d = f_v q'(s)`` is viscous friction. The coefficients are extracted from the symbolic
model with ``casadi.jacobian`` (``m = dtau/ds_ddot``, ``c = 1/2 d2tau/ds_dot2``,
``d = dtau/ds_dot - 2 c s_dot`` at ``s_dot = 1``), never from a second hand-written model.
One CasADi Function maps path samples ``(T, T', T'')`` to all constraint coefficients;
path data are its inputs, so sweeps over paths, grids and limit values do not rebuild it.

Two methods are offered.

Convex reformulation (:class:`PathConstrainedProblem`, :func:`solve_path_convex`)
    Verscheure et al. (2009): with ``a = s_ddot`` and ``b = s_dot^2`` the dynamics are
    ``db/ds = 2 a`` and every constraint is ``lo <= m(s) a + c(s) b + d(s) sqrt(b) + g(s)
    <= hi`` -- linear in ``(a, b)`` without viscous friction -- and the duration
    ``integral ds / sqrt(b)`` is convex. On a grid ``s_0 < ... < s_N``, ``a_k`` is constant
    on ``[s_k, s_{k+1}]`` so ``b`` is piecewise linear, ``b_{k+1} = b_k + 2 a_k (s_{k+1} - s_k)``,
    and the duration ``sum_k 2 ds_k / (sqrt(b_k) + sqrt(b_{k+1}))`` is exact for that profile.
    Constraints hold at the grid points ("collocation" discretisation of TOPP-RA): those
    with ``s_ddot`` at ``s_k`` on ``(a_k, b_k)`` for ``k < N`` (the left end of the interval
    where ``a_k`` applies), those on ``b`` only at every grid point; ``b_0 = b_N = 0`` and
    ``b = 0`` at the corners of a polyline. By default (``constrain_end=True``) the rows with
    ``s_ddot`` also hold at ``s_N`` on ``(a_{N-1}, 0)``: the force on arrival, which TOPP-RA
    leaves unchecked and which otherwise exceeds the limit by about ``d sqrt(b_{N-1})``.

    The gridded problem is solved by the reachability (two-pass) method of TOPP-RA
    (Pham & Pham 2018): a backward pass computes the controllable sets ``K_k`` (the
    ``b_k`` from which the end can still be reached at rest), a forward pass takes at every
    step the largest ``b_{k+1}`` in ``K_{k+1}`` reachable from ``b_k``. The one-step problems
    in ``(a, b)`` are not solved as LPs: ``a`` is eliminated exactly (Fourier-Motzkin: for
    fixed ``b`` every row bounds ``a`` from one side, so ``a`` exists iff every lower bound is
    below every upper bound), which leaves closed-form conditions on ``b``: linear, or
    quadratic in ``sqrt(b)`` where viscous friction enters. They are evaluated in plain
    Python floats in the passes (the stage sets that do not depend on the passes are
    computed for all grid points at once with NumPy). Without viscous friction, and where
    the optimality certificate below holds, this is the exact optimum of the gridded
    problem (equal to TOPP-RA's to rounding, and to IPOPT's).

    Viscous friction. ``d sqrt(b)`` is concave in ``b``: in a one-sided row
    ``p a + r b + w sqrt(b) + e <= 0`` it is convex for ``w <= 0`` and not for ``w > 0`` (an
    upper force bound of a motor moving forward, a lower bound of one moving backward).
    The robot model of Verscheure et al. (2009) has Coulomb friction ``F_s(q) sign(q_dot)``,
    which enters ``g``; TOPP-RA handles dry friction only (its maintainer on viscous
    friction, hungpham2511/toppra#92: "the mathematical form becomes non-convex"). Here the
    viscous term is kept *exactly*: after eliminating ``a`` every condition on ``b`` is
    ``P x^2 + Q x + R <= 0`` in ``x = sqrt(b) >= 0``, whose solution set is computed from the
    roots. It is an interval (convex case, or a concave parabola with at most one positive
    root) except when a concave parabola has two positive roots: then the set is
    ``[0, b1] u [b2, inf)``. The part containing rest, ``[0, b1]``, is kept -- an inner
    approximation, so every computed set is a subset of the exact one and the profile is
    always feasible -- and the solution is reported ``"acceptable"`` (not ``"optimal"``)
    whenever the discarded part ``[b2, inf)`` meets the other constraints at that stage.
    This did not happen on the L1 problems of the tests (the second range lies beyond
    other force limits).

    Optimality certificate. The forward step maps ``b_k`` to
    ``u_k(b_k) = min(max K_{k+1}, min_j l_j(b_k))``, ``l_j(b) = b + 2 ds a_j(b)`` for the
    rows ``a <= a_j(b)``. If a piece active at the greedy ``b_k`` (the cap or a row) is
    nowhere above its value at ``b_k`` on ``[min K_k, b_k]``, then no smaller ``b_k`` can
    reach a larger ``b_{k+1}``, and by induction the greedy profile dominates every
    feasible profile grid point by grid point: it is the optimum, since the duration
    decreases in every ``b_k`` (this is TOPP-RA's optimality argument, made a per-step
    check). It holds on straight lines and for the L1 force problems of the tests, but
    fails where a bound on ``s_ddot`` drops steeply with ``s_dot`` -- an axis acceleration
    limit near a point where that axis' tangent vanishes (``|T''_j / T'_j| > 1 / (2 ds)``),
    a force row with ``m`` near 0 -- where the greedy (and TOPP-RA's) profile is feasible
    but slower than the optimum (1e-4 relative on a spline in the tests). There
    :meth:`PathConstrainedProblem.solve` starts IPOPT on the same gridded problem from the
    greedy profile (``method = "reachability+ipopt"``), or reports ``"acceptable"`` with
    ``polish=False``. The IPOPT transcription (:meth:`PathConstrainedProblem.solve_nlp`,
    variables ``s_dot_k``, viscous friction exact) reproduces the certified durations to
    about 1e-8 in the tests (which require 1e-6).

    Discretisation. As in TOPP-RA's collocation scheme, constraints are checked at the
    grid points only. Between them the forces drift with the state: by about
    ``(c b + d sqrt(b))`` across an interval, and right after rest, where ``s_dot`` grows like
    ``sqrt(s)``, by about ``d sqrt(2 a ds)`` (tens of N for the L1 at 500 points); a finer grid
    (or one refined near the ends) reduces it. The gridded duration converges to the
    continuous optimum from below as the grid is refined (roughly like ``1/N``).

Projection method (:func:`solve_path_collocation`)
    The thesis' formulation (Dressler (2012), ch. 3.5, Table 3.1 "path constrained"):
    states ``(s, s_dot)``, input ``s_ddot``, forces from the inverse dynamics along the path,
    free final time, objective ``final_time + w sum_i integral tau_i^2 dt``, declared as a
    :class:`gtmodel.modeling.Optimization` and solved by direct collocation with IPOPT.

Both return a :class:`PathSolution` (python-control ``OptimalControlResult`` style) whose
:meth:`PathSolution.trajectory` resamples the motion every 4 ms.
"""

from __future__ import annotations

import logging
import math
import time as _time
from collections import OrderedDict
from dataclasses import dataclass, field
from functools import cached_property
from typing import Any, Callable, Sequence

import casadi as ca
import numpy as np
import numpy.typing  # noqa: F401  (np.typing in annotations)

from gtmodel.errors import InputError, SingularConfigurationError, SolverError
from gtmodel.modeling import CollocationTranscription, Model, Optimization
from gtmodel.modeling.result import normalize_ipopt_status
from gtmodel.robots.dynamics import GantryTau3Dynamics
from gtmodel.robots.kinematics import SINGULARITY_TOLERANCE, configuration_signs, link_cosines_expression
from gtmodel.robots.parameters import RobotParameters
from gtmodel.trajectory.path import Path
from gtmodel.trajectory.point_to_point import SAMPLE_TIME, trapezoid_profile

__all__ = [
    "PathConstraints",
    "PathConstrainedProblem",
    "GriddedPathProblem",
    "PathSolution",
    "solve_path_convex",
    "solve_path_collocation",
    "uniform_grid",
]

_log = logging.getLogger("gtmodel")

#: Relative tolerance on the emptiness of an interval (rounding of the closed forms).
_EMPTY_TOLERANCE = 1e-12
_INF = math.inf


# =============================================================================== limits
def _limit(value: Any, name: str, unit: str, size: int = 3) -> np.ndarray | None:
    if value is None:
        return None
    try:
        arr = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise InputError(f"{name}: expected {'three positive numbers' if size == 3 else 'a positive number'} in {unit}, got {value!r}") from None
    if size == 3 and arr.ndim == 0:
        arr = np.full(3, float(arr))
    want = (size,) if size > 1 else ()
    if arr.shape != want or not np.all(np.isfinite(arr)):
        raise InputError(f"{name}: expected {'three finite numbers' if size == 3 else 'a finite number'} in {unit}, got {value!r}")
    if np.any(arr <= 0):
        raise InputError(f"{name}: expected positive limits in {unit} (a limit is a bound on |value|), got {np.atleast_1d(arr).tolist()}")
    return arr


@dataclass
class PathConstraints:
    """Limits along a path: symmetric bounds on magnitudes (``|x| <= limit``).

    Parameters
    ----------
    force_limit : array_like, shape (3,), optional
        Actuator (cart) forces ``|tau_i|`` [N]; needs a robot.
    cart_velocity_limit : array_like, shape (3,), optional
        Cart velocities ``|q_dot_i|`` [m/s]; needs a robot.
    cart_acceleration_limit : array_like, shape (3,), optional
        Cart accelerations ``|q_ddot_i|`` [m/s^2]; needs a robot.
    tcp_velocity_limit : array_like, shape (3,), optional
        TCP velocity per axis ``|T_dot_j|`` [m/s].
    tcp_speed_limit : float, optional
        TCP speed ``||T_dot||`` [m/s].
    tcp_acceleration_limit : array_like, shape (3,), optional
        TCP acceleration per axis ``|T_ddot_j|`` [m/s^2].

    Raises
    ------
    InputError
        A limit that is not positive and finite, has the wrong shape, or no limit at all.

    Notes
    -----
    A scalar given for a per-axis limit applies to all three axes.
    """

    force_limit: Any = None
    cart_velocity_limit: Any = None
    cart_acceleration_limit: Any = None
    tcp_velocity_limit: Any = None
    tcp_speed_limit: Any = None
    tcp_acceleration_limit: Any = None

    def __post_init__(self) -> None:
        self.force_limit = _limit(self.force_limit, "force_limit", "N")
        self.cart_velocity_limit = _limit(self.cart_velocity_limit, "cart_velocity_limit", "m/s")
        self.cart_acceleration_limit = _limit(self.cart_acceleration_limit, "cart_acceleration_limit", "m/s^2")
        self.tcp_velocity_limit = _limit(self.tcp_velocity_limit, "tcp_velocity_limit", "m/s")
        self.tcp_speed_limit = _limit(self.tcp_speed_limit, "tcp_speed_limit", "m/s", size=1)
        self.tcp_acceleration_limit = _limit(self.tcp_acceleration_limit, "tcp_acceleration_limit", "m/s^2")
        if not self.kinds:
            raise InputError("constraints: no limit given; without limits the time-optimal motion is instantaneous")

    @property
    def kinds(self) -> tuple[str, ...]:
        """Names of the limits that are set, in a fixed order."""
        names = ("force_limit", "cart_velocity_limit", "cart_acceleration_limit", "tcp_velocity_limit", "tcp_speed_limit", "tcp_acceleration_limit")
        return tuple(n for n in names if getattr(self, n) is not None)

    @property
    def needs_robot(self) -> bool:
        """True if a limit concerns the actuators (forces or carts)."""
        return any(k in self.kinds for k in ("force_limit", "cart_velocity_limit", "cart_acceleration_limit"))

    def bounds(self) -> tuple[np.ndarray, np.ndarray, list[str]]:
        """Bounds of the constraint rows ``lo <= m a + c b + d sqrt(b) + g <= hi``.

        Returns
        -------
        lo, hi : numpy.ndarray, shape (R,)
            Row bounds (velocities appear squared: ``c b <= v^2``).
        names : list of str
            Row names, e.g. ``"tau1"``, ``"T_dot_x"``.
        """
        lo: list[float] = []
        hi: list[float] = []
        names: list[str] = []
        for kind in self.kinds:
            v = np.atleast_1d(getattr(self, kind))
            if kind in ("force_limit", "cart_acceleration_limit", "tcp_acceleration_limit"):
                lo += (-v).tolist()
                hi += v.tolist()
            else:
                lo += [-_INF] * v.size
                hi += (v**2).tolist()
            names += _ROW_NAMES[kind][: v.size]
        return np.array(lo), np.array(hi), names


_ROW_NAMES = {
    "force_limit": ["tau1", "tau2", "tau3"],
    "cart_velocity_limit": ["q_dot1", "q_dot2", "q_dot3"],
    "cart_acceleration_limit": ["q_ddot1", "q_ddot2", "q_ddot3"],
    "tcp_velocity_limit": ["T_dot_x", "T_dot_y", "T_dot_z"],
    "tcp_speed_limit": ["|T_dot|"],
    "tcp_acceleration_limit": ["T_ddot_x", "T_ddot_y", "T_ddot_z"],
}


# =============================================================================== symbolic rows
def _exact_dynamics(robot: Any) -> GantryTau3Dynamics:
    """Dynamics with the exact Coulomb sign (the path projection fixes its argument)."""
    if isinstance(robot, GantryTau3Dynamics):
        if robot.friction == "exact":
            return robot
        return GantryTau3Dynamics(robot.parameters, friction="exact", asymmetric=robot.asymmetric, gravity=robot.gravity)
    return GantryTau3Dynamics(robot, friction="exact")


_FUNCTION_CACHE: OrderedDict = OrderedDict()
_FUNCTION_CACHE_SIZE = 16


def _cache_key(robot: Any) -> Any:
    if robot is None:
        return None
    if isinstance(robot, str):
        return ("name", robot)
    return ("object", id(robot))


def _rows_function(dyn: GantryTau3Dynamics | None, kinds: tuple[str, ...], viscous: bool) -> ca.Function:
    """CasADi Function ``rows(T, dT, ddT, sg) -> (m, c, d, g, q, dq, ddq, disc, cos)``.

    Rows in the order of :meth:`PathConstraints.bounds`; ``dq = q'(s)``, ``ddq = q''(s)``.
    """
    T, dT, ddT, sg = (ca.SX.sym(n, 3) for n in ("T", "dT", "ddT", "sg"))
    M: list[ca.SX] = []
    C: list[ca.SX] = []
    D: list[ca.SX] = []
    G: list[ca.SX] = []
    zero3 = ca.SX.zeros(3)
    if dyn is not None:
        kin = dyn.kinematics
        q, disc = kin.ik_function(T, sg)
        dq, ddq = kin.cart_acceleration_function(T, dT, ddT, sg)
        cos = link_cosines_expression(T, q, kin.As, kin.v)
    else:
        q = dq = ddq = disc = cos = ca.SX(0, 1)
    for kind in kinds:
        if kind == "force_limit":
            sd, sdd = ca.SX.sym("sd"), ca.SX.sym("sdd")
            tau = dyn.inverse_dynamics_function(T, dT * sd, ddT * sd**2 + dT * sdd, sg)[0]
            m = ca.jacobian(tau, sdd)
            J1 = ca.jacobian(tau, sd)
            H = ca.jacobian(J1, sd)
            m, J1, H, tau1 = (ca.substitute(e, ca.vertcat(sd, sdd), ca.DM([1.0, 0.0])) for e in (m, J1, H, tau))
            c = H / 2
            d = J1 - H
            g = tau1 - J1 + H / 2
            M.append(m)
            C.append(c)
            D.append(d if viscous else zero3)
            G.append(g)
        elif kind == "cart_velocity_limit":
            M.append(zero3)
            C.append(dq**2)
            D.append(zero3)
            G.append(zero3)
        elif kind == "cart_acceleration_limit":
            M.append(dq)
            C.append(ddq)
            D.append(zero3)
            G.append(zero3)
        elif kind == "tcp_velocity_limit":
            M.append(zero3)
            C.append(dT**2)
            D.append(zero3)
            G.append(zero3)
        elif kind == "tcp_speed_limit":
            M.append(ca.SX(0))
            C.append(ca.sumsqr(dT))
            D.append(ca.SX(0))
            G.append(ca.SX(0))
        elif kind == "tcp_acceleration_limit":
            M.append(dT)
            C.append(ddT)
            D.append(zero3)
            G.append(zero3)
    outs = [ca.vertcat(*X) for X in (M, C, D, G)] + [q, dq, ddq, disc, cos]
    names = ["m", "c", "d", "g", "q", "dq", "ddq", "disc", "cos"]
    return ca.Function("path_rows", [T, dT, ddT, sg], outs, ["T", "dT", "ddT", "sg"], names)


def _cached_rows_function(robot: Any, dyn: GantryTau3Dynamics | None, kinds: tuple[str, ...], viscous: bool) -> ca.Function:
    key = ("rows", _cache_key(robot), kinds, viscous)
    hit = _FUNCTION_CACHE.get(key)
    if hit is not None and (robot is None or isinstance(robot, str) or hit[0] is robot):  # id() may be reused
        _FUNCTION_CACHE.move_to_end(key)
        return hit[1]
    f = _rows_function(dyn, kinds, viscous)
    _FUNCTION_CACHE[key] = (robot, f, dyn)
    if len(_FUNCTION_CACHE) > _FUNCTION_CACHE_SIZE:
        _FUNCTION_CACHE.popitem(last=False)
    return f


def _cached_dynamics(robot: Any) -> GantryTau3Dynamics:
    if isinstance(robot, GantryTau3Dynamics) and robot.friction == "exact":
        return robot
    key = ("dynamics", _cache_key(robot))
    hit = _FUNCTION_CACHE.get(key)
    if hit is not None and (isinstance(robot, str) or hit[0] is robot):
        _FUNCTION_CACHE.move_to_end(key)
        return hit[2]
    dyn = _exact_dynamics(robot)
    _FUNCTION_CACHE[key] = (robot, None, dyn)
    if len(_FUNCTION_CACHE) > _FUNCTION_CACHE_SIZE:
        _FUNCTION_CACHE.popitem(last=False)
    return dyn


class _MapCache:
    """Evaluate a Function on N samples (columns), one ``map`` per N."""

    def __init__(self, f: ca.Function) -> None:
        self.f = f
        self.maps: dict[int, ca.Function] = {}

    def __call__(self, n: int, *args: np.ndarray) -> list[np.ndarray]:
        if n not in self.maps:
            self.maps[n] = self.f.map(n)
        out = self.maps[n](*args)
        if not isinstance(out, (list, tuple)):
            out = [out]
        return [np.asarray(o) for o in out]


# =============================================================================== grids
def uniform_grid(path: Path, points: int) -> np.ndarray:
    """Uniform grid on ``[0, 1]`` with the path's corners added.

    Parameters
    ----------
    path : Path
        The path (its :attr:`Path.corners` are inserted).
    points : int
        Number of uniformly spaced points, at least 2.

    Returns
    -------
    numpy.ndarray, shape (N + 1,)
        Increasing grid from 0 to 1 (``points`` values plus the corners not already on it).

    Raises
    ------
    InputError
        ``points`` is not an integer of at least 2.
    """
    if isinstance(points, bool) or not isinstance(points, (int, np.integer)) or points < 2:
        raise InputError(f"grid: expected at least 2 grid points, got {points!r}")
    s = np.linspace(0.0, 1.0, int(points))
    if path.corners.size:
        s = np.union1d(s, path.corners)
        s = s[np.concatenate([[True], np.diff(s) > 1e-12])]
    return s


def _check_grid(path: Path, grid: Any) -> np.ndarray:
    if isinstance(grid, (int, np.integer)) and not isinstance(grid, bool):
        return uniform_grid(path, int(grid))
    try:
        s = np.asarray(grid, dtype=float)
    except (TypeError, ValueError):
        raise InputError(f"grid: expected a number of points or an increasing array of s values, got {grid!r}") from None
    if s.ndim != 1 or s.size < 2:
        raise InputError(f"grid: expected at least 2 grid points, got shape {s.shape}")
    if not np.all(np.isfinite(s)):
        raise InputError("grid: values must be finite")
    if np.any(np.diff(s) <= 0):
        k = int(np.argmax(np.diff(s) <= 0))
        raise InputError(f"grid: expected strictly increasing s, but s[{k + 1}] = {s[k + 1]!r} <= s[{k}] = {s[k]!r}")
    if abs(s[0]) > 1e-12 or abs(s[-1] - 1.0) > 1e-12:
        raise InputError(f"grid: expected to start at s = 0 and end at s = 1, got {s[0]!r} .. {s[-1]!r}")
    s = s.copy()
    s[0], s[-1] = 0.0, 1.0
    for corner in path.corners:
        if np.min(np.abs(s - corner)) > 1e-12:
            raise InputError(f"grid: the path has a corner at s = {corner:.12g} (rest required there); include it in the grid")
    return s


# =============================================================================== gridded problem
@dataclass
class GriddedPathProblem:
    """The path-constrained problem on a grid: constraint rows at every grid point.

    Row ``j`` at grid point ``k`` reads ``lo_j <= m[k, j] a + c[k, j] b + d[k, j] sqrt(b) +
    g[k, j] <= hi_j`` with ``a = s_ddot`` and ``b = s_dot^2``.

    Parameters
    ----------
    s : numpy.ndarray, shape (N + 1,)
        Grid.
    m, c, d, g : numpy.ndarray, shape (N + 1, R)
        Row coefficients (forces [N] per unit ``a`` [1/s^2], ``b`` [1/s^2], ``sqrt(b)`` [1/s]).
    lo, hi : numpy.ndarray, shape (R,)
        Row bounds (``-inf``/``inf`` where absent).
    names : list of str
        Row names.
    rest : numpy.ndarray of bool, shape (N + 1,)
        Grid points with ``s_dot = 0`` (the ends and the corners).
    samples : dict of str to numpy.ndarray
        ``T``, ``dT``, ``ddT`` (N + 1, 3) and, with a robot, ``q``, ``dq``, ``ddq`` (N + 1, 3).
    setup_time : float
        Wall time of the evaluation [s].
    constrain_end : bool
        Whether the rows with ``a`` also hold at the last grid point, on ``a_{N-1}`` (with
        ``b_N = 0``); TOPP-RA's collocation scheme does not impose them.
    """

    s: np.ndarray
    m: np.ndarray
    c: np.ndarray
    d: np.ndarray
    g: np.ndarray
    lo: np.ndarray
    hi: np.ndarray
    names: list[str]
    rest: np.ndarray
    samples: dict[str, np.ndarray]
    setup_time: float = 0.0
    constrain_end: bool = True

    @property
    def N(self) -> int:
        """Number of intervals (grid points minus one)."""
        return self.s.size - 1

    def one_sided(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, list[str], np.ndarray, np.ndarray]:
        """The rows as one-sided constraints ``p a + r b + w sqrt(b) + e <= 0``.

        Rows with ``a`` are dropped at the last grid point (no interval starts there) and
        returned separately: with :attr:`constrain_end` they hold there on ``a_{N-1}``.

        Returns
        -------
        p, r, w, e : numpy.ndarray, shape (N + 1, M)
            Coefficients of the ``M`` one-sided rows (absent bounds omitted).
        names : list of str
            ``"<row> <= hi"`` or ``"<row> >= lo"`` per one-sided row.
        p_end, e_end : numpy.ndarray, shape (M,)
            ``p_end a_{N-1} + e_end <= 0`` at the last grid point (``b_N = 0``); zeros and -1
            (always true) for rows without ``a`` or without :attr:`constrain_end`.
        """
        cols_hi = np.flatnonzero(np.isfinite(self.hi))
        cols_lo = np.flatnonzero(np.isfinite(self.lo))
        p = np.concatenate([self.m[:, cols_hi], -self.m[:, cols_lo]], axis=1)
        r = np.concatenate([self.c[:, cols_hi], -self.c[:, cols_lo]], axis=1)
        w = np.concatenate([self.d[:, cols_hi], -self.d[:, cols_lo]], axis=1)
        e = np.concatenate([self.g[:, cols_hi] - self.hi[cols_hi], self.lo[cols_lo] - self.g[:, cols_lo]], axis=1)
        names = [f"{self.names[j]} <= {self.hi[j]:.6g}" for j in cols_hi] + [f"{self.names[j]} >= {self.lo[j]:.6g}" for j in cols_lo]
        last = p[-1] != 0
        p_end = np.where(last & self.constrain_end, p[-1], 0.0)
        e_end = np.where(last & self.constrain_end, e[-1], -1.0)
        p[-1, last] = 0.0
        r[-1, last] = 0.0
        w[-1, last] = 0.0
        e[-1, last] = -1.0
        return p, r, w, e, names, p_end, e_end

    def violation(self, b: np.ndarray, a: np.ndarray) -> float:
        """Largest violation of the rows by a profile, relative to the bound.

        Parameters
        ----------
        b : numpy.ndarray, shape (N + 1,)
            ``s_dot^2`` at the grid points [1/s^2].
        a : numpy.ndarray, shape (N,)
            ``s_ddot`` on the intervals [1/s^2].

        Returns
        -------
        float
            ``max (value - hi) / |hi|`` and ``(lo - value) / |lo|`` over rows and grid points
            (0 if all hold); rows with ``a`` are checked at the last grid point on
            ``a_{N-1}`` if :attr:`constrain_end`, else not.
        """
        b = np.maximum(np.asarray(b, dtype=float), 0.0)
        a = np.asarray(a, dtype=float)
        aa = np.append(a, a[-1] if self.constrain_end else 0.0)
        val = self.m * aa[:, None] + self.c * b[:, None] + self.d * np.sqrt(b)[:, None] + self.g
        with np.errstate(invalid="ignore", divide="ignore"):
            over = np.where(np.isfinite(self.hi), (val - self.hi) / np.maximum(np.abs(self.hi), 1e-300), -np.inf)
            under = np.where(np.isfinite(self.lo), (self.lo - val) / np.maximum(np.abs(self.lo), 1e-300), -np.inf)
        viol = np.maximum(over, under)
        if not self.constrain_end:
            viol[-1, self.m[-1] != 0] = -np.inf
        return float(max(0.0, np.max(viol)))


# =============================================================================== interval algebra
def _intervals(P: np.ndarray, Q: np.ndarray, R: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``{b >= 0 : P b + Q sqrt(b) + R <= 0}`` elementwise, a quadratic in ``x = sqrt(b)``.

    Returns the lower and upper ends (``lo > hi`` when empty) and, where the set is two
    intervals ``[0, b1] u [b2, inf)`` (concave quadratic with two positive roots), ``b2``
    (else ``inf``); the first interval, which contains rest, is returned as ``lo, hi``.
    """
    shape = np.shape(P)
    lo = np.zeros(shape)
    hi = np.full(shape, _INF)
    split = np.full(shape, _INF)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        # P == 0: Q x + R <= 0
        z = P == 0
        v = -R / Q
        m = z & (Q > 0)
        hi[m] = np.where(v[m] >= 0, v[m] ** 2, -_INF)
        m = z & (Q < 0)
        lo[m] = np.maximum(v[m], 0.0) ** 2
        m = z & (Q == 0) & (R > 0)
        lo[m], hi[m] = _INF, -_INF
        # P != 0: roots of P x^2 + Q x + R (stable form)
        D = Q * Q - 4.0 * P * R
        sq = np.sqrt(np.maximum(D, 0.0))
        qq = -0.5 * (Q + np.where(Q >= 0, sq, -sq))
        r1 = qq / P
        r2 = np.where(qq != 0, R / qq, 0.0)
        x1 = np.minimum(r1, r2)
        x2 = np.maximum(r1, r2)
        # convex: [x1, x2]
        m = (P > 0) & (D >= 0)
        lo[m] = np.maximum(x1[m], 0.0) ** 2
        hi[m] = np.where(x2[m] >= 0, x2[m] ** 2, -_INF)
        m = (P > 0) & (D < 0)
        lo[m], hi[m] = _INF, -_INF
        # concave: outside (x1, x2)
        c = (P < 0) & (D > 0)
        m = c & (x2 > 0) & (x1 <= 0)
        lo[m] = x2[m] ** 2
        m = c & (x1 > 0)
        hi[m] = x1[m] ** 2
        split[m] = x2[m] ** 2
    return lo, hi, split


def _interval(P: float, Q: float, R: float) -> tuple[float, float, float]:
    """Scalar :func:`_intervals`."""
    if P == 0.0:
        if Q > 0.0:
            v = -R / Q
            return (0.0, v * v, _INF) if v >= 0.0 else (_INF, -_INF, _INF)
        if Q < 0.0:
            v = -R / Q
            return ((v * v if v > 0.0 else 0.0), _INF, _INF)
        return (0.0, _INF, _INF) if R <= 0.0 else (_INF, -_INF, _INF)
    D = Q * Q - 4.0 * P * R
    if D < 0.0:
        return (_INF, -_INF, _INF) if P > 0.0 else (0.0, _INF, _INF)
    sq = math.sqrt(D)
    qq = -0.5 * (Q + sq) if Q >= 0.0 else -0.5 * (Q - sq)
    r1 = qq / P
    r2 = R / qq if qq != 0.0 else 0.0
    x1, x2 = (r1, r2) if r1 <= r2 else (r2, r1)
    if P > 0.0:
        if x2 < 0.0:
            return (_INF, -_INF, _INF)
        return ((x1 * x1 if x1 > 0.0 else 0.0), x2 * x2, _INF)
    if D == 0.0 or x2 <= 0.0:
        return (0.0, _INF, _INF)
    if x1 <= 0.0:
        return (x2 * x2, _INF, _INF)
    return (0.0, x1 * x1, x2 * x2)


def _stage_sets(p: np.ndarray, r: np.ndarray, w: np.ndarray, e: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Sets of ``b`` admitting some ``a`` at every grid point (Fourier-Motzkin on ``a``).

    Returns ``lo, hi`` (N + 1,), the codes of the one-sided rows (``j < M``) or pairs
    (``M + i M + j``) that set each end, the upper end ignoring the upper bounds of split
    sets (N + 1,), and the number of split sets whose upper part meets the others.
    """
    n, M = p.shape
    zero = p == 0
    lo1, hi1, sp1 = _intervals(np.where(zero, r, 0.0), np.where(zero, w, 0.0), np.where(zero, e, -1.0))
    # pairs (i: p > 0, j: p < 0): p_i row_j - p_j row_i eliminates a
    ci = np.flatnonzero(np.any(p > 0, axis=0))
    cj = np.flatnonzero(np.any(p < 0, axis=0))
    pi, pj = p[:, ci, None], p[:, None, cj]
    valid = (pi > 0) & (pj < 0)
    P = np.where(valid, pi * r[:, None, cj] - pj * r[:, ci, None], 0.0)
    Q = np.where(valid, pi * w[:, None, cj] - pj * w[:, ci, None], 0.0)
    R = np.where(valid, pi * e[:, None, cj] - pj * e[:, ci, None], -1.0)
    lo2, hi2, sp2 = _intervals(P, Q, R)
    codes = M + (ci[:, None] * M + cj[None, :]).ravel()
    lo_all = np.concatenate([lo1, lo2.reshape(n, -1)], axis=1)
    hi_all = np.concatenate([hi1, hi2.reshape(n, -1)], axis=1)
    code_all = np.concatenate([np.arange(M), codes])
    arg_lo = np.argmax(lo_all, axis=1)
    arg_hi = np.argmin(hi_all, axis=1)
    idx = np.arange(n)
    split_all = np.concatenate([sp1, sp2.reshape(n, -1)], axis=1)
    hull_hi = np.min(np.where(np.isfinite(split_all), _INF, hi_all), axis=1)
    nsplit = np.sum(np.isfinite(split_all) & (split_all <= hull_hi[:, None]), axis=1)
    return lo_all[idx, arg_lo], hi_all[idx, arg_hi], code_all[arg_lo], code_all[arg_hi], hull_hi, nsplit


def _rows_of(code: int, M: int) -> list[int]:
    """One-sided rows behind a stage-set code (a row ``j < M`` or a pair ``M + i M + j``)."""
    if code < M:
        return [code]
    i, j = divmod(code - M, M)
    return [i, j]


def _empty_message(k: int, s: np.ndarray, rest: np.ndarray, p: np.ndarray, e: np.ndarray, names: list[str], klo: float, khi: float) -> str:
    """Why the controllable set at grid point k is empty (backward pass)."""
    where = f"grid point {k} (s = {s[k]:.6g})"
    head = f"infeasible: the controllable set becomes empty at {where}"
    if rest[k]:
        pos = np.flatnonzero(p[k] > 0)
        if pos.size:
            amax = -e[k, pos] / p[k, pos]
            i = int(pos[np.argmin(amax)])
            if np.min(amax) <= 0:
                return (
                    f"{head}, which is passed at rest: there constraint '{names[i]}' allows s_ddot <= {np.min(amax):.6g} "
                    "1/s^2, no acceleration from rest (e.g. a force limit below gravity plus Coulomb friction)"
                )
        return f"{head}, which is passed at rest: from rest there the motion cannot reach s_dot^2 in [{klo:.6g}, {khi:.6g}] 1/s^2 at s = {s[k + 1]:.6g} and still end at rest"
    return f"{head}: from no admissible s_dot there can the motion reach s_dot^2 in [{klo:.6g}, {khi:.6g}] 1/s^2 at s = {s[k + 1]:.6g} and still end at rest"


@dataclass
class _Pass:
    """Result of one reachability solve (internal)."""

    ok: bool
    b: np.ndarray | None = None
    a: np.ndarray | None = None
    message: str = ""
    index: int = -1
    splits: int = 0
    uncertified: np.ndarray | None = None


def _reachability(
    s: np.ndarray, rest: np.ndarray, p: np.ndarray, r: np.ndarray, w: np.ndarray, e: np.ndarray, names: list[str],
    p_end: np.ndarray | None = None, e_end: np.ndarray | None = None,
) -> _Pass:
    """Two-pass reachability solve of the gridded problem ``p a + r b + w sqrt(b) + e <= 0``.

    ``p_end a_{N-1} + e_end <= 0`` are rows at the last grid point (where ``b_N = 0``).
    """
    N = s.size - 1
    M = p.shape[1]
    S_lo, S_hi, arg_lo, arg_hi, S_hull, nsplit = _stage_sets(p, r, w, e)
    splits = int(nsplit.sum())
    tol = _EMPTY_TOLERANCE * np.maximum(1.0, np.where(np.isfinite(S_hi), np.abs(S_hi), 0.0))
    bad = S_lo > S_hi + tol
    bad |= rest & (S_lo > tol)
    if np.any(bad):
        k = int(np.argmax(bad))
        if S_lo[k] > S_hi[k] + tol[k]:
            rows = list(dict.fromkeys(_rows_of(int(arg_lo[k]), M) + _rows_of(int(arg_hi[k]), M)))
            why = f"constraints {', '.join(repr(names[i]) for i in rows)} admit no (s_ddot, s_dot^2) together"
        else:
            rows = _rows_of(int(arg_lo[k]), M)
            why = f"constraints {', '.join(repr(names[i]) for i in rows)} cannot hold at rest (they need s_dot^2 >= {S_lo[k]:.6g} 1/s^2)"
        return _Pass(False, message=f"infeasible at grid point {k} (s = {s[k]:.6g}): {why}", index=k)
    # leaving rest (start, corners) needs s_ddot > 0 there
    for k in np.flatnonzero(rest[:-1]):
        pos = np.flatnonzero(p[k] > 0)
        if pos.size and np.min(-e[k, pos] / p[k, pos]) <= 0:
            return _Pass(False, message=_empty_message(int(k), s, rest, p, e, names, 0.0, 0.0), index=int(k))
    S_lo = np.maximum(S_lo, 0.0)
    S_hi = np.where(rest, 0.0, S_hi)
    S_lo = np.minimum(S_lo, S_hi)
    two_d = 2.0 * np.diff(s)
    # backward pass. Row i at stage k with the reach constraint klo <= b + 2 ds a (p > 0) or
    # b + 2 ds a <= khi (p < 0), a eliminated: P b + Q sqrt(b) + R <= 0 with P = 2 ds r - p,
    # Q = 2 ds w, R = 2 ds e + p klo (p > 0) or 2 ds e + p khi (p < 0).
    pa = p[:-1]
    cols = np.flatnonzero(np.any(pa != 0, axis=0))
    pa = pa[:, cols]
    Pb = two_d[:, None] * r[:-1, cols] - pa
    Qb = two_d[:, None] * w[:-1, cols]
    Eb = two_d[:, None] * e[:-1, cols]
    with np.errstate(divide="ignore", invalid="ignore"):
        alpha = np.where(Pb != 0, -Eb / Pb, 0.0)
        beta = np.where(Pb != 0, -pa / Pb, 0.0)
    # codes: 0/1 lower/upper bound alpha + beta klo; 2/3 the same with khi; 4 no a;
    # 5 P == 0 (a condition on klo/khi); 6 quadratic (Q != 0)
    code = np.where(pa > 0, 0, 2) + np.where(Pb > 0, 1, 0)
    code = np.where(Pb == 0, 5, code)
    code = np.where(Qb != 0, 6, code)
    code = np.where(pa == 0, 4, code)
    table = np.stack([code, alpha, beta, Pb, Qb, Eb, pa], axis=2).tolist()
    K_lo = [0.0] * (N + 1)
    K_hi = [0.0] * (N + 1)
    slo, shi, shull = S_lo.tolist(), S_hi.tolist(), S_hull.tolist()
    interval = _interval
    end_rows = [] if p_end is None else [(float(pe), float(ee)) for pe, ee in zip(p_end, e_end) if pe != 0.0]
    td_last = float(two_d[-1])
    for k in range(N - 1, -1, -1):
        klo, khi = K_lo[k + 1], K_hi[k + 1]
        lo, hi = slo[k], shi[k]
        hull = shull[k]
        upper = None
        for cd, al, be, P, Q, E, pp in table[k]:
            if cd == 1.0:
                v = al + be * klo
                if v < hi:
                    hi = v
            elif cd == 3.0:
                v = al + be * khi
                if v < hi:
                    hi = v
            elif cd == 0.0:
                v = al + be * klo
                if v > lo:
                    lo = v
            elif cd == 2.0:
                v = al + be * khi
                if v > lo:
                    lo = v
            elif cd == 6.0:
                l2, h2, b2 = interval(P, Q, E + pp * (klo if pp > 0.0 else khi))
                if l2 > lo:
                    lo = l2
                if h2 < hi:
                    hi = h2
                if b2 < _INF:
                    upper = [b2] if upper is None else upper + [b2]
                elif h2 < hull:
                    hull = h2
            elif cd == 5.0 and E + pp * (klo if pp > 0.0 else khi) > 0.0:
                lo, hi = _INF, -_INF
        if upper is not None:
            splits += sum(1 for b2 in upper if b2 <= min(hull, hi if hi < _INF else hull))
        if k == N - 1 and end_rows:
            # rows at the last grid point on a_{N-1} = (b_N - b_{N-1}) / (2 ds), b_N = 0
            for pe, ee in end_rows:
                v = td_last * ee / pe
                if pe > 0.0:
                    if v > lo:
                        lo = v
                elif v < hi:
                    hi = v
        if lo > hi:
            if lo > hi + _EMPTY_TOLERANCE * max(1.0, abs(hi)):
                return _Pass(False, message=_empty_message(k, s, rest, p, e, names, klo, khi), index=k)
            lo = hi
        K_lo[k], K_hi[k] = lo, hi
    # forward pass: the largest b_{k+1} in K_{k+1} reachable with a <= -(r b + w sqrt(b) + e) / p
    pcols = np.flatnonzero(np.any(p[:-1] > 0, axis=0))
    pp_ = p[:-1, pcols]
    pos = pp_ > 0
    with np.errstate(divide="ignore", invalid="ignore"):
        rp = np.where(pos, r[:-1, pcols] / pp_, 0.0)
        wp = np.where(pos, w[:-1, pcols] / pp_, 0.0)
        ep = np.where(pos, e[:-1, pcols] / pp_, -_INF)
    b = [0.0] * (N + 1)
    a = [0.0] * N
    td = two_d.tolist()
    bk = 0.0
    sqrt = math.sqrt
    viscous = bool(np.any(wp != 0))
    ftable = (np.stack([rp, wp, ep], axis=2) if viscous else np.stack([rp, ep], axis=2)).tolist()
    for k in range(N):
        amax = _INF
        if viscous:
            x = sqrt(bk)
            for rr, ww, ee in ftable[k]:
                v = -(rr * bk + ww * x + ee)
                if v < amax:
                    amax = v
        else:
            for rr, ee in ftable[k]:
                v = -(rr * bk + ee)
                if v < amax:
                    amax = v
        bn = bk + td[k] * amax
        if bn > K_hi[k + 1]:
            bn = K_hi[k + 1]
        if bn < K_lo[k + 1]:
            bn = K_lo[k + 1]
        a[k] = (bn - bk) / td[k]
        b[k + 1] = bn
        bk = bn
    b_arr = np.array(b)
    uncertified = _uncertified_stages(b_arr, np.array(K_lo), np.array(K_hi), two_d, rp, wp, ep)
    return _Pass(True, b=b_arr, a=np.array(a), splits=splits, uncertified=uncertified)


def _uncertified_stages(b: np.ndarray, K_lo: np.ndarray, K_hi: np.ndarray, two_d: np.ndarray, rp: np.ndarray, wp: np.ndarray, ep: np.ndarray) -> np.ndarray:
    """Stages where the greedy forward step is not proven to dominate every feasible profile.

    Step k maps ``b_k`` to ``u_k(b_k) = min(K_hi[k+1], min_j l_j(b_k))`` with
    ``l_j(b) = b - 2 ds (rp_j b + wp_j sqrt(b) + ep_j)``. If some piece active at the greedy
    ``b_k`` (the cap, or a row) is nowhere above its value at ``b_k`` on ``[K_lo[k], b_k]``,
    then ``u_k(b) <= u_k(b_k)`` for every smaller ``b``: by induction every feasible profile
    stays below the greedy one, which is then the optimum (the duration decreases in every
    ``b_k``). Checked per piece: affine with slope >= 0, concave (``wp < 0``) with slope >= 0
    at ``b_k``, convex (``wp > 0``) with ``l_j(K_lo[k]) <= l_j(b_k)``.
    """
    bk = b[:-1]
    tol = 1e-12 * np.maximum(1.0, np.abs(K_hi[1:]))
    capped = b[1:] >= K_hi[1:] - tol
    pinned = bk <= K_lo[:-1] + 1e-12 * np.maximum(1.0, bk)
    x = np.sqrt(bk)[:, None]
    td = two_d[:, None]
    with np.errstate(invalid="ignore", divide="ignore"):
        val = bk[:, None] - td * (rp * bk[:, None] + wp * x + ep)
        val = np.where(np.isfinite(ep), val, _INF)
        active = val <= np.min(val, axis=1, keepdims=True) + tol[:, None]
        slope_lin = 1.0 - td * rp
        slope = np.where(x > 0, slope_lin - td * wp / (2.0 * x), np.where(wp < 0, _INF, np.where(wp > 0, -_INF, slope_lin)))
        lo = K_lo[:-1, None]
        val_lo = lo - td * (rp * lo + wp * np.sqrt(lo) + ep)
    ok_piece = np.where(wp > 0, val_lo <= val + tol[:, None], slope >= -1e-12)
    certified = capped | pinned | np.any(active & ok_piece, axis=1)
    return np.flatnonzero(~certified)


# =============================================================================== results
@dataclass
class PathSolution:
    """Time-optimal motion along a path (python-control ``OptimalControlResult`` style).

    Parameters
    ----------
    success : bool
        True only for status ``"optimal"``.
    status : str
        ``"optimal"``, ``"infeasible"``, ``"max_iterations"``, ``"acceptable"`` or ``"error"``.
    message : str
        What happened; for ``"infeasible"`` the grid point and ``s`` where the problem
        fails and the constraints involved.
    final_time : float
        Duration [s]; NaN unless a profile was found.
    s : numpy.ndarray, shape (K,)
        Path coordinates of the grid (convex method) or collocation mesh.
    s_dot : numpy.ndarray, shape (K,)
        Path velocity [1/s] there (NaN when infeasible).
    s_ddot : numpy.ndarray, shape (K,)
        Path acceleration [1/s^2] there; on a grid ``s_ddot[k]`` applies on
        ``[s_k, s_{k+1})``, the last entry repeats the last interval's value.
    t : numpy.ndarray, shape (K,)
        Times of the grid/mesh points [s].
    solve_time : float
        Wall time of the solve [s] (without the evaluation of the path data).
    iterations : int
        1 for the reachability solver (one backward and one forward pass), else IPOPT's.
    method : str
        ``"reachability"``, ``"reachability+ipopt"`` (IPOPT started from the reachability
        profile, see :meth:`PathConstrainedProblem.solve`), ``"ipopt"`` or ``"collocation"``.
    path : Path
        The path.
    max_constraint_violation : float
        Largest relative violation of the constraints at the grid points (0 if none).
    setup_time : float
        Wall time of the evaluation of the path data [s].
    sampler : callable or None
        ``sampler(t) -> (s, s_dot, s_ddot)`` at times ``t`` (K,) (internal).
    evaluator : callable or None
        ``evaluator(s, s_dot, s_ddot) -> dict`` of kinematic and force samples (internal).
    breaks : numpy.ndarray or None
        Times [s] between which the motion is smooth (for the energy quadrature).
    details : dict
        Extra data (``b``, ``a`` on the grid, the IPOPT stats, the collocation result ...).
    """

    success: bool
    status: str
    message: str
    final_time: float
    s: np.ndarray
    s_dot: np.ndarray
    s_ddot: np.ndarray
    t: np.ndarray
    solve_time: float
    iterations: int
    method: str
    path: Path
    max_constraint_violation: float = float("nan")
    setup_time: float = 0.0
    sampler: Callable[[np.ndarray], tuple[np.ndarray, np.ndarray, np.ndarray]] | None = field(default=None, repr=False)
    evaluator: Callable[..., dict[str, np.ndarray]] | None = field(default=None, repr=False)
    breaks: np.ndarray | None = field(default=None, repr=False)
    details: dict[str, Any] = field(default_factory=dict, repr=False)

    def _require_profile(self) -> None:
        if self.sampler is None or not np.isfinite(self.final_time):
            raise SolverError(f"no motion to sample: the solve ended with status {self.status!r} ({self.message})")

    def sample(self, t: np.typing.ArrayLike) -> dict[str, np.ndarray]:
        """The motion at given times.

        Parameters
        ----------
        t : array_like, shape (K,)
            Times in ``[0, final_time]`` [s].

        Returns
        -------
        dict of str to numpy.ndarray
            ``t``, ``s``, ``s_dot``, ``s_ddot`` (K,); ``T``, ``T_dot``, ``T_ddot`` (K, 3)
            [m, m/s, m/s^2]; with a robot also ``q``, ``q_dot``, ``q_ddot`` (K, 3) and
            ``tau`` (K, 3) [N] from the inverse dynamics of the model.

        Raises
        ------
        SolverError
            The solve found no motion (status not optimal/acceptable/max_iterations).
        InputError
            Times outside ``[0, final_time]``.
        """
        self._require_profile()
        t = np.asarray(t, dtype=float).reshape(-1)
        tol = 1e-9 * max(1.0, self.final_time)
        if not np.all(np.isfinite(t)) or np.any(t < -tol) or np.any(t > self.final_time + tol):
            raise InputError(f"t: expected times in [0, {self.final_time}] s")
        s, sd, sdd = self.sampler(np.clip(t, 0.0, self.final_time))
        out = {"t": t, "s": s, "s_dot": sd, "s_ddot": sdd}
        out.update(self.evaluator(s, sd, sdd))
        return out

    def trajectory(self, dt: float = SAMPLE_TIME) -> dict[str, np.ndarray]:
        """The motion resampled on a uniform time grid (controller sample time by default).

        Parameters
        ----------
        dt : float, optional
            Sample time [s]; default 0.004 s. The last sample is the final time.

        Returns
        -------
        dict of str to numpy.ndarray
            As :meth:`sample`, at ``t = 0, dt, 2 dt, ..., final_time``.

        Raises
        ------
        InputError
            Non-positive ``dt``.
        SolverError
            The solve found no motion.
        """
        if not (isinstance(dt, (int, float)) and np.isfinite(dt) and dt > 0):
            raise InputError(f"dt: expected a positive sample time in s, got {dt!r}")
        self._require_profile()
        tf = self.final_time
        t = np.arange(0.0, tf, dt)
        if tf - t[-1] > 1e-12:
            t = np.append(t, tf)
        return self.sample(t)

    @cached_property
    def energy(self) -> float:
        """``sum_i integral tau_i^2 dt`` [N^2 s] of the motion (NaN without a robot).

        Gauss-Legendre quadrature (6 points) on every interval between :attr:`breaks`,
        where the motion is smooth; the forces are those of the model along the motion.
        """
        self._require_profile()
        if self.breaks is None:
            return float("nan")
        nodes, weights = np.polynomial.legendre.leggauss(6)
        t0, t1 = self.breaks[:-1], self.breaks[1:]
        h = t1 - t0
        tt = (t0[:, None] + h[:, None] * (nodes[None, :] + 1) / 2).ravel()
        smp = self.sample(tt)
        if "tau" not in smp:
            return float("nan")
        f = np.sum(smp["tau"] ** 2, axis=1).reshape(h.size, nodes.size)
        return float(np.sum(h / 2 * (f @ weights)))


def _failed(status: str, message: str, path: Path, s: np.ndarray, method: str, solve_time: float, iterations: int, setup_time: float = 0.0, details: dict | None = None) -> PathSolution:
    nan = np.full(s.size, np.nan)
    _log.warning("path-constrained solve (%s): %s: %s", method, status, message)
    return PathSolution(
        success=False,
        status=status,
        message=message,
        final_time=float("nan"),
        s=s,
        s_dot=nan,
        s_ddot=nan.copy(),
        t=nan.copy(),
        solve_time=solve_time,
        iterations=iterations,
        method=method,
        path=path,
        setup_time=setup_time,
        details=details or {},
    )


def _profile_sampler(s: np.ndarray, x: np.ndarray, a: np.ndarray, tk: np.ndarray) -> Callable[[np.ndarray], tuple[np.ndarray, np.ndarray, np.ndarray]]:
    """Exact motion of a piecewise-constant ``s_ddot`` profile at times t."""

    def sampler(t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        k = np.clip(np.searchsorted(tk, t, side="right") - 1, 0, a.size - 1)
        h = t - tk[k]
        sd = np.maximum(x[k] + a[k] * h, 0.0)
        ss = np.clip(s[k] + x[k] * h + 0.5 * a[k] * h**2, s[k], s[k + 1])
        return ss, sd, a[k].copy()

    return sampler


# =============================================================================== the problem
class PathConstrainedProblem:
    """Time-optimal rest-to-rest motion along a path, Verscheure et al. (2009) / TOPP-RA.

    Built once per path, limits and robot; :meth:`solve` and :meth:`solve_nlp` take the
    grid. The CasADi Function that evaluates the constraint coefficients from path samples
    is cached per robot and set of limit kinds (path data and limit values are inputs).

    Parameters
    ----------
    path : Path
        The TCP path.
    constraints : PathConstraints
        The limits.
    robot : GantryTau3Dynamics or RobotParameters or str, optional
        The robot (needed for force and cart limits; its kinematics and workspace limits
        are then checked along the path). A dynamics object with a smooth friction form is
        replaced by the same model with the exact Coulomb sign (see the module docstring).
    configuration : int or sequence of int, optional
        IK configuration (see :func:`gtmodel.robots.kinematics.configuration_signs`).
    viscous_friction : bool, optional
        Include the viscous friction ``f_v q_dot`` of the model (default True); False drops
        it (Coulomb friction and the rigid-body terms remain), e.g. to compare with solvers
        that cannot represent it. Forces sampled from the solutions use the same model.
    constrain_end : bool, optional
        Also impose the rows with ``s_ddot`` (forces, accelerations) at the last grid point,
        on the last interval's ``s_ddot`` with ``s_dot = 0`` (default True: the force on
        arrival is checked). False gives TOPP-RA's collocation scheme, which leaves them out.

    Raises
    ------
    InputError
        Not a :class:`Path`, not :class:`PathConstraints`, an actuator limit without a
        robot, or an invalid configuration.

    Notes
    -----
    At a corner of a polyline the arrival (with the incoming tangent) is not checked; only
    the departure is (right-continuous ``dT/ds``).
    UnreachablePoseError
        The path leaves the robot's workspace (names the first ``s``).
    """

    def __init__(
        self,
        path: Path,
        constraints: PathConstraints,
        robot: GantryTau3Dynamics | RobotParameters | str | None = None,
        configuration: int | Sequence[int] = 0,
        viscous_friction: bool = True,
        constrain_end: bool = True,
    ) -> None:
        if not isinstance(path, Path):
            raise InputError(f"path: expected a gtmodel.trajectory.path.Path, got {type(path).__name__}")
        if not isinstance(constraints, PathConstraints):
            raise InputError(f"constraints: expected PathConstraints, got {type(constraints).__name__}")
        if constraints.needs_robot and robot is None:
            raise InputError("robot: force and cart limits need a robot (parameter set name, RobotParameters or GantryTau3Dynamics)")
        self.path = path
        self.constraints = constraints
        self.configuration = configuration
        self.signs = configuration_signs(configuration)
        self.viscous_friction = bool(viscous_friction)
        self.constrain_end = bool(constrain_end)
        self.robot = robot
        self.dynamics: GantryTau3Dynamics | None = None
        if robot is not None:
            self.dynamics = _cached_dynamics(robot)
            path.check_workspace(self.dynamics.kinematics, configuration)
        self._rows = _MapCache(_cached_rows_function(robot, self.dynamics, constraints.kinds, self.viscous_friction))
        self._kin_rows = None
        if self.dynamics is not None:
            self._kin_rows = _MapCache(_cached_rows_function(robot, self.dynamics, ("force_limit",), self.viscous_friction))
        self._nlp: dict[tuple[int, int, bool], Any] = {}

    # ------------------------------------------------------------------ evaluation
    def _evaluate(self, s: np.ndarray, f: _MapCache) -> dict[str, np.ndarray]:
        T, dT, ddT = self.path.evaluate(s)
        n = s.size
        m, c, d, g, q, dq, ddq, disc, cos = f(n, T.T, dT.T, ddT.T, np.repeat(self.signs[:, None], n, axis=1))
        out = {"T": T, "dT": dT, "ddT": ddT, "m": m.T, "c": c.T, "d": d.T, "g": g.T}
        if self.dynamics is not None:
            out.update(q=q.T, dq=dq.T, ddq=ddq.T, disc=disc.T, cos=cos.T)
        return out

    def _check_reach(self, s: np.ndarray, ev: dict[str, np.ndarray]) -> None:
        if self.dynamics is None:
            return
        lim = self.dynamics.parameters.limits
        q, cos = ev["q"], ev["cos"]
        ok = np.all(ev["disc"] >= 0, axis=1)
        ok &= np.all((q >= lim.cart_travel[:, 0]) & (q <= lim.cart_travel[:, 1]), axis=1)
        ok &= np.all(np.abs(cos) >= np.cos(lim.joint_angle_max), axis=1)
        if not np.all(ok):
            k = int(np.argmin(ok))
            self.path.check_workspace(self.dynamics.kinematics, self.configuration, s=[s[k]])
        cmin = np.min(np.abs(cos), axis=1)
        if np.any(cmin < SINGULARITY_TOLERANCE):
            k = int(np.argmin(cmin))
            raise SingularConfigurationError(f"the path is singular at s = {s[k]:.6g}: a link is perpendicular to its guideway")

    def gridded(self, grid: int | np.typing.ArrayLike = 100) -> GriddedPathProblem:
        """Evaluate the constraint rows on a grid.

        Parameters
        ----------
        grid : int or array_like, shape (N + 1,)
            Number of uniformly spaced grid points (at least 2; the path's corners are
            added), or the grid itself: strictly increasing from 0 to 1, containing the
            corners.

        Returns
        -------
        GriddedPathProblem
            The rows at the grid points.

        Raises
        ------
        InputError
            Fewer than 2 grid points, a grid that is not strictly increasing, does not run
            from 0 to 1, or misses a corner.
        UnreachablePoseError
            A grid point is outside the workspace (names ``s``).
        SingularConfigurationError
            A grid point is singular.
        """
        t0 = _time.perf_counter()
        s = _check_grid(self.path, grid)
        ev = self._evaluate(s, self._rows)
        self._check_reach(s, ev)
        lo, hi, names = self.constraints.bounds()
        rest = np.zeros(s.size, dtype=bool)
        rest[[0, -1]] = True
        for corner in self.path.corners:
            rest[int(np.argmin(np.abs(s - corner)))] = True
        samples = {k: ev[k] for k in ("T", "dT", "ddT", "q", "dq", "ddq") if k in ev}
        return GriddedPathProblem(
            s=s, m=ev["m"], c=ev["c"], d=ev["d"], g=ev["g"], lo=lo, hi=hi, names=names, rest=rest, samples=samples,
            setup_time=_time.perf_counter() - t0, constrain_end=self.constrain_end,
        )

    def _motion(self, s: np.ndarray, sd: np.ndarray, sdd: np.ndarray) -> dict[str, np.ndarray]:
        """Kinematic and force samples along the motion (the model's inverse dynamics)."""
        if self._kin_rows is None:
            T, dT, ddT = self.path.evaluate(s)
            out = {}
        else:
            ev = self._evaluate(s, self._kin_rows)
            T, dT, ddT = ev["T"], ev["dT"], ev["ddT"]
            tau = ev["m"] * sdd[:, None] + ev["c"] * (sd**2)[:, None] + ev["d"] * sd[:, None] + ev["g"]
            out = {
                "q": ev["q"],
                "q_dot": ev["dq"] * sd[:, None],
                "q_ddot": ev["dq"] * sdd[:, None] + ev["ddq"] * (sd**2)[:, None],
                "tau": tau,
            }
        out = {"T": T, "T_dot": dT * sd[:, None], "T_ddot": ddT * (sd**2)[:, None] + dT * sdd[:, None], **out}
        return out

    def _solution(self, gp: GriddedPathProblem, b: np.ndarray, a: np.ndarray, status: str, message: str, solve_time: float, iterations: int, method: str, details: dict) -> PathSolution:
        b = np.maximum(b, 0.0)
        x = np.sqrt(b)
        with np.errstate(divide="ignore"):
            dt = 2.0 * np.diff(gp.s) / (x[:-1] + x[1:])
        if not np.all(np.isfinite(dt)):
            k = int(np.argmax(~np.isfinite(dt)))
            return _failed("infeasible", f"infeasible: s_dot is zero at both ends of interval {k} (s = {gp.s[k]:.6g} .. {gp.s[k + 1]:.6g}): the path cannot be traversed on this grid", self.path, gp.s, method, solve_time, iterations, gp.setup_time, details)
        tk = np.concatenate([[0.0], np.cumsum(dt)])
        details = {**details, "b": b, "a": a}
        return PathSolution(
            success=status == "optimal",
            status=status,
            message=message,
            final_time=float(tk[-1]),
            s=gp.s.copy(),
            s_dot=x,
            s_ddot=np.append(a, a[-1]),
            t=tk,
            solve_time=solve_time,
            iterations=iterations,
            method=method,
            path=self.path,
            max_constraint_violation=gp.violation(b, a),
            setup_time=gp.setup_time,
            sampler=_profile_sampler(gp.s, x, a, tk),
            evaluator=self._motion,
            breaks=tk if self.dynamics is not None else None,
            details=details,
        )

    # ------------------------------------------------------------------ reachability
    def solve(self, grid: int | np.typing.ArrayLike | GriddedPathProblem = 100, polish: bool = True) -> PathSolution:
        """Solve the gridded problem by reachability analysis (TOPP-RA's two passes).

        The greedy forward pass is the optimum when every step is certified (see the module
        docstring): then the status is ``"optimal"`` and ``method`` ``"reachability"``.
        Where a step is limited by a constraint whose bound on the next ``s_dot`` falls as
        the current one rises (e.g. an axis acceleration limit near a point where that axis'
        tangent vanishes, ``|T''_j / T'_j| > 1 / (2 ds)``), the greedy profile is feasible
        but not proven optimal; it then starts IPOPT on the same gridded problem
        (:meth:`solve_nlp`), ``method`` ``"reachability+ipopt"``.

        Parameters
        ----------
        grid : int or array_like or GriddedPathProblem, optional
            Grid (see :meth:`gridded`) or an already evaluated problem; default 100 points.
        polish : bool, optional
            Run IPOPT from the greedy profile when its optimality is not certified (default
            True); if False, or if IPOPT does not improve it, the greedy profile is returned
            as ``"acceptable"``.

        Returns
        -------
        PathSolution
            Status ``"optimal"``; ``"infeasible"`` (the message names the grid point, ``s``
            and the constraints); ``"acceptable"`` when the profile is feasible but not
            proven optimal (uncertified steps without polish, or a non-convex
            viscous-friction set that split in two and whose part containing rest was kept;
            the message says where).

        Raises
        ------
        InputError
            Invalid grid.
        UnreachablePoseError
            A grid point is outside the workspace.
        SingularConfigurationError
            A grid point is singular.
        """
        gp = grid if isinstance(grid, GriddedPathProblem) else self.gridded(grid)
        t0 = _time.perf_counter()
        p, r, w, e, names, p_end, e_end = gp.one_sided()
        res = _reachability(gp.s, gp.rest, p, r, w, e, names, p_end, e_end)
        elapsed = _time.perf_counter() - t0
        if not res.ok:
            return _failed("infeasible", res.message, self.path, gp.s, "reachability", elapsed, 1, gp.setup_time, {"index": res.index})
        notes = []
        if res.splits:
            notes.append(
                f"at {res.splits} stage(s) a viscous-friction constraint admitted two separate ranges of s_dot and the "
                "range containing rest was kept"
            )
        if res.uncertified.size:
            ks = res.uncertified
            notes.append(
                f"the greedy step is not proven optimal at {ks.size} stage(s) (first: grid point {int(ks[0])}, "
                f"s = {gp.s[ks[0]]:.6g}): a constraint whose bound falls as s_dot rises limits it"
            )
        greedy = self._solution(gp, res.b, res.a, "optimal", "optimal: reachability (backward and forward pass)", elapsed, 1, "reachability", {})
        if not notes or greedy.status != "optimal":
            return greedy
        if polish and res.uncertified.size:
            nlp = self.solve_nlp(gp, initial_s_dot=greedy.s_dot)
            if nlp.status == "optimal" and nlp.final_time <= greedy.final_time * (1 + 1e-9):
                nlp.method = "reachability+ipopt"
                nlp.solve_time += elapsed
                nlp.message = f"optimal: reachability, then IPOPT from it because {'; '.join(notes)}; IPOPT ({nlp.message}) shortened the duration by {greedy.final_time - nlp.final_time:.3g} s"
                _log.info("path-constrained solve: %s", nlp.message)
                return nlp
            notes.append(f"the IPOPT polish did not improve it ({nlp.status})")
        greedy.status = "acceptable"
        greedy.success = False
        greedy.message = "acceptable: feasible, but " + "; ".join(notes)
        _log.warning("path-constrained solve: %s", greedy.message)
        return greedy

    # ------------------------------------------------------------------ IPOPT cross-check
    def _nlp_solver(self, N: int, R: int, end: bool, options: dict) -> tuple[ca.Function, Any]:
        key = (N, R, end)
        if key in self._nlp:
            return self._nlp[key]
        X = ca.SX.sym("s_dot", N + 1)
        A = ca.SX.sym("a", N)
        Dl = ca.SX.sym("delta", N)
        Mc, Cc, Dc, Gc = (ca.SX.sym(n, N + 1, R) for n in ("m", "c", "d", "g"))
        Aext = ca.vertcat(A, A[-1] if end else 0)
        rows = []
        for j in range(R):
            rows.append(Mc[:, j] * Aext + Cc[:, j] * X**2 + Dc[:, j] * X + Gc[:, j])
        g = ca.vertcat(X[1:] ** 2 - X[:-1] ** 2 - 2 * Dl * A, *rows)
        f = ca.sum1(2 * Dl / (X[:-1] + X[1:]))
        pvec = ca.vertcat(Dl, ca.vec(Mc), ca.vec(Cc), ca.vec(Dc), ca.vec(Gc))
        solver = ca.nlpsol("path_nlp", "ipopt", {"x": ca.vertcat(X, A), "p": pvec, "f": f, "g": g}, options)
        self._nlp[key] = (solver, None)
        return self._nlp[key]

    def solve_nlp(
        self,
        grid: int | np.typing.ArrayLike | GriddedPathProblem = 100,
        tol: float = 1e-10,
        max_iter: int = 3000,
        verbose: bool = False,
        initial_s_dot: np.typing.ArrayLike | None = None,
    ) -> PathSolution:
        """Solve the same gridded problem with IPOPT (an independent cross-check of :meth:`solve`).

        Variables ``s_dot_k`` (N + 1) and ``a_k`` (N); constraints ``s_dot_{k+1}^2 -
        s_dot_k^2 = 2 a_k ds_k`` and the rows with ``b = s_dot^2`` (viscous friction
        exact); objective ``sum 2 ds_k / (s_dot_k + s_dot_{k+1})``. The initial guess is
        a small sine-shaped profile, independent of the reachability solution. The NLP is
        built once per grid size (path data and limits are its parameters and bounds).

        Parameters
        ----------
        grid : int or array_like or GriddedPathProblem, optional
            Grid (see :meth:`gridded`); default 100 points.
        tol : float, optional
            IPOPT tolerance.
        max_iter : int, optional
            IPOPT iteration limit.
        verbose : bool, optional
            Show IPOPT's log.
        initial_s_dot : array_like, shape (N + 1,), optional
            Initial guess of ``s_dot`` on the grid (default: the sine-shaped profile).

        Returns
        -------
        PathSolution
            With IPOPT's status mapped by :func:`gtmodel.modeling.result.normalize_ipopt_status`.

        Raises
        ------
        InputError
            Invalid grid or initial guess.
        SolverError
            IPOPT could not be built.
        """
        gp = grid if isinstance(grid, GriddedPathProblem) else self.gridded(grid)
        N, R = gp.N, gp.m.shape[1]
        x0 = None
        if initial_s_dot is not None:
            x0 = np.asarray(initial_s_dot, dtype=float).reshape(-1)
            if x0.shape != (N + 1,) or not np.all(np.isfinite(x0)):
                raise InputError(f"initial_s_dot: expected {N + 1} finite values, got shape {x0.shape}")
            x0 = np.maximum(x0, 0.0)
        options = {
            "ipopt": {"tol": tol, "max_iter": max_iter, "print_level": 5 if verbose else 0, "sb": "yes", "constr_viol_tol": 1e-10, "acceptable_tol": 1e-8},
            "print_time": bool(verbose),
            "error_on_fail": False,
        }
        try:
            solver, _ = self._nlp_solver(N, R, gp.constrain_end, options)
        except RuntimeError as exc:
            raise SolverError(f"could not build the IPOPT solver: {exc}") from exc
        delta = np.diff(gp.s)
        pvec = np.concatenate([delta] + [np.asarray(X, dtype=float).ravel(order="F") for X in (gp.m, gp.c, gp.d, gp.g)])
        lo = np.tile(gp.lo, (N + 1, 1))
        hi = np.tile(gp.hi, (N + 1, 1))
        if not gp.constrain_end:
            lo[-1, gp.m[-1] != 0] = -_INF
            hi[-1, gp.m[-1] != 0] = _INF
        lbg = np.concatenate([np.zeros(N), lo.ravel(order="F")])
        ubg = np.concatenate([np.zeros(N), hi.ravel(order="F")])
        lbx = np.concatenate([np.zeros(N + 1), np.full(N, -_INF)])
        ubx = np.concatenate([np.where(gp.rest, 0.0, _INF), np.full(N, _INF)])
        if x0 is None:
            x0 = 0.05 * np.sqrt(np.sin(np.pi * gp.s))
            x0[gp.rest] = 0.0
        a0 = (x0[1:] ** 2 - x0[:-1] ** 2) / (2 * delta)
        t0 = _time.perf_counter()
        try:
            sol = solver(x0=np.concatenate([x0, a0]), p=pvec, lbg=lbg, ubg=ubg, lbx=lbx, ubx=ubx)
            error = None
        except RuntimeError as exc:
            error = str(exc)
        elapsed = _time.perf_counter() - t0
        stats = solver.stats()
        if error is not None:
            return _failed("error", error, self.path, gp.s, "ipopt", elapsed, 0, gp.setup_time)
        message = str(stats.get("return_status", "unknown"))
        status = normalize_ipopt_status(message)
        z = np.asarray(sol["x"], dtype=float).ravel()
        x, a = z[: N + 1], z[N + 1 :]
        if status not in ("optimal", "acceptable") or not np.all(np.isfinite(z)):
            return _failed(status if status != "optimal" else "error", f"IPOPT: {message}", self.path, gp.s, "ipopt", elapsed, int(stats.get("iter_count", 0)), gp.setup_time, {"stats": stats})
        return self._solution(gp, np.maximum(x, 0.0) ** 2, a, status, f"IPOPT: {message}", elapsed, int(stats.get("iter_count", 0)), "ipopt", {"stats": stats})


def solve_path_convex(
    path: Path,
    constraints: PathConstraints,
    robot: GantryTau3Dynamics | RobotParameters | str | None = None,
    grid: int | np.typing.ArrayLike = 100,
    configuration: int | Sequence[int] = 0,
    viscous_friction: bool = True,
    constrain_end: bool = True,
) -> PathSolution:
    """Time-optimal rest-to-rest motion along a path (Verscheure et al. (2009), TOPP-RA).

    Shorthand for ``PathConstrainedProblem(path, constraints, robot, configuration,
    viscous_friction, constrain_end).solve(grid)``; keep the problem object for sweeps.

    Parameters
    ----------
    path : Path
        The TCP path.
    constraints : PathConstraints
        The limits.
    robot : GantryTau3Dynamics or RobotParameters or str, optional
        The robot (needed for force and cart limits).
    grid : int or array_like, optional
        Number of grid points or the grid (see :meth:`PathConstrainedProblem.gridded`).
    configuration : int or sequence of int, optional
        IK configuration.
    viscous_friction : bool, optional
        Include viscous friction (default True).
    constrain_end : bool, optional
        Check the rows with ``s_ddot`` at the last grid point too (default True).

    Returns
    -------
    PathSolution
        The solution (see :meth:`PathConstrainedProblem.solve`).

    Raises
    ------
    InputError
        Invalid arguments.
    UnreachablePoseError
        The path leaves the workspace.
    """
    return PathConstrainedProblem(path, constraints, robot, configuration, viscous_friction, constrain_end).solve(grid)


# =============================================================================== collocation
def solve_path_collocation(
    path: Path,
    robot: GantryTau3Dynamics | RobotParameters | str,
    force_limit: np.typing.ArrayLike,
    w: float = 0.0,
    configuration: int | Sequence[int] = 0,
    friction: str = "exact",
    viscous_friction: bool = True,
    elements: int = 50,
    points: int = 3,
    scheme: str = "radau",
    final_time_guess: float = 1.0,
    final_time_bounds: tuple[float, float] = (0.05, 10.0),
    max_iter: int = 3000,
    tol: float = 1e-8,
    verbose: bool = False,
) -> PathSolution:
    """Path-constrained optimal motion by the projection method, solved by collocation.

    Dressler (2012), ch. 3.5 ("path constrained" row of Table 3.1): states ``s`` and
    ``s_dot`` (``0 <= s <= 1``, ``s_dot >= 0``), input ``s_ddot``, the forces ``tau`` of the
    inverse dynamics along the path bounded by ``force_limit``, free final time, rest at
    both ends, objective ``final_time + w sum_i integral tau_i^2 dt``. Declared with
    :class:`gtmodel.modeling.Model` and :class:`gtmodel.modeling.Optimization`, transcribed
    by :class:`gtmodel.modeling.CollocationTranscription` and solved with IPOPT; the initial
    guess is a trapezoidal velocity profile over ``final_time_guess``.

    Parameters
    ----------
    path : Path
        The TCP path; without corners (a single phase cannot stop at a corner).
    robot : GantryTau3Dynamics or RobotParameters or str
        The robot.
    force_limit : array_like, shape (3,)
        ``|tau_i| <= force_limit_i`` [N].
    w : float, optional
        Energy weight [1/(N^2)]; default 0 (minimum time).
    configuration : int or sequence of int, optional
        IK configuration.
    friction : {"exact", "tanh"}, optional
        ``"exact"`` (default): Coulomb friction ``f_c sign(q'(s))``, as the convex method;
        ``"tanh"``: the model's smooth ``tanh(q_dot / 0.01 m/s)`` (as the free-path problem).
    viscous_friction : bool, optional
        Include viscous friction (default True; only with ``friction="exact"``).
    elements, points, scheme : int, int, str, optional
        Collocation mesh (default 50 elements, 3 Radau points).
    final_time_guess : float, optional
        Initial guess of the duration [s].
    final_time_bounds : tuple of float, optional
        Bounds of the duration [s].
    max_iter : int, optional
        IPOPT iteration limit.
    tol : float, optional
        IPOPT tolerance.
    verbose : bool, optional
        Show IPOPT's log.

    Returns
    -------
    PathSolution
        ``method="collocation"``; ``s``, ``s_dot``, ``s_ddot`` and ``t`` on the collocation
        mesh; ``details["result"]`` is the :class:`gtmodel.modeling.OptimizationResult`.

    Raises
    ------
    InputError
        Invalid limits, weight, friction form, or a path with corners.
    UnreachablePoseError
        The path leaves the workspace.
    """
    if not isinstance(path, Path):
        raise InputError(f"path: expected a gtmodel.trajectory.path.Path, got {type(path).__name__}")
    if path.corners.size:
        raise InputError(f"path: the collocation method needs a path without corners (rest at s = {path.corners.tolist()}); use the convex method")
    if friction not in ("exact", "tanh"):
        raise InputError(f"friction: expected 'exact' or 'tanh', got {friction!r}")
    if not (isinstance(w, (int, float)) and np.isfinite(w) and w >= 0):
        raise InputError(f"w: expected a non-negative weight, got {w!r}")
    constraints = PathConstraints(force_limit=force_limit)
    problem = PathConstrainedProblem(path, constraints, robot, configuration, viscous_friction)
    dyn = problem.dynamics
    rows_f = _cached_rows_function(robot, dyn, ("force_limit",), problem.viscous_friction)
    model = Model(f"path_{dyn.parameters.name}")
    s = model.state("s", 1, lb=0.0, ub=1.0)
    sd = model.state("s_dot", 1, lb=0.0)
    u = model.input("s_ddot", 1)
    model.equation(model.der(s), sd)
    model.equation(model.der(sd), u)
    T, dT, ddT = path.casadi_expression(s)
    sg = ca.DM(problem.signs)
    if friction == "exact":
        m, c, d, g = rows_f(T, dT, ddT, sg)[:4]
        tau = m * u + c * sd**2 + d * sd + g
    else:
        smooth = GantryTau3Dynamics(dyn.parameters, friction="tanh", asymmetric=dyn.asymmetric, gravity=dyn.gravity)
        tau = smooth.inverse_dynamics_function(T, dT * sd, ddT * sd**2 + dT * u, sg)[0]
    tau = model.output("tau", tau)
    wp = model.parameter("w", float(w))
    opt = Optimization(model, final_time=final_time_guess, free_final_time=True, final_time_guess=final_time_guess, final_time_bounds=final_time_bounds)
    opt.set_objective(mayer=opt.final_time, lagrange=wp * ca.sumsqr(tau))
    F = constraints.force_limit
    opt.add_path_constraint(tau, lb=-F, ub=F, name="tau")
    opt.add_point_constraint(tau, at="start", lb=-F, ub=F, name="tau(start)")
    opt.add_point_constraint(ca.vertcat(s, sd), at="start", lb=0.0, ub=0.0, name="rest(start)")
    opt.add_point_constraint(ca.vertcat(s - 1.0, sd), at="final", lb=0.0, ub=0.0, name="rest(final)")

    def guess(t: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        return trapezoid_profile(np.zeros(3), np.array([1.0, 0.0, 0.0]), final_time_guess, np.atleast_1d(t))

    opt.set_initial_guess(s, lambda t: guess(t)[0][:, 0])
    opt.set_initial_guess(sd, lambda t: guess(t)[1][:, 0])
    opt.set_initial_guess(u, lambda t: guess(t)[2][:, 0])
    tr = CollocationTranscription(opt, elements=elements, points=points, scheme=scheme, verbose=verbose, solver_options={"max_iter": max_iter, "tol": tol})
    res = tr.solve()
    mesh_s = np.asarray(res.states["s"], dtype=float).reshape(-1)
    mesh_sd = np.asarray(res.states["s_dot"], dtype=float).reshape(-1)
    mesh_u = np.asarray(res.inputs["s_ddot"], dtype=float).reshape(-1)
    if res.status not in ("optimal", "acceptable"):
        return _failed(res.status, f"IPOPT: {res.message}", path, mesh_s, "collocation", res.solve_time, res.iterations, details={"result": res})

    def sampler(t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        smp = res.sample(t)
        ss = np.clip(np.asarray(smp["states"]["s"], dtype=float).reshape(-1), 0.0, 1.0)
        v = np.maximum(np.asarray(smp["states"]["s_dot"], dtype=float).reshape(-1), 0.0)
        return ss, v, np.asarray(smp["inputs"]["s_ddot"], dtype=float).reshape(-1)

    colloc = res.collocation
    breaks = colloc.t0 + (colloc.tf - colloc.t0) * np.arange(colloc.elements + 1) / colloc.elements
    if friction == "tanh":
        smooth_tau = _MapCache(ca.Function("tau", [s, sd, u], [tau]))

        def evaluator(ss: np.ndarray, v: np.ndarray, acc: np.ndarray) -> dict[str, np.ndarray]:
            out = problem._motion(ss, v, acc)
            out["tau"] = smooth_tau(ss.size, ss[None, :], v[None, :], acc[None, :])[0].T
            return out
    else:
        evaluator = problem._motion
    _log.info("path collocation: %s after %d iterations, final time %.5f s", res.status, res.iterations, res.final_time)
    return PathSolution(
        success=res.status == "optimal",
        status=res.status,
        message=f"IPOPT: {res.message}",
        final_time=float(res.final_time),
        s=mesh_s,
        s_dot=mesh_sd,
        s_ddot=mesh_u,
        t=np.asarray(res.t, dtype=float),
        solve_time=res.solve_time,
        iterations=res.iterations,
        method="collocation",
        path=path,
        max_constraint_violation=res.max_constraint_violation,
        sampler=sampler,
        evaluator=evaluator,
        breaks=breaks,
        details={"result": res, "transcription": tr},
    )
