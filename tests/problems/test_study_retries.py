"""Bounded retries of a case whose worker dies: Dask's own (``allowed-failures``), then a
row with status ``internal_error``, never a hung or lost study.

Independent reference: a model file that kills the process importing it (``os._exit``),
so every worker that runs the case dies; the local cluster's nanny replaces it.
"""

from __future__ import annotations

import pytest

from gtmodel.problems import study_engine
from gtmodel.problems.study_engine import run_study

from ..conftest import PROBLEMS_DIR
from .study_fixtures import write_study


@pytest.mark.slow  # about 30 s: a local cluster and worker restarts
def test_a_case_that_kills_every_worker_is_a_row_after_bounded_retries(tmp_path, monkeypatch):
    """Dask reschedules it after its worker died, at most ALLOWED_FAILURES times (here 1);
    then the case is an internal_error row and the study ends (exit 3), nothing hangs."""
    monkeypatch.setattr(study_engine, "ALLOWED_FAILURES", 1)
    (tmp_path / "crash.py").write_text("import os\nos._exit(1)  # a model file that kills the process loading it\n")
    model = (PROBLEMS_DIR / "cart_pendulum_swing_up.toml").read_text()
    assert 'file = "../models/cart_pendulum.py"' in model
    study = write_study(tmp_path, "")
    (tmp_path / "pendulum.toml").write_text(model.replace('"../models/cart_pendulum.py"', '"crash.py"'))
    study.write_text('base = "pendulum.toml"\nplots = false\n[design]\n[[design.axes]]\nfield = "model.file"\nvalues = ["crash.py"]\n')
    outcome = run_study(study, tmp_path / "out", workers=2)
    assert outcome.table["status"].tolist() == ["internal_error"]
    assert "worker died 1 times" in outcome.table["message"][0]
    assert outcome.exit_code == 3
