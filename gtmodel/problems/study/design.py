"""Study files: a base problem file and a design of cases, expanded to :class:`CaseSpec`.

A study file (TOML, ``gtmodel study STUDY.toml``) names a base problem file and a design:

.. code-block:: toml

    name = "l1_map"                              # optional, default the file stem
    base = "../problems/l1_time_optimal.toml"    # relative to the study file
    analysis = "generic"                         # a key of gtmodel.problems.study.analyses.ANALYSES
    warm_start = false                           # chains along the last axis
    plots = true

    [design]
    combine = "product"                          # or "zip" (axes of equal length)
    [[design.axes]]
    field = "w"                                  # a (dotted) field of the base file
    values = [0.0, 0.001, 0.01]                  # or range / seeds / points

Each axis gives its values by exactly one of ``values`` (TOML literals), ``range``
(``numpy.linspace``, ``integer = true`` to round), ``seeds`` (``first``, ``first + 1``,
...) or ``points`` (a product over ``x``, ``y``, ``z``, each a number or a range: a grid
of 3-vectors, e.g. end poses of a motion). Instead of axes, ``[[design.cases]]`` lists
explicit cases (``label``, ``overrides``). The format is documented in
``docs/study_files.md``.

Every error names the study file and the field (:class:`~gtmodel.errors.ProblemError`).
"""

from __future__ import annotations

import itertools
import json
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Literal, Sequence

import numpy as np
from pydantic import Field, ValidationError

from gtmodel._toml import read_toml
from gtmodel.errors import ProblemError
from gtmodel.problems.study.analyses import ANALYSES
from gtmodel.problems.study.preflight import check_problem_files
from gtmodel.problems.results import is_file_name
from gtmodel.problems.schema import FileName, Flag, NonEmptyText, Section, Text, integer, number, problem_error

__all__ = ["CaseSpec", "Study", "StudySchema", "load_study", "comparison_study", "expand_design", "value_text", "MAX_CASES"]

#: Largest number of cases of one study (a typo such as ``num = 1e9`` fails at once).
MAX_CASES = 1_000_000


_Count = integer(1, MAX_CASES, description="number of values")
_Number = number()


class RangeSpec(Section):
    """``range = { start = 0.0, stop = 1.0, num = 5 }``: ``numpy.linspace(start, stop, num)``.

    Parameters
    ----------
    start : float
        First value.
    stop : float
        Last value (included).
    num : int
        Number of values (1..1e6).
    integer : bool, optional
        Round the values to integers (e.g. a number of poses).
    """

    start: _Number
    stop: _Number
    num: _Count
    integer: Flag = Field(default=False, description="round the values to integers")


class AxisSchema(Section):
    """One ``[[design.axes]]`` entry: a field and its values (exactly one of four forms).

    Parameters
    ----------
    field : str
        Dotted field of the base problem file (a bare name is looked up in
        ``[parameters]`` first), e.g. ``"truth.seed"`` or ``"w"``.
    values : list, optional
        TOML literals of any type (vectors too).
    range : RangeSpec, optional
        Evenly spaced numbers.
    seeds : int, optional
        Number of integer seeds ``first``, ``first + 1``, ...
    first : int, optional
        First seed (default 0; only with ``seeds``).
    points : dict, optional
        ``{x = ..., y = ..., z = ...}``, each a number or a range table: the product grid
        of 3-vectors.
    """

    field: NonEmptyText
    values: list[Any] | None = None
    range: RangeSpec | None = None
    seeds: _Count | None = None
    first: integer(0, 2**62) | None = None
    points: dict[str, Any] | None = None


class CaseSchema(Section):
    """One ``[[design.cases]]`` entry: an explicit case.

    Parameters
    ----------
    label : str, optional
        Case label (default ``case<i>``).
    overrides : dict
        Field -> value, e.g. ``{ w = 0.001, "limits.force" = [500.0, 500.0, 500.0] }``.
    """

    label: NonEmptyText | None = None
    overrides: dict[str, Any] = Field(default_factory=dict)


