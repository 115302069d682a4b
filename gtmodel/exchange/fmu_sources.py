"""Build a source FMU's binary, with the compiler confined to the FMU's own files.

A source FMU is C code written by someone else that will run inside the gtmodel process.
Its build must read nothing but the unpacked FMU and the compiler's system headers, embed
nothing else, and no message may quote another file. What decides is the compiler's own
view, in four steps per source file (each through :func:`gtmodel._compiler.run_compiler`):

1. **preprocess** (``-E`` with the FMU's ``-D``/``-I`` flags, dependency output ``-MD``):
   every file the preprocessor read (its line markers and its dependency list) must lie in
   the unpacked folder, gtmodel's FMI headers or a system include directory of the compiler
   (``cc -E -Wp,-v``); ``__has_include``/``__has_include_next``/``__has_embed`` are poisoned
   (``#pragma GCC poison``, which also catches names built by macros and token pasting): a
   use located in the FMU refuses it, so no existence of an outside file is probed (a system
   header probing its own headers, as glibc's do with ``_GNU_SOURCE``, is preprocessed
   again without the poison); inline assembly (``asm``, ``__asm__``) in the FMU's own code
   is refused;
2. **compile** the checked preprocessed text (``-x cpp-output -S``): no header is read again;
3. **scan the assembly** the compiler wrote for assembler-level inclusion (``.incbin``,
   ``.include``) and for assembler macros and loops that could build them (``.macro``,
   ``.irp``, ``.irpc``, ``.rept``, ``.altmacro``) -- these arrive through ``asm`` but also
   through attribute strings (``section``, ``symver``) -- before the assembler runs;
4. **assemble** the checked assembly and **link** the objects.

Before these, a text filter over every file under ``sources/`` (line splices joined,
comments removed, digraphs read as the compiler reads them) refuses ``#include`` of
absolute paths, ``..`` or macros and ``#pragma GCC dependency``/``pch_preprocess``, with a
message naming the file; the preprocessed text is refused with ``#pragma GCC
pch_preprocess`` (which would make the compile step load a file as a precompiled header). Compiler messages are shown only for locations inside the unpacked FMU; others are
replaced by a generic sentence.
"""

from __future__ import annotations

import logging
import os
import re
import shutil
import subprocess
import tempfile
import xml.etree.ElementTree as ET
from pathlib import Path
from typing import Callable

from gtmodel._compiler import FIX, find_compiler, run_child, run_compiler
from gtmodel.errors import CodegenError, CompilerNotFoundError, InputError
from gtmodel.exchange.fmu_archive import ArchiveLimits, inside
from gtmodel.exchange.fmu_export import INCLUDE_DIR, fmi_platform

__all__ = ["build_from_sources", "system_include_dirs"]

_log = logging.getLogger("gtmodel")

#: Identifiers poisoned while preprocessing (probing or reading a file by name).
POISONED = ("__has_include", "__has_include_next", "__has_include__", "__has_include_next__", "__has_embed")
#: Assembler directives refused in the assembly of a source FMU (case-insensitive, as the assembler reads them).
ASM_REFUSED = ("incbin", "include", "macro", "irp", "irpc", "rept", "altmacro", "purgem")
_ASM_DIRECTIVE = re.compile(r"(?i)\.(" + "|".join(ASM_REFUSED) + r")\b")  # anywhere: also inside a string (conservative)
_ASM_KEYWORD = re.compile(r"\b(asm|__asm|__asm__)\b")
_MARKER = re.compile(r'^# \d+ "((?:[^"\\]|\\.)*)"((?: \d+)*)\s*$')
_LITERAL = re.compile(r'"(?:[^"\\\n]|\\.)*"|\'(?:[^\'\\\n]|\\.)*\'')
_LOCATION = re.compile(r"^(?P<file>[^:\n]+):(?P<line>\d+):(?:\d+:)?\s")
_SYSTEM_DIRS: dict[tuple[str, ...], tuple[Path, ...]] = {}


