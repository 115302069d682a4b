"""Import an FMU (FMI 2.0 or 3.0, model exchange) as an explicit model usable by gtmodel.

CasADi loads the FMU (``casadi.DaeBuilder(name, unzipped_folder)``) and evaluates it as a
``FmuFunction`` (``DaeBuilder.create``): ``f(t, x, u, p) -> (xdot, y)`` calling the FMU's
binary. Its derivatives (for the linearisation, the integrator's Jacobian and the optimal
control problem) come from the FMU's directional derivatives when the FMU declares
``providesDirectionalDerivative(s)``, otherwise from CasADi's finite differences; which
one is used is :attr:`ImportedFmu.derivatives`.

The result is an :class:`~gtmodel.exchange.explicit.ExplicitModel` (:attr:`ImportedFmu.model`)
that :mod:`gtmodel.exchange.explicit_ops` simulates, linearises and connects to gtmodel
models and components, and :mod:`gtmodel.exchange.explicit_ocp` uses in optimal control.

An FMU without a binary for this platform but with C sources (a source FMU) is built with
the C compiler of :mod:`gtmodel._compiler`.
"""

from __future__ import annotations

import logging
import re
import shutil
import weakref
import xml.etree.ElementTree as ET
import zipfile
from dataclasses import dataclass
from pathlib import Path

import casadi as ca
import numpy as np

from gtmodel._compiler import find_compiler, run_compiler
from gtmodel.errors import CodegenError, CompilerNotFoundError, InputError
from gtmodel.exchange.explicit import ExplicitModel
from gtmodel.exchange.fmu_archive import ArchiveLimits, extract_fmu, inside, plain_identifier
from gtmodel.exchange.fmu_export import INCLUDE_DIR, fmi_platform

__all__ = ["ImportedFmu", "import_fmu", "DERIVATIVES"]

_log = logging.getLogger("gtmodel")

#: Choices of :func:`import_fmu`'s ``derivatives``.
DERIVATIVES = ("auto", "directional", "finite_differences")


@dataclass
class ImportedFmu:
    """An FMU loaded by :func:`import_fmu`.

    Parameters
    ----------
    path : pathlib.Path
        The ``.fmu`` file.
    version : str
        FMI version (``"2.0"`` or ``"3.0"``).
    model : ExplicitModel
        ``f(t, x, u, p) -> (xdot, y)`` evaluating the FMU, with the names, start values,
        units and descriptions of its variables.
    derivatives : str
        ``"directional derivatives of the FMU"`` or ``"finite differences (CasADi)"``.
    folder : pathlib.Path
        The unzipped FMU (removed when :attr:`model` is garbage-collected).
    built_from_sources : bool
        Whether the binary was built here from the FMU's sources.
    """

    path: Path
    version: str
    model: ExplicitModel
    derivatives: str
    folder: Path
    built_from_sources: bool = False


def _parse_xml(path: Path, file: Path, member: str, limits: ArchiveLimits) -> ET.Element:
    """Parse one XML member of the archive, its size capped (``limits.max_description_bytes``)."""
    size = file.stat().st_size
    if size > limits.max_description_bytes:
        raise InputError(f"{path}: {member} has {size} bytes, more than {limits.max_description_bytes} "
                         "(limits.max_description_bytes); the FMU is refused")
    with open(file, "rb") as fh:
        head = fh.read(size)
    if re.search(rb"<!\s*(DOCTYPE|ENTITY)", head, re.IGNORECASE):  # FMI descriptions use none: no entity expansion at all
        raise InputError(f"{path}: {member} declares a DTD or entities (<!DOCTYPE>, <!ENTITY>), which FMI descriptions "
                         "do not use; the FMU is refused")
    try:
        return ET.fromstring(head)
    except ET.ParseError as exc:
        raise InputError(f"{path}: {member} is not valid XML ({exc})") from None


