"""Self-check of generated C: compiled functions against the Python evaluation.

:func:`check` compiles the generated code (unless given a loaded library), evaluates
every generated C function through ctypes on ``n`` random valid inputs and compares the
outputs with the Python evaluation of the same model (the NumPy methods of
``GantryTau3Kinematics``, ``GantryTau3Dynamics``, ``SixLinkClosure``, ``F1Closure``, or
the CasADi Function itself for a function without such a method). It probes the edge
cases: poses on the workspace boundary (an arm stretched to ``(1 - 1e-9) L``: OK for the
IK and equal to Python, singular for the Jacobian-based functions), just beyond it, far
unreachable poses, singular poses, non-finite inputs and invalid configurations must give
the stated non-zero status and leave the outputs untouched (so they stay finite). Finally
it times every function in a small C program linked against the library (ns/call).
"""

from __future__ import annotations

import logging
import shutil
import subprocess
from dataclasses import dataclass, field
from functools import lru_cache
from importlib import resources
from pathlib import Path
from typing import Any, Mapping

import casadi as ca
import numpy as np

from gtmodel.codegen.build import CompiledLibrary, compile_shared, find_compiler, load_library
from gtmodel.codegen.controller import robot_part
from gtmodel.codegen.generate import GeneratedCode
from gtmodel.codegen.declarations import (
    FK_TOLERANCE,
    IK_TOLERANCE,
    INVERSE_DYNAMICS_TOLERANCE,
    JACOBIAN_TOLERANCE,
    STATUS_CODES,
    FunctionSpec,
)
from gtmodel.codegen.robot import RobotModel
from gtmodel.codegen.specs import SPECS_BY_KIND
from gtmodel.errors import CodegenError, InputError, SingularConfigurationError
from gtmodel.robots.kinematics import SINGULARITY_TOLERANCE, GantryTau3Kinematics, configuration_signs
from gtmodel.robots.parameters import available_parameter_sets

__all__ = [
    "IK_TOLERANCE",
    "FK_TOLERANCE",
    "JACOBIAN_TOLERANCE",
    "INVERSE_DYNAMICS_TOLERANCE",
    "FLOAT_RELATIVE_TOLERANCE",
    "SENTINEL",
    "FunctionCheck",
    "StatusProbe",
    "CheckReport",
    "sample_inputs",
    "timed_rows",
    "time_functions",
    "run_harness_unit_tests",
    "harness_dir",
    "harness_applies",
    "HARNESS_FILES",
    "check",
]

log = logging.getLogger("gtmodel")

