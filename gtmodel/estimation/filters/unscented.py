"""Sampling filters of the end-effector state: the unscented Kalman filter (Cvitanic (2021), sec. 4.1).

The particle filter is in :mod:`gtmodel.estimation.filters.particle`; it uses the helpers
here (mapped evaluation, covariance checks, aligned weighted means) and the UKF for its
start. Both filters run the ONE model of :mod:`gtmodel.estimation.filters.end_effector`: the sigma points
and the particles go through the model's CasADi Functions ``transition`` (eqs. (21)-(28))
and ``measurement`` (incl. the lever arm (29)), each mapped over all points at once
(:meth:`casadi.Function.map`, evaluated in place through :meth:`casadi.Function.buffer`:
no copies between NumPy and CasADi; ``compiled=True``: the two Functions as C generated from
the same graph, :func:`gtmodel._compiler.compiled_function`). Nothing of the model is
written again here.

Library (a decision): filterpy 2.0.0 gives the sigma points and weights
(:class:`filterpy.kalman.MerweScaledSigmaPoints`, Van der Merwe (2004)) and the
resampling (:func:`filterpy.monte_carlo.systematic_resample`); its ``UnscentedKalmanFilter``
and particle helpers are not used: its UKF measures the propagated sigma points, which
leaves ``H Q H^T`` out of the innovation covariance for an additive process noise (so it
is not the KF on a linear model), and the filters here must evaluate the model mapped.

Unscented Kalman filter, per sample (predict then update, as the EKF of
:mod:`gtmodel.estimation.filters.gaussian`; additive noises ``Q``, ``R``)::

    chi = sigma(x, P);   Y_i = f(chi_i);   x- = sum Wm_i Y_i;   P- = sum Wc_i (Y_i - x-)(Y_i - x-)^T + Q
    chi = sigma(x-, P-); Z_i = h(chi_i);   z- = sum Wm_i Z_i;   S = sum Wc_i (Z_i - z-)(..)^T + R
    C = sum Wc_i (chi_i - x-)(Z_i - z-)^T;  K = C S^-1;  x = x- + K (z - z-);  P = P- - K S K^T (symmetrised)

The sigma points are drawn again from ``(x-, P-)`` for the measurement, so ``Q`` reaches
``S`` and ``C``: on a linear model every step equals the Kalman filter's (exact for
any ``alpha, beta, kappa``; the default ``alpha = 1, beta = 2, kappa = 0`` gives the
weights ``Wm = [0, 1/(2n), ...]``, ``Wc_0 = 2``, all of order one, so the sums keep the
rounding of the KF: the test holds 1e-9; a small ``alpha`` such as 1e-3 gives weights of
order 1e6 of both signs and loses digits by cancellation).

Quaternion (a decision, the same parameterisation as the EKF so the two are comparable
state by state and ``FilterRun.P`` is ``(nx, nx)`` for both): the quaternion is kept as
its 4 components in the state and in ``P``. The transition normalises it in every sigma
point; the weighted means (predicted state, predicted measurement, particle cloud) are
taken over quaternions sign-aligned with a reference (the propagated centre sigma point,
or the previous estimate) and then normalised; the measured quaternion is sign-aligned
with the predicted one before the innovation; the updated quaternion is normalised (as
the EKF does). Why not an error-state (rotation-vector) UKF: it is the better filter for
large attitude uncertainty, but it would need its own 18-D ``Q``/``P`` and a mapping to
compare with the EKF; at the tracker's 0.015 deg orientation noise the normalised
4-component mean differs from the intrinsic (Karcher) mean by terms of the order of the
squared spread (< 1e-7), far below the noise. The radial direction of the quaternion has
almost no spread after normalisation; the small quaternion term of ``Q``
(:meth:`EndEffectorModel.process_noise`) keeps ``P-`` positive definite.

Status of a run (as :class:`~gtmodel.estimation.filters.gaussian.FilterRun`: never NaN rows):
``completed`` when every step ran; ``error`` when a covariance was not positive definite or
a value not finite (UKF), or when the particle filter lost the measurement (every
particle's ``d2`` above the chi-square quantile ``1 - lost_probability``, ``nz`` degrees
of freedom: the cloud no longer holds the state) or its weights degenerated (ESS below
1 + 1e-9: all weight on one particle). The arrays then hold the samples before the
failing one and the message names it.
"""

from __future__ import annotations

import logging
import time
from typing import Any

import casadi as ca
import numpy as np
import scipy.linalg
from filterpy.kalman import MerweScaledSigmaPoints

from gtmodel._arrays import as_array, as_finite, as_signal
from gtmodel._compiler import compiled_function
from gtmodel.errors import InputError

