"""The fault schedule: its text syntax, its errors, reproducible rates."""

from __future__ import annotations

import pytest

from gtmodel.errors import InputError
from gtmodel.robot_sim.faults import FaultRule, FaultSchedule, parse_faults

VALID = {
    "loss:rate=0.5": [FaultRule("loss", rate=0.5)],
    "delay:cycles=3-5,ms=9": [FaultRule("delay", 3, 5, delay_ms=9.0)],
    "ipoc_jump:at=7,by=3; stop:at=20": [FaultRule("ipoc_jump", 7, 7, jump=3), FaultRule("stop", 20, 20)],
    " ": [],
}


@pytest.mark.parametrize("spec", sorted(VALID))
def test_spec_parses(spec):
    assert parse_faults(spec) == VALID[spec]


INVALID = ["bogus:at=1", "loss", "loss:rate=2", "loss:cycles=5-2", "loss:at=1,rate=0.1", "stop:rate=0.1", "delay:at=1,ms=-3",
           "loss:at=x", "loss:when=3", "stop:at=1;stop:at=2", "loss:rate=nan"]


@pytest.mark.parametrize("spec", INVALID)
def test_bad_spec_is_an_input_error(spec):
    with pytest.raises(InputError):
        FaultSchedule.from_spec(spec)


def _hits(spec: str, seed: int, n: int = 200) -> list[tuple[int, tuple[str, ...]]]:
    s = FaultSchedule.from_spec(spec, seed)
    return [(k, tuple(sorted(s.at(k)))) for k in range(n)]


def test_rates_are_reproducible_and_independent_of_other_entries():
    a = [k for k, kinds in _hits("loss:rate=0.2", 4) if "loss" in kinds]
    b = [k for k, kinds in _hits("loss:rate=0.2;garbage:rate=0.5", 4) if "loss" in kinds]
    assert a == b and 15 < len(a) < 65


def test_ranges_and_stop():
    hits = dict(_hits("nan:cycles=2-3;stop:at=5", 0, 7))
    assert hits == {0: (), 1: (), 2: ("nan",), 3: ("nan",), 4: (), 5: ("stop",), 6: ("stop",)}
