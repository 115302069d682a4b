"""Fixtures shared by the tests of the optimal-control layer."""

from __future__ import annotations

import pytest


@pytest.fixture(scope="module")
def cache(tmp_path_factory):
    """A fresh cache of compiled libraries (``GTMODEL_CACHE_DIR``) with compilation on, for one test module."""
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("GTMODEL_CACHE_DIR", str(tmp_path_factory.mktemp("cache")))
        mp.delenv("GTMODEL_COMPILE", raising=False)
        yield


@pytest.fixture
def refinement_solves(monkeypatch):
    """The solver options of every collocation solve the refinement starts (a spy on its CollocationTranscription)."""
    from gtmodel.modeling.ocp import refinement

    seen: list[dict] = []
    real = refinement.CollocationTranscription

    def spy(*args, **kwargs):
        seen.append(dict(kwargs.get("solver_options") or {}))
        return real(*args, **kwargs)

    monkeypatch.setattr(refinement, "CollocationTranscription", spy)
    return seen
