"""SIGINT and SIGTERM, one way for the whole process (the ``gtmodel`` command and library runs).

The ``gtmodel`` command installs :func:`handler` as the first thing it does
(``gtmodel/__main__.py``, before anything heavy is imported), so every SIGINT or SIGTERM
of a run is counted. Whether a signal raises :class:`KeyboardInterrupt` where it lands
depends on the section the process is in:

- inside :func:`interruptible` (the work: imports, loading, solving, writing data files)
  the *first* signal raises at once; a signal that came earlier, outside, raises when the
  section is entered;
- inside :func:`protected` (the few steps that must not be cut: renaming a result folder
  into place, writing the summary of a failed run) a signal is only counted, and raised
  when the protected section ends (if it is the first one and the work is interruptible);
- inside :func:`settled` (writing what an interrupted run leaves) a signal is only
  counted, never raised;
- every later signal (a second Ctrl-C while the run is already stopping) is only counted:
  it never cuts the clean-up short, so repeated Ctrl-C still ends with status
  ``interrupted`` and exit code 130.

:func:`received` tells whether any signal came (solvers called through CasADi swallow the
:class:`KeyboardInterrupt`; :class:`gtmodel.problems.runtime.InterruptGuard` checks it
afterwards). Only the main thread handles signals; elsewhere the helpers are no-ops.
"""

from __future__ import annotations

import signal
import threading
from contextlib import contextmanager
from types import FrameType
from typing import Any, Iterator

__all__ = ["SIGNALS", "SIGNAL_EXIT_CODES", "handler", "install", "restore", "installed", "received", "reset", "interruptible", "protected",
           "settled", "raise_if_pending", "process_exit_code"]

#: The signals that stop a run (status ``interrupted``; the process exits 130 for SIGINT, 143 for SIGTERM).
SIGNALS = (signal.SIGINT, signal.SIGTERM)
#: Exit code of a run the first signal stopped, by signal: 128 + its number, as a shell reports a process the signal ended.
SIGNAL_EXIT_CODES = {signal.SIGINT.name: 128 + signal.SIGINT, signal.SIGTERM.name: 128 + signal.SIGTERM}


class _State:
    count = 0  # signals received since the last reset
    raised = False  # a KeyboardInterrupt was raised for them
    interruptible = 0  # depth of interruptible sections
    protected = 0  # depth of protected sections
    name = ""  # the first signal's name


_state = _State()


def _main_thread() -> bool:
    return threading.current_thread() is threading.main_thread()


def handler(signum: int, frame: FrameType | None) -> None:
    """The signal handler: count the signal; raise for the first one where that is allowed.

    Parameters
    ----------
    signum : int
        The signal number (SIGINT or SIGTERM).
    frame : frame or None
        The interrupted frame (unused).

    Raises
    ------
    KeyboardInterrupt
        For the first signal, inside an :func:`interruptible` section and outside a
        :func:`protected` one.
    """
    _state.count += 1
    if _state.count == 1:
        _state.name = signal.Signals(signum).name
    raise_if_pending()


def raise_if_pending() -> None:
    """Raise :class:`KeyboardInterrupt` for a signal that came and was not raised yet.

    Only inside an :func:`interruptible` section and outside any :func:`protected` one;
    elsewhere (and when the signal was already raised) nothing happens.

    Raises
    ------
    KeyboardInterrupt
        A signal came and was not raised yet.
    """
    if _state.count and not _state.raised and _state.interruptible > 0 and _state.protected == 0:
        _state.raised = True
        raise KeyboardInterrupt(_state.name or "interrupted")


def installed() -> bool:
    """Whether :func:`handler` handles SIGINT and SIGTERM now.

    Returns
    -------
    bool
    """
    return all(signal.getsignal(s) is handler for s in SIGNALS)


def install() -> dict[int, Any] | None:
    """Install :func:`handler` for SIGINT and SIGTERM (main thread only).

    A SIGINT ignored by the parent (a shell's background job) is handled too: a signal
    sent to gtmodel on purpose always stops the run cleanly. If the handler is already
    installed nothing changes (the count is kept: a signal during start-up still counts).

    Returns
    -------
    dict or None
        The previous handlers (for :func:`restore`), or None when nothing was installed
        (not the main thread, or already installed).
    """
    if not _main_thread() or installed():
        return None
    reset()
    return {s: signal.signal(s, handler) for s in SIGNALS}


def restore(previous: dict[int, Any] | None) -> None:
    """Put back the handlers :func:`install` replaced.

    Parameters
    ----------
    previous : dict or None
        What :func:`install` returned (None: nothing to do).
    """
    for sig, old in (previous or {}).items():
        signal.signal(sig, old if old is not None else signal.SIG_DFL)


def reset() -> None:
    """Forget the signals received so far (a new run in the same process)."""
    _state.count = 0
    _state.raised = False
    _state.name = ""


def received() -> bool:
    """Whether a SIGINT or SIGTERM came since the last :func:`reset`.

    Returns
    -------
    bool
    """
    return _state.count > 0


def process_exit_code(code: int) -> int:
    """The exit code of the process for a run that returned ``code``.

    A run stopped by a signal returns 130 (:data:`gtmodel.status.EXIT_CODES`, status
    ``interrupted``); the process then exits with the code of the *first* signal received
    (:data:`SIGNAL_EXIT_CODES`: 130 for SIGINT, 143 for SIGTERM), as a shell or a job
    scheduler expects. Any other code (a run that finished before the signal) stands.

    Parameters
    ----------
    code : int
        The code the command returned.

    Returns
    -------
    int
    """
    if code == SIGNAL_EXIT_CODES[signal.SIGINT.name] and _state.count:
        return SIGNAL_EXIT_CODES.get(_state.name, code)
    return code


@contextmanager
def interruptible() -> Iterator[None]:
    """A section where the first signal raises :class:`KeyboardInterrupt` at once.

    Raises
    ------
    KeyboardInterrupt
        On entry, for a signal that came before and was not raised yet; inside, for the
        first signal.
    """
    _state.interruptible += 1
    try:
        raise_if_pending()
        yield
    finally:
        _state.interruptible -= 1


@contextmanager
def protected() -> Iterator[None]:
    """A section that a signal does not cut: it is counted and raised at the end.

    Raises
    ------
    KeyboardInterrupt
        At the end, for a first signal that came inside (within an interruptible section).
    """
    _state.protected += 1
    try:
        yield
    finally:
        _state.protected -= 1
    raise_if_pending()


@contextmanager
def settled() -> Iterator[None]:
    """A section that ends a run (writing what an interrupted or finished run leaves).

    Signals inside are only counted, and nothing is raised for them afterwards either: the
    run's outcome is being written and stands.
    """
    _state.protected += 1
    try:
        yield
    finally:
        _state.protected -= 1
        if _state.count:
            _state.raised = True
