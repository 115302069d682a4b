"""Verification of a collocation (or multiple-shooting) solution by simulation with a variable-step integrator.

A collocation solution satisfies the model equations at the collocation points only.
Between them, and for a spurious minimum of the NLP (a polynomial that collocates the
equations but is no solution of them: the COPS hanging chain on 20 elements ends
"optimal" 5.5 % below the true minimum), the transcribed states can be far from what the
optimal inputs do to the model. :func:`verify` checks: the inputs, interpolated as the
transcription defines them (per element the Lagrange polynomial through the ``d``
collocation points, the same polynomial :meth:`OptimizationResult.sample` evaluates),
drive the model in SUNDIALS through ``casadi.integrator`` (the integrator chosen by the
model: CVODES for an ODE and for a DAE whose algebraic variables are eliminated
symbolically, IDAS for a nonlinear algebraic loop; CVODES's BDF for a model stiff along the
solution, its Adams method otherwise: :func:`~gtmodel.modeling.ocp.verification_methods.cvodes_method`), element by element with the model written in the element's
scaled time ``t = t_k + tau h_k``, ``tau in [0, 1]`` (one integrator serves every
element). Two simulations are compared with the collocation polynomials at the
collocation points, the element ends and the midpoints between them:

* the *simulation* (global): one run over the whole horizon from the initial state; its
  largest deviation per state is the verification figure (``max_abs_deviation``,
  ``max_rel_deviation``);
* the *element defects* (local, as Dymos' and GPOPS-II's error estimates): each element
  simulated from its own collocated start state; their largest scaled deviation per
  element is what mesh refinement (:mod:`gtmodel.modeling.ocp.refinement`) refines.

A state ``i`` passes when ``max |x_sim - x_col| <= tolerance * max(1, max |x_col|)``
(the mixed absolute/relative test of integrators with ``atol = rtol = tolerance``).
The relative deviation reported is ``max |x_sim - x_col| / max |x_col|``.

A multiple-shooting result (:mod:`gtmodel.modeling.ocp.shooting`) is verified the same
way: its inputs are piecewise constant or linear (the Lagrange polynomial through their
values at the interval's sample points reproduces them exactly), and the simulation is
compared with what the transcription integrated: the node states ``X_k`` and the states
its integrator reached at the sample points of each interval (three Radau points, the
interval's end included). A shooting result whose fixed-step integrator (``rk``,
``collocation``) is too coarse for the model, or whose continuity constraints hold only
loosely, deviates from the variable-step simulation and fails.

The integrals of the problem (``integral()`` in constraints: isoperimetric constraints;
:meth:`~gtmodel.modeling.Optimization.integral`) are checked the same way: the integrand
is integrated as a quadrature of the simulation, and the value the NLP used (its
collocation quadrature) passes when ``|I_sim - I_col| <= tolerance * max(|I_col|, 0.01 A) + e``,
relative, with a floor scaled by the problem: ``A`` is the integral of the integrand's
modulus (:data:`INTEGRAL_FLOOR`, for an integral that cancels to about zero), ``e`` the
simulated quadrature's own accuracy (:data:`QUADRATURE_NOISE`, for one that vanishes). A
spurious minimum that satisfies an integral constraint only at the collocation points (the
hanging chain's length with the input oscillating between them) is caught here.

The state bounds are checked on the simulation too, between the collocation points
(:mod:`gtmodel.modeling.ocp.verification_bounds`: :func:`bound_violations`, :func:`check_bounds`): the
transcription enforces them at its points only, and a stiff motor's current limited there can overshoot
inside an element. So are the input bounds, on the inputs' polynomials (:func:`input_bound_violations`): where a
bang-bang input leaves its bound, its polynomial swings past it between the points. Where it does beyond the
tolerance, the verdict of :func:`check_result` is the simulation under the inputs clipped to their bounds
(``input_bounds``, what a saturating amplifier delivers; its ``method`` says so): its deviations, element defects,
integrals and state bounds, so that a plan verified is one a saturating actuator reproduces, and mesh refinement
refines where the clipped simulation deviates. ``verification.bounds.clipped`` says so and keeps the polynomial
inputs' deviation beside it (docs/verification.md, 2026-11-25).
"""

from __future__ import annotations

import functools
import logging
import time as _time
from dataclasses import dataclass, field
from typing import Any, Callable

import casadi as ca
import numpy as np

from gtmodel.defaults import defaults
from gtmodel.errors import InputError
from gtmodel.modeling.dae import casadi_name
from gtmodel.modeling.ocp.methods import VerificationSettings
from gtmodel.modeling.ocp.result import OptimizationResult, lagrange_basis
from gtmodel.modeling.ocp.terms import Integral
from gtmodel.modeling.ocp.verification_bounds import (BOUND_SAMPLES, REFINING, bound_violations, bounds_verdict, check_bounds,
                                                       dense_grid, element_bound_violations, input_bound_violations)
