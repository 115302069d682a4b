"""Kind ``optimica``: an Optimica ``optimization`` class of a ``.mop`` file, solved as an ``optimal_control`` problem.

A problem file names the file and the class, and JModelica.org's compiler options under
their names (JModelica.org's ``transfer_optimization_problem(class, file, compiler_options)``)::

    kind = "optimica"
    [optimica]
    file = "double_integrator_min_time.mop"   # relative to this file, inside its folder
    class = "DoubleIntegrator.MinTime"
    [compiler_options]
    state_start_values_fixed = false

and, as an ``optimal_control`` file, ``[collocation]``, ``[transcription]``,
``[verification]``, ``[solver]`` and ``[continuation]``. The class is read by
:func:`gtmodel.exchange.optimica.load_optimica` and declared by :func:`optimica_declaration`,
the one path also of ``gtmodel solve FILE.mop --class NAME``
(:mod:`gtmodel.problems.optimica_run`, with the tables' defaults). The declaration is an
:class:`~gtmodel.trajectory.model_ocp.OptimalControl`: solved, verified, refined and written
as the ``optimal_control`` kind's (this kind is that kind with another file).
"""

from __future__ import annotations

import logging
import stat
from pathlib import Path
from types import SimpleNamespace
from typing import Any

from gtmodel._docstrings import fill_doc
from gtmodel.errors import GtModelError
from gtmodel.exchange.optimica import load_optimica
from gtmodel.exchange.optimica_syntax import CLASS_NAME_RE, OptimicaError
from gtmodel.modeling import Optimization
from gtmodel.modeling.ocp.methods import SolverSettings
from gtmodel.problems.base import KIND_DOCS, ProblemFile
from gtmodel.problems.kinds.optimal_control import OptimalControlKind, _continuation, _method, _refinement, _scalar_variables
from gtmodel.problems.kinds.schemas.optimica import OptimicaFile
from gtmodel.trajectory.model_ocp import OptimalControl

__all__ = ["OptimicaKind", "OptimicaFile", "optimica_declaration", "optimica_file", "default_settings", "SUFFIXES"]

_log = logging.getLogger("gtmodel")

#: File endings an ``optimica.file`` may have.
SUFFIXES = (".mop", ".mo")
#: The tables of an ``optimica`` file that set how the class is solved (their defaults: :func:`default_settings`).
SETTINGS = ("transcription", "verification", "collocation", "solver", "continuation")


def default_settings() -> Any:
    """The solve settings of an ``optimica`` file that gives none of its tables (``gtmodel solve FILE.mop``).

    Returns
    -------
    types.SimpleNamespace
        ``transcription``, ``verification``, ``collocation``, ``solver``, ``continuation``: the
        schema's defaults (direct collocation, verification by simulation, refinement on a
        failed verification, IPOPT).
    """
    fields = OptimicaFile.model_fields
    return SimpleNamespace(**{k: fields[k].default for k in SETTINGS})


def optimica_file(file: ProblemFile, field: str, ref: str) -> Path:
    """Resolve the ``.mop`` file a problem file names: inside the problem file's folder, a regular ``.mop``/``.mo`` file.

    Parameters
    ----------
    file : ProblemFile
        The problem file.
    field : str
        Dotted field name (``"optimica.file"``).
    ref : str
        The path written in the file (relative to the problem file; an absolute path must
        lie inside its folder too).

    Returns
    -------
    pathlib.Path
        The resolved path (symbolic links resolved).

    Raises
    ------
    ProblemError
        Naming the problem file and ``field``: no such file, a path that resolves outside the
        problem file's folder (``..``, an absolute path elsewhere, a symbolic link out), not a
        regular file, or another ending than ``.mop``/``.mo``.
    """
    folder = file.path.parent.resolve()
    try:
        target = Path(ref) if Path(ref).is_absolute() else folder / ref
        real = target.resolve(strict=True)
        mode = real.stat().st_mode
    except (OSError, RuntimeError, ValueError):  # missing, a loop of links, a NUL byte, a name too long
        raise file.fail(field, f"an existing .mop file inside the problem file's folder {folder}", ref) from None
    if not real.is_relative_to(folder):
        raise file.fail(field, f"a .mop file inside the problem file's folder {folder} (symbolic links resolved)", ref)
    if not stat.S_ISREG(mode):
        raise file.fail(field, "a regular .mop file (not a folder, device, FIFO or socket)", ref)
    if real.suffix.lower() not in SUFFIXES:
        raise file.fail(field, f"a Modelica/Optimica source file ({', '.join(SUFFIXES)})", ref)
    return real


