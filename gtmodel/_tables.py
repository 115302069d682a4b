"""CSV tables of numbers: the one reader (and writer) of gtmodel's data files.

Every CSV file gtmodel reads goes through :func:`read_table`: pose measurements and cart
surveys (:mod:`gtmodel.calibration.measurements`), motion logs
(:func:`gtmodel.calibration.identification.read_motion_log`), joint deflections
(``joint_stiffness_calibration``) and the ``trajectory.csv`` a trajectory problem writes
(re-read as an initial guess or replayed by ``tracking``). Each reader then checks its own
columns and what the numbers mean; the format below is the same for all.

Format
------
::

    # robot: L1, device: Leica laser tracker          <- comments: provenance, kept
    # date: 2011-05-03
    q1_m,q2_m,q3_m,Tx_m,Ty_m,Tz_m                     <- header: one name per column
    -0.25,0.10,0.35,-1.0723,2.9135,-0.6311            <- one row of numbers per line
    # tracker re-levelled here                        <- a comment between rows: skipped
    -0.20,0.12,0.31,-1.0511,2.9202,-0.6127

- UTF-8 text (a byte-order mark is allowed), values separated by commas.
- Lines starting with ``#`` are comments. Those above the header are the file's provenance
  (:attr:`Table.comments`, written back by :func:`write_table`); those between rows are skipped.
- The header is the first line that is not a comment: the column names, each non-empty and
  unique (surrounding spaces are ignored). Each reader says which columns it needs; most
  may come in any order.
- Units are SI and part of the column name where a format names them (``t_s``, ``q1_m``,
  ``tau1_N``, ``theta1_deg``: degrees only where the name says so); the ``trajectory.csv``
  of the trajectory problems uses its short names ``t, x, y, z, q1, ...`` in s and m.
- A column name may end in its unit in square brackets after a space, ``name [unit]``
  (``t [s]``, ``ind.i [A]``, ``T[0] [m]``; the ``trajectories.csv`` of a model's result
  writes them so, :func:`split_unit`): the column is ``name`` (:attr:`Table.columns`) and the unit is
  kept (:attr:`Table.units`); a header without units (a file written before) reads as before.
  A units header keeps the file one header line and one row per sample, so that pandas'
  ``read_csv`` and NumPy's ``loadtxt(skiprows=1)`` read it as they read any table.
- Every data row holds exactly one value per header column, each a decimal number
  (``[+-]digits[.digits][e[+-]digits]``, spaces around it allowed). NaN, inf, empty fields,
  thousands separators and quotes are errors.
- Empty lines are allowed only at the end of the file.

Every error is an :class:`~gtmodel.errors.InputError` naming the file, the line (1-based
line number in the file) and, for a value, the column (by its number, 1-based, and by its
name where the name is a plain short token, :func:`column_label`) and what was expected.
A message never quotes a value of the file, nor a line of it: a file named by mistake (a
``.env``, ``/etc/passwd``) must not end up in a terminal, a log or a ``summary.json``.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Sequence

import numpy as np
import numpy.typing  # noqa: F401  (np.typing in annotations)

from gtmodel._escape import csv_comment, csv_name
from gtmodel.errors import InputError

__all__ = ["Table", "read_table", "write_table", "split_unit", "with_unit", "column_label", "column_names", "is_token", "quotable", "label"]

_NUMBER = r"[+-]?(?:\d+(?:\.\d*)?|\.\d+)(?:[eE][+-]?\d+)?"
_NUMBER_RE = re.compile(_NUMBER)
_NONFINITE_RE = re.compile(r"[+-]?(?:nan|inf|infinity)", re.IGNORECASE)
#: ``name [unit]``: a space, then the unit in brackets at the end (``T[0]`` alone is a name).
_UNIT_RE = re.compile(r"(\S(?:.*\S)?) \[([^\[\],]*)\]")
#: Largest file :func:`read_table` reads when its caller sets no smaller cap [bytes].
DEFAULT_MAX_BYTES = 256_000_000
#: Lines beyond ``max_rows`` a table may have (header, comments, empty lines at the end).
_SLACK_LINES = 10_000
#: Longest column name a message quotes [characters]; a longer one is named by its number alone.
TOKEN = 24
#: A column name a message may quote: a plain short token (letters, digits, ``_``, ``.``, an index ``[k]``).
_TOKEN_RE = re.compile(r"[A-Za-z_][A-Za-z0-9_.]*(?:\[[0-9]+\])*")


def column_label(index: int, name: str | None = None) -> str:
    """How a message names a column of a data file: its number, and its name only if that is a plain token.

    The one place messages about a data file's columns are formatted: a header cell is the
    file's content (the first line of a ``.env`` file read by mistake, a password), so it is
    quoted only when it is a short plain name (``q1``, ``t_s``, ``T[0]``; at most
    :data:`TOKEN` characters of letters, digits, ``_`` and ``.``), never otherwise.

    Parameters
    ----------
    index : int
        0-based position of the column.
    name : str, optional
        Its name as read from the header.

    Returns
    -------
    str
        ``"column 'q1'"`` or ``"column 3"`` (1-based).
    """
    return f"column '{name}'" if is_token(name) else f"column {index + 1}"


def is_token(name: str | None) -> bool:
    """Whether a name read from a data file may be quoted in a message (:func:`column_label`).

    Parameters
    ----------
    name : str or None
        A header cell.

    Returns
    -------
    bool
    """
    return isinstance(name, str) and len(name) <= TOKEN and _TOKEN_RE.fullmatch(name) is not None


def quotable(columns: Sequence[str]) -> bool:
    """Whether a header's names may be quoted at all: two columns or more, every one a plain token (:func:`is_token`).

    A line without a comma (a ``.env`` line, a password, a line of ``/etc/passwd``) is a
    one-column "header" of a file that is no table: its name is never quoted.

    Parameters
    ----------
    columns : sequence of str
        The header's column names.

    Returns
    -------
    bool
    """
    return len(columns) >= 2 and all(is_token(c) for c in columns)


def label(columns: Sequence[str], index: int) -> str:
    """:func:`column_label` of a column of a header: named only where the header is :func:`quotable`.

    Parameters
    ----------
    columns : sequence of str
        The header's column names.
    index : int
        0-based position of the column.

    Returns
    -------
    str
    """
    return column_label(index, columns[index] if quotable(columns) else None)


def column_names(columns: Sequence[str]) -> str:
    """A data file's columns for a message: their names where the header is :func:`quotable`, else their count.

    Parameters
    ----------
    columns : sequence of str
        The header's column names.

    Returns
    -------
    str
        E.g. ``"t, q1, q2"`` or ``"3 columns, named by number"``.
    """
    if quotable(columns):
        return ", ".join(columns)
    return f"{len(columns)} column{'s' if len(columns) != 1 else ''}, named by number"


def _what_is(text: str) -> str:
    """What a cell holds, in words, without its content."""
    s = text.strip()
    if not s:
        return "an empty field"
    if _NONFINITE_RE.fullmatch(s):
        return "NaN or infinity"
    return f"{len(s)} character{'s' if len(s) != 1 else ''} of text"


@dataclass(frozen=True)
class Table:
    """A CSV table read by :func:`read_table`.

    Parameters
    ----------
    source : str
        The file (named in errors).
    columns : tuple of str
        The header's column names, in file order.
    data : numpy.ndarray, shape (N, len(columns))
        The values, one row per data line.
    lines : numpy.ndarray of int, shape (N,)
        The 1-based line number in the file of each row.
    header_line : int
        The 1-based line number of the header.
    comments : tuple of str
        The ``#`` lines above the header, without the ``#``.
    units : dict of str to str
        Column name -> unit, for the columns whose header named one (``name [unit]``).
    """

    source: str
    columns: tuple[str, ...]
    data: np.ndarray
    lines: np.ndarray
    header_line: int
    comments: tuple[str, ...] = ()
    units: dict[str, str] = field(default_factory=dict)

    @property
    def n_rows(self) -> int:
        """Number of data rows N."""
        return int(self.data.shape[0])

    def column(self, name: str) -> np.ndarray:
        """The values of one column.

        Parameters
        ----------
        name : str
            A header name.

        Returns
        -------
        numpy.ndarray, shape (N,)

        Raises
        ------
        InputError
            No such column (the header line named).
        """
        return self.data[:, self.index(name)]

    def columns_of(self, names: Sequence[str]) -> np.ndarray:
        """The values of several columns, in the order given.

        Parameters
        ----------
        names : sequence of str
            Header names.

        Returns
        -------
        numpy.ndarray, shape (N, len(names))

        Raises
        ------
        InputError
            A name not in the header.
        """
        return self.data[:, [self.index(c) for c in names]]

    def index(self, name: str) -> int:
        """Position of a column in the header.

        Parameters
        ----------
        name : str
            A header name.

        Returns
        -------
        int

        Raises
        ------
        InputError
            No such column (the header line named).
        """
        try:
            return self.columns.index(name)
        except ValueError:
            raise self.error(f"missing column(s) {name}") from None

    def check_columns(self, required: Sequence[str] = (), allowed: Sequence[str] | None = None, note: str = "") -> None:
        """Check the header: every ``required`` column present, no column outside ``allowed``.

        Parameters
        ----------
        required : sequence of str, optional
            Columns the file must have.
        allowed : sequence of str, optional
            Every accepted column (None: any).
        note : str, optional
            Appended to a missing-column message (e.g. which columns come together).

        Raises
        ------
        InputError
            ``"<file>: line <k> (header): unknown column '<c>' (allowed: ...)"`` or
            ``"... missing column(s) <c1>, <c2>"``.
        """
        if allowed is not None:
            for k, c in enumerate(self.columns):
                if c not in allowed:
                    raise self.error(f"unknown {label(self.columns, k)} (allowed: {', '.join(allowed)})")
        missing = [c for c in required if c not in self.columns]
        if missing:
            raise self.error(f"missing column(s) {', '.join(missing)}{f' ({note})' if note else ''}")

    def check_unique_rows(self, key_columns: Sequence[str] | None = None, what: str = "identical to") -> None:
        """Reject a row whose values (in ``key_columns``, or in every column) repeat an earlier row's.

        Parameters
        ----------
        key_columns : sequence of str, optional
            The columns that must not repeat together (default: all).
        what : str, optional
            How the repeated row relates to the first, for the message.

        Raises
        ------
        InputError
            The first repeated row, naming its line and the line it repeats.
        """
        cols = list(range(len(self.columns))) if key_columns is None else [self.index(c) for c in key_columns]
        key = np.ascontiguousarray(self.data[:, cols] + 0.0)  # + 0.0 maps -0.0 to 0.0
        first: dict[bytes, int] = {}
        for r in range(key.shape[0]):
            b = key[r].tobytes()
            if b in first:
                named = "all columns" if key_columns is None else ", ".join(f"'{c}'" for c in key_columns)
                raise self.error(f"duplicated row, {what} line {int(self.lines[first[b]])} ({named})", row=r)
            first[b] = r

    def error(self, message: str, row: int | None = None, column: str | None = None) -> InputError:
        """An error naming the file, the line (the header's when ``row`` is None) and the column.

        Parameters
        ----------
        message : str
            What is wrong (after the location).
        row : int, optional
            0-based data row (its file line is named); None names the header line.
        column : str, optional
            Column name, one the reader asked for (quoted in the message); several may be
            given joined by commas. A name from the file itself is never passed here
            (:func:`column_label`).

        Returns
        -------
        InputError
            ``"<file>: line <k>, column '<c>': <message>"`` (to raise).
        """
        where = f"line {int(self.lines[row])}" if row is not None else f"line {self.header_line} (header)"
        if column is not None:
            where += f", column{'s' if ',' in column else ''} '{column}'"
        return InputError(f"{self.source}: {where}: {message}")


def _number(source: str, lineno: int, index: int, columns: Sequence[str], text: str) -> float:
    s = text.strip()
    if _NUMBER_RE.fullmatch(s):
        return float(s)
    where = f"{source}: line {lineno}, {label(columns, index)}"
    if _NONFINITE_RE.fullmatch(s):
        raise InputError(f"{where}: NaN/inf is not allowed, expected a finite decimal number")
    raise InputError(f"{where}: expected a decimal number, got {_what_is(text)}")


def split_unit(column: str) -> tuple[str, str | None]:
    """A header cell's name and unit: ``"ind.i [A]"`` -> ``("ind.i", "A")``, ``"t"`` -> ``("t", None)``.

    Parameters
    ----------
    column : str
        A column name as written, surrounding spaces ignored.

    Returns
    -------
    tuple
        ``(name, unit)``; ``unit`` is None without a ``" [unit]"`` ending (``"T[0]"`` is a name).
    """
    text = column.strip()
    m = _UNIT_RE.fullmatch(text)
    return (m.group(1), m.group(2).strip()) if m else (text, None)


def with_unit(name: str, unit: str | None) -> str:
    """The header cell of column ``name`` with its unit: ``name [unit]`` (``name`` alone without one).

    Parameters
    ----------
    name : str
        The column name.
    unit : str or None
        Its unit (e.g. ``"A"``, ``"rad/s"``); None or empty: no unit written.

    Returns
    -------
    str
    """
    return f"{name} [{unit}]" if unit else name


def read_table(
    path: str | Path, what: str = "table", header: Sequence[str] | None = None, max_rows: int | None = None, max_bytes: int | None = None,
    text_columns: Sequence[str] = (),
) -> Table:
    """Read a CSV table of numbers (format in the module docstring), strictly validated.

    Parameters
    ----------
    path : str or pathlib.Path
        The file.
    what : str, optional
        What the file is, for messages (``"cannot read <what>"``).
    header : sequence of str, optional
        The exact header (names in this order), when the format fixes it.
    max_rows : int, optional
        Most data rows accepted (a larger file is refused at the first row too many).
    max_bytes : int, optional
        Largest file size accepted [bytes]: checked on the file's size before reading and
        while reading (a file whose size the system does not report is read at most this
        far); default :data:`DEFAULT_MAX_BYTES`.
    text_columns : sequence of str, optional
        Columns of text, left out of the table if present (e.g. ``"point"`` of a result's
        ``trajectories.csv``: which kind of collocation point each time is).

    Returns
    -------
    Table

    Raises
    ------
    InputError
        Unreadable, too large or non-UTF-8 file; no header; an empty or repeated column
        name (or another header than ``header``); a row with another number of values than
        the header; a value that is not a finite decimal number; a comment-free empty line
        inside the data; more than ``max_rows`` rows. The message names the file, the line
        (1-based), the column (:func:`column_label`) and what was expected, and never
        quotes a value or a line of the file.
    """
    source = str(path)
    cap = DEFAULT_MAX_BYTES if max_bytes is None else max_bytes
    try:
        if Path(path).stat().st_size > cap:
            raise InputError(f"{source}: {Path(path).stat().st_size} bytes, expected at most {cap} bytes")
        with open(path, "rb") as fh:
            raw = fh.read(cap + 1)  # bounded also when the size was not reported (a pipe, /proc)
        if len(raw) > cap:
            raise InputError(f"{source}: more than {cap} bytes, expected at most {cap} bytes")
        text = raw.decode("utf-8-sig")
    except OSError as exc:
        raise InputError(f"{source}: cannot read {what} ({exc.strerror})") from None
    except UnicodeDecodeError as exc:
        raise InputError(f"{source}: cannot read {what} (not UTF-8 text: byte {exc.start})") from None
    if max_rows is not None and text.count("\n") > max_rows + _SLACK_LINES:  # before splitting: lines cost memory
        raise InputError(f"{source}: more than {max_rows + _SLACK_LINES} lines, expected at most {max_rows} data rows "
                         f"(and up to {_SLACK_LINES} lines of header, comments and trailing empty lines)")
    lines = text.splitlines()
    n = len(lines)
    while n > 0 and not lines[n - 1].strip():
        n -= 1  # empty lines at the end are allowed
    comments: list[str] = []
    k = 0
    while k < n and lines[k].startswith("#"):
        comments.append(lines[k][1:])
        k += 1
    expected = ",".join(header) if header is not None else "(a line of column names)"
    if k >= n:
        state = "the file is empty" if not comments else "the file holds only '#' comments"
        raise InputError(f"{source}: expected the header {expected}, {state} (no header line)")
    header_line = k + 1
    if not lines[k].strip():
        raise InputError(f"{source}: line {header_line}: empty line where the header {expected} was expected")
    named = [split_unit(c) for c in lines[k].split(",")]
    columns = tuple(name for name, _ in named)
    units = {name: unit for name, unit in named if unit}
    if header is not None and columns != tuple(header):
        k_bad = next((j for j, (a, b) in enumerate(zip(columns, header)) if a != b), min(len(columns), len(header)))
        got = (f"{len(columns)} columns" if len(columns) != len(header) else
               f"{label(columns, k_bad)} is not '{header[k_bad]}'")
        raise InputError(f"{source}: line {header_line}: expected the header {expected}, got {got}")
    seen: dict[str, int] = {}
    for j, c in enumerate(columns):
        if c == "":
            raise InputError(f"{source}: line {header_line} (header): empty column name (column {j + 1})")
        if c in seen:
            raise InputError(f"{source}: line {header_line} (header): {label(columns, j)} appears twice (columns {seen[c] + 1} and {j + 1})")
        seen[c] = j
    if max_rows is not None and n - k - 1 > max_rows:  # refuse a huge file before parsing it
        count = 0
        for j in range(k + 1, n):
            if not lines[j].startswith("#"):
                count += 1
                if count > max_rows:
                    raise InputError(f"{source}: line {j + 1}: more than {max_rows} data rows")
    width = len(columns)
    row_re = re.compile(rf"\s*{_NUMBER}\s*(?:,\s*{_NUMBER}\s*){{{width - 1}}}")
    rows: list[list[str]] = []
    linenos: list[int] = []
    for j in range(k + 1, n):
        line, lineno = lines[j], j + 1
        if line.startswith("#"):
            continue
        if max_rows is not None and len(rows) >= max_rows:
            raise InputError(f"{source}: line {lineno}: more than {max_rows} data rows")
        fields = line.split(",")
        if not row_re.fullmatch(line):  # the slow path finds what is wrong
            if not line.strip():
                raise InputError(f"{source}: line {lineno}: empty line inside the data (allowed only at the end of the file)")
            if len(fields) != width:
                raise InputError(f"{source}: line {lineno}: {len(fields)} values, expected {width} (one per column of the "
                                 f"header, line {header_line})")
            for index, (name, cell) in enumerate(zip(columns, fields)):
                if name not in text_columns:
                    _number(source, lineno, index, columns, cell)
        rows.append([f for name, f in zip(columns, fields) if name not in text_columns])
        linenos.append(lineno)
    columns = tuple(c for c in columns if c not in text_columns)
    width = len(columns)
    data = np.array(rows, dtype=float) if rows else np.empty((0, width))
    return Table(source, columns, data.reshape(len(rows), width), np.array(linenos, dtype=int), header_line, tuple(comments),
                 {c: u for c, u in units.items() if c in columns})


def write_table(path: str | Path, columns: Sequence[str], data: np.typing.ArrayLike, comments: Sequence[str] = (), integer_columns: Sequence[int] = (), what: str = "table") -> Path:
    """Write a CSV table that :func:`read_table` reads back exactly (``repr`` of each float).

    Parameters
    ----------
    path : str or pathlib.Path
        File to write (overwritten).
    columns : sequence of str
        Header names.
    data : array_like, shape (N, len(columns))
        Values.
    comments : sequence of str, optional
        Comment lines written above the header (each after a ``#``; line breaks and control
        characters become spaces, :func:`gtmodel._escape.csv_comment`).
    integer_columns : sequence of int, optional
        Columns written as integers.
    what : str, optional
        What the file is, for messages.

    Returns
    -------
    pathlib.Path
        The file written.

    Raises
    ------
    InputError
        The file cannot be written, or a column name would not read back as one column
        (:func:`gtmodel._escape.csv_name`: a comma, quote, line break, ...).
    """
    path = Path(path)
    lines = ["#" + csv_comment(c) for c in comments]
    lines.append(",".join(csv_name(c, f"{path}: {what}") for c in columns))
    for row in np.asarray(data, dtype=float):
        lines.append(",".join(str(int(x)) if j in integer_columns else repr(float(x)) for j, x in enumerate(row)))
    try:
        path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    except OSError as exc:
        raise InputError(f"{path}: cannot write {what} ({exc.strerror})") from None
    return path