from gtmodel.modeling.ocp.verification_remedy import SPURIOUS_DEVIATION, SWITCH_FRACTION, switch_elements, verification_remedy
from gtmodel.modeling.ocp.verification_methods import (INTEGRAL_FLOOR, QUADRATURE_NOISE, STIFF_STEPS, checked_integrals,
                                                        cvodes_method, explicit_algebraics)
from gtmodel.modeling.simulation.explicit import damped_newton
from gtmodel.status import Status

__all__ = ["Verification", "verify", "check_result", "bound_violations", "element_bound_violations", "check_bounds", "input_bound_violations", "problem_integrals", "integrator_rtol", "skipped",
           "switch_elements", "INTEGRATOR_RTOL", "INTEGRATORS", "SWITCH_FRACTION", "SPURIOUS_DEVIATION", "INTEGRAL_FLOOR", "QUADRATURE_NOISE",
           "STIFF_STEPS", "BOUND_SAMPLES"]

_log = logging.getLogger("gtmodel")


def refinement_passes(func: Callable) -> Callable:
    """Decorator: the solves inside ``func`` are refinement passes, whose failed checks :func:`check_result` and
    :func:`check_bounds` log at INFO.

    A pass that fails its verification is what refinement refines (each pass and the end are logged by the
    refinement itself); as a warning, with its "likely remedy: refine = true", it told a user who had refinement
    on to turn it on, once per pass.
    """
    @functools.wraps(func)
    def wrapper(*args: Any, **kwargs: Any) -> Any:
        token = REFINING.set(True)
        try:
            return func(*args, **kwargs)
        finally:
            REFINING.reset(token)
    return wrapper

#: Tightest relative tolerance of the verifying integrator (its absolute tolerance is
#: 1e-2 times the relative one): the default is :func:`integrator_rtol`, ``1e-3`` times the
#: verification tolerance within ``[INTEGRATOR_RTOL, 1e-6]``, far below the tolerance, so
#: that the deviation measured is the transcription's. A fixed 1e-9 cost 5 to 10 times the
#: solve on a stiff DC motor (electrical time constant 1.7 ms) for the same deviation to 7 digits.
INTEGRATOR_RTOL = 1e-10


#: The verifying integrators: SUNDIALS' CVODES (ODEs) and IDAS (DAEs), both BDF with a
#: Newton iteration on the model's Jacobian (CasADi's algorithmic derivative).
INTEGRATORS = ("cvodes", "idas")



def integrator_rtol(tolerance: float) -> float:
    """The default relative tolerance of the verifying integrator for a verification ``tolerance``.

    Parameters
    ----------
    tolerance : float
        The verification tolerance (scaled deviation).

    Returns
    -------
    float
        ``1e-3 * tolerance`` clipped to ``[INTEGRATOR_RTOL, 1e-6]``.
    """
    return float(np.clip(1e-3 * float(tolerance), INTEGRATOR_RTOL, 1e-6))


