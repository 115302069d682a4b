"""Structural analysis of a model: scalar view, incidence, matching, structural check, alias elimination.

The passes of ModelingToolkit.jl's ``structural_simplify`` and of Modelica tools start from the
bipartite graph of scalar equations and scalar unknowns (Pantelides (1988); Duff & Reid
(1978)). Here:

* :func:`scalarize` turns a :class:`~gtmodel.modeling.Model` into a :class:`ScalarDAE`: one
  residual per scalar equation, one symbol per scalar unknown (states and algebraic variables;
  ``der()`` of a state is kept next to its state);
* :func:`incidence` gives the sparse equation x unknown incidence matrix (from the sparsity of
  the CasADi Jacobian, no expression walking), with ``der(x)`` merged into ``x`` by default:
  Pantelides' criterion (a DAE is solvable after differentiations iff this merged graph has a
  perfect matching);
* :func:`check_structure` matches equations to unknowns (``scipy.sparse.csgraph.
  maximum_bipartite_matching``) and, when no perfect matching exists, raises ONE
  :class:`~gtmodel.errors.ModelError` naming the over-determined equations and the
  under-determined variables (the coarse Dulmage-Mendelsohn decomposition: alternating paths
  from the unmatched equations and from the unmatched variables);
* :func:`eliminate_aliases` removes the equations ``a = b`` and ``a = -b`` between unknowns
  (connection aliases), keeping the eliminated variables as observed expressions.
"""

from __future__ import annotations

import logging
from collections import deque
from dataclasses import dataclass, field
from typing import Any

import casadi as ca
import numpy as np

from gtmodel._lazy import lazy_module
from gtmodel.errors import InputError, ModelError
from gtmodel.modeling.dae import expand_names

#: SciPy's sparse matrices and graph algorithms (``sps.csgraph``), imported on first use (~1 s of imports a
#: problem that never checks a model's structure should not pay for).
sps = lazy_module("scipy.sparse")

__all__ = [
    "ScalarDAE",
    "Incidence",
    "scalarize",
    "incidence",
    "matching",
    "dulmage_mendelsohn",
    "check_structure",
    "require_regular",
    "pattern_rows",
    "eliminate_aliases",
]

_log = logging.getLogger("gtmodel")


@dataclass
class ScalarDAE:
    """A model seen as scalar residuals ``0 = F(t, der(x), x, z, u, p)`` over scalar unknowns.

    Parameters
    ----------
    name : str
        Model name.
    t : casadi.SX
        Time symbol (1x1), s.
    var_syms : list of casadi.SX
        Scalar unknowns: state elements, then algebraic elements (declaration order).
    var_names : list of str
        Their expanded names (``"T[0]"`` style).
    var_kinds : list of str
        ``"state"`` or ``"algebraic"`` per unknown.
    der_syms : dict of int to casadi.SX
        Unknown index of a state element -> its ``der()`` symbol.
    start : numpy.ndarray
        Start values of the unknowns, shape ``(n,)``.
    eq_res : list of casadi.SX
        Scalar residuals of the equations.
    eq_names : list of str
        Equation labels (``"label[i]"`` for the elements of a vector equation).
    init_res, init_names : list
        Scalar residuals and labels of the initial equations.
    p, u : casadi.SX
        Parameter and input vectors of the model.
    p_value, u_start : numpy.ndarray
        Parameter values and input start values.
    u_names : list of str
        Expanded input names.
    outputs : dict of str to casadi.SX
        Declared outputs (may contain ``der()`` symbols).
    observed : dict of str to casadi.SX
        Every original scalar unknown name (and ``"der(name)"`` of each state element) ->
        its expression in the remaining unknowns (identity, or ``+-`` an alias).
    aliases : dict of str to tuple
        Eliminated unknown name -> ``(sign, kept name)``.
    fixed_start : dict of str to float
        Original scalar unknown name -> its start value, for the starts declared
        ``fixed=True`` (initial conditions; kept by name through alias elimination).
    given_start : dict of str to float
        Original scalar unknown name -> start value, for every start that was given (not
        the default 0), fixed or not.
    """

    name: str
    t: ca.SX
    var_syms: list[ca.SX]
    var_names: list[str]
    var_kinds: list[str]
    der_syms: dict[int, ca.SX]
    start: np.ndarray
    eq_res: list[ca.SX]
    eq_names: list[str]
    init_res: list[ca.SX]
    init_names: list[str]
    p: ca.SX
    u: ca.SX
    p_value: np.ndarray
    u_start: np.ndarray
    u_names: list[str]
    outputs: dict[str, ca.SX]
    observed: dict[str, ca.SX] = field(default_factory=dict)
    aliases: dict[str, tuple[float, str]] = field(default_factory=dict)
    fixed_start: dict[str, float] = field(default_factory=dict)
    given_start: dict[str, float] = field(default_factory=dict)

    @property
    def n_vars(self) -> int:
        """Number of scalar unknowns."""
        return len(self.var_syms)

    @property
    def n_eqs(self) -> int:
        """Number of scalar equations."""
        return len(self.eq_res)


