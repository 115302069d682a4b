"""The position-interface controllers as C: generated through the front door, checked against their Functions.

Reference: the CasADi Functions of :mod:`gtmodel.control.position_loop` evaluated from Python
(the check harness compares the compiled step on random inputs and probes the step contract:
NaN measurement, NULL pointers, a glitch in the memory).
"""

from __future__ import annotations

import numpy as np
import pytest

from gtmodel.codegen import check_code
from gtmodel.codegen.loop_step import LOOP_KIND, position_step
from gtmodel.control.position_loop import PoseCorrection, ReferenceStreaming
from gtmodel.errors import InputError

CONTROLLERS = {
    "correction": lambda: PoseCorrection(gain=[0.1, 0.05, 0.0], limit=[5.0, 5.0, 5.0]),
    "streaming": lambda: ReferenceStreaming(np.cumsum(np.full((60, 3), 0.05), axis=0), 0.01 * np.ones((60, 3))),
}


@pytest.mark.parametrize("name", sorted(CONTROLLERS))
def test_position_step_passes_the_code_check(name, tmp_path):
    step = position_step(CONTROLLERS[name](), name)
    generated = step.generate(tmp_path, prefix=f"gt_{name}")
    assert generated.kind == LOOP_KIND
    check = check_code(generated, n=300)
    assert check.passed, check.status


def test_position_step_refuses_another_controller():
    with pytest.raises(InputError, match="controller: expected a PoseCorrection or a ReferenceStreaming"):
        position_step(object())
