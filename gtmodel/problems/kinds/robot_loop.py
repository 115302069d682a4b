"""Kind ``robot_loop``: the 4 ms loop on a robot controller's position interface (KUKA RSI, ABB EGM).

``gtmodel loop FILE --out DIR`` (or ``gtmodel solve FILE``) runs it in four stages, each of
which ends the run with a status when it fails:

1. the controller (:mod:`gtmodel.control.position_loop`: Cvitanic's pose correction from a
   tracker, or a planned trajectory streamed with its ILC correction) becomes a loop step
   (:func:`gtmodel.codegen.loop_step.position_step`);
2. the runtime around it (:class:`gtmodel.codegen.robot_runtime.RobotRuntime`: the cycle,
   the RSI or EGM messages, the limits after the step, the fault rules, the log) is written
   through codegen's one front door, the step's C checked against its CasADi Function
   (:func:`gtmodel.codegen.check_code`; a failed check never runs on a robot: status
   ``check_failed``) and the runtime compiled;
3. the runtime serves the robot (or ``gtmodel robot-sim``) that sends to the listening
   port until the robot stops sending for ``idle_timeout``, ``max_cycles``, ``time_limit``
   or a signal (:func:`gtmodel.control.runtime.run_loop`);
4. for a streamed reference with ``[ilc]``, the next iteration's correction is learned
   from the cycle log, Dressler (2012), eq. 7.2 (:func:`gtmodel.estimation.ilc.next_correction`):
   ``eps = r - y`` per cycle with ``y`` the robot's feedback, ``u_next = Q (u + L eps)``;
   ``ilc_next.csv`` is the next run's ``--correction-file``. Dressler's experiment loop, closed.

The result folder holds ``summary.json`` (the run's figures: cycles, late, held and missing
replies, reply latency percentiles, faults seen and what was done, whether real-time
scheduling was granted), ``cycle_log.csv`` (one row per cycle: the measurement, the step's
output and the reply sent), ``code/`` (the generated C, the runtime's program in
``code/build``) and ``ilc_next.csv``. The field reference is ``docs/problem_files.md``, the
guide ``docs/robot.md``.
"""

from __future__ import annotations

import csv
import logging
import shutil
import tempfile
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from gtmodel._docstrings import fill_doc
from gtmodel._escape import csv_field
from gtmodel.codegen import check_code
from gtmodel.codegen.loop_step import position_step
from gtmodel.codegen.robot_runtime import RobotRuntime, RuntimeSpec, build_runtime
from gtmodel.control.position_loop import PoseCorrection, ReferenceStreaming
from gtmodel.control.runtime import read_cycle_log, run_loop
from gtmodel.errors import GtModelError
from gtmodel.estimation.ilc.iteration import error_measure, next_correction
from gtmodel.estimation.ilc.lifted import LearningFilter, QFilter, time_window
from gtmodel.problems.base import KIND_DOCS, Column, ProblemFile, ProblemKind, Written
from gtmodel.problems.kinds.schemas.robot_loop import DEFAULT_PORTS, RobotLoopFile, parse_address
from gtmodel.status import Status, StatusResult

__all__ = ["RobotLoopFile", "RobotLoopKind", "RobotLoopDeclaration", "RobotLoopRun", "MAX_TRAJECTORY_ROWS"]

_log = logging.getLogger("gtmodel")

