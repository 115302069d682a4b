"""Automated calibration: from *a priori* parameters to accepted poses, a program and a calibration.

Dressler (2012), ch. 5.6, Fig. 5.21: the calibration workspace
(:class:`~gtmodel.calibration.automated.workspace.CalibrationWorkspace`), measurement poses
spread evenly over it, the acceptance of the pose set by eq. 5.14 per arm and by a simulated
calibration with the device's noise (:func:`~gtmodel.calibration.pose_selection.simulate_calibration`:
the mean calibrated parameters must lie within ``recovery_sigmas`` standard errors of the
truth), more poses (the desired count times ``growth``) when either fails, an
identifiability report per arm, the joint positions of the poses for the controller, and
the calibration from the measurements taken there (a measurement file, or synthetic
measurements of the truth with the device's noise at the accepted poses): the *a priori*
model calibrated on every second pose and validated on the others, as in the thesis.

Eq. 5.14 as printed, ``sigma_max^2 / sigma_min = sigma_max / cond(J) < C``, is not one
quantity (``sigma_max / cond(J)`` is ``sigma_min``). Two readings are offered
(``criterion``): ``"condition"`` (default), ``cond(J) = sigma_max / sigma_min < C`` of each
arm's closure Jacobian as it is (residuals in m^2): the thesis reports singular values
between 0.3 and 64 per arm with ``C = 200``, a ratio of this order, and the Table 5.7 set-up
here gives 0.5-56 (cond ~100); ``"noise_amplification"``, ``sigma_max^2 / sigma_min < C``
with unit-norm columns (:func:`~gtmodel.calibration.pose_selection.acceptance_value`, about
220-290 on the same poses, so ``C = 200`` rejects every set, more poses or not). Both values
are reported.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass, field

import numpy as np

from gtmodel.calibration.automated.workspace import CalibrationWorkspace, grid_constant
from gtmodel.calibration.evaluation import tcp_errors
from gtmodel.calibration.identifiability import IdentifiabilityReport, analyze_jacobian
from gtmodel.calibration.kinematic import CalibrationProblem, CalibrationResult, ParameterSelection, calibrate
from gtmodel.calibration.measurements import MeasurementSet
from gtmodel.calibration.pose_selection import SimulationResult, acceptance_value, simulate_calibration
from gtmodel.calibration.synthetic import DeviceNoise, synthetic_measurements
from gtmodel.robots.closure import ThreeLinkClosure
from gtmodel.status import Status

__all__ = ["AutomatedCalibrationDeclaration", "AutomatedCalibrationResult", "Round", "Calibrated"]

_log = logging.getLogger("gtmodel")


@dataclass
class Round:
    """One round of pose selection and acceptance.

    Parameters
    ----------
    desired : int
        Desired number of poses.
    grid_constant : float
        Grid spacing [m].
    T : numpy.ndarray, shape (N, 3)
        The poses [m] (a priori model).
    q : numpy.ndarray, shape (N, 3)
        Their joint positions [m].
    acceptance : list of float
        eq. 5.14 value per arm (the declared criterion).
    noise_amplification : list of float
        ``sigma_max^2 / sigma_min`` per arm with unit-norm columns.
    singular_values : list of tuple of float
        ``(min, max)`` singular value of each arm's unscaled Jacobian [m].
    accepted_5_14 : bool
    simulation : SimulationResult or None
    recovered : bool
        Every parameter's mean over the runs within ``recovery_sigmas`` standard errors of
        the truth, every run converged.
    worst_recovery : float
        ``max |mean - truth| / (predicted std / sqrt(runs))`` over the parameters.
    """

    desired: int
    grid_constant: float
    T: np.ndarray
    q: np.ndarray
    acceptance: list[float]
    noise_amplification: list[float]
    singular_values: list[tuple[float, float]]
    accepted_5_14: bool
    simulation: SimulationResult | None = None
    recovered: bool = False
    worst_recovery: float = math.inf

    @property
    def accepted(self) -> bool:
        """Both tests passed."""
        return self.accepted_5_14 and self.recovered


@dataclass
class Calibrated:
    """The calibration from the measurements at the poses (Dressler (2012), ch. 5.6, Fig. 5.26).

    Parameters
    ----------
    result : CalibrationResult
        The *a priori* model calibrated on every second measured pose.
    source : str
        ``"synthetic"`` (truth + device noise) or the measurement file.
    validation_errors : numpy.ndarray, shape (M,)
        ``||T_k - fk(q_k)||`` on the other poses [m] (eq. 5.5).
    true_errors : numpy.ndarray, shape (M,) or None
        Synthetic data: the calibrated model's distance from the true robot's TCP at the
        validation poses [m].
    parameter_errors : dict of str to float or None
        Synthetic data: calibrated minus true parameter.
    """

    result: CalibrationResult
    source: str
    validation_errors: np.ndarray
    true_errors: np.ndarray | None = None
    parameter_errors: dict[str, float] | None = None


@dataclass
class AutomatedCalibrationResult:
    """The result of an automated calibration.

    Parameters
    ----------
    status : str
        ``optimal`` when a pose set was accepted, ``check_failed`` when none was within
        the rounds, ``error`` when a calibration failed.
    message : str
    kinematic_points, remaining_points : int
        Grid points of the kinematic workspace and of what remains for calibration.
    removed : dict of str to int
        Points removed per step (``kinematic``, ``margin``, ``obstacles``, ``device``).
    search_step : float
        Grid step of the workspace search [m].
    rounds : list of Round
    identifiability : list of IdentifiabilityReport
        Per arm, for the last round's poses.
    workspace_points : numpy.ndarray, shape (M, 3)
        The remaining grid points [m].
    calibrated : Calibrated or None
        The calibration from the measurements (after an accepted round).
    """

    status: str
    message: str
    kinematic_points: int = 0
    remaining_points: int = 0
    removed: dict[str, int] = field(default_factory=dict)
    search_step: float = 0.0
    rounds: list[Round] = field(default_factory=list)
    identifiability: list[IdentifiabilityReport] = field(default_factory=list)
    workspace_points: np.ndarray | None = None
    calibrated: Calibrated | None = None

    @property
    def workspace_ratio(self) -> float:
        """Remaining / kinematic workspace (thesis: 0.4)."""
        return self.remaining_points / self.kinematic_points if self.kinematic_points else 0.0

    @property
    def final(self) -> Round:
        """The last round."""
        return self.rounds[-1]


@dataclass(frozen=True)
class AutomatedCalibrationDeclaration:
    """An automated calibration (Dressler (2012), Fig. 5.21).

    Parameters
    ----------
    workspace : CalibrationWorkspace
        The tests of the *a priori* model.
    apriori : ThreeLinkClosure
        The *a priori* model (the calibration's start).
    truth : ThreeLinkClosure
        The robot of the simulated calibration.
    search_step : float
        Grid step of the workspace search [m].
    desired : int
        Desired number of poses.
    threshold : float
        ``C`` of eq. 5.14.
    noise_sigma : float
        Device noise per coordinate [m].
    runs : int
        Simulated calibrations.
    recovery_sigmas : float
        A parameter is recovered when the mean over the runs is within this many standard
        errors (the std each calibration reports, over ``sqrt(runs)``) of the truth.
    growth : float
        Factor on the desired count after a rejected round.
    max_rounds : int
        Rounds before giving up.
    seed : int
        Noise seed.
    criterion : str
        ``"condition"`` or ``"noise_amplification"`` (module docstring).
    measurements : MeasurementSet or None
        Measurements taken at the poses (None: synthetic ones of ``truth``).
    """

    workspace: CalibrationWorkspace
    apriori: ThreeLinkClosure
    truth: ThreeLinkClosure
    search_step: float = 0.1
    desired: int = 100
    threshold: float = 200.0
    noise_sigma: float = 1.7e-3
    runs: int = 5
    recovery_sigmas: float = 4.0
    growth: float = 1.5
    max_rounds: int = 4
    seed: int = 0
    criterion: str = "condition"
    measurements: MeasurementSet | None = None

    def calibrate(self, q: np.ndarray) -> Calibrated:
        """Calibrate the *a priori* model on every second pose, validate on the others.

        Parameters
        ----------
        q : numpy.ndarray, shape (N, 3)
            The accepted poses' joint positions [m] (used for synthetic measurements).

        Returns
        -------
        Calibrated
        """
        if self.measurements is not None:
            q_m, T_m, source = self.measurements.q, self.measurements.T, self.measurements.source
        else:
            data = synthetic_measurements(self.truth, q, noise=DeviceNoise(self.noise_sigma, 0.0, "device"), seed=self.seed + 1)
            q_m, T_m, source = data.q, data.T, "synthetic"
        fit, val = np.arange(0, q_m.shape[0], 2), np.arange(1, q_m.shape[0], 2)
        res = calibrate(self.apriori, q_m[fit], T_m[fit])
        errors = tcp_errors(res.model, q_m[val], T_m[val])
        out = Calibrated(res, source, errors)
        if self.measurements is None:
            T_true = np.atleast_2d(self.truth.fk(q_m[val])[0])
            out.true_errors = np.linalg.norm(np.atleast_2d(res.model.fk(q_m[val])[0]) - T_true, axis=1)
            out.parameter_errors = {n: float(v - t) for n, v, t in zip(res.model.parameter_names(), res.model.parameter_vector(),
                                                                       self.truth.parameter_vector())}
        return out

    def arm_jacobians(self, q: np.ndarray, T: np.ndarray) -> list[tuple[np.ndarray, tuple[str, ...]]]:
        """The closure Jacobian of each arm with respect to its parameters (a priori model).

        Parameters
        ----------
        q : numpy.ndarray, shape (N, 3)
            Joint positions [m].
        T : numpy.ndarray, shape (N, 3)
            TCP positions [m].

        Returns
        -------
        list of (numpy.ndarray, tuple of str)
            Per arm: ``(N, 7)`` Jacobian [m] and the parameter names.
        """
        problem = CalibrationProblem(self.apriori, ParameterSelection())
        _, J, names = problem.jacobian(self.apriori.parameter_vector(), q, T)
        out = []
        for arm in range(3):
            idx = self.apriori.arm_parameter_indices(arm)
            out.append((J[:, arm, idx], tuple(names[i] for i in idx)))
        return out

    def _round(self, desired: int, volume: float, verbose: bool) -> Round:
        h = grid_constant(volume, desired)
        G = self.workspace.grid(h)
        ok, _ = self.workspace.admissible(G)
        T = G[ok]
        q = self.workspace.kinematics.ik(T)
        jac = self.arm_jacobians(q, T)
        amplification = [acceptance_value(J) for J, _ in jac]
        sv = []
        for J, _ in jac:
            s = np.linalg.svd(J, compute_uv=False)
            sv.append((float(s[-1]), float(s[0])))
        values = [hi / lo if lo > 0 else math.inf for lo, hi in sv] if self.criterion == "condition" else amplification
        rnd = Round(desired, h, T, q, values, amplification, sv, all(v < self.threshold for v in values))
        _log.log(logging.INFO if verbose else logging.DEBUG, "automated calibration: %d desired, h = %.4f m, %d poses, eq. 5.14 %s",
                 desired, h, T.shape[0], ", ".join(f"{v:.3g}" for v in values))
        if T.shape[0] >= 8:
            sim = simulate_calibration(self.truth, self.apriori, q, self.noise_sigma, self.runs, self.seed)
            rnd.simulation = sim
            standard_error = np.maximum(sim.predicted_std / math.sqrt(self.runs), 1e-15)
            ratio = np.abs(sim.parameter_bias) / standard_error
            rnd.worst_recovery = float(ratio.max())
            rnd.recovered = bool(np.all(ratio <= self.recovery_sigmas) and all(Status(s).success for s in sim.statuses))
        return rnd

    def solve(self, verbose: bool = False, previous: object = None, warm_start: bool = False) -> AutomatedCalibrationResult:
        """Search the workspace, choose and check poses until accepted, report identifiability.

        Parameters
        ----------
        verbose : bool, optional
            Log the rounds at INFO.
        previous : object, optional
            Unused.
        warm_start : bool, optional
            Unused.

        Returns
        -------
        AutomatedCalibrationResult
        """
        ws = self.workspace
        P = ws.grid(self.search_step)
        kin_ok = ws.kinematic(P)
        ok, removed = ws.admissible(P)
        res = AutomatedCalibrationResult(Status.OPTIMAL.value, "", int(kin_ok.sum()), int(ok.sum()), removed, self.search_step,
                                         workspace_points=P[ok])
        if not ok.any():
            res.status = Status.INFEASIBLE.value
            res.message = "no grid point remains for calibration (obstacles, margin or the device remove the whole workspace)"
            return res
        volume = ok.sum() * self.search_step**3
        desired = self.desired
        for _ in range(self.max_rounds):
            rnd = self._round(desired, volume, verbose)
            res.rounds.append(rnd)
            if rnd.accepted:
                break
            desired = int(math.ceil(desired * self.growth))
        final = res.final
        for arm, (J, names) in enumerate(self.arm_jacobians(final.q, final.T)):
            res.identifiability.append(analyze_jacobian(J, names))
        if not final.accepted:
            res.status = Status.CHECK_FAILED.value
            res.message = (f"no pose set accepted in {len(res.rounds)} rounds: eq. 5.14 {['%.3g' % v for v in final.acceptance]} "
                           f"(C = {self.threshold:g}), worst parameter bias {final.worst_recovery:.3g} standard errors")
        else:
            res.calibrated = self.calibrate(final.q)
            cal = res.calibrated.result
            if not Status(cal.status).success:
                res.status = Status(cal.status).value
            res.message = (f"{final.T.shape[0]} poses ({final.desired} desired, h = {final.grid_constant:.4f} m), "
                           f"workspace ratio {res.workspace_ratio:.2f}, eq. 5.14 max {max(final.acceptance):.3g} < {self.threshold:g}; "
                           f"calibrated ({res.calibrated.source}): validation error mean {res.calibrated.validation_errors.mean() * 1e3:.2f} mm")
        return res
