"""The MPC's weight on the input's change per period (``R_rate``, ``[mpc] input_rate_weights``).

Reference: the horizon problem of a double integrator under an explicit Euler step written out
by hand in NumPy (its states linear in the inputs), the stacked residuals
``sqrt(R) (u_j - u*_j)``, ``sqrt(R_rate) (u_j - u_{j-1})`` with ``u_{-1}`` the input acting
before the horizon, ``sqrt(Q) (x_{j+1} - x*_{j+1})``, solved by ``numpy.linalg.lstsq``: a
second method, independent of CasADi. The generated step (``function()``) and the Python
solve must give its first input.
"""

from __future__ import annotations

import numpy as np
import pytest

from gtmodel.control.mpc import mpc_controller
from gtmodel.errors import InputError, ProblemError
from gtmodel.modeling import explicit_ode

from ..modeling._builders import double_integrator

DT, H = 0.004, 8
Q, R = np.array([1.0, 0.01]), 1e-4


def _reference():
    t = DT * np.arange(101)
    return t, np.column_stack([np.minimum(t / 0.2, 1.0), np.where(t < 0.2, 5.0, 0.0)]), np.zeros((101, 1))


def _mpc(rate, **kw):
    t, x_ref, u_ref = _reference()
    return mpc_controller(explicit_ode(double_integrator()[0]), t, x_ref, u_ref, horizon=H, Q=Q, R=[R], u_lb=[-1e3], u_ub=[1e3],
                          method="euler", R_rate=rate if rate is None or isinstance(rate, list) else [rate], **kw)


def _lstsq(x0, u_prev, k, rate):
    """The horizon problem's first input by stacked least squares (states linear in the inputs)."""
    _, x_ref, u_ref = _reference()
    A, B = np.array([[1.0, DT], [0.0, 1.0]]), np.array([0.0, DT])
    rows, rhs = [], []
    lift, free = np.zeros((2, H)), np.asarray(x0, dtype=float)  # x_j = free + lift @ u
    for j in range(H):
        e = np.zeros(H)
        e[j] = 1.0
        rows.append(np.sqrt(R) * e), rhs.append(np.sqrt(R) * u_ref[k + j, 0])
        prev = np.zeros(H)
        if j:
            prev[j - 1] = 1.0
        rows.append(np.sqrt(rate) * (e - prev)), rhs.append(np.sqrt(rate) * (u_prev if j == 0 else 0.0))
        lift, free = A @ lift + np.outer(B, e), A @ free
        for i in range(2):
            rows.append(np.sqrt(Q[i]) * lift[i]), rhs.append(np.sqrt(Q[i]) * (x_ref[k + j + 1, i] - free[i]))
    return np.linalg.lstsq(np.array(rows), np.array(rhs), rcond=None)[0]


@pytest.mark.parametrize("rate", [0.0, 1e-3, 1.0])
def test_python_solve_is_the_hand_built_least_squares(rate):
    c, x0, u_prev, k = _mpc(rate), np.array([0.01, 0.3]), 7.0, 5
    _, w = c.solve(k * DT, x0, plugin="sqpmethod", iterations=1, u_prev=[u_prev])
    assert np.allclose(w, _lstsq(x0, u_prev, k, rate), rtol=1e-8, atol=1e-8 * np.max(np.abs(w)))


@pytest.mark.parametrize("rate", [1e-3, 1.0])
def test_the_step_reads_its_last_input_as_the_previous_one(rate):
    """The step's ``u_last`` (the input acting now) is ``u_{-1}``; no delay: the horizon starts at the measured state."""
    c, x0, u_last, k = _mpc(rate), np.array([0.01, 0.3]), 7.0, 5
    u, _, ok = c.function()(k * DT, x0, u_last, c.w_initial)
    assert float(ok) == 1.0 and float(u) == pytest.approx(_lstsq(x0, u_last, k, rate)[0], rel=1e-8)


