"""Controller declarations: the Kalman step and the ILC correction as generated C functions.

Independent references: the CasADi Functions evaluated from Python (gtmodel.estimation's
stationary Kalman step and ILC correction lookup, via ``controller_functions``); the issue's contract (state in a caller-owned struct, status codes, no heap).
"""

from __future__ import annotations

import re

import casadi as ca
import numpy as np
import pytest

from gtmodel.codegen import Controller, generate
from gtmodel.codegen.controller import CONTROLLER_KIND
from gtmodel.codegen.generate import controller_part, robot_part
from gtmodel.errors import InputError

from .controller_functions import ilc_correction_function, kalman_step_function, learned_table

TABLE = learned_table(50, 3)


def _f(name, ins, outs, sizes_in, sizes_out):
    s_in = [ca.SX.sym(n, k) for n, k in zip(ins, sizes_in)]
    s_out = [ca.SX.zeros(k) + ca.sum1(s_in[0]) for k in sizes_out]
    return ca.Function(name, s_in, s_out, list(ins), list(outs))


BAD_CONTROLLERS = [
    ({}, r"at least one of kalman_step, ilc_correction, kf_step, ekf_step"),
    ({"kalman_step": "not a function"}, r"kalman_step: expected a casadi.Function, got str"),
    ({"kalman_step": _f("k", ("x", "z"), ("x_next", "z_hat"), (9, 6), (9, 3))}, r"kalman_step: expected .*\(x, y\) -> \(x_next, z_hat\), got \(x, z\)"),
    ({"kalman_step": _f("k", ("x", "y"), ("x_next", "z_hat"), (9, 6), (8, 3))}, r"kalman_step: x has 9 elements but x_next has 8"),
    ({"kalman_step": kalman_step_function(), "dt": 0.0}, r"dt: expected a positive sample time"),
    ({"kalman_step": kalman_step_function(), "dt": float("nan")}, r"dt: expected a positive sample time"),
    ({"ilc_correction": ilc_correction_function(TABLE)}, r"ilc_table: .*a Function without its table"),
    ({"kalman_step": kalman_step_function(), "ilc_table": TABLE}, r"ilc_table: .*a table without a Function"),
    ({"ilc_correction": _f("i", ("k",), ("u",), (2,), (3,)), "ilc_table": TABLE}, r"ilc_correction: input 'k' must be scalar, has 2"),
    ({"ilc_correction": ilc_correction_function(TABLE), "ilc_table": TABLE[:, :2]}, r"ilc_table: has 2 columns but ilc_correction's u has 3"),
    ({"ilc_correction": ilc_correction_function(TABLE), "ilc_table": np.full((50, 3), np.nan)}, r"ilc_table: expected an \(N, d\) array of finite values"),
    ({"ilc_correction": ilc_correction_function(TABLE), "ilc_table": TABLE[:, 0]}, r"ilc_table: expected an \(N, d\) array"),
    ({"ilc_correction": ilc_correction_function(TABLE), "ilc_table": TABLE * 1.001}, r"ilc_correction: u\(k=\d+\) = .* differs from ilc_table\[\d+\]"),
    ({"ilc_correction": ilc_correction_function(TABLE), "ilc_table": TABLE[:40]}, r"ilc_correction: u\(k=40\) = .* differs from 0 \(outside the table\)"),
]


@pytest.mark.parametrize("kwargs, match", BAD_CONTROLLERS, ids=[m for _, m in BAD_CONTROLLERS])
def test_bad_controller_is_refused_naming_the_argument(kwargs, match):
    with pytest.raises(InputError, match=match):
        Controller(**kwargs)


def test_generate_refuses_something_else_than_a_controller(tmp_path):
    with pytest.raises(InputError, match=r"controller: expected a gtmodel.codegen.Controller, got dict"):
        generate("L1", tmp_path, functions=("ik",), controller={"kalman_step": kalman_step_function()})


@pytest.mark.parametrize("d", [1, 2, 3])
def test_controller_sizes_follow_the_functions(d):
    table = learned_table(20, d)
    c = Controller(kalman_step=kalman_step_function(d), ilc_correction=ilc_correction_function(table), ilc_table=table)
    assert c.kalman_sizes == (3 * d, 2 * d, d)
    assert (c.ilc_length, c.ilc_d) == (20, d)
    assert [s.name for s in c.specs()] == ["kalman_step", "ilc_correction"]
    assert {s.kind for s in c.specs()} == {CONTROLLER_KIND}


EXPECTED_DECLARATIONS = [
    "int gt_L1_kalman_step(const double x[9], const double y[6], double x_next[9], double z_hat[3]);",
    "int gt_L1_ilc_correction(int k, double u[3]);",
    "int gt_L1_kalman_init(gt_L1_kalman_state *state, const double x0[9]);",
    "int gt_L1_kalman_update(gt_L1_kalman_state *state, const double y[6], double z_hat[3]);",
    "#define GT_L1_KALMAN_NX 9",
    "#define GT_L1_KALMAN_NY 6",
    "#define GT_L1_KALMAN_NZ 3",
    "#define GT_L1_ILC_LENGTH 400",
    "#define GT_L1_ILC_D 3",
    "#define GT_L1_CONTROLLER_DT 0.004",
]


@pytest.mark.parametrize("line", EXPECTED_DECLARATIONS)
def test_header_declares_the_controller_api(controller_built, line):
    gen, _ = controller_built
    assert line in gen.header.read_text()


def test_header_keeps_the_state_in_a_caller_owned_struct(controller_built):
    gen, _ = controller_built
    text = gen.header.read_text()
    assert re.search(r"typedef struct gt_L1_kalman_state \{\s*double x\[9\];.*\} gt_L1_kalman_state;", text, re.S)
    assert "(k < 0 or k >= ILC_LENGTH) the correction is 0 and the status GT_OK" in text.replace("\n * ", " ")


def test_robot_and_controller_parts_split_the_library(controller_built):
    gen, _ = controller_built
    assert robot_part(gen).functions == ("ik", "jacobian", "inverse_dynamics")
    assert controller_part(gen).functions == ("kalman_step", "ilc_correction")
    assert gen.functions == ("ik", "jacobian", "inverse_dynamics", "kalman_step", "ilc_correction")


@pytest.mark.parametrize("k", [-(2**31), -1, 0, 1, 199, 399, 400, 2**31 - 1])
def test_ilc_correction_is_the_table_row_and_zero_outside(controller_built, k):
    """Against the learned table itself (the Function's source), exactly."""
    gen, lib = controller_built
    status, (u,) = lib["ilc_correction"](k)
    table = gen.controller.ilc_table
    assert status == 0
    np.testing.assert_array_equal(u, table[k] if 0 <= k < len(table) else np.zeros(3))


def test_kalman_step_in_place_update_equals_python(controller_built):
    """x_next may be x: the wrapper writes its outputs only after the evaluation (CasADi from Python)."""
    gen, lib = controller_built
    x = np.linspace(-1, 1, 9)
    y = np.linspace(0.5, -0.5, 6)
    ref = np.asarray(gen.controller.kalman_step(x, y)[0]).ravel()
    buf = x.copy()
    status, _ = lib["kalman_step"](buf, y, out=(buf, np.zeros(3)))
    assert status == 0
    np.testing.assert_allclose(buf, ref, rtol=0, atol=1e-12)
