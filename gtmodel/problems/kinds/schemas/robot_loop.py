"""The schema of a ``robot_loop`` file (light: validated before the runtime is built).

A robot-loop file declares the 4 ms loop on a robot controller's position interface: the
interface (KUKA RSI or ABB EGM over UDP) and where to listen, the controller
(:mod:`gtmodel.control.position_loop`: Cvitanic's pose correction from a tracker, or a
streamed reference with its ILC correction), the limits the runtime enforces after the
controller, the fault rules and, for a streamed reference, the learning law of the next
iteration. ``gtmodel loop FILE --out DIR`` runs it (the kind is
:mod:`gtmodel.problems.kinds.robot_loop`); the field reference is ``docs/problem_files.md``
and the guide ``docs/robot.md``.
"""

from __future__ import annotations

import errno
import ipaddress
import socket
from typing import Annotated, Literal

from pydantic import BeforeValidator, Field, model_validator

from gtmodel._docstrings import fill_doc
from gtmodel.defaults import INTERFACE_PORTS, LOOP_PERIOD_S
from gtmodel.problems.base import KIND_DOCS
from gtmodel.problems.schema import Flag, NonEmptyText, ProblemSchema, Section, _fail, choice, integer, number, vector

__all__ = ["RobotLoopFile", "DEFAULT_PORTS", "parse_address", "parse_source", "local_address_problem", "MAX_AXES", "MAX_SEN_TYPE"]

#: The interfaces' usual ports (the sensor side listens, the robot sends to it).
DEFAULT_PORTS = INTERFACE_PORTS
#: Most outputs (axes) of a loop.
MAX_AXES = 12
#: Longest RSI ``Sen Type`` string.
MAX_SEN_TYPE = 32


def parse_address(text: str) -> tuple[str, int]:
    """``"HOST:PORT"`` with an IPv4 address (no host names: nothing is looked up) and a port in 1..65535.

    Parameters
    ----------
    text : str
        E.g. ``"127.0.0.1:49152"`` or ``"0.0.0.0:6510"``.

    Returns
    -------
    tuple of (str, int)
        The address and the port.

    Raises
    ------
    ValueError
        Another form, naming what was expected.
    """
    expected = "HOST:PORT with an IPv4 address and a port in 1..65535, e.g. 127.0.0.1:49152"
    if not isinstance(text, str) or text.count(":") != 1 or len(text) > 21:
        raise ValueError(f"expected {expected}, got {text!r}")
    host, port = text.split(":")
    try:
        ipaddress.IPv4Address(host)
    except ValueError:
        raise ValueError(f"expected {expected}, got {text!r}") from None
    if not _ascii_port(port):
        raise ValueError(f"expected {expected}, got {text!r}")
    return host, int(port)


def _ascii_port(text: str) -> bool:
    """A port written in ASCII digits 1..65535 (``str.isdigit`` and ``int`` also take other scripts' digits, e.g. Arabic-Indic)."""
    return text.isascii() and text.isdigit() and 1 <= int(text) <= 65535


def local_address_problem(host: str) -> str | None:
    """Why the runtime could not listen on ``host`` of this machine, or None when it can.

    Checked when a loop file is loaded (before anything is generated or built) by binding a
    UDP socket to ``host`` and a free port, then closing it: an address of another machine
    (``8.8.8.8``) is refused here, not at the runtime's bind after the build.

    Parameters
    ----------
    host : str
        An IPv4 address (:func:`parse_address`'s).

    Returns
    -------
    str or None
        What is wrong, in words, or None.
    """
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as probe:
        try:
            probe.bind((host, 0))
        except OSError as exc:
            if exc.errno == errno.EADDRNOTAVAIL:
                return (f"an address of this machine (0.0.0.0: every interface, 127.0.0.1: this machine only); {host} is "
                        "not one of its interfaces' addresses")
            return f"an address this machine can listen on ({exc.strerror or exc})"
    return None


def _address(v: object) -> object:
    try:
        parse_address(v)  # type: ignore[arg-type]
    except ValueError:
        raise _fail("HOST:PORT with an IPv4 address and a port in 1..65535, e.g. 127.0.0.1:49152") from None
    return v


#: A listening address ``HOST:PORT``.
Address = Annotated[str, BeforeValidator(_address)]


