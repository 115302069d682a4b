"""Static stiffness of the 3-link (translational) Gantry-Tau model, in CasADi.

Dressler (2012), ch. 6.3 and 2.1 (spec section 4): for a parallel kinematic machine whose
links carry axial forces only, the Cartesian stiffness at the TCP is

    K_x(T) = sum_i k_i u_i u_i^T = U^T diag(k) U,                                   (1)

``u_i = (T - A_i) / |T - A_i|`` the unit link vector of arm ``i`` (rows of ``U``),
``A_i = As_i + q_i v_i`` its cart joint (eq. 4.9), and ``k_i`` the effective axial stiffness
of the arm. Since row ``i`` of the inverse Jacobian (eq. 6.5) is ``u_i^T / (u_i . v_i)``,
(1) is the familiar ``K_x = J^-T diag(k_i (u_i . v_i)^2) J^-1`` form.

Derivation of ``k_i`` (each arm a series chain)
------------------------------------------------
Arm ``i`` is a cluster of ``n_i`` parallel links (the 3-2-1 configuration: ``n = (1, 2, 3)``),
each link a tube of axial stiffness ``k_l = E A / L_i`` with a spherical joint of stiffness
``k_j`` (115 kN/mm) at each end, and the cart is held along its guideway by the actuator with
stiffness ``k_a`` (rigid across the guideway). Let ``f_i`` be the axial (tension-positive)
force of the arm, shared equally by its links (parallelogram clusters, rigid plate).

- The links and joints lengthen by ``dL_i = f_i (1/k_l + 2/k_j) / n_i``.
- The cart carries the component ``f_i (u_i . w_i)`` of the link force along the unit guideway
  direction ``w_i = v_i / |v_i|`` and moves by ``ds_i = f_i (u_i . w_i) / k_a`` along ``w_i``.
- To first order the distance between the cart joint and the TCP changes by
  ``u_i . (dT - ds_i w_i)``, so the TCP displacement along the link is
  ``u_i . dT = dL_i + ds_i (u_i . w_i) = c_i f_i`` with the arm compliance

      c_i = 1/k_i = (1/k_l + 2/k_j) / n_i + (u_i . w_i)^2 / k_a.                     (2)

  The actuator's share depends on the pose through the link angle to the guideway.

Statics of the plate: an external force ``F`` on the plate (gravity, a process force at the
TCP) is balanced by the arm forces, ``sum_i f_i u_i = U^T f = F``, so

    f = U^-T F,     u_i . dT = c_i f_i  =>  U dT = C U^-T F  =>  K_x dT = F,           (3)

with ``K_x = U^T C^-1 U``, i.e. (1). The plate's orientation is held by the parallelograms
(the translational model: no rotation compliance); gravity on the plate is
``F_g = -g (m_p + m_payload + sum_i m_a,i / 2) e_z``, the plate's share of ``G`` in eq. 6.7.
The geometric stiffness of the pre-loaded links (``f_i / L_i (I - u_i u_i^T)``, ~50 N/m for
100 N links) is neglected against ``K_x`` (~1e6 N/m).

:func:`closure_stiffness` is the general form for any closure model (the six-link geometry,
Dressler (2012), eq. 4.14): the link lengths are differentiated with respect to the plate's
position and rotation and the cart displacements, ``C^T diag(k_l) C`` plus the actuators is
assembled and the carts (and, for a force at the TCP, the plate rotation) are condensed out.
For the 3-link model it reproduces (1)-(2) exactly; for the six-link D1 the free plate
rotation makes the TCP 5-10 % softer.

Every expression is written once here in CasADi; :class:`GantryTau3Stiffness` wraps them in
:class:`casadi.Function` objects mapped over poses, and the elasto-geometric calibration
(:mod:`gtmodel.calibration.elasto_geometric`) builds its closure equations from the same
expressions. Stiffness values with their sources and assumptions are in the data file
``gtmodel/robots/data/stiffness.toml`` (:func:`load_stiffness`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import cached_property
from importlib import resources
from pathlib import Path
from typing import TYPE_CHECKING, Any, Sequence

import casadi as ca
import numpy as np
import numpy.typing  # noqa: F401  (np.typing in annotations)

from gtmodel._docstrings import fill_doc
from gtmodel._toml import read_toml
from gtmodel.errors import InputError, ParameterError, SingularConfigurationError, UnreachablePoseError
from gtmodel.robots.mapped import MappedFunction as _Mapped
from gtmodel.robots.kinematics import (
    SINGULARITY_TOLERANCE,
    GantryTau3Kinematics,
    _as_points,
    configuration_signs,
    ik_expression,
)
from gtmodel.robots.parameters import RobotParameters, load_parameters

if TYPE_CHECKING:  # closure.py is imported inside closure_stiffness (no import cycle at load)
    from gtmodel.robots.closure import ClosureModel

__all__ = [
    "StiffnessParameters",
    "StiffnessMap",
    "GantryTau3Stiffness",
    "load_stiffness",
    "link_unit_vectors_expression",
    "arm_compliance_expression",
    "cartesian_stiffness_expression",
    "link_forces_expression",
    "deflection_expression",
    "plot_stiffness_map",
    "ClosureStiffness",
    "closure_stiffness",
    "MEASURED_D1_N_PER_UM",
    "N_PER_UM",
]

#: Measured static TCP stiffness of the D1 [N/um], Dressler (2012), ch. 6.3.
MEASURED_D1_N_PER_UM = (2.0, 4.0)
#: 1 N/um in N/m.
N_PER_UM = 1e6

_DATA_PACKAGE = "gtmodel.robots"

# numpydoc entries shared by the methods that take the same arguments (gtmodel._docstrings)
_LENGTHS_PARAMETERS = """
Parameters
----------
L : array_like, shape (3,)
    Link lengths [m].
