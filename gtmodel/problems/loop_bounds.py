"""What a loop controller takes from its reference besides the motion: the declared bounds and whether it was verified.

A loop controller (the MPC, the tracking controller) keeps the bounds that the model and the
reference problem declare, and its closed-loop check counts their violations on the plant
(:func:`gtmodel.control.bounds.bound_report`). :class:`DeclaredBounds` holds
them by scalar name (states, inputs, algebraic variables and outputs) with where they came
from:

- a reference problem (``optimal_control``): its ``[bounds]`` as its file declares them (without
  the ``[reference] overrides`` of the plan) over the model's own
  (:meth:`gtmodel.modeling.Optimization.bounds_vectors`), :func:`dae_bounds`;
- a result folder's ``trajectories.csv``: the bounds its ``summary.json`` records (the NLP's),
  :func:`summary_bounds`;
- another table: the model's declared bounds alone.

An input whose bound is known nowhere stays infinite, and :meth:`DeclaredBounds.unknown` names
it so that the controller's summary says so (its violations cannot be counted).

A reference solved by gtmodel is taken when it is verified (:func:`unverified_reason` gives
why not: a failed or skipped verification, a status other than ``optimal`` /
``acceptable``); an unverified one only through ``[reference] accept_unverified = true``,
which the controller's summary and verdict repeat (:func:`accept_reference`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from gtmodel.problems.base import ProblemFile

if TYPE_CHECKING:
    from gtmodel.modeling import ExplicitODE

__all__ = ["DeclaredBounds", "dae_bounds", "summary_bounds", "unverified_reason", "accept_reference", "input_limits", "input_bounds"]

#: Statuses of a solved reference (the solver converged); its verification decides the rest.
SOLVED = ("optimal", "acceptable")


@dataclass
class DeclaredBounds:
    """Bounds by scalar variable name, and where they were declared.

    Parameters
    ----------
    lb, ub : dict of str to float
        Lower and upper bound by scalar name (``"ind.i"``, ``"T[0]"``); a name with no finite
        side is left out; an open side is ``-inf`` / ``inf``.
    source : str
        Where they come from, for the summary (e.g. ``"the reference problem's [bounds] and the model's"``).
    """

    lb: dict[str, float] = field(default_factory=dict)
    ub: dict[str, float] = field(default_factory=dict)
    source: str = "none"

    def add(self, name: str, lo: float, hi: float) -> None:
        """Record the bounds of one scalar (nothing when both sides are infinite).

        Parameters
        ----------
        name : str
            Scalar name.
        lo, hi : float
            Lower and upper bound (``-inf`` / ``inf``: none).
        """
        lo, hi = float(lo), float(hi)
        if math.isfinite(lo) or math.isfinite(hi):
            self.lb[name], self.ub[name] = lo, hi

    @property
    def names(self) -> list[str]:
        """The bounded scalars' names."""
        return list(self.lb)

    def vectors(self, names: list[str]) -> tuple[np.ndarray, np.ndarray]:
        """The bounds of ``names`` in order.

        Parameters
        ----------
        names : list of str
            Scalar names.

        Returns
        -------
        lb, ub : numpy.ndarray
            ``(len(names),)`` each; ``-inf`` / ``inf`` where none is declared.
        """
        return (np.array([self.lb.get(n, -math.inf) for n in names], dtype=float),
                np.array([self.ub.get(n, math.inf) for n in names], dtype=float))

    def unknown(self, names: list[str]) -> list[str]:
        """The sides of ``names`` with no declared bound, as ``"name (lower)"`` / ``"name (upper)"``.

        Parameters
        ----------
        names : list of str
            Scalar names (e.g. the inputs).

        Returns
        -------
        list of str
        """
        return [f"{n} ({side})" for n in names for side, v in (("lower", self.lb.get(n, -math.inf)), ("upper", self.ub.get(n, math.inf)))
                if not math.isfinite(v)]

    def restricted(self, names: list[str]) -> "DeclaredBounds":
        """The bounds of the scalars in ``names`` only (those a model has).

        Parameters
        ----------
        names : list of str
            Scalar names kept.

        Returns
        -------
        DeclaredBounds
        """
        keep = set(names)
        return DeclaredBounds({k: v for k, v in self.lb.items() if k in keep}, {k: v for k, v in self.ub.items() if k in keep}, self.source)


