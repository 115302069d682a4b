"""The ``modelDescription.xml`` of an exported FMU (FMI 2.0 and FMI 3.0).

Variables per FMI rules: parameters ``causality="parameter" variability="tunable"
initial="exact"`` with their value as ``start``; states ``causality="local"
variability="continuous" initial="exact"`` with their start value; inputs with a start
value (FMI requires one); derivatives and outputs ``initial="calculated"`` without start.
The dependencies of the outputs and derivatives on the states and inputs are the
structural sparsity of the model's Jacobian (``casadi.Function.jac_sparsity``); the
initial unknowns are the outputs and derivatives (the states start ``exact``), depending on
the states, inputs and parameters (all ``exact`` at initialisation).
"""

from __future__ import annotations

import uuid
from dataclasses import dataclass

from gtmodel._escape import xml_attr
from gtmodel.modeling import ExplicitODE

__all__ = ["ValueReferences", "model_description"]


@dataclass
class ValueReferences:
    """Value references of the scalar variables of an FMU.

    Parameters
    ----------
    x, dx, u, p, y : list of int
        Value references of states, their derivatives, inputs, parameters and outputs, in
        the order of :class:`~gtmodel.modeling.ExplicitODE`'s names.
    time : int or None
        Value reference of the independent variable (FMI 3.0 only).
    """

    x: list[int]
    dx: list[int]
    u: list[int]
    p: list[int]
    y: list[int]
    time: int | None = None

    @classmethod
    def contiguous(cls, em: ExplicitODE) -> "ValueReferences":
        """The layout of gtmodel's own wrapper: states, derivatives, inputs, parameters, outputs.

        Parameters
        ----------
        em : ExplicitODE
            The model.

        Returns
        -------
        ValueReferences
            References 0, 1, ... in that order (time: ``nx*2 + nu + np + ny``).
        """
        nx, nu, npar, ny = em.nx, len(em.u_names), len(em.p_names), em.ny
        r = iter(range(2 * nx + nu + npar + ny + 1))
        take = lambda n: [next(r) for _ in range(n)]  # noqa: E731 - consecutive blocks
        return cls(take(nx), take(nx), take(nu), take(npar), take(ny), next(r))


def _attr(**kw: object) -> str:
    """XML attributes; ``None`` and ``""`` are left out, except ``dependencies`` (empty: none)."""
    return " ".join(f"{k}={xml_attr(str(v))}" for k, v in kw.items()
                    if v is not None and (v != "" or k.startswith("dependencies")))


def _deps(em: ExplicitODE, with_parameters: bool = False) -> tuple[list[list[int]], list[list[int]]]:
    """Per derivative and per output: indices into ``[x; u]`` (``[x; u; p]``) they depend on."""
    out = []
    for o in range(2):
        rows = [[] for _ in range(em.rhs.size1_out(o))]
        offset = 0
        for i in (1, 2, 3) if with_parameters else (1, 2):
            for r, c in zip(*em.rhs.jac_sparsity(o, i).get_triplet()):
                rows[r].append(offset + c)
            offset += em.rhs.size1_in(i)
        out.append([sorted(set(r)) for r in rows])
    return out[0], out[1]


def _fmt(v: float) -> str:
    return repr(float(v))


