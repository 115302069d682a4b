"""An ILC experiment as declared by a problem file: the experiment, its cases, and their results.

Dressler (2012), section 7.3: :class:`ILCDeclaration` holds the
:class:`~gtmodel.estimation.ILCExperiment` (plant, reference, learning law, estimators)
and the cases; :meth:`ILCDeclaration.solve` first runs the lifted check (7.15), (7.16) that
each case requires (eigenvalues and singular values of the lifted matrices: seconds to
minutes, so not at load), stops with the case's error before any trial if one fails, then
runs every case and gives an :class:`ILCOutcome` (the worst case status is its status).
"""

from __future__ import annotations

import logging
import time
from dataclasses import dataclass
from typing import Any, Callable

import numpy as np
from threadpoolctl import threadpool_limits

from gtmodel._docstrings import SHARED_DOCS, fill_doc
from gtmodel.errors import GtModelError, InputError
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
    final_time : float
        Duration of the square motion (without lead-in/out) [s].
    estimator_comparison : dict, optional
        The tool-position estimators compared on the uncorrected trial (RMS of the
        estimation error per estimator, the Kalman filters' tuning), when computed.
    rounds : int, optional
        Rounds of the square in the reference (the thesis: 2).
    fail : callable, optional
        ``fail(field, expected, got) -> GtModelError``: the error of a case whose required
        check fails, for its field ``cases[i].require`` (a problem file's
        :meth:`~gtmodel.problems.base.ProblemFile.fail`, naming the file); default an
        :class:`~gtmodel.errors.InputError` naming the field.
    """

    experiment: ILCExperiment
    cases: list[ILCCase]
    final_time: float
    estimator_comparison: dict[str, Any] | None = None
    rounds: int = 1
    fail: Callable[[str, str, Any], GtModelError] | None = None

    @property
    def checks(self) -> dict[str, Any]:
        """Per case name, per channel the lifted check (:class:`~gtmodel.estimation.ILCStability`), computed on first use.

        Dressler (2012), eqs. 7.15-7.16. The same figures as :meth:`check_requirements`,
        without raising for a case that fails what it requires.
        """
        return {case.name: self.experiment.check(case) for case in self.cases}

    def check_requirements(self) -> dict[str, Any]:
        """The lifted check of every case (7.15), (7.16); an error for the first case that fails what it requires.

        Dressler (2012), eqs. 7.15 (stable: spectral radius ``rho < 1``) and 7.16 (monotone:
        largest singular value ``sigma_max < 1``) of ``Q (I - L T)`` per channel.

        Returns
        -------
        dict
            Per case name, per channel the :class:`~gtmodel.estimation.ILCStability`.

        Raises
        ------
        GtModelError
            From :attr:`fail` for the field ``cases[i].require``: the case, the channel and
            the figure, and what to change.
        """
        checks: dict[str, Any] = {}
        for i, case in enumerate(self.cases):
            checks[case.name] = self.experiment.check(case)
            if case.require == "none":
                continue
            key = "monotone" if case.require == "monotone" else "stable"
            figure = "sigma_max" if key == "monotone" else "rho"
            bad = {ch: getattr(r, figure) for ch, r in checks[case.name].items() if not getattr(r, key)}
            if bad:
                ch, value = next(iter(bad.items()))
                eq = "7.16" if key == "monotone" else "7.15"
                args = (f"cases[{i}].require", f"a {key} design ({figure} < 1, Dressler (2012) eq. {eq}) for case {case.name!r}",
                        f"{figure} = {value:.4g} on channel {ch}; lower gamma or the Q cut-off, or require = \"none\"")
                raise self.fail(*args) if self.fail is not None else InputError(f"{args[0]}: expected {args[1]}, got {args[2]}")
        return checks

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

        Raises
        ------
        GtModelError
            A case's design fails the check it requires (:meth:`check_requirements`),
            before any trial is simulated.
        """
        t0 = time.perf_counter()
        results = {}
        with threadpool_limits(limits=1, user_api="blas"):  # small products: BLAS threads cost 10-20x CPU on a busy machine
            self.check_requirements()
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
