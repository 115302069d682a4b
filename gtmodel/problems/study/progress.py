"""Progress of a study: a rich progress bar on a terminal, log lines when piped, or nothing.

On a terminal (standard error is a TTY) a :mod:`rich` bar shows cases done, failed and
the ETA (from the first finished case on: a local cluster forks its workers before any
thread of the bar writes to the terminal); otherwise one ``gtmodel`` log line is written every ``every`` cases or every
``interval`` seconds, whichever comes first; ``mode="off"`` (tests, library use) is
silent.
"""

from __future__ import annotations

import logging
import sys
import time
from types import TracebackType
from typing import Literal

from rich.console import Console
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn, TimeRemainingColumn

from gtmodel.status import Status

__all__ = ["StudyProgress", "progress_mode"]

_log = logging.getLogger("gtmodel")


def progress_mode(enabled: bool) -> Literal["off", "rich", "log"]:
    """``"rich"`` on a terminal, ``"log"`` when standard error is piped, ``"off"`` if not enabled.

    Parameters
    ----------
    enabled : bool
        Whether to show progress at all.

    Returns
    -------
    str
    """
    if not enabled:
        return "off"
    return "rich" if sys.stderr.isatty() else "log"


class StudyProgress:
    """Count finished cases and show them.

    Parameters
    ----------
    name : str
        The study name.
    total : int
        Cases to run now (the skipped finished ones excluded).
    mode : {"off", "rich", "log"}, optional
        See :func:`progress_mode`.
    every : int, optional
        Log a line every this many cases (default: 5 % of ``total``, at least 1).
    interval : float, optional
        ... or after this many seconds [s] (default 10).
    """

    def __init__(self, name: str, total: int, mode: Literal["off", "rich", "log"] = "off", every: int | None = None,
                 interval: float = 10.0) -> None:
        self.name = name
        self.total = total
        self.mode = mode
        self.every = every or max(1, total // 20)
        self.interval = interval
        self.done = 0
        self.failed = 0
        self._start = time.monotonic()
        self._last_log = self._start
        self._last_count = 0
        self._bar: Progress | None = None
        self._task = None

    def __enter__(self) -> "StudyProgress":
        self._start = self._last_log = time.monotonic()
        return self

    def _start_bar(self) -> None:
        # started at the first finished case, not before: the local cluster forks its workers
        # first, while no thread of the bar writes to the terminal
        frozen: list[float] = [self._start]  # the task's clock starts with the study, not with the bar

        def now() -> float:
            return frozen[0] if frozen else time.monotonic()

        self._bar = Progress(
            TextColumn("{task.description}"), BarColumn(), MofNCompleteColumn(),
            TextColumn("failed {task.fields[failed]}"), TimeElapsedColumn(), TextColumn("ETA"), TimeRemainingColumn(),
            console=Console(stderr=True), get_time=now,
        )
        self._task = self._bar.add_task(self.name, total=self.total, failed=0)
        frozen.clear()
        self._bar.__enter__()

    def __exit__(self, exc_type: type[BaseException] | None, exc: BaseException | None, tb: TracebackType | None) -> None:
        if self._bar is not None:
            self._bar.__exit__(exc_type, exc, tb)
            self._bar = None

    def update(self, status: Status) -> None:
        """Count one finished case.

        Parameters
        ----------
        status : Status
            Its status (anything but optimal/converged counts as failed).
        """
        self.done += 1
        self.failed += 0 if Status(status).success else 1
        if self.mode == "rich" and self._bar is None:
            self._start_bar()
        if self._bar is not None and self._task is not None:
            self._bar.update(self._task, completed=self.done, failed=self.failed)
        elif self.mode == "log":
            now = time.monotonic()
            if self.done - self._last_count >= self.every or now - self._last_log >= self.interval or self.done == self.total:
                elapsed = now - self._start
                eta = elapsed / self.done * (self.total - self.done)
                _log.info("%s: %d/%d cases done, %d failed, %.0f s elapsed, ETA %.0f s", self.name, self.done, self.total,
                          self.failed, elapsed, eta)
                self._last_log, self._last_count = now, self.done
