"""The generic C writer of every library: the wrapped functions (doc comments, prototypes, wrappers, Newton loops) and the wrapper source.

Given the CasADi Functions prepared by :mod:`gtmodel.codegen.writer` (renamed, dense,
their work sizes known), :func:`functions_fragment` writes the wrapped functions (a
robot's, a controller's, a user model's) as a :class:`~gtmodel.codegen.emit.Fragment`:
doc comment and prototype per function, and the wrappers around the CasADi-generated code
(argument checks, status conditions, the bounded Newton loops of
:class:`~gtmodel.codegen.declarations.NewtonLoop`). :func:`wrapper_text` puts it and the
other fragments in the frame of the wrapper source (the hand-written ``harness/template_wrapper.c``
and ``template_wrapper_helpers.c``); each source's header is its own (a robot's:
:func:`gtmodel.codegen.emit.robot.header_text`; a user model's and a loop step's in their modules).
"""

from __future__ import annotations

import textwrap
from typing import Sequence

import casadi as ca

from gtmodel.codegen.declarations import STATUS_CODES, THRESHOLD_MACROS, FunctionSpec, StatusCheck
from gtmodel.codegen.emit import Fragment, fill
from gtmodel._escape import c_comment
from gtmodel.errors import CodegenError

__all__ = ["functions_fragment", "wrapper_text"]


def _check_every(nl, newton_check_every: int | None) -> int:
    """Steps between convergence tests of a Newton loop (generation option, else the declaration's)."""
    return newton_check_every if newton_check_every is not None else nl.check_every


def _arg_size(spec: FunctionSpec, funcs: dict, a) -> int:
    """Number of values of an array argument (0 for ``int`` arguments)."""
    if a.kind not in ("vector", "matrix"):
        return 0
    for f in _parts(spec, funcs):
        if a.casadi_input in f.name_in():
            return f.numel_in(a.casadi_input)
    raise CodegenError(f"{spec.name}: argument {a.name!r} feeds no CasADi Function")  # pragma: no cover


def _out_function(spec: FunctionSpec, funcs: dict) -> ca.Function:
    """The Function whose outputs are published (the finish Function of a Newton loop)."""
    return funcs[spec.name]["finish"] if spec.newton is not None else funcs[spec.name]


def _parts(spec: FunctionSpec, funcs: dict) -> list[ca.Function]:
    v = funcs[spec.name]
    return list(v.values()) if isinstance(v, dict) else [v]


def _c_params(spec: FunctionSpec, funcs: dict, real: str) -> str:
    parts = []
    fo = _out_function(spec, funcs)
    for a in spec.args:
        if a.kind in ("vector", "matrix"):
            parts.append(f"const {real} {a.name}[{_arg_size(spec, funcs, a)}]")
        else:
            parts.append(f"int {a.name}")
    for o in spec.outputs:
        parts.append(f"{real} {o.name}[{fo.numel_out(o.casadi_output)}]")
    if spec.newton is not None:
        parts.append("int *iterations")
    return ", ".join(parts)


def _comment_block(lines: Sequence[str], indent: str = "") -> str:
    out = [f"{indent}/*"]
    out += [f"{indent} *{(' ' + c_comment(l)) if l else ''}" for l in lines]
    out.append(f"{indent} */")
    return "\n".join(out)


def _statuses(spec: FunctionSpec) -> list[str]:
    checks = list(spec.checks) + (list(spec.newton.start_checks) if spec.newton else [])
    out = ["GT_OK"] + list(dict.fromkeys(c.status for c in checks)) + ["GT_BAD_ARGUMENT", "GT_NUMERIC_ERROR"]
    if spec.newton is not None:
        out.append("GT_NOT_CONVERGED")
    return list(dict.fromkeys(out))


