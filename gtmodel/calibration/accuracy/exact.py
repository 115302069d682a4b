"""The exact worst case of the TCP error as a CasADi NLP, and a Monte-Carlo estimate.

Beyond Dressler (2012), Appendix A: instead of approximating the error set ``S^T`` by
ellipsoid shells or a parallelepiped, the largest TCP deviation is found by maximising::

    || T(A^n + dA, L + dL) - T^n ||^2   over   dA_i in E_i^A,  |dL_i| <= l_i

where ``T(A, L)`` is the 3-link model's forward kinematics from the joint points (the
trilateration of :func:`~gtmodel.robots.kinematic_expressions.fk_expression`, eq. 4.9).
The joint points are parametrised by the unit ball, ``dA_i = R_i diag(r_i) w_i`` with
``|w_i| <= 1``, the lengths by ``dL_i = l_i z_i`` with ``|z_i| <= 1``. The problem is
non-convex (a maximum); IPOPT is started from the best corners of the geometric method and
from random points, and the best local optimum is kept. The same CasADi graph, mapped over
samples, gives the Monte-Carlo distribution (uniform in the ellipsoids and intervals).
"""

from __future__ import annotations

import logging
from dataclasses import dataclass
from functools import lru_cache

import casadi as ca
import numpy as np

from gtmodel.calibration.accuracy.geometric import CORNER_SIGNS, _fk_points_function, fk_branch
from gtmodel.calibration.accuracy.tolerances import NominalPoses, Tolerances
from gtmodel.robots.mapped import MappedFunction
from gtmodel.status import Status

__all__ = ["WorstCase", "MonteCarlo", "worst_case", "monte_carlo"]

_log = logging.getLogger("gtmodel")

#: IPOPT options of the worst-case NLP (objective scaled to order 1).
_IPOPT = {"ipopt.print_level": 0, "print_time": False, "ipopt.sb": "yes", "ipopt.tol": 1e-12,
          "ipopt.max_iter": 200, "ipopt.acceptable_tol": 1e-9}


@lru_cache(maxsize=1)
def _deviation_function() -> ca.Function:
    """``deviation(w[9], z[3], p) -> dT[3]``, the TCP deviation for unit-ball coordinates.

    ``p`` stacks ``A^n`` (9, row-major per arm), ``L`` (3), ``v`` (9), the branch (1),
    ``T^n`` (3), the maps ``R_i diag(r_i)`` (27, column-major per arm) and ``l`` (3).
    """
    w = ca.SX.sym("w", 9)
    z = ca.SX.sym("z", 3)
    p = ca.SX.sym("p", 55)
    An = ca.reshape(p[0:9], 3, 3).T
    L = p[9:12]
    v = ca.reshape(p[12:21], 3, 3).T
    branch = p[21]
    Tn = p[22:25]
    rows = []
    for i in range(3):
        Mi = ca.reshape(p[25 + 9 * i: 34 + 9 * i], 3, 3)
        rows.append((An[i, :].T + Mi @ w[3 * i: 3 * i + 3]).T)
    A = ca.vertcat(*rows)
    T = _fk_points_function()(A, L + p[52:55] * z, v, branch)
    return ca.Function("deviation", [w, z, p], [T - Tn], ["w", "z", "p"], ["dT"])


@lru_cache(maxsize=1)
def _deviation_mapped() -> MappedFunction:
    """:func:`_deviation_function` over samples (maps cached per sample count)."""
    return MappedFunction(_deviation_function())


@lru_cache(maxsize=1)
def _solver() -> ca.Function:
    """The worst-case NLP: max |dT|^2 / scale^2 over the unit balls and intervals."""
    x = ca.SX.sym("x", 12)
    p = ca.SX.sym("p", 56)
    dT = _deviation_function()(x[:9], x[9:], p[:55])
    f = -ca.dot(dT, dT) / p[55] ** 2
    g = ca.vertcat(*[ca.dot(x[3 * i: 3 * i + 3], x[3 * i: 3 * i + 3]) for i in range(3)])
    return ca.nlpsol("worst_case", "ipopt", {"x": x, "p": p, "f": f, "g": g}, _IPOPT)


