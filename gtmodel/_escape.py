"""Names in generated artefacts: the one rule, one escaping function per target language.

A name (of a model, variable, unit, parameter set, CSV column, ...) or a description may
come from a user's file and hold anything. Where it becomes an identifier (a C symbol, a
macro prefix, an FMU's ``modelIdentifier``) it is validated with :func:`check_c_identifier`
or mapped with :func:`casadi_name` before anything is written; everywhere else it
passes through the function of this module for the language it lands in:

======================================  ===============================================
target                                  function
======================================  ===============================================
C string literal (``#define X "..."``)  :func:`c_string` (the literal, quotes included)
C comment (``/* ... */``)               :func:`c_comment` (one line of plain ASCII)
XML attribute / text (FMU description)  :func:`xml_attr` (quoted) / :func:`xml_text`
HTML text and attributes (reports)      :func:`html_text`
JSON inside ``<script>`` (reports)      :func:`json_script`
TOML basic string / comment written     :func:`toml_string` (quoted) / :func:`toml_comment`
CSV text cell, header name, comment     :func:`csv_field` / :func:`csv_name` (validated) / :func:`csv_comment`
======================================  ===============================================

Every function takes any ``str`` (lone surrogates and NUL included) and returns text that,
in its language, is exactly one literal, one attribute, one comment line or one text node:
nothing in the name ends the construct it stands in, continues it to the next line or is
read as markup or code.
"""

from __future__ import annotations

import html
import json
import re
from typing import Any

from gtmodel.errors import InputError

__all__ = ["C_IDENTIFIER", "casadi_name", "check_c_identifier", "c_string", "c_comment", "xml_attr", "xml_text", "html_text",
           "json_script", "toml_string", "toml_comment", "csv_field", "csv_name", "csv_comment"]

#: A C identifier (ASCII letters, digits and ``_``, not starting with a digit); matched with ``fullmatch``.
C_IDENTIFIER = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")
#: Characters XML 1.0 forbids even as references (C0 controls but tab, newline, return; surrogates; U+FFFE/U+FFFF).
_XML_BAD = re.compile("[\x00-\x08\x0b\x0c\x0e-\x1f\ud800-\udfff\ufffe\uffff]")
#: JSON characters that would end or alter a ``<script>`` block, or a JavaScript string (U+2028/2029).
_SCRIPT_CHARS = {"<": "\\u003c", ">": "\\u003e", "&": "\\u0026", "\u2028": "\\u2028", "\u2029": "\\u2029"}
_TOML_ESCAPES = {'"': '\\"', "\\": "\\\\", "\b": "\\b", "\t": "\\t", "\n": "\\n", "\f": "\\f", "\r": "\\r"}


def check_c_identifier(value: Any, what: str, example: str = "gt_model") -> str:
    """A C identifier, checked before it is written into generated code.

    Parameters
    ----------
    value : Any
        The candidate (e.g. a C prefix).
    what : str
        What it is, for the message (e.g. ``"prefix"``).
    example : str, optional
        A valid example shown in the message.

    Returns
    -------
    str
        ``value`` unchanged.

    Raises
    ------
    InputError
        ``value`` is not a string matching ``[A-Za-z_][A-Za-z0-9_]*`` in full (a trailing
        newline or any non-ASCII character is refused); the message shows it escaped.
    """
    if not isinstance(value, str) or not C_IDENTIFIER.fullmatch(value):
        shown = value[:80].encode("unicode_escape").decode("ascii") if isinstance(value, str) else type(value).__name__
        raise InputError(f"{what}: expected a C identifier (ASCII letters, digits, '_'; not starting with a digit) "
                         f"such as {example!r}, got {shown!r}")
    return value


def casadi_name(name: str) -> str:
    """A model name as a valid CasADi Function name and C identifier (the one mapping).

    Also importable as ``gtmodel.modeling.dae.casadi_name``.

    CasADi accepts a letter followed by letters, digits and non-consecutive underscores; C
    symbols of generated code are built from the same text. Every character outside
    ``[A-Za-z0-9]`` becomes ``_``, runs of ``_`` become one, ``_`` at either end is dropped and
    ``m_`` is put in front of a name that does not start with a letter: ``my-model`` ->
    ``my_model``, ``cart__pole`` -> ``cart_pole``, ``x.y`` -> ``x_y``, ``2dof`` -> ``m_2dof``.

    Parameters
    ----------
    name : str
        The model's name as the user wrote it.

    Returns
    -------
    str
        The mapped name.

    Raises
    ------
    InputError
        ``name`` is not a string, is longer than 200 characters, holds a control character,
        or has no ASCII letter or digit at all (nothing to map); the message shows it escaped.
    """
    if not isinstance(name, str):
        raise InputError(f"model name: expected a string, got {type(name).__name__}")
    shown = name[:60].encode("unicode_escape").decode("ascii")
    if len(name) > 200 or any(ord(c) < 32 or ord(c) == 127 for c in name) or not re.search(r"[A-Za-z0-9]", name):
        raise InputError(f"model name {shown!r}: expected at most 200 printable characters with a letter or digit "
                         "(mapped to a C and CasADi name: other characters become '_')")
    mapped = re.sub(r"_+", "_", re.sub(r"[^A-Za-z0-9]", "_", name)).strip("_")
    return mapped if mapped[0].isalpha() else f"m_{mapped}"


