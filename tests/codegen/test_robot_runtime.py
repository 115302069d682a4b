"""The robot runtime's codegen side: RuntimeSpec validation, the generated configuration, the build,
and the parsers (RSI XML, GTS1 sensor stream, EGM protobuf) fuzzed with hostile inputs.

Independent checks: the expected parses of the table are written from the public formats (KUKA's
<Rob> datagram, the contract's GTS1 line, ABB's egm.proto through Python's protobuf package), not
from the C; the fuzz runs the C under AddressSanitizer and UndefinedBehaviorSanitizer (when the
compiler has them) in a child process, so that any overrun aborts it.
"""

from __future__ import annotations

import ctypes
import json
import logging
import os
import random
import subprocess
import sys
import textwrap

import casadi as ca
import numpy as np
import pytest

from gtmodel import _egm_pb2 as egm
from gtmodel._compiler import find_compiler
from gtmodel.codegen.loop_step import LoopStep
from gtmodel.codegen.build import stack_work_bytes
from gtmodel.codegen.robot_runtime import (CYCLE_STACK_BASE, CYCLE_STACK_MAX, EGM_INPUTS, RSI_INPUTS, RUNTIME_SOURCES, RobotRuntime,
                                          RuntimeSpec, build_runtime, cycle_stack_bytes)
from gtmodel.errors import CodegenError, InputError

HARNESS = os.path.join(os.path.dirname(__import__("gtmodel.codegen", fromlist=["x"]).__file__), "harness", "runtime")


def _step(nx: int, nu: int, gain: float = 0.5, dt: float = 0.004) -> LoopStep:
    t, x, ul = ca.SX.sym("t"), ca.SX.sym("x", nx), ca.SX.sym("u_last", nu)
    u = ca.vertcat(*[gain * (1.0 - x[i % nx]) for i in range(nu)])
    f = ca.Function("control", [t, x, ul], [u, ca.SX(1)], ["t", "x", "u_last"], ["u", "ok"])
    return LoopStep("p", f, dt, np.full(nu, -np.inf), np.full(nu, np.inf), np.zeros(nu), [f"x{i}" for i in range(nx)],
                    [f"u{i}" for i in range(nu)])


GOOD = dict(interface="rsi", inputs=["RIst.X", "sensor.0"], outputs=["RKorr.X", "AKorr.A1"], lower=[-1, -1], upper=[1, 1], rate=[0.1, 0.1])

BAD_SPECS = [
    ({"interface": "kuka"}, "interface: expected 'rsi' or 'egm'"),
    ({"inputs": ["RIst.Q"]}, "inputs: 'RIst.Q' is not a field"),
    ({"inputs": ["RIst.X", "RIst.X"]}, "inputs: expected distinct"),
    ({"inputs": "RIst.X"}, "inputs: expected a sequence"),
    ({"outputs": ["planned.joints.0", "AKorr.A1"]}, "outputs: 'planned.joints.0' is not a reply field"),
    ({"lower": [-1]}, "lower: expected 2 values"),
    ({"upper": [1, float("inf")]}, "upper: expected finite values"),
    ({"rate": [0.1, float("nan")]}, "rate: expected finite values"),
    ({"rate": [0.1, 0.0]}, "rate: expected positive"),
    ({"rate": [0.1, 1e-7]}, "rate: RSI's numbers have 6 decimals"),
    ({"lower": [2, -1], "upper": [1, 1]}, "lower, upper: expected lower <= upper"),
    ({"lower": [0.5, -1]}, "RSI corrections start at zero"),
    ({"correction": "incremental"}, "correction: expected 'relative' or 'absolute'"),
    ({"sen_type": 'Im"Free'}, "sen_type: expected 1 to 64"),
    ({"sen_type": ""}, "sen_type: expected 1 to 64"),
    ({"fallback": "ramp_to_zero"}, "fallback: expected 'hold' or 'ramp'"),
    ({"stale_cycles": 0}, "stale_cycles: expected an integer"),
    ({"stale_cycles": 2.5}, "stale_cycles: expected an integer"),
    ({"reply_deadline_s": 0.004}, "reply_deadline_s: expected 0 < reply_deadline_s < period"),
    ({"period": -1.0}, "period: expected a cycle"),
    ({"egm_mode": "speed"}, "egm_mode: expected one of"),
    ({"interface": "egm", "inputs": ["feedback.joints.0"], "outputs": ["planned.joints.1", "planned.joints.2"]},
     "outputs: EGM joint mode sends all of planned.joints.0..1"),
    ({"interface": "egm", "egm_mode": "cartesian", "inputs": ["feedback.joints.0"], "outputs": ["planned.cartesian.x", "planned.cartesian.y"]},
     "outputs: EGM cartesian mode sends all of"),
]


