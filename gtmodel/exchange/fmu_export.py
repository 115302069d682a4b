"""Export a gtmodel model as a Functional Mock-up Unit (FMI 2.0 / 3.0, source + binary).

What comes from CasADi and what from gtmodel (CasADi 3.8):

* **FMI 3.0 model exchange** (and co-simulation on top of it, below): CasADi's own export (``casadi.DaeBuilder.export_fmu``)
  writes the C code of the equations and their directional and adjoint derivatives and
  the FMI 3.0 wrapper (``<id>.c``, ``<id>_wrap.c``, ``buildDescription.xml``). Its
  ``modelDescription.xml`` fails FMPy's validation (internal variables with illegal
  names, units without ``UnitDefinitions``, states without start values, incomplete
  initial unknowns), so gtmodel writes that file itself
  (:mod:`gtmodel.exchange.description`) with CasADi's value references.
* **FMI 2.0 model exchange and co-simulation** (CasADi 3.8 has none): gtmodel's own
  wrapper (``templates/fmi2_wrapper.c``) around CasADi-generated C of the explicit ODE
  and its forward derivative (``casadi.CodeGenerator``); co-simulation integrates with
  the fixed-step classical 4th-order Runge-Kutta method (no SUNDIALS), inputs held over
  the communication step, substeps of at most ``step`` seconds (error ``O(step^4)``).
* Both: the model reduced to an explicit ODE (:func:`gtmodel.exchange.explicit.explicit_model`),
  parameters as tunable FMI parameters with units and descriptions, the binary built for
  this platform with the C compiler of :mod:`gtmodel._compiler`, the sources inside the
  FMU (a source FMU: a user on another platform rebuilds it), zipped with :mod:`zipfile`.

FMI 3.0 co-simulation: CasADi's wrapper leaves ``fmi3InstantiateCoSimulation``,
``fmi3EnterStepMode`` and ``fmi3DoStep`` unimplemented; gtmodel replaces those three
bodies in the generated ``<id>_wrap.c`` (the same RK4 on the wrapper's own model-exchange
functions).

Events: the when-clauses with ``reinit`` of a model that flattens as it is become FMI 2.0
event indicators (model exchange: the importer locates the crossing; co-simulation: the
RK4 step length is bisected to the crossing). Not exported yet: modes (``Model.mode``,
``assign``, ``sign()`` switching), events in FMI 3.0; discrete-time
controller steps are FMI 2.0 co-simulation FMUs (:mod:`gtmodel.exchange.fmu_step`).
"""

from __future__ import annotations

import contextlib
import os
import platform
import sys
import tempfile
import uuid
import xml.etree.ElementTree as ET
import zipfile
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Iterator

import casadi as ca
import numpy as np

from gtmodel._compiler import find_compiler, run_compiler
from gtmodel.errors import CodegenError, InputError
from gtmodel.exchange.description import ValueReferences, model_description
from gtmodel.modeling import ExplicitODE
from gtmodel.exchange.explicit import explicit_model, fmi_identifier

__all__ = ["ExportedFmu", "export_fmu", "fmi_platform"]

_HERE = Path(__file__).parent
INCLUDE_DIR = _HERE / "include"
TEMPLATE_FMI2 = _HERE / "templates" / "fmi2_wrapper.c"
VERSIONS = ("2.0", "3.0")
INTERFACES = ("me", "cs", "both")


@dataclass
class ExportedFmu:
    """An FMU written by :func:`export_fmu`.

    Parameters
    ----------
    path : pathlib.Path
        The ``.fmu`` archive.
    version : str
        FMI version (``"2.0"`` or ``"3.0"``).
    interfaces : tuple of str
        ``"ModelExchange"`` and/or ``"CoSimulation"``.
    identifier : str
        ``modelIdentifier``.
    model : ExplicitODE
        The exported explicit ODE and its variable names.
    platform : str
        Platform folder of the binary (e.g. ``"linux64"``, ``"x86_64-linux"``), ``""`` if
        only sources were packed.
    step : float or None
        The co-simulation's fixed embedded step [s] (``None`` without co-simulation).
    """

    path: Path
    version: str
    interfaces: tuple[str, ...]
    identifier: str
    model: ExplicitODE
    platform: str
    step: float | None


def fmi_platform(version: str) -> tuple[str, str]:
    """The binaries folder and shared-library suffix of this platform for an FMI version.

    Parameters
    ----------
    version : {"2.0", "3.0"}
        FMI version.

    Returns
    -------
    tuple of str
        E.g. ``("linux64", ".so")`` for FMI 2.0, ``("x86_64-linux", ".so")`` for 3.0.
    """
    system = {"linux": "linux", "darwin": "darwin", "win32": "win"}.get(sys.platform, sys.platform)
    ext = {"linux": ".so", "darwin": ".dylib", "win": ".dll"}.get(system, ".so")
    machine = platform.machine().lower().replace("amd64", "x86_64").replace("arm64", "aarch64")
    if version == "2.0":
        return f"{system}{'64' if sys.maxsize > 2**32 else '32'}", ext
    return f"{machine}-{'windows' if system == 'win' else system}", ext


