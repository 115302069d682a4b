"""pymoca against rumoca, the two Modelica front ends issue 68 weighs, on the project's Modelica files (a benchmark, not a test).

Usage: python benchmarks/bench_modelica_front_ends.py [--json] [--repeat 5] [--rumoca-python PATH]

The files: the shipped Optimica problems (``problems/optimica/*.mop``, ``*.mo``), every
instantiable class of the shipped Modelica Standard Library subset
(``gtmodel/exchange/modelica_library/Modelica.mo``) and the Modelica test fixtures
(``tests/exchange/**/*.mo``, ``*.mop``). Each front end is given the same text: a ``.mo``
file as written; of a ``.mop`` file the text gtmodel gives its front end (the ``optimization``
class read as a ``model``, its Optimica parts taken out by
:func:`gtmodel.exchange.optimica_syntax.split_optimica`: neither front end reads Optimica;
rumoca is also tried on the ``.mop`` file as written); with the MSL subset available when the
text names ``Modelica.`` (pymoca: its classes parsed and added to the tree; rumoca: its folder
as a library root); with the package ``GantryTau`` gtmodel ships
(:mod:`gtmodel.exchange.robot_library`, ``modelica_library/GantryTau.mo``) when the text names
``GantryTau.``, as gtmodel's Optimica front end adds it (pymoca: the package parsed and added to
the tree; rumoca: its folder as a library root). No gtmodel rewriting (``gtmodel.exchange.msl.prepare``) is applied, so
what a front end does with the file itself shows. A file naming ``RealInput``/``RealOutput`` is
read twice more, each front end as it can: ``[msl.prepare]`` (the text as gtmodel rewrites it
for pymoca: ``input Real u``) and ``[MSL RealInput]`` (the library with the MSL's own
``connector RealInput = input Real;``). Then :data:`PROBES`: one construct each (a short
connector class, a conditional component, a ``final`` modification, ``when``, ...).

Measured for each file and class, and for each front end:

- whether it accepts the class (parse and flatten to a DAE), else its first error line;
- the flattened DAE's scalar counts: unknowns (states + algebraic variables + outputs
  that are not inputs), equations, states, inputs, parameters (and constants), initial
  equations; rumoca also reports the ``when`` clauses, ``algorithm`` sections and
  ``assert`` calls it kept;
- the time to read it: parse + flatten (pymoca: ``parser.parse`` and
  ``backends.casadi.generator.generate``, the two calls gtmodel makes; rumoca: a fresh
  ``rumoca.Session().loads(...)`` to its DAE stage), the median of ``--repeat`` runs after
  one warm-up run;
- what gtmodel's own import (``load_modelica`` / ``load_optimica``, pymoca behind its
  checks) does with it: accepted with its counts, or refused with file:line.

A front end "loses without a word" where it accepts the class and its counts fall short of
its peer's (or of the equations the file writes, e.g. a ``when`` clause). Printed: one row
per class with each figure next to its peer's and the time ratio pymoca / rumoca. rumoca
runs in the Python that has it: this one if ``import rumoca`` works, else
``--rumoca-python`` (default ``/tmp/rumoca_env/bin/python``, a venv made by ``python -m venv
/tmp/rumoca_env && /tmp/rumoca_env/bin/pip install rumoca``) as a child process running this
file with ``--worker``; without either, the rumoca side is skipped with a message saying so.
With ``--json`` the last line of stdout is one JSON object.
"""

from __future__ import annotations

import argparse
import atexit
import functools
import json
import math
import re
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