def _read_description(path: Path, folder: Path, limits: ArchiveLimits) -> ET.Element:
    md = folder / "modelDescription.xml"
    if not md.is_file():
        raise InputError(f"{path}: not an FMU (no modelDescription.xml in the archive)")
    return _parse_xml(path, md, "modelDescription.xml", limits)


def _sources(path: Path, folder: Path, root: ET.Element, ident: str, limits: ArchiveLimits) -> tuple[list[Path], list[str]]:
    """The C sources to build (each once) and the compiler's ``-D``/``-I`` flags, all inside ``sources/``."""
    src_dir = folder / "sources"
    listed: list[Path] = []
    flags: list[str] = []
    bd = src_dir / "buildDescription.xml"
    if bd.is_file():  # FMI 3.0: the build configuration of this model identifier (else the first)
        configs = list(_parse_xml(path, bd, "sources/buildDescription.xml", limits).iter("BuildConfiguration"))
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


_INCLUDE = re.compile(rb"^[ \t]*#[ \t]*(?:include|include_next|import|embed)\b[ \t]*(.*)$", re.MULTILINE)


def _check_includes(path: Path, src_dir: Path) -> None:
    """Refuse ``#include`` of absolute paths, ``..`` or macros in any file under ``sources/``:
    the compiler must read nothing outside the unpacked FMU but the system headers."""
    for file in sorted(p for p in src_dir.rglob("*") if p.is_file()):
        for m in _INCLUDE.finditer(file.read_bytes()):
            target = m.group(1).split(b"//")[0].strip()
            name = target[1:-1] if target[:1] in (b'"', b"<") and target[-1:] in (b'"', b">") else None
            if name is None or name.startswith(b"/") or b".." in name or b"\\" in name or b":" in name:
                shown = target[:80].decode("ascii", "backslashreplace")
                raise InputError(f"{path}: sources/{file.relative_to(src_dir).as_posix()} includes {shown!r}: "
                                 "an #include must name a header by a relative path without '..'; the FMU is refused")


def _first_error(msg: str) -> str:
    """The compiler's first ``error:`` line (file, line and message), shortened and escaped."""
    for line in msg.splitlines():
        if "error" in line:
            return line.strip()[:300].encode("unicode_escape").decode("ascii")
    return msg.strip().splitlines()[-1][:300].encode("unicode_escape").decode("ascii") if msg.strip() else "(no output)"


def _build_from_sources(path: Path, folder: Path, root: ET.Element, ident: str, version: str, limits: ArchiveLimits) -> Path:
    """Compile the FMU's C sources into ``binaries/<platform>/<id><ext>`` (a source FMU)."""
    plat, ext = fmi_platform(version)
    src_dir = folder / "sources"
    sources, flags = _sources(path, folder, root, ident, limits) if src_dir.is_dir() else ([], [])
    present = sorted(p.name for p in (folder / "binaries").glob("*")) if (folder / "binaries").is_dir() else []
    missing = [s for s in sources if not s.is_file()]
    if not sources or missing:
        what = f"missing source {missing[0].relative_to(src_dir.resolve()).as_posix()!r}" if missing else "no C sources to build one"
        raise InputError(
            f"{path}: no binary for this platform ({plat}) and {what} "
            f"(binaries for: {', '.join(present) or 'none'})"
        )
    _check_includes(path, src_dir)
    out = inside(path, folder / "binaries", f"{plat}/{ident}{ext}", "binary")
    out.parent.mkdir(parents=True, exist_ok=True)
    # a shared library exports the plain fmi3 names (the standard header's override of a source FMU's prefix)
    plain = ["-DFMI3_OVERRIDE_FUNCTION_PREFIX"] if version == "3.0" else []
    cmd = [*find_compiler(), "-shared", "-fPIC", "-O1", f"-I{INCLUDE_DIR}", f"-I{src_dir}", *plain, *flags,
           *map(str, sources), "-o", str(out), "-lm"]
    try:
        run_compiler(cmd, f"{path}: building the FMU's binary from its sources")
    except CompilerNotFoundError:
        raise
    except CodegenError as exc:
        raise CodegenError(f"{path}: building the FMU's binary from its {len(sources)} C source(s) failed: "
                           f"{_first_error(str(exc).split(chr(10), 1)[-1])}") from None
    _log.info("built %s from the sources of %s", out.name, path)
    return out


