"""The problem layer's protocol: a :class:`ProblemKind` per problem kind, and the file context.

A kind declares (rockit's split between declaring and transcribing):

- ``name``: the ``kind = "..."`` of its files;
- ``schema``: a :class:`~gtmodel.problems.schema.ProblemSchema` subclass (pydantic);
- :meth:`ProblemKind.load`: the validated document -> the solver-level declaration
  (semantic checks the schema cannot express: workspace, expressions, data files);
- :meth:`ProblemKind.solve`: declaration -> solution (a result with ``status``); by default
  the declaration's own ``solve`` (the domain object carries its method and solver settings);
- :meth:`ProblemKind.write`: solution -> files in a result folder and summary fields;
- ``columns``: what it contributes to a study's comparison table (their keys are the
  summary fields left empty when a run fails before a solution, with
  ``extra_empty_fields``).

Adding a kind is one class in :mod:`gtmodel.problems.kinds` and one line in
:mod:`gtmodel.problems.registry`.
"""

from __future__ import annotations

import os
import stat
from abc import ABC, abstractmethod
from dataclasses import dataclass, field
from fnmatch import fnmatchcase
from pathlib import Path
from typing import Any, ClassVar, Collection, Mapping

from gtmodel._docstrings import SHARED_DOCS, fill_doc
from gtmodel.errors import ProblemError
from gtmodel.problems.schema import ProblemSchema
from gtmodel.status import Status

__all__ = ["ProblemFile", "Column", "ProblemKind", "Problem", "Written", "KIND_DOCS", "COMMON_FILES"]

#: The files of every result folder, with what they hold (:attr:`ProblemKind.file_descriptions`).
COMMON_FILES = {"summary.json": "status, message, figures and settings of the run (always written)",
                "report.html": "this folder on one page: status, trajectories, tables, plots and files (gtmodel report)"}

#: Docstring sections shared by every kind (inserted by :func:`fill_doc`): the arguments of
#: :meth:`ProblemKind.load` and the top-level fields of every problem file.
KIND_DOCS = {
    "load_args": """
        doc : ProblemSchema
            The validated file (an instance of the kind's ``schema``).
        file : ProblemFile
            The file, for references and error messages.
        name : str
            Problem name.
    """,
    "write_args": """
        out : pathlib.Path
            The result folder (new and empty).
        plots : bool
            Write the PNG plots.
        name : str
            Problem name (plot titles).
    """,
    "header_fields": """
        name : str, optional
            Problem name (default: the file name without ``.toml``).
        kind : str
            The kind, ``kind = "..."`` in the file.
        description : str, optional
            Free text.
    """,
}


