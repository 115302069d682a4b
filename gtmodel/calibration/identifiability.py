"""Identifiability of calibration parameters from the residual Jacobian.

Which parameters a set of measurements determines is read from the Jacobian ``J``
(``m`` residuals x ``n`` parameters) of the calibration residuals, Dressler (2012),
ch. 5.4 and Table 5.4:

1. **Column scaling.** Every column is divided by its Euclidean norm, so the analysis
   does not depend on the units of the parameters (lengths in m, dimensionless
   directions, rotation angles in rad) nor on the number of poses. A column that is
   exactly zero (a parameter that does not enter the residuals) is left at zero.
2. **Rank and identifiable subset.** A column-pivoted QR factorisation
   ``J_s P = Q R`` (:func:`scipy.linalg.qr` with ``pivoting=True``) orders the columns
   by how much new information each adds. The numerical rank is the number of diagonal
   entries with ``|R_ii| > RANK_TOLERANCE * |R_00|``; the first ``rank`` pivot columns
   are the identifiable parameters, the rest are not identifiable from these data.
3. **Dependencies.** With ``R = [[R11, R12], [0, R22]]`` the scaled column of each
   non-identifiable parameter is, up to ``R22``, the combination ``R11^-1 R12`` of the
   identifiable columns. Coefficients whose magnitude (in the scaled, dimensionless
   form) exceeds :data:`DEPENDENCY_THRESHOLD` are reported, converted back to the
   parameters' units: ``J_j ~= sum_i c_ij J_i`` means that a change ``d`` of parameter
   ``j`` has the same effect on the residuals as the changes ``c_ij d`` of the
   parameters ``i`` (the content of Dressler (2012), Table 5.4).
4. **Observability indices** from the singular values ``sigma_1 >= ... >= sigma_n`` of
   the *scaled Jacobian* (not of ``J^T J``, whose singular values are their squares),
   ``m`` its number of rows:

   - ``O1 = (sigma_1 sigma_2 ... sigma_n)^(1/n) / sqrt(m)`` -- Borm and Menq (1991);
   - ``O2 = sigma_n / sigma_1``, the inverse condition number -- Driels and Pathre (1990);
   - ``O3 = sigma_n``, the minimum singular value -- Nahvi, Hollerbach and Hayward (1994);
   - ``O4 = sigma_n^2 / sigma_1``, the noise amplification index -- Nahvi and Hollerbach
     (1996);
   - ``O5 = 1 / (1/sigma_1 + ... + 1/sigma_n)`` -- Sun and Hollerbach (2008).

   The list and the definitions follow Sun and Hollerbach, "Observability index
   selection for robot calibration", IEEE ICRA 2008, and Nahvi and Hollerbach, "The
   noise amplification index for optimal pose selection in robot calibration", IEEE
   ICRA 1996 (whose introduction reviews O1-O3). Larger is better for all five; all are
   zero for a rank-deficient Jacobian (numerical rank below the number of columns).
5. **Standard deviations** (when the residuals are given):
   ``cov = sigma^2 (J_I^T J_I)^-1`` with ``sigma^2 = RSS / (m - n)`` for the identifiable
   columns ``J_I``; a non-identifiable parameter has an infinite standard deviation.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Sequence

import numpy as np
import scipy.linalg

from gtmodel.errors import InputError

__all__ = [
    "IdentifiabilityReport",
    "analyze_jacobian",
    "analyze_qr",
    "numerical_rank",
    "combine_reports",
    "observability_indices",
    "scale_columns",
    "RANK_TOLERANCE",
    "DEPENDENCY_THRESHOLD",
]

#: Relative rank tolerance of the column-pivoted QR of the column-scaled Jacobian: a
#: parameter is identifiable if ``|R_ii| > RANK_TOLERANCE * |R_00|``. Exact dependencies
#: give ratios at round-off level (1e-13 and below); identifiable parameters of usable
#: pose sets give 1e-5 and above (L1, 21 parameters, 780 poses: 2e-3). A parameter
#: between 1e-8 and round-off would have a standard deviation more than 1e8 times that
#: of a well-determined one: it is not identifiable in practice.
RANK_TOLERANCE = 1e-8

#: Smallest magnitude of a (scaled, dimensionless) dependency coefficient ``R11^-1 R12``
#: that is reported in :attr:`IdentifiabilityReport.non_identifiable`.
DEPENDENCY_THRESHOLD = 1e-6

_INDEX_NAMES = ("O1", "O2", "O3", "O4", "O5")


@dataclass(frozen=True)
class IdentifiabilityReport:
    """Identifiability of parameters from a residual Jacobian (Dressler (2012), Table 5.4).

    Parameters
    ----------
    names : tuple of str
        Names of the analysed parameters (the Jacobian's columns, in order).
    rank : int
        Numerical rank of the column-scaled Jacobian (see :data:`RANK_TOLERANCE`).
    n_parameters : int
        Number of analysed parameters (columns).
    n_residuals : int
        Number of residuals (rows).
    identifiable : tuple of str
        The identifiable parameters, in pivot order (most informative first).
    non_identifiable : dict
        ``{name: {"depends_on": {name: coefficient}}}`` for every parameter that the data
        do not determine; the coefficients are in the parameters' units (see the module
        docstring, step 3).
    singular_values : numpy.ndarray, shape (n_parameters,)
        Singular values of the column-scaled Jacobian, descending (dimensionless).
    observability : dict of str to float
        Observability indices ``"O1"`` .. ``"O5"`` of the scaled Jacobian.
    condition_number : float
        ``sigma_max / sigma_min`` of the scaled Jacobian (``inf`` if rank-deficient).
    column_norms : numpy.ndarray, shape (n_parameters,)
        Euclidean norms of the unscaled columns (the scaling of step 1).
    std : dict of str to float
        Standard deviation per parameter in its unit (``inf`` where not identifiable);
        empty if no residuals were given or ``n_residuals <= n_parameters``.
    covariance : numpy.ndarray, shape (n_parameters, n_parameters) or (0, 0)
        ``sigma^2 (J_I^T J_I)^-1`` in the parameters' units, columns in ``names`` order;
        rows and columns of non-identifiable parameters are ``inf``. Empty when ``std``
        is.
    tolerance : float
        The relative rank tolerance used.
    """

    names: tuple[str, ...]
    rank: int
    n_parameters: int
    n_residuals: int
    identifiable: tuple[str, ...]
    non_identifiable: dict[str, dict[str, dict[str, float]]]
    singular_values: np.ndarray
    observability: dict[str, float]
    condition_number: float
    column_norms: np.ndarray
    std: dict[str, float] = field(default_factory=dict)
    covariance: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))
    tolerance: float = RANK_TOLERANCE

    @property
    def full_rank(self) -> bool:
        """Whether every parameter is identifiable (``rank == n_parameters``)."""
        return self.rank == self.n_parameters

    def describe(self) -> str:
        """One line per non-identifiable parameter with what it depends on.

        Returns
        -------
        str
            E.g. ``"b_x (depends on As1_x: -1, As2_x: -1, As3_x: -1)"``; ``"all identifiable"``
            for a full-rank Jacobian.
        """
        if self.full_rank:
            return "all identifiable"
        lines = []
        for name, info in self.non_identifiable.items():
            deps = info["depends_on"]
            if deps:
                dep = ", ".join(f"{k}: {v:.6g}" for k, v in deps.items())
                lines.append(f"{name} (depends on {dep})")
            else:
                lines.append(f"{name} (does not affect the residuals)")
        return "; ".join(lines)


def scale_columns(J: np.typing.ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """Scale the columns of a Jacobian to unit Euclidean norm.

    Parameters
    ----------
    J : array_like, shape (m, n)
        Jacobian.

    Returns
    -------
    J_s : numpy.ndarray, shape (m, n)
        ``J`` with every non-zero column divided by its norm (zero columns stay zero).
    norms : numpy.ndarray, shape (n,)
        The column norms.

    Raises
    ------
    InputError
        If ``J`` is not a finite 2-D array.
    """
    Ja = np.asarray(J, dtype=float)
    if Ja.ndim != 2:
        raise InputError(f"J: expected a 2-D Jacobian (m, n), got shape {Ja.shape}")
    if not np.all(np.isfinite(Ja)):
        rows = np.flatnonzero(~np.all(np.isfinite(Ja), axis=1))
        raise InputError(f"J: non-finite entries in row(s) {rows[:10].tolist()}")
    norms = np.linalg.norm(Ja, axis=0)
    div = np.where(norms > 0, norms, 1.0)
    return Ja / div, norms


def observability_indices(singular_values: np.typing.ArrayLike, n_residuals: int) -> dict[str, float]:
    """Observability indices O1-O5 of a Jacobian from its singular values.

    Definitions in the module docstring (Sun and Hollerbach (2008); Nahvi and
    Hollerbach (1996)).

    Parameters
    ----------
    singular_values : array_like, shape (n,)
        Singular values of the (scaled) Jacobian, any order, non-negative.
    n_residuals : int
        Number of rows ``m`` of the Jacobian (for O1).

    Returns
    -------
    dict of str to float
        ``{"O1": ..., "O2": ..., "O3": ..., "O4": ..., "O5": ...}``; all zero if the
        smallest singular value is zero.

    Raises
    ------
    InputError
        If the singular values are empty, negative or not finite, or ``n_residuals < 1``.
    """
    s = np.sort(np.asarray(singular_values, dtype=float).ravel())[::-1]
    if s.size == 0 or not np.all(np.isfinite(s)) or np.any(s < 0):
        raise InputError(f"singular_values: expected finite non-negative values, got {s.tolist()}")
    if int(n_residuals) < 1:
        raise InputError(f"n_residuals: expected a positive number of rows, got {n_residuals!r}")
    return _observability(s, int(n_residuals))


def _observability(s: np.ndarray, n_residuals: int) -> dict[str, float]:
    """O1-O5 from singular values sorted descending (no checks; see observability_indices)."""
    smax, smin = float(s[0]), float(s[-1])
    if smin <= 0.0:
        return {"O1": 0.0, "O2": 0.0, "O3": 0.0, "O4": 0.0, "O5": 0.0}
    return {
        "O1": float(np.exp(np.mean(np.log(s)))) / math.sqrt(n_residuals),
        "O2": smin / smax,
        "O3": smin,
        "O4": smin * smin / smax,
        "O5": 1.0 / float(np.sum(1.0 / s)),
    }


def analyze_jacobian(
    J: np.typing.ArrayLike,
    names: Sequence[str] | None = None,
    residuals: np.typing.ArrayLike | None = None,
    tolerance: float = RANK_TOLERANCE,
    threshold: float = DEPENDENCY_THRESHOLD,
) -> IdentifiabilityReport:
    """Rank, identifiable subset, dependencies and observability of a residual Jacobian.

    The method is the column-pivoted QR of the column-scaled Jacobian (module docstring),
    as used for the F1 in Dressler (2012), ch. 5.4, Table 5.4.

    Parameters
    ----------
    J : array_like, shape (m, n)
        Jacobian of the residuals with respect to the parameters.
    names : sequence of str, optional
        Parameter names (default ``"p0", "p1", ...``).
    residuals : array_like, shape (m,), optional
        Residuals at the point where ``J`` was evaluated; if given and ``m > n``, the
        standard deviations ``sqrt(diag(sigma^2 (J_I^T J_I)^-1))``,
        ``sigma^2 = RSS / (m - n)``, are reported.
    tolerance : float, optional
        Relative rank tolerance (default :data:`RANK_TOLERANCE`).
    threshold : float, optional
        Smallest reported scaled dependency coefficient (default
        :data:`DEPENDENCY_THRESHOLD`).

    Returns
    -------
    IdentifiabilityReport

    Raises
    ------
    InputError
        If ``J`` is not a finite 2-D array with at least one column, the names or
        residuals do not match its shape, or the tolerances are not positive.
    """
    Js, norms = scale_columns(J)
    m, n = Js.shape
    if n == 0 or m == 0:
        raise InputError(f"J: expected at least one row and one column, got shape {Js.shape}")
    if names is None:
        names = [f"p{i}" for i in range(n)]
    names = tuple(str(s) for s in names)
    if len(names) != n:
        raise InputError(f"names: expected {n} names (one per column of J), got {len(names)}")
    if not (tolerance > 0 and threshold > 0):
        raise InputError(f"tolerance and threshold must be positive, got {tolerance!r}, {threshold!r}")

    R, piv = scipy.linalg.qr(Js, mode="r", pivoting=True, check_finite=False)
    rss = None
    if residuals is not None:
        r = np.asarray(residuals, dtype=float).ravel()
        if r.size != m:
            raise InputError(f"residuals: expected {m} values (one per row of J), got {r.size}")
        if not np.all(np.isfinite(r)):
            raise InputError("residuals: non-finite values")
        rss = float(r @ r)
    return analyze_qr(R, piv, norms, m, names, rss=rss, tolerance=tolerance, threshold=threshold)


def analyze_qr(
    R: np.ndarray,
    piv: np.ndarray,
    norms: np.ndarray,
    n_residuals: int,
    names: Sequence[str],
    rss: float | None = None,
    tolerance: float = RANK_TOLERANCE,
    threshold: float = DEPENDENCY_THRESHOLD,
) -> IdentifiabilityReport:
    """The report of :func:`analyze_jacobian` from a pivoted QR already computed.

    For a solver that has factorised the column-scaled Jacobian anyway (a Gauss-Newton
    step): ``J_s P = Q R`` with ``J_s = J / norms`` (steps 1-2 of the module docstring);
    the rank, dependencies, observability and covariance need ``R`` only. No argument
    checks (an internal fast path; :func:`analyze_jacobian` checks its inputs first).

    Parameters
    ----------
    R : numpy.ndarray, shape (k, n), k >= n (or k = m < n)
        Upper-triangular factor of the column-pivoted QR of the column-scaled Jacobian.
    piv : numpy.ndarray of int, shape (n,)
        The column permutation ``P`` (``J_s[:, piv] = Q R``).
    norms : numpy.ndarray, shape (n,)
        Column norms of the unscaled Jacobian (:func:`scale_columns`).
    n_residuals : int
        Number of rows ``m`` of the Jacobian.
    names : sequence of str
        Parameter names (columns, unpermuted order).
    rss : float, optional
        Residual sum of squares at the point of ``J``; with ``m > n`` the standard
        deviations are reported (``sigma^2 = rss / (m - n)``).
    tolerance : float, optional
        Relative rank tolerance (default :data:`RANK_TOLERANCE`).
    threshold : float, optional
        Smallest reported scaled dependency coefficient (default
        :data:`DEPENDENCY_THRESHOLD`).

    Returns
    -------
    IdentifiabilityReport
        The same report as :func:`analyze_jacobian` of that Jacobian.
    """
    names = tuple(names)
    m, n = int(n_residuals), len(names)
    diag = np.abs(np.diag(R))
    ref = diag[0] if diag.size else 0.0
    rank = int(np.sum(diag > tolerance * ref)) if ref > 0 else 0
    ident = piv[:rank]
    nonid = piv[rank:]

    non_identifiable: dict[str, dict[str, dict[str, float]]] = {}
    if nonid.size:
        if rank > 0:
            C = scipy.linalg.solve_triangular(R[:rank, :rank], R[:rank, rank:n], lower=False, check_finite=False)
        else:
            C = np.zeros((0, nonid.size))
        for jj, j in enumerate(nonid):
            deps: dict[str, float] = {}
            order = np.argsort(-np.abs(C[:, jj])) if rank else []
            for ii in order:
                c = C[ii, jj]
                if abs(c) > threshold and norms[j] > 0:
                    i = ident[ii]
                    deps[names[i]] = float(c * norms[j] / norms[i])
            non_identifiable[names[j]] = {"depends_on": deps}

    # singular values of J_s = those of R (J_s P = Q R with orthonormal Q)
    sv = np.linalg.svd(R, compute_uv=False)
    sv_full = np.zeros(n)
    sv_full[: sv.size] = sv
    obs = _observability(sv_full, m) if rank == n else dict.fromkeys(_INDEX_NAMES, 0.0)
    cond = float(sv_full[0] / sv_full[-1]) if sv_full[-1] > 0 and rank == n else math.inf

    std: dict[str, float] = {}
    cov = np.zeros((0, 0))
    if rss is not None and m > n:
        sigma2 = rss / (m - n)
        std = {s: math.inf for s in names}
        cov = np.full((n, n), math.inf)
        if rank > 0:
            Rinv, info = scipy.linalg.lapack.dtrtri(R[:rank, :rank])
            if info != 0:  # a zero diagonal entry cannot pass the rank test; kept as a guard
                Rinv = scipy.linalg.solve_triangular(R[:rank, :rank], np.eye(rank), lower=False, check_finite=False)
            # (J_I^T J_I)^-1 = D^-1 (R11^T R11)^-1 D^-1 with D the column norms (pivot order)
            C = sigma2 * (Rinv @ Rinv.T) / np.outer(norms[ident], norms[ident])
            cov[np.ix_(ident, ident)] = C
            for ii, i in enumerate(ident):
                std[names[i]] = float(math.sqrt(C[ii, ii]))
    return IdentifiabilityReport(
        names=names,
        rank=rank,
        n_parameters=n,
        n_residuals=m,
        identifiable=tuple(names[i] for i in ident),
        non_identifiable=non_identifiable,
        singular_values=sv_full,
        observability=obs,
        condition_number=cond,
        column_norms=norms,
        std=std,
        covariance=cov,
        tolerance=float(tolerance),
    )


def numerical_rank(J: np.typing.ArrayLike, tolerance: float = RANK_TOLERANCE) -> int:
    """Numerical rank of the column-scaled Jacobian (pivoted QR only; the cheap check).

    Parameters
    ----------
    J : array_like, shape (m, n)
        Jacobian.
    tolerance : float, optional
        Relative rank tolerance (default :data:`RANK_TOLERANCE`).

    Returns
    -------
    int
        Number of diagonal entries of ``R`` with ``|R_ii| > tolerance |R_00|``.

    Raises
    ------
    InputError
        If ``J`` is not a finite 2-D array.
    """
    Js, _ = scale_columns(J)
    if Js.size == 0:
        return 0
    R = scipy.linalg.qr(Js, mode="r", pivoting=True, check_finite=False)[0]
    d = np.abs(np.diag(R))
    return int(np.sum(d > tolerance * d[0])) if d.size and d[0] > 0 else 0


def combine_reports(reports: Sequence[IdentifiabilityReport]) -> IdentifiabilityReport:
    """Report of a block-diagonal Jacobian from the reports of its blocks.

    Groups of arms that share no parameter give a block-diagonal Jacobian (after ordering
    rows by group); its singular values are the union of the blocks' (the column scaling
    is per column, so the same), its rank the sum of the ranks, and the dependencies stay
    within blocks. The standard deviations and covariances are the blocks' (each with its
    own residual variance; zero between blocks).

    Parameters
    ----------
    reports : sequence of IdentifiabilityReport
        One report per block (empty: an empty report).

    Returns
    -------
    IdentifiabilityReport
        ``O1`` uses the total number of rows.
    """
    if not reports:
        return IdentifiabilityReport(
            names=(), rank=0, n_parameters=0, n_residuals=0, identifiable=(), non_identifiable={},
            singular_values=np.zeros(0), observability={}, condition_number=math.inf, column_norms=np.zeros(0),
        )
    if len(reports) == 1:
        return reports[0]
    sv = np.sort(np.concatenate([r.singular_values for r in reports]))[::-1]
    m = sum(r.n_residuals for r in reports)
    rank = sum(r.rank for r in reports)
    n = sum(r.n_parameters for r in reports)
    nonid: dict[str, dict[str, dict[str, float]]] = {}
    std: dict[str, float] = {}
    for r in reports:
        nonid.update(r.non_identifiable)
        std.update(r.std)
    cov = np.zeros((0, 0))
    if all(r.covariance.shape == (r.n_parameters, r.n_parameters) for r in reports):
        cov = np.zeros((n, n))
        k = 0
        for r in reports:
            cov[k:k + r.n_parameters, k:k + r.n_parameters] = r.covariance
            k += r.n_parameters
    return IdentifiabilityReport(
        names=tuple(s for r in reports for s in r.names),
        rank=rank,
        n_parameters=n,
        n_residuals=m,
        identifiable=tuple(s for r in reports for s in r.identifiable),
        non_identifiable=nonid,
        singular_values=sv,
        observability=observability_indices(sv, m) if rank == n else dict.fromkeys(_INDEX_NAMES, 0.0),
        condition_number=float(sv[0] / sv[-1]) if rank == n and sv[-1] > 0 else math.inf,
        column_norms=np.concatenate([r.column_norms for r in reports]),
        std=std,
        covariance=cov,
        tolerance=reports[0].tolerance,
    )
