"""Robot parameter sets: TOML files shipped with the package, loaded and validated.

A parameter set holds the kinematic parameters of the 3-link Gantry-Tau model
(Dressler (2012), eq. 4.9), the rigid-body and friction parameters of the dynamic
model (Dressler (2012), eqs. 6.7-6.8, Tables 6.1 and 6.3) and the motion limits.
Every field is validated on load; an error names the file and the field.
"""

from __future__ import annotations

import math
import tomllib
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from typing import Any, Mapping

import numpy as np

from gtmodel._toml import read_toml
from gtmodel.errors import ParameterError

__all__ = [
    "KinematicParameters",
    "FrictionParameters",
    "DynamicParameters",
    "Limits",
    "RobotParameters",
    "available_parameter_sets",
    "load_parameters",
    "parameters_from_mapping",
]

_DATA_PACKAGE = "gtmodel.robots"


@dataclass(frozen=True)
class KinematicParameters:
    """Kinematic parameters of the simplified 3-link Gantry-Tau model.

    Dressler (2012), eqs. 4.7-4.9: ``L_i^2 = ||As_i + q_i v_i - T||^2``.

    Parameters
    ----------
    L : numpy.ndarray, shape (3,)
        Link lengths [m].
    As : numpy.ndarray, shape (3, 3)
        Row i is the joint point of arm i at ``q_i = 0`` [m].
    v : numpy.ndarray, shape (3, 3)
        Row i is the guideway direction of arm i (dimensionless; ``|v_i| != 1``
        absorbs a gear-ratio correction). In the "ideal" model all rows are equal.
    model : str
        ``"ideal"`` (15 parameters, one common ``v``) or ``"modified"`` (21 parameters,
        one ``v_i`` per guideway).
    source : str
        Where the numbers come from.
    """

    L: np.ndarray
    As: np.ndarray
    v: np.ndarray
    model: str = "modified"
    source: str = ""

    @property
    def n_parameters(self) -> int:
        """Number of free kinematic parameters (15 ideal, 21 modified)."""
        return 15 if self.model == "ideal" else 21


@dataclass(frozen=True)
class FrictionParameters:
    """Asymmetric Coulomb + viscous cart friction, Dressler (2012), Table 6.1.

    Parameters
    ----------
    f_c_plus, f_c_minus : numpy.ndarray, shape (3,)
        Coulomb friction [N] for positive / negative cart velocity (both positive numbers).
    f_v_plus, f_v_minus : numpy.ndarray, shape (3,)
        Viscous friction [N s/m] for positive / negative cart velocity.
    source : str
        Where the numbers come from.
    """

    f_c_plus: np.ndarray
    f_c_minus: np.ndarray
    f_v_plus: np.ndarray
    f_v_minus: np.ndarray
    source: str = ""


@dataclass(frozen=True)
class DynamicParameters:
    """Point-mass rigid-body model with cart friction, Dressler (2012), eqs. 6.7-6.8.

    Parameters
    ----------
    m_p : float
        Plate (end-effector) mass [kg].
    m_c : numpy.ndarray, shape (3,)
        Cart masses [kg].
    m_a : numpy.ndarray, shape (3,)
        Link-cluster masses [kg], each lumped at the link midpoint.
    f_c : numpy.ndarray, shape (3,)
        Symmetric Coulomb friction [N].
    f_v : numpy.ndarray, shape (3,)
        Symmetric viscous friction [N s/m].
    g : float
        Gravitational acceleration [m/s^2], acting along -z.
    asymmetric : FrictionParameters or None
        Asymmetric friction (Table 6.1), if given.
    assumed : bool
        True when the values are an assumption rather than identified on this robot.
    source : str
        Where the numbers come from.
    """

    m_p: float
    m_c: np.ndarray
    m_a: np.ndarray
    f_c: np.ndarray
    f_v: np.ndarray
    g: float = 9.81
    asymmetric: FrictionParameters | None = None
    assumed: bool = False
    source: str = ""


