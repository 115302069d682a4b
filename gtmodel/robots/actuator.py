"""The piecewise-linear actuator model, Dressler (2012), eq. 5.7, as a closure model.

A real guideway is not straight and a rack-and-pinion drive is not linear (Table 4.1:
32-77 um mean deviation from a linear fit). Instead of ``A_i = As_i + q_i v_i`` the cart
joint point follows the cart positions measured along guideway ``i`` in a separate
survey, interpolated linearly between the measured nodes (eq. 5.7)::

    P_i(q_i) = P_ik + (q_i - q_ik) / (q_i,k+1 - q_ik) (P_i,k+1 - P_ik),  q_ik <= q_i <= q_i,k+1

The survey has its own frame, so each arm gets a rigid frame between the guideway data
and the TCP data (Table 5.8, model 2: per arm ``L_i``, an offset and a rotation)::

    A_ij = R_i (P_i(q_i) - Pbar_i + a_ij) + c_i,    R_i = F_i Rot(w_i) C_i^T

:class:`PiecewiseActuatorClosure` implements it for

- the simplified 3-link model (model 2; ``B_i = T``, ``a_i = 0``), and
- the six-link error model (model 4 of Table 5.3; ``B_ij = T + R_T B0_ij``; ``a_ij`` is
  the fixed offset of joint ``ij`` from the surveyed cart point on the same cart, in the
  survey frame, ``a_i1 = 0``).

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

Six-link layout: the cart-side offsets ``a_ij``
----------------------------------------------
Near-parallelogram clusters keep the plate orientation almost constant (D1: 0.1 deg over
the workspace). Then ``R_i a_ij`` and ``R_T B0_ij`` trade off: scaling the within-arm
offsets of cart and plate together changes the closure residuals only at second order in
the orientation variation, and the end of that valley, all links of an arm on top of each
other, fits the data as well (measured: the D1 comparison with free ``a_ij`` slid there
from the true geometry, ``|a_2b|`` 0.25 m -> 0, and the FK of the result, whose plate
orientation the closure equations no longer fix, failed on the validation poses).
So by default ``a_ij`` are constants of the model, taken from the linear six-link model in
:meth:`~PiecewiseActuatorClosure.from_model` (Table 5.9 geometry), and ``B0_ij`` absorb
their error; ``free_link_offsets=True`` makes them parameters again.

The interpolation is a CasADi SX expression (a sum of ramps, see :func:`piecewise_linear`),
so the closure equations keep exact derivatives with respect to the parameters and ``T``
and the model serves calibration, the generic Newton FK and code generation alike. Poses
on a survey node sit on a kink of the ramps; that is harmless: the calibration
differentiates with respect to the parameters and the FK with respect to ``T`` and
``R_T``, never with respect to ``q``.
"""

from __future__ import annotations

import logging
from functools import cached_property
from typing import Any

import casadi as ca
import numpy as np
import numpy.typing  # noqa: F401  (np.typing in annotations)
from scipy.spatial.transform import Rotation

from gtmodel._arrays import as_rows
from gtmodel.errors import InputError
from gtmodel._geometry import rotation_to_zyz, rotation_vector_to_rotation, zyz_to_rotation
from gtmodel.robots.closure import ClosureModel, ThreeLinkClosure
from gtmodel.robots.parameters import KinematicParameters
from gtmodel.robots.six_link import estimate_nominal_orientation
from gtmodel.robots.wrapped import WrappedClosure, guideway_frame

__all__ = [
    "PiecewiseActuatorClosure",
    "piecewise_linear",
    "line_frame",
    "THREE_LINK_LAYOUT",
    "SIX_LINK_LAYOUT",
    "CART_RANGE_TOLERANCE",
    "COLLINEAR_TOLERANCE",
]

_log = logging.getLogger("gtmodel")

