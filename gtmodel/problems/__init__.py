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
:mod:`~gtmodel.problems.study` (one engine for study files, comparisons of several files
and sweeps, locally or on Dask), :mod:`~gtmodel.problems.docs` (reference page and JSON
Schemas).

The names below are imported on first use (:mod:`gtmodel._lazy`), so that the
``gtmodel`` command starts without importing the whole stack.
"""

from gtmodel._lazy import lazy_exports

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

__getattr__, __dir__ = lazy_exports(__name__, {
    "KINDS": "registry", "get_kind": "registry",
    "Column": "base", "Problem": "base", "ProblemFile": "base", "ProblemKind": "base", "Written": "base",
    "RunOutcome": "run", "load_problem": "run", "run_problem": "run", "solve_problem": "run", "write_results": "run",
})