@dataclass
class Incidence:
    """Sparse incidence of scalar equations (rows) versus scalar unknowns (columns).

    Parameters
    ----------
    matrix : scipy.sparse.csr_matrix
        ``(n_eqs, n_vars)``, 1 where equation ``i`` depends on unknown ``j``.
    eq_names, var_names : list of str
        Row and column labels.
    """

    matrix: sps.csr_matrix
    eq_names: list[str]
    var_names: list[str]


def _cat(syms: list[ca.SX]) -> ca.SX:
    return ca.vertcat(*syms) if syms else ca.SX(0, 1)


def scalarize(model: Any) -> ScalarDAE:
    """The scalar view of a model (no transformation).

    Parameters
    ----------
    model : Model
        A :class:`gtmodel.modeling.Model`.

    Returns
    -------
    ScalarDAE
        One residual per scalar equation and one symbol per scalar unknown.

    Raises
    ------
    InputError
        If ``model`` is not a :class:`~gtmodel.modeling.Model`.
    """
    if not all(hasattr(model, a) for a in ("_vars", "_equations", "_outputs", "_time")):
        raise InputError(f"model must be a gtmodel.modeling.Model, got {type(model).__name__}")
    vars_ = list(model._vars.values())
    syms, names, kinds, starts, ders = [], [], [], [], {}
    fixed_start: dict[str, float] = {}
    given_start: dict[str, float] = {}
    for kind in ("state", "algebraic"):
        for v in (w for w in vars_ if w.kind == kind):
            for j, nm in enumerate(expand_names(v.name, v.size)):
                if kind == "state":
                    ders[len(syms)] = v.der[j]
                syms.append(v.sym[j])
                names.append(nm)
                kinds.append(kind)
                starts.append(float(v.start[j]))
                if getattr(v, "given", False):
                    given_start[nm] = float(v.start[j])
                if getattr(v, "fixed", None) is not None and bool(v.fixed[j]):
                    fixed_start[nm] = float(v.start[j])

    def split(items: list[tuple[str, ca.SX]]) -> tuple[list[ca.SX], list[str]]:
        res, lab = [], []
        for label, r in items:
            for i in range(int(r.numel())):
                res.append(r[i])
                lab.append(label if r.numel() == 1 else f"{label}[{i}]")
        return res, lab

    eq_res, eq_names = split(model._equations)
    init_res, init_names = split(getattr(model, "_initial_equations", []))
    params = [v for v in vars_ if v.kind == "parameter"]
    inputs = [v for v in vars_ if v.kind == "input"]
    observed = {nm: s for nm, s in zip(names, syms)}
    observed.update({f"der({names[i]})": d for i, d in ders.items()})
    return ScalarDAE(
        name=model.name,
        t=model._time,
        var_syms=syms,
        var_names=names,
        var_kinds=kinds,
        der_syms=ders,
        start=np.array(starts, dtype=float),
        eq_res=eq_res,
        eq_names=eq_names,
        init_res=init_res,
        init_names=init_names,
        p=_cat([v.sym for v in params]),
        u=_cat([v.sym for v in inputs]),
        p_value=np.concatenate([v.start for v in params]) if params else np.zeros(0),
        u_start=np.concatenate([v.start for v in inputs]) if inputs else np.zeros(0),
        u_names=[n for v in inputs for n in expand_names(v.name, v.size)],
        outputs=dict(model._outputs),
        observed=observed,
        fixed_start=fixed_start,
        given_start=given_start,
    )


