"""The rule of the tests marked ``realtime``: they count replies made in real time, so they run on a quiet machine only.

They are left out of the default run (``pyproject.toml``: ``-m 'not slow and not realtime'``);
``python -m pytest -m realtime -n 0`` runs them (``.ci/run``, a step of its own). On a machine
whose load (the 1-minute average, ``os.getloadavg``) is over its number of cores they skip,
saying so: a count of on-time replies measures the machine then, not the code.
``GTMODEL_REALTIME_TESTS=always`` runs them whatever the load (to measure a busy machine).
"""

from __future__ import annotations

import os

import pytest

__all__ = ["busy_reason", "skip_when_busy"]


def busy_reason() -> str | None:
    """Why this machine is too busy for real-time counts, or None when it is quiet enough.

    Returns
    -------
    str or None
        The load and the cores, when the 1-minute load average exceeds the number of cores
        (None whatever the load with ``GTMODEL_REALTIME_TESTS=always``).
    """
    if os.environ.get("GTMODEL_REALTIME_TESTS") == "always":
        return None
    try:
        load = os.getloadavg()[0]
    except OSError:  # no load average (not a Unix): nothing to judge by
        return None
    cores = os.cpu_count() or 1
    if load > cores:
        return (f"a busy machine (1-minute load {load:.1f} on {cores} cores): the real-time counts of this test measure the load, "
                "not the code; run `python -m pytest -m realtime -n 0` on a quiet machine (.ci/run does)")
    return None


def skip_when_busy(item: pytest.Item) -> None:
    """Skip a test marked ``realtime`` on a busy machine, with the reason.

    Parameters
    ----------
    item : pytest.Item
        The test about to run.
    """
    if item.get_closest_marker("realtime") is not None:
        reason = busy_reason()
        if reason:
            pytest.skip(reason)
