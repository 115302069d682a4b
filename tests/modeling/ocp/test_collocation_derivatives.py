"""Assembled NLP derivatives: compiled against interpreted, banded against one shared final time."""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

from gtmodel.modeling import CollocationTranscription, Optimization
from gtmodel.modeling.dae import casadi_name

from .._builders import double_integrator, rest_to_rest
from .test_optimization import _free_parameter_problem


def _values(tr, function, rng):
    args = [rng.uniform(0.5, 1.5, tr._lbw.size), tr.dae.p_value]
    if function == "nlp_hess_l":
        args += [1.3, rng.standard_normal(tr._lbg.size)]
    out = tr.solver.get_function(function)(*args)
    return np.array(ca.DM(out[-1] if isinstance(out, (list, tuple)) else out))


@pytest.mark.parametrize("banded", [False, True])
@pytest.mark.parametrize("function", ["nlp_jac_g", "nlp_hess_l"])
def test_compiled_and_banded_derivatives_equal_casadis(cache, function, banded):
    # second method: CasADi differentiating the whole NLP graph (same layout), at a random point
    kw = dict(elements=3, points=2, nominal={"c": 0.5}, banded=banded)
    a = CollocationTranscription(_free_parameter_problem(), derivatives="assembled", compile=True, **kw)
    b = CollocationTranscription(_free_parameter_problem(), derivatives="casadi", **kw)
    assert a.evaluation.startswith("compiled C")
    va, vb = _values(a, function, np.random.default_rng(0)), _values(b, function, np.random.default_rng(0))
    np.testing.assert_allclose(va, vb, rtol=0, atol=1e-12)


def test_second_transcription_in_a_process_reuses_the_compiled_library(cache):
    # one library per model: a second mesh size neither generates nor compiles again
    CollocationTranscription(_free_parameter_problem(), elements=3, points=2, compile=True)
    again = CollocationTranscription(_free_parameter_problem(), elements=7, points=2, compile=True)
    assert "already loaded" in again.evaluation


def _min_time(banded):
    m, x, v, u = double_integrator()
    opt = Optimization(m, final_time=1.5, free_final_time=True, final_time_bounds=(0.5, 4.0))
    opt.set_bounds(u, -1.0, 1.0)
    opt.set_objective(mayer=opt.final_time)
    rest_to_rest(opt, x, v)
    return CollocationTranscription(opt, elements=20, points=3, banded=banded).solve()


@pytest.mark.parametrize("banded", [False, True])
def test_final_time_copies_give_the_bang_bang_optimum(banded):
    # closed form: rest to rest over 1 with |u| <= 1 takes 2 s (bang-bang)
    res = _min_time(banded)
    assert res.status == "optimal"
    assert res.final_time == pytest.approx(2.0, rel=1e-6)


def test_banded_layout_copies_the_final_time_per_element():
    # the layout itself: one copy per element, one bounded, tied by N - 1 equalities
    opt = _free_parameter_problem()
    tr = CollocationTranscription(opt, elements=4, points=2, banded=True)
    copies = [i for i, (kind, _, _) in enumerate(tr._blocks) if kind == "tf"]
    assert len(copies) == 4 and len(tr.nlp.rows_tf) == 3
    assert np.isfinite(tr._lbw[tr.nlp.offsets[("tf", 3, 0)]]) and np.isinf(tr._lbw[tr.nlp.offsets[("tf", 0, 0)]])


@pytest.mark.parametrize("env, value", [("GTMODEL_COMPILE", "0"), ("CC", "/no/such/compiler")])
def test_without_a_compiler_the_interpreter_gives_the_same_values(monkeypatch, tmp_path, env, value):
    # second method: the interpreted transcription (compile=False) at a random point
    monkeypatch.setenv("GTMODEL_CACHE_DIR", str(tmp_path))
    monkeypatch.delenv("GTMODEL_COMPILE", raising=False)
    monkeypatch.setenv(env, value)
    kw = dict(elements=3, points=2, nominal={"c": 0.5})
    a = CollocationTranscription(_free_parameter_problem(), compile=True, **kw)
    b = CollocationTranscription(_free_parameter_problem(), compile=False, **kw)
    assert a.evaluation.startswith("CasADi interpreter")
    va, vb = _values(a, "nlp_hess_l", np.random.default_rng(1)), _values(b, "nlp_hess_l", np.random.default_rng(1))
    np.testing.assert_array_equal(va, vb)


@pytest.mark.parametrize("function, output", [("nlp_f", "f"), ("nlp_g", "g")])
def test_objective_and_constraints_are_apart_and_equal_casadis(function, output):
    # second method: CasADi's own nlp_f / nlp_g of the whole NLP graph (derivatives="casadi"); the assembled
    # oracle's f must not evaluate the constraints (IPOPT asks for f and g in separate calls)
    kw = dict(elements=4, points=3)
    a = CollocationTranscription(_free_parameter_problem(), derivatives="assembled", **kw)
    b = CollocationTranscription(_free_parameter_problem(), derivatives="casadi", **kw)
    w = np.random.default_rng(1).uniform(0.5, 1.5, a._lbw.size)
    fa, fb = (tr.solver.get_function(function) for tr in (a, b))
    np.testing.assert_allclose(np.array(fa(w, a.dae.p_value)), np.array(fb(w, b.dae.p_value)), rtol=0, atol=1e-12)
    calls = {fa.instruction_MX(k).which_function().name() for k in range(fa.n_instructions()) if fa.instruction_id(k) == ca.OP_CALL}
    assert calls == {f"{casadi_name(a.dae.name)}_{output}"}
