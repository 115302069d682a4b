"""Inputs, Python references, comparisons and edge-case probes of the robot functions' self-check.

:func:`sample_inputs` draws random valid inputs per function (reachable poses, random
configurations, velocities and accelerations; F1 and six-link samples around a grid with
a share from the default Newton start); :func:`compare` evaluates a compiled function on
them and compares with the Python model (the NumPy methods of ``GantryTau3Kinematics``,
``GantryTau3Dynamics``, ``SixLinkClosure``, ``F1Closure``, or the CasADi Function itself
for a function without such a method); :func:`edge_probes` feeds the edge cases (workspace
boundary, beyond it, singular poses, non-finite inputs, invalid configurations) and
checks the status and that the outputs stay untouched.
"""

from __future__ import annotations

from functools import lru_cache
from typing import Mapping

import casadi as ca
import numpy as np

from gtmodel.codegen.check.report import SENTINEL, FunctionCheck, StatusProbe, tolerance_rule, within
from gtmodel.codegen.declarations import STATUS_CODES, FunctionSpec
from gtmodel.codegen.writer import GeneratedCode
from gtmodel.codegen.robot import RobotModel
from gtmodel.codegen.specs import SPECS_BY_KIND
from gtmodel.errors import CodegenError, SingularConfigurationError
from gtmodel.robots.kinematic_expressions import configuration_signs
from gtmodel.robots.kinematics import SINGULARITY_TOLERANCE, GantryTau3Kinematics
from gtmodel.robots.parameters import available_parameter_sets

__all__ = ["sample_inputs", "compare", "probe", "edge_probes", "row_args"]

#: Range of the random TCP velocities [m/s] (each component uniform in +-).
VELOCITY_RANGE = 1.0
#: Range of the random TCP accelerations [m/s^2] (each component uniform in +-).
ACCELERATION_RANGE = 5.0
#: Relative distance to the reach limit of the workspace-boundary probes.
BOUNDARY_MARGIN = 1e-9
#: F1 samples: perturbation of the grid actuator values (m for q1-q3, rad for q4-q6).
F1_PERTURBATION = np.array([0.004, 0.004, 0.004, 0.01, 0.01, 0.01])
#: Fraction of the F1 / six-link samples evaluated from the default Newton start (NULL).
DEFAULT_START_FRACTION = 0.1


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


def row_args(spec: FunctionSpec, inputs: Mapping[str, np.ndarray], i: int, overrides: Mapping | None = None) -> list:
    """C arguments of one sample.

    Parameters
    ----------
    spec : FunctionSpec
        The function.
    inputs : Mapping
        ``{argument name: (N, ...) samples}``.
    i : int
        Sample index.
    overrides : Mapping or None, optional
        Argument values used instead of the sample's (passed as given).

    Returns
    -------
    list
        One value per C argument; a non-finite optional sample value is None (NULL).
    """
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
    return cf(*row_args(spec, inputs, i, overrides), out=out)


def _diffs(spec: FunctionSpec, out, ref: Mapping[str, np.ndarray], real: str) -> tuple[float, float, float, bool]:
    """Largest absolute, relative and tolerance-relative ``|C - Python|`` of stacked outputs ``(N, n)``, and the verdict (:func:`within`)."""
    worst_abs, worst_rel, worst_ratio, ok = 0.0, 0.0, 0.0, True
    for o, val in zip(spec.outputs, out):
        val = np.asarray(val, dtype=float)
        if val.size == 0:
            continue
        a, r, q, good = within(val, np.reshape(ref[o.name], val.shape), real, spec.tolerance, spec.relative_tolerance, spec.float_tolerance)
        if not np.isfinite(a):
            return np.inf, np.inf, np.inf, False
        worst_abs, worst_rel, worst_ratio, ok = max(worst_abs, a), max(worst_rel, r), max(worst_ratio, q), ok and good
    return worst_abs, worst_rel, worst_ratio, ok


def compare(spec: FunctionSpec, cf, model: RobotModel, inputs: Mapping[str, np.ndarray], real: str) -> FunctionCheck:
    """Evaluate a compiled function on samples and compare it with the Python model.

    Parameters
    ----------
    spec : FunctionSpec
        The function.
    cf : CompiledFunction
        Its compiled C function.
    model : RobotModel or ModelSource
        The model evaluated from Python (``spec.reference``, else the CasADi Function).
    inputs : Mapping
        ``{argument name: (N, ...) samples}``.
    real : {"double", "float"}
        Floating-point type of the C code.

    Returns
    -------
    FunctionCheck
        The largest differences, the tolerance with its rule (:func:`~gtmodel.codegen.check.report.within`)
        and the samples the Python model refused (non-finite reference: skipped).
    """
    n = len(inputs[spec.args[0].name])
    ref = spec.reference(model, inputs) if spec.reference is not None else _casadi_reference(spec, model, inputs)
    ref = {o.name: np.reshape(ref[o.name], (n, -1)) for o in spec.outputs}
    valid = np.all([np.all(np.isfinite(ref[o.name]), axis=1) for o in spec.outputs], axis=0)
    rows = np.flatnonzero(valid)
    status, out = cf.call_rows(*[np.asarray(inputs[a.name])[rows] for a in spec.args], fill=SENTINEL)
    good = status == 0
    worst_abs, worst_rel, worst_ratio, all_ok = _diffs(spec, [o[good] for o in out], {k: v[rows[good]] for k, v in ref.items()}, real)
    refused = n - rows.size
    not_ok = int(np.sum(~good))
    passed = bool(all_ok and not_ok == 0 and rows.size > 0)
    tol = spec.float_tolerance if real == "float" else spec.tolerance
    return FunctionCheck(spec.name, int(rows.size), worst_abs, tol, spec.unit, not_ok, passed, worst_rel, None, refused,
                         tolerance_rule(real, spec.relative_tolerance), worst_ratio)


