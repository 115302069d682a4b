"""Inverse models: the inputs (forces) that produce a prescribed motion, from a model's equations.

Modelica's "inverse model" idea (Looye, Thuemmel, Kurze, Otter, Bals (2005), "Nonlinear
inverse models for control", Proc. 4th International Modelica Conference): declare which
variables are known (the prescribed motion: positions, velocities, accelerations) and
which are wanted (the actuator inputs); the same acausal equations, differentiated where
the index requires it, are solved for the wanted ones. For mechanical models with the
motion prescribed, the equations are linear in the forces and the constraint multipliers,
so the inverse model is a closed-form CasADi expression.

:func:`inverse_model` does it in five steps:

1. the model's scalar equations, differentiated by Pantelides' algorithm
   (:func:`~gtmodel.modeling.structure.index_reduction.pantelides`) so that every variable's
   derivatives up to the needed order are variables of an augmented system
   (``der(der(x))`` of a position is a variable, or ``der(v)`` where ``der(x) = v``);
2. the known variables substituted (and the parameter values, unless they stay an input);
   every other variable (and the inputs named unknown) must be determined: a full
   matching of the remaining unknowns to the equations (minimum weight,
   ``scipy.sparse.csgraph.min_weight_full_bipartite_matching``, so that an unknown is
   preferably computed from an equation linear in it with a coefficient that depends on
   known values only); without one, ONE :class:`~gtmodel.errors.ModelError` names the
   undetermined variables and their equations (the under-determined part of the
   Dulmage-Mendelsohn decomposition);
3. the block lower-triangular form of the matched system (strongly connected components,
   the BLT of Modelica tools); every block must be linear in its own unknowns;
4. the blocks grouped in layers, each linear in all its unknowns once the earlier layers
   are known (for a mechanism: positions, velocities, accelerations with the forces), and
   each layer solved symbolically (``casadi.solve``);
5. the equations left unmatched (e.g. the position-level closure constraints when the
   cart positions and the TCP are both prescribed) are consistency conditions of the
   prescribed motion, returned as the output ``residual``. Where they are linear in a
   layer's unknowns (the motion over-prescribed: more known accelerations than degrees of
   freedom), they are solved with that layer in the least-squares sense, so that the
   result does not depend on which rows the structural matching picked (a picked row
   may degenerate at a configuration, e.g. a rod direction component passing zero); the
   layer's rows are then all reported in ``residual``.
"""

from __future__ import annotations

import logging
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import casadi as ca
import numpy as np

from gtmodel._lazy import lazy_module
from gtmodel.errors import InputError, ModelError
from gtmodel.modeling.dae import _vector_value, casadi_name, expand_names
from gtmodel.modeling.structure.index_reduction import pantelides
from gtmodel.modeling.structure.analysis import check_structure, dulmage_mendelsohn, scalarize

#: Imported on first use (PEP 562 lazy module): the solve path of a problem file need not pay for it.
sps = lazy_module("scipy.sparse")  # and its graph algorithms, sps.csgraph

__all__ = ["InverseModel", "inverse_model"]

_log = logging.getLogger("gtmodel")

#: Matching weights: an unknown computed from an equation linear in it with a coefficient of
#: known values only; linear with a coefficient depending on other unknowns; nonlinear in it.
_W_CONSTANT, _W_COUPLED, _W_NONLINEAR = 1.0, 10.0, 1000.0
#: Longest list of names quoted in an error message.
_MAX_NAMES = 12


@dataclass(frozen=True)
class InverseModel:
    """The inverse model of :func:`inverse_model`: a CasADi Function and its description.

    Parameters
    ----------
    function : casadi.Function
        Inputs: the known variables in the order given (each of its declared size), then
        ``p`` (the parameter vector) if requested; outputs: the unknown variables in the
        order given, then ``residual`` (the consistency conditions, zero for a consistent
        prescribed motion).
    known, unknown : list of str
        The names of the inputs and outputs.
    residual_names : list of str
        Labels of the equations in ``residual`` (``"der(link1.length)"`` ...).
    layer_sizes : list of int
        Numbers of scalar unknowns of the layers solved one after the other.
    p_names : list of str
        Expanded parameter names (the order of the ``p`` input, if any).
    p_value : numpy.ndarray
        The parameter values used (embedded, or the defaults for the ``p`` input).
    """

    function: ca.Function
    known: list[str]
    unknown: list[str]
    residual_names: list[str]
    layer_sizes: list[int]
    p_names: list[str]
    p_value: np.ndarray


