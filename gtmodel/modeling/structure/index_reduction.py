"""Index reduction: Pantelides' algorithm and dummy derivatives, and ``structural_simplify``.

* :func:`pantelides` (Pantelides (1988), the algorithm as in ModelingToolkit.jl's
  ``pantelides!``): finds the equations that must be differentiated so that every equation
  can be matched to a highest-order derivative, and differentiates them symbolically with
  CasADi AD, ``d r/dt = dr/dt|_explicit + (dr/dv) v'`` (``casadi.jtimes``), giving an
  :class:`AugmentedDAE` (the original and differentiated equations, the variables and their
  derivatives up to the needed order);
* :func:`select_dummies` (Mattsson & Soederlind (1993), dummy derivatives): level by level,
  from the most differentiated equations down, picks as many highest derivatives as there
  are equations at that level such that their Jacobian block is nonsingular (column-pivoted
  QR at a point, or a structural matching); those derivatives become algebraic "dummy"
  variables, so the position-level constraints stay equations (no drift) and the result is
  index 1;
* :func:`reduced_system` gives the semi-explicit index-1 DAE of a selection: the states are
  the variables whose derivative was not made a dummy, ``der(state) = <its derivative
  variable>``, and every (original and differentiated) equation is algebraic;
* :func:`structural_simplify` (MTK's name): alias elimination, structural check, index
  reduction, returning a :class:`~gtmodel.modeling.Model` that ``flatten()`` accepts.

A dummy selection is valid only where its Jacobian block is nonsingular (e.g. the Cartesian
pendulum with ``x`` as dummy fails at ``x = 0``): :func:`selection_quality` measures it, and
:mod:`gtmodel.modeling.simulation.structured_simulation` re-selects during a simulation.
"""

from __future__ import annotations

import logging
import re
from dataclasses import dataclass, field
from typing import Any

import casadi as ca
import numpy as np

from gtmodel.errors import ConvergenceError, InputError, ModelError
from gtmodel.modeling.dae import _vector_value, expand_names
from gtmodel.modeling.structure.events import transfer_events
from gtmodel.modeling.structure.analysis import (
    ScalarDAE,
    eliminate_aliases,
    matching,
    pattern_rows,
    require_regular,
    scalarize,
    sparsity_pattern,
)
from gtmodel.modeling.structure.pivoting import pivoted_qr
from gtmodel.modeling.units import derivative_unit
from gtmodel.modeling.structure.initialization import (
    InconsistentInitialisation,
    fill_order,
    guess_and_conditions,
    solve_initial,
)


__all__ = [
    "AugmentedDAE",
    "Selection",
    "pantelides",
    "select_dummies",
    "selection_quality",
    "quality_function",
    "build_model",
    "reduced_system",
    "structural_simplify",
]

_log = logging.getLogger("gtmodel")

#: Highest derivative order Pantelides may create before giving up (index > 10 is not physical).
MAX_ORDER = 10


def _cat(syms: list[ca.SX]) -> ca.SX:
    return ca.vertcat(*syms) if syms else ca.SX(0, 1)


@dataclass
class AugmentedDAE:
    """The DAE after Pantelides' algorithm: equations, their derivatives, variables and theirs.

    Parameters
    ----------
    system : ScalarDAE
        The scalar DAE it was built from (after alias elimination).
    syms : list of casadi.SX
        Scalar variables: the unknowns, the ``der()`` of the states, then the derivatives
        created by the algorithm.
    names : list of str
        ``"x"``, ``"der(x)"``, ``"der(der(x))"``, ...
    order : list of int
        Differentiation order of each variable relative to its base unknown.
    diff, pred : list of int or None
        Index of the derivative / the antiderivative of each variable (None if none).
    res : list of casadi.SX
        Scalar residuals: the equations, then their derivatives.
    eq_names : list of str
        ``"label"``, ``"der(label)"``, ...
    eq_diff, eq_pred : list of int or None
        Index of the derivative / the antiderivative of each equation.
    incidence : list of list of int
        Variables each equation depends on.
    """

    system: ScalarDAE
    syms: list[ca.SX]
    names: list[str]
    order: list[int]
    diff: list[int | None]
    pred: list[int | None]
    res: list[ca.SX]
    eq_names: list[str]
    eq_diff: list[int | None]
    eq_pred: list[int | None]
    incidence: list[list[int]]

    @property
    def n_differentiated(self) -> int:
        """Number of equations Pantelides differentiated."""
        return sum(d is not None for d in self.eq_diff)

    @property
    def args(self) -> list[ca.SX]:
        """Symbolic arguments ``[t, v, u, p]`` of the functions of this DAE."""
        s = self.system
        return [s.t, _cat(self.syms), s.u, s.p]


