"""Flattening of a :class:`~gtmodel.modeling.Model` into its semi-explicit DAE (:class:`FlatDAE`).

:meth:`gtmodel.modeling.Model.flatten` calls :func:`flatten_model`: the variables are
stacked by kind (``x``, ``z``, ``u``, ``p``), the equations containing ``der()`` are solved
for ``der()`` symbolically (``M(.) xdot = -b(.)`` with ``M = d res / d xdot``,
``casadi.solve``; a constant ``M`` is inverted numerically once), and the algebraic
equations are checked to be index 1 in the algebraic variables::

    xdot = f(t, x, z, u, p)
       0 = g(t, x, z, u, p)

The record of one declared variable (:class:`_Var`) is shared with
:mod:`gtmodel.modeling.simulation.model`.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import casadi as ca
import numpy as np

from gtmodel._lazy import lazy_module
from gtmodel.errors import ModelError
from gtmodel.modeling.dae import FlatDAE, casadi_name, expand_names
from gtmodel.modeling.structure.analysis import incidence, matching, scalarize, structure_message, structure_parts

#: Imported on first use (PEP 562 lazy module): the solve path of a problem file need not pay for it.
sps = lazy_module("scipy.sparse")

__all__ = ["flatten_model"]

_KINDS = ("parameter", "state", "algebraic", "input")


@dataclass
class _Var:
    """One declared variable (internal record)."""

    name: str
    kind: str
    sym: ca.SX
    start: np.ndarray
    lb: np.ndarray
    ub: np.ndarray
    der: ca.SX | None = None
    unit: str = ""
    fixed: np.ndarray | None = None  # per element: the start is an initial condition (Modelica's fixed)
    given: bool = False  # the start was given (not the default 0)
    smoothing: bool = False  # a parameter that is a smoothing width (Model.smoothing)

    @property
    def size(self) -> int:
        return int(self.sym.numel())


def flatten_model(model: Any) -> FlatDAE:
    """Flatten a model into a semi-explicit DAE (the work of :meth:`gtmodel.modeling.Model.flatten`).

    Parameters
    ----------
    model : Model
        The model, with its declared variables, equations and outputs.

    Returns
    -------
    FlatDAE
        The semi-explicit DAE and its CasADi Functions.

    Raises
    ------
    ModelError
        One message naming equations and variables: structurally singular, over- or
        under-determined (as :func:`~gtmodel.modeling.structure.analysis.check_structure`
        says); or, for a structurally regular model, of higher index (the states whose
        ``der()`` the equations cannot give, or the algebraic equations that do not fix
        the algebraic variables), with the way out (``structural_simplify``).
    """
    by_kind = {k: [v for v in model._vars.values() if v.kind == k] for k in _KINDS}

    def cat(vs: list[_Var], attr: str = "sym") -> ca.SX:
        return ca.vertcat(*[getattr(v, attr) for v in vs]) if vs else ca.SX(0, 1)

    def slices(vs: list[_Var]) -> dict[str, slice]:
        out, k = {}, 0
        for v in vs:
            out[v.name] = slice(k, k + v.size)
            k += v.size
        return out

    def names(vs: list[_Var]) -> list[str]:
        return [n for v in vs for n in expand_names(v.name, v.size)]

    def arr(vs: list[_Var], attr: str) -> np.ndarray:
        return np.concatenate([getattr(v, attr) for v in vs]) if vs else np.zeros(0)

    states, algs = by_kind["state"], by_kind["algebraic"]
    x, xdot, z = cat(states), cat(states, "der"), cat(algs)
    u, p = cat(by_kind["input"]), cat(by_kind["parameter"])
    nx, nz = int(x.numel()), int(z.numel())
    x_names, z_names = names(states), names(algs)

    res = ca.vertcat(*[r for _, r in model._equations]) if model._equations else ca.SX(0, 1)
    neq = int(res.numel())
    if neq != nx + nz:
        counts = f"model {model.name!r} has {neq} scalar equations but {nx} states + {nz} algebraic variables"
        found = structure_parts(incidence(scalarize(model)))
        raise ModelError("; ".join([f"{counts} = {nx + nz} unknowns ({found[0] if found else 'singular'})",
                                    *(found[1] if found else [])]))
    subst_rows = {  # scalar rows of the substitute_der equations
        k for j, (lo, hi) in enumerate(_row_ranges(model._equations)) if j in model._der_substituted
        for k in range(lo, hi)
    }
    diff_rows = [i for i in range(neq) if nx and i not in subst_rows and ca.depends_on(res[i], xdot)]
    alg_rows = [i for i in range(neq) if i not in set(diff_rows)]
    res_d = res[diff_rows] if diff_rows else ca.SX(0, 1)
    res_a = res[alg_rows] if alg_rows else ca.SX(0, 1)

    # --- differential part: M xdot + b = 0
    if nx:
        M = ca.jacobian(res_d, xdot)
        missing = [x_names[j] for j in range(nx) if M[:, j].nnz() == 0]
        if missing:
            raise _refusal(model, f"der() of state(s) {missing} appear(s) in no equation")
        if len(diff_rows) != nx or ca.sprank(M) < nx:
            raise _refusal(
                model, f"the equations containing der() ({len(diff_rows)} scalar) cannot be solved for der() of "
                f"the states {_unmatched(M, x_names)} (of the {nx} states {x_names}; not index 1): two or more states "
                f"are dependent (equations {[_row_labels(model._equations)[i] for i in diff_rows]})"
            )
        b = ca.substitute(res_d, xdot, ca.SX.zeros(nx))
        if not ca.depends_on(M, ca.vertcat(x, z, u, p, model._time)) and M.is_constant():
            Mn = np.array(ca.DM(M))
            if np.linalg.matrix_rank(Mn) < nx:
                labels = _row_labels(model._equations)
                raise ModelError(
                    f"model {model.name!r}: the der() coefficient matrix of equations "
                    f"{[labels[i] for i in diff_rows]} is singular for states {x_names} (numerically: the "
                    "equations are dependent in der())"
                )
            if np.allclose(Mn, np.eye(nx)):
                f = -b
            else:
                f = ca.SX(ca.DM(np.linalg.solve(Mn, np.eye(nx)))) @ (-b)
        else:
            f = ca.solve(M, -b)
        f = ca.simplify(f) if f.numel() < 50 else f
    else:
        f = ca.SX(0, 1)
    if subst_rows and nx:
        res_a = ca.substitute(res_a, xdot, f)

    # --- algebraic part: index-1 check
    if nz:
        Jz = ca.jacobian(res_a, z)
        if int(res_a.numel()) != nz or ca.sprank(Jz) < nz:
            labels = _row_labels(model._equations)
            raise _refusal(
                model, f"the algebraic equations {[labels[i] for i in alg_rows]} are not solvable for the algebraic "
                f"variables {_unmatched(Jz, z_names)} (not index 1)"
            )
    elif res_a.numel():
        # unreachable by the count check, kept for safety
        raise ModelError(f"model {model.name!r}: algebraic equations without algebraic variables")

    g = res_a
    args = [model._time, x, z, u, p]
    argn = ["t", "x", "z", "u", "p"]
    out_exprs = {
        n: (ca.substitute(e, xdot, f) if nx else e) for n, e in model._outputs.items()
    }
    ode = ca.Function(f"{casadi_name(model.name)}_ode", args, [f], argn, ["xdot"])
    alg = ca.Function(f"{casadi_name(model.name)}_alg", args, [g], argn, ["g"])
    outputs = ca.Function(
        f"{casadi_name(model.name)}_outputs", args, list(out_exprs.values()), argn, list(out_exprs.keys()),
        {"allow_duplicate_io_names": True},  # an output may be called x, z, u, p or t
    )
    return FlatDAE(
        name=model.name,
        t=model._time,
        x=x,
        z=z,
        u=u,
        p=p,
        xdot=xdot,
        ode_expr=f,
        alg_expr=g,
        output_exprs=out_exprs,
        ode=ode,
        alg=alg,
        outputs=outputs,
        x_vars=slices(states),
        z_vars=slices(algs),
        u_vars=slices(by_kind["input"]),
        p_vars=slices(by_kind["parameter"]),
        x_names=x_names,
        z_names=z_names,
        u_names=names(by_kind["input"]),
        p_names=names(by_kind["parameter"]),
        output_names=[n for k, e in out_exprs.items() for n in expand_names(k, int(e.numel()))],
        output_sizes={k: int(e.numel()) for k, e in out_exprs.items()},
        x_start=arr(states, "start"),
        z_start=arr(algs, "start"),
        p_value=arr(by_kind["parameter"], "start"),
        x_lb=arr(states, "lb"),
        x_ub=arr(states, "ub"),
        z_lb=arr(algs, "lb"),
        z_ub=arr(algs, "ub"),
        u_lb=arr(by_kind["input"], "lb"),
        u_ub=arr(by_kind["input"], "ub"),
    )


def _refusal(model: Any, detail: str) -> ModelError:
    """Why ``flatten()`` refuses a model: structurally singular (the one message of the structural
    check, naming equations and variables), else of higher index (``detail``, and the way out).

    A model is blamed on its index only when Pantelides' test passes (``der(x)`` merged
    into ``x``, the equations match the unknowns one to one,
    :func:`~gtmodel.modeling.structure.analysis.check_structure`): otherwise no index
    reduction helps, and the message names the equations in excess and the variables left
    undetermined, as ``simulate()`` and ``structural_simplify`` do.
    """
    msg = structure_message(incidence(scalarize(model)), f"model {model.name!r}")
    if msg:
        return ModelError(msg)
    return ModelError(
        f"model {model.name!r}: {detail}; the model is structurally regular but of higher index (or has alias "
        "equations between states): flatten() needs an index-1 DAE: reduce it with "
        "gtmodel.modeling.structural_simplify(model) (simulate(), Optimization, problem files and codegen --model do)"
    )


def _unmatched(jac: ca.SX, names: list[str]) -> list[str]:
    """Columns of a Jacobian left unmatched by a maximum matching of its sparsity (the variables it cannot fix)."""
    rows, cols = jac.sparsity().get_triplet()
    pat = sps.csr_matrix((np.ones(len(rows), dtype=np.int8), (rows, cols)), shape=(jac.size1(), jac.size2()))
    var_to_eq = matching(pat)[1]
    return [names[j] for j in range(len(names)) if var_to_eq[j] < 0] or list(names)


def _row_labels(equations: Sequence[tuple[str, ca.SX]]) -> list[str]:
    """The label of each scalar row of the stacked residual (``"label[i]"`` for vector equations)."""
    return [name if r.numel() == 1 else f"{name}[{i}]" for name, r in equations for i in range(int(r.numel()))]


def _row_ranges(equations: Sequence[tuple[str, ca.SX]]) -> list[tuple[int, int]]:
    """Scalar row range ``[lo, hi)`` of each equation in the stacked residual."""
    out, k = [], 0
    for _, r in equations:
        out.append((k, k + int(r.numel())))
        k += int(r.numel())
    return out
