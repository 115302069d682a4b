"""Parameter sets: shipped files load and carry the thesis' numbers; bad files are refused.

Independent reference: the thesis tables as transcribed in ../shared/reference/*.toml.
"""

from __future__ import annotations

import tomllib
from pathlib import Path

import numpy as np
import pytest

from gtmodel.errors import ParameterError
from gtmodel.robots.parameters import available_parameter_sets, load_parameters

from ..conftest import SHARED_REFERENCE

EXACT = 0.0  # numbers are copied, not computed


def _reference(name: str) -> dict:
    path = SHARED_REFERENCE / name
    if not path.exists():
        pytest.skip(f"reference data {path} not available")
    return tomllib.loads(path.read_text())


@pytest.mark.parametrize("name, n_parameters", [("L1", 21), ("L1_ideal", 15), ("D1", 21)])
def test_shipped_sets_load(name, n_parameters):
    p = load_parameters(name)
    assert p.name == name
    assert p.kinematics.L.shape == (3,)
    assert p.kinematics.As.shape == (3, 3)
    assert p.kinematics.v.shape == (3, 3)
    assert p.kinematics.n_parameters == n_parameters


def test_l1_ideal_matches_table_5_1_with_one_direction():
    ref = _reference("gantry_tau_L1.toml")
    p = load_parameters("L1_ideal")
    np.testing.assert_allclose(p.kinematics.L, ref["table_5_1"]["ideal"]["L"], atol=EXACT)
    np.testing.assert_allclose(p.kinematics.As, ref["table_5_1"]["ideal"]["As"], atol=EXACT)
    assert np.all(p.kinematics.v == p.kinematics.v[0])
    assert "ASSUMPTION" in p.kinematics.source


def test_available_sets():
    assert {"L1", "L1_ideal", "D1"} <= set(available_parameter_sets())


def test_l1_matches_table_5_1_and_6_3():
    ref = _reference("gantry_tau_L1.toml")
    p = load_parameters("L1")
    np.testing.assert_allclose(p.kinematics.L, ref["table_5_1"]["modified"]["L"], atol=EXACT)
    np.testing.assert_allclose(p.kinematics.As, ref["table_5_1"]["modified"]["As"], atol=EXACT)
    np.testing.assert_allclose(p.kinematics.v, ref["table_5_1"]["modified"]["v"], atol=EXACT)
    dyn = ref["dynamics"]
    assert p.dynamics.m_p == dyn["m_p"]
    np.testing.assert_allclose(p.dynamics.m_c, dyn["m_c"], atol=EXACT)
    np.testing.assert_allclose(p.dynamics.f_c, dyn["f_c"], atol=EXACT)
    np.testing.assert_allclose(p.dynamics.f_v, dyn["f_v"], atol=EXACT)
    t61 = dyn["table_6_1"]
    np.testing.assert_allclose(p.dynamics.asymmetric.f_c_plus, t61["f_c_plus"], atol=EXACT)
    np.testing.assert_allclose(p.dynamics.asymmetric.f_v_minus, t61["f_v_minus"], atol=EXACT)


def test_d1_matches_table_5_8_and_says_masses_are_assumed():
    ref = _reference("gantry_tau_D1_F1.toml")
    p = load_parameters("D1")
    np.testing.assert_allclose(p.kinematics.L, ref["D1"]["model_1"]["L"], atol=EXACT)
    np.testing.assert_allclose(p.kinematics.As, ref["D1"]["model_1"]["As"], atol=EXACT)
    np.testing.assert_allclose(p.kinematics.v, ref["D1"]["model_1"]["v"], atol=EXACT)
    assert p.dynamics.assumed
    assert "ASSUMPTION" in p.dynamics.source


def test_load_by_path(tmp_path):
    src = Path(load_parameters("L1").path).read_text()
    f = tmp_path / "mine.toml"
    f.write_text(src.replace('name = "L1"', 'name = "mine"'))
    assert load_parameters(f).name == "mine"
    assert load_parameters(str(f)).name == "mine"


L1_TEXT = None


def _l1_text() -> str:
    return Path(load_parameters("L1").path).read_text()


BAD_FILES = [
    ("missing_L", lambda s: s.replace("L  = [2.0608, 2.0633, 2.0611]\n", ""), r"missing field 'kinematics\.L'"),
    ("short_L", lambda s: s.replace("L  = [2.0608, 2.0633, 2.0611]", "L = [2.0608, 2.0633]"), r"'kinematics\.L'.*shape \(3,\)"),
    ("negative_L", lambda s: s.replace("L  = [2.0608,", "L = [-2.0608,"), r"'kinematics\.L'.*positive"),
    ("string_mass", lambda s: s.replace("m_p = 9.13", 'm_p = "heavy"'), r"'dynamics\.m_p'.*finite number"),
    ("negative_mass", lambda s: s.replace("m_p = 9.13", "m_p = -1.0"), r"'dynamics\.m_p'.*positive"),
    ("unknown_field", lambda s: s.replace("m_p = 9.13", "m_p = 9.13\nmass_plate = 3.0"), r"unknown field 'dynamics\.mass_plate'"),
    ("bad_model", lambda s: s.replace('model = "modified"', 'model = "fancy"'), r"'kinematics\.model'.*'ideal' or 'modified'"),
    ("travel_reversed", lambda s: s.replace("cart_travel = [[-1.0, 1.0],", "cart_travel = [[1.0, -1.0],"), r"'limits\.cart_travel'.*q_min < q_max"),
    ("zero_direction", lambda s: s.replace("[0.9994, -0.0293, -0.0022]", "[0.0, 0.0, 0.0]"), r"'kinematics\.v'.*norm"),
    ("missing_table", lambda s: s[: s.index("[limits]")], r"missing table '\[limits\]'"),
    ("toml_syntax", lambda s: s + "\n[broken\n", r"invalid TOML"),
]


@pytest.mark.parametrize("case, edit, match", BAD_FILES, ids=[c[0] for c in BAD_FILES])
def test_bad_files_name_file_and_field(tmp_path, case, edit, match):
    f = tmp_path / f"{case}.toml"
    f.write_text(edit(_l1_text()))
    with pytest.raises(ParameterError, match=match) as info:
        load_parameters(f)
    assert str(info.value).startswith(str(f))


def test_unknown_name():
    with pytest.raises(ParameterError, match="unknown parameter set 'X9'"):
        load_parameters("X9")