@pytest.mark.parametrize("change, match", BAD_SPECS)
def test_a_bad_spec_is_refused_naming_the_field(change, match):
    with pytest.raises(InputError, match=match.replace("(", r"\(").replace(".", r"\.")):
        RuntimeSpec(**{**GOOD, **change})


def test_a_good_spec_is_kept_as_tuples():
    spec = RuntimeSpec(**GOOD)
    assert spec.inputs == ("RIst.X", "sensor.0") and spec.lower == (-1.0, -1.0) and spec.relative


def test_the_step_must_match_the_spec():
    with pytest.raises(InputError, match="step: expected nx = 2"):
        RobotRuntime(_step(3, 2), RuntimeSpec(**GOOD))
    with pytest.raises(InputError, match="period dt"):
        RobotRuntime(_step(2, 2, dt=0.002), RuntimeSpec(**GOOD))


def test_generate_writes_the_step_the_runtime_and_its_configuration(tmp_path):
    source = RobotRuntime(_step(2, 2), RuntimeSpec(**{**GOOD, "sen_type": "My_Type1"}))
    generated = source.generate(tmp_path)
    assert generated.source.name == "gt_loop.c" and source.summary().startswith("the RSI runtime")
    assert [name for name in RUNTIME_SOURCES if not (tmp_path / name).is_file()] == []
    cfg = (tmp_path / "gt_runtime_config.h").read_text()
    assert '#define GT_RT_SEN_TYPE "My_Type1"' in cfg
    assert f"gt_rt_x_source[GT_RT_NX] = {{{RSI_INPUTS.index('RIst.X')}, -1}}" in cfg
    assert "gt_rt_u_reply[GT_RT_NU] = {0, 6}" in cfg and "#define GT_RT_RSI_ELEMENTS 3u" in cfg
    assert "gt_rt_rate[GT_RT_NU] = {0.1, 0.1}" in cfg and "#define GT_RT_NSENSOR 1" in cfg


def test_egm_joint_configuration_starts_from_the_measured_joints(tmp_path):
    spec = RuntimeSpec(interface="egm", inputs=["feedback.joints.0", "feedback.joints.1"], outputs=["planned.joints.1", "planned.joints.0"],
                       lower=[-90, -90], upper=[90, 90], rate=[1, 1])
    RobotRuntime(_step(2, 2), spec).generate(tmp_path)
    cfg = (tmp_path / "gt_runtime_config.h").read_text()
    # the measured position first (the rate limit applies from where the robot is), the planned one when absent
    assert f"gt_rt_u_init[GT_RT_NU] = {{{EGM_INPUTS.index('feedback.joints.1')}, {EGM_INPUTS.index('feedback.joints.0')}}}" in cfg
    assert f"gt_rt_u_init2[GT_RT_NU] = {{{EGM_INPUTS.index('planned.joints.1')}, {EGM_INPUTS.index('planned.joints.0')}}}" in cfg
    assert "gt_rt_u_reply[GT_RT_NU] = {1, 0}" in cfg and "#define GT_RT_NREPLY 2" in cfg