class DesignSchema(Section):
    """``[design]``: axes (with ``combine``) or explicit cases.

    Parameters
    ----------
    combine : {"product", "zip"}, optional
        Cartesian product of the axes (default) or the axes side by side (equal lengths).
    axes : list of AxisSchema, optional
        The axes.
    cases : list of CaseSchema, optional
        Explicit cases (instead of axes).
    """

    combine: Literal["product", "zip"] = "product"
    axes: list[AxisSchema] | None = None
    cases: list[CaseSchema] | None = None


class StudySchema(Section):
    """Top level of a study file.

    Parameters
    ----------
    name : str, optional
        Study name (default: the file name without ``.toml``).
    description : str, optional
        Free text.
    base : str
        The base problem file, relative to the study file.
    analysis : str, optional
        A key of :data:`~gtmodel.problems.study.analyses.ANALYSES` (default ``"generic"``).
    warm_start : bool, optional
        Solve each row of the design (all columns but the last axis fixed) in order, each
        case starting from the previous solution.
    plots : bool, optional
        Write the plots of the cases and of the analysis (default true).
    design : DesignSchema
        The cases.
    """

    name: FileName | None = None
    description: Text = ""
    base: NonEmptyText
    analysis: NonEmptyText = "generic"
    warm_start: Flag = False
    plots: Flag = True
    design: DesignSchema


@dataclass
class CaseSpec:
    """One case of a study design.

    Parameters
    ----------
    label : str
        Human-readable label, e.g. ``"truth.seed=3,w=0.001"``.
    overrides : dict
        Field -> value applied to the base problem file.
    design : dict
        Table column -> scalar (a 3-vector of a ``points`` axis gives ``<field>.x``,
        ``.y``, ``.z``; other vectors are their TOML text).
    chain : str, optional
        The row of the design this case belongs to (all design columns but the last
        axis'), for warm-started chains.
    base : pathlib.Path, optional
        The case's own problem file (a comparison of several files); default the
        study's base file.
    """

    label: str
    overrides: dict[str, Any]
    design: dict[str, Any]
    chain: str = ""
    base: Path | None = None


@dataclass
class Study:
    """A loaded study file.

    Parameters
    ----------
    path : pathlib.Path or None
        The study file (None for a comparison given on the command line).
    name : str
        Study name.
    description : str
        Free text.
    base : pathlib.Path
        The base problem file (resolved).
    analysis : str
        Key of :data:`~gtmodel.problems.study.analyses.ANALYSES`.
    warm_start : bool
        Warm-started chains along the last axis.
    plots : bool
        Write plots.
    cases : list of CaseSpec
        The expanded design, in order.
    comparison : bool, optional
        A comparison (``gtmodel solve A.toml B.toml`` or ``--sweep``): each case in
        ``DIR/<case>/``, the folder replaced whole when the run ends (nothing is resumed),
        a problem file that cannot be read is its case's status, and the kinds'
        comparison table and overlay plots (:mod:`~gtmodel.problems.study.comparison`).
    reuse : bool, optional
        In this process, solve each chain in order, each case reusing the NLP built for
        the previous one (a sweep over a named parameter), also without ``warm_start``.
    sweep : tuple of (str, list), optional
        The swept field and its values (recorded in the summary).
    """

    path: Path | None
    name: str
    description: str
    base: Path
    analysis: str
    warm_start: bool
    plots: bool
    cases: list[CaseSpec] = field(default_factory=list)
    comparison: bool = False
    reuse: bool = False
    sweep: tuple[str, list[Any]] | None = None


def value_text(value: Any) -> str:
    """A value as short TOML-like text (labels, table cells of vectors).

    Parameters
    ----------
    value : Any
        A TOML value.

    Returns
    -------
    str
        E.g. ``"0.001"``, ``"[500.0,500.0,500.0]"``, ``"true"``, ``'"name"'``.
    """
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        return repr(value)
    if isinstance(value, (list, tuple)):
        return "[" + ",".join(value_text(v) for v in value) + "]"
    if isinstance(value, dict):
        return "{" + ",".join(f"{k}={value_text(v)}" for k, v in value.items()) + "}"
    if isinstance(value, str):
        return json.dumps(value)
    return str(value)


def _cell(value: Any) -> Any:
    return value if isinstance(value, (bool, int, float, str)) else value_text(value)


