"""Field overrides of a problem document: a sweep never adds a field; a command-line setting may, the schema judges it.

Reference: the document before and after, written out by hand.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from gtmodel.errors import ProblemError
from gtmodel.problems.overrides import apply_override

DOC = {"kind": "robot_loop", "interface": {"type": "rsi"}, "parameters": {"w": 1.0}}


@pytest.mark.parametrize("field, value, create, expected", [
    ("w", 2.0, False, {**DOC, "parameters": {"w": 2.0}}),
    ("interface.type", "egm", False, {**DOC, "interface": {"type": "egm"}}),
    ("interface.listen", "0.0.0.0:1", True, {**DOC, "interface": {"type": "rsi", "listen": "0.0.0.0:1"}}),
    ("faults.fallback", "ramp", True, {**DOC, "faults": {"fallback": "ramp"}}),
])
def test_override_sets_the_field(field, value, create, expected):
    assert apply_override(DOC, field, value, Path("f.toml"), create=create) == expected
    assert DOC["interface"] == {"type": "rsi"}  # the input is not modified


@pytest.mark.parametrize("field, create, match", [
    ("interface.listen", False, r"cannot sweep 'interface.listen': the field is not in the file"),
    ("faults.fallback", False, r"cannot sweep 'faults.fallback': no table 'faults'"),
    ("kind.listen", True, r"cannot set 'kind.listen': 'kind' is not a table"),
])
def test_override_refuses(field, create, match):
    with pytest.raises(ProblemError, match=match):
        apply_override(DOC, field, 1, Path("f.toml"), create=create)
