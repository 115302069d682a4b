"""An ILC experiment as declared by a problem file: the experiment, its cases, and their results.

Dressler (2012), section 7.3: :class:`ILCDeclaration` holds the
:class:`~gtmodel.estimation.ILCExperiment` (plant, reference, learning law, estimators)
and the cases checked at load (7.15), (7.16); :meth:`ILCDeclaration.solve` runs every
case and gives an :class:`ILCOutcome` (the worst case status is its status).
"""

from __future__ import annotations

import logging
import time
from dataclasses import dataclass
from typing import Any

import numpy as np
from threadpoolctl import threadpool_limits

from gtmodel._docstrings import SHARED_DOCS, fill_doc
from gtmodel.estimation.ilc.experiment import ILCCase, ILCCaseResult, ILCExperiment
from gtmodel.status import Status

__all__ = ["ILCDeclaration", "ILCOutcome"]

_log = logging.getLogger("gtmodel")


@dataclass
class ILCDeclaration:
    """A validated ILC experiment.

    Parameters
    ----------
    experiment : ILCExperiment
        Plant, reference, learning law and estimators.
    cases : list of ILCCase
        The cases, in file order.
    checks : dict
        Per case name the lifted check computed at load (7.15), (7.16).
    final_time : float
        Duration of the square motion (without lead-in/out) [s].
    estimator_comparison : dict, optional
        The tool-position estimators compared on the uncorrected trial (RMS of the
        estimation error per estimator, the Kalman filters' tuning), when computed.
    rounds : int, optional
        Rounds of the square in the reference (the thesis: 2).
    """

    experiment: ILCExperiment
    cases: list[ILCCase]
    checks: dict[str, Any]
    final_time: float
    estimator_comparison: dict[str, Any] | None = None
    rounds: int = 1

    @fill_doc(**SHARED_DOCS)
    def solve(self, *, verbose: bool = False, previous: Any = None, warm_start: bool = False) -> "ILCOutcome":
        """Run every case's ILC iterations (Dressler (2012), eqs. 7.2-7.16).

        Parameters
        ----------
        {solve_args}

        Returns
        -------
        ILCOutcome
            One result per case, each with its status.
        """
        t0 = time.perf_counter()
        results = {}
        with threadpool_limits(limits=1, user_api="blas"):  # small products: BLAS threads cost 10-20x CPU on a busy machine
            for case in self.cases:
                results[case.name] = self.experiment.run(case)
                if verbose:
                    r = results[case.name]
                    _log.info("ILC case %s: %s, tool error x/y relative %s", case.name, r.status,
                              np.round(r.relative("tool")[:2], 4).tolist())
        return ILCOutcome(results, time.perf_counter() - t0)


@dataclass
class ILCOutcome:
    """Results of the ILC cases.

    Parameters
    ----------
    results : dict of str to ILCCaseResult
        Per case name.
    solve_time : float
        Wall time [s].
    """

    results: dict[str, ILCCaseResult]
    solve_time: float

    @property
    def status(self) -> Status:
        """Worst status of the cases."""
        return Status.worst(Status(r.status) for r in self.results.values())
