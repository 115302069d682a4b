"""Loading the F1 parameter file (:file:`data/F1.toml`, printed in mm, converted to SI)."""

from __future__ import annotations

import math
from importlib import resources
from pathlib import Path
from typing import Any, Mapping

import numpy as np

from gtmodel._toml import read_toml
from gtmodel.errors import ParameterError
from gtmodel.robots.f1.layout import _N_PARAMETERS, _OFFSET, F1_LINKS, F1Limits
from gtmodel.robots.f1.model import F1Closure

__all__ = ["load_f1"]

_DATA_PACKAGE = "gtmodel.robots"

class _Fields:
    """Field access with messages naming the file and the field."""

    def __init__(self, data: Mapping[str, Any], origin: str, prefix: str = "") -> None:
        self.data, self.origin, self.prefix = data, origin, prefix

    def fail(self, key: str, expected: str, got: Any = None) -> ParameterError:
        what = "" if got is None else f", got {got!r}"
        return ParameterError(f"{self.origin}: field '{self.prefix}{key}': expected {expected}{what}")

    def keys(self, allowed: set[str]) -> None:
        unknown = sorted(set(self.data) - allowed)
        if unknown:
            raise ParameterError(
                f"{self.origin}: unknown field '{self.prefix}{unknown[0]}' (allowed: {', '.join(sorted(allowed))})"
            )

    def table(self, key: str) -> "_Fields":
        if key not in self.data:
            raise ParameterError(f"{self.origin}: missing table '[{self.prefix}{key}]'")
        if not isinstance(self.data[key], Mapping):
            raise self.fail(key, "a table", self.data[key])
        return _Fields(self.data[key], self.origin, f"{self.prefix}{key}.")

    def string(self, key: str, default: str | None = None) -> str:
        if key not in self.data:
            if default is None:
                raise ParameterError(f"{self.origin}: missing field '{self.prefix}{key}'")
            return default
        if not isinstance(self.data[key], str):
            raise self.fail(key, "a string", self.data[key])
        return self.data[key]

    def array(self, key: str, shape: tuple[int, ...]) -> np.ndarray:
        if key not in self.data:
            raise ParameterError(f"{self.origin}: missing field '{self.prefix}{key}'")
        value = self.data[key]
        try:
            arr = np.array(value, dtype=float)
        except (TypeError, ValueError):
            raise self.fail(key, f"an array of numbers of shape {shape}", value) from None
        if arr.shape != shape or not np.all(np.isfinite(arr)):
            raise self.fail(key, f"finite numbers of shape {shape}", value)
        return arr

    def number(self, key: str) -> float:
        if key not in self.data:
            raise ParameterError(f"{self.origin}: missing field '{self.prefix}{key}'")
        value = self.data[key]
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
            raise self.fail(key, "a finite number", value)
        return float(value)

    def vectors(self, key: str, names: tuple[str, ...], size: int) -> dict[str, np.ndarray]:
        t = self.table(key)
        t.keys(set(names))
        return {n: t.array(n, (size,)) for n in names}


