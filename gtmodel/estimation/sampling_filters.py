"""Sampling filters of the end-effector state: unscented Kalman filter and particle filter (Cvitanic (2021), sec. 4.1).

Both filters run the ONE model of :mod:`gtmodel.estimation.end_effector`: the sigma points
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
:mod:`gtmodel.estimation.filters`; additive noises ``Q``, ``R``)::

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

Particle filter (sampling-importance-resampling, Gordon et al. (1993)), per sample::

    propose x_i from x_i (below);  log w_i <- log w_i - d2_i / 2;  normalise (log-sum-exp)
    estimate: weighted mean (quaternion aligned, normalised) and weighted covariance
    when ESS = 1 / sum w_i^2 < resample_threshold * n_particles: systematic resampling,
    then the regularisation move (below), weights 1 / n_particles

Proposals: ``"prior"`` (the bootstrap filter) ``x_i = f(x_i) + w_i``, ``w_i ~ N(0, Q)``,
``d2_i = |z - h(x_i)|^2_R``; ``"linearised"`` (the default; Doucet, Godsill and Andrieu
(2000), sec. II-D, the optimal importance function of a locally linearised measurement):
``H`` the measurement Jacobian (CasADi AD, ``measurement_jacobian``) at the weighted mean
of ``f(x_i)``, ``S = H Q H^T + R``, ``K = Q H^T S^-1``, ``x_i = f(x_i) + K (z - h(f(x_i))) +
N(0, Q - K S K^T)``, ``d2_i = |z - h(f(x_i))|^2_S`` (exact weights for a linear
measurement; for the 19-D model the linearisation over the cloud's spread, of the order
of the noise, is the approximation). ``Q`` is sampled through its symmetric square root
(eigen-decomposition: the jerk model's ``Q = sigma^2 G G^T`` is singular); quaternions
are normalised after every move. Weights are kept as logarithms.

Regularisation after resampling (Liu and West (2001); Musso, Oudjane and Le Gland (2001)):
``x_i <- m + a (x_i - m) + h L e_i``, ``a = sqrt(1 - h^2)``, ``L L^T`` the weighted
covariance, ``e_i ~ N(0, I)``: the duplicates separate and the cloud keeps its mean and
covariance. The bandwidth defaults to the Gaussian kernel's optimum
``h = (4 / (n_particles (nx + 2)))^(1 / (nx + 4))`` (0.69 for 1000 particles, 19-D).

Start: a cloud drawn from a prior ``(x0, P0)`` much wider than the likelihood (e.g. 0.1 m/s^2
against the accelerometer's 0.012 m/s^2, 0.01 rad/s against the gyro's 0.0009 rad/s) has no
particle near the first measurement in 12 directions at once (measured on est_study's
baseline 5-axis case: smallest ``d2`` 81 at sample 0 > the 1e-9 quantile 69.5). So by default
(``gaussian_start``) the cloud of sample 0 is drawn from the Gaussian posterior of the UKF
update of ``(x0, P0)`` with ``z[0]`` (:meth:`UnscentedKalmanFilter.step`, the same model).

The peaked likelihood (measured on a 1000-sample run generated from the 19-D model with
Table 7's noises, jerk 10 m/s^3, angular jerk 1 rad/s^3, 1000 particles; the test file's
``_simulate``, seed 1; RMS errors after sample 200): the tracker's 6.4 um noise and the
per-sample gyro/accelerometer noises make the likelihood narrow in 12 measured directions,
while the jerk noise moves a particle's position by only ``sigma_jerk dt^3 / 6`` per sample,
so resampled duplicates stay together and the cloud collapses. The plain bootstrap filter
(``proposal="prior", bandwidth=0``) lost the measurement (no particle within the chi-square
bound) at sample 30, the linearised proposal alone at sample 46. Gordon's roughening
(independent jitter per component, K = 0.2; tried, not kept) kept track but destroyed the
position-velocity correlation (velocity error 2.0 mm/s against the UKF's 0.077). The
bootstrap proposal with the regularisation tracked (position 3.4 um, velocity 0.115 mm/s;
ESS median 212 of 1000, resampling at 98 % of the samples; mean NEES 1540); the linearised
proposal with it (the defaults) came closest (position 2.2 um against the EKF's and UKF's
1.69, velocity 0.093 mm/s against 0.077; ESS median 374, minimum 11, resampling at 74 % of
the samples). It stays over-confident: mean NEES 85 against the EKF's 16 (18 degrees of
freedom), the cloud's variances about 0.75 of the EKF's: 1000 particles in 19 dimensions
do not hold the posterior's thin directions (held as a strict xfail in the tests).

Status of a run (as :class:`~gtmodel.estimation.filters.FilterRun`: never NaN rows):
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
from dataclasses import dataclass
from typing import Any

import casadi as ca
import numpy as np
import scipy.linalg
import scipy.special
import scipy.stats
from filterpy.kalman import MerweScaledSigmaPoints
from filterpy.monte_carlo import systematic_resample

from gtmodel._arrays import as_array, as_finite, positive_int
from gtmodel._compiler import compiled_function
from gtmodel.errors import InputError
from gtmodel.estimation._signals import signal_rows
from gtmodel.estimation.end_effector import EndEffectorModel
from gtmodel.estimation.filters import FilterRun
from gtmodel.status import Status

__all__ = ["UnscentedKalmanFilter", "ParticleFilter", "ParticleRun"]

_LOG = logging.getLogger("gtmodel")
#: Flags of the optional compiled evaluation (as the EKF's compiled run).
_COMPILE_FLAGS = ("-O1", "-fPIC", "-shared")
#: Relative asymmetry accepted in a covariance argument.
_SYMMETRY_TOLERANCE = 1e-9
#: ESS at or below 1 + this: the whole posterior on one particle (degenerate).
_DEGENERATE_ESS = 1e-9


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
        zz = signal_rows(z, "z", self.model.nz)
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


# ----------------------------------------------------------------------------- PF


@dataclass(kw_only=True)
class ParticleRun(FilterRun):
    """A :class:`FilterRun` of the particle filter with its weight diagnostics.

    Parameters
    ----------
    status : Status
        ``"completed"``, or ``"error"`` (measurement lost, weights degenerate).
    message : str
        Summary: resamplings and ESS, or the failing sample.
    name : str
        ``"pf"``.
    x : numpy.ndarray, shape (N, nx)
        Weighted means of the cloud (quaternion aligned and normalised).
    P : numpy.ndarray, shape (N, nx, nx)
        Weighted covariances of the cloud.
    step_time_s : float
        Mean wall time per step of the run [s].
    quaternion_slice : slice or None
        The quaternion's columns of ``x``.
    ess : numpy.ndarray, shape (N,)
        Effective sample size ``1 / sum w_i^2`` after each sample's weighting [particles]
        (``n_particles`` at sample 0 with the Gaussian start; NaN at a sample that lost the
        measurement before its weighting).
    resampled : numpy.ndarray, shape (N,), bool
        Whether the sample ended with a resampling.
    min_d2 : numpy.ndarray, shape (N,)
        Smallest normalised measurement distance ``d2_i`` over the particles (how well the
        best particle explains the measurement; chi-square with ``nz`` degrees of freedom
        for the true state).
    """

    ess: np.ndarray
    resampled: np.ndarray
    min_d2: np.ndarray


class ParticleFilter:
    """Particle filter on the end-effector model with systematic resampling (Gordon et al. (1993)).

    Cvitanic (2021), sec. 4.1 (1000 particles: the real-time limit). Particles propagate
    through the model's ``transition`` (mapped over the particles) and a proposal (the
    prior, or the locally linearised optimal one) and are weighted by the Gaussian
    likelihood of the ``measurement`` Function's prediction;
    :func:`filterpy.monte_carlo.systematic_resample` resamples when the effective sample
    size falls below ``resample_threshold * n_particles``; a moment-preserving
    regularisation then separates the duplicates. See the module docstring.

    Parameters
    ----------
    model : EndEffectorModel
        The state model.
    Q : array_like, shape (nx, nx)
        Process noise covariance per sample (symmetric, positive semi-definite).
    R : array_like, shape (nz, nz)
        Measurement noise covariance (symmetric, positive definite).
    x0 : array_like, shape (nx,)
        Mean of the initial cloud; its quaternion is normalised.
    P0 : array_like, shape (nx, nx)
        Covariance of the initial cloud (symmetric, positive semi-definite; definite with
        ``gaussian_start``).
    n_particles : int, optional
        Number of particles.
    seed : int, optional
        Seed of the filter's random numbers (:func:`numpy.random.default_rng`); every
        :meth:`run` starts from it, so runs are reproducible.
    resample_threshold : float, optional
        Resample when ``ESS < resample_threshold * n_particles``; in ``(0, 1]`` (1: every sample).
    bandwidth : float, optional
        Regularisation bandwidth ``h`` in ``[0, 1)`` (0: off); default the Gaussian kernel's
        optimum ``(4 / (n_particles (nx + 2)))^(1 / (nx + 4))``.
    proposal : {"linearised", "prior"}, optional
        Importance function: the locally linearised optimal one or the prior (bootstrap).
    lost_probability : float, optional
        The filter has lost the measurement when every particle's ``d2`` exceeds the
        chi-square (``nz`` degrees of freedom) quantile ``1 - lost_probability``; in ``(0, 1)``.
    gaussian_start : bool, optional
        Draw the cloud of sample 0 from the UKF's Gaussian posterior of ``(x0, P0)`` updated
        with ``z[0]`` (True), or from ``N(x0, P0)`` propagated and weighted like any sample.
    compiled : bool, optional
        Evaluate ``transition`` and ``measurement`` as compiled C (see :class:`UnscentedKalmanFilter`).

    Attributes
    ----------
    model, Q, R, x0, P0, n_particles, seed, resample_threshold, bandwidth, proposal, lost_probability, gaussian_start, compiled
        The arguments (checked).

    Raises
    ------
    InputError
        ``model`` not an :class:`EndEffectorModel`; a matrix of another shape, not finite,
        not symmetric or not (semi-)definite; ``x0`` of another shape or with a zero
        quaternion; ``n_particles`` not a positive integer; a parameter out of range.
    """

    name = "pf"

    def __init__(
        self,
        model: Any,
        Q: Any,
        R: Any,
        x0: Any,
        P0: Any,
        n_particles: int = 1000,
        seed: int = 0,
        resample_threshold: float = 0.5,
        bandwidth: float | None = None,
        proposal: str = "linearised",
        lost_probability: float = 1e-9,
        gaussian_start: bool = True,
        compiled: bool = False,
    ) -> None:
        self.model = _model(model)
        nx, nz = self.model.nx, self.model.nz
        self.Q = _covariance(Q, nx, "Q", definite=False)
        self.R = _covariance(R, nz, "R", definite=True)
        self.x0 = _initial_state(x0, self.model)
        self.P0 = _covariance(P0, nx, "P0", definite=False)
        self.n_particles = positive_int(n_particles, "n_particles")
        if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
            raise InputError(f"seed: expected a non-negative integer, got {seed!r}")
        self.seed = int(seed)
        self.resample_threshold = float(as_finite(resample_threshold, "resample_threshold"))
        if not 0.0 < self.resample_threshold <= 1.0:
            raise InputError(f"resample_threshold: expected a fraction in (0, 1], got {resample_threshold!r}")
        if bandwidth is None:
            bandwidth = (4.0 / (self.n_particles * (nx + 2))) ** (1.0 / (nx + 4))
        self.bandwidth = float(as_finite(bandwidth, "bandwidth", nonnegative=True))
        if not self.bandwidth < 1.0:
            raise InputError(f"bandwidth: expected 0 <= bandwidth < 1 (kernel spread / cloud spread), got {bandwidth!r}")
        self.lost_probability = float(as_finite(lost_probability, "lost_probability"))
        if not 0.0 < self.lost_probability < 1.0:
            raise InputError(f"lost_probability: expected a probability in (0, 1), got {lost_probability!r}")
        if proposal not in ("prior", "linearised"):
            raise InputError(f"proposal: expected 'prior' or 'linearised', got {proposal!r}")
        self.proposal = proposal
        self.gaussian_start = _flag(gaussian_start, "gaussian_start")
        self.compiled = _flag(compiled, "compiled")
        self._ukf = UnscentedKalmanFilter(self.model, self.Q, self.R, self.x0, self.P0, compiled=self.compiled) if self.gaussian_start else None
        self._lost_d2 = float(scipy.stats.chi2.isf(self.lost_probability, nz))
        self._f = _Mapped(_evaluator(self.model.transition, self.compiled), self.n_particles)
        self._h = _Mapped(_evaluator(self.model.measurement, self.compiled), self.n_particles)
        self._qs = self.model.state_slices.get("quaternion")
        self._zqs = self.model.measurement_slices.get("quaternion")
        self._q_root = _square_root(self.Q)
        # Whitening: d2 = |W r|^2 with W = L^-1, R = L L^T.
        self._r_white = _inverse_cholesky(self.R)

    def _normalised(self, particles: np.ndarray) -> np.ndarray:
        if self._qs is not None:
            particles[:, self._qs] /= np.linalg.norm(particles[:, self._qs], axis=1, keepdims=True)
        return particles

    def _resample(self, weights: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        """Indexes by :func:`filterpy.monte_carlo.systematic_resample`, with the offset drawn from ``rng``.

        filterpy draws its offset from NumPy's global generator: it is seeded from ``rng``
        for the call and the caller's global state restored after it. The weights'
        cumulative sum is made to reach 1 (filterpy walks past the end otherwise).
        """
        w = weights / weights.sum()
        w[-1] += max(0.0, 1.0 - float(np.cumsum(w)[-1])) + np.finfo(float).eps
        saved = np.random.get_state()
        np.random.seed(int(rng.integers(2**32)))
        try:
            return systematic_resample(w)
        finally:
            np.random.set_state(saved)

    def _propagate(self, particles: np.ndarray, w: np.ndarray, z: np.ndarray, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
        """Draw the particles of the next sample and their normalised measurement distances ``d2``.

        ``"prior"``: ``x_i = f(x_i) + w_i``, ``d2_i = |z - h(x_i)|^2_R``. ``"linearised"``
        (Doucet et al. (2000), sec. II-D): ``H`` the measurement Jacobian at the weighted
        mean of ``f(x_i)``, ``S = H Q H^T + R``, ``K = Q H^T S^-1``,
        ``x_i = f(x_i) + K (z - h(f(x_i))) + N(0, Q - K S K^T)``, ``d2_i = |z - h(f(x_i))|^2_S``.
        """
        npart, nx = particles.shape
        fx = self._f(particles)
        if self.proposal == "prior":
            new = self._normalised(fx + rng.standard_normal((npart, nx)) @ self._q_root.T)
            return new, self._distances(z, self._h(new), self._r_white)
        mean, _ = _weighted_mean(fx, w, self._qs, fx[int(np.argmax(w)), self._qs] if self._qs is not None else None)
        h = np.asarray(self.model.measurement_jacobian(mean))
        s = h @ self.Q @ h.T + self.R
        white = _inverse_cholesky(s)
        gain = (white.T @ white @ h @ self.Q).T  # Q H^T S^-1
        sigma = self.Q - gain @ s @ gain.T
        zs = self._h(fx)
        r = self._residuals(z, zs)
        new = self._normalised(fx + r @ gain.T + rng.standard_normal((npart, nx)) @ _square_root(0.5 * (sigma + sigma.T)).T)
        rw = r @ white.T  # whitened: |L^-1 r|^2 = r^T S^-1 r
        return new, np.einsum("ij,ij->i", rw, rw)

    def _residuals(self, z: np.ndarray, zs: np.ndarray) -> np.ndarray:
        """``z - zs`` per row, the quaternion of ``z`` sign-aligned with each row's."""
        r = z - zs
        if self._zqs is not None:
            zq = z[self._zqs]
            r[:, self._zqs] = np.where((zs[:, self._zqs] @ zq < 0.0)[:, None], -zq, zq) - zs[:, self._zqs]
        return r

    def _distances(self, z: np.ndarray, zs: np.ndarray, white: np.ndarray) -> np.ndarray:
        rw = self._residuals(z, zs) @ white.T
        return np.einsum("ij,ij->i", rw, rw)

    def _regularise(self, particles: np.ndarray, mean: np.ndarray, cov: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        """Moment-preserving kernel move after resampling (Liu and West (2001); Musso et al. (2001)).

        ``x_i <- m + a (x_i - m) + h L e_i`` with ``a = sqrt(1 - h^2)``, ``L L^T`` the weighted
        covariance before resampling, ``e_i ~ N(0, I)``: the duplicates separate while the
        cloud's mean and covariance stay those of the weighted cloud.
        """
        h = self.bandwidth
        a = np.sqrt(1.0 - h * h)
        n, nx = particles.shape
        moved = mean + a * (particles - mean) + h * rng.standard_normal((n, nx)) @ _square_root(cov).T
        return self._normalised(moved)

    def run(self, z: Any) -> ParticleRun:
        """Filter a whole record from a cloud drawn around ``(x0, P0)``.

        Parameters
        ----------
        z : array_like, shape (N, nz)
            Measurements, one row per sample ``dt`` apart (model's measurement order).

        Returns
        -------
        ParticleRun
            Name ``"pf"``; ``x`` (N, nx) the weighted means, ``P`` (N, nx, nx) the weighted
            covariances (before resampling), ``step_time_s`` the mean wall time per step [s],
            ``ess``, ``resampled``, ``min_d2`` per sample; status ``completed``, or ``error``
            (measurement lost or weights degenerate) with ``x``, ``P`` cut before the
            failing sample (named in the message; the diagnostics include it).

        Raises
        ------
        InputError
            ``z`` of another width, empty, or not finite.
        """
        zz = signal_rows(z, "z", self.model.nz)
        n, nx, npart = zz.shape[0], self.model.nx, self.n_particles
        rng = np.random.default_rng(self.seed)
        xs, ps = np.empty((n, nx)), np.empty((n, nx, nx))
        ess, resampled, min_d2 = np.full(n, np.nan), np.zeros(n, bool), np.full(n, np.nan)
        status, message = Status.COMPLETED, ""
        t0 = time.perf_counter()
        x_start, p_start, first = self.x0, self.P0, 0
        if self.gaussian_start:
            try:
                with np.errstate(over="ignore", invalid="ignore"):
                    x_start, p_start = self._ukf.step(self.x0, self.P0, zz[0])
            except (scipy.linalg.LinAlgError, ValueError):
                x_start = p_start = np.full(1, np.nan)
            first = 1
        if not (np.all(np.isfinite(x_start)) and np.all(np.isfinite(p_start))):
            status, message, n = Status.ERROR, "pf: step 0: the Gaussian start (UKF update of x0, P0 with z[0]) failed", 0
        else:
            particles = self._normalised(x_start + rng.standard_normal((npart, nx)) @ _square_root(p_start).T)
            if self._qs is not None:
                particles[:, self._qs] = _aligned(particles[:, self._qs], x_start[self._qs])
            log_w = np.full(npart, -np.log(npart))
            ref = x_start[self._qs] if self._qs is not None else None
            if first:
                with np.errstate(over="ignore", invalid="ignore"):
                    xs[0], aligned = _weighted_mean(particles, np.exp(log_w), self._qs, ref)
                    ps[0] = (aligned - xs[0]).T @ (aligned - xs[0]) / npart
                    ess[0], min_d2[0] = npart, float(self._distances(zz[0], self._h(particles), self._r_white).min())
                if not (np.all(np.isfinite(xs[0])) and np.all(np.isfinite(ps[0]))):
                    status, message, n = Status.ERROR, "pf: step 0: the Gaussian start's cloud is not finite", 0
        k = min(first, n)
        with np.errstate(over="ignore", invalid="ignore"):  # an overflow is a lost measurement, checked below
            for k in range(first, n):
                try:
                    particles, d2 = self._propagate(particles, np.exp(log_w), zz[k], rng)
                except (scipy.linalg.LinAlgError, ValueError) as exc:
                    status, message = Status.ERROR, f"pf: step {k}: proposal covariance not positive definite or not finite ({exc})"
                    break
                min_d2[k] = float(d2.min()) if np.all(np.isfinite(d2)) else np.inf
                if not min_d2[k] <= self._lost_d2:
                    status = Status.ERROR
                    message = f"pf: step {k}: measurement lost (smallest d2 {min_d2[k]:.4g} > chi2 quantile {self._lost_d2:.4g})"
                    break
                log_w = log_w - 0.5 * d2
                log_w -= scipy.special.logsumexp(log_w)
                w = np.exp(log_w)
                ess[k] = 1.0 / float(w @ w)
                if ess[k] <= 1.0 + _DEGENERATE_ESS:
                    status, message = Status.ERROR, f"pf: step {k}: weights degenerate (ESS {ess[k]:.6g}: one particle)"
                    break
                xs[k], aligned = _weighted_mean(particles, w, self._qs, ref)
                d = aligned - xs[k]
                ps[k] = (d.T * w) @ d
                if not (np.all(np.isfinite(xs[k])) and np.all(np.isfinite(ps[k]))):
                    status, message = Status.ERROR, f"pf: step {k}: weighted mean or covariance not finite"
                    break
                if self._qs is not None:
                    ref = xs[k, self._qs]
                if ess[k] < self.resample_threshold * npart:
                    particles = aligned[self._resample(w, rng)]
                    if self.bandwidth > 0.0:
                        particles = self._regularise(particles, w @ aligned, ps[k], rng)
                    log_w = np.full(npart, -np.log(npart))
                    resampled[k] = True
            else:
                k = n
        elapsed = time.perf_counter() - t0
        if status is Status.COMPLETED:
            message = (
                f"pf: filtered {n} samples, {npart} particles, {int(resampled.sum())} resamplings, "
                f"ESS min {np.nanmin(ess):.4g} median {np.nanmedian(ess):.4g}"
            )
        else:
            _LOG.warning(message)
        last = min(k + 1, n)
        return ParticleRun(
            name=self.name,
            x=xs[:k],
            P=ps[:k],
            step_time_s=elapsed / max(k, 1),
            status=status,
            message=message,
            quaternion_slice=self._qs,
            ess=ess[:last],
            resampled=resampled[:last],
            min_d2=min_d2[:last],
        )

    def __repr__(self) -> str:
        return (
            f"ParticleFilter(nx={self.model.nx}, nz={self.model.nz}, n_particles={self.n_particles}, seed={self.seed}, "
            f"resample_threshold={self.resample_threshold}, bandwidth={self.bandwidth})"
        )
