"""gtmodel._escape: one escaping function per target language, checked by that language's own reader.

Independent checks: a C compiler (gcc -Werror -pedantic, trigraphs on) compiles the escaped
literals and comments and the program prints back the original UTF-8 bytes; expat
(xml.etree) parses the XML, tomllib the TOML, json/html.parser the script block. Hypothesis
feeds arbitrary Unicode (quotes, ``*/``, newlines, backslashes, NUL, ``??=``, ``%:``, lone
surrogates); the C strings of one run are batched into one program (one compile per example).
"""

from __future__ import annotations

import csv
import html
import json
import subprocess
import tomllib
import xml.etree.ElementTree as ET
from html.parser import HTMLParser

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from gtmodel._escape import (c_comment, c_string, check_c_identifier, csv_comment, csv_field, csv_name, html_text,
                             json_script, toml_comment, toml_string, xml_attr, xml_text)
from gtmodel.codegen.build import find_compiler
from gtmodel.errors import InputError

#: The name of issue 44: unescaped, it closes the version literal and adds a constructor.
ISSUE_NAME = ('p"; } int system(const char *); __attribute__((constructor)) static void pwn(void) '
              '{ system("touch PWNED"); } const char *gt_q(void) { return "')
FRAGMENTS = ['"', "'", "*/", "/*", "//", "\\", "\n", "\r", "\x00", "??=", "??/", "??", "%:", "%:%:", "<:", "#",
             "\u2028", "\u2029", "é", "😀", "\ud800", "<!--<script>", "</script>", "&", "]]>", "\x7f", "?"]
#: Arbitrary Unicode with the hostile fragments mixed in.
TEXTS = st.lists(st.one_of(st.text(max_size=8), st.sampled_from(FRAGMENTS)), max_size=12).map("".join)
FIXED = [ISSUE_NAME, "", "?", "??", "*", "/", "a*", "/a", "\\", "x\\", "??/", "*/*/", "\x00\x00", "\\\n", "%:include </etc/passwd>"]

#: The pure-Python properties: fewer examples than Hypothesis' 100 (the machine is shared).
QUICK = settings(max_examples=40, deadline=None)

CFLAGS = ["-std=c99", "-trigraphs", "-Wall", "-Wextra", "-Wtrigraphs", "-Wcomment", "-pedantic", "-Werror"]


def _round_trip_program(texts: list[str]) -> str:
    """C that holds each text as a literal, between comments inside code, and prints each literal's bytes."""
    lines = ["#include <stdio.h>", "int main(void)", "{", "    int n = 0;"]
    for i, s in enumerate(texts):
        lines += [f"    /* {c_comment(s)} */ n += 1; // {c_comment(s)}",
                  f"    {{ static const char s[] = {c_string(s)}; /* {c_comment(s)}*/n += 1;",
                  '      printf("%lu:", (unsigned long)(sizeof s - 1)); fwrite(s, 1, sizeof s - 1, stdout); }']
    lines += ['    printf("%d", n);', "    return 0;", "}"]
    return "\n".join(lines) + "\n"


def _compile_and_run(texts: list[str], tmp_path) -> bytes:
    src, exe = tmp_path / "rt.c", tmp_path / "rt"
    src.write_text(_round_trip_program(texts), encoding="ascii")  # escaped C is plain ASCII
    subprocess.run([*find_compiler(), *CFLAGS, str(src), "-o", str(exe)], check=True, capture_output=True, text=True)
    return subprocess.run([str(exe)], check=True, capture_output=True).stdout


def _parse_output(out: bytes, count: int) -> tuple[list[bytes], int]:
    got = []
    for _ in range(count):
        size, out = out.split(b":", 1)
        got.append(out[:int(size)])
        out = out[int(size):]
    return got, int(out)


def _check_round_trip(texts: list[str], tmp_path) -> None:
    got, n = _parse_output(_compile_and_run(texts, tmp_path), len(texts))
    assert got == [s.encode("utf-8", "surrogatepass") for s in texts]
    assert n == 2 * len(texts)  # no comment swallowed a statement


@pytest.fixture(scope="module")
def compiler():
    try:
        return find_compiler()
    except Exception as exc:  # noqa: BLE001 - any missing compiler skips
        pytest.skip(f"no C compiler: {exc}")


def test_fixed_hostile_texts_compile_and_print_back(compiler, tmp_path):
    _check_round_trip(FIXED + FRAGMENTS, tmp_path)


