"""The MPC of an MPC file as C, checked in closed loop (``gtmodel codegen --mpc FILE --out DIR --check``).

:func:`build_mpc` generates the loop step (:func:`gtmodel.codegen.loop_step.mpc_step`,
:func:`~gtmodel.codegen.loop_step.generate_loop_step`: CasADi's code generation of the
``sqpmethod`` + ``qrqp`` solver inside one Function, the plain-C memory interface
``<prefix>_init`` / ``<prefix>_step``) and compiles it; :func:`closed_loop_check` loads it
through ctypes and runs it against the mismatched plant of the file's ``[check]``
(:func:`gtmodel.estimation.closed_loop.controller_loop.run_controller_loop`), beside the
feedforward alone (``u*`` of the reference, saturated) on the same plant, noise and
disturbance, and compares the first input with the horizon problem solved to convergence
by IPOPT at a sample of the closed loop's states after repeated SQP iterations there.
"""

from __future__ import annotations

import ctypes
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from gtmodel.codegen.build import compile_shared, load_library
from gtmodel.codegen.declarations import STATUS_CODES
from gtmodel.codegen.generate import GeneratedCode
from gtmodel.codegen.loop_step import generate_loop_step, load_loop_step, mpc_step
from gtmodel.errors import InputError
from gtmodel.estimation.closed_loop.controller_loop import LoopSummary, run_controller_loop
from gtmodel.problems.mpc_file import MPCSetup

__all__ = ["MPCCheck", "build_mpc", "compiled_step", "closed_loop_check", "ipopt_agreement"]

#: Status names by code.
STATUS_NAMES = {code: name for name, (code, _) in STATUS_CODES.items()}


@dataclass
class MPCCheck:
    """Closed-loop figures of a generated MPC.

    Parameters
    ----------
    mpc : LoopSummary
        The generated C step in the loop.
    feedforward : LoopSummary
        The feedforward alone on the same plant.
    memory_bytes : int
        ``sizeof(<prefix>_memory)`` (the caller's static memory).
    work_bytes : int
        Stack work arrays of one step (CasADi's ``sz_arg``, ``sz_res`` pointers, ``sz_iw``
        integers, ``sz_w`` reals).
    """

    mpc: LoopSummary
    feedforward: LoopSummary
    memory_bytes: int
    work_bytes: int

    @property
    def ratio_to_feedforward(self) -> float:
        """RMS tracking error of the MPC over that of the feedforward alone."""
        return self.mpc.rms_error / self.feedforward.rms_error

    def summary_lines(self) -> list[str]:
        """Human-readable summary.

        Returns
        -------
        list of str
        """
        return (["closed loop, generated C MPC:"] + ["  " + line for line in self.mpc.summary_lines()]
                + ["feedforward alone:", f"  tracking error: RMS {self.feedforward.rms_error:.4g}, max {self.feedforward.max_error:.4g}",
                   f"RMS ratio MPC / feedforward: {self.ratio_to_feedforward:.4g}",
                   f"static memory: {self.memory_bytes} bytes (memory struct) + {self.work_bytes} bytes of stack work arrays"])


def build_mpc(setup: MPCSetup, out_dir: str | Path, prefix: str | None = None) -> tuple[GeneratedCode, Path]:
    """Generate and compile the MPC step of an MPC file.

    Parameters
    ----------
    setup : MPCSetup
        From :func:`gtmodel.problems.mpc_file.load_mpc_file`.
    out_dir : str or pathlib.Path
        Folder of the C files (the shared library in ``out_dir/build``).
    prefix : str, optional
        C prefix (default ``gt_<name>``).

    Returns
    -------
    generated : GeneratedCode
    library : pathlib.Path
        The compiled shared library.
    """
    generated = generate_loop_step(mpc_step(setup.controller, setup.name), out_dir, prefix=prefix or f"gt_{setup.name}")
    return generated, compile_shared(generated, Path(out_dir) / "build")


def compiled_step(generated: GeneratedCode, library: Path) -> tuple[Any, Any, int]:
    """The compiled step as ``controller(t, x) -> (status, u)`` with its own memory, and a reset.

    Parameters
    ----------
    generated : GeneratedCode
        From :func:`build_mpc`.
    library : pathlib.Path
        The compiled library.

    Returns
    -------
    controller : callable
        ``controller(t, x) -> (status, u)`` calling ``<prefix>_step`` through ctypes.
    reset : callable
        ``reset()`` calls ``<prefix>_init`` (returns its status).
    memory_bytes : int
        ``sizeof(<prefix>_memory)``.
    """
    memory, init, step = load_loop_step(generated, load_library(generated, library))
    mem = memory()
    nx, nu = generated.parameters.nx, generated.parameters.nu
    x_buf, u_buf = (ctypes.c_double * nx)(), (ctypes.c_double * nu)()
    ref = ctypes.byref(mem)

    def controller(t: float, x: np.ndarray) -> tuple[int, np.ndarray]:
        x_buf[:] = [float(v) for v in x]
        code = step(ref, t, x_buf, u_buf)
        return code, np.array(u_buf[:])

    def reset() -> int:
        return init(ref)

    reset()
    return controller, reset, ctypes.sizeof(memory)


def closed_loop_check(setup: MPCSetup, generated: GeneratedCode, library: Path, repeat: int = 1, clock: Any = time.perf_counter) -> MPCCheck:
    """Run the generated MPC and the feedforward alone against the file's plant.

    Parameters
    ----------
    setup : MPCSetup
        The MPC file's controller, plant and loop options.
    generated : GeneratedCode
        From :func:`build_mpc`.
    library : pathlib.Path
        The compiled library.
    repeat : int, optional
        Runs of the whole motion (``_init`` before each; the step times and statuses of
        all runs are kept, the tracking figures are those of the first run).
    clock : callable, optional
        Clock of the step times (see :func:`run_controller_loop`).

    Returns
    -------
    MPCCheck
    """
    controller, reset, memory_bytes = compiled_step(generated, library)
    args = (setup.plant_step, setup.plant_x0, setup.t, setup.x_ref)
    kw = dict(setup.loop, plant_p=setup.plant_p, status_names=STATUS_NAMES, clock=clock)
    first = run_controller_loop(controller, *args, **kw)
    times, statuses = [first.step_s], [first.status]
    for _ in range(max(int(repeat), 1) - 1):
        reset()
        again = run_controller_loop(controller, *args, **kw)
        times.append(again.step_s)
        statuses.append(again.status)
    first.step_s, first.status = np.concatenate(times), np.concatenate(statuses)
    c = setup.controller
    ff = run_controller_loop(lambda t, x: (0, np.clip(c.u_ref[min(int(round((t - c.t0) / c.dt)), c.length - 1)], c.u_lb, c.u_ub)),
                             *args, **kw)
    sz = generated.work_sizes["control"]
    work = 8 * (sz[0] + sz[1]) + 8 * sz[2] + 8 * sz[3]
    return MPCCheck(mpc=first, feedforward=ff, memory_bytes=memory_bytes, work_bytes=work)


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
        u_ip, _ = c.solve(summary.t[k], summary.x[k], plugin="ipopt")
        u_sqp, _ = c.solve(summary.t[k], summary.x[k], plugin="sqpmethod", iterations=iterations)
        out.append(np.max(np.abs(u_sqp - u_ip)) / (1 + np.max(np.abs(u_ip))))
    return np.asarray(out)
