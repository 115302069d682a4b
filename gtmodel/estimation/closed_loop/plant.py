"""Closed-loop tracking plant of the L1 Gantry-Tau at 4 ms: actuators, kinematics, structure, sensors.

Dressler (2012), eqs. 6.11, 6.14/6.15 and ch. 7.3. The chain, every block a discrete
python-control system at the loop period ``dt`` (4 ms, from the robot's data file; no hand-written integrator)::

    q_ref --(6.11, per axis)--> q = q_m --fk--> T_kin --(2nd difference)--> a_kin
    a_kin(x, y) --(structure (6.14), c2d "foh")--> d, d''
    z = T_kin + d,   a = a_kin + d'',   a_m = clip(a + noise),   z_m = z + noise

Actuators
    The closed-loop actuator models (6.11), ``q_k = a_i q_(k-1) + b_i q_ref,(k-5)``, from
    :func:`gtmodel.robots.actuator_dynamics.actuator_models`; the encoders are exact
    (``q_m = q``). Their DC gains ``b_i / (1 - a_i)`` are the thesis' identified ones,
    0.999150, 0.995640 and 1.010294 for the three L1 axes, not exactly 1: a move of
    ``Delta q`` ends with a static error ``(1 - b_i/(1 - a_i)) Delta q`` (up to 1 % of the move
    on axis 3). They are kept as identified; an ILC removes such a repetitive error.
Structure (the modes this model has, and why)
    The tool deflection ``d`` from the kinematic position (x and y; z: 0) is one
    decoupled mode per direction in the standard form of (6.14),
    ``M d'' + D d' + K d = B a_kin`` (:class:`gtmodel.robots.structural.PhysicalModel`,
    ``convention="standard"``) with ``K = diag(k_x, k_y)``, ``M = diag(k_j / w_j^2)``,
    ``D = diag(2 zeta_j sqrt(k_j M_j))``, ``B = -m_acc I``. So the model has exactly two
    modes at the ILC operating point: **7.4 Hz in x and 11.5 Hz in y**, 5 % damping each
    (:meth:`ToolStructure.modes`). Why these figures: the thesis measured the lowest
    resonances of the L1 with the wrist mounted (the ILC set-up) at 7.4 Hz for an
    excitation in x and 11.4-11.5 Hz in y (Table 6.4); the identified 4th-order model
    (6.14) (14 and 103 Hz) was measured without the wrist, with only cart 3 moving, so it
    is not the structure of the ILC experiment. The static TCP stiffness is 2-4 N/um
    (measured on the D1; the thesis: "stiffer in x"), hence ``k_x = 4 N/um``,
    ``k_y = 2 N/um``; the inertial load is the accumulated moving mass
    ``m_acc = m_p + sum m_a/2 = 22.38 kg`` of the friction experiment (6.9); ``zeta = 0.05``
    is a typical structural damping (the thesis gives none for these modes). The static
    deflection per unit acceleration is ``m_acc / k``: 5.6 um per m/s^2 in x, 11.2 um per
    m/s^2 in y (the tool lags: ``d = -m_acc a / k``). The modal masses ``k / w^2``
    (1850 kg in x, 383 kg in y) are not physical masses: the one-mode model places the
    measured resonance and the measured static stiffness, and ``B`` scales the load.
Kinematic acceleration
    ``a_kin`` is the central second difference of the sampled ``T_kin``,
    ``(T_(k+1) - 2 T_k + T_(k-1)) / dt^2`` (exact when ``T_kin`` is quadratic between samples;
    at rest before the first and after the last sample), and the structure is discretised
    with a first-order hold (``control.c2d(..., "foh")``: ``a_kin`` linear between samples),
    so the deflection has no half-sample lag. ``a_kin`` at sample ``k`` uses ``T_kin`` at
    ``k + 1``; the chain stays causal with respect to ``q_ref`` (5 samples of delay).
Sensors
    :class:`SensorModel`: accelerometer (0.07 m/s^2 noise, range 1.5 g, clipped; gravity
    removed, i.e. the motion acceleration is measured) and a position gauge (1 um);
    Gaussian noise from ``numpy.random.default_rng([seed, trial])``.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass, field
from typing import Any, Sequence

import numpy as np

from gtmodel._lazy import lazy_module
from gtmodel._arrays import as_rows, positive_float, positive_int
from gtmodel.defaults import LOOP_PERIOD_S, STANDARD_GRAVITY  # standard gravity [m/s^2]: the accelerometer range is 1.5 of it
from gtmodel.errors import InputError
from gtmodel.robots.actuator_dynamics import actuator_models, load_dynamics_models, loop_period
from gtmodel.robots.kinematics import GantryTau3Kinematics
from gtmodel.robots.structural import Modes, PhysicalModel
from gtmodel.status import Status, StatusResult

#: python-control, imported on first use (it imports matplotlib.pyplot: ~2 s of CPU).
control = lazy_module("control")

__all__ = ["DT", "STANDARD_GRAVITY", "MIN_FREQUENCY_HZ", "ToolStructure", "SensorModel", "TrackingResponse", "TrackingPlant"]

_log = logging.getLogger("gtmodel")

#: Sample time of the controller [s] where no robot's data file is at hand (the L1's own
#: comes from its file, :func:`gtmodel.robots.actuator_dynamics.loop_period`).
DT = LOOP_PERIOD_S
#: Largest accepted difference between an actuator model's sample time and ``dt`` [s].
_DT_TOLERANCE = 1e-12


def _pair(value: Any, name: str) -> tuple[float, float]:
    arr = np.asarray(value, dtype=float) if not isinstance(value, str) else np.array([np.nan])
    if arr.shape != (2,) or not np.all(np.isfinite(arr)) or np.any(arr <= 0):
        raise InputError(f"{name}: expected 2 positive finite numbers (x, y), got {value!r}")
    return (float(arr[0]), float(arr[1]))


#: Lowest accepted structural resonance [Hz] (a structure mode, not a drift; keeps the modal mass finite).
MIN_FREQUENCY_HZ = 0.01


@dataclass(frozen=True)
class ToolStructure:
    """One structural mode per direction (x, y) between kinematic and true tool position.

    Dressler (2012), eq. 6.14 in standard form, ``M d'' + D d' + K d = B a_kin``, with
    ``K = diag(stiffness)``, ``M = diag(stiffness / w^2)``, ``w = 2 pi frequencies_hz``,
    ``D = diag(2 damping sqrt(K M))``, ``B = -mass I``. The defaults are the ILC operating
    point of ch. 7.3 (see the module docstring for why).

    Parameters
    ----------
    frequencies_hz : tuple of float, shape (2,), optional
        Undamped resonance in x and y [Hz] (default 7.4, 11.5: Table 6.4, with wrist), at
        least :data:`MIN_FREQUENCY_HZ`.
    stiffness : tuple of float, shape (2,), optional
        Static TCP stiffness in x and y [N/m] (default 4e6, 2e6: 4 and 2 N/um).
    damping : tuple of float, shape (2,), optional
        Damping ratios (default 0.05, 0.05).
    mass : float, optional
        Inertial load ``m_acc`` [kg] (default 22.38: ``m_p + sum m_a/2``).

    Raises
    ------
    InputError
        A field is not 2 positive finite numbers (``mass``: not a positive number), a
        resonance below :data:`MIN_FREQUENCY_HZ` (its modal mass ``stiffness / w^2`` would
        overflow), or a damping ratio is 1 or more (no oscillating mode).
    """

    frequencies_hz: tuple[float, float] = (7.4, 11.5)
    stiffness: tuple[float, float] = (4.0e6, 2.0e6)
    damping: tuple[float, float] = (0.05, 0.05)
    mass: float = 22.38

    def __post_init__(self) -> None:
        for name in ("frequencies_hz", "stiffness", "damping"):
            object.__setattr__(self, name, _pair(getattr(self, name), name))
        if min(self.frequencies_hz) < MIN_FREQUENCY_HZ:
            raise InputError(f"frequencies_hz: expected resonances of at least {MIN_FREQUENCY_HZ} Hz, got {self.frequencies_hz!r}")
        if max(self.damping) >= 1.0:
            raise InputError(f"damping: expected damping ratios below 1 (oscillating modes), got {self.damping!r}")
        object.__setattr__(self, "mass", positive_float(self.mass, "mass"))

    def physical_model(self) -> PhysicalModel:
        """The structure as a :class:`~gtmodel.robots.structural.PhysicalModel` (standard convention).

        Dressler (2012), eq. 6.14: ``M d'' + D d' + K d = B a_kin``, 2 coordinates (x, y), 2
        inputs (the kinematic acceleration in x, y).

        Returns
        -------
        PhysicalModel
            ``M, D, K`` diagonal (2, 2), ``B = -mass I``.
        """
        k = np.array(self.stiffness)
        w = 2.0 * math.pi * np.array(self.frequencies_hz)
        m = k / w**2
        d = 2.0 * np.array(self.damping) * np.sqrt(k * m)
        return PhysicalModel(np.diag(m), np.diag(d), np.diag(k), -self.mass * np.eye(2), convention="standard", name="tool structure")

    def modes(self) -> Modes:
        """Resonance modes of the structure, Dressler (2012), eq. 6.15.

        Returns
        -------
        Modes
            ``frequencies_hz`` equal to :attr:`frequencies_hz` (sorted), damping ratios
            equal to :attr:`damping`.
        """
        return self.physical_model().modes()

    def static_deflection(self) -> np.ndarray:
        """Magnitude of the static deflection per unit acceleration, ``m_acc / k`` [m per m/s^2].

        Dressler (2012), eq. 6.14 at ``s = 0``: ``K d = -m_acc a`` (the tool lags the
        acceleration).

        Returns
        -------
        numpy.ndarray, shape (2,)
            x, y (defaults: 5.595e-6 and 1.119e-5).
        """
        return self.mass / np.array(self.stiffness)

    def continuous(self) -> control.StateSpace:
        """Continuous state space with states ``[d, d']``, inputs ``a_kin`` (x, y), outputs ``[d, d'']``.

        Dressler (2012), eq. 6.14: the ``A``, ``B`` of
        :meth:`PhysicalModel.to_state_space`; the acceleration outputs are its lower
        rows (``d'' = M^-1 (B a_kin - D d' - K d)``, a direct feedthrough).

        Returns
        -------
        control.StateSpace
            4 states, 2 inputs, 4 outputs ``(d_x, d_y, d''_x, d''_y)`` [m, m/s^2].
        """
        ss = self.physical_model().to_state_space()
        A, B = np.asarray(ss.A), np.asarray(ss.B)
        C = np.vstack([np.asarray(ss.C), A[2:, :]])
        D = np.vstack([np.asarray(ss.D), B[2:, :]])
        return control.ss(A, B, C, D)

    def discrete(self, dt: float = DT) -> control.StateSpace:
        """The structure sampled at ``dt``: ``control.c2d`` with a first-order hold.

        Dressler (2012), eq. 6.14; the hold makes ``a_kin`` linear between samples (exact
        for piecewise-linear inputs, no half-sample lag).

        Parameters
        ----------
        dt : float, optional
            Sample time [s] (default :data:`DT`, the loop period).

        Returns
        -------
        control.StateSpace
            Discrete, as :meth:`continuous`; poles ``exp(s dt)`` of the continuous ones.

        Raises
        ------
        InputError
            ``dt`` not a positive number.
        """
        return control.c2d(self.continuous(), positive_float(dt, "dt"), method="foh")

    def kinematic_model(self, dt: float = DT) -> list[tuple[np.ndarray, np.ndarray, np.ndarray]]:
        """The model (6.13) from the kinematic to the true tool position, per direction, exactly as simulated.

        Dressler (2012), eqs. 6.13 and 7.19: ``z = z_kin + d`` with the deflection ``d`` of
        :meth:`discrete` (one SISO mode per direction, first-order hold) driven by the central
        second difference of ``z_kin`` (as :class:`TrackingPlant` does). State
        ``x = [xi (2), z_kin(t + 1), z_kin(t), z_kin(t - 1)]``, input ``u(t) = z_kin(t + 2)``
        (a look-ahead of 2 samples makes the model strictly proper: ``z(t) = C x(t)``).

        Parameters
        ----------
        dt : float, optional
            Sample time [s].

        Returns
        -------
        list of tuple
            ``[(A (5, 5), B (5,), C (5,))]`` for x and y; the look-ahead is 2 samples.

        Raises
        ------
        InputError
            ``dt`` not a positive number.
        """
        dt = positive_float(dt, "dt")
        pm = self.physical_model()
        out = []
        for j in range(2):
            m, c, k, b = pm.M[j, j], pm.D[j, j], pm.K[j, j], pm.B[j, j]
            mode = control.c2d(control.ss([[0.0, 1.0], [-k / m, -c / m]], [[0.0], [b / m]], [[1.0, 0.0]], [[0.0]]), dt, method="foh")
            Af, Bf = np.asarray(mode.A), np.asarray(mode.B).reshape(-1)
            Cf, Df = np.asarray(mode.C).reshape(-1), float(np.asarray(mode.D).reshape(-1)[0])
            g = np.array([0.0, 0.0, 1.0, -2.0, 1.0]) / dt**2  # a_kin(t) from [xi, z_kin(t+1), z_kin(t), z_kin(t-1)]
            A = np.zeros((5, 5))
            A[:2, :2] = Af
            A[:2] += np.outer(Bf, g)
            A[3, 2] = A[4, 3] = 1.0  # the shift register
            B = np.array([0.0, 0.0, 1.0, 0.0, 0.0])
            C = np.concatenate([Cf, [0.0, 1.0, 0.0]]) + Df * g
            out.append((A, B, C))
        return out


@dataclass(frozen=True)
class SensorModel:
    """Tool accelerometer and position gauge of the ILC experiment, Dressler (2012), ch. 7.3.

    ``a_m = clip(a + n_a, -range, range)``, ``z_m = z + n_z``, ``n_a``, ``n_z`` Gaussian,
    per component. The accelerometer measures the motion acceleration (gravity removed).

    Parameters
    ----------
    accelerometer_noise : float, optional
        Standard deviation of the accelerometer noise [m/s^2] (default 0.07).
    accelerometer_range : float, optional
        Measuring range, ``|a_m| <= range`` [m/s^2] (default 1.5 g = 14.709975).
    gauge_noise : float, optional
        Standard deviation of the position gauge noise [m] (default 1e-6).
    seed : int, optional
        Seed of the noise; trial ``k`` uses ``numpy.random.default_rng([seed, k])``
        (default 0).

    Raises
    ------
    InputError
        A negative or non-finite noise, a non-positive range, a negative or non-integer
        seed.
    """

    accelerometer_noise: float = 0.07
    accelerometer_range: float = 1.5 * STANDARD_GRAVITY
    gauge_noise: float = 1e-6
    seed: int = 0

    def __post_init__(self) -> None:
        for name in ("accelerometer_noise", "gauge_noise"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)) or not math.isfinite(value) or value < 0:
                raise InputError(f"{name}: expected a non-negative finite standard deviation, got {value!r}")
            object.__setattr__(self, name, float(value))
        object.__setattr__(self, "accelerometer_range", positive_float(self.accelerometer_range, "accelerometer_range"))
        if isinstance(self.seed, bool) or not isinstance(self.seed, (int, np.integer)) or self.seed < 0:
            raise InputError(f"seed: expected a non-negative integer, got {self.seed!r}")

    def measure(self, a: Any, z: Any, trial: int = 0) -> tuple[np.ndarray, np.ndarray]:
        """Measured tool acceleration and position of one trial.

        Parameters
        ----------
        a : array_like, shape (N, 3)
            True tool acceleration [m/s^2].
        z : array_like, shape (N, 3)
            True tool position [m].
        trial : int, optional
            Trial number (an ILC iteration): independent noise per trial, reproducible
            (default 0).

        Returns
        -------
        a_m : numpy.ndarray, shape (N, 3)
            ``clip(a + noise)`` [m/s^2].
        z_m : numpy.ndarray, shape (N, 3)
            ``z + noise`` [m].

        Raises
        ------
        InputError
            ``a``, ``z`` not finite (N, 3) arrays of equal length, ``trial`` negative.
        """
        a, _ = as_rows(a, "a", 3)
        z, _ = as_rows(z, "z", 3)
        if a.shape != z.shape:
            raise InputError(f"z: expected the shape {a.shape} of a, got {z.shape}")
        if isinstance(trial, bool) or not isinstance(trial, (int, np.integer)) or trial < 0:
            raise InputError(f"trial: expected a non-negative integer, got {trial!r}")
        rng = np.random.default_rng([int(self.seed), int(trial)])
        noise_a = rng.normal(0.0, 1.0, a.shape) * self.accelerometer_noise
        noise_z = rng.normal(0.0, 1.0, z.shape) * self.gauge_noise
        r = self.accelerometer_range
        return np.clip(a + noise_a, -r, r), z + noise_z


@dataclass
class TrackingResponse(StatusResult):
    """One closed-loop run of :class:`TrackingPlant` (all arrays rows = samples, SI).

    Parameters
    ----------
    status : Status
        ``"completed"``: the simulation completed (keyword only).
    message : str
        Summary (keyword only).
    t : numpy.ndarray, shape (N,)
        Sample times ``k dt`` [s].
    q_ref : numpy.ndarray, shape (N, 3)
        Actuator reference [m].
    q, q_m : numpy.ndarray, shape (N, 3)
        Actuator position and its measurement (exact encoders: equal) [m].
    T_ref : numpy.ndarray, shape (N, 3)
        Tool reference ``fk(q_ref)`` [m].
    T_kin : numpy.ndarray, shape (N, 3)
        Kinematic tool position ``fk(q)`` [m].
    d : numpy.ndarray, shape (N, 3)
        Structural deflection (z column 0) [m].
    z : numpy.ndarray, shape (N, 3)
        True tool position ``T_kin + d`` [m].
    a_kin : numpy.ndarray, shape (N, 3)
        Kinematic tool acceleration (second difference of ``T_kin``) [m/s^2].
    a : numpy.ndarray, shape (N, 3)
        True tool acceleration ``a_kin + d''`` [m/s^2].
    a_m : numpy.ndarray, shape (N, 3)
        Accelerometer reading [m/s^2].
    z_m : numpy.ndarray, shape (N, 3)
        Position gauge reading [m].
    """

    t: np.ndarray = field(default_factory=lambda: np.zeros(0))
    q_ref: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    q: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    q_m: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    T_ref: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    T_kin: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    d: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    z: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    a_kin: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    a: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    a_m: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    z_m: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))

    @property
    def actuator_error(self) -> np.ndarray:
        """``q - q_ref`` [m], shape (N, 3)."""
        return self.q - self.q_ref

    @property
    def tool_error(self) -> np.ndarray:
        """``z - T_ref`` [m], shape (N, 3)."""
        return self.z - self.T_ref


def _second_difference(x: np.ndarray, dt: float) -> np.ndarray:
    """Central second difference of sampled rows, at rest outside the samples.

    ``(x_(k+1) - 2 x_k + x_(k-1)) / dt^2`` with ``x_(-1) = x_0`` and ``x_N = x_(N-1)``.

    Parameters
    ----------
    x : numpy.ndarray, shape (N, d)
        Samples (rows).
    dt : float
        Sample time [s].

    Returns
    -------
    numpy.ndarray, shape (N, d)
        Second derivative estimate [unit / s^2].
    """
    padded = np.vstack([x[:1], x, x[-1:]])
    return np.diff(padded, n=2, axis=0) / dt**2


class TrackingPlant:
    """The L1 in closed loop at 4 ms: actuator reference -> actuators, tool, sensors.

    Dressler (2012), eqs. 6.11 (actuators), 4.9 (fk), 6.14 (structure), ch. 7.3 (sensors);
    the chain is described in the module docstring.

    Parameters
    ----------
    kinematics : GantryTau3Kinematics
        The robot's kinematics (fk of the actuator positions, Jacobian).
    actuators : sequence of control.LTI, length 3
        Closed-loop actuator models (6.11), discrete SISO with sample time ``dt``
        (:func:`gtmodel.robots.actuator_dynamics.actuator_models`).
    structure : ToolStructure, optional
        The structural modes (default :class:`ToolStructure`'s defaults).
    sensors : SensorModel, optional
        Accelerometer and gauge (default :class:`SensorModel`'s defaults).
    dt : float, optional
        Sample time [s] (default :data:`DT`, the loop period).
    configuration : int, optional
        IK configuration for the Jacobian (default 0).
    solution : {1, -1}, optional
        FK branch (default 1).

    Raises
    ------
    InputError
        Not a GantryTau3Kinematics, not three discrete SISO systems with sample time
        ``dt``, a wrong structure or sensor type, a bad ``dt``.
    """

    def __init__(
        self,
        kinematics: GantryTau3Kinematics,
        actuators: Sequence[control.LTI],
        structure: ToolStructure | None = None,
        sensors: SensorModel | None = None,
        dt: float = DT,
        configuration: int = 0,
        solution: int = 1,
    ) -> None:
        if not isinstance(kinematics, GantryTau3Kinematics):
            raise InputError(f"kinematics: expected a GantryTau3Kinematics, got {type(kinematics).__name__}")
        self.dt = positive_float(dt, "dt")
        acts = list(actuators) if isinstance(actuators, (list, tuple)) else None
        if acts is None or len(acts) != 3:
            raise InputError(f"actuators: expected a list of 3 discrete SISO systems, got {actuators!r}")
        for i, g in enumerate(acts):
            if not isinstance(g, control.LTI) or not g.issiso() or not g.isdtime(strict=True):
                raise InputError(f"actuators[{i}]: expected a discrete SISO control.LTI system, got {g!r}")
            if abs(float(g.dt) - self.dt) > _DT_TOLERANCE:
                raise InputError(f"actuators[{i}]: expected sample time dt = {self.dt} s, got {g.dt}")
        structure = ToolStructure() if structure is None else structure
        sensors = SensorModel() if sensors is None else sensors
        if not isinstance(structure, ToolStructure):
            raise InputError(f"structure: expected a ToolStructure, got {type(structure).__name__}")
        if not isinstance(sensors, SensorModel):
            raise InputError(f"sensors: expected a SensorModel, got {type(sensors).__name__}")
        self.kinematics = kinematics
        self.actuators = acts
        self.structure = structure
        self.sensors = sensors
        self.configuration = configuration
        self.solution = solution
        #: The structure at ``dt`` (:meth:`ToolStructure.discrete`).
        self.structure_system = structure.discrete(self.dt)

    @classmethod
    def l1(cls, structure: ToolStructure | None = None, sensors: SensorModel | None = None, configuration: int = 0) -> "TrackingPlant":
        """The L1 plant: parameter set ``"L1"`` and the actuator models of ``"L1_dynamics_models"``.

        Dressler (2012), eq. 6.11 and Table 5.1.

        Parameters
        ----------
        structure : ToolStructure, optional
            Default :class:`ToolStructure` (7.4 / 11.5 Hz).
        sensors : SensorModel, optional
            Default :class:`SensorModel` (seed 0).
        configuration : int, optional
            IK configuration (default 0).

        Returns
        -------
        TrackingPlant
            At the loop period of ``L1_dynamics_models`` (4 ms).
        """
        models = load_dynamics_models("L1_dynamics_models")
        return cls(GantryTau3Kinematics("L1"), actuator_models(models), structure, sensors, loop_period(models), configuration)

    def _times(self, n: int) -> np.ndarray:
        return np.arange(n) * self.dt

    def _actuators(self, u: np.ndarray) -> np.ndarray:
        t = self._times(u.shape[0])
        return np.column_stack([np.squeeze(control.forced_response(g, t, u[:, i]).outputs) for i, g in enumerate(self.actuators)])

    def _structure(self, a_kin: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Deflection and its acceleration (N, 3) (z column 0) for ``a_kin`` (N, 3)."""
        n = a_kin.shape[0]
        out = np.asarray(control.forced_response(self.structure_system, self._times(n), a_kin[:, :2].T).outputs).reshape(4, n)
        d = np.zeros((n, 3))
        dd = np.zeros((n, 3))
        d[:, :2] = out[:2].T
        dd[:, :2] = out[2:].T
        return d, dd

    def simulate(self, q_ref: Any, trial: int = 0) -> TrackingResponse:
        """One closed-loop run from rest at ``q_ref[0]``.

        The linear blocks act on deviations from ``q_ref[0]`` (the plant is at rest there
        before ``t = 0``); :func:`control.forced_response` on every discrete system.

        Parameters
        ----------
        q_ref : array_like, shape (N, 3)
            Actuator reference at ``t = k dt`` [m], ``N >= 2``.
        trial : int, optional
            Trial number for the sensor noise (:meth:`SensorModel.measure`).

        Returns
        -------
        TrackingResponse
            Status ``"completed"`` and every signal (N, 3).

        Raises
        ------
        InputError
            ``q_ref`` not a finite (N, 3) array with N >= 2, a bad ``trial``.
        UnreachablePoseError
            An actuator position admits no tool pose (fk).
        """
        q_ref, _ = as_rows(q_ref, "q_ref", 3)
        if q_ref.shape[0] < 2:
            raise InputError(f"q_ref: expected at least 2 samples, got {q_ref.shape[0]}")
        n = q_ref.shape[0]
        q = q_ref[0] + self._actuators(q_ref - q_ref[0])
        T_ref = self.kinematics.fk(q_ref, self.solution)
        T_kin = self.kinematics.fk(q, self.solution)
        a_kin = _second_difference(T_kin, self.dt)
        d, dd = self._structure(a_kin)
        z = T_kin + d
        a = a_kin + dd
        a_m, z_m = self.sensors.measure(a, z, trial)
        return TrackingResponse(
            status=Status.COMPLETED, message=f"simulated {n} samples of {self.dt} s",
            t=self._times(n), q_ref=q_ref, q=q, q_m=q.copy(), T_ref=T_ref, T_kin=T_kin, d=d, z=z, a_kin=a_kin, a=a, a_m=a_m, z_m=z_m,
        )

    def actuator_impulse_responses(self, n: int) -> np.ndarray:
        """Response of each actuator position to a unit impulse of its reference (delay included).

        Dressler (2012), eqs. 6.11 and 7.9 (the first column of the lifted matrix):
        ``h_i[k] = b_i a_i^(k-5)`` for ``k >= 5``, 0 before. Computed with
        :func:`control.impulse_response`, whose discrete impulse is a pulse of area 1
        (height ``1/dt``), hence scaled by ``dt`` to a unit sample.

        Parameters
        ----------
        n : int
            Number of samples.

        Returns
        -------
        numpy.ndarray, shape (n, 3)
            Column ``i``: actuator ``i`` [m per m].

        Raises
        ------
        InputError
            ``n`` not a positive integer.
        """
        n = positive_int(n, "n")
        t = self._times(n)
        return np.column_stack([np.squeeze(control.impulse_response(g, t).outputs).reshape(n) * self.dt for g in self.actuators])

    def tool_impulse_responses(self, T0: Any, n: int) -> dict[str, np.ndarray]:
        """Responses to a unit impulse of the tool reference, linearised at ``T0`` (lifted systems, 7.9).

        Dressler (2012), eq. 7.9 with the chain tool reference -> IK (``J^-1`` at ``T0``) ->
        actuators (6.11) -> fk (``J``) -> structure (6.14): the kinematic response matrix
        ``H_kin[k] = J diag(h[k]) J^-1`` (``h``: :meth:`actuator_impulse_responses`). Only
        the diagonal terms (direction ``j`` to ``j``) are returned for ``kin``, ``acc``,
        ``tool_position``; the cross terms come from the different actuator dynamics and
        are reported by ``cross_coupling``.

        Parameters
        ----------
        T0 : array_like, shape (3,)
            Operating point of the tool [m].
        n : int
            Number of samples.

        Returns
        -------
        dict of str to numpy.ndarray
            ``kin`` (n, 3): ``T_kin,j`` per unit impulse of the tool reference ``j`` [m/m];
            ``acc`` (n, 3): true acceleration ``a_j`` [m/s^2 per m];
            ``tool_position`` (n, 3): ``T_kin,j + d_j`` [m/m];
            ``cross_coupling`` (3, 3): ``max_k |H_kin[k][l, j]| / max_k |H_kin[k][j, j]|``
            (response in ``l`` to an impulse in ``j``; diagonal 1);
            ``kin_full``, ``acc_full``, ``tool_position_full`` (n, 3, 3): the whole responses,
            ``[k, l, j]`` the response in direction ``l`` to an impulse of the tool reference
            in ``j`` (the coupled lifted check uses them; the diagonals are the entries above).

        Raises
        ------
        InputError
            Bad ``T0`` or ``n``.
        UnreachablePoseError, SingularConfigurationError
            ``T0`` is unreachable or singular.
        """
        T0 = np.asarray(as_rows(T0, "T0", 3)[0])
        if T0.shape[0] != 1:
            raise InputError(f"T0: expected one position of shape (3,), got {T0.shape}")
        n = positive_int(n, "n")
        J = self.kinematics.jacobian(T0[0], self.configuration)
        h = self.actuator_impulse_responses(n)
        H = np.einsum("li,ki,ij->klj", J, h, np.linalg.inv(J))  # (n, 3 out, 3 in)
        peak = np.max(np.abs(H), axis=0)
        coupling = peak / np.diag(peak)[None, :]
        acc_full = np.empty_like(H)
        pos_full = np.empty_like(H)
        for j in range(3):  # every input direction: the structure sees the whole kinematic acceleration
            a_kin = _second_difference(H[:, :, j], self.dt)
            d, dd = self._structure(a_kin)
            acc_full[:, :, j] = a_kin + dd
            pos_full[:, :, j] = H[:, :, j] + d
        diag = lambda X: np.einsum("kjj->kj", X).copy()  # noqa: E731 - the diagonal responses
        return {"kin": diag(H), "acc": diag(acc_full), "tool_position": diag(pos_full), "cross_coupling": coupling,
                "kin_full": H, "acc_full": acc_full, "tool_position_full": pos_full}
