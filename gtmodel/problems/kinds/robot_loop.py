"""Kind ``robot_loop``: the 4 ms loop on a robot controller's position interface (KUKA RSI, ABB EGM).

``gtmodel loop FILE --out DIR`` (or ``gtmodel solve FILE``) runs it in four stages
(:class:`gtmodel.codegen.robot_loop.RobotLoopDeclaration`, the declaration this kind loads),
each of which ends the run with a status when it fails:

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

import shutil
from pathlib import Path

import numpy as np

from gtmodel._docstrings import fill_doc
from gtmodel._tables import read_table
from gtmodel.codegen.robot_loop import ILCLaw, RobotLoopDeclaration, RobotLoopRun
from gtmodel.codegen.robot_runtime import RuntimeSpec
from gtmodel.control.position_loop import PoseCorrection, ReferenceStreaming
from gtmodel.errors import GtModelError
from gtmodel.estimation.ilc.lifted import LearningFilter, QFilter, time_window
from gtmodel.problems.base import KIND_DOCS, Column, ProblemFile, ProblemKind, Written
from gtmodel.problems.kinds.schemas.robot_loop import DEFAULT_PORTS, RobotLoopFile, local_address_problem, parse_address

__all__ = ["RobotLoopFile", "RobotLoopKind", "MAX_TRAJECTORY_ROWS"]

#: Most rows of a streamed trajectory (an hour at 4 ms).
MAX_TRAJECTORY_ROWS = 900_000


#: The runtime's rules (:class:`~gtmodel.codegen.robot_runtime.RuntimeSpec`, whose messages start with its field)
#: -> the file's field they come from.
_SPEC_FIELDS = {"reply_deadline_s": "interface.reply_deadline", "period": "interface.period", "sen_type": "interface.sen_type",
                "correction": "interface.correction", "egm_mode": "interface.egm_mode", "rate": "limits.rate",
                "fallback": "faults.fallback", "stale_cycles": "faults.stale_cycles", "interface": "interface.type"}


def _read_table(path: Path, what: str, file: ProblemFile, field_name: str, width: int | None = None) -> np.ndarray:
    """A CSV of the project's format (:func:`gtmodel._tables.read_table`, capped in rows): ``t`` then one column per axis."""
    try:
        table = read_table(path, what, max_rows=MAX_TRAJECTORY_ROWS)
    except GtModelError as exc:
        raise file.wrap(field_name, exc) from None
    data = table.data
    if data.ndim != 2 or data.shape[0] < 2 or data.shape[1] < 2 or (width is not None and data.shape[1] != width):
        cols = f"{width} columns" if width is not None else "at least two columns"
        raise file.fail(field_name, f"at least two rows of {cols}, t then one per axis ({what})", f"{path}: shape {data.shape}")
    return data


#: The ``[ilc]`` field an error of the ILC's filters is about (by the first word of its message).
_ILC_FIELDS = {"cutoff_hz": "ilc.q_cutoff_hz", "tukey_points": "ilc.tukey_points", "lead": "ilc.lead", "alpha": "ilc.tukey_alpha",
               "gamma": "ilc.gamma", "delta": "ilc.delta"}


def _check_ilc(file: ProblemFile, ilc: ILCLaw, length: int, period: float) -> None:
    """The ``[ilc]`` law against the trajectory and the period, before anything runs (the run learns with exactly these)."""
    try:
        window = time_window(length, lead=ilc.lead, tukey_points=ilc.tukey_points, alpha=ilc.tukey_alpha) if ilc.lead else None
        QFilter(ilc.q_cutoff_hz, dt=period, window=window)
        LearningFilter(ilc.gamma, ilc.delta)
    except GtModelError as exc:
        name = str(exc).split(":", 1)[0]
        raise file.wrap(_ILC_FIELDS.get(name, "ilc"), exc) from None
    if ilc.delta >= length:
        raise file.fail("ilc.delta", f"a learning lead shorter than the trajectory ({length} rows)", ilc.delta)


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
        problem = local_address_problem(listen[0])
        if problem is not None:  # here, not at the runtime's bind after the build (exit 1)
            raise file.fail("interface.listen", problem, it.listen)
        if it.reply_deadline >= it.period:
            raise file.fail("interface.reply_deadline", f"a deadline shorter than the period ({it.period:g} s): the reply is due "
                                                        "before the robot's next packet", it.reply_deadline)
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
            raise file.wrap(_SPEC_FIELDS.get(str(exc).split(":")[0], "limits"), exc) from None
        ilc = ILCLaw(**doc.ilc.model_dump()) if doc.ilc is not None else None
        if ilc is not None:
            _check_ilc(file, ilc, controller.length, it.period)
        if it.tracker is not None and sensor is None:
            raise file.fail("interface.tracker", "no tracker for a streaming loop (only a pose correction reads the sensor stream)", it.tracker)
        return RobotLoopDeclaration(name=name, controller=controller, spec=spec, listen=listen, sensor_port=sensor,
                                    idle_timeout=it.idle_timeout, time_limit=it.time_limit, max_cycles=it.max_cycles, ilc=ilc,
                                    robot=it.robot, tracker=it.tracker, log_max_mb=it.log_max_mb)

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


