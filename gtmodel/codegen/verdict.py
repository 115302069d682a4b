"""One verdict over generated code: :func:`check_code` dispatches on the code's source (:func:`gtmodel.codegen.sources.source_of`).

A robot's functions, a user model's, a controller bundle's run, a loop controller's step and
its closed loop are checked by their own harness (:mod:`gtmodel.codegen.check`); their
reports are joined in one :class:`CodeCheck` whose :attr:`CodeCheck.status` is the shared
:class:`~gtmodel.status.Status` (``converged`` when every part passed, ``check_failed``
otherwise; exit codes from :data:`gtmodel.status.EXIT_CODES`). :func:`check_generated` is
one source's report (``gtmodel.codegen.check_generated``; named so that the package
:mod:`gtmodel.codegen.check` is not shadowed: ``import gtmodel.codegen.check.closed_loop`` works).
"""

from __future__ import annotations

import logging
from dataclasses import dataclass
from typing import Any, Callable

import numpy as np

from gtmodel.codegen.check.closed_loop import closed_loop_check
from gtmodel.codegen.check.controller import check_controller
from gtmodel.codegen.check.loop_step import check_loop_step
from gtmodel.codegen.check.mpc import closed_loop_check as mpc_closed_loop_check
from gtmodel.codegen.check.robot import check as check_robot
from gtmodel.codegen.loop_step import LoopStep
from gtmodel.codegen.model_code import check_model
from gtmodel.codegen.sources import ControllerSource, RobotSource, UserModelSource, source_of
from gtmodel.codegen.writer import GeneratedCode
from gtmodel.errors import InputError
from gtmodel.status import Status

__all__ = ["CodeCheck", "check_code", "check_generated"]

log = logging.getLogger("gtmodel")


@dataclass
class CodeCheck:
    """Every part of one library's check, with one verdict.

    Parameters
    ----------
    source : CodeSource
        What was generated.
    reports : tuple
        The parts' reports, each with a ``status`` and ``summary_lines()``: C against Python
        (:class:`~gtmodel.codegen.check.report.CheckReport`, the controller bundle's run
        :class:`~gtmodel.codegen.check.controller.ControllerCheckReport`) and, for a loop
        controller given a plant, the closed loop
        (:class:`~gtmodel.codegen.check.closed_loop.LoopCheck`).
    """

    source: Any
    reports: tuple = ()

    @property
    def status(self) -> Status:
        """The worst of the parts' statuses (``converged`` when every part passed; ``check_failed`` otherwise)."""
        return Status.worst([r.status for r in self.reports]) if self.reports else Status.CONVERGED

    @property
    def passed(self) -> bool:
        """Whether every part passed."""
        return self.status.success

    def failures(self) -> list[str]:
        """Why the check fails (empty: it passes).

        Returns
        -------
        list of str
        """
        out = []
        for r in self.reports:
            if hasattr(r, "failures"):
                out += r.failures()
            elif not r.passed:
                out.append("the C differs from Python" if isinstance(self.source, LoopStep) else f"{type(r).__name__} failed")
        return out

    def to_dict(self) -> dict[str, Any]:
        """The verdict and every part's figures as JSON-able values (``DIR/summary.json`` of ``gtmodel codegen ... --check``).

        Returns
        -------
        dict
            ``status`` (the shared :class:`~gtmodel.status.Status`, as a string), ``passed``, ``failures`` and ``parts``:
            per report its ``part`` (the report's class), ``status`` and, for a closed loop, its figures
            (:meth:`gtmodel.codegen.check.closed_loop.LoopCheck.to_dict`: the ratio to the feedforward, every declared
            bound's value, limit, percent and time at the samples and between them, the step times).
        """
        parts = []
        for r in self.reports:
            entry = r.to_dict() if hasattr(r, "to_dict") else {"status": str(r.status)}
            parts.append({"part": type(r).__name__, **entry})
        return {"status": str(self.status), "passed": bool(self.passed), "failures": self.failures(), "parts": parts}

    def summary_lines(self) -> list[str]:
        """The parts' summaries; with a closed loop the verdict ``closed-loop check: PASSED | FAILED (why) [notes]``.

        Returns
        -------
        list of str
        """
        lines = [line for r in self.reports for line in r.summary_lines()]
        loops = [r for r in self.reports if hasattr(r, "failures")]
        if loops:
            notes = "".join(f" [{n}]" for r in loops for n in getattr(r, "notes", []))
            failures = self.failures()
            lines.append("closed-loop check: " + ("PASSED" if not failures else "FAILED (" + "; ".join(failures) + ")") + notes)
        return lines


