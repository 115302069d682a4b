"""Simulate, linearise and connect explicit models (imported FMUs and gtmodel models).

An explicit model (:class:`~gtmodel.modeling.ExplicitODE`, ``ExplicitODE`` in this
package) is ``xdot, y = rhs(t, x, u, p)``: an FMU loaded by
:func:`~gtmodel.exchange.fmu_import.import_fmu` (its ``rhs`` calls the FMU's binary) or a
gtmodel model or component reduced by :func:`~gtmodel.exchange.explicit.explicit_model`.
CasADi's ``rhs`` is an MX-callable function either way, so the same code serves both:

* :func:`simulate_explicit`: CasADi's CVODES on a time grid, inputs held over each interval
  (gtmodel's convention, :meth:`gtmodel.modeling.Model.simulate`);
* :func:`linearize_explicit`: ``A, B, C, D`` from ``rhs``'s Jacobian (the FMU's directional
  derivatives or finite differences, :attr:`ImportedFmu.derivatives`) as a
  :class:`~gtmodel.modeling.simulation.linear.Linearization`;
* :func:`connect_explicit`: causal connections (an output drives an input) between
  several models, the result one explicit model with prefixed names (``"fmu.x"``).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import casadi as ca
import numpy as np

from gtmodel.errors import ConvergenceError, InputError, ModelError
from gtmodel.exchange.explicit import explicit_model, fmi_identifier
from gtmodel.modeling import Component, ExplicitODE, Model, SimulationResult
from gtmodel.modeling.simulation.linear import Linearization

__all__ = ["simulate_explicit", "linearize_explicit", "connect_explicit"]


def _values(em: ExplicitODE, kind: str, given: Any) -> np.ndarray:
    """Default values of ``kind`` (x, u, p) with a mapping or vector of overrides."""
    names = {"x": em.x_names, "u": em.u_names, "p": em.p_names}[kind]
    base = {"x": em.x0, "u": em.u0, "p": em.p_default}[kind].astype(float).copy()
    if given is None:
        return base
    if isinstance(given, Mapping):
        for k, v in given.items():
            if k not in names:
                raise InputError(f"model {em.name!r} has no {dict(x='state', u='input', p='parameter')[kind]} {k!r}; "
                                 f"known: {names}")
            base[names.index(k)] = float(v)
        return base
    arr = np.asarray(given, dtype=float).reshape(-1)
    if arr.size == 1 and base.size != 1:
        arr = np.full(base.size, arr[0])
    if arr.size != base.size:
        raise InputError(f"{kind}: expected {base.size} values for model {em.name!r}, got {arr.size}")
    return arr


def simulate_explicit(
    em: ExplicitODE,
    t_grid: Any,
    x0: Any = None,
    u: Any = None,
    p: Any = None,
    rtol: float = 1e-8,
    atol: float = 1e-10,
) -> SimulationResult:
    """Integrate an explicit model with CasADi's CVODES.

    Parameters
    ----------
    em : ExplicitODE
        The model (e.g. ``import_fmu(...).model``).
    t_grid : array_like
        Increasing time grid, shape ``(N,)``, s.
    x0, p : mapping or array_like, optional
        Start states and parameters by scalar name (or full vectors); default the model's.
    u : mapping, array_like, optional
        Inputs: a mapping name -> constant, a constant vector ``(nu,)``, or per interval
        ``(N-1, nu)`` / ``(N, nu)`` (row ``k`` held on ``[t[k], t[k+1])``); default start values.
    rtol, atol : float, optional
        CVODES tolerances.

    Returns
    -------
    SimulationResult
        States, inputs and outputs by scalar name.

    Raises
    ------
    InputError
        Malformed grid or values.
    ConvergenceError
        CVODES fails (its message).
    """
    t = np.asarray(t_grid, dtype=float).reshape(-1)
    if t.size < 2 or np.any(np.diff(t) <= 0):
        raise InputError("t_grid: expected at least two strictly increasing times")
    xv, pv = _values(em, "x", x0), _values(em, "p", p)
    nu, n = len(em.u_names), t.size
    if u is None or isinstance(u, Mapping) or np.asarray(u).ndim <= 1:
        u_int = np.tile(_values(em, "u", u), (n - 1, 1))
    else:
        arr = np.asarray(u, dtype=float)
        if arr.shape not in ((n - 1, nu), (n, nu)):
            raise InputError(f"u: expected shape ({n - 1}, {nu}) or ({n}, {nu}), got {arr.shape}")
        u_int = arr[: n - 1]
    ts, xs, us, ps = ca.MX.sym("t"), ca.MX.sym("x", em.nx), ca.MX.sym("u", nu), ca.MX.sym("p", len(em.p_names))
    xdot, _ = em.rhs(ts, xs, us, ps)
    dae = {"t": ts, "x": xs, "u": us, "p": ps, "ode": xdot}
    try:
        F = ca.integrator(f"{fmi_identifier(em.name)}_sim", "cvodes", dae, float(t[0]), list(t), {"abstol": atol, "reltol": rtol})
        u_cas = np.vstack([u_int[:1], u_int]).T if nu else np.zeros((0, n))  # u[:, k] held on (t[k-1], t[k]]
        x_traj = np.array(F(x0=xv, p=pv, u=u_cas)["xf"]).reshape(em.nx, n).T
    except RuntimeError as exc:
        lines = [ln for ln in str(exc).splitlines() if "returned" in ln] or str(exc).splitlines()
        raise ConvergenceError(f"simulation of {em.name!r} with cvodes failed: {lines[0].strip() if lines else exc}") from None
    u_all = np.vstack([u_int, u_int[-1:]]) if nu else np.zeros((n, 0))
    fmap = em.rhs.map(n)
    _, y = fmap(t.reshape(1, -1), x_traj.T, u_all.T, np.tile(pv.reshape(-1, 1), (1, n)))
    y = np.array(y).reshape(em.ny, n).T
    return SimulationResult(
        t=t, x={k: x_traj[:, i] for i, k in enumerate(em.x_names)}, z={},
        u={k: u_all[:, i] for i, k in enumerate(em.u_names)}, outputs={k: y[:, i] for i, k in enumerate(em.y_names)},
        p={k: np.array([pv[i]]) for i, k in enumerate(em.p_names)},
    )


def linearize_explicit(em: ExplicitODE, x: Any = None, u: Any = None, p: Any = None, t: float = 0.0) -> Linearization:
    """Linearise ``xdot, y = f(t, x, u, p)`` about an operating point.

    Parameters
    ----------
    em : ExplicitODE
        The model.
    x, u, p : mapping or array_like, optional
        Operating point by scalar name or full vectors; default the start values.
    t : float, optional
        Time of the operating point, s.

    Returns
    -------
    Linearization
        ``A = df/dx``, ``B = df/du``, ``C = dy/dx``, ``D = dy/du`` (for an imported FMU from
        its directional derivatives or finite differences, :attr:`ImportedFmu.derivatives`).

    Raises
    ------
    InputError
        Malformed operating point.
    """
    xv, uv, pv = _values(em, "x", x), _values(em, "u", u), _values(em, "p", p)
    xs, us = ca.MX.sym("x", em.nx), ca.MX.sym("u", len(em.u_names))
    xdot, y = em.rhs(t, xs, us, pv)
    J = ca.Function("J", [xs, us], [ca.jacobian(xdot, xs), ca.jacobian(xdot, us), ca.jacobian(y, xs), ca.jacobian(y, us)])
    A, B, C, D = (np.array(m, dtype=float) for m in J(xv, uv))
    return Linearization(A=A, B=B, C=C, D=D, x_names=list(em.x_names), u_names=list(em.u_names),
                         y_names=list(em.y_names), x=xv, z=np.zeros(0), u=uv)


def _as_explicit(obj: Any, name: str) -> ExplicitODE:
    if isinstance(obj, ExplicitODE):
        return obj
    if hasattr(obj, "model") and isinstance(obj.model, ExplicitODE):  # an ImportedFmu
        return obj.model
    if isinstance(obj, (Model, Component)):
        return explicit_model(obj)
    raise InputError(f"models[{name!r}]: expected an ExplicitODE, ImportedFmu, Model or Component, got {type(obj).__name__}")


def connect_explicit(models: Mapping[str, Any], connections: Sequence[tuple[str, str]], name: str = "connected") -> ExplicitODE:
    """Connect models causally: each connection feeds an output into an input.

    Parameters
    ----------
    models : mapping of str to model
        Instance name -> :class:`ExplicitODE`, :class:`~gtmodel.exchange.fmu_import.ImportedFmu`,
        gtmodel :class:`~gtmodel.modeling.Model` or :class:`~gtmodel.modeling.Component`.
    connections : sequence of (str, str)
        ``("a.y", "b.u")``: output ``y`` of instance ``a`` drives input ``u`` of ``b``
        (an output may drive several inputs; a state may be used as an output too).
    name : str, optional
        Name of the connected model.

    Returns
    -------
    ExplicitODE
        States, free inputs, parameters and outputs of all instances, names prefixed by the
        instance name (``"fmu.x"``); the outputs are evaluated in dependency order.

    Raises
    ------
    InputError
        Unknown instance, output or input; an input driven twice.
    ModelError
        An algebraic loop (outputs that depend directly on inputs, in a cycle).
    """
    ems = {k: _as_explicit(v, k) for k, v in models.items()}
    drive: dict[tuple[str, str], tuple[str, str]] = {}
    for src, dst in connections:
        (a, _, y), (b, _, u) = src.partition("."), dst.partition(".")
        if a not in ems or b not in ems:
            raise InputError(f"connection {src} -> {dst}: unknown instance (known: {sorted(ems)})")
        if y not in ems[a].y_names and y not in ems[a].x_names:
            raise InputError(f"connection {src} -> {dst}: {a!r} has no output or state {y!r}")
        if u not in ems[b].u_names:
            raise InputError(f"connection {src} -> {dst}: {b!r} has no input {u!r}")
        if (b, u) in drive:
            raise InputError(f"connection {src} -> {dst}: input {dst} is already driven by {'.'.join(drive[(b, u)])}")
        drive[(b, u)] = (a, y)
    t = ca.MX.sym("t")
    xs = {k: ca.MX.sym(f"x_{i}", e.nx) for i, (k, e) in enumerate(ems.items())}
    ps = {k: ca.MX.sym(f"p_{i}", len(e.p_names)) for i, (k, e) in enumerate(ems.items())}
    free = [(k, n) for k, e in ems.items() for n in e.u_names if (k, n) not in drive]
    uf = ca.MX.sym("u", len(free))
    u_free = {key: uf[i] for i, key in enumerate(free)}
    outs: dict[str, tuple[ca.MX, ca.MX]] = {}
    ys: dict[str, ca.MX] = {}  # outputs known so far: first those that do not depend on inputs
    for k, e in ems.items():
        if e.ny and e.u_names and e.rhs.jac_sparsity(1, 2).nnz() == 0:
            ys[k] = e.rhs(t, xs[k], ca.DM.zeros(len(e.u_names)), ps[k])[1]
    pending = list(ems)
    while pending:
        progressed = False
        for k in list(pending):
            e = ems[k]
            ok = True
            u_parts = []
            for n in e.u_names:
                if (k, n) not in drive:
                    u_parts.append(u_free[(k, n)])
                    continue
                a, y = drive[(k, n)]
                if y in ems[a].x_names:
                    u_parts.append(xs[a][ems[a].x_names.index(y)])
                elif a in ys:
                    u_parts.append(ys[a][ems[a].y_names.index(y)])
                else:
                    ok = False
                    break
            if not ok:
                continue
            uk = ca.vertcat(*u_parts) if u_parts else ca.MX(0, 1)
            outs[k] = tuple(e.rhs(t, xs[k], uk, ps[k]))
            ys.setdefault(k, outs[k][1])
            pending.remove(k)
            progressed = True
        if not progressed:
            raise ModelError(f"connect_explicit: algebraic loop through the outputs of {sorted(pending)} "
                             "(an output that depends on an input feeds back to it)")
    order = list(ems)
    xdot = ca.vertcat(*[outs[k][0] for k in order])
    y = ca.vertcat(*[ys[k] for k in order])
    xall, pall = ca.vertcat(*[xs[k] for k in order]), ca.vertcat(*[ps[k] for k in order])
    f = ca.Function(fmi_identifier(name), [t, xall, uf, pall], [xdot, y], ["t", "x", "u", "p"], ["xdot", "y"])
    pre = lambda k, names: [f"{k}.{n}" for n in names]  # noqa: E731
    meta = lambda attr: {f"{k}.{n}": v for k in order for n, v in getattr(ems[k], attr).items()}  # noqa: E731
    return ExplicitODE.from_function(
        name, f, [n for k in order for n in pre(k, ems[k].x_names)], [f"{k}.{n}" for k, n in free],
        [n for k in order for n in pre(k, ems[k].p_names)], [n for k in order for n in pre(k, ems[k].y_names)],
        np.concatenate([ems[k].x0 for k in order]),
        np.array([ems[k].u0[ems[k].u_names.index(n)] for k, n in free], dtype=float),
        np.concatenate([ems[k].p_default for k in order]) if order else np.zeros(0),
        units=meta("units"), descriptions=meta("descriptions"), algebraic=sum(ems[k].algebraic for k in order),
    )
