"""Tests of OptimizationResult: status mapping, polynomial sampling, export.

References: IPOPT's documented return_status strings; Lagrange interpolation is exact
for polynomials of degree <= number of nodes - 1; the raw NLP values at the nodes.
"""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from gtmodel.errors import InputError
from gtmodel.modeling.ocp.result import CollocationData, lagrange_basis, normalize_ipopt_status

NODE_TOL = 1e-12  # evaluation at a node reproduces the node value up to rounding
POLY_TOL = 1e-10  # interpolation of a polynomial of admissible degree


@pytest.mark.parametrize(
    "ipopt_status, expected",
    [
        ("Solve_Succeeded", "optimal"),
        ("Solved_To_Acceptable_Level", "acceptable"),
        ("Infeasible_Problem_Detected", "infeasible"),
        ("Maximum_Iterations_Exceeded", "max_iterations"),
        ("Maximum_CpuTime_Exceeded", "max_iterations"),
        ("Restoration_Failed", "error"),
        ("Invalid_Number_Detected", "error"),
        ("Search_Direction_Becomes_Too_Small", "error"),
        ("something new", "error"),
    ],
)
def test_status_mapping(ipopt_status, expected):
    assert normalize_ipopt_status(ipopt_status) == expected


def test_lagrange_basis_is_identity_at_nodes():
    # reference: l_j(tau_i) = delta_ij
    nodes = np.array([0.0, 0.155, 0.645, 1.0])
    np.testing.assert_allclose(lagrange_basis(nodes, nodes), np.eye(4), atol=NODE_TOL)


def _cubic_data(points=3, scheme_nodes=(0.15505102572168, 0.64494897427832, 1.0)):
    """Two elements on [0, 2] holding x(t) = t^3 (states) and u(t) = t^2 (inputs)."""
    root = np.concatenate([[0.0], scheme_nodes])
    ts = np.array([[k + r for r in root] for k in range(2)])  # h = 1
    xc = (ts**3)[:, :, None]
    uc = (ts[:, 1:] ** 2)[:, :, None]
    return CollocationData(0.0, 2.0, 2, points, "radau", root, xc, uc, np.zeros((2, points, 0)))


def test_sampling_reproduces_polynomials_exactly():
    # reference: x = t^3 (degree d = 3 through d + 1 nodes), u = t^2 (degree d - 1 through d nodes)
    data = _cubic_data()
    t = np.linspace(0.0, 2.0, 37)
    x, u, z = data.evaluate(t)
    np.testing.assert_allclose(x[:, 0], t**3, atol=POLY_TOL)
    np.testing.assert_allclose(u[:, 0], t**2, atol=POLY_TOL)
    assert z.shape == (37, 0)


def test_sample_reproduces_nlp_values_at_collocation_points(min_energy_result):
    # reference: the raw NLP values stored per element (collocation.uc / xc)
    res = min_energy_result
    c = res.collocation
    h = (c.tf - c.t0) / c.elements
    k = np.repeat(np.arange(c.elements), c.points)
    j = np.tile(np.arange(1, c.points + 1), c.elements)
    t = c.t0 + (k + c.tau_root[j]) * h
    s = res.sample(t)
    np.testing.assert_allclose(s["inputs"]["u"], c.uc[k, j - 1, 0], atol=NODE_TOL)
    np.testing.assert_allclose(s["states"]["x"], c.xc[k, j, 0], atol=NODE_TOL)


def test_mesh_contains_start_and_collocation_points(min_energy_result):
    # reference: Radau d = 3 with N = 10 elements: t0 plus 3 points per element (last = end)
    res = min_energy_result
    assert res.t.shape == (1 + 10 * 3,)
    assert res.t[0] == 0.0 and res.t[-1] == pytest.approx(1.0)
    assert np.all(np.diff(res.t) > 0)


def test_resample_uniform_grid(min_energy_result):
    # reference: closed form x = 3 t^2 - 2 t^3 (exact for the cubic collocation polynomial)
    s = min_energy_result.resample(0.004)
    assert s["t"].shape == (251,)
    np.testing.assert_allclose(np.diff(s["t"]), 0.004, atol=1e-15)
    np.testing.assert_allclose(s["states"]["x"], 3 * s["t"] ** 2 - 2 * s["t"] ** 3, atol=1e-7)
    assert set(s) == {"t", "states", "inputs", "algebraics", "outputs"}


def test_to_csv_header_and_rows(min_energy_result, tmp_path):
    path = min_energy_result.to_csv(tmp_path / "trajectory.csv", dt=0.1)
    with open(path) as fh:
        assert fh.readline().strip() == "t,x,v,u,kinetic"
    df = pd.read_csv(path)
    assert len(df) == 11
    np.testing.assert_allclose(df["t"], np.linspace(0.0, 1.0, 11), atol=1e-12)


def test_to_dataframe_on_mesh(min_energy_result):
    df = min_energy_result.to_dataframe()
    assert list(df.columns) == ["t", "point", "x", "v", "u", "kinetic"]
    assert len(df) == min_energy_result.t.size
    d = min_energy_result.collocation.points  # Radau: t0, then d points per element, the last its end
    assert list(df["point"][: d + 1]) == ["start"] + ["collocation"] * (d - 1) + ["collocation_boundary"]


@pytest.mark.parametrize(
    "call, match",
    [
        (lambda r: r.sample([1.5]), r"sample times must lie in \[0.0, 1.0"),
        (lambda r: r.sample([-0.1]), "sample times must lie"),
        (lambda r: r.resample(0.0), "dt must be positive"),
        (lambda r: r.resample(float("nan")), "dt must be positive"),
    ],
    ids=["after_tf", "before_t0", "dt_zero", "dt_nan"],
)
def test_sampling_errors(min_energy_result, call, match):
    with pytest.raises(InputError, match=match):
        call(min_energy_result)
