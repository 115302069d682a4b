"""The Kalman filters of the loop: the stationary Kalman filter of the tool position, and the
Kalman and extended Kalman filters of the end-effector state.

* :class:`StationaryKalman`, :func:`tune_position_noise`: the stationary Kalman filter for the
  tool position (Dressler (2012), eqs. 7.19-7.22), described below.
* :class:`KalmanFilter`, :class:`ExtendedKalmanFilter`: the Kalman filter of the linear
  (translation-only) and the extended Kalman filter of the 19-D end-effector model of the
  laser tracker + IMU fusion (Cvitanic (2021), section 4.1); both run the one CasADi
  predict-update step of :mod:`gtmodel.estimation.filters.gaussian`.

Stationary Kalman filter for the tool position (Dressler (2012), eqs. 7.19-7.22).

Model, per direction ``j`` (x, y, ...): the tool position extended with velocity and
acceleration states, driven by white jerk (7.19)::

    x_j = [p, v, a],   x_j[k+1] = A1 x_j[k] + G1 w_j[k],   w_j ~ N(0, jerk_noise_j^2)
    y_j = [z_kin, a_m] = C1 x_j + e_j,  e_j ~ N(0, diag(position_noise_j^2, accelerometer_noise_j^2))

``A1, G1`` are the zero-order-hold discretisation (:func:`control.c2d`) of the triple
integrator (:func:`~gtmodel.estimation.filters.end_effector.constant_acceleration`, shared with the
19-D end-effector model of the laser tracker + IMU fusion) ``p' = v, v' = a, a' = jerk`` (jerk constant over a sample), so
``A1 = [[1, dt, dt^2/2], [0, 1, dt], [0, 0, 1]]``, ``G1 = [dt^3/6, dt^2/2, dt]``;
``C1 = [[1, 0, 0], [0, 0, 1]]``. The ``d`` directions are stacked as
``x = [p_1..p_d, v_1..v_d, a_1..a_d]`` (3d) and ``y = [z_kin_1..z_kin_d, a_m_1..a_m_d]`` (2d):
``A = kron(A1, I_d)``, ``C = kron(C1, I_d)``, ``G = kron(G1, I_d)``.

Stationary gain (7.20)-(7.21): the a-priori covariance ``P`` solves the discrete
Riccati equation; :func:`control.dlqe` gives ``P`` and the predictor gain
``L = A P C^T (C P C^T + R)^-1``; the measurement-update gain is
``M = P C^T (C P C^T + R)^-1`` (``L = A M``). The filter step (7.22), predictor-corrector::

    x_corr = x + M (y - C x)       (estimate after the measurement y[k])
    z_hat  = H x_corr              (H picks the positions)
    x_next = A x_corr              (prediction of the state at k + 1)

is ONE CasADi Function ``"kalman_step"(x[3d], y[2d]) -> (x_next[3d], z_hat[d])``
(:meth:`StationaryKalman.step_function`); :meth:`StationaryKalman.estimate` runs it over a
record through :meth:`casadi.Function.mapaccum`, and the generated C runs the same graph.

Noise choices (a decision; the thesis gives the model and the accelerometer noise):

* ``accelerometer_noise`` 0.07 m/s^2 (the sensor, spec section 7).
* The kinematic position's error is the structural deflection, tens of um, but it is
  not white: it is concentrated at the resonances (7.4 Hz x, 11.5 Hz y). Modelled as
  white noise of its RMS size (e.g. 30 um), the optimal filter trusts ``z_kin`` up to
  15-25 Hz, above the resonances, and would not see the deflection at all. Lowering
  ``jerk_noise`` instead lowers the crossover but makes the acceleration state a slow
  average of ``a_m``: the estimate then stops following the true motion above the
  crossover (measured: 95 % of a consistent 7.4 Hz motion is lost with 30 um and the
  jerk noise tuned to a 4.5 Hz crossover). So the jerk noise is large (100 m/s^3 per
  sample, the order of the jerk of the planned motions: 1 m/s^2 changed within
  10 ms), which makes the acceleration state follow ``a_m`` (the accelerometer is
  trusted as the tool acceleration), and ``position_noise`` is the white-noise level
  with the same spectral density as the deflection near its resonance (hundreds of um:
  a 20 um RMS deflection concentrated in ~2 Hz has the density of white noise of
  ~0.16 mm RMS over the 125 Hz band). It is tuned (:func:`tune_position_noise`) so that
  the filter's crossover, the -3 dB frequency of the ``z_kin`` path (as for the
  complementary filter), is at the complementary cut-offs: 0.358 mm (x, 4.502 Hz) and
  1.064 mm (y, 2.630 Hz) (:data:`DEFAULT_POSITION_NOISE`). With them the estimator is nearly
  complementary: a consistent motion (``z_kin = z``, ``a_m = z''``) is lost by 0.4 % at
  7.4 Hz (x) and 0.9 % at 11.5 Hz (y), and 42 % (x, 7.4 Hz) and 16 % (y, 11.5 Hz) of a
  deflection the kinematic position misses remain in the estimate (``|T_kin|``).

The price of a causal filter (measured, not a choice): the accelerometer path of a
causal estimator with this crossover passes the accelerometer noise's low frequencies
with the flat gain ``~1 / (2 pi f_c)^2``, where the zero-phase complementary filter
rolls it off (``1 - |H|^2 ~ f^4``). With 0.07 m/s^2 white noise per 4 ms sample the
estimate carries about 45 um RMS of noise in x and 170 um in y (the complementary filter:
6 um and 14 um); a deflection must be larger than that for the estimate to be closer to
the truth than ``z_kin``. Neither a smaller jerk noise nor an accelerometer-bias state
changes this much at a given crossover (tried); a higher crossover lowers the noise but
leaves the resonances in the kinematic path.
"""

