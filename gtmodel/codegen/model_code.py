"""C for a user's own model (``gtmodel codegen --model FILE:CLASS``): the flattened DAE's functions.

A :class:`~gtmodel.modeling.Model` flattens to the semi-explicit DAE
``xdot = f(t, x, z, u, p)``, ``0 = g(t, x, z, u, p)`` with outputs ``y(t, x, z, u, p)``
(:class:`~gtmodel.modeling.FlatDAE`). :func:`generate_model` writes C for

``<prefix>_ode(t, x[, z][, u], xdot)``
    the right-hand side ``f`` (models with states);
``<prefix>_alg(t, x[, z][, u], g)``
    the algebraic residual ``g`` (models with algebraic variables);
``<prefix>_outputs(t, x[, z][, u], <output 1>, ...)``
    the declared outputs (models with outputs),

with the machinery of the robot code (:mod:`gtmodel.codegen.generate`: CasADi's code
generator, common subexpressions merged, plain-C wrappers with argument checks, status
codes, stack work arrays, no heap, reentrant) and a header of its own: the model's
name, variables and units as declared, and its OWN parameter hash
(:func:`model_parameter_hash`, of the flattened model), no robot or Gantry-Tau macros.
The parameter values (the model's defaults) are embedded as constants, as a robot's
are. :func:`check_model` compiles the code under the robot code's strict flags
(``-std=c99 -Wall -Wextra -Werror -pedantic``) and compares every function with the CasADi evaluation from Python on random
inputs (1e-12, absolute or relative) and probes non-finite inputs; the Python side is
the model's own CasADi Functions (``FlatDAE.ode``, ``alg``, ``outputs``, which simulation
and the transcriptions use) with the parameter values as an input.
"""

from __future__ import annotations

import hashlib
import json
import logging
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Sequence

import casadi as ca
import numpy as np

import gtmodel
from gtmodel.codegen.build import CompiledLibrary, compile_shared, load_library
from gtmodel.codegen.emit import fill, header_guard
from gtmodel.codegen.emit.robot import _arg_size, _out_function, functions_fragment, wrapper_text
from gtmodel.codegen.check.compare import compare, probe
from gtmodel.codegen.check.report import CheckReport
from gtmodel.codegen.check.robot import time_functions
from gtmodel.codegen.declarations import ArgSpec, FunctionSpec, OutputSpec
from gtmodel.codegen.emit.casadi_source import _static_helpers, _void_unused_parameters, _work_sizes
from gtmodel.codegen.generate import REAL_TYPES, GeneratedCode, _prepare
from gtmodel.errors import CodegenError, InputError
from gtmodel.modeling import FlatDAE, Model
from gtmodel.modeling.dae import casadi_name

__all__ = ["MODEL_KIND", "MODEL_FUNCTIONS", "MODEL_TOLERANCE", "STRICT_EXTRA", "ModelSource", "model_parameter_hash", "model_specs",
           "generate_model", "check_model"]

log = logging.getLogger("gtmodel")

#: ``FunctionSpec.kind`` / ``GeneratedCode.kind`` of a user model's functions.
MODEL_KIND = "model"
#: The functions a model can have, in C order.
MODEL_FUNCTIONS = ("ode", "alg", "outputs")
#: Largest accepted ``|C - Python|`` of a model function (absolute, or relative to ``|Python|``).
MODEL_TOLERANCE = 1e-12
#: Flags :func:`check_model` adds to :func:`~gtmodel.codegen.build.compile_shared`'s
#: ``-std=c99 -O2 -Wall -Wextra -Werror``: the robot code's strict set (ISO C, no extensions).
STRICT_EXTRA = ("-pedantic",)
#: Range of the random time samples of the check [s].
TIME_RANGE = 10.0
_IDENT = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*$")
#: Names an output's C parameter may not take (arguments, wrapper locals, C keywords): ``y_<name>`` then.
_RESERVED = frozenset(
    "t x z u arg res iw w i k flag iterations x_next residual valid pre converged auto break case char const continue "
    "default do double else enum extern float for goto if inline int long register restrict return short signed sizeof "
    "static struct switch typedef union unsigned void volatile while".split()
)


def _c_names(names: Sequence[str]) -> dict[str, str]:
    """C parameter names of outputs: the name with non-identifier characters as ``_``
    (``"mass.a"`` of a composed model: ``mass_a``), ``y_<name>`` if reserved, unique."""
    out: dict[str, str] = {}
    for name in names:
        c = re.sub(r"[^A-Za-z0-9_]", "_", name)
        if c in _RESERVED or c.startswith(("in_", "out_", "st_")) or c[0].isdigit():
            c = f"y_{c}"
        base, k = c, 1
        while c in out.values():
            c, k = f"{base}_{k}", k + 1
        out[name] = c
    return out


@dataclass(frozen=True)
class ModelSource:
    """What the model code is generated from: the model and its flattened DAE.

    Parameters
    ----------
    model : Model
        The user's model.
    dae : FlatDAE
        Its flattening.
    """

    model: Model
    dae: FlatDAE

    @property
    def name(self) -> str:
        """The model's name."""
        return self.model.name


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