def test_the_cycle_threads_stack_holds_the_steps_work_arrays(tmp_path):
    """Independent: the work-array sizes the generated wrapper declares (its #defines, read from gt_loop.c)."""
    import re
    from types import SimpleNamespace

    RobotRuntime(_step(2, 2), RuntimeSpec(**GOOD)).generate(tmp_path)
    sizes = {k: int(v) for k, v in re.findall(r"#define GT_LOOP_\w+_SZ_(ARG|RES|IW|W) (\d+)", (tmp_path / "gt_loop.c").read_text())}
    stack = int(re.search(r"#define GT_RT_CYCLE_STACK \(\(size_t\)(\d+)u\)", (tmp_path / "gt_runtime_config.h").read_text())[1])
    assert stack >= CYCLE_STACK_BASE + 8 * sum(sizes.values()) and stack % 65536 == 0 and stack < CYCLE_STACK_BASE + 65536 * 2
    assert stack_work_bytes((1, 2, 3, 100), "float") == 8 * 3 + 8 * 3 + 4 * 100
    big = SimpleNamespace(work_sizes={"control": (0, 0, 0, 1_000_000)}, real="double")  # 8 MB of reals
    assert cycle_stack_bytes(big) == CYCLE_STACK_BASE + 8_060_928  # 8,000,000 rounded up to 64 KiB
    with pytest.raises(CodegenError, match="stack work arrays take 2000000000 bytes: over the runtime's cycle-thread stack cap"):
        cycle_stack_bytes(SimpleNamespace(work_sizes={"control": (0, 0, 0, 250_000_000)}, real="double"))
    assert CYCLE_STACK_MAX >= 64 * CYCLE_STACK_BASE


@pytest.mark.parametrize("real", ["double", "float"])
def test_build_runtime_makes_one_executable(tmp_path, real):
    exe = build_runtime(RobotRuntime(_step(2, 2), RuntimeSpec(**GOOD)), tmp_path, real=real)
    assert exe.is_file() and os.access(exe, os.X_OK)
    proc = subprocess.run([str(exe), "--listen", "127.0.0.1:0"], capture_output=True, text=True, timeout=10)
    assert proc.returncode == 2 and "--out DIR is required" in proc.stderr and proc.stderr.count("\n") == 1


def test_build_runtime_compiles_code_generated_before_without_generating_it_again(tmp_path, caplog):
    """gtmodel loop generates and checks the step first, then builds: one 'codegen: wrote' per file (issue 67)."""
    caplog.set_level(logging.INFO, logger="gtmodel")
    source = RobotRuntime(_step(2, 2), RuntimeSpec(**GOOD))
    generated = source.generate(tmp_path / "code")
    exe = build_runtime(source, tmp_path / "code", generated=generated)
    wrote = [r.getMessage() for r in caplog.records if r.getMessage().startswith("codegen: wrote")]
    assert exe.is_file() and len(wrote) == len(set(wrote)) == 2, wrote
    with pytest.raises(InputError, match="generated: expected the code generated into"):
        build_runtime(source, tmp_path / "elsewhere", generated=generated)


def test_build_runtime_refuses_another_source(tmp_path):
    with pytest.raises(InputError, match="source: expected a RobotRuntime"):
        build_runtime(_step(2, 2), tmp_path)


# ---- fuzz: the parsers as a shared library, under the sanitizers when the compiler has them ----

def _sanitizers() -> list[str]:
    return ["-fsanitize=address,undefined", "-fno-sanitize-recover=undefined", "-fno-omit-frame-pointer"]


@pytest.fixture(scope="module")
def parsers(tmp_path_factory):
    out = tmp_path_factory.mktemp("parsers")
    cc = find_compiler()
    srcs = [os.path.join(HARNESS, f) for f in ("gt_rsi.c", "gt_sensor_stream.c", "gt_egm.c", "egm.pb.c", "nanopb/pb_common.c",
                                                 "nanopb/pb_decode.c", "nanopb/pb_encode.c")]
    base = [*cc, "-std=c11", "-O1", "-g", "-Wall", "-Wextra", "-Werror", "-shared", "-fPIC", "-I", HARNESS, "-I", os.path.join(HARNESS, "nanopb")]
    lib = out / "libparsers.so"
    asan = subprocess.run([*base, *_sanitizers(), *srcs, "-o", str(lib), "-lm"], capture_output=True, text=True).returncode == 0
    if not asan:
        subprocess.run([*base, *srcs, "-o", str(lib), "-lm"], check=True, capture_output=True, text=True)
    preload = subprocess.run([*cc, "-print-file-name=libasan.so"], capture_output=True, text=True).stdout.strip() if asan else ""
    return lib, preload


