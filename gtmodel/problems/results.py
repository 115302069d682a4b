"""Result folders that are never stale and never half-written.

A run writes into a new hidden folder beside the target (``.<name>.partial-<pid>``) and
replaces the target only when everything, ``summary.json`` last, is written. The rule for
an earlier run's folder: **every finished run replaces it whole**, whatever its outcome
(optimal, infeasible, invalid input, interrupted). So after a failed run the folder holds
the failed run's ``summary.json`` alone and no file of the earlier run can look current.
A process killed outright (SIGKILL, power loss) never reaches the replacement: the earlier
folder stays intact, and the orphaned partial folder is removed by the next run.

``summary.json`` lists every file of its folder (``files``, itself included).
"""

from __future__ import annotations

import json
import math
import os
import shutil
import sys
from pathlib import Path
from typing import Any, Mapping

from gtmodel.errors import GtModelError, ResultWriteError
from gtmodel.status import Status

__all__ = ["check_output_folder", "ResultFolder", "json_safe", "write_json", "failure_summary", "verification_fields"]


def json_safe(value: Any) -> Any:
    """A JSON-serialisable copy (non-finite numbers become ``null``, arrays lists).

    Parameters
    ----------
    value : Any
        Numbers, arrays, mappings, sequences, :class:`~gtmodel.status.Status`.

    Returns
    -------
    Any
    """
    if isinstance(value, Status):
        return value.value
    # numpy values exist only once numpy is imported: it is not imported here, so that a
    # summary of a file that failed validation is written without it (fast start).
    np = sys.modules.get("numpy")
    if isinstance(value, bool) or (np is not None and isinstance(value, np.bool_)):
        return bool(value)
    if np is not None and isinstance(value, np.integer):
        return int(value)
    if isinstance(value, float) or (np is not None and isinstance(value, np.floating)):
        return float(value) if math.isfinite(value) else None
    if np is not None and isinstance(value, np.ndarray):
        return [json_safe(x) for x in value.tolist()]
    if isinstance(value, Mapping):
        return {str(k): json_safe(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [json_safe(v) for v in value]
    if isinstance(value, Path):
        return str(value)
    return value


def write_json(path: Path, data: Mapping[str, Any]) -> Path:
    """Write a JSON file (through :func:`json_safe`).

    Parameters
    ----------
    path : pathlib.Path
        Target file.
    data : Mapping[str, Any]
        Content.

    Returns
    -------
    pathlib.Path

    Raises
    ------
    ResultWriteError
        The file cannot be written (names the path).
    """
    try:
        path.write_text(json.dumps(json_safe(dict(data)), indent=2) + "\n", encoding="utf-8")
    except OSError as exc:
        raise ResultWriteError(f"cannot write {path}: {exc.strerror or exc}") from None
    return path


def failure_summary(problem: str | Path, error: BaseException | str, status: Status, kind: str | None = None,
                    name: str | None = None, empty_fields: tuple[str, ...] = ()) -> dict[str, Any]:
    """Summary of a run that produced no solution (bad input, internal error, interrupt).

    Parameters
    ----------
    problem : str or pathlib.Path
        The problem file.
    error : BaseException or str
        What went wrong.
    status : Status
        ``invalid_input``, ``internal_error``, ``interrupted`` or ``error``.
    kind : str, optional
        The problem kind, if known.
    name : str, optional
        The problem name, if known (default: the problem file's name without ``.toml``).
    empty_fields : tuple of str, optional
        The kind's numeric summary fields, written as null.

    Returns
    -------
    dict
    """
    if isinstance(error, GtModelError) or isinstance(error, str):
        message = str(error)
    elif isinstance(error, KeyboardInterrupt):
        message = "interrupted by the user"
    else:
        message = f"{type(error).__name__}: {error}"
    out: dict[str, Any] = {"problem": str(problem), "name": name if name is not None else Path(problem).stem, "kind": kind, "status": Status(status), "message": message}
    out.update({k: None for k in empty_fields})
    return out


def verification_fields(result: Any) -> dict[str, Any]:
    """The ``verification`` (and ``refinement``) summary fields of a collocation result.

    Parameters
    ----------
    result : object
        A result with ``verification`` (a
        :class:`gtmodel.modeling.ocp.verification.Verification` or None) and
        ``refinement`` (list of dict) attributes, e.g. an
        :class:`~gtmodel.modeling.OptimizationResult`; anything else gives no fields.

    Returns
    -------
    dict
        ``{"verification": {...}}`` when the result was verified (``passed``,
        ``tolerance``, largest deviations, per-state deviations, integrator), plus
        ``{"refinement": [...]}`` (one entry per pass) when its mesh was refined; else
        ``{"verification": None}`` for a collocation result that was not verified.
    """
    if not hasattr(result, "verification"):
        return {}
    v = result.verification
    out: dict[str, Any] = {"verification": v.to_dict() if v is not None else None}
    if getattr(result, "refinement", None):
        out["refinement"] = json_safe(result.refinement)
    return out


def check_output_folder(out: str | Path) -> None:
    """Check that a run may write its result (or study) folder where asked.

    A run writes only into a folder that is new, empty, or a gtmodel result folder (its
    ``summary.json`` is a run's summary, or, for a study stopped before its summary, one of
    its ``cases/*/summary.json`` is), so a mistyped ``--out`` never replaces a folder of the
    user's own files (DESIGN.md, "A user's files are never destroyed").

    Parameters
    ----------
    out : str or pathlib.Path
        The folder.

    Raises
    ------
    ResultWriteError
        ``out`` or a parent of it is an existing file, or ``out`` holds files no gtmodel
        run wrote (names the folder and what to do).
    """
    out = Path(out)
    for p in (out, *out.parents):
        if p.exists() or p.is_symlink():
            if not p.is_dir():
                why = "a file of that name is in the way" if p == out else f"its parent {p} is a file"
                raise ResultWriteError(f"cannot write the result folder {out}: {why}")
            break
    if out.is_dir() and not _written_by_gtmodel(out):
        raise ResultWriteError(f"will not write the result folder {out}: it holds files that no gtmodel run wrote "
                               "(no summary.json of a run) and a run replaces its folder whole; give a new or empty folder")


def _written_by_gtmodel(folder: Path) -> bool:
    """Empty, or a result folder of a run or of a study (see :func:`check_output_folder`)."""
    if not any(folder.iterdir()):
        return True
    if _is_run_summary(folder / "summary.json"):
        return True
    cases = folder / "cases"
    return cases.is_dir() and any(_is_run_summary(c / "summary.json") for c in cases.iterdir())


def _is_run_summary(path: Path) -> bool:
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return False
    return isinstance(data, dict) and data.get("status") in {s.value for s in Status}


class ResultFolder:
    """A result folder being written: files go to a partial folder until :meth:`commit`.

    Parameters
    ----------
    target : str or pathlib.Path
        The folder the results end up in.

    Raises
    ------
    ResultWriteError
        The target may not be written (:func:`check_output_folder`: a file, or a folder of
        files no gtmodel run wrote) or the partial folder cannot be created (names the path).

    Examples
    --------
    >>> with ResultFolder("results/x") as folder:                  # doctest: +SKIP
    ...     (folder.path / "trajectory.csv").write_text("...")
    ...     folder.commit({"status": "optimal"})

    As a context manager, the partial folder is removed at the end of the block unless it
    was committed (an exception or Ctrl-C inside leaves the earlier target as it was).
    """

    def __init__(self, target: str | Path) -> None:
        self.target = Path(target)
        check_output_folder(self.target)
        parent = self.target.parent
        self.path = parent / f".{self.target.name}.partial-{os.getpid()}"
        try:
            parent.mkdir(parents=True, exist_ok=True)
            _remove_orphans(parent, self.target.name)
            if self.path.exists():
                shutil.rmtree(self.path)
            self.path.mkdir()
        except OSError as exc:
            raise ResultWriteError(f"cannot create the result folder {self.target}: {exc.strerror or exc}") from None
        self.committed = False

    def commit(self, summary: Mapping[str, Any]) -> dict[str, Any]:
        """Write ``summary.json`` (listing every file) and replace the target folder.

        Parameters
        ----------
        summary : Mapping[str, Any]
            The summary fields (``files`` is set here).

        Returns
        -------
        dict
            The summary as written.

        Raises
        ------
        ResultWriteError
            ``summary.json`` cannot be written or the target cannot be replaced (the
            earlier folder is then left as it was).
        """
        files = sorted(p.name for p in self.path.iterdir() if p.name != "summary.json")
        out = dict(summary)
        out["files"] = ["summary.json", *files]
        write_json(self.path / "summary.json", out)
        old = self.target.parent / f".{self.target.name}.old-{os.getpid()}"
        try:
            if self.target.exists() or self.target.is_symlink():
                if not self.target.is_dir():
                    raise ResultWriteError(f"cannot write the result folder {self.target}: a file of that name is in the way")
                os.replace(self.target, old)
            os.replace(self.path, self.target)
        except OSError as exc:
            if old.exists() and not self.target.exists():
                os.replace(old, self.target)
            raise ResultWriteError(f"cannot replace the result folder {self.target}: {exc.strerror or exc}") from None
        shutil.rmtree(old, ignore_errors=True)
        self.committed = True
        return out

    def discard(self) -> None:
        """Remove the partial folder (the target is left untouched)."""
        shutil.rmtree(self.path, ignore_errors=True)

    def __enter__(self) -> "ResultFolder":
        return self

    def __exit__(self, *exc: Any) -> None:
        if not self.committed:
            self.discard()


def _remove_orphans(parent: Path, name: str) -> None:
    """Partial and old folders of earlier runs whose process no longer exists."""
    for prefix in (f".{name}.partial-", f".{name}.old-"):
        for p in parent.glob(prefix + "*"):
            try:
                pid = int(p.name.rsplit("-", 1)[1])
            except ValueError:
                continue
            if pid == os.getpid() or not _alive(pid):
                shutil.rmtree(p, ignore_errors=True)


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True
