"""Kinematic calibration from closure equations as least-squares NLPs.

The cost is the closure-equation cost of Dressler (2012), eqs. 5.1-5.2,

    V(s) = sum_k w_k sum_(links j) ( ||A_j(q_k, s) - B_j(T_k, R_k, s)||^2 - L_j(s)^2 )^2,

always real-valued (unlike FK/IK residuals), with optional measurement weights ``w_k``
(the residual of pose k is multiplied by ``sqrt(w_k)``). The steps:

1. **Frame alignment** (Dressler (2012), eqs. 5.3-5.4). Parameters are identified in the
   measurement frame, so the start model is moved there first: the rigid transform
   ``(R, t)`` that best maps its FK positions onto the measured TCP positions (orthogonal
   Procrustes/Kabsch by SVD, :func:`fit_rigid_transform`) is applied with
   ``model.transformed(R, t)``. The alignment only sets the start point, so it is guarded
   by the cost: of no transform, the centroid translation and the rigid fit, the one with
   the lowest ``V`` is used (on a small pose cloud with a poor nominal model the fitted
   rotation can be far off). Collinear FK positions give a translation only.
2. **Groups of arms** (Dressler (2012), ch. 5: arms are independent). Arms whose closure
   equations share a free parameter (read with ``model.arm_parameter_indices``, e.g. the
   common ``v`` of the ideal 3-link model, or joined by a tie) form one NLP; the others are
   solved separately. The modified 3-link model (21 parameters) gives three 7-parameter
   problems, the ideal one a single 15-parameter problem.
3. **Parameters**: free, fixed or tied (:class:`ParameterSelection`). Quaternion parameters
   (``model.quaternion_indices()``) are never moved as 4-vectors: the variables are a
   rotation vector ``r`` (3 per quaternion, rad) with ``quat = quat0 * exp(r / 2)``
   (a local parametrisation about the anchor ``quat0``), for both solver families; the
   anchor is re-set to the (normalised) solution after each solve, so the reported
   quaternions have unit norm (the improvement asked for in Dressler (2012), ch. 5.4,
   where unconstrained 4-vectors drifted to norms 0.974-1.003).
4. **Residuals and exact Jacobian** come from one CasADi graph per group: the closure
   residuals of one pose (``model.closure_function``) with their Jacobian with respect to
   the group's variables, mapped over blocks of :data:`CHUNK_SIZE` poses and expanded to
   one SX graph per block, then mapped over the blocks (poses padded with zero weight).
   The graph depends neither on the number of poses nor on the data: re-solving with
   other data or another start re-uses it. Evaluation goes through ``Function.buffer`` on
   NumPy arrays (no conversion to DM, which alone cost ~1 ms per call for 779 poses).
5. **Checks before solving**: shapes and finite data, at least as many residuals as free
   variables per group, and full rank of the Jacobian at the start (a rank-deficient
   problem is a :class:`~gtmodel.errors.ModelError` naming the non-identifiable
   parameters and what they depend on, with the report attached, not a fit).

Measured (``python benchmarks/bench_calibration.py``; CasADi 3.8.2, 2 cores shared with
other jobs, load 3-4, so ranges over five runs; one 7-parameter arm group of the L1, 779
poses, residuals + Jacobian per evaluation):

=================================================  ============  ===========
variant                                             build [s]     eval [ms]
=================================================  ============  ===========
``map`` of the per-pose Function (serial)           0.001         0.26-0.5
one SX graph over all poses (Python loop)           0.15-0.35     0.1-0.23
``map(N).expand()`` (one SX graph per N)            0.013-0.03    0.1-0.23
blocks of 64 poses expanded, then mapped (used)     0.002-0.006   0.1-0.23
=================================================  ============  ===========

The block variant builds once for any number of poses and evaluates at SX speed (the
same speed as one graph over all poses, 2-2.5x faster than the plain ``map``).

Solvers (``solver=``) on the L1 21-parameter problem (779 synthetic laser-tracker poses:
true = Table 5.1 modified model, start = the ideal model, noise 10 um; summed over the
three arm groups; same benchmark):

==============  ==========  ===========  ==========  ==============================
solver          iterations  solve [ms]   build [s]   optimum vs ``"lm"`` (relative)
==============  ==========  ===========  ==========  ==============================
``"lm"``        12          4.5-14       0.03-0.07   (reference)
``"trf"``       14          6.6-28       --          1e-13
``"ipopt"``     9           69-160       0.4-1.0     8e-12
``"ipopt-gn"``  19          76-160       0.01-0.04   7e-14
==============  ==========  ===========  ==========  ==============================

(``"lm"``/``"trf"`` iterations are Jacobian evaluations including the polishing step.)
``"lm"`` -- MINPACK's Levenberg-Marquardt through :func:`scipy.optimize.least_squares`
with the exact CasADi Jacobian, plus one Gauss-Newton polishing step (see
:data:`POLISH_STEPS`) -- is the default: fewest evaluations, least overhead; the whole
``calibrate`` call (alignment, rank check, statistics, report) takes 12-36 ms. SciPy's
least_squares with its 2-point finite-difference Jacobian on the same residuals (all 21
parameters, same CasADi graph through buffers, method "lm" or "trf") needs 37-91 ms and
~89 residual evaluations: 3-11x the solve time, 1.2-5x the whole call (the ratio
moves with the machine's load: the many small calls of the exact-Jacobian path suffer
more from a busy CPU than the peer's few long ones). IPOPT (exact Hessian
of V, or the Gauss-Newton Hessian ``2 J^T J``) reaches the same optimum with a different
method; it is kept as that independent check and for calibration problems that need
constraints, at ~10x the time here (its per-iteration overhead dominates).

Standard deviations: ``sigma^2 (J^T J)^-1`` restricted to the free variables, with
``sigma^2 = RSS / (m - n)`` per group (m residuals, n variables), propagated to the
parameters through the Jacobian of the parameter map (tied parameters get the
deviation of their source, quaternion components that of the 4-vector).
"""

from __future__ import annotations

import difflib
import fnmatch
import hashlib
import logging
import math
import time
from collections import OrderedDict
from dataclasses import dataclass
from typing import Any, Iterable, Mapping, Sequence

import casadi as ca
import numpy as np
import scipy.linalg
import scipy.optimize

from gtmodel.calibration.identifiability import IdentifiabilityReport, analyze_jacobian, combine_reports, numerical_rank
from gtmodel.errors import ConvergenceError, InputError, ModelError, SingularConfigurationError, UnreachablePoseError
from gtmodel.modeling.result import normalize_ipopt_status
from gtmodel.robots.closure import ClosureModel, rotation_vector_to_rotation

__all__ = [
    "ParameterSelection",
    "CalibrationProblem",
    "CalibrationResult",
    "GroupResult",
    "calibrate",
    "analyze_identifiability",
    "fit_rigid_transform",
    "align_model",
    "tcp_errors",
    "SOLVERS",
    "DEFAULT_SOLVER",
    "MAX_ITER",
    "LSQ_TOLERANCE",
    "IPOPT_TOLERANCE",
    "CHUNK_SIZE",
    "REANCHOR_ANGLE",
    "MAX_REANCHOR",
    "COLLINEAR_TOLERANCE",
    "POLISH_STEPS",
    "FK_CACHE_SIZE",
    "PROBLEM_CACHE_SIZE",
    "POLISH_MAX_STEP",
]

_log = logging.getLogger("gtmodel")

#: Solver names: SciPy least_squares ("lm": MINPACK Levenberg-Marquardt, "trf": trust
#: region reflective) with the exact CasADi Jacobian, IPOPT with the exact Hessian of
#: V ("ipopt") or the Gauss-Newton Hessian 2 J^T J ("ipopt-gn").
SOLVERS = ("lm", "trf", "ipopt", "ipopt-gn")
#: Default solver, chosen by measurement (see the module docstring).
DEFAULT_SOLVER = "lm"
#: Iteration limit per group: residual evaluations (``max_nfev``) for "lm"/"trf", IPOPT
#: iterations for "ipopt"/"ipopt-gn".
MAX_ITER = 200
#: Termination tolerance of least_squares: ``ftol = xtol = gtol`` (relative change of the
#: cost, relative step, scaled gradient).
LSQ_TOLERANCE = 1e-10
#: IPOPT ``tol``: the objective is ``V / S``, ``S`` the largest component of grad V at the
#: start, so this is the relative reduction of the gradient. Tighter values end in
#: "Search_Direction_Becomes_Too_Small" on noisy data (the rounding of V, see ``_polish``).
IPOPT_TOLERANCE = 1e-10
#: Gauss-Newton polishing steps after a converged least_squares run (see ``_polish``).
POLISH_STEPS = 1
#: Largest relative polishing step ``|dx| / (1 + |x|)``; larger steps mean the run had not
#: converged and are not taken.
POLISH_MAX_STEP = 1e-6
#: Poses per expanded SX block of the residual/Jacobian graph.
CHUNK_SIZE = 64
#: Rotation [rad] of a quaternion's local variables beyond which a failed solve is repeated
#: from the re-set anchor (the anchor is always re-set to the solution).
REANCHOR_ANGLE = 0.5
#: Maximum number of such re-anchored solves.
MAX_REANCHOR = 5
#: Nominal FK results kept per problem (keyed by the actuator values), for repeated solves
#: on the same poses (simulated calibrations, benchmarks).
FK_CACHE_SIZE = 8
#: Nominal FK positions whose second singular value (centred) is below this fraction of
#: the first are treated as collinear: the alignment then fits a translation only.
COLLINEAR_TOLERANCE = 1e-6



# ------------------------------------------------------------------ quaternion helpers
def _quat_mul(a: Any, b: Any) -> ca.SX:
    w1, x1, y1, z1 = a[0], a[1], a[2], a[3]
    w2, x2, y2, z2 = b[0], b[1], b[2], b[3]
    return ca.vertcat(
        w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2,
        w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2,
        w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2,
        w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2,
    )


