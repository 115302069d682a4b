"""Choosing calibration poses before measuring (Dressler (2012), ch. 5.6, eqs. 5.9 and 5.14).

**Selection (5.9).** From ``N`` candidate poses (e.g. a workspace grid) keep ``n``: greedy
removal, one pose at a time, of the pose whose removal leaves the lowest condition number

    C_k = cond(J_s without the rows of pose k),

where ``J_s`` is the Jacobian of the closure residuals (eqs. 5.1-5.2) with respect to
the free parameters, evaluated at the nominal model on the candidate poses, with its
columns scaled to unit norm **once, over all candidates** (the scaling is then kept
fixed, so the ``C_k`` of successive steps are comparable).

Every step needs ``C_k`` for every remaining pose. With the Gram matrix
``G = J_s^T J_s`` (block-diagonal over the groups of arms that share no parameter),
removing pose ``k`` is the downdate ``G - A_k^T A_k`` by its rows ``A_k``. For blocks with
one residual per pose (every arm of the 3-link models) this is a rank-one downdate: with
``G = U diag(lambda) U^T`` and ``z = (U^T a_k)^2``, the extreme eigenvalues of the
downdated matrix are the roots of the secular equation ``sum_i z_i / (lambda_i - mu) = 1``
below ``lambda_1`` and in ``(lambda_(n-1), lambda_n]`` (Golub (1973), "Some modified
matrix eigenvalue problems"), found for all candidates at once by bracketed Newton
iterations (:data:`SECULAR_TOLERANCE`, :data:`SECULAR_MAX_ITER`). Blocks with several
residuals per pose use batched ``numpy.linalg.eigvalsh`` of the downdated matrices.
Measured (``python benchmarks/bench_calibration.py``, 2 shared cores, load ~3): L1
modified model (21 parameters, three 7-column blocks), 1347 grid candidates -> 200 in
2.4-6.4 s, condition number 212 -> 124 (200 random poses: ~205-220). The eigvalsh path
(ideal model, 15 parameters with 3 rows per pose) takes ~2 s for 400 -> 100.

**Acceptance (5.14).** A pose set is accepted if ``sigma_max^2 / sigma_min < C`` with
``C = ACCEPTANCE_LIMIT = 200``. The value is not scale-free; here it is computed on the
Jacobian of the pose set itself with unit-norm columns (dimensionless, independent of
the parameters' units and of the number of poses; ``sigma_max^2 <= n_parameters``).
Dressler does not state his scaling, so ``C = 200`` is the thesis' number applied to this
scaling, not a calibrated equivalent. Measured on the L1 grid (21 parameters): 236 for the
200 poses chosen from 1347, ~465 for 200 random ones, ~430 for all 1347 -- with this
scaling ``C = 200`` rejects even the best L1 pose set, so the simulated calibration
(:func:`simulate_calibration`) is the check that matters.

**Simulated calibration (ch. 5.6).** Before measuring, calibrate ``n_runs`` times on
synthetic measurements of a "true" model with the measuring device's noise, giving the
expected parameter spread and TCP error of the real run.
"""

from __future__ import annotations

import logging
import math
import time
from dataclasses import dataclass
from typing import Any, Sequence

import numpy as np
import scipy.linalg
import scipy.sparse
import scipy.sparse.csgraph

from gtmodel.calibration.kinematic import (
    DEFAULT_SOLVER,
    ParameterSelection,
    calibrate,
)
from gtmodel.calibration.evaluation import tcp_errors
from gtmodel.calibration.kinematic.shortcuts import _problem, _selection_of
from gtmodel.calibration.identifiability import RANK_TOLERANCE, analyze_jacobian, scale_columns
from gtmodel.errors import InputError, ModelError
from gtmodel.robots.closure import ClosureModel, rotation_to_quaternion, rotation_vector_to_rotation

__all__ = [
    "PoseSelectionResult",
    "SimulationResult",
    "select_poses",
    "select_rows",
    "acceptance_value",
    "scaled_condition_number",
    "simulate_calibration",
    "ACCEPTANCE_LIMIT",
    "SECULAR_TOLERANCE",
    "SECULAR_MAX_ITER",
]

_log = logging.getLogger("gtmodel")

