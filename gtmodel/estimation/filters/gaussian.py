"""The predict-update step of the Kalman and extended Kalman filters (Cvitanic (2021), section 4.1).

The filters themselves are in :mod:`gtmodel.estimation.filters.kalman`; this module holds
their one step, the record of a filter run (:class:`FilterRun`, with the NEES) and the
Cholesky pivots.

ONE implementation: the filter step is one CasADi Function built from the
:class:`~gtmodel.estimation.filters.end_effector.EndEffectorModel`'s transition, measurement and their AD
Jacobians. On the linear translation-only model the same graph is the Kalman filter
(:class:`~gtmodel.estimation.filters.kalman.KalmanFilter`, ``"kf_step"``); on the 19-D model it is the extended Kalman filter
(:class:`~gtmodel.estimation.filters.kalman.ExtendedKalmanFilter`, ``"ekf_step"``). Predict-then-update, sample ``k``::

    x- = f(x),  F = df/dx(x),  P- = F P F^T + Q                     (predict)
    z^ = h(x-), H = dh/dx(x-), S = H P- H^T + R                      (innovation covariance)
    K  = P- H^T S^-1                                                 (Cholesky of S, triangular solves)
    x+ = x- + K (z - z^)                                             (quaternion renormalised)
    P+ = (I - K H) P- (I - K H)^T + K R K^T                          (Joseph form)

``P-``, ``S`` and ``P+`` are symmetrised: their lower triangles are computed and mirrored.

Before the innovation the measured quaternion is sign-aligned with the predicted one
(``quat`` and ``-quat`` are the same orientation). The step also returns the Cholesky
pivots (the diagonal of the factor) of ``S`` and of ``P+``, written out in the graph
(an SX loop), so the generated C can test them: all pivots finite and > 0 <=> both matrices
positive definite <=> the step is good. A non-positive-definite matrix gives a NaN pivot
(``sqrt`` of a negative number) or a zero one.
"""

from __future__ import annotations

import logging
import time
from dataclasses import dataclass, field
from typing import Any

import casadi as ca
import numpy as np
from scipy.spatial.transform import Rotation

from gtmodel._arrays import as_signal
from gtmodel._compiler import compiled_function
from gtmodel._geometry import quat_conj, quat_mul
from gtmodel.errors import InputError
from gtmodel.estimation.filters.end_effector import EndEffectorModel
from gtmodel.status import Status, StatusResult

__all__ = ["FilterRun", "cholesky_pivots"]

logger = logging.getLogger("gtmodel")

#: Flags of the optional compiled run (-O1: straight-line code, a third of -O2's build time, as fast).
_COMPILE_FLAGS = ("-O1", "-fPIC", "-shared")
_SYMMETRY_TOLERANCE = 1e-10
_PSD_TOLERANCE = 1e-12


def _quaternion_error_jacobian() -> ca.Function:
    """``J(q^) = d(2 vec(q^* (x) q)) / dq``: first-order rotation-vector error, shape (3, 4)."""
    qh, q = ca.SX.sym("quat_hat", 4), ca.SX.sym("quat", 4)
    err = 2 * quat_mul(quat_conj(qh), q)[1:4]
    return ca.Function("quaternion_error_jacobian", [qh], [ca.jacobian(err, q)])


_QUAT_ERROR_JACOBIAN = _quaternion_error_jacobian()


def _scalar_last(quat: np.ndarray) -> np.ndarray:
    return np.concatenate([quat[..., 1:], quat[..., :1]], axis=-1)


