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
import shutil
import tempfile
import weakref
import xml.etree.ElementTree as ET
import zipfile
from dataclasses import dataclass
from pathlib import Path

import casadi as ca
import numpy as np

from gtmodel._compiler import find_compiler, run_compiler
from gtmodel.errors import InputError
from gtmodel.exchange.explicit import ExplicitModel
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


def _read_description(path: Path, folder: Path) -> ET.Element:
    md = folder / "modelDescription.xml"
    if not md.is_file():
        raise InputError(f"{path}: not an FMU (no modelDescription.xml in the archive)")
    try:
        return ET.parse(md).getroot()
    except ET.ParseError as exc:
        raise InputError(f"{path}: modelDescription.xml is not valid XML ({exc})") from None


def _build_from_sources(path: Path, folder: Path, root: ET.Element, ident: str, version: str) -> Path:
    """Compile ``sources/*.c`` into ``binaries/<platform>/<id><ext>`` (a source FMU)."""
    plat, ext = fmi_platform(version)
    src_dir = folder / "sources"
    listed = [f.get("name") for f in root.iter("File") if f.get("name", "").endswith(".c")]
    bd = src_dir / "buildDescription.xml"
    if bd.is_file():  # FMI 3.0: the source files of the build description
        listed = [f.get("name") for f in ET.parse(bd).getroot().iter("SourceFile") if f.get("name", "").endswith(".c")]
    sources = [src_dir / n for n in listed] if listed else sorted(src_dir.glob("*.c"))
    present = sorted(p.name for p in (folder / "binaries").glob("*")) if (folder / "binaries").is_dir() else []
    if not sources or not all(s.is_file() for s in sources):
        raise InputError(
            f"{path}: no binary for this platform ({plat}) and no C sources to build one "
            f"(binaries for: {', '.join(present) or 'none'})"
        )
    out = folder / "binaries" / plat / f"{ident}{ext}"
    out.parent.mkdir(parents=True, exist_ok=True)
    cmd = [*find_compiler(), "-shared", "-fPIC", "-O1", f"-I{INCLUDE_DIR}", f"-I{src_dir}", *map(str, sources), "-o", str(out), "-lm"]
    run_compiler(cmd, f"{path}: building the FMU's binary from its sources")
    _log.info("built %s from the sources of %s", out.name, path)
    return out


def import_fmu(path: str | Path, derivatives: str = "auto", name: str | None = None) -> ImportedFmu:
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

    Returns
    -------
    ImportedFmu
        The loaded FMU; :attr:`ImportedFmu.model` is its explicit model.

    Raises
    ------
    InputError
        Naming the file: missing, not a zip archive (corrupt), no ``modelDescription.xml``,
        an FMI version other than 2.0/3.0, no model exchange interface, event indicators
        (events are not imported), no binary for this
        platform and no sources, ``derivatives="directional"`` for an FMU without them, or
        CasADi cannot load it.
    CodegenError
        Building a source FMU failed.
    """
    path = Path(path)
    if derivatives not in DERIVATIVES:
        raise InputError(f"derivatives: expected one of {', '.join(DERIVATIVES)}, got {derivatives!r}")
    if not path.is_file():
        raise InputError(f"{path}: no such FMU file")
    if not zipfile.is_zipfile(path):
        raise InputError(f"{path}: not an FMU (corrupt: not a zip archive)")
    folder = Path(tempfile.mkdtemp(prefix="gtmodel_fmu_import_"))
    try:
        with zipfile.ZipFile(path) as zf:
            zf.extractall(folder)
    except (zipfile.BadZipFile, OSError) as exc:
        shutil.rmtree(folder, ignore_errors=True)
        raise InputError(f"{path}: not an FMU (corrupt archive: {exc})") from None
    try:
        imported = _load(path, folder, derivatives, name)
    except BaseException:
        shutil.rmtree(folder, ignore_errors=True)
        raise
    weakref.finalize(imported.model, shutil.rmtree, str(folder), True)  # the folder lives as long as the model
    return imported


def _load(path: Path, folder: Path, derivatives: str, name: str | None) -> ImportedFmu:
    root = _read_description(path, folder)
    version = root.get("fmiVersion", "")
    if version not in ("2.0", "3.0"):
        raise InputError(f"{path}: FMI version {version or '(none)'} is not supported (2.0 or 3.0)")
    me = root.find("ModelExchange")
    if me is None:
        kinds = [k for k in ("CoSimulation", "ScheduledExecution") if root.find(k) is not None]
        raise InputError(f"{path}: no model exchange interface (the FMU has {', '.join(kinds) or 'no interface'}); "
                         "gtmodel imports model-exchange FMUs")
    ident = me.get("modelIdentifier", "")
    n_events = int(root.get("numberOfEventIndicators", "0") or 0) if version == "2.0" else len(list(root.iter("EventIndicator")))
    if n_events:
        raise InputError(f"{path}: the FMU has {n_events} event indicator(s); gtmodel's import (CasADi's FmuFunction) "
                         "evaluates the continuous-time equations only, so its events would be lost")
    plat, ext = fmi_platform(version)
    built = False
    if not (folder / "binaries" / plat / f"{ident}{ext}").is_file():
        _build_from_sources(path, folder, root, ident, version)
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
        dae = ca.DaeBuilder(name or ident, str(folder), {})
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
