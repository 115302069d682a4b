"""The piecewise-linear actuator model, Dressler (2012), eq. 5.7, as a closure model.

A real guideway is not straight and a rack-and-pinion drive is not linear (Table 4.1:
32-77 um mean deviation from a linear fit). Instead of ``A_i = As_i + q_i v_i`` the cart
joint point follows the cart positions measured along guideway ``i`` in a separate
survey, interpolated linearly between the measured nodes (eq. 5.7)::

    P_i(q_i) = P_ik + (q_i - q_ik) / (q_i,k+1 - q_ik) (P_i,k+1 - P_ik),  q_ik <= q_i <= q_i,k+1

The survey has its own frame, so each arm gets a frame between the guideway data and the
TCP data, an offset ``o_i`` and a rotation ``R_i`` from ZYZ Euler angles (eq. 4.15)::

    A_ij = R_i P_i(q_i) + o_i + R_i a_ij

(Dressler (2012), Table 5.8, model 2: per arm ``L_i``, ``o_i`` (3), Euler ZYZ (3) = 7
parameters). :class:`PiecewiseActuatorClosure` implements it for

- the simplified 3-link model (model 2; ``B_i = T``, ``a_i = 0``), and
- the six-link error model (model 4 of Table 5.3; ``B_ij = T + R_T B0_ij`` and a fixed
  offset ``a_ij`` of joint ``ij`` from the surveyed cart point, expressed in the survey
  frame; ``a_i1 = 0`` because ``o_i`` already carries the first joint's offset).

The interpolation is a CasADi SX expression (a sum of ramps, see :func:`piecewise_linear`),
so the closure equations keep exact derivatives with respect to the parameters and ``T``
and the model serves calibration, the generic Newton FK and code generation alike.
"""

from __future__ import annotations

import logging
import warnings
from functools import cached_property
from typing import Any

import casadi as ca
import numpy as np
import numpy.typing  # noqa: F401  (np.typing in annotations)
from scipy.spatial.transform import Rotation

from gtmodel.errors import InputError
from gtmodel.robots.closure import ClosureModel, ThreeLinkClosure, rotation_to_zyz, zyz_to_rotation
from gtmodel.robots.parameters import KinematicParameters

__all__ = [
    "PiecewiseActuatorClosure",
    "piecewise_linear",
    "THREE_LINK_LAYOUT",
    "SIX_LINK_LAYOUT",
    "CART_RANGE_TOLERANCE",
]

_log = logging.getLogger("gtmodel")

#: Link names of the simplified 3-link model (one link per arm, ``B = T``).
THREE_LINK_LAYOUT: tuple[tuple[str, ...], ...] = (("1",), ("2",), ("3",))
#: Link names of the six-link model (3-2-1 clusters, orientation from the closure equations).
SIX_LINK_LAYOUT: tuple[tuple[str, ...], ...] = (("1",), ("2a", "2b"), ("3a", "3b", "3c"))
#: How far [m] :meth:`PiecewiseActuatorClosure.fk` accepts ``q`` outside the surveyed
#: range of a guideway before refusing (unless built with ``extrapolate=True``).
CART_RANGE_TOLERANCE = 1e-9


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