def import_fmu(path: str | Path, derivatives: str = "auto", name: str | None = None,
               limits: ArchiveLimits | None = None) -> ImportedFmu:
    """Load an FMU (FMI 2.0 / 3.0 model exchange) as an explicit model.

    Parameters
    ----------
    path : str or pathlib.Path
        The ``.fmu`` file.
    derivatives : {"auto", "directional", "finite_differences"}, optional
        Where derivatives come from: the FMU's directional derivatives (``"auto"`` when it
        provides them) or CasADi's finite differences.
    name : str, optional
        Model name; default the FMU's ``modelName``.
    limits : ArchiveLimits, optional
        Caps on the archive (members, unpacked sizes, ``modelDescription.xml``); default
        :class:`~gtmodel.exchange.fmu_archive.ArchiveLimits` (docs/fmu.md).

    Returns
    -------
    ImportedFmu
        The loaded FMU; :attr:`ImportedFmu.model` is its explicit model.

    Raises
    ------
    InputError
        Naming the file: missing, not a zip archive (corrupt), no ``modelDescription.xml``,
        an archive beyond ``limits`` or with a member name that leaves the archive (naming
        the member), a ``modelIdentifier`` that is not a C identifier, a source, include
        folder or binary name outside the unpacked folder, an FMI version other than
        2.0/3.0, no model exchange interface, a feature that cannot be simulated here
        (event indicators, clocks, time events of discrete variables, no continuous
        states; the message names it), no binary for this
        platform and no sources, ``derivatives="directional"`` for an FMU without them, or
        CasADi cannot load it.
    CodegenError
        Building a source FMU failed: the message names the compiler's first error.
    """
    path = Path(path)
    if derivatives not in DERIVATIVES:
        raise InputError(f"derivatives: expected one of {', '.join(DERIVATIVES)}, got {derivatives!r}")
    if not path.is_file():
        raise InputError(f"{path}: no such FMU file")
    if not zipfile.is_zipfile(path):
        raise InputError(f"{path}: not an FMU (corrupt: not a zip archive)")
    limits = limits or ArchiveLimits()
    folder = extract_fmu(path, limits)
    try:
        imported = _load(path, folder, derivatives, name, limits)
    except BaseException:
        shutil.rmtree(folder, ignore_errors=True)
        raise
    weakref.finalize(imported.model, shutil.rmtree, str(folder), True)  # the folder lives as long as the model
    return imported


def _unsupported(path: Path, root: ET.Element, version: str) -> str | None:
    """The FMU feature gtmodel's import cannot simulate, named; ``None`` when there is none."""
    n_events = int(root.get("numberOfEventIndicators", "0") or 0) if version == "2.0" else len(root.findall("ModelStructure/EventIndicator"))
    if n_events:
        return (f"the FMU has {n_events} event indicator(s) (state events); gtmodel's import (CasADi's FmuFunction) "
                "evaluates the continuous-time equations only, so its events would be lost")
    variables = list(root.find("ModelVariables") if root.find("ModelVariables") is not None else [])
    clocks = [v.get("name", "?") for v in variables if v.tag == "Clock"]
    if clocks:
        return f"the FMU has clocks ({', '.join(clocks[:5])}); FMI 3.0 clocked partitions cannot be simulated by gtmodel's import"
    discrete = [v.get("name", "?") for v in variables if v.get("variability") == "discrete"
                and v.get("causality", "local") in ("local", "output")]
    if discrete:
        return (f"the FMU has discrete-time variables changed at events ({', '.join(discrete[:5])}): time events "
                "(next event time) and event updates are not simulated by gtmodel's import")
    n_states = len(root.findall("ModelStructure/Derivatives/Unknown")) if version == "2.0" else len(root.findall("ModelStructure/ContinuousStateDerivative"))
    if not n_states:
        return ("the FMU has no continuous states (no derivatives in ModelStructure); gtmodel imports an FMU as an "
                "ODE xdot = f(t, x, u, p) and an algebraic input-output map has nothing to integrate")
    return None


