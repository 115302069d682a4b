"""Kind ``optimal_control``: an optimal control problem on the user's own model.

``[model] file = "models/cart_pendulum.py"`` (relative to the problem file) and
``class = "CartPendulum"`` name a class whose instance is, or builds, a
:class:`gtmodel.modeling.Model` (the protocol: :mod:`gtmodel.problems.user_model`); the
file is the user's own code, imported as such. Everything else in the problem file is
data: parameter overrides, boundary conditions, bounds, and the objective and constraints
in the problem language over the model's variable names (:mod:`gtmodel.modeling.ocp.expressions`,
``docs/problem_language.md``: parsed, never evaluated). A composed model's hierarchical
names (``mass.s``, ``spring.c``) are written with ``_`` for ``.`` in expressions
(``mass_s``; the language has no attribute access) and may be written either way as keys
of the tables (``"mass.s" = 0.0`` or ``mass_s = 0.0``). The problem is declared as a
:class:`~gtmodel.modeling.Optimization` and solved by direct collocation
(:class:`~gtmodel.modeling.CollocationTranscription`, IPOPT) or, with ``[transcription]
method = "multiple_shooting"``, by direct multiple shooting
(:class:`~gtmodel.modeling.ocp.shooting.ShootingTranscription`). The initial guess
(``[initial_guess]``) is :mod:`gtmodel.problems.kinds.optimal_control_guess`; measured
data fitted by least squares (``[[data]]``, parameter estimation) is
:mod:`gtmodel.problems.kinds.optimal_control_data`, its estimates and residual statistics
in the summary's ``estimation`` block.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import logging
import re

import casadi as ca
import numpy as np

from gtmodel._docstrings import fill_doc
from gtmodel.errors import GtModelError, InputError, ModelError
from gtmodel.modeling import Model, Optimization, OptimizationResult, apply_to, optimization_names, parse_expression
from gtmodel.modeling.ocp.budget import check_shooting_memory
from gtmodel.modeling.ocp.diagnostics import solution_warnings
from gtmodel.modeling.ocp.suggestions import MSL_NAMES, close_names
from gtmodel.modeling.ocp.initial import InitialConditionConflict, fixed_starts
from gtmodel.modeling.ocp.shooting_steps import EXPLICIT_INTEGRATORS, explicit_algebraics
from gtmodel.modeling.ocp.verification import skipped
from gtmodel.problems.base import KIND_DOCS, Column, ProblemFile, ProblemKind, Written
from gtmodel.problems.kinds.optimal_control_data import declare_data
from gtmodel.problems.kinds.optimal_control_guess import declare_initial_guess
from gtmodel.problems.kinds.schemas.optimal_control import MAX_VALUE, OptimalControlFile, OptimizationSection
from gtmodel.problems.references import named_parameters
from gtmodel.problems.results import json_safe, verification_fields
from gtmodel.problems.user_model import ModelFileError, load_user_model
from gtmodel.report.model_trajectory import plot_signals
from gtmodel.modeling.ocp.methods import MultipleShooting
from gtmodel.trajectory.model_ocp import OptimalControl
from gtmodel.modeling.ocp.continuation import Continuation
from gtmodel.modeling.ocp.methods import Collocation, Refinement, SolverSettings

__all__ = ["OptimalControlKind", "OptimalControlFile", "OptimalControl", "MAX_VALUE"]

_log = logging.getLogger("gtmodel")


def _scalar_variables(model: Model) -> dict[str, tuple[str, ca.SX]]:
    """Scalar states, inputs, algebraics and outputs by name: ``name -> (kind, symbol or expression)``.

    The outputs of a reduced model are the aliases the reduction eliminated (``motor.phi``
    of a motor behind a gear): every variable of the user's model can be named.
    """
    out = {}
    for kind in ("state", "input", "algebraic"):
        for name, sym in model.variables(kind).items():
            if sym.numel() == 1:
                out[name] = (kind, sym)
    for name, expr in model.outputs.items():
        if expr.numel() == 1 and name not in out:
            out[name] = ("output", expr)
    return out


def _shown_variables(file: ProblemFile, names: list[str], opt: Optimization, variables: dict[str, tuple[str, ca.SX]],
                     vkeys: dict[str, str]) -> tuple[str, ...]:
    """The variables of ``variables.png``: ``[output] variables`` checked by name; by default, for a
    reduced model, the scalar states of the model as written (the variables the user thinks in)."""
    for k, key in enumerate(names):
        if key not in vkeys:
            raise _unknown(file, f"output.variables[{k}]", key, variables)
    if names:
        return tuple(vkeys[k] for k in names)
    if opt.user_model is opt.model:
        return ()
    return tuple(n for n, sym in opt.user_model.variables("state").items() if sym.numel() == 1 and n in variables)


def _final_time(file: ProblemFile, opt: OptimizationSection) -> dict[str, Any]:
    """Keyword arguments of :class:`Optimization` for the horizon, checked."""
    t0, ft, ftn = opt.start_time, opt.final_time, "optimization.final_time"
    if not ft.free:
        if ft.value is None:
            raise file.fail(f"{ftn}.value", "the final time [s] when free = false")
        if not ft.value > t0:
            raise file.fail(f"{ftn}.value", f"a final time after start_time ({t0})", ft.value)
        for key in ("bounds", "initial_guess"):
            if getattr(ft, key) is not None:
                raise file.fail(f"{ftn}.{key}", "no bounds or initial guess when free = false (the final time is value)")
        return {"start_time": t0, "final_time": ft.value}
    if ft.bounds is None:
        raise file.fail(f"{ftn}.bounds", "bounds [lo, hi] for a free final time (free = true)")
    lo, hi = ft.bounds
    if not t0 < lo <= hi:
        raise file.fail(f"{ftn}.bounds", f"[lo, hi] with start_time ({t0}) < lo <= hi", ft.bounds)
    if ft.value is not None:
        raise file.fail(f"{ftn}.value", "no fixed value when free = true (use initial_guess)")
    guess = ft.initial_guess if ft.initial_guess is not None else 0.5 * (lo + hi)
    if not lo <= guess <= hi:
        raise file.fail(f"{ftn}.initial_guess", f"a time within {ftn}.bounds {ft.bounds}", guess)
    return {"start_time": t0, "final_time": guess, "free_final_time": True, "final_time_bounds": (lo, hi)}


def _aliases(names: Any) -> dict[str, str]:
    """Key -> declared name: every name, and a hierarchical one (``mass.s``) also as ``mass_s`` (if not taken)."""
    out = {n: n for n in names}
    for n in names:
        alias = re.sub(r"[^A-Za-z0-9_]", "_", n)
        out.setdefault(alias, n)
    return out


def _bound_value(file: ProblemFile, field_: str, value: float | str, table: dict[str, Any], numeric: bool = False) -> Any:
    """One side of a ``[lo, hi]`` pair: a number, or an expression of parameters (a number or, unless ``numeric``, an SX)."""
    if not isinstance(value, str):
        return float(value)
    e = parse_expression(value, table, str(file.path), field_)
    if not ca.symvar(e):
        return float(ca.DM(ca.evalf(e)))
    if numeric:
        raise file.fail(field_, "numbers or expressions of [parameters] names", value)
    return e


def _objective(file: ProblemFile, opt: OptimizationSection, data: bool) -> tuple[str | None, str | None, str]:
    """The objective text, its sense and its field: exactly one of objective, minimize, maximize (none with data)."""
    given = [(k, getattr(opt, k)) for k in ("objective", "minimize", "maximize") if getattr(opt, k) is not None]
    if len(given) > 1:
        raise file.fail(f"optimization.{given[1][0]}", f"one objective (optimization.{given[0][0]} is given too)")
    if not given:
        if data:
            return None, "minimize", "objective"
        raise file.fail("optimization.objective", "an objective (objective, minimize or maximize) or [[data]] to fit")
    key, text = given[0]
    return text, "maximize" if key == "maximize" else "minimize", key


def _unknown(file: ProblemFile, field_: str, name: str, known: Any) -> Exception:
    close = close_names(name, known)
    hint = f"did you mean {', '.join(repr(c) for c in close)}? " if close else ""
    last = str(name).rpartition(".")[2]
    if close and MSL_NAMES.get(last.lower()) and close[0].endswith("." + MSL_NAMES[last.lower()]):
        hint += f"(the Modelica Standard Library's name of {last} is {MSL_NAMES[last.lower()]}) "
    return file.fail(field_, f"one of the model's names: {hint}(all: {', '.join(sorted(known)) or 'none'})", name)


class OptimalControlKind(ProblemKind):
    """Optimal control of a user's model (:class:`~gtmodel.modeling.Optimization`, collocation)."""

    name = "optimal_control"
    schema = OptimalControlFile
    title = "optimal control or parameter estimation on the user's own model ([model] file and class), by direct collocation or multiple shooting"
    file_descriptions = {
        "trajectories.csv": "time, kind of point, states, inputs, algebraic variables and outputs, headers with units",
        "states.png": "the states against time with their bounds",
        "inputs.png": "the inputs against time with their bounds, as verified (between the points, clipped to the bounds)",
        "variables.png": "algebraic variables and outputs against time with their bounds",
    }
    columns = (
        Column("final_time_s", "T_final [s]", "{:.4f}"),
        Column("objective", "objective", "{:.6g}"),
        Column("iterations", "iterations", "{}"),
        Column("solve_time_s", "solve time [s]", "{:.3f}"),
    )
    extra_empty_fields = ("max_constraint_violation",)

    @fill_doc(**KIND_DOCS)
    def load(self, doc: OptimalControlFile, file: ProblemFile, name: str) -> OptimalControl:
        """Import the model and declare the :class:`~gtmodel.modeling.Optimization` (see :meth:`ProblemKind.load`).

        Parameters
        ----------
        {load_args}

        Returns
        -------
        OptimalControl

        Raises
        ------
        ProblemError
            The model file is missing or fails (syntax error, no such class, not a
            Model), an unknown parameter or variable name, inconsistent final-time
            settings, an invalid expression; the message names the file and the field.
        """
        path = Path(file.reference("model.file", doc.model.file))
        try:
            written = load_user_model(path, doc.model.class_, reduce=False)  # Optimization reduces it
        except ModelFileError as exc:
            raise file.wrap("model.file", exc) from None
        except GtModelError as exc:
            raise file.wrap("model.class", exc) from None
        final_time = _final_time(file, doc.optimization)  # its ProblemError already names the file and field
        try:
            opt = Optimization(written, **final_time)
        except ModelError as exc:
            raise file.wrap("model.class", ModelError(f"{path}: class {doc.model.class_}: {exc}")) from None
        except GtModelError as exc:
            raise file.wrap("optimization.final_time", exc) from None
        model = opt.model  # the model as written, or reduced to index 1 (simulate()'s reduction)
        params = model.variables("parameter")
        pkeys = _aliases(params)
        for key, value in doc.model.parameters.items():
            if key not in pkeys:
                raise _unknown(file, f"model.parameters.{key}", key, params)
            if params[pkeys[key]].numel() != 1:
                raise file.fail(f"model.parameters.{key}", f"a scalar parameter ({key!r} has {params[pkeys[key]].numel()} elements)")
            try:
                opt.set_parameter(pkeys[key], value)
            except GtModelError as exc:
                raise file.fail(f"model.parameters.{key}", f"a value in the parameter's range ({exc})") from None
        origin = str(file.path)
        named = named_parameters(file, doc.parameters, set(_aliases(optimization_names(opt, origin=origin))) | {"pi"})
        table = optimization_names(opt, named, origin=origin)
        table = {k: table[n] for k, n in _aliases(table).items() if k.isidentifier()}
        for key, pair in doc.free_parameters.items():
            if key not in pkeys:
                raise _unknown(file, f"free_parameters.{key}", key, params)
            lo, hi = (_bound_value(file, f"free_parameters.{key}", v, table, numeric=True) for v in pair)
            if lo > hi:
                raise file.fail(f"free_parameters.{key}", "[lo, hi] with lo <= hi", [lo, hi])
            opt.free_parameter(pkeys[key], lo, hi)
        variables = _scalar_variables(model)
        vkeys = _aliases(variables)
        bounds: dict[str, tuple[float, float]] = {}
        for key, pair in doc.bounds.items():
            if key not in vkeys:
                raise _unknown(file, f"bounds.{key}", key, variables)
            lo, hi = (_bound_value(file, f"bounds.{key}", v, table) for v in pair)
            if isinstance(lo, float) and isinstance(hi, float) and lo > hi:
                raise file.fail(f"bounds.{key}", "[lo, hi] with lo <= hi", [lo, hi])
            try:
                opt.set_bounds(variables[vkeys[key]][1], lo, hi)
            except GtModelError as exc:
                raise file.wrap(f"bounds.{key}", exc) from None
            if isinstance(lo, float) and isinstance(hi, float):
                bounds[vkeys[key]] = (lo, hi)
        boundary = {at: {vkeys.get(k, k): v for k, v in getattr(doc.boundary, at).items()} for at in ("start", "final")}
        for at in ("start", "final"):
            for key, value in getattr(doc.boundary, at).items():
                if key not in vkeys:
                    raise _unknown(file, f"boundary.{at}.{key}", key, variables)
                lo, hi = bounds.get(vkeys[key], (-np.inf, np.inf))
                if not lo <= value <= hi:  # SciPy-style up-front: no solver run ends "infeasible" for a contradiction in the file
                    raise file.fail(f"boundary.{at}.{key}", f"a value within [bounds] {vkeys[key]} = [{lo:g}, {hi:g}] "
                                    "(the boundary value and the bound cannot both hold)", value)
                opt.add_point_constraint(variables[vkeys[key]][1], at=at, lb=value, ub=value, name=f"boundary.{at}.{key}")
        objective, sense, objective_key = _objective(file, doc.optimization, bool(doc.data))
        apply_to(opt, objective, doc.optimization.constraints, names=table, origin=origin, prefix="optimization.", sense=sense,
                 objective_key=objective_key)
        fit = declare_data(file, doc.data, opt, table)
        if fit is not None:
            if sense == "maximize":
                raise file.fail("optimization.maximize", "a minimised objective with [[data]] (the fit is a sum of squares)")
            opt.set_objective(mayer=opt.mayer + fit, sense="minimize")
        try:  # the model's fixed starts are initial conditions unless the file states its own (conflicts named here)
            fixed = fixed_starts(opt)
        except InitialConditionConflict as exc:
            raise file.wrap(exc.constraint if exc.constraint.startswith(("boundary.", "optimization.")) else "boundary.start",
                            exc) from None
        boundary["start"] = {**{n: v for n, v in fixed.items() if n in variables}, **boundary["start"]}
        nkeys = {**vkeys, "final_time": "final_time", **{k: n for k, n in pkeys.items() if n in opt.free_parameters}}
        for key in doc.nominal:
            if key not in nkeys:
                raise _unknown(file, f"nominal.{key}", key, set(variables) | {"final_time"} | set(opt.free_parameters))
        declare_initial_guess(file, doc.initial_guess, opt, boundary, variables, vkeys, table,
                              doc.optimization.final_time.initial_guess is not None)
        method = _method(file, doc, opt)
        shown = _shown_variables(file, doc.output.variables, opt, variables, vkeys)
        bench = doc.benchmark.model_dump() if doc.benchmark is not None else None
        if bench is not None and bench["sign"] not in (1.0, -1.0):
            raise file.fail("benchmark.sign", "1 or -1", bench["sign"])
        return OptimalControl(
            name=name, model_file=path, class_name=doc.model.class_, optimization=opt,
            method=method,
            solver=SolverSettings(name=doc.solver.name, max_iter=doc.solver.max_iter, tol=doc.solver.tol, jit=doc.solver.jit),
            nominal={nkeys[k]: v for k, v in doc.nominal.items()},
            objective=objective or "", sense=sense or "minimize", constraints=tuple(doc.optimization.constraints),
            named_parameters=named, bounds=bounds,
            refinement=_refinement(file, doc),
            benchmark=bench, variables=shown,
            continuation=_continuation(file, doc),
        )

    @fill_doc(**KIND_DOCS)
    def write(self, declaration: OptimalControl, solution: OptimizationResult, out: Path, plots: bool, name: str) -> Written:
        """Summary fields; ``trajectories.csv`` and plots of the states and inputs.

        Nothing but the summary fields is written for a failed solve (its last iterate
        is not a trajectory); a solution that failed its verification (``check_failed``)
        is written with its ``verification`` block, to be inspected.

        Parameters
        ----------
        declaration : OptimalControl
            The declaration.
        solution : OptimizationResult
            Its solution.
        {write_args}

        Returns
        -------
        Written
        """
        d, r = declaration, solution
        written = Written({
            "status": r.status,
            "message": r.message,
            "objective": r.objective,
            "final_time_s": r.final_time,
            "iterations": r.iterations,
            "solve_time_s": r.solve_time,
            "max_constraint_violation": r.max_constraint_violation,
            "last_iterate": r.last_iterate,
            "objective_expression": d.objective,
            "objective_sense": d.sense,
            "constraints": list(d.constraints),
            "parameters": dict(d.named_parameters),
            "model": {"file": str(d.model_file), "class": d.class_name, "name": d.model.name,
                      "states": list(d.model.flatten().x_names)},
            "free_parameters": sorted(d.optimization.free_parameters),
            "model_parameters": {k: float(np.ravel(v)[0]) if np.size(v) == 1 else np.ravel(v).tolist() for k, v in r.parameters.items()},
            "free_final_time": d.optimization.free_final_time,
            **({"estimation": d.estimation} if d.estimation is not None else {}),
            "transcription": _transcription_summary(d.method, r),
            **({"collocation": {"elements": d.method.elements, "points": d.method.points, "scheme": d.method.scheme}}
               if isinstance(d.method, Collocation) else {}),
            **verification_fields(r),
            **({"continuation": json_safe(r.continuation)} if r.continuation else {}),
            **_variable_fields(d, r),
        })
        warnings = solution_warnings(d.optimization, r)
        if not d.refinement.verify and r.status in ("optimal", "acceptable"):
            written.fields["verification"] = skipped("not verified: [verification] enabled = false")
        if d.benchmark is not None:
            b = d.benchmark
            value = b["sign"] * r.objective
            rel = abs(value - b["published"]) / max(abs(b["published"]), 1e-300)
            within = bool(rel <= b["tolerance"])
            written.fields["benchmark"] = {**b, "value": value, "relative_error": rel, "within_tolerance": within}
            if not within and r.status in ("optimal", "acceptable", "check_failed"):
                warnings.append(f"benchmark: {b['quantity']} {value:.7g} is {100 * rel:.3g} % away from the published "
                                f"{b['published']:.7g} ({b['source']}), beyond benchmark.tolerance {b['tolerance']:g}")
        for w in warnings:
            _log.warning("%s: warning: %s", name, w)
        written.fields["warnings"] = warnings
        if r.status not in ("optimal", "acceptable", "check_failed"):
            return written
        r.to_csv(out / "trajectories.csv", units=d.model.units or {})  # headers "name [unit]" (gtmodel._tables.split_unit)
        written.files.append("trajectories.csv")
        if plots:
            values = scalar_signals({**r.states, **r.algebraics, **r.outputs, **r.inputs})
            shown = {k: values[k] for k in d.variables if k in values}
            t_in, applied = applied_inputs(r, d.optimization)
            for group, fname, t, signals in (
                ("states", "states.png", r.t, scalar_signals(r.states)),
                ("inputs as verified", "inputs.png", t_in, applied),
                ("variables", "variables.png", r.t, shown),
            ):
                if signals:
                    plot_signals(t, signals, out / fname, title=f"{name}: {group}", bounds=d.bounds, units=d.model.units)
                    written.files.append(fname)
        return written