def model_specs(dae: FlatDAE) -> tuple[FunctionSpec, ...]:
    """The declarations of a model's C functions (``ode``, ``alg``, ``outputs`` as it has them).

    Parameters
    ----------
    dae : FlatDAE
        The flattened model; its parameter values are embedded as constants.

    Returns
    -------
    tuple of FunctionSpec
        One per non-empty function; empty arguments (no algebraics, no inputs) are left out.
    """
    p = ca.DM(dae.p_value)
    ins = [("t", dae.t, "time [s]"), ("x", dae.x, _names_doc(dae.x_names, "states")),
           ("z", dae.z, _names_doc(dae.z_names, "algebraic variables")), ("u", dae.u, _names_doc(dae.u_names, "inputs"))]
    ins = [(n, s, d) for n, s, d in ins if s.numel() > 0]
    args = tuple(ArgSpec(n, "vector", n, d) for n, s, d in ins)

    def fixed(e: ca.SX) -> ca.SX:
        return ca.substitute(e, dae.p, p) if dae.npar else e

    def function(name: str, outs: dict[str, ca.SX]) -> Any:
        f = ca.Function(f"{casadi_name(dae.name)}_{name}", [s for _, s, _ in ins], [fixed(e) for e in outs.values()], [n for n, _, _ in ins], list(outs))
        return lambda source: f

    def reference(fname: str, names: dict[str, str]) -> Any:
        """The model's own Function (``FlatDAE.ode``/``alg``/``outputs``, parameters as input) from Python."""

        def ref(source: ModelSource, inputs: Any) -> dict[str, np.ndarray]:
            n = len(next(iter(inputs.values())))
            f = getattr(source.dae, fname)
            cols = {k: np.asarray(inputs[k], dtype=float).reshape(n, -1).T for k in inputs}
            cols["p"] = np.tile(source.dae.p_value.reshape(-1, 1), (1, n))
            res = f.map(n)(**{k: cols.get(k, np.zeros((f.numel_in(k), n))) for k in f.name_in()})
            return {c: np.asarray(ca.DM(res[o])).T.reshape(n, -1) for o, c in names.items()}

        return ref

    specs = []
    common = dict(args=args, tolerance=MODEL_TOLERANCE, relative_tolerance=MODEL_TOLERANCE, kind=MODEL_KIND)
    if dae.nx:
        specs.append(FunctionSpec("ode", function("ode", {"xdot": dae.ode_expr}), reference=reference("ode", {"xdot": "xdot"}), outputs=(OutputSpec("xdot", "xdot", _names_doc(dae.x_names, "der() of the states")),),
                                  doc=f"Right-hand side xdot = f(t, x, z, u) of the flattened model {dae.name}.", **common))
    if dae.nz:
        specs.append(FunctionSpec("alg", function("alg", {"g": dae.alg_expr}), reference=reference("alg", {"g": "g"}), outputs=(OutputSpec("g", "g", "algebraic residual, zero on the solution"),),
                                  doc=f"Algebraic residual 0 = g(t, x, z, u) of the flattened model {dae.name}.", **common))
    if dae.output_exprs:
        names = _c_names(list(dae.output_exprs))
        outs = {names[k]: v for k, v in dae.output_exprs.items()}
        specs.append(FunctionSpec("outputs", function("outputs", outs), reference=reference("outputs", names),
                                  outputs=tuple(OutputSpec(c, c, f"output {k}") for k, c in names.items()),
                                  doc=f"The declared outputs of the model {dae.name}.", **common))
    return tuple(specs)


def _header_text(prefix: str, functions, version: str, phash: str, dae: FlatDAE, real: str) -> str:
    P = prefix.upper()
    return fill(
        "template_model_header.h", GP=prefix, P=P, NAME=dae.name, VERSION=version, HASH=phash, REAL=real,
        STATES=", ".join(dae.x_names) or "none", ALGEBRAIC=", ".join(dae.z_names) or "none", INPUTS=", ".join(dae.u_names) or "none",
        PARAMETERS=", ".join(f"{n} = {v!r}" for n, v in zip(dae.p_names, dae.p_value.tolist())) or "none",
        NX=dae.nx, NZ=dae.nz, NU=dae.nu,
        OPEN=header_guard(P)[0], CLOSE=header_guard(P)[1],
        PROTOTYPES="\n".join(functions.header),
    )


