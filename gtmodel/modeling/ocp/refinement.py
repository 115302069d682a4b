"""Adaptive mesh refinement of a collocation solution (h-refinement, as GPOPS-II's and Dymos' grid refinement).

:func:`solve_refined` solves on a mesh, verifies the solution
(:mod:`gtmodel.modeling.ocp.verification`) and refines where it is least accurate, until
the verification tolerance is met or a limit on elements or passes is reached. Each pass
starts from the previous solution, interpolated onto the new mesh. Two error indicators
choose the elements to split:

* the *element defect*: the largest scaled deviation of an element's own simulation
  under the optimal inputs from its collocated start (``Verification.element_errors``).
  An element above the tolerance is split into 2, 3 or 4 equal parts (by how far it is
  above: below ``10 tol``, ``100 tol``, beyond).
* a *switch*: an input that crosses most of its range within one element (a bang-bang
  switch, which no polynomial represents: the collocation smooths it, and a model that
  integrates the input, such as the double integrator, shows no defect while the
  optimum is missed by O(h)). Such an element, if longer than ``tol`` times the horizon,
  is split where the input's collocation polynomial crosses the middle of its range
  within the element, so that the switch moves onto an element boundary. Repeated, this
  locates the switch time to the width of the element that holds it.

A pass whose deviation exceeds :data:`SPURIOUS` times the tolerance and
:data:`SPURIOUS_DEVIATION` has found a spurious
minimum of the NLP (the COPS hanging chain on 20 elements: its length shrinks inside the
first element): the next pass starts from a repaired guess instead of the spurious
trajectory (the inputs of the failing elements interpolated from their neighbours', the
states simulated under those inputs). The result of the pass with the smallest
verification deviation (normally the last) is returned with ``refinement``: one dict per pass (elements, objective, status, largest
defect, switches, verification deviation).
"""

from __future__ import annotations

import copy
import dataclasses
import logging
from typing import Any

import numpy as np

from gtmodel.defaults import defaults
from gtmodel.errors import InputError
from gtmodel.modeling.ocp.collocation import CollocationTranscription
from gtmodel.modeling.ocp.collocation_nlp import collocation_coefficients
from gtmodel.modeling.ocp.optimization import Optimization
from gtmodel.modeling.ocp.result import OptimizationResult, lagrange_basis
from gtmodel.modeling.ocp.verification import SPURIOUS_DEVIATION, SWITCH_FRACTION, switch_elements, verify
from gtmodel.status import Status

__all__ = ["solve_refined", "refine_mesh", "switch_elements", "switch_times", "MAX_ELEMENTS", "MAX_PASSES", "SWITCH_FRACTION", "SPURIOUS", "SPURIOUS_DEVIATION"]

_log = logging.getLogger("gtmodel")

#: Default limit on the elements of a refined mesh.
MAX_ELEMENTS = 400
#: Default limit on refinement passes (solves).
MAX_PASSES = 10
#: A verification deviation this many times the tolerance, and above
#: :data:`SPURIOUS_DEVIATION`, marks a spurious minimum of the NLP rather than a
#: discretisation error: the next pass starts from a repaired guess.
SPURIOUS = 100.0


def switch_times(result: OptimizationResult) -> list[float]:
    """Switch times of the inputs: jumps at element boundaries and switches inside elements.

    Parameters
    ----------
    result : OptimizationResult
        A collocation result.

    Returns
    -------
    list of float
        Increasing times, s: element boundaries across which an input jumps by more than
        :data:`SWITCH_FRACTION` of its range, and the estimates of
        :func:`switch_elements` inside elements. Located to the width of the elements
        around them.
    """
    col = result.collocation
    if col is None or col.uc.shape[2] == 0:
        return []
    uc = col.uc
    breaks = col.breaks()
    span = uc.max(axis=(0, 1)) - uc.min(axis=(0, 1))
    jump = np.abs(uc[1:, 0, :] - uc[:-1, -1, :]) / np.where(span > 0, span, np.inf)
    times = [float(breaks[k + 1]) for k in np.nonzero(np.any(jump > SWITCH_FRACTION, axis=1))[0]]
    times += [float(breaks[k] + tau * (breaks[k + 1] - breaks[k])) for k, tau in switch_elements(result).items()]
    return sorted(times)


