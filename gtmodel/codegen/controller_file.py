"""The controller file: the Kalman step and the learned ILC table of a run, for ``gtmodel codegen --controller``.

A controller file carries what :class:`~gtmodel.codegen.controller.Controller` holds, so that
the C of the loop can be generated from the result of an ILC run
(``gtmodel codegen --robot L1 --controller results/l1_ilc/controller.json --out DIR``).
Two encodings with the same keys: JSON (``.json``, human-readable; floats written with 17
significant digits, exact) or a NumPy archive (``.npz``, read with ``allow_pickle=False``).

========================  ========================================================  ===========
key                       value                                                     required
========================  ========================================================  ===========
``format``                ``"gtmodel.controller/1"``                                yes
``dt``                    sample time of the loop [s], positive (4 ms on the L1)    yes
``kalman_step``           the CasADi Function ``"kalman_step"(x, y) -> (x_next,     no
                          z_hat)`` serialised by ``casadi.Function.serialize()``
                          (string; e.g. ``StationaryKalman(...).step_function()``)
``ilc_correction``        the CasADi Function ``"ilc_correction"(k) -> u``          with
                          serialised (string; ``ilc_correction_function(table)``)   ``ilc_table``
``ilc_table``             the learned correction ``(N, d)`` [m] the Function        with
                          looks up (JSON: a list of N rows of d numbers)            ``ilc_correction``
``kf_step``               the KF step of the tracker + IMU fusion ``"kf_step"(x,    no
                          P, z) -> (x_next, P_next, pivots)`` serialised
                          (``KalmanFilter(...).step_function()``)
``ekf_step``              the EKF step of the 19-D model, same signature            no
                          (``ExtendedKalmanFilter(...).step_function()``)
``lead_through_step``     the lead-through controller step ``"lead_through_step"    no
                          (x, F_h, F_t, n_n) -> (x_next, V_tool, n, valid)``
                          serialised (``LeadThroughLaw(...).step_function()``)
``description``           free text (what run, which case)                          no
========================  ========================================================  ===========

At least one of ``kalman_step``, ``ilc_correction``, ``kf_step``, ``ekf_step`` and ``lead_through_step`` must be
present. For the filters ``dt`` is the sensors' sample time (0.001 at 1 kHz). The Functions are
stored themselves, not rebuilt from matrices: the C is generated from the very graph the
Python estimation ran (the serialisation is CasADi's; a file written by another CasADi
version may not load: regenerate it). On loading every key is validated; an error names
the file and the key.

Writing the filters of the fusion (``gtmodel codegen --controller fusion.json --out DIR``
then generates them alone, without robot functions)::

    save_controller("fusion.json", Controller(kf_step=kf.step_function(),
                                              ekf_step=ekf.step_function(), dt=0.001))

Writing from an ILC run (the ``ilc`` problem kind)::

    save_controller(out / "controller.json", Controller(
        kalman_step=kalman.step_function(),
        ilc_correction=ilc_correction_function(u_table), ilc_table=u_table))
"""

from __future__ import annotations

import json
import math
import zipfile
from pathlib import Path
from typing import Any

import casadi as ca
import numpy as np

from gtmodel.codegen.controller import Controller
from gtmodel.errors import InputError

__all__ = ["CONTROLLER_FORMAT", "CONTROLLER_KEYS", "save_controller", "load_controller"]

#: Value of the ``format`` key.
CONTROLLER_FORMAT = "gtmodel.controller/1"
#: Every key a controller file may hold.
CONTROLLER_KEYS = ("format", "dt", "kalman_step", "ilc_correction", "ilc_table", "kf_step", "ekf_step", "lead_through_step", "description")
#: Keys holding a serialised CasADi Function.
_FUNCTION_KEYS = ("kalman_step", "ilc_correction", "kf_step", "ekf_step", "lead_through_step")
_SUFFIXES = (".json", ".npz")
#: Largest controller file, and largest unpacked content of an ``.npz`` one [bytes] (checked before reading).
MAX_BYTES = 100_000_000


def _suffix(path: Path) -> str:
    if path.suffix.lower() not in _SUFFIXES:
        raise InputError(f"controller file {path}: expected a .json or .npz file, got suffix {path.suffix!r}")
    return path.suffix.lower()


def save_controller(path: str | Path, controller: Controller, description: str = "") -> Path:
    """Write a controller file (JSON or NPZ by the suffix of ``path``).

    Parameters
    ----------
    path : str or pathlib.Path
        ``*.json`` or ``*.npz`` (parent folder must exist).
    controller : Controller
        The functions and the learned table.
    description : str, optional
        Free text stored under ``description``.

    Returns
    -------
    pathlib.Path
        The written file.

    Raises
    ------
    InputError
        Another suffix, ``controller`` not a Controller, or the file cannot be written.
    """
    path = Path(path)
    kind = _suffix(path)
    if not isinstance(controller, Controller):
        raise InputError(f"controller: expected a gtmodel.codegen.Controller, got {type(controller).__name__}")
    data: dict[str, Any] = {"format": CONTROLLER_FORMAT, "dt": controller.dt}
    for key in ("kalman_step", "kf_step", "ekf_step", "lead_through_step"):
        if getattr(controller, key) is not None:
            data[key] = getattr(controller, key).serialize()
    if controller.ilc_correction is not None:
        data["ilc_correction"] = controller.ilc_correction.serialize()
        data["ilc_table"] = np.asarray(controller.ilc_table, dtype=float)
    if description:
        data["description"] = str(description)
    try:
        if kind == ".json":
            if "ilc_table" in data:
                data["ilc_table"] = data["ilc_table"].tolist()
            path.write_text(json.dumps(data, indent=1) + "\n", encoding="utf-8")
        else:
            with path.open("wb") as fh:
                np.savez(fh, **{k: np.asarray(v) for k, v in data.items()})
    except OSError as exc:
        raise InputError(f"controller file {path}: cannot write ({exc.strerror or exc})") from None
    return path


