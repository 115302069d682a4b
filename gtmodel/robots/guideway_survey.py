"""The guideway survey of the piecewise-linear actuator model: interpolation and frames.

What :class:`~gtmodel.robots.actuator.PiecewiseActuatorClosure` builds on: the checked
survey (cart positions per arm), their interpolation as a CasADi expression
(:func:`piecewise_linear`, Dressler (2012), eq. 5.7), the survey's line frame
(:func:`line_frame`) and the fit of the survey frames onto a linear-actuator model
(:func:`fit_survey_frames`, the start of a model-2/model-4 calibration), with why the
frames are parametrised as they are (the module docstring of
:mod:`gtmodel.robots.actuator` gives the model)::

    A_ij = R_i (P_i(q_i) - Pbar_i + a_ij) + c_i,    R_i = F_i Rot(w_i) C_i^T

Frame parametrisation (why not the thesis' ``o_i`` and ZYZ angles)
------------------------------------------------------------------
The thesis writes ``A_i = R_i P_i + o_i`` with ``R_i`` from ZYZ Euler angles. Calibrated
that way, the D1 error-model comparison on synthetic data (``problems/d1_error_models.toml``
with a 0.10 m grid: 233 calibration poses, Table 4.1 actuator errors, survey in the TCP
frame, so the true ``R_i = I``) never converged for the piecewise models (LM: 800-1000
evaluations on most arms, IPOPT: max_iter) while the linear models took 12-30 iterations.
Measured causes, all in the frame:

1. **The rotation about the guideway line (the twist).** It changes ``A`` only through the
   bends of the survey (Table 4.1: tens of um), so the data barely determine it: free, its
   standard deviation came out at 2-7 deg per arm, the estimates 1-13 deg (3-link) and up
   to 52 deg (six-link, 82 poses, 229 LM iterations) away from the true 0, and IPOPT
   stopped at "acceptable". Fixed, the same problems converge in 4-5 LM iterations per
   arm with the same validation error (within 2 um mean). So the twist is **not a
   parameter by default**: ``w_i = (0, ry, rz)`` tilts the surveyed line about the
   anchor ``F_i`` and the twist stays that of the anchor (``free_twist=True`` adds
   ``frame<i>_rx``, for a survey whose orientation about the guideway is unknown; the
   test module shows its recovery from a bent guideway).
2. **Rotation about the far survey origin.** ``o_i`` is the survey origin, metres from the
   guideway (D1: 5-6 m), so every rotation swings the whole guideway and the offset must
   follow: rotation and translation are coupled through a 5-6 m lever (the free-twist
   optimum of 3-link arm 3, 6.6 deg about the guideway, has ``o_3`` 0.57 m away from the
   fixed-twist one). Here the rotation acts about the survey centroid ``Pbar_i`` (a
   constant of the survey) and the offset parameter is ``c_i = R_i Pbar_i + o_i``, that
   centroid in the TCP frame.
   (:attr:`PiecewiseActuatorClosure.frame_offset` and ``frame_euler_zyz`` still give
   ``o_i`` and the ZYZ angles for comparison with Table 5.8.)
3. **Gimbal lock.** Survey and tracker frames are nearly aligned or turned about the
   vertical (Table 5.8: ``beta`` = -0.5..-0.9 deg), i.e. ``beta`` near 0 or pi where ZYZ
   ``alpha`` and ``gamma`` are interchangeable (the D1 start frames had ``beta`` =
   0.02-0.06 and 3.08 rad; the smallest singular value of the column-scaled Jacobian was
   1.5e-7 to 3e-6 of the largest; at the truth ``R_i = I``, ``beta = 0``, it is
   singular). ``w_i`` is a rotation vector about the fixed anchor ``F_i`` (the frame
   given to the constructor, e.g. fitted by ``from_model``), in the axes
   of the survey's *line frame* ``C_i`` (:func:`line_frame`, x along the surveyed line):
   no singularity within a turn, and ``rx`` is exactly the twist.
4. **Arbitrary start twist.** :meth:`PiecewiseActuatorClosure.from_model` fitted the frame
   onto the *straight* joint path of a linear-actuator model, which leaves the twist free
   (the SVD returned 176 and 104 deg for two D1 arms). It now takes the minimal rotation
   (no twist), exact when survey and TCP frames differ by a rotation about an axis
   perpendicular to the guideway (a levelled tracker turned about the vertical; Table 5.8's
   D1 frames differ from it by 0.3-1.5 deg about the guideway, less than the data's 2-7 deg
   uncertainty; 1.5 deg of a 100 um bend is 2.6 um).

With these, the comparison converges in 4-5 LM iterations per arm (12 and 13 in all for
models 2 and 4) to mean/max validation errors of 34/114 and 34/117 um, against 82/180 and
91/262 um of the linear models; the column-scaled Jacobians have the conditioning of the
linear models (smallest/largest singular value 4.5e-3 for the 3-link, 1e-5 for the six-link
layouts, the latter the offset of ``c_i`` against ``B0_ij`` that model 3 shares).

The anchors are constants of the closure equations: :meth:`~PiecewiseActuatorClosure.transformed`
turns them (``F_i' = R F_i``), so a calibration that moves the start into the
measurement frame builds its graphs for the moved model (~0.3 s for the six-link layout).
"""