@contextlib.contextmanager
def _cwd(path: Path) -> Iterator[None]:
    old = os.getcwd()
    os.chdir(path)
    try:
        yield
    finally:
        os.chdir(old)


def _compile(sources: list[Path], out: Path, build: Path, what: str) -> None:
    cc = find_compiler()
    flags = ["-shared", "-fPIC", "-O1", "-fvisibility=default", f"-I{INCLUDE_DIR}", f"-I{build}"]
    run_compiler([*cc, *flags, *(str(s) for s in sources), "-o", str(out), "-lm"], what)


def _codegen(em: ExplicitODE, ident: str, build: Path) -> tuple[Path, Path]:
    """CasADi C of ``f`` and its forward derivative as ``<id>_model.c/.h``."""
    cg = ca.CodeGenerator(f"{ident}_model.c", {"with_header": True, "prefix": f"{ident}_"})
    functions = [(em.rhs, "f"), (em.derivative_function(), "df")]
    if em.indicators is not None:  # when-clauses: event indicators and the jump map
        functions += [(em.indicators, "ind"), (em.jump, "jump")]
    for fn, suffix in functions:  # C names <id>_f, <id>_df (, <id>_ind, <id>_jump)
        args = fn.mx_in()
        cg.add(ca.Function(f"{ident}_{suffix}", args, fn.call(args), fn.name_in(), fn.name_out()))
    with _cwd(build):
        cg.generate()
    return build / f"{ident}_model.c", build / f"{ident}_model.h"


def _fmi2_files(em: ExplicitODE, ident: str, build: Path, step: float, me: bool, cs: bool) -> tuple[dict, str]:
    """Sources and description of gtmodel's FMI 2.0 wrapper: {local path: archive path}, XML."""
    c_model, h_model = _codegen(em, ident, build)
    vr = ValueReferences.contiguous(em)
    start = np.zeros(2 * em.nx + len(em.u_names) + len(em.p_names) + em.ny + 1)
    start[vr.x] = em.x0
    start[vr.u] = em.u0
    start[vr.p] = em.p_default
    guid = "{" + str(uuid.uuid4()) + "}"
    subs = {"@ID@": ident, "@NX@": str(em.nx), "@NU@": str(len(em.u_names)), "@NP@": str(len(em.p_names)),
            "@NY@": str(em.ny), "@STEP@": repr(float(step)), "@GUID@": guid, "@NZ@": str(len(em.directions)),
            "@DIRS@": ", ".join(str(d) for d in em.directions) or "0",
            "@START@": ", ".join(repr(float(v)) for v in start)}
    text = TEMPLATE_FMI2.read_text()
    for k, v in subs.items():
        text = text.replace(k, v)
    wrap = build / f"{ident}.c"
    wrap.write_text(text)
    xml = model_description(em, "2.0", ident, vr, model_exchange=me, co_simulation=cs, step_size=step if cs else None, token=guid)
    src = ["{id}.c", "{id}_model.c"]
    files_xml = "".join(f'<File name="{s.format(id=ident)}"/>' for s in src)
    for tag in ("ModelExchange", "CoSimulation"):  # the sources a user rebuilds from (FMI 2.0 SourceFiles)
        xml = _with_sources(xml, tag, files_xml)
    files = {wrap: f"sources/{wrap.name}", c_model: f"sources/{c_model.name}", h_model: f"sources/{h_model.name}"}
    return files, xml


def _with_sources(xml: str, tag: str, files_xml: str) -> str:
    start = xml.find(f"<{tag} ")
    if start < 0:
        return xml
    end = xml.find("/>", start)
    return xml[:end] + f"><SourceFiles>{files_xml}</SourceFiles></{tag}>" + xml[end + 2:]