def _add_var(aug: AugmentedDAE, v: int) -> int:
    base = aug.names[v]
    if aug.order[v] + 1 > MAX_ORDER:
        raise ModelError(f"model {aug.system.name!r}: index reduction needs der() of order > {MAX_ORDER} of {base}")
    k = len(aug.syms)
    aug.syms.append(ca.SX.sym(f"der({base})"))
    aug.names.append(f"der({base})")
    aug.order.append(aug.order[v] + 1)
    aug.diff.append(None)
    aug.pred.append(v)
    aug.diff[v] = k
    return k


def _differentiate(aug: AugmentedDAE, e: int) -> int:
    """Append d/dt of equation ``e`` (CasADi AD) and return its index."""
    r, inc, s = aug.res[e], aug.incidence[e], aug.system
    if s.u.numel() and ca.depends_on(r, s.u):
        used = [s.u_names[i] for i in range(int(s.u.numel())) if ca.depends_on(r, s.u[i])]
        raise ModelError(
            f"model {s.name!r}: equation {aug.eq_names[e]!r} must be differentiated for index reduction "
            f"but depends on input(s) {used}, whose derivatives are unknown; make the input a state "
            "or move it out of the constraint"
        )
    vs = _cat([aug.syms[v] for v in inc])
    dvs = _cat([aug.syms[aug.diff[v]] for v in inc])
    dr = ca.jtimes(r, vs, dvs) + ca.jacobian(r, s.t)
    k = len(aug.res)
    aug.res.append(dr)
    aug.eq_names.append(f"der({aug.eq_names[e]})")
    aug.eq_diff.append(None)
    aug.eq_pred.append(e)
    aug.eq_diff[e] = k
    aug.incidence.append(sorted(pattern_rows([dr], aug.syms)[0]))
    return k


def pantelides(system: ScalarDAE) -> AugmentedDAE:
    """Pantelides' algorithm: differentiate equations until each matches a highest derivative.

    Pantelides (1988), "The consistent initialization of differential-algebraic systems",
    SIAM J. Sci. Stat. Comput. 9(2), the algorithm of section 5 (augmenting paths over the
    highest-order variables; on failure every coloured variable gets a derivative and every
    coloured equation is differentiated).

    Parameters
    ----------
    system : ScalarDAE
        Structurally regular (see :func:`~gtmodel.modeling.structure.analysis.check_structure`).

    Returns
    -------
    AugmentedDAE
        The equations and variables with their derivatives.

    Raises
    ------
    ModelError
        If an equation to differentiate contains an input, or the order exceeds ``MAX_ORDER``.
    """
    n = system.n_vars
    syms = list(system.var_syms)
    names = list(system.var_names)
    aug = AugmentedDAE(
        system=system, syms=syms, names=names, order=[0] * n, diff=[None] * n, pred=[None] * n,
        res=list(system.eq_res), eq_names=list(system.eq_names), eq_diff=[None] * system.n_eqs,
        eq_pred=[None] * system.n_eqs, incidence=[],
    )
    for i in sorted(system.der_syms):
        k = len(aug.syms)
        aug.syms.append(system.der_syms[i])
        aug.names.append(f"der({names[i]})")
        aug.order.append(1)
        aug.diff.append(None)
        aug.pred.append(i)
        aug.diff[i] = k
    aug.incidence = [sorted(cols) for cols in pattern_rows(aug.res, aug.syms)]
    assign: dict[int, int] = {}

    def augment(e: int, ceq: set[int], cvar: set[int]) -> bool:
        ceq.add(e)
        active = [v for v in aug.incidence[e] if aug.diff[v] is None]
        for v in active:
            if v not in assign:
                assign[v] = e
                return True
        for v in active:
            if v not in cvar:
                cvar.add(v)
                if augment(assign[v], ceq, cvar):
                    assign[v] = e
                    return True
        return False

    for k in range(system.n_eqs):
        e = k
        while True:
            ceq: set[int] = set()
            cvar: set[int] = set()
            if augment(e, ceq, cvar):
                break
            for v in sorted(cvar):
                _add_var(aug, v)
            for q in sorted(ceq):
                _differentiate(aug, q)
            for v in cvar:
                assign[aug.diff[v]] = aug.eq_diff[assign[v]]
            e = aug.eq_diff[e]
    _log.debug("pantelides on %s: %d equations differentiated", system.name, aug.n_differentiated)
    return aug


