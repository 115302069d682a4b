"""Weighted least-squares identification of masses and friction, with statistics and base parameters.

Dressler (2012), ch. 6.2, Table 6.3: ``min || W (Y theta + tau0 - tau) ||^2`` over the
rows with a well-defined friction sign; standard deviations, condition numbers, the
base (identifiable) parameters and the near-dependencies behind a large std.

Why the link masses are poorly identifiable (ch. 6.2): a link cluster's mass sits at the
link midpoint ``(T + A_i)/2``, so its kinetic energy is that of a quarter of its mass in
the plate, a quarter in the cart and a cross term, and its potential energy that of half
its mass in the plate (eq. 6.7: ``m_p + sum m_a/2`` and ``m_c,i + m_a,i/4``). The column of
``m_a,i`` in ``Y`` is therefore nearly ``1/2 (m_p column) + 1/4 (m_c,i column)``; the
column-pivoted QR of :func:`gtmodel.calibration.identifiability.analyze_jacobian` puts
the ``m_a`` last, with the tiny ``|R_ii|`` and the dependency coefficients reported in
:attr:`DynamicIdentificationResult.near_dependencies`.
"""

from __future__ import annotations

import dataclasses
import logging
import math
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Sequence

import numpy as np
import numpy.typing  # noqa: F401  (np.typing in annotations)
import scipy.linalg

from gtmodel.calibration.identifiability import IdentifiabilityReport, analyze_jacobian, observability_indices
from gtmodel.calibration.identification.regressor import DynamicRegressor
from gtmodel.calibration.identification.signals import DynamicSamples
from gtmodel.calibration.identification.variants import TABLE_6_3_COLUMNS, ModelVariant, _unit, get_variant
from gtmodel.errors import InputError, ModelError
from gtmodel.robots.parameters import RobotParameters
from gtmodel.status import Status, StatusResult

__all__ = ["DynamicIdentificationResult", "identify_dynamics", "column_dependency", "SPEED_BINS"]

_log = logging.getLogger("gtmodel")

#: Edges [m/s] of the speed bins of the residual report (Stribeck effect at low speed).
SPEED_BINS = (0.0, 0.02, 0.05, 0.1, 0.2, 0.5, math.inf)


