"""The robot runtime's C: a loop step behind KUKA RSI or ABB EGM over UDP, as one executable.

A :class:`RobotRuntime` is a :class:`~gtmodel.codegen.code_source.CodeSource` that owns a
:class:`~gtmodel.codegen.loop_step.LoopStep` (the controller, the one C step interface
``PREFIX_step``) and a :class:`RuntimeSpec` (the interface, which packet fields make the step's
``x``, which reply fields its ``u`` fills, the limits and the fault rules). Its
:meth:`~RobotRuntime.generate` writes the step through
:func:`~gtmodel.codegen.loop_step.generate_loop_step`, copies the runtime's C
(``harness/runtime/``: ``gt_runtime.c`` with its report ``gt_runtime_report.c``, the network guard
``gt_guard.c`` (one robot per session, strangers, the sequence window), the RSI XML parser ``gt_rsi.c``, the EGM protobuf
messages ``gt_egm.c`` through the vendored nanopb 0.4.9.1 and ``egm.pb.c`` generated from ABB's
``egm.proto``, the ``GTS1`` sensor stream ``gt_sensor_stream.c``) and writes
``gt_runtime_config.h`` (field indices, limits as C initialisers, validated names only);
:func:`build_runtime` compiles one executable with the system C compiler
(``-std=c11 -O2 -Wall -Wextra -Wpedantic -Wshadow -Werror -pthread``). :func:`gtmodel.control.runtime.run_loop`
runs it.

The executable's rules (the module docstring of ``gt_runtime.c`` and ``docs/robot.md``):
malformed datagrams get no reply; non-finite fields, duplicate or older IPOC/seqno and missing
input fields get the held reply and never reach the step; stale sensor data or a failed step
get the fallback (``hold`` the last reply, or ``ramp`` at the rate limit towards zero for
corrections / the start position for EGM guidance); the limits ``lower <= reply <= upper`` and
``|reply - last reply| <= rate`` are applied after the step and nothing changes a value after
them. Deadline rule: a reply computed later than ``reply_deadline_s`` after the datagram's
arrival is replaced by the held reply if the period has not passed yet (it still reaches the
robot within its cycle, so RSI does not count it late); at or after the period no reply is sent
and the robot counts that cycle late. RSI ``correction = "relative"``: the runtime keeps the
limited total correction and sends its increment per cycle.

Field names: RSI inputs ``RIst.X``.. ``RIst.C``, ``RSol.*``, ``AIPos.A1``.. ``A6``,
``ASPos.*``, ``ELPos.E1``.. ``E6``, ``ESPos.*``, ``Delay.D`` (mm, degrees); RSI outputs
``RKorr.X``.. ``RKorr.C``, ``AKorr.A1``.. ``A6``, ``EKorr.E1``.. ``E6``. EGM inputs
``feedback.joints.0``.. ``11``, ``feedback.cartesian.x|y|z``, ``feedback.orient.u0``.. ``u3``,
``planned.joints.*``, ``planned.cartesian.*``, ``planned.orient.*``,
``feedback.externalJoints.0``.. ``5``, ``planned.externalJoints.*`` (degrees, mm; linear axes
in ``joints`` as mm); EGM outputs ``planned.joints.0``.. (joint mode), ``planned.cartesian.x|y|z``
(Cartesian mode, the robot's orientation echoed), ``pathcorr.x|y|z`` (path correction). The
sensor stream's values are ``sensor.0``.. ``sensor.15``.
"""

from __future__ import annotations

import logging
import math
import re
import shutil
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from gtmodel._compiler import find_compiler, run_compiler
from gtmodel._escape import c_string, check_c_identifier
from gtmodel.codegen.build import stack_work_bytes
from gtmodel.codegen.code_source import CodeSource
from gtmodel.codegen.declarations import FunctionSpec
from gtmodel.codegen.loop_step import LoopStep, generate_loop_step
from gtmodel.codegen.writer import GeneratedCode
from gtmodel.errors import CodegenError, InputError
from gtmodel.defaults import INTERFACE_PORTS, LOOP_PERIOD_S

__all__ = ["RSI_INPUTS", "RSI_OUTPUTS", "EGM_INPUTS", "EGM_OUTPUTS", "SENSOR_INPUTS", "DEFAULT_PORTS", "RUNTIME_FLAGS",
           "RUNTIME_SOURCES", "BUILD_FLAGS", "CYCLE_STACK_BASE", "CYCLE_STACK_MAX", "RuntimeSpec", "RobotRuntime", "build_runtime",
           "cycle_stack_bytes"]

