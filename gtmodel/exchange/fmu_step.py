"""A discrete-time step (a controller or filter of the 4 ms loop) as an FMI 2.0 co-simulation FMU.

A step ``x_next, y = step(x, u)`` with a fixed sample period (e.g. the stationary Kalman
step of Dressler (2012), eqs. 7.19-7.22, ``kalman_step(x, y) -> (x_next, z_hat)`` of a
:class:`gtmodel.codegen.controller.Controller`) becomes a co-simulation FMU whose states,
inputs and outputs are ``discrete`` FMI variables: ``fmi2DoStep`` advances by a whole
number of periods (another communication step is discarded), per period computing the
outputs from the state and the held inputs and replacing the state by ``x_next``. The C is
CasADi's (``casadi.CodeGenerator``) inside gtmodel's wrapper
(``templates/fmi2_step_wrapper.c``), built with the C compiler of :mod:`gtmodel._compiler`,
sources packed beside the binary.
"""

from __future__ import annotations

import tempfile
import uuid
import zipfile
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import casadi as ca
import numpy as np

from gtmodel._escape import xml_attr
from gtmodel.errors import InputError
from gtmodel.exchange.explicit import fmi_identifier
from gtmodel.exchange.fmu_export import _compile, _cwd, fmi_platform

__all__ = ["StepFmu", "export_step_fmu"]

TEMPLATE = Path(__file__).parent / "templates" / "fmi2_step_wrapper.c"


@dataclass
class StepFmu:
    """A discrete-step FMU written by :func:`export_step_fmu`.

    Parameters
    ----------
    path : pathlib.Path
        The ``.fmu`` archive.
    dt : float
        Sample period [s].
    x_names, u_names, y_names : list of str
        Scalar names of the states, inputs and outputs in the FMU.
    platform : str
        Folder of the binary (``""`` for sources only).
    """

    path: Path
    dt: float
    x_names: list[str]
    u_names: list[str]
    y_names: list[str]
    platform: str


def _names(prefix: str, n: int) -> list[str]:
    return [f"{prefix}[{i}]" for i in range(n)] if n > 1 else [prefix] if n == 1 else []


def export_step_fmu(
    step: ca.Function,
    out: str | Path,
    dt: float,
    name: str | None = None,
    x_start: Sequence[float] | None = None,
    binary: bool = True,
) -> StepFmu:
    """Export ``x_next, y = step(x, u)`` as an FMI 2.0 co-simulation FMU with period ``dt``.

    Parameters
    ----------
    step : casadi.Function
        Two dense column-vector inputs (state, input) and two outputs (next state of the
        state's size, output); their names name the FMU's variables (``x[0]``, ...).
    out : str or pathlib.Path
        The ``.fmu`` file.
    dt : float
        Sample period [s], e.g. ``gtmodel.defaults.LOOP_PERIOD_S`` (4 ms).
    name : str, optional
        Model name; default the Function's name.
    x_start : sequence of float, optional
        Start state; default zeros.
    binary : bool, optional
        Build the binary for this platform (default) or pack sources only.

    Returns
    -------
    StepFmu
        The path and variable names.

    Raises
    ------
    InputError
        ``step`` not a Function of that signature, ``dt <= 0``, ``x_start`` of another
        size, ``out`` not ending in ``.fmu`` or not writable.
    CodegenError
        The C compiler fails.
    """
    if not isinstance(step, ca.Function) or step.n_in() != 2 or step.n_out() != 2:
        raise InputError("step: expected a casadi.Function (x, u) -> (x_next, y)")
    sizes = [step.sparsity_in(i) for i in range(2)] + [step.sparsity_out(i) for i in range(2)]
    if not all(s.is_dense() and s.is_column() for s in sizes) or sizes[0].numel() != sizes[2].numel():
        raise InputError(f"step {step.name()!r}: inputs and outputs must be dense columns, x_next the size of x")
    if not (isinstance(dt, (int, float)) and dt > 0 and np.isfinite(dt)):
        raise InputError(f"dt: expected a positive sample period in seconds, got {dt!r}")
    out = Path(out)
    if out.suffix != ".fmu":
        raise InputError(f"out {out}: the file name must end in .fmu")
    nx, nu, ny = sizes[0].numel(), sizes[1].numel(), sizes[3].numel()
    x0 = np.zeros(nx) if x_start is None else np.asarray(x_start, dtype=float).reshape(-1)
    if x0.size != nx:
        raise InputError(f"x_start: expected {nx} values, got {x0.size}")
    x_names, u_names, y_names = (_names(step.name_in(0), nx), _names(step.name_in(1), nu), _names(step.name_out(1), ny))
    model_name = name or step.name()
    ident = fmi_identifier(model_name)
    guid = "{" + str(uuid.uuid4()) + "}"
    with tempfile.TemporaryDirectory(prefix="gtmodel_step_fmu_") as tmp:
        build = Path(tmp)
        args = step.mx_in()
        cg = ca.CodeGenerator(f"{ident}_model.c", {"with_header": True, "prefix": f"{ident}_"})
        cg.add(ca.Function(f"{ident}_step", args, step(*args)))
        with _cwd(build):
            cg.generate()
        start = np.concatenate([x0, np.zeros(nu + ny + 1)])
        text = TEMPLATE.read_text()
        for k, v in {"@ID@": ident, "@NX@": str(nx), "@NU@": str(nu), "@NY@": str(ny), "@DT@": repr(float(dt)),
                     "@GUID@": guid, "@START@": ", ".join(repr(float(s)) for s in start)}.items():
            text = text.replace(k, v)
        (build / f"{ident}.c").write_text(text)
        files = {build / f"{ident}.c": f"sources/{ident}.c", build / f"{ident}_model.c": f"sources/{ident}_model.c",
                 build / f"{ident}_model.h": f"sources/{ident}_model.h"}
        plat = ""
        if binary:
            plat, ext = fmi_platform("2.0")
            lib = build / f"{ident}{ext}"
            _compile([p for p in files if p.suffix == ".c"], lib, build, f"building the FMU binary of {model_name!r}")
            files[lib] = f"binaries/{plat}/{lib.name}"
        xml = _description(model_name, ident, guid, float(dt), x_names, x0, u_names, y_names)
        try:
            out.parent.mkdir(parents=True, exist_ok=True)
            with zipfile.ZipFile(out, "w", zipfile.ZIP_DEFLATED) as zf:
                zf.writestr("modelDescription.xml", xml)
                for local, arc in files.items():
                    zf.write(local, arc)
        except OSError as exc:
            raise InputError(f"out {out}: cannot write the FMU ({exc.strerror or exc})") from None
    return StepFmu(out, float(dt), x_names, u_names, y_names, plat)