def _sources(path: Path, folder: Path, root: ET.Element, ident: str, limits: ArchiveLimits,
             parse_xml: Callable[[Path, Path, str, ArchiveLimits], ET.Element]) -> tuple[list[Path], list[str]]:
    """The C sources to build (each once) and the compiler's ``-D``/``-I`` flags, all inside ``sources/``."""
    src_dir = folder / "sources"
    listed: list[Path] = []
    flags: list[str] = []
    bd = src_dir / "buildDescription.xml"
    if bd.is_file():  # FMI 3.0: the build configuration of this model identifier (else the first)
        configs = list(parse_xml(path, bd, "sources/buildDescription.xml", limits).iter("BuildConfiguration"))
        chosen = [c for c in configs if c.get("modelIdentifier") == ident] or configs[:1]
        for config in chosen:
            for fileset in config.iter("SourceFileSet"):
                for f in fileset.iter("SourceFile"):
                    listed.append(inside(path, src_dir, f.get("name"), "buildDescription SourceFile"))
                for d in fileset.iter("PreprocessorDefinition"):
                    key = d.get("name", "")
                    if not re.fullmatch(r"[A-Za-z_][A-Za-z0-9_]{0,99}", key):
                        raise InputError(f"{path}: buildDescription PreprocessorDefinition name {key[:100]!r} is not a C identifier; the FMU is refused")
                    value = d.get("value")
                    if value is not None and (len(value) > 200 or any(ord(c) < 32 or ord(c) == 127 for c in value)):
                        raise InputError(f"{path}: buildDescription PreprocessorDefinition {key} has a value with control "
                                         "characters or over 200 characters; the FMU is refused")
                    flags.append(f"-D{key}" if value is None else f"-D{key}={value}")
                for inc in fileset.iter("IncludeDirectory"):
                    flags.append(f"-I{inside(path, src_dir, inc.get('name'), 'buildDescription IncludeDirectory')}")
    else:  # FMI 2.0: <SourceFiles> of the model exchange interface (also listed again under CoSimulation)
        for f in root.findall("ModelExchange/SourceFiles/File"):
            listed.append(inside(path, src_dir, f.get("name"), "SourceFiles File"))
    if not listed and src_dir.is_dir():
        listed = sorted(src_dir.glob("*.c"))
    once = list(dict.fromkeys(p for p in listed if p.suffix == ".c"))  # each source once, in order
    return once, flags


#: Where a comment, a GNU raw string, a string or a character literal starts.
_START = re.compile(r"/\*|//|(?<!\w)(?:u8|[uUL])?R\"(?P<d>[^()\\\s]{0,16})\(|[\"']")
#: The rest of a string or character literal (an unterminated one ends at the line's end).
_REST = {'"': re.compile(r'(?:[^"\\\n]|\\.)*"?'), "'": re.compile(r"(?:[^'\\\n]|\\.)*'?")}


def _phase3(text: str) -> str:
    """The text as the preprocessor tokenises it: line splices joined (also with blanks before
    the newline), comments replaced by one space (string and character literals, also GNU
    raw strings, kept), digraphs ``%:`` read as ``#``. Linear in the text's length."""
    text = re.sub(r"(?:\\|\?\?/)[ \t\f\v]*\r?\n", "", text.replace("\r\n", "\n"))
    out, pos, n = [], 0, len(text)
    while (m := _START.search(text, pos)) is not None:
        out.append(text[pos:m.start()])
        start, tok = m.start(), m.group(0)
        if tok == "/*":
            end = text.find("*/", start + 2)
            out.append(" ")
            pos = n if end < 0 else end + 2
            continue
        if tok == "//":
            end = text.find("\n", start)
            pos = n if end < 0 else end
            continue
        if m.group("d") is not None:  # raw: no escapes, no comments, up to )delimiter"
            end = text.find(f"){m.group('d')}\"", m.end())
            end = n if end < 0 else end + len(m.group("d")) + 2
        else:
            end = _REST[tok].match(text, m.end()).end()
        out.append(text[start:end])
        pos = end
    out.append(text[pos:])
    return "".join(out).replace("%:", "#")


_DIRECTIVE = re.compile(r"^[ \t\f\v]*#[ \t\f\v]*([A-Za-z_]\w*)(.*)$", re.MULTILINE)


