"""Fault schedule of the robot-side simulators: what goes wrong on the robot's side of the link, and when.

A schedule is declared by a short text (``--faults`` of ``gtmodel robot-sim``) or built from
:class:`FaultRule` objects; it is seeded, so a run is reproducible. Syntax::

    SPEC  := ENTRY (";" ENTRY)*
    ENTRY := KIND ":" ARG ("," ARG)*
    ARG   := "cycles=" A "-" B      (the cycles A..B, both included, counted from 0)
           | "at=" N                (the cycle N only; for "stop": from N on)
           | "rate=" P              (each cycle with probability P, 0 <= P <= 1, seeded)
           | "ms=" D                (delay: how late the packet is sent [ms], default 6)
           | "by=" N                (ipoc_jump: how many cycles the counter jumps, default 10)

e.g. ``loss:rate=0.01;delay:cycles=200-210,ms=6;garbage:rate=0.02;nan:at=300;stop:at=2000``.

Kinds (:data:`FAULT_KINDS`), all on the robot's side:

``loss``       the robot's packet of the cycle is not sent (the cycle gets no reply: late);
``drop``       the reply to the cycle is dropped on its way back (not seen by the robot);
``delay``      the packet is sent ``ms`` late (a burst of delay over a range of cycles);
``duplicate``  the packet is sent twice;
``reorder``    the packet is held and sent after the next cycle's packet;
``garbage``    a datagram of random bytes is sent before the packet;
``nan``        a field of the packet is NaN (RSI: ``RIst X``; EGM: the first feedback joint);
``ipoc_jump``  the IPOC (RSI) or sequence number (EGM) jumps ahead by ``by`` cycles from
               this cycle on (the counter stays shifted);
``stop``       the robot stops sending at the cycle (the run ends there; the sensor side
               must exit on its idle timeout).

A rate draws per cycle from ``numpy.random.default_rng([seed, index of the kind])``, so the
cycles of one kind do not depend on the other entries.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from gtmodel.errors import InputError

__all__ = ["FAULT_KINDS", "DEFAULT_DELAY_MS", "DEFAULT_JUMP_CYCLES", "FaultRule", "FaultSchedule", "parse_faults"]

#: The fault kinds, in the order of the module docstring.
FAULT_KINDS = ("loss", "drop", "delay", "duplicate", "reorder", "garbage", "nan", "ipoc_jump", "stop")
#: Default delay of a ``delay`` fault [ms] (more than one 4 ms cycle: the reply is late).
DEFAULT_DELAY_MS = 6.0
#: Default jump of an ``ipoc_jump`` fault [cycles].
DEFAULT_JUMP_CYCLES = 10
#: Longest accepted spec text [characters].
_MAX_SPEC = 2000


@dataclass(frozen=True)
class FaultRule:
    """One entry of a fault schedule.

    Parameters
    ----------
    kind : str
        One of :data:`FAULT_KINDS`.
    first : int, optional
        First cycle of a range (with ``last``), or the cycle of ``at``; None with ``rate``.
    last : int, optional
        Last cycle of the range (included); equal to ``first`` for ``at``.
    rate : float, optional
        Probability per cycle in [0, 1] (instead of a range).
    delay_ms : float, optional
        Delay of a ``delay`` fault [ms], > 0 (default :data:`DEFAULT_DELAY_MS`).
    jump : int, optional
        Jump of an ``ipoc_jump`` fault [cycles], >= 1 (default :data:`DEFAULT_JUMP_CYCLES`).

    Raises
    ------
    InputError
        An unknown kind, neither or both of a range and a rate, a bad range, rate, delay or
        jump, or a ``stop`` given by a rate.
    """

    kind: str
    first: int | None = None
    last: int | None = None
    rate: float | None = None
    delay_ms: float = DEFAULT_DELAY_MS
    jump: int = DEFAULT_JUMP_CYCLES

    def __post_init__(self) -> None:
        if self.kind not in FAULT_KINDS:
            raise InputError(f"fault kind {self.kind!r}: expected one of {', '.join(FAULT_KINDS)}")
        ranged = self.first is not None
        if ranged == (self.rate is not None):
            raise InputError(f"fault {self.kind}: expected either cycles=A-B / at=N or rate=P")
        if ranged:
            last = self.first if self.last is None else self.last
            if not (isinstance(self.first, int) and isinstance(last, int)) or self.first < 0 or last < self.first:
                raise InputError(f"fault {self.kind}: expected cycles 0 <= A <= B, got {self.first}-{last}")
            object.__setattr__(self, "last", last)
        else:
            if self.kind == "stop":
                raise InputError("fault stop: expected at=N (a stop is one event), got a rate")
            if not isinstance(self.rate, (int, float)) or not 0.0 <= float(self.rate) <= 1.0:
                raise InputError(f"fault {self.kind}: expected a rate in [0, 1], got {self.rate!r}")
        if not (isinstance(self.delay_ms, (int, float)) and math.isfinite(self.delay_ms) and 0 < self.delay_ms <= 1000):
            raise InputError(f"fault {self.kind}: expected ms in (0, 1000], got {self.delay_ms!r}")
        if not isinstance(self.jump, int) or not 1 <= self.jump <= 1_000_000:
            raise InputError(f"fault {self.kind}: expected by in [1, 1000000], got {self.jump!r}")


def _int(value: str, entry: str, key: str) -> int:
    try:
        out = int(value)
    except ValueError:
        raise InputError(f"fault entry {entry!r}: {key}= expected an integer, got {value!r}") from None
    if out < 0:
        raise InputError(f"fault entry {entry!r}: {key}= expected a non-negative integer, got {value!r}")
    return out


def _float(value: str, entry: str, key: str) -> float:
    try:
        out = float(value)
    except ValueError:
        raise InputError(f"fault entry {entry!r}: {key}= expected a number, got {value!r}") from None
    if not math.isfinite(out):
        raise InputError(f"fault entry {entry!r}: {key}= expected a finite number, got {value!r}")
    return out


def _parse_entry(entry: str) -> FaultRule:
    kind, sep, args = entry.partition(":")
    kind = kind.strip()
    if not sep or not args.strip():
        raise InputError(f"fault entry {entry!r}: expected KIND:ARG[,ARG...], e.g. loss:rate=0.01")
    opts: dict = {}
    for arg in args.split(","):
        key, eq, value = (s.strip() for s in arg.partition("="))
        if not eq:
            raise InputError(f"fault entry {entry!r}: expected KEY=VALUE, got {arg.strip()!r}")
        if key in opts or (key in ("cycles", "at") and ("first" in opts)):
            raise InputError(f"fault entry {entry!r}: {key}= given twice (or with another range)")
        if key == "cycles":
            a, dash, b = value.partition("-")
            if not dash:
                raise InputError(f"fault entry {entry!r}: cycles= expected A-B, got {value!r}")
            opts["first"], opts["last"] = _int(a, entry, key), _int(b, entry, key)
        elif key == "at":
            opts["first"] = opts["last"] = _int(value, entry, key)
        elif key == "rate":
            opts["rate"] = _float(value, entry, key)
        elif key == "ms":
            opts["delay_ms"] = _float(value, entry, key)
        elif key == "by":
            opts["jump"] = _int(value, entry, key)
        else:
            raise InputError(f"fault entry {entry!r}: unknown key {key!r} (cycles, at, rate, ms, by)")
    return FaultRule(kind, **opts)


def parse_faults(spec: str) -> list[FaultRule]:
    """Parse a fault spec (the syntax of the module docstring).

    Parameters
    ----------
    spec : str
        E.g. ``"loss:rate=0.01;stop:at=2000"``; empty or blank for no fault.

    Returns
    -------
    list of FaultRule
        One per entry, in order.

    Raises
    ------
    InputError
        Not a string, longer than 2000 characters, or an entry that does not parse (the
        entry is quoted).
    """
    if not isinstance(spec, str):
        raise InputError(f"faults: expected a string, got {type(spec).__name__}")
    if len(spec) > _MAX_SPEC:
        raise InputError(f"faults: expected at most {_MAX_SPEC} characters, got {len(spec)}")
    return [_parse_entry(e.strip()) for e in spec.split(";") if e.strip()]


@dataclass
class FaultSchedule:
    """The faults of a run, decided per cycle (seeded).

    Parameters
    ----------
    rules : list of FaultRule
        The entries (:func:`parse_faults`).
    seed : int, optional
        Seed of the rates (default 0).

    Raises
    ------
    InputError
        A rule that is not a :class:`FaultRule`, or more than one ``stop``.
    """

    rules: list[FaultRule] = field(default_factory=list)
    seed: int = 0

    def __post_init__(self) -> None:
        self.rules = list(self.rules)
        for r in self.rules:
            if not isinstance(r, FaultRule):
                raise InputError(f"faults: expected FaultRule entries, got {type(r).__name__}")
        if sum(r.kind == "stop" for r in self.rules) > 1:
            raise InputError("faults: expected at most one stop")
        self._rngs = [np.random.default_rng([int(self.seed), FAULT_KINDS.index(r.kind), i]) for i, r in enumerate(self.rules)]

    @classmethod
    def from_spec(cls, spec: str | None, seed: int = 0) -> "FaultSchedule":
        """A schedule from the text syntax (None or blank: no fault).

        Parameters
        ----------
        spec : str or None
            The spec (module docstring).
        seed : int, optional
            Seed of the rates.

        Returns
        -------
        FaultSchedule

        Raises
        ------
        InputError
            A spec that does not parse.
        """
        return cls(parse_faults(spec) if spec else [], seed)

    @property
    def stop_cycle(self) -> int | None:
        """The cycle at which the robot stops sending, or None."""
        return next((r.first for r in self.rules if r.kind == "stop"), None)

    def at(self, cycle: int) -> dict[str, FaultRule]:
        """The faults of a cycle (call once per cycle, in order: rates draw as they go).

        Parameters
        ----------
        cycle : int
            The cycle, from 0.

        Returns
        -------
        dict of str to FaultRule
            Per active kind, its rule (the first active rule of that kind).
        """
        out: dict[str, FaultRule] = {}
        for r, rng in zip(self.rules, self._rngs):
            if r.kind == "stop":
                hit = cycle >= r.first
            elif r.rate is not None:
                hit = bool(rng.random() < r.rate)
            else:
                hit = r.first <= cycle <= r.last
            if hit and r.kind not in out:
                out[r.kind] = r
        return out
