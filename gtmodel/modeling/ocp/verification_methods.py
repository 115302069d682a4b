"""How the verification simulates and what it holds integrals to (:mod:`gtmodel.modeling.ocp.verification`).

* :func:`explicit_algebraics`: a DAE whose algebraic variables are eliminated symbolically
  (each block affine in its own variables, as the connections and laws of composed components
  are) is integrated as an ODE by CVODES; IDAS serves a nonlinear algebraic loop. The DC motor
  of ``dc_motor_min_energy`` (3 states, 29 algebraic variables): IDAS 0.18 CPU-s, CVODES 0.03 s;
  a flexible joint (5 states, 25 algebraic variables, 60 elements): 4.06 s against 0.024 s,
  the same deviation to five digits.
* :func:`cvodes_method`: CVODES's BDF (Newton iterations on the model's Jacobian) where the
  model is stiff along the solution, its Adams method (functional iterations) otherwise.
* :func:`checked_integrals`: an integral passes relative to its value, with a floor scaled by
  the problem and the simulation's own resolution.
"""

from __future__ import annotations

from typing import Any

import casadi as ca
import numpy as np

from gtmodel.modeling.ocp.collocation_nlp import collocation_coefficients
from gtmodel.modeling.ocp.result import OptimizationResult
from gtmodel.modeling.simulation.explicit import eliminated_algebraics

__all__ = ["explicit_algebraics", "cvodes_method", "checked_integrals", "integral_magnitudes", "INTEGRAL_FLOOR",
           "QUADRATURE_NOISE", "STIFF_STEPS"]


#: Floor of the integrals' relative test, as a fraction of the integral of the integrand's
#: modulus (:func:`checked_integrals`): an integral that cancels to about zero is held to
#: ``tolerance * INTEGRAL_FLOOR * integral |f| dt``, not to its own (vanishing) value.
INTEGRAL_FLOOR = 1e-2

#: The simulated integrals' own accuracy, in units of the quadrature's absolute tolerance per
#: second of the horizon (:func:`checked_integrals`): below it the simulation cannot tell two values apart.
QUADRATURE_NOISE = 10.0

#: Stiffness threshold of the verifying CVODES (:func:`cvodes_method`): BDF with Newton iterations
#: where an element holds more than this many of the model's fastest time constants
#: (``h_k max |lambda(df/dx)|`` along the solution), Adams with functional iterations otherwise.
STIFF_STEPS = 20.0


def explicit_algebraics(dae: Any, plugin: str | None) -> ca.SX | None:
    """The algebraic variables eliminated symbolically (:func:`~gtmodel.modeling.simulation.explicit.eliminated_algebraics`),
    unless IDAS is asked for, there are none, or a block needs Newton's method (then IDAS integrates the DAE).

    A composed component's algebraic variables (connections, Kirchhoff's and Newton's laws, a
    gear) are affine in themselves: the 3-state DC motor of ``dc_motor_min_energy`` has 29, and
    IDAS on the 32-variable DAE cost 0.18 CPU-s where CVODES on the 3-state ODE costs a fraction.

    Parameters
    ----------
    dae : FlatDAE
        The model.
    plugin : {"cvodes", "idas"} or None
        The integrator asked for (None: chosen here).

    Returns
    -------
    casadi.SX or None
        ``z`` as an expression of ``(t, x, u, p)``, shape ``(nz, 1)``; None: IDAS on the DAE.
    """
    if plugin == "idas" or not dae.nz:
        return None
    return eliminated_algebraics(dae)


def cvodes_method(result: OptimizationResult, rhs: ca.SX, x: ca.SX, p_all: ca.SX, tau: ca.SX) -> tuple[str, dict[str, Any]]:
    """CVODES' method by the model's stiffness along the solution: BDF with Newton iterations, or Adams with
    functional iterations; ``(label, options)``.

    ``rhs`` is the ODE in the element's scaled time (``dx/dtau = h_k f``), so the eigenvalues of
    its Jacobian ``dF/dx`` at a collocation point are ``h_k`` times the model's there: their
    largest modulus ``rho`` is how many of the model's fastest time constants fit in an element.
    An explicit (Adams) method is stable for steps up to about ``1 / rho`` of the element, so
    where ``rho > STIFF_STEPS`` somewhere along the solution the model is stiff there (a DC
    motor's 1.7 ms electrical time constant in 5 ms elements: rho = 3; in a 1 s element
    of the coarse start: 600), and BDF with Newton iterations on the Jacobian (CasADi's
    derivative) takes steps of the trajectory's scale instead; otherwise Adams, with no
    Jacobian and no linear solve. The eigenvalues are those of the collocated solution
    (``x`` at every collocation point, the element's inputs there): a linearisation along it.

    Parameters
    ----------
    result : OptimizationResult
        The solution (its collocation data, model and parameters).
    rhs : casadi.SX
        ``dx/dtau`` on the scaled element, shape ``(nx, 1)``.
    x : casadi.SX
        The states, shape ``(nx, 1)``.
    p_all : casadi.SX
        The integrator's parameters: the model's, the element's inputs ``U`` (column-major),
        ``t_k``, ``h_k``.
    tau : casadi.SX
        The scaled time in ``[0, 1]``.

    Returns
    -------
    tuple of (str, dict)
        A label for the summary (method, largest ``h |lambda|``) and CVODES's options.
    """
    col = result.collocation
    N, d = col.elements, col.points
    J = ca.Function("stiffness_jacobian", [x, p_all, tau], [ca.jacobian(rhs, x)])
    breaks = col.breaks()
    pvec = result.dae.parameter_vector(result.parameters)
    nu = result.dae.nu
    U = np.stack([col.uc[k].T.reshape(-1, order="F") for k in range(N)], axis=1) if nu else np.zeros((0, N))
    P = np.vstack([np.tile(pvec[:, None], (1, N)), U, breaks[None, :-1], np.diff(breaks)[None, :]])
    taus = np.asarray(col.tau_root[1:], dtype=float)
    xs = col.xc[:, 1:, :].reshape(N * d, -1).T  # (nx, N d): element k's points k d .. k d + d - 1
    jac = np.asarray(J.map(N * d)(xs, np.repeat(P, d, axis=1), np.tile(taus, N)[None, :]), dtype=float)
    nx = x.numel()
    blocks = jac.reshape(nx, N * d, nx).transpose(1, 0, 2) if nx else np.zeros((0, 0, 0))
    finite = np.all(np.isfinite(blocks), axis=(1, 2))
    rho = float(np.max(np.abs(np.linalg.eigvals(blocks[finite])))) if finite.any() and nx else 0.0
    if rho > STIFF_STEPS or not finite.all():
        return f", BDF: stiff, h |lambda| up to {rho:.3g}", {"linear_multistep_method": "bdf", "nonlinear_solver_iteration": "newton"}
    return f", Adams: non-stiff, h |lambda| up to {rho:.3g}", {"linear_multistep_method": "adams", "nonlinear_solver_iteration": "functional"}