REPO = Path(__file__).resolve().parents[1]
LIBRARY = REPO / "gtmodel" / "exchange" / "modelica_library"
DEFAULT_RUMOCA_PYTHON = "/tmp/rumoca_env/bin/python"
_MSL_REF = re.compile(r"(?<![\w.])Modelica\s*\.")
_OPT_RE = re.compile(r"\boptimization\s+([A-Za-z_]\w*)")
_CLASS_DECL_RE = re.compile(r"\b(?:model|block|package|connector|record|function|class|type)\s+([A-Za-z_]\w*)")
_A = "model A parameter Real k = 1; Real x(start = 1); equation der(x) = -k * x; end A; "
#: Constructs tried on both front ends, each a class ``M`` (docs/optimica.md says what each front end does with them).
PROBES = {
    "short connector class (connector RealInput = input Real)":
        "connector RealInput = input Real; model M RealInput u; Real x(start = 0); equation der(x) = u; end M;",
    "short connector class, an input nothing uses yet":
        "connector RealInput = input Real; model M RealInput u; Real x(start = 0); equation der(x) = -x; end M;",
    "modifier of a missing element (A a(kk = 3))": _A + "model M A a(kk = 3); end M;",
    "modification of a final parameter": _A.replace("parameter", "final parameter") + "model M A a(k = 3); end M;",
    "modifiers of a component (A a(k = 3, x(start = 2)))": _A + "model M A a(k = 3, x(start = 2)); end M;",
    "redeclare model": _A + "model B extends A(k = 2); end B; model C replaceable model P = A; P p; end C; "
                       "model M extends C(redeclare model P = B); end M;",
    "conditional component (A a if false)": _A + "model M parameter Boolean use = false; A a if use; Real y(start = 1); "
                                              "equation der(y) = -y; end M;",
    "constant of another package (C.pi)": "package C constant Real pi = 3.14159; end C; model M Real x(start = 1); "
                                        "equation der(x) = -C.pi * x; end M;",
    "if-equation": "model M parameter Real p = 1; Real x(start = 1); Real y; equation der(x) = -x; "
                   "if p > 0 then y = x; else y = -x; end if; end M;",
    "when-clause without pre()": "model M Real x(start = 1); discrete Real y(start = 0); equation der(x) = -x; "
                                 "when x < 0.5 then y = 1; end when; end M;",
    "when-clause with reinit()": "model M Real h(start = 1); Real v(start = 0); equation der(h) = v; der(v) = -9.81; "
                                 "when h < 0 then reinit(v, -0.8 * v); end when; end M;",
    "algorithm section": "model M Real x(start = 1); Real y; equation der(x) = -x; algorithm y := 2 * x; end M;",
    "assert()": "model M Real x(start = 1); equation der(x) = -x; assert(x > -1, \"negative\"); end M;",
}


# ----------------------------------------------------------------------------------------------
# rumoca side (runs with rumoca only: no gtmodel, pymoca or CasADi needed in its Python)

def _size(dims: Any) -> int:
    return int(math.prod(int(d) for d in dims)) if dims else 1


def rumoca_read(job: dict[str, Any]) -> dict[str, Any]:
    """Read one job's text with rumoca to its DAE (one fresh session).

    Parameters
    ----------
    job : dict
        ``text``, ``class``, ``filename``, ``msl`` (whether the MSL subset's folder is a library root)
        and ``robots`` (the ``GantryTau.mo`` file whose folder is a library root too, or "").

    Returns
    -------
    dict
        rumoca's model (``model``) or the exception (``error``), and the seconds taken (``s``).
    """
    import rumoca

    roots = ([job["library"]] if job["msl"] else []) + ([str(Path(job["robots"]).parent)] if job.get("robots") else [])
    session = rumoca.Session(roots=list(dict.fromkeys(roots)))
    t0 = time.perf_counter()
    try:
        model = session.loads(job["text"], model=job["class"], filename=job["filename"])
    except Exception as exc:  # noqa: BLE001 - rumoca's ParseError, CompileError, ...
        return {"error": exc, "s": time.perf_counter() - t0}
    return {"model": model, "s": time.perf_counter() - t0}


