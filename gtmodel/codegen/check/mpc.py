"""The MPC of an MPC file as C, checked in closed loop (``gtmodel codegen mpc FILE --out DIR --check``).

:func:`build_mpc` generates the loop step (:func:`gtmodel.codegen.loop_step.mpc_step`,
:func:`~gtmodel.codegen.loop_step.generate_loop_step`: CasADi's code generation of the
``sqpmethod`` + ``qrqp`` solver inside one Function, the plain-C memory interface
``<prefix>_init`` / ``<prefix>_step``) and compiles it; :func:`closed_loop_check` loads it
through ctypes and runs it against the mismatched plant of the file's ``[check]``
(:func:`gtmodel.estimation.closed_loop.controller_loop.run_controller_loop`, through
:func:`gtmodel.codegen.check.closed_loop.closed_loop_check`), beside the
feedforward alone (``u*`` of the reference, saturated) on the same plant, noise and
disturbance, and compares the first input with the horizon problem solved to convergence
by IPOPT at a sample of the closed loop's states after repeated SQP iterations there.
"""

from __future__ import annotations

import time
from pathlib import Path
from typing import Any

import numpy as np

from gtmodel.codegen.build import CompiledLibrary
from gtmodel.codegen.check import closed_loop as loop_check
from gtmodel.codegen.check.closed_loop import STATUS_NAMES, LoopCheck, compiled_step
from gtmodel.codegen.writer import GeneratedCode
from gtmodel.codegen.loop_step import build_step, mpc_step
from gtmodel.errors import InputError, SolverError
from gtmodel.estimation.closed_loop.controller_loop import LoopSummary

#: An MPC file's setup (:class:`gtmodel.problems.mpc_file.MPCSetup`), used through its attributes.
MPCSetup = Any

__all__ = ["MPCCheck", "STATUS_NAMES", "build_mpc", "compiled_step", "closed_loop_check", "ipopt_agreement"]


class MPCCheck(LoopCheck):
    """Closed-loop figures of a generated MPC (:class:`~gtmodel.codegen.check.closed_loop.LoopCheck`; :attr:`mpc` the C MPC's run).

    Parameters
    ----------
    closed : LoopSummary
        The generated C step in the loop.
    feedforward : LoopSummary
        The feedforward alone on the same plant.
    memory_bytes : int
        ``sizeof(<prefix>_memory)``.
    work_bytes : int
        Stack work arrays of one step.
    label : str
        ``"MPC"``.
    state_limits : bool
        False: the MPC holds the bounds by its constraint rows (its remedy is the MPC's).
    max_ratio : float
        The largest RMS ratio to the feedforward that passes (exclusive).
    step_budget_s : float
        The largest 99th-percentile step time that passes [s].
    heap : tuple of int or None
        The QP solver's arena figures (:func:`~gtmodel.codegen.check.closed_loop.heap_stats`).
    clock : str
        Name of the clock of the step times.
    reference_at_bounds : float
        Fraction of the reference's samples at an input bound.
    bounds, bounds_feedforward : list of BoundExcess
        Every declared bound on the plant under the MPC and under the feedforward alone
        (:func:`~gtmodel.codegen.check.closed_loop.plant_bounds`).
    notes : list of str
        What the summary and the verdict repeat.
    real : str
        The step's real type.
    states_at_bounds : dict of str to float
        Per declared state bound the reference rides, the fraction of its samples there.
    bounds_between : list of BoundExcess
        The declared state bounds counted between the samples (judged as ``bounds``).
    estimates : list of dict
        The MPC's estimator read from its memory along the run (:func:`~gtmodel.control.mpc_memory.memory_estimates`).
    predictions : list of dict
        Where a state went beyond its bound, what the MPC's model predicted there
        (:func:`~gtmodel.codegen.check.loop_causes.excess_predictions`).
    noise_gain : dict or None
        None: an MPC has no gain table (:func:`~gtmodel.codegen.check.loop_causes.noise_gain`).
    """

    @property
    def mpc(self) -> LoopSummary:
        """The generated C MPC's run (:attr:`closed`)."""
        return self.closed


