"""How a mesh refinement's pass is started: from the last pass, from a repaired guess, or again cold after a failure.

:func:`guess_from` is the start of a pass from the pass it refines (its trajectories interpolated onto the new mesh);
:func:`repaired_guess` the start away from a spurious minimum; :func:`solved_cold` solves a pass again with IPOPT's own
barrier and bound push when its warm start (:data:`~gtmodel.modeling.ocp.coarse_start.WARM_MU`,
:data:`~gtmodel.modeling.ocp.coarse_start.WARM_PUSH`) ended without a solution. The loop that uses them is
:func:`gtmodel.modeling.ocp.refinement.solve_refined`.
"""

from __future__ import annotations

import copy
import dataclasses
import logging
from typing import Any, Mapping

import numpy as np

from gtmodel.modeling.ocp.coarse_start import _IPOPT_DEFAULTS
from gtmodel.modeling.ocp.result import OptimizationResult
from gtmodel.modeling.ocp.verification import verify

__all__ = ["guess_from", "repaired_guess", "solved_cold"]

_log = logging.getLogger("gtmodel")


def guess_from(result: OptimizationResult) -> dict[str, Any]:
    """An initial guess mapping from a result: its trajectories on its mesh and its final time.

    Parameters
    ----------
    result : OptimizationResult
        A collocation result.

    Returns
    -------
    dict
        ``name -> (t, values)`` for its states, inputs and algebraic variables (``t`` strictly
        increasing, s), and ``"final_time"`` (s).
    """
    out: dict[str, Any] = {"final_time": result.final_time}
    t = np.asarray(result.t, dtype=float)
    keep = np.concatenate([[True], np.diff(t) > 0])
    for group in (result.states, result.inputs, result.algebraics):
        for name, values in group.items():
            out[name] = (t[keep], np.asarray(values, dtype=float)[keep])
    return out


def repaired_guess(result: OptimizationResult, tolerance: float) -> dict[str, Any]:
    """A guess away from a spurious minimum: the inputs of the elements whose defect exceeds
    the tolerance interpolated from the other elements', the states simulated under them.

    Parameters
    ----------
    result : OptimizationResult
        A verified collocation result (its ``verification.element_errors``).
    tolerance : float
        The verification tolerance (scaled deviation) an element's defect is compared with.

    Returns
    -------
    dict
        As :func:`guess_from`; unrepaired (:func:`guess_from`) when no element, or every element,
        exceeds the tolerance, the model has no input or the simulation fails.
    """
    col, v = result.collocation, result.verification
    bad = np.asarray(v.element_errors) > tolerance
    guess = guess_from(result)
    if col is None or not bad.any() or bad.all() or col.uc.shape[2] == 0:
        return guess
    breaks = col.breaks()
    tc = breaks[:-1, None] + col.tau_root[None, 1:] * np.diff(breaks)[:, None]  # (N, d)
    uc = col.uc.copy()
    for i in range(uc.shape[2]):
        uc[bad, :, i] = np.interp(tc[bad], tc[~bad].ravel(), uc[~bad, :, i].ravel())
    repaired = copy.copy(result)
    repaired.collocation = dataclasses.replace(col, uc=uc)
    sim = verify(repaired, tolerance)
    if sim.simulated.size == 0:
        return guess
    t_sim = np.concatenate([[col.t0], sim.t])
    x_sim = np.vstack([col.xc[0, 0][None, :], sim.simulated])
    for name, sl in result.dae.x_vars.items():
        guess[name] = (t_sim, x_sim[:, sl])
    for name, sl in result.dae.u_vars.items():
        guess[name] = (tc.ravel(), uc.reshape(-1, uc.shape[2])[:, sl])
    return guess


def solved_cold(transcription: Any, failed: OptimizationResult, guess: Any, parameters: Mapping[str, Any] | None,
                cpu_left: float) -> OptimizationResult:
    """A warm pass that IPOPT ended without a solution, solved again from the same start with IPOPT's own barrier.

    A warm pass starts IPOPT's barrier at :data:`~gtmodel.modeling.ocp.coarse_start.WARM_MU` with its start
    kept on its bounds; where the new mesh's interpolated start is far from feasible (a split element of a
    stiff drive), its restoration phase can fail from there (``drive1_18``'s pass on its verified mesh with
    every element halved: Restoration_Failed after 34 iterations). Solved again with IPOPT's defaults
    (barrier 0.1, bound push 1e-2), held to the CPU time left.

    Parameters
    ----------
    transcription : CollocationTranscription
        The failed pass's transcription (its solver rebuilt with IPOPT's defaults for the options above).
    failed : OptimizationResult
        The warm pass's result (no verification: no solution).
    guess : OptimizationResult or mapping
        The start it was solved from.
    parameters : mapping or None
        Its parameter values (:meth:`CollocationTranscription.solve`).
    cpu_left : float
        CPU seconds left of the refinement's budget: IPOPT's ``max_cpu_time``; none left, no retry.

    Returns
    -------
    OptimizationResult
        The cold solve when it ended with a solution (verified or not), else ``failed``; either with
        ``stats["cold_retry"]``: the warm pass's status, message and iterations and the cold solve's status.
    """
    if not cpu_left > 1.0:
        return failed
    transcription.set_solver_options({**_IPOPT_DEFAULTS, "max_cpu_time": float(cpu_left)})
    again = transcription.solve(parameters=parameters, initial_guess=guess)
    record = {"warm_status": str(failed.status), "warm_message": str(failed.message)[:200],
              "warm_iterations": failed.iterations, "status": str(again.status), "iterations": again.iterations}
    _log.info("mesh refinement: a warm pass ended %s; solved again cold: %s", failed.status, again.status)
    out = again if again.verification is not None else failed
    out.stats = {**(out.stats or {}), "cold_retry": record}
    return out