@dataclass
class Verification:
    """The outcome of :func:`verify`.

    Parameters
    ----------
    tolerance : float
        The tolerance of the scaled deviation.
    passed : bool
        Every state's deviation within the tolerance (and the simulation ran).
    max_abs_deviation, max_rel_deviation : float
        Largest absolute deviation (model units) and largest relative deviation over the
        states (``inf`` if the simulation failed).
    max_scaled_deviation : float
        Largest ``|x_sim - x_col| / max(1, max |x_col|)``, compared with ``tolerance``.
    states : dict of str to dict
        Per scalar state name: ``{"max_abs_deviation", "max_rel_deviation", "at_time_s"}``.
    element_errors : numpy.ndarray
        Per element, the largest scaled deviation of its own simulation from its start
        (the local error estimate), shape ``(N,)``.
    integrator : str
        ``"cvodes"`` or ``"idas"`` and its tolerance.
    message : str
        Why it failed (or ``""``).
    time_s : float
        Wall time of the verification, s.
    t : numpy.ndarray
        Times of the comparison (collocation points, their midpoints, element ends), s,
        shape ``(K,)``, increasing.
    simulated : numpy.ndarray
        The simulated states there, shape ``(K, nx)`` (empty if the simulation failed).
    integrals : dict of str to dict
        Per checked integral (by its integrand): ``{"collocation", "simulated",
        "abs_deviation", "passed"}``.
    method : str
        What was compared (the ``method`` of :meth:`to_dict`).
    remedy : str
        For a failed verification, what is likely to fix it (``""`` otherwise).
    cpu_s : float
        CPU time of the verification (this process), s: on a loaded machine the wall time
        :attr:`time_s` mostly measures waiting.
    bounds : dict
        The largest violation of a state bound by the simulation, between the nodes
        included (:func:`bound_violations`; ``{}`` without bounded states).
    dense_t : numpy.ndarray
        Times of the dense samples of the global simulation, s, shape ``(K2,)``: every element (or
        shooting interval) at :data:`BOUND_SAMPLES` equidistant points besides :attr:`t`'s, where the
        bounded states' peaks between the nodes are looked for (:func:`bound_violations`).
    dense_simulated : numpy.ndarray
        The simulated states there, shape ``(K2, nx)`` (empty if the simulation failed).
    local_dense_simulated : numpy.ndarray
        The same samples with each element simulated from the collocation's own state at its start
        (the local simulation of :attr:`element_errors`), shape ``(K2, nx)``; empty where not
        computed (multiple shooting, a failed simulation).
    """

    tolerance: float
    passed: bool
    max_abs_deviation: float
    max_rel_deviation: float
    max_scaled_deviation: float
    states: dict[str, dict[str, float]] = field(default_factory=dict)
    element_errors: np.ndarray = field(default_factory=lambda: np.zeros(0), repr=False)
    integrator: str = ""
    message: str = ""
    time_s: float = 0.0
    t: np.ndarray = field(default_factory=lambda: np.zeros(0), repr=False)
    simulated: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)), repr=False)
    integrals: dict[str, dict[str, Any]] = field(default_factory=dict)
    method: str = "the optimal inputs (collocation polynomials) drive the model from the initial state"
    remedy: str = ""
    cpu_s: float = 0.0
    bounds: dict[str, Any] = field(default_factory=dict)
    dense_t: np.ndarray = field(default_factory=lambda: np.zeros(0), repr=False)
    dense_simulated: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)), repr=False)
    local_dense_simulated: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)), repr=False)

    @property
    def status(self) -> str:
        """``"passed"`` or ``"failed"`` (a :func:`skipped` verification: ``"skipped"``)."""
        return "passed" if self.passed else "failed"

    def to_dict(self) -> dict[str, Any]:
        """The ``verification`` block of a ``summary.json`` (JSON types only).

        Returns
        -------
        dict
            ``passed`` (the deviations within the tolerance and the state bounds kept between the
            points), ``deviations_passed`` (the deviations alone), ``tolerance``, the largest deviations,
            per-state deviations, the integrator, the largest element defect, the message.
        """
        def num(v: float) -> float | str:
            return float(v) if np.isfinite(v) else str(v)

        kept = bool(self.bounds.get("within_tolerance", True))  # a bound exceeded between the points fails it (issue 64)
        return {
            "status": "passed" if self.passed and kept else "failed",
            "passed": bool(self.passed) and kept,
            "deviations_passed": bool(self.passed),
            "tolerance": float(self.tolerance),
            "max_abs_deviation": num(self.max_abs_deviation),
            "max_rel_deviation": num(self.max_rel_deviation),
            "max_scaled_deviation": num(self.max_scaled_deviation),
            "max_element_error": num(float(np.max(self.element_errors))) if self.element_errors.size else None,
            "states": {k: {kk: num(vv) for kk, vv in v.items()} for k, v in self.states.items()},
            **({"integrals": {k: {kk: (num(vv) if not isinstance(vv, bool) else vv) for kk, vv in v.items()}
                              for k, v in self.integrals.items()}} if self.integrals else {}),
            "integrator": self.integrator,
            "time_s": float(self.time_s),
            "cpu_s": float(self.cpu_s),
            "method": self.method,
            "message": self.message,
            **({"remedy": self.remedy} if self.remedy else {}),
            **({"bounds": {k: (num(vv) if isinstance(vv, float) else vv) for k, vv in self.bounds.items()}} if self.bounds else {}),
        }


def skipped(reason: str) -> dict[str, Any]:
    """The ``verification`` block of a solution whose verification was switched off.

    Parameters
    ----------
    reason : str
        Why (e.g. ``"[verification] enabled = false"``).

    Returns
    -------
    dict
        ``{"status": "skipped", "passed": None, "message": reason}``: never ``passed``.
    """
    return {"status": "skipped", "passed": None, "message": reason}


def _check_taus(root: np.ndarray) -> np.ndarray:
    """Points of an element where the deviation is measured: the collocation points, their midpoints, the end."""
    # sorted(set(...)) rather than numpy.unique, which imports numpy.ma on first use (numpy 2.4)
    pts = np.array(sorted(set(np.concatenate([root, [1.0]]).tolist())))
    mids = 0.5 * (pts[:-1] + pts[1:])
    return np.array(sorted(set(np.concatenate([pts[1:], mids]).tolist())))