def check_code(generated: GeneratedCode, *, n: int = 1000, seed: int = 0, timing: bool = False, plant: Any = None,
               label: str = "controller", progress: Callable[[str], None] | None = None) -> CodeCheck:
    """Check generated code against its Python reference, dispatching on its source; one shared status.

    A robot's functions: :func:`gtmodel.codegen.check.robot.check` (with the controller bundle's
    run, :func:`~gtmodel.codegen.check.controller.check_controller`, when it has one); a user
    model: :func:`~gtmodel.codegen.model_code.check_model`; a controller bundle alone:
    :func:`~gtmodel.codegen.check.controller.check_controller`; a loop controller:
    :func:`~gtmodel.codegen.check.loop_step.check_loop_step` and, with a ``plant``, the closed loop
    :func:`~gtmodel.codegen.check.closed_loop.closed_loop_check` (the MPC's,
    :func:`gtmodel.codegen.check.mpc.closed_loop_check`, for an MPC), in ``double`` and ``float`` alike.

    Parameters
    ----------
    generated : GeneratedCode
        What was generated.
    n : int, optional
        Random inputs per function (default 1000).
    seed : int, optional
        Random seed.
    timing : bool, optional
        Also time the functions in C.
    plant : LoopSetup, optional
        A loop-controller file's setup (:func:`gtmodel.problems.loop_file.read_loop_file`): the
        closed loop runs against its plant. Only for a loop controller.
    label : str, optional
        What the loop controller is, for the closed loop's summary (``"MPC"`` is the MPC's check).
    progress : callable, optional
        ``progress(line)`` before each part and while the closed loop runs.

    Returns
    -------
    CodeCheck
        The parts' reports and :attr:`CodeCheck.status`.

    Raises
    ------
    InputError
        A plant for code that is not a loop controller's.
    CompilerNotFoundError
        No C compiler.
    CodegenError
        Compilation failed.
    """
    say = progress or (lambda line: None)
    source = source_of(generated)
    reports: list = []
    if plant is not None and not isinstance(source, LoopStep):
        raise InputError("plant: a closed loop applies to a loop controller's code (tracking controller, MPC)")
    if isinstance(source, LoopStep):
        say(f"compiling {generated.prefix} and comparing it with Python on {n} random inputs")
        reports.append(check_loop_step(generated, n=n, seed=seed, timing=timing))
        if plant is not None:
            say(f"closed loop of {label} against the plant simulated in Python ({np.size(plant.t)} periods, and the feedforward alone)")
            if label == "MPC":
                reports.append(mpc_closed_loop_check(plant, generated, reports[0].library, progress=progress))
            else:
                reports.append(closed_loop_check(plant, generated, reports[0].library, label=label, progress=progress))
    elif isinstance(source, UserModelSource):
        say(f"compiling {generated.prefix} and comparing it with Python on {n} random inputs per function")
        reports.append(check_model(generated, n=n, seed=seed, timing=timing))
    else:
        if isinstance(source, RobotSource) and source.functions:
            say(f"compiling {generated.prefix} and comparing it with Python on {n} random inputs per function")
            reports.append(check_robot(generated, n=n, seed=seed, timing=timing))
        if generated.controller is not None:
            say(f"running the controller bundle of {generated.prefix} over a run in C and in Python")
            reports.append(check_controller(generated, seed=seed, timing=timing))
    result = CodeCheck(source, tuple(reports))
    log.debug("codegen check of %s: %s", generated.prefix, result.status)
    return result


def check_generated(generated: GeneratedCode, *args: Any, **options: Any) -> Any:
    """``gtmodel.codegen.check_generated``: the check of one part of any generated code, dispatching on its source; its report has a ``status``.

    Parameters
    ----------
    generated : GeneratedCode
        What was generated.
    *args, **options
        The source's check's options (``n``, ``seed``, ``library``, ``build_dir``, ``timing``, ...).

    Returns
    -------
    CheckReport
        Of the robot's functions (:func:`gtmodel.codegen.check.robot.check`, as before), a user
        model's (:func:`~gtmodel.codegen.model_code.check_model`), a loop controller's
        (:func:`~gtmodel.codegen.check.loop_step.check_loop_step`) or a controller bundle's
        alone (:func:`~gtmodel.codegen.check.controller.check_controller`, its ``cycles``); each
        with :attr:`~gtmodel.codegen.check.report.CheckReport.status` (the shared
        :class:`~gtmodel.status.Status`). :func:`check_code` joins the parts and the closed loop.

    Raises
    ------
    InputError
        Bad options.
    CompilerNotFoundError
        No C compiler.
    CodegenError
        Compilation failed.
    """
    source = source_of(generated)
    if isinstance(source, LoopStep):
        return check_loop_step(generated, *args, **options)
    if isinstance(source, UserModelSource):
        return check_model(generated, *args, **options)
    if isinstance(source, ControllerSource):
        return check_controller(generated, *args, **options)
    return check_robot(generated, *args, **options)
