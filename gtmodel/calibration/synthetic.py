"""Synthetic measurements for calibration studies and tests, reproducible with a seed.

The "true" robot is a :class:`~gtmodel.robots.closure.ClosureModel` (any of them: the 3-link
model now, the six-link and F1 models with the same interface) plus the actuator errors of a
real drive train (:class:`ActuatorErrors`, Dressler (2012), ch. 4.2 and Table 4.1) added to
the actuator-side joint points (:class:`DeviatedClosure`). Its TCP (and orientation) comes
from the generic Newton FK on its closure equations; the measuring device adds its noise
(:class:`DeviceNoise`, ch. 5: laser tracker ~10 um, stereo vision ~1.7 mm).

Poses come from :mod:`gtmodel.calibration.poses` (inside the workspace, ch. 5.6), as
actuator values ``q`` (what the robot is commanded to).

Random numbers come from one :func:`numpy.random.default_rng` ``(seed)`` per call, drawn in
a fixed order (position noise, orientation noise, then random backlash directions), so a
seed reproduces a data set exactly.
"""

from __future__ import annotations

import dataclasses
import logging
from dataclasses import dataclass, field
from functools import cached_property
from typing import Any, Sequence

import casadi as ca
import numpy as np
import numpy.typing  # noqa: F401  (np.typing in annotations)
from scipy.spatial.transform import Rotation

from gtmodel.calibration.measurements import CartMeasurements, MeasurementSet
from gtmodel.errors import InputError
from gtmodel._geometry import rotation_to_quaternion
from gtmodel.robots.closure import ClosureModel
from gtmodel.robots.deviated import DeviatedClosure, guideway_axes, joint_point_functions

__all__ = [
    "DeviceNoise",
    "LASER_TRACKER",
    "STEREO_VISION",
    "NO_NOISE",
    "device_noise",
    "ActuatorErrors",
    "line_fit_residuals",
    "backlash_directions",
    "synthetic_measurements",
    "synthetic_cart_measurements",
    "TABLE_4_1_MEAN_RESIDUAL_M",
    "TABLE_4_2_AXIAL_M",
    "TABLE_4_2_ORTHOGONAL_M",
    "CART_SURVEY_RANGE_M",
    "PINION_CIRCUMFERENCE_M",
    "BACKLASH_M",
]

_log = logging.getLogger("gtmodel")

#: Table 4.1 (D1): mean norm of the deviation of the measured cart positions from a
#: linear fit, per actuator [m].
TABLE_4_1_MEAN_RESIDUAL_M = np.array([32e-6, 77e-6, 54e-6])
#: Table 4.2, case 2 (D1): assumed axial actuator errors per arm [m]; used here only for
#: the split of Table 4.1 into an axial and an orthogonal part.
TABLE_4_2_AXIAL_M = np.array([11e-6, 58e-6, 19e-6])
#: Table 4.2, case 2 (D1): assumed errors orthogonal to the guideway per arm [m].
TABLE_4_2_ORTHOGONAL_M = np.array([28e-6, 38e-6, 47e-6])
#: Range of the D1 cart survey of the piecewise-linear actuator model [m] (ch. 4.2).
CART_SURVEY_RANGE_M = (-0.650, 0.700)
#: ASSUMPTION: pinion circumference = period of the cyclic rack-and-pinion error [m]
#: (the thesis names the cyclic error but not the pinion; 0.2 m is a typical size).
PINION_CIRCUMFERENCE_M = 0.2
#: Backlash of the drive train [m] (L2, similar drive train; Dressler (2012), ch. 4.2).
BACKLASH_M = 40e-6


# ----------------------------------------------------------------------------- device noise
@dataclass(frozen=True)
class DeviceNoise:
    """Gaussian noise of a measuring device.

    Parameters
    ----------
    position_sigma_m : float
        Standard deviation per axis of the measured position [m].
    orientation_sigma_rad : float
        Standard deviation per axis of the rotation vector of the orientation error
        [rad] (6-D targets only).
    name : str
        Device name, used by :func:`device_noise`.

    Raises
    ------
    InputError
        If a sigma is negative or not finite.
    """

    position_sigma_m: float
    orientation_sigma_rad: float
    name: str

    def __post_init__(self) -> None:
        for f in ("position_sigma_m", "orientation_sigma_rad"):
            v = getattr(self, f)
            if not (np.isfinite(v) and v >= 0):
                raise InputError(f"DeviceNoise.{f}: expected a non-negative finite number, got {v!r}")

    @property
    def mean_position_error_m(self) -> float:
        """Mean norm of the 3-D position error, ``sigma * 2 sqrt(2/pi)`` (chi distribution, 3 dof)."""
        return float(self.position_sigma_m * 2.0 * np.sqrt(2.0 / np.pi))