def refine_mesh(result: OptimizationResult, tolerance: float, max_elements: int) -> tuple[np.ndarray, dict[str, Any]]:
    """The next mesh: elements split where the defect exceeds the tolerance or an input switches.

    Parameters
    ----------
    result : OptimizationResult
        A verified collocation result (``result.verification`` set).
    tolerance : float
        Verification tolerance (scaled deviation); switches are located to
        ``tolerance`` times the horizon.
    max_elements : int
        Limit on the elements of the new mesh (the worst elements are split first).

    Returns
    -------
    fractions : numpy.ndarray
        Relative element lengths of the new mesh, shape ``(M,)`` (the old mesh if
        nothing is to be split or the limit is reached).
    info : dict
        ``{"split": elements split, "switches": switch times [s] found}``.

    Raises
    ------
    InputError
        If the result holds no collocation data or verification.
    """
    col, v = result.collocation, result.verification
    if col is None or v is None:
        raise InputError("refine_mesh: the result holds no collocation data or verification")
    N = col.elements
    frac = np.full(N, 1.0 / N) if col.fractions is None else np.asarray(col.fractions, dtype=float)
    errors = np.asarray(v.element_errors, dtype=float) / tolerance
    errors = np.where(np.isfinite(errors), errors, 1e6)
    plans: dict[int, tuple[float, list[float]]] = {}
    for k in np.nonzero(errors > 1.0)[0]:
        parts = 2 if errors[k] < 10 else 3 if errors[k] < 100 else 4
        plans[int(k)] = (float(errors[k]), list(np.arange(1, parts) / parts))
    switches = switch_elements(result)
    for k, tau in switches.items():
        if frac[k] > tolerance:
            # the switch explains the element's defect: one cut, at the switch
            plans[k] = (max(plans.get(k, (0.0, []))[0], 1e3), [tau])
    budget = max_elements - N
    split: list[int] = []
    for k in sorted(plans, key=lambda k: -plans[k][0]):
        cuts = plans[k][1]
        if len(cuts) > budget:
            continue
        budget -= len(cuts)
        split.append(k)
    new: list[float] = []
    for k in range(N):
        if k in split:
            edges = np.concatenate([[0.0], plans[k][1], [1.0]])
            new.extend(frac[k] * np.diff(edges))
        else:
            new.append(frac[k])
    info = {"split": sorted(split), "switches": switch_times(result)}
    return np.asarray(new), info


def _guess_from(result: OptimizationResult) -> dict[str, Any]:
    """An initial guess mapping from a result: its trajectories on its mesh and its final time."""
    out: dict[str, Any] = {"final_time": result.final_time}
    t = np.asarray(result.t, dtype=float)
    keep = np.concatenate([[True], np.diff(t) > 0])
    for group in (result.states, result.inputs, result.algebraics):
        for name, values in group.items():
            out[name] = (t[keep], np.asarray(values, dtype=float)[keep])
    return out


def _repaired_guess(result: OptimizationResult, tolerance: float) -> dict[str, Any]:
    """A guess away from a spurious minimum: the inputs of the elements whose defect exceeds
    the tolerance interpolated from the other elements', the states simulated under them."""
    col, v = result.collocation, result.verification
    bad = np.asarray(v.element_errors) > tolerance
    guess = _guess_from(result)
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