from __future__ import annotations

import logging
from typing import Any

import casadi as ca
import numpy as np
import numpy.typing  # noqa: F401  (np.typing in annotations)
from scipy.spatial.transform import Rotation

from gtmodel.errors import InputError
from gtmodel.robots.closure import ClosureModel
from gtmodel.robots.six_link import estimate_nominal_orientation
from gtmodel.robots.wrapped import guideway_frame

__all__ = [
    "piecewise_linear",
    "line_frame",
    "fit_survey_frames",
    "THREE_LINK_LAYOUT",
    "SIX_LINK_LAYOUT",
    "COLLINEAR_TOLERANCE",
]

_log = logging.getLogger("gtmodel")

#: Link names of the simplified 3-link model (one link per arm, ``B = T``).
THREE_LINK_LAYOUT: tuple[tuple[str, ...], ...] = (("1",), ("2",), ("3",))
#: Link names of the six-link model (3-2-1 clusters, orientation from the closure equations).
SIX_LINK_LAYOUT: tuple[tuple[str, ...], ...] = (("1",), ("2a", "2b"), ("3a", "3b", "3c"))
#: :meth:`PiecewiseActuatorClosure.from_model`: a model's joint path whose second singular
#: value (centred, over the survey nodes) is below this fraction of the first is straight;
#: a rigid fit onto it leaves the twist free and the minimal rotation is used. A linear
#: actuator gives ~1e-16, a Table 4.1 bend ~1e-5.
COLLINEAR_TOLERANCE = 1e-9


def piecewise_linear(x: Any, nodes: np.typing.ArrayLike, values: np.typing.ArrayLike) -> Any:
    """Linear interpolation between nodes as a CasADi expression (Dressler (2012), eq. 5.7).

    Written as a sum of ramps, ``f(x) = f_0 + s_0 (x - x_0) + sum_k (s_k - s_k-1) max(x - x_k, 0)``
    with ``s_k`` the slope of segment ``k``: exact linear interpolation inside
    ``[x_0, x_M-1]``, linear extrapolation with the end segments' slopes outside. Plain SX
    operations only (``fmax``), so it lives in SX graphs, is differentiated by AD and code
    generated like any other expression (no lookup-table Function call node).

    Parameters
    ----------
    x : casadi.SX or casadi.MX or float
        Where to interpolate (scalar).
    nodes : array_like, shape (M,)
        Strictly increasing node positions, M >= 2.
    values : array_like, shape (M,) or (M, d)
        Values at the nodes (one row per node).

    Returns
    -------
    casadi.SX or casadi.MX or casadi.DM, shape (d, 1)
        The interpolated value (column vector; ``d = 1`` for 1-D values).

    Raises
    ------
    InputError
        If the nodes are not strictly increasing, fewer than 2, or shapes disagree.
    """
    g = np.asarray(nodes, dtype=float).reshape(-1)
    V = np.asarray(values, dtype=float)
    V = V.reshape(-1, 1) if V.ndim == 1 else V
    if g.size < 2 or V.shape[0] != g.size:
        raise InputError(f"piecewise_linear: need >= 2 nodes and one value row per node, got {g.size} nodes, values {V.shape}")
    if not (np.all(np.isfinite(g)) and np.all(np.isfinite(V))):
        raise InputError("piecewise_linear: nodes and values must be finite")
    if np.any(np.diff(g) <= 0):
        raise InputError("piecewise_linear: nodes must be strictly increasing")
    slopes = np.diff(V, axis=0) / np.diff(g)[:, None]
    out = ca.DM(V[0]) + ca.DM(slopes[0]) * (x - g[0])
    for k in range(1, g.size - 1):
        ds = slopes[k] - slopes[k - 1]
        if np.any(ds != 0.0):
            out = out + ca.DM(ds) * ca.fmax(x - g[k], 0.0)
    return out


