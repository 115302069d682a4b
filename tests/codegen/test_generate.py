"""C generation: files, header declarations, version string, declarations of new functions.

Independent reference: the CasADi model evaluated from Python (kinematics/dynamics
Functions) for values; the issue text for the required C signatures and status codes.
"""

from __future__ import annotations

import dataclasses
import re

import casadi as ca
import numpy as np
import pytest

import gtmodel
from gtmodel.codegen import FUNCTION_SPECS, FunctionSpec, check_generated as check, compile_shared, generate, load_library, parameter_hash
from gtmodel.codegen.check import SENTINEL
from gtmodel.codegen.declarations import ArgSpec, OutputSpec
from gtmodel.codegen.writer import _hoist_invariants, _renamed, _residual_part
from gtmodel.codegen.robot import RobotModel, load_robot
from gtmodel.codegen.specs import F1_SPECS
from gtmodel.errors import CodegenError, InputError
from gtmodel.robots.parameters import load_parameters

#: Generic functions are compared with the CasADi Function evaluated from Python [m/s, m/s^2].
CART_ACCELERATION_TOLERANCE = 1e-10
#: Newton steps per block of the Python F1 solvers (``F1Closure.ik``/``fk``).
F1_BLOCK = 4

EXPECTED_SIGNATURES = [
    "int gt_L1_ik(const double T[3], int configuration, double q[3]);",
    "int gt_L1_fk(const double q[3], int solution, double T[3]);",
    "int gt_L1_jacobian(const double T[3], int configuration, double J[9]);",
    "int gt_L1_jacobian_inverse(const double T[3], int configuration, double Jinv[9]);",
    "int gt_L1_acceleration(const double T[3], const double T_dot[3], const double q_ddot[3], int configuration, double T_ddot[3]);",
    "int gt_L1_inverse_dynamics(const double T[3], const double T_dot[3], const double T_ddot[3], "
    "int configuration, double tau[3]);",
    "int gt_L1_gravity(const double T[3], int configuration, double tau[3]);",
]


def test_files_exist_and_header_declares_all_functions(built):
    gen, _ = built("L1")
    assert gen.prefix == "gt_L1"
    assert gen.functions == ("ik", "fk", "jacobian", "jacobian_inverse", "acceleration", "inverse_dynamics", "gravity")
    empty = [p for p in gen.files if not (p.exists() and p.stat().st_size > 0)]
    assert not empty, empty
    assert gen.header.name == "gt_L1.h" and gen.source.name == "gt_L1.c"
    header = gen.header.read_text()
    missing = [sig for sig in EXPECTED_SIGNATURES if sig not in header]
    assert not missing, missing
    macros = [
        ("GT_OK", 0), ("GT_UNREACHABLE", 1), ("GT_SINGULAR", 2), ("GT_DEGENERATE", 3), ("GT_BAD_ARGUMENT", 4), ("GT_NOT_CONVERGED", 6)
    ]
    missing = [macro for macro, value in macros if not re.search(rf"#define {macro} {value}\b", header)]
    assert not missing, missing
    assert "ROW-MAJOR" in header
    # the public header is plain C: no CasADi types
    assert "casadi_real" not in header and "casadi_int" not in header and "#include" not in header


def test_version_string_names_versions_and_parameter_hash(built):
    gen, lib = built("L1")
    assert f"gtmodel {gtmodel.__version__}" in gen.version
    assert f"casadi {ca.__version__}" in gen.version
    assert gen.parameter_hash in gen.version
    assert lib.version() == gen.version
    assert f'#define GT_L1_VERSION "{gen.version}"' in gen.header.read_text()


def test_parameter_hash_identifies_the_numbers():
    p = load_parameters("L1")
    changed = dataclasses.replace(p, kinematics=dataclasses.replace(p.kinematics, L=p.kinematics.L + np.array([1e-12, 0, 0])))
    assert parameter_hash(p) == parameter_hash(load_parameters("L1"))
    assert parameter_hash(p) != parameter_hash(changed)
    assert parameter_hash(p) != parameter_hash(load_parameters("D1"))


def test_wrapper_uses_fixed_stack_arrays_only(built):
    gen, _ = built("L1")
    src = gen.source.read_text()
    assert "malloc" not in src and "static double" not in src
    missing = [
        name for name in gen.functions if not (f"#define GT_L1_{name.upper()}_SZ_W " in src and name in gen.work_sizes)
    ]
    assert not missing, missing


def test_subset_and_custom_prefix_compile_warning_free(tmp_path):
    gen = generate("D1", tmp_path / "src", functions=("ik",), prefix="robot_d1")
    assert gen.functions == ("ik",)
    header = gen.header.read_text()
    assert "int robot_d1_ik(const double T[3], int configuration, double q[3]);" in header
    assert "robot_d1_fk" not in header
    lib = load_library(gen, compile_shared(gen, tmp_path / "build", werror=True))
    status, (q,) = lib["ik"](np.array([0.3, 0.2, -0.1]) + 0.0, 0)
    assert status in (0, 1)


