"""The project's plant models behind the robot protocols, stepped once per 4 ms cycle.

:class:`KR500CorrectionPlant` (for RSI): the KR 500-3 executing the programmed sine path of
Cvitanic (2021), sec. 5.4.1, eq. (33), ``50.8 sin(2 pi 0.0098 s)`` mm across the feed ``s``
at 42.33 mm/s (here the feed along the world y axis and the offset along x, the thesis'
"y directional" wave; the feed ramped in over :data:`FEED_RAMP_S`), with a TCP path error
the programmed path does not know about, and the sensor's corrections applied as the
controller does:

- the robot's path following lags the programmed path (a first-order lag of time constant
  ``lag_s``, 10 ms by default: an ASSUMPTION standing for the servo and interpolator lag;
  it gives ``A w lag`` = 1.3 mm across the sine and ``feed lag`` = 0.42 mm along the feed;
  the thesis measured an average positioning error of 0.5 mm on this robot, sec. 4.2.3);
- the payload sags the TCP by a static deflection (``deflection_mm``, (0, 0, -0.5) mm by
  default: an ASSUMPTION, about 100 kg on the z stiffness of Table 16);
- corrections (RSI's ``RKorr``, summed when relative) reach the commanded position
  ``delay_cycles`` = 12 cycles after the cycle they answer; with the one cycle the reply
  itself takes, the loop through the protocol sees the 13 cycles (52 ms) of the measured
  controller delay, Cvitanic (2021), sec. 5.3.2, in the loop of sec. 5.3.5 (the project's
  :mod:`~gtmodel.estimation.closed_loop.correction_loop`, "sec. 5, eq. (33)");
- the TCP responds to the commanded position through the two-mode "truth"
  :func:`~gtmodel.estimation.closed_loop.correction.truth_model` at the first Table 13 pose
  (:class:`~gtmodel.estimation.closed_loop.correction.OffsetResponseModel`, eqs. (8),
  (30)-(32)): the commanded position is followed exactly at constant rate, with the
  deflection under the equivalent force of its second difference;
- a laser tracker measures the TRUE TCP with the Table 7 noise (0.0064 mm per axis and
  sample, :class:`~gtmodel.estimation.fusion.tracker_imu.SensorSpec`) at 1000 Hz, sec. 4.2.2
  (the TCP is held between the 4 ms cycles of the plant); optionally the IMU (``imu=True``).

The robot reports ``RIst`` = the commanded position (its encoders do not see the
deflection), ``RSol`` = the programmed path before the correction (so a sensor side forms
the path error as ``RSol - tracker``), and the Table 13 pose's joints as ``AIPos``/``ASPos``
(held: the +-50 mm path hardly moves them; the joints are not solved along the path).

:class:`L1ServoPlant` (for EGM): the L1 Gantry-Tau's three linear actuators with the
closed-loop servo models of Dressler (2012), eq. 6.11 (5 cycles of delay, first order;
:func:`~gtmodel.robots.actuator_dynamics.actuator_models`, as in
:class:`~gtmodel.estimation.closed_loop.plant.TrackingPlant`), at rest at the ILC operating
point (``problems/l1_ilc.toml``'s first corner), following the planned joints the sensor
sends (position guidance, held when no reply arrives), reporting the joints [mm] with
encoder noise (1 um, an ASSUMPTION: the thesis' encoders are exact) and the TCP
``fk(q)`` [mm]; the tool gauge (1 um, :class:`~gtmodel.estimation.closed_loop.plant.SensorModel`)
measures ``fk(q)`` on the sensor stream.
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod

import numpy as np

from gtmodel.defaults import LOOP_PERIOD_S
from gtmodel._lazy import lazy_module
from gtmodel.errors import InputError
from gtmodel.estimation.closed_loop.correction import DELAY_CYCLES, VALIDATION_POSES_DEG, WRIST_JOINTS_DEG, joint_angles, truth_model
from gtmodel.estimation.closed_loop.correction_loop import FEED_RATE_M_S, SINE_AMPLITUDE_M, SINE_SPATIAL_FREQUENCY_PER_M
from gtmodel.estimation.closed_loop.plant import SensorModel
from gtmodel.estimation.fusion.tracker_imu import SensorSpec
from gtmodel.robot_sim.state import Command, RobotState
from gtmodel.robots.actuator_dynamics import actuator_models, load_dynamics_models, loop_period
from gtmodel.robots.dynamic_stiffness import DIRECTIONS
from gtmodel.robots.kinematics import GantryTau3Kinematics
from gtmodel.robots.serial import load_serial_arm

#: python-control, imported on first use.
control = lazy_module("control")

__all__ = ["PLANTS", "FEED_RAMP_S", "SimPlant", "KR500CorrectionPlant", "L1ServoPlant", "make_plant"]

#: The plant names of ``gtmodel robot-sim --plant``.
PLANTS = ("kr500", "l1")
#: Time over which the feed ramps up from rest (smoothstep of the speed) [s].
FEED_RAMP_S = 0.5
#: The L1's operating point [m] (``problems/l1_ilc.toml``, the first corner of the ILC square).
L1_OPERATING_POINT_M = (0.0, 2.9, -0.5)


class _Discrete:
    """A discrete state-space system stepped one sample at a time (numpy)."""

    def __init__(self, sys) -> None:
        s = control.ss(sys)
        self.A, self.B, self.C, self.D = (np.asarray(m, dtype=float) for m in (s.A, s.B, s.C, s.D))
        self.x = np.zeros(self.A.shape[0])

    def step(self, u: float) -> float:
        y = float((self.C @ self.x)[0] + self.D[0, 0] * u)
        self.x = self.A @ self.x + self.B[:, 0] * u
        return y


class SimPlant(ABC):
    """A plant behind a robot protocol: one state per cycle, a command per reply.

    Subclasses set ``name``, ``error_name``, ``record_columns`` and ``dt``.
    """

    name = ""
    error_name = ""
    record_columns: tuple[str, ...] = ()
    dt = LOOP_PERIOD_S

    @abstractmethod
    def state(self) -> RobotState:
        """The robot's view of the current cycle (what it sends).

        Returns
        -------
        RobotState
        """

    @abstractmethod
    def step(self, command: Command | None) -> None:
        """Apply the reply of the current cycle (None: no reply in time, hold) and advance one cycle.

        Parameters
        ----------
        command : Command or None
            The parsed reply.
        """

    @abstractmethod
    def true_position(self) -> np.ndarray:
        """The true TCP (or tool) position the sensor stream measures [m], shape (3,).

        Returns
        -------
        numpy.ndarray
        """

    @property
    @abstractmethod
    def sensor_noise_m(self) -> float:
        """Standard deviation of the sensor stream's noise per axis and sample [m]."""

    def sensor_values(self, rng: np.random.Generator) -> np.ndarray:
        """One sample of the sensor stream: the true position plus noise [m] (x, y, z first).

        Parameters
        ----------
        rng : numpy.random.Generator
            The noise.

        Returns
        -------
        numpy.ndarray, shape (3,) or more
            The values of a ``GTS1`` line.
        """
        return self.true_position() + rng.normal(0.0, self.sensor_noise_m, 3)

    @abstractmethod
    def error_mm(self) -> float:
        """The tracking error of the current cycle [mm] (the summary's RMS and max are over these).

        Returns
        -------
        float
        """

    @abstractmethod
    def record(self) -> list[float]:
        """The current cycle's values of ``record_columns``.

        Returns
        -------
        list of float
        """

    @abstractmethod
    def parameters(self) -> dict:
        """The plant's parameters for the summary (JSON-safe).

        Returns
        -------
        dict
        """


