"""Studies: many cases of problem files, on one engine, locally or on a Dask cluster.

One engine (:func:`run_study`) runs a study file (``gtmodel study STUDY.toml``), a
comparison of several problem files (``gtmodel solve A.toml B.toml --out DIR``) and a
sweep of one field (``gtmodel solve A.toml --sweep w=0,0.001``); it returns one result
type, :class:`StudyOutcome`, whose status maps to the exit code by the one table of
:mod:`gtmodel.status`.

Modules, by job:

- :mod:`~gtmodel.problems.study.design`: study files and comparisons -> the cases;
- :mod:`~gtmodel.problems.study.preflight`: input checks before anything is imported or written;
- :mod:`~gtmodel.problems.study.engine`: the engine (plan, skip finished, execute, table, summary);
- :mod:`~gtmodel.problems.study.cases`: case keys and folders, one case solved (the worker's part);
- :mod:`~gtmodel.problems.study.executors`: in this process or on Dask;
- :mod:`~gtmodel.problems.study.table`: the tidy table of the cases;
- :mod:`~gtmodel.problems.study.comparison`: the kinds' comparison table and overlay plots;
- :mod:`~gtmodel.problems.study.progress`: the progress bar or log lines;
- :mod:`~gtmodel.problems.study.analysis` and :mod:`~gtmodel.problems.study.analyses`:
  what a study computes from its table.

The names below are imported on first use (:mod:`gtmodel._lazy`).
"""

from gtmodel._lazy import lazy_exports

__all__ = ["run_study", "solve_study", "plan_cases", "StudyOutcome", "Study", "CaseSpec", "load_study", "comparison_study",
           "StudyCase", "write_comparison", "comparison_columns", "CaseRecord", "CaseTask", "StudyAnalysis", "ANALYSES"]

__getattr__, __dir__ = lazy_exports(__name__, {
    "run_study": "engine", "solve_study": "engine", "plan_cases": "engine", "StudyOutcome": "engine",
    "Study": "design", "CaseSpec": "design", "load_study": "design", "comparison_study": "design",
    "StudyCase": "comparison", "write_comparison": "comparison", "comparison_columns": "comparison",
    "CaseRecord": "cases", "CaseTask": "cases", "StudyAnalysis": "analysis", "ANALYSES": "analyses",
})
