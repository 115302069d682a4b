"""C for a user's own model (``gtmodel codegen --model FILE:CLASS``): its explicit ODE and fixed steps.

A :class:`~gtmodel.modeling.Model` (or :class:`~gtmodel.modeling.Component`) is reduced
to its explicit ODE ``xdot = f(x, u)``, ``y = h(x, u)`` by
:func:`gtmodel.modeling.explicit_ode` (the reduction :meth:`Model.simulate` uses; the
algebraic variables eliminated symbolically in block-triangular order, or by a bounded
Newton iteration inside the graph where a block is not affine in its variables), and
:func:`generate_model` writes C for

``<prefix>_ode([t,] x[, u], xdot)``
    the right-hand side ``f`` (a true ODE: no algebraic variables among the inputs);
``<prefix>_outputs([t,] x[, u], <output 1>, ...)``
    the declared outputs ``h`` (models with outputs);
``<prefix>_step_rk4(x[, u], x_next)``
    one explicit Runge-Kutta 4 step over the period ``<PREFIX>_DT`` (the 4 ms loop by
    default), the input held;
``<prefix>_step_implicit(x[, u], x_next)``
    one step of the 2-stage Radau IIA method (order 3, L-stable: for stiff models such as a
    motor whose electrical time constant is shorter than the period), its stage equations
    solved by a bounded simplified Newton iteration (the exact Jacobian at the predictor),

(the steps for models that do not depend on time explicitly) with the machinery of the
robot code (:mod:`gtmodel.codegen.generate`: CasADi's code generator, plain-C wrappers
with argument checks, status codes, stack work arrays, no heap, reentrant) and a header
of its own: the model's name, variables and units as declared, and its OWN parameter hash
(:func:`model_parameter_hash`). The parameter values (the model's defaults) are embedded
as constants. A Newton iteration that does not converge (the algebraic one or the
implicit step's) gives ``GT_NOT_CONVERGED`` with the outputs untouched, never NaN.
:func:`check_model` compiles the code under the robot code's strict flags
(``-std=c99 -Wall -Wextra -Werror -pedantic``), compares every function with the same
CasADi Functions evaluated from Python on random inputs (1e-12, absolute or relative),
probes non-finite inputs, and iterates each C step over a horizon of periods against
:meth:`Model.simulate` (IDAS, tight tolerances) to :data:`HORIZON_TOLERANCE`.
"""

from __future__ import annotations

import hashlib
import json
import logging
import math
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Mapping, Sequence

import casadi as ca
import numpy as np

import gtmodel
from gtmodel.codegen.build import STRICT_EXTRA, CompiledLibrary, load_strict
from gtmodel.codegen.emit import fill, header_guard
from gtmodel.codegen.check.compare import compare, probe
from gtmodel.codegen.check.report import CheckReport, with_timings
from gtmodel.codegen.check.robot import time_functions
from gtmodel.codegen.declarations import ArgSpec, FunctionSpec, OutputSpec
from gtmodel.codegen.writer import REAL_TYPES, GeneratedCode, write_library
from gtmodel.codegen.check.report import FunctionCheck
from gtmodel.codegen.declarations import StatusCheck
from gtmodel.defaults import LOOP_PERIOD_S
from gtmodel._escape import check_c_identifier
from gtmodel.errors import CodegenError, GtModelError, InputError
from gtmodel.modeling import Component, ExplicitODE, FlatDAE, Model, explicit_ode
from gtmodel.modeling.dae import casadi_name

__all__ = ["MODEL_KIND", "MODEL_FUNCTIONS", "MODEL_TOLERANCE", "HORIZON_TOLERANCE", "HORIZON_PERIODS", "STEP_FUNCTIONS", "SUBSTEPS",
           "STRICT_EXTRA", "ModelSource", "model_parameter_hash", "model_specs", "generate_model", "check_model", "check_horizon"]

log = logging.getLogger("gtmodel")