def _read(path: Path) -> dict[str, Any]:
    kind = _suffix(path)
    if not path.is_file():
        raise InputError(f"controller file {path}: not found")
    try:
        size = path.stat().st_size
        if kind == ".npz" and zipfile.is_zipfile(path):  # the arrays' unpacked size, as the archive declares it
            with zipfile.ZipFile(path) as zf:
                size = max(size, sum(i.file_size for i in zf.infolist()))
        if size > MAX_BYTES:
            raise InputError(f"controller file {path}: {size} bytes (unpacked), expected at most {MAX_BYTES}")
        if kind == ".json":
            data = json.loads(path.read_text(encoding="utf-8"))
            if not isinstance(data, dict):
                raise InputError(f"controller file {path}: expected a JSON object with keys {', '.join(CONTROLLER_KEYS)}")
            return data
        with np.load(path, allow_pickle=False) as z:
            return {k: z[k] for k in z.files}
    except InputError:
        raise
    except (OSError, ValueError, UnicodeDecodeError, zipfile.BadZipFile) as exc:
        raise InputError(f"controller file {path}: cannot read it as {kind[1:].upper()} ({str(exc)[:200]})") from None


def _string(path: Path, data: dict, key: str) -> str:
    v = data[key]
    if isinstance(v, np.ndarray) and v.ndim == 0 and v.dtype.kind == "U":
        v = str(v)
    if not isinstance(v, str):
        raise InputError(f"controller file {path}: key {key!r}: expected a string, got {type(v).__name__}")
    return v


def _function(path: Path, data: dict, key: str) -> ca.Function:
    text = _string(path, data, key)
    try:
        return ca.Function.deserialize(text)
    except Exception as exc:  # noqa: BLE001 - CasADi raises RuntimeError or others
        first = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
        raise InputError(
            f"controller file {path}: key {key!r}: not a serialised CasADi Function readable by CasADi "
            f"{ca.__version__} ({first}); write the file again with save_controller"
        ) from None


def load_controller(path: str | Path) -> Controller:
    """Read and validate a controller file.

    Parameters
    ----------
    path : str or pathlib.Path
        A ``.json`` or ``.npz`` file with the keys of :data:`CONTROLLER_KEYS` (see the
        module docstring).

    Returns
    -------
    Controller
        The Functions, the learned table and the sample time.

    Raises
    ------
    InputError
        Naming the file and the key: missing file, unreadable JSON/NPZ, unknown or missing
        key, wrong ``format``, ``dt`` not a positive number, a Function that does not
        deserialise or has another signature, an ``ilc_table`` that is not ``(N, d)``
        finite or does not match ``ilc_correction``.
    """
    path = Path(path)
    data = _read(path)
    unknown = [k for k in data if k not in CONTROLLER_KEYS]
    if unknown:
        raise InputError(f"controller file {path}: unknown key {unknown[0]!r} (allowed: {', '.join(CONTROLLER_KEYS)})")
    for key in ("format", "dt"):
        if key not in data:
            raise InputError(f"controller file {path}: missing key {key!r}")
    fmt = _string(path, data, "format")
    if fmt != CONTROLLER_FORMAT:
        raise InputError(f"controller file {path}: key 'format': expected {CONTROLLER_FORMAT!r}, got {fmt!r}")
    dt = data["dt"]
    dt = dt.item() if isinstance(dt, np.ndarray) and dt.ndim == 0 and dt.dtype.kind in "fi" else dt
    if isinstance(dt, bool) or not isinstance(dt, (int, float)) or not (math.isfinite(dt) and dt > 0):
        raise InputError(f"controller file {path}: key 'dt': expected a positive sample time [s], got {dt!r}")
    if not any(k in data for k in _FUNCTION_KEYS):
        raise InputError(f"controller file {path}: expected at least one of the keys {', '.join(map(repr, _FUNCTION_KEYS))}")
    for a, b in (("ilc_correction", "ilc_table"), ("ilc_table", "ilc_correction")):
        if a in data and b not in data:
            raise InputError(f"controller file {path}: key {a!r} needs the key {b!r}")
    if "description" in data:
        _string(path, data, "description")
    kw: dict[str, Any] = {"dt": float(dt)}
    for key in ("kalman_step", "kf_step", "ekf_step", "lead_through_step"):
        if key in data:
            kw[key] = _function(path, data, key)
    if "ilc_correction" in data:
        kw["ilc_correction"] = _function(path, data, "ilc_correction")
        try:
            table = np.asarray(data["ilc_table"], dtype=float)
        except (TypeError, ValueError):
            raise InputError(f"controller file {path}: key 'ilc_table': expected an (N, d) array of numbers") from None
        if table.ndim != 2 or table.shape[0] < 1 or not np.all(np.isfinite(table)):
            raise InputError(f"controller file {path}: key 'ilc_table': expected an (N, d) array of finite numbers, got shape {table.shape}")
        kw["ilc_table"] = table
    try:
        return Controller(**kw)
    except InputError as exc:
        key = str(exc).split(":", 1)[0]
        key = key if key in CONTROLLER_KEYS else "controller"
        raise InputError(f"controller file {path}: key {key!r}: {str(exc).split(':', 1)[-1].strip()}") from None
