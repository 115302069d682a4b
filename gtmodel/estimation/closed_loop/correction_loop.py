"""Closed-loop stability of real-time pose-offset corrections, Cvitanic (2021), section 5, eq. (33).

The loop, one Cartesian direction at a time (cross-coupling neglected as in eq. (8)):

- every cycle ``k`` (``dt = 4 ms``) the tracker error ``e_k = r_k - p_k`` is measured;
- the P controller sends the pose-offset command ``K e_k`` (RSI's relative correction: the
  offsets accumulate, ``u_k = u_{k-1} + K e_k``);
- the robot executes the command ``delay = 13`` cycles later (the measured 52 ms lumps the
  controller and measurement latencies), ``c_k = u_{k-13}`` plus the programmed path, and the
  TCP responds through an :class:`~gtmodel.estimation.closed_loop.correction.OffsetResponseModel`.

The programmed feed is a constant-rate motion: by eqs. (31)-(32) it has no equivalent force,
and the loop is linear, so the reference of the correction loop in the corrected direction is
the test path's offset ``r = 50.8 sin(2 pi 0.0098 s)`` mm with ``s`` the distance fed at
42.33 mm/s (``y`` for the y loop; its counterpart ``x = 50.8 sin(2 pi 0.0098 y)`` for the x
loop) (:func:`sine_reference`).

Two methods decide stability at a gain:

- ``"simulation"`` (:func:`simulate_loop`): the loop simulated cycle by cycle (one CasADi
  step Function, ``mapaccum`` over the run) on the sine path. STABILITY CRITERION: the
  error stays finite and its largest magnitude over the last path period is at most
  ``1 + GROWTH_TOLERANCE`` times that over the period before (bounded, not growing);
- ``"eigenvalues"`` (:func:`spectral_radius`): the poles of the closed-loop discrete system
  ``feedback(K z/(z-1) z^-13 P(z), 1)`` (python-control), stable when all are inside the
  unit circle (with a margin of :data:`POLE_MARGIN`).

:func:`largest_stable_gain` scans ``K = resolution, 2 resolution, ...`` and returns the last
stable grid gain before the first unstable one (Table 14's resolution: 0.01 in y, 0.1 in x).
:func:`critical_gain` bisects the spectral radius for the exact limit.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass, field
from typing import Any

import casadi as ca
import numpy as np
from threadpoolctl import threadpool_limits  # a dependency of scikit-learn

from gtmodel._arrays import as_vector, positive_float, positive_int
from gtmodel._lazy import lazy_module
from gtmodel.errors import InputError
from gtmodel.estimation.closed_loop.correction import (
    CALIBRATION_POSES_DEG,
    CYCLE_TIME_S,
    DELAY_CYCLES,
    VALIDATION_POSES_DEG,
    WRIST_JOINTS_DEG,
    OffsetResponseModel,
    fit_offset_response,
    offset_response_gp,
    truth_model,
)
from gtmodel.estimation.closed_loop.vibration_loop import (
    bisect_critical_gain,
    delay_line,
)
from gtmodel.robots.dynamic_stiffness import DIRECTIONS, ModeFitResult
from gtmodel.robots.serial import SerialArm
from gtmodel.status import Status, StatusResult

#: python-control, imported on first use (it imports matplotlib.pyplot: ~2 s of CPU).
control = lazy_module("control")

__all__ = [
    "DEFAULT_RESOLUTIONS",
    "FEED_RATE_M_S",
    "GROWTH_TOLERANCE",
    "METHODS",
    "POLE_MARGIN",
    "SINE_AMPLITUDE_M",
    "SINE_SPATIAL_FREQUENCY_PER_M",
    "CorrectionStudy",
    "GainScan",
    "LoopSimulation",
    "closed_loop",
    "correction_study",
    "critical_gain",
    "largest_stable_gain",
    "loop_plant",
    "path_period",
    "simulate_loop",
    "sine_reference",
    "spectral_radius",
]

_log = logging.getLogger("gtmodel")

#: Feed rate of the test path [m/s] (Cvitanic (2021), section 5: 42.33 mm/s).
FEED_RATE_M_S = 0.04233
#: Amplitude of the test path [m] (50.8 mm).
SINE_AMPLITUDE_M = 0.0508
#: Spatial frequency of the test path [1/m] (0.0098 / mm).
SINE_SPATIAL_FREQUENCY_PER_M = 9.8
#: Simulation criterion: largest allowed growth of max|e| from one path period to the next.
GROWTH_TOLERANCE = 0.01
#: Eigenvalue criterion: stable when the spectral radius is below ``1 - POLE_MARGIN``.
POLE_MARGIN = 1e-9
#: The two stability methods.
METHODS = ("simulation", "eigenvalues")
#: Gain resolution per direction (Cvitanic (2021), Table 14: 0.1 in x, 0.01 in y).
DEFAULT_RESOLUTIONS = {"x": 0.1, "y": 0.01}


def path_period(feed_rate: float = FEED_RATE_M_S, spatial_frequency: float = SINE_SPATIAL_FREQUENCY_PER_M) -> float:
    """Period of the sine path in time, ``1 / (spatial_frequency feed_rate)`` [s].

    Parameters
    ----------
    feed_rate : float, optional
        Feed rate [m/s], > 0.
    spatial_frequency : float, optional
        Cycles per metre fed [1/m], > 0.

    Returns
    -------
    float
        The period [s] (2.41 s for the thesis' path).

    Raises
    ------
    InputError
        A non-positive argument.
    """
    return 1.0 / (positive_float(spatial_frequency, "spatial_frequency") * positive_float(feed_rate, "feed_rate"))


def sine_reference(n: int, dt: float = CYCLE_TIME_S, amplitude: float = SINE_AMPLITUDE_M, feed_rate: float = FEED_RATE_M_S,
                   spatial_frequency: float = SINE_SPATIAL_FREQUENCY_PER_M) -> np.ndarray:
    """Offset of the test path across the feed, ``A sin(2 pi f_s v t)`` per cycle, Cvitanic (2021), section 5.

    Parameters
    ----------
    n : int
        Cycles, >= 1.
    dt : float, optional
        Cycle time [s].
    amplitude : float, optional
        ``A`` [m], > 0 (50.8 mm).
    feed_rate : float, optional
        ``v`` [m/s], > 0 (42.33 mm/s).
    spatial_frequency : float, optional
        ``f_s`` [1/m], > 0 (0.0098 / mm).

    Returns
    -------
    numpy.ndarray, shape (n,)
        Reference offset per cycle [m].

    Raises
    ------
    InputError
        A non-positive argument.
    """
    n = positive_int(n, "n")
    w = 2 * np.pi / path_period(feed_rate, spatial_frequency)
    return positive_float(amplitude, "amplitude") * np.sin(w * np.arange(n) * positive_float(dt, "dt"))


def loop_plant(model: OffsetResponseModel, delay_cycles: int = DELAY_CYCLES) -> control.StateSpace:
    """Plant from the accumulated offset ``u_k`` to the TCP position: ``z^-delay P(z)``.

    Parameters
    ----------
    model : OffsetResponseModel
        Response of the direction (eqs. (8), (30)-(32)).
    delay_cycles : int, optional
        Controller delay in cycles (default 13 = 52 ms / 4 ms).

    Returns
    -------
    control.StateSpace
        Discrete, strictly proper (the delay), sample time ``model.dt``.

    Raises
    ------
    InputError
        Not an OffsetResponseModel or a delay below 1.
    """
    if not isinstance(model, OffsetResponseModel):
        raise InputError(f"model: expected an OffsetResponseModel, got {type(model).__name__}")
    delay = positive_int(delay_cycles, "delay_cycles")
    return control.series(delay_line(delay, model.dt), model.response_ss())


def closed_loop(model: OffsetResponseModel, gain: float, delay_cycles: int = DELAY_CYCLES) -> control.StateSpace:
    """Closed loop ``feedback(K z/(z-1) z^-delay P(z), 1)`` from the reference to the TCP, eq. (33).

    Parameters
    ----------
    model : OffsetResponseModel
        Response of the direction.
    gain : float
        P gain ``K`` [-], > 0.
    delay_cycles : int, optional
        Controller delay in cycles.

    Returns
    -------
    control.StateSpace
        The discrete closed loop (python-control ``feedback``).

    Raises
    ------
    InputError
        Bad model, gain or delay.
    """
    K = positive_float(gain, "gain")
    dt = model.dt if isinstance(model, OffsetResponseModel) else CYCLE_TIME_S
    accumulate = control.ss([[1.0]], [[1.0]], [[K]], [[K]], dt)  # u_k = u_{k-1} + K e_k
    return control.feedback(control.series(accumulate, loop_plant(model, delay_cycles)), 1)


def spectral_radius(model: OffsetResponseModel, gain: float, delay_cycles: int = DELAY_CYCLES) -> float:
    """Largest pole magnitude of the closed loop (second method of :func:`largest_stable_gain`).

    Parameters
    ----------
    model : OffsetResponseModel
        Response of the direction.
    gain : float
        P gain, > 0.
    delay_cycles : int, optional
        Controller delay in cycles.

    Returns
    -------
    float
        ``max |eig|`` of the closed-loop state matrix [-]; stable when below 1.

    Raises
    ------
    InputError
        Bad model, gain or delay.
    """
    return float(np.max(np.abs(np.linalg.eigvals(closed_loop(model, gain, delay_cycles).A))))


@dataclass
class LoopSimulation(StatusResult):
    """A step-by-step simulation of the correction loop (status ``"completed"``; ``stable`` says the verdict).

    Parameters
    ----------
    status : Status
        ``"completed"`` (the simulation ran, whatever the verdict); keyword only.
    message : str
        The verdict in words; keyword only.
    gain : float
        P gain [-].
    reference : numpy.ndarray, shape (n,)
        Reference offset [m].
    position : numpy.ndarray, shape (n,)
        TCP position (offset part) [m].
    error : numpy.ndarray, shape (n,)
        ``reference - position`` [m] (``inf`` once it overflowed).
    command : numpy.ndarray, shape (n,)
        Accumulated offset command ``u`` [m].
    growth : float
        ``max|e|`` over the last path period over that of the period before [-] (``inf`` if not finite).
    stable : bool
        The criterion of the module docstring.
    """

    gain: float = 0.0
    reference: np.ndarray = field(default_factory=lambda: np.zeros(0))
    position: np.ndarray = field(default_factory=lambda: np.zeros(0))
    error: np.ndarray = field(default_factory=lambda: np.zeros(0))
    command: np.ndarray = field(default_factory=lambda: np.zeros(0))
    growth: float = math.inf
    stable: bool = False


def _step_function(plant: control.StateSpace, n: int) -> ca.Function:
    """CasADi ``mapaccum`` of one loop cycle: (x, u_prev) -> next; outputs e, p, u."""
    A, B, C = (ca.DM(np.asarray(M, dtype=float)) for M in (plant.A, plant.B, plant.C))
    nx = plant.A.shape[0]
    s = ca.SX.sym("s", nx + 1)
    r = ca.SX.sym("r")
    K = ca.SX.sym("K")
    x, u_prev = s[:nx], s[nx]
    p = ca.mtimes(C, x)
    e = r - p
    u = u_prev + K * e  # the P controller's relative pose-offset command, accumulated
    x_next = ca.mtimes(A, x) + ca.mtimes(B, u)
    step = ca.Function("correction_step", [s, r, K], [ca.vertcat(x_next, u), ca.vertcat(e, p, u)], ["s", "r", "K"], ["s_next", "out"])
    return step.mapaccum("correction_loop", n, [0], [0])


def simulate_loop(model: OffsetResponseModel, gain: float, reference: Any, delay_cycles: int = DELAY_CYCLES,
                  period_cycles: int | None = None) -> LoopSimulation:
    """Simulate the correction loop cycle by cycle from rest, eq. (33) (see the module docstring).

    Parameters
    ----------
    model : OffsetResponseModel
        Response of the direction.
    gain : float
        P gain ``K`` [-], > 0.
    reference : array_like, shape (n,)
        Reference offset per cycle [m] (e.g. :func:`sine_reference`), n >= 2 ``period_cycles``.
    delay_cycles : int, optional
        Controller delay in cycles (default 13).
    period_cycles : int, optional
        Window of the growth criterion [cycles] (default: the thesis' path period, 603 cycles at 4 ms).

    Returns
    -------
    LoopSimulation
        The run, its growth ratio and verdict.

    Raises
    ------
    InputError
        Bad model, gain, delay, or a reference that is not finite or shorter than two windows.
    """
    K = positive_float(gain, "gain")
    r, w = _reference(model, reference, period_cycles)
    return _simulate(_step_function(loop_plant(model, delay_cycles), r.size), K, r, w)


def _reference(model: OffsetResponseModel, reference: Any, period_cycles: int | None) -> tuple[np.ndarray, int]:
    r = as_vector(reference, "reference")
    w = positive_int(period_cycles, "period_cycles") if period_cycles is not None else int(round(path_period() / model.dt))
    if r.size < 2 * w:
        raise InputError(f"reference: expected at least 2 windows of {w} cycles, got {r.size}")
    return r, w


def _simulate(loop: ca.Function, K: float, r: np.ndarray, w: int) -> LoopSimulation:
    """Run the mapaccum ``loop`` from rest and apply the growth criterion over windows of ``w`` cycles."""
    with np.errstate(over="ignore", invalid="ignore"):
        _, out = loop(np.zeros(loop.size1_in(0)), r.reshape(1, -1), K)
        out = np.array(out)
    e, p, u = out
    finite = bool(np.all(np.isfinite(e)))
    if finite:
        last, before = np.max(np.abs(e[-w:])), np.max(np.abs(e[-2 * w:-w]))
        growth = float(last / before) if before > 0 else (math.inf if last > 0 else 0.0)
    else:
        growth = math.inf
        e = np.where(np.isfinite(e), e, math.inf)
    stable = finite and growth <= 1.0 + GROWTH_TOLERANCE
    verdict = "stable" if stable else "unstable"
    return LoopSimulation(status=Status.COMPLETED, message=f"{verdict} at K = {K:g}: max|e| grows x{growth:.4g} over the last period",
                          gain=K, reference=r, position=p, error=e, command=u, growth=growth, stable=stable)


@dataclass
class GainScan(StatusResult):
    """The largest stable P gain on a grid (status ``"completed"``, or ``"max_iterations"`` if the grid ran out).

    Parameters
    ----------
    status : Status
        ``"completed"``: an unstable grid gain was found above :attr:`gain`;
        ``"max_iterations"``: stable up to ``max_gain``; keyword only.
    message : str
        Summary; keyword only.
    method : str
        ``"simulation"`` or ``"eigenvalues"``.
    resolution : float
        Grid step [-].
    gain : float
        Largest stable grid gain before the first unstable one (0 if the first is unstable) [-].
    gains : numpy.ndarray, shape (n,)
        Grid gains tried.
    stable : numpy.ndarray, shape (n,), bool
        Verdict per tried gain.
    measure : numpy.ndarray, shape (n,)
        Growth ratio (simulation) or spectral radius (eigenvalues) per tried gain [-].
    """

    method: str = "simulation"
    resolution: float = 0.0
    gain: float = 0.0
    gains: np.ndarray = field(default_factory=lambda: np.zeros(0))
    stable: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=bool))
    measure: np.ndarray = field(default_factory=lambda: np.zeros(0))


def largest_stable_gain(model: OffsetResponseModel, resolution: float, method: str = "simulation", max_gain: float = 2.0,
                        delay_cycles: int = DELAY_CYCLES, duration: float = 10.0, reference: Any = None,
                        period_cycles: int | None = None) -> GainScan:
    """Scan ``K = resolution, 2 resolution, ...`` up to the first unstable gain, Cvitanic (2021), section 5.

    Parameters
    ----------
    model : OffsetResponseModel
        Response of the direction.
    resolution : float
        Grid step [-], > 0 (Table 14: 0.01 in y, 0.1 in x).
    method : str, optional
        ``"simulation"`` (:func:`simulate_loop` on the sine path) or ``"eigenvalues"``
        (:func:`spectral_radius`).
    max_gain : float, optional
        Largest gain tried [-] (at most 10000 grid steps).
    delay_cycles : int, optional
        Controller delay in cycles.
    duration : float, optional
        Simulated time [s] (method ``"simulation"``), at least two path periods.
    reference : array_like, optional
        Reference per cycle [m] (default :func:`sine_reference` over ``duration``).
    period_cycles : int, optional
        Window of the growth criterion [cycles] (default: the thesis' path period).

    Returns
    -------
    GainScan
        The grid result.

    Raises
    ------
    InputError
        Bad arguments, an unknown method, more than 10000 grid steps.
    """
    h = positive_float(resolution, "resolution")
    top = positive_float(max_gain, "max_gain")
    if method not in METHODS:
        raise InputError(f"method: expected one of {', '.join(METHODS)}, got {method!r}")
    n_grid = int(math.floor(top / h + 1e-9))
    if not 1 <= n_grid <= 10_000:
        raise InputError(f"resolution: expected 1 to 10000 grid steps up to max_gain = {top:g}, got {n_grid}")
    if method == "simulation":
        if reference is None:
            reference = sine_reference(int(round(positive_float(duration, "duration") / model.dt)), model.dt)
        r, w = _reference(model, reference, period_cycles)
        loop = _step_function(loop_plant(model, delay_cycles), r.size)
    gains, flags, measure = [], [], []
    for j in range(1, n_grid + 1):
        K = j * h
        if method == "simulation":
            sim = _simulate(loop, K, r, w)
            ok, value = sim.stable, sim.growth
        else:
            value = spectral_radius(model, K, delay_cycles)
            ok = value < 1.0 - POLE_MARGIN
        gains.append(K)
        flags.append(ok)
        measure.append(value)
        if not ok:
            break
    found = not flags[-1]
    gain = gains[-2] if found and len(gains) > 1 else (0.0 if found else gains[-1])
    status = Status.COMPLETED if found else Status.MAX_ITERATIONS
    msg = f"{method}: largest stable K = {gain:g} (resolution {h:g})" + ("" if found else f"; stable up to max_gain = {top:g}")
    return GainScan(status=status, message=msg, method=method, resolution=h, gain=float(gain), gains=np.array(gains),
                    stable=np.array(flags, dtype=bool), measure=np.array(measure))


def critical_gain(model: OffsetResponseModel, delay_cycles: int = DELAY_CYCLES, max_gain: float = 10.0, tol: float = 1e-5) -> float:
    """Gain at which the spectral radius of the closed loop reaches 1 (bisection), eq. (33).

    Assumes the loop is stable for small gains and loses stability once (checked on the
    bracket ends).

    Parameters
    ----------
    model : OffsetResponseModel
        Response of the direction.
    delay_cycles : int, optional
        Controller delay in cycles.
    max_gain : float, optional
        Upper end of the bracket [-].
    tol : float, optional
        Bracket width at the end [-].

    Returns
    -------
    float
        The critical gain [-] (``max_gain`` if the loop is stable there, 0 if unstable at ``tol``).

    Raises
    ------
    InputError
        Bad arguments.
    """
    return bisect_critical_gain(lambda K: spectral_radius(model, K, delay_cycles), max_gain, tol)


@dataclass
class CorrectionStudy(StatusResult):
    """Prediction of the largest stable gain at the validation poses against the richer simulation, section 5.

    Gains are arrays ``(n_validation, n_directions)`` (columns in :attr:`directions`).

    Parameters
    ----------
    status : Status
        Worst of the fits and scans (``"max_iterations"`` when a scan ran out of grid); keyword only.
    message : str
        Summary; keyword only.
    directions : tuple of str
        Corrected directions, e.g. ``("x", "y")``.
    resolutions : dict of str to float
        Gain grid step per direction [-].
    calibration_poses_deg : numpy.ndarray, shape (N, 2)
        ``(j2, j3)`` of the calibration poses [deg].
    validation_poses_deg : numpy.ndarray, shape (V, 2)
        ``(j2, j3)`` of the validation poses [deg].
    offset : float
        The single offset command of the calibration experiment [m].
    calibration_truth : list of dict
        Per calibration pose, the truth model per direction (:class:`OffsetResponseModel`).
    fits : list of dict
        Per calibration pose, the single-mode fit per direction (:class:`ModeFitResult`).
    predicted_models : list of dict
        Per validation pose, the GPR-predicted single-mode model per direction.
    truth_models : list of dict
        Per validation pose, the truth (two-mode) model per direction.
    predicted_gain : numpy.ndarray, shape (V, D)
        Largest stable gain of the predicted model, step-by-step simulation [-].
    simulated_gain : numpy.ndarray, shape (V, D)
        Largest stable gain of the richer simulation (truth), step-by-step simulation [-].
    predicted_gain_eigenvalues : numpy.ndarray, shape (V, D)
        The same as ``predicted_gain`` by the closed-loop poles (second method) [-].
    simulated_gain_eigenvalues : numpy.ndarray, shape (V, D)
        The same as ``simulated_gain`` by the closed-loop poles [-].
    predicted_critical_gain : numpy.ndarray, shape (V, D)
        Exact stability limit of the predicted model (bisection of the poles) [-].
    simulated_critical_gain : numpy.ndarray, shape (V, D)
        Exact stability limit of the truth [-].
    scans : dict
        ``(which, pose index, direction) -> GainScan`` with ``which`` in ``"predicted", "simulated"``
        (simulation method).
    """

    directions: tuple[str, ...] = ("x", "y")
    resolutions: dict[str, float] = field(default_factory=dict)
    calibration_poses_deg: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)))
    validation_poses_deg: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)))
    offset: float = 0.0
    calibration_truth: list[dict[str, OffsetResponseModel]] = field(default_factory=list)
    fits: list[dict[str, ModeFitResult]] = field(default_factory=list)
    predicted_models: list[dict[str, OffsetResponseModel]] = field(default_factory=list)
    truth_models: list[dict[str, OffsetResponseModel]] = field(default_factory=list)
    predicted_gain: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))
    simulated_gain: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))
    predicted_gain_eigenvalues: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))
    simulated_gain_eigenvalues: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))
    predicted_critical_gain: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))
    simulated_critical_gain: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))
    scans: dict[tuple[str, int, str], GainScan] = field(default_factory=dict)

    def within_one_increment(self) -> np.ndarray:
        """Per validation pose and direction: ``|predicted - simulated| <= resolution`` (Table 14's test).

        Returns
        -------
        numpy.ndarray, shape (V, D), bool
        """
        h = np.array([self.resolutions[d] for d in self.directions])
        return np.abs(self.predicted_gain - self.simulated_gain) <= h * (1 + 1e-9)


def correction_study(arm: SerialArm, calibration_poses_deg: Any = CALIBRATION_POSES_DEG, validation_poses_deg: Any = VALIDATION_POSES_DEG,
                     directions: tuple[str, ...] = ("x", "y"), resolutions: dict[str, float] | None = None, offset: float = 1e-4,
                     response_cycles: int = 250, delay_cycles: int = DELAY_CYCLES, duration: float = 10.0, max_gain: float = 2.0,
                     seed: int = 0, path: tuple[float, float, float] = (SINE_AMPLITUDE_M, FEED_RATE_M_S, SINE_SPATIAL_FREQUENCY_PER_M),
                     wrist_deg: Any = WRIST_JOINTS_DEG) -> CorrectionStudy:
    """Cvitanic (2021), section 5 end to end: truth, one-offset fits, GPR over ``(j2, j3)``, gains.

    1. At each calibration pose the truth (:func:`~gtmodel.estimation.closed_loop.correction.truth_model`)
       answers ONE offset command of ``offset``; one mode is fitted per direction
       (:func:`~gtmodel.estimation.closed_loop.correction.fit_offset_response`).
    2. A GPR over ``(j2, j3)`` (:func:`~gtmodel.estimation.closed_loop.correction.offset_response_gp`)
       predicts ``(m, c, k)`` at the validation poses.
    3. Per validation pose and direction, the largest stable gain of the predicted model
       (``predicted_gain``) and of the truth (``simulated_gain``), both by step-by-step
       simulation on the sine path and cross-checked by the closed-loop poles.

    Parameters
    ----------
    arm : SerialArm
        Arm of the truth's pose dependence; its joint limits are checked.
    calibration_poses_deg : array_like, shape (N, 2), optional
        ``(j2, j3)`` [deg], N >= 3 (default Table 12).
    validation_poses_deg : array_like, shape (V, 2), optional
        ``(j2, j3)`` [deg] (default Table 13).
    directions : tuple of str, optional
        Subset of ``"x", "y", "z"``.
    resolutions : dict of str to float, optional
        Gain step per direction (default :data:`DEFAULT_RESOLUTIONS`, z: 0.01).
    offset : float, optional
        The single offset command [m] (default 0.1 mm).
    response_cycles : int, optional
        Cycles of the recorded response to the offset (default 250 = 1 s).
    delay_cycles : int, optional
        Controller delay [cycles] (default 13).
    duration : float, optional
        Simulated time of each loop run [s] (default 10 s, about 4 path periods).
    max_gain : float, optional
        Largest gain scanned [-].
    seed : int, optional
        Seed of the GPR optimiser.
    path : tuple of float, optional
        Test path ``(amplitude [m], feed rate [m/s], spatial frequency [1/m])`` (default the thesis').
    wrist_deg : array_like, shape (4,), optional
        Joints 1, 4, 5, 6 of every pose [deg] (default :data:`~gtmodel.estimation.closed_loop.correction.WRIST_JOINTS_DEG`).

    Returns
    -------
    CorrectionStudy

    Raises
    ------
    InputError
        Bad poses (outside the joint limits: named), unknown directions, bad numbers.
    """
    with threadpool_limits(limits=1, user_api="blas"):  # 2x2..20x20 matrices: BLAS threads only cost (10x on a busy machine)
        return _study(arm, calibration_poses_deg, validation_poses_deg, directions, resolutions, offset, response_cycles, delay_cycles,
                      duration, max_gain, seed, path, wrist_deg)


def _study(arm: SerialArm, calibration_poses_deg: Any, validation_poses_deg: Any, directions: tuple[str, ...], resolutions: dict[str, float] | None,
           offset: float, response_cycles: int, delay_cycles: int, duration: float, max_gain: float, seed: int,
           path: tuple[float, float, float], wrist_deg: Any) -> CorrectionStudy:
    """The body of :func:`correction_study` (same arguments)."""
    dirs = tuple(directions)
    if not dirs or any(d not in DIRECTIONS for d in dirs) or len(set(dirs)) != len(dirs):
        raise InputError(f"directions: expected distinct entries of {DIRECTIONS}, got {directions!r}")
    res = {**DEFAULT_RESOLUTIONS, "z": 0.01, **(resolutions or {})}
    res = {d: positive_float(res[d], f"resolutions[{d!r}]") for d in dirs}
    offset = positive_float(offset, "offset")
    n_resp = positive_int(response_cycles, "response_cycles")
    calib = np.atleast_2d(np.asarray(calibration_poses_deg, dtype=float))
    valid = np.atleast_2d(np.asarray(validation_poses_deg, dtype=float))
    amplitude, feed, spatial = path
    n_sim = int(round(positive_float(duration, "duration") / CYCLE_TIME_S))
    reference = sine_reference(n_sim, CYCLE_TIME_S, amplitude, feed, spatial)
    window = int(round(path_period(feed, spatial) / CYCLE_TIME_S))
    cal_truth = truth_model(arm, calib, wrist_deg)
    fits = []
    for models in cal_truth:
        fits.append({d: fit_offset_response(models[d].offset_response(offset, n_resp)[1], offset, models[d].mass, models[d].dt) for d in DIRECTIONS})
    gp = offset_response_gp(calib, fits, seed=seed)
    pred = gp.predict(np.radians(valid))
    truth = truth_model(arm, valid, wrist_deg)
    predicted = [{d: OffsetResponseModel((pred["m"][v, i],), (pred["c"][v, i],), (pred["k"][v, i],), truth[v][d].mass, truth[v][d].dt)
                  for i, d in enumerate(DIRECTIONS)} for v in range(valid.shape[0])]
    shape = (valid.shape[0], len(dirs))
    out = {key: np.zeros(shape) for key in ("ps", "ss", "pe", "se", "pc", "sc")}
    scans: dict[tuple[str, int, str], GainScan] = {}
    statuses = [Status(f[d].status) for f in fits for d in DIRECTIONS]
    for v in range(valid.shape[0]):
        for j, d in enumerate(dirs):
            for which, model, ks, ke, kc in (("predicted", predicted[v][d], "ps", "pe", "pc"), ("simulated", truth[v][d], "ss", "se", "sc")):
                scan = largest_stable_gain(model, res[d], "simulation", max_gain, delay_cycles, reference=reference, period_cycles=window)
                eig = largest_stable_gain(model, res[d], "eigenvalues", max_gain, delay_cycles)
                scans[(which, v, d)] = scan
                statuses += [scan.status, eig.status]
                out[ks][v, j], out[ke][v, j] = scan.gain, eig.gain
                out[kc][v, j] = critical_gain(model, delay_cycles, max_gain)
    status = Status.worst(statuses)
    study = CorrectionStudy(status=status, message="", directions=dirs, resolutions=res, calibration_poses_deg=calib, validation_poses_deg=valid,
                            offset=offset, calibration_truth=cal_truth, fits=fits, predicted_models=predicted, truth_models=truth,
                            predicted_gain=out["ps"], simulated_gain=out["ss"], predicted_gain_eigenvalues=out["pe"],
                            simulated_gain_eigenvalues=out["se"], predicted_critical_gain=out["pc"], simulated_critical_gain=out["sc"], scans=scans)
    hits = study.within_one_increment().all(axis=1).sum()
    study.message = f"prediction within one gain increment of the richer simulation at {hits} of {valid.shape[0]} validation poses"
    _log.info("correction study: %s", study.message)
    return study