@dataclass(frozen=True)
class Selection:
    """A dummy-derivative selection (Mattsson & Soederlind (1993)).

    Parameters
    ----------
    levels : tuple
        One ``(equations, candidates, chosen)`` triple of index tuples per level, from the
        most differentiated equations down.
    dummies : frozenset of int
        All chosen derivative variables (they become algebraic).
    """

    levels: tuple[tuple[tuple[int, ...], tuple[int, ...], tuple[int, ...]], ...]
    dummies: frozenset[int] = field(default_factory=frozenset)


def _jacobian_function(aug: AugmentedDAE, eqs: list[int], cand: list[int]) -> ca.Function:
    g = _cat([aug.res[e] for e in eqs])
    z = _cat([aug.syms[v] for v in cand])
    return ca.Function("dd_jac", aug.args, [ca.densify(ca.jacobian(g, z))])


def select_dummies(aug: AugmentedDAE, point: tuple | None = None, avoid: frozenset[int] = frozenset()) -> Selection:
    """Choose the dummy derivatives, numerically at a point or structurally.

    Mattsson & Soederlind (1993), "Index reduction in differential-algebraic equations using
    dummy derivatives", SIAM J. Sci. Comput. 14(3), the algorithm of section 3: at level
    ``i`` the equations ``g_i`` (differentiated ones, highest derivative first) and the
    candidates ``z_i`` (highest derivatives; at the next levels the antiderivatives of the
    chosen ones); pick ``len(g_i)`` columns of ``dg_i/dz_i`` forming a nonsingular block.

    Parameters
    ----------
    aug : AugmentedDAE
        From :func:`pantelides`.
    point : tuple, optional
        ``(t, v, u, p)``: time (s), all variable values ``(len(aug.syms),)``, inputs and
        parameters; columns are then chosen by column-pivoted QR (the best-conditioned
        block, greedily). Without it (or if the block is singular there) the choice is a
        structural matching.
    avoid : frozenset of int, optional
        Candidate variables to leave out of the numeric choice when the others give a
        nonsingular block (Modelica's ``stateSelect = prefer`` for their antiderivatives:
        e.g. the states a when-clause reinitialises); default none.

    Returns
    -------
    Selection
        The levels and the dummy variables.

    Raises
    ------
    ModelError
        If no structurally nonsingular choice exists at some level.
    """
    g = [e for e in range(len(aug.res)) if aug.eq_pred[e] is not None and aug.eq_diff[e] is None]
    cand = sorted({v for e in g for v in aug.incidence[e] if aug.diff[v] is None and aug.pred[v] is not None})
    levels = []
    dummies: set[int] = set()
    while g:
        chosen = None
        if point is not None:
            G = np.array(_jacobian_function(aug, g, cand)(*point))
            if G.size and np.all(np.isfinite(G)):
                cols = [k for k, v in enumerate(cand) if v not in avoid]
                for pool in ([cols] if len(cols) < len(cand) else []) + [list(range(len(cand)))]:
                    if len(pool) < len(g):
                        continue
                    d, piv = pivoted_qr(G[:, pool])
                    if len(d) >= len(g) and d[len(g) - 1] > 1e-10 * max(d[0], 1e-300):
                        chosen = sorted(cand[pool[k]] for k in piv[: len(g)])
                        break
        if chosen is None:
            if point is not None:
                _log.warning(
                    "model %s: the dummy-derivative block of %s is singular at the given point; "
                    "choosing structurally", aug.system.name, [aug.eq_names[e] for e in g],
                )
            pat = sparsity_pattern([aug.res[e] for e in g], [aug.syms[v] for v in cand])
            eq_to_var, _ = matching(pat)
            if np.any(eq_to_var < 0):
                raise ModelError(
                    f"model {aug.system.name!r}: no dummy derivatives for equations "
                    f"{[aug.eq_names[e] for e in g]} among {[aug.names[v] for v in cand]}"
                )
            chosen = sorted(cand[int(j)] for j in eq_to_var)
        levels.append((tuple(g), tuple(cand), tuple(chosen)))
        dummies.update(chosen)
        g = [aug.eq_pred[e] for e in g if aug.eq_pred[aug.eq_pred[e]] is not None]
        cand = [aug.pred[v] for v in chosen if aug.pred[aug.pred[v]] is not None]
    return Selection(levels=tuple(levels), dummies=frozenset(dummies))