#: Laser tracker (Leica, Dressler (2012), ch. 5): 10 um per axis; orientation of a 6-D
#: target (T-Mac) ASSUMED 0.01 deg per axis.
LASER_TRACKER = DeviceNoise(10e-6, np.radians(0.01), "laser_tracker")
#: Stereo vision (Table 5.6): a mean measurement error of 1.7 mm, i.e. per-axis sigma
#: 1.7 mm / (2 sqrt(2/pi)) = 1.065 mm; orientation ASSUMED 0.1 deg per axis.
STEREO_VISION = DeviceNoise(1.7e-3 / (2.0 * np.sqrt(2.0 / np.pi)), np.radians(0.1), "stereo_vision")
#: No noise (exact synthetic data).
NO_NOISE = DeviceNoise(0.0, 0.0, "none")
_DEVICES = {d.name: d for d in (LASER_TRACKER, STEREO_VISION, NO_NOISE)}


def device_noise(name: str | DeviceNoise) -> DeviceNoise:
    """Noise model of a device by name.

    Parameters
    ----------
    name : str or DeviceNoise
        ``"laser_tracker"``, ``"stereo_vision"`` or ``"none"`` (a DeviceNoise is returned
        as it is).

    Returns
    -------
    DeviceNoise

    Raises
    ------
    InputError
        If the name is unknown.
    """
    if isinstance(name, DeviceNoise):
        return name
    try:
        return _DEVICES[str(name)]
    except KeyError:
        raise InputError(f"unknown measuring device {name!r}; expected one of {sorted(_DEVICES)}") from None


# ----------------------------------------------------------------------------- actuator errors
def line_fit_residuals(q: np.typing.ArrayLike, points: np.typing.ArrayLike) -> np.ndarray:
    """Deviation of points along a guideway from their least-squares linear model.

    Fits ``P(q) = a + q b`` (each coordinate linear in ``q``, the linear actuator model
    ``As_i + q_i v_i`` of eq. 4.9) and returns the residual norms, the quantity of
    Dressler (2012), Table 4.1.

    Parameters
    ----------
    q : array_like, shape (M,)
        Actuator values [m], at least 3 distinct.
    points : array_like, shape (M, 3)
        Cart points [m].

    Returns
    -------
    numpy.ndarray, shape (M,)
        ``||P_k - (a + q_k b)||`` [m].

    Raises
    ------
    InputError
        If shapes disagree or fewer than 3 points are given.
    """
    qa = np.asarray(q, dtype=float).reshape(-1)
    P = np.asarray(points, dtype=float)
    if P.shape != (qa.size, 3) or qa.size < 3:
        raise InputError(f"line_fit_residuals: expected q (M,) and points (M, 3) with M >= 3, got {qa.shape} and {P.shape}")
    X = np.column_stack([np.ones_like(qa), qa])
    coef, *_ = np.linalg.lstsq(X, P, rcond=None)
    return np.linalg.norm(P - X @ coef, axis=1)


