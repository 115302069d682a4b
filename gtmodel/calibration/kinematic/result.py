"""Results of a kinematic calibration: one per group of arms, one for the whole model."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from gtmodel.calibration.identifiability import IdentifiabilityReport
from gtmodel.robots.closure import ClosureModel
from gtmodel.status import Status, StatusResult

__all__ = ["GroupResult", "CalibrationResult"]


@dataclass
class GroupResult(StatusResult):
    """Result of one group of arms (one NLP).

    Parameters
    ----------
    arms : tuple of int
        Arm indices (0-based) solved together.
    variable_names : tuple of str
        Names of the NLP variables (free parameters; ``<quaternion>_rx/ry/rz`` for the
        local rotation of a quaternion parameter).
    status : Status
        ``optimal``, ``acceptable``, ``max_iterations``, ``infeasible`` or ``error``; a
        group without variables (all its parameters fixed: nothing to fit) is
        ``optimal`` with the message ``"no free parameters"``.
    message : str
        Solver message.
    iterations : int
        Iterations (Jacobian evaluations for least_squares, IPOPT iterations).
    initial_cost : float
        ``V`` of the group at the start [m^4].
    cost : float
        ``V`` of the group at the solution [m^4].
    sigma : float
        Residual standard deviation ``sqrt(RSS / (m - n))`` [m^2].
    n_residuals : int
        Number of residuals (links x poses with non-zero weight).
    identifiability : IdentifiabilityReport
        Report at the solution (variables of the group; empty for a group without
        variables).
    """

    arms: tuple[int, ...]
    variable_names: tuple[str, ...]
    iterations: int
    initial_cost: float
    cost: float
    sigma: float
    n_residuals: int
    identifiability: IdentifiabilityReport


@dataclass
class CalibrationResult(StatusResult):
    """Result of a kinematic calibration (python-control style: status, never None).

    Parameters
    ----------
    status : Status
        Worst group status (:meth:`~gtmodel.status.Status.worst`): ``optimal``,
        ``acceptable``, ``max_iterations``, ``infeasible`` or ``error``.
    message : str
        Per-group solver messages.
    model : ClosureModel
        The calibrated model (in the measurement frame), ``aligned.with_parameters(p)``.
    parameters : dict of str to float
        Calibrated parameters (SI units).
    initial_parameters : dict of str to float
        Start values in the measurement frame (after alignment and ties).
    std : dict of str to float
        Standard deviation of each parameter (0 for fixed ones; ``inf`` if not
        identifiable at the solution or without residual degrees of freedom, ``m = n``).
    cost : float
        ``V`` at the solution (eq. 5.2) [m^4].
    cost_per_arm : numpy.ndarray, shape (n_arms,)
        ``V`` of each arm at the solution [m^4].
    initial_cost_per_arm : numpy.ndarray, shape (n_arms,)
        ``V`` of each arm at the start [m^4].
    iterations : int
        Iterations summed over the groups.
    solve_time : float
        Wall time of the solves [s] (without building the CasADi functions).
    build_time : float
        Wall time spent building CasADi functions and solvers in this call [s] (0 when
        re-used).
    identifiability : IdentifiabilityReport
        Identifiability of all free variables at the solution (block-diagonal Jacobian
        of the groups; standard deviations per group).
    groups : tuple of GroupResult
        One entry per NLP.
    rotation : numpy.ndarray, shape (3, 3)
        Rotation of the frame alignment (identity without alignment).
    translation : numpy.ndarray, shape (3,)
        Translation of the frame alignment [m].
    quaternion_norms : dict of str to float
        Norm of each quaternion parameter after the solve (1 to round-off).
    residuals : numpy.ndarray, shape (N, n_links)
        Weighted closure residuals at the solution [m^2], links in model order.
    solver : str
        Solver used.
    n_poses : int
        Number of poses.
    """

    model: ClosureModel
    parameters: dict[str, float]
    initial_parameters: dict[str, float]
    std: dict[str, float]
    cost: float
    cost_per_arm: np.ndarray
    initial_cost_per_arm: np.ndarray
    iterations: int
    solve_time: float
    build_time: float
    identifiability: IdentifiabilityReport
    groups: tuple[GroupResult, ...]
    rotation: np.ndarray
    translation: np.ndarray
    quaternion_norms: dict[str, float]
    residuals: np.ndarray
    solver: str
    n_poses: int

    @property
    def success(self) -> bool:
        """True if every group ended ``optimal`` or ``acceptable`` (a least-squares fit
        stopped at the "acceptable" level is still a calibration to use)."""
        return self.status in (Status.OPTIMAL, Status.ACCEPTABLE)

    @property
    def parameter_vector(self) -> np.ndarray:
        """Calibrated parameters in model order (``model.parameter_vector()``)."""
        return np.array(list(self.parameters.values()))

    def summary(self) -> str:
        """A short text summary: status, cost per arm, iterations, times.

        Returns
        -------
        str
        """
        arms = ", ".join(f"arm {i + 1}: {c:.3g}" for i, c in enumerate(self.cost_per_arm))
        return (
            f"calibration {self.status} ({self.solver}, {self.n_poses} poses): V = {self.cost:.4g} m^4 ({arms}); "
            f"{self.iterations} iterations, solve {1e3 * self.solve_time:.1f} ms, build {1e3 * self.build_time:.1f} ms"
        )