class PiecewiseActuatorClosure(ClosureModel):
    """Closure model with piecewise-linear actuators, Dressler (2012), eq. 5.7 and Table 5.8.

    ``A_ij = R_i P_i(q_i) + o_i + R_i a_ij`` with ``P_i`` the linear interpolation of the
    surveyed cart positions, ``R_i = Rz(alpha_i) Ry(beta_i) Rz(gamma_i)``. Layouts:

    - :data:`THREE_LINK_LAYOUT` (model 2): ``B_i = T``, constant orientation; parameters
      per arm ``L_i, o_i_x, o_i_y, o_i_z, euler_i_alpha, euler_i_beta, euler_i_gamma``
      (7 per arm, 21 in all).
    - :data:`SIX_LINK_LAYOUT` (model 4): ``B_ij = T + R_T B0_ij``, orientation from the six
      closure equations; parameters per arm: the arm's ``L_ij``, ``o_i``, Euler angles,
      then ``a_ij`` (not for the first link of the arm, whose offset is ``o_i``) and
      ``B0_ij`` per link (10, 17 and 24 parameters for arms 1-3).

    Parameters
    ----------
    cart : CartMeasurements
        Surveyed cart positions per arm (:class:`gtmodel.calibration.CartMeasurements`,
        or any object with per-arm tuples ``q`` (M_i,) [m] and ``positions`` (M_i, 3) [m]).
    L : array_like, shape (n_links,)
        Link lengths [m], in link order.
    frame_offset : array_like, shape (3, 3)
        Row i: ``o_i`` [m].
    frame_euler_zyz : array_like, shape (3, 3)
        Row i: ZYZ Euler angles ``(alpha, beta, gamma)`` of ``R_i`` [rad].
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

    Raises
    ------
    InputError
        If the layout is unknown, shapes disagree, values are not finite, a length is not
        positive or a first-link offset is non-zero.

    Notes
    -----
    With a perfectly straight survey the rotation of ``R_i`` about the guideway line does
    not change ``A_i``: one parameter combination per arm is not identifiable (a bent
    guideway makes it weakly identifiable). The Euler angles of Table 5.8 have
    ``beta`` near 0 (about -0.5 deg), close to the ZYZ gimbal lock, where ``alpha`` and
    ``gamma`` are nearly redundant. Both are the calibration's business
    (identifiability analysis), not this model's.
    """

    n_q = 3

    def __init__(
        self,
        cart: Any,
        L: np.typing.ArrayLike,
        frame_offset: np.typing.ArrayLike,
        frame_euler_zyz: np.typing.ArrayLike,
        links: tuple[tuple[str, ...], ...] = THREE_LINK_LAYOUT,
        link_offsets: np.typing.ArrayLike | None = None,
        B0: np.typing.ArrayLike | None = None,
        extrapolate: bool = False,
        name: str | None = None,
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
        n_l = sum(len(a) for a in links)

        def arr(x: Any, shape: tuple[int, ...], what: str) -> np.ndarray:
            a = np.asarray(np.zeros(shape) if x is None else x, dtype=float)
            if a.shape != shape or not np.all(np.isfinite(a)):
                raise InputError(f"{what}: expected finite values of shape {shape}, got {np.shape(x)}")
            return a.copy()

        self.L = arr(L, (n_l,), "L")
        if np.any(self.L <= 0):
            raise InputError(f"L: link lengths must be positive, got {self.L.tolist()}")
        self.frame_offset = arr(frame_offset, (3, 3), "frame_offset")
        self.frame_euler_zyz = arr(frame_euler_zyz, (3, 3), "frame_euler_zyz")
        if not self.orientation and (link_offsets is not None or B0 is not None):
            if np.any(np.asarray(link_offsets if link_offsets is not None else 0.0) != 0) or np.any(
                np.asarray(B0 if B0 is not None else 0.0) != 0
            ):
                raise InputError("link_offsets and B0 belong to the six-link layout; the 3-link model has B = T")
        self.link_offsets = arr(link_offsets, (n_l, 3), "link_offsets")
        self.B0 = arr(B0, (n_l, 3), "B0")
        for i in range(3):
            j0 = self._first_link(i)
            if np.any(self.link_offsets[j0] != 0):
                raise InputError(f"link_offsets: row {j0} (first link of arm {i + 1}) must be zero; its offset is o_{i + 1}")

    # ------------------------------------------------------------------ layout helpers
    def _first_link(self, arm: int) -> int:
        return sum(len(a) for a in self.links[:arm])

    def _arm_slices(self) -> list[dict[str, Any]]:
        """Per arm the parameter index layout."""
        out, k = [], 0
        for i, arm in enumerate(self.links):
            d: dict[str, Any] = {"L": list(range(k, k + len(arm)))}
            k += len(arm)
            d["o"] = list(range(k, k + 3))
            k += 3
            d["euler"] = list(range(k, k + 3))
            k += 3
            d["a"], d["B0"] = {}, {}
            if self.orientation:
                for j in range(len(arm)):
                    if j > 0:
                        d["a"][j] = list(range(k, k + 3))
                        k += 3
                    d["B0"][j] = list(range(k, k + 3))
                    k += 3
            out.append(d)
        return out

    # ------------------------------------------------------------------ ClosureModel API
    def parameter_names(self) -> tuple[str, ...]:
        """Names per arm: ``L<link>``, ``o<i>_x..z``, ``euler<i>_alpha/beta/gamma`` then (six-link) ``a<link>_x..z``, ``B0_<link>_x..z``.

        Returns
        -------
        tuple of str
            E.g. ``("L1", "o1_x", "o1_y", "o1_z", "euler1_alpha", "euler1_beta", "euler1_gamma", "L2", ...)``.
        """
        names: list[str] = []
        for i, arm in enumerate(self.links):
            names += [f"L{n}" for n in arm]
            names += [f"o{i + 1}_{c}" for c in "xyz"]
            names += [f"euler{i + 1}_{a}" for a in ("alpha", "beta", "gamma")]
            if self.orientation:
                for j, n in enumerate(arm):
                    if j > 0:
                        names += [f"a{n}_{c}" for c in "xyz"]
                    names += [f"B0_{n}_{c}" for c in "xyz"]
        return tuple(names)

    def parameter_vector(self) -> np.ndarray:
        """Current values in the order of :meth:`parameter_names` (m, rad).

        Returns
        -------
        numpy.ndarray, shape (21,) or (51,)
        """
        p = np.empty(self.n_parameters)
        for i, d in enumerate(self._arm_slices()):
            j0 = self._first_link(i)
            p[d["L"]] = self.L[j0: j0 + len(self.links[i])]
            p[d["o"]] = self.frame_offset[i]
            p[d["euler"]] = self.frame_euler_zyz[i]
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
        """``A_ij = R_i P_i(q_i) + o_i + R_i a_ij`` (eq. 5.7), ``B_ij = T`` or ``T + R_T B0_ij``, ``L_ij``.

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
        Ri = zyz_to_rotation(p[d["euler"][0]], p[d["euler"][1]], p[d["euler"][2]])
        oi = p[d["o"][0]: d["o"][-1] + 1]
        Ai = ca.mtimes(Ri, self.cart_expression(arm, q[arm])) + oi
        A, B = [], []
        for j in range(len(self.links[arm])):
            if j in d["a"]:
                A.append(Ai + ca.mtimes(Ri, p[d["a"][j][0]: d["a"][j][-1] + 1]))
            else:
                A.append(Ai)
            if self.orientation:
                B.append(T + ca.mtimes(R, p[d["B0"][j][0]: d["B0"][j][-1] + 1]))
            else:
                B.append(T)
        L = ca.vertcat(*[p[k] for k in d["L"]])
        return ca.horzcat(*A), ca.horzcat(*B), L

    def _copy(self, L: np.ndarray, o: np.ndarray, e: np.ndarray, a: np.ndarray, B0: np.ndarray) -> "PiecewiseActuatorClosure":
        return PiecewiseActuatorClosure(
            self._cart, L, o, e, links=self.links,
            link_offsets=a if self.orientation else None, B0=B0 if self.orientation else None,
            extrapolate=self.extrapolate, name=self.name,
        )

    def with_parameters(self, p: np.typing.ArrayLike) -> "PiecewiseActuatorClosure":
        """The model with other parameter values (same cart survey).

        Parameters
        ----------
        p : array_like, shape (n_parameters,)
            Values in the order of :meth:`parameter_names`.

        Returns
        -------
        PiecewiseActuatorClosure

        Raises
        ------
        InputError
            If ``p`` has the wrong size or is not finite.
        """
        pa = np.asarray(p, dtype=float).ravel()
        if pa.size != self.n_parameters or not np.all(np.isfinite(pa)):
            raise InputError(f"{self.name}: expected {self.n_parameters} finite parameters, got {pa.size}")
        L = self.L.copy()
        o, e = self.frame_offset.copy(), self.frame_euler_zyz.copy()
        a, B0 = self.link_offsets.copy(), self.B0.copy()
        for i, d in enumerate(self._arm_slices()):
            j0 = self._first_link(i)
            L[j0: j0 + len(self.links[i])] = pa[d["L"]]
            o[i] = pa[d["o"]]
            e[i] = pa[d["euler"]]
            for j, ix in d["a"].items():
                a[j0 + j] = pa[ix]
            for j, ix in d["B0"].items():
                B0[j0 + j] = pa[ix]
        return self._copy(L, o, e, a, B0)

    def transformed(self, R: np.typing.ArrayLike, t: np.typing.ArrayLike) -> "PiecewiseActuatorClosure":
        """The model in another frame, ``x' = R x + t`` (Dressler (2012), eqs. 5.3-5.4).

        ``R_i' = R R_i`` (Euler angles recomputed, ``beta`` in [0, pi]), ``o_i' = R o_i + t``;
        ``a_ij`` (survey frame), ``B0_ij`` (plate frame) and ``L`` are unchanged.

        Parameters
        ----------
        R : array_like, shape (3, 3)
            Rotation.
        t : array_like, shape (3,)
            Translation [m].

        Returns
        -------
        PiecewiseActuatorClosure
        """
        Rm = np.asarray(R, dtype=float).reshape(3, 3)
        tv = np.asarray(t, dtype=float).reshape(3)
        e = np.array([rotation_to_zyz(Rm @ self.frame_rotation(i)) for i in range(3)])
        o = self.frame_offset @ Rm.T + tv
        return self._copy(self.L.copy(), o, e, self.link_offsets.copy(), self.B0.copy())

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
        return zyz_to_rotation(*self.frame_euler_zyz[arm])

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
        qa = np.asarray(q, dtype=float)
        single = qa.ndim == 1
        qa = np.atleast_2d(qa)
        if qa.shape[1] != 3:
            raise InputError(f"q must have 3 columns, got shape {np.shape(q)}")
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

        ``As_i = A_i1(0)`` moved by ``-B0_i1`` (plate at the nominal orientation), ``v_i`` the
        chord of ``A_i1`` over the surveyed range, ``L_i`` the first link's length.

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
            As[i] = A[2] - self.B0[j0]
        L = np.array([self.L[self._first_link(i)] for i in range(3)])
        return ThreeLinkClosure(KinematicParameters(L=L, As=As, v=v, model="modified", source=f"chord of {self.name}"))

    def fk(self, q: np.typing.ArrayLike) -> tuple[np.ndarray, np.ndarray]:
        """Forward kinematics: Newton on the closure equations from the chord 3-link model.

        The start value is the closed-form FK of :meth:`linear_approximation` (nominal
        assembly), refined by :meth:`ClosureModel.fk_newton` (tolerance
        :data:`gtmodel.robots.closure.POSE_TOLERANCE`).

        Parameters
        ----------
        q : array_like, shape (3,) or (N, 3)
            Cart positions [m], inside the surveyed ranges (see ``extrapolate``).

        Returns
        -------
        T : numpy.ndarray, shape (3,) or (N, 3)
            TCP positions [m].
        R : numpy.ndarray, shape (3, 3) or (N, 3, 3)
            Plate orientations (identity for the 3-link layout).

        Raises
        ------
        InputError
            If ``q`` has the wrong shape or lies outside a surveyed range.
        UnreachablePoseError
            If the start model admits no pose.
        ConvergenceError
            If Newton's method does not converge (names the pose).
        """
        qa = np.asarray(q, dtype=float)
        single = qa.ndim == 1
        q2 = np.atleast_2d(qa)
        if q2.shape[1] != 3 or not np.all(np.isfinite(q2)):
            raise InputError(f"q must be finite with 3 columns, got shape {np.shape(q)}")
        self._check_range(q2)
        T0, _ = self.linear_approximation().fk(q2)
        T, R = self.fk_newton(q2, T0)
        return (T[0], R[0]) if single else (T, R)

    # ------------------------------------------------------------------ construction
    @classmethod
    def from_model(cls, model: ClosureModel, cart: Any, extrapolate: bool = False) -> "PiecewiseActuatorClosure":
        """Piecewise-linear model matching a linear-actuator model: the frame fit.

        Per arm, ``(R_i, o_i)`` is the least-squares rigid fit (Kabsch/Wahba, SciPy's
        ``Rotation.align_vectors``) of the surveyed cart points ``P_i(q_ik)`` onto the
        model's joint points ``A_i1(q_ik)``; ``L`` (and for a six-link model ``B0_ij`` and
        ``a_ij = R_i^T (A_ij - A_i1)``) are copied from the model. This is the start value of
        a model-2/model-4 calibration; with a straight survey of the same guideway the
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
        e = np.empty((3, 3))
        a = np.zeros((len(Lm), 3))
        j0 = 0
        for i, arm in enumerate(links):
            qs = np.zeros((3, cq[i].size))
            qs[i] = cq[i]
            Ak = np.array(fA.map(cq[i].size)(pv, qs)).reshape(3, cq[i].size, len(Lm))[:, :, j0].T
            Pc, Ac = cp[i] - cp[i].mean(axis=0), Ak - Ak.mean(axis=0)
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", UserWarning)  # straight survey: rotation about the line is free
                rot, _ = Rotation.align_vectors(Ac, Pc)
            Ri = rot.as_matrix()
            o[i] = Ak.mean(axis=0) - Ri @ cp[i].mean(axis=0)
            e[i] = rotation_to_zyz(Ri)
            A0 = np.array(fA(pv, np.zeros(3))).reshape(3, len(Lm)).T
            for j in range(1, len(arm)):
                a[j0 + j] = Ri.T @ (A0[j0 + j] - A0[j0])
            j0 += len(arm)
        _log.debug("%s: frames fitted to the cart survey %s", model.name, getattr(cart, "source", ""))
        return cls(
            cart, Lm, o, e, links=links,
            link_offsets=a if six else None, B0=B0m if six else None, extrapolate=extrapolate,
        )
