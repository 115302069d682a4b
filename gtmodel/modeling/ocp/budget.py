"""The memory a collocation NLP will need, estimated and checked before it is built.

A transcription with ``N`` elements of ``d`` collocation points of a DAE with ``nx`` states,
``nz`` algebraic variables and ``nu`` inputs has about

- variables: ``N (d (nx + nz + nu) + nx)`` (the states also at each element's start),
- constraint Jacobian nonzeros: ``N d (nx + nz) (nx + nz + nu + d + 1)`` (each collocation
  equation couples the ``d + 1`` state values of its element with the point's variables).

The memory of building and solving it (CasADi's expression graphs and functions, IPOPT's
vectors, the sparse factorisation of its KKT matrix) grows linearly in these; measured on
``problems/l1_time_optimal.toml`` with ``points = 9`` (226 MB peak at 100 elements, 521 MB
at 400, about 110 kB per collocation point: 2,000 bytes per variable and 800 per Jacobian
nonzero, on a 150 MB base) the estimate below follows the peak resident memory, and
``elements = 10000, points = 9`` (which grew to 5.6 GB and was killed) is refused at once.

A multiple-shooting NLP (:mod:`gtmodel.modeling.ocp.shooting`) with ``N`` intervals of ``s``
fixed integration steps has ``(N + 1)(nx + nz) + N nu`` variables; its continuity
constraints couple each node with the next and the interval's inputs, about
``N nx (2 nx + nz + 2 nu)`` Jacobian nonzeros; and each of the ``N s`` integration steps keeps
its states and algebraic variables (the bounds are imposed at every step's end) in the
evaluation and derivative work of the NLP, :data:`_PER_STEP` bytes per value: measured on a
two-mass drive (5 states, 29 algebraic variables, Radau steps) 254 MB peak at 100 x 8,
229 MB at 25 x 64, 528 MB at 1,000 x 8 (estimates 206, 221, 710 MB). ``intervals = 10000,
steps = 1000`` (still building after 142 CPU-s) is refused at once.

The limit is :data:`MEMORY_SHARE` of the memory available when the check runs (the least of
Linux ``MemAvailable`` or the free physical pages, a cgroup's memory limit minus its use, and
``ulimit -v`` minus the process's virtual size), or the number of megabytes in the
environment variable :data:`MEMORY_ENV`.

A refinement's CPU budget reaches IPOPT as ``max_cpu_time``: :func:`ipopt_left` gives it.
"""

from __future__ import annotations

import os
import time as _time

try:  # POSIX only: the address-space limit (ulimit -v)
    import resource
except ImportError:  # pragma: no cover
    resource = None
from dataclasses import dataclass

from gtmodel.errors import InputError

__all__ = ["IPOPT_CPU_SHARE", "ipopt_left", "STALL_FACTOR", "STALL_FLOOR_S", "stall_cap", "NlpSize", "MEMORY_ENV", "MEMORY_SHARE", "estimate", "max_elements", "FALLBACK_ELEMENTS", "MOST_ELEMENTS", "memory_limit", "check_memory", "estimate_shooting",
           "check_shooting_memory"]

#: Environment variable: the memory limit of one NLP in megabytes (default: a share of what is available).
MEMORY_ENV = "GTMODEL_MAX_MEMORY_MB"
#: Share of the available memory one NLP may take by default.
MEMORY_SHARE = 0.8
_BASE = 150e6
_PER_VARIABLE = 2000.0
_PER_NONZERO = 800.0
_PER_STEP = 1200.0


@dataclass(frozen=True)
class NlpSize:
    """Estimated size of a collocation NLP.

    Parameters
    ----------
    variables : int
        Number of NLP variables.
    nonzeros : int
        Nonzeros of the constraint Jacobian.
    bytes : float
        Peak memory of building and solving it [bytes].
    """

    variables: int
    nonzeros: int
    bytes: float


def estimate(elements: int, points: int, nx: int, nz: int, nu: int) -> NlpSize:
    """The size and memory of a collocation NLP (formulas in the module docstring).

    Parameters
    ----------
    elements, points : int
        Finite elements ``N`` and collocation points per element ``d``.
    nx, nz, nu : int
        States, algebraic variables and inputs of the DAE.

    Returns
    -------
    NlpSize
    """
    n, d = int(elements), int(points)
    variables = n * (d * (nx + nz + nu) + nx)
    nonzeros = n * d * (nx + nz) * (nx + nz + nu + d + 1)
    return NlpSize(variables, nonzeros, _BASE + _PER_VARIABLE * variables + _PER_NONZERO * nonzeros)


def _read_number(path: str) -> float | None:
    try:
        with open(path, encoding="ascii") as fh:
            text = fh.read().strip()
    except OSError:
        return None
    return float(text) if text.isdigit() else None


