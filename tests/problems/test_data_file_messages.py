"""Messages about a data file never quote it (issue 67): a field pointed at a ``.env`` file or a
copy of ``/etc/passwd`` gives the file, the line, the column and what was expected, and no line
of the file, neither in the message nor in ``summary.json`` (``gtmodel._tables.column_label``).

Independent reference: the secret files are written here; their secret words must appear in
no output.
"""

from __future__ import annotations

import json
import shutil

import pytest

from gtmodel.cli import EXIT_BAD_INPUT, main
from gtmodel.errors import ProblemError
from gtmodel.problems import load_problem

from ..conftest import PROBLEMS_DIR, REPO, replace_once

SECRET = "sk-SECRET-4f1c"
#: Files a user could name by mistake, each with the secret in a line that is not the first.
FILES = {
    "dotenv": (".env", f"API_USER=robot\nAPI_KEY={SECRET}\nDB_PASSWORD={SECRET}x\n"),
    "passwd": ("passwd", f"root:x:0:0:root:/root:/bin/bash\nsvc:x:1:1:{SECRET}:/usr/sbin:/usr/sbin/nologin\n"),
    "secret_first_line": ("token.txt", f"{SECRET}\n{SECRET}\n"),
    "a_table_with_a_secret_cell": ("log.csv", f"t,q1,q2,q3\n0,0,0,0\n0.004,{SECRET},0,0\n"),
}
#: The message for each file: named by line and column (a header that is no table: by number).
EXPECTED = {
    "dotenv": r"\.env: line 2, column 1: expected a decimal number, got 22 characters of text",
    "passwd": r"passwd: line 2, column 1: expected a decimal number, got \d+ characters of text",
    "secret_first_line": r"token\.txt: line 2, column 1: expected a decimal number, got 14 characters of text",
    "a_table_with_a_secret_cell": r"log\.csv: line 3, column 'q1': expected a decimal number, got 14 characters of text",
}
LOOP = REPO / "loops" / "l1_egm_ilc.toml"
TRACKING = PROBLEMS_DIR / "l1_tracking.toml"


def _loop(tmp_path, name):
    shutil.copytree(REPO / "loops" / "data", tmp_path / "data")
    shutil.copy(LOOP, tmp_path / LOOP.name)
    return tmp_path / LOOP.name, {"controller.correction_file": name}


def _tracking(tmp_path, name):
    path = tmp_path / "track.toml"
    path.write_text(replace_once('problem = "l1_time_optimal.toml"', f'file = "{name}"')(TRACKING.read_text()))
    return path, {}


#: Fields that name a data file: the loop's correction file, a tracking problem's trajectory.
FIELDS = {"loop_correction_file": (_loop, "controller.correction_file"), "tracking_trajectory_file": (_tracking, r"trajectory\.file")}
CASES = [(f, k) for f in FIELDS for k in FILES]


def _write(tmp_path, key):
    name, text = FILES[key]
    (tmp_path / name).write_text(text)
    return name


@pytest.mark.parametrize(("field", "key"), CASES, ids=[f"{f}-{k}" for f, k in CASES])
def test_a_data_file_error_names_line_and_column_and_quotes_nothing(tmp_path, field, key):
    make, dotted = FIELDS[field]
    path, settings = make(tmp_path, _write(tmp_path, key))
    with pytest.raises(ProblemError, match=rf"field '{dotted}': .*{EXPECTED[key]}") as info:
        load_problem(path, settings=settings)
    assert SECRET not in str(info.value) and "root:" not in str(info.value) and "API_" not in str(info.value)


@pytest.mark.parametrize("key", ["dotenv", "passwd"])
def test_gtmodel_loop_with_a_secret_correction_file_keeps_it_out_of_stderr_and_summary(tmp_path, capsys, key):
    path, _ = _loop(tmp_path, _write(tmp_path, key))
    out = tmp_path / "out"
    code = main(["loop", str(path), "--correction-file", str(tmp_path / FILES[key][0]), "--out", str(out), "--quiet"])
    err = capsys.readouterr().err
    summary = (out / "summary.json").read_text()
    assert (code, json.loads(summary)["status"]) == (EXIT_BAD_INPUT, "invalid_input")
    assert SECRET not in err + summary and "root:" not in err + summary and "Traceback" not in err