def check_source_text(path: Path, src_dir: Path) -> None:
    """The text filter (first line): refuse ``#include`` (``include_next``, ``import``,
    ``embed``) of absolute paths, ``..`` or macros, and ``#pragma GCC dependency``, in any
    file under ``sources/``, read as the preprocessor reads it (:func:`_phase3`).

    Parameters
    ----------
    path : pathlib.Path
        The ``.fmu`` file (for the messages).
    src_dir : pathlib.Path
        The unpacked ``sources/`` folder.

    Raises
    ------
    InputError
        Naming the file and the directive (escaped, at most 80 characters of it).
    """
    for file in sorted(p for p in src_dir.rglob("*") if p.is_file()):
        text = _phase3(file.read_bytes().decode("latin-1"))
        where = f"{path}: sources/{file.relative_to(src_dir).as_posix()}"
        for m in _DIRECTIVE.finditer(text):
            word, rest = m.group(1), m.group(2).strip()
            if word in ("include", "include_next", "import", "embed"):
                name = rest[1:].split(rest[0] if rest[:1] == '"' else ">", 1)[0] if rest[:1] in ('"', "<") else None
                if name is None or name.startswith("/") or ".." in name or "\\" in name or ":" in name:
                    raise InputError(f"{where} includes {rest[:80].encode('unicode_escape').decode('ascii')!r}: an #{word} must "
                                     "name a header by a relative path without '..'; the FMU is refused")
            elif word == "pragma" and (p := re.search(r"\b(dependency|pch_preprocess)\b", rest)):
                raise InputError(f"{where} has '#pragma GCC {p.group(1)}', which makes the compiler look at another file; the FMU is refused")
        if p := re.search(r"_Pragma\s*\([^)]*\b(dependency|pch_preprocess)\b", text):
            raise InputError(f"{where} has '_Pragma(\"GCC {p.group(1)} ...\")', which makes the compiler look at another file; the FMU is refused")


def system_include_dirs(cc: list[str]) -> tuple[Path, ...]:
    """The compiler's system include directories (``cc -E -Wp,-v -x c /dev/null``), resolved.

    Parameters
    ----------
    cc : list of str
        The compiler command (:func:`gtmodel._compiler.find_compiler`).

    Returns
    -------
    tuple of pathlib.Path
        The ``#include <...>`` search list of the compiler without any ``-I`` (cached per command).

    Raises
    ------
    CodegenError
        The compiler fails on an empty file.
    """
    key = tuple(cc)
    if key not in _SYSTEM_DIRS:
        err = run_compiler([*cc, "-E", "-Wp,-v", "-x", "c", os.devnull, "-o", os.devnull], "listing the compiler's include directories")
        dirs, on = [], False
        for line in err.splitlines():
            if line.startswith("#include <...> search starts here"):
                on = True
            elif line.startswith("End of search list"):
                on = False
            elif on and line.startswith(" "):
                dirs.append(Path(os.path.realpath(line.strip().split(" (framework directory)")[0])))
        _SYSTEM_DIRS[key] = tuple(dirs)
    return _SYSTEM_DIRS[key]


def _within(file: Path, roots: tuple[Path, ...]) -> bool:
    return any(file == r or file.is_relative_to(r) for r in roots)


def _unescape(name: str) -> str:
    return os.fsdecode(name.encode("latin-1").decode("unicode_escape").encode("latin-1"))


def _files_read(i_text: str, d_file: Path) -> list[str]:
    """Every file the preprocessor read: files entered in its line markers and its dependency list."""
    files = [_unescape(m.group(1)) for m in map(_MARKER.match, i_text.splitlines()) if m and (not m.group(2) or "1" in m.group(2).split())]
    if d_file.is_file():
        deps = d_file.read_bytes().decode("latin-1").replace("\\\n", " ")
        deps = deps.split(": ", 1)[1] if ": " in deps else ""
        files += [w.replace("\\ ", " ").replace("\\#", "#").replace("$$", "$") for w in re.findall(r"(?:\\ |[^\s])+", deps)]
    return [f for f in dict.fromkeys(files) if not (f.startswith("<") and f.endswith(">"))]


def _own_code(i_text: str, folder: Path) -> list[str]:
    """The preprocessed lines that come from files of the FMU (per the line markers), without markers and blank lines."""
    own, lines = False, []
    for text in i_text.splitlines():
        m = _MARKER.match(text)
        if m:
            own = _within(Path(os.path.realpath(_unescape(m.group(1)))), (folder,))
        elif own and text.strip():
            lines.append(text)
    return lines


def _asm_in_own_code(i_text: str, folder: Path) -> tuple[str, int] | None:
    """The first FMU file and line (per the line markers) whose preprocessed code has ``asm``."""
    current, own, line = "", False, 0
    for text in i_text.splitlines():
        m = _MARKER.match(text)
        if m:
            current = _unescape(m.group(1))
            own = _within(Path(os.path.realpath(current)), (folder,))
            line = int(text.split()[1])
            continue
        if own and _ASM_KEYWORD.search(_LITERAL.sub('""', text)):
            return current, line
        line += 1
    return None


def _poisoned_in(stderr: str, folder: Path) -> str | None:
    """The first use of a poisoned name located in the FMU (``sources/x.c:2:5``), if any."""
    for line in stderr.splitlines():
        m = _LOCATION.match(line)
        if m and "poisoned" in line and _within(Path(os.path.realpath(m.group("file"))), (folder,)):
            return f"{Path(os.path.realpath(m.group('file'))).relative_to(folder).as_posix()}:{m.group('line')}"
    return None