@dataclass(frozen=True)
class ProblemFile:
    """Where a problem file is, and the one rule for what it refers to.

    Parameters
    ----------
    path : pathlib.Path
        The problem file.
    """

    path: Path

    def fail(self, field: str, expected: str, got: Any = ...) -> ProblemError:
        """An error naming the file and the (dotted) field.

        Parameters
        ----------
        field : str
            Dotted field name, e.g. ``"limits.force"``.
        expected : str
            What was expected.
        got : Any, optional
            The offending value (omitted from the message if not given).

        Returns
        -------
        ProblemError
            To be raised by the caller.
        """
        tail = "" if got is ... else f", got {got!r}"
        return ProblemError(f"{self.path}: field '{field}': expected {expected}{tail}")

    def wrap(self, field: str, error: Exception) -> ProblemError:
        """An error from a lower layer, prefixed with the file and the field.

        Parameters
        ----------
        field : str
            Dotted field name.
        error : Exception
            What the lower layer said.

        Returns
        -------
        ProblemError
            A :class:`ProblemError` of this file is returned as it is (it already names the
            file and its field, which is more precise than ``field``).
        """
        if isinstance(error, ProblemError) and str(error).startswith(f"{self.path}: "):
            return error
        return ProblemError(f"{self.path}: field '{field}': {error}")

    def reference(self, field: str, ref: str, shipped: Collection[str] = ()) -> str | Path:
        """Resolve a reference to a parameter set or model file.

        The rule, the same for every kind: a value among ``shipped`` (a name without
        ``/`` and without a file ending) is that shipped set; anything else is a file path,
        absolute, or relative to the folder of the problem file.

        Parameters
        ----------
        field : str
            Dotted field name (for messages).
        ref : str
            The value written in the file.
        shipped : collection of str, optional
            Names of the shipped sets.

        Returns
        -------
        str or pathlib.Path
            The shipped name, or the resolved path.

        Raises
        ------
        ProblemError
            Neither a shipped name nor an existing file.
        """
        if ref in shipped:
            return ref
        try:
            target = Path(ref) if Path(ref).is_absolute() else (self.path.parent / ref).resolve()
            found = target.is_file()
        except (OSError, ValueError):  # a name too long, a NUL byte, ...
            found = False
        if not found:
            names = f"a shipped set ({', '.join(sorted(shipped))}) or " if shipped else ""
            raise self.fail(field, f"{names}an existing file (relative to {self.path.parent})", ref)
        return target

    def data_file(self, field: str, ref: str) -> Path:
        """Resolve a data file (CSV, ...) named in the problem file: the one place data paths are checked.

        A data file must stay where the problem lives: after symbolic links are resolved it
        lies inside the problem file's folder or inside a folder named with ``gtmodel solve
        --data-dir`` (the environment variable :data:`DATA_DIRS_ENV`, folders separated by
        ``os.pathsep``), and it is a regular file (not a device, FIFO or socket, nothing
        under ``/proc``, ``/sys`` or ``/dev``). So a problem file from someone else cannot make
        gtmodel read, and quote in its messages, any other file of the machine.

        Parameters
        ----------
        field : str
            Dotted field name.
        ref : str
            The path written in the file (absolute, or relative to the problem file).

        Returns
        -------
        pathlib.Path

        Raises
        ------
        ProblemError
            The file does not exist, resolves outside the allowed folders, or is not a
            regular file; the message names the problem file, the field and the path.
        """
        target = Path(self.reference(field, ref))
        try:
            real = target.resolve(strict=True)
            mode = real.stat().st_mode
        except (OSError, RuntimeError, ValueError):
            raise self.fail(field, "an existing, readable data file", ref) from None
        roots = [self.path.parent.resolve(), *data_dirs()]
        if any(real.is_relative_to(s) for s in _SPECIAL) or not stat.S_ISREG(mode):
            raise self.fail(field, "a regular data file (not a device, FIFO, socket or a file under /proc, /sys, /dev)", ref)
        if not any(real.is_relative_to(r) for r in roots):
            raise self.fail(field, f"a data file inside the problem file's folder {self.path.parent} "
                                   "or a folder given with --data-dir (symbolic links resolved)", ref)
        return target


#: Environment variable naming extra folders data files may come from (``os.pathsep``-separated; ``gtmodel solve --data-dir``).
DATA_DIRS_ENV = "GTMODEL_DATA_DIRS"
_SPECIAL = (Path("/proc"), Path("/sys"), Path("/dev"))


def data_dirs() -> list[Path]:
    """The extra folders data files may come from (:data:`DATA_DIRS_ENV`), resolved.

    Returns
    -------
    list of pathlib.Path
        Existing folders named in the environment variable; empty when it is unset.
    """
    out = []
    for part in os.environ.get(DATA_DIRS_ENV, "").split(os.pathsep):
        if part.strip():
            try:
                out.append(Path(part).resolve())
            except (OSError, RuntimeError):
                continue
    return out


@dataclass(frozen=True)
class Column:
    """A column a kind contributes to a study's comparison table.

    Parameters
    ----------
    key : str
        The summary field.
    header : str
        Column header with unit, e.g. ``"T_final [s]"``.
    fmt : str, optional
        Format of a value (``str.format`` spec).
    """

    key: str
    header: str
    fmt: str = "{:.6g}"


@dataclass
class Written:
    """What :meth:`ProblemKind.write` produced.

    Parameters
    ----------
    fields : dict
        Summary fields of the kind (numbers, lists, strings).
    files : list of str
        File names written into the folder (``summary.json`` excluded).
    """

    fields: dict[str, Any] = field(default_factory=dict)
    files: list[str] = field(default_factory=list)