def _scalars(name: str, sl: Any, lb: np.ndarray, ub: np.ndarray) -> list[tuple[str, float, float]]:
    lo, hi = np.atleast_1d(lb[sl]), np.atleast_1d(ub[sl])
    if lo.size == 1:
        return [(name, float(lo[0]), float(hi[0]))]
    return [(f"{name}[{k}]", float(lo[k]), float(hi[k])) for k in range(lo.size)]


def dae_bounds(dae: Any, optimization: Any = None, source: str = "the model's declared bounds") -> DeclaredBounds:
    """The bounds of a flat model's states, algebraic variables and inputs, with a problem's over them.

    Parameters
    ----------
    dae : FlatDAE
        The flat model (``x_vars``, ``z_vars``, ``u_vars`` and their ``*_lb``, ``*_ub``).
    optimization : gtmodel.modeling.Optimization, optional
        A problem whose ``[bounds]`` override the model's
        (:meth:`~gtmodel.modeling.Optimization.bounds_vectors`); default the model's alone.
    source : str, optional
        Where they come from, for the summary.

    Returns
    -------
    DeclaredBounds
    """
    out = DeclaredBounds(source=source)
    for cat in ("x", "z", "u"):
        if optimization is not None:
            lb, ub = optimization.bounds_vectors(dae, cat)
        else:
            lb, ub = np.asarray(getattr(dae, f"{cat}_lb"), float), np.asarray(getattr(dae, f"{cat}_ub"), float)
        for name, sl in getattr(dae, f"{cat}_vars").items():
            for scalar, lo, hi in _scalars(name, sl, lb, ub):
                out.add(scalar, lo, hi)
    return out


def summary_bounds(summary: dict[str, Any], source: str) -> DeclaredBounds:
    """The bounds a result folder's ``summary.json`` records (``"bounds"``: ``[lo, hi]`` by name, ``null`` an open side).

    Parameters
    ----------
    summary : dict
        The parsed ``summary.json``.
    source : str
        Where they come from, for the summary (the folder).

    Returns
    -------
    DeclaredBounds
        Empty when the summary has no ``"bounds"``.
    """
    out = DeclaredBounds(source=source)

    def num(v: Any, default: float) -> np.ndarray:
        return np.array([default if e is None else float(e) for e in np.ravel(np.asarray(v, dtype=object))], dtype=float)

    for name, pair in (summary.get("bounds") or {}).items():
        if not isinstance(pair, (list, tuple)) or len(pair) != 2:
            continue
        lo, hi = num(pair[0], -math.inf), num(pair[1], math.inf)
        if lo.size == 1 and hi.size == 1:
            out.add(name, lo[0], hi[0])
        else:
            for k in range(min(lo.size, hi.size)):
                out.add(f"{name}[{k}]", lo[k], hi[k])
    return out


def unverified_reason(status: str, verification: Any) -> str | None:
    """Why a reference solved by gtmodel is not a verified solution (None: it is).

    Parameters
    ----------
    status : str
        The solve's status (``"optimal"``, ``"check_failed"``, ...).
    verification : dict or object or None
        Its verification (the summary's ``"verification"`` block, or a
        :class:`~gtmodel.modeling.ocp.verification.Verification`): ``passed`` and ``message``.

    Returns
    -------
    str or None
    """
    status = str(getattr(status, "value", status))
    if isinstance(verification, dict):
        passed, message = verification.get("passed"), verification.get("message") or verification.get("status")
    elif verification is not None:
        passed, message = getattr(verification, "passed", None), getattr(verification, "message", "")
    else:
        passed, message = None, ""
    if status == "check_failed":
        return f"status check_failed: its verification failed ({message})" if message else "status check_failed: its verification failed"
    if status not in SOLVED:
        return f"status {status}"
    if passed is not True:
        return f"status {status}, not verified ({message or 'no verification'})"
    return None