@dataclass(frozen=True)
class ActuatorErrors:
    """Non-linearity of rack-and-pinion linear actuators (Dressler (2012), ch. 4.2, Table 4.1).

    Displacement of the cart joint point of arm ``i`` in its guideway frame (axes
    ``e1`` along the guideway, ``e2`` horizontal, ``e3`` completing, see
    :func:`guideway_axes`), with ``x = (q - r0) / (r1 - r0)`` over the survey range::

        d_axial = c_i sin(2 pi q / lambda + phi_i) - direction * b_i / 2
        d_e2    = s_i cos(2 pi x)
        d_e3    = s_i / 2 cos(4 pi x)

    - cyclic rack-and-pinion error: amplitude ``c_i``, period ``lambda`` = the pinion
      circumference;
    - guideway straightness: slow waves perpendicular to the guideway (one and two periods
      over the range; both orthogonal to a linear fit over the range, so they show fully
      in Table 4.1);
    - backlash ``b_i``: the cart lags by ``b_i / 2`` behind the commanded position in the
      direction of the last motion (``direction = +1`` for a positive motion).

    Parameters
    ----------
    cyclic_amplitude_m : array_like, shape (3,)
        ``c_i`` [m].
    straightness_amplitude_m : array_like, shape (3,)
        ``s_i`` [m].
    backlash_m : array_like, shape (3,)
        ``b_i`` [m].
    cyclic_period_m : float, optional
        ``lambda`` [m], default :data:`PINION_CIRCUMFERENCE_M`.
    cyclic_phase_rad : array_like, shape (3,), optional
        ``phi_i`` [rad], default ``(0, 2 pi / 3, 4 pi / 3)``.
    straightness_range_m : tuple of float, optional
        ``(r0, r1)`` [m], default :data:`CART_SURVEY_RANGE_M`.
    source : str, optional
        Where the magnitudes come from.

    Raises
    ------
    InputError
        If shapes are wrong, values are not finite, amplitudes or backlash are negative,
        the period is not positive or the range is empty.
    """

    cyclic_amplitude_m: np.ndarray
    straightness_amplitude_m: np.ndarray
    backlash_m: np.ndarray
    cyclic_period_m: float = PINION_CIRCUMFERENCE_M
    cyclic_phase_rad: np.ndarray = field(default_factory=lambda: np.array([0.0, 2 * np.pi / 3, 4 * np.pi / 3]))
    straightness_range_m: tuple[float, float] = CART_SURVEY_RANGE_M
    source: str = ""

    def __post_init__(self) -> None:
        for f in ("cyclic_amplitude_m", "straightness_amplitude_m", "backlash_m", "cyclic_phase_rad"):
            a = np.asarray(getattr(self, f), dtype=float)
            a = np.full(3, float(a)) if a.ndim == 0 else a
            if a.shape != (3,) or not np.all(np.isfinite(a)):
                raise InputError(f"ActuatorErrors.{f}: expected 3 finite values (one per arm), got {getattr(self, f)!r}")
            if f != "cyclic_phase_rad" and np.any(a < 0):
                raise InputError(f"ActuatorErrors.{f}: expected non-negative values, got {a.tolist()}")
            object.__setattr__(self, f, a.copy())
        if not (np.isfinite(self.cyclic_period_m) and self.cyclic_period_m > 0):
            raise InputError(f"ActuatorErrors.cyclic_period_m: expected a positive length, got {self.cyclic_period_m!r}")
        r = tuple(float(x) for x in self.straightness_range_m)
        if len(r) != 2 or not r[0] < r[1]:
            raise InputError(f"ActuatorErrors.straightness_range_m: expected (r0, r1) with r0 < r1, got {self.straightness_range_m!r}")
        object.__setattr__(self, "straightness_range_m", r)

    @classmethod
    def none(cls) -> "ActuatorErrors":
        """Perfect actuators (all magnitudes zero).

        Returns
        -------
        ActuatorErrors
        """
        return cls(np.zeros(3), np.zeros(3), np.zeros(3), source="none")

    @classmethod
    def table_4_1(
        cls,
        mean_residual_m: np.typing.ArrayLike = TABLE_4_1_MEAN_RESIDUAL_M,
        backlash_m: float | np.typing.ArrayLike = BACKLASH_M,
        cyclic_period_m: float = PINION_CIRCUMFERENCE_M,
        survey_range_m: tuple[float, float] = CART_SURVEY_RANGE_M,
    ) -> "ActuatorErrors":
        """Actuator errors with the magnitudes of the D1 (Dressler (2012), Tables 4.1, 4.2).

        The axial (cyclic) and orthogonal (straightness) parts are split in the ratio of
        Table 4.2 case 2 (RMS axial : RMS orthogonal = 11:28, 58:38, 19:47 um), then
        scaled so that the mean deviation from a linear fit over the survey range (a
        survey in one direction, :func:`line_fit_residuals` on 2001 points) equals
        ``mean_residual_m`` (Table 4.1: 32, 77, 54 um).

        Parameters
        ----------
        mean_residual_m : array_like, shape (3,), optional
            Target mean deviation from a linear fit per actuator [m].
        backlash_m : float or array_like, shape (3,), optional
            Backlash [m], default :data:`BACKLASH_M`.
        cyclic_period_m : float, optional
            Period of the rack-and-pinion error [m].
        survey_range_m : tuple of float, optional
            Range of the cart survey [m].

        Returns
        -------
        ActuatorErrors

        Raises
        ------
        InputError
            If a value is invalid (see the class).
        """
        target = np.asarray(mean_residual_m, dtype=float).reshape(-1)
        if target.shape != (3,) or np.any(~(target >= 0)):
            raise InputError(f"mean_residual_m: expected 3 non-negative values [m], got {mean_residual_m!r}")
        # RMS of c sin(.) is c / sqrt(2); of the straightness waves s sqrt(1 + 1/4) / sqrt(2)
        c = TABLE_4_2_AXIAL_M * np.sqrt(2.0)
        s = TABLE_4_2_ORTHOGONAL_M * np.sqrt(2.0) / np.sqrt(1.25)
        unit = cls(c, s, np.zeros(3), cyclic_period_m=cyclic_period_m, straightness_range_m=survey_range_m)
        qs = np.linspace(*unit.straightness_range_m, 2001)
        mean = np.array([line_fit_residuals(qs, unit.deviation(i, qs)).mean() for i in range(3)])
        k = target / mean
        return cls(
            c * k, s * k, np.broadcast_to(np.asarray(backlash_m, dtype=float), (3,)).copy(),
            cyclic_period_m=cyclic_period_m, straightness_range_m=survey_range_m,
            source="Dressler (2012), Table 4.1 means split as Table 4.2 case 2, backlash ch. 4.2",
        )

    def deviation_expression(self, arm: int, q_i: Any, direction: Any = 1.0, axes: Any = None) -> Any:
        """Displacement of the cart joint point as a CasADi expression of ``q_i``.

        Parameters
        ----------
        arm : int
            Arm index 0, 1, 2.
        q_i : casadi.SX or casadi.MX or float
            Actuator value of the arm [m].
        direction : float or casadi.SX, optional
            Direction of the last motion, +1 or -1 (backlash sign).
        axes : array_like or casadi.SX, shape (3, 3), optional
            Guideway frame, columns ``e1`` (along), ``e2``, ``e3``; default identity (x
            along the guideway, the horizontal prototypes' frame, spec section 1).

        Returns
        -------
        casadi.SX or casadi.MX or casadi.DM, shape (3, 1)
            Displacement [m] in the frame of ``axes``' columns.

        Raises
        ------
        InputError
            If ``arm`` is not 0, 1 or 2.
        """
        if arm not in range(3):
            raise InputError(f"arm must be one of 0..2, got {arm!r}")
        r0, r1 = self.straightness_range_m
        x = (q_i - r0) / (r1 - r0)
        c, s, b = self.cyclic_amplitude_m[arm], self.straightness_amplitude_m[arm], self.backlash_m[arm]
        local = ca.vertcat(
            c * ca.sin(2 * np.pi * q_i / self.cyclic_period_m + self.cyclic_phase_rad[arm]) - direction * b / 2,
            s * ca.cos(2 * np.pi * x),
            0.5 * s * ca.cos(4 * np.pi * x),
        )
        E = ca.DM.eye(3) if axes is None else (axes if isinstance(axes, (ca.SX, ca.MX)) else ca.DM(np.asarray(axes, dtype=float)))
        return ca.mtimes(E, local)

    @cached_property
    def _deviation_functions(self) -> list[ca.Function]:
        q, d, E = ca.SX.sym("q"), ca.SX.sym("direction"), ca.SX.sym("axes", 3, 3)
        return [ca.Function(f"deviation_arm{i + 1}", [q, d, E], [self.deviation_expression(i, q, d, E)]) for i in range(3)]

    def deviation(
        self,
        arm: int,
        q: np.typing.ArrayLike,
        direction: float | np.typing.ArrayLike = 1.0,
        axes: np.typing.ArrayLike | None = None,
    ) -> np.ndarray:
        """Displacement of the cart joint point of one arm (numeric, from :meth:`deviation_expression`).

        Parameters
        ----------
        arm : int
            Arm index 0, 1, 2.
        q : array_like, shape (N,)
            Actuator values of the arm [m].
        direction : float or array_like, shape (N,), optional
            Direction of the last motion, +1 or -1 per sample.
        axes : array_like, shape (3, 3), optional
            Guideway frame (columns), default identity.

        Returns
        -------
        numpy.ndarray, shape (N, 3)
            Displacements [m].

        Raises
        ------
        InputError
            If ``arm`` is invalid, a direction is not +-1 or shapes disagree.
        """
        if arm not in range(3):
            raise InputError(f"arm must be one of 0..2, got {arm!r}")
        qa = np.asarray(q, dtype=float).reshape(-1)
        da = np.broadcast_to(np.asarray(direction, dtype=float), qa.shape)
        if not np.all(np.abs(da) == 1.0):
            raise InputError(f"direction: expected +1 or -1, got {np.unique(da).tolist()}")
        E = np.eye(3) if axes is None else np.asarray(axes, dtype=float)
        if E.shape != (3, 3):
            raise InputError(f"axes: expected shape (3, 3), got {E.shape}")
        f = self._deviation_functions[arm].map(qa.size)
        return np.array(f(qa[None, :], da[None, :], np.tile(E, (1, qa.size)))).T

    def __eq__(self, other: object) -> bool:
        return isinstance(other, ActuatorErrors) and all(
            np.array_equal(np.asarray(getattr(self, f.name)), np.asarray(getattr(other, f.name)))
            for f in dataclasses.fields(self)
            if f.name != "source"
        )

    __hash__ = None  # type: ignore[assignment]