def _element_integrator(result: OptimizationResult, taus: np.ndarray, rtol: float,
                        integrands: ca.Function | None = None, plugin: str | None = None,
                        input_bounds: tuple[np.ndarray, np.ndarray] | None = None) -> tuple[ca.Function, str, ca.Function | None]:
    """``F(x0, z0, p=[model p, U (nu d), t_k, h_k]) -> xf (nx, len(taus)), qf`` on the scaled element.

    ``input_bounds``: the inputs' polynomials clipped to these (lower, upper), each shape ``(nu,)``.

    ``integrands(t, x, z, u, p)``: the integrands integrated as quadratures (``qf`` their
    integrals over the element, at each of ``taus``). The third value (None without algebraic
    variables), ``consistent(x0, z_guess, p) -> z0``: the algebraic variables at the element's
    start consistent with ``x0`` (damped Newton from the guess, the guess kept where it does not
    converge), the start when IDAS's own initialisation (a few undamped Newton steps from the
    first collocation point's values) fails, as on a diode's exponential (IDA_CONV_FAIL).
    """
    dae, col = result.dae, result.collocation
    d = col.points
    nu = dae.nu
    tau = ca.SX.sym("tau")
    tk, hk = ca.SX.sym("t_k"), ca.SX.sym("h_k")
    U = ca.SX.sym("U", nu, d)
    nodes = [float(v) for v in col.tau_root[1:]]  # Python floats: SX / numpy scalar converts through DM each time
    basis = []
    for j in range(d):
        b = ca.SX(1)
        for r in range(d):
            if r != j:
                b = b * (tau - nodes[r]) / (nodes[j] - nodes[r])
        basis.append(b)
    u_tau = ca.mtimes(U, ca.vertcat(*basis)) if nu else ca.SX(0, 1)
    if input_bounds is not None and nu:  # as a saturating amplifier: the polynomial's swing past a bound cut off
        lo, hi = (np.asarray(b, dtype=float).reshape(-1) for b in input_bounds)
        parts = [u_tau[i] for i in range(nu)]
        for i in range(nu):
            parts[i] = ca.fmax(parts[i], float(lo[i])) if np.isfinite(lo[i]) else parts[i]
            parts[i] = ca.fmin(parts[i], float(hi[i])) if np.isfinite(hi[i]) else parts[i]
        u_tau = ca.vertcat(*parts)
    t_of = tk + tau * hk
    ode = ca.substitute([dae.ode_expr, dae.alg_expr], [dae.t, dae.u], [t_of, u_tau])
    p_all = ca.vertcat(dae.p, ca.vec(U), tk, hk)
    quad = integrands is not None and integrands.numel_out() > 0
    q_expr = integrands(t_of, dae.x, dae.z, u_tau, dae.p) if quad else None
    z_expr = explicit_algebraics(dae, plugin)
    if z_expr is not None:  # z eliminated: the ODE alone, for CVODES
        z_sub = ca.substitute(z_expr, ca.vertcat(dae.t, dae.u), ca.vertcat(t_of, u_tau))
        ode[0] = ca.substitute(ode[0], dae.z, z_sub)
        q_expr = ca.substitute(q_expr, dae.z, z_sub) if quad else None
        plugin = "cvodes"
    spec: dict[str, Any] = {"x": dae.x, "p": p_all, "t": tau, "ode": hk * ode[0]}
    if quad:
        spec["quad"] = hk * q_expr
    plugin = plugin or ("idas" if dae.nz else "cvodes")
    if plugin == "idas" and dae.nz:
        spec.update(z=dae.z, alg=ode[1])
    opts: dict[str, Any] = {"abstol": rtol * 1e-2, "reltol": rtol, "max_num_steps": 100000}
    if quad:  # the integrals' error controlled too (not by default in SUNDIALS)
        opts["quad_err_con"] = True
    method = ""
    if plugin == "cvodes":
        method, cv_opts = cvodes_method(result, spec["ode"], dae.x, p_all, tau)
        opts.update(cv_opts)
    F = ca.integrator(f"{casadi_name(dae.name)}_verify", plugin, spec, 0.0, list(taus), opts)
    consistent = None
    if dae.nz and plugin == "idas":
        guess = ca.SX.sym("z_guess", dae.nz)
        z0, ok = damped_newton(ca.substitute(ode[1], tau, 0.0), dae.z, guess)
        consistent = ca.Function("consistent_start", [dae.x, guess, p_all], [ca.if_else(ok, z0, guess)])
    return F, f"{plugin}{method} (rtol {rtol:g})", consistent


