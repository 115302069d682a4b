"""Complementary filter for the tool position (Dressler (2012), eq. 7.17).

The tool position ``z`` is estimated per direction from the kinematic position
``z_kin = fk(q_m)`` (right at low frequencies: it misses the structural deflection) and
the tool accelerometer ``a_m`` (right at high frequencies once integrated twice: its
noise and bias drift at low frequencies)::

    z_hat = LP(z_kin) + HP(I(a_m)),    HP = 1 - LP                       (7.17)

Choices made here (each one a decision; the thesis gives the filter type and cut-offs):

* ``LP`` is a Butterworth low-pass (:func:`scipy.signal.butter`, second-order sections)
  applied forward and backward (:func:`scipy.signal.sosfiltfilt`): zero phase, magnitude
  ``|H|^2``. Forward-backward squares the magnitude, so a Butterworth designed at the
  cut-off would be -6 dB there. The design frequency is corrected so that the zero-phase
  magnitude is exactly -3 dB (``1/sqrt(2)``) at ``cutoff_hz``: with the bilinear
  Butterworth ``|H|^2 = 1 / (1 + (tan(pi f dt) / tan(pi f_d dt))^(2 n))`` the condition
  ``|H(f_c)|^2 = 1/sqrt(2)`` gives ``tan(pi f_d dt) = tan(pi f_c dt) / (sqrt(2) - 1)^(1/(2n))``
  (for n = 2: ``f_d ~ 1.25 f_c``).
* ``HP = 1 - LP`` exactly (computed as ``x - LP(x)``): the two paths are complementary,
  so consistent measurements (``z_kin = z``, ``a_m = z''``) give ``z_hat = z`` up to the
  double integral's discretisation error and the filters' end effects.
* ``I`` is the discrete double integral that inverts the central second difference,
  ``y[k] - 2 y[k-1] + y[k-2] = dt^2 a[k-1]`` (:func:`scipy.signal.lfilter` with
  ``b = [0, dt^2]``, ``a = [1, -2, 1]``), started at rest at 0. It is exact for a signal
  whose accelerations are its central second differences; for samples of a smooth
  signal its error is ``(w dt)^2 / 12`` relative at angular frequency ``w``.
* Drift: ``I(a_m)`` starts at 0 with zero velocity, so it differs from ``z`` by a
  line ``z(0) + v(0) t``, and an accelerometer bias adds a parabola; noise adds a
  doubly integrated random walk. ``HP`` removes them: the zero-phase Butterworth has
  ``1 - |H|^2 ~ (f / f_d)^(2 n)`` near 0 Hz, so it passes polynomials of degree
  ``< 2 n`` unchanged inside the record (``HP`` of them is 0) and attenuates the random
  walk's low frequencies by ``f^(2n)`` against its ``1 / f^2`` growth. At the ends of
  the record the forward-backward filter needs a continuation: odd extension
  (``padtype="odd"``, which continues a line exactly) over ``padlen`` samples, chosen as
  the number of samples the slowest filter pole needs to decay to ``1e-9``
  (:data:`PAD_DECAY`), at most ``N - 1``; so the start-up transient of the padding has
  died out before the record begins.

Every operation is linear in ``(z_kin, a_m)``, so the estimator is a fixed pair of
``(N, N)`` matrices per direction; :meth:`ComplementaryFilter.lifted` builds them by
applying :meth:`ComplementaryFilter.estimate`'s operators to identity columns (exact).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import scipy.signal

from gtmodel._arrays import as_finite, as_signal, as_vector, positive_float, positive_int
from gtmodel.defaults import LOOP_PERIOD_S
from gtmodel.errors import InputError

__all__ = ["ComplementaryFilter", "THESIS_CUTOFFS_HZ", "PAD_DECAY", "CUTOFF_READINGS", "forward_backward_design_hz"]

#: How a cut-off is read: -3 dB of the zero-phase filter, or Matlab's ``butter`` + ``filtfilt`` (-6 dB, the crossover).
CUTOFF_READINGS = ("zero_phase_3db", "matlab")

#: Cut-off frequencies [Hz] of the thesis' complementary filter, x and y (Dressler (2012), ch. 7.3).
THESIS_CUTOFFS_HZ = (4.50, 2.63)
#: Lowest cut-off as a fraction of the sample rate ``1/dt`` (0.025 Hz at 4 ms): below it the
#: Butterworth design is numerically degenerate (badly conditioned, singular initial state).
MIN_CUTOFF_FRACTION = 1e-4
#: Relative size to which the padding's start-up transient decays before the record begins.
PAD_DECAY = 1e-9


def forward_backward_design_hz(cutoff_hz: float, dt: float, order: int) -> float:
    """The Butterworth design frequency whose forward-backward magnitude is -3 dB at ``cutoff_hz``.

    Forward-backward filtering squares the magnitude; the bilinear Butterworth low-pass
    of order ``n`` designed at ``f_d`` has ``|H(f)|^2 = 1 / (1 + (tan(pi f dt) /
    tan(pi f_d dt))^(2n))``. Setting ``|H(f_c)|^2 = 1 / sqrt(2)`` gives
    ``tan(pi f_d dt) = tan(pi f_c dt) / (sqrt(2) - 1)^(1 / (2n))``.

    Parameters
    ----------
    cutoff_hz : float
        Wanted -3 dB frequency of the zero-phase filter [Hz], ``0 < cutoff_hz < 1 / (2 dt)``.
    dt : float
        Sample time [s].
    order : int
        Order ``n`` of the Butterworth filter applied in each direction of time.

    Returns
    -------
    float
        Design frequency ``f_d`` [Hz] for :func:`scipy.signal.butter`, below the Nyquist frequency.

    Raises
    ------
    InputError
        ``cutoff_hz`` not in ``(0, 1 / (2 dt))``, ``dt`` not positive, ``order`` not a positive integer.
    """
    dt = positive_float(dt, "dt")
    order = positive_int(order, "order")
    nyquist = 0.5 / dt
    fc = float(cutoff_hz)
    lowest = MIN_CUTOFF_FRACTION / dt
    if not (lowest <= fc < nyquist):
        raise InputError(f"cutoff_hz: expected a frequency in [{lowest:g}, {nyquist:g}) Hz (below Nyquist for dt = {dt:g} s; "
                         f"lower cut-offs give a numerically degenerate filter), got {cutoff_hz!r}")
    rho = (math.sqrt(2.0) - 1.0) ** (1.0 / (2 * order))
    return math.atan(math.tan(math.pi * fc * dt) / rho) / (math.pi * dt)


class ComplementaryFilter:
    """Zero-phase complementary filter ``z_hat = LP(z_kin) + HP(I(a_m))`` (Dressler (2012), eq. 7.17).

    Per direction ``j``: ``LP`` is a Butterworth low-pass of order ``order`` applied
    forward and backward (zero phase), designed so that its zero-phase magnitude is
    -3 dB at ``cutoff_hz[j]``; ``HP = 1 - LP``; ``I`` the discrete double integral that
    inverts the central second difference. See the module docstring for the choices.

    Parameters
    ----------
    cutoff_hz : array_like, shape (d,), optional
        Cut-off frequency per direction [Hz], each in ``(0, 1 / (2 dt))``. Default: the
        thesis' 4.50 Hz (x) and 2.63 Hz (y) (:data:`THESIS_CUTOFFS_HZ`).
    dt : float, optional
        Sample time [s] (default the loop period, :data:`gtmodel.defaults.LOOP_PERIOD_S`).
    order : int, optional
        Butterworth order per pass (the thesis: 2).
    reading : str, optional
        How ``cutoff_hz`` is read: ``"zero_phase_3db"`` (default: the zero-phase magnitude
        is -3 dB there, the design frequency moved up by :func:`forward_backward_design_hz`)
        or ``"matlab"`` (the thesis' tool, ``butter(order, fc)`` then ``filtfilt``: the
        design frequency is the cut-off, the zero-phase magnitude is -6 dB there, so LP
        and HP = 1 - LP cross over exactly at ``cutoff_hz``).

    Attributes
    ----------
    cutoff_hz : numpy.ndarray, shape (d,)
        The cut-off frequencies as given [Hz] (read per ``reading``).
    reading : str
        The reading of ``cutoff_hz``.
    design_hz : numpy.ndarray, shape (d,)
        The Butterworth design frequencies (:func:`forward_backward_design_hz`) [Hz].
    sos : list of numpy.ndarray
        Second-order sections of the one-pass low-pass, one array per direction.
    dt : float
        Sample time [s].
    order : int
        Butterworth order per pass.
    d : int
        Number of directions.

    Raises
    ------
    InputError
        A cut-off not in ``(0, Nyquist)`` (message names ``cutoff_hz``), ``cutoff_hz`` not
        1-D, ``dt`` not positive, ``order`` not a positive integer, an unknown ``reading``.
    """

    def __init__(self, cutoff_hz: Any = THESIS_CUTOFFS_HZ, dt: float = LOOP_PERIOD_S, order: int = 2, reading: str = "zero_phase_3db") -> None:
        if reading not in CUTOFF_READINGS:
            raise InputError(f"reading: expected one of {', '.join(CUTOFF_READINGS)}, got {reading!r}")
        self.reading = reading
        self.dt = positive_float(dt, "dt")
        self.order = positive_int(order, "order")
        fc = as_vector(cutoff_hz, "cutoff_hz", what="frequencies (one per direction)")
        nyquist = 0.5 / self.dt
        bad = (fc <= 0) | (fc >= nyquist)
        if np.any(bad):
            j = int(np.argmax(bad))
            raise InputError(f"cutoff_hz: entry {j} = {float(fc[j])!r} Hz is outside (0, {nyquist:g}) Hz (Nyquist for dt = {self.dt:g} s)")
        self.cutoff_hz = fc
        self.d = int(fc.size)
        self.design_hz = (np.array(fc, dtype=float) if reading == "matlab"
                          else np.array([forward_backward_design_hz(f, self.dt, self.order) for f in fc]))
        self.sos = [scipy.signal.butter(self.order, f, btype="low", output="sos", fs=1.0 / self.dt) for f in self.design_hz]
        poles = [np.max(np.abs(scipy.signal.sos2zpk(s)[1])) for s in self.sos]
        self._settle = [int(math.ceil(math.log(PAD_DECAY) / math.log(p))) for p in poles]

    def padlen(self, n: int) -> list[int]:
        """Odd-extension length used by the forward-backward filter on ``n`` samples, per direction.

        Parameters
        ----------
        n : int
            Number of samples of the record.

        Returns
        -------
        list of int
            ``min(n - 1, s_j)`` with ``s_j`` the samples the slowest pole of direction ``j``
            needs to decay to :data:`PAD_DECAY`.

        Raises
        ------
        InputError
            ``n`` not a positive integer.
        """
        n = positive_int(n, "n")
        return [min(n - 1, s) for s in self._settle]

    def _lp(self, j: int, x: np.ndarray) -> np.ndarray:
        """Zero-phase low-pass of direction ``j`` along axis 0 of ``x`` (N, m)."""
        return scipy.signal.sosfiltfilt(self.sos[j], x, axis=0, padtype="odd", padlen=self.padlen(x.shape[0])[j])

    def _integral(self, a: np.ndarray) -> np.ndarray:
        """Discrete double integral along axis 0 (inverse of the central second difference)."""
        return scipy.signal.lfilter([0.0, self.dt * self.dt], [1.0, -2.0, 1.0], a, axis=0)

    def low_pass(self, x: Any) -> np.ndarray:
        """The zero-phase low-pass ``LP`` of each column.

        Parameters
        ----------
        x : array_like, shape (N, d)
            Signal, rows are samples.

        Returns
        -------
        numpy.ndarray, shape (N, d)

        Raises
        ------
        InputError
            Not of shape ``(N, d)`` or not finite.
        """
        arr = as_signal(x, "x", self.d)
        return np.column_stack([self._lp(j, arr[:, j]) for j in range(self.d)])

    def high_pass(self, x: Any) -> np.ndarray:
        """The complementary high-pass ``HP = 1 - LP`` of each column.

        Parameters
        ----------
        x : array_like, shape (N, d)
            Signal, rows are samples.

        Returns
        -------
        numpy.ndarray, shape (N, d)
            ``x - LP(x)``.

        Raises
        ------
        InputError
            Not of shape ``(N, d)`` or not finite.
        """
        arr = as_signal(x, "x", self.d)
        return arr - self.low_pass(arr)

    def double_integral(self, a_m: Any) -> np.ndarray:
        """The discrete double integral ``I(a_m)``, started at rest at 0.

        ``y[k] = 2 y[k-1] - y[k-2] + dt^2 a_m[k-1]`` (:func:`scipy.signal.lfilter`): the
        inverse of the central second difference, so the acceleration at sample ``k - 1``
        is centred between ``y[k-2]`` and ``y[k]``.

        Parameters
        ----------
        a_m : array_like, shape (N, d)
            Accelerations [m/s^2].

        Returns
        -------
        numpy.ndarray, shape (N, d)
            Positions [m] (``y[0] = 0``, ``y[1] = dt^2 a_m[0]``).

        Raises
        ------
        InputError
            Not of shape ``(N, d)`` or not finite.
        """
        return self._integral(as_signal(a_m, "a_m", self.d))

    def estimate(self, z_kin: Any, a_m: Any) -> np.ndarray:
        """Tool-position estimate ``z_hat = LP(z_kin) + HP(I(a_m))`` (Dressler (2012), eq. 7.17).

        Parameters
        ----------
        z_kin : array_like, shape (N, d)
            Kinematic tool position ``fk(q_m)`` [m], rows are samples ``dt`` apart.
        a_m : array_like, shape (N, d)
            Measured tool acceleration [m/s^2], same samples.

        Returns
        -------
        numpy.ndarray, shape (N, d)
            Estimated tool position [m].

        Raises
        ------
        InputError
            A signal not of shape ``(N, d)``, of another length than ``z_kin``, or not finite.
        """
        zk = as_signal(z_kin, "z_kin", self.d)
        am = as_signal(a_m, "a_m", self.d, zk.shape[0], like="z_kin")
        acc = self._integral(am)
        return np.column_stack([self._lp(j, zk[:, j]) + acc[:, j] - self._lp(j, acc[:, j]) for j in range(self.d)])

    def lifted(self, n: int) -> tuple[np.ndarray, np.ndarray]:
        """Lifted matrices of :meth:`estimate` on ``n`` samples: ``z_hat[:, j] = F_kin[j] z_kin[:, j] + F_acc[j] a_m[:, j]``.

        Built by applying the same operators to the columns of the identity, so they
        agree with :meth:`estimate` to rounding (Dressler (2012), eq. 7.9 for lifted systems).

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
        eye = np.eye(n)
        acc = self._integral(eye)
        f_kin = np.stack([self._lp(j, eye) for j in range(self.d)])
        f_acc = np.stack([acc - self._lp(j, acc) for j in range(self.d)])
        return f_kin, f_acc

    def magnitude(self, f_hz: Any) -> np.ndarray:
        """Magnitude of the zero-phase low-pass ``|H(f)|^2`` (the ``z_kin`` path; ``HP = 1 - |H|^2``).

        Parameters
        ----------
        f_hz : array_like, shape (F,)
            Frequencies [Hz], in ``[0, 1 / (2 dt)]``.

        Returns
        -------
        numpy.ndarray, shape (d, F)
            Magnitude [1] per direction (:func:`scipy.signal.sosfreqz`).

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
        return np.stack([np.abs(scipy.signal.sosfreqz(s, worN=f, fs=1.0 / self.dt)[1]) ** 2 for s in self.sos])

    def __repr__(self) -> str:
        return f"ComplementaryFilter(cutoff_hz={self.cutoff_hz.tolist()}, dt={self.dt}, order={self.order}, reading={self.reading!r})"
