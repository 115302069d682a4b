"""Tests marked ``realtime`` skip on a busy machine, saying why (:mod:`tests.robot_sim.realtime`)."""

from __future__ import annotations

import pytest

from ..robot_sim.realtime import skip_when_busy


@pytest.fixture(autouse=True)
def _realtime_needs_a_quiet_machine(request):
    skip_when_busy(request.node)
