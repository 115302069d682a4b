"""A solve of an ``optimal_control`` declaration passes its verification settings to the transcription.

Independent check: the declared :class:`~gtmodel.modeling.Optimization` is inspected
directly (its ``verification_*`` fields and its instance dictionary) before and after two
solves with different settings, and each solve's verification reports the tolerance,
integrator and rtol it was given, not the other solve's.
"""

from __future__ import annotations

import dataclasses

import pytest

from gtmodel.modeling.ocp.methods import Collocation, MultipleShooting, Refinement
from gtmodel.problems import load_problem

from ..conftest import PROBLEMS_DIR

DOUBLE_INTEGRATOR = PROBLEMS_DIR / "benchmarks" / "double_integrator_min_time.toml"
FIELDS = ("verification_tolerance", "verification_rtol", "verification_integrator")


def _declared(opt):
    return {name: getattr(opt, name) for name in FIELDS}, {k for k in vars(opt) if k.startswith("verification")}


@pytest.mark.parametrize("method", [Collocation(elements=8), MultipleShooting(intervals=8)], ids=["collocation", "shooting"])
def test_solving_twice_with_other_settings_leaves_the_declaration_unchanged(method):
    decl = dataclasses.replace(load_problem(DOUBLE_INTEGRATOR).declaration, method=method)
    before = _declared(decl.optimization)
    first = dataclasses.replace(decl, refinement=Refinement(tolerance=0.5, integrator="idas", on_failure=False)).solve()
    second = dataclasses.replace(decl, refinement=Refinement(tolerance=0.05, rtol=1e-8, integrator="cvodes",
                                                             on_failure=False)).solve()
    assert _declared(decl.optimization) == before == ({name: None for name in FIELDS}, set())
    assert (first.verification.tolerance, first.verification.integrator) == (0.5, "idas (rtol 1e-06)")
    assert second.verification.tolerance == 0.05
    assert second.verification.integrator.startswith("cvodes") and second.verification.integrator.endswith("(rtol 1e-08)")


@pytest.mark.parametrize("within, refined", [(True, False), (False, True)])
def test_a_bound_exceeded_between_the_nodes_is_refined_from_like_a_failed_verification(monkeypatch, within, refined):
    # issue 49: a single solve that verifies but whose simulation exceeds a state bound between the nodes is refined
    # from (refine_on_failure), as a failed verification is; the single solve here is the real double integrator's,
    # its between-node check replaced by one that holds or not (the refinement itself: test_verification_bounds.py)
    from gtmodel.modeling.ocp.result import OptimizationResult
    from gtmodel.trajectory import model_ocp

    real, calls = model_ocp.solve_from_coarse, []

    def single(*args, **kwargs):
        result = real(*args, **kwargs)
        result.verification.bounds = {"within_tolerance": within, "max_scaled_violation": 0.0 if within else 0.05}
        return result

    def refine(*args, start: OptimizationResult, **kwargs):
        calls.append(start)
        return start

    monkeypatch.setattr(model_ocp, "solve_from_coarse", single)
    monkeypatch.setattr(model_ocp, "solve_refined", refine)
    # the file asks for refine = true; here a single solve with refine_on_failure (the default)
    decl = dataclasses.replace(load_problem(DOUBLE_INTEGRATOR).declaration, method=Collocation(elements=8), refinement=Refinement())
    result = decl.solve()
    assert str(result.status) == "optimal" and result.verification.passed
    assert len(calls) == int(refined) and all(c is result for c in calls)