def rumoca_counts(model: Any) -> dict[str, int]:
    """The scalar counts of a DAE rumoca flattened (see the module docstring).

    Parameters
    ----------
    model : rumoca.Model
        As :func:`rumoca_read` returns it.

    Returns
    -------
    dict of str to int
    """
    st = model.structure()
    flat = model.to_dict("flat")
    scalars = lambda view: sum(_size(v.dims) for v in view)  # noqa: E731
    values = {p.name: float(p.value) for p in model.parameters if p.value is not None and not p.dims}
    try:
        model.render("casadi-ode")
        casadi = "ok"
    except Exception as exc:  # noqa: BLE001 - its explicit-ODE target refuses residual equations, initial equations, ...
        casadi = re.sub(r"^.*?unsupported-feature:([\w-]+).*$", r"\1", _first_line(exc))
        casadi = re.sub(r"^Target rendering error: ", "", casadi)[:80]
    return {"unknowns": int(st.n_unknowns), "equations": int(st.n_equations), "states": scalars(model.states),
            "inputs": scalars(model.inputs), "parameters": scalars(model.parameters),
            "initial_equations": len(flat.get("initial_equations", [])), "when": len(flat.get("when_chains", [])),
            "algorithms": len(flat.get("algorithms", [])), "asserts": len(flat.get("assert_equations", [])),
            "casadi_export": casadi, "parameter_values": values}


def _first_line(exc: BaseException) -> str:
    lines = [ln.strip() for ln in str(exc).splitlines() if ln.strip()]
    return (lines[0] if lines else type(exc).__name__)[:240]


def rumoca_side(jobs: list[dict[str, Any]], repeat: int) -> dict[str, Any]:
    """Run the jobs with rumoca in this Python: acceptance, counts, median time.

    Parameters
    ----------
    jobs : list of dict
        See :func:`rumoca_read`, each with a ``label``.
    repeat : int
        Timed runs of each (after one warm-up run).

    Returns
    -------
    dict
        ``version`` and ``results`` by label: ``ok``, ``error``, ``counts``, ``median_s``.
    """
    import rumoca

    out = {}
    for job in jobs:
        first = rumoca_read(job)
        times = [rumoca_read(job)["s"] for _ in range(repeat)]
        entry: dict[str, Any] = {"ok": "model" in first, "median_s": statistics.median(times)}
        if "model" in first:
            entry["counts"] = rumoca_counts(first["model"])
        else:
            entry["error"] = _first_line(first["error"])
        out[job["label"]] = entry
    return {"version": rumoca.version(), "results": out}


def _worker() -> None:
    """``--worker``: jobs as JSON on stdin, rumoca's results as JSON on stdout."""
    req = json.load(sys.stdin)
    json.dump(rumoca_side(req["jobs"], req["repeat"]), sys.stdout)


# ----------------------------------------------------------------------------------------------
# jobs and the pymoca side (the project's Python)

def _default_class(text: str) -> str:
    """The class gtmodel's ``load_modelica`` translates by default (the last top-level model, in a package its last model)."""
    from pymoca import parser

    ast = parser.parse(text)
    user = [c for c in ast.classes if c not in ("Real", "Integer", "Boolean", "String", "StateSelect", "Clock")]
    top = ast.classes[user[-1]]
    models = [n for n, c in top.classes.items() if c.type in ("model", "block")] if top.type == "package" else []
    return f"{user[-1]}.{models[-1]}" if models else user[-1]


def _library_classes() -> list[str]:
    """The instantiable (not partial) ``model``/``block`` classes of the shipped MSL subset, dotted."""
    from pymoca import parser

    out = []

    def walk(node: Any, prefix: str) -> None:
        for name, cls in node.classes.items():
            path = f"{prefix}.{name}" if prefix else name
            if cls.type in ("model", "block") and not getattr(cls, "partial", False):
                out.append(path)
            walk(cls, path)

    walk(parser.parse((LIBRARY / "Modelica.mo").read_text(encoding="utf-8")), "")
    return out


