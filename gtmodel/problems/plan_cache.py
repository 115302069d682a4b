"""The plan cache: the reference problem of a loop-controller file solved once, its plan reused while nothing it depends on changed.

``gtmodel codegen mpc`` and ``gtmodel codegen tracking`` plan the ``[reference] problem`` of
their file (with its ``overrides``) before they build the controller
(:func:`gtmodel.problems.loop_file.loop_reference`); the solve of a user model's
``optimal_control`` or ``optimica`` problem is the slow part of the run (tens of CPU-s). What
:func:`planned` keeps of it is what the loop-controller file reads: the status, the
verification's verdict (``passed``, ``message``), the times, the states and inputs by name and
the model's parameter values. A robot's ``point_to_point`` reference is solved every time.

The key (:func:`plan_key`, sha256) is over everything the plan depends on that gtmodel can
name: the problem file's bytes, the canonical JSON of the overrides, the bytes of every file
the problem (overrides applied) names (its model file, data files, an initial guess's table:
every string value of the document that names an existing regular file, absolute or relative
to the problem file; ``FILE:CLASS`` is read as ``FILE``), gtmodel's version and a digest of
its source files, CasADi's version (IPOPT is CasADi's own build), NumPy's,
the session's :data:`gtmodel.defaults.defaults` (solver options, tolerances) and
:data:`FORMAT`. A file the model imports from elsewhere is not in the key: ``--replan``
solves again.

An entry is ``<key>.json`` in :func:`cache_dir` (``$GTMODEL_CACHE_DIR/plans``, else
``$XDG_CACHE_HOME/gtmodel/plans``, else ``~/.cache/gtmodel/plans``), written to a temporary
file in the same folder and renamed into place, with a checksum of its contents. Only a
solve that ended with a solution is stored (``optimal``, ``acceptable``, ``check_failed``:
an unverified one is refused or accepted again by its stored verdict, exactly as it was).
An entry that cannot be read, is larger than :data:`MAX_ENTRY_BYTES`, fails its checksum
or is inconsistent (arrays not one row per time, a name missing) is ignored with a warning
and the problem solved again; a folder that cannot be written is warned about and the run
goes on without the cache.
"""

from __future__ import annotations

import hashlib
import json
import logging
import os
import tempfile
import tomllib
from dataclasses import dataclass, field
from functools import lru_cache
from pathlib import Path
from typing import Any, Callable, Collection, Mapping

import casadi as ca
import numpy as np

from gtmodel import __version__
from gtmodel._compiler import cache_dir as compiled_cache_dir
from gtmodel.defaults import defaults
from gtmodel.errors import GtModelError
from gtmodel.problems.base import _SPECIAL, data_dirs
from gtmodel.problems.loop_bounds import SOLVED
from gtmodel.problems.overrides import apply_override

__all__ = ["CACHE_ENV", "FORMAT", "MAX_ENTRY_BYTES", "MAX_HASHED_BYTES", "CachedPlan", "CachedVerification", "cache_dir", "plan_key", "cached_entry",
           "planned"]

_log = logging.getLogger("gtmodel")

#: The environment variable naming gtmodel's cache folder (the plans in its subfolder ``plans``).
CACHE_ENV = "GTMODEL_CACHE_DIR"
#: The environment variable of the plans' own folder (before :data:`CACHE_ENV`).
PLAN_CACHE_ENV = "GTMODEL_PLAN_CACHE_DIR"
#: Version of the key and of the entries' layout (a change makes every earlier entry a miss).
FORMAT = 1
#: Largest entry read [bytes]; a larger file is ignored (and a larger plan not stored).
MAX_ENTRY_BYTES = 64 * 2**20
#: A file the problem names above this size enters the key by its size and time of change, not read whole [bytes].
MAX_HASHED_BYTES = 256 * 2**20
#: Statuses of a solve that ended with a solution: the only plans stored.
STORED = (*SOLVED, "check_failed")
_MAX_REFERENCE_CHARS = 4096


@dataclass(frozen=True)
class CachedVerification:
    """The verdict of a plan's verification, as :func:`~gtmodel.problems.loop_bounds.unverified_reason` reads it.

    Parameters
    ----------
    passed : bool or None
        Whether the verification passed.
    message : str
        Why it failed (``""`` when it passed).
    """

    passed: bool | None
    message: str | None = ""