def _quat_exp(r: Any) -> ca.SX:
    """Unit quaternion of the rotation vector ``r`` (= exp(r/2)), smooth at r = 0."""
    th2 = ca.dot(r, r)
    th = ca.sqrt(th2 + 1e-300)
    small = th2 < 1e-8
    c = ca.if_else(small, 1 - th2 / 8 + th2 * th2 / 384, ca.cos(th / 2))
    s = ca.if_else(small, 0.5 - th2 / 48 + th2 * th2 / 3840, ca.sin(th / 2) / th)
    return ca.vertcat(c, s * r)


# ------------------------------------------------------------------ parameter selection
def _parse_tie(item: Any) -> tuple[str, str]:
    if isinstance(item, str):
        parts = item.split("=")
        if len(parts) != 2 or not parts[0].strip() or not parts[1].strip():
            raise InputError(f"ties: expected 'target = source', got {item!r}")
        return parts[0].strip(), parts[1].strip()
    try:
        target, source = item
    except (TypeError, ValueError):
        raise InputError(f"ties: expected 'target = source' or a (target, source) pair, got {item!r}") from None
    return str(target).strip(), str(source).strip()


def _as_names(value: Any, what: str) -> tuple[str, ...]:
    if value is None:
        return ()
    if isinstance(value, str):
        return (value,)
    try:
        out = tuple(str(v) for v in value)
    except TypeError:
        raise InputError(f"{what}: expected a name or a sequence of names, got {value!r}") from None
    return out


@dataclass(frozen=True)
class ParameterSelection:
    """Which parameters a calibration estimates: free, fixed and tied parameters.

    Names are exact parameter names (``model.parameter_names()``) or shell-style patterns
    (``"v*"``, ``"As?_z"``). A tie ``"target = source"`` makes ``target`` take the value
    of ``source`` (which may be free or fixed) throughout, e.g. ``"Abj_2b_z = Abj_2a_z"``:
    ``Abj_2b_z`` follows ``Abj_2a_z``.

    Parameters
    ----------
    free : str or sequence of str, optional
        The free parameters; default (None): every parameter that is neither fixed nor
        a tie target.
    fixed : str or sequence of str, optional
        Parameters kept at their start values. Only allowed together with ``free=None``
        or for names not in ``free``. May also name single local rotation components
        of a quaternion parameter, ``<name>_rx``, ``_ry``, ``_rz`` (as the identifiability
        report names them): that rotation of the quaternion about the start value is
        then not estimated.
    ties : str or sequence or mapping, optional
        ``"target = source"`` strings, ``(target, source)`` pairs or a mapping
        ``{target: source}``.

    Raises
    ------
    InputError
        If a tie is malformed (checked here); unknown names and conflicts are reported
        when the selection is applied to a model (:class:`CalibrationProblem`).
    """

    free: tuple[str, ...] | None = None
    fixed: tuple[str, ...] = ()
    ties: tuple[tuple[str, str], ...] = ()

    def __post_init__(self) -> None:
        object.__setattr__(self, "free", None if self.free is None else _as_names(self.free, "free"))
        object.__setattr__(self, "fixed", _as_names(self.fixed, "fixed"))
        ties = self.ties
        if isinstance(ties, Mapping):
            items = [(str(k), str(v)) for k, v in ties.items()]
        elif isinstance(ties, str):
            items = [_parse_tie(ties)]
        else:
            items = [_parse_tie(t) for t in (ties or ())]
        object.__setattr__(self, "ties", tuple(items))

    def _resolve(self, model: ClosureModel) -> "_Resolution":
        """Check the selection against a model and index it.

        Parameters
        ----------
        model : ClosureModel
            The model whose ``parameter_names()`` the names refer to.

        Returns
        -------
        _Resolution
            Internal index of free variables, fixed and tied parameters.

        Raises
        ------
        InputError
            Unknown names (with close matches), a parameter both free and fixed, a tie
            whose target is free or fixed, tie cycles, ties on quaternion components, or
            a quaternion that is only partly free.
        """
        return _Resolution(model, self)


def _match(names: Sequence[str], pattern: str, what: str) -> list[int]:
    if any(c in pattern for c in "*?["):
        hits = [i for i, n in enumerate(names) if fnmatch.fnmatchcase(n, pattern)]
    else:
        hits = [i for i, n in enumerate(names) if n == pattern]
    if not hits:
        close = difflib.get_close_matches(pattern, names, n=5, cutoff=0.5)
        if close:
            hint = f"; close matches: {', '.join(close)}"
        else:
            hint = f"; known names: {', '.join(names[:12])}{' ...' if len(names) > 12 else ''}"
        raise InputError(f"{what}: unknown parameter name {pattern!r}{hint}")
    return hits