def _cat(syms: Sequence[ca.SX]) -> ca.SX:
    return ca.vertcat(*syms) if syms else ca.SX(0, 1)


def _names_list(names: Any, what: str) -> list[str]:
    if isinstance(names, str) or not isinstance(names, Sequence) or not all(isinstance(n, str) for n in names):
        raise InputError(f"{what}: expected a list of variable names, got {names!r}")
    dup = sorted({n for n in names if list(names).count(n) > 1})
    if dup:
        raise InputError(f"{what}: names listed twice: {dup}")
    return list(names)


def _quote(names: Sequence[str]) -> str:
    names = list(names)
    more = f" ... ({len(names)} in all)" if len(names) > _MAX_NAMES else ""
    return f"{names[:_MAX_NAMES]}{more}"


def _parameters(model: Any, p: Mapping[str, Any] | None) -> tuple[list[str], np.ndarray, ca.SX]:
    params = [v for v in model._vars.values() if v.kind == "parameter"]
    values = {v.name: v.start.copy() for v in params}
    if p is not None:
        if not isinstance(p, Mapping):
            raise InputError(f"p: expected a mapping of parameter names to values, got {type(p).__name__}")
        for name, value in p.items():
            if name not in values:
                raise InputError(f"p: model {model.name!r} has no parameter {name!r}; parameters: {_quote(sorted(values))}")
            values[name] = _vector_value(value, values[name].size, f"p[{name!r}]")
            if not np.all(np.isfinite(values[name])):
                raise InputError(f"p[{name!r}]: expected finite values, got {value!r}")
    names = [n for v in params for n in expand_names(v.name, v.size)]
    vec = np.concatenate([values[v.name] for v in params]) if params else np.zeros(0)
    return names, vec, _cat([v.sym for v in params])


class _Resolver:
    """Maps user names (``"plate.r"``, ``"der(plate.v)"``, ``"der(der(cart1.q))"``) to scalar symbols."""

    def __init__(self, model: Any, aug: Any) -> None:
        self.model = model
        self.system = aug.system
        self.index = {nm: k for k, nm in enumerate(aug.names)}
        self.syms = aug.syms
        self.inputs = {nm: self.system.u[k] for k, nm in enumerate(self.system.u_names)}
        self.kinematic = self._kinematic_pairs(aug)

    @staticmethod
    def _kinematic_pairs(aug: Any) -> dict[str, tuple[float, str]]:
        """``a der(x) + b w = 0`` equations (x, w states): ``"der(x)"`` -> ``(-b/a, "w")`` (element names)."""
        s = aug.system
        display = {str(s.var_syms[k].name()): s.var_names[k] for k in s.der_syms}
        ders = {str(d.name()): f"der({s.var_names[k]})" for k, d in s.der_syms.items()}
        out: dict[str, tuple[float, str]] = {}
        for res in s.eq_res:
            syms = ca.symvar(res)
            if len(syms) != 2 or not ca.is_linear(res, _cat(syms)):
                continue
            names = [str(sym.name()) for sym in syms]
            d = [k for k, n in enumerate(names) if n in ders]
            w = [k for k, n in enumerate(names) if n in display]
            jac = ca.jacobian(res, _cat(syms))
            const = ca.substitute(res, _cat(syms), ca.SX.zeros(2))
            if len(d) != 1 or len(w) != 1 or not jac.is_constant() or not (const.is_constant() and float(ca.DM(const)) == 0.0):
                continue
            coef = np.array(ca.DM(jac)).ravel()
            out[ders[names[d[0]]]] = (-coef[w[0]] / coef[d[0]], display[names[w[0]]])
        return out

    def scalar(self, name: str, what: str) -> tuple[ca.SX, float]:
        """The symbol of one scalar element name and the sign with which it equals the user's."""
        if name in self.index:
            return self.syms[self.index[name]], 1.0
        if name in self.inputs:
            return self.inputs[name], 1.0
        m = re.fullmatch(r"der\((.*)\)", name)
        if m and m.group(1) in self.kinematic:  # der(der(x)) = +-der(w) where der(x) = +-w
            sign, w = self.kinematic[m.group(1)]
            sym, s2 = self.scalar(f"der({w})", what)
            return sym, sign * s2
        raise ModelError(f"{what}: {name!r} is not a variable of model {self.model.name!r} or of its index-reduced form")

    def resolve(self, name: str, what: str) -> tuple[list[ca.SX], list[float], list[str]]:
        """Symbols, signs and element names of a user name."""
        if name in ("time", "t"):
            return [self.system.t], [1.0], ["time"]
        depth, base = 0, name.strip()
        m = re.fullmatch(r"der\((.*)\)", base)
        while m:
            depth, base = depth + 1, m.group(1).strip()
            m = re.fullmatch(r"der\((.*)\)", base)
        var = self.model._vars.get(base)
        if var is not None and var.kind != "parameter":
            elements = expand_names(base, var.size)
        elif re.fullmatch(r".+\[\d+\]", base) and base.rsplit("[", 1)[0] in self.model._vars:
            elements = [base]
        else:
            declared = [v.name for v in self.model._vars.values() if v.kind != "parameter"]
            raise ModelError(f"{what}: {name!r} names no state, algebraic variable or input of model "
                             f"{self.model.name!r}; declared: {_quote(declared)}")
        if depth and base.split("[")[0] in self.model._vars and self.model._vars[base.split("[")[0]].kind == "input":
            raise ModelError(f"{what}: {name!r}: derivatives of the input {base!r} are not variables of the model")
        scal = [("der(" * depth) + e + (")" * depth) for e in elements]
        pairs = [self.scalar(s, what) for s in scal]
        return [p[0] for p in pairs], [p[1] for p in pairs], scal