def make_jobs() -> list[dict[str, Any]]:
    """The files and classes read (see the module docstring).

    Returns
    -------
    list of dict
        ``label``, ``path`` (relative), ``kind`` (``mo``, ``mop``, ``library``), ``class``,
        ``text`` (what the front ends read), ``raw`` (the file as written), ``filename``,
        ``msl``, ``library``, ``robots`` (the path of the shipped ``GantryTau`` package when the
        text names ``GantryTau.``, as gtmodel adds it; else "").
    """
    from gtmodel.exchange import msl, robot_library
    from gtmodel.exchange.msl import code_only
    from gtmodel.exchange.optimica_syntax import split_optimica

    jobs = []
    files = sorted(REPO.glob("problems/optimica/*.mo")) + sorted(REPO.glob("problems/optimica/*.mop"))
    files += sorted(REPO.glob("tests/exchange/**/*.mo")) + sorted(REPO.glob("tests/exchange/**/*.mop"))
    for path in files:
        rel = path.relative_to(REPO).as_posix()
        raw = path.read_text(encoding="utf-8", errors="replace")
        base = {"path": rel, "raw": raw, "filename": path.name, "library": str(LIBRARY), "robots": ""}
        if path.suffix == ".mop":
            for bare in _OPT_RE.findall(raw):
                oc = split_optimica(path, raw, bare)
                text = oc.model_text + _siblings(path, oc.model_text)
                robots = str(robot_library.ROBOT_SOURCE) if robot_library.uses_robots(code_only(text)) else ""
                jobs.append({**base, "label": f"{rel}:{oc.name}", "kind": "mop", "class": oc.name, "text": text,
                             "msl": bool(_MSL_REF.search(text)), "robots": robots})
        else:
            try:
                cls = _default_class(raw)
            except Exception as exc:  # noqa: BLE001 - a fixture pymoca cannot parse (syntax_error.mo): the last class named
                names = re.findall(r"^\s*(?:model|block)\s+([A-Za-z_]\w*)", raw, re.M)
                cls = names[-1] if names else "?"
                base["note"] = f"pymoca cannot parse it to pick a class: {_first_line(exc)}"
            robots = str(robot_library.ROBOT_SOURCE) if robot_library.uses_robots(code_only(raw)) else ""
            jobs.append({**base, "label": f"{rel}:{cls}", "kind": "mo", "class": cls, "text": raw, "msl": bool(_MSL_REF.search(raw)),
                         "robots": robots})
        last = jobs[-1]
        if last["msl"] and re.search(r"\bReal(?:In|Out)put\b", last["text"]):  # the MSL's own short connector classes
            jobs.append({**last, "label": last["label"] + " [MSL RealInput]", "kind": last["kind"] + "-msl-connectors",
                         "library": str(_library_with_connectors()),
                         "note": "the library with the MSL's connector RealInput = input Real; / RealOutput declared"})
        if last["msl"] and msl.prepare(path, last["text"]) != last["text"]:  # RealInput/RealOutput, Modelica.Constants read by gtmodel
            jobs.append({**last, "label": last["label"] + " [msl.prepare]", "kind": last["kind"] + "-prepared",
                         "text": msl.prepare(path, last["text"]), "note": "the text as gtmodel.exchange.msl.prepare rewrites it"})
    lib = (LIBRARY / "Modelica.mo").read_text(encoding="utf-8")
    lib_rel = (LIBRARY / "Modelica.mo").relative_to(REPO).as_posix()
    for cls in _library_classes():
        jobs.append({"label": f"Modelica.mo:{cls}", "path": lib_rel, "kind": "library", "class": cls, "text": lib, "raw": lib,
                     "filename": "Modelica.mo", "msl": False, "library": str(LIBRARY), "robots": ""})
    for what, text in PROBES.items():
        jobs.append({"label": f"probe: {what}", "path": "", "kind": "probe", "class": "M", "text": text, "raw": text,
                     "filename": "probe.mo", "msl": False, "library": str(LIBRARY), "robots": ""})
    return jobs


#: The MSL's declarations of ``Modelica.Blocks.Interfaces.RealInput``/``RealOutput`` (the shipped subset leaves them out).
MSL_CONNECTORS = ('    package Interfaces\n      connector RealInput = input Real "connector with one input signal";\n'
                  '      connector RealOutput = output Real "connector with one output signal";\n    end Interfaces;\n')