#: ``FunctionSpec.kind`` / ``GeneratedCode.kind`` of a user model's functions.
MODEL_KIND = "model"
#: The functions a model can have, in C order.
MODEL_FUNCTIONS = ("ode", "outputs", "step_rk4", "step_implicit")
#: The fixed-step functions and their :meth:`~gtmodel.modeling.ExplicitODE.step` methods.
STEP_FUNCTIONS = {"step_rk4": "rk4", "step_implicit": "radau2"}
#: Largest accepted deviation of a C step iterated over the horizon from ``simulate()``,
#: relative to the largest magnitude of that state over the horizon (plus the same absolute floor).
HORIZON_TOLERANCE = 1e-3
#: Default substeps of the generated fixed steps within one period (``<PREFIX>_SUBSTEPS``):
#: four RK4 or Radau IIA steps of 1 ms hold a motor's 1.7 ms electrical time constant to
#: :data:`HORIZON_TOLERANCE` where one 4 ms step does not.
SUBSTEPS = 4
#: Periods of the horizon check (1 s at the 4 ms loop).
HORIZON_PERIODS = 250
#: Largest accepted ``|C - Python|`` of a model function (absolute, or relative to ``|Python|``).
MODEL_TOLERANCE = 1e-12
#: Range of the random time samples of the check [s].
TIME_RANGE = 10.0
#: Names an output's C parameter may not take (arguments, wrapper locals, C keywords): ``y_<name>`` then.
_RESERVED = frozenset(
    "t x z u arg res iw w i k flag iterations x_next residual valid pre converged auto break case char const continue "
    "default do double else enum extern float for goto if inline int long register restrict return short signed sizeof "
    "static struct switch typedef union unsigned void volatile while "
    # identifiers and macros of the headers the wrapper includes (math.h, stddef.h, errno.h, ...)
    "main errno assert offsetof bool true false mem status sink".split()
)


def _c_names(names: Sequence[str]) -> dict[str, str]:
    """C parameter names of outputs: the name with non-identifier characters as ``_``
    (``"mass.a"`` of a composed model: ``mass_a``), ``y_<name>`` if reserved, a possible macro
    (no lowercase letter: ``NULL``, ``GT_OK``) or the generated code's (``casadi_*``, ``gt_*``), unique."""
    out: dict[str, str] = {}
    for name in names:
        c = re.sub(r"[^A-Za-z0-9_]", "_", name)
        # a name without a lowercase letter may be a macro (NULL, GT_OK, NAN, EOF); casadi_/gt_ the generated code's
        if c in _RESERVED or c.startswith(("in_", "out_", "st_", "casadi", "gt_")) or c[0].isdigit() or c == c.upper():
            c = f"y_{c}"
        base, k = c, 1
        while c in out.values():
            c, k = f"{base}_{k}", k + 1
        out[name] = c
    return out


@dataclass(frozen=True)
class ModelSource:
    """What the model code is generated from: the model, its explicit ODE and the step period.

    Parameters
    ----------
    model : Model
        The user's model (a component's flattened model).
    ode : ExplicitODE
        Its explicit ODE (:func:`gtmodel.modeling.explicit_ode`).
    dt : float
        Period of the fixed-step functions [s].
    substeps : int
        Steps of the method within the period.
    """

    model: Model
    ode: ExplicitODE
    dt: float = LOOP_PERIOD_S
    substeps: int = SUBSTEPS

    @property
    def name(self) -> str:
        """The model's name."""
        return self.model.name

    @property
    def dae(self) -> FlatDAE:
        """The reduced, flattened model the ODE was built from."""
        return self.ode.dae


def model_parameter_hash(dae: FlatDAE) -> str:
    """Short hash identifying a flattened model: its names, parameter values and equations.

    Parameters
    ----------
    dae : FlatDAE
        The flattened model.

    Returns
    -------
    str
        First 16 hex digits of the SHA-256 of the model name, the variable and output
        names, the exact parameter values (``float.hex``) and the text of the
        right-hand side, algebraic residual and output expressions. A changed parameter
        value or equation changes it.
    """
    text = json.dumps({
        "name": dae.name,
        "names": [dae.x_names, dae.z_names, dae.u_names, dae.p_names, dae.output_names],
        "p": [float.hex(float(v)) for v in dae.p_value],
        "f": str(dae.ode_expr), "g": str(dae.alg_expr), "y": {k: str(v) for k, v in dae.output_exprs.items()},
    }, sort_keys=True)
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def _names_doc(names: Sequence[str], what: str) -> str:
    shown = ", ".join(names[:12]) + (", ..." if len(names) > 12 else "")
    return f"{what} ({shown})"


