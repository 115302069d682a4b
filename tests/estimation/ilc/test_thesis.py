"""The thesis' Table 7.2 figures come from the package data, one copy.

Independent reference: Dressler (2012), section 7.4, Table 7.2 (x 13.3 / 12.6 / 13.3 / 10.3 %,
y 36.1 / 23.9 / 25.2 / 24.9 %) and eq. (7.28) (0.90, 0.91, 0.93), typed here from the thesis
to check the reference file; the kind and the fidelity report read only the file.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from gtmodel.errors import InputError
from gtmodel.estimation.ilc import thesis_table_7_2


def test_every_case_of_table_7_2_is_in_the_reference_data():
    t = thesis_table_7_2()
    assert sorted(t) == ["1", "2A", "2B", "3"]
    assert [t[c]["tool_x"] for c in ("1", "2A", "2B", "3")] == [0.133, 0.126, 0.133, 0.103]
    assert [t[c]["tool_y"] for c in ("1", "2A", "2B", "3")] == [0.361, 0.239, 0.252, 0.249]
    assert t["1"]["sigma_max"] == [0.90, 0.91, 0.93]
    assert [t[c]["sigma_max"] for c in ("2A", "2B", "3")] == [[0.86], [0.93], [0.95]]


def test_the_result_is_a_copy():
    thesis_table_7_2()["1"]["tool_x"] = 9.0
    assert thesis_table_7_2()["1"]["tool_x"] == 0.133


@pytest.mark.parametrize("text, match", [
    ("[ilc]\nsource = 'x'\n", r"no table \[ilc.table_7_2\]"),
    ("[ilc.table_7_2]\ncase_1 = { tool_x = 0.1 }\n", r"case_1: expected tool_x, tool_y and sigma_max"),
    ("[ilc.table_7_2\n", "invalid TOML"),
])
def test_bad_reference_file_names_the_table(tmp_path, text, match):
    f = tmp_path / "ref.toml"
    f.write_text(text)
    with pytest.raises(InputError, match=match):
        thesis_table_7_2(f)


def test_the_default_file_is_package_data():
    import gtmodel
    from gtmodel.estimation.ilc import thesis

    assert thesis.REFERENCE_FILE.is_relative_to(Path(gtmodel.__file__).resolve().parent)


def test_a_missing_default_file_is_an_error_not_an_empty_table(monkeypatch, tmp_path):
    """A broken installation fails loudly: no summary row silently says "not in the thesis"."""
    from gtmodel.estimation.ilc import thesis

    monkeypatch.setattr(thesis, "REFERENCE_FILE", tmp_path / "absent.toml")
    with pytest.raises(InputError, match="absent.toml"):
        thesis_table_7_2()