#: Acceptance limit ``C`` of eq. 5.14, ``sigma_max^2 / sigma_min < C`` on the unit-column
#: scaled Jacobian of the pose set (dimensionless; see the module docstring).
ACCEPTANCE_LIMIT = 200.0
#: Relative tolerance of the secular-equation roots (extreme eigenvalues of a downdate).
SECULAR_TOLERANCE = 1e-13
#: Iteration limit of the bracketed Newton iterations on the secular equation (bisection
#: alone would need ~50 halvings for 1e-15; Newton typically needs 5-8).
SECULAR_MAX_ITER = 100
#: Candidates per batch of exact downdated eigenvalues (blocks with several rows per pose).
_EXACT_BLOCK = 32
#: Relative safety margin on the Rayleigh-quotient lower bound of ``C_k`` (rounding).
_BOUND_MARGIN = 1e-9
#: The Gram matrices of those blocks are downdated pose by pose and recomputed from the
#: remaining poses after this many removals (bounds the accumulated rounding).
_GRAM_REFRESH = 32


# ------------------------------------------------------------------ scaled Jacobians
def _as_rows(J: np.typing.ArrayLike) -> np.ndarray:
    Ja = np.asarray(J, dtype=float)
    if Ja.ndim == 3:
        Ja = Ja.reshape(-1, Ja.shape[2])
    if Ja.ndim != 2:
        raise InputError(f"J: expected shape (m, n) or (N, rows_per_pose, n), got {np.shape(J)}")
    return Ja


def scaled_condition_number(J: np.typing.ArrayLike) -> float:
    """Condition number ``sigma_max / sigma_min`` of a Jacobian with unit-norm columns.

    Parameters
    ----------
    J : array_like, shape (m, n) or (N, rows_per_pose, n)
        Residual Jacobian.

    Returns
    -------
    float
        Condition number (``inf`` if rank-deficient: ``sigma_min <= RANK_TOLERANCE sigma_max``).

    Raises
    ------
    InputError
        Wrong shape or non-finite entries.
    """
    Js, _ = scale_columns(_as_rows(J))
    s = np.linalg.svd(Js, compute_uv=False)
    if Js.shape[0] < Js.shape[1] or not s[-1] > RANK_TOLERANCE * s[0]:
        return math.inf
    return float(s[0] / s[-1])


def acceptance_value(J: np.typing.ArrayLike) -> float:
    """Acceptance value ``sigma_max^2 / sigma_min`` of a pose set, Dressler (2012), eq. 5.14.

    Computed on the Jacobian of the pose set with unit-norm columns (see the module
    docstring); compare with :data:`ACCEPTANCE_LIMIT`.

    Parameters
    ----------
    J : array_like, shape (m, n) or (N, rows_per_pose, n)
        Residual Jacobian of the pose set.

    Returns
    -------
    float
        ``sigma_max^2 / sigma_min`` (dimensionless; ``inf`` if rank-deficient:
        ``sigma_min <= RANK_TOLERANCE sigma_max``).

    Raises
    ------
    InputError
        Wrong shape or non-finite entries.
    """
    Js, _ = scale_columns(_as_rows(J))
    s = np.linalg.svd(Js, compute_uv=False)
    if Js.shape[0] < Js.shape[1] or not s[-1] > RANK_TOLERANCE * s[0]:
        return math.inf
    return float(s[0] ** 2 / s[-1])