def _f1_from_mapping(data: Mapping[str, Any], origin: str) -> F1Closure:
    f = _Fields(data, origin)
    f.keys({"name", "description", "frame", "length_unit", "kinematics", "home", "limits"})
    unit = f.string("length_unit")
    if unit not in ("mm", "m"):
        raise f.fail("length_unit", "'mm' or 'm'", unit)
    s = 1e-3 if unit == "mm" else 1.0
    k = f.table("kinematics")
    k.keys({"source", "links", "L", "A0", "v", "q1u2", "q1u3", "r3", "q2u3", "Abj", "B0"})
    all_links = tuple(n for arm in F1_LINKS for n in arm)
    if "links" in k.data and list(k.data["links"]) != list(all_links):
        raise k.fail("links", f"{list(all_links)}", k.data["links"])
    L = k.array("L", (6,))
    if np.any(L <= 0):
        raise k.fail("L", "positive link lengths", L.tolist())
    A0 = k.vectors("A0", ("arm1", "arm2", "arm3"), 3)
    v = k.vectors("v", ("arm1", "arm2", "arm3"), 3)
    for arm, vv in v.items():
        if not 0.5 < np.linalg.norm(vv) < 2.0:
            raise ParameterError(
                f"{origin}: field 'kinematics.v.{arm}': expected a guideway direction of norm about 1 "
                f"(0.5 < |v| < 2), got {vv.tolist()}"
            )
    quats = {}
    for name in ("q1u2", "q1u3", "q2u3"):
        qv = k.array(name, (4,))
        nrm = np.linalg.norm(qv)
        if not 0.5 < nrm < 2.0:
            raise k.fail(name, "a quaternion (w, x, y, z) of norm about 1 (0.5 < |q| < 2)", qv.tolist())
        quats[name] = qv / nrm  # printed values are not unit: normalised at load
    r3 = k.array("r3", (3,))
    Abj = k.vectors("Abj", ("2a", "2b", "3a", "3b", "3c"), 3)
    B0 = k.vectors("B0", all_links, 3)
    Ld = dict(zip(all_links, L))
    values = {
        "L_1": Ld["1"] * s, "A0_1": A0["arm1"] * s, "v1": v["arm1"], "B0_1": B0["1"] * s,
        "A0_2": A0["arm2"] * s, "v2": v["arm2"], "q1u2": quats["q1u2"],
        "A0_3": A0["arm3"] * s, "v3": v["arm3"], "q1u3": quats["q1u3"], "r3": r3 * s, "q2u3": quats["q2u3"],
    }
    for n in all_links[1:]:
        values[f"L_{n}"] = Ld[n] * s
        values[f"Abj_{n}"] = Abj[n] * s
        values[f"B0_{n}"] = B0[n] * s
    p = np.zeros(_N_PARAMETERS)
    for name, (i, n) in _OFFSET.items():
        p[i:i + n] = values[name]
    h = f.table("home")
    h.keys({"source", "cart_positions", "joint_plate_angles_deg"})
    q_home = np.concatenate([h.array("cart_positions", (3,)) * s, np.radians(h.array("joint_plate_angles_deg", (3,)))])
    lt = f.table("limits")
    lt.keys({"source", "cart_travel", "joint_plate_angles_deg", "ball_joint_angle_max_deg", "reorientation_range_deg",
             "position_error_amplification_max", "orientation_error_amplification_max_deg_per_mm",
             "joint_plate_amplification_max"})
    travel = lt.array("cart_travel", (3, 2)) * s
    plate = np.radians(lt.array("joint_plate_angles_deg", (3, 2)))
    for key, arr in (("cart_travel", travel), ("joint_plate_angles_deg", plate)):
        if np.any(arr[:, 0] >= arr[:, 1]):
            raise lt.fail(key, "rows (min, max) with min < max", lt.data[key])
    ball = lt.number("ball_joint_angle_max_deg")
    if not 0 < ball < 90:
        raise lt.fail("ball_joint_angle_max_deg", "an angle in (0, 90) degrees", ball)
    reo = lt.array("reorientation_range_deg", (3,))
    if np.any(reo < 0) or np.any(reo >= 90):
        raise lt.fail("reorientation_range_deg", "three angles in [0, 90) degrees", reo.tolist())
    amp = np.array([lt.number("position_error_amplification_max"), lt.number("orientation_error_amplification_max_deg_per_mm")])
    if np.any(amp <= 0):
        raise lt.fail("position_error_amplification_max" if amp[0] <= 0 else "orientation_error_amplification_max_deg_per_mm",
                      "a positive number", float(amp[0] if amp[0] <= 0 else amp[1]))
    amp[1] = math.radians(amp[1]) * 1e3  # deg/mm -> rad/m
    plate_amp = lt.number("joint_plate_amplification_max")
    if plate_amp <= 0:
        raise lt.fail("joint_plate_amplification_max", "a positive number", plate_amp)
    rng = np.vstack([travel, plate])
    if np.any(q_home < rng[:, 0]) or np.any(q_home > rng[:, 1]):
        raise ParameterError(f"{origin}: table '[home]': the home actuator values lie outside the limits of '[limits]'")
    limits = F1Limits(cart_travel=travel, joint_plate_range=plate, ball_joint_angle_max=math.radians(ball),
                      reorientation_range=np.radians(reo), error_amplification_max=amp,
                      joint_plate_amplification_max=plate_amp, source=lt.string("source", default=""))
    return F1Closure(p, q_home, limits, name=f.string("name"), source=k.string("source", default=""))


def load_f1(name_or_path: str | Path = "F1") -> F1Closure:
    """Load and validate an F1 parameter file (shipped name ``"F1"`` or a path).

    The shipped :file:`F1.toml` holds Dressler (2012), Table 5.5 in mm as printed
    (``length_unit = "mm"``); lengths are converted to metres and the printed, non-unit
    quaternions normalised at load. ``v`` is kept as printed (``|v| = 0.99``, a
    gear-ratio correction).

    Parameters
    ----------
    name_or_path : str or pathlib.Path, optional
        ``"F1"`` or the path of a TOML file in the same format.

    Returns
    -------
    F1Closure
        The model with its home pose and limits.

    Raises
    ------
    ParameterError
        Unknown name, unreadable file, TOML syntax error, or an invalid field (the
        message names the file and the field).
    """
    text_name = str(name_or_path)
    if isinstance(name_or_path, str) and text_name == "F1":
        resource = resources.files(_DATA_PACKAGE) / "data" / "F1.toml"
        origin = "F1.toml (shipped)"
        data = read_toml(Path(str(resource)), ParameterError, "F1 parameter file", origin, resource.read_text(encoding="utf-8"))
    else:
        path = Path(name_or_path)
        if path.suffix != ".toml" and not path.exists():
            raise ParameterError(f"unknown F1 parameter set {text_name!r}: not 'F1' (shipped) and no such file")
        origin = str(path)
        data = read_toml(path, ParameterError, "F1 parameter file")
    return _f1_from_mapping(data, origin)