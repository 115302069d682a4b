"""The tracker + IMU fusion study of Cvitanic (2021), sections 4.2-4.3 (Tables 8-10, the filter comparison).

One case (:meth:`FusionStudy.run_case`): the sine path (3-axis or 5-axis,
:class:`~gtmodel.estimation.fusion.tracker_imu.SinePath`), its sensors measured with the TRUE
IMU-to-target transform (:func:`~gtmodel.estimation.fusion.tracker_imu.measure`), a filter built on
the :class:`~gtmodel.estimation.filters.end_effector.EndEffectorModel` with the BELIEVED transform
(Table 7's transform errors are the difference), and the sensor-only estimates
(:func:`~gtmodel.estimation.fusion.tracker_imu.sensor_only`: tracker position and orientation, the
four-point regressions of the positions and of the gyro, the accelerometer moved to the target).
3-axis cases use the Kalman filter on the linear 9-D model, 5-axis cases the EKF on the 19-D one.

Error metric of every table: the MEAN over the samples of the EUCLIDEAN NORM of the error
(orientation: of the rotation angle), over the samples from ``warmup`` on (both the filter and
the regressions are judged on the same samples), in the thesis' units (mm, mm/s, m/s^2, deg,
deg/s, deg/s^2).

Filter tuning (a decision, documented in :meth:`FusionStudy.process_noise`): ``R`` is the
Table 7 noise (``sigma = density sqrt(1 / dt)`` for the IMU); ``Q`` is the white-jerk model with
the standard deviation set from the path, ``sigma_j = max |jerk|`` and ``sigma_alpha' = max
|angular jerk|`` of the closed-form path, the same on each axis (Bar-Shalom, Li and Kirubarajan
(2001), sec. 6.3.3: the process-noise standard deviation of the order of the largest increment
of the modelled derivative over a sample, ``0.5 Delta_M <= sigma dt <= Delta_M``; we take the
upper end), floored at :data:`MIN_JERK_STD`. The thesis' own Appendix B ``Q_diag`` (diagonal
per-state variances of the 9-D filter) is run beside it on the 3-axis path (Table 8 column
``fusion_appendix_b``): with ``Q_p = 2.54e-4 m^2`` per sample, six orders of magnitude above
``R_p``, that filter passes the tracker position through unchanged.

One case's result is a :class:`~gtmodel.estimation.fusion.runs.FusionRun`.
Consistency (:func:`~gtmodel.estimation.fusion.runs.nees_test`): the time-average NEES of the baseline run against its two-sided
95 % chi-square band, with the number of effectively independent samples from the NEES'
integrated autocorrelation time (the samples of one run are correlated; see the function).
"""

from __future__ import annotations

import logging
import math
import time
from dataclasses import dataclass, field
from typing import Any

import casadi as ca
import numpy as np

from gtmodel._arrays import as_array, as_finite, positive_float, positive_int
from gtmodel._geometry import quat_exp, quat_mul
from gtmodel.errors import InputError
from gtmodel.estimation.filters.end_effector import (
    IMU_ROTATION,
    IMU_TRANSLATION_M,
    EndEffectorModel,
)
from gtmodel.estimation.filters.kalman import ExtendedKalmanFilter, KalmanFilter
from gtmodel.estimation.fusion.limits import ROTATION_ONLY_PARAMETERS, TUNINGS, limits
from gtmodel.estimation.fusion.runs import QUANTITIES, FusionRun, nees_test
from gtmodel.estimation.filters.particle import ParticleFilter
from gtmodel.estimation.filters.unscented import UnscentedKalmanFilter
from gtmodel.estimation.fusion.tracker_imu import (
    SWEEP_PARAMETERS,
    TABLE_7,
    SensorSpec,
    SinePath,
    Truth,
    believed_transform,
    error_axis,
    measure,
    sensor_only,
)
from gtmodel.status import Status, StatusResult

__all__ = [
    "APPENDIX_B",
    "THESIS_TABLE_8",
    "THESIS_TABLE_11",
    "FILTERS",
    "MIN_JERK_STD",
    "PEAK_FRACTION",
    "DEFAULT_INITIAL_COVARIANCE",
    "MOTIONS",
    "FusionStudy",
    "FusionStudyResult",
]

_log = logging.getLogger("gtmodel")