RUNNER = textwrap.dedent('''
    import ctypes, json, sys
    lib = ctypes.CDLL(sys.argv[1])
    class Rob(ctypes.Structure):
        _fields_ = [("field", ctypes.c_double * 37), ("present", ctypes.c_uint64), ("ipoc", ctypes.c_uint64)]
    class Sample(ctypes.Structure):
        _fields_ = [("seq", ctypes.c_uint64), ("t", ctypes.c_double), ("n", ctypes.c_int), ("value", ctypes.c_double * 16)]
    class Egm(ctypes.Structure):
        _fields_ = [("field", ctypes.c_double * 50), ("present", ctypes.c_uint64), ("seqno", ctypes.c_uint32), ("has_tm", ctypes.c_int),
                    ("tm", ctypes.c_uint32), ("has_orient", ctypes.c_int), ("orient", ctypes.c_double * 4)]
    kinds = {"rsi": (lib.gt_rsi_parse, Rob), "sensor": (lib.gt_sensor_parse, Sample), "egm": (lib.gt_egm_parse, Egm)}
    out = []
    with open(sys.argv[2], "rb") as f:
        cases = f.read().split(b"\\n--CASE--\\n")
    for case in cases:
        kind, _, data = case.partition(b":")
        fn, T = kinds[kind.decode()]
        buf = ctypes.create_string_buffer(data, len(data))  # exactly len bytes, no terminating NUL read by contract
        res = T()
        code = fn(buf, ctypes.c_size_t(len(data)), ctypes.byref(res))
        if kind == b"rsi":
            out.append([code, res.ipoc, res.present, [v for v in res.field]])
        elif kind == b"sensor":
            out.append([code, res.seq, res.n, [res.t] + [v for v in res.value][:max(res.n, 0)]])
        else:
            out.append([code, res.seqno, res.present, [v for v in res.field]])
    print(json.dumps(out, allow_nan=True))
''')


def _run_cases(parsers, tmp_path, cases: list[tuple[str, bytes]]) -> list:
    lib, preload = parsers
    blob = b"\n--CASE--\n".join(k.encode() + b":" + d for k, d in cases)
    assert all(b"\n--CASE--\n" not in d for _, d in cases)
    path = tmp_path / "cases.bin"
    path.write_bytes(blob)
    env = dict(os.environ, ASAN_OPTIONS="detect_leaks=0:abort_on_error=1", UBSAN_OPTIONS="halt_on_error=1:print_stacktrace=1")
    if preload:
        env["LD_PRELOAD"] = preload
    script = tmp_path / "runner.py"
    script.write_text(RUNNER)
    proc = subprocess.run([sys.executable, "-I", str(script), str(lib), str(path)], capture_output=True, text=True, env=env, timeout=300)
    assert proc.returncode == 0, proc.stderr[-3000:]
    results = json.loads(proc.stdout)
    assert len(results) == len(cases)
    return results


def _rob(rist='X="1.5" Y="-2" Z="3e1" A="0" B="0.25" C="-0"', ipoc="123456", extra=""):
    return f'<Rob Type="KUKA"><RIst {rist}/>{extra}<AIPos A1="10" A2="20" A3="30" A4="40" A5="50" A6="60"/><IPOC>{ipoc}</IPOC></Rob>'.encode()