def _available() -> float | None:
    """Memory this process may still take [bytes]: the least of the system's available
    memory, the cgroup's limit minus its use (v2 and v1), and ``RLIMIT_AS`` minus this
    process's virtual size; None when none is known."""
    known: list[float] = []
    try:
        with open("/proc/meminfo", encoding="ascii") as fh:
            for line in fh:
                if line.startswith("MemAvailable:"):
                    known.append(float(line.split()[1]) * 1024.0)
    except OSError:
        try:
            known.append(float(os.sysconf("SC_AVPHYS_PAGES")) * float(os.sysconf("SC_PAGE_SIZE")))
        except (ValueError, OSError, AttributeError):
            pass
    for limit_file, usage_file in (("/sys/fs/cgroup/memory.max", "/sys/fs/cgroup/memory.current"),
                                   ("/sys/fs/cgroup/memory/memory.limit_in_bytes", "/sys/fs/cgroup/memory/memory.usage_in_bytes")):
        limit, usage = _read_number(limit_file), _read_number(usage_file)
        if limit is not None and limit < 1 << 60:
            known.append(max(0.0, limit - (usage or 0.0)))
    try:
        if resource is None:
            raise ImportError("no resource module on this platform")
        soft = resource.getrlimit(resource.RLIMIT_AS)[0]
        if soft != resource.RLIM_INFINITY:
            with open("/proc/self/statm", encoding="ascii") as fh:
                virtual = float(fh.read().split()[0]) * os.sysconf("SC_PAGE_SIZE")
            known.append(max(0.0, soft - virtual))
    except (ImportError, OSError, ValueError, IndexError):
        pass
    return min(known) if known else None


def memory_limit() -> float | None:
    """The memory one NLP may take [bytes].

    Returns
    -------
    float or None
        ``$GTMODEL_MAX_MEMORY_MB`` megabytes when set, else :data:`MEMORY_SHARE` of the
        available memory; None when neither is known (no check then).

    Raises
    ------
    InputError
        ``$GTMODEL_MAX_MEMORY_MB`` is not a positive number.
    """
    text = os.environ.get(MEMORY_ENV, "").strip()
    if text:
        try:
            value = float(text)
        except ValueError:
            value = -1.0
        if not value > 0:
            raise InputError(f"{MEMORY_ENV}: expected a positive number of megabytes, got {text[:40]!r}")
        return value * 1e6
    available = _available()
    return None if available is None else MEMORY_SHARE * available


def check_memory(elements: int, points: int, nx: int, nz: int, nu: int) -> NlpSize:
    """Refuse a collocation NLP whose estimated memory exceeds :func:`memory_limit`.

    Parameters
    ----------
    elements, points : int
        Finite elements and collocation points per element.
    nx, nz, nu : int
        States, algebraic variables and inputs of the DAE.

    Returns
    -------
    NlpSize
        The estimate (within the limit).

    Raises
    ------
    InputError
        The estimate exceeds the limit: the message names ``elements`` and ``points`` (in a
        problem file ``collocation.elements``/``collocation.points`` or
        ``transcription.elements``), the estimate and the limit, and how to raise it.
    """
    size = estimate(elements, points, nx, nz, nu)
    limit = memory_limit()
    if limit is not None and size.bytes > limit:
        raise InputError(
            f"elements = {elements}, points = {points}: the NLP would have {size.variables} variables and "
            f"{size.nonzeros} Jacobian nonzeros and need about {size.bytes / 1e6:.0f} MB, more than the limit of "
            f"{limit / 1e6:.0f} MB ({'$' + MEMORY_ENV if os.environ.get(MEMORY_ENV, '').strip() else f'{MEMORY_SHARE:.0%} of the available memory'}); "
            f"use fewer elements or points (collocation.elements, collocation.points in a problem file), or set {MEMORY_ENV}")
    return size


#: Elements of a refined mesh when the memory available is unknown (no limit to read), and the most ever allowed
#: (beyond it a pass's IPOPT and verification time, not memory, is what a refinement runs out of).
FALLBACK_ELEMENTS = 2000
MOST_ELEMENTS = 20000