def _load(path: Path, folder: Path, derivatives: str, name: str | None, limits: ArchiveLimits) -> ImportedFmu:
    root = _read_description(path, folder, limits)
    version = root.get("fmiVersion", "")
    if version not in ("2.0", "3.0"):
        raise InputError(f"{path}: FMI version {version or '(none)'} is not supported (2.0 or 3.0)")
    me = root.find("ModelExchange")
    if me is None:
        kinds = [k for k in ("CoSimulation", "ScheduledExecution") if root.find(k) is not None]
        raise InputError(f"{path}: no model exchange interface (the FMU has {', '.join(kinds) or 'no interface'}); "
                         "gtmodel imports model-exchange FMUs")
    ident = plain_identifier(path, me.get("modelIdentifier", ""), "ModelExchange")
    why = _unsupported(path, root, version)
    if why:
        raise InputError(f"{path}: {why}")
    plat, ext = fmi_platform(version)
    built = False
    if not inside(path, folder / "binaries", f"{plat}/{ident}{ext}", "binary").is_file():
        _build_from_sources(path, folder, root, ident, version, limits)
        built = True
    provides = (me.get("providesDirectionalDerivatives") or me.get("providesDirectionalDerivative") or "false") == "true"
    if derivatives == "directional" and not provides:
        raise InputError(f"{path}: the FMU provides no directional derivatives; use derivatives='finite_differences' or 'auto'")
    use_dd = provides and derivatives != "finite_differences"
    if provides and not use_dd:  # CasADi follows the description: say "none" in the unzipped copy
        md = folder / "modelDescription.xml"
        md.write_text(md.read_text(encoding="utf-8").replace('providesDirectionalDerivatives="true"', 'providesDirectionalDerivatives="false"')
                      .replace('providesDirectionalDerivative="true"', 'providesDirectionalDerivative="false"'), encoding="utf-8")
    try:
        dae = ca.DaeBuilder(ident, str(folder), {})  # a C identifier; the model keeps the name asked for
        f = dae.create("f", ["t", "x", "u", "p"], ["ode", "y"], {"enable_fd": not use_dd})
    except RuntimeError as exc:
        msg = str(exc).strip().splitlines()
        raise InputError(f"{path}: CasADi cannot load the FMU: {msg[-1] if msg else exc}") from None
    x_names, u_names, p_names, y_names = list(dae.x()), list(dae.u()), list(dae.p()), list(dae.y())
    start = lambda names: np.array([float(np.ravel(dae.start(n))[0]) for n in names], dtype=float)  # noqa: E731
    units, descriptions = {}, {}
    for n in x_names + u_names + p_names + y_names:
        if dae.unit(n):
            units[n] = dae.unit(n)
        if dae.description(n):
            descriptions[n] = dae.description(n)
    em = ExplicitModel(
        name=name or root.get("modelName", ident), f=f, x_names=x_names, u_names=u_names, p_names=p_names,
        y_names=y_names, x_start=start(x_names), u_start=start(u_names), p_value=start(p_names),
        units=units, descriptions=descriptions,
    )
    how = "directional derivatives of the FMU" if use_dd else "finite differences (CasADi)"
    return ImportedFmu(path=path, version=version, model=em, derivatives=how, folder=folder, built_from_sources=built)