log = logging.getLogger("gtmodel")

_XYZABC = ("X", "Y", "Z", "A", "B", "C")
#: The measured fields of RSI's ``<Rob>``, in the C parser's order (``gt_rsi.h``).
RSI_INPUTS: tuple[str, ...] = (
    tuple(f"RIst.{a}" for a in _XYZABC) + tuple(f"RSol.{a}" for a in _XYZABC)
    + tuple(f"AIPos.A{i}" for i in range(1, 7)) + tuple(f"ASPos.A{i}" for i in range(1, 7))
    + tuple(f"ELPos.E{i}" for i in range(1, 7)) + tuple(f"ESPos.E{i}" for i in range(1, 7)) + ("Delay.D",))
#: The reply fields of RSI's ``<Sen>``, in the composer's order.
RSI_OUTPUTS: tuple[str, ...] = (tuple(f"RKorr.{a}" for a in _XYZABC) + tuple(f"AKorr.A{i}" for i in range(1, 7))
                                + tuple(f"EKorr.E{i}" for i in range(1, 7)))
_XYZ = ("x", "y", "z")
_QUAT = ("u0", "u1", "u2", "u3")
#: The measured fields of EGM's ``EgmRobot``, in the C decoder's order (``gt_egm.h``).
EGM_INPUTS: tuple[str, ...] = (
    tuple(f"feedback.joints.{i}" for i in range(12)) + tuple(f"feedback.cartesian.{a}" for a in _XYZ)
    + tuple(f"feedback.orient.{a}" for a in _QUAT) + tuple(f"planned.joints.{i}" for i in range(12))
    + tuple(f"planned.cartesian.{a}" for a in _XYZ) + tuple(f"planned.orient.{a}" for a in _QUAT)
    + tuple(f"feedback.externalJoints.{i}" for i in range(6)) + tuple(f"planned.externalJoints.{i}" for i in range(6)))
#: The reply fields of EGM per mode (joint: the first n joints, all of them in any order).
EGM_OUTPUTS: dict[str, tuple[str, ...]] = {
    "joint": tuple(f"planned.joints.{i}" for i in range(12)),
    "cartesian": tuple(f"planned.cartesian.{a}" for a in _XYZ),
    "path_correction": tuple(f"pathcorr.{a}" for a in _XYZ),
}
#: The values of the ``GTS1`` sensor stream.
SENSOR_INPUTS: tuple[str, ...] = tuple(f"sensor.{i}" for i in range(16))
#: The usual ports the sensor side listens on (the robot sends to them).
DEFAULT_PORTS = INTERFACE_PORTS
#: Flags of a cycle-log row (bit values of its ``flags`` column; ``gt_runtime.c``).
RUNTIME_FLAGS = {"sent": 1, "step": 2, "held": 4, "fallback_stale": 8, "fallback_step": 16, "ramp": 32, "malformed": 64,
                 "non_finite": 128, "duplicate_or_old": 256, "missing_field": 512, "deadline_held": 1024, "late_dropped": 2048,
                 "clamped": 4096, "no_safe_reply": 8192, "too_long": 16384, "out_of_window": 32768, "resync": 65536, "unapplied": 131072,
                 "sent_late": 262144}
#: The runtime's C files copied next to the step (folder ``harness/runtime/`` of the package).
RUNTIME_SOURCES = ("gt_runtime.c", "gt_runtime_report.c", "gt_runtime_state.h", "gt_guard.c", "gt_guard.h", "gt_rsi.c", "gt_rsi.h", "gt_egm.c", "gt_egm.h", "gt_sensor_stream.c", "gt_sensor_stream.h",
                   "egm.pb.c", "egm.pb.h", "egm.proto", "egm.options", "nanopb/pb.h", "nanopb/pb_common.c", "nanopb/pb_common.h",
                   "nanopb/pb_decode.c", "nanopb/pb_decode.h", "nanopb/pb_encode.c", "nanopb/pb_encode.h", "nanopb/LICENSE.txt",
                   "nanopb/README.md")