#: Value pre-filled into output buffers to detect writes on a non-OK status.
SENTINEL = 1234.5678
#: Range of the random TCP velocities [m/s] (each component uniform in +-).
VELOCITY_RANGE = 1.0
#: Range of the random TCP accelerations [m/s^2] (each component uniform in +-).
ACCELERATION_RANGE = 5.0
#: Single-precision code: accepted |C - Python| <= FLOAT_RELATIVE_TOLERANCE (1 + |Python|).
FLOAT_RELATIVE_TOLERANCE = 1e-4
#: Relative distance to the reach limit of the workspace-boundary probes.
BOUNDARY_MARGIN = 1e-9
#: F1 samples: perturbation of the grid actuator values (m for q1-q3, rad for q4-q6).
F1_PERTURBATION = np.array([0.004, 0.004, 0.004, 0.01, 0.01, 0.01])
#: Fraction of the F1 / six-link samples evaluated from the default Newton start (NULL).
DEFAULT_START_FRACTION = 0.1

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
        Largest accepted absolute difference.
    unit : str
        Unit of the outputs (``""`` if dimensionless).
    n_not_ok : int
        Samples (all valid for Python) on which the C function returned a non-OK status.
    passed : bool
        Every sample within tolerance (absolute, or relative where declared) and
        ``n_not_ok == 0``.
    max_rel_diff : float, optional
        Largest ``|C - Python| / |Python|`` (elements with ``|Python| > 0``).
    ns_per_call : float or None, optional
        Mean time per call of the C function in a C loop [ns] (None if not timed).
    n_refused : int, optional
        Random samples the Python model refused (no convergence): skipped.
    """

    name: str
    n: int
    max_abs_diff: float
    tolerance: float
    unit: str
    n_not_ok: int
    passed: bool
    max_rel_diff: float = 0.0
    ns_per_call: float | None = None
    n_refused: int = 0


@dataclass(frozen=True)
class StatusProbe:
    """One status-code probe: an edge-case input must give a given status.

    Parameters
    ----------
    function : str
        Function probed.
    case : str
        What was fed, e.g. ``"unreachable pose"``.
    expected : str
        Expected status macro, e.g. ``"GT_UNREACHABLE"`` (alternatives separated by ``|``).
    status : int
        Returned status.
    untouched : bool
        For a non-OK status: the output buffers kept their pre-filled values. For
        ``GT_OK``: the outputs equal the Python evaluation within the tolerance.
    passed : bool
        ``status`` is an expected one and ``untouched`` holds.
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
        Robot (parameter-set) name.
    prefix : str
        C prefix of the library.
    n : int
        Number of random inputs per function.
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
    timings : dict
        Extra C timings [ns/call], e.g. ``{"fk (default start)": 25000.0}``.
    harness : str
        What the C unit tests of the harness (:func:`run_harness_unit_tests`) did: the
        program run and its last output line, why they could not run, or why they do
        not apply (empty if not attempted).
    harness_passed : bool or None
        Its verdict (None if not run).
    """

    robot: str
    prefix: str
    n: int
    seed: int
    functions: tuple[FunctionCheck, ...]
    probes: tuple[StatusProbe, ...]
    version: str = ""
    library: Path | None = field(default=None, compare=False)
    timings: dict[str, float] = field(default_factory=dict, compare=False)
    harness: str = ""
    harness_passed: bool | None = None

    @property
    def passed(self) -> bool:
        """True if every comparison, every status probe and the C unit tests (if run) passed."""
        return (
            all(f.passed for f in self.functions)
            and all(p.passed for p in self.probes)
            and self.harness_passed is not False
        )

    def summary_lines(self) -> list[str]:
        """Printable lines: one per function, then the status probes and the verdict.

        Returns
        -------
        list of str
            E.g. ``"ik: max |C - Python| = 2.2e-16 m (tol 1e-12), 85 ns/call OK"``.
        """
        lines = [f"check of {self.prefix} ({self.robot}) on {self.n} random valid inputs per function (seed {self.seed}):"]
        for f in self.functions:
            unit = f" {f.unit}" if f.unit else ""
            verdict = "OK" if f.passed else "FAILED"
            extra = f", {f.n_not_ok} valid inputs gave a non-OK status" if f.n_not_ok else ""
            rel = f", max rel {f.max_rel_diff:.1e}" if f.max_rel_diff else ""
            timing = f", {f.ns_per_call:.0f} ns/call" if f.ns_per_call is not None else ""
            refused = f" ({f.n_refused} refused by Python, skipped)" if f.n_refused else ""
            lines.append(
                f"{f.name}: max |C - Python| = {f.max_abs_diff:.1e}{unit}{rel} (tol {f.tolerance:g}){timing}{extra}{refused} {verdict}"
            )
        for k, v in self.timings.items():
            lines.append(f"{k}: {v:.0f} ns/call")
        ok = sum(p.passed for p in self.probes)
        lines.append(f"edge cases: {ok}/{len(self.probes)} probes OK (expected status; outputs untouched, or equal to Python if OK)")
        for p in self.probes:
            if not p.passed:
                got = _STATUS_NAMES.get(p.status, str(p.status))
                touched = "" if p.untouched else ", outputs WRITTEN or wrong"
                lines.append(f"  FAILED {p.function} on {p.case}: expected {p.expected}, got {got}{touched}")
        if self.harness:
            lines.append(f"C unit tests: {self.harness}")
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
        raise CodegenError(f"check: could not sample {n} reachable poses of {model.name}")
    return np.concatenate(out)[:n]


@lru_cache(maxsize=2)
def _f1_grid(f1) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    return f1.workspace_grid(return_q=True)


def _three_link_inputs(generated: GeneratedCode, model: RobotModel, n: int, rng: np.random.Generator) -> dict[str, dict[str, np.ndarray]]:
    T = _reachable_poses(model, n, rng)
    data = {
        "T": T,
        "T_dot": rng.uniform(-VELOCITY_RANGE, VELOCITY_RANGE, (n, 3)),
        "T_ddot": rng.uniform(-ACCELERATION_RANGE, ACCELERATION_RANGE, (n, 3)),
        "q_ddot": rng.uniform(-ACCELERATION_RANGE, ACCELERATION_RANGE, (n, 3)),
        "q": np.reshape(model.kinematics.ik(T, 0), (n, 3)),
        "solution": rng.choice([1, -1], n),
    }
    out = {}
    for spec in generated.specs:
        inp = {}
        for a, size in zip(spec.args, generated.signatures[spec.name][0]):
            if a.kind == "configuration":
                inp[a.name] = rng.choice(np.array(spec.check_configurations), n)
            elif a.name in data:
                inp[a.name] = data[a.name]
            else:
                inp[a.name] = rng.uniform(-1.0, 1.0, (n, size))
        inp.setdefault("configuration", np.zeros(n, dtype=int))
        out[spec.name] = inp
    return out


def _six_link_inputs(generated: GeneratedCode, model: RobotModel, n: int, rng: np.random.Generator) -> dict[str, dict[str, np.ndarray]]:
    six = model.closure
    base = "D1" if "D1" in available_parameter_sets() else None
    k3 = GantryTau3Kinematics(base)
    box = k3.workspace_bounds()
    Ts = []
    while sum(len(t) for t in Ts) < n:
        X = rng.uniform(box[:, 0], box[:, 1], size=(4 * n, 3))
        Ts.append(X[k3.in_workspace(X)])
    T3 = np.concatenate(Ts)[:n]
    q = np.reshape(k3.ik(T3, 0), (n, 3))
    res = six.fk_solve(q, 0, 1)
    out = {}
    for spec in generated.specs:
        if spec.name == "fk" or spec.newton is not None:
            out[spec.name] = {"q": q, "configuration": np.zeros(n, dtype=int), "solution": np.ones(n, dtype=int)}
        else:
            out[spec.name] = {"T": res.T, "R": res.R.reshape(n, 9), "configuration": np.zeros(n, dtype=int)}
    return out


def _f1_inputs(generated: GeneratedCode, model: RobotModel, n: int, rng: np.random.Generator) -> dict[str, dict[str, np.ndarray]]:
    f1 = model.closure
    Tg, Rg, qg = _f1_grid(f1)
    idx = rng.integers(0, len(qg), n)
    q = qg[idx] + rng.uniform(-1.0, 1.0, (n, 6)) * F1_PERTURBATION
    T0, R0 = Tg[idx], Rg[idx].reshape(n, 9)
    # the pose of q: FK warm-started from the grid pose (the previous sample); rows the
    # Python model refuses stay NaN and are skipped
    ref = _model_reference(model, "fk", {"q": q, "T0": T0, "R0": R0})
    ok = np.all(np.isfinite(ref["T"]), axis=1)
    T, R = ref["T"], ref["R"]
    default = rng.random(n) < DEFAULT_START_FRACTION
    out = {}
    for spec in generated.specs:
        if spec.name == "ik":
            q0 = qg[idx].copy()
            q0[default] = np.nan  # NULL: default start
            T_in = np.where(ok[:, None], T, T0)
            R_in = np.where(ok[:, None], R, R0)
            out["ik"] = {"T": T_in, "R": R_in, "q0": q0}
        elif spec.name == "fk":
            T0s, R0s = T0.copy(), R0.copy()
            T0s[default] = np.nan
            R0s[default] = np.nan
            out["fk"] = {"q": q, "T0": T0s, "R0": R0s}
    return out


def _model_reference(model: RobotModel, name: str, inputs: Mapping[str, np.ndarray]) -> dict[str, np.ndarray]:
    """Python evaluation of the declared function ``name`` of the model's kind (NaN rows: refused)."""
    return SPECS_BY_KIND[model.kind][name].reference(model, inputs)