from __future__ import annotations

import math
from typing import Any

import casadi as ca
import numpy as np
import scipy.linalg
import scipy.optimize

from gtmodel._lazy import lazy_module
from gtmodel._arrays import as_array, as_finite, as_per_axis, as_signal, positive_float, positive_int
from gtmodel.defaults import LOOP_PERIOD_S
from gtmodel.errors import InputError
from gtmodel.estimation.filters.end_effector import EndEffectorModel, constant_acceleration
from gtmodel.estimation.filters.gaussian import FilterRun, _GaussianFilter

#: python-control, imported on first use (it imports matplotlib.pyplot: ~2 s of CPU).
control = lazy_module("control")

__all__ = [
    "StationaryKalman",
    "tune_position_noise",
    "KalmanFilter",
    "ExtendedKalmanFilter",
    "DEFAULT_POSITION_NOISE",
    "DEFAULT_JERK_NOISE",
    "DEFAULT_ACCELEROMETER_NOISE",
]

#: Accelerometer noise [m/s^2] (1 sigma per sample), spec section 7.
DEFAULT_ACCELEROMETER_NOISE = 0.07
#: Jerk noise [m/s^3] (1 sigma per sample, jerk constant over the sample), x and y.
DEFAULT_JERK_NOISE = (100.0, 100.0)
#: Kinematic-position noise [m] (1 sigma), x and y: crossovers 4.50 Hz and 2.63 Hz (module docstring).
DEFAULT_POSITION_NOISE = (0.358e-3, 1.064e-3)

_MINUS_3_DB = 1.0 / math.sqrt(2.0)


