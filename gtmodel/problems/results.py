"""Result folders that are never stale and never half-written.

A run writes into a new hidden folder beside the target (``.<name>.partial-<pid>``) and
replaces the target only when everything, ``summary.json`` last, is written. The rule for
an earlier run's folder: **only a run that finished replaces it** (any status of exit code
0 or 1 but ``error``; a loop's ``interrupted``, its normal end). A run that did not finish
(invalid input, internal error, ``error``, interrupted) over a folder holding a complete
result (one with data files, :func:`holds_result`) leaves that folder byte for byte as it
was and writes its own folder beside it instead, ``<name>.failed`` (:func:`failed_folder`;
its ``summary.json`` says ``"earlier_result_kept"``); a failed run over a new or empty
folder, or over a folder holding only a failed run's summary, writes into the folder
itself. A finished run that replaces the target removes the stale ``<name>.failed``
beside it. A process killed outright (SIGKILL, power loss) never reaches the replacement:
the earlier folder stays intact, and the orphaned partial folder is removed by the next run.

The replacement swaps the two folders in one step (Linux ``renameat2`` with
``RENAME_EXCHANGE``), so a reader never finds the target missing; where that call is not
available (another OS or file system) it is two renames with a window of microseconds
in between. :func:`output_lock` keeps a second ``gtmodel`` command off a folder in use.

``summary.json`` lists every file of its folder (``files``, itself included) and carries
the marker ``"written_by": "gtmodel ..."`` by which a folder is recognised as a result.
"""

from __future__ import annotations

import ctypes
import errno
import json
import math
import os
import shutil
import sys
from contextlib import contextmanager
from pathlib import Path
from typing import Any, Iterator, Mapping

from gtmodel import __version__, _signals

try:
    import fcntl
except ImportError:  # pragma: no cover - Windows
    fcntl = None
from gtmodel.errors import GtModelError, ResultWriteError
from gtmodel.status import Status

__all__ = ["check_output_folder", "is_file_name", "MAX_FILE_NAME", "output_lock", "ResultFolder", "json_safe", "write_json", "failure_summary", "MARKER", "verification_fields",
           "FAILED_SUFFIX", "failed_folder", "holds_result", "finished", "kept_message", "replace_folder", "remove_orphans"]

#: The ``written_by`` field of every ``summary.json`` gtmodel writes (how a result folder is recognised).
MARKER = f"gtmodel {__version__}"


#: Longest name that becomes a file or folder name [bytes of UTF-8] (well inside the 255 of common file systems).
MAX_FILE_NAME = 100


def is_file_name(value: Any) -> bool:
    """Whether ``value`` can name a file or folder of its own: one plain path component.

    A name that becomes a folder (``results/<name>``) or a file of a result folder must not
    climb out of it or name another place: a string of 1 to :data:`MAX_FILE_NAME` bytes
    (UTF-8), without ``/``, ``\\``, control characters or a leading or trailing space,
    and neither ``.`` nor ``..``.

    Parameters
    ----------
    value : Any
        A field's value as read from the file.

    Returns
    -------
    bool
    """
    return (isinstance(value, str) and value not in ("", ".", "..") and value == value.strip()
            and not any(c in "/\\" or not c.isprintable() for c in value) and len(value.encode("utf-8")) <= MAX_FILE_NAME)


#: What a run that did not finish adds to its result folder's name when it leaves an earlier complete result as it was.
FAILED_SUFFIX = ".failed"

#: Statuses of a run that did not finish: it never replaces an earlier complete result.
UNFINISHED = frozenset({Status.INVALID_INPUT, Status.INTERNAL_ERROR, Status.ERROR, Status.INTERRUPTED})

#: Files of a result folder that are not its data (a folder with nothing else holds no result).
_NOT_DATA = frozenset({"summary.json", "report.html"})