@functools.lru_cache(maxsize=1)
def _library_with_connectors() -> Path:
    """A folder with the shipped ``Modelica.mo`` plus :data:`MSL_CONNECTORS` in ``Modelica.Blocks`` (a temporary folder)."""
    text = (LIBRARY / "Modelica.mo").read_text(encoding="utf-8")
    text = re.sub(r"^(  package Blocks\b[^\n]*\n)", lambda m: m.group(1) + MSL_CONNECTORS, text, count=1, flags=re.M)
    folder = Path(tempfile.mkdtemp(prefix="msl_connectors_"))
    atexit.register(shutil.rmtree, folder, True)  # removed when the process ends (the rumoca child reads it before)
    (folder / "Modelica.mo").write_text(text, encoding="utf-8")
    return folder


def _siblings(path: Path, text: str) -> str:
    """The ``.mo`` files beside a ``.mop`` file that declare a class its text uses and does not declare (as gtmodel reads them)."""
    needed = set(re.findall(r"[A-Za-z_]\w*", text)) - set(_CLASS_DECL_RE.findall(text))
    out = []
    for other in sorted(path.parent.glob("*.mo")):
        other_text = other.read_text(encoding="utf-8", errors="replace")
        if needed & set(_CLASS_DECL_RE.findall(other_text)):
            out.append(f"\n// {other.name}\n{other_text}")
    return "".join(out)


def pymoca_read(job: dict[str, Any]) -> tuple[Any, float]:
    """Read one job's text with pymoca: parse, add the MSL subset if named, flatten to CasADi.

    Parameters
    ----------
    job : dict
        See :func:`make_jobs`; the MSL subset and the ``GantryTau`` package are parsed in each run, as gtmodel does.

    Returns
    -------
    tuple
        pymoca's CasADi model or the exception, and the seconds taken.
    """
    from gtmodel.exchange.modelica import _pymoca

    parser, generator = _pymoca()  # with the CasADi 3.8 division patch gtmodel applies
    t0 = time.perf_counter()
    try:
        ast = parser.parse(job["text"])
        if ast is None:
            raise ValueError("the parser returned nothing")
        if job["msl"]:
            ast.extend(parser.parse((Path(job["library"]) / "Modelica.mo").read_text(encoding="utf-8")))
        if job.get("robots"):  # the shipped Gantry-Tau robots, as gtmodel.exchange.robot_library.extend adds them
            ast.extend(parser.parse(Path(job["robots"]).read_text(encoding="utf-8")))
        mo = generator.generate(ast, job["class"])
    except Exception as exc:  # noqa: BLE001 - pymoca raises many types
        return exc, time.perf_counter() - t0
    return mo, time.perf_counter() - t0


def pymoca_counts(mo: Any) -> dict[str, int]:
    """The scalar counts of a DAE pymoca flattened (see the module docstring).

    Parameters
    ----------
    mo : pymoca.backends.casadi.model.Model
        As :func:`pymoca_read` returns it.

    Returns
    -------
    dict of str to int
    """
    n = lambda group: sum(int(v.symbol.numel()) for v in group)  # noqa: E731
    eq = lambda group: sum(int(e.numel()) for e in group)  # noqa: E731
    values = {}
    for p in mo.parameters:
        try:
            value = float(p.value if p.value is not None else p.start)
            if int(p.symbol.numel()) == 1 and math.isfinite(value):
                values[p.symbol.name()] = value
        except (TypeError, ValueError, RuntimeError):
            pass  # bound to an expression of other parameters
    return {"unknowns": n(mo.states) + n(mo.alg_states), "equations": eq(mo.equations), "states": n(mo.states),
            "inputs": n(mo.inputs), "parameters": n(mo.parameters) + n(mo.constants),
            "initial_equations": eq(mo.initial_equations), "parameter_values": values}