def c_string(text: str) -> str:
    """A C string literal, quotes included, holding exactly the UTF-8 bytes of ``text``.

    Printable ASCII is kept except ``"``, ``\\`` and ``?`` (written ``\\"``, ``\\\\``,
    ``\\?``: no trigraph such as ``??=`` forms); every other byte of the UTF-8 encoding
    (newline, NUL, non-ASCII; lone surrogates as their ``surrogatepass`` bytes) is a
    three-digit octal escape, which no following character can extend.

    Parameters
    ----------
    text : str
        Any text.

    Returns
    -------
    str
        E.g. ``c_string('a"b\\n')`` -> ``"a\\"b\\012"``.
    """
    out = ['"']
    for b in str(text).encode("utf-8", "surrogatepass"):
        c = chr(b)
        if c in '"\\?':
            out.append("\\" + c)
        elif 0x20 <= b < 0x7F:
            out.append(c)
        else:
            out.append(f"\\{b:03o}")
    out.append('"')
    return "".join(out)


def _code_point(c: str) -> str:
    return f"\\u{ord(c):04x}" if ord(c) <= 0xFFFF else f"\\U{ord(c):08x}"


def c_comment(text: str) -> str:
    """``text`` as one line of plain ASCII inside a C comment.

    Printable ASCII is kept; every other character (newline, NUL, non-ASCII), every
    ``\\`` and the second character of ``*/``, ``/*`` and ``??`` (a trigraph could splice
    lines) are written as ``\\uXXXX`` (``\\UXXXXXXXX`` beyond the BMP), as is a ``*``, ``/``
    or ``?`` at either end (the template's text around it). Readable, not reversible.

    Parameters
    ----------
    text : str
        Any text.

    Returns
    -------
    str
        Text with no line break, no comment delimiter and no backslash-newline; it may
        stand in a ``/* */`` or a ``//`` comment.
    """
    text = str(text)
    out: list[str] = []
    prev = ""
    for i, c in enumerate(text):
        edge = (i == 0 or i == len(text) - 1) and c in "*/?"
        pair = prev + c in ("*/", "/*", "??")
        if edge or pair or c == "\\" or not " " <= c <= "~":
            out.append(_code_point(c))
            prev = ""
        else:
            out.append(c)
            prev = c
    return "".join(out)


def xml_text(text: str) -> str:
    """``text`` as XML 1.0 character data (text or attribute content without the quotes).

    ``&``, ``<``, ``>``, ``"`` and ``'`` become entities; tab, newline and return become
    character references (kept through attribute normalisation); characters XML 1.0
    forbids (other C0 controls, lone surrogates, U+FFFE, U+FFFF) become U+FFFD.

    Parameters
    ----------
    text : str
        Any text.

    Returns
    -------
    str
        The escaped text.
    """
    s = html.escape(_XML_BAD.sub("\ufffd", str(text)), quote=True)
    return s.replace("\t", "&#9;").replace("\n", "&#10;").replace("\r", "&#13;")


def xml_attr(text: str) -> str:
    """``text`` as a double-quoted XML attribute value, quotes included (:func:`xml_text` inside).

    Parameters
    ----------
    text : str
        Any text.

    Returns
    -------
    str
        E.g. ``xml_attr('a"<b')`` -> ``"a&quot;&lt;b"`` (with the quotes).
    """
    return f'"{xml_text(text)}"'


def html_text(text: Any) -> str:
    """``str(text)`` as HTML text or a quoted attribute value (``&<>"'`` as references).

    Characters HTML does not allow in a document (C0 controls but tab, newline, return;
    lone surrogates, which UTF-8 cannot encode) become U+FFFD.

    Parameters
    ----------
    text : Any
        Any value (shown as ``str(text)``).

    Returns
    -------
    str
        The escaped text.
    """
    return html.escape(_XML_BAD.sub("\ufffd", str(text)), quote=True)


