"""The fixed-step integrators of a multiple-shooting interval, on the model's explicit form.

:class:`~gtmodel.modeling.ocp.shooting.ShootingTranscription` integrates each interval of
a model whose algebraic variables can be eliminated symbolically on its explicit form
``xdot = F(t, x, z(t, x, u, p), u, p)``: ``z`` is the expression of
:func:`gtmodel.modeling.simulation.explicit._eliminate` (the elimination that the generated C,
``gtmodel codegen --model``, and the FMU use; block triangular form, each block affine in its
own variables solved in order), so an ODE integrator runs on a DAE without a rootfinder:

* ``"rk"``: classical Runge-Kutta 4 (order 4, explicit), the method of CasADi's ``rk``
  plugin, as one SX function;
* ``"radau"``: the 2-stage Radau IIA method (order 3, L-stable, stiffly accurate; Hairer &
  Wanner, *Solving ODE II*, sec. IV.5), its stage equations solved by the unrolled
  simplified Newton iteration of :meth:`~gtmodel.modeling.simulation.explicit.ExplicitODE.step`
  (the exact Jacobian at the start of the step, factorised once): for stiff models (a DC
  motor's armature, a stiff shaft), whose time constants are shorter than a step.

Both return the states and algebraic variables at every step's end, so that bounds and path
constraints are imposed there (between the shooting nodes, not only at them) and the
result's rows are points the integrator computed.
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np

from gtmodel.errors import ModelError
from gtmodel.modeling.dae import FlatDAE
from gtmodel.modeling.simulation.explicit import (
    _RADAU_A,
    _RADAU_C,
    NEWTON_ITERATIONS,
    NEWTON_TOLERANCE,
    STEP_NEWTON_ITERATIONS,
    _eliminate,
    _newton,
)

__all__ = ["ExplicitAlgebraics", "explicit_algebraics", "fixed_steps", "EXPLICIT_INTEGRATORS"]

#: Integrators of :func:`fixed_steps` (on the explicit form).
EXPLICIT_INTEGRATORS = ("rk", "radau")


@dataclass(frozen=True)
class ExplicitAlgebraics:
    """The algebraic variables of a flat DAE as expressions of ``(t, x, u, p)``, or why not.

    Parameters
    ----------
    z : casadi.SX or None
        ``(nz, 1)`` in the DAE's symbols ``t, x, u, p``; None when they cannot be eliminated
        symbolically.
    reason : str
        Why not (empty when eliminated).
    """

    z: ca.SX | None
    reason: str = ""


def explicit_algebraics(dae: FlatDAE) -> ExplicitAlgebraics:
    """Eliminate the algebraic variables of ``dae`` as codegen does (symbolically only).

    Parameters
    ----------
    dae : FlatDAE
        The flattened model.

    Returns
    -------
    ExplicitAlgebraics
        ``z(t, x, u, p)`` when every algebraic block is affine in its own variables (solved
        in block triangular order); otherwise None and the reason (a structurally singular
        system, or the number of variables that only a Newton iteration solves).
    """
    if dae.nz == 0:
        return ExplicitAlgebraics(ca.SX(0, 1))
    try:
        z, _, newton = _eliminate(dae, NEWTON_ITERATIONS, NEWTON_TOLERANCE)
    except ModelError as exc:
        return ExplicitAlgebraics(None, str(exc))
    if newton:
        return ExplicitAlgebraics(None, f"{newton} of its {dae.nz} algebraic variables are solved by a Newton iteration "
                                        "(equations not affine in them)")
    return ExplicitAlgebraics(z)


def fixed_steps(problem: dict[str, ca.SX], steps: int, method: str) -> ca.Function:
    """``steps`` equal steps of ``method`` over ``tau`` in ``[0, 1]``, with the quadratures and every step's end.

    Parameters
    ----------
    problem : dict of str to casadi.SX
        ``x`` (nx, 1) states, ``p`` (np, 1) parameters, ``t`` the scalar normalised time,
        ``ode`` (nx, 1) ``dx/dtau``, ``quad`` (nq, 1) ``dq/dtau``, ``zout`` (nz, 1) the
        algebraic variables as expressions of ``x, p, t``.
    steps : int
        Equal steps.
    method : {"rk", "radau"}
        Classical Runge-Kutta 4, or the 2-stage Radau IIA method by
        :data:`~gtmodel.modeling.simulation.explicit.STEP_NEWTON_ITERATIONS` simplified
        Newton steps.

    Returns
    -------
    casadi.Function
        ``(x0 (nx,1), z0 (nz,1), p) -> (xf (nx,1), zf (nz,1), qf (nq,1), xs (nx,steps),
        zs (nz,steps), ok (1,1))``: the end, its algebraic variables, the quadratures, the
        states and algebraic variables at the end of each step, and 1 when every stage
        Newton iteration converged (always 1 for ``"rk"``).
    """
    x, p, t, zout = problem["x"], problem["p"], problem["t"], problem["zout"]
    f = ca.Function("rhs", [x, p, t], [problem["ode"], problem["quad"]])
    dt = 1.0 / steps
    n = x.numel()
    xc, tk = ca.SX.sym("x", n), ca.SX.sym("t")
    if method == "rk":
        k1, q1 = f(xc, p, tk)
        k2, q2 = f(xc + dt / 2 * k1, p, tk + dt / 2)
        k3, q3 = f(xc + dt / 2 * k2, p, tk + dt / 2)
        k4, q4 = f(xc + dt * k3, p, tk + dt)
        x_next = xc + dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        dq = dt / 6 * (q1 + 2 * q2 + 2 * q3 + q4)
        ok = ca.SX(1.0)
    else:  # Radau IIA, 2 stages: stage derivatives K1, K2
        kk = ca.SX.sym("K", 2 * n)
        ks = (kk[:n], kk[n:])
        stages = [xc + dt * (_RADAU_A[i][0] * ks[0] + _RADAU_A[i][1] * ks[1]) for i in range(2)]
        res = ca.vertcat(*[ks[j] - f(stages[j], p, tk + _RADAU_C[j] * dt)[0] for j in range(2)])
        k0 = f(xc, p, tk)[0]
        k_sol, ok = _newton(res, kk, ca.vertcat(k0, k0), STEP_NEWTON_ITERATIONS, NEWTON_TOLERANCE * max(1.0, 1.0 / dt),
                            simplified=True)
        k1, k2 = k_sol[:n], k_sol[n:]
        s1 = xc + dt * (_RADAU_A[0][0] * k1 + _RADAU_A[0][1] * k2)
        x_next = xc + dt * (_RADAU_A[1][0] * k1 + _RADAU_A[1][1] * k2)
        dq = dt * (_RADAU_A[1][0] * f(s1, p, tk + _RADAU_C[0] * dt)[1] + _RADAU_A[1][1] * f(x_next, p, tk + dt)[1])
    z_next = ca.substitute(zout, ca.vertcat(x, t), ca.vertcat(x_next, tk + dt))
    # one step as an SX function, repeated by mapaccum: the graph (and its derivatives) of one step,
    # not of all of them (64 unrolled Radau steps of a 5-state drive took 3.6 GB to build)
    step = ca.Function("step", [xc, p, tk], [x_next, dq, z_next, ok])
    x0, z0, pm = ca.MX.sym("x0", n), ca.MX.sym("z0", zout.numel()), ca.MX.sym("p", p.numel())
    xs, dqs, zs, oks = step.mapaccum("steps", steps)(x0, pm, ca.DM(np.arange(steps) * dt).T)
    return ca.Function("interval", [x0, z0, pm], [xs[:, -1], zs[:, -1], ca.sum2(dqs), xs, zs, ca.mmin(oks)],
                       ["x0", "z0", "p"], ["xf", "zf", "qf", "xs", "zs", "ok"])
