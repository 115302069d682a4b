"""The MPC step's memory beyond its warm start: the offset-free input-disturbance estimate and the reset.

With :attr:`~gtmodel.control.mpc.MPCController.disturbance_gain` the memory of the generated
step (:mod:`gtmodel.codegen.loop_step`) holds, after the blocked inputs ``w``, the estimate
``d (nu)``, the last measured state ``(nx)``, the last ``u_last (nu)`` and a flag (1 once a
step ran). The estimate is updated each period from the one-period prediction error of the
last measured state, ``d += gain (B'B + eps I)^{-1} B' (x - F(x_prev, u_act + d))``
(``B = dF/du`` there; Pannocchia & Rawlings, AIChE J. 49 (2003), the input-disturbance
model; Maeder, Borrelli & Morari, Automatica 45 (2009)). The functions take the controller
``c`` (an :class:`~gtmodel.control.mpc.MPCController`) as their first argument.
"""

from __future__ import annotations

from typing import Any

import casadi as ca

from gtmodel.control.reference import period_index
from gtmodel.control.tracking import saturate

__all__ = ["disturbance_estimate", "memory_predict", "memory_reset"]


def _estimator_memory(c: Any, u_last: ca.MX, mem: ca.MX) -> tuple[ca.MX, ca.MX, ca.MX, ca.MX]:
    """The estimate ``d``, the last measured state, the input that acted over the last period and the flag, from the memory."""
    nx, nu, nw = c.nx, c.nu, c.nw
    d, x_prev, u_prev, ran = mem[nw:nw + nu], mem[nw + nu:nw + nu + nx], mem[nw + nu + nx:nw + 2 * nu + nx], mem[-1]
    # the input that acted over the last period: the one computed then (u_last now) without a delay, with a
    # one-period delay the one computed a period earlier (u_last then, kept in the memory)
    return d, x_prev, (u_last if c.delay == 0 else u_prev), ran


def memory_predict(c: Any) -> ca.Function:
    """The state the memory predicts for now (:meth:`~gtmodel.control.mpc.MPCController.memory_predict`).

    Parameters
    ----------
    c : MPCController
        A controller with a non-zero ``disturbance_gain``.

    Returns
    -------
    casadi.Function
        ``predict(u_last (nu,1), w (n_memory,1)) -> x (nx,1)``: ``c.step`` from the last measured state
        with the input that acted over the last period plus the estimate.
    """
    u_last, mem = ca.MX.sym("u_last", c.nu), ca.MX.sym("w", c.n_memory)
    d, x_prev, u_act, _ = _estimator_memory(c, u_last, mem)
    return ca.Function("predict", [u_last, mem], [c.step(x_prev, u_act + d)], ["u_last", "w"], ["x"])


def disturbance_estimate(c: Any, x: ca.MX, u_last: ca.MX, mem: ca.MX) -> ca.MX:
    """The input-disturbance estimate of this period (see the module docstring) from the memory ``mem``.

    Parameters
    ----------
    c : MPCController
        A controller with a non-zero ``disturbance_gain``.
    x : casadi.MX
        ``(nx, 1)`` the measured state.
    u_last : casadi.MX
        ``(nu, 1)`` the step's ``u_last``.
    mem : casadi.MX
        ``(n_memory, 1)`` the step's memory.

    Returns
    -------
    casadi.MX
        ``(nu, 1)`` the updated estimate ``d`` (unchanged before the first step ran: the memory
        holds no measured state then).
    """
    d, x_prev, u_act, ran = _estimator_memory(c, u_last, mem)
    xs, us = ca.MX.sym("x", c.nx), ca.MX.sym("u", c.nu)
    B = ca.Function("B", [xs, us], [ca.jacobian(c.step(xs, us), us)])(x_prev, u_act + d)
    btb = ca.mtimes(B.T, B)
    eps = 1e-9 * (ca.trace(btb) / c.nu + 1e-300)
    gain = ca.solve(btb + eps * ca.DM.eye(c.nu), B.T)  # (B'B + eps I)^{-1} B': least squares of the state error
    innovation = x - memory_predict(c)(u_last, mem)  # the measurement less the state the memory predicts
    return ca.if_else(ran > 0.5, d + c.disturbance_gain * ca.mtimes(gain, innovation), d)


def memory_reset(c: Any) -> ca.Function:
    """The step's memory reset to the reference's at the current period (:meth:`~gtmodel.control.mpc.MPCController.memory_reset`).

    Parameters
    ----------
    c : MPCController
        The controller.

    Returns
    -------
    casadi.Function
        ``reset(t (1,1), x (nx,1)) -> (u_last (nu,1), w (n_memory,1))``.
    """
    t, x = ca.MX.sym("t"), ca.MX.sym("x", c.nx)
    n, nu, b = c.length, c.nu, c.horizon // c.blocks
    values = ca.MX(ca.DM(c.u_ref.reshape(-1)))

    def u_star(k: Any) -> ca.MX:
        return saturate(ca.vertcat(*[values[nu * ca.fmin(k, n - 1) + i] for i in range(nu)]), c.u_lb, c.u_ub)

    u_last = u_star(period_index(t, c.t0, c.dt, n - 1))
    k = period_index(t + c.delay * c.dt, c.t0, c.dt, n - 1)
    w = ca.vertcat(*[u_star(k + s * b) for s in range(c.blocks)])
    if c.disturbance_gain:
        w = ca.vertcat(w, ca.DM.zeros(nu), x, u_last, 0.0)
    return ca.Function("reset", [t, x], [u_last, w], ["t", "x"], ["u_last", "w"])