_HARNESS = Path(__file__).resolve().parent / "harness" / "runtime"
#: Largest accepted magnitude of a limit (mm, degrees; a limit must bound the correction).
LIMIT_MAX = 1.0e6
_SEN_TYPE = re.compile(r"[A-Za-z0-9_]{1,64}")


def _tuple(name: str, value: Any, kind: type) -> tuple:
    if isinstance(value, (str, bytes)) or not hasattr(value, "__iter__"):
        raise InputError(f"{name}: expected a sequence, got {type(value).__name__}")
    out = tuple(value)
    for v in out:
        if kind is float:
            if isinstance(v, bool) or not isinstance(v, (int, float)) and not hasattr(v, "__float__"):
                raise InputError(f"{name}: expected numbers, got {v!r}")
        elif not isinstance(v, kind):
            raise InputError(f"{name}: expected {kind.__name__} items, got {v!r}")
    return tuple(float(v) for v in out) if kind is float else out


@dataclass(frozen=True)
class RuntimeSpec:
    """What the runtime does around the step: interface, field maps, limits, fault rules.

    Every field is validated when the spec is made (an :class:`~gtmodel.errors.InputError`
    naming the field).

    Parameters
    ----------
    interface : {"rsi", "egm"}
        KUKA RSI (XML) or ABB EGM (protobuf), both over UDP, the robot the client.
    inputs : sequence of str
        ``(nx,)`` the packet fields (or ``sensor.k``) that make the step's ``x``, in order
        (:data:`RSI_INPUTS`, :data:`EGM_INPUTS`, :data:`SENSOR_INPUTS`; mm, degrees).
    outputs : sequence of str
        ``(nu,)`` the reply fields the step's ``u`` fills, in order (:data:`RSI_OUTPUTS`;
        :data:`EGM_OUTPUTS` of ``egm_mode``: joint mode ``planned.joints.0..n-1`` all of them).
    lower, upper : sequence of float
        ``(nu,)`` the bounds of every reply [mm or deg]; finite, ``|.| <= 1e6``; RSI
        corrections must allow zero (``lower <= 0 <= upper``).
    rate : sequence of float
        ``(nu,)`` the largest change of a reply per cycle [mm or deg per cycle], positive, finite
        (RSI: at least 1e-6, its numbers' last decimal).
    egm_mode : {"joint", "cartesian", "path_correction"}, optional
        EGM's reply: ``EgmSensor`` planned joints, ``EgmSensor`` planned Cartesian position,
        or ``EgmSensorPathCorr``.
    correction : {"relative", "absolute"}, optional
        RSI: the robot sums increments (``relative``: the runtime sends the increment of the
        limited total) or takes the total (``absolute``). Not used by EGM.
    sen_type : str, optional
        RSI's ``<Sen Type="...">`` (must match the robot's configuration): letters, digits, ``_``.
    fallback : {"hold", "ramp"}, optional
        On stale sensor data or a failed step: hold the last reply, or ramp at the rate limit
        (to zero for corrections, to the start position for EGM joint / Cartesian guidance).
    stale_cycles : int, optional
        Sensor data older than this many robot cycles is stale.
    reply_deadline_s : float, optional
        Time after a datagram's arrival after which the held reply replaces a computed one [s];
        ``0 < reply_deadline_s < period``.
    period : float, optional
        The robot's cycle [s] (RSI and EGM: 0.004).

    Raises
    ------
    InputError
        A field of the wrong type, size or value (the message names it).
    """

    interface: str
    inputs: tuple[str, ...]
    outputs: tuple[str, ...]
    lower: tuple[float, ...]
    upper: tuple[float, ...]
    rate: tuple[float, ...]
    egm_mode: str = "joint"
    correction: str = "relative"
    sen_type: str = "ImFree"
    fallback: str = "hold"
    stale_cycles: int = 10
    reply_deadline_s: float = 0.002
    period: float = LOOP_PERIOD_S

    def __post_init__(self) -> None:
        if self.interface not in ("rsi", "egm"):
            raise InputError(f"interface: expected 'rsi' or 'egm', got {self.interface!r}")
        if self.egm_mode not in EGM_OUTPUTS:
            raise InputError(f"egm_mode: expected one of {', '.join(EGM_OUTPUTS)}, got {self.egm_mode!r}")
        for name in ("inputs", "outputs"):
            object.__setattr__(self, name, _tuple(name, getattr(self, name), str))
        for name in ("lower", "upper", "rate"):
            object.__setattr__(self, name, _tuple(name, getattr(self, name), float))
        known_in = (RSI_INPUTS if self.interface == "rsi" else EGM_INPUTS) + SENSOR_INPUTS
        if not self.inputs or len(set(self.inputs)) != len(self.inputs):
            raise InputError(f"inputs: expected distinct field names, got {list(self.inputs)}")
        for f in self.inputs:
            if f not in known_in:
                raise InputError(f"inputs: {f!r} is not a field of {self.interface.upper()} or the sensor stream "
                                 f"(e.g. {known_in[0]!r}, {known_in[-1]!r})")
        if not self.outputs or len(set(self.outputs)) != len(self.outputs):
            raise InputError(f"outputs: expected distinct reply fields, got {list(self.outputs)}")
        known_out = RSI_OUTPUTS if self.interface == "rsi" else EGM_OUTPUTS[self.egm_mode]
        for f in self.outputs:
            if f not in known_out:
                raise InputError(f"outputs: {f!r} is not a reply field of {self.interface.upper()}"
                                 + (f" in egm_mode {self.egm_mode!r}" if self.interface == "egm" else "") + f" ({', '.join(known_out[:6])}, ...)")
        if self.interface == "egm" and set(self.outputs) != set(known_out[:len(self.outputs)] if self.egm_mode == "joint" else known_out):
            raise InputError(f"outputs: EGM {self.egm_mode} mode sends all of "
                             + (f"planned.joints.0..{len(self.outputs) - 1}" if self.egm_mode == "joint" else ", ".join(known_out)))
        n = len(self.outputs)
        for name in ("lower", "upper", "rate"):
            v = getattr(self, name)
            if len(v) != n:
                raise InputError(f"{name}: expected {n} values (one per output), got {len(v)}")
            if not all(math.isfinite(x) and abs(x) <= LIMIT_MAX for x in v):
                raise InputError(f"{name}: expected finite values of magnitude at most {LIMIT_MAX:g}, got {list(v)}")
        if any(lo > hi for lo, hi in zip(self.lower, self.upper)):
            raise InputError(f"lower, upper: expected lower <= upper per output, got {list(self.lower)} and {list(self.upper)}")
        if any(r <= 0 for r in self.rate):
            raise InputError(f"rate: expected positive rates per cycle, got {list(self.rate)}")
        if self.interface == "rsi" and any(r < 1e-6 for r in self.rate):
            raise InputError(f"rate: RSI's numbers have 6 decimals; expected rates of at least 1e-6 per cycle, got {list(self.rate)}")
        if self.interface == "rsi" and any(lo > 0 or hi < 0 for lo, hi in zip(self.lower, self.upper)):
            raise InputError("lower, upper: RSI corrections start at zero; expected lower <= 0 <= upper")
        if self.correction not in ("relative", "absolute"):
            raise InputError(f"correction: expected 'relative' or 'absolute', got {self.correction!r}")
        if not isinstance(self.sen_type, str) or not _SEN_TYPE.fullmatch(self.sen_type):
            raise InputError(f"sen_type: expected 1 to 64 ASCII letters, digits or '_', got {self.sen_type!r}")
        if self.fallback not in ("hold", "ramp"):
            raise InputError(f"fallback: expected 'hold' or 'ramp', got {self.fallback!r}")
        if isinstance(self.stale_cycles, bool) or not isinstance(self.stale_cycles, int) or not 1 <= self.stale_cycles <= 1_000_000:
            raise InputError(f"stale_cycles: expected an integer in 1..1000000, got {self.stale_cycles!r}")
        if not (isinstance(self.period, (int, float)) and math.isfinite(self.period) and 0 < self.period <= 1.0):
            raise InputError(f"period: expected a cycle in (0, 1] s, got {self.period!r}")
        if not (isinstance(self.reply_deadline_s, (int, float)) and 0 < self.reply_deadline_s < self.period):
            raise InputError(f"reply_deadline_s: expected 0 < reply_deadline_s < period = {self.period:g} s, got {self.reply_deadline_s!r}")

    @property
    def relative(self) -> bool:
        """True when the runtime sends increments (RSI with ``correction = "relative"``)."""
        return self.interface == "rsi" and self.correction == "relative"


