"""Tests of the structural passes: incidence, matching, the structural check, alias elimination.

References: incidence and matchings written out by hand for small systems; closed-form
oscillator responses; the unreduced model simulated as a second formulation.
"""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest
import scipy.sparse as sps

from gtmodel.errors import InputError, ModelError
from gtmodel.modeling import Model, check_structure, structural_simplify
from gtmodel.modeling.components.component import Component
from gtmodel.modeling.library.translational import Fixed, Mass, Spring
from gtmodel.modeling.structure.analysis import (
    dulmage_mendelsohn,
    eliminate_aliases,
    incidence,
    matching,
    pattern_rows,
    require_regular,
    scalarize,
    sparsity_pattern,
)


def small_dae():
    """x' = -y, 0 = y - 2 x + z, 0 = z - sin(t): incidence written out in the tests."""
    m = Model("small")
    x = m.state("x", start=1.0)
    y = m.algebraic("y")
    z = m.algebraic("z")
    m.equation(m.der(x), -y, name="ode")
    m.equation(y - 2 * x + z, 0.0, name="coupling")
    m.equation(z, ca.sin(m.time), name="source")
    return m


@pytest.mark.parametrize(
    "merge, names, dense",
    [
        # reference: the incidence read off the three equations by hand
        (True, ["x", "y", "z"], [[1, 1, 0], [1, 1, 1], [0, 0, 1]]),
        (False, ["x", "y", "z", "der(x)"], [[0, 1, 0, 1], [1, 1, 1, 0], [0, 0, 1, 0]]),
    ],
    ids=["merged", "with_der"],
)
def test_incidence(merge, names, dense):
    inc = incidence(scalarize(small_dae()), merge_derivatives=merge)
    assert inc.var_names == names
    assert inc.eq_names == ["ode", "coupling", "source"]
    np.testing.assert_array_equal(inc.matrix.toarray(), dense)


def test_matching_is_perfect_on_a_regular_system():
    # reference: a perfect matching exists (the system is regular); each pair is an incidence
    mat = incidence(scalarize(small_dae())).matrix
    eq_to_var, var_to_eq = matching(mat)
    assert sorted(eq_to_var.tolist()) == [0, 1, 2]
    assert all(mat[i, j] for i, j in enumerate(eq_to_var))
    assert [var_to_eq[j] for j in eq_to_var] == [0, 1, 2]


def test_dulmage_mendelsohn_parts():
    # reference: rows e0 = {v0}, e1 = {v0}, e2 = {v1, v2}: e0/e1 over-determine v0, v1/v2 share e2
    mat = sps.csr_matrix(np.array([[1, 0, 0], [1, 0, 0], [0, 1, 1]]))
    dm = dulmage_mendelsohn(mat)
    assert dm["over_eqs"] == [0, 1] and dm["over_vars"] == [0]
    assert dm["under_vars"] == [1, 2] and dm["under_eqs"] == [2]


def _over():
    m = Model("over")
    x = m.state("x")
    m.equation(m.der(x), 1.0, name="a")
    m.equation(x, 2.0, name="b")
    m.equation(x, 3.0, name="c")
    return m


def _under():
    m = Model("under")
    x = m.state("x")
    m.algebraic("y")
    m.algebraic("w")
    m.equation(m.der(x), 1.0, name="a")
    return m


def _singular():
    m = Model("singular")
    x = m.algebraic("x")
    y = m.algebraic("y")
    z = m.algebraic("z")
    m.equation(x, 1.0, name="e1")
    m.equation(2 * x, 3.0, name="e2")
    m.equation(y + z, 0.0, name="e3")
    return m


@pytest.mark.parametrize(
    "build, match",
    [
        (_over, r"model 'over' is over-determined \(3 scalar equations, 1 unknowns\); equations \['a', 'b', 'c'\] "
                r"over-determine variables \['x'\] \(2 equation\(s\) in excess\)"),
        (_under, r"model 'under' is under-determined .* variables \['y', 'w'\] are under-determined"),
        (_singular, r"structurally singular .* equations \['e1', 'e2'\] over-determine variables \['x'\].*"
                    r"variables \['y', 'z'\] are under-determined \(by equations \['e3'\]"),
    ],
    ids=["over", "under", "singular"],
)
def test_structural_errors_name_equations_and_variables(build, match):
    with pytest.raises(ModelError, match=match):
        check_structure(build())
    with pytest.raises(ModelError, match=match):  # the SciPy-free test (CasADi's structural rank) gives the same message
        require_regular(build())
    with pytest.raises(ModelError, match=match):  # simulate gives the same single message
        build().simulate([0.0, 1.0])


def alias_oscillator():
    """m x'' = -k x written with aliases: p = x, q = -p, f = -k q ... (k = 4, m = 1)."""
    m = Model("aliases")
    x = m.state("x", start=1.0)
    v = m.state("v")
    p = m.algebraic("p")
    q = m.algebraic("q")
    f = m.algebraic("f")
    m.equation(p, x, name="alias_p")
    m.equation(q, -p, name="alias_q")
    m.equation(f, -4.0 * x, name="force")
    m.equation(m.der(x), v)
    m.equation(m.der(v), f)
    m.output("q_out", q)
    return m


