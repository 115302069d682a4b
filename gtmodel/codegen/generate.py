"""The robot's writer: C for a robot's model functions, CasADi-generated code plus plain-C wrappers.

The generic library writer (:func:`~gtmodel.codegen.writer.write_library`,
:class:`~gtmodel.codegen.writer.GeneratedCode`, the Functions' preparation) is
:mod:`gtmodel.codegen.writer`, the generic emitter :mod:`gtmodel.codegen.emit.wrapper`; both
names are re-exported here (their former home).

For a robot (a 3-link parameter set such as ``"L1"`` or a calibration's
``parameters.toml``, the six-link model ``"D1_six_link"``, or ``"F1"``) :func:`generate`
writes, into ``out_dir``:

``<prefix>_casadi.c`` / ``<prefix>_casadi.h``
    The CasADi Functions of the model (kinematics, dynamics, Newton steps), emitted by
    :class:`casadi.CodeGenerator`: the maths, with the parameters embedded as constants.
    Unused parameters of CasADi's function signatures are marked ``(void)`` so that the
    file compiles with ``-Wall -Wextra -Werror``; its scalar helpers are made ``static``
    (inlined). Every Function passes through ``casadi.cse`` (common subexpressions merged)
    and, in a Newton loop, the subexpressions of the fixed inputs are computed once before
    the loop (``casadi.extract_parametric``); neither changes a single value.
``<prefix>.c`` / ``<prefix>.h``
    The public API: one plain-C function per model function with fixed-size array
    arguments, an ``int`` status return (``GT_OK`` = 0) and no dynamic memory. The work
    arrays are on the stack, sized at generation time from the generated ``*_work``
    functions (the header states the largest). On any non-OK status the outputs are left
    untouched: no NaN is ever written. Functions solved by Newton's method run a loop of
    at most ``<PREFIX>_<NAME>_MAX_ITER + 1`` step evaluations with an early exit on
    convergence and return ``GT_NOT_CONVERGED`` otherwise; a loop that tests convergence
    every ``k > 1`` steps evaluates only the residual at the tests.

With ``retime_n_max`` the wrapper source also holds ``<prefix>_retime``, the online
re-timing along a path (:mod:`gtmodel.codegen.retime`): hand-written two passes around the
CasADi-generated row coefficients ``<prefix>_cg_retime_rows``, its work memory a
caller-owned struct sized at generation.

The C functions are reentrant (no static or global mutable state) and thus thread-safe.
``real="float"`` generates single-precision code (``float`` arrays in the API).
"""

from __future__ import annotations

import dataclasses
import logging
from pathlib import Path
from typing import Any, Iterable, Sequence

import casadi as ca
import numpy as np

import gtmodel
from gtmodel._escape import casadi_name, check_c_identifier
from gtmodel.errors import CodegenError, InputError
from gtmodel.codegen.controller import Controller
from gtmodel.codegen.declarations import CONTROLLER_KIND, FunctionSpec
from gtmodel.codegen.emit import Fragment
from gtmodel.codegen.emit.casadi_source import _static_helpers, _void_unused_parameters, _work_sizes
from gtmodel.codegen.emit.controller import controller_fragment
from gtmodel.codegen.emit.retime import check_retime_n_max, retime_fragment, retime_rows_function
from gtmodel.codegen.emit.robot import header_text
from gtmodel.codegen.emit.wrapper import _arg_size, _check_every, _out_function, functions_fragment, wrapper_text
from gtmodel.codegen.writer import REAL_TYPES, GeneratedCode, write_library
from gtmodel.codegen.writer import _hoist_invariants, _prepare, _prepare_part, _residual_part
from gtmodel.codegen.robot import RobotModel, load_robot
from gtmodel.codegen.out_dir import check_out_dir
from gtmodel.codegen.specs import SPECS_BY_KIND, default_functions
from gtmodel.robots.friction import DEFAULT_FRICTION_WIDTH, check_friction_form

__all__ = ["GeneratedCode", "generate", "REAL_TYPES", "controller_part", "robot_part", "write_library", "check_out_dir"]

log = logging.getLogger("gtmodel")


def _resolve_specs(functions: Iterable[str | FunctionSpec], kind: str) -> tuple[FunctionSpec, ...]:
    table = SPECS_BY_KIND[kind]
    if isinstance(functions, (str, FunctionSpec)):
        functions = (functions,)
    specs = []
    for f in functions:
        if isinstance(f, FunctionSpec):
            specs.append(f)
        elif isinstance(f, str) and f in table:
            specs.append(table[f])
        else:
            raise InputError(f"functions: unknown function {f!r} for a {kind} robot (available: {', '.join(table)})")
    if not specs:
        raise InputError("functions: expected at least one function")
    names = [s.name for s in specs]
    if len(set(names)) != len(names):
        raise InputError(f"functions: duplicate names in {names}")
    for s in specs:
        check_c_identifier(s.name, "functions", "ik")
        if s.kind != kind:
            raise InputError(f"functions: {s.name!r} is declared for a {s.kind} robot, not a {kind} robot")
    return tuple(specs)