@dataclass(frozen=True)
class CachedPlan:
    """A plan read from the cache, with the attributes of a solution that the loop-controller file reads.

    Parameters
    ----------
    status : str
        The solve's status (``"optimal"``, ``"acceptable"``, ``"check_failed"``).
    verification : CachedVerification or None
        Its verification's verdict.
    t : numpy.ndarray
        ``(N,)`` times [s].
    states, inputs : dict of str to numpy.ndarray
        By name, each with ``N`` rows.
    parameters : dict of str to numpy.ndarray
        The model's parameter values of the solve.
    path : pathlib.Path, optional
        The entry it was read from.
    """

    status: str
    verification: CachedVerification | None
    t: np.ndarray
    states: dict[str, np.ndarray]
    inputs: dict[str, np.ndarray]
    parameters: dict[str, np.ndarray]
    path: Path | None = field(default=None, compare=False)


def cache_dir() -> Path | None:
    """The folder of the plan cache: the subfolder ``plans`` of gtmodel's cache (that of the compiled libraries).

    Returns
    -------
    pathlib.Path or None
        ``$GTMODEL_PLAN_CACHE_DIR`` if set (the plans alone elsewhere: the test suite's own folder), else
        ``$GTMODEL_CACHE_DIR/plans`` if that is set, else ``$XDG_CACHE_HOME/gtmodel/plans``, else
        ``~/.cache/gtmodel/plans``; None when there is no home folder to put it in.
    """
    own = os.environ.get(PLAN_CACHE_ENV, "").strip()
    if own:
        return Path(own)
    try:
        return compiled_cache_dir("plans")
    except RuntimeError:  # no home folder
        return None


def _canonical(value: Any) -> str:
    return json.dumps(value, sort_keys=True, separators=(",", ":"), default=repr)


@lru_cache(maxsize=1)
def _source_digest() -> str:
    """sha256 over gtmodel's own source files (an edited checkout plans again)."""
    root = Path(__file__).resolve().parents[1]
    h = hashlib.sha256()
    for p in sorted(root.rglob("*.py")):
        try:
            h.update(f"{p.relative_to(root)}\0".encode() + hashlib.sha256(p.read_bytes()).digest())
        except OSError:
            h.update(f"{p.relative_to(root)}\0unreadable".encode())
    return h.hexdigest()


def _file_digest(path: Path) -> str:
    h = hashlib.sha256()
    try:
        info = path.stat()
        if info.st_size > MAX_HASHED_BYTES:  # its size and time of change stand for it: never a huge file read whole
            return f"size {info.st_size}, changed {info.st_mtime_ns}"
        with open(path, "rb") as f:
            for block in iter(lambda: f.read(1 << 20), b""):
                h.update(block)
    except OSError as exc:
        return f"unreadable ({type(exc).__name__})"
    return h.hexdigest()


def _strings(value: Any) -> list[str]:
    if isinstance(value, str):
        return [value]
    if isinstance(value, Mapping):
        return [s for v in value.values() for s in _strings(v)]
    if isinstance(value, (list, tuple)):
        return [s for v in value for s in _strings(v)]
    return []


def _referenced(problem: Path, data: Mapping[str, Any]) -> list[tuple[str, Path]]:
    """Every (reference as written, resolved regular file) a problem document names that its load reads: the model
    file of ``[model] file`` wherever it is (the loader reads it there), any other file only inside the problem file's
    folder or a ``--data-dir`` folder (the rule of :meth:`~gtmodel.problems.base.ProblemFile.data_file`): a string of
    someone else's problem file never makes the cache read another file of the machine."""
    found: dict[str, Path] = {}
    model = data.get("model") if isinstance(data.get("model"), Mapping) else {}
    model_file = model.get("file") if isinstance(model.get("file"), str) else None
    roots = [problem.parent.resolve(), *data_dirs()]
    for text in _strings(data):
        if not text or len(text) > _MAX_REFERENCE_CHARS or "\0" in text or "\n" in text:
            continue
        for ref in dict.fromkeys([text, text.rpartition(":")[0]]):
            if not ref:
                continue
            try:
                real = (Path(ref) if Path(ref).is_absolute() else problem.parent / ref).resolve()
                inside = ref == model_file or any(real.is_relative_to(r) for r in roots)
                if inside and not any(real.is_relative_to(s) for s in _SPECIAL) and real.is_file():
                    found.setdefault(ref, real)
            except (OSError, ValueError, RuntimeError):
                continue
    return sorted(found.items())