def _split_outputs(dae: FlatDAE, y: ca.SX) -> dict[str, ca.SX]:
    """The stacked outputs ``y`` by declared output (vector outputs keep their length)."""
    out, k = {}, 0
    for name, size in dae.output_sizes.items():
        out[name] = y[k:k + size]
        k += size
    return out


def _model_functions(ode: ExplicitODE, dt: float, substeps: int = SUBSTEPS) -> dict[str, tuple[list[str], ca.Function]]:
    """Per C function: its CasADi input names and the Function with ``p`` as the last input."""
    dae = ode.dae
    ins = (["t"] if ode.time_dependent else []) + ["x"] + (["u"] if ode.nu else [])
    sym = {"t": ca.SX.sym("t"), "x": ca.SX.sym("x", ode.nx), "u": ca.SX.sym("u", ode.nu), "p": ca.SX.sym("p", ode.np)}
    res = ode.full(t=sym["t"] if ode.time_dependent else 0.0, x=sym["x"], u=sym["u"], p=sym["p"])
    args = [sym[n] for n in ins] + [sym["p"]]
    out = {"ode": (ins, ca.Function("ode", args, [res["xdot"], res["converged"]], ins + ["p"], ["xdot", "converged"]))}
    if dae.output_sizes:
        names = _c_names(list(dae.output_sizes))
        ys = _split_outputs(dae, res["y"])
        out["outputs"] = (ins, ca.Function("outputs", args, [ys[k] for k in names] + [res["converged"]], ins + ["p"],
                                           [names[k] for k in names] + ["converged"]))
    if not ode.time_dependent:
        for name, method in STEP_FUNCTIONS.items():
            st = ode.step(dt, method, substeps=substeps)
            r = st(x=sym["x"], u=sym["u"], p=sym["p"])
            out[name] = (ins, ca.Function(name, args, [r["x_next"], r["converged"]], ins + ["p"], ["x_next", "converged"]))
    return out