def sparsity_pattern(residuals: list[ca.SX], syms: list[ca.SX]) -> sps.csr_matrix:
    """Structural incidence ``(len(residuals), len(syms))`` from the CasADi Jacobian sparsity.

    Parameters
    ----------
    residuals : list of casadi.SX
        Scalar residuals.
    syms : list of casadi.SX
        Scalar symbols (columns).

    Returns
    -------
    scipy.sparse.csr_matrix
        0/1 matrix of ``int8``.
    """
    n, m = len(residuals), len(syms)
    if n == 0 or m == 0:
        return sps.csr_matrix((n, m), dtype=np.int8)
    sp = ca.jacobian(_cat(residuals), _cat(syms)).sparsity()
    rows, cols = sp.get_triplet()
    return sps.csr_matrix((np.ones(len(rows), dtype=np.int8), (rows, cols)), shape=(n, m))


def pattern_rows(residuals: list[ca.SX], syms: list[ca.SX]) -> list[list[int]]:
    """The structural incidence of :func:`sparsity_pattern` as lists: the columns of each residual, ascending.

    The same pattern (the CasADi Jacobian sparsity) without SciPy's sparse matrices, for the
    passes that only walk the rows (alias elimination, Pantelides): importing SciPy's sparse
    package costs ~0.15 CPU-s, a sixth of a small problem file's whole solve.

    Parameters
    ----------
    residuals : list of casadi.SX
        Scalar residuals.
    syms : list of casadi.SX
        Scalar symbols (columns).

    Returns
    -------
    list of list of int
        ``len(residuals)`` lists of column indices.
    """
    n, m = len(residuals), len(syms)
    if n == 0 or m == 0:
        return [[] for _ in range(n)]
    indptr, cols = ca.jacobian(_cat(residuals), _cat(syms)).sparsity().get_crs()
    return [list(cols[indptr[e]:indptr[e + 1]]) for e in range(n)]


def _merged_sparsity(system: ScalarDAE) -> ca.Sparsity:
    """The incidence of :func:`incidence` (``der(x)`` merged into ``x``) as a CasADi sparsity."""
    n, k = len(system.eq_res), len(system.var_syms)
    if n == 0 or k == 0:
        return ca.Sparsity(n, k)
    res = _cat(system.eq_res)
    rows, cols = ca.jacobian(res, _cat(system.var_syms)).sparsity().get_triplet()
    if system.der_syms:
        idx = sorted(system.der_syms)
        drows, dcols = ca.jacobian(res, _cat([system.der_syms[i] for i in idx])).sparsity().get_triplet()
        rows, cols = list(rows) + list(drows), list(cols) + [idx[c] for c in dcols]
    return ca.Sparsity.triplet(n, k, list(rows), list(cols))  # duplicates merged


def require_regular(system: ScalarDAE | Any) -> None:
    """:func:`check_structure` without building its incidence when the structure is regular.

    Pantelides' test (a perfect matching of the merged incidence) as CasADi's structural
    rank (:func:`casadi.sprank`, the maximum matching of CSparse's ``cs_maxtrans``): equal
    to the number of equations and of unknowns, the model passes at the cost of one Jacobian
    sparsity; otherwise :func:`check_structure` names the equations and variables (with
    SciPy's matching and the Dulmage-Mendelsohn decomposition).

    Parameters
    ----------
    system : ScalarDAE or Model
        A scalar DAE, or a model (scalarised here).

    Raises
    ------
    ModelError
        As :func:`check_structure`: over-determined, under-determined or structurally singular.
    """
    sys_ = system if isinstance(system, ScalarDAE) else scalarize(system)
    sp = _merged_sparsity(sys_)
    n, k = sp.size1(), sp.size2()
    if n == k and (n == 0 or ca.sprank(sp) == n):
        return
    check_structure(sys_)