#: Most rows of a streamed trajectory (an hour at 4 ms).
MAX_TRAJECTORY_ROWS = 900_000
#: Samples of the code check of the step.
CHECK_SAMPLES = 300


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
    ilc : Any
        The ``[ilc]`` section (streaming only) or None.
    """

    name: str
    controller: PoseCorrection | ReferenceStreaming
    spec: RuntimeSpec
    listen: tuple[str, int]
    sensor_port: int | None
    idle_timeout: float
    time_limit: float
    max_cycles: int
    ilc: Any = None


@dataclass(kw_only=True)
class RobotLoopRun(StatusResult):
    """The outcome of a loop run: its status, the runtime's figures, its files, the next ILC correction.

    Parameters
    ----------
    status : Status
        ``completed`` when the runtime served the robot and ended by rule (robot stopped,
        cycle limit, signal) with every reply within its limits; ``check_failed`` when the
        step's C disagreed with Python (nothing ran); ``error`` when the runtime failed or
        no robot packet arrived.
    message : str
        One line saying what happened.
    work : pathlib.Path
        The folder the run wrote into (copied into the result folder by ``write``).
    summary : dict
        The runtime's figures (:class:`gtmodel.control.runtime.LoopRun`).
    check : Any
        The code check of the step.
    ilc : dict
        The next ILC iteration: error RMS per axis, the correction's path (empty: none).
    """

    work: Path = Path()
    summary: dict[str, Any] = field(default_factory=dict)
    check: Any = None
    ilc: dict[str, Any] = field(default_factory=dict)


def _read_table(path: Path, what: str, file: ProblemFile, field_name: str, width: int | None = None) -> np.ndarray:
    """A CSV with a header row and numbers (no NaN), capped in rows."""
    try:
        with open(path, newline="", encoding="utf-8") as fh:
            rows = list(csv.reader(line for _, line in zip(range(MAX_TRAJECTORY_ROWS + 2), fh)))
    except (OSError, UnicodeDecodeError) as exc:
        raise file.fail(field_name, f"a readable UTF-8 CSV of {what}", f"{path} ({exc})") from None
    if len(rows) > MAX_TRAJECTORY_ROWS + 1:
        raise file.fail(field_name, f"at most {MAX_TRAJECTORY_ROWS} rows of {what}", str(path))
    try:
        data = np.array([[float(v) for v in row] for row in rows[1:]], dtype=float)
    except ValueError as exc:
        raise file.fail(field_name, f"a header row then rows of numbers ({what})", f"{path}: {exc}") from None
    if data.ndim != 2 or data.shape[0] < 2 or data.shape[1] < 2 or not np.all(np.isfinite(data)):
        raise file.fail(field_name, f"at least two rows of finite numbers, t then one column per axis ({what})", f"{path}: shape {data.shape}")
    if width is not None and data.shape[1] != width:
        raise file.fail(field_name, f"{width} columns (t then one per axis)", f"{path}: {data.shape[1]} columns")
    return data


class RobotLoopKind(ProblemKind):
    """The 4 ms loop behind KUKA RSI or ABB EGM: Cvitanic's tracker correction, or streaming with ILC (Dressler's experiment loop)."""

    name = "robot_loop"
    schema = RobotLoopFile
    title = ("the 4 ms loop on a robot controller: the generated step behind KUKA RSI or ABB EGM over UDP, with limits, fault rules "
             "and a cycle log (Cvitanic (2021), sec. 5; Dressler (2012), sec. 7.3)")
    file_descriptions = {
        "cycle_log.csv": "one row per cycle: cycle, IPOC or sequence, time, flags, reply latency, the measurement, the step's output and the reply sent",
        "runtime_stats.json": "the runtime's own counters at exit (cycles, replies, faults by kind, fallbacks, real-time scheduling)",
        "ilc_next.csv": "streaming with [ilc]: the next iteration's learned correction per cycle (the next run's --correction-file)",
        "code": "the generated C: the step, the runtime and its configuration (gt_runtime_config.h), nanopb, the program gt_runtime; "
                  "code/build the step's check",
    }
    ends_on_signal = True
    columns = (
        Column("cycles", "cycles", "{:d}"),
        Column("latency_p99_ms", "reply p99 [ms]", "{:.3f}"),
    )

    @fill_doc(**KIND_DOCS)
    def load(self, doc: RobotLoopFile, file: ProblemFile, name: str) -> RobotLoopDeclaration:
        """Build the controller and the runtime's rules; read the trajectory and the correction.

        Parameters
        ----------
        {load_args}

        Returns
        -------
        RobotLoopDeclaration

        Raises
        ------
        ProblemError
            An unreadable or malformed trajectory or correction file (naming the field), a
            correction of another shape, limits of another length than the outputs, a
            reference outside the limits.
        """
        it, ct, lim = doc.interface, doc.controller, doc.limits
        listen = parse_address(it.listen) if it.listen else ("127.0.0.1", DEFAULT_PORTS[it.type])
        sensor = None
        if ct.type == "pose_correction":
            sensor = it.sensor_port or (listen[1] + 1 if listen[1] < 65535 else listen[1] - 1)
            if sensor == listen[1]:
                raise file.fail("interface.sensor_port", f"a port other than the listen port {listen[1]}", sensor)
            try:
                controller: PoseCorrection | ReferenceStreaming = PoseCorrection(
                    gain=ct.gain, limit=np.maximum(np.abs(lim.lower), np.abs(lim.upper)), dt=it.period,
                    sensor_scale=ct.sensor_scale, reference_includes_correction=ct.reference_includes_correction)
            except GtModelError as exc:
                raise file.wrap("controller", exc) from None
        else:
            table = _read_table(Path(file.data_file("controller.trajectory", ct.trajectory)), "planned positions", file, "controller.trajectory")
            ref = table[:, 1:]
            if len(lim.lower) != ref.shape[1]:
                raise file.fail("limits.lower", f"one value per axis of the trajectory ({ref.shape[1]})", len(lim.lower))
            corr = None
            if ct.correction_file is not None:
                corr = _read_table(Path(file.data_file("controller.correction_file", ct.correction_file)), "a learned correction", file,
                                   "controller.correction_file", width=table.shape[1])[:, 1:]
                if corr.shape != ref.shape:
                    raise file.fail("controller.correction_file", f"the trajectory's {ref.shape[0]} rows", corr.shape[0])
            try:
                controller = ReferenceStreaming(ref, corr, lower=lim.lower, upper=lim.upper, dt=it.period)
            except GtModelError as exc:
                raise file.wrap("controller.trajectory", exc) from None
        try:
            spec = RuntimeSpec(interface=it.type, egm_mode=it.egm_mode, inputs=tuple(controller.x_names), outputs=tuple(controller.u_names),
                               lower=tuple(lim.lower), upper=tuple(lim.upper), rate=tuple(lim.rate), correction=it.correction,
                               sen_type=it.sen_type, fallback=doc.faults.fallback, stale_cycles=doc.faults.stale_cycles,
                               reply_deadline_s=it.reply_deadline, period=it.period)
        except GtModelError as exc:
            raise file.wrap("limits", exc) from None
        return RobotLoopDeclaration(name=name, controller=controller, spec=spec, listen=listen, sensor_port=sensor,
                                    idle_timeout=it.idle_timeout, time_limit=it.time_limit, max_cycles=it.max_cycles, ilc=doc.ilc)

    def solve(self, declaration: RobotLoopDeclaration, *, verbose: bool = False, previous: Any = None, warm_start: bool = False) -> RobotLoopRun:
        """Generate and check the step, build the runtime, serve the robot, learn the next ILC correction.

        Parameters
        ----------
        declaration : RobotLoopDeclaration
            From :meth:`load`.
        verbose : bool, optional
            Unused (the runtime logs to its files).
        previous, warm_start : Any, optional
            Unused (a loop run has no warm start).

        Returns
        -------
        RobotLoopRun
        """
        d = declaration
        work = Path(tempfile.mkdtemp(prefix="gtmodel-loop-"))
        prefix = f"gt_{d.name}" if d.name.isidentifier() and d.name.isascii() else "gt_loop"
        source = RobotRuntime(position_step(d.controller, d.name if d.name.isidentifier() else "loop"), d.spec)
        generated = source.generate(work / "code", prefix=prefix)
        check = check_code(generated, n=CHECK_SAMPLES)
        if not check.passed:
            return RobotLoopRun(status=Status.CHECK_FAILED, work=work, check=check,
                                message="the step's C disagrees with its CasADi Function; nothing ran (code/ holds the check)")
        executable = build_runtime(source, work / "code", prefix=prefix)
        _log.info("loop %s: listening on %s:%d (%s); the robot or gtmodel robot-sim sends there", d.name, *d.listen, d.spec.interface.upper())
        run = run_loop(executable, work / "run", listen=d.listen, sensor_port=d.sensor_port,
                       idle_timeout=d.idle_timeout, max_cycles=d.max_cycles or None, time_limit=d.time_limit, end_on_signal=True)
        result = RobotLoopRun(status=run.status, message=run.message, work=work, summary=dict(run.summary), check=check)
        if d.ilc is not None and isinstance(d.controller, ReferenceStreaming) and run.log_path is not None and run.summary.get("cycles"):
            result.ilc = _next_iteration(d, read_cycle_log(run.log_path), work / "run")
        return result

    @fill_doc(**KIND_DOCS)
    def write(self, declaration: RobotLoopDeclaration, solution: RobotLoopRun, out: Path, plots: bool, name: str) -> Written:
        """The run's figures, the cycle log, the runtime's counters, the code and the next ILC correction.

        Parameters
        ----------
        declaration : RobotLoopDeclaration
            From :meth:`load`.
        solution : RobotLoopRun
            From :meth:`solve`.
        {write_args}

        Returns
        -------
        Written
            ``status``, ``message``, ``interface``, ``listen``, ``loop`` (the runtime's figures),
            ``cycles``, ``latency_p99_ms``, ``check`` and ``ilc``.
        """
        files = []
        for item in ("cycle_log.csv", "runtime_stats.json", "ilc_next.csv"):
            if (solution.work / "run" / item).is_file():
                shutil.copy2(solution.work / "run" / item, out / item)
                files.append(item)
        if (solution.work / "code").is_dir():
            shutil.copytree(solution.work / "code", out / "code", symlinks=True)
            files.append("code")
        shutil.rmtree(solution.work, ignore_errors=True)
        d = declaration
        lat = solution.summary.get("reply_latency_ms") or {}
        fields = {
            "status": str(solution.status), "message": solution.message, "interface": d.spec.interface,
            "listen": f"{d.listen[0]}:{d.listen[1]}", "sensor_port": d.sensor_port,
            "controller": type(d.controller).__name__, "loop": solution.summary, "cycles": solution.summary.get("cycles"),
            "latency_p99_ms": lat.get("p99"), "check": {"passed": bool(solution.check.passed) if solution.check is not None else None},
            "ilc": solution.ilc or None,
        }
        return Written(fields=fields, files=files)


def _next_iteration(d: RobotLoopDeclaration, log: dict[str, np.ndarray], work: Path) -> dict[str, Any]:
    """Dressler (2012), eq. 7.2 on the logged run: ``eps = r - y`` per streamed row, ``u_next = Q (u + L eps)``; writes ilc_next.csv."""
    c: ReferenceStreaming = d.controller  # type: ignore[assignment]
    t = log["t"]
    rows = np.clip(np.floor(t / c.dt + 1e-6).astype(int), 0, c.length - 1)
    y = np.full(c.reference.shape, np.nan)
    for j, name in enumerate(c.x_names):  # the last feedback logged in each streamed row
        y[rows, j] = log[f"x:{name}"]
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
    names = ["t"] + [f"q{j + 1}" for j in range(c.nu)]
    with open(work / "ilc_next.csv", "w", encoding="utf-8", newline="") as fh:
        fh.write(",".join(csv_field(n) for n in names) + "\n")
        np.savetxt(fh, np.column_stack([np.arange(c.length) * c.dt, u_next]), delimiter=",", fmt="%.17g")
    mask = None if window is None else window >= 1.0  # the fully corrected samples (7.25)
    return {"error_rms": np.atleast_1d(error_measure(eps, mask)).tolist(), "rows_logged": int(np.sum(seen)), "rows": c.length,
            "gamma": d.ilc.gamma, "delta": d.ilc.delta, "q_cutoff_hz": d.ilc.q_cutoff_hz, "file": "ilc_next.csv"}