@dataclass(frozen=True)
class RobotRuntime(CodeSource):
    """A loop step behind a robot interface: the source of the runtime's executable.

    Parameters
    ----------
    step : LoopStep
        The controller; ``x`` are :attr:`RuntimeSpec.inputs`, ``u`` :attr:`RuntimeSpec.outputs`
        and its period is :attr:`RuntimeSpec.period`.
    spec : RuntimeSpec
        Interface, field maps, limits and fault rules.

    Raises
    ------
    InputError
        The step's sizes or period disagree with the spec.
    """

    step: LoopStep
    spec: RuntimeSpec
    #: The :class:`~gtmodel.codegen.code_source.CodeSource` kind.
    kind = "robot_runtime"

    def __post_init__(self) -> None:
        if not isinstance(self.step, LoopStep):
            raise InputError(f"step: expected a LoopStep, got {type(self.step).__name__}")
        if not isinstance(self.spec, RuntimeSpec):
            raise InputError(f"spec: expected a RuntimeSpec, got {type(self.spec).__name__}")
        self.step.validate()
        if self.step.nx != len(self.spec.inputs) or self.step.nu != len(self.spec.outputs):
            raise InputError(f"step: expected nx = {len(self.spec.inputs)} inputs and nu = {len(self.spec.outputs)} outputs "
                             f"of the spec, got nx = {self.step.nx}, nu = {self.step.nu}")
        if abs(self.step.dt - self.spec.period) > 1e-12 * self.spec.period:
            raise InputError(f"step: its period dt = {self.step.dt:g} s differs from the spec's period {self.spec.period:g} s")

    def _summary(self) -> str:
        return (f"the {self.spec.interface.upper()} runtime ({self.spec.period:g} s cycle over UDP) around "
                f"{self.step._summary()}")

    def _specs(self) -> tuple[FunctionSpec, ...]:
        return self.step._specs()

    def _target(self, spec: FunctionSpec) -> Any:
        return self.step._target(spec)

    def _evaluate(self, spec: FunctionSpec, inputs: Any) -> dict:
        return self.step._evaluate(spec, inputs)

    def _write(self, out_dir: str | Path, real: str, prefix: str | None) -> GeneratedCode:
        prefix = check_c_identifier(prefix or "gt_loop", "prefix", "gt_loop")
        generated = generate_loop_step(self.step, out_dir, prefix=prefix, real=real)
        stack = cycle_stack_bytes(generated)
        out = Path(out_dir)
        try:
            (out / "nanopb").mkdir(exist_ok=True)
            for name in RUNTIME_SOURCES:
                shutil.copyfile(_HARNESS / name, out / name)
            (out / "gt_runtime_config.h").write_text(_config(self.spec, prefix, stack))
        except OSError as exc:
            raise CodegenError(f"cannot write the runtime's sources to {out}: {exc.strerror or exc}") from None
        log.info("codegen: wrote the %s runtime around %s in %s (cycle thread stack %d bytes)", self.spec.interface.upper(),
                 self.step.name, out, stack)
        return generated