def sample_inputs(generated: GeneratedCode, n: int = 1000, seed: int = 0, model: RobotModel | None = None) -> dict[str, dict[str, np.ndarray]]:
    """Random valid inputs for the generated functions, keyed by function, then C argument.

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
    dict of str to dict of str to numpy.ndarray
        3-link: ``T`` (n, 3) [m] uniform in the workspace (inside the bounding box and
        ``in_workspace``, configuration 0), ``T_dot`` [m/s], ``T_ddot``, ``q_ddot``
        [m/s^2] uniform in ``+-VELOCITY_RANGE``/``+-ACCELERATION_RANGE``, ``q`` the IK of
        ``T``, ``solution`` +-1, ``configuration`` drawn from the function's
        ``check_configurations``. Six-link: ``q`` the 3-link D1 IK of workspace poses;
        ``T``, ``R`` their six-link FK. F1: actuator values of the workspace grid
        perturbed by up to ``F1_PERTURBATION``, their poses, and the grid sample as the
        warm start (NaN rows: NULL, the default start, for ``DEFAULT_START_FRACTION``).
    """
    model = model or generated.model()
    rng = np.random.default_rng(seed)
    if generated.kind == "three_link":
        return _three_link_inputs(generated, model, n, rng)
    if generated.kind == "six_link":
        return _six_link_inputs(generated, model, n, rng)
    return _f1_inputs(generated, model, n, rng)