def _update(u: np.ndarray, offset: np.ndarray, mode: str) -> np.ndarray:
    n = min(u.size, offset.size)
    out = u.copy()
    out[:n] = out[:n] + offset[:n] if mode == "relative" else offset[:n]
    return out


class KR500CorrectionPlant(SimPlant):
    """The KR 500 on the sine path with pose-offset corrections (module docstring).

    Cvitanic (2021), sec. 5.4.1, eq. (33) (the path), sec. 5.3.2 (the 52 ms delay), eqs. (8),
    (30)-(32) (the response), Tables 16-17 (the modes), Table 7 (the tracker and IMU noise).

    Parameters
    ----------
    rng : numpy.random.Generator
        Noise of the tracker.
    pose_deg : array_like, shape (2,), optional
        Joints 2, 3 of the pose [deg] (default the first Table 13 pose).
    start_mm : array_like, shape (3,), optional
        Start of the path in the base frame [mm] (default (1800, 0, 1200), an assumption).
    amplitude_mm : float, optional
        Sine amplitude [mm] (50.8).
    spatial_frequency_per_mm : float, optional
        Cycles per mm fed (0.0098).
    feed_mm_s : float, optional
        Feed rate [mm/s] (42.33).
    lag_s : float, optional
        Time constant of the path-following lag [s] (0.010), >= 0.
    deflection_mm : array_like, shape (3,), optional
        Static deflection of the TCP [mm] ((0, 0, -0.5)).
    delay_cycles : int, optional
        Cycles from a reply to its effect on the commanded position (12; see the module docstring), >= 1.
    tracker_noise_mm : float, optional
        Tracker noise per axis and sample [mm] (Table 7: 0.0064), >= 0.
    dt : float, optional
        Cycle time [s] (0.004).
    imu : bool, optional
        Append the IMU to the sensor stream (default False): accelerometer ``ax, ay, az``
        [m/s^2] (the TCP's acceleration, the second difference of the true TCP over the last
        cycles, gravity-free) and gyro ``wx, wy, wz`` [rad/s] (the orientation is held: 0),
        each with the Table 7 bias and noise (``sigma = density sqrt(1 / 0.001 s)``); the IMU
        sits at the tracker target with the base frame's axes (an ASSUMPTION).

    Raises
    ------
    InputError
        A bad value (the argument is named).
    """

    name = "kr500"
    error_name = "tcp_path_error"
    record_columns = tuple(f"{p}_{a}_mm" for p in ("programmed", "correction", "true") for a in "xyz")

    def __init__(self, rng: np.random.Generator, pose_deg=None, start_mm=(1800.0, 0.0, 1200.0), amplitude_mm: float = SINE_AMPLITUDE_M * 1e3,
                 spatial_frequency_per_mm: float = SINE_SPATIAL_FREQUENCY_PER_M / 1e3, feed_mm_s: float = FEED_RATE_M_S * 1e3,
                 lag_s: float = 0.010, deflection_mm=(0.0, 0.0, -0.5), delay_cycles: int = DELAY_CYCLES - 1,
                 tracker_noise_mm: float = SensorSpec().position_noise_mm, dt: float = LOOP_PERIOD_S, imu: bool = False) -> None:
        pose = np.asarray(VALIDATION_POSES_DEG[0] if pose_deg is None else pose_deg, dtype=float)
        for name, v in (("amplitude_mm", amplitude_mm), ("spatial_frequency_per_mm", spatial_frequency_per_mm), ("feed_mm_s", feed_mm_s), ("dt", dt)):
            if not (isinstance(v, (int, float)) and math.isfinite(v) and v > 0):
                raise InputError(f"{name}: expected a positive number, got {v!r}")
        for name, v in (("lag_s", lag_s), ("tracker_noise_mm", tracker_noise_mm)):
            if not (isinstance(v, (int, float)) and math.isfinite(v) and v >= 0):
                raise InputError(f"{name}: expected a non-negative number, got {v!r}")
        if not isinstance(delay_cycles, int) or delay_cycles < 1:
            raise InputError(f"delay_cycles: expected an integer >= 1, got {delay_cycles!r}")
        self.start = np.asarray(start_mm, dtype=float).reshape(3) / 1e3
        self.deflection = np.asarray(deflection_mm, dtype=float).reshape(3) / 1e3
        if not (np.all(np.isfinite(self.start)) and np.all(np.isfinite(self.deflection)) and pose.shape == (2,) and np.all(np.isfinite(pose))):
            raise InputError("start_mm, deflection_mm: expected 3 finite numbers; pose_deg: 2 finite numbers")
        self.rng = rng
        self.pose_deg = pose
        self.amplitude = amplitude_mm / 1e3
        self.spatial_frequency = spatial_frequency_per_mm * 1e3
        self.feed = feed_mm_s / 1e3
        self.lag_s = float(lag_s)
        self.delay_cycles = delay_cycles
        self.tracker_noise = tracker_noise_mm / 1e3
        self.dt = float(dt)
        models = truth_model(load_serial_arm(), pose)[0]
        self._response = [_Discrete(models[d].response_ss()) for d in DIRECTIONS]
        self.joints_deg = np.degrees(joint_angles(pose, WRIST_JOINTS_DEG)[0])
        self.orientation = np.zeros(3)
        self.k = 0
        self.s = 0.0  # distance fed [m]
        self.u = np.zeros(6)  # commanded correction [m, deg]
        self._line = [np.zeros(6) for _ in range(delay_cycles)]
        self.applied = np.zeros(6)
        self.programmed = self._path(0.0)
        self.lagged = self.programmed.copy()
        self._rest = self.programmed.copy()
        self.commanded = self.programmed.copy()
        self.true = self._respond()
        self._history = [self.true.copy(), self.true.copy()]
        self.imu = bool(imu)
        self._spec = SensorSpec()

    def _path(self, s: float) -> np.ndarray:
        return self.start + np.array([self.amplitude * math.sin(2 * math.pi * self.spatial_frequency * s), s, 0.0])

    def _respond(self) -> np.ndarray:
        dev = self.commanded - self._rest
        return self._rest + np.array([r.step(float(v)) for r, v in zip(self._response, dev)]) + self.deflection

    def state(self) -> RobotState:
        """The commanded pose as ``RIst``, the programmed path as ``RSol``, the pose's joints.

        Returns
        -------
        RobotState
        """
        ori = self.orientation + self.applied[3:]
        return RobotState(np.concatenate([self.commanded * 1e3, ori]), np.concatenate([self.programmed * 1e3, self.orientation]),
                          self.joints_deg.copy(), self.joints_deg.copy())

    def step(self, command: Command | None) -> None:
        """Sum (relative) or take (absolute) the Cartesian offset, delay it, advance the path and the TCP.

        Axis corrections (``AKorr``) are not applied by this plant (Cartesian correction only).

        Parameters
        ----------
        command : Command or None
            The reply of the current cycle; None holds the correction.
        """
        if command is not None and command.cart is not None:
            off = np.asarray(command.cart, dtype=float).copy()
            if command.positions:
                off[:3] = off[:3] - self.programmed * 1e3
            off = np.concatenate([off[:3] / 1e3, off[3:6] if off.size >= 6 else np.zeros(3)])
            self.u = _update(self.u, off, "absolute" if command.positions else command.mode)
        self._line.append(self.u.copy())
        self.applied = self._line.pop(0)
        self.k += 1
        t = self.k * self.dt
        ramp = min(t / FEED_RAMP_S, 1.0)
        self.s += self.dt * self.feed * ramp * ramp * (3 - 2 * ramp)
        self.programmed = self._path(self.s)
        a = math.exp(-self.dt / self.lag_s) if self.lag_s > 0 else 0.0
        self.lagged = a * self.lagged + (1 - a) * self.programmed
        self.commanded = self.lagged + self.applied[:3]
        self._history = [self._history[1], self.true]
        self.true = self._respond()

    def true_position(self) -> np.ndarray:
        """The true TCP [m], shape (3,).

        Returns
        -------
        numpy.ndarray
        """
        return self.true.copy()

    @property
    def sensor_noise_m(self) -> float:
        """The tracker's noise per axis [m]."""
        return self.tracker_noise

    def sensor_values(self, rng: np.random.Generator) -> np.ndarray:
        """The tracker's position [m], then (``imu=True``) the accelerometer [m/s^2] and the gyro [rad/s].

        Parameters
        ----------
        rng : numpy.random.Generator
            The noise.

        Returns
        -------
        numpy.ndarray, shape (3,) or (9,)
        """
        pos = self.true + rng.normal(0.0, self.tracker_noise, 3)
        if not self.imu:
            return pos
        sp = self._spec
        acc = (self.true - 2 * self._history[1] + self._history[0]) / self.dt**2
        acc = acc + sp.accel_bias + rng.normal(0.0, sp.accel_std, 3)
        gyro = sp.gyro_bias + rng.normal(0.0, sp.gyro_std, 3)
        return np.concatenate([pos, acc, gyro])

    def error_mm(self) -> float:
        """``|programmed - true TCP|`` [mm] (the TCP path error at the cycle).

        Returns
        -------
        float
        """
        return float(np.linalg.norm(self.programmed - self.true) * 1e3)

    def record(self) -> list[float]:
        """Programmed path, applied correction, true TCP [mm].

        Returns
        -------
        list of float
        """
        return [*(self.programmed * 1e3), *(self.applied[:3] * 1e3), *(self.true * 1e3)]

    def parameters(self) -> dict:
        """The plant's parameters and sources.

        Returns
        -------
        dict
        """
        return {"pose_j2_j3_deg": self.pose_deg.tolist(), "start_mm": (self.start * 1e3).tolist(), "amplitude_mm": self.amplitude * 1e3,
                "spatial_frequency_per_mm": self.spatial_frequency / 1e3, "feed_mm_s": self.feed * 1e3, "sine_axis": "x", "feed_axis": "y",
                "lag_s": self.lag_s, "deflection_mm": (self.deflection * 1e3).tolist(), "delay_cycles": self.delay_cycles,
                "tracker_noise_mm": self.tracker_noise * 1e3, "imu": self.imu,
                "source": "Cvitanic (2021), sec. 5.4.1 eq. (33) (path), sec. 5.3.2 (52 ms delay), eqs. (8), (30)-(32), Tables 7, 13, 16, 17; "
                          "lag and deflection assumed"}