def quality_function(aug: AugmentedDAE, sel: Selection) -> ca.Function:
    """CasADi Function ``(t, v, u, p) -> [dg_i/dz_i]`` (one dense Jacobian block per level).

    Parameters
    ----------
    aug : AugmentedDAE
        From :func:`pantelides`.
    sel : Selection
        A selection of :func:`select_dummies`.

    Returns
    -------
    casadi.Function
        Outputs one ``(len(g_i), len(z_i))`` matrix per level.
    """
    outs = []
    for eqs, cand, _ in sel.levels:
        g = _cat([aug.res[e] for e in eqs])
        outs.append(ca.densify(ca.jacobian(g, _cat([aug.syms[v] for v in cand]))))
    return ca.Function("dd_quality", aug.args, outs)


def selection_quality(sel: Selection, blocks: list[np.ndarray]) -> float:
    """How well-conditioned a selection is at a point, relative to the best greedy choice.

    For each level, ``|det dg_i/dz_i[:, chosen]| / prod |R_kk|`` with ``R`` the
    column-pivoted QR factor of the level's block (1 when the selection is the pivoted one,
    0 when it is singular); the minimum over the levels.

    Parameters
    ----------
    sel : Selection
        The selection.
    blocks : list of numpy.ndarray
        The Jacobian blocks of :func:`quality_function` at the point.

    Returns
    -------
    float
        In ``[0, inf)``; a re-selection is worthwhile below ~0.5.
    """
    q = np.inf
    for (eqs, cand, chosen), G in zip(sel.levels, blocks):
        G = np.atleast_2d(np.asarray(G, dtype=float)).reshape(len(eqs), len(cand))
        cols = [cand.index(v) for v in chosen]
        det = abs(np.linalg.det(G[:, cols]))
        best = float(np.prod(pivoted_qr(G)[0][: len(eqs)]))
        q = min(q, det / best if best > 0 else 0.0)
    return float(q)


def reduced_system(aug: AugmentedDAE, sel: Selection) -> tuple[list[int], list[int]]:
    """States and algebraic variables of the index-1 DAE of a selection.

    A variable is a state iff its derivative exists and is not a dummy; the ODE is
    ``der(v) = <derivative variable of v>`` and all residuals of ``aug`` are algebraic.

    Parameters
    ----------
    aug : AugmentedDAE
        From :func:`pantelides`.
    sel : Selection
        From :func:`select_dummies`.

    Returns
    -------
    states, algebraics : list of int
        Variable indices.

    Raises
    ------
    ModelError
        If the counts do not give a square algebraic system (should not happen after
        :func:`pantelides`).
    """
    states = [v for v in range(len(aug.syms)) if aug.diff[v] is not None and aug.diff[v] not in sel.dummies]
    sset = set(states)
    algs = [v for v in range(len(aug.syms)) if v not in sset]
    if len(algs) != len(aug.res):
        raise ModelError(
            f"model {aug.system.name!r}: after index reduction {len(aug.res)} equations for "
            f"{len(algs)} algebraic variables {[aug.names[v] for v in algs]}"
        )
    return states, algs


