"""The robot loop of ``gtmodel loop``: the declaration of a loop file, and its run.

:class:`RobotLoopDeclaration` holds what a ``robot_loop`` file declares (the kind
:mod:`gtmodel.problems.kinds.robot_loop` reads it): the controller behind the interface
(:mod:`gtmodel.control.position_loop`), the runtime's rules (:class:`~gtmodel.codegen.robot_runtime.RuntimeSpec`),
where to listen and when to end, and for a streamed reference the ILC law of the next
iteration (:class:`ILCLaw`). Its :meth:`~RobotLoopDeclaration.solve` runs the four stages:

1. the controller becomes a loop step (:func:`gtmodel.codegen.loop_step.position_step`);
2. the runtime around it is written through codegen's front door
   (:class:`~gtmodel.codegen.robot_runtime.RobotRuntime`), the step's C checked against its
   CasADi Function (:func:`gtmodel.codegen.verdict.check_code`; a failed check never runs on a
   robot: status ``check_failed``) and the program compiled
   (:func:`~gtmodel.codegen.robot_runtime.build_runtime`);
3. the runtime serves the robot that sends to the listening port until it ends by rule
   (:func:`gtmodel.control.runtime.run_loop`; a signal ends it as a normal end, ``interrupted``,
   its log and counts complete);
4. streaming with an ILC law: :func:`next_iteration` learns the next correction from the
   cycle log, Dressler (2012), eq. 7.2 (:func:`gtmodel.estimation.ilc.next_correction`).
"""

from __future__ import annotations

import logging
import math
import tempfile
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from gtmodel._escape import C_IDENTIFIER
from gtmodel._tables import write_table
from gtmodel.codegen.loop_step import position_step
from gtmodel.codegen.robot_runtime import RobotRuntime, RuntimeSpec, build_runtime
from gtmodel.codegen.verdict import check_code
from gtmodel.control.position_loop import PoseCorrection, ReferenceStreaming
from gtmodel.control.runtime import read_cycle_log, run_loop
from gtmodel.estimation.ilc.iteration import error_measure, next_correction
from gtmodel.estimation.ilc.lifted import LearningFilter, QFilter, time_window
from gtmodel.status import Status, StatusResult

__all__ = ["ILCLaw", "RobotLoopDeclaration", "RobotLoopRun", "next_iteration", "hour_of_log_mb", "CHECK_SAMPLES"]

_log = logging.getLogger("gtmodel")

#: Samples of the code check of the step before it runs.
CHECK_SAMPLES = 300
#: Longest loop name used in the C prefix ``gt_<name>`` (a longer or non-identifier name gives ``gt_loop``).
MAX_C_NAME = 40


@dataclass(frozen=True)
class ILCLaw:
    """The learning law of the next iteration, Dressler (2012), eq. 7.2: ``u_next = Q (u + L eps)``.

    Parameters
    ----------
    gamma : float
        Learning gain of ``L = gamma q^delta``.
    delta : int
        Learning lead of ``L`` [cycles].
    q_cutoff_hz : float
        Cut-off of the zero-phase Butterworth Q filter [Hz].
    lead : int, optional
        Rows at rest before and after the motion, where Q's time window rises and falls (0: no window).
    tukey_points : int, optional
        Length of the Tukey window whose halves are the ramps.
    tukey_alpha : float, optional
        The Tukey window's taper fraction.
    """

    gamma: float
    delta: int
    q_cutoff_hz: float
    lead: int = 0
    tukey_points: int = 200
    tukey_alpha: float = 0.95


