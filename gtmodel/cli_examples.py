"""``gtmodel examples DIR``: the shipped problems, models, studies and loop files copied into a new folder.

::

    gtmodel examples DIR

A user with only ``pip install gtmodel`` has no checkout: the example trees (:data:`EXAMPLES`)
travel in the wheel as ``gtmodel/_examples/`` (``setup.py`` copies them at build time; an
editable install reads them from its checkout). ``DIR`` must be new or empty: nothing of the
user's is overwritten or mixed in. The trees are copied into a folder beside ``DIR`` first and
moved into place once complete, so a failed or interrupted copy leaves no half of one. The
problem files name their models by relative paths (``../models/dc_motor.py``), which the copy
keeps. :mod:`gtmodel.cli` dispatches here.
"""

from __future__ import annotations

import argparse
import os
import shutil
import tempfile
from pathlib import Path
from typing import Any

from gtmodel.errors import GtModelError

__all__ = ["EXAMPLES", "add_examples_parser", "shipped_examples", "copy_examples", "examples_command"]

#: The example trees, as the repository and the wheel hold them (``setup.py``'s ``EXAMPLES``).
EXAMPLES = ("problems", "models", "studies", "loops")
#: The problem the printed command runs (the getting-started problem, a few seconds).
FIRST = "problems/l1_time_optimal.toml"
_SKIPPED = shutil.ignore_patterns("__pycache__", "*.pyc", ".ipynb_checkpoints", "results")


def add_examples_parser(sub: Any) -> argparse.ArgumentParser:
    """Add ``examples`` to the ``gtmodel`` parser.

    Parameters
    ----------
    sub : argparse._SubParsersAction
        The ``gtmodel`` parser's sub-commands.

    Returns
    -------
    argparse.ArgumentParser
        The ``examples`` parser.
    """
    p = sub.add_parser("examples", help="copy the shipped example problems, models, studies and loop files into a new folder",
                       description="Copy the example problems (problems/), the models they use (models/), the studies (studies/) "
                                   "and the robot-loop files (loops/) shipped with gtmodel into DIR, which must be new or empty.")
    p.add_argument("folder", type=Path, metavar="DIR", help="the folder to create (or an empty one), e.g. gtmodel-examples")
    return p


def shipped_examples() -> Path:
    """The folder holding the example trees of this installation.

    Returns
    -------
    pathlib.Path
        ``gtmodel/_examples`` of an installed wheel, or the checkout of an editable install.

    Raises
    ------
    GtModelError
        This installation carries no examples (a package built without ``setup.py``'s hook).
    """
    package = Path(__file__).resolve().parent
    for root in (package / "_examples", package.parent):
        if all((root / tree).is_dir() for tree in ("problems", "models")):
            return root
    raise GtModelError(f"this installation of gtmodel ({package}) carries no example problems: reinstall it from a wheel or "
                       "an sdist of the project (pip install gtmodel), or take problems/ and models/ from its repository")


def copy_examples(folder: str | Path, source: Path | None = None) -> dict[str, int]:
    """Copy the example trees into ``folder``, which must be new or empty.

    Parameters
    ----------
    folder : str or pathlib.Path
        Where to put them.
    source : pathlib.Path, optional
        The folder holding the trees (default :func:`shipped_examples`).

    Returns
    -------
    dict of str to int
        Files copied per tree (only the trees present).

    Raises
    ------
    GtModelError
        ``folder`` exists and is not an empty folder, or cannot be written.
    """
    target = Path(folder)
    if target.is_symlink():
        raise GtModelError(f"{target}: is a symbolic link; give a new or empty folder for the examples")
    if target.exists() and not target.is_dir():
        raise GtModelError(f"{target}: exists and is not a folder; give a new or empty folder for the examples")
    if target.is_dir() and any(target.iterdir()):
        raise GtModelError(f"{target}: the folder is not empty; give a new or empty folder for the examples (nothing was copied)")
    root = source if source is not None else shipped_examples()
    parent = target.resolve().parent
    try:
        parent.mkdir(parents=True, exist_ok=True)
        staging = Path(tempfile.mkdtemp(prefix=f".{target.name}.", suffix=".partial", dir=parent))
    except OSError as exc:
        raise GtModelError(f"{target}: cannot create the folder ({exc.strerror or exc})") from None
    counts: dict[str, int] = {}
    try:
        for tree in EXAMPLES:
            if (root / tree).is_dir():
                shutil.copytree(root / tree, staging / tree, ignore=_SKIPPED)
                counts[tree] = sum(1 for p in (staging / tree).rglob("*") if p.is_file())
        if target.is_dir():
            target.rmdir()  # empty (checked above)
        os.replace(staging, target)
    except OSError as exc:
        raise GtModelError(f"{target}: cannot write the examples ({exc.strerror or exc})") from None
    finally:
        shutil.rmtree(staging, ignore_errors=True)  # gone already when moved into place
    return counts


def examples_command(args: argparse.Namespace) -> int:
    """Run ``gtmodel examples DIR``: copy, then say what was copied and how to run one.

    Parameters
    ----------
    args : argparse.Namespace
        Parsed arguments (``folder``).

    Returns
    -------
    int
        0 when copied.
    """
    counts = copy_examples(args.folder)
    target = Path(args.folder)
    problems = sum(1 for _ in (target / "problems").rglob("*.toml"))
    parts = ", ".join(f"{n} in {tree}/" for tree, n in counts.items())
    print(f"copied {sum(counts.values())} files into {target}/ ({parts}): {problems} problem files")
    print(f"run one:     cd {target} && gtmodel solve {FIRST}")
    print("the schemas their '#:schema' lines name: gtmodel schema --docs docs (in that folder)")
    return 0
