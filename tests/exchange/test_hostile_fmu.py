"""FMU archives from someone else: crafted hostile archives are refused with exit 2 naming the
member, nothing is written outside the extraction and output folders, no foreign file's content
reaches the output; source FMUs build (each source once, FMI 3.0 build definitions).

Independent references: the FMI 2.0/3.0 standards' rules for archive layout, ``modelIdentifier``
(a C identifier) and source file names (relative to ``sources/``); the closed form
``x(t) = exp(-k t)`` for the source-built model.
"""

from __future__ import annotations

import tempfile
import zipfile
from pathlib import Path

import numpy as np
import pytest

from gtmodel.cli import main
from gtmodel.errors import CodegenError, InputError
from gtmodel.exchange import ArchiveLimits, export_fmu, import_fmu, simulate_explicit
from gtmodel.modeling import Model

MARKER = "FOREIGN-CONTENT-7f3a"


def _decay(name: str = "dq") -> Model:
    m = Model(name)
    k = m.parameter("k", 2.0)
    x = m.state("x", start=1.0)
    m.equation(m.der(x), -k * x)
    return m


@pytest.fixture(scope="module")
def sources(tmp_path_factory):
    """Source-only FMUs (no binary), both interfaces: FMI 2.0 lists the sources twice."""
    folder = tmp_path_factory.mktemp("src")
    return {v: export_fmu(_decay(), folder / f"dq{v[0]}.fmu", version=v, interface="both", binary=False).path
            for v in ("2.0", "3.0")}


@pytest.fixture
def sandbox(tmp_path, monkeypatch):
    """A private temporary folder and a foreign folder holding a marker file outside everything."""
    tmp = tmp_path / "tmp"
    tmp.mkdir()
    monkeypatch.setattr(tempfile, "tempdir", str(tmp))
    foreign = tmp_path / "foreign"
    foreign.mkdir()
    (foreign / "secret.c").write_text(f'#error "{MARKER}"\nint x = 1;\n')
    (foreign / "secret.txt").write_text(f"{MARKER}\n")
    return tmp_path


def _repack(src: Path, dst: Path, edit=None, add: dict | None = None, drop: tuple = ()) -> Path:
    with zipfile.ZipFile(src) as zin, zipfile.ZipFile(dst, "w", zipfile.ZIP_DEFLATED) as zout:
        for item in zin.namelist():
            if (drop and item.startswith(drop)) or item in (add or {}):
                continue
            data = zin.read(item)
            if edit and item == "modelDescription.xml":
                data = edit(data.decode()).encode()
            zout.writestr(item, data)
        for name, data in (add or {}).items():
            zout.writestr(name, data)
    return dst


def _zip(dst: Path, members: dict) -> Path:
    with zipfile.ZipFile(dst, "w", zipfile.ZIP_DEFLATED) as zf:
        for name, data in members.items():
            if isinstance(data, zipfile.ZipInfo):
                zf.writestr(data, b"x")
            else:
                zf.writestr(name, data)
    return dst


def _symlink_member(name: str) -> zipfile.ZipInfo:
    info = zipfile.ZipInfo(name)
    info.external_attr = (0o120777 << 16)
    return info


def _md(version: str = "2.0", ident: str = "m", variables: str = "", structure: str = "", extra: str = "") -> str:
    if version == "2.0":
        return (f'<fmiModelDescription fmiVersion="2.0" modelName="m" guid="{{0}}" {extra}>'
                f'<ModelExchange modelIdentifier="{ident}"/><ModelVariables>{variables}</ModelVariables>'
                f'<ModelStructure>{structure}</ModelStructure></fmiModelDescription>')
    return (f'<fmiModelDescription fmiVersion="3.0" modelName="m" instantiationToken="{{0}}">'
            f'<ModelExchange modelIdentifier="{ident}"/><ModelVariables>{variables}</ModelVariables>'
            f'<ModelStructure>{structure}</ModelStructure></fmiModelDescription>')


_STATE2 = ('<ScalarVariable name="x" valueReference="0" causality="local" variability="continuous" initial="exact"><Real start="1"/></ScalarVariable>'
           '<ScalarVariable name="der(x)" valueReference="1" causality="local" variability="continuous"><Real derivative="1"/></ScalarVariable>')
_DERIV2 = '<Derivatives><Unknown index="2"/></Derivatives>'