class ProblemKind(ABC):
    """One kind of problem file: its schema, and how it is loaded, solved and written."""

    #: The ``kind`` value of its files.
    name: ClassVar[str]
    #: The schema of its files.
    schema: ClassVar[type[ProblemSchema]]
    #: One line for ``gtmodel schema --list`` and the reference page.
    title: ClassVar[str] = ""
    #: Columns of a study table (after ``case`` and ``status``).
    columns: ClassVar[tuple[Column, ...]] = ()
    #: Summary fields that are None when a case failed before solving, besides the keys of
    #: :attr:`columns`.
    extra_empty_fields: ClassVar[tuple[str, ...]] = ()
    #: Every file its :meth:`write` may put in a result folder: name (an :mod:`fnmatch`
    #: pattern for a file per case, ``"ilc_tool_path_case_*.png"``) -> one line saying what
    #: it holds. ``summary.json`` and ``report.html`` are every kind's (:data:`COMMON_FILES`).
    #: The run writes them into ``summary.json`` (``file_descriptions``) and the report lists
    #: them; a test fails for a kind that writes a file it does not describe.
    file_descriptions: ClassVar[Mapping[str, str]] = {}
    #: A signal (SIGINT, SIGTERM) ends the kind's solve as a normal end rather than
    #: interrupting the run: the solution says ``interrupted`` and its results are written
    #: (the robot loop of ``gtmodel loop``: Ctrl-C stops serving the robot, the log and the
    #: summary are kept). Default False: a signal interrupts the run.
    ends_on_signal: ClassVar[bool] = False

    def describe_files(self, names: Collection[str]) -> dict[str, str]:
        """What each file of a result folder holds, from :attr:`file_descriptions`.

        Parameters
        ----------
        names : collection of str
            File names in the folder.

        Returns
        -------
        dict of str to str
            Name -> its description, for the names described (:data:`COMMON_FILES` or a
            pattern of :attr:`file_descriptions`); an undescribed name is left out.
        """
        patterns = {**COMMON_FILES, **self.file_descriptions}
        out = {}
        for name in names:
            text = patterns.get(name) or next((d for pat, d in patterns.items() if fnmatchcase(name, pat)), None)
            if text:
                out[name] = text
        return out

    @property
    def empty_fields(self) -> tuple[str, ...]:
        """Summary fields that are None when a case failed before solving.

        The keys of :attr:`columns`, then :attr:`extra_empty_fields` (each once).
        """
        return tuple(dict.fromkeys([c.key for c in self.columns] + list(self.extra_empty_fields)))

    @abstractmethod
    def load(self, doc: Any, file: ProblemFile, name: str) -> Any:
        """Build the solver-level declaration from a validated document.

        Parameters
        ----------
        doc : ProblemSchema
            The validated document (an instance of :attr:`schema`).
        file : ProblemFile
            The file, for resolving references and naming fields in errors.
        name : str
            The problem name.

        Returns
        -------
        Any
            The declaration.

        Raises
        ------
        ProblemError
            A semantic error (outside the workspace, bad expression, unreadable data).
        """

    @fill_doc(**SHARED_DOCS)
    def solve(self, declaration: Any, *, verbose: bool = False, previous: Any = None, warm_start: bool = False) -> Any:
        """Solve a declaration: by default its own ``solve`` method, with the same arguments.

        Parameters
        ----------
        declaration : Any
            From :meth:`load`.
        {solve_args}

        Returns
        -------
        Any
            The solution; :meth:`status` reads its status.
        """
        return declaration.solve(verbose=verbose, previous=previous, warm_start=warm_start)

    @abstractmethod
    def write(self, declaration: Any, solution: Any, out: Path, plots: bool, name: str) -> Written:
        """Write the data files and plots of a solution into a (new, empty) folder.

        Parameters
        ----------
        declaration : Any
            From :meth:`load`.
        solution : Any
            From :meth:`solve`.
        out : pathlib.Path
            The folder to write into.
        plots : bool
            Write PNG plots.
        name : str
            Problem name (plot titles).

        Returns
        -------
        Written
            Summary fields (``status`` and ``message`` among them) and file names.
        """

    def status(self, solution: Any) -> Status:
        """The status of a solution (default: ``solution.status``).

        Parameters
        ----------
        solution : Any
            From :meth:`solve`.

        Returns
        -------
        Status
        """
        return Status(solution.status)

    def overlay(self, solutions: Mapping[str, Any], out: Path) -> list[str]:
        """Overlay plots of a study's solved cases (default: none).

        Parameters
        ----------
        solutions : Mapping[str, Any]
            Case label -> solution (only cases with a usable solution).
        out : pathlib.Path
            The study folder.

        Returns
        -------
        list of str
            Written file names.
        """
        return []


@dataclass
class Problem:
    """A validated problem file.

    Parameters
    ----------
    path : pathlib.Path
        The file.
    name : str
        Problem name.
    kind : str
        The kind's name.
    description : str
        Free text.
    declaration : Any
        The solver-level declaration built by the kind.
    data : dict
        The parsed file (after overrides), for sweeps.
    overrides : dict
        Fields replaced on load (``--sweep``), field -> value.
    """

    path: Path
    name: str
    kind: str
    description: str
    declaration: Any
    data: dict = field(default_factory=dict, repr=False)
    overrides: dict = field(default_factory=dict)