def pymoca_side(jobs: list[dict[str, Any]], repeat: int) -> dict[str, Any]:
    """Run the jobs with pymoca: acceptance, counts, median time.

    Parameters
    ----------
    jobs : list of dict
        See :func:`make_jobs`.
    repeat : int
        Timed runs of each (after one warm-up run).

    Returns
    -------
    dict
        ``version`` and ``results`` by label: ``ok``, ``error``, ``counts``, ``median_s``.
    """
    import logging

    import pymoca

    logging.getLogger("pymoca").setLevel(logging.ERROR)  # its warnings ("Connector class ... not defined") would break the table
    out = {}
    for job in jobs:
        first, _ = pymoca_read(job)
        times = [pymoca_read(job)[1] for _ in range(repeat)]
        entry: dict[str, Any] = {"ok": not isinstance(first, BaseException), "median_s": statistics.median(times)}
        if entry["ok"]:
            entry["counts"] = pymoca_counts(first)
        else:
            entry["error"] = _first_line(first) or type(first).__name__
        out[job["label"]] = entry
    return {"version": pymoca.__version__, "results": out}


def gtmodel_side(jobs: list[dict[str, Any]]) -> dict[str, Any]:
    """What gtmodel's own import (pymoca behind its checks) does with each file's class.

    Parameters
    ----------
    jobs : list of dict
        See :func:`make_jobs` (the library's classes are not loaded alone: they are read through the files naming them).

    Returns
    -------
    dict
        By label: ``ok`` and the model's counts (unknowns, equations, states, inputs,
        parameters), or the refusal's first line (``error``).
    """
    import logging

    from gtmodel.exchange.modelica import load_modelica
    from gtmodel.exchange.optimica import load_optimica

    logging.getLogger("gtmodel").setLevel(logging.ERROR)
    out = {}
    for job in jobs:
        if job["kind"] not in ("mo", "mop"):
            continue
        try:
            if job["kind"] == "mop":
                model = load_optimica(REPO / job["path"], job["class"]).model
            else:
                model = load_modelica(REPO / job["path"], job["class"])
        except Exception as exc:  # noqa: BLE001 - InputError, OptimicaError, ModelError
            out[job["label"]] = {"ok": False, "error": _first_line(exc).replace(str(REPO) + "/", "")}
            continue
        size = lambda kind: sum(int(s.numel()) for s in model.variables(kind).values())  # noqa: E731
        out[job["label"]] = {"ok": True, "counts": {
            "unknowns": size("state") + size("algebraic"), "equations": sum(int(e.numel()) for e in _equations(model)),
            "states": size("state"), "inputs": size("input"), "parameters": size("parameter")}}
    return out


def _equations(model: Any) -> list[Any]:
    """The residuals of a gtmodel model's equations (``(name, residual)`` pairs inside ``Model``)."""
    return [eq[1] for eq in getattr(model, "_equations", [])]


def _run_rumoca(jobs: list[dict[str, Any]], repeat: int, python: str) -> dict[str, Any]:
    """The rumoca side: in this Python if it imports rumoca, else in ``python`` (``--worker``), else skipped."""
    wire = [{k: j.get(k, "") for k in ("label", "text", "class", "filename", "msl", "library", "robots")} for j in jobs]
    wire += [{**{k: j.get(k, "") for k in ("class", "filename", "msl", "library", "robots")}, "label": j["label"] + " [as written]",
              "text": j["raw"]}
             for j in jobs if j["kind"] == "mop"]
    try:
        import rumoca  # noqa: F401
    except ImportError:
        pass
    else:
        return rumoca_side(wire, repeat)
    if not Path(python).is_file():
        return {"skipped": f"rumoca is not importable here and {python} does not exist: python -m venv /tmp/rumoca_env && "
                           "/tmp/rumoca_env/bin/pip install rumoca, then --rumoca-python /tmp/rumoca_env/bin/python"}
    proc = subprocess.run([python, __file__, "--worker"], input=json.dumps({"jobs": wire, "repeat": repeat}),
                          capture_output=True, text=True)
    if proc.returncode:
        return {"skipped": f"{python} --worker failed: {proc.stderr.strip().splitlines()[-1] if proc.stderr.strip() else proc.returncode}"}
    return json.loads(proc.stdout)


def _cell(entry: dict[str, Any] | None, key: str) -> str:
    if not entry:
        return "-"
    if not entry["ok"]:
        return "ERR"
    return str(entry["counts"].get(key, "-"))