class StationaryKalman:
    """Stationary Kalman filter of the tool position from ``z_kin`` and ``a_m`` (Dressler (2012), eqs. 7.19-7.22).

    See the module docstring for the model, the state ordering and the noise choices.

    Parameters
    ----------
    dt : float, optional
        Sample time [s].
    accelerometer_noise : float or array_like, shape (d,), optional
        Standard deviation of the accelerometer noise [m/s^2] per sample.
    position_noise : float or array_like, shape (d,), optional
        Standard deviation of the kinematic position's error [m] (see the module docstring).
    jerk_noise : float or array_like, shape (d,), optional
        Standard deviation of the jerk [m/s^3] per sample (constant over the sample).
    d : int, optional
        Number of directions (x, y: 2).

    Attributes
    ----------
    dt : float
        Sample time [s].
    d : int
        Number of directions.
    A : numpy.ndarray, shape (3d, 3d)
        State transition ``kron(A1, I_d)`` (7.19).
    G : numpy.ndarray, shape (3d, d)
        Jerk input ``kron(G1, I_d)``.
    C : numpy.ndarray, shape (2d, 3d)
        Measurement matrix, ``y = [z_kin, a_m] = C x``.
    H : numpy.ndarray, shape (d, 3d)
        Output matrix picking the positions, ``z_hat = H x_corr``.
    Q : numpy.ndarray, shape (3d, 3d)
        Process noise covariance ``G diag(jerk_noise^2) G^T``.
    R : numpy.ndarray, shape (2d, 2d)
        Measurement noise covariance ``diag(position_noise^2, accelerometer_noise^2)``.
    P : numpy.ndarray, shape (3d, 3d)
        A-priori (predicted) error covariance, the Riccati solution (7.21).
    L : numpy.ndarray, shape (3d, 2d)
        Predictor gain ``A P C^T (C P C^T + R)^-1`` from :func:`control.dlqe`.
    M : numpy.ndarray, shape (3d, 2d)
        Measurement-update gain ``P C^T (C P C^T + R)^-1`` (7.20).
    poles : numpy.ndarray, shape (3d,)
        Eigenvalues of ``A - L C`` (the estimator's poles, inside the unit circle).
    accelerometer_noise, position_noise, jerk_noise : numpy.ndarray, shape (d,)
        The noise levels used.

    Raises
    ------
    InputError
        ``dt`` or a noise not positive, a noise of another shape than ``(d,)``, ``d`` not
        a positive integer.
    """

    def __init__(
        self,
        dt: float = LOOP_PERIOD_S,
        accelerometer_noise: Any = DEFAULT_ACCELEROMETER_NOISE,
        position_noise: Any = DEFAULT_POSITION_NOISE,
        jerk_noise: Any = DEFAULT_JERK_NOISE,
        d: int = 2,
    ) -> None:
        self.dt = positive_float(dt, "dt")
        self.d = positive_int(d, "d")
        self.accelerometer_noise = as_per_axis(accelerometer_noise, self.d, "accelerometer_noise", positive=True)
        self.position_noise = as_per_axis(position_noise, self.d, "position_noise", positive=True)
        self.jerk_noise = as_per_axis(jerk_noise, self.d, "jerk_noise", positive=True)
        self.A, self.G = constant_acceleration(self.dt, self.d)  # kron(A1, I_d), kron(G1, I_d): shared with the 19-D model
        eye = np.eye(self.d)
        self.C = np.kron(np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]), eye)
        self.H = np.kron(np.array([[1.0, 0.0, 0.0]]), eye)
        q = (self.G * self.jerk_noise**2) @ self.G.T
        self.Q = 0.5 * (q + q.T)
        self.R = np.diag(np.concatenate([self.position_noise**2, self.accelerometer_noise**2]))
        # (7.21): Riccati equation through python-control (G = I: the covariance Q is given whole).
        L, P, E = control.dlqe(self.A, np.eye(3 * self.d), self.C, self.Q, self.R)
        self.L = np.asarray(L)
        self.P = np.asarray(P)
        self.poles = np.asarray(E)
        s = self.C @ self.P @ self.C.T + self.R
        self.M = scipy.linalg.solve(s, self.C @ self.P, assume_a="pos").T
        self._step: ca.Function | None = None

    def step_function(self) -> ca.Function:
        """The filter step as one CasADi Function (Dressler (2012), eq. 7.22).

        ``"kalman_step"(x[3d], y[2d]) -> (x_next[3d], z_hat[d])`` with
        ``x_corr = x + M (y - C x)``, ``z_hat = H x_corr``, ``x_next = A x_corr``.
        ``x`` is the predicted state ``[p, v, a]`` (stacked per direction, see the module
        docstring), ``y = [z_kin, a_m]`` the measurements of the current sample.

        Returns
        -------
        casadi.Function
            Named ``"kalman_step"``, inputs ``x``, ``y``, outputs ``x_next``, ``z_hat``
            (the same object on every call).
        """
        if self._step is None:
            x = ca.SX.sym("x", 3 * self.d)
            y = ca.SX.sym("y", 2 * self.d)
            x_corr = x + ca.mtimes(ca.DM(self.M), y - ca.mtimes(ca.DM(self.C), x))
            self._step = ca.Function(
                "kalman_step",
                [x, y],
                [ca.mtimes(ca.DM(self.A), x_corr), ca.mtimes(ca.DM(self.H), x_corr)],
                ["x", "y"],
                ["x_next", "z_hat"],
            )
        return self._step

    def initial_state(self, z_kin0: Any, a_m0: Any) -> np.ndarray:
        """The predicted state before the first sample: ``[z_kin[0], 0, a_m[0]]`` (start at rest).

        Parameters
        ----------
        z_kin0 : array_like, shape (d,)
            First kinematic position [m].
        a_m0 : array_like, shape (d,)
            First measured acceleration [m/s^2].

        Returns
        -------
        numpy.ndarray, shape (3d,)
            ``[p, v, a]`` stacked per direction, velocity 0 (the loop starts at rest).

        Raises
        ------
        InputError
            Another shape or not finite.
        """
        z0 = as_signal(np.reshape(z_kin0, (1, -1)) if np.ndim(z_kin0) == 1 else z_kin0, "z_kin0", self.d, 1)[0]
        a0 = as_signal(np.reshape(a_m0, (1, -1)) if np.ndim(a_m0) == 1 else a_m0, "a_m0", self.d, 1)[0]
        return np.concatenate([z0, np.zeros(self.d), a0])

    def run(self, z_kin: Any, a_m: Any, x0: Any = None) -> tuple[np.ndarray, np.ndarray]:
        """Run the step Function over a record (:meth:`casadi.Function.mapaccum`).

        Parameters
        ----------
        z_kin : array_like, shape (N, d)
            Kinematic tool position [m].
        a_m : array_like, shape (N, d)
            Measured tool acceleration [m/s^2].
        x0 : array_like, shape (3d,), optional
            Predicted state before sample 0; default :meth:`initial_state` of the first samples.

        Returns
        -------
        z_hat : numpy.ndarray, shape (N, d)
            Position estimates ``H x_corr`` [m].
        x_next : numpy.ndarray, shape (N, 3d)
            Predicted states after each sample.

        Raises
        ------
        InputError
            Signals of another shape or length, or not finite; ``x0`` not of shape ``(3d,)``.
        """
        zk = as_signal(z_kin, "z_kin", self.d)
        am = as_signal(a_m, "a_m", self.d, zk.shape[0], like="z_kin")
        if x0 is None:
            x_init = self.initial_state(zk[0], am[0])
        else:
            x_init = as_array(x0, (3 * self.d,), "x0")
        runner = self.step_function().mapaccum("kalman_run", zk.shape[0])
        x_next, z_hat = runner(x_init, np.hstack([zk, am]).T)
        return np.asarray(z_hat).T, np.asarray(x_next).T

    def estimate(self, z_kin: Any, a_m: Any) -> np.ndarray:
        """Tool-position estimate ``z_hat`` (Dressler (2012), eq. 7.22), started at rest (:meth:`initial_state`).

        Parameters
        ----------
        z_kin : array_like, shape (N, d)
            Kinematic tool position ``fk(q_m)`` [m], rows ``dt`` apart.
        a_m : array_like, shape (N, d)
            Measured tool acceleration [m/s^2].

        Returns
        -------
        numpy.ndarray, shape (N, d)
            Estimated tool position [m].

        Raises
        ------
        InputError
            Signals of another shape or length, or not finite.
        """
        return self.run(z_kin, a_m)[0]

    def lifted(self, n: int) -> tuple[np.ndarray, np.ndarray]:
        """Lifted matrices of :meth:`estimate` on ``n`` samples: ``z_hat[:, j] = F_kin[j] z_kin[:, j] + F_acc[j] a_m[:, j]``.

        The operator is applied to the identity columns ``e_0`` and ``e_1`` of each input
        (all directions at once: they are decoupled). Column 0 includes the initial state
        (:meth:`initial_state` reads sample 0); columns ``i >= 1`` are the response to
        ``e_1`` shifted by ``i - 1`` (:func:`scipy.linalg.toeplitz`), which is exactly the
        response to ``e_i``: the filter is time-invariant and its state is exactly 0
        until the impulse. So the matrices agree with :meth:`estimate` to rounding.

        Parameters
        ----------
        n : int
            Number of samples.

        Returns
        -------
        F_kin : numpy.ndarray, shape (d, n, n)
            From the kinematic position [m/m].
        F_acc : numpy.ndarray, shape (d, n, n)
            From the measured acceleration [m/(m/s^2)].

        Raises
        ------
        InputError
            ``n`` not a positive integer.
        """
        n = positive_int(n, "n")
        out = []
        for which in range(2):  # 0: z_kin, 1: a_m
            cols = []
            for k in range(min(2, n)):
                sig = [np.zeros((n, self.d)), np.zeros((n, self.d))]
                sig[which][k] = 1.0
                cols.append(self.estimate(*sig))  # (n, d)
            f = np.empty((self.d, n, n))
            for j in range(self.d):
                f[j, :, 0] = cols[0][:, j]
                if n > 1:
                    h = cols[1][:, j]
                    f[j, :, 1:] = scipy.linalg.toeplitz(np.concatenate([[0.0], h[1:]]), np.zeros(n))[:, :-1]
            out.append(f)
        return out[0], out[1]

    def direction_system(self, j: int) -> control.StateSpace:
        """The estimator of direction ``j`` as a discrete state-space system ``[z_kin_j, a_m_j] -> z_hat_j``.

        ``x[k+1] = (A - L C) x[k] + L y[k]``, ``z_hat[k] = H (I - M C) x[k] + H M y[k]``
        restricted to the states of direction ``j`` (the directions are decoupled).

        Parameters
        ----------
        j : int
            Direction index, ``0 <= j < d``.

        Returns
        -------
        control.StateSpace
            Discrete (``dt``), 3 states, 2 inputs, 1 output.

        Raises
        ------
        InputError
            ``j`` not a direction index.
        """
        if isinstance(j, bool) or not isinstance(j, (int, np.integer)) or not 0 <= j < self.d:
            raise InputError(f"j: expected a direction index in [0, {self.d}), got {j!r}")
        s = [j, self.d + j, 2 * self.d + j]
        m = [j, self.d + j]
        eye = np.eye(3 * self.d)
        a = (self.A - self.L @ self.C)[np.ix_(s, s)]
        b = self.L[np.ix_(s, m)]
        c = (self.H @ (eye - self.M @ self.C))[np.ix_([j], s)]
        dd = (self.H @ self.M)[np.ix_([j], m)]
        return control.ss(a, b, c, dd, self.dt)

    def frequency_response(self, f_hz: Any) -> tuple[np.ndarray, np.ndarray]:
        """Frequency responses of the two paths, ``z_kin -> z_hat`` and ``a_m -> z_hat``.

        Parameters
        ----------
        f_hz : array_like, shape (F,)
            Frequencies [Hz] in ``[0, 1 / (2 dt)]``.

        Returns
        -------
        T_kin : numpy.ndarray, shape (d, F), complex
            Kinematic path [1].
        T_acc : numpy.ndarray, shape (d, F), complex
            Accelerometer path [m/(m/s^2)].

        Raises
        ------
        InputError
            Frequencies not finite, negative, above Nyquist or not 1-D.
        """
        f = np.atleast_1d(as_finite(f_hz, "f_hz", nonnegative=True))
        if f.ndim != 1:
            raise InputError(f"f_hz: expected a 1-D array of frequencies, got shape {f.shape}")
        if np.any(f > 0.5 / self.dt):
            raise InputError(f"f_hz: expected frequencies up to Nyquist {0.5 / self.dt:g} Hz, got max {f.max()!r}")
        zs = np.exp(2j * np.pi * f * self.dt)
        resp = [np.asarray(self.direction_system(j)(zs)) for j in range(self.d)]  # (1, 2, F) each
        return np.stack([r.reshape(2, -1)[0] for r in resp]), np.stack([r.reshape(2, -1)[1] for r in resp])

    def crossover_hz(self) -> np.ndarray:
        """The crossover per direction: the frequency where ``|T_kin|`` falls through -3 dB.

        The same definition as the complementary filter's cut-off (the kinematic path
        passes low frequencies; the causal filter peaks above 1 before the crossover).

        Returns
        -------
        numpy.ndarray, shape (d,)
            Crossover frequencies [Hz] (:func:`scipy.optimize.brentq` on a 0.05 Hz grid bracket).
            NaN for a direction whose ``|T_kin|`` stays above -3 dB up to Nyquist.
        """
        grid = np.linspace(0.0, 0.5 / self.dt, int(round(10.0 / self.dt)) + 1)
        mag = np.abs(self.frequency_response(grid)[0])
        out = np.full(self.d, np.nan)
        for j in range(self.d):
            below = np.nonzero(mag[j] < _MINUS_3_DB)[0]
            if below.size:
                k = int(below[0])
                sys_j = self.direction_system(j)

                def excess(f: float, sys_j: control.StateSpace = sys_j) -> float:
                    return abs(complex(np.asarray(sys_j(np.exp(2j * np.pi * f * self.dt))).reshape(2)[0])) - _MINUS_3_DB

                out[j] = scipy.optimize.brentq(excess, grid[k - 1], grid[k], xtol=1e-10)
        return out

    def __repr__(self) -> str:
        return (
            f"StationaryKalman(dt={self.dt}, accelerometer_noise={self.accelerometer_noise.tolist()}, "
            f"position_noise={self.position_noise.tolist()}, jerk_noise={self.jerk_noise.tolist()}, d={self.d})"
        )