# ----------------------------------------------------------------------------- comparison
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
        elif a.kind == "matrix":
            cols[a.casadi_input] = v.reshape(n, 3, 3).transpose(1, 0, 2).reshape(3, 3 * n)
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


def _row_args(spec: FunctionSpec, inputs: Mapping[str, np.ndarray], i: int, overrides: Mapping | None = None) -> list:
    """C arguments of sample ``i``; a non-finite optional sample value means NULL (overrides are passed as given)."""
    args = []
    for a in spec.args:
        if overrides and a.name in overrides:
            args.append(overrides[a.name])
            continue
        v = inputs[a.name][i]
        if a.optional and not np.all(np.isfinite(v)):
            v = None
        args.append(v)
    return args


def _call_row(cf, spec: FunctionSpec, inputs: Mapping[str, np.ndarray], i: int, overrides: Mapping | None = None):
    out = [np.full(n, SENTINEL, dtype=cf.dtype) for n in cf.sizes_out]
    return cf(*_row_args(spec, inputs, i, overrides), out=out)


def _diffs(spec: FunctionSpec, out, ref: Mapping[str, np.ndarray], real: str) -> tuple[float, float, bool]:
    """Largest absolute and relative ``|C - Python|`` of stacked outputs ``(N, n)``, and the verdict."""
    worst_abs, worst_rel, ok = 0.0, 0.0, True
    for o, val in zip(spec.outputs, out):
        val = np.asarray(val, dtype=float)
        if val.size == 0:
            continue
        r = np.reshape(ref[o.name], val.shape)
        d = np.abs(val - r)
        if not np.all(np.isfinite(d)):
            return np.inf, np.inf, False
        worst_abs = max(worst_abs, float(d.max()))
        nz = np.abs(r) > 0
        if nz.any():
            worst_rel = max(worst_rel, float((d[nz] / np.abs(r[nz])).max()))
        if real == "float":
            ok &= bool(np.all(d <= FLOAT_RELATIVE_TOLERANCE * (1.0 + np.abs(r))))
        else:
            ok &= bool(np.all((d <= spec.tolerance) | (d <= spec.relative_tolerance * np.abs(r))))
    return worst_abs, worst_rel, ok


def _compare(spec: FunctionSpec, cf, model: RobotModel, inputs: Mapping[str, np.ndarray], real: str) -> FunctionCheck:
    n = len(inputs[spec.args[0].name])
    ref = spec.reference(model, inputs) if spec.reference is not None else _casadi_reference(spec, model, inputs)
    ref = {o.name: np.reshape(ref[o.name], (n, -1)) for o in spec.outputs}
    valid = np.all([np.all(np.isfinite(ref[o.name]), axis=1) for o in spec.outputs], axis=0)
    rows = np.flatnonzero(valid)
    status, out = cf.call_rows(*[np.asarray(inputs[a.name])[rows] for a in spec.args], fill=SENTINEL)
    good = status == 0
    worst_abs, worst_rel, all_ok = _diffs(spec, [o[good] for o in out], {k: v[rows[good]] for k, v in ref.items()}, real)
    refused = n - rows.size
    not_ok = int(np.sum(~good))
    passed = bool(all_ok and not_ok == 0 and rows.size > 0)
    tol = FLOAT_RELATIVE_TOLERANCE if real == "float" else spec.tolerance
    return FunctionCheck(spec.name, int(rows.size), worst_abs, tol, spec.unit, not_ok, passed, worst_rel, None, refused)


def _probe(cf, spec: FunctionSpec, inputs, case: str, expected: str, overrides: Mapping, model: RobotModel | None = None, real: str = "double") -> StatusProbe:
    status, out = _call_row(cf, spec, inputs, 0, overrides)
    codes = [STATUS_CODES[e][0] for e in expected.split("|")]
    if status == 0 and model is not None:
        row = {a.name: np.asarray([overrides.get(a.name, inputs[a.name][0])]) for a in spec.args}
        ref = spec.reference(model, row) if spec.reference is not None else _casadi_reference(spec, model, row)
        fine = _diffs(spec, [np.reshape(o, (1, -1)) for o in out], ref, real)[2]
    else:
        fine = all(np.all(o == np.asarray(SENTINEL, dtype=o.dtype)) for o in out)
    passed = bool(status in codes and fine)
    return StatusProbe(spec.name, case, expected, status, bool(fine), passed)


