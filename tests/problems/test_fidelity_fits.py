"""``python -m gtmodel.problems.fidelity_fits`` reproduces ``docs/fidelity_fits.json`` (the fits the fidelity page renders).

Independent reference: the stored file, written by the same command; recomputed here (slow, a few minutes).
"""

from __future__ import annotations

import json

import pytest

from gtmodel.problems import fidelity_fits as run_fits
from gtmodel.report.fidelity_fits import FITS


@pytest.fixture(scope="module")
def stored():
    return json.loads(FITS.read_text(encoding="utf-8"))


@pytest.mark.slow
def test_the_command_reproduces_the_stored_fits(stored):
    # python -m gtmodel.problems.fidelity_fits (a few minutes): the same fit and predictions as docs/fidelity_fits.json
    got, want = _flat(run_fits.compute()), _flat(stored)
    assert {k: v for k, v in got.items() if isinstance(v, float)} == pytest.approx({k: v for k, v in want.items() if isinstance(v, float)}, rel=1e-6, abs=1e-6)
    assert {k: v for k, v in got.items() if not isinstance(v, float)} == {k: v for k, v in want.items() if not isinstance(v, float)}


def _flat(d, prefix=""):
    out = {}
    for k, v in d.items():
        if isinstance(v, list):
            v = {str(i): x for i, x in enumerate(v)}
        if isinstance(v, dict):
            out.update(_flat(v, f"{prefix}{k}."))
        elif isinstance(v, (int, float)) and not isinstance(v, bool):
            out[prefix + k] = float(v)
        else:
            out[prefix + k] = v
    return out
