"""The drive family of issue 49 taken through the tracking controller and the MPC as C, each on a plant 20 % off.

For each drive of ``models/drives.py`` (motor + gear + load, two-mass with a compliant shaft, flexible joint with
gravity, belt drive, ball-screw axis with a compliant coupling) the shipped ``codegen/mpc/drive_<drive>_mpc.toml``
(the problem's current limit as soft MPC rows) and ``codegen/controllers/drive_<drive>_tracking.toml`` are loaded
(their verified references solved), their loop step generated and compiled, and the C run against the file's
mismatched plant (inertias or masses +20 %, stiffness -20 % where the drive has them). Independent checks: the
feedforward alone on the same plant (the RMS ratio at most 0.5), the plant's own columns against every declared bound
(none exceeded by more than 1 %, counted by the check at the samples and between them, at the plant's substeps), the step's C against its CasADi Function at random arguments
(``check_loop_step``). The L1's drives with compliance are the shipped ``l1_mpc.toml`` / ``l1_tracking.toml``
(``tests/problems/test_mpc_check.py``, ``tests/test_cli_codegen.py``).
"""

from __future__ import annotations

import tomllib

import pytest

from gtmodel.codegen.check.loop_step import check_loop_step
from gtmodel.codegen.loop_step import mpc_step, tracking_step
from gtmodel.problems import loop_check
from gtmodel.problems.mpc_file import load_mpc_file
from gtmodel.problems.tracking_file import load_tracking_file

from ..conftest import REPO

FIXTURES = REPO / "tests" / "fixtures" / "user_models"
DRIVES = ["motor_gear_load", "two_mass", "flexible_joint", "belt", "ball_screw"]
ROUTES = {"mpc": (REPO / "codegen" / "mpc", "mpc", load_mpc_file, mpc_step),
          "tracking": (REPO / "codegen" / "controllers", "tracking", load_tracking_file, tracking_step)}


@pytest.mark.parametrize("route", sorted(ROUTES))
@pytest.mark.parametrize("drive", DRIVES)
def test_loop_files_declare_the_mismatch_and_the_current_row(drive, route):
    # read without solving: the plant 20 % off, the problem's current limit as the MPC's row (problem_constraints default)
    folder, suffix, _, _ = ROUTES[route]
    doc = tomllib.loads((folder / f"drive_{drive}_{suffix}.toml").read_text())
    factors = doc["check"]["parameter_factors"]
    assert doc["check"]["max_ratio"] == 0.5 and doc["check"]["parameter_factor"] == 1.0
    assert sorted(set(factors.values())) in ([0.8, 1.2], [1.2])
    assert doc.get("mpc", {}).get("problem_constraints", True) and "accept_unverified" not in doc["reference"]


@pytest.mark.slow  # solves the reference and compiles the step (MPC about 1-2 min, tracking about 20 s)
@pytest.mark.parametrize("route", sorted(ROUTES))
@pytest.mark.parametrize("drive", DRIVES)
def test_generated_c_tracks_and_keeps_every_declared_bound(drive, route, tmp_path):
    folder, suffix, load, step = ROUTES[route]
    setup = load(folder / f"drive_{drive}_{suffix}.toml")
    generated, library = loop_check.build_step(step(setup.controller, setup.name), tmp_path, f"gt_{setup.name}")
    report = check_loop_step(generated, n=50, seed=0)
    check = loop_check.closed_loop_check(setup, generated, library, label=route)
    bounds = {b.name: b for b in check.bounds}
    assert report.passed and not [n for n in setup.notes if "NOT verified" in n]  # a verified reference: no accept_unverified note
    assert "ind.i" in bounds and "src.v" in bounds  # the declared current limit counted on the plant
    assert [b.name for b in check.bounds if b.beyond_tolerance] == []
    assert check.bounds_between and [b.name for b in check.bounds_between if b.beyond_tolerance] == []  # at the plant's substeps
    assert not check.plant_diverged and check.ratio_to_feedforward <= 0.5
    assert [f for f in check.failures() if "step time" not in f] == []  # the step time: shared 2-core machine, reported


@pytest.mark.slow  # the refined solve of the fixture's lift (about 1 min)
def test_the_refined_flexible_plan_keeps_the_current_limit(tmp_path):
    # the fixture's lift refined to a verified plan (refine_on_failure, the default): its MPC (the current rows, the plant
    # 20 % off) once drew 11.1 A of 10 in the first period, under the plan's first 20 V sample held before the first
    # computed input arrived; the input holding the start at rest acts then now. References: the feedforward alone on the
    # same plant (ratio) and the plant's own current column against the declared 10 A.
    from .test_flexible_joint_loop import _loop

    tag = tmp_path.name
    move, mpc = FIXTURES / f"_test_refined_move_{tag}.toml", FIXTURES / f"_test_refined_mpc_{tag}.toml"  # beside the fixture
    move.write_text((FIXTURES / "flexible_move.toml").read_text().replace("refine_on_failure = false", "refine_on_failure = true"))
    mpc.write_text((FIXTURES / "flexible_mpc.toml").read_text().replace('problem = "flexible_move.toml"', f'problem = "{move.name}"')
                   .replace("accept_unverified = true", ""))
    try:
        setup = load_mpc_file(mpc)
    finally:
        move.unlink()
        mpc.unlink()
    check = _loop(setup)
    current = {b.name: b for b in check.bounds}["ind.i"]
    assert not [n for n in setup.notes if "NOT verified" in n] and check.ratio_to_feedforward < 0.5  # verified: no such note
    assert current.relative <= 0.01 and check.closed.u[0, 0] == pytest.approx(0.0, abs=1e-9)