def tune_position_noise(
    crossover_hz: float,
    dt: float = LOOP_PERIOD_S,
    accelerometer_noise: float = DEFAULT_ACCELEROMETER_NOISE,
    jerk_noise: float = DEFAULT_JERK_NOISE[0],
) -> float:
    """The position noise that puts the Kalman filter's crossover at ``crossover_hz``.

    One direction; :func:`scipy.optimize.brentq` on ``log(position_noise)`` in
    ``[1e-9, 1]`` m over :meth:`StationaryKalman.crossover_hz` (which falls as the
    position noise grows).

    Parameters
    ----------
    crossover_hz : float
        Wanted -3 dB frequency of the ``z_kin`` path [Hz].
    dt : float, optional
        Sample time [s].
    accelerometer_noise : float, optional
        Accelerometer noise [m/s^2].
    jerk_noise : float, optional
        Jerk noise [m/s^3].

    Returns
    -------
    float
        Position noise [m].

    Raises
    ------
    InputError
        A non-positive argument, or a crossover no position noise in ``[1e-9, 1]`` m reaches
        (message names ``crossover_hz`` and the reachable range).
    """
    target = positive_float(crossover_hz, "crossover_hz")

    def crossover(log_sp: float) -> float:
        f = float(StationaryKalman(dt, accelerometer_noise, math.exp(log_sp), jerk_noise, d=1).crossover_hz()[0])
        return 0.5 / dt if math.isnan(f) else f  # above -3 dB up to Nyquist

    lo, hi = math.log(1e-9), math.log(1.0)
    f_lo, f_hi = crossover(lo), crossover(hi)
    if not (f_hi < target < f_lo):
        raise InputError(f"crossover_hz: expected a frequency in ({f_hi:.4g}, {f_lo:.4g}) Hz for these noises, got {crossover_hz!r}")
    return math.exp(scipy.optimize.brentq(lambda v: crossover(v) - target, lo, hi, xtol=1e-12))


