"""The one CSV table reader (:mod:`gtmodel._tables`): format rules and the errors naming file, line and column.

Independent reference: the tables are written here as literal text, so each expected line
number and value is read off the test itself.
"""

from __future__ import annotations

import numpy as np
import pytest

from gtmodel._tables import read_table, split_unit, with_unit, write_table
from gtmodel.errors import GtModelError, InputError

GOOD = "# robot: L1\n# date: 2011-05-03\nt_s, q1_m ,tau1_N\n0.0,0.1,-2.5\n# a note between rows\n0.004,+.2,3e-1\n\n\n"


def _write(tmp_path, text, name="t.csv"):
    p = tmp_path / name
    p.write_text(text, encoding="utf-8")
    return p


def test_good_table(tmp_path):
    """Comments at the top kept, a comment between rows skipped, names stripped, trailing empty lines allowed."""
    t = read_table(_write(tmp_path, GOOD))
    assert t.columns == ("t_s", "q1_m", "tau1_N") and t.header_line == 3
    assert t.comments == (" robot: L1", " date: 2011-05-03")
    np.testing.assert_array_equal(t.data, [[0.0, 0.1, -2.5], [0.004, 0.2, 0.3]])
    assert t.lines.tolist() == [4, 6] and t.n_rows == 2
    np.testing.assert_array_equal(t.column("tau1_N"), [-2.5, 0.3])
    np.testing.assert_array_equal(t.columns_of(["tau1_N", "t_s"]), [[-2.5, 0.0], [0.3, 0.004]])


def test_byte_order_mark_and_header_only(tmp_path):
    p = tmp_path / "bom.csv"
    p.write_bytes(b"\xef\xbb\xbfa,b\n")
    t = read_table(p)
    assert t.columns == ("a", "b") and t.data.shape == (0, 2)


def test_round_trip_is_exact(tmp_path):
    data = np.array([[1.0, 0.1 + 0.2, -1e-300], [2.0, np.pi, 6.02e23]])
    p = write_table(tmp_path / "w.csv", ["arm", "x_m", "y_m"], data, comments=[" source: test"], integer_columns=(0,))
    assert p.read_text().splitlines()[:2] == ["# source: test", "arm,x_m,y_m"]
    t = read_table(p)
    np.testing.assert_array_equal(t.data, data)
    assert t.comments == (" source: test",)


BAD = [
    ("letters", "a,b\n1,2\n3,x\n", r"t\.csv: line 3, column 'b': expected a decimal number, got 1 character of text$"),
    ("empty_field", "a,b\n1,\n", r"line 2, column 'b': expected a decimal number, got an empty field$"),
    ("nan", "a,b\n1,2\nnan,4\n", r"line 3, column 'a': NaN/inf is not allowed, expected a finite decimal number$"),
    ("inf", "a,b\n-Infinity,2\n", r"line 2, column 'a': NaN/inf is not allowed"),
    ("underscore", "a,b\n1_000,2\n", r"line 2, column 'a': expected a decimal number, got 5 characters of text$"),
    ("quoted", 'a,b\n"1",2\n', r"line 2, column 'a': expected a decimal number, got 3 characters of text$"),
    ("thousands", "a,b\n1,2,5\n", r"line 2: 3 values, expected 2 \(one per column of the header, line 1\)"),
    ("too_few", "a,b,c\n1,2\n", r"line 2: 2 values, expected 3"),
    ("empty_line_inside", "a,b\n1,2\n\n3,4\n", r"line 3: empty line inside the data"),
    ("repeated_column", "# c\na,b,a\n1,2,3\n", r"line 2 \(header\): column 'a' appears twice \(columns 1 and 3\)"),
    ("empty_column", "a,,b\n1,2,3\n", r"line 1 \(header\): empty column name \(column 2\)"),
    ("one_column_not_named", "hunter2\nx\n", r"line 2, column 1: expected a decimal number, got 1 character of text$"),
    ("a_name_not_a_token", "a,b=c\n1,x\n", r"line 2, column 2: expected a decimal number"),
    ("no_header", "# only\n# comments\n", r"expected the header \(a line of column names\), the file holds only '#' comments \(no header line\)"),
    ("empty_file", "", r"t\.csv: expected the header .*the file is empty \(no header line\)"),
]


