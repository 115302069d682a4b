"""Source FMUs are built with the compiler confined to the FMU (gtmodel.exchange.fmu_sources):
hostile sources that make the compiler or the assembler read, probe or quote a file outside
are refused (exit 2), by the text filter or by the compiler's own view, and no message holds
a line of that file.

Independent references: the file itself (``/etc/passwd``, whose lines must not appear in
any message), GCC's documented preprocessing (digraphs, line splices, comments, GNU raw
strings, ``__has_include``, token pasting) and the GNU assembler's ``.incbin``/``.include``;
each trick was checked by hand to make an unconfined ``gcc`` read the file.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from gtmodel._compiler import find_compiler
from gtmodel.cli import main
from gtmodel.errors import CodegenError, InputError
from gtmodel.exchange import fmu_sources, import_fmu
from gtmodel.exchange.fmu_sources import _phase3, system_include_dirs
from tests.exchange.test_hostile_fmu import _FMI3_FILES, _bd, _repack, sources  # noqa: F401 - the source-FMU fixture

SECRET = "/etc/passwd"
pytestmark = pytest.mark.skipif(not Path(SECRET).is_file(), reason=f"needs {SECRET}, a file outside every FMU")
_LINES = [line for line in (Path(SECRET).read_text(errors="replace").splitlines() if Path(SECRET).is_file() else []) if line.strip()]

_READS = r"compiling sources/evil.c reads '/etc/passwd', outside the FMU and the compiler's system include directories"
_TEXT = r"sources/evil.c includes .*: an #include must name a header by a relative path without '..'"
_ASM = r"sources/evil.c:\d+ has inline assembly \(asm\)"
_POISON = r"sources/evil.c:\d+: __has_include \(__has_include_next, __has_embed\) would probe files outside the FMU; the FMU is refused"

# (case, content of sources/evil.c compiled with the FMU, regex of the message)
HOSTILE = [
    ("digraph_include", f'%:include "{SECRET}"\n', _TEXT),
    ("comment_inside_directive", f'#/* c */include "{SECRET}"\n', _TEXT),
    ("line_splice", f'#inc\\\nlude "{SECRET}"\n', _TEXT),
    ("splice_after_blanks", f'#  include \\  \n"{SECRET}"\n', _TEXT),
    ("macro_include", f'#define F "{SECRET}"\n#include F\n', _TEXT),
    ("climbing_system_include", "#include <../../../../../../../etc/passwd>\n", _TEXT),
    ("raw_string_with_a_comment_start", f'const char *s = R"a(" /* )a";\n#include "{SECRET}"\n/* */\n', _TEXT),
    ("has_include", f'#if __has_include("{SECRET}")\nint leak = 1;\n#endif\n', _POISON),
    ("has_include_by_token_pasting", f'#define P(a, b) a##b\n#if P(__has_, include)("{SECRET}")\nint leak = 1;\n#endif\n', _POISON),
    ("has_include_by_a_macro", f'#define H __has_include\n#if H(<{SECRET}>)\nint leak = 1;\n#endif\n', _POISON),
    ("pragma_dependency", f'#pragma GCC dependency "{SECRET}"\n', r"'#pragma GCC dependency'"),
    ("pragma_operator_dependency", f'_Pragma("GCC dependency \\"{SECRET}\\"")\n', r"_Pragma\(\"GCC dependency"),
    ("pragma_pch_preprocess", f'#pragma GCC pch_preprocess "{SECRET}"\n', r"'#pragma GCC pch_preprocess'"),
    ("pragma_operator_pch_preprocess_pasted", f'#define S(x) #x\n#define Q(a, b) S(GCC a##b "{SECRET}")\n_Pragma(Q(pch_, preprocess))\nint x;\n',
     r"the preprocessed sources/evil.c has '#pragma GCC pch_preprocess'"),
    ("incbin_in_asm", f'__asm__(".incbin \\"{SECRET}\\"");\n', _ASM),
    ("include_in_asm", f'__asm__(".include \\"{SECRET}\\"");\n', _ASM),
    ("asm_by_a_macro", f'#define A __asm__\nA(".incbin \\"{SECRET}\\"");\n', _ASM),
    ("incbin_in_a_section_name", f'__attribute__((section("s\\n.incbin \\"{SECRET}\\"\\n#"))) int q = 1;\n',
     r"the assembly compiled from sources/evil.c has the assembler directive '.incbin' \(through an asm statement or an attribute string\)"),
    ("include_in_a_symbol_version", f'__attribute__((symver("q@V\\n.include \\"{SECRET}\\"\\n#"))) int q(void) {{ return 1; }}\n',
     r"has the assembler directive '.include'"),
]


def _fmu(sources, folder: Path, name: str, text: str) -> Path:  # noqa: F811 - the fixture's value
    return _repack(sources["3.0"], folder / f"{name}.fmu", add={
        "sources/evil.c": text, "sources/buildDescription.xml": _bd(_FMI3_FILES + '<SourceFile name="evil.c"/>')})


@pytest.mark.parametrize(("case", "text", "match"), HOSTILE, ids=[c[0] for c in HOSTILE])
def test_hostile_source_is_refused_with_exit_2_and_quotes_nothing_outside(sources, tmp_path, capsys, case, text, match):  # noqa: F811
    fmu = _fmu(sources, tmp_path, case, text)
    code = main(["import-fmu", str(fmu)])
    err = capsys.readouterr().err
    leaked = [line for line in _LINES if line in err] + (["root:"] if "root:" in err else [])
    assert (code, leaked, len(__import__("re").findall(match, err))) == (2, [], 1), err


# The deciding check without the text filter: the files the preprocessor read (its line markers and dependency list).
READ_CASES = [c for c in HOSTILE if c[2] == _TEXT]


@pytest.mark.parametrize(("case", "text", "match"), READ_CASES, ids=[c[0] for c in READ_CASES])
def test_without_the_text_filter_the_compilers_view_refuses_the_same_file(sources, tmp_path, monkeypatch, case, text, match):  # noqa: F811
    monkeypatch.setattr(fmu_sources, "check_source_text", lambda path, src_dir: None)
    with pytest.raises(InputError, match=_READS) as info:
        import_fmu(_fmu(sources, tmp_path, case, text))
    assert [line for line in _LINES if line in str(info.value)] == []


def test_an_error_located_outside_the_fmu_is_not_quoted(sources, tmp_path):  # noqa: F811
    """A macro that breaks a system header: gcc's errors are located in the header; none is shown."""
    with pytest.raises(CodegenError, match=r"sys.fmu: building the FMU's binary from its 3 C source\(s\) failed \(compiling sources/evil.c\): "
                                           r"\(the compiler's messages concern no file of the FMU and are not shown\)$"):
        import_fmu(_fmu(sources, tmp_path, "sys", "#define FILE 1\n#include <stdio.h>\n"))