OK, MALFORMED, TOO_LONG, NON_FINITE = 0, 1, 2, 3
RSI_TABLE = [
    (_rob(), OK, 123456, {"RIst.X": 1.5, "RIst.Y": -2.0, "RIst.Z": 30.0, "AIPos.A6": 60.0}),
    (_rob(rist='C="6" B="5" A="4" Z="3" Y="2" X="1"'), OK, 123456, {"RIst.X": 1.0, "RIst.C": 6.0}),
    (b'<?xml version="1.0"?>\n<!-- robot -->\n<Rob Type="KUKA">\n  <RIst X = \'1\' Y="2"  Z="3" A="4" B="5" C="6" />\n'
     b'  <Digout o1="0"><Sub x="1">text</Sub></Digout><EStr>hello &amp; x > y</EStr>\n  <IPOC> 42 </IPOC>\n</Rob>\n', OK, 42, {"RIst.Z": 3.0}),
    (_rob(extra='<Foo><RSol X="9" Y="9" Z="9" A="9" B="9" C="9"/></Foo>'), OK, 123456, {"RSol.X": None}),
    (_rob(rist='X="NaN" Y="0" Z="0" A="0" B="0" C="0"'), NON_FINITE, 123456, {}),
    (_rob(rist='X="-inf" Y="0" Z="0" A="0" B="0" C="0"'), NON_FINITE, 123456, {}),
    (_rob(rist='X="1e999" Y="0" Z="0" A="0" B="0" C="0"'), NON_FINITE, 123456, {}),
    (_rob(rist='X="1e-999" Y="0" Z="0" A="0" B="0" C="0"'), OK, 123456, {"RIst.X": 0.0}),
    (_rob(rist='X="' + "9" * 70 + '" Y="0"'), MALFORMED, None, {}),
    (_rob(rist='X="0x10"'), MALFORMED, None, {}),
    (_rob(rist='X="1.2.3"'), MALFORMED, None, {}),
    (_rob(rist='X="1e"'), MALFORMED, None, {}),
    (_rob(rist='X=""'), MALFORMED, None, {}),
    (_rob(rist='X="1" X="2"'), MALFORMED, None, {}),
    (_rob(rist='X="1'), MALFORMED, None, {}),
    (_rob(rist='X=1'), MALFORMED, None, {}),
    (_rob(ipoc="18446744073709551615"), OK, 18446744073709551615, {}),
    (_rob(ipoc="18446744073709551616"), MALFORMED, None, {}),
    (_rob(ipoc="-4"), MALFORMED, None, {}),
    (_rob(ipoc=""), MALFORMED, None, {}),
    (_rob(ipoc="12</IPOC><IPOC>13"), MALFORMED, None, {}),
    (b'<Rob><RIst X="1"/></Rob>', MALFORMED, None, {}),
    (b'<Rob><IPOC>1</IPOC>', MALFORMED, None, {}),
    (b'<Rob><IPOC>1</IPOC></Rob><Rob/>', MALFORMED, None, {}),
    (b'<Sen><IPOC>1</IPOC></Sen>', MALFORMED, None, {}),
    (b'<Rob><IPOC>1</IPOC></Rob>trailing', MALFORMED, None, {}),
    (b'<Rob><a><b></a></b><IPOC>1</IPOC></Rob>', MALFORMED, None, {}),
    (b'<Rob>' + b'<a>' * 40 + b'</a>' * 40 + b'<IPOC>1</IPOC></Rob>', MALFORMED, None, {}),
    (b'<Rob><IPOC>1\x00</IPOC></Rob>', MALFORMED, None, {}),
    (b'<Rob><IPOC>7</IPOC>' + b' ' * 5000 + b'</Rob>', TOO_LONG, None, {}),
    (b'', MALFORMED, None, {}),
    (b'<', MALFORMED, None, {}),
]


