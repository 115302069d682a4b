"""The state-estimation study a problem file declares, with its ``solve``.

:class:`StateEstimationDeclaration`: the laser tracker + IMU fusion study
(:class:`~gtmodel.estimation.fusion.study.FusionStudy`, Cvitanic (2021), Tables 8-10). A
simulation: its result reports ``completed`` (or ``error``), never ``optimal``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from gtmodel._docstrings import SHARED_DOCS, fill_doc
from gtmodel.estimation.fusion.study import FusionStudy, FusionStudyResult

__all__ = ["StateEstimationDeclaration"]


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