from gtmodel.estimation.filters.end_effector import EndEffectorModel
from gtmodel.estimation.filters.gaussian import FilterRun
from gtmodel.status import Status

__all__ = ["UnscentedKalmanFilter"]

_LOG = logging.getLogger("gtmodel")
#: Flags of the optional compiled evaluation (as the EKF's compiled run).
_COMPILE_FLAGS = ("-O1", "-fPIC", "-shared")
#: Relative asymmetry accepted in a covariance argument.
_SYMMETRY_TOLERANCE = 1e-9


# ----------------------------------------------------------------------------- helpers


class _Mapped:
    """``f`` mapped over ``n`` columns, evaluated in place (:meth:`casadi.Function.buffer`).

    The input rows ``(n, n_in)`` in C order are the CasADi column-major ``(n_in, n)``
    matrix, so NumPy and CasADi share the memory.
    """

    def __init__(self, f: ca.Function, n: int) -> None:
        self.function = f.map(n)
        self.arg = np.zeros((n, f.size1_in(0)))
        self.res = np.zeros((n, f.size1_out(0)))
        self._buffer, self._trigger = self.function.buffer()
        self._buffer.set_arg(0, memoryview(self.arg))
        self._buffer.set_res(0, memoryview(self.res))

    def __call__(self, rows: np.ndarray) -> np.ndarray:
        self.arg[...] = rows
        self._trigger()
        return self.res.copy()


def _covariance(value: Any, n: int, name: str, definite: bool) -> np.ndarray:
    """A symmetric ``(n, n)`` covariance, positive (semi-)definite; symmetrised."""
    c = as_array(value, (n, n), name)
    scale = max(float(np.abs(c).max()), np.finfo(float).tiny)
    asym = float(np.abs(c - c.T).max())
    if asym > _SYMMETRY_TOLERANCE * scale:
        raise InputError(f"{name}: expected a symmetric matrix, got max |C - C^T| = {asym:.3g} (max |C| = {scale:.3g})")
    c = 0.5 * (c + c.T)
    if definite:
        try:
            scipy.linalg.cholesky(c, lower=True)
        except scipy.linalg.LinAlgError:
            raise InputError(f"{name}: expected a positive definite matrix (Cholesky failed)") from None
    else:
        low = float(np.linalg.eigvalsh(c).min())
        if low < -1e-12 * scale:
            raise InputError(f"{name}: expected a positive semi-definite matrix, got smallest eigenvalue {low:.3g}")
    return c


def _flag(value: Any, name: str) -> bool:
    if not isinstance(value, (bool, np.bool_)):
        raise InputError(f"{name}: expected True or False, got {value!r}")
    return bool(value)


def _evaluator(f: ca.Function, compiled: bool) -> ca.Function:
    """``f``, or ``f`` compiled to C from the same graph (cached; ``f`` itself when no compiler builds)."""
    if not compiled:
        return f
    g, how = compiled_function(f, _COMPILE_FLAGS, "sampling_filters")
    _LOG.info("%s: %s", f.name(), how)
    return g


def _model(model: Any) -> EndEffectorModel:
    if not isinstance(model, EndEffectorModel):
        raise InputError(f"model: expected an EndEffectorModel, got {type(model).__name__}")
    return model


def _initial_state(x0: Any, model: EndEffectorModel) -> np.ndarray:
    x = as_array(x0, (model.nx,), "x0")
    qs = model.state_slices.get("quaternion")
    if qs is not None:
        norm = float(np.linalg.norm(x[qs]))
        if norm < 1e-12:
            raise InputError(f"x0: expected a quaternion (x0[{qs.start}:{qs.stop}]) of norm > 0, got {x[qs].tolist()}")
        x[qs] /= norm
    return x


def _aligned(quats: np.ndarray, ref: np.ndarray) -> np.ndarray:
    """Quaternion rows ``(M, 4)`` with the sign that puts each on the side of ``ref`` (``q`` and ``-q`` are one rotation)."""
    sign = np.where(quats @ ref < 0.0, -1.0, 1.0)
    return quats * sign[:, None]


def _weighted_mean(rows: np.ndarray, weights: np.ndarray, qs: slice | None, ref: np.ndarray | None) -> tuple[np.ndarray, np.ndarray]:
    """Weighted mean of state/measurement rows and the rows with their quaternions aligned to it.

    The quaternion part: rows aligned with ``ref``, weighted sum, normalised.
    """
    if qs is not None:
        rows = rows.copy()
        rows[:, qs] = _aligned(rows[:, qs], ref)
    mean = weights @ rows
    if qs is not None:
        mean[qs] /= np.linalg.norm(mean[qs])
    return mean, rows


