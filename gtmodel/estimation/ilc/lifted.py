"""Lifted-system operators of iterative learning control and their stability checks.

Dressler (2012), eqs. 7.2-7.16. One trial of ``n`` samples of a linear, time-invariant,
causal plant is the matrix ``T`` (``y = T u``, eq. 7.9): the lower-triangular Toeplitz
matrix of its impulse response ``h`` (``h[0]`` the direct feedthrough, ``h[delay]`` the
first non-zero sample of a plant with a dead time). The ILC update (7.2)::

    u_{k+1} = Q (u_k + L eps_k)

has the learning filter ``L = gamma q^delta`` (:class:`LearningFilter`, a non-causal
shift by ``delta`` samples, gain ``gamma``) and the robustness filter ``Q``
(:class:`QFilter`): a Butterworth low-pass applied forward and backward (zero phase) and
then the time window of :func:`time_window` (Tukey, 200 points, alpha 0.95, rising over
the 100-sample lead-in, falling over the lead-out). Both are linear operators on a
trial; their lifted matrices are built by applying them to the columns of the identity,
so the matrices equal the operators to rounding.

With ``eps_k = r - z_hat_k`` and ``z_hat = T u + (terms that do not depend on u)``, the
correction evolves as ``u_{k+1} = Q (I - L T) u_k + const``:

- asymptotic stability (7.15): ``rho(Q (I - L T)) < 1`` (spectral radius);
- monotone convergence of ``u_k`` to its limit in the 2-norm (7.16):
  ``sigma_max(Q (I - L T)) < 1`` (largest singular value).

``T = F_u + F_y T_uy`` in the thesis' notation: the map from the correction to the
estimate used in the error (:func:`stability` takes it as given, built by the caller).

Closed form used by the tests: with a first-order-plus-delay plant
``y_k = a y_(k-1) + b u_(k-delta)`` and ``L = gamma q^delta``, ``L T`` is lower
triangular with ``gamma b`` on the diagonal of its first ``n - delta`` rows and zero on
the last ``delta`` rows (the shift reads beyond the end of the trial: nothing is learned
there). So with ``Q = I`` the eigenvalues are ``1 - gamma b`` and ``1`` (marginal: the
last ``delta`` samples of the correction never change), and with the time window alone
as ``Q`` (``cutoff_hz=None``), ``rho = |1 - gamma b|`` exactly.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass
from typing import Any

import numpy as np
import scipy.linalg
import scipy.signal

from gtmodel.estimation.filters.complementary import MIN_CUTOFF_FRACTION

from gtmodel._arrays import as_finite, as_signal, as_vector, positive_float, positive_int
from gtmodel.defaults import LOOP_PERIOD_S
from gtmodel.errors import InputError

__all__ = ["lifted_matrix", "time_window", "QFilter", "RobustQFilter", "LearningFilter", "ILCStability", "stability"]

_log = logging.getLogger("gtmodel")


def _lift(apply: Any, n: Any) -> np.ndarray:
    """The ``(n, n)`` matrix of a linear operator on ``(n,)`` signals: its images of the unit vectors."""
    n = positive_int(n, "n")
    return np.asarray(apply(np.eye(n)), dtype=float)


def lifted_matrix(h: Any) -> np.ndarray:
    """Lower-triangular Toeplitz matrix of an impulse response: one trial of an LTI plant.

    Dressler (2012), eq. 7.9: ``y = T u`` with ``T[i, j] = h[i - j]`` for ``i >= j`` and 0
    above the diagonal (causal); built with :func:`scipy.linalg.toeplitz`.

    Parameters
    ----------
    h : array_like, shape (n,)
        Impulse response, ``h[0]`` the response at the sample of the impulse (unit of the
        output per unit of the input).

    Returns
    -------
    numpy.ndarray, shape (n, n)
        The lifted matrix ``T``.

    Raises
    ------
    InputError
        ``h`` not one-dimensional, empty or not finite.
    """
    h = as_vector(h, "h", what="impulse-response samples")
    return scipy.linalg.toeplitz(h, np.zeros(h.size))


def time_window(n: int, lead: int = 100, tukey_points: int = 200, alpha: float = 0.95) -> np.ndarray:
    """Time window of the Q filter: rising over the lead-in, 1 in between, falling over the lead-out.

    Dressler (2012), ch. 7.3 (Tukey window, 200 points, alpha 0.95, 100-sample lead-in and
    lead-out). Interpretation: ``w = scipy.signal.windows.tukey(tukey_points, alpha)`` is cut
    into its rising half ``w[:tukey_points // 2]`` and its falling half
    ``w[tukey_points // 2:]``; the rising half ends with the last sample of the lead-in
    (samples ``lead - tukey_points // 2 .. lead - 1``; zeros before it when ``lead`` is
    longer), the falling half starts with the first sample of the lead-out (samples
    ``n - lead ..``), and the window is 1 in between. With the defaults the first 100
    samples are the rising half of ``tukey(200, 0.95)`` (starting at 0) and the last 100
    its falling half (ending at 0). Where the window is exactly 1 the correction is
    applied in full ("fully corrected samples", see :func:`gtmodel.estimation.error_measure`).

    Parameters
    ----------
    n : int
        Trial length in samples (``n >= 2 * lead``).
    lead : int, optional
        Lead-in and lead-out length in samples (default 100).
    tukey_points : int, optional
        Length of the Tukey window cut in halves (default 200; even, at most ``2 * lead``).
    alpha : float, optional
        Tukey shape parameter, fraction of the window inside the cosine tapers (default
        0.95; ``0 <= alpha <= 1``).

    Returns
    -------
    numpy.ndarray, shape (n,)
        The weights, in ``[0, 1]``.

    Raises
    ------
    InputError
        Non-positive ``n``, ``lead`` or ``tukey_points``, odd ``tukey_points``,
        ``tukey_points > 2 * lead``, a window longer than the signal (``2 * lead > n``) or
        ``alpha`` outside ``[0, 1]``.
    """
    n = positive_int(n, "n")
    lead = positive_int(lead, "lead")
    tukey_points = positive_int(tukey_points, "tukey_points")
    if tukey_points % 2:
        raise InputError(f"tukey_points: expected an even number of points (cut in two halves), got {tukey_points}")
    if tukey_points > 2 * lead:
        raise InputError(f"tukey_points: expected at most 2 * lead = {2 * lead} points, got {tukey_points}")
    if 2 * lead > n:
        raise InputError(f"lead: the window (lead-in + lead-out = {2 * lead} samples) is longer than the signal (n = {n})")
    alpha_v = as_finite(alpha, "alpha")
    if alpha_v.ndim != 0 or not 0.0 <= float(alpha_v) <= 1.0:
        raise InputError(f"alpha: expected a number in [0, 1], got {alpha!r}")
    half = tukey_points // 2
    taper = scipy.signal.windows.tukey(tukey_points, float(alpha_v))
    w = np.ones(n)
    w[: lead - half] = 0.0
    w[lead - half : lead] = taper[:half]
    w[n - lead : n - lead + half] = taper[half:]
    w[n - lead + half :] = 0.0
    return w


class QFilter:
    """Robustness filter Q of the ILC: zero-phase Butterworth low-pass, then a time window.

    Dressler (2012), eqs. 7.2 and 7.12-7.14 (Q), ch. 7.3 (design): the causal
    Butterworth filter ``scipy.signal.butter(order, cutoff_hz, fs=1/dt)`` is applied
    forward and backward (:func:`scipy.signal.sosfiltfilt`, SciPy's default odd
    extension at the ends: a linear operation), which gives zero phase and the squared
    magnitude (-6 dB at ``cutoff_hz``, the usual ``filtfilt`` convention: the cut-off is
    that of the causal filter); the result is multiplied by the time window (if any).

    Parameters
    ----------
    cutoff_hz : float or None
        Cut-off of the causal Butterworth filter [Hz], ``0 < cutoff_hz < 1 / (2 dt)``;
        None for no low-pass (the window only).
    dt : float, optional
        Sample time [s] (default the loop period, :data:`gtmodel.defaults.LOOP_PERIOD_S`).
    order : int, optional
        Order of the causal filter (default 2).
    window : array_like, shape (N,), optional
        Time window (e.g. :func:`time_window`); None for none. Signals filtered must then
        have ``N`` samples.

    Raises
    ------
    InputError
        Cut-off not in ``(0, Nyquist)`` (the message names ``cutoff_hz``), bad ``dt`` or
        ``order``, or a window that is not a finite 1-D array.

    Examples
    --------
    >>> q = QFilter(10.0, window=time_window(320))  # at the 4 ms loop period
    >>> q.lifted(320).shape
    (320, 320)
    """

    def __init__(self, cutoff_hz: float | None, dt: float = LOOP_PERIOD_S, order: int = 2, window: Any = None) -> None:
        self.dt = positive_float(dt, "dt")
        self.order = positive_int(order, "order")
        nyquist = 0.5 / self.dt
        if cutoff_hz is None:
            self.cutoff_hz = None
            self._sos = None
        else:
            c = as_finite(cutoff_hz, "cutoff_hz")
            lowest = MIN_CUTOFF_FRACTION / self.dt
            if c.ndim != 0 or not lowest <= float(c) < nyquist:
                raise InputError(f"cutoff_hz: expected a cut-off in [{lowest:g}, {nyquist:g}) Hz (below the Nyquist frequency of "
                                 f"dt = {self.dt:g} s; lower cut-offs give a numerically degenerate filter), got {cutoff_hz!r}")
            self.cutoff_hz = float(c)
            self._sos = scipy.signal.butter(self.order, self.cutoff_hz, btype="low", output="sos", fs=1.0 / self.dt)
        if window is None:
            self.window = None
        else:
            self.window = as_vector(window, "window", what="weights")

    def apply(self, x: Any) -> np.ndarray:
        """Filter a signal (each column separately): zero-phase low-pass, then the window.

        Dressler (2012), eq. 7.2 (the ``Q`` of ``u_{k+1} = Q (u_k + L eps_k)``).

        Parameters
        ----------
        x : array_like, shape (N,) or (N, d)
            Signal, rows are samples.

        Returns
        -------
        numpy.ndarray
            Same shape as ``x``.

        Raises
        ------
        InputError
            ``x`` not finite or of another shape, or ``N`` different from the window's length.
        """
        arr, single = as_signal(x, "x", vector=True), np.ndim(x) == 1
        if self.window is not None and arr.shape[0] != self.window.size:
            raise InputError(f"x: expected {self.window.size} samples (the window's length), got {arr.shape[0]}")
        out = self._filter(arr)
        if self.window is not None:
            out = out * self.window[:, None]
        return out[:, 0] if single else out

    def _filter(self, arr: np.ndarray) -> np.ndarray:
        """The filter alone on checked ``(N, d)`` columns: forward-backward Butterworth (or none)."""
        if self._sos is None:
            return arr
        try:
            return scipy.signal.sosfiltfilt(self._sos, arr, axis=0)
        except ValueError as exc:  # too short for the end extension
            raise InputError(f"x: {arr.shape[0]} samples are too few for the forward-backward filter ({exc})") from None

    def lifted(self, n: int) -> np.ndarray:
        """The lifted matrix of :meth:`apply` on ``(n,)`` signals (Dressler (2012), eq. 7.9).

        Built by filtering the columns of the identity: ``lifted(n) @ x == apply(x)``
        to rounding.

        Parameters
        ----------
        n : int
            Trial length in samples (the window's length if there is a window).

        Returns
        -------
        numpy.ndarray, shape (n, n)

        Raises
        ------
        InputError
            ``n`` not a positive integer or not the window's length.
        """
        n = positive_int(n, "n")
        if self.window is not None and n != self.window.size:
            raise InputError(f"n: expected the window's length {self.window.size}, got {n}")
        return _lift(self.apply, n)

    def magnitude(self, f_hz: Any) -> np.ndarray:
        """Magnitude of the zero-phase low-pass (without the window): ``|H(f)|^2``.

        Parameters
        ----------
        f_hz : array_like, shape (F,)
            Frequencies [Hz].

        Returns
        -------
        numpy.ndarray, shape (F,)
            Magnitude (1 everywhere without a low-pass); the phase is 0.

        Raises
        ------
        InputError
            Frequencies not finite.
        """
        f = np.atleast_1d(as_finite(f_hz, "f_hz"))
        if self._sos is None:
            return np.ones(f.shape)
        _, h = scipy.signal.sosfreqz(self._sos, worN=f, fs=1.0 / self.dt)
        return np.abs(h) ** 2

    def __repr__(self) -> str:
        w = None if self.window is None else self.window.size
        return f"QFilter(cutoff_hz={self.cutoff_hz}, dt={self.dt}, order={self.order}, window={w} samples)"


class RobustQFilter(QFilter):
    """Q shaped below the inverse loop gain: learning up to a cut-off, robust around resonances.

    Dressler (2012), ch. 7.4, Cases 2 and 3 (Figs. 7.14, 7.17): Q "learns up to 30 Hz" and is
    "robust to large model errors especially around the resonance frequencies", i.e. its
    magnitude stays below ``|1 - L T|^-1`` (the frequency-domain condition for monotone
    convergence, Norrlöf and Gunnarsson (2002)). The thesis gives no formula; here the wanted
    magnitude is ``min(|B(f)|^2, margin / g(f))`` with ``|B|^2`` the zero-phase Butterworth
    of :class:`QFilter` at ``cutoff_hz`` and ``g(f)`` the loop gain ``sigma_max(I - L T)``
    at ``f`` (given on a grid, interpolated linearly), realised as a symmetric FIR filter of
    ``taps`` taps (:func:`scipy.signal.firwin2`, frequency sampling, Hamming window) applied
    centred (zero phase, :func:`scipy.signal.oaconvolve`, zeros beyond the trial), then the
    time window.

    Parameters
    ----------
    cutoff_hz : float
        Cut-off of the Butterworth part [Hz] (the thesis: 30).
    freqs_hz : array_like, shape (F,)
        Frequency grid of the loop gain [Hz], increasing, from 0 to the Nyquist frequency.
    loop_gain : array_like, shape (F,)
        ``sigma_max(I - L T)`` at ``freqs_hz`` (positive).
    margin : float, optional
        Wanted bound of ``|Q| g`` (default 0.9; below 1).
    dt : float, optional
        Sample time [s].
    order : int, optional
        Order of the Butterworth part.
    window : array_like, shape (N,), optional
        Time window.
    taps : int, optional
        FIR length (odd; default 101).

    Raises
    ------
    InputError
        A bad cut-off, grid, gain, margin or tap count.
    """

    def __init__(self, cutoff_hz: float, freqs_hz: Any, loop_gain: Any, margin: float = 0.9, dt: float = LOOP_PERIOD_S,
                 order: int = 2, window: Any = None, taps: int = 101) -> None:
        super().__init__(cutoff_hz, dt=dt, order=order, window=window)
        f = as_vector(freqs_hz, "freqs_hz", what="frequencies")
        g = as_vector(loop_gain, "loop_gain", what="gains")
        nyquist = 0.5 / self.dt
        if f.size != g.size or f.size < 2 or np.any(np.diff(f) <= 0) or f[0] != 0.0 or abs(f[-1] - nyquist) > 1e-9 * nyquist:
            raise InputError(f"freqs_hz: expected an increasing grid from 0 to {nyquist:g} Hz with one loop gain each")
        if np.any(g <= 0):
            raise InputError("loop_gain: expected positive gains")
        m = float(as_finite(margin, "margin"))
        if not 0.0 < m < 1.0:
            raise InputError(f"margin: expected a number in (0, 1), got {margin!r}")
        taps = positive_int(taps, "taps")
        if taps % 2 == 0:
            raise InputError(f"taps: expected an odd FIR length (a centred, zero-phase filter), got {taps}")
        self.margin = m
        self.taps = taps
        self.freqs_hz, self.loop_gain = f, g
        self.wanted = np.minimum(super().magnitude(f), m / g)
        self.fir = scipy.signal.firwin2(taps, f, self.wanted, fs=1.0 / self.dt)

    def _filter(self, arr: np.ndarray) -> np.ndarray:
        """The centred FIR alone on checked ``(N, d)`` columns (:meth:`apply` adds the window)."""
        return scipy.signal.oaconvolve(arr, self.fir[:, None], mode="full", axes=0)[self.taps // 2: self.taps // 2 + arr.shape[0]]

    def magnitude(self, f_hz: Any) -> np.ndarray:
        """Magnitude of the FIR (without the window); its phase is 0 (centred, symmetric).

        Parameters
        ----------
        f_hz : array_like, shape (F,)
            Frequencies [Hz].

        Returns
        -------
        numpy.ndarray, shape (F,)

        Raises
        ------
        InputError
            Frequencies not finite.
        """
        f = np.atleast_1d(as_finite(f_hz, "f_hz"))
        _, h = scipy.signal.freqz(self.fir, worN=f, fs=1.0 / self.dt)
        return np.abs(h)

    def __repr__(self) -> str:
        return f"RobustQFilter(cutoff_hz={self.cutoff_hz}, margin={self.margin}, taps={self.taps})"


class LearningFilter:
    """Learning filter ``L = gamma q^delta``: gain and a non-causal shift.

    Dressler (2012), eq. 7.2 and ch. 7.3 (``gamma = 0.9``, ``delta = 5`` samples, the dead
    time of the actuators (6.11)): ``(L e)[t] = gamma e[t + delta]`` for
    ``t < N - delta`` and 0 for the last ``delta`` samples (nothing is known beyond the
    end of the trial).

    Parameters
    ----------
    gamma : float, optional
        Learning gain (dimensionless, ``>= 0``; default 0.9).
    delta : int, optional
        Shift in samples (``>= 0``; default 5).

    Raises
    ------
    InputError
        Negative or non-finite ``gamma``; ``delta`` not a non-negative integer.
    """

    def __init__(self, gamma: float = 0.9, delta: int = 5) -> None:
        g = as_finite(gamma, "gamma")
        if g.ndim != 0 or float(g) < 0:
            raise InputError(f"gamma: expected a non-negative learning gain, got {gamma!r}")
        if isinstance(delta, bool) or not isinstance(delta, (int, np.integer)) or delta < 0:
            raise InputError(f"delta: expected a non-negative integer shift in samples, got {delta!r}")
        self.gamma = float(g)
        self.delta = int(delta)

    def apply(self, e: Any) -> np.ndarray:
        """``gamma`` times the error shifted ``delta`` samples earlier, zero at the end.

        Dressler (2012), eq. 7.2 (the ``L`` of ``u_{k+1} = Q (u_k + L eps_k)``).

        Parameters
        ----------
        e : array_like, shape (N,) or (N, d)
            Error signal, rows are samples.

        Returns
        -------
        numpy.ndarray
            Same shape as ``e``.

        Raises
        ------
        InputError
            ``e`` not finite or of another shape.
        """
        arr, single = as_signal(e, "e", vector=True), np.ndim(e) == 1
        out = np.zeros_like(arr)
        if self.delta < arr.shape[0]:
            out[: arr.shape[0] - self.delta] = self.gamma * arr[self.delta :]
        return out[:, 0] if single else out

    def lifted(self, n: int) -> np.ndarray:
        """The lifted matrix ``gamma`` times the ``delta``-th upper diagonal (eq. 7.9).

        Built by applying :meth:`apply` to the identity (equal to
        ``gamma * numpy.eye(n, k=delta)``).

        Parameters
        ----------
        n : int
            Trial length in samples.

        Returns
        -------
        numpy.ndarray, shape (n, n)

        Raises
        ------
        InputError
            ``n`` not a positive integer.
        """
        return _lift(self.apply, n)

    def __repr__(self) -> str:
        return f"LearningFilter(gamma={self.gamma}, delta={self.delta})"


@dataclass(frozen=True)
class ILCStability:
    """Stability and monotone-convergence figures of an ILC design (Dressler (2012), eqs. 7.15-7.16).

    Parameters
    ----------
    rho : float
        Spectral radius of ``Q (I - L T)`` (7.15).
    sigma_max : float
        Largest singular value of ``Q (I - L T)`` (7.16).
    stable : bool
        ``rho < 1``: the iteration converges.
    monotone : bool
        ``sigma_max < 1``: the correction converges monotonically in the 2-norm.
    """

    rho: float
    sigma_max: float
    stable: bool
    monotone: bool


def _square(x: Any, name: str, n: int | None) -> np.ndarray:
    arr = as_finite(x, name)
    if arr.ndim != 2 or arr.shape[0] != arr.shape[1] or arr.shape[0] == 0:
        raise InputError(f"{name}: expected a square matrix (n, n), got shape {arr.shape}")
    if n is not None and arr.shape[0] != n:
        raise InputError(f"{name}: expected shape ({n}, {n}) like Q, got {arr.shape}")
    return arr


def stability(Q: Any, L: Any, T: Any) -> ILCStability:
    """Stability (7.15) and monotone convergence (7.16) of ``u_{k+1} = Q (u_k + L eps_k)``.

    Dressler (2012), eqs. 7.15-7.16: with ``eps_k = r - T u_k - (terms independent of
    u)``, the correction evolves with the matrix ``A = Q (I - L T)``; the iteration is
    stable iff ``rho(A) < 1`` (:func:`numpy.linalg.eigvals`) and converges monotonically
    (2-norm of ``u_k - u_inf``) if ``sigma_max(A) < 1`` (:func:`numpy.linalg.norm`, ord 2).

    Parameters
    ----------
    Q : array_like, shape (n, n)
        Lifted Q filter (:meth:`QFilter.lifted`).
    L : array_like, shape (n, n)
        Lifted learning filter (:meth:`LearningFilter.lifted`).
    T : array_like, shape (n, n)
        Lifted map from the correction to the signal the error is taken of
        (``F_u + F_y T_uy`` in the thesis; :func:`lifted_matrix` of an impulse response).

    Returns
    -------
    ILCStability
        ``rho``, ``sigma_max`` and the two verdicts.

    Raises
    ------
    InputError
        Matrices not square, not finite or of different sizes.
    """
    Qm = _square(Q, "Q", None)
    n = Qm.shape[0]
    Lm = _square(L, "L", n)
    Tm = _square(T, "T", n)
    A = Qm @ (np.eye(n) - Lm @ Tm)
    rho = float(np.max(np.abs(np.linalg.eigvals(A))))
    sigma = float(np.linalg.norm(A, 2))
    if not (math.isfinite(rho) and math.isfinite(sigma)):  # pragma: no cover - finite inputs give finite figures
        raise InputError("Q, L, T: the iteration matrix has no finite spectrum")
    _log.debug("ILC stability: rho = %.6g, sigma_max = %.6g (n = %d)", rho, sigma, n)
    return ILCStability(rho=rho, sigma_max=sigma, stable=rho < 1.0, monotone=sigma < 1.0)
