"""Import an FMU (FMI 2.0 or 3.0, model exchange) as an explicit model usable by gtmodel.

CasADi loads the FMU (``casadi.DaeBuilder(name, unzipped_folder)``) and evaluates it as a
``FmuFunction`` (``DaeBuilder.create``): ``f(t, x, u, p) -> (xdot, y)`` calling the FMU's
binary. Its derivatives (for the linearisation, the integrator's Jacobian and the optimal
control problem) come from the FMU's directional derivatives when the FMU declares
``providesDirectionalDerivative(s)``, otherwise from CasADi's finite differences; which
one is used is :attr:`ImportedFmu.derivatives`.

The result is an explicit model, :class:`~gtmodel.modeling.ExplicitODE` (``ExplicitODE``,
:meth:`~gtmodel.modeling.ExplicitODE.from_function`; :attr:`ImportedFmu.model`)
that :mod:`gtmodel.exchange.explicit_ops` simulates, linearises and connects to gtmodel
models and components, and :mod:`gtmodel.exchange.explicit_ocp` uses in optimal control.

An FMU without a binary for this platform but with C sources (a source FMU) is built with
the C compiler of :mod:`gtmodel._compiler`, confined to the FMU's own files by the
compiler's own view (:mod:`gtmodel.exchange.fmu_sources`).
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

from gtmodel.errors import InputError
from gtmodel.modeling import ExplicitODE
from gtmodel.exchange.fmu_archive import ArchiveLimits, extract_fmu, inside, plain_identifier
from gtmodel.exchange.fmu_export import fmi_platform
from gtmodel.exchange.fmu_sources import build_from_sources

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
    model : ExplicitODE
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
    model: ExplicitODE
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
        When building a source FMU: a file the preprocessor reads outside the FMU and the system
        include directories, ``__has_include``, inline assembly or assembler-level inclusion
        (:func:`gtmodel.exchange.fmu_sources.build_from_sources`); nothing outside is quoted.
    CodegenError
        Building a source FMU failed: the message names the compiler's first error located
        in the FMU (or says that none is).
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
        build_from_sources(path, folder, root, ident, version, limits, _parse_xml)
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
    em = ExplicitODE.from_function(
        name or root.get("modelName", ident), f, x_names, u_names, p_names, y_names, start(x_names), start(u_names),
        start(p_names), units=units, descriptions=descriptions,
    )
    how = "directional derivatives of the FMU" if use_dd else "finite differences (CasADi)"
    return ImportedFmu(path=path, version=version, model=em, derivatives=how, folder=folder, built_from_sources=built)