def failed_folder(target: str | Path) -> Path:
    """The folder beside ``target`` that receives a run that did not finish over a complete result.

    Parameters
    ----------
    target : str or pathlib.Path
        The result folder (``--out``).

    Returns
    -------
    pathlib.Path
        ``<target>.failed`` in the same folder.
    """
    target = Path(target)
    return target.parent / f"{target.name}{FAILED_SUFFIX}"


def finished(status: Status | str, ends_on_signal: bool = False) -> bool:
    """Whether a run with this status finished, so that its folder may replace an earlier complete result.

    Parameters
    ----------
    status : Status or str
        The run's status.
    ends_on_signal : bool, optional
        The kind ends on a signal (a loop: ``interrupted`` is its normal end, its log complete).

    Returns
    -------
    bool
        False for ``invalid_input``, ``internal_error``, ``error`` and (unless
        ``ends_on_signal``) ``interrupted``.
    """
    status = Status(status)
    return status not in UNFINISHED or (status is Status.INTERRUPTED and ends_on_signal)


def holds_result(folder: str | Path) -> bool:
    """Whether ``folder`` holds a complete earlier result that a run which did not finish must leave as it was.

    Parameters
    ----------
    folder : str or pathlib.Path
        A result folder.

    Returns
    -------
    bool
        True when its ``summary.json`` is a run's, lists a data file (anything but
        ``summary.json`` and ``report.html``) and its status is not ``invalid_input``,
        ``internal_error`` or ``error``; a run's ``interrupted`` result with data (a loop's
        log, the last verified pass of a refinement) counts.
    """
    path = Path(folder) / "summary.json"
    if not _is_run_summary(path):
        return False
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return False
    files = data.get("files")
    status = Status(data["status"])
    return isinstance(files, list) and any(f not in _NOT_DATA for f in files) and (status is Status.INTERRUPTED or finished(status))


