"""The correction-stability study a problem file declares, with its ``solve``.

:class:`CorrectionStabilityDeclaration`: the largest stable gain of pose-offset
corrections, predicted and simulated (:func:`~gtmodel.estimation.closed_loop.correction_loop.correction_study`,
Cvitanic (2021), eqs. (30)-(33), Table 14). A simulation: its result reports ``completed``
(or ``error`` / ``max_iterations``), never ``optimal``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from gtmodel._docstrings import SHARED_DOCS, fill_doc
from gtmodel.estimation.closed_loop.correction_loop import CorrectionStudy, correction_study
from gtmodel.robots import SerialArm

__all__ = ["CorrectionStabilityDeclaration"]


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
        """Run the study (:func:`~gtmodel.estimation.closed_loop.correction_loop.correction_study`).

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