@pytest.mark.parametrize(
    "kwargs, match",
    [
        ({"functions": ("ik", "nope")}, "unknown function 'nope'"),
        ({"prefix": "1bad-prefix"}, "prefix"),
        ({"friction": "magic"}, "friction"),
        ({"functions": ()}, "at least one"),
    ],
)
def test_bad_arguments_are_refused(tmp_path, kwargs, match):
    with pytest.raises(InputError, match=match):
        generate("L1", tmp_path, **kwargs)


def test_declaration_mismatch_is_a_codegen_error(tmp_path):
    bad = dataclasses.replace(FUNCTION_SPECS["ik"], name="ik2", args=FUNCTION_SPECS["ik"].args[:1])
    with pytest.raises(CodegenError, match="not fed"):
        generate("L1", tmp_path, functions=(bad,))


def test_new_function_is_a_declaration(tmp_path):
    """A function not shipped (cart accelerations, eq. 6.6) added by declaring it only.

    Reference: the same CasADi Function evaluated from Python (the generic fallback).
    """
    spec = FunctionSpec(
        name="cart_acceleration",
        build=lambda m: m.kinematics.cart_acceleration_function,
        args=(
            ArgSpec("T", "vector", "T", "TCP position [m]"),
            ArgSpec("T_dot", "vector", "T_dot", "TCP velocity [m/s]"),
            ArgSpec("T_ddot", "vector", "T_ddot", "TCP acceleration [m/s^2]"),
            ArgSpec("configuration", "configuration", "s", "IK configuration 0-7"),
        ),
        outputs=(OutputSpec("q_dot", "q_dot", "cart velocities [m/s]"), OutputSpec("q_ddot", "q_ddot", "cart accelerations [m/s^2]")),
        doc="Cart velocities and accelerations for a TCP motion (Dressler (2012), eq. 6.6).",
        tolerance=CART_ACCELERATION_TOLERANCE,
        unit="m/s, m/s^2",
    )
    gen = generate("L1", tmp_path / "src", functions=("ik", spec))
    assert (
        "int gt_L1_cart_acceleration(const double T[3], const double T_dot[3], const double T_ddot[3], "
        "int configuration, double q_dot[3], double q_ddot[3]);" in gen.header.read_text()
    )
    report = check(gen, n=200, build_dir=tmp_path / "build")
    assert report.passed, "\n".join(report.summary_lines())
    assert report.functions[1].max_abs_diff <= CART_ACCELERATION_TOLERANCE


def test_header_documents_units_sizes_statuses_and_newton_bounds(generated):
    """The F1 header: units, array sizes, status codes, the Newton bounds, version and hash."""
    gen = generated("F1")
    header = gen.header.read_text()
    assert "int gt_F1_ik(const double T[3], const double R[9], const double q0[6], double q[6], int *iterations);" in header
    assert "int gt_F1_fk(const double q[6], const double T0[3], const double R0[9], double T[3], double R[9], int *iterations);" in header
    assert re.search(r"#define GT_F1_IK_MAX_ITER 20\b", header) and re.search(r"#define GT_F1_FK_TOLERANCE 1e-13\b", header)
    assert "q0[6] (may be NULL)" in header and "[m, rad]" in header and "ROW-MAJOR" in header
    assert "GT_NOT_CONVERGED" in header and f'#define GT_F1_PARAMETER_HASH "{gen.parameter_hash}"' in header
    assert "typedef double gt_F1_real;" in header and "no heap allocation" in header


@pytest.mark.parametrize("robot", ["D1_six_link", "F1"])
def test_newton_loops_are_bounded(generated, robot):
    """No unbounded branch: no while loop; every Newton loop runs k = 0 .. MAX_ITER."""
    gen = generated(robot)
    src = gen.source.read_text()
    assert "while" not in src and "goto" not in src
    bad = [
        (name, tol, max_iter)
        for name, (tol, max_iter) in gen.newton.items()
        if not (
            f"for (k = 0; k <= {gen.prefix.upper()}_{name.upper()}_MAX_ITER; ++k)" in src and max_iter == 20 and tol > 0
        )
    ]
    assert not bad, bad


@pytest.mark.parametrize("name", ["ik", "fk"])
def test_f1_loop_hoists_invariants_and_tests_the_residual_alone(generated, name):
    """F1 loops: the fixed-input part once before the loop, the residual alone at the tests."""
    gen = generated("F1")
    src = gen.source.read_text()
    body = src[src.index(f"int gt_F1_{name}(") :]
    body = body[: body.index("\n}\n")]
    loop = body.index("for (k = 0;")
    assert 0 < body.index(f"gt_F1_cg_{name}_invariant(") < loop
    assert body.index(f"gt_F1_cg_{name}_residual(") > loop
    assert f"k % {F1_BLOCK} == 0" in body