@dataclass
class DynamicIdentificationResult(StatusResult):
    """Identified rigid-body and friction parameters (Dressler (2012), ch. 6.2, Table 6.3).

    Parameters
    ----------
    variant : str
        The model variant (:data:`VARIANTS`).
    names : tuple of str
        Parameter names (order of ``theta``).
    theta : numpy.ndarray, shape (p,)
        Estimates [kg, N, N s/m]; parameters outside the identifiable (base) set are 0.
    std : numpy.ndarray, shape (p,)
        Standard deviations from ``sigma^2 (Y_w^T Y_w)^-1`` (``inf`` if not identifiable).
    covariance : numpy.ndarray, shape (p, p)
        Covariance of ``theta``.
    residual_rms : numpy.ndarray, shape (3,)
        RMS of ``tau - Y theta - tau0`` per actuator on the fitted rows [N].
    residual_ss : numpy.ndarray, shape (3,)
        Sum of squared residuals per actuator on the fitted rows [N^2] (the thesis' Table
        6.3 residuals are of this kind, on its own data and scaling).
    residual_by_speed : list of dict
        Per speed bin (:data:`SPEED_BINS`) and actuator: ``{"v_min", "v_max", "n",
        "rms"}`` of all samples (fitted or not) [N]: the unmodelled low-speed (Stribeck)
        friction shows here.
    condition_number : float
        Condition number of the weighted, column-scaled regressor.
    condition_number_raw : float
        Condition number of the weighted regressor in SI units.
    identifiability : IdentifiabilityReport
        Pivoted-QR analysis (base parameters) of the weighted regressor.
    near_dependencies : list of dict
        The least-determined parameters (pivot order, last first): ``parameter``,
        ``r_ratio`` (``|R_jj| / |R_00|`` of the scaled QR) and ``depends_on`` (the column
        as a combination of the better-determined ones, in parameter units).
    weights : numpy.ndarray, shape (3,)
        Row weight per actuator [1/N].
    n_samples : int
        Samples used.
    n_rows : int
        Equations fitted (samples x actuators above ``min_speed``).
    status : Status
        ``optimal`` (the least-squares optimum; an identification that cannot be posed
        raises instead).
    message : str
        What happened.
    solve_time : float
        Wall time [s].
    info : dict
        Options (min_speed, weighting, preprocessing) and the split of :attr:`solve_time`
        [s]: ``regressor_time_s`` (regressor evaluation), ``filter_time_s`` (parallel
        filtering of the regressor) and ``least_squares_time_s`` (least squares and all
        statistics).
    """

    variant: str
    names: tuple[str, ...]
    theta: np.ndarray
    std: np.ndarray
    covariance: np.ndarray
    residual_rms: np.ndarray
    residual_ss: np.ndarray
    residual_by_speed: list
    condition_number: float
    condition_number_raw: float
    identifiability: IdentifiabilityReport
    near_dependencies: list
    weights: np.ndarray
    n_samples: int
    n_rows: int
    solve_time: float = 0.0
    info: dict = field(default_factory=dict)

    @property
    def parameters(self) -> dict[str, float]:
        """``{name: estimate}``."""
        return {n: float(v) for n, v in zip(self.names, self.theta)}

    def table_6_3_row(self) -> np.ndarray:
        """The estimates in the column order of Table 6.3 (:data:`TABLE_6_3_COLUMNS`).

        Returns
        -------
        numpy.ndarray, shape (10,)
            ``[m_p, m_c1..3, f_c1..3, f_v1..3]``; ``nan`` where the variant does not estimate
            the parameter (taken from Table 6.1), 0 where it fixes it at zero (model 1's
            ``f_v``), as in the thesis' table.
        """
        p = self.parameters
        v = get_variant(self.variant)
        row = []
        for c in TABLE_6_3_COLUMNS:
            if c in p:
                row.append(p[c])
            elif c.startswith("f_") and not v.asymmetric:
                row.append(0.0)
            else:
                row.append(math.nan)
        return np.array(row)

    def z_scores(self, truth: np.typing.ArrayLike) -> np.ndarray:
        """``|theta - truth| / std`` per parameter.

        Parameters
        ----------
        truth : array_like, shape (p,)
            Reference values in the order of :attr:`names`.

        Returns
        -------
        numpy.ndarray, shape (p,)
            Deviations in standard deviations (``nan`` where ``std`` is 0 or infinite).

        Raises
        ------
        InputError
            ``truth`` of the wrong length.
        """
        tr = np.asarray(truth, dtype=float).ravel()
        if tr.size != self.theta.size:
            raise InputError(f"truth: expected {self.theta.size} values, got {tr.size}")
        with np.errstate(divide="ignore", invalid="ignore"):
            z = np.abs(self.theta - tr) / self.std
        return np.where(np.isfinite(self.std) & (self.std > 0), z, np.nan)

    def describe(self) -> str:
        """Parameter table as text.

        Returns
        -------
        str
            One line per parameter: name, estimate, standard deviation, unit.
        """
        lines = [f"variant {self.variant}: {self.message}"]
        for n, v, s in zip(self.names, self.theta, self.std):
            lines.append(f"  {n:12s} {v:12.4f} +- {s:9.4f} {_unit(n)}")
        lines.append(f"  residual RMS [N]: {np.round(self.residual_rms, 2).tolist()}, cond (scaled) {self.condition_number:.3g}")
        return "\n".join(lines)


def _near_dependencies(A: np.ndarray, names: Sequence[str], count: int) -> list[dict[str, Any]]:
    """The last ``count`` pivots of the column-pivoted QR of the scaled regressor, each as a
    combination of the columns before it (the near-dependencies behind a large std)."""
    norms = np.linalg.norm(A, axis=0)
    As = A / np.where(norms > 0, norms, 1.0)
    R, piv = scipy.linalg.qr(As, mode="r", pivoting=True, check_finite=False)
    d = np.abs(np.diag(R))
    out = []
    n = len(piv)
    for j in range(n - 1, max(n - 1 - count, 0), -1):
        c = scipy.linalg.solve_triangular(R[:j, :j], R[:j, j], lower=False, check_finite=False) if j else np.zeros(0)
        col = piv[j]
        deps = {}
        for ii in np.argsort(-np.abs(c)):
            if abs(c[ii]) > 1e-3 and norms[col] > 0:
                deps[names[piv[ii]]] = float(c[ii] * norms[col] / norms[piv[ii]])
        out.append({"parameter": names[col], "r_ratio": float(d[j] / d[0]) if d[0] > 0 else 0.0, "depends_on": deps})
    return out