def model_specs(ode: ExplicitODE, dt: float = LOOP_PERIOD_S, substeps: int = SUBSTEPS) -> tuple[FunctionSpec, ...]:
    """The declarations of a model's C functions (``ode``, ``outputs``, ``step_rk4``, ``step_implicit``).

    Parameters
    ----------
    ode : ExplicitODE
        The model's explicit ODE; its default parameter values are embedded as constants.
    dt : float, optional
        Period of the fixed-step functions [s] (default the 4 ms loop).
    substeps : int, optional
        Steps of the method within the period (default :data:`SUBSTEPS`).

    Returns
    -------
    tuple of FunctionSpec
        One per function the model has (``outputs`` with declared outputs; the steps for
        models that do not depend on time explicitly); the input ``u`` is left out for a
        model without inputs. Each has the status check ``converged`` (``GT_NOT_CONVERGED``).
    """
    dae = ode.dae
    p = ca.DM(ode.p_default)
    docs = {"t": "time [s]", "x": _names_doc(ode.x_names, "states"), "u": _names_doc(ode.u_names, "inputs")}
    checks = (StatusCheck("converged", ">", "0.5", "GT_NOT_CONVERGED"),)
    table = _model_functions(ode, dt, substeps)

    def fixed(name: str) -> Any:
        ins, f = table[name]
        sy = [ca.SX.sym(n, f.size1_in(n)) for n in ins]
        g = ca.Function(f"{casadi_name(dae.name)}_{name}", sy, f.call(sy + [p]), ins, f.name_out())
        return lambda source: g

    def reference(name: str, outs: Sequence[str]) -> Any:
        """The same Function with the parameters as an input, from Python; rows that did not converge NaN (skipped)."""

        def ref(source: ModelSource, inputs: Any) -> dict[str, np.ndarray]:
            ins, f = _model_functions(source.ode, source.dt, source.substeps)[name]
            n = len(next(iter(inputs.values())))
            cols = [np.asarray(inputs[k], dtype=float).reshape(n, -1).T for k in ins]
            res = f.map(n)(*cols, np.tile(source.ode.p_default.reshape(-1, 1), (1, n)))
            res = res if isinstance(res, (list, tuple)) else [res]
            ok = np.asarray(res[-1]).reshape(-1) > 0.5
            got = {o: np.asarray(ca.DM(v)).T.reshape(n, -1) for o, v in zip(f.name_out(), res)}
            return {o: np.where(ok[:, None], got[o], np.nan) for o in outs}

        return ref

    common = dict(tolerance=MODEL_TOLERANCE, relative_tolerance=MODEL_TOLERANCE, kind=MODEL_KIND, checks=checks)
    specs = []
    for name, (ins, f) in table.items():
        args = tuple(ArgSpec(n, "vector", n, docs[n]) for n in ins)
        if name == "ode":
            outputs = (OutputSpec("xdot", "xdot", _names_doc(ode.x_names, "der() of the states")),)
            doc = f"Explicit right-hand side xdot = f(x, u) of the model {dae.name} (algebraic variables eliminated)."
        elif name == "outputs":
            outputs = tuple(OutputSpec(c, c, f"output {k}") for k, c in _c_names(list(dae.output_sizes)).items())
            doc = f"The declared outputs y = h(x, u) of the model {dae.name}."
        else:
            outputs = (OutputSpec("x_next", "x_next", _names_doc(ode.x_names, "states one period later")),)
            what = "explicit Runge-Kutta 4" if STEP_FUNCTIONS[name] == "rk4" else "2-stage Radau IIA (order 3, L-stable, bounded Newton)"
            doc = (f"One period ({dt!r} s, {substeps} {what} steps) of the model {dae.name}, the input held "
                   "(GT_NOT_CONVERGED: a Newton iteration failed).")
        specs.append(FunctionSpec(name, fixed(name), args=args, outputs=outputs, doc=doc,
                                  reference=reference(name, [o.casadi_output for o in outputs]), **common))
    return tuple(specs)


def _with_units(names: Sequence[str], units: Mapping[str, str]) -> str:
    """``name [unit], ...`` (a name without a declared unit bare), or ``none``: the header's lists."""
    return ", ".join(f"{n} [{units[n]}]" if units.get(n) else n for n in names) or "none"


def _header_text(prefix: str, functions, version: str, phash: str, dae: FlatDAE, real: str, dt: float, substeps: int,
                 units: Mapping[str, str] | None = None) -> str:
    P = prefix.upper()
    units = units or {}
    names = dict(NAME=dae.name, VERSION=version, STATES=_with_units(dae.x_names, units),
                 ALGEBRAIC=_with_units(dae.z_names, units), INPUTS=_with_units(dae.u_names, units),
                 OUTPUTS=_with_units(dae.output_names, units),
                 PARAMETERS=", ".join(f"{n} = {v!r}" for n, v in zip(dae.p_names, dae.p_value.tolist())) or "none")
    return fill(
        "template_model_header.h", names, GP=prefix, P=P, HASH=phash, REAL=real,
        NX=dae.nx, NZ=dae.nz, NU=dae.nu, NY=len(dae.output_names), DT=repr(float(dt)), SUBSTEPS=substeps,
        OPEN=header_guard(P)[0], CLOSE=header_guard(P)[1],
        PROTOTYPES="\n".join(functions.header),
    )