def _ident(name: str) -> str:
    m = re.fullmatch(r"der\((.*)\)", name)
    k = 0
    while m:
        k += 1
        name = m.group(1)
        m = re.fullmatch(r"der\((.*)\)", name)
    base = re.sub(r"\W+", "_", name).strip("_") or "v"
    return base if k == 0 else f"der{k if k > 1 else ''}_{base}"


def structural_simplify(model: Any, point: tuple | None = None, keep_states: tuple[str, ...] = ()) -> Any:
    """Alias elimination, structural check and index reduction: an index-1 model (MTK's name).

    Returns ``model`` itself when it has no alias equation and already flattens.
    Otherwise a new model of the same class with scalar variables: the selected states,
    algebraic variables (the unknowns made algebraic, the dummy derivatives ``der_x``,
    ``der2_x`` ... — non-identifier characters of element names become ``_``, e.g.
    ``T[0]`` -> ``T_0``), the equations ``der(s) = der_s`` plus all original and
    differentiated equations, the same parameters and inputs, and as outputs the declared
    outputs and the eliminated aliases. The dummy selection is fixed (made at ``point`` or at
    the start values); ``Model.simulate`` re-selects when it becomes singular,
    this model does not. Fixed starts (Modelica's ``fixed``, :mod:`gtmodel.modeling.structure.initialization`)
    stay fixed starts of the kept variables; a model without events and with fixed starts
    gets the consistent values at t = 0 as its start values (so ``flatten().x_start`` of
    the reduced model starts where the user said, whichever states were selected). The modes, when-clauses and ``substitute_der`` marks of the
    model (:mod:`gtmodel.modeling.structure.events`) are carried over to the new model.

    Parameters
    ----------
    model : Model
        The model.
    point : tuple, optional
        ``(t, v, u, p)`` values for the numeric dummy selection (see
        :func:`select_dummies`); default the start values (derivatives 0).
    keep_states : tuple of str, optional
        Scalar names of states to keep as states when the dummy selection allows it (their
        ``der()`` are ``avoid`` ed in :func:`select_dummies`), e.g. reinit targets.

    Returns
    -------
    Model
        An index-1 model that ``flatten()``, ``simulate`` and ``Optimization`` accept.

    Raises
    ------
    InputError
        If ``model`` is not a model or ``point`` is malformed.
    ModelError
        If the model is structurally singular (one message naming the equations and
        variables) or cannot be reduced, or its fixed starts contradict each other or the
        model (InconsistentInitialisation, naming them).
    """
    full = scalarize(model)
    require_regular(full)  # on the user's own equations, so that the message names them
    system = eliminate_aliases(full)
    if not system.aliases:
        try:
            model.flatten()
            return model
        except ModelError:
            pass
    aug = pantelides(system)
    nv = len(aug.syms)
    if point is None:
        v0 = np.concatenate([system.start, np.zeros(nv - system.n_vars)])
        if system.fixed_start and getattr(model, "_events", None) is None:
            v0 = _consistent_start_values(model, aug, v0)  # the reduced model starts where the user said
        point = (0.0, v0, system.u_start, system.p_value)
    elif not isinstance(point, (tuple, list)) or len(point) != 4:
        raise InputError(f"point must be a tuple (t, v, u, p), got {point!r}")
    else:
        t0 = float(_vector_value(point[0], 1, "point t")[0])
        point = (
            t0,
            _vector_value(point[1], nv, f"point v ({[aug.names[k] for k in range(nv)]})"),
            _vector_value(point[2], int(system.u.numel()), "point u"),
            _vector_value(point[3], int(system.p.numel()), "point p"),
        )
    values = np.asarray(point[1], dtype=float)
    if aug.n_differentiated == 0:
        states = [v for v in range(system.n_vars) if aug.diff[v] is not None]
        algs = [v for v in range(system.n_vars) if aug.diff[v] is None]
        new = build_model(model, aug, Selection(()), states, algs, values, direct=True)
        try:
            new.flatten()
            return new
        except ModelError:
            pass
    keep = {system.aliases.get(nm, (1.0, nm))[1] for nm in keep_states}
    avoid = frozenset(aug.diff[v] for v in range(system.n_vars) if aug.names[v] in keep and aug.diff[v] is not None)
    sel = select_dummies(aug, point, avoid)  # a state stays one while its der() is no dummy
    states, algs = reduced_system(aug, sel)
    return build_model(model, aug, sel, states, algs, values)


