"""Actuator and link tolerances of a pose accuracy analysis, and the nominal pose they act on.

Dressler (2012), Appendix A.2: the spherical joint centre ``A_i`` of arm ``i`` lies on or
inside an ellipsoid ``E_i^A`` around its nominal position ``A_i^n`` with semi-axes
``r_i1, r_i2, r_i3`` along the unit directions ``u_i1, u_i2, u_i3``; A.3: a link length
``L_i`` within ``L_i +- l_i``. :class:`Tolerances` holds both (the ellipsoid axes default
to the base axes, as in Table 4.2); :func:`nominal_pose` evaluates the 3-link model
(:class:`~gtmodel.robots.kinematics.GantryTau3Kinematics`) at the TCP positions analysed:
the joint points ``A_i^n = As_i + q_i v_i`` and the unit link directions.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Sequence

import numpy as np

from gtmodel._arrays import as_array, as_rows, as_rotation
from gtmodel.errors import InputError
from gtmodel.robots.kinematics import GantryTau3Kinematics

__all__ = ["Tolerances", "NominalPoses", "nominal_pose"]

#: Largest tolerance accepted [m]: the analysis assumes ``L_i >> r_ij`` (Appendix A.4).
MAX_TOLERANCE_M = 0.05


@dataclass(frozen=True)
class Tolerances:
    """Bounds of the actuator (joint point) and link-length errors, Dressler (2012), A.2-A.3.

    Parameters
    ----------
    semi_axes : numpy.ndarray, shape (3, 3)
        Row i: the semi-axes ``(r_i1, r_i2, r_i3)`` of the error ellipsoid of joint point
        ``A_i`` [m], every one positive (Table 4.2 case 1: ``r_i1 = r_i2 = r_i3``).
    axes : numpy.ndarray, shape (3, 3, 3), optional
        ``axes[i]`` is a rotation whose columns are ``u_i1, u_i2, u_i3`` (default: the base
        axes, as in Table 4.2).
    link : numpy.ndarray, shape (3,), optional
        Link-length tolerances ``l_i`` [m], ``L_i`` in ``[L_i - l_i, L_i + l_i]``
        (default 0; A.3).

    Raises
    ------
    InputError
        A semi-axis that is not a positive finite number below :data:`MAX_TOLERANCE_M`
        (zero is refused: a joint known exactly is a tiny tolerance, not none), a negative
        or non-finite link tolerance, or axes that are not rotations; the message names
        the argument and the arm.
    """

    semi_axes: np.ndarray
    axes: np.ndarray | None = None
    link: np.ndarray | None = None

    def __post_init__(self) -> None:
        r = np.array(self.semi_axes, dtype=float)
        if r.shape == (3,):
            r = np.repeat(r[:, None], 3, axis=1)
        r = as_array(r, (3, 3), "semi_axes")
        for i in range(3):
            if not np.all((r[i] > 0) & (r[i] <= MAX_TOLERANCE_M)):
                raise InputError(f"semi_axes: arm {i + 1}: expected positive tolerances up to {MAX_TOLERANCE_M} m, got {r[i].tolist()}")
        axes = np.repeat(np.eye(3)[None], 3, axis=0) if self.axes is None else as_array(self.axes, (3, 3, 3), "axes")
        for i in range(3):
            as_rotation(axes[i], f"axes[{i}]", 1e-9)
        link = np.zeros(3) if self.link is None else as_array(self.link, (3,), "link")
        if not np.all((link >= 0) & (link <= MAX_TOLERANCE_M)):
            raise InputError(f"link: expected non-negative link-length tolerances up to {MAX_TOLERANCE_M} m, got {link.tolist()}")
        for name, value in (("semi_axes", r), ("axes", axes), ("link", link)):
            value.setflags(write=False)
            object.__setattr__(self, name, value)

    @classmethod
    def spherical(cls, radii: Sequence[float], link: Sequence[float] | None = None) -> "Tolerances":
        """Spherical joint-point errors ``r_i`` (Table 4.2 case 1).

        Parameters
        ----------
        radii : sequence of float, shape (3,)
            Radius per arm [m].
        link : sequence of float, shape (3,), optional
            Link-length tolerances [m].

        Returns
        -------
        Tolerances
        """
        return cls(np.repeat(as_array(radii, (3,), "radii")[:, None], 3, axis=1), link=link)

    @property
    def spherical_errors(self) -> bool:
        """True when every ellipsoid is a sphere (the A.3 case)."""
        return bool(np.allclose(self.semi_axes, self.semi_axes[:, :1], rtol=1e-12, atol=0.0))

    @property
    def scale(self) -> float:
        """The largest tolerance [m] (scales the NLP)."""
        return float(max(self.semi_axes.max(), self.link.max()))

    def shape_matrices(self) -> np.ndarray:
        """``M_i = R_i diag(r_i^2) R_i^T``, ellipsoid ``E_i^A = {A^n + d : d^T M_i^-1 d <= 1}``.

        Returns
        -------
        numpy.ndarray, shape (3, 3, 3)
            One matrix per arm [m^2].
        """
        return np.einsum("ijk,ik,ilk->ijl", self.axes, self.semi_axes**2, self.axes)

    def scaled(self, factors: Any) -> "Tolerances":
        """The tolerances of every arm scaled by its factor (semi-axes and link).

        Parameters
        ----------
        factors : float or array_like, shape (3,)
            Positive factor per arm.

        Returns
        -------
        Tolerances
        """
        k = np.broadcast_to(np.asarray(factors, dtype=float), (3,))
        return Tolerances(self.semi_axes * k[:, None], self.axes, self.link * k)


@dataclass(frozen=True)
class NominalPoses:
    """The nominal geometry at N TCP positions (Dressler (2012), Fig. A.3).

    Parameters
    ----------
    T : numpy.ndarray, shape (N, 3)
        Nominal TCP positions ``T^n`` [m].
    q : numpy.ndarray, shape (N, 3)
        Cart positions [m].
    A : numpy.ndarray, shape (N, 3, 3)
        ``A[n, i]``: nominal joint point ``A_i^n`` [m].
    u : numpy.ndarray, shape (N, 3, 3)
        ``u[n, i]``: unit link direction from ``A_i^n`` to ``T^n``.
    L : numpy.ndarray, shape (3,)
        Link lengths [m].
    v : numpy.ndarray, shape (3, 3)
        Guideway directions.
    """

    T: np.ndarray
    q: np.ndarray
    A: np.ndarray
    u: np.ndarray
    L: np.ndarray
    v: np.ndarray


def nominal_pose(kinematics: GantryTau3Kinematics, T: Any, configuration: int | Sequence[int] = 0) -> NominalPoses:
    """The nominal joint points and link directions at TCP positions (eq. 4.9).

    Parameters
    ----------
    kinematics : GantryTau3Kinematics
        The 3-link model.
    T : array_like, shape (3,) or (N, 3)
        TCP positions [m].
    configuration : int or sequence of int, optional
        IK configuration.

    Returns
    -------
    NominalPoses

    Raises
    ------
    InputError
        Non-finite or misshaped ``T``.
    UnreachablePoseError
        An arm cannot reach a pose.
    """
    Tn, _ = as_rows(T, "T", 3)
    q = np.atleast_2d(kinematics.ik(Tn, configuration))
    A = kinematics.As[None] + q[:, :, None] * kinematics.v[None]
    d = Tn[:, None, :] - A
    u = d / np.linalg.norm(d, axis=2, keepdims=True)
    return NominalPoses(Tn, q, A, u, kinematics.L.copy(), kinematics.v.copy())