def generate(
    robot: Any = "L1",
    out_dir: str | Path = "codegen_out",
    functions: Sequence[str | FunctionSpec] | None = None,
    prefix: str | None = None,
    friction: str = "exact",
    real: str = "double",
    newton_tolerance: float | None = None,
    max_iter: int | None = None,
    newton_check_every: int | None = None,
    controller: Controller | None = None,
    retime_n_max: int | None = None,
) -> GeneratedCode:
    """Generate C source and a public header for the model functions of a robot.

    Parameters
    ----------
    robot : str or pathlib.Path or RobotParameters or SixLinkClosure or F1Closure, optional
        The robot: a 3-link parameter set (shipped name ``"L1"``, ``"D1"``, ``"L1_ideal"``
        or a TOML path, e.g. a calibration's ``parameters.toml``), the six-link error model
        (``"D1_six_link"``) or the F1 (``"F1"``); see
        :func:`gtmodel.codegen.robot.load_robot`. Its values are embedded as constants.
    out_dir : str or pathlib.Path, optional
        Folder to write into (created if missing; existing files of the same names are
        overwritten).
    functions : sequence of str or FunctionSpec, optional
        Functions to generate: names from the robot kind's table in
        :data:`gtmodel.codegen.specs.SPECS_BY_KIND` or declarations; default all of
        :func:`gtmodel.codegen.specs.default_functions` (3-link: ``ik``, ``fk``,
        ``jacobian``, ``jacobian_inverse``, ``acceleration``, ``inverse_dynamics``,
        ``gravity``; six-link: ``fk``, ``ik``; F1: ``ik``, ``fk``). Empty with a
        ``controller``: the controller functions alone (the robot then only names the
        default prefix; the header names no robot and the version carries the controller's
        :meth:`~gtmodel.codegen.controller.Controller.content_hash`), e.g. the KF/EKF steps of the fusion.
    prefix : str or None, optional
        C symbol prefix; default ``"gt_<robot name>"``, e.g. ``gt_L1`` (giving
        ``gt_L1_ik``, header ``gt_L1.h``).
    friction : str, optional
        Friction form of the dynamics (eq. 6.8): ``"exact"`` sign (default), ``"tanh"``
        (smooth) or ``"piecewise"``.
    real : {"double", "float"}, optional
        Floating-point type of the generated code and its API.
    newton_tolerance : float or None, optional
        Convergence tolerance of every Newton loop (unit of its residual, see the header);
        default the declaration's (the Python model's tolerance in double precision, a
        looser one in single precision).
    max_iter : int or None, optional
        Iteration limit of every Newton loop; default the declaration's (20).
    newton_check_every : int or None, optional
        Test convergence every this many Newton steps; default the declaration's (F1: 4,
        the block size of the Python model, for identical results; 1 exits earliest).
    controller : Controller or None, optional
        Controller functions of the 4 ms loop to add to the library
        (:class:`~gtmodel.codegen.controller.Controller`: the stationary Kalman step
        ``<prefix>_kalman_step`` with its state struct, ``<prefix>_kalman_init`` and
        ``<prefix>_kalman_update``, and the ILC correction lookup
        ``<prefix>_ilc_correction``; the KF/EKF steps of the tracker + IMU fusion
        ``<prefix>_kf_step``/``<prefix>_ekf_step`` with ``<prefix>_kf_state`` ... of
        :mod:`~gtmodel.codegen.specs.filter`), e.g. from
        :func:`~gtmodel.codegen.controller_file.load_controller`; checked by
        :func:`~gtmodel.codegen.check.controller.check_controller`.
    retime_n_max : int or None, optional
        Also generate the online re-timing function ``<prefix>_retime`` (3-link sets,
        double precision; :mod:`gtmodel.codegen.retime`): the time-optimal ``s_dot(s)``
        along a sampled path by the two-pass reachability of the Python path solver, for
        at most this many grid points (``<PREFIX>_RETIME_N_MAX``, the size of the
        caller's work struct). None (default): not generated.

    Returns
    -------
    GeneratedCode
        Paths of the written ``.c``/``.h`` files, the prefix and the functions.

    Raises
    ------
    InputError
        Unknown function name, invalid prefix, friction form, real type, tolerance or
        iteration limit; ``controller`` not a Controller; ``retime_n_max`` out of range
        or given for a robot that is not a 3-link set or in single precision.
    ParameterError
        Unknown or invalid robot / parameter set.
    CodegenError
        A CasADi Function does not match its declaration, or writing the files failed.
    """
    model = RobotModel(load_robot(robot), friction)
    if prefix is None:
        prefix = "gt_" + casadi_name(model.name)
    check_c_identifier(prefix, "prefix", "gt_L1")

    check_friction_form(friction, DEFAULT_FRICTION_WIDTH)
    if real not in REAL_TYPES:
        raise InputError(f"real: expected 'double' or 'float', got {real!r}")
    if newton_tolerance is not None and not (
        isinstance(newton_tolerance, (int, float)) and not isinstance(newton_tolerance, bool)
        and np.isfinite(newton_tolerance) and newton_tolerance > 0
    ):
        raise InputError(f"newton_tolerance: expected a positive number, got {newton_tolerance!r}")
    if max_iter is not None and (isinstance(max_iter, bool) or not isinstance(max_iter, (int, np.integer)) or not 1 <= max_iter <= 1000):
        raise InputError(f"max_iter: expected an integer from 1 to 1000, got {max_iter!r}")
    if newton_check_every is not None and (
        isinstance(newton_check_every, bool) or not isinstance(newton_check_every, (int, np.integer)) or not 1 <= newton_check_every <= 100
    ):
        raise InputError(f"newton_check_every: expected an integer from 1 to 100, got {newton_check_every!r}")
    if retime_n_max is not None:
        retime_n_max = check_retime_n_max(retime_n_max, model, real)
    only_controller = controller is not None and functions is not None and not isinstance(functions, (str, FunctionSpec)) and len(functions) == 0
    specs = () if only_controller else _resolve_specs(default_functions(model.kind) if functions is None else functions, model.kind)
    if controller is not None:
        if not isinstance(controller, Controller):
            raise InputError(f"controller: expected a gtmodel.codegen.Controller, got {type(controller).__name__}")
        clash = [s.name for s in specs if s.name in controller.functions]
        if clash:
            raise InputError(f"functions: {clash} clash with the controller's functions")
        specs = specs + controller.specs()  # the controller fragment's specs
    out = Path(out_dir)
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise CodegenError(f"cannot create output folder {out}: {exc.strerror}") from None

    funcs: dict[str, Any] = {}
    cnames: dict[str, Any] = {}
    newton: dict[str, tuple[float, int]] = {}
    cg = ca.CodeGenerator(
        f"{prefix}_casadi.c", {"with_header": True, "prefix": f"{prefix}_cg_", "casadi_real": real}
    )
    for spec in specs:
        base = f"{prefix}_cg_{spec.name}"
        if spec.newton is None:
            if spec.build is None:
                raise CodegenError(f"{spec.name}: a declaration needs build or newton")
            f = _prepare(spec, spec.build(model), base)
            funcs[spec.name] = f
            cnames[spec.name] = base
            cg.add(f)
            continue
        nl = spec.newton
        parts = {
            "start": _prepare_part(spec, "start", nl.start(model), f"{base}_start", nl.size, ["x0"] + [c.casadi_output for c in nl.start_checks]),
            "step": _prepare_part(spec, "step", nl.step(model), f"{base}_step", nl.size, ["x_next", "residual"]),
            "finish": _prepare_part(
                spec, "finish", nl.finish(model), f"{base}_finish", nl.size,
                [o.casadi_output for o in spec.outputs] + [c.casadi_output for c in spec.checks],
            ),
        }
        if nl.warm:
            if nl.warm_start is None:
                raise CodegenError(f"{spec.name}: newton.warm is set but warm_start is None")
            parts["warm"] = _prepare_part(spec, "warm", nl.warm_start(model), f"{base}_warm", nl.size, ["x0"])
        parts = _hoist_invariants(parts, f"{base}_invariant")
        if _check_every(nl, newton_check_every) > 1:
            parts["residual"] = _residual_part(parts["step"], f"{base}_residual")
        fed = {"x"} | {a.casadi_input for a in spec.args}
        used = {n for f in parts.values() for n in f.name_in()}
        unused = [a.name for a in spec.args if a.casadi_input not in used]
        if unused:
            raise CodegenError(f"{spec.name}: C arguments {unused} feed no Function of the Newton loop")
        del fed
        funcs[spec.name] = parts
        cnames[spec.name] = {k: f"{base}_{k}" for k in parts}
        for f in parts.values():
            cg.add(f)
        tol = newton_tolerance if newton_tolerance is not None else (nl.tolerance if real == "double" else nl.float_tolerance)
        newton[spec.name] = (float(tol), int(max_iter if max_iter is not None else nl.max_iter))
    retime_f = None
    if retime_n_max is not None:
        if only_controller:
            raise InputError("retime_n_max: the re-timing function needs the robot's functions (functions is empty)")
        retime_f = retime_rows_function(model, f"{prefix}_cg_retime_rows")
        cg.add(retime_f)
    try:
        cg.generate(str(out) + "/")
    except RuntimeError as exc:
        raise CodegenError(f"CasADi code generation failed: {exc}") from None
    casadi_source = out / f"{prefix}_casadi.c"
    casadi_text = casadi_source.read_text()
    sizes: dict[str, tuple[int, int, int, int]] = {}
    for spec in specs:
        if spec.newton is None:
            sizes[spec.name] = _work_sizes(casadi_text, cnames[spec.name], funcs[spec.name])
        else:
            each = [_work_sizes(casadi_text, cnames[spec.name][k], f) for k, f in funcs[spec.name].items()]
            sizes[spec.name] = tuple(max(s[i] for s in each) for i in range(4))  # type: ignore[assignment]
    retime_sizes = _work_sizes(casadi_text, f"{prefix}_cg_retime_rows", retime_f) if retime_f is not None else None
    casadi_source.write_text(
        "/* CasADi-generated code; gtmodel marked unused function parameters (void) and the\n"
        " * scalar helpers (casadi_sq, casadi_fmax, ...) static, so that they are inlined. */\n"
        + _static_helpers(_void_unused_parameters(casadi_text))
    )

    if only_controller:  # no robot function: the controller's own hash, no robot in the version
        phash = controller.content_hash()
        version = f"gtmodel {gtmodel.__version__}; casadi {ca.__version__}; controller sha256:{phash}; real {real}"
    else:
        phash = model.parameter_hash()
        version = (
            f"gtmodel {gtmodel.__version__}; casadi {ca.__version__}; "
            f"parameters {model.name} sha256:{phash}; friction {friction}; real {real}"
        )
    header = out / f"{prefix}.h"
    source = out / f"{prefix}.c"
    wrapped = functions_fragment(prefix, specs, funcs, cnames, sizes, real, newton_check_every)  # the robot's and controller's functions
    extra = Fragment.join([
        *([controller_fragment(prefix, controller, real)] if controller else ()),
        *([retime_fragment(prefix, model, retime_n_max, retime_sizes)] if retime_f is not None else ()),
    ])
    try:
        header.write_text(header_text(prefix, wrapped, version, phash, model, friction, real, newton, extra.header))
        source.write_text(wrapper_text(prefix, wrapped, sizes, extra.source))
    except OSError as exc:
        raise CodegenError(f"cannot write generated code to {out}: {exc.strerror}") from None
    log.info("codegen: wrote %s (%s) for %s", source, ", ".join(s.name for s in specs), model.name)
    signatures = {}
    for s in specs:
        fo = _out_function(s, funcs)
        signatures[s.name] = (
            tuple(_arg_size(s, funcs, a) for a in s.args),
            tuple(fo.numel_out(o.casadi_output) for o in s.outputs),
        )
    return GeneratedCode(
        out_dir=out,
        prefix=prefix,
        functions=tuple(s.name for s in specs),
        source=source,
        header=header,
        casadi_source=casadi_source,
        casadi_header=out / f"{prefix}_casadi.h",
        parameters=model.robot,
        friction=friction,
        parameter_hash=phash,
        version=version,
        specs=specs,
        work_sizes=sizes,
        signatures=signatures,
        real=real,
        kind=model.kind,
        newton=newton,
        controller=controller,
        retime_n_max=retime_n_max or 0,
    )


def controller_part(generated: GeneratedCode) -> GeneratedCode:
    """The generated code restricted to its controller functions.

    Parameters
    ----------
    generated : GeneratedCode
        A library generated with ``controller=``.

    Returns
    -------
    GeneratedCode
        The same files, ``specs`` and ``functions`` only those of kind
        :data:`~gtmodel.codegen.declarations.CONTROLLER_KIND`.
    """
    specs = tuple(s for s in generated.specs if s.kind == CONTROLLER_KIND)
    return dataclasses.replace(generated, specs=specs, functions=tuple(s.name for s in specs))


def robot_part(generated: GeneratedCode) -> GeneratedCode:
    """The generated code restricted to its robot-model functions (what :func:`~gtmodel.codegen.check.check` checks).

    Parameters
    ----------
    generated : GeneratedCode
        Any generated library.

    Returns
    -------
    GeneratedCode
        The same files, ``specs`` and ``functions`` without the controller functions.
    """
    specs = tuple(s for s in generated.specs if s.kind != CONTROLLER_KIND)
    if len(specs) == len(generated.specs):
        return generated
    return dataclasses.replace(generated, specs=specs, functions=tuple(s.name for s in specs))