class L1ServoPlant(SimPlant):
    """The L1's three actuators following planned joints (module docstring).

    Dressler (2012), eq. 6.11 (the closed-loop actuator models), eq. 4.9 (fk).

    Parameters
    ----------
    rng : numpy.random.Generator
        Noise of the encoders and the gauge.
    encoder_noise_mm : float, optional
        Encoder noise per axis [mm] (0.001), >= 0.
    gauge_noise_mm : float, optional
        Tool gauge noise per axis [mm] (:class:`SensorModel`'s 1 um), >= 0.

    Raises
    ------
    InputError
        A negative noise.
    """

    name = "l1"
    error_name = "joint_tracking_error"
    record_columns = tuple(f"{p}_q{i}_mm" for p in ("reference", "true", "feedback") for i in (1, 2, 3))

    def __init__(self, rng: np.random.Generator, encoder_noise_mm: float = 0.001, gauge_noise_mm: float = SensorModel().gauge_noise * 1e3) -> None:
        for name, v in (("encoder_noise_mm", encoder_noise_mm), ("gauge_noise_mm", gauge_noise_mm)):
            if not (isinstance(v, (int, float)) and math.isfinite(v) and v >= 0):
                raise InputError(f"{name}: expected a non-negative number, got {v!r}")
        self.rng = rng
        models = load_dynamics_models("L1_dynamics_models")
        self.dt = float(loop_period(models))
        self._servo = [_Discrete(g) for g in actuator_models(models)]
        self.kin = GantryTau3Kinematics("L1")
        self.q0 = np.asarray(self.kin.ik(np.array(L1_OPERATING_POINT_M), 0), dtype=float).reshape(3)
        self.T0 = np.asarray(self.kin.fk(self.q0, 1), dtype=float).reshape(3)
        self.encoder_noise = encoder_noise_mm / 1e3
        self.gauge_noise = gauge_noise_mm / 1e3
        self.reference = self.q0.copy()
        self.q = self.q0.copy()
        self.measured = self.q0.copy()
        self.k = 0

    def _fk_mm(self, q: np.ndarray) -> np.ndarray:
        return np.asarray(self.kin.fk(q, 1), dtype=float).reshape(3) * 1e3

    def state(self) -> RobotState:
        """Joints [mm] with encoder noise, ``fk`` of them [mm]; the reference as the setpoint.

        Returns
        -------
        RobotState
        """
        self.measured = self.q + self.rng.normal(0.0, self.encoder_noise, 3) if self.encoder_noise > 0 else self.q.copy()
        return RobotState(np.concatenate([self._fk_mm(self.measured), np.zeros(3)]), np.concatenate([self._fk_mm(self.reference), np.zeros(3)]),
                          self.measured * 1e3, self.reference * 1e3)

    def step(self, command: Command | None) -> None:
        """Take the planned joints (or a Cartesian position through ik) as the reference, step the servos.

        Parameters
        ----------
        command : Command or None
            The reply of the current cycle; None holds the reference.

        Raises
        ------
        UnreachablePoseError
            A planned Cartesian position the L1 cannot reach.
        """
        if command is not None:
            if command.joints is not None:
                q = np.asarray(command.joints[:3], dtype=float) / 1e3
                self.reference = q if command.positions else _update(self.reference - self.q0, q, command.mode) + self.q0
            elif command.cart is not None:
                T = np.asarray(command.cart[:3], dtype=float) / 1e3
                T = T if command.positions else self.T0 + T
                self.reference = np.asarray(self.kin.ik(T, 0), dtype=float).reshape(3)
        self.q = self.q0 + np.array([s.step(float(v)) for s, v in zip(self._servo, self.reference - self.q0)])
        self.k += 1

    def true_position(self) -> np.ndarray:
        """The true ``fk(q)`` [m], shape (3,).

        Returns
        -------
        numpy.ndarray
        """
        return self._fk_mm(self.q) / 1e3

    @property
    def sensor_noise_m(self) -> float:
        """The gauge's noise per axis [m]."""
        return self.gauge_noise

    def error_mm(self) -> float:
        """``|reference - q|`` [mm] (the servo's tracking error at the cycle).

        Returns
        -------
        float
        """
        return float(np.linalg.norm(self.reference - self.q) * 1e3)

    def record(self) -> list[float]:
        """Reference, true and fed-back (encoder, what the robot sends) joints [mm].

        Returns
        -------
        list of float
        """
        return [*(self.reference * 1e3), *(self.q * 1e3), *(self.measured * 1e3)]

    def parameters(self) -> dict:
        """The plant's parameters and sources.

        Returns
        -------
        dict
        """
        return {"q0_mm": (self.q0 * 1e3).tolist(), "operating_point_m": list(L1_OPERATING_POINT_M), "encoder_noise_mm": self.encoder_noise * 1e3,
                "gauge_noise_mm": self.gauge_noise * 1e3, "servo": "Dressler (2012), eq. 6.11 (L1_dynamics_models)"}


def make_plant(name: str, rng: np.random.Generator, **options) -> SimPlant:
    """A plant by name.

    Parameters
    ----------
    name : {"kr500", "l1"}
        The plant.
    rng : numpy.random.Generator
        Its noise.
    **options
        Keyword arguments of the plant's class.

    Returns
    -------
    SimPlant

    Raises
    ------
    InputError
        An unknown name or option.
    """
    classes = {"kr500": KR500CorrectionPlant, "l1": L1ServoPlant}
    if name not in classes:
        raise InputError(f"plant: expected one of {', '.join(PLANTS)}, got {name!r}")
    try:
        return classes[name](rng, **options)
    except TypeError as exc:
        raise InputError(f"plant {name}: {exc}") from None
