"""The rule of the tests marked ``realtime``: they count replies made in real time, so they run on a quiet machine only.

They are left out of the default run (``pyproject.toml``: ``-m 'not slow and not realtime'``);
``python -m pytest -m realtime -n 0`` runs them (``.ci/run``, a step of its own). On a machine
whose load (the 1-minute average, ``os.getloadavg``) is over its number of cores they skip,
saying so: a count of on-time replies measures the machine then, not the code.
``GTMODEL_REALTIME_TESTS=always`` runs them whatever the load (to measure a busy machine).

On a quiet machine the machine itself still pauses: a virtual CPU taken by the hypervisor stops
every thread on it, the runtime's SCHED_FIFO cycle thread included (seen: pauses up to 10 ms
several times a minute on a 2-core machine of this project's kind, and a reply missed by 200 ms
on one CI machine). :class:`MachinePauses` measures them beside a test, by canaries that run above
the runtime; a reply missing or late exactly by such a pause is the machine's, and the tests
report it as such and count only the rest against the runtime.
"""

from __future__ import annotations

import os
import time

import numpy as np
import pytest

__all__ = ["CANARY_C", "CANARY_PRIORITY", "QUIET_PAUSED_FRACTION", "MachinePauses", "busy_reason", "skip_when_busy"]


def busy_reason() -> str | None:
    """Why this machine is too busy for real-time counts, or None when it is quiet enough.

    Returns
    -------
    str or None
        The load and the cores, when the 1-minute load average exceeds the number of cores
        (None whatever the load with ``GTMODEL_REALTIME_TESTS=always``).
    """
    if os.environ.get("GTMODEL_REALTIME_TESTS") == "always":
        return None
    try:
        load = os.getloadavg()[0]
    except OSError:  # no load average (not a Unix): nothing to judge by
        return None
    cores = os.cpu_count() or 1
    if load > cores:
        return (f"a busy machine (1-minute load {load:.1f} on {cores} cores): the real-time counts of this test measure the load, "
                "not the code; run `python -m pytest -m realtime -n 0` on a quiet machine (.ci/run does)")
    return None


def skip_when_busy(item: pytest.Item) -> None:
    """Skip a test marked ``realtime`` on a busy machine, with the reason.

    Parameters
    ----------
    item : pytest.Item
        The test about to run.
    """
    if item.get_closest_marker("realtime") is not None:
        reason = busy_reason()
        if reason:
            pytest.skip(reason)


# ---- the machine's own pauses, measured beside a real-time test ----

#: A canary: pinned to one CPU, SCHED_FIFO above the runtime's cycle thread (80), it wakes every
#: period (CLOCK_MONOTONIC, absolute) and records each wake-up later than two periods as a pause
#: [the wake it missed, the wake it made]. Above the runtime, it is blind to what the runtime does
#: to the CPU; what stops it (the hypervisor taking the virtual CPU, interrupts, the kernel's
#: stop-machine work) stops the runtime's cycle thread on that CPU too.
CANARY_C = r"""
#define _GNU_SOURCE
#include <sched.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <sys/mman.h>
#include <time.h>

#define MAX_PAUSES 100000
static volatile sig_atomic_t stop;
static double pauses[2 * MAX_PAUSES];

static void on_term(int sig) { (void)sig; stop = 1; }

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

int main(int argc, char **argv)
{
    int cpu, prio, pinned, fifo;
    long n = 0, more = 0, i, step_ns;
    double period, last, t;
    struct timespec next;
    cpu_set_t set;
    struct sched_param sp;
    struct sigaction sa = {0};
    if (argc != 4) return 2;
    cpu = atoi(argv[1]);
    step_ns = atol(argv[2]);
    prio = atoi(argv[3]);
    if (cpu < 0 || cpu >= CPU_SETSIZE || step_ns < 100000 || step_ns > 100000000) return 2;
    period = 1e-9 * (double)step_ns;
    CPU_ZERO(&set);
    CPU_SET(cpu, &set);
    pinned = sched_setaffinity(0, sizeof set, &set) == 0;
    sp.sched_priority = prio;
    fifo = prio > 0 && sched_setscheduler(0, SCHED_FIFO, &sp) == 0;
    mlockall(MCL_CURRENT | MCL_FUTURE);
    sa.sa_handler = on_term;
    sigaction(SIGTERM, &sa, NULL);
    printf("ready %d %d %d\n", cpu, pinned, fifo);
    fflush(stdout);
    clock_gettime(CLOCK_MONOTONIC, &next);
    last = now();
    while (!stop) {
        next.tv_nsec += step_ns;
        while (next.tv_nsec >= 1000000000L) {
            next.tv_nsec -= 1000000000L;
            ++next.tv_sec;
        }
        clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &next, NULL);
        t = now();
        if (t - last > 2.0 * period) {
            if (n < MAX_PAUSES) {
                pauses[2 * n] = last + period;
                pauses[2 * n + 1] = t;
                ++n;
            } else {
                ++more;
            }
            clock_gettime(CLOCK_MONOTONIC, &next); /* behind: the next wake-up one period from now */
        }
        last = t;
    }
    printf("pauses %ld %ld\n", n, more);
    for (i = 0; i < n; ++i) printf("%.9f %.9f\n", pauses[2 * i], pauses[2 * i + 1]);
    return 0;
}
"""