def test_rsi_parser_table_and_hostile_inputs(parsers, tmp_path):
    rng = random.Random(48)
    cases = [("rsi", d) for d, *_ in RSI_TABLE]
    base = RSI_TABLE[2][0]
    cases += [("rsi", base[:k]) for k in range(len(base))]  # every truncation
    tokens = [b'"', b"'", b"<", b">", b"/", b"=", b"\x00", b" ", b"<a>", b"</Rob>", b"<IPOC>", b"1e308", b"9" * 100, b"\xff", b"<!--"]
    for _ in range(3000):
        d = bytearray(base if rng.random() < 0.7 else _rob())
        for _ in range(rng.randint(1, 4)):
            k = rng.randrange(len(d) + 1)
            op = rng.random()
            if op < 0.4:
                d[k:k] = rng.choice(tokens)
            elif op < 0.7 and d:
                del d[k:k + rng.randint(1, 8)]
            elif d:
                d[min(k, len(d) - 1)] = rng.randrange(256)
        cases.append(("rsi", bytes(d)))
    cases += [("rsi", bytes(rng.randrange(256) for _ in range(rng.randint(0, 300)))) for _ in range(300)]
    cases.append(("rsi", b'<Rob><RIst X="' + b"1" * 10**6 + b'"/><IPOC>1</IPOC></Rob>'))
    cases.append(("rsi", b'<Rob><RIst X="' + b"1" * 4000 + b'"/><IPOC>1</IPOC></Rob>'))
    results = _run_cases(parsers, tmp_path, cases)
    wrong = []
    for (data, code, ipoc, values), (got, got_ipoc, present, fields) in zip(RSI_TABLE, results):
        if got != code or (code in (OK, NON_FINITE) and got_ipoc != ipoc):
            wrong.append((data[:80], got, got_ipoc))
        for name, v in values.items():
            i = RSI_INPUTS.index(name)
            if (bool(present >> i & 1), fields[i] if v is not None else None) != (v is not None, v):
                wrong.append((data[:80], name))
    assert wrong == []
    assert {r[0] for r in results} <= {OK, MALFORMED, TOO_LONG, NON_FINITE}
    assert all(np.isfinite(r[3][i]) for r in results if r[0] == OK for i in range(len(RSI_INPUTS)) if r[2] >> i & 1)
    assert results[-2][0] == TOO_LONG and results[-1][0] == MALFORMED


SENSOR_TABLE = [
    (b"GTS1 0 0.5 1 2 3\n", OK, [0.5, 1.0, 2.0, 3.0]),
    (b"GTS1 17 -1e-3 -0.25", OK, [-0.001, -0.25]),
    (b"GTS1 1 0 " + b" ".join([b"1"] * 16), OK, [0.0] + [1.0] * 16),
    (b"GTS1 1 0 " + b" ".join([b"1"] * 17), MALFORMED, None),
    (b"GTS1 1 0", MALFORMED, None),
    (b"GTS1 1 0 nan", NON_FINITE, None),
    (b"GTS1 1 0 1e400", NON_FINITE, None),
    (b"GTS1 1 inf 1", NON_FINITE, None),
    (b"GTS1 -1 0 1", MALFORMED, None),
    (b"GTS1 1  0 1", MALFORMED, None),
    (b"GTS1 1 0 1 ", MALFORMED, None),
    (b"GTS1 1 0 1\n\n", MALFORMED, None),
    (b"GTS2 1 0 1", MALFORMED, None),
    (b"GTS1 18446744073709551616 0 1", MALFORMED, None),
    (b"GTS1 1 0 1\x00", MALFORMED, None),
    (b"GTS1 1 0 " + b"1" * 2000, TOO_LONG, None),
    (b"GTS1 1 0 " + b"1" * 100, MALFORMED, None),
]


