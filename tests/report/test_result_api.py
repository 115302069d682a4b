"""The results API for notebooks: gtmodel.report.plot_result, result.to_dataframe(), Bode and step plots of a linearisation.

References: the minimum-energy rest-to-rest transfer of the double integrator over 1 s
has the closed form ``u = 6 - 12 t``, ``x = 3 t^2 - 2 t^3``, ``v = 6 t - 6 t^2``
(collocation of degree 3 holds the cubic exactly); the mass-spring-damper's frequency
response and step response have closed forms too (``1 / (m s^2 + d s + k)``, final value
``1 / k``).
"""

from __future__ import annotations

import numpy as np
import pytest

from gtmodel.errors import GtModelError, InputError
from gtmodel.modeling import Model, Optimization, solve
from gtmodel.modeling.simulation.linear import linearize
from gtmodel.report import bode_plot, plot_result, step_plot
from gtmodel.report.linear import plot_bode

from ._figures import assert_line

M, D, K = 2.0, 0.8, 50.0


@pytest.fixture(scope="module")
def transfer():
    """The minimum-energy transfer, with a bound on u that the optimum does not touch (u in [-6, 6])."""
    m = Model("double_integrator")
    x, v = m.state("x", unit="m"), m.state("v", unit="m/s", ub=2.0)
    u = m.input("u", unit="N")
    m.equation(m.der(x), v)
    m.equation(m.der(v), u)
    m.output("kinetic", 0.5 * v**2)
    opt = Optimization(m, final_time=1.0)
    opt.set_objective(lagrange=u**2)
    for var, at, value in ((x, "start", 0.0), (v, "start", 0.0), (x, "final", 1.0), (v, "final", 0.0)):
        opt.add_point_constraint(var, at=at, lb=value, ub=value)
    opt.set_bounds(u, -7.0, 8.0)
    result = solve(opt, elements=8)
    assert result.status == "optimal"
    return m, opt, result


def _dashed(ax) -> list[float]:
    return sorted(float(ln.get_ydata()[0]) for ln in ax.get_lines() if ln.get_linestyle() == "--")


def test_plot_draws_the_named_variables_against_the_closed_form(transfer):
    _, _, r = transfer
    fig = plot_result(r, "x", "u", "kinetic")
    t = r.t
    x_ref, u_ref = 3 * t**2 - 2 * t**3, 6 - 12 * t
    axes = [ax for ax in fig.axes if ax.get_visible()]
    assert [ax.get_ylabel() for ax in axes] == ["x", "u", "kinetic"]
    assert_line(axes[0], "x", t, x_ref, atol=1e-7)
    assert_line(axes[2], "kinetic", t, 0.5 * (6 * t - 6 * t**2) ** 2, atol=1e-6)
    u_line = axes[1].get_lines()[0]
    inner = ~np.isclose(t, 0.0)  # u at t = 0 is the collocation polynomial's extrapolation
    np.testing.assert_allclose(u_line.get_ydata()[inner], u_ref[inner], atol=1e-6)


def test_plot_draws_the_model_bounds_and_those_given(transfer):
    """``v <= 2`` is the model's; ``-7 <= u <= 8`` comes with ``bounds=opt.bounds``, not otherwise."""
    _, opt, r = transfer
    without = plot_result(r, "v", "u")
    with_opt = plot_result(r, "v", "u", bounds=opt.bounds, units={"v": "m/s", "u": "N"})
    assert [_dashed(ax) for ax in without.axes[:2]] == [[2.0], []]
    assert [_dashed(ax) for ax in with_opt.axes[:2]] == [[2.0], [-7.0, 8.0]]
    assert [ax.get_ylabel() for ax in with_opt.axes[:2]] == ["v [m/s]", "u [N]"]