@dataclass(kw_only=True)
class FilterRun(StatusResult):
    """A filter run over a measurement record (rows are samples, SI units).

    On failure (``status`` ``"error"``: a covariance stopped being positive definite, or a
    non-finite value) the arrays hold the samples BEFORE the failing one and ``message``
    names it; never NaN rows.

    Parameters
    ----------
    status : Status
        ``"completed"`` when every step's pivots were finite and positive, ``"error"`` otherwise.
    message : str
        Summary (the failing sample and matrix on failure).
    name : str
        Filter name (``"kf"``, ``"ekf"``, ``"ukf"``, ``"pf"``).
    x : numpy.ndarray, shape (N, nx)
        Posterior means ``x_{k|k}``.
    P : numpy.ndarray, shape (N, nx, nx)
        Posterior covariances ``P_{k|k}``.
    step_time_s : float
        Mean wall time per step of the run [s].
    quaternion_slice : slice or None
        The quaternion's columns of ``x`` (``None`` without rotation); used by :meth:`nees`.
    """

    name: str = ""
    x: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))
    P: np.ndarray = field(default_factory=lambda: np.zeros((0, 0, 0)))
    step_time_s: float = float("nan")
    quaternion_slice: slice | None = None

    @property
    def dof(self) -> int:
        """Degrees of freedom of the NEES: ``nx``, or ``nx - 1`` with a quaternion (3-D rotation error)."""
        return self.x.shape[1] - (1 if self.quaternion_slice is not None else 0)

    def nees(self, x_true: Any) -> np.ndarray:
        """Normalised estimation error squared per sample, ``e^T P_e^-1 e`` (Bar-Shalom et al. (2001), sec. 5.4).

        Without a quaternion ``e = x_true - x`` and ``P_e = P``. With a quaternion its 4 entries
        are replaced by the rotation vector ``dtheta`` of ``q^* (x) q_true`` (the error in the
        body frame, ``q_true = q (x) exp(dtheta / 2)``, SciPy's ``as_rotvec``) and the covariance
        by ``T P T^T`` with ``T = blockdiag(I, J, I)``, ``J = d(2 vec(q^* (x) q)) / dq`` at the
        estimate (CasADi AD): ``nx - 1`` degrees of freedom (:attr:`dof`).

        Parameters
        ----------
        x_true : array_like, shape (N, nx)
            True states of the same samples (``N`` as :attr:`x`).

        Returns
        -------
        numpy.ndarray, shape (N,)
            NEES; ``chi^2(dof)`` distributed for a consistent filter.

        Raises
        ------
        InputError
            ``x_true`` of another shape or not finite.
        """
        n, nx = self.x.shape
        xt = as_signal(x_true, "x_true", nx, n, like="the run")
        if self.quaternion_slice is None:
            e, cov = xt - self.x, self.P
        else:
            qs = self.quaternion_slice
            keep = np.r_[0 : qs.start, qs.stop : nx]
            dtheta = (Rotation.from_quat(_scalar_last(self.x[:, qs])).inv() * Rotation.from_quat(_scalar_last(xt[:, qs]))).as_rotvec()
            e = np.hstack([(xt - self.x)[:, keep[: qs.start]], dtheta, (xt - self.x)[:, keep[qs.start :]]])
            jac = np.asarray(_QUAT_ERROR_JACOBIAN.map(n)(self.x[:, qs].T)).reshape(3, n, 4).transpose(1, 0, 2)
            t = np.zeros((n, nx - 1, nx))
            t[:, : qs.start, : qs.start] = np.eye(qs.start)
            t[:, qs.start : qs.start + 3, qs] = jac
            t[:, qs.start + 3 :, qs.stop :] = np.eye(nx - qs.stop)
            cov = t @ self.P @ t.transpose(0, 2, 1)
        return np.einsum("ni,ni->n", e, np.linalg.solve(cov, e[..., None])[..., 0])


def cholesky_pivots(A: Any) -> tuple[Any, Any]:
    """Cholesky factor ``L`` (``A = L L^T``) and its pivots ``diag(L)``, written out in CasADi SX.

    The column-by-column algorithm (Golub and Van Loan (2013), alg. 4.2.1) as an expression graph,
    so generated C can evaluate it without a library: for a matrix that is not positive definite
    a pivot is ``sqrt`` of a non-positive number (0 or NaN), so "all pivots finite and > 0" is the
    positive-definiteness test.

    Parameters
    ----------
    A : casadi.SX, shape (n, n)
        Symmetric matrix (only the lower triangle is read).

    Returns
    -------
    L : casadi.SX, shape (n, n)
        Lower-triangular factor.
    pivots : casadi.SX, shape (n, 1)
        ``diag(L)``.

    Raises
    ------
    InputError
        ``A`` not square.
    """
    n = A.shape[0]
    if A.shape != (n, n):
        raise InputError(f"A: expected a square matrix, got shape {A.shape}")
    L = [[ca.SX(0) for _ in range(n)] for _ in range(n)]
    for j in range(n):
        s = A[j, j]
        for k in range(j):
            s = s - L[j][k] * L[j][k]
        L[j][j] = ca.sqrt(s)
        inv = 1 / L[j][j]
        for i in range(j + 1, n):
            s = A[i, j]
            for k in range(j):
                s = s - L[i][k] * L[j][k]
            L[i][j] = s * inv
    lmat = ca.vertcat(*[ca.horzcat(*row) for row in L])
    return lmat, ca.vertcat(*[L[j][j] for j in range(n)])


def _symmetric_product(A: Any, B: Any, C: Any = None) -> Any:
    """``A B^T (+ C)`` when it is symmetric: the lower triangle computed, mirrored (SX)."""
    n = A.shape[0]
    out = ca.SX.zeros(n, n)
    for i in range(n):
        for j in range(i + 1):
            v = ca.dot(A[i, :], B[j, :])
            if C is not None:
                v = v + C[i, j]
            out[i, j] = v
            out[j, i] = v
    return out


