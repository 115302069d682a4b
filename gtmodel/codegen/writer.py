"""The one library writer: CasADi's C of declared functions, their plain-C wrappers, a header (:func:`write_library`).

Every source of generated code (:mod:`gtmodel.codegen.sources`) ends here or in the robot's
writer :func:`gtmodel.codegen.generate.generate`, which uses the same preparation of the
Functions (``_prepare``: renamed, dense inputs checked, common subexpressions merged; the
parts of a Newton loop with their invariants hoisted) and the same emitter
(:mod:`gtmodel.codegen.emit.wrapper`). :class:`GeneratedCode` describes what was written.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Sequence

import casadi as ca

from gtmodel.codegen.controller import Controller
from gtmodel.codegen.declarations import FunctionSpec
from gtmodel.codegen.emit.casadi_source import _static_helpers, _void_unused_parameters, _work_sizes
from gtmodel.codegen.emit.wrapper import _arg_size, _out_function, functions_fragment, wrapper_text
from gtmodel.codegen.robot import RobotModel
from gtmodel.defaults import REAL_TYPES  # noqa: F401  (re-exported: the codegen modules' import)
from gtmodel.errors import CodegenError

__all__ = ["REAL_TYPES", "GeneratedCode", "write_library"]

log = logging.getLogger("gtmodel")




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
    parameters : RobotParameters or SixLinkClosure or F1Closure
        The robot model embedded in the code.
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
    real : str
        ``"double"`` or ``"float"``.
    kind : str
        Robot kind (``"three_link"``, ``"six_link"``, ``"f1"``).
    newton : dict
        ``{name: (tolerance, max_iter)}`` of the Newton functions.
    controller : Controller or None
        The controller functions generated with the model's (``kalman_step``,
        ``ilc_correction``; see :mod:`gtmodel.codegen.controller`), or None.
    retime_n_max : int
        ``<PREFIX>_RETIME_N_MAX`` of the re-timing function ``<prefix>_retime``
        (:mod:`gtmodel.codegen.retime`); 0 when it was not generated.
    include_dirs, link_flags : tuple of str
        Header folders and linker arguments of the solver libraries the CasADi source
        includes (DAQP's, fatrop's, from the casadi wheel); empty for plain C.
    """

    out_dir: Path
    prefix: str
    functions: tuple[str, ...]
    source: Path
    header: Path
    casadi_source: Path
    casadi_header: Path
    parameters: Any = field(repr=False)
    friction: str
    parameter_hash: str
    version: str
    specs: tuple[FunctionSpec, ...] = field(repr=False)
    work_sizes: dict[str, tuple[int, int, int, int]] = field(repr=False)
    signatures: dict[str, tuple[tuple[int, ...], tuple[int, ...]]] = field(repr=False)
    real: str = "double"
    kind: str = "three_link"
    newton: dict[str, tuple[float, int]] = field(default_factory=dict, repr=False)
    controller: Controller | None = field(default=None, repr=False)
    retime_n_max: int = 0
    include_dirs: tuple[str, ...] = ()
    link_flags: tuple[str, ...] = ()

    @property
    def c_sources(self) -> tuple[Path, Path]:
        """The two C sources to compile: CasADi part and wrapper."""
        return (self.casadi_source, self.source)

    @property
    def files(self) -> tuple[Path, ...]:
        """All written files."""
        return (self.casadi_source, self.casadi_header, self.source, self.header)

    @property
    def robot_name(self) -> str:
        """Name of the robot model (e.g. ``"L1"``)."""
        return str(self.parameters.name)

    def model(self) -> RobotModel:
        """The symbolic model the code was generated from.

        Returns
        -------
        RobotModel
            Built from :attr:`parameters` and :attr:`friction`.
        """
        return RobotModel(self.parameters, self.friction)

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
def _check_arg_input(spec: FunctionSpec, f: ca.Function, a, where: str) -> None:
    sp = f.sparsity_in(a.casadi_input)
    n = sp.numel()
    if not sp.is_dense():
        raise CodegenError(f"{spec.name}: {where} input {a.casadi_input!r} must be dense")
    if a.kind == "matrix":
        if (sp.size1(), sp.size2()) != (3, 3):
            raise CodegenError(f"{spec.name}: matrix input {a.casadi_input!r} must be 3x3")
        return
    if sp.size2() != 1:
        raise CodegenError(f"{spec.name}: {where} input {a.casadi_input!r} must be a dense column vector")
    if a.kind == "configuration" and n != 3:
        raise CodegenError(f"{spec.name}: configuration input {a.casadi_input!r} must have 3 elements, has {n}")
    if a.kind in ("solution", "index") and n != 1:
        raise CodegenError(f"{spec.name}: {a.kind} input {a.casadi_input!r} must be scalar, has {n}")
    if a.kind not in ("vector", "configuration", "solution", "index"):
        raise CodegenError(f"{spec.name}: unknown argument kind {a.kind!r}")