def _doc_lines(spec: FunctionSpec, funcs: dict, P: str, sizes: tuple[int, int, int, int]) -> list[str]:
    fo = _out_function(spec, funcs)
    lines = textwrap.wrap(spec.doc, 88) + ["", "Inputs:"]
    for a in spec.args:
        null = " (may be NULL)" if a.optional else ""
        if a.kind in ("vector", "matrix"):
            lines.append(f"  {a.name}[{_arg_size(spec, funcs, a)}]{null}: {a.doc}")
        else:
            lines.append(f"  {a.name}: {a.doc}")
    lines.append("Outputs (written only when GT_OK is returned):")
    for o in spec.outputs:
        lines.append(f"  {o.name}[{fo.numel_out(o.casadi_output)}]: {o.doc}")
    if spec.newton is not None:
        nl = spec.newton
        N = f"{P}_{spec.name.upper()}"
        if nl.warm:
            lines.append(f"  Start: {' and '.join(nl.warm)} if non-NULL, else the default start.")
        lines += [
            "  iterations (may be NULL): Newton steps taken (written on every return after the",
            "    argument checks, also on GT_NOT_CONVERGED).",
            f"Newton loop: at most {N}_MAX_ITER + 1 step evaluations, converged when the residual,",
            f"  {nl.residual_unit}, is <= {N}_TOLERANCE.",
        ]
    lines.append("Returns: " + ", ".join(_statuses(spec)) + ".")
    sa, sr, siw, sw = sizes
    lines.append(f"Stack use: about {8 * (sw + 64) + 8 * (sa + sr) + 8 * siw} bytes of work arrays; no heap.")
    return lines


def functions_fragment(gen_prefix: str, specs: Sequence[FunctionSpec], funcs: dict, cnames: dict, sizes: dict, real: str,
                       newton_check_every: int | None = None) -> Fragment:
    """The wrapped functions (a robot's, a controller's, a user model's) as a fragment of the library.

    Parameters
    ----------
    gen_prefix : str
        C prefix (``gt_L1``).
    specs : sequence of FunctionSpec
        The functions, in order.
    funcs : dict
        ``{name: casadi.Function}`` of a closed-form function, ``{name: {part: casadi.Function}}``
        of a Newton loop (prepared by :mod:`gtmodel.codegen.writer`).
    cnames : dict
        The C names of those Functions, in the same layout.
    sizes : dict
        ``{name: (sz_arg, sz_res, sz_iw, sz_w)}`` of the stack work arrays.
    real : {"double", "float"}
        Floating-point type.
    newton_check_every : int or None, optional
        Steps between convergence tests of every Newton loop (None: each declaration's).

    Returns
    -------
    Fragment
        Header: per function its doc comment and prototype; source: the wrappers
        (argument checks, calls of the CasADi-generated code, status conditions, bounded
        Newton loops); specs: ``specs``.
    """
    P = gen_prefix.upper()
    prototypes: list[str] = []
    bodies: list[str] = []
    for spec in specs:
        prototypes += [*_comment_block(_doc_lines(spec, funcs, P, sizes[spec.name])).splitlines(),
                       f"int {gen_prefix}_{spec.name}({_c_params(spec, funcs, real)});", ""]
        if spec.newton is None:
            bodies += _closed_form_body(gen_prefix, P, spec, funcs[spec.name], cnames[spec.name], real, funcs)
        else:
            bodies += _newton_body(gen_prefix, P, spec, funcs[spec.name], cnames[spec.name], real, funcs, newton_check_every)
    return Fragment(tuple(prototypes), tuple(bodies), tuple(specs))


def _helpers(gp: str) -> list[str]:
    """The static helpers of the wrapper source (all; :func:`_wrapper_text` drops the unused ones)."""
    return fill("template_wrapper_helpers.c", GP=gp).splitlines()


def _drop_function(lines: list[str], name: str) -> list[str]:
    """Remove a static helper (comment line, definition, blank line) from ``lines``."""
    start = next(i for i, l in enumerate(lines) if name + "(" in l and l.startswith("static"))
    end = lines.index("}", start)
    return lines[: start - 1] + lines[end + 2 :]