def _weights(res: ca.SX, unknowns: ca.SX) -> sps.csr_matrix:
    """Matching weights ``(n_eqs, n_unknowns)`` from the Jacobian and the dependence of its entries."""
    n, m = int(res.numel()), int(unknowns.numel())
    if n == 0 or m == 0:
        return sps.csr_matrix((n, m))
    jac = ca.jacobian(res, unknowns)
    rows, cols = jac.sparsity().get_triplet()
    if not rows:
        return sps.csr_matrix((n, m))
    coeff = ca.vertcat(*jac.nonzeros())
    dep = ca.jacobian(coeff, unknowns).sparsity()
    dep_rows, dep_cols = dep.get_triplet()
    depends: dict[int, set[int]] = {}
    for k, c in zip(dep_rows, dep_cols):
        depends.setdefault(k, set()).add(c)
    w = np.full(len(rows), _W_CONSTANT)
    for k, c in enumerate(cols):
        on = depends.get(k)
        if on:
            w[k] = _W_NONLINEAR if c in on else _W_COUPLED
    return sps.csr_matrix((w, (rows, cols)), shape=(n, m))


def _undetermined_message(model: Any, pattern: sps.csr_matrix, eq_names: list[str], var_names: list[str],
                          known: list[str]) -> str:
    dm = dulmage_mendelsohn(pattern)
    vars_ = [var_names[j] for j in dm["under_vars"]] or var_names
    eqs = [eq_names[i] for i in dm["under_eqs"]]
    return (
        f"inverse model of model {model.name!r}: the variables {_quote(vars_)} are not determined by the "
        f"equations {_quote(eqs)} once {_quote(known)} are known ({len(dm['unmatched_vars'])} equation(s) "
        "missing): prescribe more of the motion (positions and their derivatives) or ask for fewer unknowns"
    )


def _blocks(weights: sps.csr_matrix, eq_of: np.ndarray) -> tuple[list[list[int]], list[set[int]]]:
    """Unknowns grouped in strongly connected blocks in a topological order, and each block's predecessors."""
    m = weights.shape[1]
    pat = weights.tocsr()
    src, dst = [], []
    for v in range(m):
        e = eq_of[v]
        for w in pat.indices[pat.indptr[e]:pat.indptr[e + 1]]:
            if w != v:
                src.append(int(w))  # v is computed from an equation using w: w before v
                dst.append(v)
    graph = sps.csr_matrix((np.ones(len(src)), (src, dst)), shape=(m, m))
    ncomp, label = sps.csgraph.connected_components(graph, directed=True, connection="strong")
    members: list[list[int]] = [[] for _ in range(ncomp)]
    for v in range(m):
        members[label[v]].append(v)
    succ: list[set[int]] = [set() for _ in range(ncomp)]
    pred: list[set[int]] = [set() for _ in range(ncomp)]
    for a, b in zip(src, dst):
        la, lb = int(label[a]), int(label[b])
        if la != lb:
            succ[la].add(lb)
            pred[lb].add(la)
    indeg = [len(p) for p in pred]
    order, ready = [], [c for c in range(ncomp) if indeg[c] == 0]
    while ready:
        c = ready.pop()
        order.append(c)
        for d in succ[c]:
            indeg[d] -= 1
            if indeg[d] == 0:
                ready.append(d)
    pos = {c: k for k, c in enumerate(order)}
    return [members[c] for c in order], [{pos[p] for p in pred[c]} for c in order]