def plan_key(problem: str | Path, overrides: Mapping[str, Any] | None = None) -> str:
    """The cache key of a reference problem planned with overrides (see the module docstring).

    Parameters
    ----------
    problem : str or pathlib.Path
        The problem file.
    overrides : Mapping[str, Any], optional
        Its ``[reference] overrides`` (dotted fields).

    Returns
    -------
    str
        64 hexadecimal digits (sha256).
    """
    path = Path(problem)
    overrides = dict(overrides or {})
    h = hashlib.sha256()

    def part(name: str, data: bytes) -> None:
        h.update(name.encode() + b"\0" + len(data).to_bytes(8, "little") + data)

    part("format", str(FORMAT).encode())
    part("versions", _canonical({"gtmodel": __version__, "casadi": ca.__version__, "numpy": np.__version__}).encode())
    part("gtmodel source", _source_digest().encode())
    part("defaults", _canonical(defaults).encode())
    try:
        text = path.read_bytes()
    except OSError as exc:
        text = f"unreadable ({type(exc).__name__})".encode()
    part("problem", text)
    part("overrides", _canonical(overrides).encode())
    try:
        data = tomllib.loads(text.decode("utf-8"))
    except (UnicodeDecodeError, tomllib.TOMLDecodeError):
        data = {}
    for key, value in overrides.items():
        try:
            data = apply_override(data, key, value, path)
        except GtModelError:
            pass  # the load refuses it (named there); the overrides are in the key as written
    for ref, real in _referenced(path, data):
        part(f"file {ref}", _file_digest(real).encode())
    return h.hexdigest()


def _entry_path(key: str) -> Path | None:
    folder = cache_dir()
    return None if folder is None else folder / f"{key}.json"


def cached_entry(problem: str | Path, overrides: Mapping[str, Any] | None = None) -> Path | None:
    """The cache entry of a reference problem with overrides, when there is one (not yet read nor checked).

    Parameters
    ----------
    problem : str or pathlib.Path
        The problem file.
    overrides : Mapping[str, Any], optional
        Its overrides.

    Returns
    -------
    pathlib.Path or None
    """
    path = _entry_path(plan_key(problem, overrides))
    try:
        return path if path is not None and path.is_file() else None
    except OSError:
        return None


def _overrides_text(overrides: Mapping[str, Any]) -> str:
    return f" (with overrides {', '.join(f'{k} = {v}' for k, v in overrides.items())})" if overrides else " (without overrides)"


def _arrays(value: Any, rows: int | None, what: str) -> dict[str, np.ndarray]:
    if not isinstance(value, dict):
        raise ValueError(f"{what}: not a table")
    out = {}
    for name, v in value.items():
        a = np.asarray(v)
        if a.dtype.kind not in "fiub":
            raise ValueError(f"{what}.{name}: not numbers")
        if rows is not None and (a.ndim == 0 or a.shape[0] != rows):
            raise ValueError(f"{what}.{name}: shape {a.shape}, not {rows} rows (one per time)")
        out[name] = a
    return out


def _read(path: Path, key: str, names: Collection[str]) -> CachedPlan:
    """The plan of an entry; ValueError (or OSError) saying why it is not one."""
    if path.stat().st_size > MAX_ENTRY_BYTES:
        raise ValueError(f"larger than {MAX_ENTRY_BYTES} bytes")
    entry = json.loads(path.read_bytes().decode("utf-8"))
    if not isinstance(entry, dict) or entry.get("format") != FORMAT or entry.get("key") != key:
        raise ValueError("not an entry of this key and format")
    payload = entry.get("payload")
    if hashlib.sha256(_canonical(payload).encode()).hexdigest() != entry.get("checksum"):
        raise ValueError("checksum mismatch")
    status, ver = payload.get("status"), payload.get("verification")
    if status not in STORED:
        raise ValueError(f"status {status!r}")
    if ver is not None and not (isinstance(ver, dict) and ver.get("passed") in (True, False, None)
                                and isinstance(ver.get("message"), (str, type(None)))):
        raise ValueError("verification: not a verdict")
    t = np.asarray(payload.get("t"))
    if t.ndim != 1 or t.size == 0 or t.dtype.kind not in "fiu":
        raise ValueError(f"t: shape {t.shape}, not a row of times")
    states, inputs = _arrays(payload.get("states"), t.size, "states"), _arrays(payload.get("inputs"), t.size, "inputs")
    missing = [n for n in names if n not in states and n not in inputs]
    if missing:
        raise ValueError(f"no {missing[0]!r}")
    verification = None if ver is None else CachedVerification(ver["passed"], ver.get("message"))
    return CachedPlan(status=status, verification=verification, t=t, states=states, inputs=inputs,
                      parameters=_arrays(payload.get("parameters"), None, "parameters"), path=path)


