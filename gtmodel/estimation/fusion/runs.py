"""One case of the fusion study (:class:`FusionRun`) and the NEES consistency test (:func:`nees_test`).

Cvitanic (2021), section 4.3: the errors of a case are the tables' metric, the MEAN over the
samples of the EUCLIDEAN NORM of the error (orientation: of the rotation angle), from the warm-up
on, in the thesis' units (:data:`QUANTITIES`). The study itself is
:class:`~gtmodel.estimation.fusion.study.FusionStudy`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import scipy.signal
import scipy.stats

from gtmodel._arrays import as_finite, as_vector, positive_int
from gtmodel.errors import InputError
from gtmodel.estimation.filters.gaussian import FilterRun
from gtmodel.estimation.fusion.tracker_imu import Measurements, SensorEstimate, SensorSpec, Truth, orientation_error
from gtmodel.status import StatusResult

__all__ = ["QUANTITIES", "FusionRun", "nees_test"]

#: Quantities of the tables: name -> (state slice name, unit scale from SI, rotation only).
QUANTITIES = {
    "position_mm": ("position", 1e3, False),
    "velocity_mm_s": ("velocity", 1e3, False),
    "acceleration_m_s2": ("acceleration", 1.0, False),
    "orientation_deg": ("quaternion", math.degrees(1.0), True),
    "angular_velocity_deg_s": ("angular_velocity", math.degrees(1.0), True),
    "angular_acceleration_deg_s2": ("angular_acceleration", math.degrees(1.0), True),
}

def nees_test(nees: Any, dof: int, level: float = 0.95) -> dict[str, Any]:
    """Consistency test of one run's NEES (Bar-Shalom, Li and Kirubarajan (2001), sec. 5.4.2).

    The time-average ``eps = mean_k NEES_k`` of a consistent filter has mean ``dof``; were the
    ``N`` samples independent, ``N eps ~ chi2(N dof)``. They are not (the estimation error of
    a filter is correlated over its time constant), so the band uses the number of effectively
    independent samples ``M = N / tau`` with ``tau = 1 + 2 sum_l rho_l`` the integrated
    autocorrelation time of the NEES sequence (autocorrelation ``rho_l`` by FFT, summed up to
    the first negative lag: the initial-positive-sequence truncation of MCMC practice). The
    filter passes when ``eps`` lies in ``[chi2_{(1-level)/2}(M dof), chi2_{(1+level)/2}(M dof)] / M``.
    The independent-sample band (``M = N``) is reported beside it.

    Parameters
    ----------
    nees : array_like, shape (N,)
        NEES per sample (e.g. :meth:`FilterRun.nees` after a warm-up), ``N >= 2``.
    dof : int
        Degrees of freedom of each NEES (``nx``, or ``nx - 1`` with a quaternion).
    level : float, optional
        Two-sided probability of the band, in (0, 1).

    Returns
    -------
    dict
        ``mean``, ``dof``, ``samples``, ``autocorrelation_time``, ``effective_samples``,
        ``band`` (2), ``independent_band`` (2), ``fraction_below_quantile`` (fraction of samples
        with ``NEES_k <= chi2_level(dof)``, ``level`` for a consistent filter), ``passed``.

    Raises
    ------
    InputError
        ``nees`` not a finite 1-D array of at least 2 non-negative values, ``dof`` not a
        positive integer, ``level`` outside (0, 1).
    """
    e = as_vector(nees, "nees", min_size=2, nonnegative=True)
    dof = positive_int(dof, "dof")
    level = float(as_finite(level, "level"))
    if not 0.0 < level < 1.0:
        raise InputError(f"level: expected a probability in (0, 1), got {level!r}")
    n = e.size
    d = e - e.mean()
    denom = float(np.dot(d, d))
    if denom > 0.0:
        acf = scipy.signal.correlate(d, d, mode="full", method="fft")[n - 1 :] / denom
        negative = np.nonzero(acf[1:] < 0.0)[0]
        last = int(negative[0]) if negative.size else n - 1
        tau = max(1.0, 1.0 + 2.0 * float(np.sum(acf[1 : last + 1])))
    else:
        tau = 1.0
    m = n / tau
    lo, hi = (1.0 - level) / 2.0, (1.0 + level) / 2.0
    band = scipy.stats.chi2.ppf([lo, hi], m * dof) / m
    independent = scipy.stats.chi2.ppf([lo, hi], n * dof) / n
    mean = float(e.mean())
    return {
        "mean": mean,
        "dof": dof,
        "samples": n,
        "autocorrelation_time": tau,
        "effective_samples": m,
        "band": [float(band[0]), float(band[1])],
        "independent_band": [float(independent[0]), float(independent[1])],
        "fraction_below_quantile": float(np.mean(e <= scipy.stats.chi2.ppf(level, dof))),
        "passed": bool(band[0] <= mean <= band[1]),
    }


@dataclass(kw_only=True)
class FusionRun(StatusResult):
    """One case: truth, measurements, the filter's run and the sensor-only estimates, with the errors.

    Parameters
    ----------
    status : Status
        The filter run's status (``"error"``: it diverged; the errors are then over the
        samples before the failure).
    message : str
        The filter's message.
    label : str
        Case label.
    filter_name : str
        ``"kf"``, ``"ekf"``, ``"ukf"`` or ``"pf"``.
    spec : SensorSpec
        The sensor figures.
    truth : Truth
        The true states.
    measurements : Measurements
        The sensor readings.
    sensor : SensorEstimate
        Sensor-only estimates (rows from sample 3 on).
    run : FilterRun
        The filter's run.
    first : int
        First sample of the error metrics (the warm-up).
    errors : dict
        Quantity (:data:`QUANTITIES`, thesis units) -> ``{"sensor": float, "fusion": float}``
        (rotation quantities only for 5-axis cases).
    step_time_us : float
        Mean wall time per filter step [us].
    setup : dict of str to numpy.ndarray
        The filter's set-up, for an independent re-run: ``x0`` (nx,), ``P0``, ``Q`` (nx, nx),
        ``R`` (nz, nz); for the linear 3-axis model also ``F`` (nx, nx) and ``H`` (nz, nx).
    """

    label: str
    filter_name: str
    spec: SensorSpec
    truth: Truth
    measurements: Measurements
    sensor: SensorEstimate
    run: FilterRun
    first: int
    errors: dict[str, dict[str, float]] = field(default_factory=dict)
    step_time_us: float = float("nan")
    setup: dict[str, np.ndarray] = field(default_factory=dict)

    @property
    def end(self) -> int:
        """One past the last filtered sample (the run's row ``j`` is sample ``j + 1``; fewer after a divergence)."""
        return self.run.x.shape[0] + 1

    def fused(self, name: str, k: Any) -> np.ndarray:
        """The filter's estimate of a state part at samples ``k`` (each in ``1 .. end - 1``).

        Parameters
        ----------
        name : str
            A state slice name (``"position"``, ..., ``"angular_acceleration"``).
        k : array_like of int
            Sample indices.

        Returns
        -------
        numpy.ndarray, shape (len(k), 3 or 4)
        """
        return self.run.x[np.asarray(k) - 1][:, _SLICES_19[name]]

    def nees(self) -> np.ndarray:
        """NEES of the filtered samples from :attr:`first` on (:meth:`FilterRun.nees` against the truth).

        Returns
        -------
        numpy.ndarray, shape (end - first,)
        """
        return self.run.nees(self.truth.x[1 : self.end])[self.first - 1 :]

    def series(self, quantity: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Per-sample error norms of one quantity (thesis units), over the metric's samples.

        Parameters
        ----------
        quantity : str
            A key of :data:`QUANTITIES`.

        Returns
        -------
        t : numpy.ndarray, shape (M,)
            Times [s].
        sensor : numpy.ndarray, shape (M,)
            Sensor-only error norms.
        fusion : numpy.ndarray, shape (M,)
            Fused error norms.

        Raises
        ------
        InputError
            An unknown quantity, or a rotation quantity of a 3-axis case.
        """
        if quantity not in QUANTITIES or (QUANTITIES[quantity][2] and not self.truth.rotation):
            raise InputError(f"quantity: expected one of {', '.join(self.errors)}, got {quantity!r}")
        name, scale, _ = QUANTITIES[quantity]
        k = np.arange(self.first, self.end)
        truth = getattr(self.truth, name)[k]
        sensor = getattr(self.sensor, name)[k - self.sensor.first]
        fused = self.fused(name, k)
        if name == "quaternion":
            return self.truth.t[k], scale * orientation_error(sensor, truth), scale * orientation_error(fused, truth)
        return self.truth.t[k], scale * np.linalg.norm(sensor - truth, axis=1), scale * np.linalg.norm(fused - truth, axis=1)


_SLICES_19 = {"position": slice(0, 3), "velocity": slice(3, 6), "acceleration": slice(6, 9), "quaternion": slice(9, 13),
              "angular_velocity": slice(13, 16), "angular_acceleration": slice(16, 19)}


