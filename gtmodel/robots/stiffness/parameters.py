"""Stiffness values (:class:`StiffnessParameters`) and their data file (:func:`load_stiffness`)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing  # noqa: F401  (np.typing in annotations)

from gtmodel._docstrings import fill_doc
from gtmodel._toml import read_toml
from gtmodel.errors import InputError, ParameterError

__all__ = ["StiffnessParameters", "load_stiffness", "MEASURED_D1_N_PER_UM", "N_PER_UM"]

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
_lengths_doc = fill_doc(lengths_parameters=_LENGTHS_PARAMETERS, lengths_raises=_LENGTHS_RAISES)


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
