"""Parameter layout, solver constants and motion limits of the F1 model.

The 72 parameters of :class:`~gtmodel.robots.f1.F1Closure` in the order of Dressler
(2012), eqs. 5.10-5.12 (arm 1: 10, arm 2: 24, arm 3: 38), the Newton tolerances and
iteration limits of its IK and FK, and :class:`F1Limits`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from gtmodel._arrays import as_rotations, as_rows
from gtmodel.errors import InputError

#: Link names per arm.
F1_LINKS: tuple[tuple[str, ...], ...] = (("1",), ("2a", "2b"), ("3a", "3b", "3c"))
#: Parameters fixed for identifiability in Dressler (2012), Table 5.4 (names of
#: :meth:`F1Closure.parameter_names`; the last entry is the equality constraint
#: ``Abj_2b_z = Abj_2a_z``).
F1_FIXED_FOR_IDENTIFIABILITY: tuple[str, ...] = ("Abj_2b_y", "r3_y", "r3_z", "Abj_3c_x", "Abj_3c_z", "Abj_2b_z = Abj_2a_z")
#: Newton tolerance of the IK: max |L^2 - ||B - A||^2| over the links of arms 2, 3 [m^2]
#: (about 3e-14 m in link length).
IK_TOLERANCE = 1e-13
#: Newton iteration limit of the IK (the unrolled Functions run exactly this many).
IK_MAX_ITER = 20
#: Newton tolerance of the FK: max | ||B - A|| - L | over the six links [m].
FK_TOLERANCE = 1e-13
#: Newton iteration limit of the FK (the unrolled Functions run exactly this many).
FK_MAX_ITER = 20
#: Default starts (:attr:`F1Closure.ik_start_function`, :attr:`F1Closure.fk_start_function`):
#: continuation from the home pose in this many equal sub-steps ...
START_SUBSTEPS = 12
#: ... each followed by this many Newton steps.
START_NEWTON_STEPS = 2
#: Steps in ``q`` of the second FK start (:meth:`F1Closure.fk` with the default start): a
#: pose whose continuation from the home pose fails is reached from the nearest converged
#: pose of the same call in this many equal steps.
FK_CONTINUATION_STEPS = 8
#: Newton steps per evaluation (the block size) in the NumPy methods: :meth:`F1Closure.ik` and
#: :meth:`F1Closure.fk` run chunks of this many unrolled steps on the poses not yet
#: converged (the same iterates as one unrolled run of ``max_iter`` steps).
NEWTON_CHUNK = 4
#: Largest distance [m] (and rotation-matrix entry difference) between a grid pose and the
#: FK of its IK solution for :meth:`F1Closure.workspace_grid` to keep it.
GRID_FK_TOLERANCE = 1e-9
#: Largest accepted deviation of an input orientation from a rotation, max |R^T R - I|.
ROTATION_TOLERANCE = 1e-8


# (name, size) in parameter-vector order: arm 1 (10), arm 2 (24), arm 3 (38); eqs. 5.10-5.12.
_BLOCKS: tuple[tuple[str, int], ...] = (
    ("L_1", 1), ("A0_1", 3), ("v1", 3), ("B0_1", 3),
    ("L_2a", 1), ("L_2b", 1), ("A0_2", 3), ("v2", 3), ("q1u2", 4),
    ("Abj_2a", 3), ("Abj_2b", 3), ("B0_2a", 3), ("B0_2b", 3),
    ("L_3a", 1), ("L_3b", 1), ("L_3c", 1), ("A0_3", 3), ("v3", 3), ("q1u3", 4), ("r3", 3), ("q2u3", 4),
    ("Abj_3a", 3), ("Abj_3b", 3), ("Abj_3c", 3), ("B0_3a", 3), ("B0_3b", 3), ("B0_3c", 3),
)
_SUFFIX = {1: ("",), 3: ("_x", "_y", "_z"), 4: ("_w", "_x", "_y", "_z")}
_OFFSET: dict[str, tuple[int, int]] = {}
_k = 0
for _name, _size in _BLOCKS:
    _OFFSET[_name] = (_k, _size)
    _k += _size
_N_PARAMETERS = _k
_NAMES: tuple[str, ...] = tuple(n + s for n, size in _BLOCKS for s in _SUFFIX[size])
del _k, _name, _size



def _get(p: Any, name: str) -> Any:
    """The block ``name`` of a parameter vector (a scalar for size-1 blocks)."""
    i, n = _OFFSET[name]
    return p[i] if n == 1 else p[i:i + n]


# ------------------------------------------------------------------ limits
@dataclass(frozen=True)
class F1Limits:
    """Motion limits of the F1 and the reorientation range of its workspace grid.

    Parameters
    ----------
    cart_travel : numpy.ndarray, shape (3, 2)
        Row i is ``(q_min, q_max)`` of cart i+1 [m].
    joint_plate_range : numpy.ndarray, shape (3, 2)
        Rows ``(min, max)`` of ``q4, q5, q6`` [rad].
    ball_joint_angle_max : float
        Largest angle of a link to its ball-joint axis [rad] (see
        :meth:`F1Closure.ball_joint_angles`), Dressler (2012), ch. 5.5: 45 deg.
    reorientation_range : numpy.ndarray, shape (3,)
        Largest rotation from the home orientation about the world x, y, z axes used by
        :meth:`F1Closure.workspace_grid` [rad].
    error_amplification_max : numpy.ndarray, shape (2,)
        Largest TCP position error per link-length error [m/m] and orientation error per
        link-length error [rad/m] (:meth:`F1Closure.error_amplification`), the margin to
        the FK (type II) singularities.
    joint_plate_amplification_max : float
        Largest joint-plate rotation per plate rotation [rad/rad]
        (:meth:`F1Closure.joint_plate_amplification`), the margin to the IK (type I)
        singularities.
    source : str
        Where the numbers come from.
    """

    cart_travel: np.ndarray
    joint_plate_range: np.ndarray
    ball_joint_angle_max: float
    reorientation_range: np.ndarray
    error_amplification_max: np.ndarray
    joint_plate_amplification_max: float
    source: str = ""


#: Docstring sections of the F1 methods that take poses ``(T, R, q)`` (inserted by
#: :func:`~gtmodel._docstrings.fill_doc`).
POSE_DOCS = {
    "pose_args": """
        T : array_like, shape (3,) or (N, 3)
            TCP positions [m].
        R : array_like, shape (3, 3) or (N, 3, 3)
            Plate orientations.
        q : array_like, shape (6,) or (N, 6)
            Actuator values of the poses [m, rad].
    """,
    "pose_raises": """
        Raises
        ------
        InputError
            Wrong shapes, non-finite values or ``R`` not a rotation.
    """,
}


def pose_rows(T: np.typing.ArrayLike, R: np.typing.ArrayLike, q: np.typing.ArrayLike) -> tuple[np.ndarray, np.ndarray, np.ndarray, bool]:
    """Checked poses ``(T, R, q)`` of the F1 as rows.

    Parameters
    ----------
    T : array_like, shape (3,) or (N, 3)
        TCP positions [m].
    R : array_like, shape (3, 3) or (N, 3, 3)
        Plate orientations (one matrix is used for every position).
    q : array_like, shape (6,) or (N, 6)
        Actuator values [m, rad].

    Returns
    -------
    T : numpy.ndarray, shape (N, 3)
    R : numpy.ndarray, shape (N, 3, 3)
    q : numpy.ndarray, shape (N, 6)
    single : bool
        True when ``T`` was one position.

    Raises
    ------
    InputError
        Wrong shapes, non-finite values, ``q`` rows not matching ``T``, ``R`` not a rotation.
    """
    Ta, single = as_rows(T, "T", 3)
    N = Ta.shape[0]
    qa, _ = as_rows(q, "q", 6)
    if qa.shape[0] != N:
        raise InputError(f"q: expected {N} rows to match T, got {qa.shape[0]}")
    return Ta, as_rotations(R, N, "R", ROTATION_TOLERANCE), qa, single