def test_plot_writes_a_png_and_defaults_to_states_and_inputs(transfer, tmp_path):
    _, _, r = transfer
    fig = plot_result(r, path=tmp_path / "r.png")
    assert (tmp_path / "r.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert [ax.get_ylabel() for ax in fig.axes if ax.get_visible()] == ["x", "v", "u"]


@pytest.mark.parametrize("names, match", [(("w",), "'w' is no variable of this result; it has x, v, u, kinetic"),
                                          (("x", "load.phi"), "'load.phi' is no variable")])
def test_plot_refuses_a_name_the_result_does_not_have(transfer, names, match):
    with pytest.raises(InputError, match=match):
        plot_result(transfer[2], *names)


def test_to_dataframe_has_time_and_every_variable(transfer):
    _, _, r = transfer
    df = r.to_dataframe()
    assert list(df.columns) == ["t", "point", "x", "v", "u", "kinetic"]  # point: start, collocation, boundary (which kind of time)
    np.testing.assert_allclose(df["x"], 3 * r.t**2 - 2 * r.t**3, atol=1e-7)
    sampled = r.to_dataframe(dt=0.25)
    np.testing.assert_allclose(sampled["t"], [0.0, 0.25, 0.5, 0.75, 1.0])
    np.testing.assert_allclose(sampled["v"], 6 * sampled["t"] - 6 * sampled["t"] ** 2, atol=1e-7)


@pytest.fixture(scope="module")
def oscillator():
    m = Model("msd")
    x, v = m.state("x"), m.state("v")
    f = m.input("f")
    m.equation(m.der(x), v)
    m.equation(m.der(v), (f - D * v - K * x) / M)
    return linearize(m, outputs=["x"])


def test_bode_plot_is_the_closed_form_frequency_response(oscillator):
    w = np.logspace(-1, 2, 60)
    fig = bode_plot(oscillator, omega=w)
    mag, phase = fig.axes[0].get_lines()[0], fig.axes[1].get_lines()[0]
    g = 1.0 / (M * (1j * w) ** 2 + D * (1j * w) + K)
    assert mag.get_label() == "f -> x"
    np.testing.assert_allclose(mag.get_xdata(), w)
    np.testing.assert_allclose(mag.get_ydata(), 20 * np.log10(np.abs(g)), atol=1e-9)
    np.testing.assert_allclose(phase.get_ydata(), np.degrees(np.unwrap(np.angle(g))), atol=1e-7)


def test_bode_plot_in_hz(oscillator):
    w = np.array([1.0, 10.0])
    line = bode_plot(oscillator, omega=w, hz=True).axes[0].get_lines()[0]
    np.testing.assert_allclose(line.get_xdata(), w / (2 * np.pi))


def test_step_plot_settles_at_the_static_gain(oscillator, tmp_path):
    fig = step_plot(oscillator, T=np.linspace(0.0, 30.0, 3001), path=tmp_path / "step.png")
    line = fig.axes[0].get_lines()[0]
    wn, zeta = np.sqrt(K / M), D / (2 * np.sqrt(K * M))
    wd, t = wn * np.sqrt(1 - zeta**2), line.get_xdata()
    closed = (1 - np.exp(-zeta * wn * t) * (np.cos(wd * t) + zeta / np.sqrt(1 - zeta**2) * np.sin(wd * t))) / K
    np.testing.assert_allclose(line.get_ydata(), closed, atol=1e-6 / K)
    assert (tmp_path / "step.png").is_file()


def test_what_is_no_system_is_refused():
    with pytest.raises(InputError, match="expected a Linearization or a python-control system, got str"):
        plot_bode("not a system")


@pytest.mark.parametrize("call, match", [(lambda r, lin: r.plot("x"), r"gtmodel\.report import plot_result"),
                                         (lambda r, lin: lin.bode_plot(), r"gtmodel\.report import bode_plot"),
                                         (lambda r, lin: lin.step_plot(), r"gtmodel\.report import step_plot")])
def test_the_former_methods_name_the_report_function(transfer, oscillator, call, match):
    """The modelling layer does not draw: its former plot methods say where the plot went."""
    with pytest.raises(GtModelError, match=match):
        call(transfer[2], oscillator)