def _triangular_solves(L: Any, B: Any) -> Any:
    """``(L L^T)^-1 B`` by forward and back substitution (SX, column by column)."""
    n, m = B.shape
    inv = [1 / L[i, i] for i in range(n)]
    cols = []
    for c in range(m):
        y = []
        for i in range(n):
            s = B[i, c]
            for k in range(i):
                s = s - L[i, k] * y[k]
            y.append(s * inv[i])
        xs: list[Any] = [None] * n
        for i in reversed(range(n)):
            s = y[i]
            for k in range(i + 1, n):
                s = s - L[k, i] * xs[k]
            xs[i] = s * inv[i]
        cols.append(ca.vertcat(*xs))
    return ca.horzcat(*cols)


def _matrix(value: Any, n: int, name: str, definite: bool) -> np.ndarray:
    try:
        arr = np.array(value, dtype=float)
    except (TypeError, ValueError):
        raise InputError(f"{name}: expected a numeric ({n}, {n}) covariance, got {value!r}") from None
    if arr.shape != (n, n):
        raise InputError(f"{name}: expected shape ({n}, {n}), got {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise InputError(f"{name}: expected finite values")
    scale = max(np.abs(arr).max(), np.finfo(float).tiny)
    if np.abs(arr - arr.T).max() > _SYMMETRY_TOLERANCE * scale:
        raise InputError(f"{name}: expected a symmetric covariance, got max |{name} - {name}^T| = {np.abs(arr - arr.T).max():.3g}")
    arr = 0.5 * (arr + arr.T)
    if definite:
        try:
            np.linalg.cholesky(arr)
        except np.linalg.LinAlgError:
            raise InputError(f"{name}: expected a positive definite covariance (Cholesky failed)") from None
    else:
        eig = np.linalg.eigvalsh(arr)
        if eig.min() < -_PSD_TOLERANCE * max(eig.max(), 0.0) or eig.min() < 0 and eig.max() <= 0:
            raise InputError(f"{name}: expected a positive semi-definite covariance, smallest eigenvalue {eig.min():.3g}")
    return arr


class _GaussianFilter:
    """The KF/EKF implementation; see :class:`ExtendedKalmanFilter`."""

    _name = "ekf"

    def __init__(self, model: EndEffectorModel, Q: Any, R: Any, x0: Any, P0: Any, compiled: bool = False) -> None:
        if not isinstance(model, EndEffectorModel):
            raise InputError(f"model: expected an EndEffectorModel, got {type(model).__name__}")
        self.model = model
        self.nx, self.nz = model.nx, model.nz
        self.Q = _matrix(Q, self.nx, "Q", definite=False)
        self.R = _matrix(R, self.nz, "R", definite=True)
        self.P0 = _matrix(P0, self.nx, "P0", definite=True)
        try:
            x = np.array(x0, dtype=float)
        except (TypeError, ValueError):
            raise InputError(f"x0: expected a numeric state of shape ({self.nx},), got {x0!r}") from None
        if x.shape != (self.nx,) or not np.all(np.isfinite(x)):
            raise InputError(f"x0: expected a finite state of shape ({self.nx},), got shape {x.shape}")
        qs = model.state_slices.get("quaternion")
        if qs is not None:
            norm = np.linalg.norm(x[qs])
            if norm < 1e-12:
                raise InputError(f"x0: the quaternion x0[{qs.start}:{qs.stop}] has zero norm, got {x[qs].tolist()}")
            x[qs] /= norm
        self.x0 = x
        if not isinstance(compiled, (bool, np.bool_)):
            raise InputError(f"compiled: expected True or False, got {compiled!r}")
        self.compiled = bool(compiled)
        self._evaluator: ca.Function | None = None
        self._step: ca.Function | None = None
        self._runners: dict[int, ca.Function] = {}

    def step_function(self) -> ca.Function:
        """The filter step as one CasADi Function (predict-then-update, Joseph form; module docstring).

        ``"<name>_step"(x[nx], P[nx, nx], z[nz]) -> (x_next[nx], P_next[nx, nx], pivots[nz + nx])``:
        ``(x_{k-1|k-1}, P_{k-1|k-1}, z_k) -> (x_{k|k}, P_{k|k})``; ``pivots`` are the Cholesky
        pivots of the innovation covariance ``S`` (first ``nz``) and of ``P_next`` (last ``nx``):
        all finite and > 0 <=> the step is good.

        Returns
        -------
        casadi.Function
            Named ``"kf_step"`` or ``"ekf_step"`` (the same object on every call).
        """
        if self._step is None:
            self._step = self._build_step()
        return self._step

    def _build_step(self) -> ca.Function:
        m = self.model
        x = ca.SX.sym("x", self.nx)
        P = ca.SX.sym("P", self.nx, self.nx)
        z_sym = ca.SX.sym("z", self.nz)
        z = z_sym
        x_pred = m.transition(x)
        F = m.transition_jacobian(x)
        P_pred = _symmetric_product(ca.mtimes(F, P), F, ca.sparsify(ca.DM(self.Q)))  # F P F^T + Q
        z_hat = m.measurement(x_pred)
        H = m.measurement_jacobian(x_pred)
        qz = m.measurement_slices.get("quaternion")
        if qz is not None:  # sign alignment: quat and -quat are one orientation
            sign = ca.if_else(ca.dot(z[qz], z_hat[qz]) < 0, -1.0, 1.0)
            z = ca.vertcat(z[: qz.start], sign * z[qz], z[qz.stop :])
        HP = ca.mtimes(H, P_pred)
        S = _symmetric_product(HP, H, ca.sparsify(ca.DM(self.R)))  # H P- H^T + R
        L_s, piv_s = cholesky_pivots(S)
        K = _triangular_solves(L_s, HP).T  # P- H^T S^-1
        x_upd = x_pred + ca.mtimes(K, z - z_hat)
        qs = m.state_slices.get("quaternion")
        if qs is not None:
            quat = x_upd[qs] / ca.norm_2(x_upd[qs])
            x_upd = ca.vertcat(x_upd[: qs.start], quat, x_upd[qs.stop :])
        # Joseph form (I - K H) P- (I - K H)^T + K R K^T, evaluated as A + (K R - A H^T) K^T with
        # A = (I - K H) P- = P- - K (H P-) (the same terms, grouped: one product with K^T instead of
        # two); the lower triangle is computed and mirrored, so P_next is exactly symmetric.
        A = P_pred - ca.mtimes(K, HP)
        P_upd = _symmetric_product(ca.mtimes(K, ca.sparsify(ca.DM(self.R))) - ca.mtimes(A, H.T), K, A)
        _, piv_p = cholesky_pivots(P_upd)
        return ca.Function(
            f"{self._name}_step",
            [x, P, z_sym],
            [x_upd, P_upd, ca.vertcat(piv_s, piv_p)],
            ["x", "P", "z"],
            ["x_next", "P_next", "pivots"],
        )

    def run(self, z: Any) -> FilterRun:
        """Filter a whole record through :meth:`step_function` (:meth:`casadi.Function.mapaccum`).

        Starts from ``(x0, P0)`` as the posterior of the sample before ``z[0]``.

        Parameters
        ----------
        z : array_like, shape (N, nz)
            Measurements (model's measurement order, SI units), rows ``dt`` apart.

        Returns
        -------
        FilterRun
            Posterior means and covariances; ``status`` ``"error"`` (arrays cut before the
            failing sample) when a pivot is not finite and positive.

        Raises
        ------
        InputError
            ``z`` of another shape or not finite.
        """
        zz = as_signal(z, "z", self.nz)
        n = zz.shape[0]
        if self._evaluator is None:
            self._evaluator = self.step_function()
            if self.compiled:  # the same graph as C (cached shared library), or the interpreter if none builds
                self._evaluator, how = compiled_function(self._evaluator, _COMPILE_FLAGS, "filters")
                logger.info("%s run: %s", self._name, how)
        runner = self._runners.get(n)
        if runner is None:
            runner = self._runners[n] = self._evaluator.mapaccum(f"{self._name}_run", n, 2)
        t0 = time.perf_counter()
        xs, ps, pivots = runner(self.x0, self.P0, zz.T)
        elapsed = time.perf_counter() - t0
        xs = np.asarray(xs).T
        ps = np.asarray(ps).reshape(self.nx, n, self.nx).transpose(1, 0, 2)
        pivots = np.asarray(pivots).T
        ok = np.all(np.isfinite(pivots) & (pivots > 0), axis=1) & np.all(np.isfinite(xs), axis=1)
        qs = self.model.state_slices.get("quaternion")
        if np.all(ok):
            status, message = Status.COMPLETED, f"{self._name}: filtered {n} samples"
        else:
            k = int(np.argmin(ok))
            which = "S (innovation covariance)" if not np.all(np.isfinite(pivots[k, : self.nz]) & (pivots[k, : self.nz] > 0)) else "P"
            status = Status.ERROR
            message = f"{self._name}: sample {k}: covariance {which} not positive definite (filter diverged); results cut before it"
            logger.warning(message)
            xs, ps = xs[:k], ps[:k]
        return FilterRun(
            status=status, message=message, name=self._name, x=xs, P=ps, step_time_s=elapsed / n, quaternion_slice=qs
        )