def test_an_error_in_the_fmu_is_named_with_its_location(sources, tmp_path):  # noqa: F811
    with pytest.raises(CodegenError, match=r"failed: sources/evil.c:1:\d+: error: .*x.* undeclared"):
        import_fmu(_fmu(sources, tmp_path, "undeclared", "int f(void) { return x; }\n"))


def test_benign_source_with_system_headers_builds(sources, tmp_path):  # noqa: F811
    """A source using the C library's headers (read from the system include directories) builds."""
    fmu = _fmu(sources, tmp_path, "ok", '#include <math.h>\n#include <string.h>\ndouble gtm_ok(double x) { return sqrt(x) + (double)strlen("a"); }\n')
    assert import_fmu(fmu).built_from_sources


def test_system_include_directories_are_the_compilers():
    """Reference: gcc's documented default search list ends with /usr/include."""
    dirs = system_include_dirs(find_compiler())
    assert Path("/usr/include") in dirs


@pytest.mark.parametrize(("text", "expected"), [
    ("#inc\\\nlude <a.h>", "#include <a.h>"),
    ("#inc\\  \nlude <a.h>", "#include <a.h>"),
    ("%:/* x\n y */include \"a\"", "# include \"a\""),
    ("a // c\nb", "a \nb"),
    ("s = \"/* not a comment */\";", "s = \"/* not a comment */\";"),
    ('s = R"a(" /* )a"; /* c */', 's = R"a(" /* )a";  '),
])
def test_phase3_reads_the_text_as_the_preprocessor_does(text, expected):
    """Reference: C11 5.1.1.2 translation phases 1-3 and 6.4.6 digraphs."""
    assert _phase3(text) == expected


def test_a_system_header_probing_its_own_headers_does_not_refuse_the_fmu(sources, tmp_path):  # noqa: F811
    """glibc's unistd.h and sys/stat.h use __has_include under _GNU_SOURCE: preprocessed again without the poison."""
    fmu = _fmu(sources, tmp_path, "gnu", "#define _GNU_SOURCE\n#include <unistd.h>\n#include <sys/stat.h>\nint gtm_pid(void) { return (int)getpid(); }\n")
    assert import_fmu(fmu).built_from_sources


def test_fmu_code_that_depends_on_a_system_headers_probe_is_refused(sources, tmp_path):  # noqa: F811
    """An FMU hiding __has_include behind a macro defined only when a system header's own probe succeeds (linux/stat.h's guard)."""
    text = ('#define _GNU_SOURCE\n#include <sys/stat.h>\n#ifdef _LINUX_STAT_H\n#if __has_include("/etc/passwd")\nint leak = 1;\n#endif\n#endif\n')
    with pytest.raises(InputError, match=r"evil.c:4: __has_include|changes with the answers of __has_include in a system header"):
        import_fmu(_fmu(sources, tmp_path, "hidden", text))