def test_sensor_stream_parser_table_and_hostile_inputs(parsers, tmp_path):
    rng = random.Random(7)
    cases = [("sensor", d) for d, *_ in SENSOR_TABLE]
    base = b"GTS1 12345 1.25 0.1 -0.2 3e-1\n"
    cases += [("sensor", base[:k]) for k in range(len(base))]
    for _ in range(2000):
        d = bytearray(base)
        for _ in range(rng.randint(1, 3)):
            k = rng.randrange(len(d))
            d[k] = rng.choice(b" \x00\n.-+eE9x") if rng.random() < 0.7 else rng.randrange(256)
        cases.append(("sensor", bytes(d)))
    cases += [("sensor", b"GTS1 1 0 " + b"7" * 10**6), ("sensor", b"GTS1 1 0 1\x00" + b"1" * 500), ("sensor", b"\x00" * 64)]
    results = _run_cases(parsers, tmp_path, cases)
    assert [r[0] for r in results[-3:]] == [TOO_LONG, MALFORMED, MALFORMED]
    wrong = [(data[:80], got, vals) for (data, code, values), (got, _, n, vals) in zip(SENSOR_TABLE, results)
             if got != code or (values is not None and vals != values)]
    assert wrong == []
    assert {r[0] for r in results} <= {OK, MALFORMED, TOO_LONG, NON_FINITE}
    assert all(1 <= n <= 16 and np.all(np.isfinite(vals)) for got, _, n, vals in results if got == OK)


def _egm_robot(seq=5, joints=(1.0, 2.0, 3.0)) -> bytes:
    r = egm.EgmRobot()
    r.header.seqno, r.header.tm, r.header.mtype = seq, 1000, egm.EgmHeader.MSGTYPE_DATA
    r.feedBack.joints.joints.extend(joints)
    r.feedBack.cartesian.pos.x, r.feedBack.cartesian.pos.y, r.feedBack.cartesian.pos.z = 100.0, 200.0, 300.0
    r.feedBack.cartesian.orient.u0 = 1.0
    r.feedBack.cartesian.orient.u1 = r.feedBack.cartesian.orient.u2 = r.feedBack.cartesian.orient.u3 = 0.0
    r.planned.joints.joints.extend([j + 0.5 for j in joints])
    r.motorState.state = egm.EgmMotorState.MOTORS_ON
    r.mciState.state = egm.EgmMCIState.MCI_RUNNING
    return r.SerializeToString()


def test_egm_decoder_table_and_random_bytes(parsers, tmp_path):
    rng = random.Random(11)
    no_seq = egm.EgmRobot()
    no_seq.feedBack.joints.joints.extend([1.0])
    table = [(_egm_robot(), OK, 5), (_egm_robot(joints=(float("nan"), 0.0)), NON_FINITE, 5), (_egm_robot(joints=[0.0] * 13), MALFORMED, None),
             (no_seq.SerializeToString(), MALFORMED, None), (b"", MALFORMED, None), (b"\xff" * 10, MALFORMED, None),
             (_egm_robot() + b"\x00" * 5000, TOO_LONG, None)]
    cases = [("egm", d) for d, *_ in table]
    base = _egm_robot()
    cases += [("egm", base[:k]) for k in range(len(base))]
    for _ in range(2000):
        d = bytearray(base)
        for _ in range(rng.randint(1, 4)):
            d[rng.randrange(len(d))] = rng.randrange(256)
        cases.append(("egm", bytes(d)))
    cases += [("egm", bytes(rng.randrange(256) for _ in range(rng.randint(0, 200)))) for _ in range(1000)]
    cases = [(k, d) for k, d in cases if b"\n--CASE--\n" not in d]
    results = _run_cases(parsers, tmp_path, cases)
    assert [(got, got_seq if seq is not None else None) for (_, _, seq), (got, got_seq, _, _) in zip(table, results)] == [
        (code, seq) for _, code, seq in table]
    got, _, present, fields = results[0]
    assert fields[:3] == [1.0, 2.0, 3.0] and fields[12:15] == [100.0, 200.0, 300.0] and fields[19:22] == [1.5, 2.5, 3.5]
    assert present >> EGM_INPUTS.index("feedback.joints.3") & 1 == 0
    assert {r[0] for r in results} <= {OK, MALFORMED, TOO_LONG, NON_FINITE}
    assert all(np.isfinite(r[3][i]) for r in results if r[0] == OK for i in range(len(EGM_INPUTS)) if r[2] >> i & 1)