def kept_message(kept: str | Path, written: str | Path, status: Status | str) -> str:
    """The line that tells a user their earlier result was kept and where this run's folder went.

    Parameters
    ----------
    kept : str or pathlib.Path
        The result folder left as it was.
    written : str or pathlib.Path
        Where this run's folder went (:func:`failed_folder`).
    status : Status or str
        This run's status.

    Returns
    -------
    str
    """
    return (f"gtmodel: the earlier result in {kept}/ is kept as it was; this run ({Status(status).value}) "
            f"is in {written}/")


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
        ``{"refinement": [...]}`` (one entry per pass) and ``"refinement_stop"`` (why it
        ended, which pass was returned) when its mesh was refined, and ``"regularization"`` where the
        transcription regularised a minimum-time problem's inputs
        (:mod:`gtmodel.modeling.ocp.regularization`); else
        ``{"verification": None}`` for a collocation result that was not verified.
    """
    if not hasattr(result, "verification"):
        return {}
    v = result.verification
    out: dict[str, Any] = {"verification": v.to_dict() if v is not None else None}
    if (getattr(result, "stats", None) or {}).get("regularization"):  # a minimum-time problem's inputs regularised
        out["regularization"] = json_safe(result.stats["regularization"])
    if getattr(result, "refinement", None):
        out["refinement"] = json_safe(result.refinement)
        if getattr(result, "refinement_stop", None):
            out["refinement_stop"] = str(result.refinement_stop)
    return out


def check_output_folder(out: str | Path) -> None:
    """Check, before any work, that a run may write its result (or study) folder where asked.

    A run writes only into a folder that is new, empty, or a gtmodel result folder (its
    ``summary.json`` is a run's summary with the ``written_by`` marker, or, for a study
    stopped before its summary, one of its ``cases/*/summary.json`` is), so a mistyped
    ``--out`` never replaces a folder of the user's own files (DESIGN.md, "A user's files
    are never destroyed"). The folder, or the nearest folder above it that exists, must be
    writable, and it may not be a mount point or hold the current folder (a run replaces
    its folder whole).

    Parameters
    ----------
    out : str or pathlib.Path
        The folder.

    Raises
    ------
    ResultWriteError
        ``out`` or a parent of it is an existing file; ``out`` holds files no gtmodel run
        wrote; ``out`` (or the folder it would be created in) is not writable; ``out`` is
        a symbolic link, a mount point or holds the current folder. The message names
        ``out`` and what to do.
    """
    out = Path(out)
    absolute = Path(os.path.abspath(out))
    existing = absolute
    for p in (absolute, *absolute.parents):
        if p.exists() or p.is_symlink():
            if not p.is_dir():
                why = "a file of that name is in the way" if p == absolute else f"its parent {p} is a file"
                raise ResultWriteError(f"cannot write the result folder {out}: {why}")
            existing = p
            break
    if existing == absolute:
        if absolute.is_symlink():
            raise ResultWriteError(f"cannot write the result folder {out}: it is a symbolic link, which a run would replace by a "
                                   f"folder; give the folder it points to ({os.path.realpath(absolute)})")
        if os.path.ismount(absolute) or absolute == absolute.parent:
            raise ResultWriteError(f"cannot write the result folder {out}: it is a mount point, which a run cannot replace; "
                                   "give a folder inside it")
        try:
            cwd = Path(os.getcwd())
        except OSError:
            cwd = None
        if cwd is not None and (cwd == absolute or absolute in cwd.parents):
            raise ResultWriteError(f"will not write the result folder {out}: it holds the current folder and a run replaces "
                                   "its folder whole; give another folder")
        if not _written_by_gtmodel(absolute):
            raise ResultWriteError(f"will not write the result folder {out}: it holds files that no gtmodel run wrote "
                                   "(no summary.json of a run) and a run replaces its folder whole; give a new or empty folder")
        for p, what in ((absolute.parent, "the folder it is in"), (absolute, "it")):
            if not os.access(p, os.W_OK | os.X_OK):
                raise ResultWriteError(f"cannot write the result folder {out}: {what} is not writable ({p})")
    elif not os.access(existing, os.W_OK | os.X_OK):
        raise ResultWriteError(f"cannot write the result folder {out}: {existing} is not writable")


def _written_by_gtmodel(folder: Path) -> bool:
    """Empty, or a result folder of a run or of a study (see :func:`check_output_folder`)."""
    try:
        if not any(folder.iterdir()):
            return True
    except OSError:
        return False
    if _is_run_summary(folder / "summary.json"):
        return True
    cases = folder / "cases"
    try:
        return cases.is_dir() and any(_is_run_summary(c / "summary.json") for c in cases.iterdir())
    except OSError:
        return False


def _is_run_summary(path: Path) -> bool:
    """A ``summary.json`` of gtmodel: a status, and the marker (or, before the marker, the file list)."""
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return False
    if not isinstance(data, dict) or data.get("status") not in {s.value for s in Status}:
        return False
    marker = data.get("written_by")
    files = data.get("files")
    return (isinstance(marker, str) and marker.startswith("gtmodel ")) or (isinstance(files, list) and "summary.json" in files)


@contextmanager
def output_lock(out: str | Path) -> Iterator[None]:
    """Hold the lock of a result folder for a whole run: a second run on it is refused at once.

    The lock is ``.<name>.lock`` beside the folder (``fcntl.flock``; released by the
    system when the process ends, also when it is killed); it is removed at the end.

    Parameters
    ----------
    out : str or pathlib.Path
        The result folder.

    Raises
    ------
    ResultWriteError
        Another process holds the lock (names ``out`` and that process), or the lock file
        cannot be created.
    """
    out = Path(out)
    absolute = Path(os.path.realpath(out))  # one lock whatever path names the folder
    if fcntl is None:  # not POSIX: no lock (docs/reliability.md)
        yield
        return
    lock = absolute.parent / f".{absolute.name}.lock"
    try:
        absolute.parent.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise ResultWriteError(f"cannot write the result folder {out}: {exc.strerror or exc}") from None
    while True:
        try:
            fd = os.open(lock, os.O_RDWR | os.O_CREAT, 0o644)
        except OSError as exc:
            raise ResultWriteError(f"cannot write the result folder {out}: {exc.strerror or exc}") from None
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            holder = os.read(fd, 32).decode("ascii", "replace").strip()
            os.close(fd)
            who = f" (process {holder})" if holder.isdigit() else ""
            raise ResultWriteError(f"cannot write the result folder {out}: another gtmodel run{who} is writing it; "
                                   "wait for it to end or give another --out") from None
        try:
            same = os.stat(lock).st_ino == os.fstat(fd).st_ino  # not unlinked by the holder that just ended
        except FileNotFoundError:
            same = False
        if same:
            break
        os.close(fd)
    try:
        os.ftruncate(fd, 0)
        os.write(fd, str(os.getpid()).encode())
    except OSError:
        pass  # the pid is only for the message of a second run
    try:
        yield
    finally:
        try:
            os.unlink(lock)
        except OSError:
            pass
        os.close(fd)


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
    ``commit(summary, keep_complete=True)`` (a run that did not finish) leaves a complete
    earlier result as it was and writes ``<target>.failed`` instead.
    """

    def __init__(self, target: str | Path) -> None:
        self.target = Path(target)
        check_output_folder(self.target)
        parent = self.target.parent
        self.path = parent / f".{self.target.name}.partial-{os.getpid()}"
        try:
            parent.mkdir(parents=True, exist_ok=True)
            remove_orphans(parent, self.target.name)
            if self.path.exists():
                shutil.rmtree(self.path)
            self.path.mkdir()
        except OSError as exc:
            raise ResultWriteError(f"cannot create the result folder {self.target}: {exc.strerror or exc}") from None
        self.committed = False
        self.kept: Path | None = None

    def commit(self, summary: Mapping[str, Any], keep_complete: bool = False) -> dict[str, Any]:
        """Write ``summary.json`` (listing every file) and replace the target folder.

        Parameters
        ----------
        summary : Mapping[str, Any]
            The summary fields (``files`` is set here).
        keep_complete : bool, optional
            The run did not finish (:func:`finished`): if the target holds a complete
            result (:func:`holds_result`), it is left as it was and this folder replaces
            :func:`failed_folder` instead (checked as a target is; :attr:`kept` is then the
            target left as it was and :attr:`target` the folder written). Default False.

        Returns
        -------
        dict
            The summary as written.

        Raises
        ------
        ResultWriteError
            ``summary.json`` cannot be written or the target cannot be replaced (the
            earlier folder is then left as it was); with ``keep_complete``, the folder beside
            it is not new, empty nor a gtmodel result folder.
        """
        if keep_complete and self.kept is None and holds_result(self.target):
            aside = failed_folder(self.target)
            check_output_folder(aside)  # never a folder of the user's own files
            self.kept, self.target = self.target, aside
            summary = {**summary, "earlier_result_kept": str(self.kept)}
        files = sorted(p.name for p in self.path.iterdir() if p.name != "summary.json")
        out = dict(summary)
        out["files"] = ["summary.json", *files]
        out["written_by"] = MARKER
        try:
            write_json(self.path / "summary.json", out)
        except ResultWriteError as exc:
            raise self.write_error(exc) from None
        with _signals.protected():  # a signal here is raised once the target is whole again and the earlier one gone
            try:
                old = self._swap()
            except OSError as exc:
                raise ResultWriteError(f"cannot replace the result folder {self.target}: {exc.strerror or exc}") from None
            self.committed = True
            if old is not None:
                shutil.rmtree(old, ignore_errors=True)
            if self.kept is None:
                _remove_stale_failed(self.target)
        return out

    def _swap(self) -> Path | None:
        """Put the partial folder in place of the target; the earlier target's new path (to remove)."""
        return replace_folder(self.path, self.target)

    def write_error(self, exc: OSError) -> ResultWriteError:
        """One message for a failed write into the folder, naming the target, never the partial folder.

        Parameters
        ----------
        exc : OSError
            The failure (a :class:`~gtmodel.errors.ResultWriteError` keeps its words, with
            the partial folder's path replaced by the target's).

        Returns
        -------
        ResultWriteError
        """
        if isinstance(exc, ResultWriteError):
            return ResultWriteError(str(exc).replace(str(self.path), str(self.target)))
        return ResultWriteError(f"cannot write the result folder {self.target}: {exc.strerror or exc}")

    def discard(self) -> None:
        """Remove the partial folder (the target is left untouched)."""
        shutil.rmtree(self.path, ignore_errors=True)

    def __enter__(self) -> "ResultFolder":
        return self

    def __exit__(self, *exc: Any) -> None:
        if not self.committed:
            self.discard()


def replace_folder(partial: Path, target: Path) -> Path | None:
    """Put a complete folder in place of ``target`` in one step where the system can (``renameat2`` exchange).

    Parameters
    ----------
    partial : pathlib.Path
        The complete folder, beside ``target`` (same file system).
    target : pathlib.Path
        The folder it replaces (or creates).

    Returns
    -------
    pathlib.Path or None
        Where the earlier ``target`` now is (the caller removes it), None if there was none.

    Raises
    ------
    ResultWriteError
        A file (or a symbolic link) of ``target``'s name is in the way.
    OSError
        The rename failed (the earlier ``target`` is then left as it was).
    """
    if target.is_symlink() or (target.exists() and not target.is_dir()):
        raise ResultWriteError(f"cannot write the result folder {target}: a file of that name is in the way")
    if not target.exists():
        try:
            os.rename(partial, target)
            return None
        except OSError as exc:
            if exc.errno not in (errno.ENOTEMPTY, errno.EEXIST):
                raise  # else another process created the target meanwhile: swap with it
    if _exchange(partial, target):
        return partial  # the partial path now holds the earlier folder
    old = target.parent / f".{target.name}.old-{os.getpid()}"
    os.replace(target, old)  # no atomic swap here: the target is missing for a moment
    try:
        os.replace(partial, target)
    except OSError:
        os.replace(old, target)
        raise
    return old


_RENAME_EXCHANGE = 2
_libc: Any = None


def _exchange(a: Path, b: Path) -> bool:
    """Swap two folders in one step (Linux ``renameat2(RENAME_EXCHANGE)``); False where unsupported."""
    global _libc
    if not sys.platform.startswith("linux"):
        return False
    if _libc is None:
        try:
            _libc = ctypes.CDLL(None, use_errno=True)
            _libc.renameat2  # glibc >= 2.28
        except (OSError, AttributeError):
            _libc = False
    if _libc is False:
        return False
    at_fdcwd = -100
    if _libc.renameat2(at_fdcwd, os.fsencode(a), at_fdcwd, os.fsencode(b), _RENAME_EXCHANGE) == 0:
        return True
    err = ctypes.get_errno()
    if err in (errno.EINVAL, errno.ENOSYS, errno.EOPNOTSUPP):
        return False  # the file system cannot swap
    raise OSError(err, os.strerror(err), str(b))


def _remove_stale_failed(target: Path) -> None:
    """``<target>.failed`` of an earlier run that did not finish, now older than ``target`` (only a folder gtmodel wrote so)."""
    aside = failed_folder(target)
    try:
        data = json.loads((aside / "summary.json").read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return
    kept = data.get("earlier_result_kept") if isinstance(data, dict) else None
    if aside.is_symlink() or not isinstance(kept, str) or Path(kept).name != target.name or not _is_run_summary(aside / "summary.json"):
        return
    gone = target.parent / f".{aside.name}.old-{os.getpid()}"
    try:
        os.replace(aside, gone)
    except OSError:
        return
    shutil.rmtree(gone, ignore_errors=True)


def remove_orphans(parent: Path, name: str) -> None:
    """Partial and old folders of ``parent / name`` left by earlier runs whose process no longer exists.

    Parameters
    ----------
    parent : pathlib.Path
        The folder that holds them.
    name : str
        The target folder's name (they are ``.<name>.partial-<pid>`` and ``.<name>.old-<pid>``).
    """
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
