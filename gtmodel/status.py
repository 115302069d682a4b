"""One solver status for every result, its ranking, and its process exit code.

Every solver result of gtmodel (optimal control, path-constrained motion, calibration,
identification, stiffness, elasto-geometric calibration) carries a :class:`Status` and
implements the :class:`SolverResult` protocol (``success``, ``status``, ``message``). A
study, or a calibration with several groups, reports the worst of its statuses
(:meth:`Status.worst`); the ``gtmodel`` command exits with :meth:`Status.exit_code`:

=================  ====  ===================================================
status             exit  meaning
=================  ====  ===================================================
``optimal``        0     solved to the requested tolerance
``converged``      0     an iterative estimate met its stopping rule
``completed``      0     a simulation or filter run ended normally (no optimisation)
``acceptable``     1     solved to the solver's looser "acceptable" level
``check_failed``   1     solved, but the result's own check failed (its verification
                         against an independent simulation, or a self-check it
                         states); the ``checks``/``verification`` block says which
``max_iterations`` 1     stopped at the iteration or time limit
``infeasible``     1     the solver proved (locally) that no solution exists
``error``          1     the solver failed (numerical failure, exception)
``invalid_input``  2     bad input: file, field, argument, degenerate data
``internal_error`` 3     a defect of gtmodel (please report it)
``interrupted``    130   stopped by the user (Ctrl-C, SIGINT or SIGTERM); the ``gtmodel``
                         process exits 143 when the first signal was SIGTERM
                         (:func:`gtmodel._signals.process_exit_code`)
=================  ====  ===================================================
"""

from __future__ import annotations

import enum
from dataclasses import dataclass
from typing import Iterable, Protocol, runtime_checkable

__all__ = ["Status", "SolverResult", "StatusResult", "EXIT_CODES", "exit_code_table"]


class Status(enum.StrEnum):
    """Outcome of a solve; a ``str`` (``Status.OPTIMAL == "optimal"``), ranked best first.

    Examples
    --------
    >>> Status.worst(["optimal", "acceptable"])
    <Status.ACCEPTABLE: 'acceptable'>
    >>> Status("infeasible").exit_code
    1
    """

    OPTIMAL = "optimal"
    CONVERGED = "converged"
    COMPLETED = "completed"
    ACCEPTABLE = "acceptable"
    CHECK_FAILED = "check_failed"
    MAX_ITERATIONS = "max_iterations"
    INFEASIBLE = "infeasible"
    ERROR = "error"
    INVALID_INPUT = "invalid_input"
    INTERNAL_ERROR = "internal_error"
    INTERRUPTED = "interrupted"

    @property
    def rank(self) -> int:
        """Position in the ranking, 0 for the best (``optimal``)."""
        return _ORDER.index(self)

    @property
    def success(self) -> bool:
        """True for ``optimal``, ``converged`` and ``completed``: a result to rely on."""
        return self in (Status.OPTIMAL, Status.CONVERGED, Status.COMPLETED)

    @property
    def exit_code(self) -> int:
        """Exit code of the ``gtmodel`` command for this status (see the module table)."""
        return EXIT_CODES[self]

    @classmethod
    def worst(cls, statuses: Iterable[str]) -> "Status":
        """The worst of several statuses (``optimal`` for none).

        Parameters
        ----------
        statuses : iterable of Status or str
            Statuses, e.g. of the groups of a calibration or the cases of a study.

        Returns
        -------
        Status

        Raises
        ------
        ValueError
            A string that is not a status.
        """
        ranked = [cls(s) for s in statuses]
        return max(ranked, key=lambda s: s.rank, default=cls.OPTIMAL)


_ORDER = tuple(Status)

#: Exit code of the ``gtmodel`` command per status.
EXIT_CODES: dict[Status, int] = {
    Status.OPTIMAL: 0,
    Status.CONVERGED: 0,
    Status.COMPLETED: 0,
    Status.ACCEPTABLE: 1,
    Status.CHECK_FAILED: 1,
    Status.MAX_ITERATIONS: 1,
    Status.INFEASIBLE: 1,
    Status.ERROR: 1,
    Status.INVALID_INPUT: 2,
    Status.INTERNAL_ERROR: 3,
    Status.INTERRUPTED: 130,
}


def exit_code_table() -> str:
    """The status -> exit code table as plain text (printed by ``gtmodel --help``).

    Returns
    -------
    str
        One line per status.
    """
    return "\n".join(f"  {code:>3}  {status.value}" for status, code in EXIT_CODES.items())


@runtime_checkable
class SolverResult(Protocol):
    """What every solver result offers: ``success``, ``status`` and ``message``."""

    @property
    def success(self) -> bool:  # pragma: no cover - protocol
        ...

    status: Status
    message: str


@dataclass(kw_only=True)
class StatusResult:
    """Base of result dataclasses: a :class:`Status`, the solver's message, ``success``.

    Parameters
    ----------
    status : Status
        The outcome (a plain string is converted).
    message : str, optional
        The solver's own words (e.g. IPOPT's return status).
    """

    status: Status
    message: str = ""

    def __post_init__(self) -> None:
        self.status = Status(self.status)

    @property
    def success(self) -> bool:
        """True when :attr:`status` is ``optimal``, ``converged`` or ``completed``."""
        return self.status.success