def _renamed(f: ca.Function, cname: str) -> ca.Function:
    """``f`` as an SX Function named ``cname`` with dense outputs and common subexpressions merged.

    ``ca.cse`` only merges structurally identical subexpressions: every output is computed
    by the same operations on the same operands, so the values are bit-identical to the
    ones of ``f`` (fewer instructions, shorter source, faster compilation). A Function with
    MX-only operations (e.g. a table lookup by a parametric index, as the ILC correction)
    cannot be expanded: it is kept as an MX Function, renamed, with dense outputs.
    """
    if not f.is_a("SXFunction"):
        try:
            f = f.expand()
        except RuntimeError:
            ins = f.mx_in()
            return ca.Function(cname, ins, [ca.densify(o) for o in f.call(ins)], f.name_in(), f.name_out())
    ins = f.sx_in()
    outs = ca.cse([ca.densify(o) for o in f.call(ins)])
    return ca.Function(cname, ins, outs, f.name_in(), f.name_out())


def _prepare(spec: FunctionSpec, f: ca.Function, cname: str) -> ca.Function:
    """Validate ``f`` against ``spec`` and return it renamed to ``cname`` with dense outputs."""
    if not isinstance(f, ca.Function):
        raise CodegenError(f"{spec.name}: build() returned {type(f).__name__}, expected casadi.Function")
    names_in, names_out = f.name_in(), f.name_out()
    for a in spec.args:
        if a.casadi_input not in names_in:
            raise CodegenError(f"{spec.name}: CasADi Function has no input {a.casadi_input!r} (inputs: {names_in})")
        _check_arg_input(spec, f, a, "")
    fed = {a.casadi_input for a in spec.args}
    missing = [n for n in names_in if n not in fed]
    if missing:
        raise CodegenError(f"{spec.name}: CasADi inputs {missing} are not fed by any C argument")
    for name in [o.casadi_output for o in spec.outputs] + [c.casadi_output for c in spec.checks]:
        if name not in names_out:
            raise CodegenError(f"{spec.name}: CasADi Function has no output {name!r} (outputs: {names_out})")
    return _renamed(f, cname)


def _prepare_part(spec: FunctionSpec, part: str, f: ca.Function, cname: str, size: int, outputs: Sequence[str]) -> ca.Function:
    """Validate one Function of a Newton loop (inputs ``x`` and public ones) and rename it."""
    if not isinstance(f, ca.Function):
        raise CodegenError(f"{spec.name}: newton.{part} returned {type(f).__name__}, expected casadi.Function")
    by_input = {a.casadi_input: a for a in spec.args}
    for name in f.name_in():
        if name == "x":
            if f.numel_in("x") != size:
                raise CodegenError(f"{spec.name}: newton.{part} input 'x' must have {size} elements")
        elif name in by_input:
            _check_arg_input(spec, f, by_input[name], f"newton.{part}")
        else:
            raise CodegenError(f"{spec.name}: newton.{part} input {name!r} is not 'x' nor fed by any C argument")
    for name in outputs:
        if name not in f.name_out():
            raise CodegenError(f"{spec.name}: newton.{part} has no output {name!r} (outputs: {f.name_out()})")
    return _renamed(f, cname)