#: FMI 3.0 co-simulation added to CasADi's model-exchange wrapper: the three functions it
#: leaves "not implemented", replaced (instantiation as for model exchange; an RK4 DoStep on
#: the wrapper's own model-exchange functions, inputs held over the communication step).
_FMI3_CS = {
    "fmi3InstantiateCoSimulation": """{
  (void)eventModeUsed; (void)earlyReturnAllowed; (void)requiredIntermediateVariables;
  (void)nRequiredIntermediateVariables; (void)intermediateUpdate;
  return fmi3InstantiateModelExchange(instanceName, instantiationToken, resourcePath, visible, loggingOn,
                                      instanceEnvironment, logMessage);
}""",
    "fmi3EnterStepMode": """{
  (void)instance;
  return fmi3OK;
}""",
    "fmi3DoStep": """{
  /* gtmodel: classical RK4, substeps of at most GT_STEP s, inputs held over the step */
  static const double c[4] = {0.0, 0.5, 0.5, 1.0};
  double x0[N_X + 1], xs[N_X + 1], k[4][N_X + 1], h;
  double t0 = currentCommunicationPoint, H = communicationStepSize;
  long n, s;
  int i, j;
  (void)noSetFMUStatePriorToCurrentPoint;
  *eventHandlingNeeded = fmi3False;
  *terminateSimulation = fmi3False;
  *earlyReturn = fmi3False;
  *lastSuccessfulTime = t0;
  if (H <= 0) return H == 0 ? fmi3OK : fmi3Error;
  n = (long)(H / GT_STEP);
  if (n * GT_STEP < H * (1.0 - 1e-12)) ++n;
  if (n < 1) n = 1;
  h = H / n;
  if (fmi3GetContinuousStates(instance, x0, N_X) != fmi3OK) return fmi3Error;
  for (s = 0; s < n; ++s) {
    double t = t0 + s * h;
    for (j = 0; j < 4; ++j) {
      for (i = 0; i < N_X; ++i) xs[i] = x0[i] + (j ? c[j] * h * k[j - 1][i] : 0.0);
      if (fmi3SetTime(instance, t + c[j] * h) != fmi3OK || fmi3SetContinuousStates(instance, xs, N_X) != fmi3OK
          || fmi3GetContinuousStateDerivatives(instance, k[j], N_X) != fmi3OK) return fmi3Error;
    }
    for (i = 0; i < N_X; ++i) x0[i] += h * (k[0][i] + 2.0 * k[1][i] + 2.0 * k[2][i] + k[3][i]) / 6.0;
  }
  if (fmi3SetTime(instance, t0 + H) != fmi3OK || fmi3SetContinuousStates(instance, x0, N_X) != fmi3OK) return fmi3Error;
  *lastSuccessfulTime = t0 + H;
  return fmi3OK;
}""",
}


def _add_fmi3_co_simulation(wrap: Path, step: float) -> None:
    """Replace the "not implemented" co-simulation functions of CasADi's FMI 3.0 wrapper."""
    text = wrap.read_text()
    for name, body in _FMI3_CS.items():
        start = text.find(f"FMI3_Export fmi3Status {name}(")
        if start < 0:
            start = text.find(f"FMI3_Export fmi3Instance {name}(")
        brace = text.find("{", text.find(")", start)) if start >= 0 else -1  # the body after the signature
        end = text.find("\n}", brace) if brace >= 0 else -1
        if start < 0 or brace < 0 or end < 0 or "Not implemented" not in text[brace:end]:
            raise CodegenError(f"CasADi {ca.__version__}'s FMI 3.0 wrapper has no unimplemented {name} to replace; "
                               "FMI 3.0 co-simulation cannot be added")
        text = text[:brace] + body + text[end + 2:]
    wrap.write_text(f"#define GT_STEP {float(step)!r}\n" + text)


def _fmi3_files(em: ExplicitODE, ident: str, build: Path, cs: bool = False, step: float = 1e-3) -> tuple[dict, str]:
    """CasADi's FMI 3.0 model-exchange sources (with co-simulation added) and gtmodel's description."""
    dae = ca.DaeBuilder(ident)
    t = dae.add("time", "independent")
    p = [dae.add(n, "parameter", "tunable", {"start": float(v)}) for n, v in zip(em.p_names, em.p_default)]
    x = [dae.add(n, {"start": float(v)}) for n, v in zip(em.x_names, em.x0)]
    u = [dae.add(n, "input", {"start": float(v)}) for n, v in zip(em.u_names, em.u0)]
    y = [dae.add(n, "output") for n in em.y_names]
    xdot, yv = em.rhs(t, ca.vertcat(*x), ca.vertcat(*u) if u else ca.MX(0, 1), ca.vertcat(*p) if p else ca.MX(0, 1))
    for i, xi in enumerate(x):
        dae.eq(dae.der(xi), xdot[i])
    for i, yi in enumerate(y):
        dae.eq(yi, yv[i])
    with _cwd(build):
        raw = dae.export_fmu({"no_warning": True, "with_serialization": False})
    casadi_xml = ET.parse(build / "modelDescription.xml").getroot()
    refs = {v.get("name"): int(v.get("valueReference")) for v in casadi_xml.find("ModelVariables")}
    vr = ValueReferences(
        x=[refs[n] for n in em.x_names], dx=[refs[f"der({n})"] for n in em.x_names], u=[refs[n] for n in em.u_names],
        p=[refs[n] for n in em.p_names], y=[refs[n] for n in em.y_names], time=refs["time"],
    )
    token = casadi_xml.get("instantiationToken")
    if cs:
        _add_fmi3_co_simulation(build / f"{ident}_wrap.c", step)
    xml = model_description(em, "3.0", ident, vr, model_exchange=True, co_simulation=cs, step_size=step if cs else None,
                            token=token, generation_tool=f"gtmodel with CasADi {ca.__version__}")
    files = {build / local: arc for local, arc in raw.items() if arc.startswith("sources/")}
    return files, xml