def _layers(blocks: list[list[int]], preds: list[set[int]], rows: list[ca.SX], unknowns: list[ca.SX],
            pattern: sps.csr_matrix, eq_of: np.ndarray) -> list[list[int]]:
    """Group the blocks into layers, each linear in all its unknowns (greedy, in topological order).

    A block joins the current layer when its predecessors are solved or in the layer and its
    equations stay linear in the layer's unknowns (the rows of the blocks already in the
    layer cannot use its unknowns): for a mechanism, the positions, then the velocities,
    then the accelerations with the forces. Raises ``ValueError(k)`` for a block ``k``
    that is not linear in its own unknowns.
    """
    block_of = {v: k for k, block in enumerate(blocks) for v in block}
    cols_of = [{int(c) for v in block for c in pattern.indices[pattern.indptr[eq_of[v]]:pattern.indptr[eq_of[v] + 1]]}
               for block in blocks]
    exprs = [_cat([rows[eq_of[v]] for v in block]) for block in blocks]
    done: set[int] = set()
    remaining = list(range(len(blocks)))
    layers = []
    while remaining:
        layer: set[int] = set()
        changed = True
        while changed:
            changed = False
            for k in list(remaining):
                if not preds[k] <= done | layer:
                    continue
                inside = [c for c in cols_of[k] if block_of[c] in layer or block_of[c] == k]
                if ca.is_linear(exprs[k], _cat([unknowns[c] for c in inside])):
                    layer.add(k)
                    remaining.remove(k)
                    changed = True
                elif not layer:
                    raise ValueError(k)  # ready, alone, and nonlinear in its own unknowns
        done |= layer
        layers.append(sorted(layer))
    return layers


def _solve_block(rs: ca.SX, rx: ca.SX, xs: ca.SX) -> ca.SX:
    """Solution of the linear block ``rs(xs) = 0``; with redundant rows ``rx``, in the least-squares sense.

    The redundant rows (equations left unmatched whose unknowns are all known after this
    block) make the solution independent of which rows the structural matching picked:
    where a picked row degenerates (e.g. a component of a rod direction passing zero),
    the others still determine the unknowns. Least squares by QR (``casadi.qr``,
    modified Gram-Schmidt) of the stacked rows, exact for a consistent prescribed motion.
    """
    n = int(xs.numel())
    zeros = ca.SX.zeros(n)
    if rx.numel() == 0:
        A = ca.jacobian(rs, xs)
        b = ca.substitute(rs, xs, zeros)
        return -b / A if n == 1 else ca.solve(A, -b)
    r = ca.vertcat(rs, rx)
    A = ca.jacobian(r, xs)
    b = ca.substitute(r, xs, zeros)
    Q, R = ca.qr(ca.densify(A))
    return ca.solve(R, -(Q.T @ b))


def _solve_layers(
    rows: list[ca.SX], unknowns: list[ca.SX], blocks: list[list[int]], layers: list[list[int]], eq_of: np.ndarray,
    pattern: sps.csr_matrix, matched: set[int],
) -> tuple[list[ca.SX], list[ca.SX], list[int], list[int]]:
    """Solve the layers in order; the solutions in known values, sizes, and the rows to report as residual."""
    block_of = {v: k for k, block in enumerate(blocks) for v in block}
    layer_of = {k: j for j, layer in enumerate(layers) for k in layer}
    extra: dict[int, list[int]] = {}
    for e in sorted(set(range(len(rows))) - matched):  # redundant rows: with the layer that completes them
        cols = pattern.indices[pattern.indptr[e]:pattern.indptr[e + 1]]
        if len(cols):
            extra.setdefault(max(layer_of[block_of[int(c)]] for c in cols), []).append(e)
    solved_from: list[ca.SX] = []
    solved_to: list[ca.SX] = []
    sizes: list[int] = []
    least_squares: set[int] = set()
    for j, layer in enumerate(layers):
        vs = [v for k in layer for v in blocks[k]]
        xs = _cat([unknowns[v] for v in vs])
        rs = _cat([rows[eq_of[v]] for v in vs])
        rx = _cat([rows[e] for e in extra.get(j, [])])
        if solved_from:  # the earlier solutions hold known values only: so will this one
            rs, rx = ca.substitute([rs, rx], [_cat(solved_from)], [_cat(solved_to)])
        linear = [i for i in range(int(rx.numel())) if ca.is_linear(rx[i], xs)]
        sizes.append(len(vs))
        if linear:  # least squares: the matched rows may not hold exactly either, report them too
            least_squares.update(int(eq_of[v]) for v in vs)
            solved_from.append(xs)
            solved_to.append(_solve_block(rs, _cat([rx[i] for i in linear]), xs))
            continue
        for k in layer:  # square: block by block (smaller, better conditioned systems)
            xb = _cat([unknowns[v] for v in blocks[k]])
            rb = _cat([rows[eq_of[v]] for v in blocks[k]])
            solved_to.append(_solve_block(ca.substitute(rb, _cat(solved_from), _cat(solved_to)) if solved_from else rb,
                                          ca.SX(0, 1), xb))
            solved_from.append(xb)
    checked = [i for i in range(len(rows)) if i not in matched or i in least_squares]
    return solved_from, solved_to, sizes, checked