def incidence(system: ScalarDAE, merge_derivatives: bool = True) -> Incidence:
    """Incidence matrix of the equations versus the unknowns.

    Parameters
    ----------
    system : ScalarDAE
        From :func:`scalarize` (or :func:`eliminate_aliases`).
    merge_derivatives : bool, optional
        If True (default), an equation containing ``der(x)`` is incident to ``x``
        (Pantelides (1988), the graph whose perfect matching decides solvability); if False,
        the columns are the states, their ``der()`` (named ``"der(x)"``) and the algebraics.

    Returns
    -------
    Incidence
        The sparse matrix and its labels.
    """
    syms, names = list(system.var_syms), list(system.var_names)
    if merge_derivatives:
        mat = sparsity_pattern(system.eq_res, syms)
        if system.der_syms:
            idx = sorted(system.der_syms)
            dmat = sparsity_pattern(system.eq_res, [system.der_syms[i] for i in idx]).tocsc()
            extra = sps.csr_matrix(
                (np.ones(dmat.nnz, dtype=np.int8), (dmat.tocoo().row, np.asarray(idx)[dmat.tocoo().col])),
                shape=mat.shape,
            )
            mat = ((mat + extra) > 0).astype(np.int8).tocsr()
        return Incidence(mat, list(system.eq_names), names)
    idx = sorted(system.der_syms)
    syms += [system.der_syms[i] for i in idx]
    names += [f"der({system.var_names[i]})" for i in idx]
    return Incidence(sparsity_pattern(system.eq_res, syms), list(system.eq_names), names)


def matching(matrix: sps.spmatrix) -> tuple[np.ndarray, np.ndarray]:
    """Maximum bipartite matching of rows (equations) and columns (unknowns).

    Parameters
    ----------
    matrix : scipy.sparse matrix
        ``(n_eqs, n_vars)`` incidence.

    Returns
    -------
    eq_to_var : numpy.ndarray
        ``(n_eqs,)`` matched column per row, ``-1`` if unmatched.
    var_to_eq : numpy.ndarray
        ``(n_vars,)`` matched row per column, ``-1`` if unmatched.
    """
    m = sps.csr_matrix(matrix)
    n, k = m.shape
    if n == 0 or k == 0:
        return np.full(n, -1), np.full(k, -1)
    eq_to_var = sps.csgraph.maximum_bipartite_matching(m, perm_type="column")
    var_to_eq = np.full(k, -1)
    for i, j in enumerate(eq_to_var):
        if j >= 0:
            var_to_eq[j] = i
    return np.asarray(eq_to_var), var_to_eq


def dulmage_mendelsohn(matrix: sps.spmatrix) -> dict[str, list[int]]:
    """Coarse Dulmage-Mendelsohn decomposition (over- and under-determined parts).

    Parameters
    ----------
    matrix : scipy.sparse matrix
        ``(n_eqs, n_vars)`` incidence.

    Returns
    -------
    dict
        ``"over_eqs"``/``"over_vars"``: equations reachable by alternating paths from an
        unmatched equation and the variables on those paths (more equations than
        variables); ``"under_eqs"``/``"under_vars"``: the same from the unmatched variables
        (more variables than equations); ``"unmatched_eqs"``/``"unmatched_vars"``.
    """
    m = sps.csr_matrix(matrix)
    mc = m.tocsc()
    eq_to_var, var_to_eq = matching(m)
    n, k = m.shape
    # over-determined: eq -> (edge) var -> (matching) eq
    seen_e = set(int(i) for i in np.nonzero(eq_to_var < 0)[0])
    seen_v: set[int] = set()
    queue = deque(seen_e)
    while queue:
        e = queue.popleft()
        for v in m.indices[m.indptr[e]:m.indptr[e + 1]]:
            v = int(v)
            if v not in seen_v:
                seen_v.add(v)
                e2 = int(var_to_eq[v])
                if e2 >= 0 and e2 not in seen_e:
                    seen_e.add(e2)
                    queue.append(e2)
    over_eqs, over_vars = sorted(seen_e), sorted(seen_v)
    # under-determined: var -> (edge) eq -> (matching) var
    seen_v = set(int(j) for j in np.nonzero(var_to_eq < 0)[0])
    seen_e = set()
    queue = deque(seen_v)
    while queue:
        v = queue.popleft()
        for e in mc.indices[mc.indptr[v]:mc.indptr[v + 1]]:
            e = int(e)
            if e not in seen_e:
                seen_e.add(e)
                v2 = int(eq_to_var[e])
                if v2 >= 0 and v2 not in seen_v:
                    seen_v.add(v2)
                    queue.append(v2)
    return {
        "over_eqs": over_eqs,
        "over_vars": over_vars,
        "under_eqs": sorted(seen_e),
        "under_vars": sorted(seen_v),
        "unmatched_eqs": [int(i) for i in np.nonzero(eq_to_var < 0)[0]],
        "unmatched_vars": [int(j) for j in np.nonzero(var_to_eq < 0)[0]],
    }