def _stretched_pose(model: RobotModel, poses: np.ndarray, factor: float) -> np.ndarray | None:
    """A pose with arm 1 at ``factor * L_1`` from its guideway line (arms 2, 3 clearly reachable)."""
    k = model.kinematics
    vh = k.v[0] / np.linalg.norm(k.v[0])
    for T0 in poses[:200]:
        d = T0 - k.As[0]
        p = d - (d @ vh) * vh
        T = k.As[0] + (d @ vh) * vh + k.L[0] * factor * p / np.linalg.norm(p)
        _, disc = k.ik_function(T, configuration_signs(0))
        disc = np.asarray(disc).ravel()
        if np.all(disc[1:] > 1e-6):
            return T
    return None


def _singular_pose(model: RobotModel, poses: np.ndarray) -> np.ndarray | None:
    """A reachable TCP position (configuration 0) where link 1 is perpendicular to its guideway.

    Moves a workspace pose perpendicular to guideway 1 until arm 1 is stretched to
    ``(1 - 1e-13) L_1`` from the guideway line, keeping arms 2 and 3 clearly reachable;
    the Python model must judge it singular.
    """
    k = model.kinematics
    T = _stretched_pose(model, poses, 1 - 1e-13)
    if T is None:
        return None
    _, _, _, disc, cos_min = k.jacobian_function(T, configuration_signs(0))
    if float(np.min(np.asarray(disc))) >= 0 and float(cos_min) < SINGULARITY_TOLERANCE:
        try:
            k.jacobian(T, 0)
        except SingularConfigurationError:
            return T
    return None  # pragma: no cover


def _edge_probes(generated: GeneratedCode, spec: FunctionSpec, cf, model: RobotModel, inputs, cache: dict) -> list[StatusProbe]:
    probes = []
    real = generated.real
    statuses = {c.status for c in spec.checks}
    if spec.unreachable is not None:
        probes.append(_probe(cf, spec, inputs, "unreachable input", "GT_UNREACHABLE", spec.unreachable(model)))
    elif spec.newton is not None:
        far = {a.name: np.full(s, 5.0) for a, s in zip(spec.args, generated.signatures[spec.name][0]) if a.kind == "vector" and not a.optional}
        probes.append(_probe(cf, spec, inputs, "input far from any assembly", "GT_NOT_CONVERGED|GT_UNREACHABLE", far))
    # boundary and singular probes sit 1e-9 (1e-13) from the limit: meaningful in double precision only
    if generated.kind == "three_link" and real == "double" and any(a.name == "T" for a in spec.args):
        if "boundary" not in cache:
            cache["boundary"] = _stretched_pose(model, inputs["T"], 1 - BOUNDARY_MARGIN)
            cache["beyond"] = _stretched_pose(model, inputs["T"], 1 + BOUNDARY_MARGIN)
            cache["singular"] = _singular_pose(model, inputs["T"])
        conf0 = {"configuration": 0}
        if cache["beyond"] is not None and "GT_UNREACHABLE" in statuses:
            probes.append(_probe(cf, spec, inputs, "just beyond the workspace boundary", "GT_UNREACHABLE", {"T": cache["beyond"], **conf0}))
        if cache["boundary"] is not None:
            probes.append(
                _probe(cf, spec, inputs, "on the workspace boundary (arm stretched)", "GT_OK", {"T": cache["boundary"], **conf0}, model, real)
            )
        if "GT_SINGULAR" in statuses and cache["singular"] is not None:
            probes.append(_probe(cf, spec, inputs, "singular pose", "GT_SINGULAR", {"T": cache["singular"], **conf0}))
    for a, size in zip(spec.args, generated.signatures[spec.name][0]):
        if a.kind in ("vector", "matrix"):
            probes.append(_probe(cf, spec, inputs, f"NaN in {a.name}", "GT_BAD_ARGUMENT", {a.name: np.full(size, np.nan)}))
            probes.append(_probe(cf, spec, inputs, f"Inf in {a.name}", "GT_BAD_ARGUMENT", {a.name: np.full(size, np.inf)}))
        elif a.kind == "configuration":
            for bad in (-1, 8):
                probes.append(_probe(cf, spec, inputs, f"{a.name}={bad}", "GT_BAD_ARGUMENT", {a.name: bad}))
        else:
            probes.append(_probe(cf, spec, inputs, f"{a.name}=0", "GT_BAD_ARGUMENT", {a.name: 0}))
    return probes


