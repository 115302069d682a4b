"""A model as an explicit ODE ``xdot = f(x, u, p)``, ``y = h(x, u, p)``, and its fixed-step integrators.

One path for every model (a :class:`~gtmodel.modeling.Model` or a
:class:`~gtmodel.modeling.Component`, the robots' and a user's): the model is reduced as
:meth:`Model.simulate` reduces it (:func:`~gtmodel.modeling.structural_simplify`, alias
elimination and index reduction, when it does not flatten as it is), flattened to the
semi-explicit DAE ``xdot = F(t, x, z, u, p)``, ``0 = g(t, x, z, u, p)``
(:class:`~gtmodel.modeling.FlatDAE`), and the algebraic variables ``z`` are eliminated:

* **symbolically** where the structure allows: the Jacobian ``dg/dz`` is put in block
  triangular form (Dulmage-Mendelsohn, ``casadi.Sparsity.btf``), and every block whose
  equations are affine in its own variables is solved in order (a scalar block by one
  division, a larger one by ``casadi.solve`` of its small linear system). This is the common
  case of a composed component after alias elimination (connection equations, Kirchhoff
  and Newton laws, a gear's kinematics: all linear in the unknowns);
* **by Newton's method inside the graph** for the blocks that are not affine in their
  variables (an algebraic loop through a nonlinear equation): a bounded number of
  unrolled Newton steps (:data:`NEWTON_ITERATIONS`) from the variables' start values,
  with the Jacobian of the residual by CasADi's AD, damped (a step that does not decrease the
  residual is shortened, :data:`DAMPING_FACTOR`, so that a diode's exponential from a start far
  from its root gives no overflow and NaN); the Functions then carry a
  ``converged`` output (``1`` when the final residual is below :data:`NEWTON_TOLERANCE`
  relative to ``1 + |z|``, ``0`` otherwise or when anything is non-finite).

Everything is one CasADi SX graph, so the derivatives, the generated C
(:mod:`gtmodel.codegen.model_code`, ``gtmodel codegen --model``), the FMU
(:mod:`gtmodel.exchange.explicit`) and the controllers built on it all evaluate the same
equations. :meth:`ExplicitODE.step` gives a fixed-step integrator for a loop period ``dt``
(the 4 ms loop, :data:`gtmodel.defaults.LOOP_PERIOD_S`, by default): explicit Runge-Kutta 4,
implicit Euler, or the 2-stage Radau IIA method (order 3, L-stable, for stiff models such
as a DC motor whose 1.7 ms electrical time constant is shorter than the period), the
implicit stages solved by a bounded simplified Newton iteration (the exact Jacobian at
the predictor, factorised once per step).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import cached_property
from typing import Any

import casadi as ca
import numpy as np

from gtmodel.defaults import LOOP_PERIOD_S
from gtmodel.errors import InputError, ModelError
from gtmodel.modeling.dae import FlatDAE
from gtmodel.modeling.simulation.model import Model
from gtmodel.modeling.structure.index_reduction import structural_simplify

__all__ = [
    "ExplicitODE",
    "explicit_ode",
    "damped_newton",
    "fixed_step",
    "eliminated_algebraics",
    "STEP_METHODS",
    "NEWTON_ITERATIONS",
    "NEWTON_TOLERANCE",
    "STEP_NEWTON_ITERATIONS",
]

#: Unrolled (damped) Newton steps of the algebraic blocks that are not affine in their variables
#: (20: a diode's exponential from a zero start, 1 mA to 1 kA through a 1e4 Ohm leakage resistance).
NEWTON_ITERATIONS = 20
#: Convergence test of a Newton solve: ``sum|residual| <= NEWTON_TOLERANCE (1 + sum|unknowns|)``.
NEWTON_TOLERANCE = 1e-10
#: Factor by which the damped algebraic Newton iteration grows its step (up to the full Newton
#: step) after an accepted one; a rejected one shrinks it by 1/DAMPING_FACTOR to DAMPING_FACTOR^-4.
DAMPING_FACTOR = 4.0
#: Unrolled Newton steps of an implicit integrator step (one suffices for a linear model).
STEP_NEWTON_ITERATIONS = 6
#: Fixed-step methods of :meth:`ExplicitODE.step`: name -> (implicit, order).
STEP_METHODS: dict[str, tuple[bool, int]] = {"rk4": (False, 4), "implicit_euler": (True, 1), "radau2": (True, 3)}

# Butcher tableau of the 2-stage Radau IIA method (Hairer & Wanner, Solving ODE II, Table IV.5.5).
_RADAU_A = ((5.0 / 12.0, -1.0 / 12.0), (3.0 / 4.0, 1.0 / 4.0))
_RADAU_C = (1.0 / 3.0, 1.0)


def _converged(residual: ca.SX, unknowns: ca.SX, tol: float) -> ca.SX:
    """1 where ``sum|residual| <= tol (1 + sum|unknowns|)`` and all is finite, else 0.

    Sums, not maxima: a NaN propagates through a sum (``fmax`` would drop it)."""
    if residual.numel() == 0:
        return ca.SX(1.0)
    size = ca.sum1(ca.fabs(unknowns))
    return (ca.sum1(ca.fabs(residual)) <= tol * (1.0 + size)) * (size < math.inf)


def damped_newton(residual: ca.SX, v: ca.SX, v0: Any, iterations: int = NEWTON_ITERATIONS,
                  tol: float = NEWTON_TOLERANCE) -> tuple[ca.SX, ca.SX]:
    """``iterations`` unrolled, damped Newton steps on ``residual(v) = 0`` from ``v0``, as one SX graph.

    Parameters
    ----------
    residual : casadi.SX
        ``(n, 1)`` residual, a function of ``v`` (and of other symbols, kept).
    v : casadi.SX
        ``(n, 1)`` the unknowns (pure symbols).
    v0 : array_like or casadi.SX
        ``(n,)`` the start (numbers, or an expression of other symbols).
    iterations : int, optional
        Newton steps unrolled (default :data:`NEWTON_ITERATIONS`).
    tol : float, optional
        Convergence test ``sum|residual| <= tol (1 + sum|v|)`` (default :data:`NEWTON_TOLERANCE`).

    Returns
    -------
    solution : casadi.SX
        ``(n, 1)`` the last iterate.
    converged : casadi.SX
        1 where the test holds at it and all is finite, else 0.

    Notes
    -----
    Deuflhard, *Newton Methods for Nonlinear Problems* (2004), sec. 3.1 (damped Newton): a
    step that does not decrease ``sum|r|`` (or gives a non-finite residual) is rejected and a
    shorter one tried in the next iteration.
    """
    # damped Newton (Deuflhard, *Newton Methods for Nonlinear Problems*, 2004, sec. 3.1): the trial
    # v + lam d (d the Newton step) is taken where its residual is finite and smaller (sum|r|), else
    # v stays and lam times sqrt(|r| / |r_trial|), within [DAMPING_FACTOR^-4, 1 / DAMPING_FACTOR],
    # is tried next (the least for a non-finite trial); lam grows by DAMPING_FACTOR per accepted
    # step back to 1 (the plain Newton step: a model the plain iteration solves monotonically gets
    # the same numbers). Without it, Newton from a start far from the root of a stiff exponential (a
    # diode's i = I_s (exp(v / V_t) - 1)) jumps to where exp overflows and gives NaN. One residual
    # and one Jacobian per iteration, as the plain iteration.
    jac = ca.jacobian(residual, v)
    vk, rk, lam = ca.SX(v0), ca.substitute(residual, v, ca.SX(v0)), ca.SX(1.0)
    for _ in range(iterations):
        trial = vk + lam * -ca.solve(ca.substitute(jac, v, vk), rk)
        rt = ca.substitute(residual, v, trial)
        nt = ca.sum1(ca.fabs(rt))
        accept = ca.logic_or(nt < ca.sum1(ca.fabs(rk)), nt <= tol * (1.0 + ca.sum1(ca.fabs(trial))))
        vk, rk = ca.if_else(accept, trial, vk), ca.if_else(accept, rt, rk)
        shrink = ca.fmax(1.0 / DAMPING_FACTOR**4, ca.fmin(1.0 / DAMPING_FACTOR, ca.sqrt(ca.sum1(ca.fabs(rk)) / nt)))
        shrink = ca.if_else(nt < ca.inf, shrink, 1.0 / DAMPING_FACTOR**4)
        lam = ca.if_else(accept, ca.fmin(1.0, DAMPING_FACTOR * lam), lam * shrink)
    return vk, _converged(rk, vk, tol)


def _newton(residual: ca.SX, v: ca.SX, v0: Any, iterations: int, tol: float, simplified: bool = False) -> tuple[ca.SX, ca.SX]:
    """``iterations`` unrolled Newton steps on ``residual(v) = 0`` from ``v0``; (solution, converged).

    The full iteration is damped (:data:`DAMPING_FACTOR`); the simplified one is not.

    ``simplified``: the Jacobian at ``v0`` for every step (the simplified Newton iteration of
    implicit Runge-Kutta codes, Hairer & Wanner, Solving ODE II, sec. IV.8): one
    factorisation shared by the steps, a third of the generated code of the full iteration."""
    if simplified:
        jac0 = ca.substitute(ca.jacobian(residual, v), v, ca.SX(v0))
        vk = ca.SX(v0)
        for _ in range(iterations):
            vk = vk - ca.solve(jac0, ca.substitute(residual, v, vk))
        return vk, _converged(ca.substitute(residual, v, vk), vk, tol)
    return damped_newton(residual, v, v0, iterations, tol)


def fixed_step(rhs: Any, x: ca.SX, t: Any, dt: float, method: str, iterations: int = STEP_NEWTON_ITERATIONS,
               tolerance: float = NEWTON_TOLERANCE) -> tuple[ca.SX, ca.SX, ca.SX]:
    """One step of a fixed-step method, the one Runge-Kutta code of :meth:`ExplicitODE.step` and the shooting intervals.

    Parameters
    ----------
    rhs : callable
        ``rhs(x, t) -> (xdot (nx,1), q (nq,1), ok (1,1))``: the right-hand side, integrands
        integrated along with the state by the method's weights, and a flag (1 when the
        evaluation converged) multiplied over the stages.
    x : casadi.SX
        ``(nx, 1)`` the state at the start of the step.
    t : casadi.SX or float
        The time at the start of the step.
    dt : float
        The step length.
    method : {"rk4", "implicit_euler", "radau2"}
        Explicit Runge-Kutta 4 (order 4); implicit Euler (order 1, L-stable); the 2-stage
        Radau IIA method (order 3, L-stable, stiffly accurate; Hairer & Wanner, *Solving ODE
        II*, sec. IV.5). The implicit stages by ``iterations`` unrolled simplified Newton
        steps (the exact Jacobian at the predictor, factorised once; sec. IV.8).
    iterations : int, optional
        Newton steps of an implicit method.
    tolerance : float, optional
        Convergence test of the implicit stage equations (Radau's scaled by ``max(1, 1/dt)``).

    Returns
    -------
    tuple of casadi.SX
        ``x_next (nx,1)``, ``dq (nq,1)`` the integrands' increment, ``ok (1,1)`` the
        product of the stage Newton's and every evaluation's flags.
    """
    if method == "rk4":
        k1, q1, o1 = rhs(x, t)
        k2, q2, o2 = rhs(x + dt / 2 * k1, t + dt / 2)
        k3, q3, o3 = rhs(x + dt / 2 * k2, t + dt / 2)
        k4, q4, o4 = rhs(x + dt * k3, t + dt)
        return x + dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4), dt / 6 * (q1 + 2 * q2 + 2 * q3 + q4), o1 * o2 * o3 * o4
    n = x.numel()
    if method == "implicit_euler":
        v = ca.SX.sym("v", n)  # the new state
        v_sol, ok = _newton(v - x - dt * rhs(v, t + dt)[0], v, x + dt * rhs(x, t)[0], iterations, tolerance, simplified=True)
        _, q, o = rhs(v_sol, t + dt)
        return v_sol, dt * q, ok * o
    kk = ca.SX.sym("K", 2 * n)  # radau2: stage derivatives K1, K2
    ks = (kk[:n], kk[n:])
    stages = [x + dt * (_RADAU_A[i][0] * ks[0] + _RADAU_A[i][1] * ks[1]) for i in range(2)]
    res = ca.vertcat(*[ks[i] - rhs(stages[i], t + _RADAU_C[i] * dt)[0] for i in range(2)])
    k0 = rhs(x, t)[0]
    k_sol, ok = _newton(res, kk, ca.vertcat(k0, k0), iterations, tolerance * max(1.0, 1.0 / dt), simplified=True)
    k1, k2 = k_sol[:n], k_sol[n:]
    s1 = x + dt * (_RADAU_A[0][0] * k1 + _RADAU_A[0][1] * k2)
    x_next = x + dt * (_RADAU_A[1][0] * k1 + _RADAU_A[1][1] * k2)
    (_, q1, o1), (_, q2, o2) = rhs(s1, t + _RADAU_C[0] * dt), rhs(x_next, t + dt)
    return x_next, dt * (_RADAU_A[1][0] * q1 + _RADAU_A[1][1] * q2), ok * o1 * o2


def _blocks(jac: ca.SX) -> list[tuple[list[int], list[int]]]:
    """Equation and variable index blocks of ``dg/dz`` in solution order (block triangular form)."""
    sp = jac.sparsity()
    nb, rowperm, colperm, rowblock, colblock, _, _ = sp.btf()
    blocks = [([rowperm[i] for i in range(rowblock[b], rowblock[b + 1])], [colperm[j] for j in range(colblock[b], colblock[b + 1])])
              for b in range(nb)]
    # CasADi's btf is block lower triangular: a block depends on itself and earlier ones only.
    return blocks


def _eliminate(dae: FlatDAE, iterations: int, tol: float) -> tuple[ca.SX, ca.SX, int]:
    """``z`` as an expression of ``(t, x, u, p)``; its converged flag; the number solved by Newton."""
    z, g = dae.z, dae.alg_expr
    if dae.nz == 0:
        return ca.SX(0, 1), ca.SX(1.0), 0
    jac = ca.jacobian(g, z)
    if ca.sprank(jac.sparsity()) < dae.nz:
        raise ModelError(f"model {dae.name!r}: the algebraic equations are structurally singular in the algebraic variables")
    zs = [z[i] for i in range(dae.nz)]
    expr: list[Any] = [None] * dae.nz
    solved_sym: list[ca.SX] = []
    solved_expr: list[ca.SX] = []
    newton_vars: list[int] = []
    newton_res: list[ca.SX] = []
    for rows, cols in _blocks(jac):
        gb = ca.vertcat(*[g[r] for r in rows])
        if solved_sym:
            gb = ca.substitute(gb, ca.vertcat(*solved_sym), ca.vertcat(*solved_expr))
        vb = ca.vertcat(*[zs[c] for c in cols])
        jb = ca.jacobian(gb, vb)
        if ca.depends_on(jb, vb):  # not affine in its own variables: kept for Newton
            newton_vars += cols
            newton_res.append(gb)
            continue
        b = ca.substitute(gb, vb, ca.SX.zeros(vb.shape))
        sol = -b / jb if len(cols) == 1 else ca.solve(jb, -b)
        for k, c in enumerate(cols):
            expr[c] = sol[k]
            solved_sym.append(zs[c])
            solved_expr.append(sol[k])
    for c in newton_vars:
        expr[c] = zs[c]
    z_expr = ca.vertcat(*expr)
    if not newton_vars:
        return z_expr, ca.SX(1.0), 0
    vn = ca.vertcat(*[zs[c] for c in newton_vars])
    vn0 = ca.DM([float(dae.z_start[c]) for c in newton_vars])
    rn = ca.vertcat(*newton_res)
    # the residual may still name a later-solved affine variable: express it in the Newton unknowns
    rn = ca.substitute(rn, z, z_expr)
    vsol, ok = _newton(rn, vn, vn0, iterations, tol)
    return ca.substitute(z_expr, vn, vsol), ok, len(newton_vars)


def eliminated_algebraics(dae: FlatDAE) -> ca.SX | None:
    """The algebraic variables of ``dae`` as expressions of ``(t, x, u, p)`` where every block is affine in its own.

    The symbolic elimination of :func:`explicit_ode` (block triangular form, each block solved
    by a division or a small linear solve), for a caller that integrates the ODE
    ``xdot = F(t, x, z(t, x, u, p), u, p)`` itself (the verification's simulation).

    Parameters
    ----------
    dae : FlatDAE
        The model.

    Returns
    -------
    casadi.SX or None
        ``z`` as an expression, shape ``(nz, 1)``; None when a block needs Newton's method
        (a nonlinear algebraic loop) or the equations are structurally singular.
    """
    try:
        z_expr, _ok, n_newton = _eliminate(dae, NEWTON_ITERATIONS, NEWTON_TOLERANCE)
    except ModelError:
        return None
    return None if n_newton else z_expr


def _scalar_meta(meta: dict[str, str], names: list[str]) -> dict[str, str]:
    """Entry per scalar name, element names ``v[i]`` taking their declared name's."""
    out: dict[str, str] = {}
    for n in names:
        v = meta.get(n, meta.get(n.split("[", 1)[0]))
        if v:
            out[n] = v
    return out


@dataclass
class ExplicitODE:
    """A model as an explicit ODE: ``xdot = f(x, u, p)``, ``y = h(x, u, p)`` (CasADi SX Functions).

    Built by :func:`explicit_ode`. All Functions are one graph (the same equations as
    :meth:`~gtmodel.modeling.Model.simulate`), so they can be differentiated, composed
    into a transcription or a controller, and generated as C.

    Parameters
    ----------
    name : str
        Model name.
    full : casadi.Function
        ``full(t, x, u, p) -> (xdot, y, converged)``, shapes ``(1,1), (nx,1), (nu,1),
        (np,1) -> (nx,1), (ny,1), (1,1)``; ``converged`` is 1 when every algebraic Newton
        solve converged (always 1 when ``newton == 0``).
    dae : FlatDAE or None
        The reduced, flattened model the ODE was built from; None for one that arrived as a
        Function (an imported FMU, a connection of explicit models: :meth:`from_function`).
    x_names, u_names, p_names, y_names : list of str
        Scalar names (``"load.w"``, ``"T[0]"``) of states, inputs, parameters and outputs.
    x0 : numpy.ndarray
        ``(nx,)`` start values of the states (SI units).
    u0 : numpy.ndarray
        ``(nu,)`` start (nominal) values of the inputs.
    p_default : numpy.ndarray
        ``(np,)`` parameter values of the model.
    x_lb, x_ub, u_lb, u_ub : numpy.ndarray
        Declared bounds of states and inputs (``-inf``/``inf`` when none).
    units : dict of str to str
        Unit per scalar name (missing: none declared).
    symbolic : bool
        True when every algebraic variable was eliminated symbolically (no Newton inside).
    algebraic : int
        Number of algebraic variables eliminated.
    newton : int
        How many of them are solved by the in-graph Newton iteration.
    time_dependent : bool
        The right-hand side or outputs depend on time explicitly (``f``/``h`` then refuse;
        use :attr:`full`).
    descriptions : dict of str to str
        Description per scalar name (missing: none).
    indicators : casadi.Function or None
        ``c(t, x, u, p) -> c (nw, 1)``: the when-clauses' zero-crossing functions (an FMU's
        event indicators); None without events.
    jump : casadi.Function or None
        ``jump(t, x, u, p, fire (nw, 1)) -> x_new``: the reinits of the clauses whose
        ``fire`` entry is 1, right-hand sides at the values before the event.
    directions : list of int
        Per clause: 1 fires when ``c`` becomes ``> 0``, -1 when ``< 0``, 0 both.
    event_names : list of str
        The clauses' names.
    """

    name: str
    full: ca.Function
    dae: FlatDAE
    x_names: list[str]
    u_names: list[str]
    p_names: list[str]
    y_names: list[str]
    x0: np.ndarray
    u0: np.ndarray
    p_default: np.ndarray
    x_lb: np.ndarray
    x_ub: np.ndarray
    u_lb: np.ndarray
    u_ub: np.ndarray
    units: dict[str, str] = field(default_factory=dict)
    symbolic: bool = True
    algebraic: int = 0
    newton: int = 0
    time_dependent: bool = False
    descriptions: dict[str, str] = field(default_factory=dict)
    indicators: ca.Function | None = None
    jump: ca.Function | None = None
    directions: list[int] = field(default_factory=list)
    event_names: list[str] = field(default_factory=list)

    @classmethod
    def from_function(cls, name: str, f: ca.Function, x_names: list[str], u_names: list[str], p_names: list[str],
                      y_names: list[str], x0: Any, u0: Any, p_default: Any, **metadata: Any) -> "ExplicitODE":
        """An explicit ODE given as a Function ``f(t, x, u, p) -> (xdot, y)`` (an imported FMU, a connection).

        Parameters
        ----------
        name : str
            Model name.
        f : casadi.Function
            ``f(t, x, u, p) -> (xdot, y)``, shapes ``(1,1), (nx,1), (nu,1), (np,1) -> (nx,1), (ny,1)``.
        x_names, u_names, p_names, y_names : list of str
            Scalar names of states, inputs, parameters and outputs.
        x0, u0, p_default : array_like
            ``(nx,)``, ``(nu,)``, ``(np,)`` start values of states and inputs, parameter values.
        **metadata
            Further fields (``units``, ``descriptions``, ``algebraic``, events).

        Returns
        -------
        ExplicitODE
            No flat model behind it (``dae`` None), bounds infinite, ``converged`` always 1.
        """
        kind = ca.SX if f.is_a("SXFunction") else ca.MX
        t, x, u, p = (kind.sym(n, f.size1_in(i)) for i, n in enumerate(("t", "x", "u", "p")))
        xdot, y = f(t, x, u, p)
        full = ca.Function("explicit_ode", [t, x, u, p], [xdot, y, kind(1)], ["t", "x", "u", "p"], ["xdot", "y", "converged"])
        try:
            timed = bool(ca.depends_on(ca.vertcat(xdot, y), t))
        except RuntimeError:  # an external Function (an FMU) is opaque: assume it may depend on time
            timed = True
        inf = lambda n: (np.full(n, -np.inf), np.full(n, np.inf))  # noqa: E731
        (x_lb, x_ub), (u_lb, u_ub) = inf(len(x_names)), inf(len(u_names))
        return cls(name=name, full=full, dae=None, x_names=list(x_names), u_names=list(u_names), p_names=list(p_names),
                   y_names=list(y_names), x0=np.asarray(x0, float).reshape(-1), u0=np.asarray(u0, float).reshape(-1),
                   p_default=np.asarray(p_default, float).reshape(-1), x_lb=x_lb, x_ub=x_ub, u_lb=u_lb, u_ub=u_ub,
                   time_dependent=timed, **metadata)

    @property
    def nx(self) -> int:
        """Number of states."""
        return len(self.x_names)

    @property
    def nu(self) -> int:
        """Number of inputs."""
        return len(self.u_names)

    @property
    def np(self) -> int:
        """Number of parameters."""
        return len(self.p_names)

    @property
    def ny(self) -> int:
        """Number of scalar outputs."""
        return len(self.y_names)

    def _timeless(self, outputs: list[str], name: str) -> ca.Function:
        if self.time_dependent:
            raise ModelError(f"model {self.name!r} depends on time explicitly (a time-varying source in its equations): the loop's "
                             f"f(x, u, p), steps, tracking controller and MPC need a time-invariant model; make the time-varying "
                             f"signal an input (electrical.SignalVoltage, rotational.Torque, translational.Force driven by an input), or evaluate ExplicitODE.full(t, x, u, p)")
        x, u, p = ca.SX.sym("x", self.nx), ca.SX.sym("u", self.nu), ca.SX.sym("p", self.np)
        res = self.full(t=0.0, x=x, u=u, p=p)
        return ca.Function(name, [x, u, p], [res[o] for o in outputs], ["x", "u", "p"], outputs)

    @cached_property
    def f(self) -> ca.Function:
        """``f(x, u, p) -> xdot``: the right-hand side, ``(nx,1), (nu,1), (np,1) -> (nx,1)``.

        Raises
        ------
        ModelError
            The model depends on time explicitly.
        """
        return self._timeless(["xdot"], "f")

    @cached_property
    def h(self) -> ca.Function:
        """``h(x, u, p) -> y``: the declared outputs, ``(nx,1), (nu,1), (np,1) -> (ny,1)``.

        Raises
        ------
        ModelError
            The model depends on time explicitly.
        """
        return self._timeless(["y"], "h")

    @cached_property
    def rhs(self) -> ca.Function:
        """``f(t, x, u, p) -> (xdot, y)``: right-hand side and outputs with time (what an FMU evaluates).

        Shapes ``(1,1), (nx,1), (nu,1), (np,1) -> (nx,1), (ny,1)``; :attr:`full` without ``converged``.
        """
        sym = ca.SX.sym if self.full.is_a("SXFunction") else ca.MX.sym
        t, x, u, p = (sym(n, k) for n, k in (("t", 1), ("x", self.nx), ("u", self.nu), ("p", self.np)))
        out = self.full(t=t, x=x, u=u, p=p)
        return ca.Function("f", [t, x, u, p], [out["xdot"], out["y"]], ["t", "x", "u", "p"], ["xdot", "y"])

    def derivative_function(self) -> ca.Function:
        """Forward directional derivative of :attr:`rhs` (CasADi AD, an FMU's ``GetDirectionalDerivative``).

        Returns
        -------
        casadi.Function
            ``df(t, x, u, p, dx, du, dp) -> (dxdot, dy)``, the Jacobian of ``rhs`` times the
            seeds (time is not seeded).
        """
        f = self.rhs
        t, x, u, p = (ca.MX.sym(n, f.size1_in(i)) for i, n in enumerate(("t", "x", "u", "p")))
        dx, du, dp = ca.MX.sym("dx", self.nx), ca.MX.sym("du", self.nu), ca.MX.sym("dp", self.np)
        outs = f(t, x, u, p)
        douts = f.forward(1)(t, x, u, p, *outs, ca.MX(1, 1), dx, du, dp)
        return ca.Function("df", [t, x, u, p, dx, du, dp], list(douts), ["t", "x", "u", "p", "dx", "du", "dp"], ["dxdot", "dy"])

    @cached_property
    def converged(self) -> ca.Function:
        """``converged(x, u, p) -> converged``: 1 when the algebraic Newton solves converged.

        Raises
        ------
        ModelError
            The model depends on time explicitly.
        """
        return self._timeless(["converged"], "converged")

    def step(self, dt: float = LOOP_PERIOD_S, method: str = "rk4", iterations: int = STEP_NEWTON_ITERATIONS,
             tolerance: float = NEWTON_TOLERANCE, substeps: int = 1) -> ca.Function:
        """One fixed integrator step over ``dt`` with the input held: ``step(x, u, p) -> (x_next, converged)``.

        Parameters
        ----------
        dt : float, optional
            Step length [s] (default the 4 ms loop period).
        method : {"rk4", "implicit_euler", "radau2"}, optional
            Explicit Runge-Kutta 4 (order 4); implicit Euler (order 1, L-stable); the
            2-stage Radau IIA collocation method (order 3, L-stable, stiffly accurate;
            Hairer & Wanner, Solving ODE II, sec. IV.5).
        iterations : int, optional
            Unrolled steps of an implicit method's simplified Newton iteration (the exact
            Jacobian at the explicit Euler predictor, factorised once; Hairer & Wanner,
            sec. IV.8).
        tolerance : float, optional
            Convergence test of the implicit stage equations:
            ``sum|residual| <= tolerance (1 + sum|stages|)``.
        substeps : int, optional
            Equal steps of the method within ``dt`` (default 1).

        Returns
        -------
        casadi.Function
            ``step(x (nx,1), u (nu,1), p (np,1)) -> (x_next (nx,1), converged (1,1))``;
            ``converged`` is 1 when the stage Newton (implicit methods) and every
            algebraic Newton of the right-hand side converged, 0 otherwise (also for a
            non-finite result).

        Raises
        ------
        InputError
            ``dt`` not positive and finite, unknown ``method``, ``iterations`` or
            ``substeps`` below 1.
        ModelError
            The model depends on time explicitly.
        """
        if isinstance(substeps, bool) or not isinstance(substeps, (int, np.integer)) or substeps < 1:
            raise InputError(f"substeps: expected a positive number of steps per period, got {substeps!r}")
        if isinstance(dt, bool) or not isinstance(dt, (int, float, np.floating)) or not math.isfinite(dt) or dt <= 0:
            raise InputError(f"dt: expected a positive step length in seconds, got {dt!r}")
        if method not in STEP_METHODS:
            raise InputError(f"method: expected one of {', '.join(STEP_METHODS)}, got {method!r}")
        if isinstance(iterations, bool) or not isinstance(iterations, (int, np.integer)) or iterations < 1:
            raise InputError(f"iterations: expected a positive number of Newton steps, got {iterations!r}")
        single = self._single_step(float(dt) / int(substeps), method, int(iterations), float(tolerance))
        if substeps == 1:
            return single
        x, u, p = ca.SX.sym("x", self.nx), ca.SX.sym("u", self.nu), ca.SX.sym("p", self.np)
        xk, ok = x, ca.SX(1.0)
        for _ in range(int(substeps)):
            xk, ok_k = single(xk, u, p)
            ok = ok * ok_k
        return ca.Function(f"step_{method}", [x, u, p], [xk, ok], ["x", "u", "p"], ["x_next", "converged"])

    def _single_step(self, dt: float, method: str, iterations: int, tolerance: float) -> ca.Function:
        """One step of ``method`` over ``dt`` (see :meth:`step`; :func:`fixed_step`)."""
        f, ok_f = self.f, self.converged
        x, u, p = ca.SX.sym("x", self.nx), ca.SX.sym("u", self.nu), ca.SX.sym("p", self.np)
        x_next, _, ok = fixed_step(lambda xs, _t: (f(xs, u, p), ca.SX(0, 1), ok_f(xs, u, p)), x, 0.0, dt, method, iterations, tolerance)
        ok = ok * (ca.sum1(ca.fabs(x_next)) < math.inf)  # 0 for a NaN or infinite entry
        return ca.Function(f"step_{method}", [x, u, p], [x_next, ok], ["x", "u", "p"], ["x_next", "converged"])

    def simulate_steps(self, step: ca.Function, u: Any, p: Any = None, x0: Any = None) -> tuple[np.ndarray, np.ndarray]:
        """Iterate a step Function over ``N`` periods with given inputs (for checks and plots).

        Parameters
        ----------
        step : casadi.Function
            From :meth:`step`.
        u : array_like
            ``(N, nu)`` input per period (held over the period).
        p : array_like, optional
            ``(np,)`` parameters; default :attr:`p_default`.
        x0 : array_like, optional
            ``(nx,)`` start; default :attr:`x0`.

        Returns
        -------
        x : numpy.ndarray
            ``(N + 1, nx)`` states at the period boundaries.
        converged : numpy.ndarray
            ``(N,)`` the step's converged flag per period.

        Raises
        ------
        InputError
            ``u`` not ``(N, nu)``, ``p`` or ``x0`` of the wrong length.
        """
        uu = np.asarray(u, dtype=float).reshape(-1, self.nu) if self.nu else np.zeros((np.asarray(u).shape[0], 0))
        pv = self.p_default if p is None else np.asarray(p, dtype=float).reshape(-1)
        xs = self.x0 if x0 is None else np.asarray(x0, dtype=float).reshape(-1)
        if pv.size != self.np or xs.size != self.nx:
            raise InputError(f"p, x0: expected lengths {self.np} and {self.nx}, got {pv.size} and {xs.size}")
        n = uu.shape[0]
        mapped = step.mapaccum(n)
        xk, ok = mapped(xs, uu.T, np.tile(pv.reshape(-1, 1), (1, n)))
        x = np.vstack([xs.reshape(1, -1), np.asarray(xk).T])
        return x, np.asarray(ok).reshape(-1)


def _reduced(model: Any, name: str | None) -> tuple[Model, Model, dict[str, str]]:
    """(the model as given, the model reduced as ``simulate()`` reduces it, declared units).

    A component (the room above, not imported here) is recognised by its ``to_model`` and
    ``describe`` methods."""
    units: dict[str, str] = {}
    if not isinstance(model, Model) and callable(getattr(model, "to_model", None)) and callable(getattr(model, "describe", None)):
        m = model.to_model(name)
        units = {str(r.name): str(r.unit) for r in model.describe().itertuples(index=False) if r.unit}
    elif isinstance(model, Model):
        m = model
    else:
        raise InputError(f"model: expected a gtmodel Model or Component, got {type(model).__name__}")
    reduced = m if m._flattens() and not m._initial_equations else structural_simplify(m)
    return m, reduced, {**units, **reduced.units}


def explicit_ode(model: Any, name: str | None = None, iterations: int = NEWTON_ITERATIONS,
                 tolerance: float = NEWTON_TOLERANCE) -> ExplicitODE:
    """Reduce a model to an explicit ODE ``xdot = f(x, u, p)``, ``y = h(x, u, p)``.

    Parameters
    ----------
    model : Model or Component
        A gtmodel model, or a component (flattened with ``Component.to_model``). Reduced
        by :func:`~gtmodel.modeling.structural_simplify` when it does not flatten as it is
        or has initial equations (as :meth:`Model.simulate` does).
    name : str, optional
        Name of the flattened model of a component (default the component's).
    iterations : int, optional
        Unrolled Newton steps for the algebraic blocks that are not affine in their
        variables (default :data:`NEWTON_ITERATIONS`).
    tolerance : float, optional
        Their convergence tolerance (default :data:`NEWTON_TOLERANCE`).

    Returns
    -------
    ExplicitODE
        The Functions, names, units, start values, bounds and how ``z`` was eliminated.

    Raises
    ------
    InputError
        ``model`` is neither a Model nor a Component, ``iterations`` below 1.
    ModelError
        The model has no state, does not reduce to index 1, its algebraic equations are
        structurally singular, or a start or parameter value is not finite.
    """
    if isinstance(iterations, bool) or not isinstance(iterations, (int, np.integer)) or iterations < 1:
        raise InputError(f"iterations: expected a positive number of Newton steps, got {iterations!r}")
    m, reduced, units = _reduced(model, name)
    dae = reduced.flatten()
    if dae.nx == 0:
        raise ModelError(f"model {m.name!r} has no state: there is no ODE to make explicit")
    z_expr, ok, n_newton = _eliminate(dae, int(iterations), float(tolerance))
    y = ca.vertcat(*[ca.vec(dae.output_exprs[k]) for k in dae.output_sizes]) if dae.output_sizes else ca.SX(0, 1)
    xdot, y = (ca.substitute(e, dae.z, z_expr) for e in (dae.ode_expr, y)) if dae.nz else (dae.ode_expr, y)
    full = ca.Function("explicit_ode", [dae.t, dae.x, dae.u, dae.p], [xdot, y, ok], ["t", "x", "u", "p"], ["xdot", "y", "converged"])
    u0 = np.zeros(dae.nu)
    for k, sl in dae.u_vars.items():
        u0[sl] = np.asarray(reduced._vars[k].start, dtype=float).reshape(-1)
    x0 = np.asarray(dae.x_start, dtype=float).copy()
    pv = np.asarray(dae.p_value, dtype=float).copy()
    if not (np.all(np.isfinite(x0)) and np.all(np.isfinite(pv))):
        raise ModelError(f"model {m.name!r}: start and parameter values must be finite")
    names = dae.x_names + dae.z_names + dae.u_names + dae.p_names + dae.output_names
    return ExplicitODE(
        name=m.name, full=full, dae=dae, x_names=list(dae.x_names), u_names=list(dae.u_names), p_names=list(dae.p_names),
        y_names=list(dae.output_names), x0=x0, u0=u0, p_default=pv,
        x_lb=np.asarray(dae.x_lb, float).copy(), x_ub=np.asarray(dae.x_ub, float).copy(),
        u_lb=np.asarray(dae.u_lb, float).copy(), u_ub=np.asarray(dae.u_ub, float).copy(),
        units=_scalar_meta(units, names), symbolic=n_newton == 0, algebraic=dae.nz, newton=n_newton,
        time_dependent=bool(ca.depends_on(ca.vertcat(xdot, y), dae.t)),
    )
