"""The controller file: round trip in JSON and NPZ, and bad files refused naming file and key.

Independent reference: the Controller written (its Functions evaluated from Python, its
table) against the Controller read back.
"""

from __future__ import annotations

import json
import re

import casadi as ca
import numpy as np
import pytest

from gtmodel.cli import main
from gtmodel.codegen import Controller, load_controller, save_controller
from gtmodel.codegen.controller_file import CONTROLLER_FORMAT
from gtmodel.errors import InputError

from .controller_functions import ilc_correction_function, kalman_step_function, learned_table

TABLE = learned_table(30, 3)


@pytest.fixture(scope="module")
def controller():
    return Controller(kalman_step=kalman_step_function(), ilc_correction=ilc_correction_function(TABLE), ilc_table=TABLE)


@pytest.mark.parametrize("suffix", [".json", ".npz"])
def test_round_trip_is_exact(tmp_path, controller, suffix):
    path = save_controller(tmp_path / f"controller{suffix}", controller, description="stand-in")
    back = load_controller(path)
    np.testing.assert_array_equal(back.ilc_table, TABLE)
    assert back.dt == 0.004
    x, y = np.linspace(-1, 1, 9), np.linspace(1, 2, 6)
    np.testing.assert_array_equal(np.asarray(back.kalman_step(x, y)[0]), np.asarray(controller.kalman_step(x, y)[0]))
    np.testing.assert_array_equal(np.asarray(back.ilc_correction(7)), TABLE[7][:, None])


@pytest.mark.parametrize("which", ["kalman_step", "ilc_correction"])
def test_one_function_alone_is_enough(tmp_path, which):
    c = Controller(kalman_step=kalman_step_function()) if which == "kalman_step" else \
        Controller(ilc_correction=ilc_correction_function(TABLE), ilc_table=TABLE)
    assert load_controller(save_controller(tmp_path / "c.json", c)).functions == (which,)


def _json(tmp_path, controller, edit):
    path = save_controller(tmp_path / "controller.json", controller)
    data = json.loads(path.read_text())
    edit(data)
    path.write_text(json.dumps(data))
    return path


BAD_EDITS = [
    (lambda d: d.update(extra=1), r"controller.json: unknown key 'extra' \(allowed: format, dt, "),
    (lambda d: d.pop("dt"), r"controller.json: missing key 'dt'"),
    (lambda d: d.update(format="v0"), r"controller.json: key 'format': expected 'gtmodel.controller/1', got 'v0'"),
    (lambda d: d.update(dt=-0.004), r"controller.json: key 'dt': expected a positive sample time \[s\], got -0.004"),
    (lambda d: d.update(dt="4 ms"), r"controller.json: key 'dt': expected a positive sample time"),
    (lambda d: (d.pop("kalman_step"), d.pop("ilc_correction"), d.pop("ilc_table")), r"controller.json: expected at least one of the keys"),
    (lambda d: d.pop("ilc_table"), r"controller.json: key 'ilc_correction' needs the key 'ilc_table'"),
    (lambda d: d.pop("ilc_correction"), r"controller.json: key 'ilc_table' needs the key 'ilc_correction'"),
    (lambda d: d.update(kalman_step="garbage"), r"controller.json: key 'kalman_step': not a serialised CasADi Function"),
    (lambda d: d.update(kalman_step=12), r"controller.json: key 'kalman_step': expected a string, got int"),
    (lambda d: d.update(kalman_step=d["ilc_correction"]), r"controller.json: key 'kalman_step': expected a casadi.Function \(x, y\)"),
    (lambda d: d.update(ilc_table=[[1.0, 2.0], [3.0]]), r"controller.json: key 'ilc_table': expected an \(N, d\) array of numbers"),
    (lambda d: d.update(ilc_table=[1.0, 2.0]), r"controller.json: key 'ilc_table': expected an \(N, d\) array of finite numbers, got shape \(2,\)"),
    (lambda d: d["ilc_table"][3].__setitem__(1, 1.0), r"controller.json: key 'ilc_correction': u\(k=3\) = .* differs from ilc_table\[3\]"),
    (lambda d: d.update(description=["a"]), r"controller.json: key 'description': expected a string, got list"),
]


@pytest.mark.parametrize("edit, match", BAD_EDITS, ids=[m.split(": ", 1)[1][:40] for _, m in BAD_EDITS])
def test_bad_file_is_refused_naming_file_and_key(tmp_path, controller, edit, match):
    with pytest.raises(InputError, match=match):
        load_controller(_json(tmp_path, controller, edit))


@pytest.mark.parametrize("name, content, match", [
    ("c.txt", "", r"c.txt: expected a .json or .npz file, got suffix '.txt'"),
    ("missing.json", None, r"missing.json: not found"),
    ("c.json", "{not json", r"c.json: cannot read it as JSON"),
    ("c.json", "[1, 2]", r"c.json: expected a JSON object with keys format, dt"),
    ("c.npz", "not a zip", r"c.npz: cannot read it as NPZ"),
])
def test_unreadable_file_is_refused_naming_the_file(tmp_path, name, content, match):
    path = tmp_path / name
    if content is not None:
        path.write_text(content)
    with pytest.raises(InputError, match=match):
        load_controller(path)


def test_npz_with_a_bad_key_names_it(tmp_path, controller):
    path = save_controller(tmp_path / "c.npz", controller)
    with np.load(path) as z:
        data = {k: z[k] for k in z.files}
    data["dt"] = np.array([0.004, 0.004])
    np.savez(path, **data)
    with pytest.raises(InputError, match=r"c.npz: key 'dt': expected a positive sample time"):
        load_controller(path)


def test_cli_bad_controller_file_exits_2_naming_file_and_key(tmp_path, controller, capsys):
    path = _json(tmp_path, controller, lambda d: d.update(dt=0))
    assert main(["codegen", "--robot", "L1", "--functions", "ik", "--controller", str(path), "--out", str(tmp_path / "gen")]) == 2
    assert re.search(r"controller.json: key 'dt': expected a positive sample time", capsys.readouterr().err)


def test_format_constant_is_written(tmp_path, controller):
    assert json.loads(save_controller(tmp_path / "c.json", controller).read_text())["format"] == CONTROLLER_FORMAT
    assert isinstance(ca.Function.deserialize(json.loads((tmp_path / "c.json").read_text())["kalman_step"]), ca.Function)


def test_an_npz_bomb_is_refused_by_its_declared_size(tmp_path):
    """200 MB of zeros packed into ~200 kB: refused before numpy unpacks it (reference: the zip header)."""
    import zipfile

    from gtmodel.codegen.controller_file import MAX_BYTES

    bomb = tmp_path / "bomb.npz"
    with zipfile.ZipFile(bomb, "w", zipfile.ZIP_DEFLATED) as zf:
        zf.writestr("kalman_step.npy", bytes(2 * MAX_BYTES))
    with pytest.raises(InputError, match=rf"controller file .*bomb.npz: {2 * MAX_BYTES} bytes \(unpacked\), expected at most {MAX_BYTES}"):
        load_controller(bomb)


def test_the_bundle_keeps_its_former_name():
    # issue 45: codegen.Controller is named for what it bundles; the former name is the same class
    import gtmodel.codegen as codegen
    from gtmodel.codegen.controller import Controller, EstimatorILCBundle

    assert codegen.EstimatorILCBundle is codegen.Controller is Controller is EstimatorILCBundle