@pytest.mark.parametrize("case, text, match", BAD, ids=[c[0] for c in BAD])
def test_bad_rows_and_columns(tmp_path, case, text, match):
    """Each malformed table: an InputError (a GtModelError) naming the file, the line and the column."""
    p = _write(tmp_path, text)
    with pytest.raises(InputError, match=match) as info:
        read_table(p)
    assert isinstance(info.value, GtModelError) and str(p) in str(info.value)


def test_fixed_header_and_limits(tmp_path):
    p = _write(tmp_path, "# c\na,b\n1,2\n3,4\n5,6\n")
    assert read_table(p, header=("a", "b")).n_rows == 3
    with pytest.raises(InputError, match=r"line 2: expected the header b,a, got column 'a' is not 'b'$"):
        read_table(p, header=("b", "a"))
    with pytest.raises(InputError, match=r"line 5: more than 2 data rows"):
        read_table(p, max_rows=2)
    with pytest.raises(InputError, match=r"bytes, expected at most 4 bytes"):
        read_table(p, max_bytes=4)


def test_unreadable_files(tmp_path):
    with pytest.raises(InputError, match=r"nope\.csv: cannot read motion log \("):
        read_table(tmp_path / "nope.csv", "motion log")
    p = tmp_path / "latin.csv"
    p.write_bytes("a\n# caf\xe9\n1\n".encode("latin-1"))
    with pytest.raises(InputError, match=r"latin\.csv: cannot read the data file \(not UTF-8 text: byte 7\)"):
        read_table(p, "the data file")


def test_column_checks_name_the_header_line(tmp_path):
    t = read_table(_write(tmp_path, "# c\nq1_m,Tz_mm\n1,2\n"))
    with pytest.raises(InputError, match=r"line 2 \(header\): unknown column 'Tz_mm' \(allowed: q1_m, Tz_m\)"):
        t.check_columns(allowed=["q1_m", "Tz_m"])
    with pytest.raises(InputError, match=r"line 2 \(header\): missing column\(s\) q2_m, q3_m \(they come together\)"):
        t.check_columns(["q1_m", "q2_m", "q3_m"], note="they come together")
    with pytest.raises(InputError, match=r"line 2 \(header\): missing column\(s\) t_s"):
        t.column("t_s")
    err = t.error("expected a positive weight", row=0, column="q1_m")
    assert str(err).endswith("t.csv: line 3, column 'q1_m': expected a positive weight")


def test_guess_reader_uses_the_table_format(tmp_path):
    """The trajectory.csv read back as an initial guess: the same rules, its own column check."""
    from gtmodel.trajectory.point_to_point import _read_guess_csv

    cols = ["t", "x", "y", "z", "xd", "yd", "zd", "tau1", "tau2", "tau3", "q1"]
    rows = [",".join(str(0.004 * k + j) for j in range(len(cols))) for k in range(3)]
    p = _write(tmp_path, ",".join(cols) + "\n" + "\n".join(rows) + "\n", "trajectory.csv")
    got = _read_guess_csv(p)
    np.testing.assert_allclose(got["tau3"], [9.0, 9.004, 9.008])
    p.write_text(",".join(cols[:-2]) + "\n" + "\n".join(r.rsplit(",", 2)[0] for r in rows) + "\n")
    with pytest.raises(InputError, match=r"guess: .*trajectory\.csv: line 1 \(header\): missing column\(s\) tau3"):
        _read_guess_csv(p)
    p.write_text(",".join(cols) + "\n" + rows[0] + "\n" + rows[0].replace("0.0", "nan", 1) + "\n")
    with pytest.raises(InputError, match=r"guess: .*trajectory\.csv: line 3, column 't': NaN/inf is not allowed"):
        _read_guess_csv(p)


#: Files named by mistake as data: their secret must appear in no message (issue 67). Each: the text, and the
#: message (a regular expression) naming the line, the column by number and what was expected.
SECRETS = {
    "dotenv": ("API_KEY=sk-SECRET-abc123\nDB_PASSWORD=SECRET-hunter2\n",
               r"line 2, column 1: expected a decimal number, got 26 characters of text$"),
    "passwd": ("root:x:0:0:root:/root:/bin/bash-SECRET\ndaemon:x:1:1:daemon:/usr/sbin:/usr/sbin/nologin-SECRET\n",
               r"line 2, column 1: expected a decimal number, got 54 characters of text$"),
    "a_header_of_secrets": ("SECRET_a,SECRET_b=1\n1,2\n3,x\n", r"line 3, column 2: expected a decimal number, got 1 character of text$"),
    "a_secret_cell": ("t,q1\n0,1\n1,SECRETvalue\n", r"line 3, column 'q1': expected a decimal number, got 11 characters of text$"),
    "a_secret_nan": ("t,q1\n0,nan\n", r"line 2, column 'q1': NaN/inf is not allowed, expected a finite decimal number$"),
    "a_secret_row_width": ("t,q1\n0,SECRET,1\n", r"line 2: 3 values, expected 2 \(one per column of the header, line 1\)$"),
    "a_secret_repeated_name": ("SECRET:1,x,SECRET:1\n1,2,3\n", r"line 1 \(header\): column 3 appears twice \(columns 1 and 3\)$"),
}


