"""The EGM messages of the simulator: ``EgmRobot`` as ABB's egm.proto defines it, hostile ``EgmSensor`` replies."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from gtmodel import _egm_pb2
from gtmodel.robot_sim.egm import compose_egm_robot, parse_egm_sensor
from gtmodel.robot_sim.state import ReplyError, RobotState, euler_zyx_to_quaternion

STATE = RobotState(np.array([10.0, 2900.0, -500.0, 0.0, 0.0, 90.0]), np.array([11.0, 2901.0, -501.0, 0.0, 0.0, 90.0]),
                   np.array([-93.3, 41.5, 15.3]), np.array([-93.0, 41.0, 15.0]))


def _robot(**kw) -> _egm_pb2.EgmRobot:
    msg = _egm_pb2.EgmRobot()
    msg.ParseFromString(compose_egm_robot(STATE, 17, 68, **kw))
    return msg


def test_egm_robot_carries_the_state():
    m = _robot()
    got = (m.header.seqno, m.header.tm, m.header.mtype, list(m.feedBack.joints.joints), list(m.planned.joints.joints),
           (m.feedBack.cartesian.pos.x, m.feedBack.cartesian.pos.y, m.feedBack.cartesian.pos.z),
           m.motorState.state, m.mciState.state, m.rapidExecState.state, m.mciConvergenceMet)
    want = (17, 68, _egm_pb2.EgmHeader.MSGTYPE_DATA, [-93.3, 41.5, 15.3], [-93.0, 41.0, 15.0], (10.0, 2900.0, -500.0),
            _egm_pb2.EgmMotorState.MOTORS_ON, _egm_pb2.EgmMCIState.MCI_RUNNING, _egm_pb2.EgmRapidCtrlExecState.RAPID_RUNNING, True)
    assert got == want


def test_quaternion_of_c_is_the_rotation_about_x():
    q = _robot().feedBack.cartesian.orient
    assert np.allclose([q.u0, q.u1, q.u2, q.u3], [math.cos(math.pi / 4), math.sin(math.pi / 4), 0, 0])


def test_quaternion_is_kukas_zyx_euler():
    """KUKA's A, B, C: R = Rz(A) Ry(B) Rx(C) (SciPy's intrinsic "ZYX"); EGM's quaternion is scalar-first."""
    x, y, z, w = Rotation.from_euler("ZYX", [30.0, -20.0, 70.0], degrees=True).as_quat()
    assert np.allclose(euler_zyx_to_quaternion(30.0, -20.0, 70.0), [w, x, y, z])


def test_nan_fault_sends_a_nan_joint():
    assert math.isnan(_robot(nan_field=True).feedBack.joints.joints[0])


def _sensor(joints=None, cart=None, seqno=5) -> bytes:
    msg = _egm_pb2.EgmSensor()
    msg.header.seqno = seqno
    msg.header.mtype = _egm_pb2.EgmHeader.MSGTYPE_CORRECTION
    if joints is not None:
        msg.planned.joints.joints.extend(joints)
    if cart is not None:
        msg.planned.cartesian.pos.x, msg.planned.cartesian.pos.y, msg.planned.cartesian.pos.z = cart
    return msg.SerializeToString()


def test_planned_joints_are_positions():
    reply = parse_egm_sensor(_sensor(joints=[1.0, 2.0, 3.0]))
    assert (reply.seqno, reply.command.joints.tolist(), reply.command.cart, reply.command.positions) == (5, [1.0, 2.0, 3.0], None, True)


def test_planned_cartesian_is_a_position():
    assert parse_egm_sensor(_sensor(cart=(1.0, 2.0, 3.0))).command.cart.tolist() == [1.0, 2.0, 3.0]


def test_path_correction_is_an_offset():
    msg = _egm_pb2.EgmSensorPathCorr()
    msg.header.mtype = _egm_pb2.EgmHeader.MSGTYPE_PATH_CORRECTION
    msg.pathCorr.pos.x, msg.pathCorr.pos.y, msg.pathCorr.pos.z = 0.5, -0.5, 0.0
    msg.pathCorr.age = 1
    cmd = parse_egm_sensor(msg.SerializeToString()).command
    assert (cmd.cart.tolist(), cmd.positions, cmd.mode) == ([0.5, -0.5, 0.0], False, "absolute")


HOSTILE = {
    "garbage": (b"\xff\xff\xff\xff\x0f\x12", "malformed"),
    "random": (np.random.default_rng(3).integers(0, 256, 300, dtype=np.uint8).tobytes(), "malformed"),
    "too_long": (b"\x00" * 5000, "too_long"),
    "empty_message": (b"", "empty"),
    "nan_joint": (_sensor(joints=[1.0, float("nan"), 3.0]), "nonfinite"),
    "inf_cartesian": (_sensor(cart=(1.0, float("inf"), 3.0)), "nonfinite"),
    "out_of_range": (_sensor(joints=[1e300]), "out_of_range"),
    "too_many_joints": (_sensor(joints=[0.0] * 20), "malformed"),
    "xml": (b'<Sen Type="ImFree"><IPOC>1</IPOC></Sen>', "malformed"),
}


@pytest.mark.parametrize("name", sorted(HOSTILE))
def test_hostile_reply_is_rejected_with_its_reason(name):
    data, reason = HOSTILE[name]
    with pytest.raises(ReplyError) as info:
        parse_egm_sensor(data)
    assert info.value.reason == reason