class _Resolution:
    """Free variables, fixed and tied parameters of a selection on a model (internal)."""

    def __init__(self, model: ClosureModel, sel: ParameterSelection) -> None:
        names = tuple(model.parameter_names())
        n = len(names)
        self.names = names
        quats = [tuple(int(i) for i in qi) for qi in model.quaternion_indices()]
        in_quat = {i: k for k, qi in enumerate(quats) for i in qi}

        root = np.arange(n)
        targets: set[int] = set()
        for target, source in sel.ties:
            ti = _match(names, target, "ties")
            si = _match(names, source, "ties")
            if len(ti) != 1 or len(si) != 1:
                raise InputError(f"ties: {target!r} = {source!r} must name one parameter on each side")
            t, s = ti[0], si[0]
            if t == s:
                raise InputError(f"ties: {names[t]!r} is tied to itself")
            if t in in_quat or s in in_quat:
                raise InputError(
                    f"ties: {names[t]} = {names[s]}: quaternion components cannot be tied "
                    "(they are estimated as a rotation)"
                )
            if t in targets:
                raise InputError(f"ties: {names[t]!r} is the target of more than one tie")
            targets.add(t)
            root[t] = s
        # resolve chains, detect cycles
        for t in list(targets):
            seen = {t}
            r = int(root[t])
            while r in targets:
                if r in seen:
                    raise InputError(f"ties: cycle through {', '.join(names[i] for i in sorted(seen))}")
                seen.add(r)
                r = int(root[r])
            root[t] = r

        # local rotation variables of quaternions, e.g. "qt_rx": can be fixed one by one
        bases = [names[qi[0]][:-2] if names[qi[0]].endswith("_w") else f"quat{k}" for k, qi in enumerate(quats)]
        rot_names = [f"{b}_r{c}" for b in bases for c in "xyz"]
        fixed_rot: dict[int, set[int]] = {k: set() for k in range(len(quats))}
        fixed_explicit: set[int] = set()
        for pat in sel.fixed:
            hits = _match(names + tuple(rot_names), pat, "fixed")
            exact = not any(c in pat for c in "*?[")
            for i in hits:
                if i >= n:  # a rotation variable
                    fixed_rot[(i - n) // 3].add((i - n) % 3)
                    continue
                if i in targets:
                    if exact:
                        raise InputError(f"fixed: {names[i]!r} is the target of a tie and follows its source; remove one")
                    continue
                fixed_explicit.add(i)
        if sel.free is None:
            free = {i for i in range(n) if i not in fixed_explicit and i not in targets}
        else:
            free = set()
            for pat in sel.free:
                hits = _match(names, pat, "free")
                exact = not any(c in pat for c in "*?[")
                for i in hits:
                    if i in targets:
                        if exact:
                            raise InputError(f"free: {names[i]!r} is the target of a tie and cannot be free")
                        continue
                    if i in fixed_explicit:
                        raise InputError(f"{names[i]!r} is both free and fixed")
                    free.add(i)
        # quaternions: all four components share one status; all rotations fixed = fixed
        for k, qi in enumerate(quats):
            st = {i in free for i in qi}
            if len(st) > 1:
                raise InputError(
                    f"quaternion ({', '.join(names[i] for i in qi)}): free all four components or none "
                    f"(it is estimated as a rotation; fix single rotation components as {bases[k]}_rx/ry/rz)"
                )
            if len(fixed_rot[k]) == 3:
                free -= set(qi)

        self.free = free
        self.targets = targets
        self.root = root
        self.quaternions = quats
        # variables: (kind, first parameter index); quaternion variables are 3 rotation components
        var_names: list[str] = []
        var_of_param: dict[int, list[int]] = {}
        self.var_kind: list[tuple[str, int]] = []
        var_comp: list[int] = []  # rotation component (0, 1, 2) of a quaternion variable, -1 else
        done_quat: set[int] = set()
        for i in range(n):
            if i not in free:
                continue
            if i in in_quat:
                k = in_quat[i]
                if k in done_quat:
                    continue
                done_quat.add(k)
                qi = quats[k]
                comps = [c for c in range(3) if c not in fixed_rot[k]]
                idx = list(range(len(var_names), len(var_names) + len(comps)))
                var_names += [f"{bases[k]}_r{'xyz'[c]}" for c in comps]
                var_comp += comps
                self.var_kind.append(("quat", k))
                for c in qi:
                    var_of_param[c] = idx
            else:
                var_of_param[i] = [len(var_names)]
                var_names.append(names[i])
                var_comp.append(-1)
                self.var_kind.append(("scalar", i))
        # tied parameters with a free root use the root's variable
        for t in targets:
            r = int(root[t])
            if r in var_of_param:
                var_of_param[t] = var_of_param[r]
        self.var_names = tuple(var_names)
        self.var_of_param = var_of_param
        self.var_comp = var_comp
        #: index into var_kind of each variable
        widths = [3 - len(fixed_rot[idx]) if kind == "quat" else 1 for kind, idx in self.var_kind]
        self.kind_of_var = [k for k, w in enumerate(widths) for _ in range(w)]
        self.n_vars = len(var_names)

    def variables_of(self, param_indices: Sequence[int]) -> set[int]:
        out: set[int] = set()
        for i in param_indices:
            out.update(self.var_of_param.get(int(i), []))
        return out


# ------------------------------------------------------------------ rigid transform
def fit_rigid_transform(
    P: np.typing.ArrayLike, Q: np.typing.ArrayLike, weights: np.typing.ArrayLike | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """Rotation and translation that best map points ``P`` onto ``Q`` (Kabsch, by SVD).

    Minimises ``sum_k w_k ||R P_k + t - Q_k||^2`` over rotations ``R`` (``det R = +1``) and
    translations ``t``; used to move a nominal model into the measurement frame,
    Dressler (2012), eqs. 5.3-5.4. For (nearly) collinear ``P`` (see
    :data:`COLLINEAR_TOLERANCE`) the rotation is not determined and ``R = I`` is returned
    with the best translation.

    Parameters
    ----------
    P : array_like, shape (N, 3)
        Points in the source frame [m].
    Q : array_like, shape (N, 3)
        The same points in the target frame [m].
    weights : array_like, shape (N,), optional
        Non-negative weights (default 1).

    Returns
    -------
    R : numpy.ndarray, shape (3, 3)
        Rotation.
    t : numpy.ndarray, shape (3,)
        Translation [m].

    Raises
    ------
    InputError
        Mismatched shapes, non-finite values, fewer than 3 points or negative weights.
    """
    Pa = np.asarray(P, dtype=float)
    Qa = np.asarray(Q, dtype=float)
    if Pa.ndim != 2 or Pa.shape[1] != 3 or Pa.shape != Qa.shape:
        raise InputError(f"P, Q: expected two (N, 3) arrays of equal shape, got {Pa.shape} and {Qa.shape}")
    if Pa.shape[0] < 3:
        raise InputError(f"P, Q: need at least 3 points for a rigid transform, got {Pa.shape[0]}")
    if not (np.all(np.isfinite(Pa)) and np.all(np.isfinite(Qa))):
        raise InputError("P, Q: non-finite values")
    w = np.ones(Pa.shape[0]) if weights is None else np.asarray(weights, dtype=float).ravel()
    if w.size != Pa.shape[0] or np.any(w < 0) or not np.all(np.isfinite(w)) or w.sum() <= 0:
        raise InputError(f"weights: expected {Pa.shape[0]} finite non-negative values, not all zero")
    w = w / w.sum()
    pc = w @ Pa
    qc = w @ Qa
    X = (Pa - pc) * np.sqrt(w)[:, None]
    Y = (Qa - qc) * np.sqrt(w)[:, None]
    sx = np.linalg.svd(X, compute_uv=False)
    if sx[0] == 0 or sx[1] <= COLLINEAR_TOLERANCE * sx[0]:
        _log.warning("fit_rigid_transform: points are (nearly) collinear; fitting a translation only")
        return np.eye(3), qc - pc
    H = X.T @ Y
    U, _, Vt = np.linalg.svd(H)
    d = np.sign(np.linalg.det(Vt.T @ U.T))
    D = np.diag([1.0, 1.0, d if d != 0 else 1.0])
    R = Vt.T @ D @ U.T
    return R, qc - R @ pc


def _nominal_positions(model: ClosureModel, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """FK positions of the nominal model and the mask of poses where it succeeded."""
    try:
        T, _ = model.fk(q)
        return np.atleast_2d(T), np.ones(q.shape[0], dtype=bool)
    except (UnreachablePoseError, ConvergenceError, SingularConfigurationError):
        pass
    T = np.zeros((q.shape[0], 3))
    ok = np.zeros(q.shape[0], dtype=bool)
    for k in range(q.shape[0]):
        try:
            T[k] = model.fk(q[k])[0]
            ok[k] = True
        except (UnreachablePoseError, ConvergenceError, SingularConfigurationError):
            continue
    return T, ok


def align_model(
    model: ClosureModel, q: np.typing.ArrayLike, T: np.typing.ArrayLike, weights: np.typing.ArrayLike | None = None
) -> tuple[ClosureModel, np.ndarray, np.ndarray]:
    """Move a nominal model into the measurement frame (Dressler (2012), eqs. 5.3-5.4).

    The nominal FK positions ``model.fk(q)`` are fitted to the measured positions ``T``
    by :func:`fit_rigid_transform`; poses where the nominal FK fails are left out.

    Parameters
    ----------
    model : ClosureModel
        Nominal model.
    q : array_like, shape (N, n_q)
        Actuator values of the measured poses [m, rad].
    T : array_like, shape (N, 3)
        Measured TCP positions [m].
    weights : array_like, shape (N,), optional
        Pose weights (zero-weight poses are ignored).

    Returns
    -------
    model : ClosureModel
        ``model.transformed(R, t)``.
    R : numpy.ndarray, shape (3, 3)
        Rotation from the model frame to the measurement frame.
    t : numpy.ndarray, shape (3,)
        Translation [m].

    Raises
    ------
    InputError
        If the nominal FK succeeds for fewer than 3 poses or the shapes do not match.
    """
    qa = np.atleast_2d(np.asarray(q, dtype=float))
    Ta = np.atleast_2d(np.asarray(T, dtype=float))
    Tn, ok = _nominal_positions(model, qa)
    w = np.ones(qa.shape[0]) if weights is None else np.asarray(weights, dtype=float).ravel()
    ok &= w > 0
    if ok.sum() < 3:
        raise InputError(
            f"{model.name}: the nominal forward kinematics succeeds for only {int(ok.sum())} of {qa.shape[0]} poses; "
            "the frame alignment needs at least 3 (use align=False with a model already in the measurement frame)"
        )
    R, t = fit_rigid_transform(Tn[ok], Ta[ok], w[ok])
    return model.transformed(R, t), R, t


def tcp_errors(model: ClosureModel, q: np.typing.ArrayLike, T: np.typing.ArrayLike) -> np.ndarray:
    """TCP position errors ``e_k = ||T_k - fk(q_k)||``, Dressler (2012), eq. 5.5.

    Parameters
    ----------
    model : ClosureModel
        The (calibrated) model, in the frame of ``T``.
    q : array_like, shape (N, n_q)
        Actuator values [m, rad].
    T : array_like, shape (N, 3)
        Measured TCP positions [m].

    Returns
    -------
    numpy.ndarray, shape (N,)
        Errors [m].

    Raises
    ------
    InputError
        Mismatched shapes.
    UnreachablePoseError
        If the model's FK has no solution for some ``q``.
    ConvergenceError
        If an iterative FK does not converge.
    """
    qa = np.atleast_2d(np.asarray(q, dtype=float))
    Ta = np.atleast_2d(np.asarray(T, dtype=float))
    if Ta.shape != (qa.shape[0], 3):
        raise InputError(f"T: expected shape ({qa.shape[0]}, 3) to match q, got {Ta.shape}")
    from gtmodel.calibration.evaluation import evaluate
    from gtmodel.calibration.measurements import MeasurementSet

    # one implementation of eq. 5.5: the accuracy report's
    return evaluate(model, MeasurementSet(q=qa, T=Ta)).errors


# ------------------------------------------------------------------ data
@dataclass
class _Data:
    q: np.ndarray       # (N, n_q)
    T: np.ndarray       # (N, 3)
    quat: np.ndarray    # (N, 4)
    weights: np.ndarray  # (N,)

    @property
    def N(self) -> int:
        return self.q.shape[0]

    def padded(self, M: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Inputs of M >= N poses (copies of pose 0 with zero weight appended), C order."""
        N = self.N
        pad = M - N
        def ext(a: np.ndarray) -> np.ndarray:
            return np.ascontiguousarray(np.concatenate([a, np.repeat(a[:1], pad, axis=0)]) if pad else a.copy())
        s = np.sqrt(self.weights)
        return ext(self.q), ext(self.T), ext(self.quat), np.ascontiguousarray(np.concatenate([s, np.zeros(pad)]))


def _unpack_measurements(q: Any, T: Any, quat: Any, weights: Any, model: ClosureModel | None = None) -> tuple[Any, Any, Any, Any]:
    if T is None and not isinstance(q, (np.ndarray, list, tuple)) and hasattr(q, "q") and hasattr(q, "quat"):
        m = q
        # the model builds its per-pose input rows from the measurement set (the actuator
        # values; the elasto-geometric closure appends the plate load)
        return (m.q if model is None else model.pose_inputs(m)), m.T, getattr(m, "quat", None), getattr(m, "weights", None)
    return q, T, quat, weights


def _check_data(model: ClosureModel, q: Any, T: Any, quat: Any, weights: Any) -> _Data:
    if T is None:
        raise InputError("T: measured TCP positions (N, 3) are required (or pass a MeasurementSet as q)")
    try:
        qa = np.array(q, dtype=float)
        Ta = np.array(T, dtype=float)
    except (TypeError, ValueError) as e:
        raise InputError(f"q, T: expected numeric arrays ({e})") from None
    if qa.ndim != 2 or qa.shape[1] != model.n_q:
        raise InputError(f"q: expected shape (N, {model.n_q}) (actuator values of {model.name}), got {qa.shape}")
    N = qa.shape[0]
    if Ta.shape != (N, 3):
        raise InputError(f"T: expected shape ({N}, 3) to match q, got {Ta.shape}")
    for name, a in (("q", qa), ("T", Ta)):
        bad = np.flatnonzero(~np.all(np.isfinite(a), axis=1))
        if bad.size:
            raise InputError(f"{name}: non-finite values in row(s) {bad[:10].tolist()}")
    if quat is None:
        if model.orientation:
            raise InputError(f"quat: {model.name} determines the plate orientation; measured orientations (N, 4) are required")
        qu = np.tile([1.0, 0.0, 0.0, 0.0], (N, 1))
    else:
        try:
            qu = np.array(quat, dtype=float)
        except (TypeError, ValueError) as e:
            raise InputError(f"quat: expected a numeric array ({e})") from None
        if qu.shape != (N, 4):
            raise InputError(f"quat: expected shape ({N}, 4) (w, x, y, z per pose), got {qu.shape}")
        bad = np.flatnonzero(~np.all(np.isfinite(qu), axis=1))
        if bad.size:
            raise InputError(f"quat: non-finite values in row(s) {bad[:10].tolist()}")
        nrm = np.linalg.norm(qu, axis=1)
        bad = np.flatnonzero(np.abs(nrm - 1.0) > 1e-6)
        if bad.size:
            raise InputError(f"quat: rows must be unit quaternions; row {int(bad[0])} has norm {nrm[bad[0]]:.6g}")
    if weights is None:
        w = np.ones(N)
    else:
        w = np.array(weights, dtype=float).ravel()
        if w.size != N:
            raise InputError(f"weights: expected {N} values (one per pose), got {w.size}")
        bad = np.flatnonzero(~np.isfinite(w) | (w < 0))
        if bad.size:
            raise InputError(f"weights: expected finite non-negative values; row {int(bad[0])} is {w[bad[0]]!r}")
        if not np.any(w > 0):
            raise InputError("weights: all weights are zero")
    return _Data(q=qa, T=Ta, quat=qu, weights=w)


# ------------------------------------------------------------------ group functions
class _Group:
    """Residuals and exact Jacobian of one group of arms as CasADi Functions (internal)."""

    def __init__(self, model: ClosureModel, res: _Resolution, arms: tuple[int, ...], var_idx: list[int]) -> None:
        self.arms = arms
        self.var_idx = np.array(sorted(var_idx), dtype=int)
        self.var_names = tuple(res.var_names[i] for i in self.var_idx)
        self.n_links = [len(model.links[a]) for a in arms]
        self.nr = int(sum(self.n_links))
        self.nx = int(self.var_idx.size)
        n_p = model.n_parameters
        self.n_p = n_p
        self.n_q = model.n_q
        local = {int(g): j for j, g in enumerate(self.var_idx)}
        #: (quaternion number, local variable indices, rotation components) per quaternion
        slots: dict[int, tuple[list[int], list[int]]] = {}
        for g, j in local.items():
            kind, idx = res.var_kind[res.kind_of_var[g]]
            if kind == "quat":
                js, cs = slots.setdefault(idx, ([], []))
                js.append(j)
                cs.append(res.var_comp[g])
        self.quaternion_slots = [(k, js, cs) for k, (js, cs) in slots.items()]
        self.has_quaternion = bool(self.quaternion_slots)
        x = ca.SX.sym("x", self.nx)
        pb = ca.SX.sym("p0", n_p)
        p_expr = _parameter_expression(res, x, pb, {int(g): j for j, g in enumerate(self.var_idx)})
        q = ca.SX.sym("q", model.n_q)
        T = ca.SX.sym("T", 3)
        quat = ca.SX.sym("quat", 4)
        s = ca.SX.sym("s")
        r = ca.vertcat(*[model.closure_function(a)(p_expr, q, T, quat) for a in arms]) * s
        J = ca.densify(ca.jacobian(r, x)) if self.nx else ca.DM.zeros(self.nr, 0)
        ins = [x, pb, q, T, quat, s]
        self.f_r = ca.Function("r", ins, [r])
        self.f_rJ = ca.Function("rJ", ins, [r, J])
        self.f_r_chunk = self.f_r.map("r_chunk", "serial", CHUNK_SIZE, [0, 1], []).expand()
        self.f_rJ_chunk = self.f_rJ.map("rJ_chunk", "serial", CHUNK_SIZE, [0, 1], []).expand()
        self._JtJ = ca.Function("JtJ", ins, [ca.mtimes(J.T, J)])  # mapped when IPOPT-GN needs it
        self._maps: dict[tuple[str, int], ca.Function] = {}
        self._nlps: dict[tuple[str, int, int], ca.Function] = {}

    def mapped(self, kind: str, n_chunks: int) -> ca.Function:
        key = (kind, n_chunks)
        if key not in self._maps:
            if kind == "JtJ":
                base = self._JtJ.map("JtJ_chunk", "serial", CHUNK_SIZE, [0, 1], [0]).expand()
            else:
                base = {"r": self.f_r_chunk, "rJ": self.f_rJ_chunk}[kind]
            reduce_out = [0] if kind == "JtJ" else []
            self._maps[key] = base.map(f"{kind}_{n_chunks}", "serial", n_chunks, [0, 1], reduce_out)
        return self._maps[key]

    def nlp(self, kind: str, M: int, max_iter: int) -> ca.Function:
        """IPOPT solver for M padded poses; parameter vector (scale, p0, q, T, quat, s)."""
        key = (kind, M, max_iter)
        if key in self._nlps:
            return self._nlps[key]
        nch = M // CHUNK_SIZE
        X = ca.MX.sym("x", self.nx)
        n_par = 1 + self.n_p + M * (self.n_q + 3 + 4 + 1)
        P = ca.MX.sym("P", n_par)
        o = 1 + self.n_p
        pb = P[1:o]
        Q = ca.reshape(P[o:o + M * self.n_q], self.n_q, M)
        o += M * self.n_q
        Tm = ca.reshape(P[o:o + 3 * M], 3, M)
        o += 3 * M
        QU = ca.reshape(P[o:o + 4 * M], 4, M)
        o += 4 * M
        S = ca.reshape(P[o:o + M], 1, M)
        r = self.mapped("r", nch)(X, pb, Q, Tm, QU, S)
        f = P[0] * ca.sumsqr(r)
        opts: dict[str, Any] = {
            "ipopt.print_level": 0,
            "ipopt.sb": "yes",
            "print_time": False,
            "ipopt.tol": IPOPT_TOLERANCE,
            "ipopt.max_iter": int(max_iter),
        }
        if kind == "ipopt-gn":
            lam_f = ca.MX.sym("lam_f")
            lam_g = ca.MX.sym("lam_g", 0)
            H = 2 * lam_f * P[0] * self.mapped("JtJ", nch)(X, pb, Q, Tm, QU, S)
            opts["hess_lag"] = ca.Function(
                "nlp_hess_l", [X, P, lam_f, lam_g], [ca.triu(H)], ["x", "p", "lam_f", "lam_g"], ["triu_hess_gamma_x_x"]
            )
        solver = ca.nlpsol("calibration_" + kind.replace("-", "_"), "ipopt", {"x": X, "p": P, "f": f}, opts)
        self._nlps[key] = solver
        return solver


def _parameter_expression(res: _Resolution, x: ca.SX, pb: ca.SX, local: Mapping[int, int]) -> ca.SX:
    """Parameter vector p(x, p0): free scalars from x, quaternions q0*exp(r/2), ties, rest p0."""
    n = len(res.names)
    p = [pb[i] for i in range(n)]
    # scalar and quaternion variables of this group
    for g, j in local.items():
        kind, idx = res.var_kind[res.kind_of_var[g]]
        if kind == "scalar":
            p[idx] = x[j]
    done: set[int] = set()
    for g in local:
        kind, idx = res.var_kind[res.kind_of_var[g]]
        if kind == "quat" and idx not in done:
            done.add(idx)
            qi = res.quaternions[idx]
            delta: list[Any] = [0.0, 0.0, 0.0]  # fixed rotation components stay 0
            for gg in res.var_of_param[qi[0]]:
                delta[res.var_comp[gg]] = x[local[gg]]
            q0 = ca.vertcat(*[pb[c] for c in qi])
            qn = _quat_mul(q0, _quat_exp(ca.vertcat(*delta)))
            for c, comp in zip(qi, range(4)):
                p[c] = qn[comp]
    for t in res.targets:
        r = int(res.root[t])
        p[t] = p[r]
    return ca.vertcat(*p)


class _Evaluator:
    """Residuals and Jacobian of one group on one data set through Function.buffer (internal)."""

    def __init__(self, group: _Group, data: _Data, pb: np.ndarray) -> None:
        self.group = group
        N = data.N
        M = -(-N // CHUNK_SIZE) * CHUNK_SIZE
        self.N, self.M = N, M
        nch = M // CHUNK_SIZE
        self.x = np.zeros(group.nx)
        self.pb = np.ascontiguousarray(pb, dtype=float).copy()
        self.inputs = [self.x, self.pb, *data.padded(M)]
        self.r_out = np.zeros((M, group.nr))
        self.rJ_r = np.zeros((M, group.nr))
        self.rJ_J = np.zeros((M, max(group.nx, 1), group.nr))
        self.fb_r, self.ev_r = group.mapped("r", nch).buffer()
        self.fb_rJ, self.ev_rJ = group.mapped("rJ", nch).buffer()
        for fb in (self.fb_r, self.fb_rJ):
            for i, a in enumerate(self.inputs):
                if a.size:
                    fb.set_arg(i, memoryview(a))
        self.fb_r.set_res(0, memoryview(self.r_out))
        self.fb_rJ.set_res(0, memoryview(self.rJ_r))
        if group.nx:
            self.fb_rJ.set_res(1, memoryview(self.rJ_J))
        self.n_eval = 0
        self._x_J: np.ndarray | None = None
        self._r = np.zeros(0)
        self._J = np.zeros((0, 0))

    def set_pb(self, pb: np.ndarray) -> None:
        self.pb[:] = pb
        self._x_J = None

    def residuals_only(self, x: np.ndarray) -> np.ndarray:
        self.x[:] = x
        self.ev_r()
        return self.r_out[: self.N].ravel().copy()

    def residuals_jacobian(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Residuals and Jacobian at ``x``; the last point's values are kept, because
        least_squares asks for the Jacobian at the point of its last residual call."""
        if self._x_J is not None and np.array_equal(self._x_J, x):
            return self._r.copy(), self._J.copy()
        self.x[:] = x
        self.ev_rJ()
        self.n_eval += 1
        r = self.rJ_r[: self.N].ravel().copy()
        J = self.rJ_J[: self.N, : self.group.nx].transpose(0, 2, 1).reshape(self.N * self.group.nr, self.group.nx).copy()
        self._x_J, self._r, self._J = np.array(x, dtype=float), r, J
        return r.copy(), J.copy()

    def residuals(self, x: np.ndarray) -> np.ndarray:
        return self.residuals_jacobian(x)[0]

    def jacobian(self, x: np.ndarray) -> np.ndarray:
        return self.residuals_jacobian(x)[1]

    def nlp_parameters(self, scale: float) -> np.ndarray:
        parts = [np.array([scale]), self.pb] + [a.ravel() for a in self.inputs[2:]]
        return np.concatenate(parts)


# ------------------------------------------------------------------ results
@dataclass
class GroupResult:
    """Result of one group of arms (one NLP).

    Parameters
    ----------
    arms : tuple of int
        Arm indices (0-based) solved together.
    variable_names : tuple of str
        Names of the NLP variables (free parameters; ``<quaternion>_rx/ry/rz`` for the
        local rotation of a quaternion parameter).
    status : str
        ``"optimal"``, ``"acceptable"``, ``"max_iterations"`` or ``"error"`` (``"fixed"``
        for a group without variables).
    message : str
        Solver message.
    iterations : int
        Iterations (Jacobian evaluations for least_squares, IPOPT iterations).
    initial_cost : float
        ``V`` of the group at the start [m^4].
    cost : float
        ``V`` of the group at the solution [m^4].
    sigma : float
        Residual standard deviation ``sqrt(RSS / (m - n))`` [m^2].
    n_residuals : int
        Number of residuals (links x poses with non-zero weight).
    identifiability : IdentifiabilityReport
        Report at the solution (variables of the group; empty for a group without
        variables).
    """

    arms: tuple[int, ...]
    variable_names: tuple[str, ...]
    status: str
    message: str
    iterations: int
    initial_cost: float
    cost: float
    sigma: float
    n_residuals: int
    identifiability: IdentifiabilityReport


@dataclass
class CalibrationResult:
    """Result of a kinematic calibration (python-control style: status, never None).

    Parameters
    ----------
    success : bool
        True if every group ended ``"optimal"`` or ``"acceptable"``.
    status : str
        Worst group status: ``"optimal"``, ``"acceptable"``, ``"max_iterations"`` or
        ``"error"``.
    message : str
        Per-group solver messages.
    model : ClosureModel
        The calibrated model (in the measurement frame), ``aligned.with_parameters(p)``.
    parameters : dict of str to float
        Calibrated parameters (SI units).
    initial_parameters : dict of str to float
        Start values in the measurement frame (after alignment and ties).
    std : dict of str to float
        Standard deviation of each parameter (0 for fixed ones; ``inf`` if not
        identifiable at the solution or without residual degrees of freedom, ``m = n``).
    cost : float
        ``V`` at the solution (eq. 5.2) [m^4].
    cost_per_arm : numpy.ndarray, shape (n_arms,)
        ``V`` of each arm at the solution [m^4].
    initial_cost_per_arm : numpy.ndarray, shape (n_arms,)
        ``V`` of each arm at the start [m^4].
    iterations : int
        Iterations summed over the groups.
    solve_time : float
        Wall time of the solves [s] (without building the CasADi functions).
    build_time : float
        Wall time spent building CasADi functions and solvers in this call [s] (0 when
        re-used).
    identifiability : IdentifiabilityReport
        Identifiability of all free variables at the solution (block-diagonal Jacobian
        of the groups; standard deviations per group).
    groups : tuple of GroupResult
        One entry per NLP.
    rotation : numpy.ndarray, shape (3, 3)
        Rotation of the frame alignment (identity without alignment).
    translation : numpy.ndarray, shape (3,)
        Translation of the frame alignment [m].
    quaternion_norms : dict of str to float
        Norm of each quaternion parameter after the solve (1 to round-off).
    residuals : numpy.ndarray, shape (N, n_links)
        Weighted closure residuals at the solution [m^2], links in model order.
    solver : str
        Solver used.
    n_poses : int
        Number of poses.
    """

    success: bool
    status: str
    message: str
    model: ClosureModel
    parameters: dict[str, float]
    initial_parameters: dict[str, float]
    std: dict[str, float]
    cost: float
    cost_per_arm: np.ndarray
    initial_cost_per_arm: np.ndarray
    iterations: int
    solve_time: float
    build_time: float
    identifiability: IdentifiabilityReport
    groups: tuple[GroupResult, ...]
    rotation: np.ndarray
    translation: np.ndarray
    quaternion_norms: dict[str, float]
    residuals: np.ndarray
    solver: str
    n_poses: int

    @property
    def parameter_vector(self) -> np.ndarray:
        """Calibrated parameters in model order (``model.parameter_vector()``)."""
        return np.array(list(self.parameters.values()))

    def summary(self) -> str:
        """A short text summary: status, cost per arm, iterations, times.

        Returns
        -------
        str
        """
        arms = ", ".join(f"arm {i + 1}: {c:.3g}" for i, c in enumerate(self.cost_per_arm))
        return (
            f"calibration {self.status} ({self.solver}, {self.n_poses} poses): V = {self.cost:.4g} m^4 ({arms}); "
            f"{self.iterations} iterations, solve {1e3 * self.solve_time:.1f} ms, build {1e3 * self.build_time:.1f} ms"
        )


_STATUS_RANK = {"optimal": 0, "fixed": 0, "acceptable": 1, "max_iterations": 2, "error": 3}


def _worst_status(statuses: Iterable[str]) -> str:
    """The worst of solver statuses (optimal < acceptable < max_iterations < error; an unknown
    status ranks as error; the first of equally bad ones), ``"optimal"`` for none."""
    return max(statuses, key=lambda s: _STATUS_RANK.get(s, 3), default="optimal")


# ------------------------------------------------------------------ the problem
class CalibrationProblem:
    """Calibration NLPs of a model and a parameter selection, built once, solved many times.

    The CasADi graphs depend on the model's structure and the selection only: the data
    (poses, measurements, weights) and the start values are inputs. They are evaluated
    with the parameter vector of any model with the same structure (``with_parameters``
    or ``transformed`` of ``model``): a closure model's equations depend on the instance
    only through its parameter vector (the :class:`~gtmodel.robots.closure.ClosureModel`
    contract).

    Parameters
    ----------
    model : ClosureModel
        The (nominal) model.
    selection : ParameterSelection, optional
        Free/fixed/tied parameters; default: all parameters free.

    Raises
    ------
    InputError
        If the selection does not fit the model: unknown names (with close matches), a
        parameter both free and fixed, a tie whose target is free or fixed, tie cycles,
        ties on quaternion components, or a quaternion that is only partly free.
    ModelError
        If a free parameter enters no closure equation (it cannot be identified).
    """

    def __init__(self, model: ClosureModel, selection: ParameterSelection | None = None) -> None:
        if not isinstance(model, ClosureModel):
            raise InputError(f"model: expected a ClosureModel, got {type(model).__name__}")
        self.model = model
        self.selection = selection if selection is not None else ParameterSelection()
        self.resolution = self.selection._resolve(model)
        res = self.resolution
        n_arms = len(model.links)
        arm_vars = [res.variables_of(model.arm_parameter_indices(a)) for a in range(n_arms)]
        used = set().union(*arm_vars) if arm_vars else set()
        unused = [res.var_names[v] for v in range(res.n_vars) if v not in used]
        if unused:
            raise ModelError(
                f"{model.name}: free parameter(s) {', '.join(unused)} enter no closure equation and cannot be "
                "identified from these measurements; fix them"
            )
        # connected components of arms over shared variables
        parent = list(range(n_arms))

        def find(a: int) -> int:
            while parent[a] != a:
                parent[a] = parent[parent[a]]
                a = parent[a]
            return a

        for a in range(n_arms):
            for b in range(a + 1, n_arms):
                if arm_vars[a] & arm_vars[b]:
                    parent[find(b)] = find(a)
        comps: dict[int, list[int]] = {}
        for a in range(n_arms):
            comps.setdefault(find(a), []).append(a)
        self.arm_groups: tuple[tuple[int, ...], ...] = tuple(tuple(v) for v in comps.values())
        self._group_vars = [sorted(set().union(*[arm_vars[a] for a in arms])) for arms in self.arm_groups]
        self._groups: list[_Group] | None = None
        self._pfun: ca.Function | None = None
        self._closure_cache: dict[int, ca.Function] = {}
        self._fk_cache: dict[str, tuple[np.ndarray, np.ndarray]] = {}
        self._transform_safe: bool | None = None
        self.build_time = 0.0

    # -------------------------------------------------------------- building
    @property
    def variable_names(self) -> tuple[str, ...]:
        """Names of all NLP variables (free parameters; quaternions as ``_rx, _ry, _rz``)."""
        return self.resolution.var_names

    def _build(self) -> float:
        if self._groups is not None:
            return 0.0
        t0 = time.perf_counter()
        self._groups = [
            _Group(self.model, self.resolution, arms, vars_) for arms, vars_ in zip(self.arm_groups, self._group_vars)
        ]
        x = ca.SX.sym("x", self.resolution.n_vars)
        pb = ca.SX.sym("p0", self.model.n_parameters)
        p = _parameter_expression(self.resolution, x, pb, {v: v for v in range(self.resolution.n_vars)})
        self._pfun = ca.Function("p_of_x", [x, pb], [p, ca.densify(ca.jacobian(p, x))])
        n_p, n_x = self.model.n_parameters, self.resolution.n_vars
        self._pfun_io = [np.zeros(n_x), np.zeros(n_p), np.zeros(n_p), np.zeros((n_x, n_p))]
        self._pfun_fb, self._pfun_ev = self._pfun.buffer()
        for i, a in enumerate(self._pfun_io[:2]):
            if a.size:
                self._pfun_fb.set_arg(i, memoryview(a))
        for i, a in enumerate(self._pfun_io[2:]):
            if a.size:
                self._pfun_fb.set_res(i, memoryview(a))
        dt = time.perf_counter() - t0
        self.build_time += dt
        return dt

    # -------------------------------------------------------------- helpers
    def _anchor(self, p: np.ndarray) -> np.ndarray:
        """Start/anchor vector: quaternions normalised, ties applied."""
        pb = np.array(p, dtype=float)
        for qi in self.resolution.quaternions:
            v = pb[list(qi)]
            nv = np.linalg.norm(v)
            if not nv > 0:
                raise InputError(f"{self.model.name}: quaternion parameter {self.resolution.names[qi[0]]} is zero")
            pb[list(qi)] = v / nv
        for t in self.resolution.targets:
            pb[t] = pb[int(self.resolution.root[t])]
        return pb

    def _x_of(self, pb: np.ndarray) -> np.ndarray:
        """Variables at the anchor ``pb``: free scalars their values, rotations zero."""
        x = np.zeros(self.resolution.n_vars)
        for v, comp in enumerate(self.resolution.var_comp):
            if comp < 0:
                x[v] = pb[self.resolution.var_kind[self.resolution.kind_of_var[v]][1]]
        return x

    def _p_of(self, x: np.ndarray, pb: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Parameter vector p(x, p0) and dp/dx (n_parameters, n_variables)."""
        xin, pin, pout, dpout = self._pfun_io
        xin[:] = x
        pin[:] = pb
        self._pfun_ev()
        return pout.copy(), dpout.T.copy()  # the buffer holds dp/dx column-major

    def _check_counts(self, data: _Data) -> None:
        n_active = int(np.sum(data.weights > 0))
        for arms, g in zip(self.arm_groups, self._group_vars):
            m = n_active * sum(len(self.model.links[a]) for a in arms)
            if g and m < len(g):
                arm_s = ", ".join(str(a + 1) for a in arms)
                raise InputError(
                    f"too few poses for arm(s) {arm_s}: {m} residuals ({n_active} poses with non-zero weight) "
                    f"for {len(g)} free parameters"
                )

    # -------------------------------------------------------------- public
    def jacobian(
        self,
        p: np.typing.ArrayLike,
        q: np.typing.ArrayLike,
        T: np.typing.ArrayLike,
        quat: np.typing.ArrayLike | None = None,
        weights: np.typing.ArrayLike | None = None,
    ) -> tuple[np.ndarray, np.ndarray, tuple[str, ...]]:
        """Closure residuals and their exact Jacobian with respect to all free variables.

        Parameters
        ----------
        p : array_like, shape (n_parameters,)
            Parameter values (quaternion variables are evaluated at their anchor ``p``).
        q : array_like, shape (N, n_q)
            Actuator values [m, rad].
        T : array_like, shape (N, 3)
            TCP positions [m].
        quat : array_like, shape (N, 4), optional
            Plate orientations ``(w, x, y, z)`` (required for models with orientation).
        weights : array_like, shape (N,), optional
            Pose weights (residuals are multiplied by their square root).

        Returns
        -------
        r : numpy.ndarray, shape (N, n_links)
            Weighted residuals [m^2], links in model order.
        J : numpy.ndarray, shape (N, n_links, n_variables)
            ``d r / d x`` per pose (zero where a link does not depend on a variable).
        names : tuple of str
            Variable names (columns of ``J``).

        Raises
        ------
        InputError
            Wrong shapes or non-finite data.
        """
        data = _check_data(self.model, q, T, quat, weights)
        pa = np.asarray(p, dtype=float).ravel()
        if pa.size != self.model.n_parameters or not np.all(np.isfinite(pa)):
            raise InputError(f"p: expected {self.model.n_parameters} finite parameter values, got {pa.size}")
        self._build()
        pb = self._anchor(pa)
        x_all = self._x_of(pb)
        N = data.N
        offsets = np.cumsum([0] + [len(l) for l in self.model.links])
        r_out = np.zeros((N, self.model.n_links))
        J_out = np.zeros((N, self.model.n_links, self.resolution.n_vars))
        for grp in self._groups:
            ev = _Evaluator(grp, data, pb)
            r, J = ev.residuals_jacobian(x_all[grp.var_idx])
            rows = np.concatenate([np.arange(offsets[a], offsets[a + 1]) for a in grp.arms])
            r_out[:, rows] = r.reshape(N, grp.nr)
            if grp.nx:
                J_out[np.ix_(np.arange(N), rows, grp.var_idx)] = J.reshape(N, grp.nr, grp.nx)
        return r_out, J_out, self.resolution.var_names

    def solve(
        self,
        q: Any,
        T: np.typing.ArrayLike | None = None,
        quat: np.typing.ArrayLike | None = None,
        weights: np.typing.ArrayLike | None = None,
        start: ClosureModel | np.typing.ArrayLike | None = None,
        solver: str = DEFAULT_SOLVER,
        align: bool = True,
        max_iter: int = MAX_ITER,
    ) -> CalibrationResult:
        """Calibrate: align the frame, solve each group of arms, report.

        Parameters
        ----------
        q : array_like, shape (N, n_q), or MeasurementSet
            Actuator values [m, rad] (or a measurement set with ``q, T, quat, weights``).
        T : array_like, shape (N, 3)
            Measured TCP positions [m] (omit when ``q`` is a measurement set).
        quat : array_like, shape (N, 4), optional
            Measured plate orientations ``(w, x, y, z)`` (required for models with
            orientation, ignored by constant-orientation models).
        weights : array_like, shape (N,), optional
            Non-negative pose weights; residuals are multiplied by ``sqrt(w)``.
        start : ClosureModel or array_like, optional
            Start model or parameter vector (default: the problem's model). Must have
            the structure of the problem's model.
        solver : {"lm", "trf", "ipopt", "ipopt-gn"}, optional
            Solver (default :data:`DEFAULT_SOLVER`).
        align : bool, optional
            Move the start model into the measurement frame first (eqs. 5.3-5.4).
        max_iter : int, optional
            Iteration limit per group.

        Returns
        -------
        CalibrationResult
            Never None; a non-converged solve is a status.

        Raises
        ------
        InputError
            Wrong shapes, non-finite data, unknown solver, or too few poses for the free
            parameters of some arm group (the message names the arms and the counts).
        ModelError
            If the Jacobian at the start is rank-deficient: the message lists the
            non-identifiable parameters and what they depend on; the
            :class:`~gtmodel.calibration.identifiability.IdentifiabilityReport` is
            attached as the exception's ``report`` attribute.
        """
        if solver not in SOLVERS:
            close = difflib.get_close_matches(str(solver), SOLVERS, n=2)
            hint = f" (did you mean {close[0]!r}?)" if close else ""
            raise InputError(f"solver: expected one of {', '.join(SOLVERS)}, got {solver!r}{hint}")
        if not (isinstance(max_iter, (int, np.integer)) and max_iter > 0):
            raise InputError(f"max_iter: expected a positive integer, got {max_iter!r}")
        q, T, quat, weights = _unpack_measurements(q, T, quat, weights, self.model)
        data = _check_data(self.model, q, T, quat, weights)
        self._check_counts(data)
        build = self._build()

        if start is None:
            start_model = self.model
        elif isinstance(start, ClosureModel):
            if tuple(start.parameter_names()) != self.resolution.names or type(start) is not type(self.model):
                raise InputError(f"start: expected a {type(self.model).__name__} with the parameters of {self.model.name}")
            start_model = start
        else:
            start_model = self.model.with_parameters(start)
        evs = [_Evaluator(grp, data, self.model.parameter_vector()) for grp in self._groups]
        if align:
            aligned, Rf, tf = self._best_alignment(start_model, data, evs)
        else:
            aligned, Rf, tf = start_model, np.eye(3), np.zeros(3)
        if not self._shares_equations(start_model, aligned, data):
            # the model's equations hold instance data besides its parameters: build for it
            _log.info("%s: closure equations differ from the problem's model; building for the start model", self.model.name)
            res = CalibrationProblem(aligned, self.selection).solve(
                data.q, data.T, data.quat if self.model.orientation else None, data.weights,
                solver=solver, align=False, max_iter=max_iter,
            )
            res.rotation, res.translation = Rf, tf
            res.build_time += build
            return res
        pb = self._anchor(aligned.parameter_vector())
        x_all = self._x_of(pb)
        p_init, _ = self._p_of(x_all, pb)

        t_solve = 0.0
        group_results: list[GroupResult] = []
        reports: list[IdentifiabilityReport] = []
        x_final = x_all.copy()
        pb_final = pb.copy()
        cov_x = np.zeros((self.resolution.n_vars, self.resolution.n_vars))
        offsets = np.cumsum([0] + [len(l) for l in self.model.links])
        n_arms = len(self.model.links)
        cost_arm = np.zeros(n_arms)
        cost0_arm = np.zeros(n_arms)
        residuals = np.zeros((data.N, self.model.n_links))
        active = data.weights > 0
        for grp, ev in zip(self._groups, evs):
            ev.set_pb(pb_final)
            mask = np.repeat(active, grp.nr)
            m = int(mask.sum())
            x0 = x_all[grp.var_idx].copy()
            r0, J0 = ev.residuals_jacobian(x0)
            V0 = float(r0 @ r0)
            if grp.nx == 0:
                r, V = r0, V0
                group_results.append(
                    GroupResult(grp.arms, (), "fixed", "no free parameters", 0, V0, V0, 0.0, m, combine_reports([]))
                )
            else:
                if numerical_rank(J0[mask]) < grp.nx:
                    rep0 = analyze_jacobian(J0[mask], grp.var_names)
                    arm_s = ", ".join(str(a + 1) for a in grp.arms)
                    err = ModelError(
                        f"{self.model.name}, arm(s) {arm_s}: the calibration problem is singular at the start "
                        f"(rank {rep0.rank} of {rep0.n_parameters}); not identifiable: {rep0.describe()}. "
                        "Fix or tie these parameters, or measure more varied poses"
                    )
                    err.report = rep0  # type: ignore[attr-defined]
                    raise err
                t0 = time.perf_counter()
                x, status, message, iters, b = self._solve_group(grp, ev, x0, solver, int(max_iter))
                # quaternions: move the anchors to the solution; if the solve failed after a
                # large local rotation, solve again from the new anchor
                for _ in range(MAX_REANCHOR if grp.has_quaternion else 0):
                    big = self._reanchor(grp, ev, x)
                    x = self._zero_rotations(grp, x)
                    if not big or status in ("optimal", "acceptable"):
                        break
                    x, status, message, it2, b2 = self._solve_group(grp, ev, x, solver, int(max_iter))
                    iters += it2
                    b += b2
                t_solve += time.perf_counter() - t0 - b
                build += b
                r, J = ev.residuals_jacobian(x)
                V = float(r @ r)
                sigma = math.sqrt(V / (m - grp.nx)) if m > grp.nx else math.inf
                rep = analyze_jacobian(J[mask], grp.var_names, residuals=r[mask] if m > grp.nx else None)
                reports.append(rep)
                x_final[grp.var_idx] = x
                pb_final[:] = ev.pb  # carries this group's re-anchored quaternions
                if rep.covariance.size:
                    cov_x[np.ix_(grp.var_idx, grp.var_idx)] = rep.covariance
                else:  # no residual variance (m == n): deviations unknown
                    cov_x[np.ix_(grp.var_idx, grp.var_idx)] = math.inf
                group_results.append(GroupResult(grp.arms, grp.var_names, status, message, iters, V0, V, sigma, m, rep))
                _log.info("calibration arm(s) %s: %s, %d iterations, V %.4g -> %.4g", grp.arms, status, iters, V0, V)
            r = r.reshape(data.N, grp.nr)
            r0 = r0.reshape(data.N, grp.nr)
            c = 0
            for a in grp.arms:
                nl = len(self.model.links[a])
                cost_arm[a] = float(np.sum(r[:, c:c + nl] ** 2))
                cost0_arm[a] = float(np.sum(r0[:, c:c + nl] ** 2))
                residuals[:, offsets[a]:offsets[a] + nl] = r[:, c:c + nl]
                c += nl

        # final parameters from the (re-anchored) variables; deviations through dp/dx
        p_final, dp = self._p_of(x_final, pb_final)
        for qi in self.resolution.quaternions:
            v = p_final[list(qi)]
            p_final[list(qi)] = v / np.linalg.norm(v)
        inf_vars = np.isinf(np.diag(cov_x)) if cov_x.size else np.zeros(0, dtype=bool)
        var_p = np.einsum("ij,jk,ik->i", dp, np.where(np.isinf(cov_x), 0.0, cov_x), dp)
        touches_inf = (np.abs(dp[:, inf_vars]) > 0).any(axis=1) if inf_vars.any() else np.zeros(len(p_final), dtype=bool)
        std_p = np.where(touches_inf, math.inf, np.sqrt(np.maximum(var_p, 0.0)))

        names = self.resolution.names
        worst = _worst_status(g.status for g in group_results)
        status = "optimal" if worst == "fixed" else worst
        message = "; ".join(f"arm(s) {','.join(str(a + 1) for a in g.arms)}: {g.message}" for g in group_results)
        qnorms = {}
        for qi in self.resolution.quaternions:
            base = names[qi[0]][:-2] if names[qi[0]].endswith("_w") else names[qi[0]]
            qnorms[base] = float(np.linalg.norm(p_final[list(qi)]))
        return CalibrationResult(
            success=status in ("optimal", "acceptable"),
            status=status,
            message=message,
            model=aligned.with_parameters(p_final),
            parameters={n: float(v) for n, v in zip(names, p_final)},
            initial_parameters={n: float(v) for n, v in zip(names, p_init)},
            std={n: float(v) for n, v in zip(names, std_p)},
            cost=float(cost_arm.sum()),
            cost_per_arm=cost_arm,
            initial_cost_per_arm=cost0_arm,
            iterations=int(sum(g.iterations for g in group_results)),
            solve_time=t_solve,
            build_time=build,
            identifiability=combine_reports(reports),
            groups=tuple(group_results),
            rotation=Rf,
            translation=tf,
            quaternion_norms=qnorms,
            residuals=residuals,
            solver=solver,
            n_poses=data.N,
        )

    # -------------------------------------------------------------- internals
    def _start_cost(self, p: np.ndarray, evs: list["_Evaluator"]) -> float:
        """V (eq. 5.2) of all groups at the parameter vector ``p``."""
        pb = self._anchor(p)
        x = self._x_of(pb)
        V = 0.0
        for grp, ev in zip(self._groups, evs):
            ev.set_pb(pb)
            r = ev.residuals_only(x[grp.var_idx])
            V += float(r @ r)
        return V

    def _nominal_fk(self, model: ClosureModel, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Nominal FK positions, cached for the problem's own model (same q, other T)."""
        if model is not self.model:
            return _nominal_positions(model, q)
        key = hashlib.sha1(q.tobytes()).hexdigest() + str(q.shape)
        if key not in self._fk_cache:
            if len(self._fk_cache) >= FK_CACHE_SIZE:
                self._fk_cache.pop(next(iter(self._fk_cache)))
            self._fk_cache[key] = _nominal_positions(model, q)
        return self._fk_cache[key]

    def _best_alignment(
        self, model: ClosureModel, data: _Data, evs: list["_Evaluator"]
    ) -> tuple[ClosureModel, np.ndarray, np.ndarray]:
        """The start model in the measurement frame (eqs. 5.3-5.4), guarded by the cost.

        Candidates: no transform, the translation of the centroids, and the rigid fit of
        :func:`fit_rigid_transform`; the one with the lowest ``V`` at the start is used. The
        rigid fit moves a start model into a far-away device frame, but on a small pose
        cloud with a poor nominal model its rotation can be far off (worse than none).
        """
        Tn, ok = self._nominal_fk(model, data.q)
        ok = ok & (data.weights > 0)
        cands: list[tuple[ClosureModel, np.ndarray, np.ndarray]] = [(model, np.eye(3), np.zeros(3))]
        if ok.sum() >= 3:
            w = data.weights[ok] / data.weights[ok].sum()
            t_only = w @ (data.T[ok] - Tn[ok])
            cands.append((model.transformed(np.eye(3), t_only), np.eye(3), t_only))
            R, t = fit_rigid_transform(Tn[ok], data.T[ok], data.weights[ok])
            cands.append((model.transformed(R, t), R, t))
        else:
            _log.warning(
                "%s: nominal forward kinematics succeeds for %d poses only; no frame alignment", model.name, int(ok.sum())
            )
        costs = [self._start_cost(m.parameter_vector(), evs) for m, _, _ in cands]
        best = int(np.argmin(costs))
        _log.info("frame alignment: start V %s -> candidate %d", ", ".join(f"{c:.3g}" for c in costs), best)
        return cands[best]

    def _equal_closures(self, other: ClosureModel, q: np.ndarray, T: np.ndarray, quat: np.ndarray) -> bool:
        """Whether ``other`` has the problem model's closure equations (at its p and one pose)."""
        if type(other) is not type(self.model) or tuple(other.parameter_names()) != self.resolution.names:
            return False
        args = (other.parameter_vector(), q, T, quat)
        for a in range(len(self.model.links)):
            if a not in self._closure_cache:
                self._closure_cache[a] = self.model.closure_function(a)
            r0 = np.array(self._closure_cache[a](*args)).ravel()
            r1 = np.array(other.closure_function(a)(*args)).ravel()
            if not np.allclose(r0, r1, rtol=1e-12, atol=1e-15):
                return False
        return True

    def _shares_equations(self, start: ClosureModel, aligned: ClosureModel, data: _Data) -> bool:
        """Whether the problem's graphs hold for ``aligned`` (see :class:`CalibrationProblem`).

        ``with_parameters`` keeps a model's equations (the interface contract); whether
        ``transformed`` does (only parameters change) is checked once per problem with a
        test transform, and a start model that is another instance is checked explicitly.
        """
        if aligned is self.model:
            return True
        q0, T0, quat0 = data.q[0], data.T[0], data.quat[0]
        if start is not self.model and not self._equal_closures(start, q0, T0, quat0):
            return False
        if aligned is start:
            return True
        if self._transform_safe is None:
            R = rotation_vector_to_rotation([0.3, -0.2, 0.5])
            moved = self.model.transformed(R, [0.1, -0.2, 0.3])
            self._transform_safe = self._equal_closures(moved, q0, T0 @ R.T, quat0)
        return bool(self._transform_safe)

    def _reanchor(self, grp: _Group, ev: _Evaluator, x: np.ndarray) -> bool:
        """Move the group's quaternion anchors (in ``ev.pb``) to the solution ``x``.

        Returns True if some local rotation exceeded :data:`REANCHOR_ANGLE`.
        """
        x_all = self._x_of(ev.pb)
        x_all[grp.var_idx] = x
        p, _ = self._p_of(x_all, ev.pb)
        big = False
        for k, js, _ in grp.quaternion_slots:
            qi = list(self.resolution.quaternions[k])
            big |= bool(np.linalg.norm(x[js]) > REANCHOR_ANGLE)
            ev.pb[qi] = p[qi] / np.linalg.norm(p[qi])
        ev.set_pb(ev.pb.copy())  # drops the cached Jacobian
        return big

    @staticmethod
    def _zero_rotations(grp: _Group, x: np.ndarray) -> np.ndarray:
        """Group variables after re-anchoring: rotation components zero, the rest kept."""
        out = x.copy()
        for _, js, _ in grp.quaternion_slots:
            out[js] = 0.0
        return out

    @staticmethod
    def _polish(ev: _Evaluator, x: np.ndarray) -> tuple[np.ndarray, int]:
        """Gauss-Newton steps with the exact Jacobian after a converged least_squares run.

        least_squares stops when the decrease of V falls below the rounding of V, which
        near the optimum is reached ~1e-11 away from it (the closure residual
        ``|A - B|^2 - L^2`` cancels ~11 digits); the Gauss-Newton step uses the gradient,
        which is not affected, and lands on the optimum to ~1e-14. Steps larger than
        :data:`POLISH_MAX_STEP` (relative) are not taken.
        """
        n = 0
        for _ in range(POLISH_STEPS):
            r, J = ev.residuals_jacobian(x)
            dx = np.linalg.lstsq(J, -r, rcond=None)[0]
            scale = 1.0 + float(np.linalg.norm(x))
            if not np.all(np.isfinite(dx)) or np.linalg.norm(dx) > POLISH_MAX_STEP * scale:
                break
            x = x + dx
            n += 1
            if np.linalg.norm(dx) <= 1e-15 * scale:
                break
        return x, n

    def _solve_group(
        self, grp: _Group, ev: _Evaluator, x0: np.ndarray, solver: str, max_iter: int
    ) -> tuple[np.ndarray, str, str, int, float]:
        """Solve one group; returns x, status, message, iterations, build time spent."""
        if solver in ("lm", "trf"):
            try:
                sol = scipy.optimize.least_squares(
                    ev.residuals, x0, jac=ev.jacobian, method=solver, x_scale="jac",
                    ftol=LSQ_TOLERANCE, xtol=LSQ_TOLERANCE, gtol=LSQ_TOLERANCE, max_nfev=max_iter,
                )
            except (ValueError, np.linalg.LinAlgError) as e:
                return x0, "error", f"least_squares failed: {e}", 0, 0.0
            iters = int(sol.njev) if sol.njev is not None else int(sol.nfev)
            if sol.status > 0 and np.all(np.isfinite(sol.x)):
                status = "optimal"
            elif sol.status == 0:
                status = "max_iterations"
            else:
                status = "error"
            x = sol.x
            if status == "optimal":
                x, n_polish = self._polish(ev, x)
                iters += n_polish
            return x, status, str(sol.message), iters, 0.0
        t0 = time.perf_counter()
        nlp = grp.nlp(solver, ev.M, max_iter)
        b = time.perf_counter() - t0
        # objective V / S with S the largest gradient component at the start: IPOPT's tol
        # is then a relative gradient reduction, above the rounding floor of grad V
        r0, J0 = ev.residuals_jacobian(x0)
        S = max(float(np.max(np.abs(2.0 * J0.T @ r0))), 1e-300)
        sol = nlp(x0=x0, p=ev.nlp_parameters(1.0 / S))
        st = nlp.stats()
        x = np.array(sol["x"]).ravel()
        ret = str(st.get("return_status", ""))
        status = normalize_ipopt_status(ret)
        iters = int(st.get("iter_count", 0))
        if not np.all(np.isfinite(x)):
            return x0, "error", ret, iters, b
        if ret == "Search_Direction_Becomes_Too_Small":
            # IPOPT cannot move any more; accept if a Gauss-Newton step confirms the optimum
            x_p, n_p = self._polish(ev, x)
            if n_p:
                return x_p, "acceptable", f"{ret} (optimum confirmed by {n_p} Gauss-Newton step(s))", iters + n_p, b
        return x, status, ret, iters, b


# ------------------------------------------------------------------ convenience
#: Problems kept by :func:`calibrate` (least recently used dropped first); each holds its
#: model, so the cache is bounded rather than weak.
PROBLEM_CACHE_SIZE = 16
_PROBLEMS: "OrderedDict[tuple[int, Any], CalibrationProblem]" = OrderedDict()


def _selection_of(selection: Any, free: Any, fixed: Any, ties: Any) -> ParameterSelection:
    if selection is not None:
        if free is not None or fixed is not None or ties is not None:
            raise InputError("give either selection or free/fixed/ties, not both")
        if not isinstance(selection, ParameterSelection):
            raise InputError(f"selection: expected a ParameterSelection, got {type(selection).__name__}")
        return selection
    return ParameterSelection(free=free, fixed=fixed or (), ties=ties or ())


def _problem(model: ClosureModel, sel: ParameterSelection) -> CalibrationProblem:
    if not isinstance(model, ClosureModel):
        raise InputError(f"model: expected a ClosureModel, got {type(model).__name__}")
    key = (id(model), (sel.free, sel.fixed, sel.ties))
    problem = _PROBLEMS.get(key)
    if problem is None or problem.model is not model:
        problem = CalibrationProblem(model, sel)
        _PROBLEMS[key] = problem
        while len(_PROBLEMS) > PROBLEM_CACHE_SIZE:
            _PROBLEMS.popitem(last=False)
    _PROBLEMS.move_to_end(key)
    return problem


def calibrate(
    model: ClosureModel,
    q: Any,
    T: np.typing.ArrayLike | None = None,
    quat: np.typing.ArrayLike | None = None,
    weights: np.typing.ArrayLike | None = None,
    *,
    selection: ParameterSelection | None = None,
    free: str | Sequence[str] | None = None,
    fixed: str | Sequence[str] | None = None,
    ties: str | Sequence[Any] | Mapping[str, str] | None = None,
    solver: str = DEFAULT_SOLVER,
    align: bool = True,
    max_iter: int = MAX_ITER,
) -> CalibrationResult:
    """Calibrate a kinematic model from measured poses (Dressler (2012), eqs. 5.1-5.4).

    Builds (or re-uses, per model instance and selection) a :class:`CalibrationProblem`
    and solves it; see the module docstring for the method.

    Parameters
    ----------
    model : ClosureModel
        Nominal model (start values; moved into the measurement frame if ``align``).
    q : array_like, shape (N, n_q), or MeasurementSet
        Actuator values [m, rad] (or a measurement set with ``q, T, quat, weights``).
    T : array_like, shape (N, 3)
        Measured TCP positions [m].
    quat : array_like, shape (N, 4), optional
        Measured orientations ``(w, x, y, z)`` (models with orientation).
    weights : array_like, shape (N,), optional
        Non-negative pose weights (residuals multiplied by ``sqrt(w)``).
    selection : ParameterSelection, optional
        Free/fixed/tied parameters (alternative to ``free``, ``fixed``, ``ties``).
    free : str or sequence of str, optional
        Free parameter names or patterns (default: all not fixed or tied).
    fixed : str or sequence of str, optional
        Fixed parameter names or patterns.
    ties : str or sequence or mapping, optional
        ``"target = source"`` ties.
    solver : {"lm", "trf", "ipopt", "ipopt-gn"}, optional
        Solver (default :data:`DEFAULT_SOLVER`).
    align : bool, optional
        Fit the base transform first (default True).
    max_iter : int, optional
        Iteration limit per group.

    Returns
    -------
    CalibrationResult

    Raises
    ------
    InputError
        Bad shapes or values, unknown parameter names (with close matches), too few poses
        for an arm group.
    ModelError
        Singular problem at the start (non-identifiable parameters listed with their
        dependencies; ``report`` attribute), or a free parameter in no closure equation.
    """
    sel = _selection_of(selection, free, fixed, ties)
    problem = _problem(model, sel)
    return problem.solve(q, T, quat, weights, solver=solver, align=align, max_iter=max_iter)


def analyze_identifiability(
    model: ClosureModel,
    q: Any,
    T: np.typing.ArrayLike | None = None,
    quat: np.typing.ArrayLike | None = None,
    weights: np.typing.ArrayLike | None = None,
    *,
    selection: ParameterSelection | None = None,
    free: str | Sequence[str] | None = None,
    fixed: str | Sequence[str] | None = None,
    ties: str | Sequence[Any] | Mapping[str, str] | None = None,
) -> IdentifiabilityReport:
    """Identifiability of a model's free parameters from a pose set, at the model's values.

    The Jacobian of all closure residuals (eqs. 5.1-5.2) with respect to the free
    variables is analysed by :func:`~gtmodel.calibration.identifiability.analyze_jacobian`
    (column-pivoted QR, Dressler (2012), Table 5.4). No frame alignment: ``T`` must be in
    the model's frame (e.g. its own FK for a planned pose set).

    Parameters
    ----------
    model : ClosureModel
        The model (its parameter values are the linearisation point).
    q : array_like, shape (N, n_q), or MeasurementSet
        Actuator values [m, rad].
    T : array_like, shape (N, 3)
        TCP positions [m].
    quat : array_like, shape (N, 4), optional
        Plate orientations (models with orientation).
    weights : array_like, shape (N,), optional
        Pose weights.
    selection : ParameterSelection, optional
        Free/fixed/tied parameters.
    free : str or sequence of str, optional
        Free parameter names or patterns.
    fixed : str or sequence of str, optional
        Fixed parameter names or patterns.
    ties : str or sequence or mapping, optional
        ``"target = source"`` ties.

    Returns
    -------
    IdentifiabilityReport
        With standard deviations from the residuals at the model's values if there are
        more residuals than variables.

    Raises
    ------
    InputError
        Bad shapes, values or names.
    ModelError
        A free parameter enters no closure equation.
    """
    sel = _selection_of(selection, free, fixed, ties)
    problem = _problem(model, sel)
    q, T, quat, weights = _unpack_measurements(q, T, quat, weights, model)
    r, J, names = problem.jacobian(model.parameter_vector(), q, T, quat, weights)
    w = np.ones(r.shape[0]) if weights is None else np.asarray(weights, dtype=float).ravel()
    keep = w > 0
    Jm = J[keep].reshape(-1, len(names))
    rm = r[keep].ravel()
    return analyze_jacobian(Jm, names, residuals=rm if rm.size > len(names) else None)
