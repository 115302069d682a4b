"""The state and input bounds checked between the transcription's points (:mod:`gtmodel.modeling.ocp.verification`).

The transcription enforces the state bounds at its points only. The simulation under the optimal
inputs (:attr:`~gtmodel.modeling.ocp.verification.Verification.simulated`, at the collocation
points, their midpoints and the element ends) shows what the model does between them: on the
drives of ``problems/drive_*.toml`` the motor current, limited at the collocation points, overshoots
its limit by 0.5 to 1 A inside the element where the voltage leaves its bound (the input's
polynomial there swings past the bound too, and the current's polynomial follows it).

* :func:`bound_violations`: the largest violation, scaled as the deviations are;
* :func:`element_bound_violations`: the largest per element, which mesh refinement
  (:mod:`gtmodel.modeling.ocp.refinement`) splits where it exceeds the tolerance;
* :func:`input_bound_violations`: per input, the largest excess of its polynomial (per element the
  Lagrange polynomial through its collocation values, as :meth:`OptimizationResult.sample` evaluates
  it) over its bounds, sampled at :data:`INPUT_SAMPLES` points of each element: the transcription keeps
  the input bounds at the collocation points only, and in the element where a bang-bang voltage leaves
  its bound the polynomial swings past it (the drives of ``problems/drive_*.toml``, 2026-11-25: by 0.3
  to 43 V, 1 to 91 % of the bound). Beyond the tolerance, the verification's verdict is the simulation under the
  inputs clipped to their bounds (what a saturating amplifier delivers;
  :func:`~gtmodel.modeling.ocp.verification.check_result`): the drives' plans verified under their polynomial
  inputs deviated by 0.002 (the belt) to 0.099 (scaled) under the clipped ones;
* :func:`input_bound_crossings`: where in an element an input's polynomial leaves and re-enters its bounds (the
  clipped input's kinks), where mesh refinement cuts an element whose clipped simulation deviates;
* :func:`check_bounds`: all added to a result's verification, a violation beyond the tolerance
  reported in its warnings.
"""

from __future__ import annotations

import contextvars
import logging
from collections.abc import Iterator
from typing import Any

import numpy as np

from gtmodel.modeling.ocp.result import OptimizationResult, lagrange_basis
from gtmodel.status import Status

__all__ = ["bound_violations", "bound_scale", "bounds_verdict", "dense_grid", "BOUND_SAMPLES", "element_bound_violations", "bound_crossings", "input_bound_crossings", "input_bound_violations", "check_bounds",
           "INPUT_SAMPLES"]

_log = logging.getLogger("gtmodel")

#: True while mesh refinement solves its passes (:func:`gtmodel.modeling.ocp.verification.refinement_passes`): a
#: pass's failed checks are logged at INFO, refinement reporting each pass and its end.
REFINING: contextvars.ContextVar[bool] = contextvars.ContextVar("gtmodel_refining", default=False)

#: Equidistant points per element (or shooting interval) at which the global simulation is sampled besides the
#: comparison points, to find the bounded states' peaks between the nodes (issue 64: a motor current's peak of
#: 8.094 A against 8 A fell between the collocation points and their midpoints, which read 8.0795 A). A parabolic
#: peak sampled at h / N is missed by at most 1/(8 N^2) of its curvature times h squared; a sharp one, a current
#: turning within microseconds where its voltage polynomial is clipped, by up to its slope times h / N: the seed-2
#: belt drive2_04 read 19.890 A of 19.7 (0.96 %, within the 1 % tolerance) at 24, where SciPy's re-simulation of the
#: hand-written ODE finds 19.907 A (1.05 %) 6 us later, the current rising at 2,800 A/s (measured 2026-11-27). At 48
#: its refinement goes on and its answer's peak agrees with SciPy's to 1e-4 A (0.44 %); at 96 as well, but the ball
#: screw drive0_33 split hundreds of elements a pass along its current's bound arc (163, 312, 607) and ended
#: check_failed at the CPU budget, where at 48 it verifies (288.7 CPU-s beside a reference solve).
BOUND_SAMPLES = 48