def parse_source(text: str) -> tuple[str, int | None]:
    """A sender's address: ``"ADDR"`` or ``"ADDR:PORT"`` with an IPv4 address (nothing is looked up).

    Parameters
    ----------
    text : str
        E.g. ``"192.168.1.20"`` or ``"192.168.1.20:6511"``.

    Returns
    -------
    tuple of (str, int or None)
        The address and the port (None: any port of that address, the first valid packet's
        locked for the session).

    Raises
    ------
    ValueError
        Another form, naming what was expected.
    """
    expected = "an IPv4 address, optionally with :PORT (1..65535), e.g. 192.168.1.20 or 192.168.1.20:6511"
    if not isinstance(text, str) or text.count(":") > 1 or len(text) > 21:
        raise ValueError(f"expected {expected}, got {text!r}")
    host, _, port = text.partition(":")
    try:
        ipaddress.IPv4Address(host)
    except ValueError:
        raise ValueError(f"expected {expected}, got {text!r}") from None
    if ":" in text and not _ascii_port(port):
        raise ValueError(f"expected {expected}, got {text!r}")
    return host, (int(port) if port else None)


def _source(v: object) -> object:
    try:
        parse_source(v)  # type: ignore[arg-type]
    except ValueError:
        raise _fail("an IPv4 address, optionally with :PORT (1..65535), e.g. 192.168.1.20 or 192.168.1.20:6511") from None
    return v


#: A sender's address ``ADDR`` or ``ADDR:PORT``.
Source = Annotated[str, BeforeValidator(_source)]


def _sen_type(v: object) -> object:
    if not (isinstance(v, str) and 0 < len(v) <= MAX_SEN_TYPE and v.replace("_", "").isalnum() and v.isascii()):
        raise _fail(f"1 to {MAX_SEN_TYPE} ASCII letters, digits or '_' (it is written into every reply)")
    return v


class InterfaceSection(Section):
    """``[interface]``: the robot controller's interface and where the runtime listens."""

    type: choice("rsi", "egm", description="KUKA Robot Sensor Interface (XML over UDP) or ABB Externally Guided Motion (protobuf over UDP)")
    listen: Address | None = Field(default=None, description="HOST:PORT the runtime listens on; the robot sends there and gets its reply "
                                   "(default 127.0.0.1 and the interface's usual port: RSI 49152, EGM 6510; gtmodel loop --listen overrides)")
    sensor_port: integer(1, 65535, description="UDP port of the sensor stream (the tracker's GTS1 datagrams) on the listen address "
                                              "(default: the listen port + 1; only a pose correction reads it)") | None = None
    robot: Source | None = Field(default=None, description="the robot controller's address (ADDR or ADDR:PORT): only its datagrams are "
                                 "answered (default: the first valid packet's source is locked for the session; docs/robot.md, the network rules)")
    tracker: Source | None = Field(default=None, description="the sensor stream's sender (ADDR or ADDR:PORT; default: the first valid "
                                   "sample's source is locked for the session)")
    log_max_mb: number(gt=0, le=1e6, unit="MB", description="the cycle log's cap: rows past it are counted (loop.log.capped), not written "
                                                           "(default: an hour of rows at the period)") | None = None
    period: number(gt=0, le=0.1, unit="s", description="the robot's interpolation cycle") = LOOP_PERIOD_S
    idle_timeout: number(gt=0, le=3600, unit="s", description="the run ends when the robot has sent nothing this long after its first packet") = 2.0
    max_cycles: integer(0, 100_000_000, description="the run ends after this many cycles (0: no limit)") = 0
    time_limit: number(gt=0, le=86400, unit="s", description="the run ends after this long in any case") = 3600.0
    reply_deadline: number(gt=0, le=0.1, unit="s", description="a reply later than this after its packet arrived is replaced by the held one "
                                                               "(docs/robot.md, the deadline rule)") = 0.002
    sen_type: Annotated[str, BeforeValidator(_sen_type)] = Field(default="ImFree", description="RSI: the Type of the <Sen> reply (must match the robot's RSI configuration)")
    correction: choice("relative", "absolute", description="RSI: the robot sums the corrections it gets (relative, "
                                                           "RSI's usual mode) or takes each as the total") = "relative"
    egm_mode: choice("joint", "cartesian", "path_correction", description="EGM: position guidance in joints or Cartesian, or path correction") = "joint"