def verify(result: OptimizationResult, tolerance: float | None = None, rtol: float | None = None,
           integrals: tuple[list[str], ca.Function, np.ndarray] | None = None, integrator: str | None = None,
           input_bounds: tuple[np.ndarray, np.ndarray] | None = None) -> Verification:
    """Simulate the optimal inputs with a variable-step integrator and compare with the transcribed states.

    See the module docstring for the method and the test.

    Parameters
    ----------
    result : OptimizationResult
        A collocation or multiple-shooting result (with its collocation data, the
        shooting samples for the latter, and model).
    tolerance : float, optional
        Largest allowed scaled deviation; default
        ``gtmodel.defaults.defaults["ocp.verification_tolerance"]``.
    rtol : float, optional
        Relative tolerance of the integrator (its absolute one is ``1e-2 rtol``); default
        :func:`integrator_rtol` of ``tolerance``.
    integrals : tuple, optional
        ``(names, integrands, values)``: the problem's integrals to check, their integrand
        Function ``(t, x, z, u, p) -> (m,)`` (final time substituted) and the values the
        NLP used, shape ``(m,)``.
    integrator : {"cvodes", "idas"}, optional
        The SUNDIALS integrator; default CVODES for an ODE and for a DAE whose algebraic
        variables are eliminated symbolically (every block affine in its own variables: a
        composed component's connections and laws), IDAS for the others (a nonlinear
        algebraic loop). CVODES's method follows the stiffness along the solution
        (:func:`~gtmodel.modeling.ocp.verification_methods.cvodes_method`: BDF with Newton iterations, or Adams with functional iterations).
    input_bounds : tuple of numpy.ndarray, optional
        The inputs' ``(lower, upper)`` bounds, each shape ``(nu,)`` (``-inf`` / ``inf`` where there is
        none): the inputs' polynomials are clipped to them in the simulation, as a saturating amplifier
        clips them (the transcription keeps them at the collocation points only, and a bang-bang
        voltage's polynomial swings past its bound where it switches). Default: not clipped.

    Returns
    -------
    Verification
        Never raises for a failing simulation: it is a failed verification with the
        integrator's message.

    Raises
    ------
    InputError
        If the result holds no collocation data or the tolerance is not positive.
    """
    if result.collocation is None or result.dae is None:
        raise InputError("verify: this result holds no collocation data (nothing to simulate)")
    try:
        tolerance = float(defaults["ocp.verification_tolerance"] if tolerance is None else tolerance)
    except (TypeError, ValueError):
        raise InputError(f"verify: tolerance must be a positive number, got {tolerance!r}") from None
    if not (np.isfinite(tolerance) and tolerance > 0):
        raise InputError(f"verify: tolerance must be a positive number, got {tolerance!r}")
    cpu_start = _time.process_time()
    rtol = integrator_rtol(tolerance) if rtol is None else float(rtol)
    if not (np.isfinite(rtol) and 0 < rtol < 1):
        raise InputError(f"verify: rtol must be a number in (0, 1), got {rtol!r}")
    if integrator is not None and integrator not in INTEGRATORS:
        raise InputError(f"verify: integrator must be one of {', '.join(INTEGRATORS)}, got {integrator!r}")
    if integrator == "cvodes" and result.dae.nz and explicit_algebraics(result.dae, integrator) is None:
        raise InputError(f"verify: integrator 'cvodes' takes no algebraic variables that a nonlinear algebraic loop keeps "
                         f"({result.dae.name} has {result.dae.nz}, not all eliminated symbolically); use 'idas'")
    start = _time.perf_counter()
    dae, col = result.dae, result.collocation
    N, d, nx = col.elements, col.points, dae.nx
    names = dae.x_names
    if nx == 0:
        return Verification(tolerance, True, 0.0, 0.0, 0.0, {}, np.zeros(N), "", "no states", _time.perf_counter() - start)
    shooting = col.shooting is not None
    breaks = col.breaks()
    h = np.diff(breaks)
    if shooting:  # the integrated samples themselves, at the integrator's sample points (the end included)
        taus = np.asarray(col.tau_root[1:], dtype=float)
        poly = np.asarray(col.xc[:, 1:, :], dtype=float)
    else:
        taus = _check_taus(col.tau_root)
        poly = np.einsum("tr,krx->ktx", lagrange_basis(col.tau_root, taus), col.xc)  # (N, T, nx)
    t_check = breaks[:-1, None] + taus[None, :] * h[:, None]
    grid, pick = dense_grid(taus)  # the integrator's output points: the comparison's and the bounds' dense ones
    t_dense = breaks[:-1, None] + grid[None, :] * h[:, None]
    pvec = dae.parameter_vector(result.parameters)
    scale = np.maximum(1.0, np.max(np.abs(col.xc), axis=(0, 1)))
    peak = np.max(np.abs(col.xc), axis=(0, 1))
    # element k's parameters: the model's, its inputs U (nu, d) in column-major order, t_k, h_k
    U = np.stack([col.uc[k].T.reshape(-1, order="F") for k in range(N)], axis=1) if dae.nu else np.zeros((0, N))
    P = np.vstack([np.tile(pvec[:, None], (1, N)), U, breaks[None, :-1], h[None, :]])
    z0 = col.zc[:, 0, :].T if dae.nz else np.zeros((0, N))
    message = ""
    try:
        F, how, consistent = _element_integrator(result, taus, rtol, integrals[1] if integrals else None, integrator, input_bounds)
        if F.size1_in("z0") == 0:  # the algebraic variables eliminated: an ODE
            z0 = np.zeros((0, N))
        try:
            local = F.map(N)(x0=col.xc[:, 0, :].T, z0=z0, p=P)
        except RuntimeError:
            if consistent is None:
                raise
            # IDAS's initialisation from the collocation values failed (a diode's exponential): from starts made
            # consistent by a damped Newton (not always: on a two-mass drive with tanh friction IDAS then failed instead)
            z0 = np.asarray(consistent.map(N)(col.xc[:, 0, :].T, z0, P), dtype=float)
            local = F.map(N)(x0=col.xc[:, 0, :].T, z0=z0, p=P)
        xl = np.array(local["xf"], dtype=float).reshape(nx, N, taus.size).transpose(1, 2, 0)
        element_errors = np.max(np.abs(xl - poly) / scale, axis=(1, 2))
        # the global simulation: element after element, each from where the previous ended, in
        # one call (mapaccum: the integrator restarts at every element boundary, where the
        # input polynomials jump, and no Python loop runs between the elements)
        m = len(integrals[0]) if integrals else 0
        xs, zs, ps = ca.MX.sym("x0", nx), ca.MX.sym("z0", z0.shape[0]), ca.MX.sym("p", P.shape[0])
        step = F(x0=xs, z0=zs, p=ps)
        q_end = step["qf"][:, -1] if m else ca.MX(0, 1)
        chain = ca.Function("verify_chain", [xs, zs, ps], [step["xf"][:, -1], ca.vec(step["xf"]), q_end]).mapaccum(N)
        _, xf_all, q_all = chain(col.xc[0, 0, :], z0, P)
        xg = np.array(xf_all, dtype=float).reshape(nx, taus.size, N, order="F").transpose(2, 1, 0)
        # the bounded states' peaks between the points: each element again from where the global simulation entered it,
        # sampled densely (a separate integrator: its output points change CVODES's steps, and the comparison above
        # keeps its own; on a clipped bang-bang voltage's kink the two differ by a few 1e-3 of the current)
        starts = np.vstack([col.xc[0, 0, :][None, :], xg[:-1, -1, :]]).T
        Fd = _element_integrator(result, grid, rtol, None, integrator, input_bounds)[0]
        xd = np.array(Fd.map(N)(x0=starts, z0=z0 if Fd.size1_in("z0") else np.zeros((0, N)), p=P)["xf"], dtype=float)
        xd = xd.reshape(nx, N, grid.size).transpose(1, 2, 0)
        xd[:, pick, :] = xg  # the comparison points as the global simulation has them
        # the same dense samples of each element from the collocation's own state at its start (the local simulation):
        # where the global one has drifted off the collocation, its excess over a bound is the drift's, not the
        # element's, and mesh refinement splits by this one (refinement_mesh.refine_mesh)
        xdl = np.array(Fd.map(N)(x0=col.xc[:, 0, :].T, z0=z0 if Fd.size1_in("z0") else np.zeros((0, N)), p=P)["xf"],
                       dtype=float).reshape(nx, N, grid.size).transpose(1, 2, 0)
        xdl[:, pick, :] = xl
        q_sim = np.array(q_all, dtype=float).reshape(m, N).sum(axis=1) if m else np.zeros(0)
        dev = np.abs(xg - poly)
        if not np.all(np.isfinite(dev)):
            raise RuntimeError("the simulation returned non-finite states")
    except RuntimeError as exc:
        text = str(exc).strip().splitlines()
        message = f"the verifying simulation failed: {text[-1] if text else exc!r}"
        _log.warning("verification of %s: %s", dae.name, message)
        inf = float("inf")
        return Verification(tolerance, False, inf, inf, inf, {}, np.full(N, inf), "", message, _time.perf_counter() - start)
    flat = dev.reshape(-1, nx)
    t_flat = t_check.reshape(-1)
    if shooting and N > 1:  # the nodes X_1 .. X_{N-1} against the simulation there
        flat = np.vstack([flat, np.abs(xg[:-1, -1, :] - col.xc[1:, 0, :])])
        t_flat = np.concatenate([t_flat, breaks[1:-1]])
    where = np.argmax(flat, axis=0)
    abs_dev = flat[where, np.arange(nx)]
    rel_dev = abs_dev / np.where(peak > 0, peak, 1.0)
    scaled = abs_dev / scale
    states = {
        names[i]: {"max_abs_deviation": float(abs_dev[i]), "max_rel_deviation": float(rel_dev[i]), "at_time_s": float(t_flat[where[i]])}
        for i in range(nx)
    }
    clipped = input_bounds is not None and dae.nu and bool(np.isfinite(np.concatenate([np.ravel(b) for b in input_bounds])).any())
    checked = checked_integrals(result, integrals, q_sim, tolerance, pvec, rtol) if integrals else {}
    passed = bool(np.all(scaled <= tolerance)) and all(c["passed"] for c in checked.values())
    bad_integral = next((n for n, c in checked.items() if not c["passed"]), None)
    if not passed and bool(np.all(scaled <= tolerance)):
        c = checked[bad_integral]
        what = (f"the objective's integral({bad_integral.split(': ', 1)[1]})" if bad_integral.startswith("objective: ")
                else f"integral({bad_integral})")
        message = (f"{what} is {c['collocation']:.6g} in the collocation NLP but {c['simulated']:.6g} "
                   f"in the simulation under the optimal inputs (deviation {c['abs_deviation']:.3g}, relative "
                   f"{c['rel_deviation']:.3g} > tolerance {tolerance:g})")
    elif not passed:
        worst = int(np.argmax(scaled))
        message = (
            f"state {names[worst]!r} deviates by {abs_dev[worst]:.3g} (scaled {scaled[worst]:.3g} > tolerance {tolerance:g}) "
            f"at t = {states[names[worst]]['at_time_s']:.6g} s from its simulation under the optimal inputs"
            + (" clipped to their bounds" if clipped else "")
        )
    method = (f"the optimal inputs (piecewise {col.shooting}) drive the model from the initial state; compared at "
              "the shooting nodes and the integrator's sample points" if shooting else
              "the optimal inputs (collocation polynomials, clipped to their bounds as a saturating amplifier clips them) drive "
              "the model from the initial state" if clipped else Verification.method)
    out = Verification(
        tolerance, passed, float(abs_dev.max()), float(rel_dev.max()), float(scaled.max()), states,
        element_errors, how, message, 0.0, t_check.reshape(-1), xg.reshape(-1, nx), checked,
        method, "" if passed else verification_remedy(result, float(scaled.max())),
        dense_t=t_dense.reshape(-1), dense_simulated=xd.reshape(-1, nx), local_dense_simulated=xdl.reshape(-1, nx),
    )
    out.time_s, out.cpu_s = _time.perf_counter() - start, _time.process_time() - cpu_start
    return out


