"""The runtime's network guard in C (``gt_guard.c``), called directly: the sequence window and the source names.

Independent check: the expected outcomes are written here from the rule as ``docs/robot_runtime.md``
states it (accepted within the window, duplicate or older within it, out of it; resynchronised on
the N-th consecutive consistent datagram beyond it), not computed by the C.
"""

from __future__ import annotations

import ctypes

import pytest

from gtmodel._compiler import find_compiler, run_compiler
from gtmodel.codegen.robot_runtime import _HARNESS

A, OLD, OUT, RESYNC = 0, 1, 2, 3  # gt_guard.h: GT_SEQ_ACCEPT, GT_SEQ_OLD, GT_SEQ_OUT, GT_SEQ_RESYNC
WINDOW, N = 10, 3


class SeqWin(ctypes.Structure):
    _fields_ = [("have", ctypes.c_int), ("cand_n", ctypes.c_int), ("last", ctypes.c_uint64), ("cand", ctypes.c_uint64),
                ("out_of_window", ctypes.c_uint64), ("resyncs", ctypes.c_uint64)]


class Source(ctypes.Structure):
    _fields_ = [("named", ctypes.c_int), ("named_port", ctypes.c_int), ("locked", ctypes.c_int), ("family", ctypes.c_uint16),
                ("port", ctypes.c_uint16), ("ip", ctypes.c_uint32), ("zero", ctypes.c_char * 8)]


@pytest.fixture(scope="module")
def guard(tmp_path_factory):
    lib = tmp_path_factory.mktemp("guard") / "libgt_guard.so"
    run_compiler([*find_compiler(), "-std=c11", "-O2", "-Wall", "-Wextra", "-Wpedantic", "-Werror", "-shared", "-fPIC",
                  str(_HARNESS / "gt_guard.c"), "-o", str(lib)], "building gt_guard.c")
    g = ctypes.CDLL(str(lib))
    g.gt_seq_check.argtypes = [ctypes.POINTER(SeqWin), ctypes.c_uint64, ctypes.c_int, ctypes.c_uint64, ctypes.c_int]
    g.gt_source_parse.argtypes = [ctypes.c_char_p, ctypes.POINTER(Source)]
    return g


SEQUENCES = [  # (bits, the datagrams' numbers, the outcome of each, resynchronisations)
    (64, [100, 101, 105, 105, 104, 116, 106, 2 ** 64 - 1, 107], [A, A, A, OLD, OLD, OUT, A, OUT, A], 0),
    (64, [100, 10 ** 15, 101], [A, OUT, A], 0),  # a forged number moves nothing
    (64, [100, 500, 501, 502, 503], [A, OUT, OUT, RESYNC, A], 1),  # a restarted robot: followed on the N-th
    (64, [100, 500, 101, 501, 102, 502, 103, 503], [A, OUT, A, OUT, A, OUT, A, OUT], 0),  # a forger between the robot's own: never
    (64, [100, 500, 520, 521, 522, 523], [A, OUT, OUT, OUT, RESYNC, A], 1),  # candidates must be consistent with each other
    (64, [0, 2 ** 63, 1], [A, OUT, A], 0),  # the most negative difference
    (32, [2 ** 32 - 2, 2 ** 32 - 1, 0, 1], [A, A, A, A], 0),  # EGM's seqno wraps
    (32, [7, 7 + 2 ** 30, 8], [A, OUT, A], 0),
    (32, [5, 2 ** 32 - 3], [A, OLD], 0),  # 8 back across the wrap: older, within the window
]


@pytest.mark.parametrize("bits, seqs, outcomes, resyncs", SEQUENCES, ids=[f"{b}bit-{s[:3]}" for b, s, _, _ in SEQUENCES])
def test_the_sequence_window_and_its_resynchronisation(guard, bits, seqs, outcomes, resyncs):
    w = SeqWin()
    got = [guard.gt_seq_check(ctypes.byref(w), s, bits, WINDOW, N) for s in seqs]
    assert (got, w.resyncs, w.out_of_window) == (outcomes, resyncs, outcomes.count(OUT) + outcomes.count(RESYNC))


SOURCES = [("192.168.1.20", 0, (1, 0)), ("192.168.1.20:6511", 0, (1, 1)), ("127.0.0.2:1", 0, (1, 1))]
BAD_SOURCES = ["", "robot", "192.168.1.300", "1.2.3.4:", "1.2.3.4:0", "1.2.3.4:65536", "1.2.3.4:8x", ":80", "1.2.3.4:-1", "1.2.3.4:+80"]


@pytest.mark.parametrize("text, code, named", SOURCES + [(b, -1, None) for b in BAD_SOURCES], ids=[t or "empty" for t, _, _ in SOURCES] + [
    b or "empty" for b in BAD_SOURCES])
def test_source_names(guard, text, code, named):
    s = Source()
    assert guard.gt_source_parse(text.encode(), ctypes.byref(s)) == code
    assert named is None or (s.named, s.named_port) == named
