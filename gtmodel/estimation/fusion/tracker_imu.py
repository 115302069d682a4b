"""Simulated laser tracker + IMU of Cvitanic (2021), section 4.2: Table 7 sensors, sine paths, baseline estimates.

What the fusion study (:mod:`gtmodel.estimation.fusion.study`) runs on:

* :class:`SensorSpec`: the Table 7 figures (baseline and the sweep values) of the tracker
  (position and orientation noise), the gyro and the accelerometer (bias, noise density),
  the sample time, the feed rate and the error of the believed IMU-to-target transform.
  :data:`TABLE_7` holds the thesis' figures as transcribed in the reference data
  (``serial_kr500.toml``, ``[state_estimation]``); a test checks them against that file, and
  :meth:`SensorSpec.from_reference` reads the same table from any mapping of that form.
* :class:`~gtmodel.estimation.fusion.sine_path.SinePath` (re-exported here): the sine path at the
  feed rate, 3-axis or 5-axis, with its closed-form true state (:mod:`gtmodel.estimation.fusion.sine_path`).
* :func:`measure`: the sensor readings: the model's CasADi measurement Function (built with the
  TRUE IMU transform) mapped over the true states, plus a constant bias (gyro, accelerometer:
  the Table 7 value on every axis, positive) and white Gaussian noise at the sample time
  (tracker position: the Table 7 figure as the standard deviation per axis and sample; tracker
  orientation: a rotation vector of that standard deviation per axis composed on the body side,
  ``quat_m = quat (x) exp(delta / 2)``; gyro and accelerometer: ``sigma = density sqrt(1 / dt)``).
  The accelerometer is gravity-free (see :mod:`~gtmodel.estimation.filters.end_effector`).
* :func:`four_point_derivative`: the tracker-only baseline: a causal four-point linear
  regression (:func:`scipy.signal.savgol_coeffs`, window 4, order 1, first derivative,
  evaluated at the newest sample), used for the velocity from the tracker positions and for
  the angular acceleration from the gyro; :func:`sensor_only` gathers every sensor-only estimate.
* :func:`mean_error`, :func:`orientation_error`: the error metric of every table, the MEAN over
  samples of the EUCLIDEAN NORM of the error vector (orientation: of the rotation angle between
  estimate and truth).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Any, Mapping

import casadi as ca
import numpy as np
import scipy.signal

from gtmodel._arrays import as_array, as_finite, as_signal, positive_float
from gtmodel._geometry import quat_conj, quat_exp, quat_mul, quaternion_to_rotation
from gtmodel.errors import InputError
from gtmodel.estimation.fusion.sine_path import MAX_SAMPLES, MIN_SAMPLES, SINE_PATH, SinePath, Truth, _map
from gtmodel.estimation.filters.end_effector import (
    IMU_ROTATION,
    IMU_TRANSLATION_M,
    EndEffectorModel,
)

__all__ = [
    "TABLE_7",
    "SINE_PATH",
    "MIN_SAMPLES",
    "MAX_SAMPLES",
    "SWEEP_PARAMETERS",
    "SensorSpec",
    "SinePath",
    "Truth",
    "Measurements",
    "measure",
    "four_point_derivative",
    "four_point_velocity",
    "sensor_only",
    "SensorEstimate",
    "mean_error",
    "orientation_error",
    "believed_transform",
    "error_axis",
]

#: Table 7 of Cvitanic (2021): baseline and sweep values of each parameter, units in the name
#: (the reference data ``serial_kr500.toml``, ``[state_estimation]``).
TABLE_7: dict[str, dict[str, Any]] = {
    "position_noise_mm": {"baseline": 0.0064, "offsets": [0.064, 0.64]},
    "orientation_noise_deg": {"baseline": 0.015, "offsets": [0.15, 1.5]},
    "gyro_bias_deg_s": {"baseline": 0.0008, "offsets": [0.008, 0.08, 0.8, 8]},
    "gyro_noise_deg_s_rtHz": {"baseline": 0.0016, "offsets": [0.016, 0.16]},
    "accel_bias_m_s2": {"baseline": 0.00025, "offsets": [0.0025, 0.025]},
    "accel_noise_m_s2_rtHz": {"baseline": 0.00039, "offsets": [0.0039, 0.039]},
    "sample_time_s": {"baseline": 0.001, "offsets": [0.002, 0.01]},
    "feed_rate_mm_s": {"baseline": 42.33, "offsets": [21.17, 4.233]},
    "transform_translation_error_mm": {"baseline": 0.0, "offsets": [0.254, 2.54]},
    "transform_orientation_error_deg": {"baseline": 0.0, "offsets": [0.1, 1, 10]},
}
#: The Table 7 parameters, in the order of the table.
SWEEP_PARAMETERS = tuple(TABLE_7)
#: Parameters that must be > 0 (noise, sample time, feed rate); the others (biases,
#: transform errors) may have any sign.
_POSITIVE = ("position_noise_mm", "orientation_noise_deg", "gyro_noise_deg_s_rtHz", "accel_noise_m_s2_rtHz", "sample_time_s", "feed_rate_mm_s")
#: Directions of the believed-transform errors (a decision: the thesis gives magnitudes only):
#: the translation error along (1, 1, 1)/sqrt(3) of the IMU frame, the orientation error about
#: (1, 1, 1)/sqrt(3).
_ERROR_DIRECTION = np.ones(3) / math.sqrt(3.0)
#: The four-point regression window.
WINDOW = 4


@dataclass(frozen=True)
class SensorSpec:
    """Sensor figures of one run (Cvitanic (2021), Table 7), in the table's units.

    Parameters
    ----------
    position_noise_mm : float
        Tracker position noise, standard deviation per axis and sample [mm] (> 0).
    orientation_noise_deg : float
        Tracker orientation noise, standard deviation of the rotation angle per axis and sample [deg] (> 0).
    gyro_bias_deg_s : float
        Gyro bias, the same on every IMU axis [deg/s].
    gyro_noise_deg_s_rtHz : float
        Gyro noise density [deg/s/sqrt(Hz)] (> 0).
    accel_bias_m_s2 : float
        Accelerometer bias, the same on every IMU axis [m/s^2].
    accel_noise_m_s2_rtHz : float
        Accelerometer noise density [m/s^2/sqrt(Hz)] (> 0).
    sample_time_s : float
        Sample time of every sensor [s] (> 0; 1 kHz in the baseline).
    feed_rate_mm_s : float
        Feed rate of the sine path along x [mm/s] (> 0).
    transform_translation_error_mm : float
        Error of the filter's believed IMU-to-target translation [mm] (along (1, 1, 1)/sqrt(3)).
    transform_orientation_error_deg : float
        Error of the filter's believed IMU-to-target rotation [deg] (about (1, 1, 1)/sqrt(3)).

    Raises
    ------
    InputError
        A value that is not a finite number, or a noise, the sample time or the feed rate not > 0
        (the field is named).
    """

    position_noise_mm: float = TABLE_7["position_noise_mm"]["baseline"]
    orientation_noise_deg: float = TABLE_7["orientation_noise_deg"]["baseline"]
    gyro_bias_deg_s: float = TABLE_7["gyro_bias_deg_s"]["baseline"]
    gyro_noise_deg_s_rtHz: float = TABLE_7["gyro_noise_deg_s_rtHz"]["baseline"]
    accel_bias_m_s2: float = TABLE_7["accel_bias_m_s2"]["baseline"]
    accel_noise_m_s2_rtHz: float = TABLE_7["accel_noise_m_s2_rtHz"]["baseline"]
    sample_time_s: float = TABLE_7["sample_time_s"]["baseline"]
    feed_rate_mm_s: float = TABLE_7["feed_rate_mm_s"]["baseline"]
    transform_translation_error_mm: float = TABLE_7["transform_translation_error_mm"]["baseline"]
    transform_orientation_error_deg: float = TABLE_7["transform_orientation_error_deg"]["baseline"]

    def __post_init__(self) -> None:
        for f in dataclasses.fields(self):
            value = getattr(self, f.name)
            if isinstance(value, bool) or not isinstance(value, (int, float, np.floating, np.integer)) or not math.isfinite(value):
                raise InputError(f"{f.name}: expected a finite number, got {value!r}")
            if f.name in _POSITIVE and not value > 0:
                raise InputError(f"{f.name}: expected a positive number, got {value!r}")
            object.__setattr__(self, f.name, float(value))

    @classmethod
    def from_reference(cls, table: Mapping[str, Any]) -> "SensorSpec":
        """The baseline of a Table 7 mapping (``{name: {"baseline": value, "offsets": [...]}}``).

        Parameters
        ----------
        table : Mapping
            E.g. the ``[state_estimation]`` table of the reference data ``serial_kr500.toml``
            (other keys are ignored).

        Returns
        -------
        SensorSpec

        Raises
        ------
        InputError
            A parameter missing or without a ``baseline``, or a baseline the class refuses.
        """
        values = {}
        for name in SWEEP_PARAMETERS:
            entry = table.get(name) if isinstance(table, Mapping) else None
            if not isinstance(entry, Mapping) or "baseline" not in entry:
                raise InputError(f"table: expected {name} = {{ baseline = ..., offsets = [...] }}, got {entry!r}")
            values[name] = entry["baseline"]
        return cls(**values)

    def replace(self, **changes: float) -> "SensorSpec":
        """A copy with some figures changed (checked again).

        Parameters
        ----------
        **changes : float
            Field name -> new value.

        Returns
        -------
        SensorSpec

        Raises
        ------
        InputError
            An unknown field name, or a value the class refuses.
        """
        unknown = sorted(set(changes) - set(SWEEP_PARAMETERS))
        if unknown:
            raise InputError(f"changes: expected Table 7 parameters ({', '.join(SWEEP_PARAMETERS)}), got {', '.join(unknown)}")
        return dataclasses.replace(self, **changes)

    def sweep(self, name: str, offsets: Any = None) -> list["SensorSpec"]:
        """The sweep of one Table 7 parameter: a copy per value, the others unchanged.

        Parameters
        ----------
        name : str
            A Table 7 parameter (:data:`SWEEP_PARAMETERS`).
        offsets : sequence of float, optional
            The values (default: the thesis' offsets of :data:`TABLE_7`).

        Returns
        -------
        list of SensorSpec

        Raises
        ------
        InputError
            An unknown parameter, or a value the class refuses.
        """
        if name not in TABLE_7:
            raise InputError(f"name: expected one of {', '.join(SWEEP_PARAMETERS)}, got {name!r}")
        values = TABLE_7[name]["offsets"] if offsets is None else list(as_finite(offsets, "offsets").ravel())
        return [self.replace(**{name: float(v)}) for v in values]

    # -- per-sample standard deviations in SI units ---------------------------------------
    @property
    def dt(self) -> float:
        """Sample time [s]."""
        return self.sample_time_s

    @property
    def position_std(self) -> float:
        """Tracker position noise per axis and sample [m]."""
        return self.position_noise_mm * 1e-3

    @property
    def orientation_std(self) -> float:
        """Tracker orientation noise per axis and sample [rad]."""
        return math.radians(self.orientation_noise_deg)

    @property
    def gyro_std(self) -> float:
        """Gyro noise per axis and sample, ``density sqrt(1 / dt)`` [rad/s]."""
        return math.radians(self.gyro_noise_deg_s_rtHz) * math.sqrt(1.0 / self.dt)

    @property
    def accel_std(self) -> float:
        """Accelerometer noise per axis and sample, ``density sqrt(1 / dt)`` [m/s^2]."""
        return self.accel_noise_m_s2_rtHz * math.sqrt(1.0 / self.dt)

    @property
    def gyro_bias(self) -> np.ndarray:
        """Gyro bias vector in the IMU frame [rad/s], shape (3,)."""
        return np.full(3, math.radians(self.gyro_bias_deg_s))

    @property
    def accel_bias(self) -> np.ndarray:
        """Accelerometer bias vector in the IMU frame [m/s^2], shape (3,)."""
        return np.full(3, self.accel_bias_m_s2)

    @property
    def feed_rate(self) -> float:
        """Feed rate along x [m/s]."""
        return self.feed_rate_mm_s * 1e-3


def believed_transform(spec: SensorSpec, translation: Any = IMU_TRANSLATION_M, rotation: Any = IMU_ROTATION,
                       axis: Any = None) -> tuple[np.ndarray, np.ndarray]:
    """The filter's belief of the IMU-to-target transform: the true one with the Table 7 errors.

    ``t_belief = t + e_t u``, ``R_belief = R exp(e_R [u]x)`` with ``u`` the unit error axis in
    the IMU frame (the rotation error on the IMU side). Default ``u = (1, 1, 1)/sqrt(3)``; the
    thesis applies both errors "to the z axis", its sine's amplitude direction (Cvitanic (2021),
    section 4.2.2).

    Parameters
    ----------
    spec : SensorSpec
        Gives ``transform_translation_error_mm`` and ``transform_orientation_error_deg``.
    translation : array_like, shape (3,), optional
        The true lever arm IMU -> target in the IMU frame [m].
    rotation : array_like, shape (3, 3), optional
        The true rotation ``R_TI`` (IMU -> target coordinates).
    axis : array_like, shape (3,), optional
        The error axis in the IMU frame (normalised; default ``(1, 1, 1)/sqrt(3)``).

    Returns
    -------
    translation : numpy.ndarray, shape (3,)
    rotation : numpy.ndarray, shape (3, 3)

    Raises
    ------
    InputError
        ``spec`` not a SensorSpec, a transform of another shape or not finite, an axis of zero norm.
    """
    if not isinstance(spec, SensorSpec):
        raise InputError(f"spec: expected a SensorSpec, got {type(spec).__name__}")
    u = _ERROR_DIRECTION if axis is None else error_axis(axis)
    t = as_array(translation, (3,), "translation") + spec.transform_translation_error_mm * 1e-3 * u
    r = as_array(rotation, (3, 3), "rotation")
    dq = quat_exp(ca.DM(math.radians(spec.transform_orientation_error_deg) * u))
    return t, r @ quaternion_to_rotation(dq, normalise=False)


def error_axis(axis: Any) -> np.ndarray:
    """The unit axis of the transform errors (:func:`believed_transform`).

    Parameters
    ----------
    axis : array_like, shape (3,)
        A direction in the IMU frame, nonzero.

    Returns
    -------
    numpy.ndarray, shape (3,)
        ``axis / |axis|``.

    Raises
    ------
    InputError
        Another shape, a non-finite entry or a zero norm.
    """
    u = as_array(axis, (3,), "axis")
    n = float(np.linalg.norm(u))
    if not n > 1e-12:
        raise InputError(f"axis: expected a direction of nonzero norm, got {u.tolist()}")
    return u / n


def _compose_function() -> ca.Function:
    """``quat (x) exp(delta / 2)`` (a body-side rotation-vector perturbation), normalised."""
    q, d = ca.SX.sym("q", 4), ca.SX.sym("delta", 3)
    out = quat_mul(q, quat_exp(d))
    return ca.Function("perturb", [q, d], [out / ca.norm_2(out)])


def _angle_function() -> ca.Function:
    """Rotation angle ``2 atan2(|v|, |w|)`` of ``conj(q_est) (x) q_true`` (sign-invariant)."""
    qe, qt = ca.SX.sym("q_est", 4), ca.SX.sym("q_true", 4)
    d = quat_mul(quat_conj(qe / ca.norm_2(qe)), qt / ca.norm_2(qt))
    return ca.Function("angle", [qe, qt], [2 * ca.atan2(ca.norm_2(d[1:4]), ca.fabs(d[0]))])


def _sensor_acceleration_function() -> ca.Function:
    """World acceleration of the target from the IMU reading (29), the tracker orientation and ``R_TI``."""
    a_t_imu, quat, r_ti = ca.SX.sym("a_target_imu", 3), ca.SX.sym("quat", 4), ca.SX.sym("R_TI", 3, 3)
    r_wi = ca.mtimes(quaternion_to_rotation(quat / ca.norm_2(quat), normalise=False), r_ti)
    return ca.Function("sensor_acceleration", [a_t_imu, quat, r_ti], [ca.mtimes(r_wi, a_t_imu)])


_PERTURB = _compose_function()
_ANGLE = _angle_function()
_SENSOR_ACCELERATION = _sensor_acceleration_function()


@dataclass(frozen=True)
class Measurements:
    """Simulated sensor readings of one run (rows are samples).

    Parameters
    ----------
    t : numpy.ndarray, shape (N,)
        Times [s].
    z : numpy.ndarray, shape (N, nz)
        Measurements in the model's layout (13: ``[p_m, quat_m, w_m, a_m]``; 6: ``[p_m, a_m]``).
    gyro : numpy.ndarray, shape (N, 3)
        Gyro readings in the IMU frame [rad/s] (also for a 3-axis run, where the model does not use them).
    quaternion : numpy.ndarray, shape (N, 4)
        Tracker orientation readings (also for a 3-axis run).
    spec : SensorSpec
        The sensor figures used.
    """

    t: np.ndarray
    z: np.ndarray
    gyro: np.ndarray
    quaternion: np.ndarray
    spec: SensorSpec

    @property
    def position(self) -> np.ndarray:
        """Tracker positions [m], shape (N, 3)."""
        return self.z[:, 0:3]

    @property
    def accelerometer(self) -> np.ndarray:
        """Accelerometer readings in the IMU frame [m/s^2], shape (N, 3)."""
        return self.z[:, -3:]


def measure(truth: Truth, spec: SensorSpec, seed: int = 0, imu_translation: Any = IMU_TRANSLATION_M, imu_rotation: Any = IMU_ROTATION) -> Measurements:
    """Sensor readings of a true trajectory: the model's measurement Function + bias + white noise.

    The noise-free readings are the CasADi ``"measurement"`` Function of a 19-D
    :class:`~gtmodel.estimation.filters.end_effector.EndEffectorModel` built with the TRUE transform
    (``imu_translation``, ``imu_rotation``), mapped over the samples (``Function.map``); a
    3-axis truth is lifted to 19-D with its constant orientation and zero rates. Then
    (module docstring): tracker position ``+ N(0, sigma_p^2)`` per axis; tracker orientation
    ``quat (x) exp(delta / 2)``, ``delta ~ N(0, sigma_o^2 I_3)``; gyro ``+ b_g + N(0, sigma_g^2)``;
    accelerometer ``+ b_a + N(0, sigma_a^2)`` with ``sigma = density sqrt(1 / dt)``.
    The draws are in the order position, orientation, gyro, accelerometer from
    ``numpy.random.default_rng(seed)``.

    Parameters
    ----------
    truth : Truth
        From :meth:`SinePath.truth` at the sample time ``spec.sample_time_s``.
    spec : SensorSpec
        Noise and bias figures.
    seed : int, optional
        Seed of the noise.
    imu_translation : array_like, shape (3,), optional
        True lever arm IMU -> target in the IMU frame [m].
    imu_rotation : array_like, shape (3, 3), optional
        True rotation ``R_TI``.

    Returns
    -------
    Measurements
        ``z`` in the 13-D layout if ``truth.rotation``, else the 6-D one.

    Raises
    ------
    InputError
        ``truth`` or ``spec`` of the wrong type, samples not ``spec.sample_time_s`` apart,
        a bad transform.
    """
    if not isinstance(truth, Truth):
        raise InputError(f"truth: expected a Truth (SinePath.truth), got {type(truth).__name__}")
    if not isinstance(spec, SensorSpec):
        raise InputError(f"spec: expected a SensorSpec, got {type(spec).__name__}")
    if truth.t.size > 1 and abs(truth.t[1] - truth.t[0] - spec.dt) > 1e-12:
        raise InputError(f"truth: expected samples spec.sample_time_s = {spec.dt:g} s apart, got {truth.t[1] - truth.t[0]:g} s")
    n = truth.t.size
    model = EndEffectorModel(spec.dt, rotation=True, imu_translation=imu_translation, imu_rotation=imu_rotation)
    x19 = truth.x if truth.rotation else np.hstack([truth.x, np.tile(truth.orientation, (n, 1)), np.zeros((n, 6))])
    z = _map(model.measurement, n, x19.T).T  # (N, 13): [p, quat, w_I, a_I]
    rng = np.random.default_rng(seed)
    p_m = z[:, 0:3] + rng.normal(0.0, spec.position_std, (n, 3))
    quat_m = _map(_PERTURB, n, z[:, 3:7].T, rng.normal(0.0, spec.orientation_std, (n, 3)).T).T
    gyro = z[:, 7:10] + spec.gyro_bias + rng.normal(0.0, spec.gyro_std, (n, 3))
    acc = z[:, 10:13] + spec.accel_bias + rng.normal(0.0, spec.accel_std, (n, 3))
    zz = np.hstack([p_m, quat_m, gyro, acc]) if truth.rotation else np.hstack([p_m, acc])
    return Measurements(truth.t.copy(), zz, gyro, quat_m, spec)


def four_point_derivative(y: Any, dt: float) -> np.ndarray:
    """Causal four-point linear-regression derivative, at the newest sample of each window.

    The least-squares slope of a line through ``y[k-3..k]`` (:func:`scipy.signal.savgol_coeffs`
    with window 4, order 1, ``deriv=1``, ``pos=3``: the coefficients ``[-3, -1, 1, 3] / (10 dt)``
    applied to ``y[k-3], ..., y[k]``). For order 1 the slope is the same anywhere in the window,
    so it is the derivative at the window's centre, ``1.5 dt`` before the newest sample: the
    baseline's lag, ``1.5 dt y''``, is part of its error. White noise ``sigma`` gives a slope
    noise ``sigma / (sqrt(5) dt)``.

    Parameters
    ----------
    y : array_like, shape (N, d)
        Samples (rows), ``N >= 4``.
    dt : float
        Sample time [s].

    Returns
    -------
    numpy.ndarray, shape (N - 3, d)
        The derivative at samples ``3 .. N-1`` (row ``i`` belongs to sample ``i + 3``).

    Raises
    ------
    InputError
        ``y`` not a finite 2-D array with at least 4 rows, ``dt`` not positive.
    """
    dt = positive_float(dt, "dt")
    arr = as_signal(y, "y", min_samples=WINDOW)
    c = scipy.signal.savgol_coeffs(WINDOW, 1, deriv=1, delta=dt, pos=WINDOW - 1, use="dot")
    windows = np.lib.stride_tricks.sliding_window_view(arr, WINDOW, axis=0)  # (N-3, d, 4), oldest first
    return windows @ c


def four_point_velocity(positions: Any, dt: float) -> np.ndarray:
    """The tracker-only velocity baseline: :func:`four_point_derivative` of the tracker positions.

    Parameters
    ----------
    positions : array_like, shape (N, 3)
        Tracker positions [m], ``N >= 4``.
    dt : float
        Sample time [s].

    Returns
    -------
    numpy.ndarray, shape (N - 3, 3)
        Velocity [m/s] at samples ``3 .. N-1``.

    Raises
    ------
    InputError
        See :func:`four_point_derivative`.
    """
    return four_point_derivative(positions, dt)


@dataclass(frozen=True)
class SensorEstimate:
    """Sensor-only estimates of the target's state (rows are samples 3 .. N-1: the regression's).

    Parameters
    ----------
    position : numpy.ndarray, shape (M, 3)
        Tracker position [m].
    velocity : numpy.ndarray, shape (M, 3)
        Four-point regression of the tracker positions [m/s].
    acceleration : numpy.ndarray, shape (M, 3)
        Accelerometer reading moved to the target by (29) (with the gyro and its regression)
        and rotated to the world by the tracker orientation and the believed ``R_TI`` [m/s^2].
    quaternion : numpy.ndarray, shape (M, 4)
        Tracker orientation.
    angular_velocity : numpy.ndarray, shape (M, 3)
        Gyro rotated to the target frame, ``R_TI w_m`` [rad/s].
    angular_acceleration : numpy.ndarray, shape (M, 3)
        Four-point regression of the gyro, rotated to the target frame [rad/s^2].
    first : int
        Sample index of the first row (3).
    """

    position: np.ndarray
    velocity: np.ndarray
    acceleration: np.ndarray
    quaternion: np.ndarray
    angular_velocity: np.ndarray
    angular_acceleration: np.ndarray
    first: int = WINDOW - 1


def sensor_only(meas: Measurements, model: EndEffectorModel) -> SensorEstimate:
    """Every sensor-only estimate (no fusion), with the transform the filter believes.

    Velocity and angular acceleration by :func:`four_point_derivative`; the acceleration of the
    target from the accelerometer by the model's ``"lever_arm"`` Function (29) with the gyro
    and its regression (a 3-axis run: the orientation is constant and known, the rates zero),
    rotated to the world with the tracker orientation (3-axis: the model's known orientation).

    Parameters
    ----------
    meas : Measurements
        From :func:`measure`.
    model : EndEffectorModel
        The filter's model: its sample time, belief of the transform and (3-axis) orientation.

    Returns
    -------
    SensorEstimate

    Raises
    ------
    InputError
        Arguments of the wrong type, or a model of another sample time or layout.
    """
    if not isinstance(meas, Measurements) or not isinstance(model, EndEffectorModel):
        raise InputError("meas, model: expected Measurements and an EndEffectorModel")
    if abs(model.dt - meas.spec.dt) > 1e-12 or meas.z.shape[1] != model.nz:
        raise InputError(f"model: expected dt = {meas.spec.dt:g} s and nz = {meas.z.shape[1]}, got dt = {model.dt:g} s, nz = {model.nz}")
    dt, k0 = model.dt, WINDOW - 1
    n = meas.t.size - k0
    r_ti = model.imu_rotation
    velocity = four_point_velocity(meas.position, dt)
    if model.rotation:
        gyro = meas.gyro[k0:]
        alpha_i = four_point_derivative(meas.gyro, dt)
        quat = meas.quaternion[k0:]
    else:
        gyro = alpha_i = np.zeros((n, 3))
        quat = np.tile(model.orientation, (n, 1))
    a_t_imu = _map(model.lever_arm_acceleration, n, meas.accelerometer[k0:].T, gyro.T, alpha_i.T)
    acceleration = _map(_SENSOR_ACCELERATION, n, a_t_imu, quat.T, ca.DM(r_ti)).T
    return SensorEstimate(meas.position[k0:].copy(), velocity, acceleration, quat.copy(), gyro @ r_ti.T, alpha_i @ r_ti.T)


def mean_error(estimate: Any, truth: Any) -> float:
    """The tables' error metric: the mean over samples of the Euclidean norm of the error.

    Parameters
    ----------
    estimate, truth : array_like, shape (N, d)
        Estimated and true vectors (rows are samples).

    Returns
    -------
    float
        ``mean_k |estimate_k - truth_k|`` in the unit of the inputs.

    Raises
    ------
    InputError
        Shapes that differ, no rows, or values that are not finite.
    """
    e = as_finite(estimate, "estimate")
    t = as_finite(truth, "truth")
    if e.shape != t.shape or e.ndim != 2 or e.shape[0] == 0:
        raise InputError(f"estimate, truth: expected the same shape (N, d) with N >= 1, got {e.shape} and {t.shape}")
    return float(np.mean(np.linalg.norm(e - t, axis=1)))


def orientation_error(estimate: Any, truth: Any) -> np.ndarray:
    """Rotation angle between estimated and true orientations, per sample [rad].

    ``2 atan2(|v|, |w|)`` of ``conj(q_est) (x) q_true`` (both normalised; sign-invariant).

    Parameters
    ----------
    estimate, truth : array_like, shape (N, 4)
        Scalar-first quaternions.

    Returns
    -------
    numpy.ndarray, shape (N,)
        Angles in ``[0, pi]`` [rad].

    Raises
    ------
    InputError
        Shapes other than the same (N, 4), or values that are not finite.
    """
    e = as_finite(estimate, "estimate")
    t = as_finite(truth, "truth")
    if e.shape != t.shape or e.ndim != 2 or e.shape[1] != 4 or e.shape[0] == 0:
        raise InputError(f"estimate, truth: expected the same shape (N, 4), got {e.shape} and {t.shape}")
    return _map(_ANGLE, e.shape[0], e.T, t.T).ravel()
