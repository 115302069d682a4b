"""The condensed collocation of benchmarks/bench_condensed.py solves gtmodel's NLP (the same discretisation).

Independent check: gtmodel's own transcription (its variables include the collocation states) solved by IPOPT
on the same problem and mesh; the condensed NLP (the collocation states eliminated by Newton's method, its
derivatives by the implicit function theorem) must reach the same optimum.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import pytest

from gtmodel.modeling.ocp.methods import Refinement
from gtmodel.problems import load_problem
from gtmodel.trajectory.point_to_point import solve_point_to_point

from .conftest import benchmark_module

ROOT = Path(__file__).resolve().parents[1]
#: The benchmark's mesh (on 12 elements, h = 0.056 s, the element's Newton iteration from the straight line fails near
#: the friction's steep tanh and neither solver converges: the condensed NLP is not robust on coarse meshes).
ELEMENTS = 50


@pytest.fixture(scope="module")
def bench():
    """benchmarks/bench_condensed.py as a module (its folder on the path, for bench_solve and bench_mpc)."""
    with benchmark_module("bench_condensed") as module:
        yield module


@pytest.fixture(scope="module")
def problem(bench, tmp_path_factory):
    """L1 minimum time on ELEMENTS elements: its export and gtmodel's IPOPT solve (the reference).

    The reference stays on the export's mesh (no refinement on a failed verification: the
    50-element plan's forces, clipped between the points, deviate 0.015 and the shipped
    problem refines it), so both solve the same NLP."""
    decl = load_problem(ROOT / "problems" / "l1_time_optimal.toml").declaration
    decl = dataclasses.replace(decl, elements=ELEMENTS, refinement=Refinement(on_failure=False))
    folder = bench.export_acados(decl, tmp_path_factory.mktemp("condensed")).parent
    return folder, solve_point_to_point(bench.with_solver(decl, "ipopt")).result


@pytest.mark.slow  # the condensed NLP interpreted: about 14 s for both solvers
@pytest.mark.parametrize("solver", ["ipopt", "fatrop"])
def test_condensed_optimum_is_the_transcriptions(bench, problem, solver):
    """Condensed, interpreted (no compiler): gtmodel's IPOPT optimum (final time) to 1e-7 relative, both successful."""
    folder, reference = problem
    cpu, iterations, final_time, status, _ = bench.run_condensed(bench.condensed_solver(folder, solver, jit=False))
    assert str(reference.status) in ("optimal", "check_failed")  # solved; the verdict is the refinement's matter
    assert status in ("Solve_Succeeded", "SOLVER_RET_SUCCESS"), status
    assert abs(final_time - reference.final_time) <= 1e-7 * reference.final_time
