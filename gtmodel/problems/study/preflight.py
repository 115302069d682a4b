"""Checks made before anything heavy is imported or anything is written.

A mistyped problem path, or an output folder whose name is taken by a file, is reported
at once, with one message and no folder created (the ``gtmodel`` command runs these
before it imports the problem layer). Only the standard library, :mod:`gtmodel.errors` and
the result-folder rule of :mod:`gtmodel.problems.results` (standard library too) are
imported here.
"""

from __future__ import annotations

from pathlib import Path
from typing import Sequence

from gtmodel.errors import ProblemError
from gtmodel.problems.results import check_output_folder

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
