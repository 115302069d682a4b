"""Self-check of generated C: compiled functions against the Python evaluation.

:func:`check` compiles the generated code (unless given a loaded library), evaluates
every generated C function through ctypes on ``n`` random reachable poses and compares
the outputs with the Python evaluation of the same model (the NumPy wrappers
``GantryTau3Kinematics.ik/fk/jacobian`` and ``GantryTau3Dynamics.inverse_dynamics``, or
the CasADi Function itself for functions without such a wrapper). It also probes the
status codes: an unreachable pose, a singular pose, non-finite inputs and invalid
configurations must give a non-zero status and leave the outputs untouched.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, field
from pathlib import Path
from typing import Mapping

import casadi as ca
import numpy as np

from gtmodel.codegen.build import CompiledLibrary, compile_shared, load_library
from gtmodel.codegen.generate import GeneratedCode
from gtmodel.codegen.specs import (
    FK_TOLERANCE,
    IK_TOLERANCE,
    INVERSE_DYNAMICS_TOLERANCE,
    JACOBIAN_TOLERANCE,
    STATUS_CODES,
    FunctionSpec,
    RobotModel,
)
from gtmodel.errors import CodegenError, SingularConfigurationError
from gtmodel.robots.kinematics import SINGULARITY_TOLERANCE, configuration_signs

__all__ = [
    "IK_TOLERANCE",
    "FK_TOLERANCE",
    "JACOBIAN_TOLERANCE",
    "INVERSE_DYNAMICS_TOLERANCE",
    "SENTINEL",
    "FunctionCheck",
    "StatusProbe",
    "CheckReport",
    "sample_inputs",
    "check",
]

log = logging.getLogger("gtmodel")

#: Value pre-filled into output buffers to detect writes on a non-OK status.
SENTINEL = 1234.5678
#: Range of the random TCP velocities [m/s] (each component uniform in +-).
VELOCITY_RANGE = 1.0
#: Range of the random TCP accelerations [m/s^2] (each component uniform in +-).
ACCELERATION_RANGE = 5.0

_STATUS_NAMES = {v[0]: k for k, v in STATUS_CODES.items()}


@dataclass(frozen=True)
class FunctionCheck:
    """Comparison of one C function with the Python evaluation.

    Parameters
    ----------
    name : str
        Function name.
    n : int
        Number of samples compared.
    max_abs_diff : float
        Largest ``|C - Python|`` over all samples and output elements (unit ``unit``).
    tolerance : float
        Largest accepted difference.
    unit : str
        Unit of the outputs (``""`` if dimensionless).
    n_not_ok : int
        Samples (all valid) on which the C function returned a non-OK status.
    passed : bool
        ``max_abs_diff <= tolerance`` and ``n_not_ok == 0``.
    """

    name: str
    n: int
    max_abs_diff: float
    tolerance: float
    unit: str
    n_not_ok: int
    passed: bool


@dataclass(frozen=True)
class StatusProbe:
    """One status-code probe: an invalid input must give a given non-zero status.

    Parameters
    ----------
    function : str
        Function probed.
    case : str
        What was fed, e.g. ``"unreachable pose"``.
    expected : str
        Expected status macro, e.g. ``"GT_UNREACHABLE"``.
    status : int
        Returned status.
    untouched : bool
        The output buffers kept their pre-filled values.
    passed : bool
        ``status`` is the expected one and the outputs are untouched.
    """

    function: str
    case: str
    expected: str
    status: int
    untouched: bool
    passed: bool


@dataclass(frozen=True)
class CheckReport:
    """Result of :func:`check`.

    Parameters
    ----------
    robot : str
        Parameter-set name.
    prefix : str
        C prefix of the library.
    n : int
        Number of random reachable poses.
    seed : int
        Seed of the random generator.
    functions : tuple of FunctionCheck
        One comparison per generated function.
    probes : tuple of StatusProbe
        Status-code probes.
    version : str
        Version string reported by the compiled library.
    library : pathlib.Path
        The shared library checked.
    """

    robot: str
    prefix: str
    n: int
    seed: int
    functions: tuple[FunctionCheck, ...]
    probes: tuple[StatusProbe, ...]
    version: str = ""
    library: Path | None = field(default=None, compare=False)

    @property
    def passed(self) -> bool:
        """True if every comparison and every status probe passed."""
        return all(f.passed for f in self.functions) and all(p.passed for p in self.probes)

    def summary_lines(self) -> list[str]:
        """Printable lines: one per function, then the status probes and the verdict.

        Returns
        -------
        list of str
            E.g. ``"ik: max |C - Python| = 2.2e-16 m (tol 1e-12) OK"``.
        """
        lines = [f"check of {self.prefix} ({self.robot}) on {self.n} random reachable poses (seed {self.seed}):"]
        for f in self.functions:
            unit = f" {f.unit}" if f.unit else ""
            verdict = "OK" if f.passed else "FAILED"
            extra = f", {f.n_not_ok} valid poses gave a non-OK status" if f.n_not_ok else ""
            lines.append(f"{f.name}: max |C - Python| = {f.max_abs_diff:.1e}{unit} (tol {f.tolerance:g}){extra} {verdict}")
        ok = sum(p.passed for p in self.probes)
        lines.append(f"status codes: {ok}/{len(self.probes)} probes OK (non-zero status, outputs untouched)")
        for p in self.probes:
            if not p.passed:
                got = _STATUS_NAMES.get(p.status, str(p.status))
                touched = "" if p.untouched else ", outputs WRITTEN"
                lines.append(f"  FAILED {p.function} on {p.case}: expected {p.expected}, got {got}{touched}")
        lines.append("PASSED" if self.passed else "FAILED")
        return lines


# ----------------------------------------------------------------------------- sampling
def _reachable_poses(model: RobotModel, n: int, rng: np.random.Generator) -> np.ndarray:
    k = model.kinematics
    box = k.workspace_bounds()
    out: list[np.ndarray] = []
    got = 0
    for _ in range(1000):
        X = rng.uniform(box[:, 0], box[:, 1], size=(max(4 * n, 1000), 3))
        X = X[k.in_workspace(X)]
        out.append(X)
        got += len(X)
        if got >= n:
            break
    else:
        raise CodegenError(f"check: could not sample {n} reachable poses of {model.parameters.name}")
    return np.concatenate(out)[:n]


def sample_inputs(generated: GeneratedCode, n: int = 1000, seed: int = 0, model: RobotModel | None = None) -> dict[str, np.ndarray]:
    """Random valid inputs for the generated functions, keyed by C argument name.

    Parameters
    ----------
    generated : GeneratedCode
        What was generated.
    n : int, optional
        Number of samples.
    seed : int, optional
        Seed of :func:`numpy.random.default_rng`.
    model : RobotModel or None, optional
        The model (built from ``generated`` if None).

    Returns
    -------
    dict of str to numpy.ndarray
        ``T`` (n, 3) [m] uniform in the workspace (inside the bounding box and
        ``in_workspace``, configuration 0); ``T_dot`` (n, 3) [m/s] and ``T_ddot`` (n, 3)
        [m/s^2] uniform in ``+-VELOCITY_RANGE``/``+-ACCELERATION_RANGE``; ``q`` (n, 3) [m]
        the IK of ``T``; ``solution`` (n,) of +-1; ``configuration:<function>`` (n,) drawn
        from the function's ``check_configurations``; any other array argument uniform
        in [-1, 1].
    """
    model = model or RobotModel(generated.parameters, generated.friction)
    rng = np.random.default_rng(seed)
    T = _reachable_poses(model, n, rng)
    data = {
        "T": T,
        "T_dot": rng.uniform(-VELOCITY_RANGE, VELOCITY_RANGE, (n, 3)),
        "T_ddot": rng.uniform(-ACCELERATION_RANGE, ACCELERATION_RANGE, (n, 3)),
        "q": np.reshape(model.kinematics.ik(T, 0), (n, 3)),
        "solution": rng.choice([1, -1], n),
    }
    for spec in generated.specs:
        sizes_in, _ = generated.signatures[spec.name]
        data[f"configuration:{spec.name}"] = rng.choice(np.array(spec.check_configurations), n)
        for a, size in zip(spec.args, sizes_in):
            if a.kind == "vector" and a.name not in data:
                data[a.name] = rng.uniform(-1.0, 1.0, (n, size))
    return data


def _function_inputs(spec: FunctionSpec, data: Mapping[str, np.ndarray]) -> dict[str, np.ndarray]:
    out = {}
    for a in spec.args:
        out[a.name] = data[f"configuration:{spec.name}"] if a.kind == "configuration" else data[a.name]
    out.setdefault("configuration", data[f"configuration:{spec.name}"])
    return out


def _casadi_reference(spec: FunctionSpec, model: RobotModel, inputs: Mapping[str, np.ndarray]) -> dict[str, np.ndarray]:
    """Evaluate the spec's CasADi Function from Python; outputs flattened row-major."""
    f = spec.build(model)
    n = len(next(iter(inputs.values())))
    cols: dict[str, np.ndarray] = {}
    for a in spec.args:
        v = np.asarray(inputs[a.name])
        if a.kind == "configuration":
            cols[a.casadi_input] = np.array([configuration_signs(int(c)) for c in v]).T
        elif a.kind == "solution":
            cols[a.casadi_input] = v.astype(float)[None, :]
        else:
            cols[a.casadi_input] = v.reshape(n, -1).T
    res = f.map(n)(**cols)
    out = {}
    for o in spec.outputs:
        sp = f.sparsity_out(o.casadi_output)
        nr, nc = sp.size1(), sp.size2()
        val = np.asarray(ca.DM(res[o.casadi_output]))  # (nr, nc * n)
        out[o.name] = val.reshape(nr, n, nc, order="F").transpose(1, 0, 2).reshape(n, nr * nc)
    return out