def column_dependency(Y: np.typing.ArrayLike, names: Sequence[str], parameter: str, on: Sequence[str] | None = None) -> dict[str, Any]:
    """How well one regressor column is a combination of others (why a parameter is poorly identifiable).

    Least squares ``Y_j ~= sum_i c_i Y_i`` over the columns ``on``: a change ``d`` of
    parameter ``j`` acts on the forces like the changes ``c_i d`` of the others, up to the
    relative residual. For a link-cluster mass ``m_a,i`` and ``on = (m_p, m_c,i)`` the
    coefficients are near ``(1/2 .. 1/4, 1/4 .. 1/2)`` (Dressler (2012), eq. 6.7:
    ``m_p + sum m_a/2`` and ``m_c,i + m_a,i/4``) and the residual is small.

    Parameters
    ----------
    Y : array_like, shape (m, p) or (N, 3, p)
        Regressor (rows stacked or per sample and actuator).
    names : sequence of str
        Column names.
    parameter : str
        The column to explain.
    on : sequence of str, optional
        The explaining columns (default: all others).

    Returns
    -------
    dict
        ``coefficients`` ({name: c_i}, in parameter units), ``relative_residual``
        (``|Y_j - sum c_i Y_i| / |Y_j|``, 0 = exactly dependent).

    Raises
    ------
    InputError
        Unknown names or shapes that do not match.
    """
    A = np.asarray(Y, dtype=float)
    A = A.reshape(-1, A.shape[-1])
    names = list(names)
    if A.shape[1] != len(names):
        raise InputError(f"names: expected {A.shape[1]} names (one per column of Y), got {len(names)}")
    if parameter not in names:
        raise InputError(f"parameter: {parameter!r} is not one of {', '.join(names)}")
    others = [n for n in names if n != parameter] if on is None else list(on)
    for n in others:
        if n not in names or n == parameter:
            raise InputError(f"on: {n!r} is not another column ({', '.join(names)})")
    yj = A[:, names.index(parameter)]
    X = A[:, [names.index(n) for n in others]]
    c, *_ = np.linalg.lstsq(X, yj, rcond=None)
    nrm = float(np.linalg.norm(yj))
    rel = float(np.linalg.norm(yj - X @ c) / nrm) if nrm > 0 else 0.0
    return {"coefficients": {n: float(v) for n, v in zip(others, c)}, "relative_residual": rel}


def _speed_bins(q_dot: np.ndarray, r: np.ndarray) -> list[dict[str, Any]]:
    # one pass: bin index of every (sample, actuator), then counts and sums of squares per bin
    edges = np.asarray(SPEED_BINS)
    nb = edges.size - 1
    v = np.abs(q_dot)
    idx = np.searchsorted(edges, v, side="right") - 1  # edges[j] <= v < edges[j + 1]
    ok = (idx >= 0) & (idx < nb)
    flat = (idx * 3 + np.arange(3))[ok]
    n = np.bincount(flat, minlength=3 * nb).reshape(nb, 3)
    ss = np.bincount(flat, weights=np.square(r)[ok], minlength=3 * nb).reshape(nb, 3)
    out = []
    for j, (lo, hi) in enumerate(zip(SPEED_BINS[:-1], SPEED_BINS[1:])):
        out.append({"v_min": lo, "v_max": hi, "n": [int(c) for c in n[j]],
                    "rms": [float(np.sqrt(ss[j, i] / n[j, i])) if n[j, i] else math.nan for i in range(3)]})
    return out


