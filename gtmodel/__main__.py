"""``python -m gtmodel`` and the ``gtmodel`` command: signals first, then the command.

SIGINT and SIGTERM are handled (:mod:`gtmodel._signals`) before anything else of gtmodel
is imported, so an interrupt during start-up, like one at any later moment, ends the run
with status ``interrupted`` and exit code 130, or 143 when the first signal was SIGTERM
(:func:`gtmodel._signals.process_exit_code`, ``docs/reliability.md``). Only a signal in
the first milliseconds, while Python itself starts, ends the process by the signal
(like SIGKILL: the earlier result folder is left as it was).
"""

from __future__ import annotations

import atexit
import os
import signal
import sys

from gtmodel import _signals

__all__ = ["main", "exit_now", "run"]


def main() -> int:
    """Run the ``gtmodel`` command with the interrupt handling installed first.

    Returns
    -------
    int
        The exit code (:data:`gtmodel.status.EXIT_CODES`; interrupted: 130 for SIGINT, 143
        for SIGTERM).
    """
    _signals.install()
    try:
        with _signals.protected():  # a signal while the command loads is raised once the run can handle it
            from gtmodel.cli import main as cli_main
        code = cli_main()
    except KeyboardInterrupt:  # before the command could handle it (e.g. during argument parsing)
        print("gtmodel: interrupted", file=sys.stderr)
        code = 130
    for sig in _signals.SIGNALS:  # the run has ended and reported: its outcome stands
        signal.signal(sig, signal.SIG_IGN)
    return _signals.process_exit_code(code)


def exit_now(code: int) -> None:
    """End the process with ``code`` once the run has reported: exit handlers, then ``os._exit``.

    The exit handlers (:mod:`atexit`, ``weakref.finalize``: temporary folders, logging, a
    local cluster) run here, in the open, with the signals ignored; the interpreter's own
    teardown is skipped. That teardown ended about one run in eight by SIGINT (exit -2)
    after a correct ``interrupted`` summary, when two or three signals had come
    (``tests/test_faults.py``), so the process's code was not the run's.

    Parameters
    ----------
    code : int
        The exit code (:func:`main`'s).
    """
    try:
        atexit._run_exitfuncs()
    finally:
        for stream in (sys.stdout, sys.stderr):
            try:
                stream.flush()
            except (OSError, ValueError):  # a closed or broken pipe: nothing more can be said there
                pass
        os._exit(code)


def run() -> None:
    """The ``gtmodel`` command and ``python -m gtmodel``: :func:`main`, then :func:`exit_now`."""
    exit_now(main())


if __name__ == "__main__":
    run()