# ----------------------------------------------------------------------------- timing
_TIMER = r"""
#define _POSIX_C_SOURCE 199309L
#include <stdio.h>
#include <time.h>
#include "{header}"

static double now_ns(void)
{{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec * 1e9 + (double)ts.tv_nsec;
}}

int main(void)
{{
    volatile double sink = 0.0;
    int status = 0;
    long i, n;
    double t0, t1;
{blocks}
    return status != 0;
}}
"""


def _c_literal(values, real: str) -> str:
    return ", ".join(f"{float(v)!r}" + ("f" if real == "float" else "") for v in np.ravel(values))


def _c_call(generated: GeneratedCode, spec: FunctionSpec, args: list, indent: str = "        ") -> tuple[list[str], str]:
    """C declarations of the argument/output buffers of one call, and the call expression.

    Inputs become ``static const`` arrays ``a<k>`` (NULL for a None optional argument),
    outputs ``o<k>``; a Newton function also gets ``int it``.
    """
    real = generated.real
    sizes_in, sizes_out = generated.signatures[spec.name]
    lines, call = [], []
    for k, (v, n) in enumerate(zip(args, sizes_in)):
        if n == 0:
            call.append(str(int(v)))
        elif v is None:
            call.append("NULL")
        else:
            lines.append(f"{indent}static const {real} a{k}[{n}] = {{{_c_literal(v, real)}}};")
            call.append(f"a{k}")
    for k, n in enumerate(sizes_out):
        lines.append(f"{indent}{real} o{k}[{n}];")
        call.append(f"o{k}")
    if spec.newton is not None:
        lines.append(f"{indent}int it;")
        call.append("&it")
    return lines, f"{generated.prefix}_{spec.name}({', '.join(call)})"


def _timing_block(generated: GeneratedCode, spec: FunctionSpec, label: str, args: list, budget_s: float) -> str:
    decl, c = _c_call(generated, spec, args)
    lines = ["    {", *decl]
    lines += [
        f"        t0 = now_ns(); for (i = 0; i < 100; ++i) {{ status |= {c}; sink += o0[0]; }} t1 = now_ns();",
        f"        n = (long)({budget_s * 1e9} / ((t1 - t0) / 100.0 + 1.0)); if (n < 100) n = 100;",
        f"        t0 = now_ns(); for (i = 0; i < n; ++i) {{ status |= {c}; sink += o0[0]; }} t1 = now_ns();",
        f'        printf("{label}\\t%.3f\\n", (t1 - t0) / (double)n);',
        "    }",
    ]
    return "\n".join(lines)


def timed_rows(generated: GeneratedCode, samples: Mapping[str, Mapping[str, np.ndarray]]) -> dict[str, tuple[FunctionSpec, list]]:
    """The sample rows a timing uses, by label.

    Parameters
    ----------
    generated : GeneratedCode
        What was generated.
    samples : Mapping
        Inputs per function (as from :func:`sample_inputs`).

    Returns
    -------
    dict of str to tuple of (FunctionSpec, list)
        Per function the first row with a warm start (label = the function name) and, for
        Newton functions with an optional warm start, the first row without one (label
        ``"<name> (default start)"``); the list holds the C arguments (None = NULL).
    """
    out = {}
    for spec in generated.specs:
        inp = samples[spec.name]
        rows: dict[bool, list] = {}
        for i in range(len(inp[spec.args[0].name])):
            args = _row_args(spec, inp, i)
            rows.setdefault(any(a.optional and v is None for a, v in zip(spec.args, args)), args)
            if len(rows) == 2:
                break
        if False in rows:
            out[spec.name] = (spec, rows[False])
        if True in rows:
            out[f"{spec.name} (default start)" if False in rows else spec.name] = (spec, rows[True])
    return out


