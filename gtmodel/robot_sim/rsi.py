"""The robot's side of KUKA RSI (Ethernet object, XML over UDP): compose ``<Rob>``, parse ``<Sen>``.

The robot sends every cycle (4 ms; ``IPOC`` in ms, +4 per cycle)::

    <Rob Type="KUKA"><RIst X=".." Y=".." Z=".." A=".." B=".." C=".."/><RSol .../>
    <AIPos A1=".." ... A6=".."/><ASPos .../><Delay D=".."/><IPOC>123456</IPOC></Rob>

(``RIst``/``RSol`` the actual and setpoint Cartesian pose, mm and deg; ``AIPos``/``ASPos``
the actual and setpoint axes, deg; ``Delay`` the count of late replies so far, RSI's
``DEF_Delay``), and takes back::

    <Sen Type="ImFree"><EStr>..</EStr><RKorr X=".." ... C=".."/><AKorr A1=".." ... A6=".."/><IPOC>123456</IPOC></Sen>

The tags are those of KUKA's RSI documentation as the public ROS-Industrial driver
``kuka_rsi_hw_interface`` (``rsi_state.h``, ``rsi_command.h``) and its
``kuka_rsi_simulator`` use them; that driver names its axis correction ``AK`` (the tag of
the Ethernet configuration's ``<RECEIVE>`` element is the user's choice): the parser
takes ``AKorr`` or ``AK``.

The parser takes untrusted bytes: at most :data:`MAX_REPLY_BYTES`, no ``<!`` (so no
DOCTYPE and no entity declarations: expat would expand internal entities), parsed by
:mod:`xml.etree.ElementTree`; any order of elements and attributes, extra elements
ignored; numbers finite and at most :data:`MAX_ABS_VALUE` in magnitude; a missing
correction attribute is 0. Anything else raises :class:`~gtmodel.robot_sim.state.ReplyError`
with a reason the simulator counts.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from dataclasses import dataclass

import numpy as np

from gtmodel.robot_sim.state import Command, ReplyError, RobotState

__all__ = ["DEFAULT_PORT", "DEFAULT_SEN_TYPE", "MAX_REPLY_BYTES", "MAX_ABS_VALUE", "CART_TAGS", "AXIS_TAGS", "SenReply",
           "compose_rob", "parse_sen", "parse_rob", "compose_sen"]

#: The usual port of the sensor side (the robot sends to it).
DEFAULT_PORT = 49152
#: Default ``Type`` of ``<Sen>`` (must match the robot's configuration, ``SENTYPE``).
DEFAULT_SEN_TYPE = "ImFree"
#: Largest reply accepted [bytes].
MAX_REPLY_BYTES = 4096
#: Largest magnitude of a number in a reply [mm or deg].
MAX_ABS_VALUE = 1.0e6
#: Attribute names of a Cartesian element.
CART_TAGS = ("X", "Y", "Z", "A", "B", "C")
#: Attribute names of an axis element.
AXIS_TAGS = ("A1", "A2", "A3", "A4", "A5", "A6")
#: Longest IPOC text [digits].
_MAX_IPOC_DIGITS = 20


def _attrs(names: tuple[str, ...], values: np.ndarray, nan_first: bool = False) -> str:
    vals = [float(v) for v in values] + [0.0] * (len(names) - len(values))
    if nan_first:
        vals[0] = math.nan
    return " ".join(f'{n}="{v:.6f}"' for n, v in zip(names, vals))


def compose_rob(state: RobotState, ipoc: int, delay: int = 0, nan_field: bool = False) -> bytes:
    """The robot's datagram of one cycle.

    Parameters
    ----------
    state : RobotState
        The cycle's pose and axes (mm, deg); up to 6 axes (fewer are padded with 0).
    ipoc : int
        The cycle's time stamp [ms], >= 0.
    delay : int, optional
        Late replies so far (``<Delay D=..>``).
    nan_field : bool, optional
        Write ``RIst X`` as NaN (the ``nan`` fault).

    Returns
    -------
    bytes
        The ``<Rob>`` document, ASCII.
    """
    return (f'<Rob Type="KUKA"><RIst {_attrs(CART_TAGS, state.cart_actual, nan_field)}/>'
            f'<RSol {_attrs(CART_TAGS, state.cart_setpoint)}/>'
            f'<AIPos {_attrs(AXIS_TAGS, state.joints_actual[:6])}/><ASPos {_attrs(AXIS_TAGS, state.joints_setpoint[:6])}/>'
            f'<Delay D="{int(delay)}"/><IPOC>{int(ipoc)}</IPOC></Rob>').encode("ascii")


@dataclass(frozen=True)
class SenReply:
    """A parsed ``<Sen>`` reply.

    Parameters
    ----------
    ipoc : int
        The echoed time stamp [ms].
    rkorr : numpy.ndarray or None, shape (6,)
        ``RKorr`` X, Y, Z [mm], A, B, C [deg], or None when absent.
    akorr : numpy.ndarray or None, shape (6,)
        ``AKorr`` (or ``AK``) A1..A6 [deg], or None when absent.
    sen_type : str
        The ``Type`` attribute.
    estr : str or None
        The ``EStr`` text (a message of the sensor side).
    """

    ipoc: int
    rkorr: np.ndarray | None
    akorr: np.ndarray | None
    sen_type: str
    estr: str | None

    def command(self, mode: str) -> Command:
        """The reply as a :class:`~gtmodel.robot_sim.state.Command`.

        Parameters
        ----------
        mode : {"relative", "absolute"}
            How the robot applies it (RSI's correction type).

        Returns
        -------
        Command
        """
        return Command(self.rkorr, self.akorr, mode)


def _number(text: str | None, what: str) -> float:
    if text is None:
        return 0.0
    if len(text) > 40:
        raise ReplyError("malformed", f"{what}: a number of {len(text)} characters")
    try:
        v = float(text)
    except ValueError:
        raise ReplyError("malformed", f"{what}: not a number ({text[:20]!r})") from None
    if not math.isfinite(v):
        raise ReplyError("nonfinite", f"{what}: {text!r}")
    if abs(v) > MAX_ABS_VALUE:
        raise ReplyError("out_of_range", f"{what}: {v} beyond {MAX_ABS_VALUE}")
    return v


def _element(root: ET.Element, tags: tuple[str, ...], names: tuple[str, ...]) -> np.ndarray | None:
    for tag in tags:
        el = root.find(tag)
        if el is not None:
            return np.array([_number(el.get(n), f"{tag} {n}") for n in names])
    return None


def _root(data: bytes, tag: str) -> ET.Element:
    if not isinstance(data, (bytes, bytearray)):
        raise ReplyError("malformed", f"expected bytes, got {type(data).__name__}")
    if len(data) > MAX_REPLY_BYTES:
        raise ReplyError("too_long", f"{len(data)} bytes (at most {MAX_REPLY_BYTES})")
    if b"<!" in data:
        raise ReplyError("hostile", "a DOCTYPE, entity or comment declaration (<!) is not accepted")
    try:
        root = ET.fromstring(bytes(data))
    except (ET.ParseError, ValueError, UnicodeError) as exc:
        raise ReplyError("malformed", f"not XML: {exc}") from None
    if root.tag != tag:
        raise ReplyError("malformed", f"root <{root.tag[:20]}>, expected <{tag}>")
    return root


def _ipoc(root: ET.Element) -> int:
    el = root.find("IPOC")
    text = (el.text or "").strip() if el is not None else ""
    if not text or len(text) > _MAX_IPOC_DIGITS or not text.isdigit() or not text.isascii():
        raise ReplyError("malformed", f"IPOC: expected up to {_MAX_IPOC_DIGITS} digits, got {text[:24]!r}")
    return int(text)


def parse_sen(data: bytes, sen_type: str | None = DEFAULT_SEN_TYPE) -> SenReply:
    """Parse a sensor reply (untrusted bytes; see the module docstring).

    Parameters
    ----------
    data : bytes
        The datagram.
    sen_type : str or None, optional
        The ``Type`` the robot is configured for (default ``"ImFree"``); None accepts any.

    Returns
    -------
    SenReply

    Raises
    ------
    ReplyError
        Too long, a ``<!`` declaration, not XML, not ``<Sen>``, another ``Type``, no valid
        IPOC, a number that does not parse, is not finite or is out of range (``reason``
        says which).
    """
    root = _root(data, "Sen")
    typ = root.get("Type", "")
    if sen_type is not None and typ != sen_type:
        raise ReplyError("malformed", f"Sen Type {typ[:20]!r}, expected {sen_type!r}")
    estr = root.find("EStr")
    return SenReply(_ipoc(root), _element(root, ("RKorr",), CART_TAGS), _element(root, ("AKorr", "AK"), AXIS_TAGS), typ,
                    None if estr is None else (estr.text or "")[:256])


def parse_rob(data: bytes) -> tuple[int, dict[str, np.ndarray]]:
    """Parse a robot datagram (what a sensor side reads; used by the tests' peers).

    Parameters
    ----------
    data : bytes
        A ``<Rob>`` datagram.

    Returns
    -------
    ipoc : int
        The time stamp [ms].
    fields : dict of str to numpy.ndarray
        ``"RIst"``, ``"RSol"`` (6,), ``"AIPos"``, ``"ASPos"`` (6,) when present (NaN kept).

    Raises
    ------
    ReplyError
        Not a well-formed ``<Rob>`` (same rules as :func:`parse_sen`, NaN allowed).
    """
    root = _root(data, "Rob")
    out = {}
    for tag, names in (("RIst", CART_TAGS), ("RSol", CART_TAGS), ("AIPos", AXIS_TAGS), ("ASPos", AXIS_TAGS)):
        el = root.find(tag)
        if el is not None:
            out[tag] = np.array([float(el.get(n, "0")) for n in names])
    return _ipoc(root), out


def compose_sen(ipoc: int, rkorr=None, akorr=None, sen_type: str = DEFAULT_SEN_TYPE, estr: str = "gtmodel") -> bytes:
    """A sensor reply (what a sensor side sends; used by the tests' peers).

    Parameters
    ----------
    ipoc : int
        The IPOC it answers.
    rkorr : array_like, shape (6,), optional
        Cartesian correction [mm, deg].
    akorr : array_like, shape (6,), optional
        Axis correction [deg].
    sen_type : str, optional
        ``Type`` (default ``"ImFree"``).
    estr : str, optional
        ``EStr`` text.

    Returns
    -------
    bytes
    """
    parts = [f'<Sen Type="{sen_type}"><EStr>{estr}</EStr>']
    if rkorr is not None:
        parts.append(f"<RKorr {_attrs(CART_TAGS, np.asarray(rkorr, dtype=float))}/>")
    if akorr is not None:
        parts.append(f"<AKorr {_attrs(AXIS_TAGS, np.asarray(akorr, dtype=float))}/>")
    parts.append(f"<IPOC>{int(ipoc)}</IPOC></Sen>")
    return "".join(parts).encode("ascii")