#: Link names of the simplified 3-link model (one link per arm, ``B = T``).
THREE_LINK_LAYOUT: tuple[tuple[str, ...], ...] = (("1",), ("2",), ("3",))
#: Link names of the six-link model (3-2-1 clusters, orientation from the closure equations).
SIX_LINK_LAYOUT: tuple[tuple[str, ...], ...] = (("1",), ("2a", "2b"), ("3a", "3b", "3c"))
#: How far [m] :meth:`PiecewiseActuatorClosure.fk` accepts ``q`` outside the surveyed
#: range of a guideway before refusing (unless built with ``extrapolate=True``).
CART_RANGE_TOLERANCE = 1e-9
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


class PiecewiseActuatorClosure(WrappedClosure):
    """Closure model with piecewise-linear actuators, Dressler (2012), eq. 5.7 and Table 5.8.

    ``A_ij = R_i (P_i(q_i) - Pbar_i + a_ij) + c_i`` with ``P_i`` the linear interpolation
    of the surveyed cart positions, ``Pbar_i`` their centroid and ``R_i`` the rotation from
    the survey frame to the TCP data frame (see the module docstring for why the frame is
    parametrised this way). Parameters per arm:

    - ``L<link>``: link lengths [m];
    - ``c<i>_x, _y, _z``: the survey centroid in the TCP frame [m];
    - ``frame<i>_ry, _rz`` [rad] (and ``frame<i>_rx`` first, with ``free_twist``): rotation
      vector ``w_i`` of ``R_i = F_i Rot(w_i) C_i^T`` in the axes of the survey's line frame
      ``C_i`` (:attr:`line_frames`, x along the surveyed line), about the fixed anchor
      ``F_i`` (:attr:`frame_anchor`, the frame given to the constructor): ``ry, rz`` tilt the
      guideway, ``rx`` is the rotation about it (the *twist*);
    - six-link layout only: ``a<link>_x, _y, _z`` [m] (only with ``free_link_offsets``, not
      for an arm's first link) and ``B0_<link>_x, _y, _z`` [m] per link.

    Layouts: :data:`THREE_LINK_LAYOUT` (model 2; ``B_i = T``, constant orientation; 6
    parameters per arm, 7 with the twist as in Table 5.8) and :data:`SIX_LINK_LAYOUT`
    (model 4; ``B_ij = T + R_T B0_ij``, orientation from the six closure equations; 9, 13
    and 17 parameters for arms 1-3, plus 1 per arm with the twist and 3 per ``a_ij`` when
    they are free).

    Parameters
    ----------
    cart : CartMeasurements
        Surveyed cart positions per arm (:class:`gtmodel.calibration.CartMeasurements`,
        or any object with per-arm tuples ``q`` (M_i,) [m] and ``positions`` (M_i, 3) [m]).
    L : array_like, shape (n_links,)
        Link lengths [m], in link order.
    frame_offset : array_like, shape (3, 3)
        Row i: ``o_i`` [m], the survey origin in the TCP frame (thesis convention,
        ``A_i = R_i P_i + o_i``).
    frame_rotation : array_like, shape (3, 3, 3), optional
        ``R_i`` (survey frame -> TCP frame), the anchor of the frame parameters (which
        start at 0). Give this or ``frame_euler_zyz``.
    links : tuple of tuple of str, optional
        :data:`THREE_LINK_LAYOUT` (default) or :data:`SIX_LINK_LAYOUT`.
    link_offsets : array_like, shape (n_links, 3), optional
        ``a_ij`` [m] in the survey frame (six-link only; rows of each arm's first link
        must be zero). Default zeros.
    B0 : array_like, shape (n_links, 3), optional
        Plate joint points ``B0_ij`` [m] in the plate frame (six-link only). Default zeros.
    extrapolate : bool, optional
        Whether :meth:`fk` accepts ``q`` outside the surveyed range (the expression
        extrapolates linearly with the end segments). Default False: an InputError.
    name : str, optional
        Model name; default ``"piecewise_three_link"`` / ``"piecewise_six_link"``.
    frame_euler_zyz : array_like, shape (3, 3), optional
        Row i: ZYZ Euler angles of ``R_i`` [rad] (Table 5.8), instead of ``frame_rotation``.
    plate_orientation : array_like, shape (3, 3), optional
        Nominal plate orientation ``R_T0`` (six-link only): start orientation of
        :meth:`fk`, not a parameter. Default identity.
    free_link_offsets : bool, optional
        Six-link only: make ``a_ij`` parameters (default False: constants, see the module
        docstring).
    free_twist : bool, optional
        Make the rotation about the guideway line a parameter (``frame<i>_rx``). Default
        False: it stays that of ``frame_rotation`` (see the module docstring).

    Raises
    ------
    InputError
        If the layout is unknown, shapes disagree, values are not finite, a length is not
        positive, a rotation is not a rotation, a first-link offset is non-zero, or not
        exactly one of ``frame_rotation`` and ``frame_euler_zyz`` is given.
    """

    n_q = 3

    def __init__(
        self,
        cart: Any,
        L: np.typing.ArrayLike,
        frame_offset: np.typing.ArrayLike,
        frame_rotation: np.typing.ArrayLike | None = None,
        links: tuple[tuple[str, ...], ...] = THREE_LINK_LAYOUT,
        link_offsets: np.typing.ArrayLike | None = None,
        B0: np.typing.ArrayLike | None = None,
        extrapolate: bool = False,
        name: str | None = None,
        frame_euler_zyz: np.typing.ArrayLike | None = None,
        plate_orientation: np.typing.ArrayLike | None = None,
        free_link_offsets: bool = False,
        free_twist: bool = False,
    ) -> None:
        links = tuple(tuple(str(n) for n in arm) for arm in links)
        if links not in (THREE_LINK_LAYOUT, SIX_LINK_LAYOUT):
            raise InputError(f"links: expected THREE_LINK_LAYOUT {THREE_LINK_LAYOUT} or SIX_LINK_LAYOUT {SIX_LINK_LAYOUT}, got {links}")
        self.links = links
        self.orientation = links == SIX_LINK_LAYOUT
        self.name = name or ("piecewise_six_link" if self.orientation else "piecewise_three_link")
        self.cart_q, self.cart_positions = _cart_arrays(cart, 3)
        self.cart_source = str(getattr(cart, "source", ""))
        self._cart = cart
        self.extrapolate = bool(extrapolate)
        self.free_link_offsets = bool(free_link_offsets) and self.orientation
        self.free_twist = bool(free_twist)
        #: Centroid ``Pbar_i`` of each survey [m] (survey frame), shape (3, 3).
        self.survey_centroid = np.array([p.mean(axis=0) for p in self.cart_positions])
        #: Line frame ``C_i`` of each survey (:func:`line_frame`, survey frame), shape (3, 3, 3).
        self.line_frames = np.array([line_frame(q, p) for q, p in zip(self.cart_q, self.cart_positions)])
        n_l = sum(len(a) for a in links)

        def arr(x: Any, shape: tuple[int, ...], what: str) -> np.ndarray:
            a = np.asarray(np.zeros(shape) if x is None else x, dtype=float)
            if a.shape != shape or not np.all(np.isfinite(a)):
                raise InputError(f"{what}: expected finite values of shape {shape}, got {np.shape(x)}")
            return a.copy()

        self.L = arr(L, (n_l,), "L")
        if np.any(self.L <= 0):
            raise InputError(f"L: link lengths must be positive, got {self.L.tolist()}")
        o = arr(frame_offset, (3, 3), "frame_offset")
        if (frame_rotation is None) == (frame_euler_zyz is None):
            raise InputError("give exactly one of frame_rotation (3, 3, 3) and frame_euler_zyz (3, 3)")
        if frame_rotation is not None:
            R = arr(frame_rotation, (3, 3, 3), "frame_rotation")
        else:
            e = arr(frame_euler_zyz, (3, 3), "frame_euler_zyz")
            R = np.array([zyz_to_rotation(*row) for row in e])
        for i in range(3):
            _check_rotation(R[i], f"frame_rotation[{i}]")
        #: Anchors ``F_i`` of the frame rotations (line frame -> TCP frame), shape (3, 3, 3).
        self.frame_anchor = np.array([R[i] @ self.line_frames[i] for i in range(3)])
        #: Rotation vectors ``w_i`` about the anchors [rad], line-frame axes (parameters
        #: ``frame<i>_rx, _ry, _rz``; ``rx`` stays 0 unless ``free_twist``), shape (3, 3).
        self.frame_rotvec = np.zeros((3, 3))
        #: ``c_i`` = survey centroid in the TCP frame [m] (parameters ``c<i>_*``), shape (3, 3).
        self.centre = np.array([R[i] @ self.survey_centroid[i] + o[i] for i in range(3)])
        if not self.orientation and (link_offsets is not None or B0 is not None or plate_orientation is not None):
            if (
                np.any(np.asarray(link_offsets if link_offsets is not None else 0.0) != 0)
                or np.any(np.asarray(B0 if B0 is not None else 0.0) != 0)
                or plate_orientation is not None
            ):
                raise InputError("link_offsets, B0 and plate_orientation belong to the six-link layout; the 3-link model has B = T")
        self.link_offsets = arr(link_offsets, (n_l, 3), "link_offsets")
        self.B0 = arr(B0, (n_l, 3), "B0")
        self.plate_orientation = np.eye(3) if plate_orientation is None else arr(plate_orientation, (3, 3), "plate_orientation")
        _check_rotation(self.plate_orientation, "plate_orientation")
        for i in range(3):
            j0 = self._first_link(i)
            if np.any(self.link_offsets[j0] != 0):
                raise InputError(f"link_offsets: row {j0} (first link of arm {i + 1}) must be zero; its offset is the frame's")

    _STATE = (
        "links", "orientation", "name", "cart_q", "cart_positions", "cart_source", "_cart", "extrapolate",
        "free_link_offsets", "free_twist", "survey_centroid", "line_frames", "L", "frame_anchor", "frame_rotvec", "centre",
        "link_offsets", "B0", "plate_orientation",
    )

    def _replace(self, **changes: Any) -> "PiecewiseActuatorClosure":
        """A copy with some state replaced (no cached graphs carried over)."""
        new = object.__new__(type(self))
        for k in self._STATE:
            v = changes.get(k, getattr(self, k))
            new.__dict__[k] = v.copy() if isinstance(v, np.ndarray) else v
        return new

    # ------------------------------------------------------------------ layout helpers
    def _first_link(self, arm: int) -> int:
        return sum(len(a) for a in self.links[:arm])

    def _arm_slices(self) -> list[dict[str, Any]]:
        """Per arm the parameter index layout."""
        out, k = [], 0
        for arm in self.links:
            d: dict[str, Any] = {"L": list(range(k, k + len(arm)))}
            k += len(arm)
            d["c"] = list(range(k, k + 3))
            k += 3
            nr = 3 if self.free_twist else 2
            d["rot"] = list(range(k, k + nr))
            k += nr
            d["a"], d["B0"] = {}, {}
            if self.orientation:
                for j in range(len(arm)):
                    if j > 0 and self.free_link_offsets:
                        d["a"][j] = list(range(k, k + 3))
                        k += 3
                    d["B0"][j] = list(range(k, k + 3))
                    k += 3
            out.append(d)
        return out

    # ------------------------------------------------------------------ ClosureModel API
    def parameter_names(self) -> tuple[str, ...]:
        """Names per arm: ``L<link>``, ``c<i>_x..z``, ``frame<i>_(rx,) ry, rz``, (six-link) ``a<link>_x..z``, ``B0_<link>_x..z``.

        Returns
        -------
        tuple of str
            E.g. ``("L1", "c1_x", "c1_y", "c1_z", "frame1_ry", "frame1_rz", "L2", ...)``.
        """
        names: list[str] = []
        for i, arm in enumerate(self.links):
            names += [f"L{n}" for n in arm]
            names += [f"c{i + 1}_{c}" for c in "xyz"]
            names += [f"frame{i + 1}_r{c}" for c in ("xyz" if self.free_twist else "yz")]
            if self.orientation:
                for j, n in enumerate(arm):
                    if j > 0 and self.free_link_offsets:
                        names += [f"a{n}_{c}" for c in "xyz"]
                    names += [f"B0_{n}_{c}" for c in "xyz"]
        return tuple(names)

    def parameter_vector(self) -> np.ndarray:
        """Current values in the order of :meth:`parameter_names` (m, rad).

        Returns
        -------
        numpy.ndarray, shape (18,) (3-link), (39,) (six-link); 3 more with ``free_twist``,
            9 more with ``free_link_offsets``
        """
        p = np.empty(self.n_parameters)
        for i, d in enumerate(self._arm_slices()):
            j0 = self._first_link(i)
            p[d["L"]] = self.L[j0: j0 + len(self.links[i])]
            p[d["c"]] = self.centre[i]
            p[d["rot"]] = self.frame_rotvec[i, 3 - len(d["rot"]):]
            for j, ix in d["a"].items():
                p[ix] = self.link_offsets[j0 + j]
            for j, ix in d["B0"].items():
                p[ix] = self.B0[j0 + j]
        return p

    def cart_expression(self, arm: int, q_i: Any) -> Any:
        """Surveyed cart position ``P_i(q_i)`` of eq. 5.7 (survey frame), as an expression.

        Parameters
        ----------
        arm : int
            Arm index 0, 1, 2.
        q_i : casadi.SX or casadi.MX or float
            Actuator value of the arm [m].

        Returns
        -------
        casadi.SX or casadi.MX or casadi.DM, shape (3, 1)
            ``P_i(q_i)`` [m] (linear extrapolation outside the surveyed range).

        Raises
        ------
        InputError
            If ``arm`` is not 0, 1 or 2.
        """
        if arm not in range(3):
            raise InputError(f"arm must be one of 0..2, got {arm!r}")
        return piecewise_linear(q_i, self.cart_q[arm], self.cart_positions[arm])

    def link_points(self, p: ca.SX, q: ca.SX, T: ca.SX, R: ca.SX, arm: int) -> tuple[ca.SX, ca.SX, ca.SX]:
        """``A_ij = R_i (P_i(q_i) - Pbar_i + a_ij) + c_i`` (eq. 5.7), ``B_ij = T`` or ``T + R_T B0_ij``, ``L_ij``.

        ``R_i = F_i Rot(w_i) C_i^T`` (:func:`~gtmodel.robots.closure.rotation_vector_to_rotation`).

        Parameters
        ----------
        p : casadi.SX, shape (n_parameters,)
            Parameters.
        q : casadi.SX, shape (3,)
            Cart positions [m].
        T : casadi.SX, shape (3,)
            TCP position [m].
        R : casadi.SX, shape (3, 3)
            Plate orientation (used by the six-link layout only).
        arm : int
            Arm index 0, 1, 2.

        Returns
        -------
        A, B : casadi.SX, shape (3, n_links_of_arm)
            Joint points [m].
        L : casadi.SX, shape (n_links_of_arm,)
            Link lengths [m].
        """
        d = self._arm_slices()[arm]
        j0 = self._first_link(arm)
        w = ca.vertcat(*([0.0] if not self.free_twist else []), p[d["rot"][0]: d["rot"][-1] + 1])
        Ri = ca.mtimes([ca.DM(self.frame_anchor[arm]), rotation_vector_to_rotation(w), ca.DM(self.line_frames[arm].T)])
        ci = p[d["c"][0]: d["c"][-1] + 1]
        Pi = self.cart_expression(arm, q[arm]) - ca.DM(self.survey_centroid[arm])
        A, B = [], []
        for j in range(len(self.links[arm])):
            if j in d["a"]:
                a = p[d["a"][j][0]: d["a"][j][-1] + 1]
            else:
                a = ca.DM(self.link_offsets[j0 + j])
            A.append(ca.mtimes(Ri, Pi + a) + ci if j > 0 else ca.mtimes(Ri, Pi) + ci)
            if self.orientation:
                B.append(T + ca.mtimes(R, p[d["B0"][j][0]: d["B0"][j][-1] + 1]))
            else:
                B.append(T)
        L = ca.vertcat(*[p[k] for k in d["L"]])
        return ca.horzcat(*A), ca.horzcat(*B), L

    def quaternion_indices(self) -> list[tuple[int, int, int, int]]:
        """No quaternion parameters (the frame rotations are rotation vectors).

        Returns
        -------
        list of tuple of int
            Empty.
        """
        return []

    def _with_parameters(self, pa: np.ndarray) -> "PiecewiseActuatorClosure":
        """The model with other (checked) parameter values, same cart survey and constants;
        an InputError if a length is not positive."""
        L, c, w = self.L.copy(), self.centre.copy(), self.frame_rotvec.copy()
        a, B0 = self.link_offsets.copy(), self.B0.copy()
        for i, d in enumerate(self._arm_slices()):
            j0 = self._first_link(i)
            L[j0: j0 + len(self.links[i])] = pa[d["L"]]
            c[i] = pa[d["c"]]
            w[i, 3 - len(d["rot"]):] = pa[d["rot"]]
            for j, ix in d["a"].items():
                a[j0 + j] = pa[ix]
            for j, ix in d["B0"].items():
                B0[j0 + j] = pa[ix]
        if np.any(L <= 0):
            raise InputError(f"{self.name}: link lengths must be positive, got {L.tolist()}")
        return self._replace(L=L, centre=c, frame_rotvec=w, link_offsets=a, B0=B0)

    def _transformed(self, R: np.ndarray, t: Any) -> "PiecewiseActuatorClosure":
        """The model in another frame, ``x' = R x + t`` (Dressler (2012), eqs. 5.3-5.4).

        ``R_i' = R R_i`` (the anchors turn: ``F_i' = R F_i``, the parameters ``w_i`` are
        kept), ``c_i' = R c_i + t``, nominal plate orientation ``R R_T0``; ``a_ij`` (survey
        frame), ``B0_ij`` (plate frame) and ``L`` are unchanged. The anchors are constants of
        the closure equations, so a rotated model has other equations (a calibration
        builds its graphs for it). An InputError if ``R`` is not a rotation or the shapes
        are wrong.
        """
        Rm = R
        tv = np.asarray(t, dtype=float)
        if Rm.shape != (3, 3) or tv.shape not in ((3,), (3, 1)):
            raise InputError(f"R, t: expected shapes (3, 3) and (3,), got {Rm.shape} and {tv.shape}")
        _check_rotation(Rm, "R")
        return self._replace(
            frame_anchor=Rm @ self.frame_anchor, centre=self.centre @ Rm.T + tv.reshape(3), plate_orientation=Rm @ self.plate_orientation
        )

    # ------------------------------------------------------------------ numeric helpers
    def frame_rotation(self, arm: int) -> np.ndarray:
        """Rotation ``R_i`` from the survey frame of guideway ``arm`` to the TCP data frame.

        Parameters
        ----------
        arm : int
            Arm index 0, 1, 2.

        Returns
        -------
        numpy.ndarray, shape (3, 3)
        """
        w = self.frame_rotvec[arm] if self.free_twist else np.array([0.0, *self.frame_rotvec[arm, 1:]])
        return self.frame_anchor[arm] @ rotation_vector_to_rotation(w) @ self.line_frames[arm].T

    @property
    def frame_offset(self) -> np.ndarray:
        """``o_i = c_i - R_i Pbar_i``: the survey origin in the TCP frame [m] (thesis convention), shape (3, 3)."""
        return np.array([self.centre[i] - self.frame_rotation(i) @ self.survey_centroid[i] for i in range(3)])

    @property
    def frame_euler_zyz(self) -> np.ndarray:
        """ZYZ Euler angles of ``R_i`` [rad] (Table 5.8 convention, ``beta`` in [0, pi]), shape (3, 3)."""
        return np.array([rotation_to_zyz(self.frame_rotation(i)) for i in range(3)])

    @cached_property
    def _points_function(self) -> ca.Function:
        p, q, T, _ = self._symbols
        R = ca.SX.sym("R", 3, 3)
        A = ca.horzcat(*[self.link_points(p, q, T, R, i)[0] for i in range(3)])
        return ca.Function("A", [p, q], [A], ["p", "q"], ["A"])

    def joint_points(self, q: np.typing.ArrayLike) -> np.ndarray:
        """Actuator-side joint points ``A_ij(q)`` [m] (same graph as the closure equations).

        Parameters
        ----------
        q : array_like, shape (3,) or (N, 3)
            Cart positions [m].

        Returns
        -------
        numpy.ndarray, shape (n_links, 3) or (N, n_links, 3)
            Row ``j``: joint point of link ``j`` (links in order) [m].

        Raises
        ------
        InputError
            If ``q`` does not have 3 columns.
        """
        qa, single = as_rows(q, "q", 3)
        A = np.array(self._points_function.map(qa.shape[0])(self.parameter_vector(), qa.T))
        A = A.reshape(3, qa.shape[0], self.n_links).transpose(1, 2, 0)
        return A[0] if single else A

    def _check_range(self, q: np.ndarray) -> None:
        if self.extrapolate:
            return
        for i in range(3):
            lo, hi = self.cart_q[i][0], self.cart_q[i][-1]
            bad = (q[:, i] < lo - CART_RANGE_TOLERANCE) | (q[:, i] > hi + CART_RANGE_TOLERANCE)
            if np.any(bad):
                k = int(np.argmax(bad))
                raise InputError(
                    f"{self.name}: q{i + 1} = {float(q[k, i])!r} (row {k}) is outside the surveyed range [{lo}, {hi}] m of guideway "
                    f"{i + 1}; build the model with extrapolate=True to extrapolate linearly"
                )

    def linear_approximation(self) -> ThreeLinkClosure:
        """Simplified 3-link model through the ends of each surveyed range (FK start values).

        ``As_i = A_i1(0) - R_T0 B0_i1`` (plate at the nominal orientation
        :attr:`plate_orientation`), ``v_i`` the chord of ``A_i1`` over the surveyed range,
        ``L_i`` the first link's length.

        Returns
        -------
        ThreeLinkClosure
            The modified (21-parameter) linear model.
        """
        As, v = np.empty((3, 3)), np.empty((3, 3))
        for i in range(3):
            j0 = self._first_link(i)
            lo, hi = self.cart_q[i][0], self.cart_q[i][-1]
            qs = np.zeros((3, 3))
            qs[:, i] = [lo, hi, 0.0]
            A = self.joint_points(qs)[:, j0]
            v[i] = (A[1] - A[0]) / (hi - lo)
            As[i] = A[2] - self.plate_orientation @ self.B0[j0]
        L = np.array([self.L[self._first_link(i)] for i in range(3)])
        return ThreeLinkClosure(KinematicParameters(L=L, As=As, v=v, model="modified", source=f"chord of {self.name}"))

    def fk_inputs(self, q: np.typing.ArrayLike) -> np.ndarray:
        """Cart positions for :meth:`fk`, checked: finite, 3 columns, inside the surveyed ranges.

        The FK (:meth:`~gtmodel.robots.wrapped.WrappedClosure.fk`) starts from the
        closed-form FK of :meth:`linear_approximation` with the plate at
        :attr:`plate_orientation`, refined by :meth:`ClosureModel.fk_newton` (tolerance
        :data:`gtmodel.robots.closure.POSE_TOLERANCE`).

        Parameters
        ----------
        q : array_like, shape (3,) or (N, 3)
            Cart positions [m], inside the surveyed ranges (see ``extrapolate``).

        Returns
        -------
        numpy.ndarray, shape (3,) or (N, 3)

        Raises
        ------
        InputError
            If ``q`` has the wrong shape or lies outside a surveyed range.
        """
        q2, single = as_rows(q, "q", 3)
        self._check_range(q2)
        return q2[0] if single else q2

    def fk_start(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray | None]:
        """Start of Newton's method: the chord 3-link model's FK, the nominal plate orientation.

        Parameters
        ----------
        q : numpy.ndarray, shape (3,) or (N, 3)
            Cart positions [m].

        Returns
        -------
        T0 : numpy.ndarray, shape (N, 3)
            Start TCP positions [m].
        R0 : numpy.ndarray, shape (3, 3), or None
            :attr:`plate_orientation` (six-link layout), None (3-link layout).
        """
        T0, _ = self.linear_approximation().fk(np.atleast_2d(q))
        return T0, (self.plate_orientation if self.orientation else None)

    # ------------------------------------------------------------------ construction
    @classmethod
    def from_model(
        cls, model: ClosureModel, cart: Any, extrapolate: bool = False, free_link_offsets: bool = False, free_twist: bool = False
    ) -> "PiecewiseActuatorClosure":
        """Piecewise-linear model matching a linear-actuator model: the frame fit.

        Per arm, ``(R_i, c_i)`` maps the surveyed cart points ``P_i(q_ik)`` onto the model's
        joint points ``A_i1(q_ik)``: ``c_i`` is the centroid of the ``A_i1(q_ik)``; ``R_i`` the
        least-squares rigid fit (Kabsch/Wahba, SciPy's ``Rotation.align_vectors``) when the
        model's joint path is bent, and otherwise (a linear actuator, straight path, see
        :data:`COLLINEAR_TOLERANCE`) the rotation of least angle taking the survey's line
        direction onto the model's: the fit does not determine the rotation about the line
        then, and "no twist" is exact when survey and TCP frames differ by a rotation about
        an axis perpendicular to the guideway (e.g. the same levelled tracker turned about
        the vertical). ``L`` and, for a six-link model, ``B0_ij``, the nominal plate
        orientation (``model.R0``, else estimated from the parallelogram clusters by
        :func:`~gtmodel.robots.six_link.estimate_nominal_orientation`) and ``a_ij`` (the mean over the survey
        nodes of ``R_i^T (A_ij - A_i1)``) are taken from the model. This is the start value
        of a model-2/model-4 calibration; with a straight survey of the same guideway the
        result reproduces ``model`` exactly.

        Parameters
        ----------
        model : ClosureModel
            A model with linear actuators (``A_ij`` depending on ``q_i`` only): the 3-link
            model (3 single links, no orientation) or a six-link model.
        cart : CartMeasurements
            The guideway survey.
        extrapolate : bool, optional
            See the class.
        free_link_offsets, free_twist : bool, optional
            See the class.

        Returns
        -------
        PiecewiseActuatorClosure

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
        return cls(
            cart, Lm, o, Rf, links=links,
            link_offsets=a if six else None, B0=B0m if six else None, extrapolate=extrapolate,
            plate_orientation=R0, free_link_offsets=free_link_offsets, free_twist=free_twist,
        )


def _check_rotation(R: np.ndarray, what: str) -> None:
    if R.shape != (3, 3) or not np.allclose(R @ R.T, np.eye(3), atol=1e-8) or not np.linalg.det(R) > 0:
        raise InputError(f"{what}: expected a rotation matrix (orthonormal, det +1), got {np.round(R, 6).tolist()}")
