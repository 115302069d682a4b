"""The ``realtime`` marker's rule: on a machine loaded over its cores the real-time counts skip, saying why."""

from __future__ import annotations

import os

import pytest

from .realtime import busy_reason


@pytest.mark.parametrize("load, cores, busy", [(0.5, 2, False), (2.0, 2, False), (2.5, 2, True), (15.0, 2, True), (15.0, 16, False)])
def test_busy_is_a_load_over_the_cores(monkeypatch, load, cores, busy):
    monkeypatch.delenv("GTMODEL_REALTIME_TESTS", raising=False)
    monkeypatch.setattr(os, "getloadavg", lambda: (load, load, load))
    monkeypatch.setattr(os, "cpu_count", lambda: cores)
    reason = busy_reason()
    assert (reason is not None) == busy
    assert reason is None or (f"load {load:.1f} on {cores} cores" in reason and "pytest -m realtime" in reason)


def test_realtime_tests_are_out_of_the_default_run():
    """Independent: the marker expression of pyproject.toml's addopts, read as text."""
    import tomllib
    from pathlib import Path

    opts = tomllib.loads((Path(__file__).resolve().parents[2] / "pyproject.toml").read_text())["tool"]["pytest"]["ini_options"]
    assert "not realtime" in opts["addopts"] and any(m.startswith("realtime:") for m in opts["markers"])


def test_always_runs_them_whatever_the_load(monkeypatch):
    monkeypatch.setattr(os, "getloadavg", lambda: (50.0, 50.0, 50.0))
    monkeypatch.setenv("GTMODEL_REALTIME_TESTS", "always")
    assert busy_reason() is None