def dense_grid(taus: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The verifying integrator's dense output points of an element: ``taus`` and :data:`BOUND_SAMPLES` more.

    Parameters
    ----------
    taus : numpy.ndarray
        The comparison points in (0, 1], increasing, shape ``(T,)``.

    Returns
    -------
    tuple of numpy.ndarray
        ``(grid, pick)``: ``taus`` merged with :data:`BOUND_SAMPLES` equidistant points of (0, 1], increasing,
        and the indices with ``grid[pick] == taus``.
    """
    extra = np.linspace(0.0, 1.0, BOUND_SAMPLES + 1)[1:]
    extra = extra[np.min(np.abs(extra[:, None] - np.asarray(taus)[None, :]), axis=1) > 1e-9]
    grid = np.sort(np.concatenate([np.asarray(taus, dtype=float), extra]))
    pick = np.searchsorted(grid, np.asarray(taus, dtype=float))
    return grid, pick


#: Points per element (its ends included) at which :func:`input_bound_violations` samples the inputs' polynomials.
INPUT_SAMPLES = 50


def _samples(v: Any) -> tuple[np.ndarray, np.ndarray]:
    """``(t, x)`` of the verifying simulation where bounds are judged: its dense samples, else its comparison points."""
    dense = getattr(v, "dense_simulated", None)
    if dense is not None and np.size(dense):
        return np.asarray(v.dense_t, dtype=float), np.asarray(dense, dtype=float)
    return np.asarray(v.t, dtype=float), np.asarray(v.simulated, dtype=float)


def bound_scale(lower: np.ndarray, upper: np.ndarray, values: np.ndarray, typical: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(excess, relative)``: how far ``values`` are beyond their bounds, in model units and relative to the bound.

    A value beyond its bound ``b`` by ``e`` has the relative excess ``e / |b|`` (``0.01``: 1 % over a current limit
    of 8 A is 0.08 A); a bound at zero is measured against the variable's typical magnitude instead
    (``max(1, max |x|)``), and no bound against less than ``1e-6`` of it.

    Parameters
    ----------
    lower, upper : numpy.ndarray
        The bounds, shape ``(n,)`` (``-inf`` / ``inf`` where there is none).
    values : numpy.ndarray
        Samples, shape ``(K, n)``.
    typical : numpy.ndarray
        Each variable's typical magnitude, shape ``(n,)`` (the transcription's ``max(1, max |x|)``).

    Returns
    -------
    tuple of numpy.ndarray
        ``excess`` and ``relative``, each shape ``(K, n)``, zero where the bounds are kept.
    """
    lower, upper = np.asarray(lower, dtype=float), np.asarray(upper, dtype=float)
    values = np.asarray(values, dtype=float)
    over, under = values - upper[None, :], lower[None, :] - values
    excess = np.maximum(np.maximum(over, under), 0.0)
    bound = np.where(over >= under, np.broadcast_to(upper, values.shape), np.broadcast_to(lower, values.shape))
    typical = np.broadcast_to(np.asarray(typical, dtype=float), values.shape)
    with np.errstate(invalid="ignore"):
        ref = np.where(np.isfinite(bound) & (np.abs(bound) > 0), np.abs(bound), typical)
    ref = np.maximum(ref, 1e-6 * typical)
    return excess, np.where(excess > 0, excess / ref, 0.0)


def _scaled_excess(result: OptimizationResult, lower: np.ndarray, upper: np.ndarray,
                   local: bool = False) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray] | None:
    """``(t, sim, excess, relative)``: the dense simulation's violation of the bounds, model units and relative to the bound
    (``local``: the elements' local simulations where the verification holds them)."""
    v, col = result.verification, result.collocation
    lower, upper = np.asarray(lower, dtype=float), np.asarray(upper, dtype=float)
    if v is None or col is None or v.simulated.size == 0 or not (np.isfinite(lower).any() or np.isfinite(upper).any()):
        return None
    t, sim = _samples(v)
    held = getattr(v, "local_dense_simulated", None)
    if local and held is not None and np.shape(held) == np.shape(sim):
        sim = np.asarray(held, dtype=float)
    typical = np.maximum(1.0, np.max(np.abs(col.xc), axis=(0, 1)))
    excess, relative = bound_scale(lower, upper, sim, typical)
    return t, sim, excess, relative