def structure_message(inc: Incidence, what: str) -> str | None:
    """The one-message diagnosis of an incidence without a perfect matching (None if it has one).

    Parameters
    ----------
    inc : Incidence
        Equations x unknowns.
    what : str
        Subject of the message (e.g. ``"model 'pendulum'"``).

    Returns
    -------
    str or None
        ``"<what> is structurally singular / over-determined / under-determined: ..."``
        naming the equations in excess and the variables left undetermined.
    """
    found = structure_parts(inc)
    if found is None:
        return None
    kind, parts = found
    n, k = inc.matrix.shape
    return "; ".join([f"{what} is {kind} ({n} scalar equations, {k} unknowns)", *parts])


def structure_parts(inc: Incidence) -> tuple[str, list[str]] | None:
    """The diagnosis of :func:`structure_message` in pieces: the kind and the named parts.

    Parameters
    ----------
    inc : Incidence
        Equations x unknowns.

    Returns
    -------
    tuple or None
        ``(kind, parts)``: ``"over-determined"``, ``"under-determined"`` or
        ``"structurally singular"``, and the sentences naming the equations in excess and
        the variables left undetermined; None if the incidence has a perfect matching.
    """
    n, k = inc.matrix.shape
    dm = dulmage_mendelsohn(inc.matrix)
    if not dm["unmatched_eqs"] and not dm["unmatched_vars"]:
        return None
    kind = "over-determined" if n > k else "under-determined" if n < k else "structurally singular"
    parts = []
    if dm["unmatched_eqs"]:
        parts.append(
            f"equations {[inc.eq_names[i] for i in dm['over_eqs']]} over-determine "
            f"variables {[inc.var_names[j] for j in dm['over_vars']]} "
            f"({len(dm['unmatched_eqs'])} equation(s) in excess)"
        )
    if dm["unmatched_vars"]:
        parts.append(
            f"variables {[inc.var_names[j] for j in dm['under_vars']]} are under-determined "
            f"(by equations {[inc.eq_names[i] for i in dm['under_eqs']]}; "
            f"{len(dm['unmatched_vars'])} equation(s) missing)"
        )
    return kind, parts


def check_structure(system: ScalarDAE | Any) -> Incidence:
    """Raise one error naming equations and variables if the model is not structurally regular.

    The test is Pantelides' (1988): ``der(x)`` merged into ``x``, the equations must match
    the unknowns one to one; otherwise no number of differentiations gives a solvable DAE.

    Parameters
    ----------
    system : ScalarDAE or Model
        A scalar DAE, or a model (scalarised here).

    Returns
    -------
    Incidence
        The merged incidence (when the check passes).

    Raises
    ------
    ModelError
        One message: over-determined (the equations in excess and the variables they
        over-determine), under-determined (the variables without equations) or
        structurally singular (both, with equal counts).
    """
    sys_ = system if isinstance(system, ScalarDAE) else scalarize(system)
    inc = incidence(sys_)
    msg = structure_message(inc, f"model {sys_.name!r}")
    if msg:
        raise ModelError(msg)
    return inc


def _alias_of(res: ca.SX, pair: ca.SX) -> float | None:
    """``sign`` if ``res`` is ``c (pair[0] - sign pair[1])`` with ``sign = +-1``, else None."""
    others = [v for v in ca.symvar(res) if not ca.depends_on(v, pair)]
    if others or not ca.is_linear(res, pair):
        return None
    jac = ca.jacobian(res, pair)
    if not jac.is_constant():
        return None
    a, b = (float(v) for v in np.array(ca.DM(jac)).ravel())
    const = ca.substitute(res, pair, ca.SX.zeros(2))
    if not const.is_constant() or float(ca.DM(const)) != 0.0 or a == 0.0 or abs(a) != abs(b):
        return None
    return -b / a