def inverse_model(
    model: Any,
    known: Sequence[str],
    unknown: Sequence[str],
    p: Mapping[str, Any] | None = None,
    parameter_input: bool = False,
) -> InverseModel:
    """The inverse model of a (composed, possibly high-index) model, as a CasADi Function.

    Modelica's inverse-model idea (see the module docstring): with the motion prescribed
    (``known``), the model's equations and their derivatives (Pantelides' algorithm) are
    solved layer by layer for every other variable; the ones named in ``unknown`` are
    returned. Typical use: the actuator forces of a mechanism for a prescribed trajectory
    (inverse dynamics).

    Names are declared variable names (``"plate.r"``, a state, algebraic variable or
    input), single elements (``"plate.r[0]"``), derivatives ``"der(plate.v)"`` (of a
    state) and higher derivatives ``"der(der(cart1.q))"`` (a variable of the augmented
    system, or ``der(w)`` when the model has ``der(x) = w``), and ``"time"``.

    Parameters
    ----------
    model : Model
        The model (e.g. ``Component.to_model()``); structurally regular.
    known : sequence of str
        Prescribed variables, the inputs of the Function in this order. Every input of the
        model must be named in ``known`` or ``unknown``; ``"time"`` must be named when the
        equations depend on time.
    unknown : sequence of str
        Variables to return, the outputs of the Function in this order (inputs of the model,
        typically, or any other variable the equations determine).
    p : mapping of str to float or array_like, optional
        Parameter values overriding the model's (by name).
    parameter_input : bool, optional
        If True, the parameter vector is a last Function input ``p`` (the equations stay
        symbolic in it, e.g. for identification); if False (default), the values are
        embedded (a parameter equal to 0, such as a zero link mass, then drops out of the
        structure).

    Returns
    -------
    InverseModel
        The Function ``(known..., [p]) -> (unknown..., residual)`` and its description.
        Where a layer of the solution is singular (a singular configuration) the outputs
        are not finite.

    Raises
    ------
    InputError
        If ``known``/``unknown`` are not lists of names, repeat a name, overlap, ``unknown``
        is empty, or ``p`` is malformed.
    ModelError
        If a name is not a variable of the model (or of its index-reduced form), an input
        or time is neither known nor unknown, the model is structurally singular, the
        unknowns are not determined (one message naming the variables and equations), or
        a block is not linear in its unknowns (naming them).
    """
    known = _names_list(known, "known")
    unknown = _names_list(unknown, "unknown")
    if not unknown:
        raise InputError("unknown: expected at least one variable name")
    both = sorted(set(known) & set(unknown))
    if both:
        raise InputError(f"known and unknown overlap: {both}")
    p_names, p_value, p_sym = _parameters(model, p)
    system = scalarize(model)
    check_structure(system)
    aug = pantelides(system)
    resolver = _Resolver(model, aug)

    known_in: list[ca.SX] = []  # one input symbol vector per known name
    sub_from: list[ca.SX] = []
    sub_to: list[ca.SX] = []
    known_ids: set[str] = set()
    for name in known:
        syms, signs, _ = resolver.resolve(name, "known")
        inp = []
        for sym, sign in zip(syms, signs):
            if sym.name() in known_ids:
                raise InputError(f"known: {name!r} repeats an element named before")
            known_ids.add(sym.name())
            if sign == 1.0:
                inp.append(sym)
            else:
                new = ca.SX.sym(f"{sym.name()}_known")
                sub_from.append(sym)
                sub_to.append(sign * new)
                inp.append(new)
        known_in.append(_cat(inp))
    out_syms: list[tuple[list[ca.SX], list[float]]] = []
    for name in unknown:
        syms, signs, _ = resolver.resolve(name, "unknown")
        if any(s.name() in known_ids for s in syms):
            raise InputError(f"unknown: {name!r} is also known (an alias of a known variable)")
        out_syms.append((syms, signs))

    residuals = list(aug.res)
    res_all = _cat(residuals)
    if sub_from:
        res_all = ca.substitute(res_all, _cat(sub_from), _cat(sub_to))
    if not parameter_input and p_sym.numel():
        res_all = ca.substitute(res_all, p_sym, ca.DM(p_value))
    if ca.depends_on(res_all, system.t) and "time" not in known_ids:
        raise ModelError(f"inverse model of model {model.name!r}: the equations depend on time; name 'time' in known")
    unknown_inputs = {s.name() for syms, _ in out_syms for s in syms if s.name() in {str(u.name()) for u in resolver.inputs.values()}}
    free_inputs = [nm for nm, s in resolver.inputs.items() if s.name() not in known_ids and s.name() not in unknown_inputs]
    if free_inputs:
        raise ModelError(f"inverse model of model {model.name!r}: input(s) {free_inputs} are neither known nor unknown")

    unknowns = [s for s in aug.syms if s.name() not in known_ids] + [
        u for u in resolver.inputs.values() if u.name() in unknown_inputs
    ]
    display = {str(sym.name()): nm for sym, nm in zip(aug.syms, aug.names)}
    display.update({str(u.name()): nm for nm, u in resolver.inputs.items()})
    var_names = [display[str(s.name())] for s in unknowns]
    eq_names = list(aug.eq_names)
    w_all = _cat(unknowns)
    weights = _weights(res_all, w_all)
    n_eq, n_var = weights.shape
    pattern = (weights != 0).astype(np.int8).tocsr()
    try:
        if n_var > n_eq:
            raise ValueError
        var_idx, eq_idx = sps.csgraph.min_weight_full_bipartite_matching(weights.T.tocsr())
    except ValueError:
        raise ModelError(_undetermined_message(model, pattern, eq_names, var_names, known)) from None
    eq_of = np.full(n_var, -1)
    eq_of[var_idx] = eq_idx
    matched_eqs = set(int(e) for e in eq_idx)

    res_list = [res_all[i] for i in range(n_eq)]
    blocks, preds = _blocks(weights, eq_of)
    try:
        layers = _layers(blocks, preds, res_list, unknowns, pattern, eq_of)
    except ValueError as exc:
        block = blocks[exc.args[0]]
        raise ModelError(
            f"inverse model of model {model.name!r}: equations {_quote([eq_names[eq_of[v]] for v in block])} "
            f"are not linear in the variables {_quote([var_names[v] for v in block])} they determine; "
            "prescribe these (or more of the motion) as known"
        ) from None
    solved_from, solved_to, sizes, checked = _solve_layers(res_list, unknowns, blocks, layers, eq_of, pattern, matched_eqs)
    res_names = [eq_names[i] for i in checked]
    residual = _cat([res_list[i] for i in checked])
    outs = [_cat([sign * s for s, sign in zip(syms, signs)]) for syms, signs in out_syms]
    exprs = ca.substitute(outs + [residual], [_cat(solved_from)], [_cat(solved_to)]) if solved_from else outs + [residual]
    ins = list(known_in) + ([p_sym] if parameter_input else [])
    in_names = list(known) + (["p"] if parameter_input else [])
    fn = ca.Function(f"{casadi_name(model.name)}_inverse", ins, exprs, in_names, list(unknown) + ["residual"])
    free = ca.symvar(_cat([ca.vec(e) for e in exprs])) if exprs else []
    allowed = {str(s.name()) for i in ins for s in ca.symvar(i)} | {"time"}
    stray = [str(s.name()) for s in free if str(s.name()) not in allowed]
    if stray:  # cannot happen after a full matching; kept as a guard against silent zeros
        raise ModelError(f"inverse model of model {model.name!r}: the outputs still depend on {_quote(stray)}")
    _log.debug("inverse model of %s: %d layers (largest %d), %d residuals", model.name, len(sizes),
               max(sizes, default=0), len(res_names))
    return InverseModel(fn, known, unknown, res_names, sizes, p_names, p_value)
