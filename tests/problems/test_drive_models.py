"""The drive family of ``models/drives.py`` and ``problems/drive_*.toml``: minimum time with voltage and current limits.

Independent reference: ``benchmarks/drive_references.py``, a direct multiple-shooting solve
written in plain CasADi on the hand-written ODEs (no gtmodel code), the current bound enforced
at every integration step; its values are kept in ``tests/problems/data/drive_references.json``. The belt drive's
objective adds an energy term (``final_time + 1e-4 * integral(src_v^2)``): its objective is compared, not its final time.
"""

from __future__ import annotations

import json
import time
from pathlib import Path

import pytest

from gtmodel.modeling.ocp.refinement import ANCHOR_END, WORSE
from gtmodel.problems import load_problem, run_problem

REPO = Path(__file__).resolve().parents[2]
REFERENCES = json.loads((REPO / "tests" / "problems" / "data" / "drive_references.json").read_text())
DRIVES = ["drive_motor_gear_load", "drive_two_mass", "drive_flexible_joint", "drive_belt"]


@pytest.mark.parametrize("name, states", [
    ("drive_motor_gear_load", ["ind.i", "emf.phi", "rotor.w"]),
    ("drive_two_mass", ["ind.i", "emf.phi", "rotor.w", "load.w", "friction.phi_rel"]),
    ("drive_flexible_joint", ["ind.i", "emf.phi", "rotor.w", "link.phi", "link.w"]),
    ("drive_belt", ["ind.i", "emf.phi", "rotor.w", "payload.s", "payload.v"]),
])
def test_drive_model_is_reduced_to_its_states(name, states):
    # the composed models are of index 2 (the gear ties two angles); reduction keeps these states
    problem = load_problem(REPO / "problems" / f"{name}.toml")
    assert problem.declaration.optimization.model.flatten().x_names == states


@pytest.mark.parametrize("name", DRIVES)
def test_drive_reference_is_converged_in_its_mesh(name):
    # the reference's own discretisation error, O(1/N) (a switch inside a piecewise-constant interval), estimated
    # from its two finest meshes: |T_fine - T_coarse| N_coarse / (N_fine - N_coarse), at most a quarter of 1 %
    (n_c, t_c), (n_f, t_f) = sorted(((int(k), v) for k, v in REFERENCES[name]["by_intervals"].items()))[-2:]
    assert REFERENCES[name]["status"] == "Solve_Succeeded"
    assert abs(t_f - t_c) * n_c / (n_f - n_c) <= 2.5e-3 * t_f


#: The flexible joint's refinement path depends on the CPU, not on the process: on the BLAS kernel that CasADi's bundled
#: OpenBLAS (DYNAMIC_ARCH) picks for it, which MUMPS calls inside IPOPT. Pass 1 is the same to 10 digits under every
#: kernel; pass 2 (80 elements, 31 to 490 IPOPT iterations from pass 1) amplifies the round-off. Measured 2026-11-25
#: with OPENBLAS_CORETYPE on one AVX-512 machine: SkylakeX (its own kernel) pass 2 0.3332263, the path of CI's slow
#: run, ending acceptable 0.3347391 (+0.27 %; 0.3358544, +0.6 %, before an acceptable pass was re-solved), 91-96 CPU-s;
#: Haswell pass 2 0.3329877, the path of the "alone" run, optimal 0.3327827 (-0.32 %, 30 CPU-s: the test passes);
#: Sandybridge optimal 0.3334184 (16 CPU-s); Prescott acceptable 0.3360905 (+0.67 %). The same problem twice in one
#: process, after the other drives, by the CLI and under PYTHONHASHSEED 0 and 1 repeats every pass to 10 digits.
FLEXIBLE_NOT_REPEATABLE = pytest.mark.xfail(strict=False, reason="the flexible joint's refinement path depends on the CPU's "
                                            "OpenBLAS kernel (pass 2 from the same pass 1: 0.3332263 under SkylakeX, "
                                            "0.3329877 under Haswell); on AVX-512 it ends acceptable at +0.27 %, on AVX2 "
                                            "optimal at -0.32 % (issue 49)")


@pytest.mark.slow  # 3 to 100 CPU-s each: a solve, its verification and refinement from it (refine_on_failure)
@pytest.mark.parametrize("name", [pytest.param(d, marks=FLEXIBLE_NOT_REPEATABLE) if d == "drive_flexible_joint" else d for d in DRIVES])
def test_drive_minimum_time_is_within_half_a_percent_of_the_reference(name, tmp_path):
    cpu = time.process_time()
    outcome = run_problem(REPO / "problems" / f"{name}.toml", tmp_path / "out", plots=False)
    cpu = time.process_time() - cpu
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    reference = REFERENCES[name].get("objective", REFERENCES[name]["final_time"])  # the minimum time's objective is T
    assert summary["objective"] == pytest.approx(reference, rel=5e-3)
    passes = summary.get("refinement", [])
    tol = summary["verification"]["tolerance"]
    feasible = [e["objective"] for e in passes if e.get("end_deviation", 1.0) <= ANCHOR_END and e.get("max_bound_violation", 0.0) <= tol]
    # never worse than a pass feasible by simulation (its end reached, the current limit kept between the nodes),
    # by more than the rejection margin
    assert not feasible or summary["objective"] <= min(feasible) + WORSE * max(1.0, min(feasible))
    assert cpu <= 120.0  # issue 49: the whole process within 120 CPU-s
    assert str(outcome.status) == "optimal" and summary["verification"]["passed"] is True
