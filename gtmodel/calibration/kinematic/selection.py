"""Which parameters a kinematic calibration estimates: free, fixed and tied parameters.

:class:`ParameterSelection` is what a user states (names or shell patterns); applied to a
model it becomes a :class:`_Resolution` (the NLP variables, tie roots, quaternion
rotation variables), and :func:`_parameter_expression` is the parameter vector as a
CasADi expression of the variables: free scalars, quaternions ``q0 * exp(r / 2)`` about
their anchor (Dressler (2012), ch. 5.4), ties, and the rest from the anchor vector.
"""

from __future__ import annotations

import difflib
import fnmatch
from dataclasses import dataclass
from typing import Any, Mapping, Sequence

import casadi as ca
import numpy as np

from gtmodel._geometry import quat_exp, quat_mul
from gtmodel.errors import InputError
from gtmodel.robots.closure import ClosureModel

__all__ = ["ParameterSelection"]


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
            qn = quat_mul(q0, quat_exp(ca.vertcat(*delta)))
            for c, comp in zip(qi, range(4)):
                p[c] = qn[comp]
    for t in res.targets:
        r = int(res.root[t])
        p[t] = p[r]
    return ca.vertcat(*p)
