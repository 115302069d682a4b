"""The MPC's horizon problem solved from Python: the reference the generated step is checked against.

:meth:`gtmodel.control.mpc.MPCController.solve` (its documentation) calls :func:`horizon_solve`:
IPOPT, CasADi's ``sqpmethod``, or the step's own ``hpipm`` and ``fatrop`` forms.
"""

from __future__ import annotations

import math
from dataclasses import replace
from typing import Any

import numpy as np

from gtmodel.control.mpc_fatrop import fatrop_problem
from gtmodel.control.mpc_hpipm import hpipm_rti
from gtmodel.control.problem import sqrt_psd as _sqrt_psd
from gtmodel.control.tracking import saturate
from gtmodel.errors import InputError

__all__ = ["float_tolerance", "horizon_solve"]


def horizon_solve(c: Any, t: float, x: Any, w0: Any, plugin: str, iterations: int | None, u_prev: Any) -> tuple[np.ndarray, np.ndarray]:
    """:meth:`gtmodel.control.mpc.MPCController.solve` of the MPC ``c`` (its arguments and results).

    Parameters
    ----------
    c : MPCController
        The MPC.
    t : float
        Time [s].
    x : array_like
        ``(nx,)`` state.
    w0 : array_like or None
        ``(nw,)`` start (None: :attr:`~gtmodel.control.mpc.MPCController.w_initial`).
    plugin : {"ipopt", "sqpmethod", "fatrop", "hpipm"}
        The solver.
    iterations : int or None
        SQP iterations (``sqpmethod``, ``hpipm``).
    u_prev : array_like or None
        ``(nu,)`` the input acting before the horizon (with ``R_rate``).

    Returns
    -------
    u : numpy.ndarray
        ``(nu,)`` the first input.
    w : numpy.ndarray
        ``(nw,)`` the blocked inputs.
    """
    if plugin == "hpipm":
        w_start = c.w_initial if w0 is None else np.asarray(w0, dtype=float).reshape(-1)
        lbu, ubu = np.tile(c.u_lb, c.blocks), np.tile(c.u_ub, c.blocks)
        w = np.asarray(hpipm_rti(c, _sqrt_psd, iterations)(x, w_start, c.parameters(t, x), lbu, ubu, np.zeros(c.constraint_rows))[0]).reshape(-1)
        return w[: c.nu].copy(), w
    if plugin == "fatrop":
        solver, first, b = fatrop_problem(c, _sqrt_psd)
        z0 = first(x, c.w_initial if w0 is None else np.asarray(w0, dtype=float).reshape(-1))
        z = np.asarray(solver(x0=z0, p=c.parameters(t, x), **{k: b[k] for k in ("lbx", "ubx", "lbg", "ubg")})["x"]).reshape(-1)
        w = z[b["inputs"]]
        return w[: c.nu].copy(), w
    w_start = c.w_initial if w0 is None else np.asarray(w0, dtype=float).reshape(-1)
    if plugin == "ipopt" and c.n_slack:
        # the exact penalty's theorem (Nocedal & Wright, Numerical Optimization, 2nd ed., thm. 17.3):
        # where the hard problem has a solution whose multipliers are below rho, the soft problem's
        # solution is the same point; IPOPT reaches it on the hard form far more accurately
        # (the slacks' gradient rho, ~1e10 on the L1, spoils its gradient-based scaling: 4.7e-6
        # off the converged SQP on the soft form, 2e-11 on the hard one)
        hard = replace(c, constraints=replace(c.constraints, hard=True))
        solver = hard.nlp_solver("ipopt")
        sol = solver(x0=w_start, p=c.parameters(t, x, u_prev), **hard.bounds())
        lam = float(np.sum(np.abs(np.asarray(sol["lam_g"]))))  # one slack per side serves all its rows: their sum
        if solver.stats()["success"] and lam < c.constraints.weight:
            w = np.asarray(sol["x"]).reshape(-1)
            return w[: c.nu].copy(), w
    solver = c.nlp_solver(plugin, iterations)
    sol = solver(x0=np.r_[w_start, np.zeros(c.n_slack)], p=c.parameters(t, x, u_prev), **c.bounds())
    w = np.asarray(sol["x"]).reshape(-1)[: c.nw]
    return w[: c.nu].copy(), w


def float_tolerance(c: Any, rows: int = 20, tau: float = 0.0) -> float:
    """How far a single-precision step may differ from its double-precision Python reference.

    Both stop the QP of each SQP iteration once its dual infeasibility ``|H w + g|`` is
    below ``tau``, each within ``tau / lambda_min(H)`` of the QP's solution, and float32 adds a forward error of about
    ``eps cond(H)`` relative (Higham, *Accuracy and Stability of Numerical Algorithms*,
    2002, Thm. 7.2; ``eps = 2^-23``). ``H`` is the Gauss-Newton Hessian of the blocked
    inputs, evaluated at ``rows`` reference rows spread over the reference.

    Parameters
    ----------
    c : MPCController
        The MPC.
    rows : int, optional
        Reference rows evaluated (default 20; at least 1).
    tau : float, optional
        The QP's dual infeasibility tolerance (:data:`gtmodel.control.mpc.QP_FLOAT_TOLERANCE` for ``qrqp``; 0: exact).

    Returns
    -------
    float
        ``max over rows of 2 tau / lambda_min(H) + eps cond(H)``; the check bounds each
        output by it times ``(1 + |Python|)``.  ``inf`` when ``H`` is singular somewhere.

    Raises
    ------
    InputError
        ``rows`` not a positive integer.
    """
    if isinstance(rows, bool) or not isinstance(rows, (int, np.integer)) or rows < 1:
        raise InputError(f"rows: expected a positive number of reference rows, got {rows!r}")
    nlp, hess = c._nlp()
    eps = float(np.finfo(np.float32).eps)
    worst = 0.0
    for k in np.unique(np.linspace(0, c.length - 1, int(rows)).astype(int)):
        u = saturate(c.u_ref[k], c.u_lb, c.u_ub)
        w = np.r_[np.tile(u, c.blocks), np.zeros(c.n_slack)]
        h = np.array(hess(w, c.parameters(c.t0 + k * c.dt, c.x_ref[k]), 1.0, np.zeros(nlp["g"].numel())))
        lam = np.linalg.eigvalsh(h[: c.nw, : c.nw])
        if not lam[0] > 0.0:
            return math.inf
        worst = max(worst, 2.0 * tau / lam[0] + eps * lam[-1] / lam[0])
    return float(worst)

