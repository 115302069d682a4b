"""The six-link kinematic error model of the Gantry-Tau, Dressler (2012), eqs. 4.14-4.15.

Every one of the six links (arm 1: link ``1``; arm 2: ``2a, 2b``; arm 3: ``3a, 3b, 3c``)
has its own length ``L_ij``, cart-side joint point ``A0_ij`` at ``q_i = 0``, guideway
direction ``v_ij`` (or one ``v_i`` per arm) and plate-side joint point ``B0_ij`` in the
plate frame (Dressler (2012), eq. 4.14)::

    L_ij^2 = || A_ij(q_i) - B_ij(T, R_T) ||^2,   A_ij = A0_ij + q_i v_ij,
                                                 B_ij = T + R_T B0_ij

With imperfect parallelograms the plate orientation ``R_T`` is no longer constant: the six
closure equations determine the six pose unknowns ``(T, R_T)``.

Inverse kinematics stays closed form per link (a quadratic in ``q_i``, one root sign per
arm: the IK configuration, as for the 3-link model). Forward kinematics is Newton's
method on the minimal pose ``X = (T, alpha, beta, gamma)`` (Dressler (2012), eq. 4.15)::

    X_{k+1} = X_k + (d f_ik / dX)^-1 (q - f_ik(X_k))

where ``f_ik(X)`` stacks the six per-link IK values ``q_ij`` and ``q`` repeats the cart
position of arm ``i`` for each of its links. The Jacobian comes from CasADi's automatic
differentiation of the same IK expression.

Orientation parametrisation
---------------------------
ZYZ Euler angles have a gimbal lock at ``beta = 0`` (and ``pi``). They are therefore taken
relative to a reference: ``R_T = R_ref Rz(alpha) Ry(beta) Rz(gamma)`` with
``R_ref = R0 Ry(-pi/2)``, where ``R0`` is the model's nominal plate orientation. At the
nominal orientation ``X = (T, 0, pi/2, 0)``, as far from the lock as possible, for any
``R0`` (identity included). For the D1 the absolute ZYZ angles of ``R0`` are
(85.1, 100.7, -88.5) deg, so the absolute angles would also be safe there; the reference
keeps the method safe for every parameter set. Results are reported as rotation matrices;
absolute ZYZ angles via :func:`gtmodel.robots.closure.rotation_to_zyz`.

Nominal orientation ``R0``
--------------------------
``B0_ij`` is given in the plate frame, ``A0_ij`` and ``v_ij`` in the base (tracker)
frame. In a parallelogram cluster ``A0_ij - A0_ik = R_T (B0_ij - B0_ik)``, so the plate
orientation of the nominal assembly is the rotation that best maps the within-arm
differences of ``B0`` onto those of ``A0`` (:func:`estimate_nominal_orientation`,
orthogonal Procrustes / Kabsch). The model carries it as ``R0``: it is the start of the
FK iteration (with the start position from the closed-form 3-link trilateration of the
links ``1, 2a, 3a`` with ``As_i = A0_i1 - R0 B0_i1``) and the default orientation of the
IK. Moving the model into another frame (:meth:`SixLinkClosure.transformed`,
``x' = R x + t``) rotates and translates ``A0``, rotates ``v``, leaves ``B0`` unchanged
(plate frame) and turns the nominal orientation into ``R R0``.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass
from functools import cached_property
from importlib import resources
from pathlib import Path
from typing import Any, Mapping, Sequence

import casadi as ca
import numpy as np
import numpy.typing  # noqa: F401  (np.typing in annotations)
from scipy.spatial.transform import Rotation

from gtmodel._toml import read_toml
from gtmodel.errors import ConvergenceError, InputError, ParameterError, UnreachablePoseError
from gtmodel.robots.closure import ClosureModel, zyz_to_rotation
from gtmodel.robots.kinematics import configuration_signs, fk_expression
from gtmodel.robots.parameters import Limits, _limits, _Reader

__all__ = [
    "SixLinkClosure",
    "SixLinkFKResult",
    "estimate_nominal_orientation",
    "load_six_link",
    "SIX_LINKS",
    "FK_TOLERANCE",
    "FK_MAX_ITER",
    "FK_UNROLLED_ITER",
    "ROTATION_TOLERANCE",
]

_log = logging.getLogger("gtmodel")

#: Link names per arm of the 3-2-1 Gantry-Tau.
SIX_LINKS: tuple[tuple[str, ...], ...] = (("1",), ("2a", "2b"), ("3a", "3b", "3c"))
_LINK_NAMES: tuple[str, ...] = tuple(name for arm in SIX_LINKS for name in arm)
_ARM_OF_LINK: tuple[int, ...] = tuple(i for i, arm in enumerate(SIX_LINKS) for _ in arm)
#: Index of the first link of each arm in the six-link order (links 1, 2a, 3a).
_FIRST_LINK: tuple[int, ...] = (0, 1, 3)

#: Newton tolerance of the FK (eq. 4.15): max over the six links of |q_i - f_ik,ij(X)| [m].
FK_TOLERANCE = 1e-12
#: Newton iteration limit of the numeric FK (:meth:`SixLinkClosure.fk_solve`).
FK_MAX_ITER = 20
#: Newton iterations unrolled in :meth:`SixLinkClosure.fk_function` (the D1 needs 2 in its
#: workspace and at most 3 on a wider grid from the trilateration start: margin of 2).
FK_UNROLLED_ITER = 5
#: Largest accepted ``max |R^T R - I|`` of an orientation given to the IK.
ROTATION_TOLERANCE = 1e-6
#: Largest disagreement [m] of the links of one arm on the cart position for a pose to
#: count as an assembly (:meth:`SixLinkClosure.in_workspace`).
_ASSEMBLY_TOLERANCE = 1e-9
#: Smallest singular value [m] of the within-arm joint-point differences that still
#: determines the nominal orientation (:func:`estimate_nominal_orientation`).
_ORIENTATION_RANK_TOLERANCE = 1e-6

_RY_MINUS_HALF_PI = np.array([[0.0, 0.0, -1.0], [0.0, 1.0, 0.0], [1.0, 0.0, 0.0]])  # Ry(-pi/2)
_EULER_AT_REFERENCE = np.array([0.0, math.pi / 2, 0.0])


# ------------------------------------------------------------------ helpers
def _rotation(R: Any, name: str) -> np.ndarray:
    try:
        Rm = np.asarray(R, dtype=float)
    except (TypeError, ValueError):
        raise InputError(f"{name}: expected a 3x3 rotation matrix, got {R!r}") from None
    if Rm.shape != (3, 3) or not np.all(np.isfinite(Rm)):
        raise InputError(f"{name}: expected a finite 3x3 rotation matrix, got shape {Rm.shape}")
    err = np.abs(Rm.T @ Rm - np.eye(3)).max()
    if err > ROTATION_TOLERANCE or np.linalg.det(Rm) < 0:
        raise InputError(
            f"{name}: expected a rotation matrix (R^T R = I within {ROTATION_TOLERANCE}, det = +1), "
            f"got max |R^T R - I| = {err:.3g}, det = {np.linalg.det(Rm):.6g}"
        )
    return Rm


def _array(x: Any, shape: tuple[int, ...], name: str) -> np.ndarray:
    try:
        arr = np.array(x, dtype=float)
    except (TypeError, ValueError):
        raise InputError(f"{name}: expected an array of numbers of shape {shape}, got {x!r}") from None
    if arr.shape != shape:
        raise InputError(f"{name}: expected shape {shape}, got {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise InputError(f"{name}: expected finite numbers, got {arr.tolist()}")
    return arr


def _rows(x: Any, name: str, n_cols: int = 3) -> tuple[np.ndarray, bool]:
    """(N, n_cols) float array and whether the input was a single row."""
    try:
        arr = np.asarray(x, dtype=float)
    except (TypeError, ValueError):
        raise InputError(f"{name}: expected an array of shape ({n_cols},) or (N, {n_cols}), got {x!r}") from None
    single = arr.ndim == 1
    if single:
        arr = arr[None, :]
    if arr.ndim != 2 or arr.shape[1] != n_cols or arr.shape[0] == 0:
        raise InputError(f"{name}: expected shape ({n_cols},) or (N, {n_cols}), got {np.shape(x)}")
    bad = ~np.all(np.isfinite(arr), axis=1)
    if np.any(bad):
        k = int(np.argmax(bad))
        raise InputError(f"{name}: row {k} is not finite: {arr[k].tolist()}")
    return arr, single


def _vec(R: np.ndarray) -> np.ndarray:
    """Column-major vec of a 3x3 matrix (CasADi's ``reshape`` order)."""
    return np.asarray(R, dtype=float).reshape(3, 3).ravel(order="F")


def _ik_link_expressions(L: Any, A0: Sequence[Any], v: Sequence[Any], B0: Sequence[Any], T: Any, R: Any, s: Any) -> tuple[Any, Any]:
    """Per-link IK of eq. 4.14: the quadratic ``|v|^2 q^2 - 2 (d.v) q + |d|^2 - L^2 = 0``.

    ``d = T + R B0_ij - A0_ij``; ``q = (d.v + s_i sqrt(disc)) / |v|^2``. Returns the six
    values, the six discriminants (negative: the link cannot reach) and the cosines of the
    angles between each link ``B_ij - A_ij`` and its guideway (spherical-joint limit).
    """
    q, disc, cos = [], [], []
    for j in range(6):
        i = _ARM_OF_LINK[j]
        d = T + ca.mtimes(R, B0[j]) - A0[j]
        dv = ca.dot(d, v[j])
        vv = ca.dot(v[j], v[j])
        dj = dv**2 - vv * (ca.dot(d, d) - L[j] ** 2)
        qj = (dv + s[i] * ca.sqrt(ca.fmax(dj, 0))) / vv
        link = d - qj * v[j]  # B_ij - A_ij
        q.append(qj)
        disc.append(dj)
        cos.append(ca.dot(link, v[j]) / (ca.norm_2(link) * ca.sqrt(vv)))
    return ca.vertcat(*q), ca.vertcat(*disc), ca.vertcat(*cos)


def estimate_nominal_orientation(A0: np.typing.ArrayLike, B0: np.typing.ArrayLike) -> tuple[np.ndarray, float]:
    """Nominal plate orientation from the joint points of the link clusters.

    In a parallelogram cluster ``A0_ij - A0_ik = R_T0 (B0_ij - B0_ik)`` (Dressler (2012),
    eq. 4.14 with equal link vectors). ``R_T0`` is the orthogonal-Procrustes (Kabsch)
    solution over all within-arm pairs (arm 2: one pair, arm 3: three pairs), computed
    with :meth:`scipy.spatial.transform.Rotation.align_vectors`.

    Parameters
    ----------
    A0 : array_like, shape (6, 3)
        Cart-side joint points at ``q = 0`` in the base frame [m], links in the order
        ``1, 2a, 2b, 3a, 3b, 3c``.
    B0 : array_like, shape (6, 3)
        Plate-side joint points in the plate frame [m], same order.

    Returns
    -------
    R_T0 : numpy.ndarray, shape (3, 3)
        Rotation from the plate frame to the base frame.
    rms : float
        Root-mean-square residual ``|dA - R_T0 dB|`` over the pairs [m].

    Raises
    ------
    InputError
        If the shapes are wrong or the differences of ``B0`` (or ``A0``) do not span a
        plane (fewer than two independent directions: no unique rotation).
    """
    A = _array(A0, (6, 3), "A0")
    B = _array(B0, (6, 3), "B0")
    pairs = [(j, k) for arm in SIX_LINKS for a, j in enumerate(arm) for k in arm[a + 1:]]
    idx = {name: n for n, name in enumerate(_LINK_NAMES)}
    dA = np.array([A[idx[k]] - A[idx[j]] for j, k in pairs])
    dB = np.array([B[idx[k]] - B[idx[j]] for j, k in pairs])
    for name, D in (("B0", dB), ("A0", dA)):
        sv = np.linalg.svd(D, compute_uv=False)
        if sv[1] < _ORIENTATION_RANK_TOLERANCE:
            raise InputError(
                f"{name}: the within-arm differences of the joint points span no plane "
                f"(singular values {np.round(sv, 9).tolist()} m): the nominal orientation is not determined"
            )
    rot, _ = Rotation.align_vectors(dA, dB)
    R = rot.as_matrix()
    rms = float(np.sqrt(np.mean(np.sum((dA - dB @ R.T) ** 2, axis=1))))
    return R, rms


@dataclass(frozen=True)
class SixLinkFKResult:
    """Result of the six-link forward kinematics (Dressler (2012), eq. 4.15).

    Parameters
    ----------
    T : numpy.ndarray, shape (N, 3)
        TCP positions [m].
    R : numpy.ndarray, shape (N, 3, 3)
        Plate orientations ``R_T``.
    euler : numpy.ndarray, shape (N, 3)
        The Newton unknowns ``(alpha, beta, gamma)`` [rad], ZYZ angles relative to
        ``R_ref = R0 Ry(-pi/2)`` (``(0, pi/2, 0)`` at the nominal orientation).
    iterations : numpy.ndarray of int, shape (N,)
        Newton iterations used per pose.
    residual : numpy.ndarray, shape (N,)
        Final ``max |q_i - f_ik,ij(X)|`` over the six links [m].
    """

    T: np.ndarray
    R: np.ndarray
    euler: np.ndarray
    iterations: np.ndarray
    residual: np.ndarray


# ------------------------------------------------------------------ the model
class SixLinkClosure(ClosureModel):
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
        self.L = _array(L, (6,), "L")
        if np.any(self.L <= 0):
            raise InputError(f"L: expected positive link lengths [m], got {self.L.tolist()}")
        self.A0 = _array(A0, (6, 3), "A0")
        self.B0 = _array(B0, (6, 3), "B0")
        v_arr = _array(v, (3, 3) if v_per_arm else (6, 3), "v")
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
        self.R0 = _rotation(R0, "R0")
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
        Rm = _rotation(R, "R")
        tv = _array(np.asarray(t, dtype=float).ravel() if np.size(t) == 3 else t, (3,), "t")
        return self._copy_with(self.L, self.A0 @ Rm.T + tv, self._v_free @ Rm.T, self.B0, Rm @ self.R0)

    # -------------------------------------------------------------- symbolic building blocks
    @cached_property
    def _p_num(self) -> ca.DM:
        return ca.DM(self.parameter_vector())

    @cached_property
    def _ik_graph(self) -> ca.Function:
        """``ik_links(T, R, s, p) -> (q[6], disc[6], cos[6])`` (eq. 4.14), parameters symbolic."""
        T = ca.SX.sym("T", 3)
        R = ca.SX.sym("R", 3, 3)
        s = ca.SX.sym("s", 3)
        p = ca.SX.sym("p", self.n_parameters)
        L, A0, v, B0 = self._unpack(p)
        q, disc, cos = _ik_link_expressions(L, A0, v, B0, T, R, s)
        return ca.Function("ik_links", [T, R, s, p], [q, disc, cos], ["T", "R", "s", "p"], ["q", "disc", "cos"])

    @cached_property
    def _step_graph(self) -> ca.Function:
        """One Newton step of eq. 4.15: ``step(X, q, s, p, R_ref) -> (X_next, residual, disc_min)``.

        ``residual = max |q_ext - f_ik(X)|`` and ``disc_min`` are those at ``X`` (before the step).
        """
        X = ca.SX.sym("X", 6)
        q = ca.SX.sym("q", 3)
        s = ca.SX.sym("s", 3)
        p = ca.SX.sym("p", self.n_parameters)
        Rref = ca.SX.sym("R_ref", 9)
        R = self._orientation_graph(X, Rref)
        f, disc, _cos = self._ik_graph(X[:3], R, s, p)
        q_ext = ca.vertcat(*[q[i] for i in _ARM_OF_LINK])
        e = q_ext - f
        J = ca.jacobian(f, X)
        X_next = X + ca.solve(J, e)
        return ca.Function(
            "fk_step", [X, q, s, p, Rref], [X_next, ca.mmax(ca.fabs(e)), ca.mmin(disc)],
            ["X", "q", "s", "p", "R_ref"], ["X_next", "residual", "disc_min"],
        )

    @cached_property
    def _start_graph(self) -> ca.Function:
        """Start pose of the FK: 3-link trilateration of links 1, 2a, 3a at ``R0`` (eq. 4.9).

        ``start(q, solution, p, R0) -> (X0, h2)``; ``h2 < 0``: the three spheres do not meet.
        """
        q = ca.SX.sym("q", 3)
        sol = ca.SX.sym("solution")
        p = ca.SX.sym("p", self.n_parameters)
        R0 = ca.SX.sym("R0", 9)
        L, A0, v, B0 = self._unpack(p)
        R0m = ca.reshape(R0, 3, 3)
        As = ca.horzcat(*[A0[j] - ca.mtimes(R0m, B0[j]) for j in _FIRST_LINK]).T
        vs = ca.horzcat(*[v[j] for j in _FIRST_LINK]).T
        Ls = ca.vertcat(*[L[j] for j in _FIRST_LINK])
        T0, h2, _ = fk_expression(q, sol, Ls, As, vs)
        X0 = ca.vertcat(T0, ca.DM(_EULER_AT_REFERENCE))
        return ca.Function("fk_start", [q, sol, p, R0], [X0, h2], ["q", "solution", "p", "R0"], ["X0", "h2"])

    @cached_property
    def _orientation_graph(self) -> ca.Function:
        """``orientation(X, R_ref) -> R_T = R_ref Rzyz(alpha, beta, gamma)``."""
        X = ca.SX.sym("X", 6)
        Rref = ca.SX.sym("R_ref", 9)
        R = ca.mtimes(ca.reshape(Rref, 3, 3), zyz_to_rotation(X[3], X[4], X[5]))
        return ca.Function("orientation", [X, Rref], [R], ["X", "R_ref"], ["R"])

    # -------------------------------------------------------------- CasADi Functions
    def ik_links_function(self, configuration: int | Sequence[int] = 0) -> ca.Function:
        """CasADi Function ``ik_links(T[3], R[3x3]) -> (q[6], disc[6])``, eq. 4.14.

        Parameters are embedded as constants (ready for C generation).

        Parameters
        ----------
        configuration : int or sequence of int, optional
            IK configuration 0-7 or three root signs (one per arm, shared by its links),
            see :func:`gtmodel.robots.kinematics.configuration_signs`.

        Returns
        -------
        casadi.Function
            ``q`` the per-link cart positions [m] (links ``1, 2a, 2b, 3a, 3b, 3c``);
            ``disc`` the discriminants [m^2], negative where a link cannot reach.

        Raises
        ------
        InputError
            For an invalid configuration.
        """
        s = configuration_signs(configuration)
        T = ca.SX.sym("T", 3)
        R = ca.SX.sym("R", 3, 3)
        q, disc, _cos = self._ik_graph(T, R, ca.DM(s), self._p_num)
        return ca.Function("ik_links", [T, R], [q, disc], ["T", "R"], ["q", "disc"])

    def fk_function(
        self,
        n_iter: int = FK_UNROLLED_ITER,
        configuration: int | Sequence[int] = 0,
        solution: int = 1,
        parametric: bool = False,
    ) -> ca.Function:
        """FK as a CasADi Function with ``n_iter`` Newton iterations of eq. 4.15 unrolled.

        Start: 3-link trilateration of links ``1, 2a, 3a`` at the nominal orientation
        ``R0``; then ``X_{k+1} = X_k + (d f_ik/dX)^-1 (q - f_ik(X_k))``. Fixed work per
        call, no branches: suited to C generation for the 4 ms loop; check ``status``.
        Map it over N poses with ``Function.map(N)``.

        Parameters
        ----------
        n_iter : int, optional
            Number of Newton iterations (>= 1).
        configuration : int or sequence of int, optional
            IK configuration of ``f_ik`` (see :meth:`ik_links_function`).
        solution : {1, -1}, optional
            FK branch of the trilateration start (see
            :func:`gtmodel.robots.kinematics.fk_expression`).
        parametric : bool, optional
            If True the parameter vector is a second input ``p``; otherwise the current
            values are embedded as constants.

        Returns
        -------
        casadi.Function
            Inputs ``q`` (3) [m] (and ``p``); outputs ``T`` (3) [m], ``R`` (3x3),
            ``X`` (6: ``T`` and the Euler angles relative to ``R_ref``) [m, rad],
            ``residual`` = ``max |q_i - f_ik,ij(X)|`` at the result [m], and ``status``
            = 1 if ``residual <= FK_TOLERANCE`` and every link reaches, else 0.

        Raises
        ------
        InputError
            If ``n_iter`` is not a positive integer, or ``configuration`` / ``solution``
            is invalid.
        """
        if isinstance(n_iter, bool) or not isinstance(n_iter, (int, np.integer)) or n_iter < 1:
            raise InputError(f"n_iter: expected a positive integer, got {n_iter!r}")
        if solution not in (1, -1) or isinstance(solution, bool):
            raise InputError(f"solution: expected +1 or -1, got {solution!r}")
        s = ca.DM(configuration_signs(configuration))
        q = ca.MX.sym("q", 3)
        p = ca.MX.sym("p", self.n_parameters) if parametric else ca.MX(self._p_num)
        # R0 and R_ref: the model's own for the embedded case; for the parametric case the
        # reference orientation stays the model's (it is a start value, not a parameter).
        R0v = ca.MX(ca.DM(_vec(self.R0)))
        Rrefv = ca.MX(ca.DM(_vec(self.R_ref)))
        X, _h2 = self._start_graph(q, float(solution), p, R0v)
        for _ in range(int(n_iter)):
            X, _r, _d = self._step_graph(X, q, s, p, Rrefv)
        _, residual, disc_min = self._step_graph(X, q, s, p, Rrefv)
        status = ca.if_else(ca.logic_and(residual <= FK_TOLERANCE, disc_min >= 0), 1.0, 0.0)
        R = self._orientation_graph(X, Rrefv)
        ins, names = ([q, p], ["q", "p"]) if parametric else ([q], ["q"])
        return ca.Function(
            "fk_six_link", ins, [X[:3], R, X, residual, status], names, ["T", "R", "X", "residual", "status"]
        )

    # -------------------------------------------------------------- numeric API
    def _orientations(self, R: Any, N: int) -> np.ndarray:
        if R is None:
            return np.broadcast_to(self.R0, (N, 3, 3))
        try:
            Ra = np.asarray(R, dtype=float)
        except (TypeError, ValueError):
            raise InputError(f"R: expected rotation matrices of shape (3, 3) or (N, 3, 3), got {R!r}") from None
        if Ra.shape == (3, 3):
            Ra = np.broadcast_to(Ra, (N, 3, 3))
        if Ra.shape != (N, 3, 3):
            raise InputError(f"R: expected shape (3, 3) or ({N}, 3, 3) to match T, got {Ra.shape}")
        if not np.all(np.isfinite(Ra)):
            raise InputError("R: expected finite rotation matrices")
        err = np.abs(np.einsum("nji,njk->nik", Ra, Ra) - np.eye(3)).max(axis=(1, 2))
        bad = (err > ROTATION_TOLERANCE) | (np.linalg.det(Ra) < 0)
        if np.any(bad):
            k = int(np.argmax(bad))
            raise InputError(f"R: row {k} is not a rotation matrix (max |R^T R - I| = {err[k]:.3g})")
        return Ra

    def ik_links(
        self, T: np.typing.ArrayLike, R: np.typing.ArrayLike | None = None, configuration: int | Sequence[int] = 0
    ) -> np.ndarray:
        """Cart position demanded by each of the six links (closed-form IK, eq. 4.14).

        On a pose the robot can assemble (e.g. an FK result) the links of one arm agree;
        for an arbitrary ``(T, R)`` they need not (the plate would be strained).

        Parameters
        ----------
        T : array_like, shape (3,) or (N, 3)
            TCP positions [m].
        R : array_like, shape (3, 3) or (N, 3, 3), optional
            Plate orientations ``R_T``; default the nominal orientation ``R0``.
        configuration : int or sequence of int, optional
            IK configuration 0-7 or three root signs, one per arm (default 0: the TCP
            ahead of every cart along its guideway).

        Returns
        -------
        numpy.ndarray, shape (6,) or (N, 6)
            ``q_ij`` [m] for links ``1, 2a, 2b, 3a, 3b, 3c``.

        Raises
        ------
        UnreachablePoseError
            If a link cannot reach its plate joint (names the row and the link).
        InputError
            Wrong shapes, non-finite values, ``R`` not a rotation, or an invalid
            configuration.
        """
        Tn, single = _rows(T, "T")
        N = Tn.shape[0]
        Ra = self._orientations(R, N)
        s = configuration_signs(configuration)
        f = self._ik_graph.map(N) if N > 1 else self._ik_graph
        Rcols = np.ascontiguousarray(Ra.transpose(1, 0, 2).reshape(3, 3 * N))  # horizontally stacked blocks
        q, disc, _cos = f(Tn.T, Rcols, s, self._p_num)
        q, disc = np.array(q).T, np.array(disc).T  # (N, 6)
        bad = disc < 0
        if np.any(bad):
            k, j = (int(x) for x in np.argwhere(bad)[0])
            where = "" if single else f" (row {k})"
            links = ", ".join(_LINK_NAMES[jj] for jj in np.flatnonzero(bad[k]))
            raise UnreachablePoseError(
                f"{self.name}: pose T={Tn[k].tolist()}{where} is unreachable: link(s) {links} "
                f"cannot reach their plate joint (discriminant {disc[k, j]:.3g} m^2 < 0)"
            )
        return q[0] if single else q

    def ik(
        self, T: np.typing.ArrayLike, R: np.typing.ArrayLike | None = None, configuration: int | Sequence[int] = 0
    ) -> np.ndarray:
        """Cart positions for poses: the IK of the first link of each arm (``1, 2a, 3a``), eq. 4.14.

        Parameters
        ----------
        T : array_like, shape (3,) or (N, 3)
            TCP positions [m].
        R : array_like, shape (3, 3) or (N, 3, 3), optional
            Plate orientations ``R_T``; default the nominal orientation ``R0``.
        configuration : int or sequence of int, optional
            IK configuration (see :meth:`ik_links`).

        Returns
        -------
        numpy.ndarray, shape (3,) or (N, 3)
            Cart positions ``q`` [m].

        Raises
        ------
        UnreachablePoseError
            If a link cannot reach (names the row and the link).
        InputError
            Wrong shapes, non-finite values, ``R`` not a rotation, or an invalid
            configuration.
        """
        q = self.ik_links(T, R, configuration)
        return q[..., list(_FIRST_LINK)]

    def fk_solve(
        self,
        q: np.typing.ArrayLike,
        configuration: int | Sequence[int] = 0,
        solution: int = 1,
        max_iter: int = FK_MAX_ITER,
    ) -> SixLinkFKResult:
        """Forward kinematics by Newton-Raphson on ``X = (T, alpha, beta, gamma)``, eq. 4.15.

        ``X_{k+1} = X_k + (d f_ik/dX)^-1 (q - f_ik(X_k))`` with the Jacobian from automatic
        differentiation, started from the 3-link trilateration of links ``1, 2a, 3a`` at
        the nominal orientation ``R0``; a pose has converged when
        ``max |q_i - f_ik,ij(X)| <= FK_TOLERANCE``. All poses are iterated together
        (``Function.map``); converged poses are frozen.

        Parameters
        ----------
        q : array_like, shape (3,) or (N, 3)
            Cart positions [m].
        configuration : int or sequence of int, optional
            IK configuration of ``f_ik`` (see :meth:`ik_links`).
        solution : {1, -1}, optional
            FK branch of the start (see :func:`gtmodel.robots.kinematics.fk_expression`).
        max_iter : int, optional
            Newton iteration limit (default :data:`FK_MAX_ITER`).

        Returns
        -------
        SixLinkFKResult
            Arrays with a leading pose axis N (N = 1 for a single ``q``).

        Raises
        ------
        ConvergenceError
            If a pose does not reach :data:`FK_TOLERANCE` within ``max_iter`` iterations
            or the iterate leaves the domain of the IK (a link cannot reach); names the
            row.
        InputError
            Wrong shape, non-finite values, or an invalid ``configuration``,
            ``solution`` or ``max_iter``.
        """
        qn, _single = _rows(q, "q")
        if isinstance(max_iter, bool) or not isinstance(max_iter, (int, np.integer)) or max_iter < 0:
            raise InputError(f"max_iter: expected a non-negative integer, got {max_iter!r}")
        if solution not in (1, -1) or isinstance(solution, bool):
            raise InputError(f"solution: expected +1 or -1, got {solution!r}")
        s = configuration_signs(configuration)
        N = qn.shape[0]
        start = self._start_graph.map(N) if N > 1 else self._start_graph
        step = self._step_graph.map(N) if N > 1 else self._step_graph
        p = self._p_num
        X0, h2 = start(qn.T, float(solution), p, _vec(self.R0))
        X = np.array(X0)
        h2 = np.array(h2).ravel()
        Rref = _vec(self.R_ref)
        iterations = np.zeros(N, dtype=int)
        done = np.zeros(N, dtype=bool)
        lost = ~np.all(np.isfinite(X), axis=0)  # left the domain of the IK: stop iterating
        residual = np.full(N, np.inf)
        for k in range(int(max_iter) + 1):
            X_next, res, dmin = step(X, qn.T, s, p, Rref)
            res = np.array(res).ravel()
            dmin = np.array(dmin).ravel()
            active = ~done & ~lost
            ok = active & (res <= FK_TOLERANCE) & (dmin >= 0)
            iterations[ok] = k
            residual[active] = res[active]
            done |= ok
            active &= ~ok
            if not active.any() or k == max_iter:
                break
            X_next = np.array(X_next)
            X[:, active] = X_next[:, active]
            lost |= ~np.all(np.isfinite(X), axis=0)
        if not done.all():
            k = int(np.flatnonzero(~done)[0])
            if h2[k] < 0:
                why = "the start spheres of links 1, 2a, 3a do not intersect (no assembly near the nominal orientation)"
            elif lost[k]:
                why = "the iterate left the domain of the per-link IK (a link could not reach)"
            else:
                why = f"max |q - f_ik(X)| = {residual[k]:.3g} m > {FK_TOLERANCE:g} m"
            raise ConvergenceError(
                f"{self.name}: forward kinematics (Dressler (2012), eq. 4.15) did not converge for pose row {k} "
                f"(q = {qn[k].tolist()}) within {max_iter} Newton iterations: {why}; "
                f"{int((~done).sum())} of {N} pose(s) failed"
            )
        orient = self._orientation_graph.map(N) if N > 1 else self._orientation_graph
        R = np.array(orient(X, Rref)).reshape(3, N, 3).transpose(1, 0, 2)
        _log.debug("%s: six-link FK of %d pose(s), max %d Newton iterations", self.name, N, int(iterations.max()))
        return SixLinkFKResult(T=X[:3].T.copy(), R=R, euler=X[3:].T.copy(), iterations=iterations, residual=residual)

    def fk(
        self,
        q: np.typing.ArrayLike,
        configuration: int | Sequence[int] = 0,
        solution: int = 1,
        max_iter: int = FK_MAX_ITER,
    ) -> tuple[np.ndarray, np.ndarray]:
        """TCP position and plate orientation for cart positions (Newton FK, eq. 4.15).

        See :meth:`fk_solve` for the method; absolute ZYZ angles of ``R`` via
        :func:`gtmodel.robots.closure.rotation_to_zyz`.

        Parameters
        ----------
        q : array_like, shape (3,) or (N, 3)
            Cart positions [m].
        configuration : int or sequence of int, optional
            IK configuration of ``f_ik``.
        solution : {1, -1}, optional
            FK branch of the start.
        max_iter : int, optional
            Newton iteration limit.

        Returns
        -------
        T : numpy.ndarray, shape (3,) or (N, 3)
            TCP positions [m].
        R : numpy.ndarray, shape (3, 3) or (N, 3, 3)
            Plate orientations ``R_T``.

        Raises
        ------
        ConvergenceError
            If Newton's method does not converge (names the row).
        InputError
            Wrong shape, non-finite values or invalid options.
        """
        single = np.ndim(q) == 1
        res = self.fk_solve(q, configuration, solution, max_iter)
        return (res.T[0], res.R[0]) if single else (res.T, res.R)

    def in_workspace(
        self, T: np.typing.ArrayLike, R: np.typing.ArrayLike | None = None, configuration: int | Sequence[int] = 0
    ) -> np.ndarray:
        """Whether poses are reachable within the cart travel and the spherical-joint limit.

        Every link must reach (eq. 4.14), the links of each arm must agree on the cart
        position within ``1e-9`` m (the pose is an assembly, e.g. an FK result), every ``q_i`` must lie in the
        cart travel and every link make at most ``joint_angle_max`` with its guideway.

        Parameters
        ----------
        T : array_like, shape (3,) or (N, 3)
            TCP positions [m].
        R : array_like, shape (3, 3) or (N, 3, 3), optional
            Plate orientations; default ``R0``.
        configuration : int or sequence of int, optional
            IK configuration (see :meth:`ik_links`).

        Returns
        -------
        bool or numpy.ndarray of bool, shape (N,)
            True where the pose is in the workspace.

        Raises
        ------
        InputError
            Wrong shapes, or the model has no limits.
        """
        if self.limits is None:
            raise InputError(f"{self.name}: in_workspace needs limits (load the model with load_six_link or pass limits=)")
        Tn, single = _rows(T, "T")
        N = Tn.shape[0]
        Ra = self._orientations(R, N)
        s = configuration_signs(configuration)
        f = self._ik_graph.map(N) if N > 1 else self._ik_graph
        q, disc, cos = f(Tn.T, np.ascontiguousarray(Ra.transpose(1, 0, 2).reshape(3, 3 * N)), s, self._p_num)
        q, disc, cos = np.array(q).T, np.array(disc).T, np.array(cos).T
        ok = np.all(disc >= 0, axis=1)
        qa = q[:, list(_FIRST_LINK)]
        ok &= np.all(np.abs(q - qa[:, list(_ARM_OF_LINK)]) <= _ASSEMBLY_TOLERANCE, axis=1)
        lim = self.limits.cart_travel
        ok &= np.all((qa >= lim[:, 0]) & (qa <= lim[:, 1]), axis=1)
        ok &= np.all(np.abs(cos) >= np.cos(self.limits.joint_angle_max), axis=1)
        return bool(ok[0]) if single else ok


# ------------------------------------------------------------------ parameter files
_DATA_PACKAGE = "gtmodel.robots"
_VECTOR_TABLES = ("A0", "v", "B0")


def _link_table(r: _Reader, key: str, keys: Sequence[str], shape: tuple[int, ...]) -> np.ndarray:
    sub = r.sub(key)
    sub.check_keys(set(keys))
    missing = [k for k in keys if k not in sub.data]
    if missing:
        raise ParameterError(f"{r.origin}: missing field '{sub.prefix}{missing[0]}'")
    if shape == ():
        return np.array([sub.number(k, positive=True) for k in keys])
    return np.vstack([sub.array(k, shape) for k in keys])


def _six_link_from_mapping(data: Mapping[str, Any], origin: str) -> SixLinkClosure:
    r = _Reader(data, origin)
    if "model" not in data and "kinematics" in data:
        raise ParameterError(
            f"{origin}: a 3-link parameter set (table [kinematics]), not a six-link one: load it with "
            "gtmodel.robots.parameters.load_parameters, or give model = \"six_link\" and a [six_link] table"
        )
    r.check_keys({"name", "description", "frame", "model", "six_link", "limits"})
    model = r.string("model")
    if model != "six_link":
        raise r.error("model", "'six_link' (a six-link parameter file)", model)
    name = r.string("name")
    r.string("description", default="")
    r.string("frame", default="")
    k = r.sub("six_link")
    k.check_keys({"source", "assumptions", "derived", "v_per_arm", "L", "A0", "v", "B0", "nominal_orientation_zyz_deg"})
    v_per_arm = k.boolean("v_per_arm", False)
    L = _link_table(k, "L", _LINK_NAMES, ())
    A0 = _link_table(k, "A0", _LINK_NAMES, (3,))
    v_keys = ("1", "2", "3") if v_per_arm else _LINK_NAMES
    v = _link_table(k, "v", v_keys, (3,))
    norms = np.linalg.norm(v, axis=1)
    if np.any(norms < 0.5) or np.any(norms > 2.0):
        raise k.error("v", "guideway directions of norm about 1 (0.5 < |v| < 2)", v.tolist())
    B0 = _link_table(k, "B0", _LINK_NAMES, (3,))
    R0 = None
    if "nominal_orientation_zyz_deg" in k.data:
        zyz = np.radians(k.array("nominal_orientation_zyz_deg", (3,)))
        R0 = zyz_to_rotation(*zyz)
    else:
        try:
            R0, _ = estimate_nominal_orientation(A0, B0)
        except InputError as exc:
            raise ParameterError(
                f"{origin}: field 'six_link.B0': {exc}; give 'six_link.nominal_orientation_zyz_deg'"
            ) from None
    limits = _limits(r.sub("limits"))
    source = k.string("source", default="")
    if "derived" in k.data:
        derived = k.data["derived"]
        if not isinstance(derived, list) or not all(isinstance(x, str) for x in derived):
            raise k.error("derived", "a list of parameter names", derived)
    if "assumptions" in k.data:
        k.string("assumptions")
    return SixLinkClosure(L, A0, v, B0, v_per_arm=v_per_arm, R0=R0, limits=limits, name=name, source=source)


def load_six_link(name_or_path: str | Path = "D1_six_link") -> SixLinkClosure:
    """Load and validate a six-link parameter set by name (``"D1_six_link"``) or path.

    The file format (TOML, SI units): top-level ``name``, ``description``, ``frame``,
    ``model = "six_link"``; table ``[six_link]`` with ``L``, ``A0``, ``v``, ``B0`` as
    tables keyed by link name (``v`` keyed ``"1", "2", "3"`` with ``v_per_arm = true``),
    optional ``nominal_orientation_zyz_deg`` (default: estimated, see
    :func:`estimate_nominal_orientation`), ``source``, ``assumptions``, ``derived``; table
    ``[limits]`` as in the 3-link parameter files (``cart_travel``,
    ``joint_angle_max_deg``).

    Parameters
    ----------
    name_or_path : str or pathlib.Path, optional
        A shipped set's name (a file ``gtmodel/robots/data/<name>.toml``) or a path.

    Returns
    -------
    SixLinkClosure
        The model with its limits.

    Raises
    ------
    ParameterError
        Unknown name, unreadable file, TOML syntax error, or an invalid field (the
        message names the file and the field).
    """
    text_name = str(name_or_path)
    resource = resources.files(_DATA_PACKAGE) / "data" / f"{text_name}.toml"
    if isinstance(name_or_path, str) and "/" not in text_name and not text_name.endswith(".toml") and resource.is_file():
        origin = f"{text_name}.toml (shipped)"
        data = read_toml(Path(str(resource)), ParameterError, "six-link parameter file", origin, resource.read_text(encoding="utf-8"))
    else:
        path = Path(name_or_path)
        if path.suffix != ".toml" and not path.exists():
            raise ParameterError(f"unknown six-link parameter set {text_name!r}: not a shipped set and no such file")
        origin = str(path)
        data = read_toml(path, ParameterError, "six-link parameter file")
    try:
        return _six_link_from_mapping(data, origin)
    except InputError as exc:
        raise ParameterError(f"{origin}: invalid six-link parameters: {exc}") from None
