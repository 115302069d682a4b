"""The notes a loop check's summary carries about its controller (``gtmodel.problems.loop_notes``).

Independent: the figures each note must carry, written here from the controller's own fields.
"""

from __future__ import annotations

import re
from types import SimpleNamespace

import numpy as np
import pytest

from gtmodel.control.lqr import RestLinearization
from gtmodel.problems.loop_notes import controller_notes


def _law(**fields):
    base = dict(lead=0, u_initial=np.array([0.0]), gain_scale=None, rest=None)
    return SimpleNamespace(**{**base, **fields})


NOTES = [
    (dict(), []),
    (dict(lead=1, u_initial=np.array([2.5e-12, 3.0])), [r"^reference: 1 period\(s\) at rest before the plan, held by the input 0, 3 "]),
    (dict(gain_scale=np.array([[1.0], [0.5], [0.25]])), [r"^the law's gain limited in 2 of 3 periods .*smallest factor 0.25\)"]),
    (dict(rest=RestLinearization(np.eye(1), np.eye(1), radius_own=1.31, radius=0.953, moved="load.v - 0.357")),
     [r"^the held end's gain designed on the model linearised at the end with load.v - 0.357: .* radius of 1.31 within 0.1 .*, "
      r"this one 0.953$"]),
    (dict(rest=RestLinearization(np.eye(1), np.eye(1), radius_own=0.9, radius=0.9)), []),
]


@pytest.mark.parametrize("fields, patterns", NOTES, ids=["plain", "lead", "gain_limit", "rest_moved", "rest_own"])
def test_each_departure_is_noted_with_its_figures(fields, patterns):
    notes = controller_notes(_law(**fields))
    assert len(notes) == len(patterns) and all(re.search(p, n) for p, n in zip(patterns, notes)), notes