def _arg_prologue(gp: str, spec: FunctionSpec, funcs: dict) -> tuple[list[str], list[str], dict[str, str]]:
    """Declarations, validation statements and the C expression feeding each CasADi input."""
    decl, body, feed = [], [], {}
    ptrs = [a.name for a in spec.args if a.kind in ("vector", "matrix") and not a.optional] + [o.name for o in spec.outputs]
    if ptrs:
        body.append("    if (" + " || ".join(f"{p} == NULL" for p in ptrs) + ") return GT_BAD_ARGUMENT;")
    for a in spec.args:
        n = _arg_size(spec, funcs, a)
        guard = f"{a.name} != NULL && " if a.optional else ""
        if a.kind == "vector":
            body.append(f"    if ({guard}!{gp}_finite({a.name}, {n})) return GT_BAD_ARGUMENT;")
            feed[a.casadi_input] = a.name
        elif a.kind == "matrix":
            decl.append(f"    casadi_real in_{a.name}[{n}];")
            body.append(f"    if ({guard}!{gp}_finite({a.name}, {n})) return GT_BAD_ARGUMENT;")
            if a.optional:
                body.append(f"    if ({a.name} != NULL) {gp}_transpose(in_{a.name}, {a.name}, 3, 3);")
            else:
                body.append(f"    {gp}_transpose(in_{a.name}, {a.name}, 3, 3);")
            feed[a.casadi_input] = f"in_{a.name}"
        elif a.kind == "configuration":
            decl.append(f"    casadi_real in_{a.name}[3];")
            body.append(f"    if ({gp}_signs({a.name}, in_{a.name}) != 0) return GT_BAD_ARGUMENT;")
            feed[a.casadi_input] = f"in_{a.name}"
        elif a.kind == "index":
            decl.append(f"    casadi_real in_{a.name}[1];")
            body.append(f"    in_{a.name}[0] = (casadi_real){a.name};")
            feed[a.casadi_input] = f"in_{a.name}"
        else:
            decl.append(f"    casadi_real in_{a.name}[1];")
            body.append(f"    if ({a.name} != 1 && {a.name} != -1) return GT_BAD_ARGUMENT;")
            body.append(f"    in_{a.name}[0] = (casadi_real){a.name};")
            feed[a.casadi_input] = f"in_{a.name}"
    return decl, body, feed


def _call(f: ca.Function, cname: str, N: str, feed: dict[str, str], results: dict[str, str], indent: str = "    ") -> list[str]:
    """Statements setting arg/res and calling ``cname``; evaluates to the CasADi return code in ``flag``."""
    out = [f"{indent}for (i = 0; i < {N}_SZ_ARG; ++i) arg[i] = NULL;", f"{indent}for (i = 0; i < {N}_SZ_RES; ++i) res[i] = NULL;"]
    for k, name in enumerate(f.name_in()):
        out.append(f"{indent}arg[{k}] = {feed[name]};")
    for k, name in enumerate(f.name_out()):
        if name in results:
            out.append(f"{indent}res[{k}] = {results[name]};")
    out.append(f"{indent}flag = {cname}(arg, res, iw, w, 0);")
    return out


def _check_lines(gp: str, P: str, f: ca.Function, checks: Sequence[StatusCheck], prefix: str = "out_", indent: str = "    ") -> list[str]:
    out = []
    for c in checks:
        strict = 1 if c.op == ">" else 0
        thr = f"{P}_{c.threshold}" if c.threshold in THRESHOLD_MACROS else c.threshold
        out.append(f"{indent}if (!{gp}_all({prefix}{c.casadi_output}, {f.numel_out(c.casadi_output)}, {thr}, {strict})) return {c.status};")
    return out


def _publish_lines(gp: str, spec: FunctionSpec, f: ca.Function) -> list[str]:
    out = []
    for o in spec.outputs:
        out.append(f"    if (!{gp}_finite(out_{o.casadi_output}, {f.numel_out(o.casadi_output)})) return GT_NUMERIC_ERROR;")
    for o in spec.outputs:
        sp = f.sparsity_out(o.casadi_output)
        nr, nc = sp.size1(), sp.size2()
        if nc == 1 or nr == 1:
            out.append(f"    {gp}_copy({o.name}, out_{o.casadi_output}, {nr * nc});")
        else:  # CasADi is column-major; the C API is row-major
            out.append(f"    {gp}_transpose({o.name}, out_{o.casadi_output}, {nc}, {nr});")
    return out