# ----------------------------------------------------------------------------- measurements
def backlash_directions(
    q: np.typing.ArrayLike, direction: str | np.typing.ArrayLike = "pose_order", seed: int | np.random.Generator | None = 0
) -> np.ndarray:
    """Direction of the last motion of each linear actuator, per pose (the backlash sign).

    Parameters
    ----------
    q : array_like, shape (N, n_q)
        Actuator values in the order the poses are visited [m].
    direction : {"pose_order", "random"} or array_like, optional
        ``"pose_order"``: ``sign(q_k,i - q_k-1,i)``, keeping the previous sign when a cart
        does not move and +1 for the first pose (ASSUMED: the carts approach the first
        pose from below); ``"random"``: +-1 with equal probability; or an array of +-1 of
        shape (N, 3) or (3,).
    seed : int or numpy.random.Generator or None, optional
        Seed (or generator) for ``"random"``.

    Returns
    -------
    numpy.ndarray, shape (N, 3)
        +1 or -1 per pose and arm.

    Raises
    ------
    InputError
        If ``direction`` is neither a known mode nor an array of +-1 of a valid shape.
    """
    qa = np.atleast_2d(np.asarray(q, dtype=float))
    N = qa.shape[0]
    if isinstance(direction, str):
        if direction == "random":
            return np.random.default_rng(seed).choice([-1.0, 1.0], size=(N, 3))
        if direction != "pose_order":
            raise InputError(f"direction: expected 'pose_order', 'random' or an array of +-1, got {direction!r}")
        out = np.ones((N, 3))
        for k in range(1, N):
            s = np.sign(qa[k, :3] - qa[k - 1, :3])
            out[k] = np.where(s == 0, out[k - 1], s)
        return out
    d = np.asarray(direction, dtype=float)
    try:
        d = np.broadcast_to(d, (N, 3)).copy()
    except ValueError:
        raise InputError(f"direction: expected shape (N, 3) or (3,) of +-1, got {d.shape}") from None
    if not np.all(np.abs(d) == 1.0):
        raise InputError("direction: every entry must be +1 or -1")
    return d