def _call_row(cf, spec: FunctionSpec, inputs: Mapping[str, np.ndarray], i: int, overrides: Mapping | None = None):
    args = []
    for a in spec.args:
        v = overrides[a.name] if overrides and a.name in overrides else inputs[a.name][i]
        args.append(v)
    out = [np.full(n, SENTINEL) for n in cf.sizes_out]
    status, out = cf(*args, out=out)
    return status, out


def _compare(spec: FunctionSpec, cf, model: RobotModel, inputs: Mapping[str, np.ndarray]) -> FunctionCheck:
    n = len(inputs[spec.args[0].name])
    ref = spec.reference(model, inputs) if spec.reference is not None else _casadi_reference(spec, model, inputs)
    worst = 0.0
    not_ok = 0
    for i in range(n):
        status, out = _call_row(cf, spec, inputs, i)
        if status != 0:
            not_ok += 1
            continue
        for o, val in zip(spec.outputs, out):
            d = float(np.max(np.abs(val - np.reshape(ref[o.name][i], -1))))
            if not d <= worst:  # NaN propagates as failure
                worst = d if np.isfinite(d) else np.inf
    passed = bool(worst <= spec.tolerance and not_ok == 0)
    return FunctionCheck(spec.name, n, worst, spec.tolerance, spec.unit, not_ok, passed)


