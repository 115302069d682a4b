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

The survey's checks, interpolation and line frames, the fit of the frames onto a
linear-actuator model and why the frames are parametrised as they are (not as the
thesis' ``o_i`` and ZYZ angles): :mod:`gtmodel.robots.guideway_survey` (its names are
re-exported here).

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

from functools import cached_property
from typing import Any

import casadi as ca
import numpy as np
import numpy.typing  # noqa: F401  (np.typing in annotations)

from gtmodel._arrays import as_rows
from gtmodel.errors import InputError
from gtmodel._geometry import rotation_to_zyz, rotation_vector_to_rotation, zyz_to_rotation
from gtmodel.robots.closure import ClosureModel, ThreeLinkClosure
from gtmodel.robots.guideway_survey import (
    COLLINEAR_TOLERANCE,
    SIX_LINK_LAYOUT,
    THREE_LINK_LAYOUT,
    _cart_arrays,
    _check_rotation,
    fit_survey_frames,
    line_frame,
    piecewise_linear,
)
from gtmodel.robots.parameters import KinematicParameters
from gtmodel.robots.wrapped import WrappedClosure

__all__ = [
    "PiecewiseActuatorClosure",
    "piecewise_linear",
    "line_frame",
    "THREE_LINK_LAYOUT",
    "SIX_LINK_LAYOUT",
    "CART_RANGE_TOLERANCE",
    "COLLINEAR_TOLERANCE",
    "fit_survey_frames",
]

#: How far [m] :meth:`PiecewiseActuatorClosure.fk` accepts ``q`` outside the surveyed
#: range of a guideway before refusing (unless built with ``extrapolate=True``).
CART_RANGE_TOLERANCE = 1e-9


class PiecewiseActuatorClosure(WrappedClosure):
    """Closure model with piecewise-linear actuators, Dressler (2012), eq. 5.7 and Table 5.8.

    ``A_ij = R_i (P_i(q_i) - Pbar_i + a_ij) + c_i`` with ``P_i`` the linear interpolation
    of the surveyed cart positions, ``Pbar_i`` their centroid and ``R_i`` the rotation from
    the survey frame to the TCP data frame (see :mod:`gtmodel.robots.guideway_survey` for why the
    frame is parametrised this way). Parameters per arm:

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
        False: it stays that of ``frame_rotation`` (see :mod:`gtmodel.robots.guideway_survey`).

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
        return cls(
            cart, **fit_survey_frames(model, cart), extrapolate=extrapolate,
            free_link_offsets=free_link_offsets, free_twist=free_twist,
        )