def _losses(p: dict[str, Any], r: dict[str, Any] | None, g: dict[str, Any] | None) -> list[str]:
    """What differs between the two front ends' DAEs (a silent loss on one side), in words."""
    notes = []
    if r and r.get("ok") and p["ok"]:
        pc, rc = p["counts"], r["counts"]
        for key in ("unknowns", "equations", "states", "inputs", "initial_equations"):
            if pc[key] != rc[key]:
                notes.append(f"{key} pymoca {pc[key]} / rumoca {rc[key]}")
        pv, rv = pc.get("parameter_values", {}), rc.get("parameter_values", {})
        differ = [k for k in pv if k in rv and abs(pv[k] - rv[k]) > 1e-12 * max(1.0, abs(rv[k]))]
        if differ:
            notes.append("parameter values differ: " + ", ".join(f"{k} pymoca {pv[k]:g} / rumoca {rv[k]:g}" for k in differ))
        for key in ("when", "algorithms", "asserts"):
            if rc.get(key):
                notes.append(f"rumoca keeps {rc[key]} {key}, pymoca none")
    elif r and r.get("ok") != p["ok"]:
        notes.append("pymoca refuses" if r.get("ok") else "rumoca refuses")
    if g is not None:
        notes.append("gtmodel: " + ("accepts" if g["ok"] else "refuses: " + g["error"][:120]))
    return notes


def summarise(jobs: list[dict[str, Any]], py: dict[str, Any], ru: dict[str, Any], gt: dict[str, Any]) -> dict[str, Any]:
    """The totals by kind of file: classes each accepts, disagreements, total and median time ratios.

    Parameters
    ----------
    jobs : list of dict
        See :func:`make_jobs`.
    py, ru : dict
        :func:`pymoca_side`, the rumoca side (``results`` by label, or ``skipped``).
    gt : dict
        :func:`gtmodel_side`.

    Returns
    -------
    dict
        By kind (``mo``, ``mop``, ``*-prepared``, ``library``, ``probe``), and ``gtmodel_accepts`` of the files.
    """
    pr, rr = py["results"], ru.get("results", {})
    out: dict[str, Any] = {"gtmodel_accepts": f"{sum(v['ok'] for v in gt.values())}/{len(gt)}"}
    for kind in dict.fromkeys(j["kind"] for j in jobs):
        labels = [j["label"] for j in jobs if j["kind"] == kind]
        entry: dict[str, Any] = {"classes": len(labels), "pymoca_accepts": sum(pr[k]["ok"] for k in labels)}
        if rr:
            both = [k for k in labels if pr[k]["ok"] and rr.get(k, {}).get("ok")]
            entry["rumoca_accepts"] = sum(rr.get(k, {}).get("ok", False) for k in labels)
            entry["rumoca_casadi_export"] = sum(rr.get(k, {}).get("counts", {}).get("casadi_export") == "ok" for k in labels)
            entry["counts_differ"] = [k for k in both if any(pr[k]["counts"][c] != rr[k]["counts"][c]
                                                              for c in ("unknowns", "equations", "states", "inputs"))]
            tp, tr = sum(pr[k]["median_s"] for k in both), sum(rr[k]["median_s"] for k in both)
            entry["total_ms_pymoca"], entry["total_ms_rumoca"] = round(1e3 * tp, 2), round(1e3 * tr, 2)
            entry["total_ratio_pymoca_over_rumoca"] = round(tp / tr, 2) if tr else None
            ratios = [pr[k]["median_s"] / rr[k]["median_s"] for k in both if rr[k]["median_s"] > 0]
            entry["median_ratio_pymoca_over_rumoca"] = round(statistics.median(ratios), 2) if ratios else None
            if kind == "mop":
                entry["rumoca_accepts_as_written"] = sum(v["ok"] for k, v in rr.items() if k.endswith(" [as written]"))
        out[kind] = entry
    pairs = {}  # an MSL file read as each front end can: pymoca after msl.prepare, rumoca with the MSL's RealInput declared
    for job in jobs:
        p, r = pr.get(job["label"] + " [msl.prepare]"), rr.get(job["label"] + " [MSL RealInput]")
        if p and r and p["ok"] and r["ok"]:
            pairs[job["label"]] = {"unknowns": f"{p['counts']['unknowns']}/{r['counts']['unknowns']}",
                                   "equations": f"{p['counts']['equations']}/{r['counts']['equations']}",
                                   "ms": f"{1e3 * p['median_s']:.1f}/{1e3 * r['median_s']:.1f}",
                                   "ratio_pymoca_over_rumoca": round(p["median_s"] / r["median_s"], 2)}
    if pairs:
        out["msl_files_each_as_it_reads_them"] = pairs
    return out


