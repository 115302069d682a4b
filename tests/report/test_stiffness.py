"""The stiffness map colours each pose by the chosen quantity (gtmodel.report.stiffness)."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest
from matplotlib.figure import Figure

from gtmodel.errors import InputError
from gtmodel.report.stiffness import plot_stiffness_map
from gtmodel.robots.stiffness import N_PER_UM, StiffnessMap

from ._figures import assert_png


@pytest.fixture(scope="module")
def smap():
    rng = np.random.default_rng(1)
    n = 12
    T = np.column_stack([np.zeros(n), rng.uniform(2.5, 3.2, n), rng.uniform(-0.8, -0.2, n)])
    K = np.stack([np.diag([3.0, 2.0, 1.0 + 0.1 * i]) * 1e7 for i in range(n)])
    deflection = rng.normal(0.0, 1e-5, (n, 3))
    return StiffnessMap(T, K, deflection, SimpleNamespace(describe=lambda: "stated joint stiffness 115 N/um"), 40.0)


@pytest.mark.parametrize(
    "quantity, values, label",
    [
        ("min", lambda m: m.min_stiffness / N_PER_UM, "smallest principal stiffness [N/um]"),
        ("x", lambda m: m.axis_stiffness[:, 0] / N_PER_UM, "stiffness along x [N/um]"),
        ("z", lambda m: m.axis_stiffness[:, 2] / N_PER_UM, "stiffness along z [N/um]"),
        ("deflection", lambda m: np.linalg.norm(m.gravity_deflection, axis=1) * 1e6, "gravity deflection |dT| [um]"),
    ],
)
@pytest.mark.parametrize("axes", [(1, 2), (0, 1)])
def test_map_colours_each_pose_by_the_quantity(smap, tmp_path, quantity, values, label, axes):
    fig = plot_stiffness_map(smap, tmp_path / "m.png", quantity=quantity, axes=axes, title="D1")
    assert_png(tmp_path / "m.png")
    ax = fig.axes[0]
    sc = ax.collections[0]
    np.testing.assert_allclose(sc.get_offsets(), smap.T[:, list(axes)])
    np.testing.assert_allclose(sc.get_array(), values(smap))
    assert fig.axes[1].get_ylabel() == label  # the colour bar
    assert ax.get_xlabel() == f"{'xyz'[axes[0]]} [m]" and "115" in ax.get_title()


def test_draws_into_given_axes_without_a_file(smap):
    ax = Figure().subplots()
    assert plot_stiffness_map(smap, quantity="y", ax=ax) is ax.figure


@pytest.mark.parametrize("kw, match", [({"quantity": "w"}, "quantity"), ({"axes": (1, 1)}, "axes")])
def test_bad_input(smap, kw, match):
    with pytest.raises(InputError, match=match):
        plot_stiffness_map(smap, **kw)