def problem_integrals(optimization: Any, result: OptimizationResult, special: np.ndarray | None,
                      lagrange: float | None = None) -> tuple[list[str], ca.Function, np.ndarray] | None:
    """The problem's integrals for :func:`verify`: names, integrand Function, the NLP's values.

    Parameters
    ----------
    optimization : Optimization
        The problem (its :meth:`~gtmodel.modeling.Optimization.integral` s).
    result : OptimizationResult
        Its solution (model and final time).
    special : numpy.ndarray or None
        The values of the timed variables and integrals in the NLP, in the order of
        :meth:`~gtmodel.modeling.Optimization.special_symbols`.
    lagrange : float, optional
        The NLP's value of the objective's Lagrange term, ``sign * integral(lagrange)``
        (checked under the name ``"objective: <sign * lagrange>"``).

    Returns
    -------
    tuple or None
        ``(names, integrands, values)`` as :func:`verify` takes them; None without
        integrals or values.
    """
    dae = result.dae
    picked = [(i, v) for i, v in enumerate(optimization.special_symbols()) if isinstance(v, Integral)] if special is not None else []
    terms = [(str(v.expr), v.expr, float(special[i])) for i, v in picked]
    integrand = optimization.objective_sign * optimization.lagrange
    if lagrange is not None and not ca.SX(integrand).is_zero():
        terms.insert(0, (f"objective: {integrand}", integrand, float(lagrange)))
    if not terms or dae is None:
        return None
    exprs = ca.vertcat(*[e for _, e, _ in terms])
    if dae.nx:
        exprs = ca.substitute(exprs, dae.xdot, dae.ode_expr)
    exprs = ca.substitute(exprs, optimization.final_time, ca.SX(float(result.final_time)))
    integrands = ca.Function("integrands", [dae.t, dae.x, dae.z, dae.u, dae.p], [exprs])
    return [n for n, _, _ in terms], integrands, np.array([v for _, _, v in terms])


