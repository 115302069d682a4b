"""The loop-side studies a problem file declares, each with its ``solve``.

- :class:`StateEstimationDeclaration`: the laser tracker + IMU fusion study
  (:class:`~gtmodel.estimation.fusion_study.FusionStudy`, Cvitanic (2021), Tables 8-10);
- :class:`CorrectionStabilityDeclaration`: the largest stable gain of pose-offset
  corrections, predicted and simulated (:func:`~gtmodel.estimation.correction_loop.correction_study`,
  Cvitanic (2021), eqs. (30)-(33), Table 14).

Both are simulations: their results report ``completed`` (or ``error`` /
``max_iterations``), never ``optimal``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from gtmodel._docstrings import SHARED_DOCS, fill_doc
from gtmodel.estimation import CorrectionStudy, FusionStudy, FusionStudyResult, correction_study
from gtmodel.robots import SerialArm

__all__ = ["StateEstimationDeclaration", "CorrectionStabilityDeclaration"]


@dataclass(frozen=True)
class StateEstimationDeclaration:
    """A validated fusion study.

    Parameters
    ----------
    study : FusionStudy
        The study.
    """

    study: FusionStudy

    @fill_doc(**SHARED_DOCS)
    def solve(self, *, verbose: bool = False, previous: Any = None, warm_start: bool = False) -> FusionStudyResult:
        """Run the study.

        Parameters
        ----------
        {solve_args}

        Returns
        -------
        FusionStudyResult
            Status ``"completed"``, or ``"error"`` when a filter diverged (its row says which).
        """
        return self.study.run()


@dataclass(frozen=True)
class CorrectionStabilityDeclaration:
    """A validated correction-stability study (Cvitanic (2021), section 5).

    Parameters
    ----------
    arm : SerialArm
        The arm (joint limits checked on load).
    calibration_deg, validation_deg : array_like, shape (N, 2)
        ``(j2, j3)`` poses of the calibration and of the validation [deg].
    directions : tuple of str
        Corrected directions (``"x"``, ``"y"``, ...).
    resolutions : dict of str to float
        Gain step per corrected direction.
    offset : float
        Offset command of the calibration responses [m].
    response_cycles : int
        Samples of each calibration response.
    delay_cycles : int
        Cycles between command and execution.
    duration : float
        Simulated time of each loop run [s].
    max_gain : float
        Largest gain scanned.
    seed : int
        Seed of the calibration noise.
    path : tuple of float
        The sine offset path: amplitude [m], feed rate [m/s], spatial frequency [1/m].
    wrist_joints_deg : array_like
        Joints held fixed [deg].
    """

    arm: SerialArm
    calibration_deg: Any
    validation_deg: Any
    directions: tuple[str, ...]
    resolutions: dict[str, float]
    offset: float
    response_cycles: int
    delay_cycles: int
    duration: float
    max_gain: float
    seed: int
    path: tuple[float, float, float]
    wrist_joints_deg: Any

    @fill_doc(**SHARED_DOCS)
    def solve(self, *, verbose: bool = False, previous: Any = None, warm_start: bool = False) -> CorrectionStudy:
        """Run the study (:func:`~gtmodel.estimation.correction_loop.correction_study`).

        Parameters
        ----------
        {solve_args}

        Returns
        -------
        CorrectionStudy
            Status ``"completed"``, or ``"max_iterations"`` when a scan stayed stable up to
            ``max_gain``, or ``"error"`` when a fit did not converge.
        """
        return correction_study(
            self.arm, self.calibration_deg, self.validation_deg, self.directions, self.resolutions, self.offset,
            self.response_cycles, self.delay_cycles, self.duration, self.max_gain, self.seed, self.path, self.wrist_joints_deg,
        )