def export_fmu(
    model: Any,
    out: str | os.PathLike,
    version: str = "2.0",
    interface: str = "both",
    step: float = 1e-3,
    name: str | None = None,
    binary: bool = True,
) -> ExportedFmu:
    """Export a gtmodel model as an FMU (sources and a binary for this platform).

    Parameters
    ----------
    model : Model or Component
        The model: a flat :class:`~gtmodel.modeling.Model`, a composed
        :class:`~gtmodel.modeling.Component` (flattened, aliases eliminated, index reduced,
        algebraic variables solved inside), e.g. a robot's
        :func:`~gtmodel.robots.model.gantry_tau_model`.
    out : str or os.PathLike
        The ``.fmu`` file to write (parent folders are created; an existing file is replaced).
    version : {"2.0", "3.0"}, optional
        FMI version; default ``"2.0"``.
    interface : {"me", "cs", "both"}, optional
        Model exchange, co-simulation or both; default ``"both"``. FMI 3.0 always carries
        model exchange (CasADi's wrapper, on which its co-simulation is built).
    step : float, optional
        Fixed step [s] of the co-simulation's embedded RK4 integrator; default 1e-3.
    name : str, optional
        Model name in the FMU; default the model's. Its identifier form (non-identifier
        characters replaced by ``_``) names the binary.
    binary : bool, optional
        Build the binary for this platform (default); ``False`` packs sources only.

    Returns
    -------
    ExportedFmu
        The path, version, interfaces and exported model.

    Raises
    ------
    InputError
        Unknown version or interface, ``step <= 0``, when-clauses with FMI 3.0, or ``out``
        cannot be written (naming it).
    ModelError
        The model cannot be reduced to an explicit ODE (see
        :func:`~gtmodel.exchange.explicit.explicit_model`).
    CodegenError
        The C compiler fails (its message).
    """
    if version not in VERSIONS:
        raise InputError(f"version: expected one of {', '.join(VERSIONS)}, got {version!r}")
    if interface not in INTERFACES:
        raise InputError(f"interface: expected one of {', '.join(INTERFACES)}, got {interface!r}")
    if version == "3.0" and interface == "cs":
        interface = "both"  # CasADi's wrapper is model exchange; co-simulation is added on top of it
    if not (isinstance(step, (int, float)) and step > 0 and np.isfinite(step)):
        raise InputError(f"step: expected a positive number of seconds, got {step!r}")
    out = Path(out)
    if out.suffix != ".fmu":
        raise InputError(f"out {out}: the file name must end in .fmu")
    em = explicit_model(model, name)
    if version == "3.0" and em.indicators is not None:
        raise InputError(f"model {em.name!r} has when-clauses: events are exported with FMI 2.0 (version='2.0')")
    ident = fmi_identifier(em.name)
    me, cs = interface in ("me", "both"), interface in ("cs", "both")
    with tempfile.TemporaryDirectory(prefix="gtmodel_fmu_") as tmp:
        build = Path(tmp)
        if version == "2.0":
            files, xml = _fmi2_files(em, ident, build, float(step), me, cs)
        else:
            files, xml = _fmi3_files(em, ident, build, cs, float(step))
        plat = ""
        if binary:
            plat, ext = fmi_platform(version)
            lib = build / f"{ident}{ext}"
            _compile([p for p in files if p.suffix == ".c"], lib, build, f"building the FMU binary of {em.name!r}")
            files[lib] = f"binaries/{plat}/{lib.name}"
        try:
            out.parent.mkdir(parents=True, exist_ok=True)
            with zipfile.ZipFile(out, "w", zipfile.ZIP_DEFLATED) as zf:
                zf.writestr("modelDescription.xml", xml)
                for local, arc in files.items():
                    zf.write(local, arc)
        except OSError as exc:
            raise InputError(f"out {out}: cannot write the FMU ({exc.strerror or exc})") from None
    interfaces = tuple(k for k, on in (("ModelExchange", me), ("CoSimulation", cs)) if on)
    return ExportedFmu(out, version, interfaces, ident, em, plat, float(step) if cs else None)