def generate_model(
    model: Model,
    out_dir: str | Path,
    functions: Sequence[str] | None = None,
    prefix: str | None = None,
    real: str = "double",
) -> GeneratedCode:
    """Generate C and a header for the functions of a user's model.

    Parameters
    ----------
    model : Model
        The model (e.g. from :func:`gtmodel.problems.user_model.load_user_model`); its
        parameter defaults are embedded.
    out_dir : str or pathlib.Path
        Folder to write into (created if missing).
    functions : sequence of str, optional
        A subset of ``"ode"``, ``"alg"``, ``"outputs"``; default all the model has.
    prefix : str, optional
        C symbol prefix; default ``"gt_<model name>"``.
    real : {"double", "float"}, optional
        Floating-point type.

    Returns
    -------
    GeneratedCode
        ``kind = "model"``, ``parameters`` the :class:`ModelSource`, ``parameter_hash``
        from :func:`model_parameter_hash`.

    Raises
    ------
    InputError
        Not a Model, an unknown or absent function, a bad prefix or real type.
    ModelError
        The model does not flatten.
    CodegenError
        CasADi's code generation or writing the files failed.
    """
    if not isinstance(model, Model):
        raise InputError(f"model: expected a gtmodel.modeling.Model, got {type(model).__name__}")
    if real not in REAL_TYPES:
        raise InputError(f"real: expected 'double' or 'float', got {real!r}")
    dae = model.flatten()
    prefix = prefix if prefix is not None else "gt_" + casadi_name(model.name)
    if not isinstance(prefix, str) or not _IDENT.match(prefix):
        raise InputError(f"prefix: expected a C identifier such as 'gt_cart_pendulum', got {prefix!r}")
    table = {s.name: s for s in model_specs(dae)}
    if not table:
        raise InputError(f"model {model.name!r} has no states, algebraic variables or outputs: nothing to generate")
    chosen = list(table) if functions is None else list(functions)
    unknown = [f for f in chosen if f not in table]
    if unknown or not chosen:
        raise InputError(f"functions: {unknown or 'none'} not among the model's functions ({', '.join(table)})")
    specs = tuple(table[f] for f in dict.fromkeys(chosen))
    source = ModelSource(model, dae)
    out = Path(out_dir)
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise CodegenError(f"cannot create output folder {out}: {exc.strerror}") from None
    cg = ca.CodeGenerator(f"{prefix}_casadi.c", {"with_header": True, "prefix": f"{prefix}_cg_", "casadi_real": real})
    funcs, cnames = {}, {}
    for spec in specs:
        cnames[spec.name] = f"{prefix}_cg_{spec.name}"
        funcs[spec.name] = _prepare(spec, spec.build(source), cnames[spec.name])
        cg.add(funcs[spec.name])
    try:
        cg.generate(str(out) + "/")
    except RuntimeError as exc:
        raise CodegenError(f"CasADi code generation failed: {exc}") from None
    casadi_source = out / f"{prefix}_casadi.c"
    text = casadi_source.read_text()
    sizes = {s.name: _work_sizes(text, cnames[s.name], funcs[s.name]) for s in specs}
    phash = model_parameter_hash(dae)
    version = f"gtmodel {gtmodel.__version__}; casadi {ca.__version__}; model {dae.name} sha256:{phash}; real {real}"
    header, wrapper = out / f"{prefix}.h", out / f"{prefix}.c"
    try:
        casadi_source.write_text("/* CasADi-generated code; gtmodel marked unused function parameters (void) and the\n"
                                 " * scalar helpers static. */\n" + _static_helpers(_void_unused_parameters(text)))
        wrapped = functions_fragment(prefix, specs, funcs, cnames, sizes, real)
        header.write_text(_header_text(prefix, wrapped, version, phash, dae, real))
        wrapper.write_text(wrapper_text(prefix, wrapped, sizes))
    except OSError as exc:
        raise CodegenError(f"cannot write generated code to {out}: {exc.strerror}") from None
    log.info("codegen: wrote %s (%s) for model %s", wrapper, ", ".join(s.name for s in specs), dae.name)
    signatures = {
        s.name: (tuple(_arg_size(s, funcs, a) for a in s.args), tuple(_out_function(s, funcs).numel_out(o.casadi_output) for o in s.outputs))
        for s in specs
    }
    return GeneratedCode(
        out_dir=out, prefix=prefix, functions=tuple(s.name for s in specs), source=wrapper, header=header,
        casadi_source=casadi_source, casadi_header=out / f"{prefix}_casadi.h", parameters=source, friction="",
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


def check_model(
    generated: GeneratedCode,
    n: int = 1000,
    seed: int = 0,
    library: CompiledLibrary | None = None,
    build_dir: str | Path | None = None,
    timing: bool = False,
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

    Returns
    -------
    CheckReport
        Per function the largest ``|C - Python|`` against :data:`MODEL_TOLERANCE`
        (absolute or relative); probes: a NaN or infinite input gives
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
        library = load_library(generated, compile_shared(generated, build, werror=True, extra_flags=STRICT_EXTRA))
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
    if timing:
        times = time_functions(generated, library.path, samples, build)
        results = [type(r)(**{**r.__dict__, "ns_per_call": times.get(r.name)}) for r in results]
    report = CheckReport(
        robot=source.name, prefix=generated.prefix, n=int(n), seed=seed, functions=tuple(results),
        probes=tuple(probes), version=library.version(), library=library.path,
    )
    log.info("codegen check of model %s: %s", generated.prefix, "passed" if report.passed else "FAILED")
    return report

