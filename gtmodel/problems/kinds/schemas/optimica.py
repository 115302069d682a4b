"""The schema of an ``optimica`` problem file (light: validated before the kind's solvers are imported).

The kind is :mod:`gtmodel.problems.kinds.optimica`: an Optimica ``optimization`` class of a
``.mop`` file (JModelica.org's ``transfer_optimization_problem(class, file,
compiler_options)``), solved as an ``optimal_control`` problem with the transcription,
verification, refinement and solver settings of that kind's tables. The field reference is
``docs/problem_files.md``; the mapping of a ``.mop`` file is ``docs/optimica.md``.
"""

from __future__ import annotations

from typing import Literal

from pydantic import Field

from gtmodel._docstrings import fill_doc
from gtmodel.problems.base import KIND_DOCS
from gtmodel.problems.kinds.schemas.motion import CollocationSection, VerificationSection
from gtmodel.problems.kinds.schemas.optimal_control import ContinuationSection, ModelSolverSection, TranscriptionSection
from gtmodel.problems.schema import Flag, NonEmptyText, ProblemSchema, Section

__all__ = ["OptimicaSection", "CompilerOptionsSection", "OptimicaFile", "CLASS_PATTERN"]

#: A dotted Modelica class name (``Pkg.Opt``): the pattern of
#: :data:`gtmodel.exchange.optimica_syntax.CLASS_NAME_RE` (a test keeps the two equal).
CLASS_PATTERN = r"[A-Za-z_][A-Za-z0-9_]{0,99}(?:\.[A-Za-z_][A-Za-z0-9_]{0,99}){0,31}"


class OptimicaSection(Section):
    """``[optimica]``: the ``.mop`` file and its ``optimization`` class.

    Parameters
    ----------
    file : str
        The ``.mop`` (or ``.mo``) file, relative to the problem file and inside its folder
        (symbolic links resolved); models it uses may be declared in ``.mo`` files beside it.
    class_ : str
        ``class``: the dotted name of the ``optimization`` class (``"Pkg.Opt"``).
    """

    file: NonEmptyText = Field(description='the .mop file, relative to this file and inside its folder, e.g. "double_integrator_min_time.mop"')
    class_: NonEmptyText = Field(alias="class", pattern=f"^{CLASS_PATTERN}$",
                                 description='the optimization class, dotted inside packages, e.g. "DoubleIntegrator.MinTime"')


class CompilerOptionsSection(Section):
    """``[compiler_options]``: JModelica.org's compiler options that change how the file reads, under their names.

    Parameters
    ----------
    state_start_values_fixed : bool
        Every state's ``start`` is an initial condition, as if declared ``fixed = true``
        (default false: Modelica's semantics, a state's start is a guess unless ``fixed = true``).
    """

    state_start_values_fixed: Flag = Field(False, description="every state's start value is an initial condition (JModelica.org's option; default false: only fixed = true starts are)")


@fill_doc(**KIND_DOCS)
class OptimicaFile(ProblemSchema):
    """An ``optimica`` problem file.

    Parameters
    ----------
    {header_fields}
    optimica : OptimicaSection
        ``[optimica]``: the ``.mop`` file and the class.
    compiler_options : CompilerOptionsSection
        ``[compiler_options]``: JModelica.org's options (``state_start_values_fixed``).
    transcription : TranscriptionSection
        ``[transcription]``: collocation or multiple shooting, verification tolerance and
        mesh refinement (as ``optimal_control``).
    verification : VerificationSection
        ``[verification]``: whether and with which integrator the solution is verified.
    collocation : CollocationSection
        ``[collocation]``: the collocation mesh.
    solver : ModelSolverSection
        ``[solver]``: the NLP solver and its settings.
    continuation : ContinuationSection
        ``[continuation]``: the continuation over the model's smoothing widths.
    """

    kind: Literal["optimica"]
    optimica: OptimicaSection
    compiler_options: CompilerOptionsSection = CompilerOptionsSection()
    transcription: TranscriptionSection = TranscriptionSection()
    verification: VerificationSection = VerificationSection()
    collocation: CollocationSection = CollocationSection()
    solver: ModelSolverSection = ModelSolverSection()
    continuation: ContinuationSection = ContinuationSection()