#: Appendix B of Cvitanic (2021): the 9-D KF's diagonal ``Q`` and ``R`` (reference ``Q_diag``, ``R_diag``).
APPENDIX_B = {
    "Q_diag": (2.54e-4, 2.54e-4, 2.54e-4, 21.2e-4, 21.2e-4, 21.2e-4, 98.1e-4, 98.1e-4, 98.1e-4),
    "R_diag": (4.03e-11, 4.03e-11, 4.03e-11, 1.54e-4, 1.54e-4, 1.54e-4),
}
#: Table 8 of Cvitanic (2021) (reference ``[state_estimation.table_8]``): ``[3-axis, 5-axis]``;
#: ``None`` where the thesis has no entry (the 3-axis angular velocity). Velocity, orientation
#: and angular acceleration are not in the reference data.
THESIS_TABLE_8 = {
    "position_mm": {"sensor": (0.0089, 0.0089), "fusion": (0.0089, 0.0089)},
    "acceleration_m_s2": {"sensor": (0.00018, 0.00061), "fusion": (0.00012, 0.00040)},
    "angular_velocity_deg_s": {"sensor": (None, 0.070), "fusion": (None, 0.062)},
}
#: Table 11 of Cvitanic (2021) (reference ``[state_estimation.table_11]``): HARDWARE velocity mean errors
#: [mm/s] of the robot's own estimate and of the fusion at the feed rates 21.17, 42.33, 63.50 mm/s
#: (the simulation's "up to 95 %" became 35-37 % on hardware; spec section 4).
THESIS_TABLE_11 = {
    "feed_rates_mm_s": (21.17, 42.33, 63.50),
    "linear_no_rotation": {"robot_mean": (0.93, 0.80, 0.93), "fusion_mean": (0.76, 0.51, 0.51)},
    "semicircle_no_rotation": {"robot_mean": (0.93, 2.03, 0.97), "fusion_mean": (0.64, 1.27, 0.64)},
    "linear_rotation": {"robot_mean": (0.80, 0.97, 1.10), "fusion_mean": (0.64, 0.64, 0.72)},
    "semicircle_rotation": {"robot_mean": (0.85, 1.02, 1.23), "fusion_mean": (0.64, 0.72, 0.80)},
}
#: Filters of the comparison.
FILTERS = ("kf", "ekf", "ukf", "pf")
#: Floor of the path-derived jerk standard deviations [m/s^3, rad/s^3] (a straight path has none).
MIN_JERK_STD = 1e-3
#: Fraction of the largest |alpha| above which a sample is "at a sine peak".
PEAK_FRACTION = 0.9


@dataclass(kw_only=True)
class FusionStudyResult(StatusResult):
    """The study's tables (Cvitanic (2021), sec. 4.3); every error is :data:`QUANTITIES`' metric.

    Parameters
    ----------
    status : Status
        The worst status of the runs.
    message : str
        Summary.
    table_8 : dict
        Per motion (``"3-axis"``, ``"5-axis"``) per quantity ``{sensor, fusion, change_percent,
        thesis_sensor, thesis_fusion}`` (3-axis also ``fusion_appendix_b``: the KF with the thesis' Q).
    table_9 : dict
        Per motion: the tracker noise ``factor`` times the baseline; per tracker quantity
        (position, 5-axis also orientation) ``{baseline_sensor, sensor, fusion, fusion_below_sensor,
        fusion_above_baseline_sensor}``.
    velocity_mean_error_mm_s : dict
        Per motion ``{tracker, fusion, improvement_percent}`` (tracker: the four-point regression).
    angular_acceleration : dict
        5-axis: ``{gyro_regression, fusion, improvement_percent}`` over all samples, at the sine
        peaks (``|alpha| >= 0.9 max``) and elsewhere [deg/s^2].
    table_10 : list of dict
        One row per motion and swept value: ``parameter, value, motion, filter, status`` and per quantity
        ``{sensor, fusion, improvement_percent}``, ``stops_paying`` (quantities where fusion is not better).
    table_10_limits : list of dict
        Per motion, tuning and parameter where the fused velocity stops paying
        (:func:`~gtmodel.estimation.fusion.limits.velocity_limit`), against the thesis' Table 10.
    filter_comparison : list of dict
        One row per motion and filter: ``motion, filter, status, samples, step_time_us`` and the errors.
    nees : dict
        Per motion the :func:`nees_test` of the baseline run.
    process_noise : dict
        Per motion the jerk standard deviations used (and the thesis' Appendix B figures).
    runs : dict
        The baseline runs (``"3-axis"``, ``"5-axis"``) and the 10x-noisier ones (``"3-axis noisy"``, ...).
    notes : list of str
        What was not run (e.g. filters not available) and why.
    """

    table_8: dict[str, Any] = field(default_factory=dict)
    table_9: dict[str, Any] = field(default_factory=dict)
    velocity_mean_error_mm_s: dict[str, Any] = field(default_factory=dict)
    angular_acceleration: dict[str, Any] = field(default_factory=dict)
    table_10: list[dict[str, Any]] = field(default_factory=list)
    table_10_limits: list[dict[str, Any]] = field(default_factory=list)
    filter_comparison: list[dict[str, Any]] = field(default_factory=list)
    nees: dict[str, Any] = field(default_factory=dict)
    process_noise: dict[str, Any] = field(default_factory=dict)
    runs: dict[str, FusionRun] = field(default_factory=dict)
    notes: list[str] = field(default_factory=list)