def _probe(cf, spec: FunctionSpec, inputs, case: str, expected: str, overrides: Mapping) -> StatusProbe:
    status, out = _call_row(cf, spec, inputs, 0, overrides)
    untouched = all(np.all(o == SENTINEL) for o in out)
    passed = bool(status == STATUS_CODES[expected][0] and untouched)
    return StatusProbe(spec.name, case, expected, status, bool(untouched), passed)


def _singular_pose(model: RobotModel, poses: np.ndarray) -> np.ndarray | None:
    """A reachable TCP position (configuration 0) where link 1 is perpendicular to its guideway.

    Moves a workspace pose perpendicular to guideway 1 until arm 1 is stretched to
    ``(1 - 1e-13) L_1`` from the guideway line, keeping arms 2 and 3 clearly reachable;
    the Python model must judge it singular.
    """
    k = model.kinematics
    vh = k.v[0] / np.linalg.norm(k.v[0])
    for T0 in poses[:200]:
        d = T0 - k.As[0]
        p = d - (d @ vh) * vh
        T = k.As[0] + (d @ vh) * vh + k.L[0] * (1 - 1e-13) * p / np.linalg.norm(p)
        _, _, _, disc, cos_min = k.jacobian_function(T, configuration_signs(0))
        disc = np.asarray(disc).ravel()
        if disc[0] >= 0 and np.all(disc[1:] > 1e-6) and float(cos_min) < SINGULARITY_TOLERANCE:
            try:
                k.jacobian(T, 0)
            except SingularConfigurationError:
                return T
    return None


