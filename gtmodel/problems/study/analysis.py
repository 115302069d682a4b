"""What a study computes from its table of cases: the :class:`StudyAnalysis` interface.

A study (``gtmodel study STUDY.toml``) solves many cases of one problem file and collects
one row per case in a tidy table (design values, status, the kind's summary fields). Its
``analysis`` (a field of the study file) adds two things on top of that machinery:

- :meth:`StudyAnalysis.row`: extra per-case columns, computed from one case's
  ``summary.json`` (so a resumed study rebuilds them from the folders alone);
- :meth:`StudyAnalysis.analyse`: study-level figures for the study's ``summary.json`` and
  its plots, computed from the whole table.

The analyses are registered in :data:`gtmodel.problems.study.analyses.ANALYSES`.
"""

from __future__ import annotations

from abc import ABC
from pathlib import Path
from typing import Any, ClassVar, Mapping

import pandas as pd

__all__ = ["StudyAnalysis"]


class StudyAnalysis(ABC):
    """The per-study-type part of a study: extra columns, study figures and plots.

    The generic analysis (this class as is) adds nothing: the table holds the design
    values, the status and the kind's scalar summary fields.

    Attributes
    ----------
    name : str
        The value of ``analysis = "..."`` in a study file.
    description : str
        One line for the documentation.
    """

    name: ClassVar[str] = "generic"
    description: ClassVar[str] = "the table of cases only"

    def row(self, summary: Mapping[str, Any]) -> dict[str, Any]:
        """Extra table columns of one case.

        Parameters
        ----------
        summary : Mapping[str, Any]
            The case's ``summary.json`` (any status; a failed case has only the failure
            fields).

        Returns
        -------
        dict
            Column name -> scalar (float, int, str, bool or None); the same keys for
            every case of a study (None where a case has no value).
        """
        return {}

    def analyse(self, table: pd.DataFrame, out: Path, plots: bool) -> tuple[dict[str, Any], list[str]]:
        """Study-level figures and plots.

        Parameters
        ----------
        table : pandas.DataFrame
            One row per case (design columns, ``case``, ``key``, ``status``, the kind's
            summary fields and :meth:`row`'s columns).
        out : pathlib.Path
            The study folder (plots are written here).
        plots : bool
            Whether to write PNG plots.

        Returns
        -------
        figures : dict
            JSON-serialisable figures merged into the study's ``summary.json`` under
            ``"analysis"``.
        files : list of str
            Names of the files written into ``out``.
        """
        return {}, []