def verify_settings(verify: Any) -> VerificationSettings | None:
    """A transcription's ``verify`` argument checked: None for a bool, else the settings.

    Parameters
    ----------
    verify : bool or VerificationSettings
        True or False (verify with the declaration's settings, or not at all), or the
        settings to verify with (:class:`~gtmodel.modeling.ocp.methods.VerificationSettings`).

    Returns
    -------
    VerificationSettings or None
        The settings given, None for a bool.

    Raises
    ------
    InputError
        ``verify`` is neither.
    """
    if isinstance(verify, (bool, VerificationSettings)):
        return None if isinstance(verify, bool) else verify
    raise InputError(f"verify: expected True, False or a VerificationSettings, got {type(verify).__name__}")


def check_result(result: OptimizationResult, optimization: Any, special: np.ndarray | None = None,
                 what: str = "collocation solve", lagrange: float | None = None,
                 settings: VerificationSettings | None = None) -> OptimizationResult:
    """Verify a solution (:func:`verify`) and downgrade it to ``check_failed`` if it fails.

    Where an input's polynomial exceeds its bounds between the collocation points beyond the tolerance
    (:func:`input_bound_violations`), the verdict is the simulation under the inputs clipped to their bounds
    (what a saturating amplifier delivers), the polynomial inputs' deviation kept in ``verification.bounds.clipped``.

    Parameters
    ----------
    result : OptimizationResult
        A solution of a transcription of ``optimization`` (collocation or multiple shooting).
    optimization : Optimization
        The problem (its :attr:`~gtmodel.modeling.Optimization.verification_tolerance`,
        ``verification_rtol`` and ``verification_integrator`` where ``settings`` leaves
        them None; read, never written).
    special : numpy.ndarray, optional
        The NLP's values of the timed variables and integrals (see
        :func:`problem_integrals`); given, the integrals are verified too.
    what : str, optional
        The solve named in the log message.
    lagrange : float, optional
        The NLP's value of the objective's Lagrange term ``sign * integral(lagrange)``
        (its quadrature); given, it is verified as an integral too.
    settings : VerificationSettings, optional
        The transcription's verification settings (the solve's, passed down); None: the
        declaration's.

    Returns
    -------
    OptimizationResult
        ``result``, changed in place: its ``verification`` set, an ``optimal`` or
        ``acceptable`` status that fails it ``check_failed`` with the verification's
        message.
    """
    use = (settings or VerificationSettings()).over(optimization)
    integrals = problem_integrals(optimization, result, special, lagrange)
    v = verify(result, use.tolerance, rtol=use.rtol, integrals=integrals, integrator=use.integrator)
    result.verification = v
    u_bounds = optimization.bounds_vectors(result.dae, "u") if result.dae.nu else None
    inputs = input_bound_violations(result, *u_bounds, v.tolerance) if u_bounds is not None else {}
    if v.simulated.size and any(not b["within_tolerance"] for b in inputs.values()):
        # an input's polynomial past its bound between the points: the verdict is the simulation under the inputs
        # clipped to their bounds (what a saturating amplifier delivers); its deviations, element defects and state
        # bounds are what refinement refines, the polynomial inputs' deviation kept beside it
        polynomial = v
        v = verify(result, use.tolerance, rtol=use.rtol, integrals=integrals, integrator=use.integrator, input_bounds=u_bounds)
        result.verification = v
        check_bounds(result, optimization, polynomial)
    else:
        check_bounds(result, optimization)
    if v.passed and not REFINING.get():  # a state bound exceeded between the points beyond the tolerance: not optimal
        bounds_verdict(result)           # (within a refinement, the refinement decides on its returned pass)
    if not v.passed and result.status in (Status.OPTIMAL, Status.ACCEPTABLE):
        remedy = f"; likely remedy: {v.remedy}" if v.remedy else ""  # none when the verifying simulation itself failed
        _log.log(logging.DEBUG if REFINING.get() else logging.WARNING, "%s of %s: %s was %s, but %s%s", what, result.dae.name,
                 result.message, result.status, v.message, "" if REFINING.get() else remedy)  # refining: its remedy is spent
        result.message = f"{result.message}; verification failed: {v.message}{remedy}"
        result.status = Status.CHECK_FAILED
    return result
