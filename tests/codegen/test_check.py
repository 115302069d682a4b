"""Self-check: compiled C against the Python evaluation of the same CasADi model.

Independent reference: the Python evaluation (``GantryTau3Kinematics.ik/fk/jacobian``,
``GantryTau3Dynamics.inverse_dynamics``, which run the CasADi Functions in CasADi's own
virtual machine), never the generated C.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from gtmodel.codegen import check_generated as check, generate
from gtmodel.codegen.check import (
    FK_TOLERANCE,
    IK_TOLERANCE,
    INVERSE_DYNAMICS_TOLERANCE,
    JACOBIAN_TOLERANCE,
    SENTINEL,
)
from gtmodel.codegen.robot import RobotModel
from gtmodel.errors import InputError
from gtmodel.robots.dynamics import GantryTau3Dynamics
from gtmodel.robots.kinematics import GantryTau3Kinematics

#: Required accuracy from the issue: 1e-12 m / rad (kinematics), 1e-9 N (dynamics).
REQUIRED = {
    "ik": 1e-12, "fk": 1e-12, "jacobian": 1e-12, "jacobian_inverse": 1e-12,
    "acceleration": 1e-9, "inverse_dynamics": 1e-9, "gravity": 1e-9,
}
#: Random inputs per function for every robot's acceptance check (the issue: 10^4).
N_POSES = 10_000
#: Largest fraction of the random F1 / six-link inputs the Python model may refuse (no convergence).
MAX_REFUSED_FRACTION = 0.02


def test_tolerances_are_the_required_ones():
    assert (IK_TOLERANCE, FK_TOLERANCE, JACOBIAN_TOLERANCE, INVERSE_DYNAMICS_TOLERANCE) == (1e-12, 1e-12, 1e-12, 1e-9)


@pytest.mark.parametrize("robot", ["L1", "D1"])
def test_check_passes_on_10000_random_reachable_poses(built, robot):
    gen, lib = built(robot)
    n = N_POSES
    report = check(gen, n=n, seed=0, library=lib)
    lines = report.summary_lines()
    assert report.passed, "\n".join(lines)
    assert report.n == n
    assert {f.name: f.max_abs_diff <= REQUIRED[f.name] for f in report.functions} == {k: True for k in REQUIRED}
    assert all(f.n_not_ok == 0 and f.n == n for f in report.functions)
    # every generated function was probed with unreachable, boundary and bad inputs
    probed = {(p.function, p.expected) for p in report.probes}
    cases = {(p.function, p.case) for p in report.probes}
    missing = [(n, e) for n in gen.functions for e in ("GT_UNREACHABLE", "GT_BAD_ARGUMENT") if (n, e) not in probed]
    missing += [
        (n, c)
        for n in ("ik", "jacobian", "inverse_dynamics", "gravity")
        for c in ("on the workspace boundary (arm stretched)", "just beyond the workspace boundary")
        if (n, c) not in cases
    ]
    assert not missing, missing
    assert ("jacobian", "GT_SINGULAR") in probed and ("inverse_dynamics", "GT_SINGULAR") in probed
    assert lines[1].startswith("ik: max |C - Python| = ") and lines[1].endswith(" m (tol 1e-12) OK")
    assert lines[-1] == "PASSED"


@pytest.mark.parametrize("robot", ["D1_six_link", pytest.param("F1", marks=pytest.mark.slow)])  # F1: ~20 s
def test_newton_functions_match_python(built, robot):
    """Six-link FK (eq. 4.15) and F1 IK/FK (eqs. 4.27-4.33) against the Python Newton solvers.

    Reference: ``SixLinkClosure.fk_solve`` / ``ik`` and ``F1Closure.ik`` / ``fk`` (CasADi's
    virtual machine, chunked NumPy iteration), never the generated C.
    """
    gen, lib = built(robot)
    report = check(gen, n=N_POSES, seed=1, library=lib)
    assert report.passed, "\n".join(report.summary_lines())
    assert report.n == N_POSES
    bad = [
        (f.name, f.max_abs_diff, f.n_not_ok, f.n, f.n_refused)
        for f in report.functions
        if not (
            f.max_abs_diff <= REQUIRED[f.name]
            and f.n_not_ok == 0
            and f.n + f.n_refused == N_POSES
            and f.n >= (1 - MAX_REFUSED_FRACTION) * N_POSES
        )
    ]
    assert not bad, bad  # (function, max |C - Python|, not ok, compared, refused)
    expected = {(p.function, p.expected) for p in report.probes}
    assert all((name, "GT_BAD_ARGUMENT") in expected for name in gen.functions)


def test_c_matches_python_on_a_workspace_pose_directly(built):
    """One pose, every output, against the NumPy wrappers (a readable spot check)."""
    gen, lib = built("L1")
    k = GantryTau3Kinematics("L1")
    dyn = GantryTau3Dynamics("L1", friction="exact")
    T = k.workspace_grid(0.1)[17]
    Td, Tdd = np.array([0.3, -0.2, 0.1]), np.array([1.0, 2.0, -3.0])
    ik = [lib["ik"](T, c) for c in range(8)]  # every configuration
    assert [status for status, _ in ik] == [0] * 8
    np.testing.assert_allclose([q for _, (q,) in ik], [k.ik(T, c) for c in range(8)], rtol=0, atol=IK_TOLERANCE)
    status, (J,) = lib["jacobian"](T, 0)
    assert status == 0
    np.testing.assert_allclose(J.reshape(3, 3), k.jacobian(T, 0), rtol=0, atol=JACOBIAN_TOLERANCE)  # row-major
    status, (T_back,) = lib["fk"](k.ik(T, 0), 1)
    assert status == 0
    np.testing.assert_allclose(T_back, k.fk(k.ik(T, 0), 1), rtol=0, atol=FK_TOLERANCE)
    status, (tau,) = lib["inverse_dynamics"](T, Td, Tdd, 0)
    assert status == 0
    np.testing.assert_allclose(tau, dyn.inverse_dynamics(T, Td, Tdd, 0), rtol=0, atol=INVERSE_DYNAMICS_TOLERANCE)


@pytest.mark.parametrize("name", ["ik", "jacobian", "inverse_dynamics"])
def test_unreachable_pose_gives_nonzero_status_and_untouched_output(built, name):
    gen, lib = built("L1")
    k = GantryTau3Kinematics("L1")
    T = k.workspace_bounds()[:, 1] + 5.0
    assert not k.in_workspace(T, limits=False)  # Python agrees: unreachable
    cf = lib[name]
    args = {"ik": (T, 0), "jacobian": (T, 0), "inverse_dynamics": (T, np.zeros(3), np.zeros(3), 0)}[name]
    out = [np.full(n, SENTINEL) for n in cf.sizes_out]
    status, out = cf(*args, out=out)
    assert status == 1  # GT_UNREACHABLE
    assert all(np.all(o == SENTINEL) for o in out)


def test_fk_of_non_intersecting_spheres_is_unreachable(built):
    gen, lib = built("L1")
    out = [np.full(3, SENTINEL)]
    status, out = lib["fk"](np.array([-9.0, 0.0, 9.0]), 1, out=out)
    assert status == 1 and np.all(out[0] == SENTINEL)


def test_check_detects_a_difference(built):
    """Negative control: a reference shifted by 10x the tolerance must fail the check."""
    gen, lib = built("L1")
    spec = gen.spec("ik")
    shifted = dataclasses.replace(
        spec, reference=lambda m, inp: {"q": spec.reference(m, inp)["q"] + 10 * IK_TOLERANCE}
    )
    gen2 = dataclasses.replace(gen, specs=(shifted,), functions=("ik",))
    report = check(gen2, n=50, library=lib)
    assert not report.passed
    assert report.functions[0].max_abs_diff == pytest.approx(10 * IK_TOLERANCE, rel=1e-2)
    assert report.summary_lines()[1].endswith("FAILED")


def test_check_uses_the_requested_friction_form(tmp_path):
    """The smooth (tanh) friction model is generated and checked as well."""
    gen = generate("L1", tmp_path / "src", functions=("inverse_dynamics",), friction="tanh")
    assert "friction tanh" in gen.version
    report = check(gen, n=100, build_dir=tmp_path / "build")
    assert report.passed, "\n".join(report.summary_lines())
    assert RobotModel(gen.parameters, "tanh").dynamics.friction == "tanh"


def test_call_rows_equals_single_calls(built):
    """The row loop of the check against one ``__call__`` per row (same C function)."""
    gen, lib = built("L1")
    k = GantryTau3Kinematics("L1")
    T = np.vstack([k.workspace_grid(0.1)[:5], k.workspace_bounds()[:, 1] + 5.0])  # last row unreachable
    conf = np.array([0, 1, 2, 3, 7, 0])
    status, (q,) = lib["ik"].call_rows(T, conf, fill=SENTINEL)
    single = [lib["ik"](T[i], int(conf[i]), out=[np.full(3, SENTINEL)]) for i in range(len(T))]
    assert list(status) == [s_i for s_i, _ in single]
    np.testing.assert_array_equal(q, [q_i for _, (q_i,) in single])
    assert list(status) == [0, 0, 0, 0, 0, 1] and np.all(q[-1] == SENTINEL)


@pytest.mark.slow  # compiles F1 (~14 CPU-s); the F1 check row is slow too
def test_call_rows_passes_null_for_non_finite_optional_rows(built):
    """F1 IK: a NaN row of the optional start q0 is NULL, i.e. the default start."""
    gen, lib = built("F1")
    f1 = gen.model().closure
    T_h, R_h = f1.home
    q0 = np.vstack([f1.q_home, np.full(6, np.nan)])
    status, (q,) = lib["ik"].call_rows(np.vstack([T_h, T_h]), np.vstack([R_h.ravel()] * 2), q0)
    assert list(status) == [0, 0]
    np.testing.assert_allclose(q[0], f1.q_home, rtol=0, atol=IK_TOLERANCE * 100)
    np.testing.assert_allclose(q[1], q[0], rtol=0, atol=IK_TOLERANCE * 100)


def test_call_rows_refuses_wrong_row_sizes(built):
    from gtmodel.errors import CodegenError

    gen, lib = built("L1")
    with pytest.raises(CodegenError, match="T: expected rows of 3 values"):
        lib["ik"].call_rows(np.zeros((2, 4)), np.zeros(2, dtype=int))
    with pytest.raises(CodegenError, match="configuration: expected 2 values"):
        lib["ik"].call_rows(np.zeros((2, 3)), np.zeros(3, dtype=int))


@pytest.mark.parametrize("n", [0, -3, 2.5, True])
def test_bad_sample_count(built, n):
    gen, lib = built("L1")
    with pytest.raises(InputError, match="n:"):
        check(gen, n=n, library=lib)