def _row_factors(Y: np.ndarray, b: np.ndarray, mask: np.ndarray) -> np.ndarray:
    """Per actuator ``i`` a (p+1)-square ``S_i`` with ``S_i^T S_i = M_i^T M_i`` of its rows
    ``M_i = [Y[k, i, :], b[k, i]]`` (``mask[k, i]``): the R of a Householder QR (LAPACK
    ``dgeqrf`` on a Fortran-ordered copy of the rows, the only copy made)."""
    p = Y.shape[2]
    S = np.zeros((3, p + 1, p + 1))
    for i in range(3):
        mi = mask[:, i]
        r = int(np.count_nonzero(mi))
        if r == 0:
            continue
        Mt = np.empty((p + 1, r))
        Mt[:p] = Y[:, i, :][mi].T
        Mt[p] = b[mi, i]
        M = Mt.T  # Fortran order, as LAPACK wants it
        if r <= p:  # fewer rows than columns: the rows themselves have the right Gram matrix
            S[i, :r] = M
            continue
        qr, _, _, info = scipy.linalg.lapack.dgeqrf(M, overwrite_a=True)
        if info != 0:
            raise ModelError(f"QR of the regressor rows of actuator {i + 1} failed (LAPACK dgeqrf info {info})")
        S[i] = np.triu(qr[:p + 1])
    return S


def _stacked_factor(S: np.ndarray, w: np.ndarray, cols: Sequence[int]) -> np.ndarray:
    """R (k+1 square) of the weighted rows restricted to the columns ``cols`` plus the
    right-hand side: QR of the stack ``[w_i S_i[:, cols + rhs]]``; ``R[:k, :k] x = R[:k, k]``
    is the least-squares solution and ``R[k, k]^2`` the weighted residual sum of squares.
    Rows are signed so that the diagonal is non-negative: R is then the unique Cholesky
    factor of the weighted Gram matrix, whatever order the QR steps took (the pivoted QR of
    the identifiability report sees the same matrix for the same data)."""
    c = [*cols, S.shape[2] - 1]
    Z = np.concatenate([w[i] * S[i][:, c] for i in range(3)])
    R = scipy.linalg.qr(Z, mode="r", check_finite=False)[0][:len(c)]
    return R * np.where(np.diag(R) < 0, -1.0, 1.0)[:, None]