def _as_q(model: ClosureModel, q: np.typing.ArrayLike) -> np.ndarray:
    qa = np.atleast_2d(np.asarray(q, dtype=float))
    if qa.ndim != 2 or qa.shape[1] != model.n_q or qa.shape[0] == 0 or not np.all(np.isfinite(qa)):
        raise InputError(f"q: expected finite actuator values of shape (N, {model.n_q}), got shape {np.shape(q)}")
    return qa


def synthetic_measurements(
    true_model: ClosureModel,
    q: np.typing.ArrayLike,
    noise: DeviceNoise | str = LASER_TRACKER,
    actuator_errors: ActuatorErrors | None = None,
    seed: int | None = 0,
    direction: str | np.typing.ArrayLike = "pose_order",
    orientation: bool | None = None,
) -> MeasurementSet:
    """Simulated measurements of a robot at given actuator values.

    The true TCP ``T`` and orientation ``R_T`` solve the closure equations of the true robot
    (``true_model`` with ``actuator_errors`` on its joint points, :class:`DeviatedClosure`)
    by Newton's method started from ``true_model.fk``; the device adds Gaussian noise to
    ``T`` (``noise.position_sigma_m`` per axis) and a random rotation
    ``Rot(r) R_T``, ``r ~ N(0, noise.orientation_sigma_rad^2 I)``, to the orientation.

    Parameters
    ----------
    true_model : ClosureModel
        The robot's true geometry.
    q : array_like, shape (N, n_q)
        Actuator values, in the order the poses are visited [m, rad].
    noise : DeviceNoise or str, optional
        Device noise (default :data:`LASER_TRACKER`) or its name.
    actuator_errors : ActuatorErrors, optional
        Actuator errors of the true robot (none by default).
    seed : int or None, optional
        Seed of :func:`numpy.random.default_rng`.
    direction : {"pose_order", "random"} or array_like, optional
        Backlash direction per pose, see :func:`backlash_directions`.
    orientation : bool, optional
        Whether orientations are measured (default: ``true_model.orientation``).

    Returns
    -------
    MeasurementSet
        ``q`` as given, measured ``T`` (and ``quat``); ``source`` describes the set.

    Raises
    ------
    InputError
        If ``q`` has the wrong shape, the device is unknown or ``direction`` is invalid.
    ConvergenceError
        If the true robot's FK does not converge (names the pose).
    UnreachablePoseError
        If ``true_model.fk`` finds no pose.
    """
    qa = _as_q(true_model, q)
    dev = device_noise(noise)
    N = qa.shape[0]
    with_quat = true_model.orientation if orientation is None else bool(orientation)
    rng = np.random.default_rng(seed)
    e_T = rng.standard_normal((N, 3)) * dev.position_sigma_m
    e_R = rng.standard_normal((N, 3)) * dev.orientation_sigma_rad
    T = np.empty((N, 3))
    R = np.empty((N, 3, 3))
    T0, R0 = true_model.fk(qa)
    if actuator_errors is None:
        T[:], R[:] = true_model.fk_newton(qa, T0, R0)
    else:
        dirs = backlash_directions(qa, direction, rng)
        axes = guideway_axes(true_model)
        patterns, inverse = np.unique(dirs, axis=0, return_inverse=True)
        for g, pat in enumerate(patterns):
            rows = np.flatnonzero(inverse.ravel() == g)
            true_robot = DeviatedClosure(true_model, actuator_errors, pat, axes)
            T[rows], R[rows] = true_robot.fk_newton(qa[rows], T0[rows], R0[rows])
    quat = None
    if with_quat:
        quat = rotation_to_quaternion(Rotation.from_rotvec(e_R).as_matrix() @ R)
    src = (
        f"synthetic: model {true_model.name}, {N} poses, device {dev.name} "
        f"(sigma {dev.position_sigma_m:.3g} m, {np.degrees(dev.orientation_sigma_rad):.3g} deg), "
        f"actuator errors {'none' if actuator_errors is None else actuator_errors.source or 'given'}, seed {seed}"
    )
    return MeasurementSet(q=qa, T=T + e_T, quat=quat, source=src, comments=(" " + src,))