class ExtendedKalmanFilter(_GaussianFilter):
    """Extended Kalman filter of the end-effector state (Cvitanic (2021), section 4.1; the step: :mod:`gtmodel.estimation.filters.gaussian`).

    The step linearises the model's CasADi transition and measurement by AD
    (:attr:`EndEffectorModel.transition_jacobian`, :attr:`EndEffectorModel.measurement_jacobian`);
    on a linear model it is exactly the Kalman filter.

    Parameters
    ----------
    model : EndEffectorModel
        The state model (the filter's belief of the IMU-to-target transform).
    Q : array_like, shape (nx, nx)
        Process-noise covariance per sample, symmetric positive semi-definite
        (e.g. :meth:`EndEffectorModel.process_noise`).
    R : array_like, shape (nz, nz)
        Measurement-noise covariance, symmetric positive definite
        (e.g. :meth:`EndEffectorModel.measurement_noise`).
    x0 : array_like, shape (nx,)
        Initial estimate (posterior of the sample before the first measurement); its quaternion
        is normalised.
    P0 : array_like, shape (nx, nx)
        Its covariance, symmetric positive definite.
    compiled : bool, optional
        :meth:`run` evaluates the step as C compiled from the same graph
        (:func:`gtmodel._compiler.compiled_function`: cached; the CasADi interpreter when no
        compiler is found or ``GTMODEL_COMPILE=0``). The first run of a graph builds it
        (seconds); :meth:`step_function` is the CasADi Function either way.

    Attributes
    ----------
    model : EndEffectorModel
    nx, nz : int
    Q, R, P0 : numpy.ndarray
        The covariances (symmetrised).
    x0 : numpy.ndarray, shape (nx,)
    compiled : bool

    Raises
    ------
    InputError
        ``model`` not an EndEffectorModel; a matrix of another shape, not finite, not symmetric,
        ``Q`` not positive semi-definite, ``R`` or ``P0`` not positive definite; ``x0`` of another
        shape, not finite, or with a quaternion of zero norm; ``compiled`` not a bool.
    """

    _name = "ekf"

    def step_function(self) -> ca.Function:
        """The EKF step ``"ekf_step"(x[nx], P[nx, nx], z[nz]) -> (x_next, P_next, pivots[nz + nx])``.

        Returns
        -------
        casadi.Function
            See :mod:`gtmodel.estimation.filters.gaussian`; the same object on every call.
        """
        return super().step_function()

    def run(self, z: Any) -> FilterRun:
        """Filter a record (:meth:`casadi.Function.mapaccum` of :meth:`step_function`).

        Parameters
        ----------
        z : array_like, shape (N, nz)
            Measurements in the model's order [SI].

        Returns
        -------
        FilterRun
            Named ``"ekf"``; ``status`` ``"error"`` with the arrays cut at a failing sample.

        Raises
        ------
        InputError
            ``z`` of another shape or not finite.
        """
        return super().run(z)