def _bd(files: str, defs: str = "", incs: str = "", ident: str = "dq") -> str:
    return (f'<fmiBuildDescription fmiVersion="3.0"><BuildConfiguration modelIdentifier="{ident}">'
            f'<SourceFileSet language="C99">{files}{defs}{incs}</SourceFileSet></BuildConfiguration></fmiBuildDescription>')


_FMI3_FILES = '<SourceFile name="dq.c"/><SourceFile name="dq_wrap.c"/>'

# (case id, builder(sources, sandbox) -> fmu path, regex of the message)
HOSTILE = [
    ("zip_slip", lambda s, d: _zip(d / "slip.fmu", {"modelDescription.xml": _md(), "../../escaped.txt": "x"}),
     r"archive member '../../escaped.txt' is not a plain relative name"),
    ("absolute_member", lambda s, d: _zip(d / "abs.fmu", {"modelDescription.xml": _md(), "/tmp/abs_member.txt": "x"}),
     r"archive member '/tmp/abs_member.txt' is not a plain relative name"),
    ("symlink_member", lambda s, d: _zip(d / "link.fmu", {"modelDescription.xml": _md(), "sources/x.c": _symlink_member("sources/x.c")}),
     r"archive member 'sources/x.c' is a link or special file"),
    ("oversized_description", lambda s, d: _zip(d / "big.fmu", {"modelDescription.xml": _md(extra=" " * (9 << 20))}),
     r"archive member 'modelDescription.xml' declares \d+ bytes unpacked, more than its cap of 8388608"),
    ("traversing_identifier", lambda s, d: _repack(s["2.0"], d / "ident.fmu", edit=lambda x: x.replace(
        'modelIdentifier="dq"', f'modelIdentifier="../../../../../../..{d}/tmp_out/NAME"')),
     r"ModelExchange modelIdentifier '.*NAME' is not a C identifier"),
    ("absolute_source_fmi2", lambda s, d: _repack(s["2.0"], d / "abs2.fmu", edit=lambda x: x.replace(
        '<File name="dq.c"/>', f'<File name="{d}/foreign/secret.c"/>')),
     r"SourceFiles File '.*secret.c' is not a relative name inside the FMU's sources/ folder"),
    ("climbing_source_fmi2", lambda s, d: _repack(s["2.0"], d / "up2.fmu", edit=lambda x: x.replace(
        '<File name="dq.c"/>', '<File name="../../../foreign/secret.c"/>')),
     r"SourceFiles File '../../../foreign/secret.c' is not a relative name inside"),
    ("absolute_source_fmi3", lambda s, d: _repack(s["3.0"], d / "abs3.fmu", drop=("binaries/",), add={
        "sources/buildDescription.xml": _bd(f'<SourceFile name="{d}/foreign/secret.c"/>')}),
     r"buildDescription SourceFile '.*secret.c' is not a relative name inside"),
    ("climbing_include_dir", lambda s, d: _repack(s["3.0"], d / "inc3.fmu", add={
        "sources/buildDescription.xml": _bd(_FMI3_FILES, incs='<IncludeDirectory name="../../foreign"/>')}),
     r"buildDescription IncludeDirectory '../../foreign' is not a relative name inside"),
    ("include_of_a_foreign_file", lambda s, d: _repack(s["2.0"], d / "hash.fmu", add={
        "sources/dq_extra.h": f'#include "{d}/foreign/secret.txt"\n'}),
     r"sources/dq_extra.h includes '\"/.*': an #include must name a header by a relative path"),
    ("bad_definition_name", lambda s, d: _repack(s["3.0"], d / "def3.fmu", add={
        "sources/buildDescription.xml": _bd(_FMI3_FILES, defs='<PreprocessorDefinition name="X -o /tmp/y" value="1"/>')}),
     r"PreprocessorDefinition name 'X -o /tmp/y' is not a C identifier"),
    ("billion_laughs", lambda s, d: _zip(d / "lol.fmu", {"modelDescription.xml": '<?xml version="1.0"?><!DOCTYPE m [<!ENTITY a "aaaaaaaaaa">'
                                                        + "".join(f'<!ENTITY a{i} "{"&a;" * 10}">' for i in range(1, 9)) + "]>" + _md()}),
     r"modelDescription.xml declares a DTD or entities"),
    ("external_entity", lambda s, d: _zip(d / "ext.fmu", {"modelDescription.xml": f'<!DOCTYPE m [<!ENTITY e SYSTEM "file://{d}/foreign/secret.txt">]>'
                                                          + _md().replace('modelName="m"', 'modelName="&e;"')}),
     r"modelDescription.xml declares a DTD or entities"),
    ("entity_in_build_description", lambda s, d: _repack(s["3.0"], d / "bd_ent.fmu", add={
        "sources/buildDescription.xml": '<!DOCTYPE b [<!ENTITY x "y">]>' + _bd(_FMI3_FILES)}),
     r"sources/buildDescription.xml declares a DTD or entities"),
    ("definition_with_a_newline", lambda s, d: _repack(s["3.0"], d / "defnl.fmu", add={
        "sources/buildDescription.xml": _bd(_FMI3_FILES, defs=f'<PreprocessorDefinition name="X" value="1&#10;#include &quot;{d}/foreign/secret.txt&quot;"/>')}),
     r"PreprocessorDefinition X has a value with control characters"),
    ("clocks", lambda s, d: _zip(d / "clock.fmu", {"modelDescription.xml": _md("3.0", variables='<Clock name="tick" valueReference="1" causality="input" variability="discrete"/>')}),
     r"the FMU has clocks \(tick\)"),
    ("time_events", lambda s, d: _zip(d / "stair.fmu", {"modelDescription.xml": _md(variables=_STATE2 + '<ScalarVariable name="counter" valueReference="2" causality="output" variability="discrete"><Integer start="1"/></ScalarVariable>', structure=_DERIV2)}),
     r"discrete-time variables changed at events \(counter\): time events \(next event time\)"),
    ("no_states", lambda s, d: _zip(d / "feedthrough.fmu", {"modelDescription.xml": _md(variables='<ScalarVariable name="u" valueReference="0" causality="input" variability="continuous"><Real start="0"/></ScalarVariable>')}),
     r"the FMU has no continuous states"),
    ("state_events", lambda s, d: _zip(d / "ball.fmu", {"modelDescription.xml": _md(variables=_STATE2, structure=_DERIV2, extra='numberOfEventIndicators="1"')}),
     r"1 event indicator\(s\) \(state events\)"),
]


