"""The problem layer: problem files (TOML) -> declarations -> solutions -> result folders.

A problem file declares one problem; its ``kind`` selects a :class:`ProblemKind` from the
registry (:data:`KINDS`), whose pydantic schema validates the file (every error names the
file and the dotted field) and whose ``load``/``solve``/``write`` do the rest. The field
reference of every kind is ``docs/problem_files.md`` (generated from the schemas); the
JSON Schema of a kind is ``gtmodel schema KIND``.

Modules: :mod:`~gtmodel.problems.base` (the protocol), :mod:`~gtmodel.problems.schema`
(field types, validation), :mod:`~gtmodel.problems.registry`,
:mod:`~gtmodel.problems.kinds` (one module per kind), :mod:`~gtmodel.problems.run`
(load/solve/write one file), :mod:`~gtmodel.problems.results` (result folders),
:mod:`~gtmodel.problems.study` (several files or a sweep, comparison table),
:mod:`~gtmodel.problems.study_file` / :mod:`~gtmodel.problems.study_engine` (study files on Dask),
:mod:`~gtmodel.problems.docs` (reference page and JSON Schemas).
"""

from gtmodel.problems.base import Column, Problem, ProblemFile, ProblemKind, Written
from gtmodel.problems.registry import KINDS, get_kind
from gtmodel.problems.run import RunOutcome, load_problem, run_problem, solve_problem, write_results

__all__ = [
    "KINDS",
    "get_kind",
    "Column",
    "Problem",
    "ProblemFile",
    "ProblemKind",
    "Written",
    "RunOutcome",
    "load_problem",
    "run_problem",
    "solve_problem",
    "write_results",
]
