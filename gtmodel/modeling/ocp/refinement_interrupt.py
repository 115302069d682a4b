"""Ctrl-C during a mesh refinement keeps the verified pass it had (issue 67).

:func:`keeps_verified_pass` wraps :func:`gtmodel.modeling.ocp.refinement.solve_refined`:
the refinement keeps its passes in lists made by :func:`recorded`, and when a signal
(SIGINT, SIGTERM: a :class:`KeyboardInterrupt`, or the ``NotImplementedError`` /
``SystemError`` CasADi turns one into) stops it between or inside passes, the last
verified pass is returned as its result instead of losing every pass. That pass goes
through the refinement's own choice and checks once more (the refinement called again
with it as ``start`` and one pass: no solve, its bounds verdict, its returned mark), and
its history is the interrupted run's (``refinement_stop``: ``"interrupted by the user
during pass N; returned pass k of M"``). Without a verified pass the signal goes on.

The caller still sees that a signal came (:func:`gtmodel._signals.received`): the
problem layer writes that pass with status ``interrupted``
(:class:`gtmodel.problems.run.InterruptedWithResult`, docs/reliability.md).
"""

from __future__ import annotations

import copy
import functools
import inspect
import logging
from contextvars import ContextVar
from typing import Any, Callable

from gtmodel import _signals
from gtmodel.status import Status

__all__ = ["keeps_verified_pass", "recorded"]

_log = logging.getLogger("gtmodel")
_RECORD: ContextVar[dict[str, list] | None] = ContextVar("gtmodel_refinement_record", default=None)


def recorded(name: str) -> list:
    """A new, empty list of a refinement's, readable by :func:`keeps_verified_pass` if the refinement is interrupted.

    Parameters
    ----------
    name : {"passes", "history"}
        Which list: the passes' results, or their history entries.

    Returns
    -------
    list
        An empty list (recorded when a :func:`keeps_verified_pass` call is running).
    """
    out: list = []
    record = _RECORD.get()
    if record is not None:
        record[name] = out
    return out


def _interrupted(exc: BaseException) -> bool:
    return isinstance(exc, KeyboardInterrupt) or (isinstance(exc, (NotImplementedError, SystemError)) and _signals.received())


def _silenced() -> logging.Filter:
    class _All(logging.Filter):
        def filter(self, record: logging.LogRecord) -> bool:
            return False

    return _All()


def keeps_verified_pass(func: Callable) -> Callable:
    """Decorator of ``solve_refined``: a signal during the refinement returns its last verified pass.

    Parameters
    ----------
    func : callable
        ``solve_refined`` (whose ``passes`` and ``history`` lists come from :func:`recorded`).

    Returns
    -------
    callable
        The refinement, returning the last verified pass (``optimal`` first, else
        ``acceptable``) when interrupted after one; re-raising the signal otherwise.
    """

    @functools.wraps(func)
    def wrapper(*args: Any, **kwargs: Any) -> Any:
        record: dict[str, list] = {}
        token = _RECORD.set(record)
        try:
            return func(*args, **kwargs)
        except (KeyboardInterrupt, NotImplementedError, SystemError) as exc:
            if not _interrupted(exc):
                raise
            passes, history = list(record.get("passes") or []), [dict(e) for e in record.get("history") or []]
            kept = next((r for status in (Status.OPTIMAL, Status.ACCEPTABLE) for r in reversed(passes)
                         if r.verification is not None and r.verification.passed and r.status == status), None)
            if kept is None:
                raise
            return _returned(func, args, kwargs, passes, history, kept)
        finally:
            _RECORD.reset(token)

    return wrapper


def _returned(func: Callable, args: tuple, kwargs: dict, passes: list, history: list, kept: Any) -> Any:
    """``kept`` through the refinement's own choice and checks (one pass, no solve), with the interrupted run's history."""
    bound = inspect.signature(func).bind(*args, **kwargs)
    bound.arguments["start"], bound.arguments["max_passes"] = kept, 1
    quiet = _silenced()
    _log.addFilter(quiet)
    try:
        with _signals.settled():  # stopping: a further signal is counted, the kept pass still returned
            result = func(*bound.args, **bound.kwargs)
    finally:
        _log.removeFilter(quiet)
    k = next(j for j, r in enumerate(passes) if r is kept) + 1  # by identity: passes may compare equal
    for j, entry in enumerate(history):
        entry.pop("returned", None)
        if j == k - 1:
            entry["returned"] = True
    result = copy.copy(result)
    result.refinement = history
    result.refinement_stop = f"interrupted by the user during pass {len(passes) + 1}; returned pass {k} of {len(passes)}"
    result.solve_time = float(sum(e.get("solve_time") or 0.0 for e in history))
    if result.verification is not None:
        result.verification = copy.copy(result.verification)
        result.verification.time_s = float(sum(e.get("verification_time", 0.0) for e in history))
        result.verification.cpu_s = float(sum(e.get("verification_cpu_time", 0.0) for e in history))
    _log.warning("mesh refinement of %s: %s (verified)", bound.arguments["optimization"].model.name, result.refinement_stop)
    return result
