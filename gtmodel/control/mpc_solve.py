"""The MPC's horizon problem solved from Python: the reference the generated step is checked against.

:meth:`gtmodel.control.mpc.MPCController.solve` (its documentation) calls :func:`horizon_solve`:
IPOPT, CasADi's ``sqpmethod``, or the step's own ``hpipm`` and ``fatrop`` forms.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Any, Iterator

import numpy as np

from gtmodel.control.mpc_fatrop import fatrop_problem
from gtmodel.control.mpc_hpipm import HPIPM_MAX_ITER, hpipm_rti
from gtmodel.control.problem import sqrt_psd as _sqrt_psd
from gtmodel.control.tracking import saturate
from gtmodel.errors import InputError
from gtmodel.modeling.ocp.result import normalize_ipopt_status
from gtmodel.modeling.ocp.shooting_bounds import quiet_casadi
from gtmodel.status import Status

__all__ = ["HorizonSolution", "float_tolerance", "horizon_solve"]


@dataclass(frozen=True)
class HorizonSolution:
    """The horizon problem solved from Python, with the solver's verdict.

    Unpacks as ``u, w = controller.solve(...)`` (and ``[0]``, ``[1]``), as python-control's
    response objects unpack into their arrays.

    Parameters
    ----------
    u : numpy.ndarray
        ``(nu,)`` the first input.
    w : numpy.ndarray
        ``(nw,)`` the blocked inputs.
    status : Status
        ``optimal`` where the NLP solver converged (IPOPT, ``sqpmethod``, FATROP; IPOPT's statuses by
        :func:`~gtmodel.modeling.ocp.result.normalize_ipopt_status`); ``completed`` where a fixed count of
        iterations ran (``sqpmethod``'s ``iterations``, every one taken; ``hpipm``'s real-time iterations with
        every QP solved); ``error`` where HPIPM did not solve one (its iteration limit or its minimum step: ``w`` is
        then its last iterate) or the SQP stopped otherwise, and wherever ``u`` or ``w`` is not finite.
    message : str
        The solver's own status and what it means.
    plugin : str
        The solver.
    """

    u: np.ndarray
    w: np.ndarray
    status: Status
    message: str
    plugin: str

    @property
    def success(self) -> bool:
        """Whether :attr:`status` is a success (``optimal``, ``converged``, ``completed``)."""
        return self.status.success

    def __iter__(self) -> Iterator[np.ndarray]:
        return iter((self.u, self.w))

    def __getitem__(self, i: int) -> np.ndarray:
        return (self.u, self.w)[i]

    def __len__(self) -> int:
        return 2


def _solution(w: np.ndarray, nu: int, status: Status, message: str, plugin: str) -> HorizonSolution:
    """The result, ``error`` wherever the inputs are not finite (never a silent NaN)."""
    w = np.asarray(w, dtype=float).reshape(-1)
    if not np.all(np.isfinite(w)):
        status, message = Status.ERROR, f"non-finite inputs ({message})"
    return HorizonSolution(u=w[:nu].copy(), w=w, status=status, message=message, plugin=plugin)


def _nlp_status(stats: dict, fixed: int | None = None) -> tuple[Status, str]:
    """A CasADi NLP solver's verdict (IPOPT's, ``sqpmethod``'s, FATROP's ``stats()``) as a status and its message.

    ``fixed``: the SQP runs exactly that many iterations (``sqpmethod``'s ``min_iter = max_iter``, tolerances
    1e-14): reaching the count is ``completed``, not a failure.
    """
    rs = str(stats.get("return_status", ""))
    if stats.get("success"):
        return Status.OPTIMAL, rs or "converged"
    if fixed is not None and rs == "Maximum_Iterations_Exceeded":
        return Status.COMPLETED, f"{fixed} SQP iterations, the count asked for ({rs})"
    status = normalize_ipopt_status(rs)
    return (Status.ERROR if status.success else status), rs or "not converged"


def horizon_solve(c: Any, t: float, x: Any, w0: Any, plugin: str, iterations: int | None, u_prev: Any) -> HorizonSolution:
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
    HorizonSolution
        The first input, the blocked inputs and the solver's verdict (unpacks as ``u, w``).
    """
    if plugin == "hpipm":
        w_start = c.w_initial if w0 is None else np.asarray(w0, dtype=float).reshape(-1)
        args = (x, w_start, c.parameters(t, x), np.tile(c.u_lb, c.blocks), np.tile(c.u_ub, c.blocks), np.zeros(c.constraint_rows))
        k_it = c.sqp_iterations if iterations is None else int(iterations)
        try:  # HPIPM's own verdict on every QP (CasADi's error_on_fail; its dump of the QP kept off the terminal), then the
            # same iterations leniently for the iterate (CasADi has no stats of a solver inside a Function)
            with quiet_casadi():
                w = np.asarray(hpipm_rti(c, _sqrt_psd, iterations, strict=True)(*args)[0])
            status, message = Status.COMPLETED, f"{k_it} real-time iterations, every QP solved by HPIPM"
        except RuntimeError:
            w = np.asarray(hpipm_rti(c, _sqrt_psd, iterations)(*args)[0])
            status, message = Status.ERROR, (f"HPIPM did not solve a QP of the {k_it} real-time iterations (its limit of "
                                             f"{HPIPM_MAX_ITER} iterations or its minimum step): its last iterate")
        return _solution(w, c.nu, status, message, plugin)
    if plugin == "fatrop":
        solver, first, b = fatrop_problem(c, _sqrt_psd)
        z0 = first(x, c.w_initial if w0 is None else np.asarray(w0, dtype=float).reshape(-1))
        z = np.asarray(solver(x0=z0, p=c.parameters(t, x), **{k: b[k] for k in ("lbx", "ubx", "lbg", "ubg")})["x"]).reshape(-1)
        return _solution(z[b["inputs"]], c.nu, *_nlp_status(solver.stats()), plugin)
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
            status, message = _nlp_status(solver.stats())
            return _solution(sol["x"], c.nu, status, f"{message} (the hard form; its multipliers below the penalty)", plugin)
    solver = c.nlp_solver(plugin, iterations)
    sol = solver(x0=np.r_[w_start, np.zeros(c.n_slack)], p=c.parameters(t, x, u_prev), **c.bounds())
    fixed = (c.sqp_iterations if iterations is None else int(iterations)) if plugin == "sqpmethod" else None
    return _solution(np.asarray(sol["x"]).reshape(-1)[: c.nw], c.nu, *_nlp_status(solver.stats(), fixed), plugin)


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