# ------------------------------------------------------------------ secular equation
def _secular_roots(lam: np.ndarray, z: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Smallest and largest eigenvalue of ``diag(lam_k) - b_k b_k^T`` for many ``k`` (``z = b^2``).

    Roots of ``phi(mu) = sum_i z_i / (lam_i - mu) = 1``: the smallest in
    ``[lam_1 - |b|^2, lam_1)``, the largest in ``(lam_(n-1), lam_n)``. ``phi - 1`` is
    increasing on both intervals (its sign keeps the bracket); the steps are Newton steps
    on ``1/phi - 1``, which is nearly linear next to the pole (``1/phi ~ (lam - mu)/z``)
    and, for the smallest root, concave, so Newton from the pole side converges
    monotonically; a step leaving the bracket is replaced by bisection. Both roots of all
    rows are iterated together (one set of array operations per iteration).

    Parameters: ``lam`` (n,) or (K, n), ascending per row; ``z`` (K, n).
    Returns two arrays (K,).
    """
    K, n = z.shape
    lam = np.broadcast_to(np.asarray(lam, dtype=float), (K, n))
    if n == 1:
        mu = lam[:, 0] - z[:, 0]
        return mu, mu
    top = np.maximum(np.abs(lam[:, -1]), 1e-300)
    # a zero component would remove the pole; a negligible positive one keeps the formulas valid
    z = np.maximum(z, 1e-30 * top[:, None])
    L = np.concatenate([lam, lam])
    Z = np.concatenate([z, z])
    floor = np.concatenate([top, top]) * 1e-6  # absolute floor of the relative tolerance
    lo = np.concatenate([lam[:, 0] - z.sum(axis=1), lam[:, -2]])
    hi = np.concatenate([lam[:, 0], lam[:, -1]])
    # first steps from the poles: lam_1 - z_1 and lam_n - z_n
    mu = np.clip(np.concatenate([lam[:, 0] - z[:, 0], lam[:, -1] - z[:, -1]]), lo, hi)
    done = ~(hi > lo)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        for _ in range(SECULAR_MAX_ITER):
            # all rows each iteration (cheaper than compacting the active ones)
            d = L - mu[:, None]
            t = Z / d
            phi = t.sum(axis=1)
            dphi = (t / d).sum(axis=1)
            newton = mu + phi * (1.0 - phi) / dphi
            lo = np.where(phi < 1.0, mu, lo)
            hi = np.where(phi > 1.0, mu, hi)
            ok = np.isfinite(newton) & (newton >= lo) & (newton <= hi)
            new = np.where(ok, newton, 0.5 * (lo + hi))
            tol = SECULAR_TOLERANCE * np.maximum(np.abs(new), floor)
            conv = (ok & (np.abs(new - mu) <= tol)) | (hi - lo <= tol)
            mu = np.where(done, mu, new)
            done |= conv
            if done.all():
                break
    return mu[:K], mu[K:]


def _blocks(J3: np.ndarray) -> list[tuple[np.ndarray, np.ndarray]]:
    """Column blocks sharing no row, with the rows (within a pose) each block uses."""
    N, r, n = J3.shape
    nz = scipy.sparse.csr_matrix((J3.reshape(-1, n) != 0).astype(float))
    adj = (nz.T @ nz) > 0
    n_comp, labels = scipy.sparse.csgraph.connected_components(adj, directed=False)
    out = []
    for c in range(n_comp):
        cols = np.flatnonzero(labels == c)
        rows = np.flatnonzero(np.any(J3[:, :, cols] != 0, axis=(0, 2)))
        out.append((cols, rows))
    return out


def _gram(A: np.ndarray) -> np.ndarray:
    """``sum_k A_k^T A_k`` of a stack (K, r, m) (tensordot: BLAS, unlike einsum here)."""
    return np.tensordot(A, A, axes=([0, 1], [0, 1]))


# ------------------------------------------------------------------ greedy selection
@dataclass
class PoseSelectionResult:
    """Result of a greedy pose selection (Dressler (2012), eq. 5.9).

    Parameters
    ----------
    indices : numpy.ndarray of int, shape (n,)
        Indices of the kept poses into the candidates, ascending.
    removed : numpy.ndarray of int, shape (N - n,)
        Candidates in the order they were removed.
    history : numpy.ndarray, shape (N - n,)
        Condition number of the scaled Jacobian after each removal (candidate scaling).
    condition_number : float
        Condition number of the kept poses' Jacobian with the candidate scaling (the last
        entry of ``history``, recomputed by SVD).
    initial_condition_number : float
        Condition number of all candidates.
    acceptance : float
        ``sigma_max^2 / sigma_min`` of the kept poses (eq. 5.14, own unit-column scaling).
    accepted : bool
        ``acceptance < acceptance_limit`` (the limit given to :func:`select_rows`).
    names : tuple of str
        Parameter (variable) names of the Jacobian columns.
    time : float
        Wall time of the greedy removal [s].
    """

    indices: np.ndarray
    removed: np.ndarray
    history: np.ndarray
    condition_number: float
    initial_condition_number: float
    acceptance: float
    accepted: bool
    names: tuple[str, ...]
    time: float


def select_rows(
    J: np.typing.ArrayLike, n: int, names: Sequence[str] | None = None, acceptance_limit: float = ACCEPTANCE_LIMIT
) -> PoseSelectionResult:
    """Greedy pose selection on a per-pose Jacobian (Dressler (2012), eq. 5.9).

    Removes, one at a time, the pose whose removal leaves the lowest condition number of
    the column-scaled Jacobian until ``n`` poses remain (method in the module docstring).

    Parameters
    ----------
    J : array_like, shape (N, rows_per_pose, n_parameters)
        Residual Jacobian of each candidate pose.
    n : int
        Number of poses to keep, ``1 <= n <= N``, with ``n * rows_per_pose`` at least the
        number of parameters.
    names : sequence of str, optional
        Column names for the result.
    acceptance_limit : float, optional
        Limit ``C`` of eq. 5.14 (default :data:`ACCEPTANCE_LIMIT`).

    Returns
    -------
    PoseSelectionResult

    Raises
    ------
    InputError
        Wrong shape, non-finite entries, or ``n`` out of range.
    ModelError
        If the Jacobian of all candidates is rank-deficient (no pose subset can be
        better); the message lists the non-identifiable parameters.
    """
    J3 = np.asarray(J, dtype=float)
    if J3.ndim != 3:
        raise InputError(f"J: expected shape (N, rows_per_pose, n_parameters), got {J3.shape}")
    N, r, p = J3.shape
    if not np.all(np.isfinite(J3)):
        raise InputError("J: non-finite entries")
    if not (isinstance(n, (int, np.integer)) and 1 <= n <= N):
        raise InputError(f"n: expected an integer in 1..{N} (the number of candidates), got {n!r}")
    if n * r < p:
        raise InputError(f"n: {n} poses give {n * r} residuals for {p} parameters; keep at least {-(-p // r)}")
    names = tuple(names) if names is not None else tuple(f"p{i}" for i in range(p))
    flat = J3.reshape(-1, p)
    rep = analyze_jacobian(flat, names)
    if not rep.full_rank:
        raise ModelError(f"pose selection: the candidate poses do not identify every parameter: {rep.describe()}")
    _, norms = scale_columns(flat)
    Js = J3 / norms
    # blocks with one residual per pose and the same size are stacked: (n_blocks, N, size)
    stacks: dict[int, list[np.ndarray]] = {}
    general: list[np.ndarray] = []
    for cols, rows in _blocks(Js):
        Ab = Js[:, rows][:, :, cols]
        if rows.size == 1:
            stacks.setdefault(cols.size, []).append(Ab[:, 0, :])
        else:
            general.append(Ab)
    one = [np.stack(v) for v in stacks.values()]

    t0 = time.perf_counter()
    alive = np.ones(N, dtype=bool)
    removed: list[int] = []
    history: list[float] = []
    n_exact = 0
    G_general = [_gram(Ab) for Ab in general]
    while alive.sum() > n:
        idx = np.flatnonzero(alive)
        K = idx.size
        mu_min = np.full(K, np.inf)
        mu_max = np.zeros(K)
        for S in one:  # rank-one downdates, secular equation (exact, all candidates)
            Sk = S[:, idx]  # (b, K, m)
            G = np.matmul(Sk.transpose(0, 2, 1), Sk)
            lam, U = np.linalg.eigh(G)
            z = np.matmul(Sk, U) ** 2
            b, _, m = z.shape
            lo, hi = _secular_roots(np.repeat(lam, K, axis=0), z.reshape(b * K, m))
            mu_min = np.minimum(mu_min, lo.reshape(b, K).min(axis=0))
            mu_max = np.maximum(mu_max, hi.reshape(b, K).max(axis=0))
        if not general:
            with np.errstate(divide="ignore", invalid="ignore"):
                cond = np.where(mu_min > 0, np.sqrt(mu_max / mu_min), np.inf)
            k = int(np.argmin(cond))
        else:
            # several rows per pose: Rayleigh quotients at the extreme eigenvectors of G bound
            # the downdated extremes (mu_min <= lam_1 - |A u_1|^2, mu_max >= lam_n - |A u_n|^2),
            # hence cond_k from below; exact eigenvalues only for the candidates whose bound
            # is below the best exact value found (the same argmin as evaluating all)
            ub_min, lb_max = mu_min.copy(), mu_max.copy()
            Gs = []
            for Ab, G in zip(general, G_general):
                Ak = Ab[idx]
                # LAPACK's MRRR driver: numpy's eigh (divide and conquer) is up to 30x slower
                # on these small matrices when threaded BLAS competes for busy cores
                lam, U = scipy.linalg.eigh(G, driver="evr")
                ub_min = np.minimum(ub_min, lam[0] - np.sum((Ak @ U[:, 0]) ** 2, axis=1))
                lb_max = np.maximum(lb_max, lam[-1] - np.sum((Ak @ U[:, -1]) ** 2, axis=1))
                Gs.append((Ak, G))
            with np.errstate(divide="ignore", invalid="ignore"):
                lb = np.where(ub_min > 0, np.sqrt(np.maximum(lb_max, 0.0) / ub_min), np.inf) * (1.0 - _BOUND_MARGIN)
            order = np.argsort(lb, kind="stable")
            best, k = math.inf, -1
            start = 0
            while start < K:
                chunk = order[start:start + _EXACT_BLOCK]
                if k >= 0 and best < lb[chunk[0]]:
                    break
                lo_c, hi_c = mu_min[chunk].copy(), mu_max[chunk].copy()
                for Ak, G in Gs:
                    Ac = Ak[chunk]
                    ev = np.linalg.eigvalsh(G[None] - np.matmul(Ac.transpose(0, 2, 1), Ac))
                    lo_c = np.minimum(lo_c, ev[:, 0])
                    hi_c = np.maximum(hi_c, ev[:, -1])
                n_exact += chunk.size
                with np.errstate(divide="ignore", invalid="ignore"):
                    c = np.where(lo_c > 0, np.sqrt(hi_c / lo_c), np.inf)
                cmin = c.min()
                j = int(chunk[c == cmin].min())  # lowest value, then lowest index (as argmin)
                if k < 0 or cmin < best or (cmin == best and j < k):
                    best, k = float(cmin), j
                start += chunk.size
            cond = np.full(K, np.inf)
            cond[k] = best
        alive[idx[k]] = False
        removed.append(int(idx[k]))
        # Gram matrices of the remaining poses: downdated, recomputed now and then (rounding)
        if len(removed) % _GRAM_REFRESH == 0:
            G_general = [_gram(Ab[alive]) for Ab in general]
        else:
            for G, Ab in zip(G_general, general):
                G -= Ab[idx[k]].T @ Ab[idx[k]]
        history.append(float(cond[k]))
    elapsed = time.perf_counter() - t0
    keep = np.flatnonzero(alive)
    s = np.linalg.svd(Js[keep].reshape(-1, p), compute_uv=False)
    cond_keep = float(s[0] / s[-1]) if s[-1] > 0 else math.inf
    s_all = np.linalg.svd(Js.reshape(-1, p), compute_uv=False)
    acc = acceptance_value(J3[keep])
    _log.info(
        "pose selection: %d -> %d poses in %.2f s (%d exact downdates), cond %.4g -> %.4g",
        N, n, elapsed, n_exact, s_all[0] / s_all[-1], cond_keep,
    )
    return PoseSelectionResult(
        indices=keep,
        removed=np.array(removed, dtype=int),
        history=np.array(history),
        condition_number=cond_keep,
        initial_condition_number=float(s_all[0] / s_all[-1]),
        acceptance=acc,
        accepted=bool(acc < acceptance_limit),
        names=names,
        time=elapsed,
    )


def _planned_poses(model: ClosureModel, q: np.ndarray, T: Any, quat: Any) -> tuple[np.ndarray, np.ndarray | None]:
    if T is None:
        Tf, Rf = model.fk(q)
        T = np.atleast_2d(Tf)
        if model.orientation and quat is None:
            quat = rotation_to_quaternion(np.asarray(Rf).reshape(-1, 3, 3))
    return np.asarray(T, dtype=float), quat


def select_poses(
    model: ClosureModel,
    q: np.typing.ArrayLike,
    n: int,
    T: np.typing.ArrayLike | None = None,
    quat: np.typing.ArrayLike | None = None,
    *,
    selection: ParameterSelection | None = None,
    free: str | Sequence[str] | None = None,
    fixed: str | Sequence[str] | None = None,
    ties: Any = None,
    acceptance_limit: float = ACCEPTANCE_LIMIT,
) -> PoseSelectionResult:
    """Choose ``n`` of the candidate poses ``q`` for calibrating ``model`` (eq. 5.9).

    The Jacobian of the closure residuals with respect to the free parameters is
    evaluated at the model's values on the planned poses, then :func:`select_rows`.

    Parameters
    ----------
    model : ClosureModel
        Nominal model.
    q : array_like, shape (N, n_q)
        Candidate actuator values [m, rad] (e.g. the IK of a workspace grid).
    n : int
        Number of poses to keep.
    T : array_like, shape (N, 3), optional
        Planned TCP positions [m]; default: the model's FK of ``q``.
    quat : array_like, shape (N, 4), optional
        Planned orientations (models with orientation); default: from the FK.
    selection : ParameterSelection, optional
        Free/fixed/tied parameters (default: all free).
    free : str or sequence of str, optional
        Free parameter names or patterns.
    fixed : str or sequence of str, optional
        Fixed parameter names or patterns.
    ties : str or sequence or mapping, optional
        ``"target = source"`` ties.
    acceptance_limit : float, optional
        Limit ``C`` of eq. 5.14 (default :data:`ACCEPTANCE_LIMIT`).

    Returns
    -------
    PoseSelectionResult

    Raises
    ------
    InputError
        Bad shapes, values, names or ``n``.
    ModelError
        If the candidates do not identify every free parameter.
    UnreachablePoseError
        If the model's FK fails for some candidate (when ``T`` is not given).
    """
    qa = np.atleast_2d(np.asarray(q, dtype=float))
    sel = _selection_of(selection, free, fixed, ties)
    problem = _problem(model, sel)
    Ta, qu = _planned_poses(model, qa, T, quat)
    _, J, names = problem.jacobian(model.parameter_vector(), qa, Ta, qu)
    return select_rows(J, n, names, acceptance_limit)


# ------------------------------------------------------------------ simulated calibration
@dataclass
class SimulationResult:
    """Outcome of simulated calibrations (Dressler (2012), ch. 5.6).

    Parameters
    ----------
    names : tuple of str
        Parameter names.
    true_parameters : numpy.ndarray, shape (n_parameters,)
        Parameters of the true model.
    parameters : numpy.ndarray, shape (n_runs, n_parameters)
        Calibrated parameters of each run (measurement frame = true model's frame).
    parameter_std : numpy.ndarray, shape (n_parameters,)
        Spread (sample standard deviation) of the calibrated parameters over the runs.
    parameter_bias : numpy.ndarray, shape (n_parameters,)
        Mean calibrated minus true parameters.
    predicted_std : numpy.ndarray, shape (n_parameters,)
        Mean of the standard deviations each calibration reported.
    tcp_error_mean : numpy.ndarray, shape (n_runs,)
        Mean TCP error ``||fk_cal(q) - fk_true(q)||`` over the evaluation poses, per run [m].
    tcp_error_max : numpy.ndarray, shape (n_runs,)
        Maximum TCP error per run [m].
    statuses : tuple of str
        Calibration status of each run.
    """

    names: tuple[str, ...]
    true_parameters: np.ndarray
    parameters: np.ndarray
    parameter_std: np.ndarray
    parameter_bias: np.ndarray
    predicted_std: np.ndarray
    tcp_error_mean: np.ndarray
    tcp_error_max: np.ndarray
    statuses: tuple[str, ...]


def simulate_calibration(
    true_model: ClosureModel,
    nominal_model: ClosureModel,
    q: np.typing.ArrayLike,
    noise_sigma: float,
    n_runs: int,
    seed: int,
    *,
    q_eval: np.typing.ArrayLike | None = None,
    orientation_noise: float = 0.0,
    selection: ParameterSelection | None = None,
    free: str | Sequence[str] | None = None,
    fixed: str | Sequence[str] | None = None,
    ties: Any = None,
    solver: str = DEFAULT_SOLVER,
) -> SimulationResult:
    """Expected parameter spread and TCP error of a calibration before measuring (ch. 5.6).

    Each run measures the true model's FK positions at ``q`` with independent Gaussian
    noise (``noise_sigma`` per coordinate) and calibrates ``nominal_model`` on them.

    Parameters
    ----------
    true_model : ClosureModel
        The "real" robot (its frame is the measurement frame).
    nominal_model : ClosureModel
        Start model of the calibration (same structure as ``true_model``).
    q : array_like, shape (N, n_q)
        Planned calibration poses [m, rad].
    noise_sigma : float
        Measurement noise per coordinate [m] (laser tracker ~10e-6, stereo vision ~1.7e-3).
    n_runs : int
        Number of simulated calibrations.
    seed : int
        Seed of the noise generator (``numpy.random.default_rng``).
    q_eval : array_like, shape (M, n_q), optional
        Poses where the TCP error is evaluated (default ``q``).
    orientation_noise : float, optional
        Orientation noise [rad] (models with orientation): a random rotation vector with
        this standard deviation per component.
    selection : ParameterSelection, optional
        Free/fixed/tied parameters.
    free : str or sequence of str, optional
        Free parameter names or patterns.
    fixed : str or sequence of str, optional
        Fixed parameter names or patterns.
    ties : str or sequence or mapping, optional
        ``"target = source"`` ties.
    solver : str, optional
        Calibration solver.

    Returns
    -------
    SimulationResult

    Raises
    ------
    InputError
        Bad arguments (negative noise, ``n_runs < 2``, mismatched models).
    UnreachablePoseError
        If the true model's FK fails for a pose.
    """
    if not (np.isfinite(noise_sigma) and noise_sigma >= 0):
        raise InputError(f"noise_sigma: expected a non-negative noise level in m, got {noise_sigma!r}")
    if not (isinstance(n_runs, (int, np.integer)) and n_runs >= 2):
        raise InputError(f"n_runs: expected an integer >= 2, got {n_runs!r}")
    if tuple(true_model.parameter_names()) != tuple(nominal_model.parameter_names()):
        raise InputError("true_model and nominal_model must have the same parameters")
    if not (np.isfinite(orientation_noise) and orientation_noise >= 0):
        raise InputError(f"orientation_noise: expected a non-negative angle in rad, got {orientation_noise!r}")
    sel = _selection_of(selection, free, fixed, ties)
    qa = np.atleast_2d(np.asarray(q, dtype=float))
    qe = qa if q_eval is None else np.atleast_2d(np.asarray(q_eval, dtype=float))
    T_true, R_true = true_model.fk(qa)
    T_true = np.atleast_2d(T_true)
    T_eval = np.atleast_2d(true_model.fk(qe)[0])
    rng = np.random.default_rng(seed)
    names = tuple(true_model.parameter_names())
    P = np.zeros((n_runs, len(names)))
    S = np.zeros((n_runs, len(names)))
    e_mean = np.zeros(n_runs)
    e_max = np.zeros(n_runs)
    statuses = []
    for k in range(n_runs):
        Tm = T_true + noise_sigma * rng.standard_normal(T_true.shape)
        quat = None
        if nominal_model.orientation:
            Rm = np.asarray(R_true).reshape(-1, 3, 3)
            if orientation_noise > 0:
                Rm = np.array([rotation_vector_to_rotation(orientation_noise * rng.standard_normal(3)) @ R for R in Rm])
            quat = rotation_to_quaternion(Rm)
        res = calibrate(nominal_model, qa, Tm, quat, selection=sel, solver=solver)
        statuses.append(res.status)
        P[k] = res.parameter_vector
        S[k] = np.array(list(res.std.values()))
        e = tcp_errors(res.model, qe, T_eval)
        e_mean[k], e_max[k] = float(e.mean()), float(e.max())
    p_true = true_model.parameter_vector()
    return SimulationResult(
        names=names,
        true_parameters=p_true,
        parameters=P,
        parameter_std=P.std(axis=0, ddof=1),
        parameter_bias=P.mean(axis=0) - p_true,
        predicted_std=S.mean(axis=0),
        tcp_error_mean=e_mean,
        tcp_error_max=e_max,
        statuses=tuple(statuses),
    )