def _consistent_start_values(model: Any, aug: AugmentedDAE, v0: np.ndarray) -> np.ndarray:
    """Consistent values of all variables at t = 0 from the fixed starts (the start values if the
    initialisation is under-determined or does not converge).

    Raises
    ------
    InconsistentInitialisation
        If the fixed starts contradict each other or the model (naming them).
    """
    s = aug.system
    guess, conditions = guess_and_conditions(model, aug, None, None)
    fill = None
    if not s.init_res:
        sel0 = select_dummies(aug, (0.0, guess, s.u_start, s.p_value))
        fill = fill_order(aug, guess, reduced_system(aug, sel0)[0])
    try:
        return solve_initial(aug, 0.0, s.u_start, s.p_value, guess, conditions, fill)
    except InconsistentInitialisation:
        raise
    except (ModelError, ConvergenceError) as exc:  # e.g. initial equations that leave freedom: starts as given
        _log.debug("structural_simplify %s: start values as given (%s)", s.name, exc)
        return guess


def _fixed_of_kept(system: ScalarDAE) -> dict[str, float]:
    """The fixed starts on the variables the alias elimination kept (``+-`` an alias's value).

    Raises
    ------
    ModelError
        If two aliases of one variable have fixed starts that disagree (naming both).
    """
    out: dict[str, tuple[str, float]] = {}
    for nm, val in system.fixed_start.items():
        sign, keep = system.aliases.get(nm, (1.0, nm))
        value = sign * val
        if keep in out and abs(out[keep][1] - value) > 1e-12 * max(1.0, abs(value)):
            raise ModelError(
                f"model {system.name!r}: the fixed starts of {out[keep][0]!r} and {nm!r} disagree, but the equations make "
                f"them the same variable ({keep} = {out[keep][1]:g} vs {value:g}); make them consistent or one not fixed"
            )
        out.setdefault(keep, (nm, value))
    return {k: v for k, (_, v) in out.items()}


def _base(aug: AugmentedDAE, v: int) -> int:
    """The unknown that variable ``v`` of ``aug`` is a derivative of (``v`` itself if it is one)."""
    while aug.pred[v] is not None:
        v = aug.pred[v]
    return v


def _model_class(model: Any) -> type:
    """The class of a reduced model: gtmodel's own model class (the first of ``model``'s classes from gtmodel).

    A user's subclass (``class CartPendulum(Model)`` whose ``__init__`` takes no name and declares
    the equations) cannot be instantiated empty; the reduced model is a plain model either way."""
    return next((c for c in type(model).__mro__ if c.__module__.startswith("gtmodel.")), type(model))


