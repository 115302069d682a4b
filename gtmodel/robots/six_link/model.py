"""The six-link model class: parameters, the closure graph (eq. 4.14), frame changes."""

from __future__ import annotations

from typing import Any

import casadi as ca
import numpy as np
import numpy.typing  # noqa: F401  (np.typing in annotations)

from gtmodel._arrays import as_array, as_rotation
from gtmodel.errors import InputError
from gtmodel.robots.closure import ClosureModel
from gtmodel.robots.parameters import Limits
from gtmodel.robots.six_link.graphs import SixLinkGraphs
from gtmodel.robots.six_link.layout import (
    _ARM_OF_LINK,
    _FIRST_LINK,
    _LINK_NAMES,
    _RY_MINUS_HALF_PI,
    ROTATION_TOLERANCE,
    SIX_LINKS,
    estimate_nominal_orientation,
)
from gtmodel.robots.six_link.solve import SixLinkSolvers

__all__ = ["SixLinkClosure"]


# ------------------------------------------------------------------ the model
class SixLinkClosure(SixLinkGraphs, SixLinkSolvers, ClosureModel):
    """Six-link kinematic error model of the Gantry-Tau, Dressler (2012), eqs. 4.14-4.15.

    Parameters
    ----------
    L : array_like, shape (6,)
        Link lengths [m], links ``1, 2a, 2b, 3a, 3b, 3c``.
    A0 : array_like, shape (6, 3)
        Cart-side joint points at ``q_i = 0``, base frame [m].
    v : array_like, shape (6, 3), or (3, 3) with ``v_per_arm``
        Guideway directions per link (or per arm); ``|v| != 1`` absorbs a gear ratio.
    B0 : array_like, shape (6, 3)
        Plate-side joint points in the plate frame, relative to the TCP [m].
    v_per_arm : bool, optional
        One direction per arm, shared by the links of the arm (51 instead of 60
        parameters).
    R0 : array_like, shape (3, 3), optional
        Nominal plate orientation (FK start and default IK orientation). Default: the
        estimate of :func:`estimate_nominal_orientation`, or the identity when the joint
        points do not determine one (all ``B0`` of each arm on a line).
    limits : Limits, optional
        Cart travel and spherical-joint limit, for :meth:`in_workspace`.
    name : str, optional
        Model name used in reports.
    source : str, optional
        Where the numbers come from.

    Raises
    ------
    InputError
        If a shape is wrong, a value is not finite, a length is not positive, a guideway
        direction is not of norm about 1 (0.5 to 2), or ``R0`` is not a rotation.

    Attributes
    ----------
    R0 : numpy.ndarray, shape (3, 3)
        Nominal plate orientation.
    R_ref : numpy.ndarray, shape (3, 3)
        Reference of the Euler angles of the FK, ``R0 Ry(-pi/2)``.
    """

    orientation = True
    n_q = 3
    links = SIX_LINKS

    def __init__(
        self,
        L: np.typing.ArrayLike,
        A0: np.typing.ArrayLike,
        v: np.typing.ArrayLike,
        B0: np.typing.ArrayLike,
        *,
        v_per_arm: bool = False,
        R0: np.typing.ArrayLike | None = None,
        limits: Limits | None = None,
        name: str = "six_link",
        source: str = "",
    ) -> None:
        if not isinstance(v_per_arm, bool):
            raise InputError(f"v_per_arm: expected True or False, got {v_per_arm!r}")
        self.v_per_arm = v_per_arm
        self.L = as_array(L, (6,), "L")
        if np.any(self.L <= 0):
            raise InputError(f"L: expected positive link lengths [m], got {self.L.tolist()}")
        self.A0 = as_array(A0, (6, 3), "A0")
        self.B0 = as_array(B0, (6, 3), "B0")
        v_arr = as_array(v, (3, 3) if v_per_arm else (6, 3), "v")
        norms = np.linalg.norm(v_arr, axis=1)
        if np.any(norms < 0.5) or np.any(norms > 2.0):
            raise InputError(f"v: expected guideway directions of norm about 1 (0.5 < |v| < 2), got norms {norms.tolist()}")
        self._v_free = v_arr
        self.v = v_arr[list(_ARM_OF_LINK)] if v_per_arm else v_arr
        if R0 is None:
            try:
                R0, _ = estimate_nominal_orientation(self.A0, self.B0)
            except InputError:
                R0 = np.eye(3)
        self.R0 = as_rotation(R0, "R0", ROTATION_TOLERANCE)
        self.R_ref = self.R0 @ _RY_MINUS_HALF_PI
        if limits is not None and not isinstance(limits, Limits):
            raise InputError(f"limits: expected a gtmodel.robots.parameters.Limits, got {type(limits).__name__}")
        self.limits = limits
        self.name = str(name)
        self.source = str(source)

    # -------------------------------------------------------------- parameters
    def parameter_names(self) -> tuple[str, ...]:
        """Names ``L_1..L_3c``, ``A0_1_x..A0_3c_z``, ``v_1_x..`` and ``B0_1_x..B0_3c_z``.

        The directions are named per link (``v_2a_y``) or, with ``v_per_arm``, per arm
        (``v_2_y``).

        Returns
        -------
        tuple of str
            60 names (51 with ``v_per_arm``).
        """
        names = [f"L_{l}" for l in _LINK_NAMES]
        names += [f"A0_{l}_{c}" for l in _LINK_NAMES for c in "xyz"]
        v_keys = [str(i + 1) for i in range(3)] if self.v_per_arm else list(_LINK_NAMES)
        names += [f"v_{l}_{c}" for l in v_keys for c in "xyz"]
        names += [f"B0_{l}_{c}" for l in _LINK_NAMES for c in "xyz"]
        return tuple(names)

    def parameter_vector(self) -> np.ndarray:
        """Current values in the order of :meth:`parameter_names`.

        Returns
        -------
        numpy.ndarray, shape (60,) or (51,)
            Lengths and points [m], directions (dimensionless).
        """
        return np.concatenate([self.L, self.A0.ravel(), self._v_free.ravel(), self.B0.ravel()])

    def _unpack(self, p: Any) -> tuple[list, list, list, list]:
        """Split a parameter vector (numeric or symbolic) into per-link L, A0, v, B0."""
        L = [p[j] for j in range(6)]
        A0 = [p[6 + 3 * j: 9 + 3 * j] for j in range(6)]
        o = 24
        n_v = 3 if self.v_per_arm else 6
        v_free = [p[o + 3 * k: o + 3 + 3 * k] for k in range(n_v)]
        v = [v_free[_ARM_OF_LINK[j]] for j in range(6)] if self.v_per_arm else v_free
        o += 3 * n_v
        B0 = [p[o + 3 * j: o + 3 + 3 * j] for j in range(6)]
        return L, A0, v, B0

    def link_points(self, p: ca.SX, q: ca.SX, T: ca.SX, R: ca.SX, arm: int) -> tuple[ca.SX, ca.SX, ca.SX]:
        """``A_ij = A0_ij + q_i v_ij``, ``B_ij = T + R_T B0_ij``, ``L_ij`` (eq. 4.14).

        Parameters
        ----------
        p : casadi.SX, shape (60,) or (51,)
            Parameters.
        q : casadi.SX, shape (3,)
            Cart positions [m].
        T : casadi.SX, shape (3,)
            TCP position [m].
        R : casadi.SX, shape (3, 3)
            Plate orientation ``R_T``.
        arm : int
            Arm index 0, 1, 2.

        Returns
        -------
        A : casadi.SX, shape (3, n_links)
            Cart-side joint points [m].
        B : casadi.SX, shape (3, n_links)
            Plate-side joint points [m].
        L : casadi.SX, shape (n_links,)
            Link lengths [m].

        Raises
        ------
        InputError
            If ``arm`` is not 0, 1 or 2.
        """
        if arm not in (0, 1, 2):
            raise InputError(f"arm must be one of 0..2, got {arm!r}")
        Lp, A0, v, B0 = self._unpack(p)
        js = [j for j in range(6) if _ARM_OF_LINK[j] == arm]
        A = ca.horzcat(*[A0[j] + q[arm] * v[j] for j in js])
        B = ca.horzcat(*[T + ca.mtimes(R, B0[j]) for j in js])
        return A, B, ca.vertcat(*[Lp[j] for j in js])

    def _copy_with(self, L: Any, A0: Any, v: Any, B0: Any, R0: np.ndarray) -> "SixLinkClosure":
        return SixLinkClosure(
            L, A0, v, B0, v_per_arm=self.v_per_arm, R0=R0, limits=self.limits, name=self.name, source=self.source
        )

    def with_parameters(self, p: np.typing.ArrayLike) -> "SixLinkClosure":
        """The model with other parameter values (same nominal orientation ``R0`` and limits).

        Parameters
        ----------
        p : array_like, shape (60,) or (51,)
            Values in the order of :meth:`parameter_names`.

        Returns
        -------
        SixLinkClosure

        Raises
        ------
        InputError
            If ``p`` has the wrong size or is not finite, or the values are invalid (see
            the class).
        """
        try:
            pa = np.asarray(p, dtype=float).ravel()
        except (TypeError, ValueError):
            raise InputError(f"{self.name}: p: expected {self.n_parameters} numbers, got {p!r}") from None
        if pa.size != self.n_parameters or not np.all(np.isfinite(pa)):
            raise InputError(f"{self.name}: p: expected {self.n_parameters} finite parameters, got {pa.size}")
        L, A0, v, B0 = self._unpack(pa)
        v_free = np.vstack([v[i] for i in _FIRST_LINK]) if self.v_per_arm else np.vstack(v)
        return self._copy_with(np.array(L), np.vstack(A0), v_free, np.vstack(B0), self.R0)

    def transformed(self, R: np.typing.ArrayLike, t: np.typing.ArrayLike) -> "SixLinkClosure":
        """The model in another frame, ``x' = R x + t`` (Dressler (2012), eqs. 5.3-5.4).

        ``A0`` is rotated and translated, ``v`` rotated; ``B0`` is unchanged (it lives in
        the plate frame) and ``L`` too. The plate orientation seen from the new frame is
        ``R R_T``, so the nominal orientation becomes ``R R0``.

        Parameters
        ----------
        R : array_like, shape (3, 3)
            Rotation of the frame change.
        t : array_like, shape (3,)
            Translation [m].

        Returns
        -------
        SixLinkClosure

        Raises
        ------
        InputError
            If ``R`` is not a rotation or ``t`` not a finite 3-vector.
        """
        Rm = as_rotation(R, "R", ROTATION_TOLERANCE)
        tv = as_array(np.asarray(t, dtype=float).ravel() if np.size(t) == 3 else t, (3,), "t")
        return self._copy_with(self.L, self.A0 @ Rm.T + tv, self._v_free @ Rm.T, self.B0, Rm @ self.R0)