def _preprocess(cmd: list[str], i_file: Path, d_file: Path, path: Path, name: str, allowed: tuple[Path, ...]) -> tuple[int, str, str]:
    """Run the preprocessor; refuse the FMU when it read a file outside ``allowed``.

    Returns the exit code, the whole standard error and the preprocessed text."""
    i_file.unlink(missing_ok=True)
    d_file.unlink(missing_ok=True)
    try:  # the text on standard output: the compiler removes an output file when it reports an error
        proc = run_child(cmd, timeout=300, text=False)
    except FileNotFoundError:
        raise CompilerNotFoundError(f"no C compiler: {cmd[0]!r} cannot be run; {FIX}") from None
    except subprocess.TimeoutExpired:
        raise CodegenError(f"{path}: preprocessing sources/{name} did not finish within 300 s") from None
    i_text = proc.stdout.decode("latin-1")
    outside = [str(f) for f in (Path(os.path.realpath(f)) for f in _files_read(i_text, d_file)) if not _within(f, allowed)]
    if outside:
        raise InputError(f"{path}: compiling sources/{name} reads {outside[0].encode('unicode_escape').decode('ascii')!r}, "
                         "outside the FMU and the compiler's system include directories; the FMU is refused")
    i_file.write_bytes(proc.stdout)
    return proc.returncode, proc.stderr.decode("utf-8", "replace"), i_text


def _shown(stderr: str, folder: Path) -> str:
    """The compiler's first error among its messages located inside the unpacked FMU, or a generic sentence."""
    kept = []
    for line in stderr.splitlines():
        m = _LOCATION.match(line)
        if m and _within(Path(os.path.realpath(m.group("file"))), (folder,)):
            kept.append(f"{Path(os.path.realpath(m.group('file'))).relative_to(folder).as_posix()}:{line[m.end('file') + 1:]}")
    kept += re.findall(r"(?:undefined reference to|multiple definition of) [`'\u2018]\w+[`'\u2019]", stderr)  # the linker: symbol names
    first = next((k for k in kept if "error" in k.lower() or "definition" in k or "reference" in k), kept[0] if kept else None)
    if first is None:
        return "(the compiler's messages concern no file of the FMU and are not shown)"
    return first.strip()[:300].encode("unicode_escape").decode("ascii")


def _failed(base: str, step: str, exc: CodegenError, folder: Path) -> CodegenError:
    """``base failed: <first error in the FMU>``; the step is named when no message can be shown."""
    shown = _shown(str(exc).split(chr(10), 1)[-1], folder)
    return CodegenError(f"{base} failed{'' if shown[:1] != '(' else f' ({step})'}: {shown}")


def _step(cmd: list[str], base: str, step: str, folder: Path) -> str:
    """Run one compiler step; a failure is a :class:`CodegenError` with only messages located in the FMU."""
    try:
        return run_compiler(cmd, f"{base}: {step}")
    except CompilerNotFoundError:
        raise
    except CodegenError as exc:
        raise _failed(base, step, exc, folder) from None