def max_elements(points: int, nx: int, nz: int, nu: int) -> int:
    """The most elements a collocation mesh of this DAE may have within :func:`memory_limit` (mesh refinement's cap).

    The largest ``N`` whose :func:`estimate` is within the limit (the estimate is linear in ``N``), at most
    :data:`MOST_ELEMENTS`; :data:`FALLBACK_ELEMENTS` when the limit is unknown. Issue 64: the cap was a fixed 400
    elements, whatever the model and the machine.

    Parameters
    ----------
    points : int
        Collocation points per element.
    nx, nz, nu : int
        States, algebraic variables and inputs of the DAE.

    Returns
    -------
    int
        At least 1.
    """
    limit = memory_limit()
    if limit is None:
        return FALLBACK_ELEMENTS
    per = estimate(1, points, nx, nz, nu).bytes - _BASE
    return int(max(1, min(MOST_ELEMENTS, (limit - _BASE) // max(per, 1.0))))


def estimate_shooting(intervals: int, steps: int, nx: int, nz: int, nu: int) -> NlpSize:
    """The size and memory of a multiple-shooting NLP (formulas in the module docstring).

    Parameters
    ----------
    intervals, steps : int
        Shooting intervals ``N`` and fixed integration steps per interval ``s``.
    nx, nz, nu : int
        States, algebraic variables and inputs of the DAE.

    Returns
    -------
    NlpSize
    """
    n, s = int(intervals), int(steps)
    variables = (n + 1) * (nx + nz) + n * nu
    nonzeros = n * nx * (2 * nx + nz + 2 * nu)
    work = _PER_STEP * n * s * (nx + nz)
    return NlpSize(variables, nonzeros, _BASE + _PER_VARIABLE * variables + _PER_NONZERO * nonzeros + work)


def check_shooting_memory(intervals: int, steps: int, nx: int, nz: int, nu: int) -> NlpSize:
    """Refuse a multiple-shooting NLP whose estimated memory exceeds :func:`memory_limit`.

    Parameters
    ----------
    intervals, steps : int
        Shooting intervals and fixed integration steps per interval.
    nx, nz, nu : int
        States, algebraic variables and inputs of the DAE.

    Returns
    -------
    NlpSize
        The estimate (within the limit).

    Raises
    ------
    InputError
        The estimate exceeds the limit: the message names ``intervals`` and ``steps`` (in a
        problem file ``transcription.intervals``/``transcription.steps``), the estimate and the
        limit, and how to raise it.
    """
    size = estimate_shooting(intervals, steps, nx, nz, nu)
    limit = memory_limit()
    if limit is not None and size.bytes > limit:
        raise InputError(
            f"intervals = {intervals}, steps = {steps}: the multiple-shooting NLP would integrate {intervals * steps} steps "
            f"with {size.variables} variables and {size.nonzeros} Jacobian nonzeros and need about {size.bytes / 1e6:.0f} MB, "
            f"more than the limit of {limit / 1e6:.0f} MB "
            f"({'$' + MEMORY_ENV if os.environ.get(MEMORY_ENV, '').strip() else f'{MEMORY_SHARE:.0%} of the available memory'}); "
            f"use fewer intervals or steps (transcription.intervals, transcription.steps in a problem file), or set {MEMORY_ENV}")
    return size


#: IPOPT's CPU limits are this share of what is left of the budget: IPOPT reads its clock once an iteration and counts
#: less than the process does (user and system time): drive2_10's 786-element pass, its two solves held to the 241.5 s
#: left, took 258 CPU-s, and the run 307.6 against the 290 s budget (measured 2026-11-27 beside two reference solves).
IPOPT_CPU_SHARE = 0.8


def ipopt_left(budget: float, cpu0: float) -> float:
    """IPOPT's ``max_cpu_time`` for what is left of a CPU budget.

    Parameters
    ----------
    budget : float
        The refinement's CPU budget, s.
    cpu0 : float
        ``time.process_time()`` when the refinement began, s.

    Returns
    -------
    float
        :data:`IPOPT_CPU_SHARE` of ``budget`` less the CPU time spent since ``cpu0``, at least 1 s.
    """
    return max(IPOPT_CPU_SHARE * (budget - (_time.process_time() - cpu0)), 1.0)


#: A warm refinement pass's IPOPT is held to this many times the costliest pass before it, per element ...
STALL_FACTOR = 20.0
#: ... and never to less than this, CPU-s.
STALL_FLOOR_S = 10.0


def stall_cap(history: list[dict], elements: int) -> float | None:
    """IPOPT's ``max_cpu_time`` for a warm refinement pass: a multiple of what the passes before it cost.

    A warm pass that stalls (IPOPT wandering from the last pass's point) would otherwise hold the whole budget left
    before its cold retry may run: a rotary table with a power limit, its passes 1.2 to 1.8 CPU-s up to a verified
    pass of 144 elements, ran its warm 146-element pass into IPOPT's CPU limit (250 s of the 290) and the cold retry
    that followed ended in seconds, the budget spent (measured 2026-11-27).

    Parameters
    ----------
    history : list of dict
        The passes so far (``elements``, ``cpu_s``).
    elements : int
        The warm pass's elements.

    Returns
    -------
    float or None
        ``max(STALL_FLOOR_S, STALL_FACTOR * max_k(cpu_k / elements_k) * elements)``, CPU-s; None without a pass before.
    """
    rates = [float(e["cpu_s"]) / max(int(e["elements"]), 1) for e in history if e.get("cpu_s") and e.get("elements")]
    if not rates:
        return None
    return max(STALL_FLOOR_S, STALL_FACTOR * max(rates) * int(elements))