#: The runtime's cycle thread runs SCHED_FIFO at 80 (gt_runtime.c); the canaries run above it.
CANARY_PRIORITY = 90
#: A machine whose CPU was paused more than this share of a test's run is not quiet: the test skips, saying so
#: (seen here on a quiet day: 0.3-0.6 %; on a noisy one 1.9-9 %, the 15,000-cycle p99 then 1.3 ms).
QUIET_PAUSED_FRACTION = 0.01


class MachinePauses:
    """The machine's pauses beside a real-time test: one canary per CPU this process may use.

    Independent of the runtime: a C program compiled here (:data:`CANARY_C`), one process per CPU,
    pinned, SCHED_FIFO at :data:`CANARY_PRIORITY` (above the runtime's cycle thread), waking every
    ``period`` seconds on ``CLOCK_MONOTONIC`` (Python's :func:`time.monotonic` clock). A reply late
    or missing by such a pause is the machine's: the hypervisor took the virtual CPU, or the kernel
    did, from every thread of the runtime's priority. Where the canaries could not run above the
    runtime (no permission for SCHED_FIFO), :meth:`explains` explains nothing.

    Parameters
    ----------
    workdir : pathlib.Path
        A folder of the test's own for the canary's source and program.
    period : float, optional
        Wake-up period (s), 0.0005 by default; a pause is a wake-up later than two periods.

    Use as a context manager around the test's session; after it, :attr:`pauses` holds each CPU's
    pauses as ``(n, 2)`` arrays of [start, end] (s, monotonic) and :attr:`above_runtime` whether
    every canary ran pinned and SCHED_FIFO.
    """

    def __init__(self, workdir, period: float = 0.0005) -> None:
        self.workdir = workdir
        self.period = float(period)
        self.pauses: dict[int, np.ndarray] = {}
        self.above_runtime = False
        self.started = self.ended = 0.0
        self._procs: list = []

    def __enter__(self) -> "MachinePauses":
        import subprocess

        from gtmodel._compiler import find_compiler

        self.workdir.mkdir(parents=True, exist_ok=True)
        src, exe = self.workdir / "canary.c", self.workdir / "canary"
        src.write_text(CANARY_C)
        subprocess.run([*find_compiler(), "-O2", "-o", str(exe), str(src)], check=True, capture_output=True)
        flags = []
        for cpu in sorted(os.sched_getaffinity(0)):
            proc = subprocess.Popen([str(exe), str(cpu), str(round(1e9 * self.period)), str(CANARY_PRIORITY)],
                                    stdout=subprocess.PIPE, text=True)
            self._procs.append((cpu, proc))
            ready = proc.stdout.readline().split()
            flags.append(len(ready) == 4 and ready[0] == "ready" and ready[2] == "1" and ready[3] == "1")
        self.above_runtime = bool(flags) and all(flags)
        self.started = time.monotonic()
        return self

    def __exit__(self, *exc) -> None:
        import signal

        self.ended = time.monotonic()
        for cpu, proc in self._procs:
            proc.send_signal(signal.SIGTERM)
            out = proc.communicate(timeout=30)[0].splitlines()
            rows = [line.split() for line in out if line and line[0].isdigit()]
            self.pauses[cpu] = np.array(rows, dtype=float).reshape(-1, 2)

    def overlap(self, t0: float, t1: float, union: bool = False) -> float:
        """The most time one CPU was paused within ``[t0, t1]`` (s, monotonic); with ``union``, the time some CPU was."""
        def within(p: np.ndarray) -> np.ndarray:
            clipped = np.column_stack([np.maximum(p[:, 0], t0), np.minimum(p[:, 1], t1)]) if p.size else np.zeros((0, 2))
            return clipped[clipped[:, 1] > clipped[:, 0]]
        if not union:
            return max((float(np.diff(within(p), axis=1).sum()) for p in self.pauses.values()), default=0.0)
        spans = sorted(map(tuple, np.vstack([within(p) for p in self.pauses.values()] or [np.zeros((0, 2))])))
        total, end = 0.0, -np.inf
        for a, b in spans:  # merge the intervals of all CPUs
            if b > end:
                total += b - max(a, end)
                end = b
        return total

    def explains(self, t0: float, t1: float, budget: float = 0.002, union: bool = False) -> bool:
        """Whether a round ``[t0, t1]`` was long only by a pause of the machine.

        True when the canaries ran above the runtime and one CPU (with ``union``: at each moment some
        CPU, for a datagram's way through the peer's CPU and the runtime's) was paused for all of the
        window but at most ``budget`` seconds (half the 4 ms period by default: the round, less the
        machine's pause, would have been on time with room).
        """
        return self.above_runtime and self.overlap(t0, t1, union) >= (t1 - t0) - budget

    def paused_fraction(self) -> float:
        """The largest share of the canaries' run that one CPU spent paused."""
        span = max(self.ended - self.started, 1e-9)
        return max((float((p[:, 1] - p[:, 0]).sum()) / span for p in self.pauses.values()), default=0.0)

    def busy_reason(self) -> str | None:
        """Why the machine paused too much to judge a runtime by (one CPU paused over :data:`QUIET_PAUSED_FRACTION`
        of the run: a hypervisor taking the virtual CPUs), or None (also with ``GTMODEL_REALTIME_TESTS=always``)."""
        if os.environ.get("GTMODEL_REALTIME_TESTS") == "always" or self.paused_fraction() <= QUIET_PAUSED_FRACTION:
            return None
        return (f"a machine that paused {100 * self.paused_fraction():.1f} % of the run ({self.describe()}): the real-time "
                "counts of this test measure the machine, not the code; run `python -m pytest -m realtime -n 0` on a quiet machine")

    def describe(self) -> str:
        """One line: per CPU the number of pauses, the longest and the total (ms)."""
        parts = [f"cpu{cpu}: {len(p)} pauses, longest {1e3 * float((p[:, 1] - p[:, 0]).max(initial=0.0)):.1f} ms, "
                 f"total {1e3 * float((p[:, 1] - p[:, 0]).sum()):.1f} ms" for cpu, p in self.pauses.items()]
        return "; ".join(parts) + ("" if self.above_runtime else " (the canaries did not run above the runtime: they explain nothing)")

    def judge(self, rounds, late: dict[int, tuple[float, float]], timeout: float,
              ignore: frozenset = frozenset()) -> tuple[list[str], list[str]]:
        """Split a peer's missed and late round trips into those the machine's pauses explain and the rest.

        Parameters
        ----------
        rounds : list of (float, float or None)
            Each exchange's send time and reply time (s, monotonic; None: no reply within ``timeout``).
        late : dict of int to (float, float)
            The rounds the runtime itself logged later than its period: when it received the datagram
            (its ``t_monotonic``, s) and its latency ``L`` (s); the window judged is ``[received, received + L]``
            (the latency ends after ``sendto`` returns: a reply may be in the peer's hands before it does).
            A round with no reply is judged by the peer's whole wait, paused on any CPU at each moment
            (the datagram crosses the peer's CPU and the runtime's).
        timeout : float
            The peer's wait for a reply (s).
        ignore : frozenset of int, optional
            Rounds judged elsewhere (a datagram the kernel reported dropping before the runtime read it).

        Returns
        -------
        unexplained, explained : list of str
            One line per missed or late round: its index, its window (ms) and the most one CPU paused in it.
        """
        unexplained, explained = [], []
        for k in sorted(({k for k, (_, got) in enumerate(rounds) if got is None} | set(late)) - ignore):
            sent, got = rounds[k]
            start, end = (sent, sent + timeout) if got is None else (late[k][0], late[k][0] + late[k][1])
            union = got is None  # the datagram's way: the peer's CPU, then the runtime's; a late reply: the runtime's own CPU
            line = (f"round {k}: {'no reply' if got is None else 'late'} over {1e3 * (end - start):.1f} ms, "
                    f"the machine paused {1e3 * self.overlap(start, end, union):.1f} ms of it")
            (explained if self.explains(start, end, union=union) else unexplained).append(line)
        return unexplained, explained
