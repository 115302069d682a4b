"""benchmarks/bench_modelica_front_ends.py: its pymoca side on a few of its jobs, and the rumoca side skipped with a message.

Fast: two files and one probe, one run each; rumoca is neither needed nor run (it lives in a separate venv).
"""

from __future__ import annotations

import importlib.util

import pytest

from .conftest import benchmark_module

pytest.importorskip("pymoca")


@pytest.fixture(scope="module")
def bench():
    """benchmarks/bench_modelica_front_ends.py as a module."""
    with benchmark_module("bench_modelica_front_ends") as module:
        yield module


@pytest.fixture(scope="module")
def jobs(bench):
    """The benchmark's jobs (files, library classes, probes)."""
    return bench.make_jobs()


def test_the_jobs_cover_the_shipped_files_the_library_and_the_fixtures(bench, jobs):
    """Every shipped .mop class, the MSL subset's classes and the test fixtures are read; a .mop as the model gtmodel reads."""
    labels = {j["label"] for j in jobs}
    kinds = {j["kind"] for j in jobs}
    mop = next(j for j in jobs if j["label"] == "problems/optimica/double_integrator_min_time.mop:DoubleIntegrator.MinTime")
    assert {"problems/optimica/msl_drive_min_time.mop:MinTime", "tests/exchange/data/oscillator.mo:Oscillator",
            "Modelica.mo:Modelica.Mechanics.Rotational.Components.Inertia"} <= labels
    assert {"mo", "mop", "library", "probe"} <= kinds and "optimization" not in mop["text"] and len(bench.PROBES) >= 10


def test_pymoca_side_counts_a_file_and_refuses_a_short_connector_class(bench, jobs):
    """The oscillator: 3 unknowns, 3 equations, 2 states, 1 input; pymoca 0.12 refuses RealInput = input Real (rumoca reads it)."""
    chosen = [j for j in jobs if j["label"] in ("tests/exchange/data/oscillator.mo:Oscillator",
                                                 "probe: short connector class (connector RealInput = input Real)")]
    side = bench.pymoca_side(chosen, 1)
    osc = side["results"]["tests/exchange/data/oscillator.mo:Oscillator"]
    probe = side["results"]["probe: short connector class (connector RealInput = input Real)"]
    summary = bench.summarise(chosen, side, {"skipped": "test"}, {})
    assert osc["ok"] and {k: osc["counts"][k] for k in ("unknowns", "equations", "states", "inputs")} == {
        "unknowns": 3, "equations": 3, "states": 2, "inputs": 1}
    assert not probe["ok"] and osc["median_s"] > 0 and summary["mo"]["pymoca_accepts"] == 1


@pytest.mark.skipif(importlib.util.find_spec("rumoca") is not None, reason="rumoca importable here: the side runs in process")
def test_rumoca_side_is_skipped_with_a_message_without_rumoca(bench, jobs, tmp_path):
    """No rumoca here and no Python with it: the side is skipped, the message saying how to get it."""
    side = bench._run_rumoca(jobs[:1], 1, str(tmp_path / "no_python"))
    assert "pip install rumoca" in side["skipped"]


def test_a_file_naming_gantry_tau_gets_the_shipped_package_as_gtmodel_adds_it(bench, jobs):
    """opt_robot.mop names GantryTau.L1: its job carries the package, and pymoca flattens it (7 states, 3 robot.tau left open)."""
    robot = [j for j in jobs if j["label"] == "problems/optimica/opt_robot.mop:opt_robot"]
    assert len(robot) == 1 and robot[0]["robots"].endswith("GantryTau.mo")
    assert not next(j for j in jobs if j["label"] == "tests/exchange/data/oscillator.mo:Oscillator")["robots"]
    entry = bench.pymoca_side(robot, 1)["results"][robot[0]["label"]]
    assert entry["ok"] and {k: entry["counts"][k] for k in ("unknowns", "equations", "states")} == {
        "unknowns": 31, "equations": 28, "states": 7}