def load_study(path: str | Path) -> Study:
    """Read, validate and expand a study file.

    Parameters
    ----------
    path : str or pathlib.Path
        The study file (TOML).

    Returns
    -------
    Study
        With its cases expanded (:func:`expand_design`).

    Raises
    ------
    ProblemError
        Unreadable file, TOML syntax error, a missing, unknown or invalid field, a base
        file that does not exist, an unknown analysis, a design without cases or with
        both axes and cases, an axis with not exactly one of ``values``/``range``/
        ``seeds``/``points``, ``zip`` axes of different lengths, more than
        :data:`MAX_CASES` cases. The message names the study file and the field.
    """
    path = Path(path)
    data = read_toml(path, ProblemError, "study file")
    try:
        doc = StudySchema.model_validate(data)
    except ValidationError as exc:
        raise problem_error(path, exc, StudySchema) from None
    base = Path(doc.base) if Path(doc.base).is_absolute() else (path.parent / doc.base).resolve()
    if not base.is_file():
        raise ProblemError(f"{path}: field 'base': expected an existing problem file (relative to {path.parent}), got {doc.base!r}")
    if doc.analysis not in ANALYSES:
        raise ProblemError(f"{path}: field 'analysis': expected one of {', '.join(sorted(ANALYSES))}, got {doc.analysis!r}")
    return Study(path=path, name=doc.name or path.stem, description=doc.description, base=base, analysis=doc.analysis,
                 warm_start=doc.warm_start, plots=doc.plots, cases=expand_design(doc.design, path))


def comparison_study(paths: Sequence[str | Path], sweep: tuple[str, Sequence[Any]] | None = None, warm_start: bool = False,
                     plots: bool = True) -> Study:
    """The study of several problem files, or of one file over a sweep of one field.

    Parameters
    ----------
    paths : sequence of str or pathlib.Path
        Problem files (exactly one with ``sweep``).
    sweep : tuple of (str, sequence), optional
        Field name and its values, e.g. ``("w", [0, 0.001, 0.01])``.
    warm_start : bool, optional
        Start each sweep case from the previous case's solution (in this process).
    plots : bool, optional
        Write PNG plots.

    Returns
    -------
    Study
        Its name is ``<stem>_sweep_<field>`` or ``<stem>_study``; case labels are the
        problem names (``name[w=0.001]`` in a sweep).

    Raises
    ------
    ProblemError
        No files, a sweep with more than one file or without values, a problem file that
        does not exist (names it; nothing is written).
    """
    paths = [Path(p) for p in paths]
    if not paths:
        raise ProblemError("a study needs at least one problem file")
    if sweep is not None and len(paths) != 1:
        raise ProblemError(f"--sweep needs exactly one problem file, got {len(paths)}")
    if sweep is not None and not list(sweep[1]):
        raise ProblemError(f"--sweep {sweep[0]}: expected at least one value")
    check_problem_files(paths)
    cases = []
    if sweep is not None:
        name = _problem_name(paths[0])
        for v in sweep[1]:
            cases.append(CaseSpec(f"{name}[{sweep[0]}={v}]", {sweep[0]: v}, {sweep[0]: _cell(v)}, base=paths[0]))
        study_name = paths[0].stem + "_sweep_" + sweep[0].replace(".", "_")
    else:
        cases = [CaseSpec(_problem_name(p), {}, {}, base=p) for p in paths]
        study_name = paths[0].stem + "_study"
    return Study(path=None, name=study_name, description="", base=paths[0], analysis="generic", warm_start=warm_start,
                 plots=plots, cases=cases, comparison=True, reuse=sweep is not None,
                 sweep=(sweep[0], list(sweep[1])) if sweep is not None else None)


def _problem_name(path: Path) -> str:
    """The ``name`` field of a problem file, else its stem (also for an unreadable file)."""
    try:
        name = read_toml(path, ProblemError, "problem file").get("name")
    except ProblemError:
        return path.stem
    return name if is_file_name(name) else path.stem


def _linspace(r: RangeSpec) -> list[Any]:
    values = np.linspace(r.start, r.stop, r.num)
    return [int(round(v)) for v in values] if r.integer else [float(v) for v in values]