def build_from_sources(path: Path, folder: Path, root: ET.Element, ident: str, version: str, limits: ArchiveLimits,
                       parse_xml: Callable[[Path, Path, str, ArchiveLimits], ET.Element]) -> Path:
    """Compile the FMU's C sources into ``binaries/<platform>/<id><ext>`` (a source FMU), confined.

    Parameters
    ----------
    path : pathlib.Path
        The ``.fmu`` file (for the messages).
    folder : pathlib.Path
        The unpacked FMU (resolved, private).
    root : xml.etree.ElementTree.Element
        Its ``modelDescription.xml``.
    ident : str
        The model identifier (a C identifier).
    version : str
        ``"2.0"`` or ``"3.0"``.
    limits : ArchiveLimits
        Caps (``buildDescription.xml``'s size).
    parse_xml : callable
        ``parse_xml(path, file, member, limits) -> Element``, the capped XML reader.

    Returns
    -------
    pathlib.Path
        The binary built.

    Raises
    ------
    InputError
        No sources; a source, include folder or binary name outside the folder; an
        ``#include`` of an absolute path, ``..`` or a macro; a file read by the
        preprocessor outside the folder and the system include directories (named, its
        content never quoted); ``__has_include``; inline assembly in the FMU's code;
        assembler-level inclusion (``.incbin``, ``.include``) or assembler macros.
    CodegenError
        A compiler step failed: its first error located in the FMU, or a generic sentence.
    CompilerNotFoundError
        No C compiler.
    """
    plat, ext = fmi_platform(version)
    folder = Path(os.path.realpath(folder))
    src_dir = folder / "sources"
    sources, flags = _sources(path, folder, root, ident, limits, parse_xml) if src_dir.is_dir() else ([], [])
    present = sorted(p.name for p in (folder / "binaries").glob("*")) if (folder / "binaries").is_dir() else []
    missing = [s for s in sources if not s.is_file()]
    if not sources or missing:
        what = f"missing source {missing[0].relative_to(src_dir.resolve()).as_posix()!r}" if missing else "no C sources to build one"
        raise InputError(f"{path}: no binary for this platform ({plat}) and {what} (binaries for: {', '.join(present) or 'none'})")
    check_source_text(path, src_dir)
    out = inside(path, folder / "binaries", f"{plat}/{ident}{ext}", "binary")
    cc = find_compiler()
    allowed = (folder, Path(os.path.realpath(INCLUDE_DIR)), *system_include_dirs(cc))
    # a shared library exports the plain fmi3 names (the standard header's override of a source FMU's prefix)
    plain = ["-DFMI3_OVERRIDE_FUNCTION_PREFIX"] if version == "3.0" else []
    build = Path(tempfile.mkdtemp(prefix=".gtmodel-build-", dir=folder))
    try:
        poison = build / "poison.h"
        poison.write_text(f"#pragma GCC poison {' '.join(POISONED)}\n")
        objects = []
        for k, src in enumerate(sources):
            name = src.relative_to(src_dir).as_posix()
            base = f"{path}: building the FMU's binary from its {len(sources)} C source(s)"
            i_file, d_file, s_file, o_file = (build / f"{k}.{x}" for x in ("i", "d", "s", "o"))
            stage = f"preprocessing sources/{name}"
            pre = [*cc, f"-I{INCLUDE_DIR}", f"-I{src_dir}", *plain, *flags, "-E", "-MD", "-MF", str(d_file), str(src)]
            code, err, i_text = _preprocess([*pre[:-1], "-include", str(poison), pre[-1]], i_file, d_file, path, name, allowed)
            if code and _poisoned_in(err, folder):
                raise InputError(f"{path}: {_poisoned_in(err, folder)}: __has_include (__has_include_next, __has_embed) would "
                                 "probe files outside the FMU; the FMU is refused")
            if code and "poisoned" in err:  # only a system header probes its own headers (glibc with _GNU_SOURCE): again, unpoisoned
                poisoned_view = _own_code(i_text, folder)
                code, err, i_text = _preprocess(pre, i_file, d_file, path, name, allowed)
                if not code and _own_code(i_text, folder) != poisoned_view:
                    raise InputError(f"{path}: the preprocessed code of sources/{name} changes with the answers of __has_include "
                                     "in a system header; the FMU is refused")
            if code:
                raise _failed(base, stage, CodegenError("\n" + err), folder)
            if re.search(r"(?m)^[ \t]*#[ \t]*pragma\b[^\n]*\bpch_preprocess\b", i_text):  # the compiler would load that file as a PCH
                raise InputError(f"{path}: the preprocessed sources/{name} has '#pragma GCC pch_preprocess', which makes the "
                                 "compiler read another file; the FMU is refused")
            asm = _asm_in_own_code(i_text, folder)
            if asm:
                raise InputError(f"{path}: {Path(os.path.realpath(asm[0])).relative_to(folder).as_posix()}:{asm[1]} has inline assembly "
                                 "(asm), which could make the assembler read other files; the FMU is refused")
            _step([*cc, "-fPIC", "-O1", "-S", "-x", "cpp-output", str(i_file), "-o", str(s_file)], base, f"compiling sources/{name}", folder)
            directive = _ASM_DIRECTIVE.search(s_file.read_bytes().decode("latin-1"))
            if directive:
                raise InputError(f"{path}: the assembly compiled from sources/{name} has the assembler directive "
                                 f"'.{directive.group(1).lower()}' (through an asm statement or an attribute string), "
                                 "which could read other files; the FMU is refused")
            _step([*cc, "-c", str(s_file), "-o", str(o_file)], base, f"assembling sources/{name}", folder)
            objects.append(str(o_file))
        out.parent.mkdir(parents=True, exist_ok=True)
        _step([*cc, "-shared", *objects, "-o", str(out), "-lm"], f"{path}: building the FMU's binary from its {len(sources)} C source(s)", "linking", folder)
    finally:
        shutil.rmtree(build, ignore_errors=True)
    _log.info("built %s from the sources of %s", out.name, path)
    return out