def model_description(
    em: ExplicitODE,
    version: str,
    identifier: str,
    vr: ValueReferences,
    model_exchange: bool = True,
    co_simulation: bool = False,
    step_size: float | None = None,
    token: str | None = None,
    generation_tool: str = "gtmodel",
) -> str:
    """Write the ``modelDescription.xml`` text of an FMU.

    Parameters
    ----------
    em : ExplicitODE
        The model (names, start values, units, descriptions).
    version : {"2.0", "3.0"}
        FMI version.
    identifier : str
        ``modelIdentifier`` (the binary's file name without extension).
    vr : ValueReferences
        Value references of the variables.
    model_exchange, co_simulation : bool, optional
        Which interfaces to declare; default model exchange only.
    step_size : float, optional
        The co-simulation's fixed embedded step [s], stated in ``DefaultExperiment``.
    token : str, optional
        GUID (FMI 2.0) / instantiation token (3.0); default a new random one.
    generation_tool : str, optional
        ``generationTool`` attribute.

    Returns
    -------
    str
        The XML document.
    """
    token = token or "{" + str(uuid.uuid4()) + "}"
    dx_deps, y_deps = _deps(em)
    dx_init, y_init = _deps(em, with_parameters=True)  # initial unknowns: also on the parameters
    xu_vr = vr.x + vr.u + vr.p
    units = sorted({em.units[n] for n in em.x_names + em.u_names + em.p_names + em.y_names if em.units.get(n)})
    unit_of = lambda n: em.units.get(n, "")  # noqa: E731
    desc = lambda n: em.descriptions.get(n, "")  # noqa: E731
    # (name, vr, causality, variability, initial, start, unit, description, derivative-of index or None)
    rows: list[tuple] = []
    for n, r, v in zip(em.p_names, vr.p, em.p_default):
        rows.append((n, r, "parameter", "tunable", "exact", v, unit_of(n), desc(n), None))
    for i, (n, r, v) in enumerate(zip(em.x_names, vr.x, em.x0)):
        rows.append((n, r, "local", "continuous", "exact", v, unit_of(n), desc(n), None))
    for n, r, v in zip(em.u_names, vr.u, em.u0):
        rows.append((n, r, "input", "continuous", None, v, unit_of(n), desc(n), None))
    for i, (n, r) in enumerate(zip(em.x_names, vr.dx)):
        du = f"{unit_of(n)}/s" if unit_of(n) else ""
        rows.append((f"der({n})", r, "local", "continuous", "calculated", None, du, "", i))
    for n, r in zip(em.y_names, vr.y):
        rows.append((n, r, "output", "continuous", "calculated", None, unit_of(n), desc(n), None))
    units += sorted({row[6] for row in rows if row[6]} - set(units))
    lines = ['<?xml version="1.0" encoding="UTF-8"?>']
    v3 = version == "3.0"
    head = dict(fmiVersion=version, modelName=em.name, generationTool=generation_tool, variableNamingConvention="structured")
    head["instantiationToken" if v3 else "guid"] = token
    if not v3:
        head["numberOfEventIndicators"] = len(em.directions)
    lines.append(f"<fmiModelDescription {_attr(**head)}>")
    dd = "providesDirectionalDerivatives" if v3 else "providesDirectionalDerivative"
    if model_exchange:
        lines.append(f"  <ModelExchange {_attr(modelIdentifier=identifier, **{dd: 'true'})}/>")
    if co_simulation:
        lines.append(f"  <CoSimulation {_attr(modelIdentifier=identifier, canHandleVariableCommunicationStepSize='true', **{dd: 'true'})}/>")
    if units:
        lines.append("  <UnitDefinitions>")
        lines += [f"    <Unit {_attr(name=u)}/>" for u in units]
        lines.append("  </UnitDefinitions>")
    if step_size is not None:
        lines.append(f"  <DefaultExperiment {_attr(startTime='0.0', stepSize=_fmt(step_size))}/>")
    lines.append("  <ModelVariables>")
    index = {}  # FMI 2.0: 1-based position of each value reference
    if v3:
        lines.append(f"    <Float64 {_attr(name='time', valueReference=vr.time, causality='independent', variability='continuous')}/>")
    for pos, (n, r, caus, var, init, start, unit, d, der) in enumerate(rows, start=1):
        index[r] = pos
        if v3:
            a = _attr(name=n, valueReference=r, causality=caus, variability=var, initial=init, description=d,
                      unit=unit, start=None if start is None else _fmt(start),
                      derivative=None if der is None else vr.x[der])
            lines.append(f"    <Float64 {a}/>")
        else:
            a = _attr(name=n, valueReference=r, causality=caus, variability=var, initial=init, description=d)
            real = _attr(unit=unit, start=None if start is None else _fmt(start),
                         derivative=None if der is None else len(em.p_names) + der + 1)  # 1-based index of the state
            lines.append(f"    <ScalarVariable {a}><Real {real}/></ScalarVariable>")
    lines.append("  </ModelVariables>")
    lines.append("  <ModelStructure>")
    if v3:
        for r, d in zip(vr.y, y_deps):
            lines.append(f"    <Output {_attr(valueReference=r, dependencies=' '.join(str(xu_vr[j]) for j in d))}/>")
        for r, d in zip(vr.dx, dx_deps):
            lines.append(f"    <ContinuousStateDerivative {_attr(valueReference=r, dependencies=' '.join(str(xu_vr[j]) for j in d))}/>")
        for r, d in zip(vr.y + vr.dx, y_init + dx_init):
            lines.append(f"    <InitialUnknown {_attr(valueReference=r, dependencies=' '.join(str(xu_vr[j]) for j in d))}/>")
    else:
        def block(tag: str, refs: list[int], deps: list[list[int]] | None) -> None:
            if not refs:
                return
            lines.append(f"    <{tag}>")
            items = sorted((index[r], d) for r, d in zip(refs, deps or [None] * len(refs)))
            for idx, d in items:
                dep = None if d is None else " ".join(str(i) for i in sorted(index[xu_vr[j]] for j in d))
                kinds = None if d is None else " ".join("dependent" for _ in d)
                lines.append(f"      <Unknown {_attr(index=idx, dependencies=dep, dependenciesKind=kinds)}/>")
            lines.append(f"    </{tag}>")

        block("Outputs", vr.y, y_deps)
        block("Derivatives", vr.dx, dx_deps)
        block("InitialUnknowns", vr.y + vr.dx, y_init + dx_init)
    lines.append("  </ModelStructure>")
    lines.append("</fmiModelDescription>")
    return "\n".join(lines) + "\n"