def test_alias_elimination_removes_aliases_and_keeps_them_observed():
    # reference: p = x and q = -x by construction
    red = eliminate_aliases(scalarize(alias_oscillator()))
    assert red.aliases == {"p": (1.0, "x"), "q": (-1.0, "x")}
    assert red.var_names == ["x", "v", "f"]
    assert red.eq_names == ["force", "eq3", "eq4"]
    res = structural_simplify(alias_oscillator()).simulate(np.linspace(0.0, 3.0, 31))
    t = res.t
    np.testing.assert_allclose(res.x["x"], np.cos(2.0 * t), atol=1e-6)  # closed form, omega = 2
    np.testing.assert_allclose(res.outputs["q"], -np.cos(2.0 * t), atol=1e-6)


def test_alias_between_states_replaces_their_derivatives():
    # reference: two bodies glued by x1 = x2: one mass m1 + m2 = 4 on a spring k = 4,
    # x = cos(t) (closed form, omega = 1)
    m = Model("glued")
    x1 = m.state("x1", start=1.0)
    v1 = m.state("v1")
    x2 = m.state("x2", start=1.0)
    v2 = m.state("v2")
    f = m.algebraic("f")  # contact force
    m.equation(x1, x2, name="glue")
    m.equation(m.der(x1), v1)
    m.equation(m.der(x2), v2)
    m.equation(1.0 * m.der(v1), -4.0 * x1 + f)
    m.equation(3.0 * m.der(v2), -f)
    red = eliminate_aliases(scalarize(m))
    assert red.aliases == {"x2": (1.0, "x1")}
    assert "der(x1)" in str(red.eq_res[1])  # der(x2) replaced
    t = np.linspace(0.0, 5.0, 51)
    res = m.simulate(t, rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(res.x["x1"], np.cos(t), atol=1e-6)
    np.testing.assert_allclose(res.x["v2"], -np.sin(t), atol=1e-6)


class Chain(Component):
    """Fixed -- spring -- mass -- spring -- mass (helper mod_components' library)."""

    fixed = Fixed()
    s1 = Spring(c=4.0)
    m1 = Mass(m=1.0, s=1.0)
    s2 = Spring(c=2.0)
    m2 = Mass(m=3.0, s=1.5)

    def equations(self) -> None:
        """Connect the chain."""
        self.connect(self.fixed.flange, self.s1.flange_a)
        self.connect(self.s1.flange_b, self.m1.flange_a)
        self.connect(self.m1.flange_b, self.s2.flange_a)
        self.connect(self.s2.flange_b, self.m2.flange_a)


def test_composed_model_connection_aliases_are_eliminated():
    # reference: the unreduced composed model simulated as it is (a second formulation)
    model = Chain().to_model("chain")
    full = scalarize(model)
    red = eliminate_aliases(full)
    assert (full.n_vars, red.n_vars, len(red.aliases)) == (28, 16, 12)
    simple = structural_simplify(model)
    assert simple.flatten().x_names == ["m1.s", "m1.v", "m2.s", "m2.v"]
    t = np.linspace(0.0, 5.0, 51)
    a = model.simulate(t, rtol=1e-10, atol=1e-12)
    b = simple.simulate(t, rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(b.x["m2.s"], a.x["m2.s"], atol=1e-7)
    np.testing.assert_allclose(b.outputs["s2.flange_b.f"], a.z["s2.flange_b.f"], atol=1e-6)


@pytest.mark.parametrize(
    "call, match",
    [
        (lambda: check_structure("pendulum"), "model must be a gtmodel.modeling.Model, got str"),
        (lambda: structural_simplify(alias_oscillator(), point=(0.0, [1.0])), "point must be a tuple"),
        (lambda: structural_simplify(alias_oscillator(), point=(0.0, [1.0, 2.0], [], [])), r"point v .*expected 5 values, got 2"),
    ],
    ids=["not_a_model", "point_tuple", "point_size"],
)
def test_bad_arguments(call, match):
    with pytest.raises(InputError, match=match):
        call()


def test_require_regular_passes_a_regular_model_without_scipy_matrices():
    """A regular model passes CasADi's structural-rank test (second method: SciPy's matching of check_structure)."""
    system = scalarize(small_dae())
    check_structure(system)
    assert require_regular(system) is None


def test_pattern_rows_are_the_rows_of_the_sparse_pattern():
    """The row lists equal the CSR rows of :func:`sparsity_pattern` (the same Jacobian sparsity, read two ways)."""
    system = scalarize(small_dae())
    pat = sparsity_pattern(system.eq_res, system.var_syms)
    expected = [list(pat.indices[pat.indptr[e]:pat.indptr[e + 1]]) for e in range(pat.shape[0])]
    assert pattern_rows(system.eq_res, system.var_syms) == expected