def check(
    generated: GeneratedCode,
    n: int = 1000,
    seed: int = 0,
    library: CompiledLibrary | None = None,
    build_dir: str | Path | None = None,
) -> CheckReport:
    """Compile the generated C and compare it with the Python evaluation of the model.

    Parameters
    ----------
    generated : GeneratedCode
        Result of :func:`gtmodel.codegen.generate`.
    n : int, optional
        Number of random reachable poses (default 1000); see :func:`sample_inputs`.
    seed : int, optional
        Seed of the random generator (default 0).
    library : CompiledLibrary or None, optional
        An already loaded library; compiled with :func:`compile_shared` if None.
    build_dir : str or pathlib.Path or None, optional
        Build folder when compiling (default ``<out_dir>/build``).

    Returns
    -------
    CheckReport
        Per function the largest ``|C - Python|`` against its tolerance (``IK_TOLERANCE``,
        ``FK_TOLERANCE`` = 1e-12 m, ``JACOBIAN_TOLERANCE`` = 1e-12,
        ``INVERSE_DYNAMICS_TOLERANCE`` = 1e-9 N), and the status probes. A failed check is
        a report with ``passed == False``, not an exception.

    Raises
    ------
    InputError
        ``n`` is not a positive integer.
    CompilerNotFoundError
        No C compiler.
    CodegenError
        Compilation failed, or no reachable poses could be sampled.
    """
    from gtmodel.errors import InputError

    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 1:
        raise InputError(f"n: expected a positive number of poses, got {n!r}")
    if library is None:
        library = load_library(generated, compile_shared(generated, build_dir))
    model = RobotModel(generated.parameters, generated.friction)
    data = sample_inputs(generated, int(n), seed, model)
    results = []
    probes = []
    singular_T = None
    for spec in generated.specs:
        cf = library[spec.name]
        inputs = _function_inputs(spec, data)
        results.append(_compare(spec, cf, model, inputs))
        log.debug("codegen check: %s", results[-1])
        statuses = {c.status for c in spec.checks}
        if spec.unreachable is not None:
            probes.append(_probe(cf, spec, inputs, "unreachable input", "GT_UNREACHABLE", spec.unreachable(model)))
        if "GT_SINGULAR" in statuses and any(a.name == "T" for a in spec.args):
            if singular_T is None:
                singular_T = _singular_pose(model, data["T"])
            if singular_T is not None:
                probes.append(_probe(cf, spec, inputs, "singular pose", "GT_SINGULAR", {"T": singular_T, "configuration": 0}))
        for a, size in zip(spec.args, generated.signatures[spec.name][0]):
            if a.kind == "vector":
                probes.append(_probe(cf, spec, inputs, f"NaN in {a.name}", "GT_BAD_ARGUMENT", {a.name: np.full(size, np.nan)}))
            elif a.kind == "configuration":
                for bad in (-1, 8):
                    probes.append(_probe(cf, spec, inputs, f"{a.name}={bad}", "GT_BAD_ARGUMENT", {a.name: bad}))
            else:
                probes.append(_probe(cf, spec, inputs, f"{a.name}=0", "GT_BAD_ARGUMENT", {a.name: 0}))
    report = CheckReport(
        robot=generated.parameters.name,
        prefix=generated.prefix,
        n=int(n),
        seed=seed,
        functions=tuple(results),
        probes=tuple(probes),
        version=library.version(),
        library=library.path,
    )
    log.info("codegen check of %s: %s", generated.prefix, "passed" if report.passed else "FAILED")
    return report