def probe(cf, spec: FunctionSpec, inputs, case: str, expected: str, overrides: Mapping, model: RobotModel | None = None, real: str = "double") -> StatusProbe:
    """Call a compiled function on the first sample with some arguments replaced, and check its status.

    Parameters
    ----------
    cf : CompiledFunction
        The compiled C function.
    spec : FunctionSpec
        Its declaration.
    inputs : Mapping
        ``{argument name: (N, ...) samples}``.
    case : str
        What is fed, for the report.
    expected : str
        Expected status macro(s), alternatives separated by ``|``.
    overrides : Mapping
        Argument values replacing the sample's.
    model : RobotModel or None, optional
        With ``GT_OK`` the outputs must equal this model's evaluation; None: a non-OK
        status must leave the outputs untouched (:data:`~gtmodel.codegen.check.report.SENTINEL`).
    real : {"double", "float"}, optional
        Floating-point type of the C code.

    Returns
    -------
    StatusProbe
        Passed when the status is an expected one and the outputs are as required.
    """
    status, out = _call_row(cf, spec, inputs, 0, overrides)
    codes = [STATUS_CODES[e][0] for e in expected.split("|")]
    if status == 0 and model is not None:
        row = {a.name: np.asarray([overrides.get(a.name, inputs[a.name][0])]) for a in spec.args}
        ref = spec.reference(model, row) if spec.reference is not None else _casadi_reference(spec, model, row)
        fine = _diffs(spec, [np.reshape(o, (1, -1)) for o in out], ref, real)[3]
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


def edge_probes(generated: GeneratedCode, spec: FunctionSpec, cf, model: RobotModel, inputs, cache: dict) -> list[StatusProbe]:
    """The edge-case probes of one robot function (:func:`probe` each).

    Parameters
    ----------
    generated : GeneratedCode
        The generated library.
    spec : FunctionSpec
        The function.
    cf : CompiledFunction
        Its compiled C function.
    model : RobotModel
        The robot model.
    inputs : Mapping
        Its samples (:func:`sample_inputs`).
    cache : dict
        Poses shared between the functions of one check (boundary and singular poses).

    Returns
    -------
    list of StatusProbe
        Unreachable and far inputs, the workspace boundary and beyond, singular poses,
        non-finite inputs, invalid configurations and Newton starts.
    """
    probes = []
    real = generated.real
    statuses = {c.status for c in spec.checks}
    if spec.unreachable is not None:
        probes.append(probe(cf, spec, inputs, "unreachable input", "GT_UNREACHABLE", spec.unreachable(model)))
    elif spec.newton is not None:
        far = {a.name: np.full(s, 5.0) for a, s in zip(spec.args, generated.signatures[spec.name][0]) if a.kind == "vector" and not a.optional}
        probes.append(probe(cf, spec, inputs, "input far from any assembly", "GT_NOT_CONVERGED|GT_UNREACHABLE", far))
    # boundary and singular probes sit 1e-9 (1e-13) from the limit: meaningful in double precision only
    if generated.kind == "three_link" and real == "double" and any(a.name == "T" for a in spec.args):
        if "boundary" not in cache:
            cache["boundary"] = _stretched_pose(model, inputs["T"], 1 - BOUNDARY_MARGIN)
            cache["beyond"] = _stretched_pose(model, inputs["T"], 1 + BOUNDARY_MARGIN)
            cache["singular"] = _singular_pose(model, inputs["T"])
        conf0 = {"configuration": 0}
        if cache["beyond"] is not None and "GT_UNREACHABLE" in statuses:
            probes.append(probe(cf, spec, inputs, "just beyond the workspace boundary", "GT_UNREACHABLE", {"T": cache["beyond"], **conf0}))
        if cache["boundary"] is not None:
            probes.append(
                probe(cf, spec, inputs, "on the workspace boundary (arm stretched)", "GT_OK", {"T": cache["boundary"], **conf0}, model, real)
            )
        if "GT_SINGULAR" in statuses and cache["singular"] is not None:
            probes.append(probe(cf, spec, inputs, "singular pose", "GT_SINGULAR", {"T": cache["singular"], **conf0}))
    for a, size in zip(spec.args, generated.signatures[spec.name][0]):
        if a.kind in ("vector", "matrix"):
            probes.append(probe(cf, spec, inputs, f"NaN in {a.name}", "GT_BAD_ARGUMENT", {a.name: np.full(size, np.nan)}))
            probes.append(probe(cf, spec, inputs, f"Inf in {a.name}", "GT_BAD_ARGUMENT", {a.name: np.full(size, np.inf)}))
        elif a.kind == "configuration":
            for bad in (-1, 8):
                probes.append(probe(cf, spec, inputs, f"{a.name}={bad}", "GT_BAD_ARGUMENT", {a.name: bad}))
        else:
            probes.append(probe(cf, spec, inputs, f"{a.name}=0", "GT_BAD_ARGUMENT", {a.name: 0}))
    return probes

