"""The robot's side of ABB EGM (protobuf over UDP): compose ``EgmRobot``, parse ``EgmSensor``.

The messages are those of ABB's published ``egm.proto`` (``gtmodel._egm_pb2``, generated
from it). Every cycle the robot sends an ``EgmRobot``: header (``seqno`` +1 per cycle,
``tm`` in ms, ``mtype = MSGTYPE_DATA``), ``feedBack`` (joints in deg, linear axes in mm as
the L1's carts; Cartesian position in mm and a scalar-first quaternion; time),
``planned`` (the setpoint the robot follows), ``motorState`` ON, ``mciState`` RUNNING,
``mciConvergenceMet`` and ``rapidExecState`` RUNNING. It takes back an ``EgmSensor``
(``planned.joints`` or ``planned.cartesian``: position guidance, absolute positions) or,
when the header says ``MSGTYPE_PATH_CORRECTION``, an ``EgmSensorPathCorr`` (``pathCorr.pos``,
an offset in mm).

EGM does not require the reply to echo the robot's ``seqno`` (ABB's examples and
``abb-robot-client`` use their own counter; gtmodel's runtime echoes it): a reply is the
answer to the last packet sent when it arrives before the next one; the summary counts the
replies that echo. Untrusted bytes: at most :data:`MAX_REPLY_BYTES`, any decode error, a
non-finite or out-of-range value, more than :data:`MAX_JOINTS` joints or a message with no
position raise :class:`~gtmodel.robot_sim.state.ReplyError` (counted, never a crash).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from gtmodel import _egm_pb2
from gtmodel.robot_sim.state import Command, ReplyError, RobotState, euler_zyx_to_quaternion

__all__ = ["DEFAULT_PORT", "MAX_REPLY_BYTES", "MAX_JOINTS", "MAX_ABS_VALUE", "EgmReply", "compose_egm_robot", "parse_egm_sensor"]

#: The usual port of the sensor side.
DEFAULT_PORT = 6510
#: Largest reply accepted [bytes].
MAX_REPLY_BYTES = 4096
#: Most joints in a reply (6 robot axes and external axes).
MAX_JOINTS = 12
#: Largest magnitude of a position in a reply [mm or deg].
MAX_ABS_VALUE = 1.0e6


def compose_egm_robot(state: RobotState, seqno: int, tm_ms: int, nan_field: bool = False) -> bytes:
    """The robot's ``EgmRobot`` datagram of one cycle.

    Parameters
    ----------
    state : RobotState
        Joints [deg or mm] and Cartesian pose [mm, deg ZYX] (actual and setpoint).
    seqno : int
        Sequence number (uint32, wraps).
    tm_ms : int
        Controller time stamp [ms] (uint32, wraps).
    nan_field : bool, optional
        Send the first feedback joint as NaN (the ``nan`` fault).

    Returns
    -------
    bytes
        The serialized message.
    """
    msg = _egm_pb2.EgmRobot()
    msg.header.seqno = int(seqno) & 0xFFFFFFFF
    msg.header.tm = int(tm_ms) & 0xFFFFFFFF
    msg.header.mtype = _egm_pb2.EgmHeader.MSGTYPE_DATA
    joints = [float(v) for v in state.joints_actual]
    if nan_field:
        joints[0] = math.nan
    for part, q, cart in ((msg.feedBack, joints, state.cart_actual), (msg.planned, state.joints_setpoint, state.cart_setpoint)):
        part.joints.joints.extend(float(v) for v in q)
        part.cartesian.pos.x, part.cartesian.pos.y, part.cartesian.pos.z = (float(v) for v in cart[:3])
        w, x, y, z = euler_zyx_to_quaternion(*(float(v) for v in cart[3:6]))
        part.cartesian.orient.u0, part.cartesian.orient.u1, part.cartesian.orient.u2, part.cartesian.orient.u3 = w, x, y, z
        part.time.sec, part.time.usec = divmod(int(tm_ms) * 1000, 1_000_000)
    msg.motorState.state = _egm_pb2.EgmMotorState.MOTORS_ON
    msg.mciState.state = _egm_pb2.EgmMCIState.MCI_RUNNING
    msg.mciConvergenceMet = True
    msg.rapidExecState.state = _egm_pb2.EgmRapidCtrlExecState.RAPID_RUNNING
    return msg.SerializeToString()


@dataclass(frozen=True)
class EgmReply:
    """A parsed sensor message.

    Parameters
    ----------
    seqno : int or None
        ``header.seqno`` (None when absent).
    mtype : int
        ``header.mtype`` (``MSGTYPE_CORRECTION`` = 3, ``MSGTYPE_PATH_CORRECTION`` = 4).
    command : Command
        Planned positions (``positions=True``, absolute) or a path correction (an offset).
    """

    seqno: int | None
    mtype: int
    command: Command


def _values(values, what: str, n_max: int) -> np.ndarray:
    if len(values) > n_max:
        raise ReplyError("malformed", f"{what}: {len(values)} values (at most {n_max})")
    a = np.array(list(values), dtype=float)
    if not np.all(np.isfinite(a)):
        raise ReplyError("nonfinite", f"{what}: a non-finite value")
    if np.any(np.abs(a) > MAX_ABS_VALUE):
        raise ReplyError("out_of_range", f"{what}: a value beyond {MAX_ABS_VALUE}")
    return a


def parse_egm_sensor(data: bytes) -> EgmReply:
    """Parse a sensor reply (untrusted bytes; see the module docstring).

    Parameters
    ----------
    data : bytes
        The datagram.

    Returns
    -------
    EgmReply

    Raises
    ------
    ReplyError
        Too long, not a message of ``egm.proto``, a non-finite or out-of-range value, too
        many joints, or no planned position or path correction (``reason`` says which).
    """
    if not isinstance(data, (bytes, bytearray)):
        raise ReplyError("malformed", f"expected bytes, got {type(data).__name__}")
    if len(data) > MAX_REPLY_BYTES:
        raise ReplyError("too_long", f"{len(data)} bytes (at most {MAX_REPLY_BYTES})")
    try:
        msg = _egm_pb2.EgmSensor()
        msg.ParseFromString(bytes(data))
        header = msg.header
        seqno = int(header.seqno) if header.HasField("seqno") else None
        mtype = int(header.mtype)
        if mtype == _egm_pb2.EgmHeader.MSGTYPE_PATH_CORRECTION:
            pc = _egm_pb2.EgmSensorPathCorr()
            pc.ParseFromString(bytes(data))
            if not pc.HasField("pathCorr"):
                raise ReplyError("empty", "a path correction without pathCorr")
            p = pc.pathCorr.pos
            cart = _values((p.x, p.y, p.z), "pathCorr.pos", 3)
            return EgmReply(seqno, mtype, Command(cart, None, "absolute"))
        joints = cart = None
        if msg.HasField("planned"):
            if msg.planned.HasField("joints") and len(msg.planned.joints.joints):
                joints = _values(msg.planned.joints.joints, "planned.joints", MAX_JOINTS)
            if msg.planned.HasField("cartesian") and msg.planned.cartesian.HasField("pos"):
                p = msg.planned.cartesian.pos
                cart = _values((p.x, p.y, p.z), "planned.cartesian.pos", 3)
        if joints is None and cart is None:
            raise ReplyError("empty", "no planned joints or Cartesian position")
        return EgmReply(seqno, mtype, Command(cart, joints, "absolute", positions=True))
    except ReplyError:
        raise
    except Exception as exc:  # protobuf's DecodeError, or anything its parser raises on hostile bytes
        raise ReplyError("malformed", f"not an EgmSensor message: {type(exc).__name__}: {exc}") from None