def generate_model(
    model: Model | Component,
    out_dir: str | Path,
    functions: Sequence[str] | None = None,
    prefix: str | None = None,
    real: str = "double",
    dt: float = LOOP_PERIOD_S,
    substeps: int = SUBSTEPS,
) -> GeneratedCode:
    """Generate C and a header for the functions of a user's model.

    Parameters
    ----------
    model : Model or Component
        The model (e.g. from :func:`gtmodel.problems.user_model.load_user_model`); its
        parameter defaults are embedded. Reduced to its explicit ODE by
        :func:`gtmodel.modeling.explicit_ode`.
    out_dir : str or pathlib.Path
        Folder to write into (created if missing).
    functions : sequence of str, optional
        A subset of :data:`MODEL_FUNCTIONS` (``"ode"``, ``"outputs"``, ``"step_rk4"``,
        ``"step_implicit"``); default all the model has.
    prefix : str, optional
        C symbol prefix; default ``"gt_<model name>"``.
    real : {"double", "float"}, optional
        Floating-point type.
    dt : float, optional
        Period of the fixed-step functions [s] (default the 4 ms loop,
        :data:`gtmodel.defaults.LOOP_PERIOD_S`; ``<PREFIX>_DT`` in the header).
    substeps : int, optional
        Steps of the method within one period (default :data:`SUBSTEPS`; ``<PREFIX>_SUBSTEPS``).

    Returns
    -------
    GeneratedCode
        ``kind = "model"``, ``parameters`` the :class:`ModelSource`, ``parameter_hash``
        from :func:`model_parameter_hash`.

    Raises
    ------
    InputError
        Not a Model or Component, an unknown or absent function, a bad prefix, real type
        or period.
    ModelError
        The model does not reduce to an explicit ODE (no state, not index 1).
    CodegenError
        CasADi's code generation or writing the files failed.
    """
    if isinstance(model, Component):
        model = model.to_model()
    if not isinstance(model, Model):
        raise InputError(f"model: expected a gtmodel.modeling.Model or Component, got {type(model).__name__}")
    if real not in REAL_TYPES:
        raise InputError(f"real: expected 'double' or 'float', got {real!r}")
    prefix = prefix if prefix is not None else "gt_" + casadi_name(model.name)
    check_c_identifier(prefix, "prefix", "gt_cart_pendulum")
    if isinstance(dt, bool) or not isinstance(dt, (int, float, np.floating)) or not np.isfinite(dt) or dt <= 0:
        raise InputError(f"dt: expected a positive period in seconds, got {dt!r}")
    if isinstance(substeps, bool) or not isinstance(substeps, (int, np.integer)) or substeps < 1:
        raise InputError(f"substeps: expected a positive number of steps per period, got {substeps!r}")
    ode = explicit_ode(model)
    dae = ode.dae
    table = {s.name: s for s in model_specs(ode, float(dt), int(substeps))}
    chosen = list(table) if functions is None else list(functions)
    unknown = [f for f in chosen if f not in table]
    if unknown or not chosen:
        raise InputError(f"functions: {unknown or 'none'} not among the model's functions ({', '.join(table)})")
    specs = tuple(table[f] for f in dict.fromkeys(chosen))
    source = ModelSource(model, ode, float(dt), int(substeps))
    phash = model_parameter_hash(dae)
    version = f"gtmodel {gtmodel.__version__}; casadi {ca.__version__}; model {dae.name} sha256:{phash}; real {real}"
    out, _, sizes, signatures = write_library(
        prefix, specs, source, out_dir, real, lambda wrapped: _header_text(prefix, wrapped, version, phash, dae, real, float(dt), int(substeps), ode.units))
    header, wrapper = out / f"{prefix}.h", out / f"{prefix}.c"
    log.info("codegen: wrote %s (%s) for model %s", wrapper, ", ".join(s.name for s in specs), dae.name)
    return GeneratedCode(
        out_dir=out, prefix=prefix, functions=tuple(s.name for s in specs), source=wrapper, header=header,
        casadi_source=out / f"{prefix}_casadi.c", casadi_header=out / f"{prefix}_casadi.h", parameters=source, friction="",
        parameter_hash=phash, version=version, specs=specs, work_sizes=sizes, signatures=signatures, real=real, kind=MODEL_KIND,
    )


def _sample(dae: FlatDAE, n: int, rng: np.random.Generator) -> dict[str, np.ndarray]:
    """Random inputs: time in [0, TIME_RANGE], variables within finite bounds, else start +- N(0, 1)."""
    out = {"t": rng.uniform(0.0, TIME_RANGE, (n, 1))}
    starts = {"x": dae.x_start, "z": dae.z_start, "u": np.zeros(dae.nu)}
    for k in ("x", "z", "u"):
        lb, ub = getattr(dae, f"{k}_lb"), getattr(dae, f"{k}_ub")
        finite = np.isfinite(lb) & np.isfinite(ub)
        v = starts[k] + rng.standard_normal((n, lb.size))
        v[:, finite] = rng.uniform(lb[finite], ub[finite], (n, int(finite.sum())))
        out[k] = v
    return out