def _function_head(gp: str, P: str, spec: FunctionSpec, funcs: dict, real: str) -> tuple[str, list[str], list[str], list[str], dict[str, str]]:
    """Start of a wrapper: ``(macro stem, used CasADi outputs, signature and declarations, argument checks, feed)``."""
    N = f"{P}_{spec.name.upper()}"
    used_out = list(dict.fromkeys([o.casadi_output for o in spec.outputs] + [c.casadi_output for c in spec.checks]))
    decl, valid, feed = _arg_prologue(gp, spec, funcs)
    head = [
        f"int {gp}_{spec.name}({_c_params(spec, funcs, real)})",
        "{",
        f"    const casadi_real *arg[{N}_SZ_ARG];",
        f"    casadi_real *res[{N}_SZ_RES];",
        f"    casadi_int iw[{N}_SZ_IW];",
        f"    casadi_real w[{N}_SZ_W];",
        *decl,
    ]
    return N, used_out, head, valid, feed


def _closed_form_body(gp: str, P: str, spec: FunctionSpec, f: ca.Function, cname: str, real: str, funcs: dict) -> list[str]:
    N, used_out, body, valid, feed = _function_head(gp, P, spec, funcs, real)
    for name in used_out:
        body.append(f"    casadi_real out_{name}[{f.numel_out(name)}];")
    body += ["    int i, flag;", *valid]
    body += _call(f, cname, N, feed, {n: f"out_{n}" for n in used_out})
    body.append("    if (flag != 0) return GT_NUMERIC_ERROR;")
    body += _check_lines(gp, P, f, spec.checks)
    body += _publish_lines(gp, spec, f)
    body += ["    return GT_OK;", "}", ""]
    return body


def _newton_body(gp: str, P: str, spec: FunctionSpec, parts: dict, cnames: dict, real: str, funcs: dict, newton_check_every: int | None) -> list[str]:
    nl = spec.newton
    n = nl.size
    fs, fst, ff = parts["start"], parts["step"], parts["finish"]
    N, used_out, body, valid, feed = _function_head(gp, P, spec, funcs, real)
    body.append(f"    casadi_real x[{n}], x_next[{n}], residual[1]{', valid[1]' if 'valid' in fst.name_out() else ''};")
    start_out = [c.casadi_output for c in nl.start_checks]
    for name in start_out:
        body.append(f"    casadi_real st_{name}[{fs.numel_out(name)}];")
    for name in used_out:
        body.append(f"    casadi_real out_{name}[{ff.numel_out(name)}];")
    body += ["    int i, k, flag, converged = 0;", *valid]
    feed_x = dict(feed, x="x")
    start_call = _call(fs, cnames["start"], N, feed, dict({"x0": "x"}, **{s: f"st_{s}" for s in start_out}), "        ")
    start_call += ["        if (flag != 0) return GT_NUMERIC_ERROR;"]
    start_call += _check_lines(gp, P, fs, nl.start_checks, "st_", "        ")
    if nl.warm:
        cond = " && ".join(f"{w} != NULL" for w in nl.warm)
        body.append(f"    if ({cond}) {{")
        body += _call(parts["warm"], cnames["warm"], N, feed, {"x0": "x"}, "        ")
        body += ["        if (flag != 0) return GT_NUMERIC_ERROR;", "    } else {"]
        body += start_call
        body.append("    }")
    else:
        body.append("    {")
        body += start_call
        body.append("    }")
    if "invariant" in parts:  # the step's subexpressions of the fixed inputs, once
        body.insert(body.index("    int i, k, flag, converged = 0;"), f"    casadi_real pre[{parts['invariant'].numel_out('pre')}];")
        body += _call(parts["invariant"], cnames["invariant"], N, feed, {"pre": "pre"})
        body.append("    if (flag != 0) return GT_NUMERIC_ERROR;")
        feed_x["pre"] = "pre"
    has_valid = "valid" in fst.name_out()
    conv = f"residual[0] <= {N}_TOLERANCE" + (" && valid[0] >= 0" if has_valid else "")
    every = _check_every(nl, newton_check_every)
    tested = {"residual": "residual", "valid": "valid"}
    body += [
        f"    for (k = 0; k <= {N}_MAX_ITER; ++k) {{  /* bounded: at most MAX_ITER + 1 steps */",
    ]
    if every == 1:  # the step returns the residual of x_k with x_{k+1}: test every step
        body += _call(fst, cnames["step"], N, feed_x, {"x_next": "x_next", **tested}, "        ")
        body += ["        if (flag != 0) break;", f"        if ({conv}) {{", "            converged = 1;"]
        if nl.accept == "next":
            body.append(f"            if ({gp}_finite(x_next, {n})) {gp}_copy(x, x_next, {n});")
        body += ["            break;", "        }", f"        if (k == {N}_MAX_ITER) break;"]
    else:  # test x_k only at k = every, 2 every, ...: the residual alone there, no step
        if nl.accept != "current":
            raise CodegenError(f"{spec.name}: newton.check_every > 1 needs accept='current'")
        body.append(f"        if (k > 0 && k % {every} == 0) {{")
        body += _call(parts["residual"], cnames["residual"], N, feed_x, tested, "            ")
        body += [
            "            if (flag != 0) break;",
            f"            if ({conv}) {{",
            "                converged = 1;",
            "                break;",
            "            }",
            "        }",
            f"        if (k == {N}_MAX_ITER) break;",
        ]
        body += _call(fst, cnames["step"], N, feed_x, {"x_next": "x_next"}, "        ")
        body.append("        if (flag != 0) break;")
    body += [
        f"        if (!{gp}_finite(x_next, {n})) break;",
        f"        {gp}_copy(x, x_next, {n});",
        "    }",
        f"    if (iterations != NULL) *iterations = k > {N}_MAX_ITER ? {N}_MAX_ITER : k;",
    ]
    body += _call(ff, cnames["finish"], N, feed_x, {n_: f"out_{n_}" for n_ in used_out})
    body.append("    if (flag != 0) return GT_NUMERIC_ERROR;")
    body += _check_lines(gp, P, ff, spec.checks)
    body.append("    if (!converged) return GT_NOT_CONVERGED;")
    body += _publish_lines(gp, spec, ff)
    body += ["    return GT_OK;", "}", ""]
    return body