def _upper_cholesky(c: np.ndarray) -> np.ndarray:
    """Upper Cholesky factor ``U`` (``c = U^T U``), the square root filterpy's sigma points expect."""
    return np.linalg.cholesky(c).T


def _inverse_cholesky(c: np.ndarray) -> np.ndarray:
    """``L^-1`` of the Cholesky factor ``c = L L^T`` (``c^-1 = L^-T L^-1``); small matrices, NumPy's LAPACK calls.

    Raises :class:`numpy.linalg.LinAlgError` when ``c`` is not positive definite.
    """
    return np.linalg.inv(np.linalg.cholesky(0.5 * (c + c.T)))


def _square_root(c: np.ndarray) -> np.ndarray:
    """``L`` with ``L L^T = c`` for a positive semi-definite ``c`` (eigen-decomposition)."""
    lam, v = np.linalg.eigh(c)
    return v * np.sqrt(np.clip(lam, 0.0, None))


# ----------------------------------------------------------------------------- UKF


class UnscentedKalmanFilter:
    """Unscented Kalman filter on the end-effector model (Van der Merwe (2004); Cvitanic (2021), sec. 4.1).

    Sigma points and weights: :class:`filterpy.kalman.MerweScaledSigmaPoints`; propagation
    and measurement prediction: the model's ``transition`` and ``measurement`` Functions
    mapped over the ``2 nx + 1`` sigma points. See the module docstring for the step and
    the quaternion handling.

    Parameters
    ----------
    model : EndEffectorModel
        The state model (19-D with rotation, 9-D without).
    Q : array_like, shape (nx, nx)
        Process noise covariance per sample (symmetric, positive semi-definite;
        :meth:`EndEffectorModel.process_noise`).
    R : array_like, shape (nz, nz)
        Measurement noise covariance (symmetric, positive definite).
    x0 : array_like, shape (nx,)
        Posterior mean before the first sample (``x_{0|0}``); its quaternion is normalised.
    P0 : array_like, shape (nx, nx)
        Posterior covariance before the first sample (symmetric, positive definite).
    alpha : float, optional
        Spread of the sigma points, ``0 < alpha <= 1``.
    beta : float, optional
        Prior-knowledge weight of the centre point in the covariance (2 for a Gaussian), ``>= 0``.
    kappa : float, optional
        Secondary scaling, ``nx + kappa > 0``.
    compiled : bool, optional
        Evaluate ``transition`` and ``measurement`` as C compiled from the same graph
        (:func:`gtmodel._compiler.compiled_function`, cached; the CasADi interpreter when no
        compiler builds), as the EKF's ``compiled`` run.

    Attributes
    ----------
    model, Q, R, x0, P0, compiled
        The arguments (checked, covariances symmetrised).
    points : filterpy.kalman.MerweScaledSigmaPoints
        Sigma points and weights ``Wm``, ``Wc``.

    Raises
    ------
    InputError
        ``model`` not an :class:`EndEffectorModel`; a matrix of another shape, not finite,
        not symmetric or not (semi-)definite; ``x0`` of another shape or with a zero
        quaternion; ``alpha``, ``beta`` or ``kappa`` out of range; ``compiled`` not a bool.
    """

    name = "ukf"

    def __init__(
        self, model: Any, Q: Any, R: Any, x0: Any, P0: Any, alpha: float = 1.0, beta: float = 2.0, kappa: float = 0.0, compiled: bool = False
    ) -> None:
        self.model = _model(model)
        nx, nz = self.model.nx, self.model.nz
        self.Q = _covariance(Q, nx, "Q", definite=False)
        self.R = _covariance(R, nz, "R", definite=True)
        self.x0 = _initial_state(x0, self.model)
        self.P0 = _covariance(P0, nx, "P0", definite=True)
        a = float(as_finite(alpha, "alpha"))
        if not 0.0 < a <= 1.0:
            raise InputError(f"alpha: expected 0 < alpha <= 1 (spread of the sigma points), got {alpha!r}")
        b = float(as_finite(beta, "beta", nonnegative=True))
        k = float(as_finite(kappa, "kappa"))
        if nx + k <= 0.0:
            raise InputError(f"kappa: expected nx + kappa > 0 (nx = {nx}), got {kappa!r}")
        self.points = MerweScaledSigmaPoints(nx, a, b, k, sqrt_method=_upper_cholesky)
        m = self.points.num_sigmas()
        self.compiled = _flag(compiled, "compiled")
        self._f = _Mapped(_evaluator(self.model.transition, self.compiled), m)
        self._h = _Mapped(_evaluator(self.model.measurement, self.compiled), m)
        self._qs = self.model.state_slices.get("quaternion")
        self._zqs = self.model.measurement_slices.get("quaternion")

    def step(self, x: np.ndarray, P: np.ndarray, z: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """One predict-then-update step ``(x_{k-1|k-1}, P_{k-1|k-1}, z_k) -> (x_{k|k}, P_{k|k})``.

        Parameters
        ----------
        x : numpy.ndarray, shape (nx,)
            Posterior mean of the previous sample.
        P : numpy.ndarray, shape (nx, nx)
            Posterior covariance of the previous sample.
        z : numpy.ndarray, shape (nz,)
            Measurement of this sample (its quaternion sign is free).

        Returns
        -------
        x : numpy.ndarray, shape (nx,)
            Posterior mean (quaternion normalised).
        P : numpy.ndarray, shape (nx, nx)
            Posterior covariance (symmetrised).

        Raises
        ------
        scipy.linalg.LinAlgError
            ``P``, the predicted covariance or the innovation covariance not positive
            definite (:meth:`run` turns this into an ``error`` status).
        """
        wm, wc = self.points.Wm, self.points.Wc
        y = self._f(self.points.sigma_points(x, P))
        ref = y[0, self._qs] if self._qs is not None else None
        x_pred, y = _weighted_mean(y, wm, self._qs, ref)
        dy = y - x_pred
        p_pred = (dy.T * wc) @ dy + self.Q
        p_pred = 0.5 * (p_pred + p_pred.T)
        chi = self.points.sigma_points(x_pred, p_pred)
        zs = self._h(chi)
        zref = zs[0, self._zqs] if self._zqs is not None else None
        z_pred, zs = _weighted_mean(zs, wm, self._zqs, zref)
        dz = zs - z_pred
        s = (dz.T * wc) @ dz + self.R
        c = ((chi - x_pred).T * wc) @ dz
        white = _inverse_cholesky(s)
        gain = c @ white.T @ white  # C S^-1
        zk = z.copy()
        if self._zqs is not None:
            zk[self._zqs] = _aligned(zk[None, self._zqs], z_pred[self._zqs])[0]
        x_new = x_pred + gain @ (zk - z_pred)
        if self._qs is not None:
            x_new[self._qs] /= np.linalg.norm(x_new[self._qs])
        p_new = p_pred - gain @ s @ gain.T
        return x_new, 0.5 * (p_new + p_new.T)

    def run(self, z: Any) -> FilterRun:
        """Filter a whole record, step by step from ``(x0, P0)``.

        Parameters
        ----------
        z : array_like, shape (N, nz)
            Measurements, one row per sample ``dt`` apart (model's measurement order).

        Returns
        -------
        FilterRun
            Name ``"ukf"``; ``x`` (N, nx) and ``P`` (N, nx, nx) the posteriors; ``step_time_s``
            the mean wall time per step [s]; status ``completed``, or ``error`` with the
            arrays cut before the failing sample (named in the message).

        Raises
        ------
        InputError
            ``z`` of another width, empty, or not finite.
        """
        zz = as_signal(z, "z", self.model.nz)
        n, nx = zz.shape[0], self.model.nx
        xs, ps = np.empty((n, nx)), np.empty((n, nx, nx))
        x, p = self.x0.copy(), self.P0.copy()
        status, message = Status.COMPLETED, f"ukf: filtered {n} samples"
        t0 = time.perf_counter()
        k = 0
        for k in range(n):
            try:
                with np.errstate(over="ignore", invalid="ignore"):  # non-finite results are checked below
                    x, p = self.step(x, p, zz[k])
            except (scipy.linalg.LinAlgError, ValueError) as exc:
                status, message = Status.ERROR, f"ukf: step {k}: covariance not positive definite or not finite ({exc})"
                break
            if not (np.all(np.isfinite(x)) and np.all(np.isfinite(p))):
                status, message = Status.ERROR, f"ukf: step {k}: state or covariance not finite"
                break
            xs[k], ps[k] = x, p
        else:
            k = n
        elapsed = time.perf_counter() - t0
        if status is not Status.COMPLETED:
            _LOG.warning(message)
        return FilterRun(
            name=self.name,
            x=xs[:k],
            P=ps[:k],
            step_time_s=elapsed / max(k, 1),
            status=status,
            message=message,
            quaternion_slice=self._qs,
        )

    def __repr__(self) -> str:
        p = self.points
        return f"UnscentedKalmanFilter(nx={self.model.nx}, nz={self.model.nz}, alpha={p.alpha}, beta={p.beta}, kappa={p.kappa})"