def identify_dynamics(
    samples: DynamicSamples,
    parameters: RobotParameters | str | Path | None = None,
    variant: str | ModelVariant = "model_2",
    weighting: str | Sequence[float] = "actuator",
    min_speed: float = 0.05,
    rank_deficient: str = "raise",
    configuration: int | Sequence[int] = 0,
    solution: int = 1,
    regressor: DynamicRegressor | None = None,
    parallel_filter: bool = True,
) -> DynamicIdentificationResult:
    """Least-squares identification of masses and friction, Dressler (2012), ch. 6.2, Table 6.3.

    Solves ``min || W (Y theta + tau0 - tau) ||^2`` over the rows (sample k, actuator i)
    with ``|q_dot_i| >= min_speed``; ``Y`` from :class:`DynamicRegressor` (one symbolic
    model). Standard deviations from ``sigma^2 (Y_w^T Y_w)^-1`` with ``sigma^2 = RSS_w /
    (m - p)`` and the base (identifiable) parameters from the column-pivoted QR of
    :func:`gtmodel.calibration.identifiability.analyze_jacobian`. The rows are read once:
    each actuator's rows ``[Y_i, tau_i - tau0_i]`` are reduced to a (p+1)-square triangular
    factor by a Householder QR; the weighting, the solution, the standard deviations and
    the base-parameter analysis then work on the stack of these factors (the same least
    squares, as accurate as :func:`numpy.linalg.lstsq` on the rows).

    Parameters
    ----------
    samples : DynamicSamples
        Filtered motion and forces (see :func:`preprocess_log`).
    parameters : RobotParameters or str or pathlib.Path, optional
        Parameter set (a name of :func:`gtmodel.robots.available_parameter_sets`, a TOML file or the parameters): kinematics, gravity, Table 6.1 friction; required unless
        ``regressor`` is given.
    variant : str or ModelVariant, optional
        Which parameters are estimated (default ``"model_2"``, :data:`VARIANTS`).
    weighting : {"actuator", "none"} or sequence of 3 float, optional
        ``"actuator"`` (default): two steps, the second weighting each actuator's rows by
        ``1 / (residual RMS of the first)``; ``"none"``: ordinary least squares; or three
        positive weights [1/N].
    min_speed : float, optional
        Rows with ``|q_dot_i|`` below this [m/s] are not fitted (default 0.05 m/s): the
        sign is ill-defined near zero and the unmodelled Stribeck friction lives there.
    rank_deficient : {"raise", "base"}, optional
        For a rank-deficient regressor: raise :class:`~gtmodel.errors.ModelError`
        naming the dependent parameters (default), or estimate the base parameters (the
        identifiable subset; the others are set to 0 with infinite std).
    configuration : int or sequence of int, optional
        IK configuration of the data (default 0).
    solution : {1, -1}, optional
        FK assembly for cart-coordinate data (default 1).
    regressor : DynamicRegressor, optional
        A prepared regressor (reused across calls; overrides ``parameters``/``variant``).
    parallel_filter : bool, optional
        Pass ``Y`` and ``tau0`` through the filter the forces went through
        (``samples.smoother``, see :func:`preprocess_log`) before decimating (default
        True).

    Returns
    -------
    DynamicIdentificationResult

    Raises
    ------
    InputError
        Invalid options or data, neither ``parameters`` nor ``regressor``, or fewer
        fitted rows than parameters.
    ModelError
        Rank-deficient regressor with ``rank_deficient="raise"`` (names the parameters
        and their dependencies).
    UnreachablePoseError, SingularConfigurationError
        A sample outside the workspace or singular (names the sample).
    """
    t0 = time.perf_counter()
    if not isinstance(samples, DynamicSamples):
        raise InputError(f"samples: expected DynamicSamples (see preprocess_log), got {type(samples).__name__}")
    if not (isinstance(min_speed, (int, float)) and math.isfinite(min_speed) and min_speed >= 0):
        raise InputError(f"min_speed: expected a non-negative speed in m/s, got {min_speed!r}")
    if rank_deficient not in ("raise", "base"):
        raise InputError(f"rank_deficient: expected 'raise' or 'base', got {rank_deficient!r}")
    if isinstance(weighting, str):
        if weighting not in ("actuator", "none"):
            raise InputError(f"weighting: expected 'actuator', 'none' or three positive weights, got {weighting!r}")
        fixed_w = None
    else:
        fixed_w = np.asarray(weighting, dtype=float).ravel()
        if fixed_w.size != 3 or not np.all(np.isfinite(fixed_w)) or np.any(fixed_w <= 0):
            raise InputError(f"weighting: expected three positive finite weights, got {list(np.ravel(weighting))!r}")
    if regressor is None and parameters is None:
        raise InputError("parameters: expected a parameter set (name, TOML file or RobotParameters) when no regressor is given")
    reg = regressor if regressor is not None else DynamicRegressor(parameters, variant, configuration, solution)
    names = reg.names
    p = len(names)
    t_reg = time.perf_counter()
    Y, tau0, q_dot = reg.evaluate(samples.x, samples.x_dot, samples.x_ddot, samples.coordinates)
    t_reg = time.perf_counter() - t_reg
    t_filt = time.perf_counter()
    tau = samples.tau
    edge = 0
    if parallel_filter and samples.smoother is not None:
        Y, tau0 = samples.smoother(Y), samples.smoother(tau0)
        edge = int(samples.info.get("trim", 0))
    t_filt = time.perf_counter() - t_filt
    t_ls = time.perf_counter()
    sel = slice(edge, samples.n_samples - edge, samples.decimate)  # views, no copies
    n_used = len(range(samples.n_samples)[sel])
    if n_used < 2:
        raise InputError(f"samples: {samples.n_samples} samples leave {n_used} after trim={edge} and decimate={samples.decimate}")
    Y, tau0, q_dot, tau = Y[sel], tau0[sel], q_dot[sel], tau[sel]
    b_all = tau - tau0
    mask = np.abs(q_dot) >= min_speed  # (N, 3)
    counts = mask.sum(axis=0)
    m = int(counts.sum())
    if m <= p:
        raise InputError(f"samples: {m} rows with |q_dot| >= min_speed = {min_speed} m/s, expected more than the {p} parameters")

    # One pass over the data: per actuator the triangular factor S_i of its rows [Y_i b_i]
    # (Householder QR). The rows of any weighting and any column subset have the factor of
    # the small stack [w_i S_i] (orthogonal invariance), so the solution, the residual sums,
    # the standard deviations and the base-parameter analysis all come from (p+1)-square
    # blocks; no second pass and no normal equations.
    S = _row_factors(Y, b_all, mask)
    R0 = _stacked_factor(S, np.ones(3), list(range(p)))[:p, :p]
    report0 = analyze_jacobian(R0, names)
    ident = sorted(names.index(n) for n in report0.identifiable)
    if not report0.full_rank:
        msg = f"the regressor of variant {reg.variant.name!r} is rank-deficient (rank {report0.rank} of {p}): {report0.describe()}"
        if rank_deficient == "raise":
            raise ModelError(msg + "; choose a variant without these parameters or rank_deficient='base'")
        _log.warning(msg)
    k = len(ident)

    def solve(w: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        # least squares on the identifiable columns with actuator weights w: R x = c
        F = _stacked_factor(S, w, ident)
        th = np.zeros(p)
        th[ident] = scipy.linalg.solve_triangular(F[:k, :k], F[:k, k], check_finite=False)
        return th, F[:k, :k]

    w = fixed_w if fixed_w is not None else np.ones(3)
    th, R = solve(w)
    if fixed_w is None and weighting == "actuator":
        # residual sum of squares per actuator ||S_i [theta; -1]||^2 (no pass over the rows)
        ext = np.append(th, -1.0)
        rss = np.array([float(np.sum((S[i] @ ext) ** 2)) for i in range(3)])
        rms = np.where(counts > 0, np.sqrt(rss / np.maximum(counts, 1)), 1.0)
        w = 1.0 / np.where(rms > 0, rms, 1.0)
        th, R = solve(w)
    r_all = b_all - (Y.reshape(-1, p) @ th).reshape(-1, 3) if p else b_all.copy()
    res_ss = np.array([float(np.sum(np.square(r_all[:, i][mask[:, i]]))) for i in range(3)])
    res_rms = np.array([math.sqrt(res_ss[i] / counts[i]) if counts[i] else math.nan for i in range(3)])
    # covariance sigma^2 (Y_I^T W^2 Y_I)^-1 = sigma^2 R^-1 R^-T, sigma^2 = RSS_w / (m - rank)
    sigma2 = float(np.sum(w**2 * res_ss)) / (m - k)
    Rinv = scipy.linalg.solve_triangular(R, np.eye(k), check_finite=False)
    cov = np.full((p, p), math.inf)
    cov[np.ix_(ident, ident)] = sigma2 * (Rinv @ Rinv.T)
    std = np.array([math.sqrt(cov[j, j]) if j in ident else math.inf for j in range(p)])
    # the base-parameter report on all columns (R of the weighted rows, all parameters)
    R_all = R if k == p else _stacked_factor(S, w, list(range(p)))[:p, :p]
    report = analyze_jacobian(R_all, names)
    report = dataclasses.replace(
        report, n_residuals=int(m), std={n: float(std[j]) for j, n in enumerate(names)}, covariance=cov,
        observability=observability_indices(report.singular_values, m) if report.full_rank else report.observability,
    )
    sv = np.linalg.svd(R, compute_uv=False)
    cond_raw = float(sv[0] / sv[-1]) if sv[-1] > 0 else math.inf
    sv_s = np.linalg.svd(R / np.linalg.norm(R, axis=0), compute_uv=False)
    cond = float(sv_s[0] / sv_s[-1]) if sv_s[-1] > 0 else math.inf
    near = _near_dependencies(R, [names[j] for j in ident], count=min(3, k - 1))
    by_speed = _speed_bins(q_dot, r_all)
    t_ls = time.perf_counter() - t_ls
    status = Status.OPTIMAL
    message = f"{m} rows ({n_used} samples), rank {report.rank}/{p}"
    if not report.full_rank:
        message += f"; base parameters only: {report.describe()}"
    return DynamicIdentificationResult(
        variant=reg.variant.name, names=names, theta=th, std=std, covariance=cov, residual_rms=res_rms, residual_ss=res_ss,
        residual_by_speed=by_speed, condition_number=float(cond), condition_number_raw=cond_raw,
        identifiability=report, near_dependencies=near, weights=w, n_samples=n_used, n_rows=int(m),
        status=status, message=message, solve_time=time.perf_counter() - t0,
        info={"min_speed": float(min_speed), "weighting": weighting if isinstance(weighting, str) else "fixed",
              "regressor_time_s": t_reg, "filter_time_s": t_filt, "least_squares_time_s": t_ls, **samples.info},
    )