"""
_LENGTHS_RAISES = """
Raises
------
InputError
    Non-positive or wrongly shaped lengths.
"""
_POSE_PARAMETERS = """
Parameters
----------
T : array_like, shape (3,) or (N, 3)
    TCP position(s) [m].
"""
_POSE_OPTIONS = """
configuration : int or sequence of int, optional
    IK configuration (see :meth:`GantryTau3Kinematics.ik`).
limits : bool, optional
    Require the poses inside cart travel and joint limits (default True).
"""
_POSE_RAISES = """
Raises
------
UnreachablePoseError
    A pose is unreachable or outside the workspace limits.
InputError
    Wrong shapes (also of ``F`` where given) or non-finite values.
"""
_lengths_doc = fill_doc(lengths_parameters=_LENGTHS_PARAMETERS, lengths_raises=_LENGTHS_RAISES)
_pose_doc = fill_doc(pose_parameters=_POSE_PARAMETERS, pose_options=_POSE_OPTIONS, pose_raises=_POSE_RAISES)


# ----------------------------------------------------------------------------- parameters
def _positive(value: Any, name: str, shape: tuple[int, ...] = ()) -> np.ndarray:
    try:
        arr = np.array(value, dtype=float)
    except (TypeError, ValueError):
        raise InputError(f"{name}: expected positive number(s) of shape {shape}, got {value!r}") from None
    if arr.shape != shape:
        raise InputError(f"{name}: expected shape {shape}, got {arr.shape}")
    if not np.all(np.isfinite(arr)) or np.any(arr <= 0):
        raise InputError(f"{name}: expected positive finite value(s), got {arr.tolist()}")
    return arr


@dataclass(frozen=True)
class StiffnessParameters:
    """Stiffness of the links, spherical joints and actuators of a Gantry-Tau.

    Parameters
    ----------
    k_joint : float
        Axial stiffness of one spherical joint [N/m] (115 kN/mm = 1.15e8 N/m, Dressler
        (2012), ch. 2.1).
    E : float
        Axial Young's modulus of the link tubes [Pa].
    outer_diameter : float
        Outer diameter of a link tube [m].
    inner_diameter : float
        Inner diameter of a link tube [m] (0 for a solid rod), below ``outer_diameter``.
    k_actuator : array_like, shape (3,)
        Stiffness of each cart along its guideway [N/m].
    links_per_arm : array_like, shape (3,)
        Number of parallel links per arm (3-2-1 configuration: ``(1, 2, 3)``).
    joints_per_link : int, optional
        Spherical joints in series per link (default 2).
    sources : dict of str to str, optional
        Where each group of values comes from (``"joints"``, ``"links"``, ``"actuators"``).

    Raises
    ------
    InputError
        A non-positive or non-finite stiffness, modulus or diameter, an inner diameter not
        below the outer one, wrong shapes, or link/joint counts that are not positive
        integers.
    """

    k_joint: float
    E: float
    outer_diameter: float
    inner_diameter: float
    k_actuator: np.ndarray
    links_per_arm: np.ndarray
    joints_per_link: int = 2
    sources: dict = field(default_factory=dict)

    def __post_init__(self) -> None:
        object.__setattr__(self, "k_joint", float(_positive(self.k_joint, "k_joint")))
        object.__setattr__(self, "E", float(_positive(self.E, "E")))
        object.__setattr__(self, "outer_diameter", float(_positive(self.outer_diameter, "outer_diameter")))
        d_in = np.array(self.inner_diameter, dtype=float) if np.ndim(self.inner_diameter) == 0 else None
        if d_in is None or not np.isfinite(d_in) or d_in < 0 or d_in >= self.outer_diameter:
            raise InputError(
                f"inner_diameter: expected 0 <= inner_diameter < outer_diameter = {self.outer_diameter} m, got {self.inner_diameter!r}"
            )
        object.__setattr__(self, "inner_diameter", float(d_in))
        object.__setattr__(self, "k_actuator", _positive(self.k_actuator, "k_actuator", (3,)))
        n = _positive(self.links_per_arm, "links_per_arm", (3,))
        if np.any(n != np.round(n)):
            raise InputError(f"links_per_arm: expected positive integers, got {n.tolist()}")
        object.__setattr__(self, "links_per_arm", n.astype(int))
        j = self.joints_per_link
        if isinstance(j, bool) or not isinstance(j, (int, np.integer)) or j < 0:
            raise InputError(f"joints_per_link: expected a non-negative integer, got {j!r}")

    @property
    def link_area(self) -> float:
        """Cross-section of a link tube [m^2]."""
        return math.pi / 4 * (self.outer_diameter**2 - self.inner_diameter**2)

    @_lengths_doc
    def link_stiffness(self, L: np.typing.ArrayLike) -> np.ndarray:
        """Axial stiffness ``E A / L`` of one link tube of each arm.

        {lengths_parameters}

        Returns
        -------
        numpy.ndarray, shape (3,)
            ``k_l`` [N/m].

        {lengths_raises}
        """
        return self.E * self.link_area / _positive(L, "L", (3,))

    @_lengths_doc
    def compliances(self, L: np.typing.ArrayLike) -> tuple[np.ndarray, np.ndarray]:
        """Constant and actuator parts of the arm compliance, eq. (2) of the module docstring.

        {lengths_parameters}

        Returns
        -------
        c_link : numpy.ndarray, shape (3,)
            ``(1/k_l + joints_per_link/k_j) / n_i`` [m/N]: links and joints of the cluster.
        c_act : numpy.ndarray, shape (3,)
            ``1/k_a`` [m/N]: the cart along its guideway (scaled by ``(u_i . w_i)^2`` at a pose).

        {lengths_raises}
        """
        kl = self.link_stiffness(L)
        c_link = (1.0 / kl + self.joints_per_link / self.k_joint) / self.links_per_arm
        return c_link, 1.0 / self.k_actuator

    def describe(self) -> str:
        """The stated values in one line (units N/um, GPa, mm) for plots and reports.

        Returns
        -------
        str
        """
        ka = ", ".join(f"{k / N_PER_UM:g}" for k in self.k_actuator)
        return (
            f"joints {self.k_joint / N_PER_UM:g} N/um, links E = {self.E / 1e9:g} GPa, "
            f"tube {1e3 * self.outer_diameter:g}/{1e3 * self.inner_diameter:g} mm, "
            f"links per arm {tuple(int(n) for n in self.links_per_arm)}, actuators {ka} N/um"
        )


def load_stiffness(name_or_path: str | Path = "stiffness") -> StiffnessParameters:
    """Load stiffness values from a TOML file (default: the shipped ``stiffness.toml``).

    Parameters
    ----------
    name_or_path : str or pathlib.Path, optional
        ``"stiffness"`` for the shipped file, or the path of a file with the same tables
        (``[joints]``, ``[links]``, ``[actuators]``).

    Returns
    -------
    StiffnessParameters

    Raises
    ------
    ParameterError
        Unreadable file, TOML syntax error, a missing, unknown or invalid field (the message
        names the file and the field).
    """
    if isinstance(name_or_path, StiffnessParameters):
        return name_or_path
    if str(name_or_path) in ("stiffness", "default"):
        res = resources.files(_DATA_PACKAGE) / "data" / "stiffness.toml"
        origin = "stiffness.toml (shipped)"
        data = read_toml(Path(str(res)), ParameterError, "stiffness file", origin, res.read_text(encoding="utf-8"))
    else:
        origin = str(name_or_path)
        data = read_toml(Path(name_or_path), ParameterError, "stiffness file")
    allowed = {
        "": {"name", "description", "joints", "links", "actuators", "reference"},
        "joints": {"source", "k_joint", "joints_per_link"},
        "links": {"source", "E", "outer_diameter", "inner_diameter", "links_per_arm"},
        "actuators": {"source", "k_actuator"},
        "reference": {"source", "measured_tcp_N_per_um"},
    }
    for table, keys in allowed.items():
        node = data if table == "" else data.get(table)
        if node is None:
            raise ParameterError(f"{origin}: missing table '[{table}]'")
        if not isinstance(node, dict):
            raise ParameterError(f"{origin}: field '{table}': expected a table")
        unknown = sorted(set(node) - keys)
        if unknown:
            where = unknown[0] if table == "" else f"{table}.{unknown[0]}"
            raise ParameterError(f"{origin}: unknown field '{where}' (allowed: {', '.join(sorted(keys))})")

    def get(table: str, key: str, default: Any = ...) -> Any:
        if key not in data[table]:
            if default is ...:
                raise ParameterError(f"{origin}: missing field '{table}.{key}'")
            return default
        return data[table][key]

    fields = {
        "k_joint": ("joints", "k_joint"),
        "joints_per_link": ("joints", "joints_per_link"),
        "E": ("links", "E"),
        "outer_diameter": ("links", "outer_diameter"),
        "inner_diameter": ("links", "inner_diameter"),
        "links_per_arm": ("links", "links_per_arm"),
        "k_actuator": ("actuators", "k_actuator"),
    }
    values = {k: get(t, key, 2 if k == "joints_per_link" else ...) for k, (t, key) in fields.items()}
    try:
        return StiffnessParameters(
            **values,
            sources={t: str(data[t].get("source", "")) for t in ("joints", "links", "actuators")},
        )
    except InputError as exc:
        name = str(exc).split(":", 1)[0]
        table, key = fields.get(name, ("", name))
        raise ParameterError(f"{origin}: field '{table}.{key}': {str(exc).split(':', 1)[1].strip()}") from None


# ----------------------------------------------------------------------------- expressions
def _row(M: Any, i: int) -> Any:
    return M[i, :].T


def link_unit_vectors_expression(T: Any, A: Any) -> Any:
    """Unit link vectors ``u_i = (T - A_i) / |T - A_i|`` (eq. 4.9: ``A_i = As_i + q_i v_i``).

    Parameters
    ----------
    T : casadi.SX or casadi.MX, shape (3, 1)
        TCP position [m].
    A : casadi.SX or casadi.MX, shape (3, 3)
        Row i: cart joint point ``A_i`` of arm i [m].

    Returns
    -------
    casadi.SX or casadi.MX, shape (3, 3)
        ``U``, row i = ``u_i^T`` (dimensionless).
    """
    rows = []
    for i in range(3):
        d = T - A[i, :].T
        rows.append((d / ca.norm_2(d)).T)
    return ca.vertcat(*rows)


def arm_compliance_expression(U: Any, v: Any, c_link: Any, c_act: Any) -> Any:
    """Axial compliance of each arm at a pose, eq. (2) of the module docstring.

    ``c_i = c_link,i + c_act,i (u_i . w_i)^2`` with ``w_i = v_i / |v_i|``: the links and
    joints of the cluster in series with the cart's compliance along its guideway, seen
    along the link.

    Parameters
    ----------
    U : casadi.SX or casadi.MX, shape (3, 3)
        Unit link vectors (rows), :func:`link_unit_vectors_expression`.
    v : casadi.SX or numpy.ndarray, shape (3, 3)
        Row i: guideway direction of arm i.
    c_link : casadi.SX or array_like, shape (3,)
        Cluster compliance ``(1/k_l + 2/k_j) / n_i`` [m/N].
    c_act : casadi.SX or array_like, shape (3,)
        Actuator compliance ``1/k_a`` along the guideway [m/N].

    Returns
    -------
    casadi.SX or casadi.MX, shape (3, 1)
        ``c_i`` [m/N].
    """
    out = []
    for i in range(3):
        w = _row(v, i)
        cos = ca.dot(_row(U, i), w) / ca.norm_2(w)
        out.append(c_link[i] + c_act[i] * cos**2)
    return ca.vertcat(*out)


def cartesian_stiffness_expression(U: Any, c: Any) -> Any:
    """Cartesian stiffness ``K_x = sum_i u_i u_i^T / c_i = U^T diag(1/c) U``, eq. (1).

    Dressler (2012), ch. 6.3 (spec section 4): ``K_x = sum k_i u_i u_i^T``.

    Parameters
    ----------
    U : casadi.SX or casadi.MX, shape (3, 3)
        Unit link vectors (rows).
    c : casadi.SX or casadi.MX, shape (3, 1)
        Arm compliances [m/N], :func:`arm_compliance_expression`.

    Returns
    -------
    casadi.SX or casadi.MX, shape (3, 3)
        ``K_x`` [N/m], symmetric.
    """
    return ca.mtimes([U.T, ca.diag(1.0 / c), U])


def link_forces_expression(U: Any, F: Any) -> Any:
    """Axial arm forces that balance a force on the plate: ``U^T f = F``, eq. (3).

    Parameters
    ----------
    U : casadi.SX or casadi.MX, shape (3, 3)
        Unit link vectors (rows).
    F : casadi.SX or casadi.MX or array_like, shape (3,)
        External force on the plate [N] (gravity: ``-m g e_z``).

    Returns
    -------
    casadi.SX or casadi.MX, shape (3, 1)
        ``f`` [N], tension positive (the whole cluster's force).
    """
    return ca.solve(U.T, ca.vec(F) if isinstance(F, (ca.SX, ca.MX)) else ca.DM(np.asarray(F, dtype=float).reshape(3)))


def deflection_expression(U: Any, c: Any, F: Any) -> Any:
    """TCP deflection under a plate force, ``dT = K_x^-1 F``, eq. (3).

    Parameters
    ----------
    U : casadi.SX or casadi.MX, shape (3, 3)
        Unit link vectors (rows).
    c : casadi.SX or casadi.MX, shape (3, 1)
        Arm compliances [m/N].
    F : casadi.SX or casadi.MX or array_like, shape (3,)
        Force on the plate [N].

    Returns
    -------
    casadi.SX or casadi.MX, shape (3, 1)
        ``dT`` [m].
    """
    Fv = ca.vec(F) if isinstance(F, (ca.SX, ca.MX)) else ca.DM(np.asarray(F, dtype=float).reshape(3))
    return ca.solve(cartesian_stiffness_expression(U, c), Fv)


# ----------------------------------------------------------------------------- results
@dataclass
class StiffnessMap:
    """Static stiffness over a set of TCP positions (a workspace section).

    Parameters
    ----------
    T : numpy.ndarray, shape (N, 3)
        TCP positions [m].
    K : numpy.ndarray, shape (N, 3, 3)
        Cartesian stiffness ``K_x`` [N/m].
    gravity_deflection : numpy.ndarray, shape (N, 3)
        TCP deflection under the plate's gravity load (with payload) [m].
    stiffness : StiffnessParameters
        The stated values used.
    payload_kg : float
        Payload on the plate [kg].
    """

    T: np.ndarray
    K: np.ndarray
    gravity_deflection: np.ndarray
    stiffness: StiffnessParameters
    payload_kg: float

    @property
    def eigenvalues(self) -> np.ndarray:
        """Principal stiffnesses, ascending, (N, 3) [N/m]."""
        return np.linalg.eigvalsh(self.K)

    @property
    def min_stiffness(self) -> np.ndarray:
        """Smallest principal stiffness (weakest direction) per pose, (N,) [N/m]."""
        return self.eigenvalues[:, 0]

    @property
    def axis_stiffness(self) -> np.ndarray:
        """Stiffness along x, y, z: ``1 / (K_x^-1)_jj`` (force along axis j over the deflection along it), (N, 3) [N/m]."""
        return 1.0 / np.diagonal(np.linalg.inv(self.K), axis1=1, axis2=2)

    def summary(self) -> dict[str, Any]:
        """Ranges over the poses in N/um and um, with the measured D1 figure.

        Returns
        -------
        dict
            ``min_eigenvalue_N_per_um``, ``max_eigenvalue_N_per_um``, ``axis_N_per_um`` (x, y, z
            ranges), ``gravity_deflection_um`` (mean, max of the norm), ``measured_D1_N_per_um``.
        """
        ev = self.eigenvalues / N_PER_UM
        ax = self.axis_stiffness / N_PER_UM
        dn = np.linalg.norm(self.gravity_deflection, axis=1) * 1e6
        return {
            "n_poses": int(self.T.shape[0]),
            "min_eigenvalue_N_per_um": [float(ev[:, 0].min()), float(ev[:, 0].max())],
            "max_eigenvalue_N_per_um": [float(ev[:, 2].min()), float(ev[:, 2].max())],
            "axis_N_per_um": {c: [float(ax[:, j].min()), float(ax[:, j].max())] for j, c in enumerate("xyz")},
            "gravity_deflection_um": {"mean": float(dn.mean()), "max": float(dn.max())},
            "payload_kg": float(self.payload_kg),
            "measured_D1_N_per_um": list(MEASURED_D1_N_PER_UM),
        }


# ----------------------------------------------------------------------------- the model
class GantryTau3Stiffness:
    """Static stiffness and deflections of a 3-link Gantry-Tau (module docstring eqs. 1-3).

    Parameters
    ----------
    parameters : RobotParameters or str or pathlib.Path
        Robot parameter set (kinematics, plate and link masses, limits) or its name/path.
    stiffness : StiffnessParameters or str or pathlib.Path, optional
        Stiffness values (default: the shipped ``stiffness.toml``, :func:`load_stiffness`).
    payload_kg : float, optional
        Payload on the plate (spindle, tool) [kg], default 0.

    Raises
    ------
    InputError
        A negative or non-finite payload.
    ParameterError
        An invalid parameter set or stiffness file.

    Notes
    -----
    The CasADi Function :attr:`statics_function` has the kinematic parameters embedded; the
    compliances are inputs, so one graph serves every set of stiffness values.
    """

    def __init__(
        self,
        parameters: RobotParameters | str | Path,
        stiffness: StiffnessParameters | str | Path | None = None,
        payload_kg: float = 0.0,
    ) -> None:
        self.parameters = load_parameters(parameters)
        self.stiffness = load_stiffness("stiffness" if stiffness is None else stiffness)
        try:
            m = float(payload_kg)
        except (TypeError, ValueError):
            raise InputError(f"payload_kg: expected a non-negative mass in kg, got {payload_kg!r}") from None
        if not (math.isfinite(m) and m >= 0):
            raise InputError(f"payload_kg: expected a non-negative mass in kg, got {payload_kg!r}")
        self.payload_kg = m
        self.kinematics = GantryTau3Kinematics(self.parameters)
        kp = self.parameters.kinematics
        self.L, self.As, self.v = np.asarray(kp.L, float), np.asarray(kp.As, float), np.asarray(kp.v, float)
        self.c_link, self.c_act = self.stiffness.compliances(self.L)

    # ------------------------------------------------------------------ loads
    @property
    def plate_mass(self) -> float:
        """Mass carried by the plate joints: ``m_p + payload + sum m_a / 2`` [kg] (eq. 6.7's ``G``)."""
        d = self.parameters.dynamics
        return float(d.m_p + self.payload_kg + 0.5 * np.sum(d.m_a))

    @property
    def gravity_force(self) -> np.ndarray:
        """Gravity load on the plate ``(0, 0, -g m)`` [N], ``m`` = :attr:`plate_mass`."""
        return np.array([0.0, 0.0, -self.parameters.dynamics.g * self.plate_mass])

    # ------------------------------------------------------------------ CasADi
    @cached_property
    def statics_function(self) -> ca.Function:
        """CasADi Function ``statics(T[3], s[3], F[3], c_link[3], c_act[3])``.

        Outputs ``K`` (3x3) [N/m], ``k`` (3) arm stiffness [N/m], ``f`` (3) arm forces [N],
        ``dT`` (3) deflection [m], ``disc`` (3) IK discriminants, ``cos_min`` (1) smallest
        |cos| of a link to its guideway. Eqs. (1)-(3), IK of eq. 4.9.
        """
        T = ca.SX.sym("T", 3)
        s = ca.SX.sym("s", 3)
        F = ca.SX.sym("F", 3)
        cl = ca.SX.sym("c_link", 3)
        cact = ca.SX.sym("c_act", 3)
        q, disc = ik_expression(T, s, self.L, self.As, self.v)
        A = ca.vertcat(*[(ca.DM(self.As[i]) + q[i] * ca.DM(self.v[i])).T for i in range(3)])
        U = link_unit_vectors_expression(T, A)
        c = arm_compliance_expression(U, self.v, cl, cact)
        K = cartesian_stiffness_expression(U, c)
        f = link_forces_expression(U, F)
        dT = ca.solve(K, F)
        cos = ca.vertcat(*[ca.fabs(ca.dot(U[i, :].T, ca.DM(self.v[i]))) / float(np.linalg.norm(self.v[i])) for i in range(3)])
        return ca.Function(
            "statics", [T, s, F, cl, cact], [K, 1.0 / c, f, dT, disc, ca.mmin(cos)],
            ["T", "s", "F", "c_link", "c_act"], ["K", "k", "f", "dT", "disc", "cos_min"],
        )

    @cached_property
    def _statics(self) -> _Mapped:
        return _Mapped(self.statics_function)

    # ------------------------------------------------------------------ numpy glue
    def _poses(self, T: Any, configuration: Any, limits: bool) -> tuple[np.ndarray, bool, np.ndarray]:
        Tn, single = _as_points(T, "T")
        s = configuration_signs(configuration)
        self.kinematics.ik(Tn, configuration)  # UnreachablePoseError naming the arm
        if limits:
            ok = np.atleast_1d(self.kinematics.in_workspace(Tn, configuration))
            if not np.all(ok):
                k = int(np.argmin(ok))
                self.kinematics.require_in_workspace(Tn[k], configuration)  # raises with the details
        return Tn, single, s

    def _forces(self, F: Any, n: int, single: bool) -> np.ndarray:
        if F is None:
            return np.repeat(self.gravity_force[None, :], n, axis=0)
        try:
            Fa = np.array(F, dtype=float)
        except (TypeError, ValueError):
            raise InputError(f"F: expected a force of shape (3,) or ({n}, 3) in N, got {F!r}") from None
        if Fa.shape == (3,):
            Fa = np.repeat(Fa[None, :], n, axis=0)
        if Fa.shape != (n, 3):
            raise InputError(f"F: expected a force of shape (3,) or ({n}, 3) in N (one per pose), got shape {np.shape(F)}")
        bad = ~np.all(np.isfinite(Fa), axis=1)
        if np.any(bad):
            raise InputError(f"F: row {int(np.argmax(bad))} is not finite: {Fa[np.argmax(bad)].tolist()}")
        return Fa

    def _evaluate(self, T: Any, F: Any, configuration: Any, limits: bool) -> tuple[list[np.ndarray], bool, int]:
        Tn, single, s = self._poses(T, configuration, limits)
        n = Tn.shape[0]
        Fa = self._forces(F, n, single)
        K, k, f, dT, _, cos_min = self._statics(Tn.T, s[:, None], Fa.T, self.c_link[:, None], self.c_act[:, None])
        cos_min = cos_min.ravel()
        if np.any(cos_min < SINGULARITY_TOLERANCE):
            j = int(np.argmin(cos_min))
            raise SingularConfigurationError(f"pose T={Tn[j].tolist()} is singular: a link is perpendicular to its guideway")
        K = K.reshape(3, n, 3).transpose(1, 0, 2) if n > 1 else K[None]
        return [K, k.T, f.T, dT.T], single, n

    def _output(self, index: int, T: Any, F: Any, configuration: Any, limits: bool) -> np.ndarray:
        """Output ``index`` of :meth:`_evaluate` (K, k, f, dT), per pose or for the single pose given."""
        out, single, _ = self._evaluate(T, F, configuration, limits)
        return out[index][0] if single else out[index]

    # ------------------------------------------------------------------ public
    @_pose_doc
    def cartesian_stiffness(self, T: np.typing.ArrayLike, configuration: int | Sequence[int] = 0, limits: bool = True) -> np.ndarray:
        """Cartesian stiffness ``K_x(T) = sum_i k_i u_i u_i^T`` (Dressler (2012), ch. 6.3; eq. 1).

        {pose_parameters}
        {pose_options}

        Returns
        -------
        numpy.ndarray, shape (3, 3) or (N, 3, 3)
            ``K_x`` [N/m].

        {pose_raises}
        """
        return self._output(0, T, None, configuration, limits)

    @_pose_doc
    def arm_stiffness(self, T: np.typing.ArrayLike, configuration: int | Sequence[int] = 0, limits: bool = True) -> np.ndarray:
        """Effective axial stiffness ``k_i = 1 / c_i`` of each arm at a pose (eq. 2).

        {pose_parameters}
        {pose_options}

        Returns
        -------
        numpy.ndarray, shape (3,) or (N, 3)
            ``k_i`` [N/m].

        {pose_raises}
        """
        return self._output(1, T, None, configuration, limits)

    @_pose_doc
    def link_forces(
        self, T: np.typing.ArrayLike, F: np.typing.ArrayLike | None = None, configuration: int | Sequence[int] = 0, limits: bool = True
    ) -> np.ndarray:
        """Axial arm forces balancing a plate force, ``U^T f = F`` (eq. 3).

        {pose_parameters}
        F : array_like, shape (3,) or (N, 3), optional
            Force on the plate [N]; default the gravity load :attr:`gravity_force`.
        {pose_options}

        Returns
        -------
        numpy.ndarray, shape (3,) or (N, 3)
            Arm (cluster) forces [N], tension positive.

        {pose_raises}
        """
        return self._output(2, T, F, configuration, limits)

    @_pose_doc
    def deflection(
        self, T: np.typing.ArrayLike, F: np.typing.ArrayLike | None = None, configuration: int | Sequence[int] = 0, limits: bool = True
    ) -> np.ndarray:
        """TCP deflection ``dT = K_x^-1 F`` under a force on the plate (eq. 3).

        {pose_parameters}
        F : array_like, shape (3,) or (N, 3), optional
            Force at the TCP/plate [N]; default the gravity load :attr:`gravity_force`.
        {pose_options}

        Returns
        -------
        numpy.ndarray, shape (3,) or (N, 3)
            ``dT`` [m].

        {pose_raises}
        """
        return self._output(3, T, F, configuration, limits)

    @_pose_doc
    def gravity_deflection(self, T: np.typing.ArrayLike, configuration: int | Sequence[int] = 0, limits: bool = True) -> np.ndarray:
        """TCP deflection under the plate's own weight and the payload, ``K_x^-1 F_g``.

        {pose_parameters}
        {pose_options}

        Returns
        -------
        numpy.ndarray, shape (3,) or (N, 3)
            ``dT`` [m].

        {pose_raises}
        """
        return self.deflection(T, None, configuration, limits)

    def section_grid(self, x: float | None = None, step: float = 0.05, configuration: int | Sequence[int] = 0) -> np.ndarray:
        """TCP positions of a yz section of the workspace (a regular grid at fixed ``x``).

        Parameters
        ----------
        x : float, optional
            Section coordinate [m]; default the median ``x`` of a 0.1 m workspace grid.
        step : float, optional
            Grid spacing in y and z [m].
        configuration : int or sequence of int, optional
            IK configuration.

        Returns
        -------
        numpy.ndarray, shape (N, 3)
            Grid points inside the workspace [m].

        Raises
        ------
        InputError
            Non-positive step, or no grid point of the section lies in the workspace.
        """
        if not (isinstance(step, (int, float)) and np.isfinite(step) and step > 0):
            raise InputError(f"step: expected a positive spacing in m, got {step!r}")
        box = self.kinematics.workspace_bounds()
        x0 = float(np.median(self.kinematics.workspace_grid(0.1, configuration)[:, 0])) if x is None else float(x)
        ys = np.arange(box[1, 0], box[1, 1] + step / 2, step)
        zs = np.arange(box[2, 0], box[2, 1] + step / 2, step)
        Y, Z = np.meshgrid(ys, zs, indexing="ij")
        P = np.column_stack([np.full(Y.size, x0), Y.ravel(), Z.ravel()])
        P = P[self.kinematics.in_workspace(P, configuration)]
        if P.shape[0] == 0:
            raise InputError(f"no point of the section x = {x0} m (step {step} m) lies in the workspace")
        return P

    @_pose_doc
    def stiffness_map(self, T: np.typing.ArrayLike, configuration: int | Sequence[int] = 0, limits: bool = True) -> StiffnessMap:
        """Stiffness and gravity deflection over a set of poses (e.g. :meth:`section_grid`).

        Parameters
        ----------
        T : array_like, shape (N, 3)
            TCP positions [m].
        {pose_options}

        Returns
        -------
        StiffnessMap

        {pose_raises}
        """
        Tn, _ = _as_points(T, "T")
        (K, _, _, dT), _, _ = self._evaluate(Tn, None, configuration, limits)
        return StiffnessMap(Tn, K, dT, self.stiffness, self.payload_kg)


def plot_stiffness_map(
    smap: StiffnessMap,
    path: str | Path | None = None,
    quantity: str = "min",
    axes: tuple[int, int] = (1, 2),
    ax: Any = None,
    title: str = "",
) -> Any:
    """Colour map of a stiffness quantity over a workspace section, with the stated values.

    Parameters
    ----------
    smap : StiffnessMap
        From :meth:`GantryTau3Stiffness.stiffness_map`.
    path : str or pathlib.Path, optional
        Write the figure as PNG here.
    quantity : {"min", "x", "y", "z", "deflection"}, optional
        Smallest principal stiffness, stiffness along an axis [N/um], or the norm of the
        gravity deflection [um].
    axes : tuple of int, optional
        Coordinates on the plot axes (default ``(1, 2)``: a yz section).
    ax : matplotlib.axes.Axes, optional
        Draw into these axes (default: a new figure, not registered with pyplot).
    title : str, optional
        Title prefix.

    Returns
    -------
    matplotlib.figure.Figure

    Raises
    ------
    InputError
        Unknown quantity or axes.
    """
    values = {
        "min": lambda m: m.min_stiffness / N_PER_UM,
        "x": lambda m: m.axis_stiffness[:, 0] / N_PER_UM,
        "y": lambda m: m.axis_stiffness[:, 1] / N_PER_UM,
        "z": lambda m: m.axis_stiffness[:, 2] / N_PER_UM,
        "deflection": lambda m: np.linalg.norm(m.gravity_deflection, axis=1) * 1e6,
    }
    if quantity not in values:
        raise InputError(f"quantity: expected one of {', '.join(values)}, got {quantity!r}")
    if len(axes) != 2 or any(a not in (0, 1, 2) for a in axes) or axes[0] == axes[1]:
        raise InputError(f"axes: expected two different coordinates of 0, 1, 2, got {axes!r}")
    val = values[quantity](smap)
    if ax is None:
        from matplotlib.figure import Figure

        fig = Figure(figsize=(6.4, 5), layout="constrained")
        ax = fig.subplots()
    else:
        fig = ax.figure
    a, b = axes
    P = smap.T
    sc = ax.scatter(P[:, a], P[:, b], c=val, cmap="viridis", s=40, marker="s")
    label = "gravity deflection |dT| [um]" if quantity == "deflection" else (
        "smallest principal stiffness [N/um]" if quantity == "min" else f"stiffness along {quantity} [N/um]"
    )
    fig.colorbar(sc, ax=ax, label=label)
    ax.set_xlabel(f"{'xyz'[a]} [m]")
    ax.set_ylabel(f"{'xyz'[b]} [m]")
    ax.set_aspect("equal")
    lo, hi = MEASURED_D1_N_PER_UM
    import textwrap

    unit = "um" if quantity == "deflection" else "N/um"
    stated = textwrap.fill(f"stated: {smap.stiffness.describe()}, payload {smap.payload_kg:g} kg", 72)
    ax.set_title(
        f"{title + ': ' if title else ''}{label.split(' [')[0]}: {val.min():.3g}-{val.max():.3g} {unit}"
        + ("" if quantity == "deflection" else f"\n(D1 measured {lo:g}-{hi:g} N/um)")
        + f"\n{stated}",
        fontsize=8,
    )
    if path is not None:
        fig.savefig(path, dpi=110, bbox_inches="tight")
    return fig


# ----------------------------------------------------------------------------- any closure model
@dataclass
class ClosureStiffness:
    """Stiffness of a closure model at one pose, with the carts condensed out.

    Parameters
    ----------
    T : numpy.ndarray, shape (3,)
        TCP position [m].
    R : numpy.ndarray, shape (3, 3)
        Plate orientation.
    K : numpy.ndarray, shape (6, 6) or (3, 3)
        Stiffness in the plate coordinates ``(dT, dr)`` (position [m], rotation vector
        [rad]; units N/m, N, N m/rad), carts condensed; (3, 3) for a constant-orientation
        model.
    K_locked : numpy.ndarray, shape (3, 3)
        Translational stiffness with the plate rotation held (the 3-link model's assumption)
        [N/m].
    K_free : numpy.ndarray, shape (3, 3)
        Translational stiffness for a force at the TCP with the plate free to rotate
        (rotation condensed out) [N/m]; equals ``K_locked`` for a constant-orientation model.
    k_links : numpy.ndarray, shape (n_links,)
        Axial stiffness of each closure link [N/m].
    """

    T: np.ndarray
    R: np.ndarray
    K: np.ndarray
    K_locked: np.ndarray
    K_free: np.ndarray
    k_links: np.ndarray


def closure_stiffness(model: "ClosureModel", q: np.typing.ArrayLike, stiffness: StiffnessParameters | None = None) -> ClosureStiffness:
    """Static stiffness of any 3-actuator closure model (3-link or six-link), by condensation.

    The link lengths ``l_j = |A_j(q + sigma) - (T + Rot(r) R_T B0_j)|`` are differentiated
    (CasADi, the model's own :meth:`~gtmodel.robots.closure.ClosureModel.link_points`) with
    respect to the plate displacement ``x = (dT, r)`` and the cart displacements ``sigma``
    along the guideways, giving the compatibility matrix ``C = dl / d(x, sigma)``. With link
    stiffnesses ``k_l`` (tube ``E A / L_j`` in series with two joints; a 3-link model's link
    is a cluster of ``n_i`` links in parallel) and actuator stiffnesses ``k_a |dA/dq_i|^2``::

        K_full = C^T diag(k_l) C + diag(0, k_a),
        K      = K_xx - K_xs K_ss^-1 K_sx           (carts condensed)
        K_free = K_TT - K_Tr K_rr^-1 K_rT           (plate rotation condensed).

    For the 3-link model ``K`` reproduces eq. (1) with the series arm compliance (2) of the
    module docstring; for the six-link model (Dressler (2012), eq. 4.14) it adds the plate's
    rotational compliance that the translational model leaves out.

    Parameters
    ----------
    model : ClosureModel
        A model with 3 linear actuators (:class:`~gtmodel.robots.closure.ThreeLinkClosure`,
        :class:`~gtmodel.robots.six_link.SixLinkClosure`).
    q : array_like, shape (3,)
        Cart positions [m].
    stiffness : StiffnessParameters, optional
        Stiffness values (default: the shipped file).

    Returns
    -------
    ClosureStiffness

    Raises
    ------
    InputError
        A model with other than 3 actuators or arms, a link count per arm that matches
        neither 1 nor ``links_per_arm``, or a wrong ``q``.
    UnreachablePoseError
        The model cannot assemble at ``q``.
    """
    from gtmodel.robots.closure import ClosureModel, rotation_vector_to_rotation

    if not isinstance(model, ClosureModel) or model.n_q != 3 or len(model.links) != 3:
        raise InputError(f"model: expected a closure model with 3 linear actuators, got {getattr(model, 'name', model)!r}")
    qa = np.asarray(q, dtype=float)
    if qa.shape != (3,) or not np.all(np.isfinite(qa)):
        raise InputError(f"q: expected 3 finite cart positions [m], got {q!r}")
    st = load_stiffness("stiffness" if stiffness is None else stiffness)
    T0, R0 = model.fk(qa)
    T0, R0 = np.asarray(T0, float).reshape(3), np.asarray(R0, float).reshape(3, 3)
    p = ca.DM(model.parameter_vector())
    dT = ca.SX.sym("dT", 3)
    r = ca.SX.sym("r", 3)
    sig = ca.SX.sym("sigma", 3)
    qs = ca.SX.sym("q", 3)
    R = ca.mtimes(rotation_vector_to_rotation(r), ca.DM(R0))
    lengths, rest, k_links, k_act = [], [], [], []
    for arm, names in enumerate(model.links):
        n_arm = len(names)
        if n_arm == 1:
            n_par = int(st.links_per_arm[arm])
        elif n_arm == int(st.links_per_arm[arm]):
            n_par = 1
        else:
            raise InputError(f"{model.name}: arm {arm + 1} has {n_arm} links; expected 1 or {int(st.links_per_arm[arm])} (links_per_arm)")
        A, B, L = model.link_points(p, qs + ca.vertcat(*[sig[i] if i == arm else 0 for i in range(3)]), ca.DM(T0) + dT, R, arm)
        D = A - B
        lengths.append(ca.sqrt(ca.sum1(D * D)).T)
        Ln = np.array(ca.evalf(ca.substitute(L, qs, ca.DM(qa)))).reshape(-1)
        rest.append(Ln)
        k_links.append(n_par / (Ln / (st.E * st.link_area) + st.joints_per_link / st.k_joint))
        dA = ca.jacobian(A[:, 0], qs)[:, arm]
        k_act.append(st.k_actuator[arm] * float(ca.evalf(ca.substitute(ca.sumsqr(dA), qs, ca.DM(qa)))))
    ell = ca.vertcat(*lengths)
    orient = bool(model.orientation)
    x = ca.vertcat(dT, r) if orient else dT
    C_fun = ca.Function("C", [dT, r, sig, qs], [ca.jacobian(ell, ca.vertcat(x, sig)), ell])
    C, ell0 = (np.array(v) for v in C_fun(np.zeros(3), np.zeros(3), np.zeros(3), qa))
    if np.max(np.abs(ell0.ravel() - np.concatenate(rest))) > 1e-6:
        raise UnreachablePoseError(f"{model.name}: the model does not assemble at q = {qa.tolist()} (closure residual above 1 um)")
    kl = np.concatenate(k_links)
    Kf = C.T @ np.diag(kl) @ C
    nx = x.shape[0]
    Kf[nx:, nx:] += np.diag(k_act)
    Kxx, Kxs, Kss = Kf[:nx, :nx], Kf[:nx, nx:], Kf[nx:, nx:]
    K = Kxx - Kxs @ np.linalg.solve(Kss, Kxs.T)
    K = 0.5 * (K + K.T)
    if orient:
        KTT, KTr, Krr = K[:3, :3], K[:3, 3:], K[3:, 3:]
        K_free = KTT - KTr @ np.linalg.solve(Krr, KTr.T)
        K_locked = KTT
    else:
        K_free = K_locked = K
    return ClosureStiffness(T0, R0, K, K_locked, 0.5 * (K_free + K_free.T), kl)