def json_script(value: Any) -> str:
    """``value`` as JSON for the inside of an HTML ``<script>`` element.

    ``json.dumps`` (NaN and infinity refused, non-ASCII as ``\\uXXXX``) with ``<``, ``>``,
    ``&``, U+2028 and U+2029 written ``\\u003c``, ``\\u003e``, ``\\u0026``, ``\\u2028``,
    ``\\u2029``: no ``</script>``, ``<!--`` or ``<script`` can appear, so the HTML parser
    leaves the block exactly where it ends, and ``JSON.parse`` gives back ``value``.

    Parameters
    ----------
    value : Any
        A JSON-serialisable value.

    Returns
    -------
    str
        The JSON text.

    Raises
    ------
    ValueError
        A non-finite float in ``value``.
    TypeError
        A value JSON cannot represent.
    """
    text = json.dumps(value, allow_nan=False, ensure_ascii=True)
    return re.sub("[<>&\u2028\u2029]", lambda m: _SCRIPT_CHARS[m.group(0)], text)


def toml_string(text: str) -> str:
    """``text`` as a TOML basic string, quotes included, that reads back as ``text``.

    ``"`` and ``\\`` and the control characters (with DEL) are escaped (``\\n``,
    ``\\uXXXX``); lone surrogates, which TOML cannot hold, become U+FFFD.

    Parameters
    ----------
    text : str
        Any text.

    Returns
    -------
    str
        E.g. ``toml_string('a"\\n')`` -> ``"a\\"\\n"`` (with the quotes).
    """
    out = ['"']
    for c in re.sub("[\ud800-\udfff]", "\ufffd", str(text)):
        if c in _TOML_ESCAPES:
            out.append(_TOML_ESCAPES[c])
        elif c < " " or c == "\x7f":
            out.append(f"\\u{ord(c):04x}")
        else:
            out.append(c)
    out.append('"')
    return "".join(out)


def _one_line(text: str) -> str:
    """Every line break ``str.splitlines`` knows and every other control character as a space."""
    return re.sub(r"[\x00-\x1f\x7f-\x9f\u2028\u2029\ud800-\udfff]", " ", str(text))


def toml_comment(text: str) -> str:
    """``text`` as the rest of one TOML comment line (after ``#``).

    Parameters
    ----------
    text : str
        Any text.

    Returns
    -------
    str
        The text with line breaks and control characters as spaces (TOML forbids control
        characters but tab in comments).
    """
    return _one_line(text)


def csv_comment(text: str) -> str:
    """``text`` as the rest of one comment line of a CSV table (after ``#``).

    Parameters
    ----------
    text : str
        Any text.

    Returns
    -------
    str
        The text with line breaks and control characters as spaces.
    """
    return _one_line(text)


def csv_field(value: Any) -> str:
    """``str(value)`` as one field of one CSV line (RFC 4180 quoting where needed).

    Line breaks and other control characters become spaces (a table is read line by
    line); a field holding a comma or a quote, or with spaces at either end, is quoted
    with its quotes doubled. ``csv.reader`` reads the field back.

    Parameters
    ----------
    value : Any
        A cell (e.g. a case name).

    Returns
    -------
    str
        E.g. ``csv_field('3, held')`` -> ``'"3, held"'``.
    """
    text = _one_line(value)
    if any(c in text for c in ',"') or text != text.strip():
        return '"' + text.replace('"', '""') + '"'
    return text


def csv_name(name: Any, where: str) -> str:
    """A CSV column name that gtmodel's table reader reads back as the same column.

    The reader (:func:`gtmodel._tables.read_table`) has no quoting, so a name is
    validated, not escaped.

    Parameters
    ----------
    name : Any
        The column name.
    where : str
        The file written (for the message).

    Returns
    -------
    str
        ``name``.

    Raises
    ------
    InputError
        ``name`` is not a string, is empty or has spaces at either end, starts with ``#``,
        or holds a comma, a quote, a line break or another control character.
    """
    if (not isinstance(name, str) or not name or name != name.strip() or name.startswith("#")
            or re.search(r'[,"\x00-\x1f\x7f-\x9f\u2028\u2029\ud800-\udfff]', name)):
        shown = name[:80].encode("unicode_escape").decode("ascii") if isinstance(name, str) else type(name).__name__
        raise InputError(f"{where}: column name {shown!r}: expected a non-empty name without commas, quotes, line "
                         "breaks or control characters, not starting with '#'")
    return name