def _improvement(sensor: float, fusion: float) -> float | None:
    return None if not sensor > 0 else 100.0 * (sensor - fusion) / sensor


#: Default initial covariance: variances of position [m^2], velocity, acceleration, orientation
#: (rotation angle per axis) [rad^2], angular velocity, angular acceleration.
DEFAULT_INITIAL_COVARIANCE = (1e-10, 1e-6, 1e-2, 1e-6, 1e-4, 1e-2)
MOTIONS = {"3-axis": False, "5-axis": True}


@dataclass(frozen=True)
class FusionStudy:
    """The simulation study of Cvitanic (2021), sections 4.2-4.3 (see the module docstring).

    Parameters
    ----------
    spec : SensorSpec, optional
        Baseline sensors (Table 7).
    duration : float, optional
        Length of every run [s] (> 0).
    amplitude, spatial_frequency : float, optional
        The sine path [m], [cycles/m] (reference ``sine_path``).
    start : array_like, shape (3,), optional
        Start of the target [m].
    rotation_amplitude : float, optional
        5-axis rotation amplitude ``theta_0`` [rad].
    rotation_axis : array_like, shape (3,), optional
        5-axis body rotation axis.
    orientation : array_like, shape (4,), optional
        Initial orientation quaternion ``[w, x, y, z]`` (nonzero norm).
    rotation_law : {"sine", "normal"}, optional
        The 5-axis rotation (:class:`~gtmodel.estimation.fusion.sine_path.SinePath`; "normal": the thesis' tool normal to the path).
    feed : {"x", "tangential"}, optional
        The feed rate is the speed along x, or along the arc (the thesis' constant tangential speed;
        :class:`~gtmodel.estimation.fusion.sine_path.SinePath`).
    transform_error_axis : array_like, shape (3,) or None, optional
        Axis of the Table 7 transform errors in the IMU frame
        (:func:`~gtmodel.estimation.fusion.tracker_imu.believed_transform`; None: ``(1, 1, 1)/sqrt(3)``).
    seed : int, optional
        Seed of the sensor noise and of the initial-state draw.
    warmup : float, optional
        Samples before this time [s] are left out of every metric.
    jerk_std, angular_jerk_std : float or None, optional
        White-jerk standard deviations [m/s^3], [rad/s^3]; None: from the path (module docstring).
    quaternion_std : float, optional
        The quaternion term of ``Q`` (:meth:`EndEffectorModel.process_noise`).
    initial_covariance : sequence of 6 float, optional
        Initial variances per block (:data:`DEFAULT_INITIAL_COVARIANCE`), all > 0; the initial
        state is the truth plus a draw from it (the orientation perturbed by a rotation vector).
    appendix_b_q : sequence of 9 float or None, optional
        Diagonal ``Q`` of the thesis' 3-axis KF (Appendix B), run beside the white-jerk KF; None: not run.
    noisy_tracker_factor : float, optional
        Table 9: the tracker's position and orientation noise times this.
    sweep : dict or None, optional
        Table 10: Table 7 parameter -> values (None: every parameter at the thesis' offsets).
    sweep_duration : float or None, optional
        Length of the sweep runs [s] (None: ``duration``).
    sweep_motions : sequence of str, optional
        Motions of the Table 10 sweep (``"3-axis"``, ``"5-axis"``); a 3-axis run skips the
        parameters it does not measure (:data:`~gtmodel.estimation.fusion.limits.ROTATION_ONLY_PARAMETERS`, Table 10's N/A).
    limit_tunings : sequence of str, optional
        Tunings of the Table 10 limit search (:mod:`~gtmodel.estimation.fusion.limits`; empty: not run).
    limit_parameters : sequence of str or None, optional
        Parameters of the limit search (None: every row of Table 10).
    limit_bisections : int, optional
        Halvings of the bracketing decade per limit.
    limit_centred : sequence of str, optional
        Parameters searched again against the centred (lag-free) tracker regression.
    comparison_filters : sequence of str, optional
        Filters of the comparison (:data:`FILTERS`).
    comparison_duration : float, optional
        Length of the comparison runs [s].
    particles : int, optional
        Particles of the particle filter.

    Raises
    ------
    InputError
        A value out of range (named): see the checks of :class:`~gtmodel.estimation.fusion.tracker_imu.SinePath`,
        a non-positive initial variance or Appendix B entry (not a positive definite covariance),
        an unknown sweep parameter or filter.
    """

    spec: SensorSpec = SensorSpec()
    duration: float = 3.0
    amplitude: float = 0.0762
    spatial_frequency: float = 19.685
    start: Any = (1.5, 0.0, 1.0)
    rotation_amplitude: float = math.radians(10.0)
    rotation_axis: Any = (0.5, 0.0, math.sqrt(3.0) / 2.0)
    orientation: Any = (1.0, 0.0, 0.0, 0.0)
    rotation_law: str = "sine"
    feed: str = "x"
    transform_error_axis: Any = None
    seed: int = 1
    warmup: float = 0.1
    jerk_std: float | None = None
    angular_jerk_std: float | None = None
    quaternion_std: float = 1e-6
    initial_covariance: Any = DEFAULT_INITIAL_COVARIANCE
    appendix_b_q: Any = APPENDIX_B["Q_diag"]
    noisy_tracker_factor: float = 10.0
    sweep: Any = None
    sweep_duration: float | None = None
    sweep_motions: Any = ("3-axis", "5-axis")
    limit_tunings: Any = ()
    limit_parameters: Any = None
    limit_bisections: int = 4
    limit_centred: Any = ()
    comparison_filters: Any = FILTERS
    comparison_duration: float = 1.0
    particles: int = 1000

    def __post_init__(self) -> None:
        object.__setattr__(self, "_cache", {})
        if not isinstance(self.spec, SensorSpec):
            raise InputError(f"spec: expected a SensorSpec, got {type(self.spec).__name__}")
        cov = as_finite(self.initial_covariance, "initial_covariance")
        if cov.shape != (6,) or not np.all(cov > 0):
            raise InputError(f"initial_covariance: expected a positive definite covariance: 6 variances > 0, got {cov.tolist()}")
        object.__setattr__(self, "initial_covariance", tuple(float(c) for c in cov))
        if self.appendix_b_q is not None:
            q = as_finite(self.appendix_b_q, "appendix_b_q")
            if q.shape != (9,) or not np.all(q > 0):
                raise InputError(f"appendix_b_q: expected a positive definite diagonal covariance: 9 variances > 0, got {q.tolist()}")
            object.__setattr__(self, "appendix_b_q", tuple(float(v) for v in q))
        for name in ("jerk_std", "angular_jerk_std"):
            if getattr(self, name) is not None:
                object.__setattr__(self, name, positive_float(getattr(self, name), name))
        object.__setattr__(self, "quaternion_std", positive_float(self.quaternion_std, "quaternion_std"))
        object.__setattr__(self, "warmup", float(as_finite(self.warmup, "warmup", nonnegative=True)))
        object.__setattr__(self, "noisy_tracker_factor", positive_float(self.noisy_tracker_factor, "noisy_tracker_factor"))
        object.__setattr__(self, "comparison_duration", positive_float(self.comparison_duration, "comparison_duration"))
        object.__setattr__(self, "particles", positive_int(self.particles, "particles"))
        if self.sweep_duration is not None:
            object.__setattr__(self, "sweep_duration", positive_float(self.sweep_duration, "sweep_duration"))
        sweep = {k: list(v["offsets"]) for k, v in TABLE_7.items()} if self.sweep is None else dict(self.sweep)
        unknown = sorted(set(sweep) - set(SWEEP_PARAMETERS))
        if unknown:
            raise InputError(f"sweep: expected Table 7 parameters ({', '.join(SWEEP_PARAMETERS)}), got {', '.join(unknown)}")
        for name, values in sweep.items():
            for v in values:
                self.spec.replace(**{name: v})  # checks the value
        object.__setattr__(self, "sweep", sweep)
        bad = [m for m in self.sweep_motions if m not in MOTIONS]
        if bad:
            raise InputError(f"sweep_motions: expected some of {', '.join(MOTIONS)}, got {', '.join(map(str, bad))}")
        bad = [t for t in self.limit_tunings if t not in TUNINGS]
        if bad:
            raise InputError(f"limit_tunings: expected some of {', '.join(TUNINGS)}, got {', '.join(map(str, bad))}")
        object.__setattr__(self, "sweep_motions", tuple(self.sweep_motions))
        if self.transform_error_axis is not None:
            object.__setattr__(self, "transform_error_axis", tuple(float(v) for v in error_axis(self.transform_error_axis)))
        object.__setattr__(self, "limit_tunings", tuple(self.limit_tunings))
        bad = [f for f in self.comparison_filters if f not in FILTERS]
        if bad:
            raise InputError(f"comparison_filters: expected some of {', '.join(FILTERS)}, got {', '.join(map(str, bad))}")
        if isinstance(self.seed, bool) or not isinstance(self.seed, (int, np.integer)) or self.seed < 0:
            raise InputError(f"seed: expected a non-negative integer, got {self.seed!r}")
        for rotation in (False, True):  # the geometry and the sample count, checked once
            self.path(rotation, self.spec).samples(self.spec.dt)

    # -- building blocks ---------------------------------------------------------------------
    def path(self, rotation: bool, spec: SensorSpec, duration: float | None = None) -> SinePath:
        """The sine path of a motion at the spec's feed rate.

        Parameters
        ----------
        rotation : bool
            5-axis (True) or 3-axis.
        spec : SensorSpec
            Gives the feed rate.
        duration : float, optional
            Record length [s] (default :attr:`duration`).

        Returns
        -------
        SinePath

        Raises
        ------
        InputError
            See :class:`~gtmodel.estimation.fusion.tracker_imu.SinePath`.
        """
        return SinePath(self.duration if duration is None else duration, spec.feed_rate, self.amplitude, self.spatial_frequency,
                        self.start, rotation, self.rotation_amplitude, self.rotation_axis, self.orientation, self.rotation_law, self.feed)

    def process_noise(self, path: SinePath, dt: float) -> tuple[float, float]:
        """The white-jerk standard deviations of ``Q`` [m/s^3], [rad/s^3] (module docstring).

        Given values (:attr:`jerk_std`, :attr:`angular_jerk_std`) win; otherwise the largest
        ``|jerk|`` and ``|angular jerk|`` of the closed-form path over its samples (Bar-Shalom
        et al. (2001), sec. 6.3.3), floored at :data:`MIN_JERK_STD`.

        Parameters
        ----------
        path : SinePath
            The path.
        dt : float
            Sample time [s].

        Returns
        -------
        tuple of float
            ``(sigma_jerk, sigma_angular_jerk)``.
        """
        truth = path.truth(dt)
        sj = self.jerk_std if self.jerk_std is not None else max(MIN_JERK_STD, float(np.linalg.norm(truth.jerk, axis=1).max()))
        sa = self.angular_jerk_std if self.angular_jerk_std is not None else max(MIN_JERK_STD, float(np.linalg.norm(truth.angular_jerk, axis=1).max()))
        return sj, sa

    def _initial(self, truth: Truth, rng: np.random.Generator, model: EndEffectorModel, P0: Any = None) -> tuple[np.ndarray, np.ndarray]:
        if P0 is not None:  # a given prior: the truth plus a draw from it, the quaternion renormalised
            P0 = as_array(P0, (model.nx, model.nx), "P0")
            x0 = truth.x[0] + rng.multivariate_normal(np.zeros(model.nx), P0, method="eigh")
            if model.rotation:
                x0[9:13] /= np.linalg.norm(x0[9:13])
            return x0, P0
        var = np.repeat(np.asarray(self.initial_covariance), 3)  # per axis: p, v, a, theta, w, alpha
        x0 = truth.x[0].copy()
        draw = rng.normal(0.0, np.sqrt(var))
        x0[0:9] += draw[0:9]
        if not model.rotation:
            return x0, np.diag(var[0:9])
        # orientation: the true quaternion turned by the drawn rotation vector, quat (x) exp(theta / 2)
        x0[9:13] = np.asarray(quat_mul(ca.DM(x0[9:13]), quat_exp(ca.DM(draw[9:12])))).ravel()
        x0[13:19] += draw[12:18]
        p0 = np.diag(np.r_[var[0:9], np.full(4, var[9] / 4.0), var[12:18]])
        return x0, p0

    def run_case(self, rotation: bool, spec: SensorSpec | None = None, filter_name: str | None = None, *,
                 q_diag: Any = None, duration: float | None = None, label: str = "", P0: Any = None) -> FusionRun:
        """Simulate, filter and score one case.

        Parameters
        ----------
        rotation : bool
            5-axis (True) or 3-axis.
        spec : SensorSpec, optional
            Sensor figures (default :attr:`spec`).
        filter_name : str, optional
            One of :data:`FILTERS` (default: ``"ekf"`` for 5-axis, ``"kf"`` for 3-axis).
        q_diag : array_like, shape (nx,), optional
            A diagonal ``Q`` instead of the white-jerk model (the thesis' Appendix B).
        duration : float, optional
            Record length [s] (default :attr:`duration`).
        label : str, optional
            Case label.
        P0 : array_like, shape (nx, nx), optional
            The initial covariance (default: :attr:`initial_covariance`); the initial state is
            the truth plus a draw from it.

        Returns
        -------
        FusionRun

        Raises
        ------
        InputError
            The KF on a 5-axis case, a filter that is not available, a path with too few samples.
        """
        spec = self.spec if spec is None else spec
        filter_name = filter_name or ("ekf" if rotation else "kf")
        if filter_name == "kf" and rotation:
            raise InputError("filter_name: the Kalman filter needs the linear 3-axis model (rotation=False)")
        path = self.path(rotation, spec, duration)
        dt = spec.dt
        truth = path.truth(dt)
        rng = np.random.default_rng(self.seed)
        meas = measure(truth, spec, int(rng.integers(2**31)), IMU_TRANSLATION_M, IMU_ROTATION)
        t_belief, r_belief = believed_transform(spec, axis=self.transform_error_axis)
        model = EndEffectorModel(dt, rotation=rotation, imu_translation=t_belief, imu_rotation=r_belief, orientation=path.orientation)
        sj, sa = self.process_noise(path, dt)
        Q = np.diag(as_array(q_diag, (model.nx,), "q_diag")) if q_diag is not None else model.process_noise(sj, sa, self.quaternion_std)
        R = model.measurement_noise(spec.position_std, spec.accel_std, spec.orientation_std, spec.gyro_std)
        x0, P0 = self._initial(truth, rng, model, P0)
        filt = self._filter(filter_name, model, Q, R, x0, P0, path.orientation)
        t0 = time.perf_counter()
        run = filt.run(meas.z[1:])  # (x0, P0) is the posterior of sample 0: the filters predict to sample 1 first
        _log.debug("%s: %s %d samples in %.2f s", label, filter_name, truth.t.size, time.perf_counter() - t0)
        sensor = sensor_only(meas, model)
        first = max(sensor.first, int(math.ceil(self.warmup / dt - 1e-9)))
        out = FusionRun(status=run.status, message=run.message, label=label, filter_name=filter_name, spec=spec, truth=truth,
                        measurements=meas, sensor=sensor, run=run, first=first, step_time_us=1e6 * run.step_time_s,
                        setup={"x0": np.asarray(x0, float), "P0": np.asarray(P0, float), "Q": np.asarray(Q, float), "R": np.asarray(R, float)})
        if model.is_linear:
            zero = np.zeros(model.nx)
            out.setup["F"] = np.asarray(model.transition_jacobian(zero), float)
            out.setup["H"] = np.asarray(model.measurement_jacobian(zero), float)
        if out.end <= first + 1:
            return out
        for q, (_, _, needs_rotation) in QUANTITIES.items():
            if needs_rotation and not rotation:
                continue
            _, s, f = out.series(q)
            out.errors[q] = {"sensor": float(np.mean(s)), "fusion": float(np.mean(f))}
        return out

    def _filter(self, name: str, model: EndEffectorModel, Q: np.ndarray, R: np.ndarray, x0: np.ndarray, P0: np.ndarray, orientation: Any) -> Any:
        if name in ("kf", "ekf"):
            # The KF/EKF step is a CasADi graph with Q and R built in (about 1 s to build for 19-D):
            # one filter per (model, Q, R, x0, P0) is kept and reused (e.g. by the bias sweeps, which
            # change only the measurements).
            key = (name, model.dt, model.rotation, model.imu_translation.tobytes(), model.imu_rotation.tobytes(),
                   np.asarray(orientation).tobytes(), Q.tobytes(), R.tobytes(), x0.tobytes(), P0.tobytes())
            if key not in self._cache:
                self._cache[key] = (KalmanFilter if name == "kf" else ExtendedKalmanFilter)(model, Q, R, x0, P0)
            return self._cache[key]
        if name == "pf":
            return ParticleFilter(model, Q, R, x0, P0, n_particles=self.particles, seed=self.seed)
        if name == "ukf":
            return UnscentedKalmanFilter(model, Q, R, x0, P0)
        raise InputError(f"filter_name: expected one of {', '.join(FILTERS)}, got {name!r}")

    # -- the tables ----------------------------------------------------------------------------
    def run(self, table_10: bool = True, comparison: bool = True) -> FusionStudyResult:
        """Run the whole study: Tables 8, 9, the velocity and angular-acceleration figures, Table 10, the comparison.

        Parameters
        ----------
        table_10 : bool, optional
            Run the sweeps of :attr:`sweep`.
        comparison : bool, optional
            Run the filter comparison.

        Returns
        -------
        FusionStudyResult
            Status: the worst of the runs' (a diverged filter is ``"error"``, its row says so).
        """
        res = FusionStudyResult(status=Status.COMPLETED)
        for motion, rotation in MOTIONS.items():
            base = res.runs[motion] = self.run_case(rotation, label=motion)
            noisy_spec = self.spec.replace(position_noise_mm=self.spec.position_noise_mm * self.noisy_tracker_factor,
                                           orientation_noise_deg=self.spec.orientation_noise_deg * self.noisy_tracker_factor)
            noisy = res.runs[f"{motion} noisy"] = self.run_case(rotation, noisy_spec, label=f"{motion} noisy")
            sj, sa = self.process_noise(self.path(rotation, self.spec), self.spec.dt)
            res.process_noise[motion] = {"jerk_std_m_s3": sj, "angular_jerk_std_rad_s3": sa if rotation else None,
                                         "quaternion_std": self.quaternion_std if rotation else None,
                                         "appendix_b_Q_diag": list(APPENDIX_B["Q_diag"]), "appendix_b_R_diag": list(APPENDIX_B["R_diag"])}
            appendix = None
            if not rotation and self.appendix_b_q is not None:
                appendix = res.runs["3-axis appendix_b"] = self.run_case(False, q_diag=self.appendix_b_q, label="3-axis appendix_b")
            res.table_8[motion] = self._table_8(base, appendix, motion)
            res.table_9[motion] = self._table_9(base, noisy)
            v = base.errors.get("velocity_mm_s", {})
            res.velocity_mean_error_mm_s[motion] = {"tracker": v.get("sensor"), "fusion": v.get("fusion"),
                                                    "improvement_percent": _improvement(v.get("sensor", 0.0), v.get("fusion", 0.0)) if v else None}
            if base.end > base.first + 2:
                res.nees[motion] = {"filter": base.filter_name, **nees_test(base.nees(), base.run.dof)}
            if rotation:
                res.angular_acceleration = self._angular_acceleration(base)
        if table_10:
            res.table_10 = self._table_10()
            if self.limit_tunings:
                res.table_10_limits = limits(self, self.sweep_motions, self.limit_tunings, self.limit_parameters, self.limit_bisections,
                                             self.limit_centred)
        if comparison:
            res.filter_comparison = self._comparison({m: res.runs[m].run.P[-1] for m in MOTIONS if res.runs[m].run.P.shape[0]})
        statuses = [r.status for r in res.runs.values()] + [row["status"] for row in res.table_10 + res.filter_comparison]
        statuses += [e["status"] for row in res.table_10_limits for e in row["evaluations"] if e["status"] != "error"]
        res.status = Status.worst(statuses)
        res.message = f"{len(res.runs)} baseline runs, {len(res.table_10)} sweep runs, {len(res.filter_comparison)} comparison runs"
        if res.table_10_limits:
            res.message += f", {len(res.table_10_limits)} Table 10 limits"
        return res

    @staticmethod
    def _table_8(base: FusionRun, appendix: FusionRun | None, motion: str) -> dict[str, Any]:
        col = 0 if motion == "3-axis" else 1
        out = {}
        for q, e in base.errors.items():
            row = {"sensor": e["sensor"], "fusion": e["fusion"], "change_percent": -_improvement(e["sensor"], e["fusion"]) if e["sensor"] > 0 else None}
            thesis = THESIS_TABLE_8.get(q)
            row["thesis_sensor"] = thesis["sensor"][col] if thesis else None
            row["thesis_fusion"] = thesis["fusion"][col] if thesis else None
            if appendix is not None and q in appendix.errors:
                row["fusion_appendix_b"] = appendix.errors[q]["fusion"]
            out[q] = row
        return out

    def _table_9(self, base: FusionRun, noisy: FusionRun) -> dict[str, Any]:
        out: dict[str, Any] = {"factor": self.noisy_tracker_factor}
        for q in ("position_mm", "orientation_deg"):
            if q not in base.errors or q not in noisy.errors:
                continue
            b, n = base.errors[q]["sensor"], noisy.errors[q]
            out[q] = {"baseline_sensor": b, "baseline_fusion": base.errors[q]["fusion"], "sensor": n["sensor"], "fusion": n["fusion"],
                      "fusion_below_sensor": n["fusion"] < n["sensor"], "fusion_above_baseline_sensor": n["fusion"] > b}
        return out

    @staticmethod
    def _angular_acceleration(base: FusionRun) -> dict[str, Any]:
        t, s, f = base.series("angular_acceleration_deg_s2")
        alpha = np.linalg.norm(base.truth.angular_acceleration[base.first : base.first + t.size], axis=1)
        peak = alpha >= PEAK_FRACTION * alpha.max() if alpha.max() > 0 else np.zeros(t.size, bool)
        out: dict[str, Any] = {"peak_fraction": PEAK_FRACTION}
        for name, mask in (("all", np.ones(t.size, bool)), ("peaks", peak), ("off_peaks", ~peak)):
            if not mask.any():
                out[name] = None
                continue
            gs, fs = float(np.mean(s[mask])), float(np.mean(f[mask]))
            out[name] = {"gyro_regression": gs, "fusion": fs, "improvement_percent": _improvement(gs, fs), "samples": int(mask.sum())}
        return out

    def _table_10(self) -> list[dict[str, Any]]:
        rows = []
        for motion in self.sweep_motions:
            rotation = MOTIONS[motion]
            for name, values in self.sweep.items():
                if not rotation and name in ROTATION_ONLY_PARAMETERS:
                    continue  # Table 10: N/A
                for value in values:
                    spec = self.spec.replace(**{name: value})
                    try:
                        case = self.run_case(rotation, spec, duration=self.sweep_duration, label=f"{motion} {name}={value:g}")
                    except InputError as exc:  # e.g. a sample time leaving too few samples
                        rows.append({"parameter": name, "value": value, "motion": motion, "filter": "ekf" if rotation else "kf",
                                     "status": str(Status.ERROR), "message": str(exc)})
                        continue
                    rows.append(self._row(name, value, case))
        return rows

    @staticmethod
    def _row(name: str, value: float, case: FusionRun) -> dict[str, Any]:
        row: dict[str, Any] = {"parameter": name, "value": value, "motion": "5-axis" if case.truth.rotation else "3-axis",
                               "filter": case.filter_name, "status": str(case.status), "message": case.message}
        stops = []
        for q, e in case.errors.items():
            imp = _improvement(e["sensor"], e["fusion"])
            row[q] = {"sensor": e["sensor"], "fusion": e["fusion"], "improvement_percent": imp}
            if imp is None or imp <= 0:
                stops.append(q)
        row["stops_paying"] = stops
        return row

    def _comparison(self, priors: dict[str, np.ndarray]) -> list[dict[str, Any]]:
        """Every filter from the same prior: the baseline run's last posterior covariance (a steady state).

        The default initial covariance is wider than one sample's measurement noise; the particle
        filter's linearised proposal then finds no particle that explains the first measurement
        (measured: "measurement lost" at step 0), so the comparison starts all filters settled.
        """
        rows = []
        for motion, rotation in MOTIONS.items():
            for name in self.comparison_filters:
                if name == "kf" and rotation:
                    continue
                case = self.run_case(rotation, filter_name=name, duration=self.comparison_duration, label=f"{motion} {name}", P0=priors.get(motion))
                row = {"motion": motion, "filter": name, "status": str(case.status), "message": case.message,
                       "samples": int(case.end), "step_time_us": case.step_time_us}
                row.update({q: e["fusion"] for q, e in case.errors.items()})
                row["velocity_tracker_mm_s"] = case.errors.get("velocity_mm_s", {}).get("sensor")
                rows.append(row)
        return sorted(rows, key=lambda r: (r["motion"], FILTERS.index(r["filter"])))