def test_a_large_rate_weight_holds_the_input():
    """Move suppression: as R_rate grows the first input approaches the one acting."""
    first = [float(_mpc(rate).function()(5 * DT, np.array([0.01, 0.3]), 7.0, np.zeros(H))[0]) for rate in (0.0, 1e-2, 1e2)]
    assert abs(first[2] - 7.0) < 0.01 * abs(first[0] - 7.0) and abs(first[1] - 7.0) < abs(first[0] - 7.0)


def test_no_rate_weight_leaves_the_parameters_as_before():
    c = _mpc(None)
    assert c.R_rate is None and c.parameters(0.0, np.zeros(2)).size == 2 + H * 3


BAD = [
    ({"rate": [1.0, 2.0]}, "R_rate: expected 1 diagonal entries or a \\(1, 1\\) matrix"),
    ({"rate": [-1.0]}, "R_rate: "),
    ({"rate": [1.0], "solver": "fatrop"}, "R_rate: the input's rate term is built for sqpmethod"),
    ({"rate": [1.0], "solver": "hpipm"}, "R_rate: the input's rate term is built for sqpmethod"),
]


@pytest.mark.parametrize("kw, match", BAD, ids=["shape", "negative", "fatrop", "hpipm"])
def test_bad_rate_weights_are_refused(kw, match):
    with pytest.raises(InputError, match=match):
        _mpc(**kw)


def test_a_file_naming_an_unknown_input_is_refused(tmp_path):
    """The file's table by input name: an unknown name is refused naming the field."""
    from gtmodel.problems.mpc_file import load_mpc_file

    with pytest.raises(ProblemError, match=r"mpc\.input_rate_weights\.src\.w"):
        load_mpc_file(_dc_motor_file(tmp_path, 'input_rate_weights = { "src.w" = 1.0 }\n'))


def _dc_motor_file(tmp_path, extra: str):
    from ..conftest import REPO

    text = (REPO / "codegen" / "mpc" / "dc_motor_mpc.toml").read_text().replace("[mpc]\n", "[mpc]\n" + extra, 1)
    path = tmp_path / "m.toml"
    path.write_text(text.replace('"../../', f'"{REPO.as_posix()}/'))
    return path


@pytest.mark.parametrize("extra, factor", [
    ("", None),  # no rows (qrqp): no default
    ('state_ub = { "ind.i" = 20.0 }\n', 100.0),  # rows: RATE_FACTOR times R
    ('state_ub = { "ind.i" = 20.0 }\ninput_rate_weights = { "src.v" = 0.0 }\n', None),  # 0: off
    ('state_ub = { "ind.i" = 20.0 }\ninput_rate_weights = { "src.v" = 0.5 }\n', "given"),
], ids=["no rows", "rows", "rows, zero", "rows, given"])
def test_an_mpc_files_default_rate_weight(tmp_path, extra, factor):
    from gtmodel.problems.mpc_file import RATE_FACTOR, load_mpc_file

    c = load_mpc_file(_dc_motor_file(tmp_path, extra)).controller
    if factor is None:
        assert c.R_rate is None
    elif factor == "given":
        assert np.array_equal(c.R_rate, [[0.5]])
    else:
        assert RATE_FACTOR == factor and np.array_equal(c.R_rate, factor * c.R) and c.constraints is not None


def test_a_file_with_rate_weights_and_another_solver_is_refused_before_planning(tmp_path, monkeypatch):
    import gtmodel.problems.mpc_file as mpc_file

    monkeypatch.setattr(mpc_file, "loop_inputs", lambda *a, **k: pytest.fail("planned before refusing"))
    path = _dc_motor_file(tmp_path, 'input_rate_weights = { "src.v" = 1.0 }\n')
    path.write_text(path.read_text().replace('solver = "sqpmethod"', 'solver = "hpipm"'))
    with pytest.raises(ProblemError, match=r"mpc\.input_rate_weights.*rate term is built for sqpmethod"):
        mpc_file.load_mpc_file(path)