def build_model(
    model: Any, aug: AugmentedDAE, sel: Selection, states: list[int], algs: list[int], values: np.ndarray,
    direct: bool = False,
) -> Any:
    """Declare the reduced DAE as a new model of ``type(model)`` (see :func:`structural_simplify`).

    Parameters
    ----------
    model : Model
        The original model (parameters, inputs, bounds, outputs).
    aug : AugmentedDAE
        From :func:`pantelides`.
    sel : Selection
        The dummy selection.
    states, algs : list of int
        From :func:`reduced_system`.
    values : numpy.ndarray
        Start values of all variables of ``aug``.
    direct : bool, optional
        Without differentiated equations: declare only the unknowns (``algs`` without the
        ``der()`` variables) and keep ``der()`` in the equations (default False).

    Returns
    -------
    Model
        The reduced model.
    """
    new = _model_class(model)(model.name)  # a user's subclass may take no name (its __init__ declares the model)
    new.warnings = list(getattr(model, "warnings", []))
    old, rep = [aug.system.t], [new.time]
    bounds: dict[str, tuple[float, float]] = {}
    units: dict[str, str] = {}  # the declared unit of every scalar kept (a derivative's: derivative_unit)
    for var in model._vars.values():
        if var.kind in ("parameter", "input"):
            sym = (
                new.parameter(var.name, var.start, smoothing=getattr(var, "smoothing", False))
                if var.kind == "parameter"
                else new.input(var.name, var.size, lb=var.lb, ub=var.ub, start=var.start, unit=var.unit)
            )
            old.append(var.sym)
            rep.append(sym)
        else:
            for j, nm in enumerate(expand_names(var.name, var.size)):
                bounds[nm] = (float(var.lb[j]), float(var.ub[j]))
                units[nm] = var.unit
    taken: set[str] = set(new._vars)
    new_syms: dict[int, ca.SX] = {}
    fixed = _fixed_of_kept(aug.system)
    for kind, idx in (("state", states), ("algebraic", algs)):
        for v in idx:
            nm = aug.names[v]
            lb, ub = bounds.get(nm, (-np.inf, np.inf)) if aug.order[v] == 0 else (-np.inf, np.inf)
            decl = new.state if kind == "state" else new.algebraic
            fix = aug.order[v] == 0 and nm in fixed  # a fixed start stays one (of the kept alias)
            start = fixed[nm] if fix else values[v]
            unit = derivative_unit(units.get(aug.names[_base(aug, v)], ""), aug.order[v])
            try:
                sym = decl(nm, start=start, lb=lb, ub=ub, fixed=fix, unit=unit)
            except (InputError, ModelError):
                cand, k = _ident(nm), 1
                while cand in taken:
                    cand, k = f"{_ident(nm)}_{k}", k + 1
                sym = decl(cand, start=start, lb=lb, ub=ub, fixed=fix, unit=unit)
            taken.update(new._vars)
            new_syms[v] = sym
    if direct:  # no dummy: the der() of the states stay der() of the new model
        for v in states:
            new_syms[aug.diff[v]] = new.der(new_syms[v])
    old.append(_cat(aug.syms))
    rep.append(_cat([new_syms[v] for v in range(len(aug.syms))]))

    src = _cat([ca.vec(o) for o in old])
    dst = _cat([ca.vec(r) for r in rep])

    def sub(items: list[ca.SX]) -> list[ca.SX]:
        return list(ca.substitute([ca.vec(e) for e in items], [src], [dst])) if items else []

    for v in [] if direct else states:
        new.equation(new.der(new_syms[v]), new_syms[aug.diff[v]], name=f"der_{_ident(aug.names[v])}")
    subst = {model._equations[j][0] for j in getattr(model, "_der_substituted", ())}
    for r, nm in zip(sub(aug.res), aug.eq_names):
        new.equation(r, 0.0, name=nm, substitute_der=re.sub(r"\[\d+\]$", "", nm) in subst)
    s = aug.system
    output_units = getattr(model, "_output_units", {})
    for nm, e in zip(s.outputs, sub(list(s.outputs.values()))):
        new.output(nm, e, unit=output_units.get(nm, ""))
    for nm, e in zip(s.aliases, sub([s.observed[nm] for nm in s.aliases])):
        for oname in (nm, _ident(nm)):
            if oname not in new._vars and oname not in new._outputs:
                try:
                    new.output(oname, e, unit=units.get(nm, ""))
                    break
                except InputError:
                    continue
    for r, nm in zip(sub(s.init_res), s.init_names):
        new.initial_equation(r, 0.0, name=nm)
    if getattr(model, "_events", None) is not None:  # the declared variables in the new symbols
        olds, exprs = [], []
        for var in model._vars.values():
            for j, nm in enumerate(expand_names(var.name, var.size) if var.kind in ("state", "algebraic") else []):
                olds.append(var.sym[j])
                exprs.append(s.observed[nm])
                if var.kind == "state":
                    olds.append(var.der[j])
                    exprs.append(s.observed[f"der({nm})"])
        names = {aug.names[v]: new.locate(new_syms[v])[1] for v in states + algs}
        transfer_events(
            model, new, _cat([ca.vec(o) for o in old[:-1]] + olds), _cat([ca.vec(r) for r in rep[:-1]] + sub(exprs)), names
        )
    _log.debug(
        "structural_simplify %s: %d states, %d algebraic, dummies %s",
        model.name, len(states), len(algs), sorted(aug.names[v] for v in sel.dummies),
    )
    return new