def main() -> None:
    """Run the benchmark (see the module docstring)."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--json", action="store_true", help="one JSON object on the last line")
    ap.add_argument("--repeat", type=int, default=5, help="timed runs of each read (the median is reported)")
    ap.add_argument("--rumoca-python", default=DEFAULT_RUMOCA_PYTHON, help="a Python with rumoca installed")
    ap.add_argument("--worker", action="store_true", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.worker:
        _worker()
        return
    try:
        import gtmodel  # noqa: F401
        import pymoca  # noqa: F401
    except ImportError as exc:
        raise SystemExit(f"{exc}: run this script with the project's Python (gtmodel and pymoca installed); it runs "
                         f"rumoca in --rumoca-python ({args.rumoca_python}) as a child process") from None
    jobs = make_jobs()
    py = pymoca_side(jobs, args.repeat)
    ru = _run_rumoca(jobs, args.repeat, args.rumoca_python)
    gt = gtmodel_side(jobs)
    if "skipped" in ru:
        print(f"rumoca side skipped: {ru['skipped']}")
    print(f"pymoca {py['version']}" + (f", rumoca {ru['version']}" if "version" in ru else "") + f"; median of {args.repeat} runs")
    head = f"{'file:class':58s} {'accepts p/r':>11s} {'unknowns p/r':>12s} {'equations p/r':>13s} {'time p / r ms':>16s} {'ratio':>6s}"
    print(head)
    rr = ru.get("results", {})
    rows = []
    for job in jobs:
        label = job["label"]
        p, r, g = py["results"][label], rr.get(label), gt.get(label)
        ratio = p["median_s"] / r["median_s"] if r and r["median_s"] > 0 else None
        acc = ("y" if p["ok"] else "n") + "/" + ("-" if r is None else "y" if r["ok"] else "n")
        print(f"{label[-58:]:58s} {acc:>11s} {_cell(p, 'unknowns') + '/' + _cell(r, 'unknowns'):>12s} "
              f"{_cell(p, 'equations') + '/' + _cell(r, 'equations'):>13s} "
              f"{1e3 * p['median_s']:7.2f} / {1e3 * r['median_s'] if r else float('nan'):6.2f} "
              f"{ratio if ratio else float('nan'):6.2f}")
        notes = _losses(p, r, g)
        for what, entry in (("pymoca", p), ("rumoca", r)):
            if entry and not entry["ok"]:
                notes.append(f"{what}: {entry['error'][:150]}")
        if job.get("note"):
            notes.append(job["note"])
        for note in notes:
            print(f"    {note}")
        rows.append({"label": label, "kind": job["kind"], "pymoca": p, "rumoca": r, "gtmodel": g, "ratio_pymoca_over_rumoca": ratio})
    for label, r in rr.items():
        if label.endswith(" [as written]"):
            print(f"{label}: rumoca " + ("accepts" if r["ok"] else f"refuses: {r['error'][:150]}"))
    summary = summarise(jobs, py, ru, gt)
    for kind, entry in summary.items():
        print(f"summary {kind}: {json.dumps(entry)}")
    if args.json:
        print(json.dumps({"pymoca": py["version"], "rumoca": ru.get("version"), "rumoca_skipped": ru.get("skipped"),
                          "repeat": args.repeat, "rows": rows, "summary": summary,
                          "as_written": {k: v for k, v in rr.items() if k.endswith(" [as written]")}}))


if __name__ == "__main__":
    main()
