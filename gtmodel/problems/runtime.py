"""Interrupts and progress of a running solve.

Solvers called through CasADi catch Ctrl-C themselves and return a failure status
(IPOPT's ``NonIpopt_Exception_Thrown``), which used to end a run as ``error``. Inside
:class:`InterruptGuard` (on :mod:`gtmodel._signals`) a SIGINT or SIGTERM is recorded;
:meth:`InterruptGuard.check` turns it back into :class:`KeyboardInterrupt` once the solver has returned, so the whole
run stops with status ``interrupted`` (exit code 130), also inside a study.

:class:`Heartbeat` logs one line every few seconds while a long solve runs and nothing
else shows progress (output piped, or ``--quiet`` off a terminal); it keeps quiet while the
run says something itself (e.g. ``gtmodel loop``'s serving lines, issue 67).
"""

from __future__ import annotations

import logging
import threading
import time
from types import TracebackType
from typing import Any

from gtmodel import _signals

__all__ = ["InterruptGuard", "Heartbeat"]

_log = logging.getLogger("gtmodel")


class InterruptGuard:
    """An interruptible section of a run: SIGINT/SIGTERM raise, and are remembered.

    The handler is :func:`gtmodel._signals.handler` (installed here if the ``gtmodel``
    command has not installed it already, and put back afterwards): the first signal
    raises :class:`KeyboardInterrupt`, later ones are only counted, and :meth:`check`
    raises again for a signal a solver swallowed. Main thread only; elsewhere a no-op.

    Examples
    --------
    >>> with InterruptGuard() as guard:          # doctest: +SKIP
    ...     result = solver()                     # Ctrl-C here is not swallowed
    ...     guard.check()                         # raises KeyboardInterrupt if it came
    """

    def __init__(self) -> None:
        self._previous: dict[int, Any] | None = None
        self._section: Any = None

    @property
    def interrupted(self) -> bool:
        """Whether a SIGINT or SIGTERM came (since the handler was installed)."""
        return _signals.received()

    def __enter__(self) -> "InterruptGuard":
        self._previous = _signals.install()
        self._section = _signals.interruptible()
        try:
            self._section.__enter__()
        except BaseException:
            _signals.restore(self._previous)
            raise
        return self

    def __exit__(self, exc_type: type[BaseException] | None, exc: BaseException | None, tb: TracebackType | None) -> None:
        try:
            self._section.__exit__(exc_type, exc, tb)
        finally:
            _signals.restore(self._previous)
            self._previous = None

    def check(self) -> None:
        """Raise :class:`KeyboardInterrupt` if a signal arrived since entering.

        Raises
        ------
        KeyboardInterrupt
            A SIGINT or SIGTERM was received (perhaps swallowed by a solver).
        """
        if _signals.received():
            raise KeyboardInterrupt("interrupted by the user")


class Heartbeat:
    """Log ``"<label>: still running (N s)"`` every ``interval`` seconds until stopped.

    A line is left out when another line went to the ``gtmodel`` logger within the last
    1.5 intervals (the run shows its own progress then, e.g. the loop's ``serving`` lines).

    Parameters
    ----------
    label : str
        What is running, e.g. ``"solving l1_time_optimal (point_to_point)"``.
    interval : float, optional
        Seconds between lines (default 5).
    enabled : bool, optional
        False makes it a no-op (e.g. when the solver's own log is shown).
    """

    def __init__(self, label: str, interval: float = 5.0, enabled: bool = True) -> None:
        self.label = label
        self.interval = interval
        self.enabled = enabled
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self._last_other = -float("inf")  # time.monotonic() of the last line that was not this heartbeat's

    def _seen(self, record: logging.LogRecord) -> bool:
        # a filter of the gtmodel logger while running: notes when anything else was said
        if self._thread is None or record.thread != self._thread.ident:
            self._last_other = time.monotonic()
        return True

    def _run(self) -> None:
        start = time.monotonic()
        while not self._stop.wait(self.interval):
            if time.monotonic() - self._last_other >= 1.5 * self.interval:
                _log.info("%s: still running (%.0f s)", self.label, time.monotonic() - start)

    def __enter__(self) -> "Heartbeat":
        if self.enabled:
            _log.addFilter(self._seen)
            self._thread = threading.Thread(target=self._run, name="gtmodel-heartbeat", daemon=True)
            self._thread.start()
        return self

    def __exit__(self, exc_type: type[BaseException] | None, exc: BaseException | None, tb: TracebackType | None) -> None:
        self._stop.set()
        if self._thread is not None:
            self._thread.join()
            _log.removeFilter(self._seen)
