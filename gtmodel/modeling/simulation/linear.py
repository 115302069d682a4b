"""Linearisation of a model about an operating point: ``dx = A dx + B du``, ``dy = C dx + D du``.

The flat DAE ``xdot = f(t, x, z, u, p)``, ``0 = g(t, x, z, u, p)`` is linearised with
CasADi's algorithmic differentiation, and the algebraic variables are eliminated with the
implicit function theorem (index 1: ``g_z`` non-singular)::

    dz = -g_z^-1 (g_x dx + g_u du)
    A = f_x - f_z g_z^-1 g_x,   B = f_u - f_z g_z^-1 g_u    (likewise C, D for outputs)

The consistent algebraic values at the operating point are found by CasADi's Newton
rootfinder. Used for modes (eigenvalues of ``A``) and frequency responses of composed
models (:func:`linearize`, :class:`Linearization`).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import casadi as ca
import numpy as np

from gtmodel._lazy import lazy_module
from gtmodel.errors import ConvergenceError, GtModelError, InputError, ModelError
from gtmodel.modeling.dae import FlatDAE, _vector_value
from gtmodel.modeling.structure.index_reduction import structural_simplify
from gtmodel.modeling.simulation.model import Model

#: python-control, imported on first use (it imports matplotlib.pyplot: ~2 s of CPU).
control = lazy_module("control")

__all__ = ["Linearization", "linearize"]


@dataclass(frozen=True)
class Linearization:
    """A linear state-space model of a :class:`~gtmodel.modeling.Model` at an operating point.

    Parameters
    ----------
    A : numpy.ndarray, shape (nx, nx)
        State matrix [1/s].
    B : numpy.ndarray, shape (nx, nu)
        Input matrix.
    C : numpy.ndarray, shape (ny, nx)
        Output matrix.
    D : numpy.ndarray, shape (ny, nu)
        Feed-through matrix.
    x_names, u_names, y_names : list of str
        Scalar names of states, inputs and outputs.
    x, z, u : numpy.ndarray
        The operating point (states, consistent algebraic variables, inputs).
    """

    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    D: np.ndarray
    x_names: list[str]
    u_names: list[str]
    y_names: list[str]
    x: np.ndarray
    z: np.ndarray
    u: np.ndarray

    def poles(self) -> np.ndarray:
        """Eigenvalues of ``A`` [rad/s], sorted by magnitude.

        Returns
        -------
        numpy.ndarray, shape (nx,)
            Complex poles.
        """
        lam = np.linalg.eigvals(self.A) if self.A.size else np.zeros(0, complex)
        return lam[np.argsort(np.abs(lam), kind="stable")]

    def to_state_space(self) -> control.StateSpace:
        """The model as a :class:`control.StateSpace` (python-control).

        Returns
        -------
        control.StateSpace
            With the state, input and output names (python-control allows no ``.`` in
            signal names: ``"belt.f"`` becomes ``"belt_f"``, ``"T[0]"`` ``"T_0"``).
        """

        def clean(names: list[str]) -> list[str]:
            return [n.replace(".", "_").replace("[", "_").replace("]", "") for n in names]

        return control.ss(
            self.A, self.B, self.C, self.D, states=clean(self.x_names), inputs=clean(self.u_names), outputs=clean(self.y_names)
        )

    def bode_plot(self, *args: Any, **kwargs: Any) -> Any:
        """Moved to the report layer: ``gtmodel.report.bode_plot(linearization, ...)``.

        The modelling layer never draws (nor imports the report layer that does).

        Parameters
        ----------
        *args, **kwargs : Any
            Not used.

        Raises
        ------
        GtModelError
            Always, naming the function that draws a Bode plot.
        """
        raise GtModelError("bode_plot() moved to the report layer: from gtmodel.report import bode_plot; "
                           "bode_plot(linearization, path=..., omega=..., hz=..., title=...)")

    def step_plot(self, *args: Any, **kwargs: Any) -> Any:
        """Moved to the report layer: ``gtmodel.report.step_plot(linearization, ...)``.

        Parameters
        ----------
        *args, **kwargs : Any
            Not used.

        Raises
        ------
        GtModelError
            Always, naming the function that draws step responses.
        """
        raise GtModelError("step_plot() moved to the report layer: from gtmodel.report import step_plot; "
                           "step_plot(linearization, path=..., T=..., title=...)")


def _selection(dae: FlatDAE, names: Sequence[str] | None) -> tuple[ca.SX, list[str]]:
    """Output expressions for scalar names of states, algebraic variables or outputs."""
    if names is None:
        return dae.x, list(dae.x_names)
    pool: dict[str, ca.SX] = {}
    for n, s in zip(dae.x_names, ca.vertsplit(dae.x)):
        pool[n] = s
    for n, s in zip(dae.z_names, ca.vertsplit(dae.z)):
        pool[n] = s
    for key, expr in dae.output_exprs.items():
        parts = ca.vertsplit(expr)
        for n, s in zip([key] if len(parts) == 1 else [f"{key}[{i}]" for i in range(len(parts))], parts):
            pool[n] = s
    if isinstance(names, str):
        names = [names]
    missing = [n for n in names if n not in pool]
    if missing:
        raise InputError(f"outputs: {missing} are no states, algebraic variables or outputs of model {dae.name!r}")
    return ca.vertcat(*[pool[n] for n in names]) if names else ca.SX(0, 1), list(names)


def linearize(
    model: Model,
    x: Any = None,
    u: Any = None,
    p: Mapping[str, Any] | None = None,
    t: float = 0.0,
    outputs: Sequence[str] | None = None,
    z0: Any = None,
) -> Linearization:
    """Linearise a model about ``(t, x, u)`` with the algebraic variables eliminated.

    ``A = f_x - f_z g_z^-1 g_x`` etc. (implicit function theorem; Jacobians by CasADi AD).

    Parameters
    ----------
    model : Model
        The model (flattened here; a model that does not flatten, e.g. of higher index,
        is first reduced by :func:`~gtmodel.modeling.structure.index_reduction.structural_simplify`,
        whose state selection then gives the states, at the start values).
    x : array_like or mapping, optional
        States, shape ``(nx,)``, or state name -> value (of the reduced model when it
        was reduced); default the start values.
    u : array_like, optional
        Inputs, shape ``(nu,)``; default the inputs' start values.
    p : mapping of str to float or array_like, optional
        Parameter overrides by name.
    t : float, optional
        Time [s] (default 0).
    outputs : sequence of str, optional
        Scalar names of states, algebraic variables or declared outputs; default the
        states (``C = I``).
    z0 : array_like, optional
        Guess of the algebraic variables, shape ``(nz,)``; default their start values.

    Returns
    -------
    Linearization
        ``A, B, C, D`` and the operating point.

    Raises
    ------
    InputError
        If ``model`` is not a Model, or a value or output name is malformed.
    ModelError
        If the model cannot be flattened or ``g_z`` is singular at the point.
    ConvergenceError
        If no consistent algebraic values are found.
    """
    if not isinstance(model, Model):
        raise InputError(f"model must be a gtmodel.modeling.Model, got {type(model).__name__}")
    try:
        dae = model.flatten()
    except ModelError:
        # higher index or aliases: the index-1 model of the structural passes (its states
        # may differ; A is the same up to a change of coordinates)
        model = structural_simplify(model)
        dae = model.flatten()
    if isinstance(x, Mapping):
        xv = dae.x_start.copy()
        for name, val in x.items():
            if name not in dae.x_vars:
                raise InputError(f"x: {name!r} is not a state of model {dae.name!r}")
            sl = dae.x_vars[name]
            xv[sl] = _vector_value(val, sl.stop - sl.start, f"x[{name!r}]")
    else:
        xv = dae.x_start.copy() if x is None else _vector_value(x, dae.nx, "x")
    u_start = np.concatenate([np.asarray(v, float) for v in [model._vars[n].start for n in dae.u_vars]]) if dae.nu else np.zeros(0)
    uv = u_start if u is None else _vector_value(u, dae.nu, "u")
    pv = dae.parameter_vector(p)
    tv = float(t)
    zv = dae.z_start.copy() if z0 is None else _vector_value(z0, dae.nz, "z0")
    if dae.nz:
        zsym = ca.SX.sym("z", dae.nz)
        g = ca.Function("g", [zsym, dae.x, dae.u, dae.p, dae.t], [ca.substitute(dae.alg_expr, dae.z, zsym)])
        try:
            solver = ca.rootfinder("consistent_z", "newton", g, {"error_on_fail": True})
            zv = np.array(solver(zv, xv, uv, pv, tv)).reshape(-1)
        except RuntimeError as exc:
            raise ConvergenceError(f"linearize: no consistent algebraic variables for model {dae.name!r} at the point") from exc
    y_expr, y_names = _selection(dae, outputs)
    jac = ca.Function(
        "linearization_jacobians",
        [dae.t, dae.x, dae.z, dae.u, dae.p],
        [ca.jacobian(e, v) for e in (dae.ode_expr, dae.alg_expr, y_expr) for v in (dae.x, dae.z, dae.u)],
    )
    fx, fz, fu, gx, gz, gu, hx, hz, hu = (np.array(m, dtype=float) for m in jac(tv, xv, zv, uv, pv))
    if dae.nz:
        # equilibrate rows and columns before judging singularity (stiffnesses ~1e7 next to 1)
        rs = 1.0 / np.maximum(np.abs(gz).max(axis=1, keepdims=True), 1e-300)
        cs = 1.0 / np.maximum((np.abs(gz) * rs).max(axis=0, keepdims=True), 1e-300)
        if np.linalg.cond(gz * rs * cs) > 1e12:
            raise ModelError(f"linearize: the algebraic equations of model {dae.name!r} are singular in z at the point")
        sx = np.linalg.solve(gz, gx)
        su = np.linalg.solve(gz, gu)
        A, B = fx - fz @ sx, fu - fz @ su
        C, D = hx - hz @ sx, hu - hz @ su
    else:
        A, B, C, D = fx, fu, hx, hu
    return Linearization(
        A=A, B=B, C=C, D=D, x_names=list(dae.x_names), u_names=list(dae.u_names), y_names=y_names, x=xv, z=zv, u=uv
    )