@dataclass
class RobotLoopDeclaration:
    """A loaded robot-loop file: the controller, the runtime's rules, where to listen, the ILC law.

    Parameters
    ----------
    name : str
        The loop's name (C prefix ``gt_<name>``).
    controller : PoseCorrection or ReferenceStreaming
        The step's law.
    spec : RuntimeSpec
        The runtime's interface, fields, limits and fault rules.
    listen : tuple of (str, int)
        Address and port the robot sends to.
    sensor_port : int or None
        UDP port of the sensor stream on the listen address; None: none.
    idle_timeout, time_limit : float
        When the run ends [s].
    max_cycles : int
        Cycle limit (0: none).
    ilc : ILCLaw or None
        The next iteration's law (streaming only).
    robot : str or None, optional
        The robot's address ``ADDR`` or ``ADDR:PORT`` (None: the first valid packet's source).
    tracker : str or None, optional
        The sensor stream's sender, the same way.
    log_max_mb : float or None, optional
        The cycle log's cap [MB] (None: :func:`hour_of_log_mb`).
    """

    name: str
    controller: PoseCorrection | ReferenceStreaming
    spec: RuntimeSpec
    listen: tuple[str, int]
    sensor_port: int | None
    idle_timeout: float
    time_limit: float
    max_cycles: int
    ilc: ILCLaw | None = None
    robot: str | None = None
    tracker: str | None = None
    log_max_mb: float | None = None

    def solve(self, verbose: bool = False, previous: Any = None, warm_start: bool = False) -> "RobotLoopRun":
        """Generate and check the step, build the runtime, serve the robot, learn the next ILC correction.

        Parameters
        ----------
        verbose : bool, optional
            Unused (the runtime logs to its files).
        previous, warm_start : Any, optional
            Unused (a loop run has no warm start).

        Returns
        -------
        RobotLoopRun
        """
        d = self
        work = Path(tempfile.mkdtemp(prefix="gtmodel-loop-"))
        # the file's name becomes the C prefix only as a plain, short C identifier (C99: 63 significant characters
        # for gt_<name>_heap_stats and the like); any other name gives the prefix gt_loop
        c_name = d.name if C_IDENTIFIER.fullmatch(d.name) and len(d.name) <= MAX_C_NAME else "loop"
        prefix = f"gt_{c_name}"
        source = RobotRuntime(position_step(d.controller, c_name), d.spec)
        generated = source.generate(work / "code", prefix=prefix)
        check = check_code(generated, n=CHECK_SAMPLES)
        if not check.passed:
            return RobotLoopRun(status=Status.CHECK_FAILED, work=work, check=check,
                                message="the step's C disagrees with its CasADi Function; nothing ran (code/ holds the check)")
        executable = build_runtime(source, work / "code", prefix=prefix, generated=generated)  # the checked code, not generated again
        _log.info("loop %s: listening on %s:%d (%s); the robot or gtmodel robot-sim sends there", d.name, *d.listen, d.spec.interface.upper())
        run = run_loop(executable, work / "run", listen=d.listen, sensor_port=d.sensor_port,
                       idle_timeout=d.idle_timeout, max_cycles=d.max_cycles or None, time_limit=d.time_limit, end_on_signal=True,
                       robot=d.robot, tracker=d.tracker if d.sensor_port is not None else None,
                       log_max_mb=d.log_max_mb if d.log_max_mb is not None else hour_of_log_mb(d.spec))
        result = RobotLoopRun(status=run.status, message=run.message, work=work, summary=dict(run.summary), check=check)
        if d.ilc is not None and isinstance(d.controller, ReferenceStreaming) and run.log_path is not None and run.summary.get("cycles"):
            result.ilc = next_iteration(d, read_cycle_log(run.log_path), work / "run")
        return result


@dataclass(kw_only=True)
class RobotLoopRun(StatusResult):
    """The outcome of a loop run: its status, the runtime's figures, its files, the next ILC correction.

    Parameters
    ----------
    status : Status
        The runtime's (:class:`gtmodel.control.runtime.LoopRun`): ``completed`` when it served
        the robot and ended by rule (the robot stopped sending, the cycle limit),
        ``interrupted`` when a signal ended it (log and counts complete), ``max_iterations``
        at the time limit, ``error`` when it failed; ``check_failed`` when the step's C
        disagreed with Python (nothing ran).
    message : str
        One line saying what happened.
    work : pathlib.Path
        The folder the run wrote into (``code/``, ``run/``).
    summary : dict
        The runtime's figures (:func:`gtmodel.control.runtime.summarize`).
    check : Any
        The code check of the step.
    ilc : dict
        The next ILC iteration (:func:`next_iteration`; empty: none).
    """

    work: Path = Path()
    summary: dict[str, Any] = field(default_factory=dict)
    check: Any = None
    ilc: dict[str, Any] = field(default_factory=dict)


#: Bytes of a log row's leading columns at most (cycle, IPOC, t, flags, status, latency, sensor age) and of a number (``%.17g``).
_ROW_HEAD, _NUMBER = 125, 25