@dataclass(frozen=True)
class Limits:
    """Motion limits of the robot.

    Parameters
    ----------
    cart_travel : numpy.ndarray, shape (3, 2)
        Row i is ``(q_min, q_max)`` of cart i [m].
    joint_angle_max : float
        Largest angle between a link and its guideway direction [rad] (spherical-joint limit).
    source : str
        Where the numbers come from.
    """

    cart_travel: np.ndarray
    joint_angle_max: float
    source: str = ""


@dataclass(frozen=True)
class RobotParameters:
    """A complete, validated Gantry-Tau parameter set.

    Parameters
    ----------
    name : str
        Short name, e.g. ``"L1"``.
    description : str
        One line describing the robot and the model.
    frame : str
        The coordinate frame the parameters are expressed in.
    kinematics : KinematicParameters
        3-link kinematic parameters.
    dynamics : DynamicParameters
        Rigid-body and friction parameters.
    limits : Limits
        Cart travel and spherical-joint limits.
    path : pathlib.Path or None
        File the set was loaded from (None for a mapping).
    """

    name: str
    description: str
    frame: str
    kinematics: KinematicParameters
    dynamics: DynamicParameters
    limits: Limits
    path: Path | None = field(default=None, compare=False)


# ----------------------------------------------------------------------------- helpers
class _Reader:
    """Validates fields of a nested mapping and builds messages naming file and field."""

    def __init__(self, data: Mapping[str, Any], origin: str, prefix: str = "") -> None:
        self.data = data
        self.origin = origin
        self.prefix = prefix

    def _name(self, key: str) -> str:
        return f"{self.prefix}{key}"

    def error(self, key: str, expected: str, got: Any = None) -> ParameterError:
        what = "" if got is None else f", got {got!r}"
        return ParameterError(f"{self.origin}: field '{self._name(key)}': expected {expected}{what}")

    def check_keys(self, allowed: set[str]) -> None:
        unknown = sorted(set(self.data) - allowed)
        if unknown:
            raise ParameterError(
                f"{self.origin}: unknown field '{self._name(unknown[0])}' (allowed: {', '.join(sorted(allowed))})"
            )

    def sub(self, key: str, required: bool = True) -> "_Reader | None":
        if key not in self.data:
            if required:
                raise ParameterError(f"{self.origin}: missing table '[{self._name(key)}]'")
            return None
        value = self.data[key]
        if not isinstance(value, Mapping):
            raise self.error(key, "a table", value)
        return _Reader(value, self.origin, prefix=f"{self._name(key)}.")

    def string(self, key: str, default: str | None = None) -> str:
        if key not in self.data:
            if default is None:
                raise ParameterError(f"{self.origin}: missing field '{self._name(key)}'")
            return default
        value = self.data[key]
        if not isinstance(value, str):
            raise self.error(key, "a string", value)
        return value

    def boolean(self, key: str, default: bool) -> bool:
        value = self.data.get(key, default)
        if not isinstance(value, bool):
            raise self.error(key, "true or false", value)
        return value

    def number(self, key: str, positive: bool = False, nonnegative: bool = False, default: float | None = None) -> float:
        if key not in self.data:
            if default is None:
                raise ParameterError(f"{self.origin}: missing field '{self._name(key)}'")
            return float(default)
        value = self.data[key]
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
            raise self.error(key, "a finite number", value)
        if positive and value <= 0:
            raise self.error(key, "a positive number", value)
        if nonnegative and value < 0:
            raise self.error(key, "a non-negative number", value)
        return float(value)

    def array(self, key: str, shape: tuple[int, ...], nonnegative: bool = False, positive: bool = False) -> np.ndarray:
        if key not in self.data:
            raise ParameterError(f"{self.origin}: missing field '{self._name(key)}'")
        value = self.data[key]
        try:
            arr = np.array(value, dtype=float)
        except (TypeError, ValueError):
            raise self.error(key, f"an array of numbers of shape {shape}", value) from None
        if arr.shape != shape:
            raise self.error(key, f"an array of shape {shape}", value)
        if not np.all(np.isfinite(arr)):
            raise self.error(key, "finite numbers", value)
        if positive and np.any(arr <= 0):
            raise self.error(key, "positive numbers", value)
        if nonnegative and np.any(arr < 0):
            raise self.error(key, "non-negative numbers", value)
        arr.setflags(write=False)
        return arr