def _horizon_input(ode: ExplicitODE, n: int) -> np.ndarray:
    """``(n, nu)`` smooth input over the horizon: one sine period about the start (mid-range within finite bounds)."""
    lb, ub = ode.u_lb, ode.u_ub
    finite = np.isfinite(lb) & np.isfinite(ub)
    lo, hi = np.where(finite, lb, 0.0), np.where(finite, ub, 0.0)
    centre = np.where(finite, 0.5 * (lo + hi), ode.u0)
    amplitude = np.where(finite, 0.25 * (hi - lo), np.maximum(1.0, np.abs(ode.u0)))
    phase = np.sin(2.0 * np.pi * np.arange(n) / n)
    return centre[None, :] + phase[:, None] * amplitude[None, :]


def _state_trajectory(result: Any, name: str) -> np.ndarray:
    """One scalar state (``"v"`` or ``"v[i]"``) of a :class:`~gtmodel.modeling.SimulationResult`."""
    base, _, index = name.partition("[")
    for group in (result.x, result.z):
        if base in group:
            values = np.asarray(group[base], dtype=float)
            return values if values.ndim == 1 else values[:, int(index.rstrip("]") or 0)]
    raise CodegenError(f"horizon check: simulate() reports no variable {name!r}")


def check_horizon(generated: GeneratedCode, library: CompiledLibrary, periods: int = HORIZON_PERIODS,
                  tolerance: float = HORIZON_TOLERANCE) -> list[FunctionCheck]:
    """Iterate each generated C step over a horizon and compare with :meth:`Model.simulate`.

    Parameters
    ----------
    generated : GeneratedCode
        From :func:`generate_model`.
    library : CompiledLibrary
        The compiled and loaded code.
    periods : int, optional
        Number of periods ``N`` (default :data:`HORIZON_PERIODS`).
    tolerance : float, optional
        Accepted ``|x_C - x_simulate|`` per state: ``tolerance (1 + max_t |x_simulate|)``.

    Returns
    -------
    list of FunctionCheck
        One per step function (named ``"<step> over N periods vs simulate()"``): the C
        step from ``simulate()``'s start (consistent with initial equations) with a smooth input (one sine period, held over each
        period), against the model's own simulation (IDAS, its default tolerances) of the same
        piecewise-constant input at the period boundaries. A status other than ``GT_OK``
        fails it; so does a simulation that fails (no reference, named in the report).
    """
    source: ModelSource = generated.parameters
    ode = source.ode
    steps = [s.name for s in generated.specs if s.name in STEP_FUNCTIONS]
    if not steps or periods < 1:
        return []
    t = source.dt * np.arange(periods + 1)
    u = _horizon_input(ode, periods)
    try:
        sim = source.model.simulate(t, u=u if ode.nu else None)
    except GtModelError as exc:  # no reference: every step's horizon check fails, the report says so
        log.warning("horizon check of %s: simulate() failed: %s", generated.prefix, exc)
        return [FunctionCheck(name=f"{name} over {periods} periods vs simulate() (simulate failed)", n=periods, max_abs_diff=math.inf,
                              tolerance=tolerance, unit="", n_not_ok=0, passed=False) for name in steps]
    ref = np.column_stack([_state_trajectory(sim, n) for n in ode.x_names])
    bound = tolerance * (1.0 + np.max(np.abs(ref), axis=0))
    out = []
    for name in steps:
        cf = library[name]
        xs = np.full_like(ref, np.nan)
        xs[0] = ref[0]  # simulate()'s consistent start (initial equations, fixed starts) is the C's start too
        bad = 0
        for k in range(periods):
            args = (xs[k], u[k]) if ode.nu else (xs[k],)
            status, (x_next,) = cf(*args)
            bad += status != 0
            xs[k + 1] = x_next if status == 0 else np.nan
        dev = np.abs(xs - ref)
        worst = float(np.nanmax(dev)) if np.any(np.isfinite(dev)) else math.inf
        ratio = float(np.nanmax(dev / bound)) if np.all(np.isfinite(dev)) else math.inf
        out.append(FunctionCheck(
            name=f"{name} over {periods} periods vs simulate()", n=periods, max_abs_diff=worst, tolerance=tolerance, unit="",
            n_not_ok=int(bad), passed=bool(bad == 0 and ratio <= 1.0), tolerance_rule="x (1 + max|simulate()|) per state",
            max_ratio=ratio,
        ))
    return out