def synthetic_cart_measurements(
    true_model: ClosureModel,
    actuator_errors: ActuatorErrors | None = None,
    q_grid: np.typing.ArrayLike | Sequence[np.typing.ArrayLike] | None = None,
    noise: DeviceNoise | str = LASER_TRACKER,
    seed: int | None = 0,
    frames: tuple[np.typing.ArrayLike, np.typing.ArrayLike] | None = None,
    direction: float = 1.0,
) -> CartMeasurements:
    """Simulated survey of the cart positions along each guideway (data of eq. 5.7).

    The surveyed point of arm ``i`` is the joint point ``A_i1`` of the arm's first link with
    the actuator errors (:class:`DeviatedClosure`), at ``q_i`` from ``q_grid`` and the other
    actuators at 0, expressed in the survey frame ``P = R_i^T (A - t_i)`` and disturbed by the
    device noise.

    Parameters
    ----------
    true_model : ClosureModel
        The robot's true geometry.
    actuator_errors : ActuatorErrors, optional
        Actuator errors (none by default: straight guideways).
    q_grid : array_like, shape (M,), or sequence of 3 arrays, optional
        Surveyed actuator values [m], the same for every arm or one array per arm; default
        :data:`CART_SURVEY_RANGE_M` in steps of 0.05 m (28 points).
    noise : DeviceNoise or str, optional
        Device noise (default :data:`LASER_TRACKER`).
    seed : int or None, optional
        Seed of :func:`numpy.random.default_rng`.
    frames : tuple of array_like, optional
        ``(R, t)`` with ``R`` (3, 3, 3) and ``t`` (3, 3): survey frame of each arm in the TCP
        data frame (``A = R_i P + t_i``); default the TCP data frame itself.
    direction : float, optional
        Direction of motion during the survey (+1 or -1), for the backlash.

    Returns
    -------
    CartMeasurements

    Raises
    ------
    InputError
        If the grid, frames or direction are invalid or the device is unknown.
    """
    dev = device_noise(noise)
    if q_grid is None:
        q_grid = np.round(np.arange(CART_SURVEY_RANGE_M[0], CART_SURVEY_RANGE_M[1] + 0.025, 0.05), 12)
    per_arm = isinstance(q_grid, (list, tuple)) and len(q_grid) == 3 and np.ndim(q_grid[0]) == 1
    if per_arm:
        grids = [np.asarray(g, dtype=float).reshape(-1) for g in q_grid]
    else:
        grids = [np.asarray(q_grid, dtype=float).reshape(-1)] * 3
    for i, g in enumerate(grids):
        if g.size < 2 or np.any(np.diff(g) <= 0) or not np.all(np.isfinite(g)):
            raise InputError(f"q_grid (arm {i + 1}): expected >= 2 strictly increasing finite values, got {g.tolist()}")
    if frames is None:
        Rf, tf = np.broadcast_to(np.eye(3), (3, 3, 3)), np.zeros((3, 3))
    else:
        Rf, tf = (np.asarray(x, dtype=float) for x in frames)
        if Rf.shape != (3, 3, 3) or tf.shape != (3, 3):
            raise InputError(f"frames: expected (R (3, 3, 3), t (3, 3)), got shapes {Rf.shape} and {tf.shape}")
    if direction not in (1, -1, 1.0, -1.0):
        raise InputError(f"direction: expected +1 or -1, got {direction!r}")
    robot = true_model if actuator_errors is None else DeviatedClosure(true_model, actuator_errors, [direction] * 3)
    fA, _ = joint_point_functions(robot)
    p = robot.parameter_vector()
    rng = np.random.default_rng(seed)
    qs, ps = [], []
    j0 = 0
    for i, g in enumerate(grids):
        qq = np.zeros((robot.n_q, g.size))
        qq[i] = g
        A = np.array(fA.map(g.size)(p, qq)).reshape(3, g.size, robot.n_links)[:, :, j0].T
        P = (A - tf[i]) @ Rf[i]
        ps.append(P + rng.standard_normal(P.shape) * dev.position_sigma_m)
        qs.append(g)
        j0 += len(robot.links[i])
    src = (
        f"synthetic cart survey: model {true_model.name}, device {dev.name}, actuator errors "
        f"{'none' if actuator_errors is None else actuator_errors.source or 'given'}, seed {seed}"
    )
    return CartMeasurements(q=tuple(qs), positions=tuple(ps), source=src, comments=(" " + src,))