def _files(root: Path) -> set[Path]:
    return {p for p in root.rglob("*")}


@pytest.mark.parametrize(("case", "make", "match"), HOSTILE, ids=[c[0] for c in HOSTILE])
def test_hostile_fmu_exits_2_naming_the_member_and_writes_nothing_outside(sources, sandbox, capsys, case, make, match):
    fmu = make(sources, sandbox)
    before = _files(sandbox)
    code = main(["import-fmu", str(fmu)])
    err = capsys.readouterr().err
    assert (code, MARKER in err) == (2, False), err
    assert len(__import__("re").findall(match, err)) == 1, err
    assert _files(sandbox) == before  # the private extraction folder is gone, nothing new anywhere


def test_a_zip_bomb_is_stopped_by_the_caps_before_it_is_unpacked(sandbox):
    bomb = sandbox / "bomb.fmu"
    with zipfile.ZipFile(bomb, "w", zipfile.ZIP_DEFLATED) as zf:  # 8 MiB of zeros in ~8 KB
        zf.writestr("modelDescription.xml", _md())
        zf.writestr("resources/zeros.bin", bytes(8 << 20))
    assert bomb.stat().st_size < 100_000
    with pytest.raises(InputError, match=r"member 'resources/zeros.bin' declares 8388608 bytes unpacked, more than its cap of 1048576"):
        import_fmu(bomb, limits=ArchiveLimits(max_member_bytes=1 << 20))
    with pytest.raises(InputError, match=r"declares \d+ bytes unpacked, more than 4194304 \(limits.max_total_bytes\)"):
        import_fmu(bomb, limits=ArchiveLimits(max_total_bytes=4 << 20))
    with pytest.raises(InputError, match=r"the archive declares 2 members .*, more than 1 \(limits.max_members\)"):
        import_fmu(bomb, limits=ArchiveLimits(max_members=1))
    assert list((sandbox / "tmp").iterdir()) == []