def wrapper_text(gen_prefix: str, functions: Fragment, sizes: dict, extra: Sequence[str] = ()) -> str:
    """The wrapper source ``<prefix>.c`` of a library.

    Parameters
    ----------
    gen_prefix : str
        C prefix (``gt_L1``).
    functions : Fragment
        The wrapped functions (:func:`functions_fragment`).
    sizes : dict
        ``{name: (sz_arg, sz_res, sz_iw, sz_w)}`` of the stack work arrays.
    extra : sequence of str, optional
        Source lines of the other fragments (controller, re-timing), at the end.

    Returns
    -------
    str
        ``harness/template_wrapper.c`` filled, the static helpers the wrappers call
        (``harness/template_wrapper_helpers.c``), the wrappers and ``extra``.
    """
    P = gen_prefix.upper()
    specs = functions.specs
    sizes_lines = []
    for spec in specs:
        N = f"{P}_{spec.name.upper()}"
        sa, sr, siw, sw = sizes[spec.name]
        sizes_lines += [
            f"#define {N}_SZ_ARG {max(sa, 1)}",
            f"#define {N}_SZ_RES {max(sr, 1)}",
            f"#define {N}_SZ_IW {max(siw, 1)}",
            f"#define {N}_SZ_W {max(sw, 1)}",
        ]
    cases = "\n".join(f'    case {macro}: return "{macro}";' for macro in STATUS_CODES)
    out = fill("template_wrapper.c", GP=gen_prefix, P=P, SIZES="\n".join(sizes_lines), STATUS_CASES=cases).splitlines() + [""]
    bodies = list(functions.source)
    helpers = _helpers(gen_prefix)
    used = "\n".join(bodies)
    for h in ("finite", "all", "copy", "transpose", "signs"):
        name = f"{gen_prefix}_{h}"
        if any(name + "(" in line for line in helpers) and name + "(" not in used:  # unused helper: drop it (-Werror)
            helpers = _drop_function(helpers, name)
    return "\n".join(out + helpers + bodies + list(extra))


