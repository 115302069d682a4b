"""Loading six-link parameter files (:file:`data/D1_six_link.toml` and user files)."""

from __future__ import annotations

from importlib import resources
from pathlib import Path
from typing import Any, Mapping, Sequence

import numpy as np

from gtmodel._geometry import zyz_to_rotation
from gtmodel._toml import read_toml
from gtmodel.errors import InputError, ParameterError
from gtmodel.robots.parameters import _limits, _Reader
from gtmodel.robots.six_link.layout import _LINK_NAMES, estimate_nominal_orientation
from gtmodel.robots.six_link.model import SixLinkClosure

__all__ = ["load_six_link"]

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