def solve_refined(
    optimization: Optimization,
    elements: int = 50,
    points: int = 3,
    scheme: str = "radau",
    max_elements: int = MAX_ELEMENTS,
    max_passes: int = MAX_PASSES,
    tolerance: float | None = None,
    initial_guess: OptimizationResult | dict[str, Any] | None = None,
    parameters: dict[str, Any] | None = None,
    **transcription: Any,
) -> OptimizationResult:
    """Solve by collocation with adaptive h-refinement of the mesh (see the module docstring).

    Parameters
    ----------
    optimization : Optimization
        The declared problem.
    elements : int, optional
        Elements of the first, uniform mesh; default 50.
    points : int, optional
        Collocation points per element; default 3.
    scheme : {"radau", "legendre"}, optional
        Collocation points; default ``"radau"``.
    max_elements : int, optional
        Limit on the elements of a refined mesh; default :data:`MAX_ELEMENTS`.
    max_passes : int, optional
        Limit on the solves; default :data:`MAX_PASSES`.
    tolerance : float, optional
        Verification tolerance, set as the problem's
        :attr:`Optimization.verification_tolerance`; default the problem's (or
        ``defaults["ocp.verification_tolerance"]``).
    initial_guess : OptimizationResult or mapping, optional
        Guess of the first pass (see :meth:`CollocationTranscription.solve`).
    parameters : mapping of str to float or array_like, optional
        Parameter values of every pass (see :meth:`CollocationTranscription.solve`).
    **transcription
        Further arguments of :class:`CollocationTranscription` (``solver_options``,
        ``nominal``, ``verbose``, ...).

    Returns
    -------
    OptimizationResult
        The result of the pass with the smallest verification deviation (normally the
        last), with ``refinement`` (one dict per pass) and ``solve_time`` the sum over the
        passes; ``check_failed`` if the limits
        stopped the refinement before the verification passed.

    Raises
    ------
    InputError
        On invalid limits, tolerance or transcription arguments.
    """
    for label, value, lo in (("max_elements", max_elements, elements), ("max_passes", max_passes, 1)):
        if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < lo:
            raise InputError(f"{label}: expected an integer >= {lo}, got {value!r}")
    if tolerance is not None:
        optimization.verification_tolerance = tolerance
    tol = optimization.verification_tolerance
    try:
        tol = float(defaults["ocp.verification_tolerance"] if tol is None else tol)
    except (TypeError, ValueError):
        raise InputError(f"tolerance: expected a positive number, got {tol!r}") from None
    if not (np.isfinite(tol) and tol > 0):
        raise InputError(f"tolerance: expected a positive number, got {tol!r}")
    mesh: np.ndarray | None = None
    guess: Any = initial_guess
    history: list[dict[str, Any]] = []
    result: OptimizationResult | None = None
    best: OptimizationResult | None = None  # the last pass that ended with a solution
    for n_pass in range(int(max_passes)):
        tr = CollocationTranscription(optimization, elements=elements, points=points, scheme=scheme, mesh=mesh, verify=True, **transcription)
        result = tr.solve(parameters=parameters, initial_guess=guess)
        v = result.verification
        entry: dict[str, Any] = {
            "pass": n_pass + 1, "elements": tr.elements, "status": str(result.status), "objective": result.objective,
            "final_time": result.final_time, "iterations": result.iterations, "solve_time": result.solve_time,
        }
        history.append(entry)
        if v is None:  # the solve failed: nothing to refine from
            break
        if best is None or v.max_scaled_deviation <= best.verification.max_scaled_deviation:
            best = result
        entry["max_scaled_deviation"] = v.max_scaled_deviation
        entry["verification_time"] = v.time_s
        entry["verification_cpu_time"] = v.cpu_s
        entry["max_element_error"] = float(np.max(v.element_errors)) if v.element_errors.size else 0.0
        new, info = refine_mesh(result, tol, max_elements)
        entry["switches_s"] = info["switches"]
        if not info["split"]:
            break
        entry["split"] = len(info["split"])
        mesh = new
        if v.max_scaled_deviation > max(SPURIOUS * tol, SPURIOUS_DEVIATION):
            # not a discretisation error but a spurious minimum of the NLP: start the next
            # pass away from it (its own trajectory would lead back)
            entry["restart"] = "inputs of the failing elements interpolated, states simulated"
            guess = _repaired_guess(result, tol)
        else:
            guess = _guess_from(result)
        _log.info("mesh refinement of %s: pass %d, %d elements, objective %.10g, splitting %d", tr.dae.name, n_pass + 1,
                  tr.elements, result.objective, len(info["split"]))
    assert result is not None
    if best is not None and best is not result:
        _log.warning("mesh refinement of %s: the last pass ended %s (deviation %s); returning the verified closest pass",
                     optimization.model.name, result.status,
                     "none" if result.verification is None else f"{result.verification.max_scaled_deviation:.3g}")
        result = best
    result.refinement = history
    result.solve_time = float(sum(e["solve_time"] for e in history))  # every pass's solve, not the returned one's alone
    if result.verification is not None:  # and every pass's verification
        result.verification.time_s = float(sum(e.get("verification_time", 0.0) for e in history))
        result.verification.cpu_s = float(sum(e.get("verification_cpu_time", 0.0) for e in history))
    if result.status == Status.OPTIMAL and len(history) == max_passes and history[-1].get("split"):
        _log.warning("mesh refinement of %s stopped at the pass limit (%d) with elements still to split", optimization.model.name, max_passes)
    return result