def bound_violations(result: OptimizationResult, lower: np.ndarray, upper: np.ndarray) -> dict[str, Any]:
    """The largest violation of the state bounds by the verifying simulation, between the nodes included.

    The simulation is sampled densely (:attr:`~gtmodel.modeling.ocp.verification.Verification.dense_simulated`:
    :data:`~gtmodel.modeling.ocp.verification.BOUND_SAMPLES` points per element besides the comparison points), and
    the violation is relative to the bound exceeded (:func:`bound_scale`: ``0.01`` is 1 % of the bound), compared
    with the verification's tolerance.

    Parameters
    ----------
    result : OptimizationResult
        A verified result (``result.verification`` with its simulation).
    lower, upper : numpy.ndarray
        The states' bounds, shape ``(nx,)`` (``-inf`` / ``inf`` where there is none), as
        :meth:`~gtmodel.modeling.Optimization.bounds_vectors` gives them.

    Returns
    -------
    dict
        ``{}`` without bounded states or simulation; else ``{"max_violation"`` (model units),
        ``"max_scaled_violation"`` (relative to the bound), ``"variable"``, ``"at_time_s"``, ``"value"``, ``"bound"``,
        ``"within_tolerance"`` (within the verification's tolerance), ``"samples_per_element"}``.
    """
    out = _scaled_excess(result, lower, upper)
    if out is None:
        return {}
    t, sim, excess, scaled = out
    v = result.verification
    k, i = np.unravel_index(int(np.argmax(scaled)), scaled.shape)
    value = float(sim[k, i])
    return {"max_violation": float(excess[k, i]), "max_scaled_violation": float(scaled[k, i]),
            "variable": result.dae.x_names[i], "at_time_s": float(t[k]), "value": value,
            "bound": float(upper[i] if value > upper[i] else lower[i]), "within_tolerance": bool(scaled[k, i] <= v.tolerance),
            "samples_per_element": int(sim.shape[0] // max(result.collocation.elements, 1))}


def element_bound_violations(result: OptimizationResult, lower: np.ndarray, upper: np.ndarray,
                             local: bool | None = False) -> np.ndarray:
    """Per element, the largest scaled violation of the state bounds by the verifying simulation.

    Parameters
    ----------
    result : OptimizationResult
        A verified result (``result.verification`` with its simulation, sampled element by
        element, the same number of samples in each).
    lower, upper : numpy.ndarray
        The states' bounds, shape ``(nx,)`` (as for :func:`bound_violations`).
    local : bool or None, optional
        Judge each element by its local simulation, from the collocation's own state at its
        start (:attr:`~gtmodel.modeling.ocp.verification.Verification.local_dense_simulated`),
        not by the global one, which enters it wherever it has drifted to; the global one where
        the verification holds no local samples. None: the local one while the verification's
        deviation exceeds its tolerance (the global one has drifted: mesh refinement's choice).
        Default False.

    Returns
    -------
    numpy.ndarray
        Shape ``(N,)`` over the elements (or shooting intervals), scaled as in
        :func:`bound_violations`; zeros without bounded states, empty without a simulation.
    """
    col, v = result.collocation, result.verification
    if local is None:
        local = v is not None and not v.max_scaled_deviation <= v.tolerance
    out = _scaled_excess(result, lower, upper, local)
    if col is None:
        return np.zeros(0)
    if out is None:
        v = result.verification
        return np.zeros(col.elements) if v is not None and v.simulated.size else np.zeros(0)
    scaled = out[3]
    return scaled.reshape(col.elements, -1).max(axis=1)


#: Where :func:`bound_crossings` and :func:`input_bound_crossings` evaluate an element's polynomials (its ends included).
CROSSING_TAUS = np.linspace(0.0, 1.0, 401)


def _beyond(coefficients: np.ndarray, tau_root: np.ndarray, lower: np.ndarray, upper: np.ndarray, elements: list[int],
            level: float) -> Iterator[tuple[int, np.ndarray]]:
    """Per element of ``elements``, ``(k, over)``: ``over`` (401, n) where its polynomials exceed the bounds by ``level``.

    The polynomials through ``coefficients[k]`` (``(K, d, n)``, values at ``tau_root``) at :data:`CROSSING_TAUS`, the
    excess scaled by ``max(1, max |coefficients|)`` per variable.
    """
    lower, upper = np.asarray(lower, dtype=float), np.asarray(upper, dtype=float)
    basis = lagrange_basis(tau_root, CROSSING_TAUS)
    scale = np.maximum(1.0, np.max(np.abs(coefficients), axis=(0, 1)))
    for k in elements:
        v = basis @ coefficients[k]  # (401, n)
        yield k, np.maximum(np.maximum(v - upper, lower - v), 0.0) / scale > level


def bound_crossings(result: OptimizationResult, lower: np.ndarray, upper: np.ndarray, elements: list[int],
                    level: float) -> dict[int, float]:
    """Where, in each of ``elements``, the collocated states first exceed their bounds by ``level`` (scaled).

    The collocation polynomials are evaluated on 401 points of each element; the first point where a
    state's scaled violation exceeds ``level`` estimates where the state reaches its bound (a motor
    current's junction with its limited arc, the kink that a polynomial overshoots).

    Parameters
    ----------
    result : OptimizationResult
        A collocation result.
    lower, upper : numpy.ndarray
        The states' bounds, shape ``(nx,)``.
    elements : list of int
        The elements looked at.
    level : float
        Scaled violation (as :func:`bound_violations` scales it) counted as a crossing.

    Returns
    -------
    dict of int to float
        Element -> ``tau`` in (0, 1), the first crossing, for the elements whose polynomials cross inside
        (within the bounds at the element's start).
    """
    col = result.collocation
    if col is None or not elements:
        return {}
    out: dict[int, float] = {}
    for k, over in _beyond(col.xc, col.tau_root, lower, upper, elements, level):
        over = over.any(axis=1)
        if not over[0] and over[1:-1].any():
            out[int(k)] = float(CROSSING_TAUS[1 + int(np.argmax(over[1:-1]))])
    return out


def input_bound_crossings(result: OptimizationResult, lower: np.ndarray, upper: np.ndarray, elements: list[int],
                          level: float) -> dict[int, list[float]]:
    """Where, in each of ``elements``, the inputs' polynomials leave and re-enter their bounds by ``level`` (scaled).

    The inputs' Lagrange polynomials (as :func:`input_bound_violations` evaluates them) on 401 points of each
    element; the first excess beyond ``level`` (scaled as there, by ``max(1, max |u_col|)``): where it starts
    inside the element and where it ends (a bang-bang voltage's polynomial that swings past its bound from the
    element's start up to its junction with the bound, the kink that the clipped input has there).

    Parameters
    ----------
    result : OptimizationResult
        A collocation result.
    lower, upper : numpy.ndarray
        The inputs' bounds, shape ``(nu,)``.
    elements : list of int
        The elements looked at.
    level : float
        Scaled excess counted as outside the bound.

    Returns
    -------
    dict of int to list of float
        Element -> the ``tau`` in (0, 1) where the first excess starts (if inside) and ends (if inside), over the
        inputs, sorted; elements whose polynomials stay within ``level`` are left out.
    """
    col = result.collocation
    if col is None or not elements or col.uc.size == 0:
        return {}
    out: dict[int, list[float]] = {}
    for k, over in _beyond(col.uc, col.tau_root[1:], lower, upper, elements, level):
        cuts: set[float] = set()
        for i in np.nonzero(over.any(axis=0))[0]:
            first = int(np.argmax(over[:, i]))
            end = first + int(np.argmin(over[first:, i])) if not over[first:, i].all() else CROSSING_TAUS.size
            cuts.update(float(CROSSING_TAUS[j]) for j in (first, end) if 0 < j < CROSSING_TAUS.size - 1)
        if cuts:
            out[int(k)] = sorted(cuts)
    return out


def input_bound_violations(result: OptimizationResult, lower: np.ndarray, upper: np.ndarray, tolerance: float,
                           samples: int = INPUT_SAMPLES) -> dict[str, dict[str, Any]]:
    """Per bounded input, the largest excess of its polynomial over its bounds, between the collocation points.

    Per element the input is the Lagrange polynomial through its values at the ``d`` collocation
    points (:meth:`OptimizationResult.sample`), evaluated at ``samples`` equidistant points of the
    element, its ends included. The excess of input ``i`` is scaled as the state check scales its
    violations, by ``max(1, max |u_col,i|)`` (for an input that reaches its bound ``b``: the fraction
    of ``|b|``).

    Parameters
    ----------
    result : OptimizationResult
        A collocation (or multiple-shooting) result.
    lower, upper : numpy.ndarray
        The inputs' bounds, shape ``(nu,)`` (``-inf`` / ``inf`` where there is none), as
        :meth:`~gtmodel.modeling.Optimization.bounds_vectors` gives them (``kind="u"``).
    tolerance : float
        The verification tolerance the scaled excess is compared with.
    samples : int, optional
        Points per element, at least 2.

    Returns
    -------
    dict of str to dict
        Per input with a finite bound (by name): ``{"max_violation"`` (model units, 0 when kept),
        ``"max_scaled_violation"``, ``"at_time_s"`` (s), ``"value"``, ``"bound"``, ``"within_tolerance"}``;
        ``{}`` without collocation data or bounded inputs.

    Raises
    ------
    ValueError
        If ``samples`` is less than 2.
    """
    if samples < 2:
        raise ValueError(f"input_bound_violations: samples must be at least 2, got {samples!r}")
    col, dae = result.collocation, result.dae
    if col is None or dae is None or not dae.nu or col.uc.size == 0:
        return {}
    lower, upper = np.asarray(lower, dtype=float), np.asarray(upper, dtype=float)
    taus = np.linspace(0.0, 1.0, int(samples))
    u = np.einsum("tr,kri->kti", lagrange_basis(col.tau_root[1:], taus), col.uc)  # (N, samples, nu)
    breaks = col.breaks()
    t = breaks[:-1, None] + taus[None, :] * np.diff(breaks)[:, None]
    u = u.reshape(-1, dae.nu)
    margin = np.maximum(u - upper, lower - u)  # > 0 beyond a bound; kept, its largest is the closest approach
    scale = np.maximum(1.0, np.max(np.abs(col.uc), axis=(0, 1)))
    out: dict[str, dict[str, Any]] = {}
    for i in np.nonzero(np.isfinite(lower) | np.isfinite(upper))[0]:
        j = int(np.argmax(margin[:, i]))
        value, excess = float(u[j, i]), max(float(margin[j, i]), 0.0)
        out[dae.u_names[i]] = {"max_violation": excess, "max_scaled_violation": excess / scale[i], "at_time_s": float(t.reshape(-1)[j]),
                               "value": value, "bound": float(upper[i] if upper[i] - value <= value - lower[i] else lower[i]),
                               "within_tolerance": bool(excess / scale[i] <= tolerance)}
    return out


def check_bounds(result: OptimizationResult, optimization: Any, polynomial: Any = None) -> None:
    """Add the between-node bound checks to ``result.verification``, warning where a bound is exceeded.

    The states' (:func:`bound_violations`, on the verifying simulation) at the top level of
    ``verification.bounds``, the inputs' (:func:`input_bound_violations`, their polynomials) under its
    ``"inputs"``. Given ``polynomial``, ``result.verification`` is the verdict under the inputs clipped to
    their bounds (what a saturating amplifier delivers; :func:`~gtmodel.modeling.ocp.verification.check_result`)
    and ``"clipped"`` says so (``{"verdict": True, "method", "max_scaled_deviation", "variable", "at_time_s",
    "within_tolerance", "polynomial_inputs"}``: the clipped simulation's largest deviation from the plan, scaled
    as the verification's, and the polynomial inputs' ``{"max_scaled_deviation", "passed"}``); an input's
    excess is then reported, not warned: the verdict is the clipped inputs'.

    Parameters
    ----------
    result : OptimizationResult
        A verified result; changed in place (``verification.bounds``). A violation beyond the
        tolerance is logged and added to ``result.warnings`` (the summary's ``warnings``).
    optimization : Optimization
        The problem (its state and input bounds).
    polynomial : Verification, optional
        The verification of ``result`` under its inputs' polynomials, when ``result.verification`` is the
        one under the inputs clipped to their bounds (:func:`~gtmodel.modeling.ocp.verification.verify`
        with ``input_bounds``).
    """
    v = result.verification
    if v is None or result.dae is None:
        return
    texts = []
    under = "the inputs clipped to their bounds" if polynomial is not None else "the optimal inputs"
    if result.dae.nx:
        v.bounds = bound_violations(result, *optimization.bounds_vectors(result.dae, "x"))
        if v.bounds and not v.bounds["within_tolerance"]:
            b = v.bounds
            texts.append(f"state {b['variable']!r} reaches {b['value']:.6g} against its bound {b['bound']:.6g} at t = {b['at_time_s']:.6g} s "
                         f"in the simulation under {under} (between the transcription's points; scaled violation "
                         f"{b['max_scaled_violation']:.3g} > tolerance {v.tolerance:g}): the plan keeps the bound at its points only")
    inputs = input_bound_violations(result, *optimization.bounds_vectors(result.dae, "u"), v.tolerance) if result.dae.nu else {}
    if inputs:
        v.bounds = {**v.bounds, "inputs": inputs}
    if polynomial is not None and v.simulated.size:
        scale = np.maximum(1.0, np.max(np.abs(result.collocation.xc), axis=(0, 1)))  # as the verification scales
        worst = max(zip(result.dae.x_names, scale), key=lambda ns: v.states[ns[0]]["max_abs_deviation"] / ns[1])[0]
        scaled = float(v.max_scaled_deviation)
        v.bounds = {**v.bounds, "clipped": {
            "verdict": True, "method": v.method, "max_scaled_deviation": scaled, "variable": worst,
            "at_time_s": v.states[worst]["at_time_s"], "within_tolerance": bool(scaled <= v.tolerance),
            "polynomial_inputs": {"max_scaled_deviation": float(polynomial.max_scaled_deviation), "passed": bool(polynomial.passed)}}}
    for name, b in inputs.items():
        if b["within_tolerance"]:
            continue
        if polynomial is not None:  # the verdict clipped it: reported (verification.bounds.inputs), not a warning
            _log.debug("verification of %s: the polynomial of input %r reaches %.6g against its bound %.6g at t = %.6g s; "
                      "verified under it clipped to its bounds", result.dae.name, name, b["value"], b["bound"], b["at_time_s"])
            continue
        texts.append(f"the polynomial of input {name!r} reaches {b['value']:.6g} against its bound {b['bound']:.6g} at t = {b['at_time_s']:.6g} s "
                     f"(between the collocation points, which keep it; scaled excess {b['max_scaled_violation']:.3g} > tolerance "
                     f"{v.tolerance:g}): the verifying simulation drove the model with it, a saturating amplifier clips it")
    for text in texts:
        _log.log(logging.DEBUG if REFINING.get() else logging.WARNING, "verification of %s: %s", result.dae.name, text)
        if text not in result.warnings:  # the summary's warnings and the printed result say it, not only the log
            result.warnings.append(text)


def bounds_verdict(result: OptimizationResult) -> OptimizationResult:
    """A result whose verifying simulation exceeds a state bound beyond the tolerance is not ``optimal``.

    The transcription keeps the bounds at its points; between them (the dense samples of the verifying
    simulation, :func:`bound_violations`) a stiff state can overshoot. An ``optimal`` or ``acceptable`` result
    whose ``verification.bounds`` is not ``within_tolerance`` becomes ``check_failed``, its message naming the
    state, the bound, the time and the excess (absolute and relative to the bound); ``verification.bounds["remedy"]``
    (mesh refinement's, where it stopped) is added to the message. Issue 64: a two-mass drive's current reached
    8.094 A against 8 A between the nodes and the run ended ``optimal``.

    Parameters
    ----------
    result : OptimizationResult
        A verified result; changed in place (``status``, ``message``).

    Returns
    -------
    OptimizationResult
        ``result``.
    """
    v = result.verification
    b = getattr(v, "bounds", None) or {}
    if result.status not in (Status.OPTIMAL, Status.ACCEPTABLE) or not b or b.get("within_tolerance", True):
        return result
    text = (f"state {b['variable']!r} exceeds its bound {b['bound']:.6g} between the transcription's points: "
            f"{b['value']:.6g} at t = {b['at_time_s']:.6g} s in the verifying simulation ({b['max_violation']:.3g} over, "
            f"{100 * b['max_scaled_violation']:.3g} % of the bound > tolerance {100 * v.tolerance:g} %)")
    remedy = b.get("remedy")
    result.message = f"{result.message}; {text}" + (f"; {remedy}" if remedy else "")
    result.status = Status.CHECK_FAILED
    return result
