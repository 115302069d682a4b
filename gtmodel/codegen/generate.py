"""Generate C for the robot model: CasADi-generated code plus plain-C wrappers.

For a parameter set (``"L1"``) :func:`generate` writes, into ``out_dir``:

``<prefix>_casadi.c`` / ``<prefix>_casadi.h``
    The CasADi Functions of the model (kinematics, dynamics), emitted by
    :class:`casadi.CodeGenerator`: the maths, with the parameters embedded as constants.
``<prefix>.c`` / ``<prefix>.h``
    The public API: one plain-C function per model function with fixed-size array
    arguments, an ``int`` status return (``GT_OK`` = 0) and no dynamic memory. The work
    arrays are on the stack, sized at generation time from the generated ``*_work``
    functions. On any non-OK status the outputs are left untouched: no NaN is ever written.

The C functions are reentrant (no static state) and thus thread-safe.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import logging
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Iterable, Sequence

import casadi as ca
import numpy as np

import gtmodel
from gtmodel.errors import CodegenError, InputError
from gtmodel.codegen.specs import (
    DEFAULT_FUNCTIONS,
    FUNCTION_SPECS,
    STATUS_CODES,
    THRESHOLD_MACROS,
    FunctionSpec,
    RobotModel,
)
from gtmodel.robots.parameters import RobotParameters, load_parameters

__all__ = ["GeneratedCode", "generate", "parameter_hash"]

log = logging.getLogger("gtmodel")

_IDENT = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*$")


@dataclass(frozen=True)
class GeneratedCode:
    """The files written by :func:`generate` and what they contain.

    Parameters
    ----------
    out_dir : pathlib.Path
        Folder holding the files.
    prefix : str
        C symbol prefix, e.g. ``"gt_L1"`` (functions are ``gt_L1_ik``, ...).
    functions : tuple of str
        Generated function names, e.g. ``("ik", "fk", "jacobian", "inverse_dynamics")``.
    source : pathlib.Path
        Wrapper source ``<prefix>.c``.
    header : pathlib.Path
        Public header ``<prefix>.h`` (the only header a user includes).
    casadi_source : pathlib.Path
        CasADi-generated source ``<prefix>_casadi.c``.
    casadi_header : pathlib.Path
        CasADi-generated header ``<prefix>_casadi.h`` (internal).
    parameters : RobotParameters
        The parameter set embedded in the code.
    friction : str
        Friction form of the dynamics.
    parameter_hash : str
        First 16 hex digits of the SHA-256 of the parameter set.
    version : str
        Version string compiled into the library (gtmodel, CasADi, parameter hash).
    specs : tuple of FunctionSpec
        Declarations of the generated functions (C signatures, status checks).
    work_sizes : dict
        ``{name: (sz_arg, sz_res, sz_iw, sz_w)}`` of the stack work arrays.
    signatures : dict
        ``{name: (sizes_in, sizes_out)}``: length of each C argument in order (0 for an
        ``int``) and of each output array.
    """

    out_dir: Path
    prefix: str
    functions: tuple[str, ...]
    source: Path
    header: Path
    casadi_source: Path
    casadi_header: Path
    parameters: RobotParameters = field(repr=False)
    friction: str
    parameter_hash: str
    version: str
    specs: tuple[FunctionSpec, ...] = field(repr=False)
    work_sizes: dict[str, tuple[int, int, int, int]] = field(repr=False)
    signatures: dict[str, tuple[tuple[int, ...], tuple[int, ...]]] = field(repr=False)

    @property
    def c_sources(self) -> tuple[Path, Path]:
        """The two C sources to compile: CasADi part and wrapper."""
        return (self.casadi_source, self.source)

    @property
    def files(self) -> tuple[Path, ...]:
        """All written files."""
        return (self.casadi_source, self.casadi_header, self.source, self.header)

    def spec(self, name: str) -> FunctionSpec:
        """Declaration of one generated function.

        Parameters
        ----------
        name : str
            Function name, e.g. ``"ik"``.

        Returns
        -------
        FunctionSpec
            Its declaration.

        Raises
        ------
        KeyError
            ``name`` was not generated.
        """
        for s in self.specs:
            if s.name == name:
                return s
        raise KeyError(name)


# ----------------------------------------------------------------------------- helpers
def _canonical(obj):
    if dataclasses.is_dataclass(obj):
        return {f.name: _canonical(getattr(obj, f.name)) for f in dataclasses.fields(obj) if f.name not in ("path",)}
    if isinstance(obj, np.ndarray):
        return [_canonical(x) for x in obj.tolist()] if obj.ndim else float(obj)
    if isinstance(obj, (list, tuple)):
        return [_canonical(x) for x in obj]
    if isinstance(obj, float):
        return float.hex(obj)  # exact
    return obj


def parameter_hash(parameters: RobotParameters) -> str:
    """Short hash identifying the numbers of a parameter set.

    Parameters
    ----------
    parameters : RobotParameters
        The parameter set.

    Returns
    -------
    str
        First 16 hex digits of the SHA-256 of a canonical (exact, order-fixed) encoding
        of every field except the file path.
    """
    text = json.dumps(_canonical(parameters), sort_keys=True, separators=(",", ":"))
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def _resolve_specs(functions: Iterable[str | FunctionSpec]) -> tuple[FunctionSpec, ...]:
    if isinstance(functions, (str, FunctionSpec)):
        functions = (functions,)
    specs = []
    for f in functions:
        if isinstance(f, FunctionSpec):
            specs.append(f)
        elif isinstance(f, str) and f in FUNCTION_SPECS:
            specs.append(FUNCTION_SPECS[f])
        else:
            raise InputError(f"functions: unknown function {f!r} (available: {', '.join(FUNCTION_SPECS)})")
    if not specs:
        raise InputError("functions: expected at least one function")
    names = [s.name for s in specs]
    if len(set(names)) != len(names):
        raise InputError(f"functions: duplicate names in {names}")
    for s in specs:
        if not _IDENT.match(s.name):
            raise InputError(f"functions: {s.name!r} is not a valid C identifier")
    return tuple(specs)


def _c_float(x: float) -> str:
    r = repr(float(x))
    return r if any(ch in r for ch in ".eE") else r + ".0"


def _prepare(spec: FunctionSpec, f: ca.Function, cname: str) -> ca.Function:
    """Validate ``f`` against ``spec`` and return it renamed to ``cname`` with dense outputs."""
    if not isinstance(f, ca.Function):
        raise CodegenError(f"{spec.name}: build() returned {type(f).__name__}, expected casadi.Function")
    names_in, names_out = f.name_in(), f.name_out()
    for a in spec.args:
        if a.casadi_input not in names_in:
            raise CodegenError(f"{spec.name}: CasADi Function has no input {a.casadi_input!r} (inputs: {names_in})")
        sp = f.sparsity_in(a.casadi_input)
        if not sp.is_dense() or sp.size2() != 1:
            raise CodegenError(f"{spec.name}: input {a.casadi_input!r} must be a dense column vector")
        n = sp.numel()
        if a.kind == "configuration" and n != 3:
            raise CodegenError(f"{spec.name}: configuration input {a.casadi_input!r} must have 3 elements, has {n}")
        if a.kind == "solution" and n != 1:
            raise CodegenError(f"{spec.name}: solution input {a.casadi_input!r} must be scalar, has {n}")
        if a.kind not in ("vector", "configuration", "solution"):
            raise CodegenError(f"{spec.name}: unknown argument kind {a.kind!r}")
    fed = {a.casadi_input for a in spec.args}
    missing = [n for n in names_in if n not in fed]
    if missing:
        raise CodegenError(f"{spec.name}: CasADi inputs {missing} are not fed by any C argument")
    for name in [o.casadi_output for o in spec.outputs] + [c.casadi_output for c in spec.checks]:
        if name not in names_out:
            raise CodegenError(f"{spec.name}: CasADi Function has no output {name!r} (outputs: {names_out})")
    if f.is_a("SXFunction"):
        ins = f.sx_in()
    else:
        ins = f.mx_in()
    outs = [ca.densify(o) for o in f.call(ins)]
    return ca.Function(cname, ins, outs, names_in, names_out)


def _work_sizes(casadi_c: str, cname: str, f: ca.Function) -> tuple[int, int, int, int]:
    """Work-array sizes from the generated ``<cname>_work`` function (CasADi's values as fallback)."""
    pat = re.compile(
        rf"int {re.escape(cname)}_work\(.*?\{{\s*"
        r"if \(sz_arg\) \*sz_arg = (\d+);\s*if \(sz_res\) \*sz_res = (\d+);\s*"
        r"if \(sz_iw\) \*sz_iw = (\d+);\s*if \(sz_w\) \*sz_w = (\d+);",
        re.S,
    )
    m = pat.search(casadi_c)
    if m:
        sizes = tuple(int(g) for g in m.groups())
    else:  # pragma: no cover - depends on the CasADi version
        log.warning("codegen: could not read %s_work from the generated code; using CasADi's sizes", cname)
        sizes = (f.sz_arg(), f.sz_res(), f.sz_iw(), f.sz_w())
    return (max(sizes[0], f.n_in()), max(sizes[1], f.n_out()), sizes[2], sizes[3])


def _signature(spec: FunctionSpec, f: ca.Function) -> tuple[tuple[int, ...], tuple[int, ...]]:
    sizes_in = tuple(f.numel_in(a.casadi_input) if a.kind == "vector" else 0 for a in spec.args)
    sizes_out = tuple(f.numel_out(o.casadi_output) for o in spec.outputs)
    return sizes_in, sizes_out


# ----------------------------------------------------------------------------- C text
def _c_params(spec: FunctionSpec, f: ca.Function, *, with_names: bool = True) -> str:
    parts = []
    for a in spec.args:
        if a.kind == "vector":
            parts.append(f"const double {a.name}[{f.numel_in(a.casadi_input)}]")
        else:
            parts.append(f"int {a.name}")
    for o in spec.outputs:
        parts.append(f"double {o.name}[{f.numel_out(o.casadi_output)}]")
    return ", ".join(parts)


def _comment_block(lines: Sequence[str], indent: str = "") -> str:
    out = [f"{indent}/*"]
    out += [f"{indent} *{(' ' + l) if l else ''}" for l in lines]
    out.append(f"{indent} */")
    return "\n".join(out)


def _doc_lines(spec: FunctionSpec, f: ca.Function) -> list[str]:
    lines = [spec.doc, "", "Inputs:"]
    for a in spec.args:
        if a.kind == "vector":
            lines.append(f"  {a.name}[{f.numel_in(a.casadi_input)}]: {a.doc}")
        else:
            lines.append(f"  {a.name}: {a.doc}")
    lines.append("Outputs (written only when GT_OK is returned):")
    for o in spec.outputs:
        lines.append(f"  {o.name}[{f.numel_out(o.casadi_output)}]: {o.doc}")
    statuses = ["GT_OK"] + list(dict.fromkeys(c.status for c in spec.checks)) + ["GT_BAD_ARGUMENT", "GT_NUMERIC_ERROR"]
    lines.append("Returns: " + ", ".join(statuses) + ".")
    return lines


def _header_text(gen_prefix: str, specs, funcs, version: str, phash: str, parameters: RobotParameters, friction: str) -> str:
    P = gen_prefix.upper()
    out = [
        f"/* {gen_prefix}.h: C API of the {parameters.name} Gantry-Tau model.",
        " *",
        " * Generated by gtmodel from the CasADi model; do not edit.",
        f" * {version}",
        f" * Robot: {parameters.description}",
        f" * Friction form of the dynamics: {friction}",
        " *",
        " * Conventions: SI units (m, m/s, m/s^2, N); arrays of fixed size as declared;",
        " * matrices ROW-MAJOR (element (r, c) of a 3x3 matrix at index 3*r + c).",
        " * Every function returns a status code (GT_OK = 0). On any other status the",
        " * output arrays are NOT written (left untouched), so no NaN is ever written.",
        " * The functions use no dynamic memory and no static state: they are reentrant.",
        " */",
        f"#ifndef {P}_H",
        f"#define {P}_H",
        "",
        "#ifdef __cplusplus",
        'extern "C" {',
        "#endif",
        "",
        "/* Status codes, shared by every gtmodel-generated library. */",
        "#ifndef GT_STATUS_CODES",
        "#define GT_STATUS_CODES",
    ]
    for macro, (value, doc) in STATUS_CODES.items():
        out.append(f"#define {macro} {value} /* {doc} */")
    out += [
        "#endif",
        "",
        f'#define {P}_VERSION "{version}"',
        f'#define {P}_PARAMETER_HASH "{phash}"',
        f'#define {P}_ROBOT "{parameters.name}"',
        "/* Smallest accepted |cos| of the link-to-guideway angle; below it GT_SINGULAR. */",
        f"#define {P}_SINGULARITY_TOLERANCE {_c_float(THRESHOLD_MACROS['SINGULARITY_TOLERANCE'])}",
        "/* Smallest accepted distance [m] of sphere centre 3 from the line through 1 and 2 (FK). */",
        f"#define {P}_DEGENERACY_TOLERANCE {_c_float(THRESHOLD_MACROS['DEGENERACY_TOLERANCE'])}",
        "",
        "/* Version string: gtmodel and CasADi versions and the parameter-set hash. */",
        f"const char *{gen_prefix}_version(void);",
        "",
        "/* Name of a status code, e.g. \"GT_UNREACHABLE\" (\"unknown\" for others). */",
        f"const char *{gen_prefix}_status_string(int status);",
        "",
    ]
    for spec in specs:
        f = funcs[spec.name]
        out.append(_comment_block(_doc_lines(spec, f)))
        out.append(f"int {gen_prefix}_{spec.name}({_c_params(spec, f)});")
        out.append("")
    out += ["#ifdef __cplusplus", '} /* extern "C" */', "#endif", "", f"#endif /* {P}_H */", ""]
    return "\n".join(out)


def _wrapper_text(gen_prefix: str, specs, funcs, cnames, sizes, version: str) -> str:
    P = gen_prefix.upper()
    kinds = {a.kind for s in specs for a in s.args}
    out = [
        f"/* {gen_prefix}.c: plain-C wrappers of the CasADi-generated model functions.",
        " * Generated by gtmodel; do not edit. See the header for the API. */",
        f'#include "{gen_prefix}.h"',
        f'#include "{gen_prefix}_casadi.h"',
        "",
        "#include <math.h>",
        "#include <stddef.h>",
        "",
        "/* Stack work-array sizes, from the generated *_work functions (at least 1). */",
    ]
    for spec in specs:
        N = f"{P}_{spec.name.upper()}"
        sa, sr, siw, sw = sizes[spec.name]
        cn = cnames[spec.name]
        out += [
            f"#define {N}_SZ_ARG {max(sa, 1)}",
            f"#define {N}_SZ_RES {max(sr, 1)}",
            f"#define {N}_SZ_IW {max(siw, 1)}",
            f"#define {N}_SZ_W {max(sw, 1)}",
        ]
        for k in ("ARG", "RES", "IW", "W"):
            out += [
                f"#if defined({cn}_SZ_{k}) && ({cn}_SZ_{k} > {N}_SZ_{k})",
                f'#error "work array {k} of {spec.name} too small: regenerate the code"',
                "#endif",
            ]
    out += [
        "",
        f"const char *{gen_prefix}_version(void) {{ return {P}_VERSION; }}",
        "",
        f"const char *{gen_prefix}_status_string(int status)",
        "{",
        "    switch (status) {",
    ]
    for macro in STATUS_CODES:
        out.append(f'    case {macro}: return "{macro}";')
    out += ["    default: return \"unknown\";", "    }", "}", ""]
    out += [
        "/* 1 if all n values are finite. */",
        f"static int {gen_prefix}_finite(const casadi_real *x, int n)",
        "{",
        "    int i;",
        "    for (i = 0; i < n; ++i) {",
        "        if (!isfinite(x[i])) return 0;",
        "    }",
        "    return 1;",
        "}",
        "",
        "/* 1 if x[i] >= t for all i (NaN fails). */",
        f"static int {gen_prefix}_all_ge(const casadi_real *x, int n, double t)",
        "{",
        "    int i;",
        "    for (i = 0; i < n; ++i) {",
        "        if (!(x[i] >= t)) return 0;",
        "    }",
        "    return 1;",
        "}",
        "",
        "/* 1 if x[i] > t for all i (NaN fails). */",
        f"static int {gen_prefix}_all_gt(const casadi_real *x, int n, double t)",
        "{",
        "    int i;",
        "    for (i = 0; i < n; ++i) {",
        "        if (!(x[i] > t)) return 0;",
        "    }",
        "    return 1;",
        "}",
        "",
    ]
    used_ops = {c.op for s in specs for c in s.checks}
    if ">=" not in used_ops:
        out = _drop_function(out, f"{gen_prefix}_all_ge")
    if ">" not in used_ops:
        out = _drop_function(out, f"{gen_prefix}_all_gt")
    if "configuration" in kinds:
        out += [
            "/* IK root signs of configuration c (bit i set: +1, clear: -1); 0 if c is valid. */",
            f"static int {gen_prefix}_signs(int c, casadi_real s[3])",
            "{",
            "    int i;",
            "    if (c < 0 || c > 7) return 1;",
            "    for (i = 0; i < 3; ++i) s[i] = ((c >> i) & 1) ? 1.0 : -1.0;",
            "    return 0;",
            "}",
            "",
        ]
    for spec in specs:
        f = funcs[spec.name]
        cn = cnames[spec.name]
        N = f"{P}_{spec.name.upper()}"
        names_in, names_out = f.name_in(), f.name_out()
        used_out = list(dict.fromkeys([o.casadi_output for o in spec.outputs] + [c.casadi_output for c in spec.checks]))
        body = [
            f"int {gen_prefix}_{spec.name}({_c_params(spec, f)})",
            "{",
            f"    const casadi_real *arg[{N}_SZ_ARG];",
            f"    casadi_real *res[{N}_SZ_RES];",
            f"    casadi_int iw[{N}_SZ_IW];",
            f"    casadi_real w[{N}_SZ_W];",
        ]
        for a in spec.args:
            if a.kind == "configuration":
                body.append(f"    casadi_real in_{a.name}[3];")
            elif a.kind == "solution":
                body.append(f"    casadi_real in_{a.name}[1];")
        for name in used_out:
            body.append(f"    casadi_real out_{name}[{f.numel_out(name)}];")
        body.append("    int i;")
        ptrs = [a.name for a in spec.args if a.kind == "vector"] + [o.name for o in spec.outputs]
        body.append("    if (" + " || ".join(f"{p} == NULL" for p in ptrs) + ") return GT_BAD_ARGUMENT;")
        for a in spec.args:
            if a.kind == "vector":
                body.append(
                    f"    if (!{gen_prefix}_finite({a.name}, {f.numel_in(a.casadi_input)})) return GT_BAD_ARGUMENT;"
                )
            elif a.kind == "configuration":
                body.append(f"    if ({gen_prefix}_signs({a.name}, in_{a.name}) != 0) return GT_BAD_ARGUMENT;")
            else:
                body.append(f"    if ({a.name} != 1 && {a.name} != -1) return GT_BAD_ARGUMENT;")
                body.append(f"    in_{a.name}[0] = (casadi_real){a.name};")
        body.append(f"    for (i = 0; i < {N}_SZ_ARG; ++i) arg[i] = NULL;")
        body.append(f"    for (i = 0; i < {N}_SZ_RES; ++i) res[i] = NULL;")
        for a in spec.args:
            src = a.name if a.kind == "vector" else f"in_{a.name}"
            body.append(f"    arg[{names_in.index(a.casadi_input)}] = {src};")
        for name in used_out:
            body.append(f"    res[{names_out.index(name)}] = out_{name};")
        body.append(f"    if ({cn}(arg, res, iw, w, 0) != 0) return GT_NUMERIC_ERROR;")
        for c in spec.checks:
            fn = f"{gen_prefix}_all_ge" if c.op == ">=" else f"{gen_prefix}_all_gt"
            thr = f"{P}_{c.threshold}" if c.threshold in THRESHOLD_MACROS else c.threshold
            body.append(f"    if (!{fn}(out_{c.casadi_output}, {f.numel_out(c.casadi_output)}, {thr})) return {c.status};")
        for o in spec.outputs:
            body.append(
                f"    if (!{gen_prefix}_finite(out_{o.casadi_output}, {f.numel_out(o.casadi_output)})) return GT_NUMERIC_ERROR;"
            )
        for o in spec.outputs:
            sp = f.sparsity_out(o.casadi_output)
            nr, nc = sp.size1(), sp.size2()
            if nc == 1 or nr == 1:
                body.append(f"    for (i = 0; i < {nr * nc}; ++i) {o.name}[i] = out_{o.casadi_output}[i];")
            else:  # CasADi is column-major; the C API is row-major
                body.append(
                    f"    for (i = 0; i < {nr * nc}; ++i) {o.name}[i] = out_{o.casadi_output}[(i % {nc}) * {nr} + i / {nc}];"
                )
        body += ["    return GT_OK;", "}", ""]
        out += body
    return "\n".join(out)


def _drop_function(lines: list[str], name: str) -> list[str]:
    """Remove a static helper (comment line, definition, blank line) from ``lines``."""
    start = next(i for i, l in enumerate(lines) if name + "(" in l and l.startswith("static"))
    end = lines.index("}", start)
    return lines[: start - 1] + lines[end + 2 :]


# ----------------------------------------------------------------------------- API
def generate(
    robot: str | Path | RobotParameters = "L1",
    out_dir: str | Path = "codegen_out",
    functions: Sequence[str | FunctionSpec] = DEFAULT_FUNCTIONS,
    prefix: str | None = None,
    friction: str = "exact",
) -> GeneratedCode:
    """Generate C source and a public header for model functions of a 3-link Gantry-Tau.

    Parameters
    ----------
    robot : str or pathlib.Path or RobotParameters, optional
        Parameter set: shipped name (``"L1"``, ``"D1"``), path of a TOML file, or a loaded
        set. Its values are embedded as constants.
    out_dir : str or pathlib.Path, optional
        Folder to write into (created if missing; existing files of the same names are
        overwritten).
    functions : sequence of str or FunctionSpec, optional
        Functions to generate: names from :data:`gtmodel.codegen.specs.FUNCTION_SPECS`
        (default ``ik``, ``fk``, ``jacobian``, ``inverse_dynamics``) or declarations.
    prefix : str or None, optional
        C symbol prefix; default ``"gt_<robot name>"``, e.g. ``gt_L1`` (giving
        ``gt_L1_ik``, header ``gt_L1.h``).
    friction : str, optional
        Friction form of the dynamics: ``"exact"`` (default), ``"tanh"``, ``"piecewise"``.

    Returns
    -------
    GeneratedCode
        Paths of the written ``.c``/``.h`` files, the prefix and the functions.

    Raises
    ------
    InputError
        Unknown function name, invalid prefix or friction form.
    ParameterError
        Unknown or invalid parameter set.
    CodegenError
        A CasADi Function does not match its declaration, or writing the files failed.
    """
    parameters = load_parameters(robot)
    if prefix is None:
        prefix = "gt_" + re.sub(r"[^A-Za-z0-9_]", "_", parameters.name)
    if not isinstance(prefix, str) or not _IDENT.match(prefix):
        raise InputError(f"prefix: expected a C identifier such as 'gt_L1', got {prefix!r}")
    from gtmodel.robots.friction import DEFAULT_FRICTION_WIDTH, check_friction_form

    check_friction_form(friction, DEFAULT_FRICTION_WIDTH)
    specs = _resolve_specs(functions)
    out = Path(out_dir)
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise CodegenError(f"cannot create output folder {out}: {exc.strerror}") from None

    model = RobotModel(parameters, friction)
    funcs: dict[str, ca.Function] = {}
    cnames: dict[str, str] = {}
    cg = ca.CodeGenerator(f"{prefix}_casadi.c", {"with_header": True, "prefix": f"{prefix}_cg_"})
    for spec in specs:
        cname = f"{prefix}_cg_{spec.name}"
        f = _prepare(spec, spec.build(model), cname)
        funcs[spec.name] = f
        cnames[spec.name] = cname
        cg.add(f)
    try:
        cg.generate(str(out) + "/")
    except RuntimeError as exc:
        raise CodegenError(f"CasADi code generation failed: {exc}") from None
    casadi_source = out / f"{prefix}_casadi.c"
    casadi_text = casadi_source.read_text()
    sizes = {s.name: _work_sizes(casadi_text, cnames[s.name], funcs[s.name]) for s in specs}

    phash = parameter_hash(parameters)
    version = (
        f"gtmodel {gtmodel.__version__}; casadi {ca.__version__}; "
        f"parameters {parameters.name} sha256:{phash}; friction {friction}"
    )
    header = out / f"{prefix}.h"
    source = out / f"{prefix}.c"
    try:
        header.write_text(_header_text(prefix, specs, funcs, version, phash, parameters, friction))
        source.write_text(_wrapper_text(prefix, specs, funcs, cnames, sizes, version))
    except OSError as exc:
        raise CodegenError(f"cannot write generated code to {out}: {exc.strerror}") from None
    log.info("codegen: wrote %s (%s) for %s", source, ", ".join(s.name for s in specs), parameters.name)
    return GeneratedCode(
        out_dir=out,
        prefix=prefix,
        functions=tuple(s.name for s in specs),
        source=source,
        header=header,
        casadi_source=casadi_source,
        casadi_header=out / f"{prefix}_casadi.h",
        parameters=parameters,
        friction=friction,
        parameter_hash=phash,
        version=version,
        specs=specs,
        work_sizes=sizes,
        signatures={s.name: _signature(s, funcs[s.name]) for s in specs},
    )