class KalmanFilter(_GaussianFilter):
    """Kalman filter of the translation-only (linear) end-effector model (Cvitanic (2021), section 4.1).

    The same graph as :class:`ExtendedKalmanFilter` (one implementation): on the linear model
    the Jacobians are the constant matrices ``A = kron(A1, I_3)`` and ``C``.

    Parameters
    ----------
    model : EndEffectorModel
        A linear model (``rotation=False``).
    Q : array_like, shape (nx, nx)
        Process-noise covariance per sample, symmetric positive semi-definite.
    R : array_like, shape (nz, nz)
        Measurement-noise covariance, symmetric positive definite.
    x0 : array_like, shape (nx,)
        Initial estimate.
    P0 : array_like, shape (nx, nx)
        Its covariance, symmetric positive definite.
    compiled : bool, optional
        Evaluate :meth:`run` as compiled C (see :class:`ExtendedKalmanFilter`).

    Attributes
    ----------
    model : EndEffectorModel
    nx, nz : int
    Q, R, P0 : numpy.ndarray
    x0 : numpy.ndarray, shape (nx,)
    compiled : bool

    Raises
    ------
    InputError
        As :class:`ExtendedKalmanFilter`, and a model that is not linear.
    """

    _name = "kf"

    def __init__(self, model: EndEffectorModel, Q: Any, R: Any, x0: Any, P0: Any, compiled: bool = False) -> None:
        if isinstance(model, EndEffectorModel) and not model.is_linear:
            raise InputError("model: expected a linear model (EndEffectorModel(rotation=False)) for the Kalman filter; use ExtendedKalmanFilter")
        super().__init__(model, Q, R, x0, P0, compiled)

    def step_function(self) -> ca.Function:
        """The KF step ``"kf_step"(x[nx], P[nx, nx], z[nz]) -> (x_next, P_next, pivots[nz + nx])``.

        Returns
        -------
        casadi.Function
            See :mod:`gtmodel.estimation.filters.gaussian`; the same object on every call.
        """
        return super().step_function()

    def run(self, z: Any) -> FilterRun:
        """Filter a record (:meth:`casadi.Function.mapaccum` of :meth:`step_function`).

        Parameters
        ----------
        z : array_like, shape (N, nz)
            Measurements ``[p_m, a_m]`` [m, m/s^2].

        Returns
        -------
        FilterRun
            Named ``"kf"``.

        Raises
        ------
        InputError
            ``z`` of another shape or not finite.
        """
        return super().run(z)