#: The cycle thread's stack besides the step's work arrays [bytes]: the runtime's own frames (its buffers are static).
CYCLE_STACK_BASE = 1 << 20
#: The largest cycle-thread stack a runtime is built with [bytes] (``mlockall`` locks it where permitted).
CYCLE_STACK_MAX = 256 << 20


def cycle_stack_bytes(generated: GeneratedCode) -> int:
    """The runtime's cycle-thread stack for a generated step [bytes].

    The generated wrappers declare CasADi's work arrays on the stack (an MPC's run to megabytes),
    so the thread that calls the step gets :data:`CYCLE_STACK_BASE` plus the stack work of every
    generated function (:func:`~gtmodel.codegen.build.stack_work_bytes`; summed, though the step
    calls them one after another), rounded up to 64 KiB. A fixed 1 MiB stack let a step with
    1.6 MB of work arrays kill the runtime by SIGSEGV at its first cycle.

    Parameters
    ----------
    generated : GeneratedCode
        The step's generated code (its ``work_sizes`` and ``real``).

    Returns
    -------
    int
        Bytes, at least :data:`CYCLE_STACK_BASE`.

    Raises
    ------
    CodegenError
        The stack would exceed :data:`CYCLE_STACK_MAX`.
    """
    real = getattr(generated, "real", "double")
    work = sum(stack_work_bytes(sizes, real) for sizes in generated.work_sizes.values())
    stack = CYCLE_STACK_BASE + -(-work // 65536) * 65536
    if stack > CYCLE_STACK_MAX:
        raise CodegenError(f"the step's stack work arrays take {work} bytes: over the runtime's cycle-thread stack cap of "
                           f"{CYCLE_STACK_MAX} bytes with its {CYCLE_STACK_BASE} of its own (a shorter horizon or blocked inputs "
                           "shrink an MPC's)")
    return stack


def _c_doubles(values: tuple[float, ...]) -> str:
    return ", ".join(repr(float(v)) for v in values)


def _config(spec: RuntimeSpec, prefix: str, cycle_stack: int = CYCLE_STACK_BASE) -> str:
    """``gt_runtime_config.h``: the spec as C (validated names; numbers as ``repr``), the cycle thread's stack (bytes)."""
    table = RSI_INPUTS if spec.interface == "rsi" else EGM_INPUTS
    x_source = [-1 - SENSOR_INPUTS.index(f) if f in SENSOR_INPUTS else table.index(f) for f in spec.inputs]
    nsensor = max([SENSOR_INPUTS.index(f) + 1 for f in spec.inputs if f in SENSOR_INPUTS], default=0)
    if spec.interface == "rsi":
        slots = [RSI_OUTPUTS.index(f) for f in spec.outputs]
        nreply, init, init2 = len(RSI_OUTPUTS), [-1] * len(slots), [-1] * len(slots)
        elements = sum(1 << k for k in range(3) if any(s // 6 == k for s in slots))
    else:
        slots = [EGM_OUTPUTS[spec.egm_mode].index(f) for f in spec.outputs]
        nreply, elements = (len(slots) if spec.egm_mode == "joint" else 3), 0
        if spec.egm_mode == "path_correction":
            init, init2 = [-1] * len(slots), [-1] * len(slots)
        else:
            planned = "planned.joints." if spec.egm_mode == "joint" else "planned.cartesian."
            feedback = "feedback.joints." if spec.egm_mode == "joint" else "feedback.cartesian."
            names = [f.rsplit(".", 1)[1] for f in spec.outputs]
            init = [EGM_INPUTS.index(feedback + n) for n in names]  # the measured position first: the rate limit from it
            init2 = [EGM_INPUTS.index(planned + n) for n in names]
    mode = {"joint": "GT_EGM_JOINT", "cartesian": "GT_EGM_CARTESIAN", "path_correction": "GT_EGM_PATH_CORRECTION"}[spec.egm_mode]

    def ints(v: list[int]) -> str:
        return ", ".join(str(int(i)) for i in v)

    return f"""/* gt_runtime_config.h: the runtime's configuration, generated by gtmodel.codegen.robot_runtime; do not edit. */
#ifndef GT_RUNTIME_CONFIG_H
#define GT_RUNTIME_CONFIG_H

#include "{prefix}.h"

#define GT_RT_RSI 0
#define GT_RT_EGM 1
#define GT_RT_INTERFACE {"GT_RT_RSI" if spec.interface == "rsi" else "GT_RT_EGM"}
#define GT_RT_INTERFACE_NAME "{spec.interface}"
#define GT_RT_DEFAULT_PORT "{DEFAULT_PORTS[spec.interface]}"
#define GT_RT_EGM_MODE {mode}
#define GT_RT_NX {len(spec.inputs)}
#define GT_RT_NU {len(spec.outputs)}
#define GT_RT_NREPLY {nreply}
#define GT_RT_NSENSOR {nsensor}
#define GT_RT_RELATIVE {int(spec.relative)}
#define GT_RT_RAMP {int(spec.fallback == "ramp")}
#define GT_RT_STALE_CYCLES {int(spec.stale_cycles)}
#define GT_RT_PERIOD_S {float(spec.period)!r}
#define GT_RT_REPLY_DEADLINE_S {float(spec.reply_deadline_s)!r}
#define GT_RT_SEN_TYPE {c_string(spec.sen_type)}
#define GT_RT_RSI_ELEMENTS {elements}u
#define GT_RT_CYCLE_STACK ((size_t){int(cycle_stack)}u) /* the step's stack work arrays and the runtime's own frames */

typedef {prefix}_memory gt_rt_memory;
typedef {prefix}_real gt_rt_real;
#define gt_rt_step_init {prefix}_init
#define gt_rt_step {prefix}_step
#define gt_rt_status_string {prefix}_status_string

#ifndef GT_RT_CONFIG_NO_TABLES /* the tables: the cycle's (gt_runtime.c), not the report's */
/* x[i] from packet field gt_rt_x_source[i] (>= 0) or sensor value -1 - gt_rt_x_source[i] */
static const int gt_rt_x_source[GT_RT_NX] = {{{ints(x_source)}}};
/* u[i] -> reply slot gt_rt_u_reply[i] */
static const int gt_rt_u_reply[GT_RT_NU] = {{{ints(slots)}}};
/* the start of u[i]: packet field gt_rt_u_init[i] (EGM: the measured position), else gt_rt_u_init2[i] (planned); -1: zero */
static const int gt_rt_u_init[GT_RT_NU] = {{{ints(init)}}};
static const int gt_rt_u_init2[GT_RT_NU] = {{{ints(init2)}}};
static const double gt_rt_lower[GT_RT_NU] = {{{_c_doubles(spec.lower)}}};
static const double gt_rt_upper[GT_RT_NU] = {{{_c_doubles(spec.upper)}}};
static const double gt_rt_rate[GT_RT_NU] = {{{_c_doubles(spec.rate)}}};
static const char *const gt_rt_x_names[GT_RT_NX] = {{{", ".join(c_string(f) for f in spec.inputs)}}};
static const char *const gt_rt_u_names[GT_RT_NU] = {{{", ".join(c_string(f) for f in spec.outputs)}}};
#endif

#endif
"""


#: Flags of the runtime's build (with the step's include folders and link flags).
BUILD_FLAGS = ("-std=c11", "-O2", "-Wall", "-Wextra", "-Wpedantic", "-Wshadow", "-Werror", "-pthread")


def build_runtime(source: RobotRuntime, out_dir: str | Path, *, real: str = "double", prefix: str | None = None,
                  generated: Any = None) -> Path:
    """Generate the runtime's sources into ``out_dir`` and compile ONE executable.

    Parameters
    ----------
    source : RobotRuntime
        The step and the spec.
    out_dir : str or pathlib.Path
        Folder of the sources (made when missing); the executable is ``out_dir/gt_runtime``.
    real : {"double", "float"}, optional
        The step's real type.
    prefix : str, optional
        The step's C prefix (default ``gt_loop``).
    generated : GeneratedCode, optional
        What ``source.generate(out_dir, real=real, prefix=prefix)`` returned already (``gtmodel
        loop`` checks the code before it builds): compiled as it is, not generated again.

    Returns
    -------
    pathlib.Path
        The executable (its arguments: ``gt_runtime.c``'s docstring, :func:`gtmodel.control.runtime.run_loop`).

    Raises
    ------
    InputError
        Not a :class:`RobotRuntime`, or an option refused.
    CompilerNotFoundError
        No C compiler.
    CodegenError
        Writing or compiling failed (a warning included: :data:`BUILD_FLAGS`).
    """
    if not isinstance(source, RobotRuntime):
        raise InputError(f"source: expected a RobotRuntime, got {type(source).__name__}")
    if generated is None:
        generated = source.generate(out_dir, real=real, prefix=prefix)
    elif Path(generated.out_dir).resolve() != Path(out_dir).resolve():
        raise InputError(f"generated: expected the code generated into {out_dir}, got {generated.out_dir}")
    out = generated.out_dir
    exe = out / "gt_runtime"
    cc = find_compiler()
    inc = ["-I", str(out), "-I", str(out / "nanopb")] + [a for d in generated.include_dirs for a in ("-isystem", d)]
    sources = [out / "gt_runtime.c", out / "gt_runtime_report.c", out / "gt_guard.c", out / "gt_rsi.c", out / "gt_egm.c", out / "gt_sensor_stream.c", out / "egm.pb.c",
               out / "nanopb" / "pb_common.c", out / "nanopb" / "pb_decode.c", out / "nanopb" / "pb_encode.c",
               generated.source, generated.casadi_source]
    run_compiler([*cc, *BUILD_FLAGS, *inc, *map(str, sources), "-o", str(exe), *generated.link_flags, "-lm"],
                 f"building the {source.spec.interface.upper()} runtime")
    log.info("codegen: built %s", exe)
    return exe