@pytest.mark.parametrize("text, match", SECRETS.values(), ids=SECRETS)
def test_a_file_with_secrets_is_never_quoted(tmp_path, text, match):
    """A .env file or a copy of /etc/passwd read as a table: the message names the line, the column and what was
    expected, and quotes no value nor any line of the file (no 'SECRET'). Reference: the file's own lines."""
    p = _write(tmp_path, text)
    with pytest.raises(InputError, match=match) as info:
        read_table(p)
    assert "SECRET" not in str(info.value)


@pytest.mark.parametrize("header, columns, match", [
    (("a", "b"), "SECRET=x,b\n1,2\n", r"line 1: expected the header a,b, got column 1 is not 'a'$"),
    (("a", "b"), "a,b,c\n1,2,3\n", r"line 1: expected the header a,b, got 3 columns$"),
], ids=["a_secret_name", "another_width"])
def test_a_fixed_header_is_checked_without_quoting_the_file(tmp_path, header, columns, match):
    p = _write(tmp_path, columns)
    with pytest.raises(InputError, match=match) as info:
        read_table(p, header=header)
    assert "SECRET" not in str(info.value)


def test_unknown_columns_of_a_header_that_is_no_table_are_named_by_number(tmp_path):
    t = read_table(_write(tmp_path, "SECRET=1\n"))
    with pytest.raises(InputError, match=r"line 1 \(header\): unknown column 1 \(allowed: t_s\)$") as info:
        t.check_columns(allowed=["t_s"])
    assert "SECRET" not in str(info.value)


def test_empty_lines_beyond_the_row_cap_are_refused_before_splitting(tmp_path):
    p = _write(tmp_path, "a\n1\n" + "\n" * 20_000)
    with pytest.raises(InputError, match=r"more than 10010 lines, expected at most 10 data rows"):
        read_table(p, max_rows=10)
    assert read_table(_write(tmp_path, "a\n1\n" + "\n" * 9_000), max_rows=10).n_rows == 1  # trailing empty lines within the slack


@pytest.mark.parametrize(
    "cell, expected",
    [("t [s]", ("t", "s")), ("ind.i [A]", ("ind.i", "A")), ("T[0]", ("T[0]", None)), ("T[0] [m]", ("T[0]", "m")),
     (" x ", ("x", None)), ("w [rad/s]", ("w", "rad/s")), ("a[b]", ("a[b]", None))],
    ids=["time", "scalar", "vector-element", "vector-element-unit", "spaces", "compound", "no-space"],
)
def test_split_unit(cell, expected):
    """Written out by hand: the unit is a bracketed ending after a space; ``T[0]`` stays a name."""
    assert split_unit(cell) == expected
    name, unit = expected
    assert split_unit(with_unit(name, unit)) == expected  # the writer's form reads back


@pytest.mark.parametrize(
    "header", ["t,point,ind.i,T[0]", "t [s],point,ind.i [A],T[0] [m]"], ids=["before-units", "with-units"]
)
def test_headers_with_and_without_units_read_alike(tmp_path, header):
    """A result table written before units (plain names) and one with ``name [unit]`` give the same columns and
    numbers (pandas' read_csv, a second reader, sees one header row and the same shape)."""
    import pandas as pd

    path = _write(tmp_path, header + "\n0,start,1.5,2\n0.1,collocation,2.5,3\n")
    table = read_table(path, text_columns=("point",))
    assert table.columns == ("t", "ind.i", "T[0]")
    np.testing.assert_array_equal(table.data, [[0.0, 1.5, 2.0], [0.1, 2.5, 3.0]])
    assert table.units == ({} if "[s]" not in header else {"t": "s", "ind.i": "A", "T[0]": "m"})
    assert pd.read_csv(path).shape == (2, 4)