def optimica_declaration(path: Path, class_name: str, *, state_start_values_fixed: bool, settings: Any, file: ProblemFile,
                         name: str) -> OptimalControl:
    """Read an Optimica class and declare it as the ``optimal_control`` kind's declaration (the one path of both routes).

    Parameters
    ----------
    path : pathlib.Path
        The ``.mop`` file (resolved and checked by the caller).
    class_name : str
        The ``optimization`` class (``"Pkg.Opt"``).
    state_start_values_fixed : bool
        JModelica.org's compiler option (:func:`~gtmodel.exchange.optimica.load_optimica`).
    settings : Any
        The ``transcription``, ``verification``, ``collocation``, ``solver`` and
        ``continuation`` tables (an :class:`~gtmodel.problems.kinds.schemas.optimica.OptimicaFile`,
        or :func:`default_settings`).
    file : ProblemFile
        The file whose fields the settings' errors name.
    name : str
        The problem name.

    Returns
    -------
    OptimalControl
        The class's :class:`~gtmodel.modeling.Optimization` with the settings' method,
        solver, verification, refinement and continuation.

    Raises
    ------
    OptimicaError
        The class cannot be read (naming the ``.mop`` file, line and construct).
    ProblemError
        A setting that does not fit the model (naming ``file`` and the field).
    """
    opt = load_optimica(path, class_name, state_start_values_fixed=state_start_values_fixed)
    sol = settings.solver
    bounds = {}
    flat = opt.model.flatten()
    for kind, names in (("x", flat.x_vars), ("u", flat.u_vars), ("z", flat.z_vars)):
        lb, ub = opt.bounds_vectors(flat, kind)
        for n, sl in names.items():
            if sl.stop - sl.start == 1:
                bounds[n] = (float(lb[sl.start]), float(ub[sl.start]))
    return OptimalControl(
        name=name, model_file=path, class_name=opt.optimica["class"], optimization=opt,
        method=_method(file, settings, opt),
        solver=SolverSettings(name=sol.name, max_iter=sol.max_iter, tol=sol.tol, jit=sol.jit),
        objective=objective_text(opt), sense="minimize", constraints=tuple(opt.optimica["constraints"]),
        bounds=bounds, refinement=_refinement(file, settings), continuation=_continuation(file, settings),
        variables=tuple(n for n, (k, _) in _scalar_variables(opt.model).items() if k in ("algebraic", "output")),
    )


def objective_text(opt: Optimization) -> str:
    """The objective of an Optimica class as text for the summary: the Mayer term, then ``integral(...)`` of the Lagrange term.

    Parameters
    ----------
    opt : Optimization
        From :func:`~gtmodel.exchange.optimica.load_optimica`.

    Returns
    -------
    str
        ``"0"`` for no objective.
    """
    parts = [] if opt.mayer.is_zero() else [str(opt.mayer)]
    if not opt.lagrange.is_zero():
        parts.append(f"integral({opt.lagrange})")
    return " + ".join(parts) or "0"


def _field_of(error: OptimicaError) -> str:
    """The field an error of the class's reading belongs to: the class not found -> ``optimica.class``, else the file."""
    text = str(error)
    return "optimica.class" if "optimization classes in the file" in text or "is not a dotted Modelica name" in text else "optimica.file"


class OptimicaKind(OptimalControlKind):
    """An Optimica ``optimization`` class of a ``.mop`` file ([optimica] file and class), as ``optimal_control``."""

    name = "optimica"
    schema = OptimicaFile
    title = "an Optimica optimization class of a .mop file ([optimica] file and class, [compiler_options]) solved as optimal_control"

    @fill_doc(**KIND_DOCS)
    def load(self, doc: OptimicaFile, file: ProblemFile, name: str) -> OptimalControl:
        """Read the class and declare it (see :meth:`ProblemKind.load`).

        Parameters
        ----------
        {load_args}

        Returns
        -------
        OptimalControl

        Raises
        ------
        ProblemError
            Naming the problem file and the field: ``optimica.file`` missing, outside the
            problem file's folder or unreadable as Optimica (the message then names the
            ``.mop`` file, line and construct), ``optimica.class`` not an ``optimization``
            class of it, a setting that does not fit the model.
        """
        path = optimica_file(file, "optimica.file", doc.optimica.file)
        cls = doc.optimica.class_
        if not CLASS_NAME_RE.fullmatch(cls):  # the schema's pattern; kept here for a document built in Python
            raise file.fail("optimica.class", "a dotted Modelica class name (Pkg.Opt)", cls)
        try:
            return optimica_declaration(path, cls, state_start_values_fixed=doc.compiler_options.state_start_values_fixed,
                                        settings=doc, file=file, name=name)
        except OptimicaError as exc:
            raise file.wrap(_field_of(exc), exc) from None
        except GtModelError as exc:
            raise file.wrap("optimica.file", exc) from None