def _hoist_invariants(parts: dict[str, ca.Function], cname: str) -> dict[str, ca.Function]:
    """Move what a Newton step computes from the fixed inputs alone out of the loop.

    ``casadi.extract_parametric`` replaces every subexpression of the step that depends
    only on the public inputs (e.g. the F1 cart-side joint points, with the sines and
    cosines of the actuator angles, in the forward kinematics) by a new input ``pre``;
    the Function ``invariant(public inputs) -> pre`` computes them once before the loop.
    Same operations on the same operands: bit-identical iterates.
    """
    step = parts["step"]
    names, ins = step.name_in(), step.sx_in()
    public = [v for n, v in zip(names, ins) if n != "x"]
    outs = step.call(ins)
    expr, symbols, values = ca.extract_parametric(ca.vertcat(*[ca.vec(o) for o in outs]), ca.vertcat(*[ca.vec(v) for v in public]))
    if not symbols:
        return parts
    split, k = [], 0
    for o in outs:
        split.append(ca.reshape(expr[k : k + o.numel()], o.size1(), o.size2()))
        k += o.numel()
    pre = ca.vertcat(*symbols)
    public_names = [n for n in names if n != "x"]
    return dict(
        parts,
        step=ca.Function(step.name(), [*ins, pre], split, [*names, "pre"], step.name_out()),
        invariant=ca.Function(cname, public, [ca.vertcat(*values)], public_names, ["pre"]),
    )


def _residual_part(step: ca.Function, cname: str) -> ca.Function:
    """The residual (and ``valid``) outputs of a Newton step Function alone.

    Used at the convergence tests of a loop that tests every ``k > 1`` steps: the test
    needs the residual of ``x_k`` but not the step from it. The graph is the step's,
    pruned to what these outputs depend on (same operations, bit-identical values).
    """
    keep = [n for n in ("residual", "valid") if n in step.name_out()]
    ins = step.sx_in()
    outs = step.call(dict(zip(step.name_in(), ins)))
    return ca.Function(cname, ins, [outs[n] for n in keep], step.name_in(), keep)


# ----------------------------------------------------------------------------- API
def write_library(
    prefix: str,
    specs: Sequence[FunctionSpec],
    source: Any,
    out_dir: str | Path,
    real: str,
    header: Any,
    extra_source: str = "",
) -> tuple[Path, dict[str, ca.Function], dict[str, tuple[int, int, int, int]], dict[str, tuple]]:
    """Write CasADi's C of some declared functions, their plain-C wrappers and a header.

    The one writer of the libraries that are not a robot's (a user model's,
    :mod:`gtmodel.codegen.model_code`; a loop step's, :mod:`gtmodel.codegen.loop_step`):
    ``<prefix>_casadi.c/.h`` (CasADi's code generator, unused parameters marked, helpers
    static), ``<prefix>.c`` (the wrappers with argument checks and status codes, then
    ``extra_source``) and ``<prefix>.h`` (``header(fragment)``: the text around the
    prototypes).

    Parameters
    ----------
    prefix : str
        C symbol prefix.
    specs : sequence of FunctionSpec
        The functions; ``spec.build(source)`` gives each CasADi Function.
    source : object
        Passed to ``spec.build``.
    out_dir : str or pathlib.Path
        Folder (created if missing).
    real : {"double", "float"}
        Floating-point type.
    header : callable
        ``header(fragment) -> str``, the header text (``fragment.header`` the prototypes).
    extra_source : str, optional
        C appended to ``<prefix>.c`` (e.g. the memory functions of a loop step).

    Returns
    -------
    out : pathlib.Path
        The folder.
    funcs : dict of str to casadi.Function
        The prepared Functions by spec name.
    sizes : dict
        Work sizes by spec name.
    signatures : dict
        ``(argument sizes, output sizes)`` by spec name.

    Raises
    ------
    CodegenError
        CasADi's code generation or writing the files failed.
    """
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
    try:
        casadi_source.write_text("/* CasADi-generated code; gtmodel marked unused function parameters (void) and the\n"
                                 " * scalar helpers static. */\n" + _static_helpers(_void_unused_parameters(text)))
        wrapped = functions_fragment(prefix, specs, funcs, cnames, sizes, real)
        (out / f"{prefix}.h").write_text(header(wrapped))
        (out / f"{prefix}.c").write_text(wrapper_text(prefix, wrapped, sizes) + extra_source)
    except OSError as exc:
        raise CodegenError(f"cannot write generated code to {out}: {exc.strerror}") from None
    signatures = {
        s.name: (tuple(_arg_size(s, funcs, a) for a in s.args), tuple(_out_function(s, funcs).numel_out(o.casadi_output) for o in s.outputs))
        for s in specs
    }
    return out, funcs, sizes, signatures