def hour_of_log_mb(spec: RuntimeSpec) -> float:
    """The default cap of the cycle log: an hour of its widest rows at the spec's period.

    Parameters
    ----------
    spec : RuntimeSpec
        Its inputs and outputs give the row's columns (``x:``, ``u:``, ``reply:``, and ``sent:``
        for relative RSI corrections), its period the rows per hour.

    Returns
    -------
    float
        Megabytes (2^20 bytes), rounded up to a whole one: e.g. 494 MB for the KR 500 file
        (6 inputs, 3 relative outputs, 250 Hz).
    """
    numbers = len(spec.inputs) + len(spec.outputs) * (4 if spec.relative else 3)
    return float(math.ceil(3600.0 / spec.period * (_ROW_HEAD + _NUMBER * numbers) / 1048576.0))


def next_iteration(d: RobotLoopDeclaration, log: dict[str, np.ndarray], work: Path) -> dict[str, Any]:
    """The next ILC iteration learned from a loop's cycle log, Dressler (2012), eq. 7.2.

    ``eps = r - y`` per streamed row (``y`` the robot's feedback logged in the row; rows the log
    missed take the nearest logged feedback), ``u_next = Q (u + L eps)`` with the declaration's
    :class:`ILCLaw`; written as ``work/ilc_next.csv`` (``t`` then one column per axis), the next
    run's correction file.

    Parameters
    ----------
    d : RobotLoopDeclaration
        A streaming loop with its ILC law.
    log : dict of str to numpy.ndarray
        The cycle log (:func:`gtmodel.control.runtime.read_cycle_log`).
    work : pathlib.Path
        The folder ``ilc_next.csv`` is written into.

    Returns
    -------
    dict
        ``error_rms`` per axis (7.25, over the fully corrected rows), ``rows_logged``, ``rows``,
        the law's figures and ``file``; only a ``message`` when no feedback was logged.
    """
    c: ReferenceStreaming = d.controller  # type: ignore[assignment]
    t = log["t"]
    rows = np.clip(np.floor(t / c.dt + 1e-6).astype(int), 0, c.length - 1)
    y = np.full(c.reference.shape, np.nan)
    measured = np.all(np.isfinite(np.column_stack([log[f"x:{name}"] for name in c.x_names])), axis=1) if t.size else np.zeros(0, bool)
    for j, name in enumerate(c.x_names):  # the last feedback logged in each streamed row (rows the runtime held have none)
        y[rows[measured], j] = log[f"x:{name}"][measured]
    seen = np.all(np.isfinite(y), axis=1)
    if not np.any(seen):
        return {"message": "no feedback logged: no next iteration"}
    for j in range(c.nx):  # rows the log missed (lost packets): the nearest logged feedback
        y[:, j] = np.interp(np.arange(c.length), np.flatnonzero(seen), y[seen, j])
    eps = c.reference - y
    window = time_window(c.length, lead=d.ilc.lead, tukey_points=d.ilc.tukey_points, alpha=d.ilc.tukey_alpha) if d.ilc.lead else None
    q = QFilter(d.ilc.q_cutoff_hz, dt=c.dt, window=window)
    learning = LearningFilter(d.ilc.gamma, d.ilc.delta)
    u_next = next_correction(c.correction, eps, q, learning)
    write_table(work / "ilc_next.csv", ["t"] + [f"q{j + 1}" for j in range(c.nu)], np.column_stack([np.arange(c.length) * c.dt, u_next]),
                comments=[f" the next ILC correction (Dressler (2012), eq. 7.2) learned from a gtmodel loop run: gamma {d.ilc.gamma:g}, "
                          f"delta {d.ilc.delta}, Q {d.ilc.q_cutoff_hz:g} Hz"], what="ILC correction")
    mask = None if window is None else window >= 1.0  # the fully corrected samples (7.25)
    return {"error_rms": np.atleast_1d(error_measure(eps, mask)).tolist(), "rows_logged": int(np.sum(seen)), "rows": c.length,
            "gamma": d.ilc.gamma, "delta": d.ilc.delta, "q_cutoff_hz": d.ilc.q_cutoff_hz, "file": "ilc_next.csv"}
