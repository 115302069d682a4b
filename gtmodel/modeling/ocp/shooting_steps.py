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
    NEWTON_ITERATIONS,
    NEWTON_TOLERANCE,
    STEP_NEWTON_ITERATIONS,
    _eliminate,
    fixed_step,
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
        Newton steps (:func:`~gtmodel.modeling.simulation.explicit.fixed_step`, the code of
        :meth:`~gtmodel.modeling.simulation.explicit.ExplicitODE.step`).

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
    x_next, dq, ok = fixed_step(lambda xs, ts: (*f(xs, p, ts), ca.SX(1.0)), xc, tk, dt, "rk4" if method == "rk" else "radau2",
                                STEP_NEWTON_ITERATIONS, NEWTON_TOLERANCE)
    z_next = ca.substitute(zout, ca.vertcat(x, t), ca.vertcat(x_next, tk + dt))
    # one step as an SX function, repeated by mapaccum: the graph (and its derivatives) of one step,
    # not of all of them (64 unrolled Radau steps of a 5-state drive took 3.6 GB to build)
    step = ca.Function("step", [xc, p, tk], [x_next, dq, z_next, ok])
    x0, z0, pm = ca.MX.sym("x0", n), ca.MX.sym("z0", zout.numel()), ca.MX.sym("p", p.numel())
    xs, dqs, zs, oks = step.mapaccum("steps", steps)(x0, pm, ca.DM(np.arange(steps) * dt).T)
    return ca.Function("interval", [x0, z0, pm], [xs[:, -1], zs[:, -1], ca.sum2(dqs), xs, zs, ca.mmin(oks)],
                       ["x0", "z0", "p"], ["xf", "zf", "qf", "xs", "zs", "ok"])