def _parameters(nominal: NominalPoses, k: int, tol: Tolerances, branch: float) -> np.ndarray:
    maps = np.concatenate([(tol.axes[i] * tol.semi_axes[i][None, :]).reshape(-1, order="F") for i in range(3)])
    return np.concatenate([nominal.A[k].reshape(-1), nominal.L, nominal.v.reshape(-1), [branch], nominal.T[k], maps, tol.link])


def corner_starts(nominal: NominalPoses, k: int, tol: Tolerances) -> np.ndarray:
    """The eight corners of the linearised error set in the NLP's unit-ball coordinates.

    Corner ``s``: ``dA_i = s_i M_i u_i / sqrt(u_i^T M_i u_i)`` (the point of ``E_i^A``
    farthest along link ``i``), ``dL_i = s_i l_i``.

    Parameters
    ----------
    nominal : NominalPoses
        The nominal geometry.
    k : int
        The pose.
    tol : Tolerances
        The error bounds.

    Returns
    -------
    numpy.ndarray, shape (8, 12)
        ``(w, z)`` per corner, ordered as :data:`~gtmodel.calibration.accuracy.geometric.CORNER_SIGNS`.
    """
    out = np.zeros((8, 12))
    for i in range(3):
        # w = diag(r) R^T u / |diag(r) R^T u|
        wi = tol.semi_axes[i] * (tol.axes[i].T @ nominal.u[k, i])
        wi = wi / np.linalg.norm(wi)
        out[:, 3 * i: 3 * i + 3] = CORNER_SIGNS[:, i: i + 1] * wi[None]
        out[:, 9 + i] = CORNER_SIGNS[:, i] if tol.link[i] > 0 else 0.0
    return out


@dataclass(frozen=True)
class WorstCase:
    """The exact worst case at one pose.

    Parameters
    ----------
    error : float
        Largest TCP deviation found [m].
    deviation : numpy.ndarray, shape (3,)
        The deviation vector [m].
    joint_offsets : numpy.ndarray, shape (3, 3)
        Row i: the worst ``dA_i`` [m].
    length_offsets : numpy.ndarray, shape (3,)
        The worst ``dL_i`` [m].
    best_corner : float
        Largest deviation at a corner start (before IPOPT) [m].
    starts : int
        IPOPT starts.
    converged : int
        Starts IPOPT solved (``Solve_Succeeded`` or acceptable).
    status : str
        ``"optimal"`` if the best start converged, ``"max_iterations"`` or ``"error"``.
    """

    error: float
    deviation: np.ndarray
    joint_offsets: np.ndarray
    length_offsets: np.ndarray
    best_corner: float
    starts: int
    converged: int
    status: str


