"""Faults injected on the robot's side: each kind counted in the summary; the simulator survives bad replies."""

from __future__ import annotations

import numpy as np
import pytest

from gtmodel import _egm_pb2
from gtmodel.robot_sim.faults import FAULT_KINDS
from gtmodel.robot_sim.run import simulate
from gtmodel.status import Status

from .peers import EgmPeer, RsiPeer

SPEC = ("loss:cycles=10-12;drop:cycles=20-21;delay:cycles=30-32,ms=6;duplicate:cycles=40-44;reorder:cycles=50-51;"
        "garbage:cycles=60-69;nan:cycles=70-72;ipoc_jump:at=80,by=10;stop:at=150")
EXPECTED = {"loss": 3, "drop": 2, "delay": 3, "duplicate": 5, "reorder": 2, "garbage": 10, "nan": 3, "ipoc_jump": 1, "stop": 1}


@pytest.fixture(scope="module")
def faulty():
    with RsiPeer() as peer:
        result = simulate("rsi", "kr500", peer.target, peer.sensor_target, duration_s=1.0, faults=SPEC, seed=0)
    return result, peer


def test_every_kind_is_in_the_schedule():
    assert sorted(EXPECTED) == sorted(FAULT_KINDS)


@pytest.mark.parametrize("kind", sorted(EXPECTED))
def test_each_fault_is_counted(faulty, kind):
    assert faulty[0].summary["faults_injected"][kind] == EXPECTED[kind]


def test_the_stop_ends_the_run_there(faulty):
    s = faulty[0].summary
    assert (faulty[0].status, s["cycles_sent"], s["stopped_at_cycle"], s["stopped_by_late"]) == (Status.COMPLETED, 150, 150, False)


def test_lost_dropped_delayed_and_reordered_cycles_are_late(faulty):
    result, _ = faulty
    late = {int(k) for k, flag in zip(result.column("cycle"), result.column("late")) if flag}
    must = {10, 11, 12, 20, 21, 30, 31, 32, 50, 51}
    assert (sorted(must - late), result.summary["packets_sent"]) == ([], 147), result.summary["clock_slips"]


def test_duplicates_and_garbage_reached_the_peer(faulty):
    """147 packets (150 cycles, 3 lost), 5 duplicates, 10 garbage datagrams; the NaN packets parse."""
    result, peer = faulty
    assert (peer.received, peer.unparsed, result.summary["duplicate_replies"] + result.summary["stale_replies"] >= 5) == (162, 10, True)


def test_the_ipoc_jumps_by_ten_cycles(faulty):
    seq = faulty[0].column("seq")
    assert (seq[80] - seq[79], seq[81] - seq[80]) == (44.0, 4.0)


def test_nan_fields_were_sent(faulty):
    assert list(faulty[0].column("cycle")[[k for k, f in enumerate(faulty[0].record) if "nan" in f[5]]]) == [70.0, 71.0, 72.0]


BAD_REPLIES = {
    5: b"\x00\x01garbage\xff",
    6: b'<!DOCTYPE Sen [<!ENTITY a "a">]><Sen Type="ImFree"><IPOC>{ipoc}</IPOC></Sen>',
    7: b'<Sen Type="ImFree"><RKorr X="nan" Y="0" Z="0" A="0" B="0" C="0"/><IPOC>{ipoc}</IPOC></Sen>',
    8: b'<Sen Type="ImFree"><RKorr X="0"/><IPOC>1</IPOC></Sen>',
    9: b'<Sen Type="ImFree"><EStr>' + b"x" * 6000 + b"</EStr><IPOC>{ipoc}</IPOC></Sen>",
}


def test_the_simulator_survives_bad_replies():
    with RsiPeer(misbehave=BAD_REPLIES) as peer:
        result = simulate("rsi", "kr500", peer.target, peer.sensor_target, duration_s=0.2, seed=0)
    s = result.summary
    got = (result.status, s["cycles_sent"], s["malformed_replies"], s["rejected_replies"], s["mismatched_replies"])
    assert got == (Status.COMPLETED, 50, 4, {"hostile": 1, "malformed": 1, "nonfinite": 1, "too_long": 1}, 1)


def test_too_many_late_replies_stop_the_robot():
    with RsiPeer(silent=True) as peer:
        result = simulate("rsi", "kr500", peer.target, peer.sensor_target, duration_s=1.0, late_limit=5)
    s = result.summary
    assert (result.status, s["stopped_by_late"], s["cycles_sent"], s["consecutive_late_max"]) == (Status.CHECK_FAILED, True, 6, 6)


@pytest.fixture(scope="module")
def egm_faulty():
    garbage = b"\xff\xfe\xfd"
    nan = _egm_pb2.EgmSensor()
    nan.planned.joints.joints.extend([float("nan"), 0.0, 0.0])
    with EgmPeer(misbehave={3: garbage, 4: nan.SerializeToString()}) as peer:
        result = simulate("egm", "l1", peer.target, peer.sensor_target, duration_s=0.4, seed=0,
                          faults="nan:at=10;ipoc_jump:at=20,by=5;garbage:at=30;duplicate:at=40")
    return result, peer


def test_egm_faults_and_garbage_replies(egm_faulty):
    result, peer = egm_faulty
    s = result.summary
    seq = result.column("seq")
    got = (result.status, s["rejected_replies"], peer.unparsed >= 2, seq[20] - seq[19], s["faults_injected"]["duplicate"], s["echoed_seqno"] >= 1)
    assert got == (Status.COMPLETED, {"malformed": 1, "nonfinite": 1}, True, 6.0, 1, True)
    assert np.isfinite(result.column("reference_q1_mm")).all()


@pytest.mark.realtime
def test_egm_replies_echo_their_seqno_in_time(egm_faulty):
    """Real time: on a quiet machine at least 90 of the 100 cycles get a reply echoing their seqno within 4 ms."""
    assert egm_faulty[0].summary["echoed_seqno"] >= 90, egm_faulty[0].summary