def checked_integrals(result: OptimizationResult, integrals: tuple[list[str], ca.Function, np.ndarray], q_sim: np.ndarray,
                       tolerance: float, pvec: np.ndarray, rtol: float) -> dict[str, dict[str, Any]]:
    """The integrals' test: relative, ``|I_sim - I_col| <= tolerance * max(|I_col|, INTEGRAL_FLOOR * A) + e``.

    ``A`` is the integral of the integrand's modulus (the collocation quadrature of ``|f|``
    at the collocation points, ``sum_k h_k sum_j B_j |f(t_kj)|``): the floor, scaled by the
    problem, serves an integral that cancels to about zero (an isoperimetric ``integral(u) == 0``);
    for an integrand of one sign (an energy, ``u^2``) ``A = |I|`` and the test is relative.
    ``e = QUADRATURE_NOISE * atol * (tf - t0)`` is what the simulation itself can tell apart
    (its quadrature's absolute tolerance ``atol = 1e-2 rtol`` over the horizon): an integral
    that vanishes at the optimum (a fit to noise-free data, 1e-9; an effort of 1e-44) is
    compared with a simulated value accurate to ``atol`` only.
    Was ``tolerance * max(1, |I_col|)``: absolute below 1, so that at tolerance 1e-2 an energy
    of 0.27 passed 3.7 % off, and one of 0.001 any error below ten times its value.

    Parameters
    ----------
    result : OptimizationResult
        The solution.
    integrals : tuple
        ``(names, integrands, values)`` (:func:`~gtmodel.modeling.ocp.verification.problem_integrals`).
    q_sim : numpy.ndarray
        The integrals along the simulation, shape ``(m,)``.
    tolerance : float
        The verification tolerance.
    pvec : numpy.ndarray
        The model's parameter vector.
    rtol : float
        The integrator's relative tolerance (its absolute one is ``1e-2 rtol``).

    Returns
    -------
    dict
        Name -> ``{"collocation", "simulated", "abs_deviation", "rel_deviation", "passed"}``.
    """
    names, integrands, values = integrals
    magnitude = integral_magnitudes(result, integrands, pvec)
    noise = QUADRATURE_NOISE * 1e-2 * rtol * (result.collocation.tf - result.collocation.t0)
    out = {}
    for name, col_value, sim_value, a in zip(names, np.asarray(values, dtype=float), q_sim, magnitude):
        gap = abs(float(sim_value) - float(col_value))
        reference = max(abs(float(col_value)), INTEGRAL_FLOOR * float(a))
        out[name] = {"collocation": float(col_value), "simulated": float(sim_value), "abs_deviation": gap,
                     "rel_deviation": gap / reference if reference > 0 else (0.0 if gap == 0 else float("inf")),
                     "passed": bool(gap <= tolerance * reference + noise)}
    return out


def integral_magnitudes(result: OptimizationResult, integrands: ca.Function, pvec: np.ndarray) -> np.ndarray:
    """``A_i = integral |f_i| dt`` by the collocation quadrature of the result's points.

    Parameters
    ----------
    result : OptimizationResult
        The solution (collocation data).
    integrands : casadi.Function
        ``(t, x, z, u, p) -> (m,)``.
    pvec : numpy.ndarray
        The model's parameter vector.

    Returns
    -------
    numpy.ndarray
        Shape ``(m,)``.
    """
    col = result.collocation
    N, d = col.elements, col.points
    B = np.asarray(collocation_coefficients(d, col.scheme)["B"], dtype=float).reshape(-1)
    breaks = col.breaks()
    h = np.diff(breaks)
    t = (breaks[:-1, None] + np.asarray(col.tau_root[1:], dtype=float)[None, :] * h[:, None]).reshape(1, -1)
    x = col.xc[:, 1:, :].reshape(N * d, -1).T
    z, u = col.zc.reshape(N * d, -1).T, col.uc.reshape(N * d, -1).T
    f = np.asarray(integrands.map(N * d)(t, x, z, u, pvec), dtype=float).reshape(-1, N * d)
    return np.abs(f) @ (h[:, None] * B[None, :]).reshape(-1)