class ControllerSection(Section):
    """``[controller]``: what the step computes (:mod:`gtmodel.control.position_loop`)."""

    type: choice("pose_correction", "streaming", description="Cvitanic's P correction of the TCP from a tracker (RSI), "
                                                              "or a planned trajectory streamed with its ILC correction (EGM)")
    gain: vector(3, nonnegative=True, bound=1.0, description="pose_correction: K per direction x, y, z (0: not corrected)", unit="1/cycle") | None = None
    sensor_scale: number(gt=0, le=1e6, description="pose_correction: the robot's length unit per sensor unit (1000: a tracker in m, RSI in mm)") = 1000.0
    reference_includes_correction: Flag = Field(default=False, description="pose_correction: the robot's RSol holds the corrections sent so far")
    trajectory: NonEmptyText | None = Field(default=None, description="streaming: CSV of the planned positions, one row per period "
                                            "(a header row; columns t then one per axis, robot units: mm or deg), relative to this file")
    correction_file: NonEmptyText | None = Field(default=None, description="streaming: the learned correction to add "
                                                 "(a previous run's ilc_next.csv), relative to this file; default none")

    @model_validator(mode="after")
    def _fields_of_type(self) -> "ControllerSection":
        if self.type == "pose_correction" and self.gain is None:
            raise _fail("a gain for a pose_correction (K per direction x, y, z)")
        if self.type == "streaming" and self.trajectory is None:
            raise _fail("a trajectory for streaming (the planned positions' CSV)")
        if self.type == "pose_correction" and (self.trajectory is not None or self.correction_file is not None):
            raise _fail("no trajectory or correction_file for a pose_correction (they are streaming's)")
        return self


class LimitsSection(Section):
    """``[limits]``: what the runtime enforces on every reply, after the controller."""

    lower: vector(None, max_length=MAX_AXES, bound=1e6, description="lowest value per output (mm or deg; a total correction for RSI)")
    upper: vector(None, max_length=MAX_AXES, bound=1e6, description="highest value per output")
    rate: vector(None, max_length=MAX_AXES, positive=True, bound=1e6, description="largest change per output and cycle")

    @model_validator(mode="after")
    def _same_length(self) -> "LimitsSection":
        if not len(self.lower) == len(self.upper) == len(self.rate):
            raise _fail(f"one value per output in each of lower, upper, rate (they have {len(self.lower)}, {len(self.upper)}, {len(self.rate)})")
        if any(lo > hi for lo, hi in zip(self.lower, self.upper)):
            raise _fail("lower <= upper per output")
        return self


class FaultsSection(Section):
    """``[faults]``: what the runtime does when data is missing or wrong (docs/robot.md, the safety rules)."""

    stale_cycles: integer(1, 10_000, description="sensor data older than this many cycles is stale") = 10
    fallback: choice("hold", "ramp", description="on stale sensor data or a failed step: hold the last reply, or ramp at the "
                                                 "rate limit to no correction (RSI) or the start position (EGM)") = "hold"


class ILCSection(Section):
    """``[ilc]``: the learning law of the next iteration, Dressler (2012), eq. 7.2 (streaming only)."""

    gamma: number(gt=0, le=2, description="learning gain of L = gamma q^delta") = 0.9
    delta: integer(0, 1000, description="learning lead of L in cycles (the loop's delay)") = 5
    q_cutoff_hz: number(gt=0, le=1000, unit="Hz", description="cut-off of the zero-phase Butterworth Q filter") = 10.0
    lead: integer(0, 100_000, description="samples at rest before and after the motion, where Q's time window rises and falls (0: no window)") = 0
    tukey_points: integer(2, 200_000, description="length of the Tukey window whose halves are the window's ramps (Dressler: 200)") = 200
    tukey_alpha: number(ge=0, le=1, description="the Tukey window's taper fraction (Dressler: 0.95)") = 0.95


@fill_doc(**KIND_DOCS)
class RobotLoopFile(ProblemSchema):
    """A ``robot_loop`` file.

    Parameters
    ----------
    {header_fields}
    interface : InterfaceSection
        ``[interface]``: RSI or EGM, where to listen, period, deadline, when the run ends.
    controller : ControllerSection
        ``[controller]``: pose correction or streaming.
    limits : LimitsSection
        ``[limits]``: bounds and rate per output, enforced after the controller.
    faults : FaultsSection
        ``[faults]``: stale data and the fallback.
    ilc : ILCSection or None
        ``[ilc]``: the next iteration's learning law (streaming only).
    """

    kind: Literal["robot_loop"]
    interface: InterfaceSection
    controller: ControllerSection
    limits: LimitsSection
    faults: FaultsSection = FaultsSection()
    ilc: ILCSection | None = None

    @model_validator(mode="after")
    def _consistent(self) -> "RobotLoopFile":
        if self.controller.type == "pose_correction" and len(self.limits.lower) != 3:
            raise _fail("3 values per limit for a pose_correction (its outputs x, y, z) in [limits]")
        if self.ilc is not None and self.controller.type != "streaming":
            raise _fail("no [ilc] table for a pose_correction (the next ILC iteration is streaming's)")
        if self.controller.type == "pose_correction" and self.interface.type != "rsi":
            raise _fail('interface.type = "rsi" for a pose_correction (RSI carries its RKorr)')
        return self