def accept_reference(file: ProblemFile, field: str, status: str, verification: Any, accept: bool) -> str | None:
    """A solved reference taken only when verified, or when not through ``[reference] accept_unverified``.

    Parameters
    ----------
    file : ProblemFile
        The loop-controller file (for its errors).
    field : str
        The field named when refused (``"reference.problem"``, ``"reference.file"``).
    status : str
        The solve's status.
    verification : dict or object or None
        Its verification (:func:`unverified_reason`).
    accept : bool
        ``[reference] accept_unverified``.

    Returns
    -------
    str or None
        None for a verified reference; else the note the summary and verdict repeat.

    Raises
    ------
    ProblemError
        ``field``: not solved (a status other than optimal, acceptable, check_failed), or
        unverified without ``accept_unverified``.
    """
    why = unverified_reason(status, verification)
    if why is None:
        return None
    status = str(getattr(status, "value", status))
    if status not in (*SOLVED, "check_failed"):
        raise file.fail(field, f"a problem that solves (status {status})")
    if not accept:
        raise file.fail(field, f"a verified reference, or [reference] accept_unverified = true to track it unverified ({why}; "
                        "the remedy the solve names, e.g. more [collocation] elements or [transcription] refine = true, verifies it)")
    return f"reference NOT verified ({why}); accepted by [reference] accept_unverified = true"


def input_limits(bounds: DeclaredBounds, ode: ExplicitODE) -> np.ndarray:
    """The declared input bounds within the model's.

    Parameters
    ----------
    bounds : DeclaredBounds
        The declared bounds (a missing input's: infinite).
    ode : ExplicitODE
        The model (its ``u_names``, ``u_lb``, ``u_ub``).

    Returns
    -------
    numpy.ndarray
        ``(2, nu)``: lower and upper bounds.
    """
    lb, ub = bounds.vectors(list(ode.u_names))
    return np.vstack([np.maximum(lb, ode.u_lb), np.minimum(ub, ode.u_ub)])


def input_bounds(file: ProblemFile, section: str, u_lb: list[float] | None, u_ub: list[float] | None,
                 limits: np.ndarray | None, ode: ExplicitODE) -> tuple[np.ndarray, np.ndarray]:
    """The saturation bounds: the file's ``u_lb``/``u_ub``, else the reference problem's, else the model's.

    Parameters
    ----------
    file : ProblemFile
        The file.
    section : str
        The controller section, e.g. ``"mpc"`` (the fields ``<section>.u_lb``, ``<section>.u_ub``).
    u_lb, u_ub : list of float or None
        The file's bounds.
    limits : numpy.ndarray or None
        ``(2, nu)`` the reference problem's (:func:`loop_reference`).
    ode : ExplicitODE
        The model (its declared bounds).

    Returns
    -------
    lb, ub : numpy.ndarray
        ``(nu,)`` each.

    Raises
    ------
    ProblemError
        ``<section>.u_lb`` / ``<section>.u_ub`` of another length than the model's inputs,
        a lower bound above its upper bound (``<section>.u_lb[i]``).
    """
    lb = np.asarray(u_lb, dtype=float) if u_lb is not None else (limits[0] if limits is not None else ode.u_lb)
    ub = np.asarray(u_ub, dtype=float) if u_ub is not None else (limits[1] if limits is not None else ode.u_ub)
    for field, v in ((f"{section}.u_lb", lb), (f"{section}.u_ub", ub)):
        if v.size != ode.nu:
            raise file.fail(field, f"{ode.nu} bounds ({', '.join(ode.u_names)})", v.tolist())
    crossed = np.flatnonzero(~(lb <= ub))
    if crossed.size:
        j = int(crossed[0])
        raise file.fail(f"{section}.u_lb[{j}]", f"a lower bound <= the upper bound {float(ub[j]):g} ({ode.u_names[j]})", float(lb[j]))
    return lb, ub