@settings(max_examples=6, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(texts=st.lists(TEXTS, min_size=1, max_size=30))
def test_c_literals_and_comments_compile_and_print_back_the_utf8_bytes(compiler, tmp_path, texts):
    _check_round_trip(texts, tmp_path)


@QUICK
@given(TEXTS)
def test_c_comment_is_one_line_of_plain_ascii_without_delimiters(text):
    out = c_comment(text)
    assert all(" " <= c <= "~" for c in out)
    assert not any(d in out for d in ("*/", "/*", "??")) and not out.endswith(("\\", "*", "/", "?"))


@QUICK
@given(TEXTS)
def test_c_string_is_one_ascii_literal_without_trigraphs(text):
    out = c_string(text)
    assert out[0] == out[-1] == '"' and all(" " <= c <= "~" for c in out) and "??" not in out


@QUICK
@given(TEXTS)
def test_xml_attr_and_text_parse_back_with_expat(text):
    """The same text, forbidden XML characters as U+FFFD (expat, independent of the writer)."""
    expected = "".join("\ufffd" if (c < " " and c not in "\t\n\r") or "\ud800" <= c <= "\udfff" or c in "\ufffe\uffff" else c
                       for c in text)
    root = ET.fromstring(f"<a b={xml_attr(text)}>{xml_text(text)}</a>".encode("utf-8"))
    assert root.get("b") == expected and (root.text or "") == expected


@QUICK
@given(TEXTS)
def test_html_text_unescapes_to_the_text(text):
    out = html_text(text)
    assert not any(c in out for c in "<>\"'") and html.unescape(out) == "".join(
        "\ufffd" if (c < " " and c not in "\t\n\r") or "\ud800" <= c <= "\udfff" or c in "\ufffe\uffff" else c for c in text)


class _Scripts(HTMLParser):
    def __init__(self) -> None:
        super().__init__()
        self.data: list[str] = []
        self.tags: list[str] = []

    def handle_starttag(self, tag, attrs):
        self.tags.append(tag)

    def handle_data(self, data):
        if self.tags and self.tags[-1] == "script":
            self.data.append(data)


@QUICK
@given(st.dictionaries(TEXTS, st.one_of(TEXTS, st.floats(allow_nan=False, allow_infinity=False), st.lists(TEXTS, max_size=3)),
                       max_size=4))
def test_json_script_stays_in_its_block_and_parses_back(value):
    out = json_script(value)
    assert not any(c in out for c in "<>&\u2028\u2029")
    parser = _Scripts()
    parser.feed(f'<script type="application/json">{out}</script><p>after</p>')
    assert parser.tags == ["script", "p"] and "".join(parser.data) == out
    assert json.loads(out) == value


@QUICK
@given(TEXTS)
def test_toml_string_reads_back(text):
    expected = "".join("\ufffd" if "\ud800" <= c <= "\udfff" else c for c in text)
    assert tomllib.loads(f"k = {toml_string(text)}\n") == {"k": expected}


@QUICK
@given(TEXTS)
def test_toml_and_csv_comments_stay_on_their_line(text):
    assert tomllib.loads(f"# {toml_comment(text)}\nk = 1\n") == {"k": 1}
    assert len(f"#{csv_comment(text)}".splitlines()) == 1


@pytest.mark.parametrize("value", ["gt_a\n", "1abc", "a-b", "é", "", " a", "a b", 3, None], ids=repr)
def test_check_c_identifier_refuses(value):
    with pytest.raises(InputError, match="prefix: expected a C identifier"):
        check_c_identifier(value, "prefix")


@pytest.mark.parametrize("name", ["a,b", 'a"b', "a\nb", "#a", "", " a", "a\u2028b", "a\x00"], ids=repr)
def test_csv_name_refuses(name):
    with pytest.raises(InputError, match=r"out.csv: column name .*: expected a non-empty name without commas"):
        csv_name(name, "out.csv")


@QUICK
@given(st.lists(TEXTS, min_size=2, max_size=4))  # (one empty cell alone is an empty line: no row)
def test_csv_fields_read_back_as_one_row_by_the_csv_module(cells):
    """Python's csv reader (RFC 4180) gives the cells back, line breaks and control characters as spaces."""
    line = ",".join(csv_field(c) for c in cells)
    assert len(line.splitlines()) <= 1
    expected = ["".join(" " if c < " " or "\x7f" <= c <= "\x9f" or c in "\u2028\u2029" or "\ud800" <= c <= "\udfff" else c
                        for c in cell) for cell in cells]
    assert next(csv.reader([line])) == expected