def worst_case(nominal: NominalPoses, k: int, tol: Tolerances, corner_starts_used: int = 2, random_starts: int = 2,
               seed: int = 0) -> WorstCase:
    """The exact worst-case TCP deviation at pose ``k`` by IPOPT from several starts.

    Parameters
    ----------
    nominal : NominalPoses
        The nominal geometry.
    k : int
        The pose.
    tol : Tolerances
        The error bounds.
    corner_starts_used : int, optional
        IPOPT starts from the best corners of the linearised set (1-8).
    random_starts : int, optional
        Further starts, uniform in the balls and intervals.
    seed : int, optional
        Seed of the random starts.

    Returns
    -------
    WorstCase
    """
    dev = _deviation_function()
    solver = _solver()
    branch = fk_branch(NominalPoses(nominal.T[k:k + 1], nominal.q[k:k + 1], nominal.A[k:k + 1], nominal.u[k:k + 1], nominal.L, nominal.v))[0]
    p = _parameters(nominal, k, tol, branch)
    scale = tol.scale
    corners = corner_starts(nominal, k, tol)
    values = np.linalg.norm(_deviation_mapped()(corners[:, :9].T.copy(), corners[:, 9:].T.copy(), p, n=8)[0], axis=0)
    order = np.argsort(-values)
    rng = np.random.default_rng(seed)
    starts = [corners[j] for j in order[:max(1, min(8, corner_starts_used))]]
    for _ in range(random_starts):
        w = _ball(rng, 3).reshape(-1)
        starts.append(np.concatenate([w, rng.uniform(-1, 1, 3) * (tol.link > 0)]))
    best = None
    converged = 0
    lbx = np.concatenate([np.full(9, -1.0), -(tol.link > 0).astype(float)])
    ubx = -lbx
    for x0 in starts:
        sol = solver(x0=x0, p=np.append(p, scale), lbx=lbx, ubx=ubx, lbg=-np.inf, ubg=1.0)
        stats = solver.stats()
        ok = stats["return_status"] in ("Solve_Succeeded", "Solved_To_Acceptable_Level")
        converged += ok
        x = np.array(sol["x"]).ravel()
        err = float(np.linalg.norm(np.array(dev(x[:9], x[9:], p)).ravel()))
        if best is None or err > best[0]:
            best = (err, x, ok, stats["return_status"])
    err, x, ok, rs = best
    status = Status.OPTIMAL.value if ok else (Status.MAX_ITERATIONS.value if rs == "Maximum_Iterations_Exceeded" else Status.ERROR.value)
    offsets = np.array([(tol.axes[i] * tol.semi_axes[i][None, :]) @ x[3 * i: 3 * i + 3] for i in range(3)])
    return WorstCase(err, np.array(dev(x[:9], x[9:], p)).ravel(), offsets, tol.link * x[9:], float(values.max()), len(starts), converged, status)


def _ball(rng: np.random.Generator, n: int) -> np.ndarray:
    """``n`` points uniform in the unit ball, shape (n, 3)."""
    d = rng.normal(size=(n, 3))
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    return d * rng.uniform(size=(n, 1)) ** (1.0 / 3.0)


@dataclass(frozen=True)
class MonteCarlo:
    """Monte-Carlo distribution of the TCP deviation at one pose.

    Parameters
    ----------
    errors : numpy.ndarray, shape (n,)
        Deviation of every sample [m].
    deviations : numpy.ndarray, shape (n, 3)
        The deviation vectors [m].
    """

    errors: np.ndarray
    deviations: np.ndarray

    @property
    def max(self) -> float:
        """Largest sampled deviation [m]."""
        return float(self.errors.max())

    @property
    def mean(self) -> float:
        """Mean deviation [m]."""
        return float(self.errors.mean())

    def quantile(self, level: float) -> float:
        """A quantile of the deviation [m].

        Parameters
        ----------
        level : float
            In [0, 1].

        Returns
        -------
        float
        """
        return float(np.quantile(self.errors, level))


def monte_carlo(nominal: NominalPoses, k: int, tol: Tolerances, samples: int = 20000, seed: int = 0) -> MonteCarlo:
    """TCP deviations of joint points and lengths drawn uniformly in their bounds.

    Parameters
    ----------
    nominal : NominalPoses
        The nominal geometry.
    k : int
        The pose.
    tol : Tolerances
        The error bounds.
    samples : int, optional
        Number of samples.
    seed : int, optional
        Random seed.

    Returns
    -------
    MonteCarlo
    """
    rng = np.random.default_rng(seed)
    branch = fk_branch(NominalPoses(nominal.T[k:k + 1], nominal.q[k:k + 1], nominal.A[k:k + 1], nominal.u[k:k + 1], nominal.L, nominal.v))[0]
    p = _parameters(nominal, k, tol, branch)
    w = _ball(rng, 3 * samples).reshape(samples, 9)
    z = rng.uniform(-1.0, 1.0, size=(samples, 3))
    dT = _deviation_mapped()(w.T.copy(), z.T.copy(), p, n=samples)[0]
    return MonteCarlo(np.linalg.norm(dT, axis=0), dT.T.copy())