def _read_data_file(name_or_path: str | Path, what: str, unknown: str, any_suffix_must_exist: bool = False) -> tuple[dict[str, Any], str, Path]:
    """Parse a data file shipped in ``gtmodel/robots/data`` (by bare name) or at a path.

    A ``str`` without ``/`` and ``.toml`` naming a shipped ``<name>.toml`` is that file
    (``origin`` ``"<name>.toml (shipped)"``); anything else is a path. A missing path raises
    ``ParameterError("unknown {what} {name!r}: {unknown}")``: only without the ``.toml``
    suffix, or always with ``any_suffix_must_exist`` (otherwise :func:`read_toml` says the
    file cannot be read).

    Parameters
    ----------
    name_or_path : str or pathlib.Path
        Shipped name or path.
    what : str
        What the file is, for messages (e.g. ``"dynamics-models file"``).
    unknown : str
        End of the message for an unknown name (e.g. ``"not a shipped name and no such file"``).
    any_suffix_must_exist : bool, optional
        Check the existence of ``.toml`` paths too.

    Returns
    -------
    data : dict
        The parsed document.
    origin : str
        Name of the file in messages.
    path : pathlib.Path
        The file.

    Raises
    ------
    ParameterError
        Unknown name, unreadable file or TOML syntax error.
    """
    text_name = str(name_or_path)
    resource = resources.files(_DATA_PACKAGE) / "data" / f"{text_name}.toml"
    if isinstance(name_or_path, str) and "/" not in text_name and not text_name.endswith(".toml") and resource.is_file():
        origin = f"{text_name}.toml (shipped)"
        path = Path(str(resource))
        return read_toml(path, ParameterError, what, origin, resource.read_text(encoding="utf-8")), origin, path
    path = Path(name_or_path)
    if (any_suffix_must_exist or path.suffix != ".toml") and not path.exists():
        raise ParameterError(f"unknown {what} {text_name!r}: {unknown}")
    return read_toml(path, ParameterError, what), str(path), path


def _kinematics(r: _Reader) -> KinematicParameters:
    r.check_keys({"source", "model", "L", "As", "v"})
    model = r.string("model", default="modified")
    if model not in ("ideal", "modified"):
        raise r.error("model", "'ideal' or 'modified'", model)
    L = r.array("L", (3,), positive=True)
    As = r.array("As", (3, 3))
    if model == "ideal":
        v1 = r.array("v", (3,))
        v = np.array([v1, v1, v1])
        v.setflags(write=False)
    else:
        v = r.array("v", (3, 3))
    norms = np.linalg.norm(v, axis=1)
    if np.any(norms < 0.5) or np.any(norms > 2.0):
        raise r.error("v", "guideway directions of norm about 1 (0.5 < |v_i| < 2)", v.tolist())
    return KinematicParameters(L=L, As=As, v=v, model=model, source=r.string("source", default=""))


def _dynamics(r: _Reader) -> DynamicParameters:
    r.check_keys({"source", "assumed", "m_p", "m_c", "m_a", "f_c", "f_v", "g", "asymmetric_friction"})
    asym = None
    ar = r.sub("asymmetric_friction", required=False)
    if ar is not None:
        ar.check_keys({"source", "f_c_plus", "f_c_minus", "f_v_plus", "f_v_minus"})
        asym = FrictionParameters(
            f_c_plus=ar.array("f_c_plus", (3,), nonnegative=True),
            f_c_minus=ar.array("f_c_minus", (3,), nonnegative=True),
            f_v_plus=ar.array("f_v_plus", (3,), nonnegative=True),
            f_v_minus=ar.array("f_v_minus", (3,), nonnegative=True),
            source=ar.string("source", default=""),
        )
    return DynamicParameters(
        m_p=r.number("m_p", positive=True),
        m_c=r.array("m_c", (3,), nonnegative=True),
        m_a=r.array("m_a", (3,), nonnegative=True),
        f_c=r.array("f_c", (3,), nonnegative=True),
        f_v=r.array("f_v", (3,), nonnegative=True),
        g=r.number("g", nonnegative=True, default=9.81),
        asymmetric=asym,
        assumed=r.boolean("assumed", False),
        source=r.string("source", default=""),
    )


