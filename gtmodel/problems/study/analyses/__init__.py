"""The registry of study analyses: ``analysis = "..."`` in a study file -> its :class:`StudyAnalysis`.

- ``generic``: the table of cases only (:class:`~gtmodel.problems.study.analysis.StudyAnalysis`);
- ``calibration_monte_carlo``: coverage of the predicted parameter deviations over seeds,
  accuracy against the number of poses (:mod:`.calibration_monte_carlo`);
- ``time_optimal_map``: minimum time over a grid of end positions (:mod:`.time_optimal_map`);
- ``sweep``: the kind's columns against the swept field (:mod:`.sweep`).
"""

from __future__ import annotations

from gtmodel.problems.study.analyses.calibration_monte_carlo import CalibrationMonteCarlo
from gtmodel.problems.study.analyses.sweep import Sweep
from gtmodel.problems.study.analyses.time_optimal_map import TimeOptimalMap
from gtmodel.problems.study.analysis import StudyAnalysis

__all__ = ["ANALYSES"]

#: Analysis name -> the analysis (one instance each).
ANALYSES: dict[str, StudyAnalysis] = {cls.name: cls() for cls in (StudyAnalysis, CalibrationMonteCarlo, TimeOptimalMap, Sweep)}