def applied_inputs(result: OptimizationResult, optimization: Optimization,
                   per_element: int = 10) -> tuple[np.ndarray, dict[str, np.ndarray]]:
    """The inputs as the verification applies them: the polynomials between the points, clipped to the bounds.

    A collocation input is a polynomial on each element, which may pass its bound between the
    collocation points; the verification simulates the model under it clipped to the bound, as
    a saturating amplifier delivers it (:mod:`gtmodel.modeling.ocp.verification_bounds`), and so
    does ``inputs.png``. Without polynomials (multiple shooting), the written samples.

    Parameters
    ----------
    result : OptimizationResult
        A solution.
    optimization : Optimization
        Its problem (the input bounds: the model's, overridden by the problem's,
        :meth:`Optimization.bounds_vectors`).
    per_element : int, optional
        Samples per interval between consecutive written times (at most 20,000 in all).

    Returns
    -------
    t : numpy.ndarray
        ``(K,)`` [s]: the written times and ``per_element - 1`` more between each two.
    inputs : dict of str to numpy.ndarray
        Input name (an array input's elements ``name[j]``) -> ``(K,)`` values.
    """
    t_mesh = np.asarray(result.t, dtype=float)
    if result.collocation is None or result.dae is None or t_mesh.size < 2:
        return t_mesh, scalar_signals(result.inputs)
    n = max(1, min(int(per_element), 20_000 // (t_mesh.size - 1)))
    frac = np.arange(n) / n
    t = np.append((t_mesh[:-1, None] + frac[None, :] * np.diff(t_mesh)[:, None]).ravel(), t_mesh[-1])
    lower, upper = optimization.bounds_vectors(result.dae, "u")
    sampled = result.sample(t)["inputs"]
    out = {}
    for k, v in sampled.items():
        sl = result.dae.u_vars[k]
        columns = np.asarray(v, dtype=float).reshape(t.size, sl.stop - sl.start)
        for j in range(columns.shape[1]):  # an array input (the Optimica robot's tau[3]) as its elements k[0], k[1], ...
            out[k if np.ndim(v) == 1 else f"{k}[{j}]"] = np.clip(columns[:, j], lower[sl.start + j], upper[sl.start + j])
    return t, out


def scalar_signals(values: dict[str, Any]) -> dict[str, np.ndarray]:
    """Signals for a plot: each array-valued variable split into its elements ``name[0]``, ``name[1]``, ...

    Parameters
    ----------
    values : dict of str to array_like
        Name -> ``(K,)`` samples of a scalar or ``(K, m)`` of an array variable (a Modelica
        ``Real x[3]``, written to ``trajectories.csv`` as ``x[0]``, ``x[1]``, ``x[2]``).

    Returns
    -------
    dict of str to numpy.ndarray
        Name -> ``(K,)`` samples, scalars unchanged (other shapes left out).
    """
    out: dict[str, np.ndarray] = {}
    for k, v in values.items():
        a = np.asarray(v, dtype=float)
        if a.ndim == 1:
            out[k] = a
        elif a.ndim == 2:
            out.update({f"{k}[{j}]": a[:, j] for j in range(a.shape[1])})
    return out


def _method(file: ProblemFile, doc: Any, opt: Optimization) -> Collocation | MultipleShooting:
    """``[collocation]`` or ``[transcription]`` multiple shooting as the declaration's method, checked against the
    model (algebraic variables and integrators), ``[verification]`` and ``[solver]`` (also the ``optimica`` kind's)."""
    col, tr = doc.collocation, doc.transcription
    method: Collocation | MultipleShooting = Collocation(col.elements, col.points, col.scheme, col.eliminate_algebraics)
    if tr.method == "multiple_shooting":
        if getattr(doc, "nominal", None):
            raise file.fail("nominal", 'no nominal values with [transcription] method = "multiple_shooting" (scaling is for collocation)')
        flat = opt.model.flatten()
        if flat.nz and tr.integrator == "cvodes":
            raise file.fail("transcription.integrator", "rk, radau, collocation or idas for a model with algebraic variables "
                            "(CVODES takes none)", tr.integrator)
        if flat.nz and tr.integrator in EXPLICIT_INTEGRATORS and explicit_algebraics(flat).z is None:
            raise file.fail("transcription.integrator", "collocation or idas: the algebraic variables cannot be eliminated "
                            f"symbolically for {tr.integrator} ({explicit_algebraics(flat).reason})", tr.integrator)
        try:  # refused at load, before anything is built
            check_shooting_memory(tr.intervals, tr.steps, flat.nx, flat.nz, flat.nu)
        except InputError as exc:
            raise file.wrap("transcription.intervals", exc) from None
        method = MultipleShooting(tr.intervals, tr.controls, tr.integrator, tr.steps)
    if doc.verification.integrator == "cvodes" and opt.model.flatten().nz:
        raise file.fail("verification.integrator", "idas or auto for a model with algebraic variables (CVODES takes none)", "cvodes")
    if doc.solver.name != "ipopt" and tr.method == "multiple_shooting":
        raise file.fail("solver.name", 'ipopt with method = "multiple_shooting" (fatrop solves the stage-wise '
                        'collocation NLP only; method = "collocation" for fatrop)', doc.solver.name)
    if tr.refine and tr.method == "multiple_shooting":
        raise file.fail("transcription.refine", 'false with method = "multiple_shooting" (mesh refinement splits '
                        'collocation elements; shooting is verified as it is: raise transcription.intervals or steps, '
                        'or refine with method = "collocation")', True)
    return method


def _continuation(file: ProblemFile, doc: Any) -> Continuation:
    """``[continuation]`` as the declaration's :class:`~gtmodel.modeling.ocp.continuation.Continuation`."""
    c = doc.continuation
    if c.step > c.start_factor:
        raise file.fail("continuation.step", f"at most continuation.start_factor ({c.start_factor:g})", c.step)
    return Continuation(enabled=c.enabled, start_factor=c.start_factor, step=c.step)


def _refinement(file: ProblemFile, doc: Any) -> Refinement:
    """``[transcription]`` refinement and ``[verification]`` settings, checked together."""
    tr, ver = doc.transcription, doc.verification
    if tr.refine and not ver.enabled:
        raise file.fail("verification.enabled", "true with transcription.refine = true (refinement is driven by the verification)", False)
    return Refinement(tr.refine, tr.tolerance, tr.max_elements, tr.max_passes, verify=ver.enabled,
                      integrator=None if ver.integrator == "auto" else ver.integrator, rtol=ver.rtol,
                      on_failure=tr.refine_on_failure and ver.enabled and tr.method != "multiple_shooting", max_cpu_s=tr.max_cpu_s,
                      objective_tolerance=tr.objective_tolerance, regularization=tr.regularization)


def _used_integrator(result: OptimizationResult) -> str:
    """The integrator a multiple-shooting solve chose by default (the last entry of its transcription key)."""
    key = result.transcription_key or ()
    return str(key[-1]) if len(key) > 5 and key[1] == "multiple_shooting" else "default"


def _transcription_summary(method: Collocation | MultipleShooting, result: OptimizationResult) -> dict[str, Any]:
    """The summary's ``transcription`` block (``collocation`` keeps its former keys, the declared mesh).

    ``elements`` is the mesh of the solution (after refinement), ``declared_elements``
    the file's when refinement changed it.
    """
    if isinstance(method, MultipleShooting):
        return {"method": "multiple_shooting", "intervals": method.intervals, "controls": method.controls,
                "integrator": method.integrator or _used_integrator(result), "steps": method.steps}
    col = result.collocation
    elements = col.elements if col is not None else method.elements
    return {"method": "collocation", "elements": elements, "points": method.points, "scheme": method.scheme,
            **({"declared_elements": method.elements} if elements != method.elements else {})}



def _variable_fields(d: OptimalControl, r: OptimizationResult) -> dict[str, Any]:
    """The summary's ``variables`` (names by group, as the tables' columns), ``units`` and ``bounds``.

    ``bounds`` are those the NLP imposes: the model's, overridden by the problem file's
    (``Optimization.bounds_vectors``); an open side is ``null``. They let a reader of the
    folder (``gtmodel report``) draw each trajectory with its bounds.
    """
    groups = {"states": r.states, "inputs": r.inputs, "algebraics": r.algebraics, "outputs": r.outputs}
    out: dict[str, Any] = {"variables": {g: list(v) for g, v in groups.items()}, "units": dict(d.model.units or {})}
    if r.dae is not None:
        bounds: dict[str, Any] = {}
        for cat in ("x", "z", "u"):
            lb, ub = d.optimization.bounds_vectors(r.dae, cat)
            for name, sl in getattr(r.dae, f"{cat}_vars").items():
                lo, hi = lb[sl], ub[sl]
                if np.any(np.isfinite(lo)) or np.any(np.isfinite(hi)):
                    bounds[name] = [float(lo[0]), float(hi[0])] if lo.size == 1 else [lo.tolist(), hi.tolist()]
        out["bounds"] = bounds
    return out
