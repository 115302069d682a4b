"""The registry of study analyses: ``analysis = "..."`` in a study file -> its :class:`StudyAnalysis`."""

from __future__ import annotations

from gtmodel.problems.study_analysis import StudyAnalysis

__all__ = ["ANALYSES"]

#: Analysis name -> the analysis (one instance each).
ANALYSES: dict[str, StudyAnalysis] = {cls.name: cls() for cls in (StudyAnalysis,)}
