"""Motion logs: reading, validation, zero-phase filtering and numerical differentiation.

Dressler (2012), ch. 6.2. Signals (:class:`MotionLog`, :func:`read_motion_log`): logged
cart positions ``q`` (or TCP positions ``T``) and actuator forces ``tau`` sampled at a
constant rate (4 ms on the L1); :func:`preprocess_log` differentiates positions with a
zero-phase filter (:func:`scipy.signal.filtfilt` with a Butterworth low-pass, or a
Savitzky-Golay filter), filters ``tau`` with the *same* filter (so regressor and forces
see the same phase), trims the filter transients at both ends and decimates (so the
residuals are close to white and the least-squares standard deviations hold).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import scipy.signal

from gtmodel._arrays import as_signal, as_times, positive_int
from gtmodel._tables import read_table, write_table
from gtmodel.errors import InputError

__all__ = ["MotionLog", "read_motion_log", "DynamicSamples", "preprocess_log", "MIN_SAMPLES", "MAX_SAMPLES", "MAX_LOG_BYTES",
           "SAMPLING_TOLERANCE"]

#: Fewest samples of a motion log (a Butterworth ``filtfilt`` needs some periods of data).
MIN_SAMPLES = 30
#: Most samples of a motion log (17 min at the 4 ms servo period; the logs of Dressler (2012),
#: ch. 6.2 last seconds to minutes) and the largest such file [bytes]: a larger file is
#: refused before it is parsed.
MAX_SAMPLES = 250_000
MAX_LOG_BYTES = 50_000_000
#: Largest relative deviation of a sampling interval from the median before a log is
#: rejected as non-uniformly sampled (the filters assume a constant rate).
SAMPLING_TOLERANCE = 0.01


@dataclass
class MotionLog:
    """A logged motion: time, cart (or TCP) positions and actuator forces (Dressler (2012), ch. 6.2).

    Validated on construction: equal lengths, finite values, strictly increasing time.

    Parameters
    ----------
    t : numpy.ndarray, shape (N,)
        Sample times [s], strictly increasing (constant rate for :func:`preprocess_log`).
    tau : numpy.ndarray, shape (N, 3)
        Actuator (cart) forces [N].
    q : numpy.ndarray, shape (N, 3) or None
        Cart positions [m] (encoder), or None if ``T`` is given.
    T : numpy.ndarray, shape (N, 3) or None
        TCP positions [m], or None if ``q`` is given.
    source : str
        Where the data come from.

    Raises
    ------
    InputError
        Not exactly one of ``q`` and ``T``, signal lengths differing from ``len(t)``,
        a non-finite value or non-increasing time (the message names the signal and the
        sample index).
    """

    t: np.ndarray
    tau: np.ndarray
    q: np.ndarray | None = None
    T: np.ndarray | None = None
    source: str = ""

    def __post_init__(self) -> None:
        if (self.q is None) == (self.T is None):
            raise InputError("MotionLog: give exactly one of q (cart positions) and T (TCP positions)")
        self.t = as_times(self.t, "t", MIN_SAMPLES)
        n = self.t.size
        self.tau = as_signal(self.tau, "tau", 3, n, like="t")
        if self.q is not None:
            self.q = as_signal(self.q, "q", 3, n, like="t")
        else:
            self.T = as_signal(self.T, "T", 3, n, like="t")

    @property
    def coordinates(self) -> str:
        """``"cart"`` for cart positions, ``"tcp"`` for TCP positions."""
        return "cart" if self.q is not None else "tcp"

    @property
    def positions(self) -> np.ndarray:
        """The logged positions, ``q`` or ``T`` (N, 3) [m]."""
        return self.q if self.q is not None else self.T

    @property
    def n_samples(self) -> int:
        """Number of samples N."""
        return int(self.t.size)

    def columns(self) -> tuple[str, ...]:
        """CSV column names with units.

        Returns
        -------
        tuple of str
            ``("t_s", "q1_m", "q2_m", "q3_m", "tau1_N", "tau2_N", "tau3_N")`` or with
            ``Tx_m, Ty_m, Tz_m``.
        """
        pos = ("q1_m", "q2_m", "q3_m") if self.q is not None else ("Tx_m", "Ty_m", "Tz_m")
        return ("t_s",) + pos + ("tau1_N", "tau2_N", "tau3_N")

    def to_csv(self, path: str | Path) -> Path:
        """Write the log in the format of :func:`read_motion_log`.

        Parameters
        ----------
        path : str or pathlib.Path
            Output file.

        Returns
        -------
        pathlib.Path
            The file written.

        Raises
        ------
        InputError
            The file cannot be written.
        """
        comments = [f" {self.source}"] if self.source else []
        return write_table(path, self.columns(), np.column_stack([self.t, self.positions, self.tau]), comments, what="motion log")


def read_motion_log(path: str | Path) -> MotionLog:
    """Read a logged motion from CSV (the identification data of Dressler (2012), ch. 6.2).

    Format (the CSV table of :mod:`gtmodel._tables`, like the calibration files of
    :mod:`gtmodel.calibration.measurements`): ``#`` comment lines (those at the top name the
    source), a header naming the columns with their units, then one row per sample::

        # L1, 4 ms servo log, excitation run 3
        t_s,q1_m,q2_m,q3_m,tau1_N,tau2_N,tau3_N
        0.000,-0.0933,0.0415,0.0153,-12.5,30.1,210.7
        ...

    Columns (any order, each once): ``t_s``; either ``q1_m, q2_m, q3_m`` (cart positions)
    or ``Tx_m, Ty_m, Tz_m`` (TCP positions); ``tau1_N, tau2_N, tau3_N`` (actuator forces).

    Parameters
    ----------
    path : str or pathlib.Path
        The file.

    Returns
    -------
    MotionLog

    Raises
    ------
    InputError
        Unreadable file, missing/unknown column, a malformed or non-finite number,
        non-increasing time, more than :data:`MAX_SAMPLES` samples or :data:`MAX_LOG_BYTES`
        bytes; the message names the file and the line.
    """
    table = read_table(path, "motion log", max_rows=MAX_SAMPLES, max_bytes=MAX_LOG_BYTES)
    cols = table.columns
    q_cols, T_cols, tau_cols = ["q1_m", "q2_m", "q3_m"], ["Tx_m", "Ty_m", "Tz_m"], ["tau1_N", "tau2_N", "tau3_N"]
    table.check_columns(allowed=["t_s", *q_cols, *T_cols, *tau_cols])
    has_q, has_T = all(c in cols for c in q_cols), all(c in cols for c in T_cols)
    if has_q == has_T:
        raise table.error("expected exactly one of the column sets q1_m,q2_m,q3_m and Tx_m,Ty_m,Tz_m")
    table.check_columns(["t_s", *tau_cols])
    t = table.column("t_s")
    dt = np.diff(t)
    if np.any(dt <= 0):
        r = int(np.argmax(dt <= 0)) + 1
        raise table.error(f"time not strictly increasing ({float(t[r])!r} after {float(t[r - 1])!r})", row=r, column="t_s")
    if t.size < MIN_SAMPLES:
        raise InputError(f"{table.source}: {t.size} samples, expected at least {MIN_SAMPLES}")
    pos = table.columns_of(q_cols if has_q else T_cols)
    tau = table.columns_of(tau_cols)
    source = " ".join(s.strip() for s in table.comments) or str(path)
    return MotionLog(t=t, tau=tau, q=pos if has_q else None, T=None if has_q else pos, source=source)


@dataclass
class DynamicSamples:
    """Positions, velocities, accelerations and forces ready for the regressor.

    Parameters
    ----------
    t : numpy.ndarray, shape (N,)
        Times [s].
    x, x_dot, x_ddot : numpy.ndarray, shape (N, 3)
        Cart (``coordinates="cart"``) or TCP positions [m], velocities [m/s],
        accelerations [m/s^2].
    tau : numpy.ndarray, shape (N, 3)
        Actuator forces [N] (filtered like the positions).
    coordinates : {"cart", "tcp"}
        Meaning of ``x``.
    info : dict
        How they were obtained (filter, cut-off, decimation, trimmed samples).
    decimate : int
        Row decimation applied by :func:`identify_dynamics` after the parallel filtering
        (default 1).
    smoother : callable or None
        The zero-phase filter that was applied to ``tau`` (``y (N, ...) -> y (N, ...)``
        along axis 0); :func:`identify_dynamics` applies it to the regressor too
        ("parallel filtering", Gautier 1997), so the filtered friction steps agree.

    Raises
    ------
    InputError
        Lengths differing from ``len(t)``, non-finite values, non-increasing time or an
        unknown ``coordinates`` (the message names the signal and sample).
    """

    t: np.ndarray
    x: np.ndarray
    x_dot: np.ndarray
    x_ddot: np.ndarray
    tau: np.ndarray
    coordinates: str = "cart"
    info: dict = field(default_factory=dict)
    decimate: int = 1
    smoother: Any = None

    def __post_init__(self) -> None:
        self.decimate = positive_int(self.decimate, "decimate")
        if self.smoother is not None and not callable(self.smoother):
            raise InputError("smoother: expected a callable filter (array (N, ...) -> array (N, ...)) or None")
        if self.coordinates not in ("cart", "tcp"):
            raise InputError(f"coordinates: expected 'cart' or 'tcp', got {self.coordinates!r}")
        self.t = t = as_times(self.t, "t", 1)
        n = t.size
        self.x = as_signal(self.x, "x", 3, n, like="t")
        self.x_dot = as_signal(self.x_dot, "x_dot", 3, n, like="t")
        self.x_ddot = as_signal(self.x_ddot, "x_ddot", 3, n, like="t")
        self.tau = as_signal(self.tau, "tau", 3, n, like="t")

    @property
    def n_samples(self) -> int:
        """Number of samples N."""
        return int(self.t.size)


def _savgol_window(fs: float, cutoff: float, order: int) -> int:
    # -3 dB frequency of a Savitzky-Golay smoother: f_c ~ (order + 1) fs / (3.2 n - 4.6)
    # (Schafer, "What is a Savitzky-Golay filter?", IEEE Signal Processing Magazine, 2011)
    n = int(round(((order + 1) * fs / cutoff + 4.6) / 3.2))
    n = max(n, order + 2)
    return n + 1 if n % 2 == 0 else n


def preprocess_log(
    log: MotionLog,
    cutoff: float = 10.0,
    method: str = "butter",
    order: int = 4,
    decimate: int | None = None,
    trim: int | None = None,
) -> DynamicSamples:
    """Zero-phase filtering and numerical differentiation of a logged motion.

    ``"butter"``: positions and forces are filtered forward and backward
    (:func:`scipy.signal.filtfilt`, Butterworth low-pass of ``order`` with the cut-off
    ``cutoff``), then differentiated by central differences (:func:`numpy.gradient`).
    ``"savgol"``: Savitzky-Golay filter (:func:`scipy.signal.savgol_filter`, polynomial
    order ``order``, window chosen for a -3 dB frequency near ``cutoff``) with its
    derivatives. Either way both positions and forces pass the same zero-phase filter, the
    transients at both ends are trimmed and the result is decimated (Dressler (2012),
    ch. 6.2 identifies on filtered servo data). The output keeps the full rate; the
    decimation is done by :func:`identify_dynamics` after it has passed the regressor
    through the same filter as the forces ("parallel filtering and decimation", M.
    Gautier, "Dynamic identification of robots with power model", IEEE ICRA 1997): the
    filter smears the Coulomb steps ``f_c sign(q_dot)`` of the forces, and the same filter
    on ``Y`` smears them equally, which removes a bias of the masses.

    Parameters
    ----------
    log : MotionLog
        The motion, sampled at a constant rate.
    cutoff : float, optional
        Low-pass cut-off frequency [Hz] (default 10 Hz), below the Nyquist frequency.
    method : {"butter", "savgol"}, optional
        The filter.
    order : int, optional
        Butterworth order, or Savitzky-Golay polynomial order (>= 2) (default 4).
    decimate : int, optional
        Keep every ``decimate``-th row in the identification (default
        ``max(1, round(fs / cutoff))``: rows one filter correlation time apart, so the
        filtered noise is close to white and the least-squares standard deviations hold;
        with ``fs / (2.5 cutoff)`` they come out about 1.3 times too small in simulations).
    trim : int, optional
        Samples dropped at each end (default ``ceil(2 fs / cutoff)``, two periods of the
        cut-off), here and again after the regressor is filtered.

    Returns
    -------
    DynamicSamples

    Raises
    ------
    InputError
        Non-uniform sampling (names the sample), a cut-off at or above the Nyquist
        frequency, an unknown method, invalid ``order``/``decimate``/``trim``, or too few
        samples left.
    """
    if not isinstance(log, MotionLog):
        raise InputError(f"log: expected a MotionLog, got {type(log).__name__}")
    if method not in ("butter", "savgol"):
        raise InputError(f"method: expected 'butter' or 'savgol', got {method!r}")
    t = log.t
    dt_all = np.diff(t)
    dt = float(np.median(dt_all))
    dev = np.abs(dt_all - dt) > SAMPLING_TOLERANCE * dt
    if np.any(dev):
        k = int(np.argmax(dev)) + 1
        raise InputError(f"t: sampling is not uniform at sample {k} (interval {dt_all[k - 1]!r} s, median {dt!r} s); resample the log first")
    fs = 1.0 / dt
    if not (isinstance(cutoff, (int, float)) and math.isfinite(cutoff) and 0 < cutoff < fs / 2):
        raise InputError(f"cutoff: expected a frequency in (0, {fs / 2:g}) Hz (below Nyquist), got {cutoff!r}")
    if isinstance(order, bool) or not isinstance(order, (int, np.integer)) or not 1 <= order <= 10 or (method == "savgol" and order < 2):
        raise InputError(f"order: expected an integer in 1..10 (>= 2 for savgol), got {order!r}")
    if decimate is None:
        decimate = max(1, int(round(fs / cutoff)))
    decimate = positive_int(decimate, "decimate")
    if trim is None:
        trim = int(math.ceil(2 * fs / cutoff))
    if isinstance(trim, bool) or not isinstance(trim, (int, np.integer)) or trim < 0:
        raise InputError(f"trim: expected a non-negative integer, got {trim!r}")
    x = log.positions
    n = x.shape[0]
    if method == "butter":
        b, a = scipy.signal.butter(order, cutoff, fs=fs)
        need = 3 * max(len(a), len(b))
        if n <= max(need, 2 * trim + 3):
            raise InputError(f"log: {n} samples are too few for the filter and trim={trim} (need more than {max(need, 2 * trim + 3)})")
        xf = scipy.signal.filtfilt(b, a, x, axis=0)
        xd = np.gradient(xf, dt, axis=0)
        xdd = np.gradient(xd, dt, axis=0)
        tauf = scipy.signal.filtfilt(b, a, log.tau, axis=0)
        info = {"filter": f"Butterworth order {order}, filtfilt (zero phase)", "window": None}
    else:
        w = _savgol_window(fs, cutoff, order)
        if n <= max(w, 2 * trim + 3):
            raise InputError(f"log: {n} samples are too few for the Savitzky-Golay window {w} and trim={trim}")
        xf = scipy.signal.savgol_filter(x, w, order, axis=0)
        xd = scipy.signal.savgol_filter(x, w, order, deriv=1, delta=dt, axis=0)
        xdd = scipy.signal.savgol_filter(x, w, order, deriv=2, delta=dt, axis=0)
        tauf = scipy.signal.savgol_filter(log.tau, w, order, axis=0)
        info = {"filter": f"Savitzky-Golay order {order}, window {w} samples (zero phase)", "window": w}
    keep = np.arange(trim, n - trim)
    n_left = (keep.size - 2 * trim + decimate - 1) // decimate
    if n_left < MIN_SAMPLES:
        raise InputError(f"log: only {max(n_left, 0)} samples remain after trim={trim} (twice) and decimate={decimate}, expected at least {MIN_SAMPLES}")
    info.update(cutoff_hz=float(cutoff), sample_time_s=dt, decimate=int(decimate), trim=int(trim), method=method)
    # the smoother filters each signal of y (N, ...) along time; on the (signals, N) view
    # the filter runs about a third faster than along axis 0 of (N, 3, p) (same results)
    if method == "butter":
        def smoother(y: np.ndarray) -> np.ndarray:
            y = np.asarray(y)
            return scipy.signal.filtfilt(b, a, y.reshape(y.shape[0], -1).T, axis=-1).T.reshape(y.shape)
    else:
        def smoother(y: np.ndarray) -> np.ndarray:
            y = np.asarray(y)
            return scipy.signal.savgol_filter(y.reshape(y.shape[0], -1).T, w, order, axis=-1).T.reshape(y.shape)
    return DynamicSamples(t[keep], xf[keep], xd[keep], xdd[keep], tauf[keep], log.coordinates, info, int(decimate), smoother)