def _axis_values(axis: AxisSchema, where: str, path: Path) -> tuple[list[Any], bool]:
    """The values of one axis, and whether they are 3-vectors of a ``points`` grid."""
    given = [name for name in ("values", "range", "seeds", "points") if getattr(axis, name) is not None]
    if len(given) != 1:
        raise ProblemError(f"{path}: field '{where}': give exactly one of values, range, seeds, points (got {', '.join(given) or 'none'})")
    if axis.first is not None and axis.seeds is None:
        raise ProblemError(f"{path}: field '{where}.first': only with seeds")
    if axis.values is not None:
        if not axis.values:
            raise ProblemError(f"{path}: field '{where}.values': expected at least one value")
        return list(axis.values), False
    if axis.range is not None:
        return _linspace(axis.range), False
    if axis.seeds is not None:
        first = axis.first or 0
        return list(range(first, first + axis.seeds)), False
    points = axis.points or {}
    if sorted(points) != ["x", "y", "z"]:
        raise ProblemError(f"{path}: field '{where}.points': expected the coordinates x, y, z, got {', '.join(sorted(points)) or 'none'}")
    coords = []
    for name in ("x", "y", "z"):
        v = points[name]
        if isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v):
            coords.append([float(v)])
            continue
        try:
            coords.append(_linspace(RangeSpec.model_validate(v)))
        except ValidationError:
            raise ProblemError(f"{path}: field '{where}.points.{name}': expected a number or a range table "
                               f"{{ start = ..., stop = ..., num = ... }}, got {v!r}") from None
    return [list(p) for p in itertools.product(*coords)], True


def expand_design(design: DesignSchema, path: str | Path) -> list[CaseSpec]:
    """The cases of a design, in order (the last axis varies fastest).

    Parameters
    ----------
    design : DesignSchema
        The validated ``[design]`` table.
    path : str or pathlib.Path
        The study file (for messages).

    Returns
    -------
    list of CaseSpec

    Raises
    ------
    ProblemError
        No axes and no cases, both, an invalid axis, ``zip`` of unequal lengths, more
        than :data:`MAX_CASES` cases, two axes over the same field.
    """
    path = Path(path)
    if (design.axes is None) == (design.cases is None) or not (design.axes or design.cases):
        raise ProblemError(f"{path}: field 'design': give exactly one of axes, cases (a non-empty list)")
    if design.cases is not None:
        cases = []
        for i, c in enumerate(design.cases):
            cols = {k: _cell(v) for k, v in c.overrides.items()}
            cases.append(CaseSpec(c.label or f"case{i}", dict(c.overrides), cols, chain=""))
        return cases
    axes = design.axes or []
    fields = [a.field for a in axes]
    dup = sorted({f for f in fields if fields.count(f) > 1})
    if dup:
        raise ProblemError(f"{path}: field 'design.axes': the field {dup[0]!r} has two axes")
    expanded = [_axis_values(a, f"design.axes[{i}]", path) for i, a in enumerate(axes)]
    lengths = [len(v) for v, _ in expanded]
    if design.combine == "zip":
        if len(set(lengths)) != 1:
            raise ProblemError(f"{path}: field 'design.combine': zip needs axes of equal length, got {lengths}")
        combos = list(zip(*(v for v, _ in expanded)))
        chained = set(range(len(axes)))  # one chain: all axes vary together
    else:
        if math.prod(lengths) > MAX_CASES:
            raise ProblemError(f"{path}: field 'design.axes': {math.prod(lengths)} cases, at most {MAX_CASES}")
        combos = list(itertools.product(*(v for v, _ in expanded)))
        chained = {len(axes) - 1}
    cases = []
    for combo in combos:
        overrides: dict[str, Any] = {}
        cols: dict[str, Any] = {}
        labels: list[str] = []
        chain: list[str] = []
        for i, (axis, value, (_, is_point)) in enumerate(zip(axes, combo, expanded)):
            overrides[axis.field] = value
            if is_point:
                cols.update({f"{axis.field}.{c}": v for c, v in zip("xyz", value)})
                text = "[" + ",".join(f"{v:.6g}" for v in value) + "]"
            else:
                cols[axis.field] = _cell(value)
                text = value_text(value)
            labels.append(f"{axis.field}={text}")
            if i not in chained:
                chain.append(labels[-1])
        cases.append(CaseSpec(",".join(labels), overrides, cols, chain=",".join(chain)))
    return cases