def _cart_arrays(cart: Any, n_arms: int) -> tuple[tuple[np.ndarray, ...], tuple[np.ndarray, ...]]:
    """Validated per-arm nodes and positions of a CartMeasurements-like object."""
    try:
        qs, ps = tuple(cart.q), tuple(cart.positions)
    except AttributeError:
        raise InputError(
            f"cart: expected cart measurements with attributes q and positions (CartMeasurements), got {type(cart).__name__}"
        ) from None
    if len(qs) != n_arms or len(ps) != n_arms:
        raise InputError(f"cart: expected cart positions of {n_arms} arms, got {len(qs)}")
    out_q, out_p = [], []
    for i, (qa, pa) in enumerate(zip(qs, ps)):
        qa = np.asarray(qa, dtype=float).reshape(-1)
        pa = np.asarray(pa, dtype=float)
        if pa.shape != (qa.size, 3) or qa.size < 2:
            raise InputError(f"cart arm {i + 1}: expected >= 2 nodes q (M,) and positions (M, 3), got {qa.shape} and {pa.shape}")
        if np.any(np.diff(qa) <= 0) or not np.all(np.isfinite(pa)):
            raise InputError(f"cart arm {i + 1}: q must be strictly increasing and positions finite")
        out_q.append(qa)
        out_p.append(pa)
    return tuple(out_q), tuple(out_p)


def line_frame(q: np.typing.ArrayLike, points: np.typing.ArrayLike) -> np.ndarray:
    """Frame of a surveyed guideway: ``e1`` along the fitted line, ``e2`` horizontal.

    ``e1`` is the principal direction of the centred points (SVD), pointing towards
    increasing ``q``; ``e2 = e_z x e1`` normalised (``e_x x e1`` if the line is within ~6 deg
    of the z axis), ``e3 = e1 x e2``; the same axes as
    :func:`gtmodel.robots.deviated.guideway_axes` (:func:`~gtmodel.robots.wrapped.guideway_frame`), in the frame of ``points``.

    Parameters
    ----------
    q : array_like, shape (M,)
        Actuator values of the points [m] (for the direction of ``e1``).
    points : array_like, shape (M, 3)
        Surveyed points [m], M >= 2, not all equal.

    Returns
    -------
    numpy.ndarray, shape (3, 3)
        Columns ``e1, e2, e3`` (a rotation matrix).

    Raises
    ------
    InputError
        If the shapes disagree or the points do not span a line.
    """
    qa = np.asarray(q, dtype=float).reshape(-1)
    P = np.asarray(points, dtype=float)
    if P.shape != (qa.size, 3) or qa.size < 2:
        raise InputError(f"line_frame: expected q (M,) and points (M, 3) with M >= 2, got {qa.shape} and {P.shape}")
    Pc = P - P.mean(axis=0)
    _, s, Vt = np.linalg.svd(Pc, full_matrices=False)
    if not s[0] > 0:
        raise InputError("line_frame: the points are all equal; no line direction")
    e1 = Vt[0]
    if e1 @ (Pc.T @ (qa - qa.mean())) < 0:
        e1 = -e1
    return guideway_frame(e1)


def _minimal_rotation(u: np.ndarray, d: np.ndarray, fallback_axis: np.ndarray) -> np.ndarray:
    """The rotation of least angle taking unit vector ``u`` to unit vector ``d`` (no twist)."""
    c = float(np.clip(u @ d, -1.0, 1.0))
    if c < -1.0 + 1e-12:  # opposite: half turn about an axis perpendicular to u
        return Rotation.from_rotvec(np.pi * fallback_axis / np.linalg.norm(fallback_axis)).as_matrix()
    K = np.cross(u, d)
    Kx = np.array([[0.0, -K[2], K[1]], [K[2], 0.0, -K[0]], [-K[1], K[0], 0.0]])
    return np.eye(3) + Kx + Kx @ Kx / (1.0 + c)


