"""Interrupts and progress of a running solve.

Solvers called through CasADi catch Ctrl-C themselves and return a failure status
(IPOPT's ``NonIpopt_Exception_Thrown``), which used to end a run as ``error``. Inside
:class:`InterruptGuard` a SIGINT or SIGTERM is recorded; :meth:`InterruptGuard.check`
turns it back into :class:`KeyboardInterrupt` once the solver has returned, so the whole
run stops with status ``interrupted`` (exit code 130), also inside a study.

:class:`Heartbeat` logs one line every few seconds while a long solve runs and nothing
else shows progress (output piped, or ``--quiet`` off a terminal).
"""

from __future__ import annotations

import logging
import signal
import threading
import time
from types import FrameType, TracebackType
from typing import Any

__all__ = ["InterruptGuard", "Heartbeat"]

_log = logging.getLogger("gtmodel")


class InterruptGuard:
    """Record SIGINT/SIGTERM while a run is in progress (main thread only; else a no-op).

    Examples
    --------
    >>> with InterruptGuard() as guard:          # doctest: +SKIP
    ...     result = solver()                     # Ctrl-C here is not swallowed
    ...     guard.check()                         # raises KeyboardInterrupt if it came
    """

    def __init__(self) -> None:
        self.interrupted = False
        self._previous: dict[int, Any] = {}

    def _handler(self, signum: int, frame: FrameType | None) -> None:
        self.interrupted = True
        raise KeyboardInterrupt(signal.Signals(signum).name)

    def __enter__(self) -> "InterruptGuard":
        if threading.current_thread() is threading.main_thread():
            for sig in (signal.SIGINT, signal.SIGTERM):
                self._previous[sig] = signal.signal(sig, self._handler)
        return self

    def __exit__(self, exc_type: type[BaseException] | None, exc: BaseException | None, tb: TracebackType | None) -> None:
        for sig, handler in self._previous.items():
            signal.signal(sig, handler)
        self._previous.clear()

    def check(self) -> None:
        """Raise :class:`KeyboardInterrupt` if a signal arrived since entering.

        Raises
        ------
        KeyboardInterrupt
            A SIGINT or SIGTERM was received (perhaps swallowed by a solver).
        """
        if self.interrupted:
            raise KeyboardInterrupt("interrupted by the user")


class Heartbeat:
    """Log ``"<label>: still running (N s)"`` every ``interval`` seconds until stopped.

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

    def _run(self) -> None:
        start = time.monotonic()
        while not self._stop.wait(self.interval):
            _log.info("%s: still running (%.0f s)", self.label, time.monotonic() - start)

    def __enter__(self) -> "Heartbeat":
        if self.enabled:
            self._thread = threading.Thread(target=self._run, name="gtmodel-heartbeat", daemon=True)
            self._thread.start()
        return self

    def __exit__(self, exc_type: type[BaseException] | None, exc: BaseException | None, tb: TracebackType | None) -> None:
        self._stop.set()
        if self._thread is not None:
            self._thread.join()
