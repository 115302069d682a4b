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

from gtmodel.modeling.ocp.refinement import ANCHOR_DEVIATION, ANCHOR_END, WORSE
from gtmodel.problems import load_problem, run_problem

REPO = Path(__file__).resolve().parents[2]
REFERENCES = json.loads((REPO / "tests" / "problems" / "data" / "drive_references.json").read_text())
DRIVES = ["drive_motor_gear_load", "drive_two_mass", "drive_flexible_joint", "drive_belt", "drive_ball_screw"]


@pytest.mark.parametrize("name, states", [
    ("drive_motor_gear_load", ["ind.i", "emf.phi", "rotor.w"]),
    ("drive_two_mass", ["ind.i", "emf.phi", "rotor.w", "load.w", "friction.phi_rel"]),
    ("drive_flexible_joint", ["ind.i", "emf.phi", "rotor.w", "link.phi", "link.w"]),
    ("drive_belt", ["ind.i", "emf.phi", "rotor.w", "payload.s", "payload.v"]),
    ("drive_ball_screw", ["ind.i", "rotor.w", "coupling.phi_rel", "screw_j.phi", "screw_j.w"]),
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


# The flexible joint's refinement path depends on the OpenBLAS kernel that MUMPS calls inside IPOPT (pass 2 from the same
# pass 1: 0.3332263 under SkylakeX, 0.3329877 under Haswell). It used to end acceptable at +0.27 % under SkylakeX: its passes
# stopped at IPOPT's acceptable level in crawls, not at minima. Since such a stop is continued warm to IPOPT's tolerance
# (refinement.POLISH_CPU_S; issue 49), measured 2026-11-26 with OPENBLAS_CORETYPE on one AVX-512 machine: SkylakeX optimal
# 0.3328774 (-0.29 %, 43 CPU-s), Haswell 0.3327163 (-0.34 %, 51 CPU-s), Sandybridge 0.3327225 (-0.34 %, 40 CPU-s), verified.


@pytest.mark.slow  # 3 to 55 CPU-s each: a solve, its verification and refinement from it (refine_on_failure)
@pytest.mark.parametrize("name", DRIVES)
def test_drive_minimum_time_is_within_half_a_percent_of_the_reference(name, tmp_path):
    cpu = time.process_time()
    outcome = run_problem(REPO / "problems" / f"{name}.toml", tmp_path / "out", plots=False)
    cpu = time.process_time() - cpu
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    reference = REFERENCES[name].get("objective", REFERENCES[name]["final_time"])  # the minimum time's objective is T
    assert summary["objective"] == pytest.approx(reference, rel=5e-3)
    passes = summary.get("refinement", [])
    tol = summary["verification"]["tolerance"]
    feasible = [e["objective"] for e in passes if e.get("end_deviation", 1.0) <= ANCHOR_END and e.get("max_bound_violation", 0.0) <= tol
                and e.get("max_scaled_deviation", 1.0) <= ANCHOR_DEVIATION]
    # never worse than a pass feasible by simulation (its end reached, the current limit kept between the nodes, its
    # states following their simulation), by more than the rejection margin
    assert not feasible or summary["objective"] <= min(feasible) + WORSE * abs(min(feasible))
    assert cpu <= 120.0  # issue 49: the whole process within 120 CPU-s
    assert str(outcome.status) == "optimal" and summary["verification"]["passed"] is True
    # issue 49 item 1: the current limit kept between the nodes (the verifying simulation within the tolerance of it),
    # refinement splitting where it is not; the flexible joint needs 13 passes (66 user + 2 system CPU-s under SkylakeX),
    # within the default pass limit of 30 (defaults["ocp.refine_max_passes"])
    assert summary["verification"]["bounds"]["within_tolerance"]