def _payload(solution: Any, status: str) -> dict[str, Any]:
    ver = getattr(solution, "verification", None)
    verdict = None if ver is None else ({"passed": ver.get("passed"), "message": ver.get("message") or ver.get("status")}
                                        if isinstance(ver, dict) else {"passed": getattr(ver, "passed", None),
                                                                       "message": getattr(ver, "message", "")})
    if verdict is not None:  # read as `passed is not True` (a NumPy True is not True): kept as it reads
        verdict["passed"] = True if verdict["passed"] is True else None if verdict["passed"] is None else False

    def table(values: Mapping[str, Any]) -> dict[str, Any]:
        return {str(k): np.asarray(v).tolist() for k, v in values.items()}

    return {"status": status, "verification": verdict, "t": np.asarray(solution.t, dtype=float).reshape(-1).tolist(),
            "states": table(solution.states), "inputs": table(solution.inputs), "parameters": table(solution.parameters)}


def _store(path: Path, key: str, solution: Any, status: str) -> bool:
    """Write an entry atomically; False (with a warning) when it cannot be written."""
    try:
        payload = _payload(solution, status)
        text = json.dumps({"checksum": hashlib.sha256(_canonical(payload).encode()).hexdigest(), "format": FORMAT, "key": key,
                           "payload": payload}, sort_keys=True, separators=(",", ":"))
    except (TypeError, ValueError, AttributeError) as exc:
        _log.warning("the reference's plan is not cached: it cannot be written as JSON (%s)", exc)
        return False
    if len(text) > MAX_ENTRY_BYTES:
        _log.warning("the reference's plan is not cached: %d bytes, above the cache's %d", len(text), MAX_ENTRY_BYTES)
        return False
    tmp = None
    try:
        path.parent.mkdir(parents=True, exist_ok=True, mode=0o700)
        with tempfile.NamedTemporaryFile("w", encoding="utf-8", dir=path.parent, prefix=f".{key[:16]}.", suffix=".tmp",
                                         delete=False) as f:
            tmp = f.name
            f.write(text)
        os.replace(tmp, path)
    except OSError as exc:
        _log.warning("the plan cache %s cannot be written (%s); going on without it", path.parent, exc.strerror or exc)
        if tmp is not None:
            try:
                os.unlink(tmp)
            except OSError:
                pass
        return False
    return True


def planned(problem: Any, solve: Callable[[], Any], replan: bool = False, names: Collection[str] = ()) -> Any:
    """A reference problem's solution: the cached plan, or ``solve()`` (then stored).

    Parameters
    ----------
    problem : Problem
        The loaded problem (:func:`~gtmodel.problems.run.load_problem`): its ``path`` and ``overrides``.
    solve : callable
        ``solve() -> solution`` with ``status``, ``verification``, ``t``, ``states``,
        ``inputs``, ``parameters`` (an :class:`~gtmodel.modeling.ocp.result.OptimizationResult`).
    replan : bool, optional
        Solve even when a plan is cached (and replace it).
    names : collection of str, optional
        States and inputs the caller reads: an entry without one is ignored.

    Returns
    -------
    CachedPlan or object
        The cached plan, or what ``solve()`` returned.
    """
    overrides = dict(problem.overrides or {})
    key = plan_key(problem.path, overrides)
    path = _entry_path(key)
    what = f"the reference {problem.path}{_overrides_text(overrides)}"
    if path is not None and not replan:
        try:
            found = path.is_file()
        except OSError:
            found = False
        if found:
            try:
                plan = _read(path, key, names)
            except (OSError, ValueError, TypeError, KeyError, AttributeError, UnicodeDecodeError) as exc:
                _log.warning("the plan cached at %s is ignored (%s); %s is solved again", path, exc, what)
            else:
                _log.info("%s is the plan cached at %s (key %s); --replan solves it again", what, path, key[:16])
                return plan
    elif replan:
        _log.info("%s is solved again (--replan)", what)
    solution = solve()
    status = str(getattr(solution.status, "value", solution.status))
    if path is None:
        _log.warning("no folder for the plan cache (no home folder; set %s): %s is not cached", CACHE_ENV, what)
    elif status not in STORED:
        _log.info("%s ended %s: not cached", what, status)
    elif _store(path, key, solution, status):
        _log.info("%s planned and cached at %s (key %s)", what, path, key[:16])
    return solution