def _limits(r: _Reader) -> Limits:
    r.check_keys({"source", "cart_travel", "joint_angle_max_deg"})
    travel = r.array("cart_travel", (3, 2))
    if np.any(travel[:, 0] >= travel[:, 1]):
        raise r.error("cart_travel", "rows (q_min, q_max) with q_min < q_max", travel.tolist())
    angle = r.number("joint_angle_max_deg", positive=True)
    if angle >= 90.0:
        raise r.error("joint_angle_max_deg", "an angle below 90 degrees", angle)
    return Limits(cart_travel=travel, joint_angle_max=math.radians(angle), source=r.string("source", default=""))


def parameters_from_mapping(data: Mapping[str, Any], origin: str = "<mapping>", path: Path | None = None) -> RobotParameters:
    """Validate a parsed parameter file and build a :class:`RobotParameters`.

    Parameters
    ----------
    data : Mapping[str, Any]
        The parsed TOML document (tables ``kinematics``, ``dynamics``, ``limits`` and
        top-level ``name``, ``description``, ``frame``).
    origin : str, optional
        Name used in error messages (usually the file path).
    path : pathlib.Path or None, optional
        Recorded as :attr:`RobotParameters.path`.

    Returns
    -------
    RobotParameters
        The validated parameter set.

    Raises
    ------
    ParameterError
        A field is missing, unknown, of the wrong type or shape, or out of range; the
        message names ``origin`` and the field.
    """
    r = _Reader(data, origin)
    r.check_keys({"name", "description", "frame", "kinematics", "dynamics", "limits"})
    return RobotParameters(
        name=r.string("name"),
        description=r.string("description", default=""),
        frame=r.string("frame", default=""),
        kinematics=_kinematics(r.sub("kinematics")),
        dynamics=_dynamics(r.sub("dynamics")),
        limits=_limits(r.sub("limits")),
        path=path,
    )


def available_parameter_sets() -> list[str]:
    """Names of the 3-link parameter sets shipped with gtmodel (kinematics + dynamics).

    Data files of other models (six-link, F1) in the same folder have their own loaders
    and are not listed.

    Returns
    -------
    list of str
        E.g. ``["D1", "L1", "L1_ideal"]``.
    """
    folder = resources.files(_DATA_PACKAGE) / "data"
    names = []
    for p in folder.iterdir():
        if p.name.endswith(".toml"):
            data = tomllib.loads(p.read_text(encoding="utf-8"))
            if "kinematics" in data and "dynamics" in data:
                names.append(p.name[:-5])
    return sorted(names)


def load_parameters(name_or_path: str | Path) -> RobotParameters:
    """Load and validate a robot parameter set by name (``"L1"``, ``"D1"``) or by path.

    Parameters
    ----------
    name_or_path : str or pathlib.Path
        A shipped set's name (see :func:`available_parameter_sets`) or the path of a TOML
        file in the same format.

    Returns
    -------
    RobotParameters
        The validated parameter set.

    Raises
    ------
    ParameterError
        Unknown name, unreadable file, TOML syntax error, or an invalid field (the message
        names the file and the field).
    """
    if isinstance(name_or_path, RobotParameters):
        return name_or_path
    text_name = str(name_or_path)
    if isinstance(name_or_path, str) and text_name in available_parameter_sets():
        resource = resources.files(_DATA_PACKAGE) / "data" / f"{text_name}.toml"
        path = Path(str(resource))
        data = read_toml(path, ParameterError, "parameter file", f"{text_name}.toml (shipped)", resource.read_text(encoding="utf-8"))
        origin = f"{text_name}.toml (shipped)"
    else:
        path = Path(name_or_path)
        if path.suffix != ".toml" and not path.exists():
            raise ParameterError(
                f"unknown parameter set {text_name!r}: not a shipped set ({', '.join(available_parameter_sets())}) and no such file"
            )
        origin = str(path)
        data = read_toml(path, ParameterError, "parameter file")
    return parameters_from_mapping(data, origin=origin, path=path)