def check_model(
    generated: GeneratedCode,
    n: int = 1000,
    seed: int = 0,
    library: CompiledLibrary | None = None,
    build_dir: str | Path | None = None,
    timing: bool = False,
    horizon: int = HORIZON_PERIODS,
) -> CheckReport:
    """Compile a model's generated C (``-std=c99 -Wall -Wextra -Werror -pedantic``) and compare it with Python.

    Parameters
    ----------
    generated : GeneratedCode
        From :func:`generate_model`.
    n : int, optional
        Random inputs per function (default 1000).
    seed : int, optional
        Seed of the random generator.
    library : CompiledLibrary, optional
        An already loaded library; compiled if None.
    build_dir : str or pathlib.Path, optional
        Build folder (default ``<out_dir>/build``).
    timing : bool, optional
        Also time every function in a C loop (ns/call).
    horizon : int, optional
        Periods of the horizon check of the step functions (:func:`check_horizon`; 0: none).

    Returns
    -------
    CheckReport
        Per function the largest ``|C - Python|`` against :data:`MODEL_TOLERANCE`
        (absolute or relative; random inputs where the Python evaluation did not converge
        are skipped), per step function the horizon comparison with ``simulate()``; probes: a NaN or infinite input gives
        ``GT_BAD_ARGUMENT`` with the outputs untouched. A failed check is a report with
        ``passed == False``.

    Raises
    ------
    InputError
        Not model code, or ``n`` not a positive integer.
    CompilerNotFoundError
        No C compiler.
    CodegenError
        Compilation failed.
    """
    if generated.kind != MODEL_KIND or not isinstance(generated.parameters, ModelSource):
        raise InputError("generated: expected the code of a user model (from generate_model)")
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 1:
        raise InputError(f"n: expected a positive number of samples, got {n!r}")
    build = Path(build_dir) if build_dir is not None else generated.out_dir / "build"
    if library is None:
        library = load_strict(generated, build)
    source: ModelSource = generated.parameters
    rng = np.random.default_rng(seed)
    data = _sample(source.dae, int(n), rng)
    samples = {s.name: {a.name: data[a.name] for a in s.args} for s in generated.specs}
    results, probes = [], []
    for spec in generated.specs:
        cf = library[spec.name]
        results.append(compare(spec, cf, source, samples[spec.name], generated.real))
        for a in spec.args:
            for bad in (np.nan, np.inf):
                row = np.array(samples[spec.name][a.name][0], dtype=float)
                row[0] = bad
                probes.append(probe(cf, spec, samples[spec.name], f"{a.name}[0] = {bad}", "GT_BAD_ARGUMENT", {a.name: row}))
    if timing:  # timed on a row the C accepts (a Newton that does not converge there would stop the timing program)
        accepted = {}
        for spec in generated.specs:
            inp = samples[spec.name]
            status, _ = library[spec.name].call_rows(*[inp[a.name] for a in spec.args])
            first = np.flatnonzero(status == 0)[:1]
            accepted[spec.name] = {k: np.asarray(v)[first] for k, v in inp.items()}
        results = with_timings(results, time_functions(generated, library.path, accepted, build))
    results += check_horizon(generated, library, int(horizon))
    report = CheckReport(
        robot=source.name, prefix=generated.prefix, n=int(n), seed=seed, functions=tuple(results),
        probes=tuple(probes), version=library.version(), library=library.path,
    )
    log.info("codegen check of model %s: %s", generated.prefix, "passed" if report.passed else "FAILED")
    return report