def time_functions(generated: GeneratedCode, library: Path, samples: Mapping[str, Mapping[str, np.ndarray]], build_dir: Path, budget_s: float = 0.05) -> dict[str, float]:
    """Time every generated function in a C loop linked against the shared library.

    Parameters
    ----------
    generated : GeneratedCode
        What was generated.
    library : pathlib.Path
        The shared library (``lib<prefix>.so``).
    samples : Mapping
        Inputs per function (as from :func:`sample_inputs`); the first row with a warm
        start (if any) is timed, and for Newton functions with a warm start also the
        first row without one (label ``"<name> (default start)"``).
    build_dir : pathlib.Path
        Folder for the timing program.
    budget_s : float, optional
        About this many seconds of calls per function.

    Returns
    -------
    dict of str to float
        Label -> mean time per call [ns].

    Raises
    ------
    CodegenError
        The timing program failed to build or a timed call returned a non-OK status.
    """
    blocks = [_timing_block(generated, spec, label, args, budget_s) for label, (spec, args) in timed_rows(generated, samples).items()]
    build_dir = Path(build_dir)
    build_dir.mkdir(parents=True, exist_ok=True)
    src = build_dir / f"{generated.prefix}_timing.c"
    src.write_text(_TIMER.format(header=generated.header.name, blocks="\n".join(blocks)))
    exe = build_dir / f"{generated.prefix}_timing"
    cc = find_compiler()
    proc = subprocess.run(
        [*cc, "-std=c99", "-O2", "-Wall", "-Wextra", "-I", str(generated.out_dir), str(src), "-o", str(exe),
         "-L", str(library.parent), f"-l{generated.prefix}", f"-Wl,-rpath,{library.parent}", "-lm"],
        capture_output=True, text=True,
    )
    if proc.returncode != 0:
        raise CodegenError(f"timing program failed to build:\n{proc.stderr.strip()}")
    run = subprocess.run([str(exe)], capture_output=True, text=True, timeout=600)
    if run.returncode != 0:
        raise CodegenError("timing program: a timed call returned a non-OK status")
    return {k: float(v) for k, v in (line.split("\t") for line in run.stdout.strip().splitlines())}


# ----------------------------------------------------------------------------- harness
#: Functions the C unit-test program calls.
HARNESS_FUNCTIONS = ("ik", "fk", "jacobian", "jacobian_inverse", "acceleration", "inverse_dynamics", "gravity")
#: Files of the hand-written harness shipped as package data in ``gtmodel/codegen/harness/``.
HARNESS_FILES = ("Makefile", "unit_test.c", "loop.c", "heap_watch.h")


def harness_dir() -> Path:
    """The folder of the hand-written C harness shipped with the package.

    ``gtmodel/codegen/harness/`` (package data: the Makefile rules, ``unit_test.c``,
    ``loop.c``, ``retime_example.c`` and the heap counter ``heap_watch.h`` they include), in a source checkout and after ``pip install .`` alike; ``codegen/Makefile``
    of a source checkout includes its Makefile.

    Returns
    -------
    pathlib.Path
        The folder (it may lack files in a broken installation: see
        :func:`run_harness_unit_tests`).
    """
    return Path(str(resources.files("gtmodel.codegen") / "harness"))


def harness_applies(generated: GeneratedCode) -> bool:
    """Whether the C unit-test program applies to a generated library.

    Parameters
    ----------
    generated : GeneratedCode
        The generated code.

    Returns
    -------
    bool
        True for a 3-link library in double precision with every function of
        :data:`HARNESS_FUNCTIONS` (the program calls them all).
    """
    return (
        generated.kind == "three_link" and generated.real == "double"
        and set(HARNESS_FUNCTIONS) <= set(generated.functions)
    )