def fit_survey_frames(model: ClosureModel, cart: Any) -> dict[str, Any]:
    """The frames of a guideway survey fitted onto a linear-actuator model.

    The fit of :meth:`PiecewiseActuatorClosure.from_model
    <gtmodel.robots.actuator.PiecewiseActuatorClosure.from_model>`, which documents it.

    Parameters
    ----------
    model : ClosureModel
        A model with linear actuators: the 3-link model or a six-link model.
    cart : CartMeasurements
        The guideway survey.

    Returns
    -------
    dict
        Keyword arguments of :class:`~gtmodel.robots.actuator.PiecewiseActuatorClosure`:
        ``L`` (n_links,) [m], ``frame_offset`` (3, 3) [m], ``frame_rotation`` (3, 3, 3),
        ``links``, ``link_offsets`` (n_links, 3) [m] and ``B0`` (n_links, 3) [m] (None for
        the 3-link layout), ``plate_orientation`` (3, 3) or None.

    Raises
    ------
    InputError
        If the model's link layout is neither 3-link nor six-link, ``n_q`` is not 3 or
        a joint point depends on another actuator than its own.
    """
    if model.n_q != 3:
        raise InputError(f"{model.name}: the piecewise-linear actuator model needs 3 linear actuators, model has n_q={model.n_q}")
    six = model.orientation
    links = SIX_LINK_LAYOUT if six else THREE_LINK_LAYOUT
    if sum(len(a) for a in model.links) != sum(len(a) for a in links) or [len(a) for a in model.links] != [len(a) for a in links]:
        raise InputError(f"{model.name}: links {model.links} fit neither the 3-link nor the six-link layout")
    cq, cp = _cart_arrays(cart, 3)
    p, q = ca.SX.sym("p", model.n_parameters), ca.SX.sym("q", 3)
    T, R = ca.SX.sym("T", 3), ca.SX.sym("R", 3, 3)
    outs = [model.link_points(p, q, T, R, i) for i in range(3)]
    A = ca.horzcat(*[o[0] for o in outs])
    B = ca.horzcat(*[o[1] for o in outs])
    Lx = ca.vertcat(*[o[2] for o in outs])
    dep = np.array(ca.DM(ca.jacobian(ca.vec(A), q).sparsity(), 1)) != 0
    col = 0
    for i, arm in enumerate(model.links):
        for _ in arm:
            used = {int(c) for c in np.flatnonzero(np.any(dep[3 * col: 3 * col + 3], axis=0))}
            if not used <= {i}:
                raise InputError(f"{model.name}: joint point of arm {i + 1} depends on q{sorted(used)}; only q{i + 1} is supported")
            col += 1
    fA = ca.Function("A", [p, q], [A])
    fB = ca.Function("B", [p, T, R], [B, Lx])
    pv = model.parameter_vector()
    B0m, Lm = fB(pv, np.zeros(3), np.eye(3))
    B0m = np.array(B0m).T
    Lm = np.array(Lm).ravel()
    o = np.empty((3, 3))
    Rf = np.empty((3, 3, 3))
    a = np.zeros((len(Lm), 3))
    j0 = 0
    for i, arm in enumerate(links):
        M = cq[i].size
        qs = np.zeros((3, M))
        qs[i] = cq[i]
        Aall = np.array(fA.map(M)(pv, qs)).reshape(3, M, len(Lm))
        Ak = Aall[:, :, j0].T
        Pc, Ac = cp[i] - cp[i].mean(axis=0), Ak - Ak.mean(axis=0)
        sv = np.linalg.svd(Ac, compute_uv=False)
        if sv[1] <= COLLINEAR_TOLERANCE * sv[0]:
            C = line_frame(cq[i], cp[i])
            Ri = _minimal_rotation(C[:, 0], line_frame(cq[i], Ak)[:, 0], C[:, 2])
        else:
            rot, _ = Rotation.align_vectors(Ac, Pc)
            Ri = rot.as_matrix()
        Rf[i] = Ri
        o[i] = Ak.mean(axis=0) - Ri @ cp[i].mean(axis=0)
        for j in range(1, len(arm)):
            a[j0 + j] = Ri.T @ (Aall[:, :, j0 + j] - Aall[:, :, j0]).mean(axis=1)
        j0 += len(arm)
    R0 = None
    if six:
        R0 = getattr(model, "R0", None)
        if R0 is None or np.shape(R0) != (3, 3):
            try:
                R0, _ = estimate_nominal_orientation(np.array(fA(pv, np.zeros(3))).reshape(3, len(Lm)).T, B0m)
            except InputError:
                R0 = np.eye(3)
    _log.debug("%s: frames fitted to the cart survey %s", model.name, getattr(cart, "source", ""))
    return {
        "L": Lm, "frame_offset": o, "frame_rotation": Rf, "links": links,
        "link_offsets": a if six else None, "B0": B0m if six else None, "plate_orientation": R0,
    }


def _check_rotation(R: np.ndarray, what: str) -> None:
    if R.shape != (3, 3) or not np.allclose(R @ R.T, np.eye(3), atol=1e-8) or not np.linalg.det(R) > 0:
        raise InputError(f"{what}: expected a rotation matrix (orthonormal, det +1), got {np.round(R, 6).tolist()}")