def build_mpc(setup: MPCSetup, out_dir: str | Path, prefix: str | None = None, real: str = "double") -> tuple[GeneratedCode, Path]:
    """Generate and compile the MPC step of an MPC file.

    Parameters
    ----------
    setup : MPCSetup
        From :func:`gtmodel.problems.mpc_file.load_mpc_file`.
    out_dir : str or pathlib.Path
        Folder of the C files (the shared library in ``out_dir/build``).
    prefix : str, optional
        C prefix (default ``gt_<name>``).
    real : {"double", "float"}, optional
        Floating-point type of the generated step.

    Returns
    -------
    generated : GeneratedCode
    library : pathlib.Path
        The compiled shared library.
    """
    return build_step(mpc_step(setup.controller, setup.name, real=real), out_dir, prefix or f"gt_{setup.name}", real=real)


def closed_loop_check(setup: MPCSetup, generated: GeneratedCode, library: Path | CompiledLibrary, repeat: int = 1,
                      clock: Any = time.thread_time, progress: Any = None) -> MPCCheck:
    """Run the generated MPC and the feedforward alone against the file's plant (:func:`gtmodel.codegen.check.closed_loop.closed_loop_check`).

    Parameters
    ----------
    setup : MPCSetup
        The MPC file's controller, plant and loop options.
    generated : GeneratedCode
        From :func:`build_mpc`.
    library : pathlib.Path or CompiledLibrary
        The compiled library.
    repeat : int, optional
        Runs of the whole motion (``_init`` before each; the step times and statuses of
        all runs are kept, the tracking figures are those of the first run).
    clock : callable, optional
        Clock of the step times (see :func:`~gtmodel.estimation.closed_loop.controller_loop.run_controller_loop`);
        default the thread's CPU time (:func:`gtmodel.codegen.check.closed_loop.closed_loop_check`).
    progress : callable, optional
        ``progress(line)`` while the loop runs (see :func:`gtmodel.codegen.check.closed_loop.closed_loop_check`).

    Returns
    -------
    MPCCheck
    """
    check = loop_check.closed_loop_check(setup, generated, library, repeat=repeat, clock=clock, label="MPC", progress=progress)
    return MPCCheck(**check.__dict__)


def ipopt_agreement(setup: MPCSetup, summary: LoopSummary, samples: int = 5, iterations: int = 20, min_speed: float = 0.0) -> np.ndarray:
    """First input of the SQP iterated to convergence against IPOPT's, at states of a closed loop.

    At ``samples`` evenly spaced samples ``(t_k, x_k)`` of ``summary``, the same horizon
    problem is solved by IPOPT to convergence (tolerance 1e-10) and by the step's SQP
    (Gauss-Newton, ``qrqp``) with ``iterations`` iterations from the reference input.

    Parameters
    ----------
    setup : MPCSetup
        The MPC.
    summary : LoopSummary
        A closed-loop run (its true states).
    samples : int, optional
        Number of states compared.
    iterations : int, optional
        SQP iterations (the converged real-time iteration).
    min_speed : float, optional
        Compare only at states whose second half (the velocities of a mechanical model)
        exceeds this in every entry (default 0: any state). At rest the smooth Coulomb
        friction makes the horizon problem non-convex (the sign of each force's motion is
        open) and two solvers from one start may reach different local minima.

    Raises
    ------
    InputError
        No state of the run moves faster than ``min_speed``.
    SolverError
        IPOPT, the reference, did not solve the horizon problem at a sample (its status and time).

    Returns
    -------
    numpy.ndarray
        ``(samples,)`` ``max |u_SQP - u_IPOPT| / (1 + max |u_IPOPT|)`` per state.
    """
    c = setup.controller
    moving = np.flatnonzero(np.all(np.abs(summary.x[:, c.nx // 2:]) > min_speed, axis=1)) if min_speed > 0 else np.arange(summary.t.size)
    if moving.size == 0:
        raise InputError(f"summary: no state with every velocity above min_speed = {min_speed}")
    idx = moving[np.linspace(0, moving.size - 1, samples).round().astype(int)]
    out = []
    for k in idx:
        ref = c.solve(summary.t[k], summary.x[k], plugin="ipopt")
        if not ref.success:
            raise SolverError(f"IPOPT, the reference, did not solve the horizon problem at t = {summary.t[k]!r} s: {ref.status} "
                              f"({ref.message})")
        u_ip = ref.u
        u_sqp, _ = c.solve(summary.t[k], summary.x[k], plugin="sqpmethod", iterations=iterations)
        out.append(np.max(np.abs(u_sqp - u_ip)) / (1 + np.max(np.abs(u_ip))))
    return np.asarray(out)