def test_a_bomb_whose_header_lies_is_stopped_while_streaming(sandbox):
    """The central directory says 10 bytes; the stream is counted, not the header believed."""
    bomb = sandbox / "liar.fmu"
    with zipfile.ZipFile(bomb, "w", zipfile.ZIP_DEFLATED) as zf:
        zf.writestr("modelDescription.xml", _md())
        zf.writestr("resources/zeros.bin", bytes(4 << 20))
    data = bytearray(bomb.read_bytes())
    for sig in (b"PK\x01\x02", b"PK\x03\x04"):  # uncompressed size: offset 24 (central), 22 (local)
        at = data.rfind(sig)
        off = 24 if sig == b"PK\x01\x02" else 22
        data[at + off:at + off + 4] = (10).to_bytes(4, "little")
    bomb.write_bytes(bytes(data))
    with pytest.raises(InputError, match="liar.fmu: (archive member 'resources/zeros.bin' unpacks to more than|not an FMU .corrupt)"):
        import_fmu(bomb, limits=ArchiveLimits(max_member_bytes=1 << 20))
    assert list((sandbox / "tmp").iterdir()) == []


def test_the_cli_options_raise_the_caps(sources, sandbox, capsys):
    fmu = _repack(sources["2.0"], sandbox / "padded.fmu", add={"resources/pad.bin": bytes(2 << 20)})
    assert main(["import-fmu", str(fmu), "--max-member-mb", "1"]) == 2
    assert "'resources/pad.bin' declares 2097152 bytes unpacked, more than its cap of 1048576" in capsys.readouterr().err
    assert main(["import-fmu", str(fmu), "--max-member-mb", "3"]) == 0
    assert main(["import-fmu", str(fmu), "--max-total-mb", "0"]) == 2


@pytest.mark.parametrize("version", ["2.0", "3.0"])
def test_source_fmu_with_both_interfaces_builds_each_source_once(sources, version):
    """FMI 2.0 lists the sources under ModelExchange and CoSimulation; gcc sees each once
    (twice was 'multiple definition of fmi2GetTypesPlatform'). Reference: x = exp(-k t)."""
    imp = import_fmu(sources[version])
    t = np.linspace(0.0, 1.0, 11)
    sim = simulate_explicit(imp.model, t, rtol=1e-11, atol=1e-13)
    assert imp.built_from_sources
    np.testing.assert_allclose(sim.x["x"], np.exp(-2.0 * t), rtol=1e-8)


_NEEDS_DEFINE = "#if !defined(GTM_NEEDED) || GTM_NEEDED != 3\n#error GTM_NEEDED must be 3\n#endif\nint gtm_check = GTM_NEEDED;\n"


def test_fmi3_build_description_definitions_reach_the_compiler(sources, tmp_path):
    good = _repack(sources["3.0"], tmp_path / "def.fmu", add={
        "sources/check.c": _NEEDS_DEFINE,
        "sources/buildDescription.xml": _bd(_FMI3_FILES + '<SourceFile name="check.c"/>',
                                            defs='<PreprocessorDefinition name="GTM_NEEDED" value="3"/>')})
    assert import_fmu(good).built_from_sources
    bad = _repack(sources["3.0"], tmp_path / "nodef.fmu", add={
        "sources/check.c": _NEEDS_DEFINE,
        "sources/buildDescription.xml": _bd(_FMI3_FILES + '<SourceFile name="check.c"/>')})
    with pytest.raises(CodegenError, match=r"nodef.fmu: building the FMU's binary from its 3 C source\(s\) failed: .*check.c:2:\d+: error: #error GTM_NEEDED must be 3"):
        import_fmu(bad)


def test_the_private_extraction_folder_is_removed_with_the_model(sources, sandbox):
    import gc
    import stat

    imp = import_fmu(sources["2.0"])
    assert imp.folder.parent == sandbox / "tmp" and stat.S_IMODE(imp.folder.stat().st_mode) == 0o700
    del imp
    gc.collect()
    assert list((sandbox / "tmp").iterdir()) == []


def test_an_archive_of_many_empty_members_is_refused_from_its_end_record(sandbox):
    """20,000 members: refused from the central directory's end record, before zipfile reads
    every entry into memory (reference: the zip format's end-of-central-directory record)."""
    many = sandbox / "many.fmu"
    with zipfile.ZipFile(many, "w") as zf:
        for i in range(20_000):
            zf.writestr(f"r/{i}", b"")
    with pytest.raises(InputError, match=r"many.fmu: the archive declares 20000 members \(\d+ bytes of directory\), more than 10000"):
        import_fmu(many)