def run_harness_unit_tests(generated: GeneratedCode, build_dir: str | Path, harness: str | Path | None = None) -> tuple[bool, str] | None:
    """Build and run the C unit-test program of the harness against the generated code.

    Parameters
    ----------
    generated : GeneratedCode
        A 3-link library with every function of :data:`HARNESS_FUNCTIONS` in double
        precision (:func:`harness_applies`).
    build_dir : str or pathlib.Path
        Build folder of the harness (``make BUILD=...``).
    harness : str or pathlib.Path or None, optional
        Folder of the harness sources; default :func:`harness_dir`.

    Returns
    -------
    tuple of (bool, str) or None
        Verdict and a line saying what ran (the program's last output line) or why the
        tests could not run (harness files missing, no ``make``, build failure): then the
        verdict is False. None if the tests do not apply to this library
        (:func:`harness_applies`).
    """
    if not harness_applies(generated):
        return None
    folder = Path(harness) if harness is not None else harness_dir()
    missing = [f for f in HARNESS_FILES if not (folder / f).is_file()]
    if missing:
        return False, f"not run: harness files {missing} missing in {folder} (broken installation)"
    if shutil.which("make") is None:
        return False, "not run: no 'make' program on PATH"
    model = generated.model()
    grid = model.kinematics.workspace_grid(0.1)
    T = grid[len(grid) // 2]
    build = Path(build_dir).resolve()
    target = build / "unit_test"
    cmd = [
        "make", "-s", "-C", str(folder), f"BUILD={build}", f"GEN={generated.out_dir.resolve()}",
        f"PREFIX={generated.prefix}", f"TEST_T={{{', '.join(repr(float(x)) for x in T)}}}", str(target),
    ]
    proc = subprocess.run(cmd, capture_output=True, text=True)
    if proc.returncode != 0:
        return False, f"build failed: {(proc.stderr or proc.stdout).strip().splitlines()[-1:]}"
    run = subprocess.run([str(target)], capture_output=True, text=True, timeout=120)
    last = run.stdout.strip().splitlines()[-1] if run.stdout.strip() else f"exit {run.returncode}"
    return run.returncode == 0, f"ran {folder / 'unit_test.c'}: {last}"


# ----------------------------------------------------------------------------- API
def check(
    generated: GeneratedCode,
    n: int = 1000,
    seed: int = 0,
    library: CompiledLibrary | None = None,
    build_dir: str | Path | None = None,
    timing: bool = False,
) -> CheckReport:
    """Compile the generated C and compare it with the Python evaluation of the model.

    Parameters
    ----------
    generated : GeneratedCode
        Result of :func:`gtmodel.codegen.generate`.
    n : int, optional
        Number of random valid inputs per function (default 1000); see :func:`sample_inputs`.
    seed : int, optional
        Seed of the random generator (default 0).
    library : CompiledLibrary or None, optional
        An already loaded library; compiled with :func:`compile_shared` if None.
    build_dir : str or pathlib.Path or None, optional
        Build folder when compiling or timing (default ``<out_dir>/build``).
    timing : bool, optional
        Also time every function in a C loop (ns/call, :func:`time_functions`) and build
        and run the C unit-test program of the harness shipped with the package
        (:func:`run_harness_unit_tests`; a harness that applies but cannot run fails the
        check).

    Returns
    -------
    CheckReport
        Per robot-model function (the controller functions of a library generated with
        ``controller=`` are checked by
        :func:`~gtmodel.codegen.controller_check.check_controller`) the largest ``|C - Python|`` against its tolerance (``IK_TOLERANCE``,
        ``FK_TOLERANCE`` = 1e-12 m, ``JACOBIAN_TOLERANCE`` = 1e-12,
        ``INVERSE_DYNAMICS_TOLERANCE`` = 1e-9 N or 1e-9 relative; single precision:
        ``FLOAT_RELATIVE_TOLERANCE``), the edge-case probes and the timings. A failed
        check is a report with ``passed == False``, not an exception.

    Raises
    ------
    InputError
        ``n`` is not a positive integer.
    CompilerNotFoundError
        No C compiler.
    CodegenError
        Compilation failed, or no valid inputs could be sampled.
    """
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 1:
        raise InputError(f"n: expected a positive number of poses, got {n!r}")
    build = Path(build_dir) if build_dir is not None else generated.out_dir / "build"
    generated = robot_part(generated)  # the controller functions: controller_check.check_controller
    if library is None:
        library = load_library(generated, compile_shared(generated, build))
    model = generated.model()
    data = sample_inputs(generated, int(n), seed, model)
    results = []
    probes: list[StatusProbe] = []
    cache: dict[str, Any] = {}
    for spec in generated.specs:
        cf = library[spec.name]
        inputs = data[spec.name]
        results.append(_compare(spec, cf, model, inputs, generated.real))
        log.debug("codegen check: %s", results[-1])
        probes += _edge_probes(generated, spec, cf, model, inputs, cache)
    extra: dict[str, float] = {}
    if timing:
        times = time_functions(generated, library.path, data, build)
        results = [
            FunctionCheck(**{**r.__dict__, "ns_per_call": times.get(r.name)}) for r in results
        ]
        extra = {k: v for k, v in times.items() if k not in generated.functions}
    harness = run_harness_unit_tests(generated, build / "harness") if timing else None
    if timing and harness is None:
        harness = (None, "not applicable (the harness tests a 3-link library in double precision with all of "
                   + ", ".join(HARNESS_FUNCTIONS) + ")")
    report = CheckReport(
        robot=generated.robot_name,
        prefix=generated.prefix,
        n=int(n),
        seed=seed,
        functions=tuple(results),
        probes=tuple(probes),
        version=library.version(),
        library=library.path,
        timings=extra,
        harness=harness[1] if harness else "",
        harness_passed=harness[0] if harness else None,
    )
    log.info("codegen check of %s: %s", generated.prefix, "passed" if report.passed else "FAILED")
    return report