def test_f1_casadi_helpers_are_inlined(generated):
    gen = generated("F1")
    casadi_src = gen.casadi_source.read_text()
    assert "static casadi_real casadi_sq(" in casadi_src  # inlined helper, not a PLT call


@pytest.mark.parametrize("name", ["ik", "fk"])
def test_cse_hoisting_and_residual_part_keep_every_value(name):
    """``cse``, ``extract_parametric`` and the pruned residual change no bit of the F1 step.

    Reference: the declared step Function (the Python model's own step graph) evaluated by
    CasADi's virtual machine on random iterates near the home pose.
    """

    model = RobotModel(load_robot("F1"))
    nl = F1_SPECS[name].newton
    step = nl.step(model)
    parts = _hoist_invariants({"step": _renamed(step, "s")}, "inv")
    residual = _residual_part(parts["step"], "r")
    rng = np.random.default_rng(5)
    f1 = model.closure
    for _ in range(20):
        if name == "ik":
            T_h, R_h = f1.home
            fixed = {"T": T_h + rng.uniform(-0.01, 0.01, 3), "R": R_h}
            x = f1.q_home[[1, 3, 2, 4, 5]] + rng.uniform(-0.01, 0.01, 5)
        else:
            T_h, R_h = f1.home
            fixed = {"q": f1.q_home + rng.uniform(-0.005, 0.005, 6)}
            x = np.concatenate([T_h, R_h.T.ravel()])  # column-major R
        ref = step(x=x, **fixed)
        pre = parts["invariant"](**fixed)["pre"]
        got = parts["step"](x=x, pre=pre, **fixed)
        for out in ("x_next", "residual"):
            np.testing.assert_array_equal(np.asarray(got[out]), np.asarray(ref[out]))
        np.testing.assert_array_equal(np.asarray(residual(x=x, pre=pre, **fixed)["residual"]), np.asarray(ref["residual"]))


def test_non_convergence_gives_status_and_leaves_outputs(tmp_path):
    """Six-link FK (eq. 4.15) limited to 1 Newton step: GT_NOT_CONVERGED, outputs untouched.

    Reference: the Python FK needs 2 iterations on the D1 workspace (tests/robots/test_six_link.py).
    """
    from gtmodel.robots.kinematics import GantryTau3Kinematics

    gen = generate("D1_six_link", tmp_path / "src", functions=("fk",), max_iter=1)
    assert gen.newton == {"fk": (1e-12, 1)}
    lib = load_library(gen, compile_shared(gen, tmp_path / "build", werror=True))
    k = GantryTau3Kinematics("D1")
    q = k.ik(k.workspace_grid(0.1)[5])
    out = [np.full(3, SENTINEL), np.full(9, SENTINEL)]
    status, out = lib["fk"](q, 0, 1, out=out)
    assert status == 6  # GT_NOT_CONVERGED
    assert lib["fk"].iterations.value == 1
    assert all(np.all(o == SENTINEL) for o in out)


@pytest.mark.parametrize(
    "kwargs, match",
    [
        ({"real": "long double"}, "real"),
        ({"newton_tolerance": -1.0}, "newton_tolerance"),
        ({"max_iter": 0}, "max_iter"),
        ({"newton_check_every": 0}, "newton_check_every"),
        ({"functions": ("inverse_dynamics",)}, "unknown function 'inverse_dynamics' for a six_link robot"),
    ],
)
def test_bad_generation_options_are_refused(tmp_path, kwargs, match):
    with pytest.raises(InputError, match=match):
        generate("D1_six_link", tmp_path, **kwargs)


def test_unknown_robot_is_a_parameter_error(tmp_path):
    from gtmodel.errors import ParameterError

    with pytest.raises(ParameterError, match="unknown robot 'T9'"):
        generate("T9", tmp_path)


def test_calibrated_parameters_toml_generates_and_matches(tmp_path):
    """A calibration's parameters.toml (3-link set) generates C that matches its Python model.

    Reference: ``GantryTau3Kinematics``/``GantryTau3Dynamics`` of the loaded file.
    """
    from pathlib import Path

    from gtmodel.cli import main

    problem = Path(__file__).resolve().parents[2] / "problems" / "l1_calibration.toml"
    assert main(["solve", str(problem), "--out", str(tmp_path / "cal"), "--no-plots", "-q"]) == 0
    gen = generate(tmp_path / "cal" / "parameters.toml", tmp_path / "src", functions=("ik", "jacobian", "inverse_dynamics"))
    assert gen.prefix == "gt_l1_calibration_calibrated"
    assert gen.parameter_hash != parameter_hash(load_parameters("L1"))
    report = check(gen, n=500, build_dir=tmp_path / "build")
    assert report.passed, "\n".join(report.summary_lines())
