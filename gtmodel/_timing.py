"""Phase times of a run: wall and CPU seconds per named phase (build, guess, solve, ...).

One plain mapping ``phase -> {"wall_s": float, "cpu_s": float}`` is carried from the
transcription (:mod:`gtmodel.modeling.ocp.collocation`: ``build``, ``guess``, ``solve``,
``verification``) through the problem layer (``load``, ``writing``, ``total``) into
``summary.json`` (``timing``). CPU time is :func:`time.process_time` (every thread of this
process: IPOPT's, CasADi's); on a shared machine the wall time mostly measures waiting.
"""

from __future__ import annotations

import time
from collections.abc import Iterator, Mapping, MutableMapping
from contextlib import contextmanager

__all__ = ["timed", "add_phase", "merge_phases", "phase_sum", "ordered_phases", "PHASES"]

#: The phases in the order a run passes them (``summary.json``'s ``timing`` keeps this order).
PHASES = ("load", "build", "guess", "solve", "verification", "refinement", "estimation", "other", "writing", "total")


def add_phase(phases: MutableMapping[str, dict[str, float]], name: str, wall_s: float, cpu_s: float) -> None:
    """Add ``wall_s`` and ``cpu_s`` (s) to phase ``name`` of ``phases`` (created at zero).

    Parameters
    ----------
    phases : mutable mapping
        ``phase -> {"wall_s": float, "cpu_s": float}``, changed in place.
    name : str
        The phase.
    wall_s, cpu_s : float
        Wall and CPU time to add, s.
    """
    entry = phases.setdefault(name, {"wall_s": 0.0, "cpu_s": 0.0})
    entry["wall_s"] += float(wall_s)
    entry["cpu_s"] += float(cpu_s)


@contextmanager
def timed(phases: MutableMapping[str, dict[str, float]], name: str) -> Iterator[None]:
    """Time the ``with`` block (wall and CPU) into phase ``name`` of ``phases`` (also when it raises).

    Parameters
    ----------
    phases : mutable mapping
        ``phase -> {"wall_s": float, "cpu_s": float}``, changed in place.
    name : str
        The phase.
    """
    wall, cpu = time.perf_counter(), time.process_time()
    try:
        yield
    finally:
        add_phase(phases, name, time.perf_counter() - wall, time.process_time() - cpu)


def merge_phases(into: MutableMapping[str, dict[str, float]], other: Mapping[str, Mapping[str, float]]) -> None:
    """Add every phase of ``other`` into ``into`` (in place).

    Parameters
    ----------
    into : mutable mapping
        ``phase -> {"wall_s", "cpu_s"}``, changed in place.
    other : mapping
        The phases to add (same form).
    """
    for name, entry in other.items():
        add_phase(into, name, entry.get("wall_s", 0.0), entry.get("cpu_s", 0.0))


def phase_sum(phases: Mapping[str, Mapping[str, float]]) -> dict[str, float]:
    """The sum of every phase but ``total``: ``{"wall_s": float, "cpu_s": float}`` (s).

    Parameters
    ----------
    phases : mapping
        ``phase -> {"wall_s", "cpu_s"}``.

    Returns
    -------
    dict
        Summed wall and CPU time, s.
    """
    parts = [v for k, v in phases.items() if k != "total"]
    return {"wall_s": sum(v.get("wall_s", 0.0) for v in parts), "cpu_s": sum(v.get("cpu_s", 0.0) for v in parts)}


def ordered_phases(phases: Mapping[str, Mapping[str, float]]) -> dict[str, dict[str, float]]:
    """The phases in :data:`PHASES` order (others after them), each ``{"wall_s", "cpu_s"}`` rounded to
    microseconds and not below zero, with ``total``, their sum.

    Parameters
    ----------
    phases : mapping
        ``phase -> {"wall_s", "cpu_s"}`` (s); a ``total`` given is replaced.

    Returns
    -------
    dict
        ``phase -> {"wall_s": float, "cpu_s": float}``, ending with ``total``.
    """
    names = [p for p in PHASES if p in phases and p != "total"] + [p for p in phases if p not in PHASES]
    out = {p: {k: round(max(float(phases[p].get(k, 0.0)), 0.0), 6) for k in ("wall_s", "cpu_s")} for p in names}
    out["total"] = {k: round(v, 6) for k, v in phase_sum(out).items()}
    return out
