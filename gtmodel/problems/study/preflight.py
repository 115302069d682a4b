"""Checks made before anything heavy is imported or anything is written.

A mistyped problem path, or an output folder whose name is taken by a file, is reported
at once, with one message and no folder created (the ``gtmodel`` command runs these
before it imports the problem layer). Only the standard library and
:mod:`gtmodel.errors` are imported here.
"""

from __future__ import annotations

from pathlib import Path
from typing import Sequence

from gtmodel.errors import ProblemError, ResultWriteError

__all__ = ["check_problem_files", "check_output_folder"]


def check_problem_files(paths: Sequence[str | Path], what: str = "problem file") -> None:
    """Check that every input file exists (a mistyped path writes nothing).

    Parameters
    ----------
    paths : sequence of str or pathlib.Path
        Problem files (or study files).
    what : str, optional
        What the files are, for the message.

    Raises
    ------
    ProblemError
        The first path that is not an existing file (names it).
    """
    for p in paths:
        if not Path(p).is_file():
            why = "it is a folder" if Path(p).is_dir() else "no such file"
            raise ProblemError(f"{p}: cannot read the {what} ({why})")


def check_output_folder(out: str | Path) -> None:
    """Check that a result or study folder can be created where asked.

    Parameters
    ----------
    out : str or pathlib.Path
        The folder (it may exist: a folder is replaced or resumed, never a file).

    Raises
    ------
    ResultWriteError
        ``out``, or a parent of it, is an existing file (names it).
    """
    out = Path(out)
    for p in (out, *out.parents):
        if p.exists() or p.is_symlink():
            if not p.is_dir():
                why = "a file of that name is in the way" if p == out else f"its parent {p} is a file"
                raise ResultWriteError(f"cannot write the result folder {out}: {why}")
            return
