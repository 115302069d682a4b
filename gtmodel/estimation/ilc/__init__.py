"""Iterative learning control of the 4 ms loop (Dressler (2012), ch. 7).

* :mod:`~gtmodel.estimation.ilc.iteration`: the trial-to-trial loop, the error measure and
  the learned correction table;
* :mod:`~gtmodel.estimation.ilc.lifted`: the lifted-system operators, the Q and learning
  filters and the stability checks;
* :mod:`~gtmodel.estimation.ilc.experiment`: the ILC experiment of section 7.3 on the
  simulated closed-loop L1;
* :mod:`~gtmodel.estimation.ilc.thesis`: the thesis' Table 7.2 figures, read from the reference data.
"""

from __future__ import annotations

from gtmodel.estimation.ilc.iteration import ILCResult, error_measure, ilc_correction_function, next_correction, run_ilc
from gtmodel.estimation.ilc.lifted import ILCStability, LearningFilter, QFilter, RobustQFilter, lifted_matrix, stability, time_window
from gtmodel.estimation.ilc.thesis import thesis_table_7_2
from gtmodel.estimation.ilc.experiment import Q_DESIGNS, REQUIREMENTS, SIGNALS, ILCCase, ILCCaseResult, ILCExperiment, ILCReference

__all__ = [
    "error_measure",
    "ILCResult",
    "run_ilc",
    "next_correction",
    "ilc_correction_function",
    "lifted_matrix",
    "time_window",
    "QFilter",
    "RobustQFilter",
    "LearningFilter",
    "ILCStability",
    "stability",
    "SIGNALS",
    "REQUIREMENTS",
    "Q_DESIGNS",
    "ILCCase",
    "ILCReference",
    "ILCCaseResult",
    "ILCExperiment",
    "thesis_table_7_2",
]