def eliminate_aliases(system: ScalarDAE) -> ScalarDAE:
    """Remove alias equations ``a = b`` / ``a = -b`` between unknowns (MTK's alias elimination).

    The alias equations (exactly two unknowns, linear with opposite or equal constant
    coefficients, nothing else) join the unknowns into classes (union-find with signs); each
    class keeps one representative — its first state, else its first variable — and every
    other member is replaced by ``+-`` the representative (``der()`` too for states). An alias
    equation closing a cycle in a class is kept as an equation. The eliminated variables stay
    available through ``observed`` (for results and outputs). Start values are never lost:
    the fixed starts stay initial conditions by name (``fixed_start``, solved by
    :mod:`gtmodel.modeling.structure.initialization`), and the representative's guess is
    the start of the class's first fixed member, else of its first member with a given
    start, else its own.

    Parameters
    ----------
    system : ScalarDAE
        From :func:`scalarize`.

    Returns
    -------
    ScalarDAE
        A new scalar DAE without the alias equations and the eliminated unknowns.
    """
    n = system.n_vars
    rows = pattern_rows(system.eq_res, system.var_syms)
    parent = list(range(n))
    sign_to_parent = [1.0] * n

    def find(v: int) -> tuple[int, float]:
        s = 1.0
        while parent[v] != v:
            s *= sign_to_parent[v]
            v = parent[v]
        return v, s

    kept_res, kept_names = [], []
    for e, (res, name) in enumerate(zip(system.eq_res, system.eq_names)):
        cols = rows[e]
        sign = None
        if len(cols) == 2:
            i, j = int(cols[0]), int(cols[1])
            sign = _alias_of(res, ca.vertcat(system.var_syms[i], system.var_syms[j]))
        if sign is None:
            kept_res.append(res)
            kept_names.append(name)
            continue
        (ri, si), (rj, sj) = find(i), find(j)
        if ri == rj:  # a cycle: keep the equation
            kept_res.append(res)
            kept_names.append(name)
            continue
        # v_i = sign v_j, v_i = si r_i, v_j = sj r_j  =>  r_i = si sign sj r_j
        parent[ri] = rj
        sign_to_parent[ri] = si * sign * sj
    classes: dict[int, list[int]] = {}
    for v in range(n):
        classes.setdefault(find(v)[0], []).append(v)
    rep_of: dict[int, tuple[int, float]] = {}
    start = system.start.copy()
    for root, members in classes.items():
        states = [v for v in members if system.var_kinds[v] == "state"]
        rep = states[0] if states else members[0]
        s_rep = find(rep)[1]
        for v in members:
            rep_of[v] = (rep, find(v)[1] * s_rep)  # v = s_v root = s_v s_rep rep (s_rep = +-1)
        for table in (system.fixed_start, system.given_start):  # the guess of the class
            named = [v for v in [rep] + members if system.var_names[v] in table]
            if named:
                start[rep] = rep_of[named[0]][1] * table[system.var_names[named[0]]]
                break
    subs_from, subs_to = [], []
    aliases: dict[str, tuple[float, str]] = {}
    for v in range(n):
        rep, sg = rep_of[v]
        if rep == v:
            continue
        subs_from.append(system.var_syms[v])
        subs_to.append(sg * system.var_syms[rep])
        if system.var_kinds[v] == "state":
            subs_from.append(system.der_syms[v])
            subs_to.append(sg * system.der_syms[rep])
        aliases[system.var_names[v]] = (sg, system.var_names[rep])
    src, dst = _cat(subs_from), _cat(subs_to)

    def subst(items: list[ca.SX]) -> list[ca.SX]:
        if not subs_from or not items:
            return list(items)
        out = ca.substitute([ca.vec(e) for e in items], [src], [dst])
        return [ca.reshape(o, e.shape) for o, e in zip(out, items)]

    keep_idx = [v for v in range(n) if rep_of[v][0] == v]
    remap = {old: new for new, old in enumerate(keep_idx)}
    out_names = list(system.outputs)
    obs_names = list(system.observed)
    if aliases:
        _log.debug("alias elimination in %s: %d aliases", system.name, len(aliases))
    return ScalarDAE(
        name=system.name,
        t=system.t,
        var_syms=[system.var_syms[k] for k in keep_idx],
        var_names=[system.var_names[k] for k in keep_idx],
        var_kinds=[system.var_kinds[k] for k in keep_idx],
        der_syms={remap[k]: d for k, d in system.der_syms.items() if k in remap},
        start=start[keep_idx],
        eq_res=subst(kept_res),
        eq_names=kept_names,
        init_res=subst(system.init_res),
        init_names=list(system.init_names),
        p=system.p,
        u=system.u,
        p_value=system.p_value,
        u_start=system.u_start,
        u_names=list(system.u_names),
        outputs=dict(zip(out_names, subst([system.outputs[k] for k in out_names]))),
        observed=dict(zip(obs_names, subst([system.observed[k] for k in obs_names]))),
        aliases={**system.aliases, **aliases},
        fixed_start=dict(system.fixed_start),
        given_start=dict(system.given_start),
    )