def _description(name: str, ident: str, guid: str, dt: float, x_names: list[str], x0: np.ndarray,
                 u_names: list[str], y_names: list[str]) -> str:
    q = xml_attr
    lines = ['<?xml version="1.0" encoding="UTF-8"?>',
             f'<fmiModelDescription fmiVersion="2.0" modelName={q(name)} guid={q(guid)} generationTool="gtmodel" '
             'variableNamingConvention="structured" numberOfEventIndicators="0">',
             f'  <CoSimulation modelIdentifier={q(ident)} canHandleVariableCommunicationStepSize="true">'
             f'<SourceFiles><File name={q(ident + ".c")}/><File name={q(ident + "_model.c")}/></SourceFiles></CoSimulation>',
             f'  <DefaultExperiment startTime="0.0" stepSize={q(repr(dt))}/>',
             "  <ModelVariables>"]
    for n, v in zip(x_names, x0):
        lines.append(f'    <ScalarVariable name={q(n)} valueReference="{len(lines) - 5}" causality="local" variability="discrete" '
                     f'initial="exact" description="state"><Real start={q(repr(float(v)))}/></ScalarVariable>')
    for n in u_names:
        lines.append(f'    <ScalarVariable name={q(n)} valueReference="{len(lines) - 5}" causality="input" variability="discrete" '
                     'description="input, held over the period"><Real start="0.0"/></ScalarVariable>')
    first_y = len(lines) - 5
    for n in y_names:
        lines.append(f'    <ScalarVariable name={q(n)} valueReference="{len(lines) - 5}" causality="output" variability="discrete" '
                     'initial="calculated" description="output of the last period"><Real/></ScalarVariable>')
    lines.append("  </ModelVariables>")
    lines.append("  <ModelStructure>")
    if y_names:
        lines.append("    <Outputs>")
        lines += [f'      <Unknown index="{first_y + i + 1}"/>' for i in range(len(y_names))]
        lines.append("    </Outputs>")
        lines.append("    <InitialUnknowns>")
        lines += [f'      <Unknown index="{first_y + i + 1}"/>' for i in range(len(y_names))]
        lines.append("    </InitialUnknowns>")
    lines.append("  </ModelStructure>")
    lines.append("</fmiModelDescription>")
    return "\n".join(lines) + "\n"
