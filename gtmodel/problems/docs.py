"""The problem-file reference and the JSON Schemas, generated from the kinds' schemas.

The kinds are the problem kinds (:data:`~gtmodel.problems.registry.KINDS`) and the
loop-controller file kinds (:data:`~gtmodel.problems.registry.LOOP_KINDS`: the MPC file,
the tracking-controller file, the estimator + ILC bundle), from the same declarations.
``docs/problem_files.md`` and ``docs/schemas/<kind>.schema.json`` are written by
:func:`write_docs` (``gtmodel schema --docs docs``); a test fails when they are stale.
Editors validate problem files as they are typed from the JSON Schema: with taplo /
Even Better TOML, a first line ``#:schema ../docs/schemas/<kind>.schema.json`` (path
relative to the problem file) is enough.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from pydantic import BaseModel

from gtmodel.problems.registry import KINDS, LOOP_KINDS, all_kinds, canonical_kind, get_kind, get_schema

__all__ = ["json_schema", "reference_markdown", "write_docs"]


def json_schema(kind: str) -> dict[str, Any]:
    """The JSON Schema (draft 2020-12) of a kind's problem files.

    Parameters
    ----------
    kind : str
        A registered kind, e.g. ``"point_to_point"``, or a loop-controller file kind (``"mpc"``).

    Returns
    -------
    dict
        The schema (``title``, ``$schema``, ``properties``, ``$defs``, ...).

    Raises
    ------
    ProblemError
        Unknown kind.
    """
    kind = canonical_kind(kind)
    schema = get_schema(kind).model_json_schema(mode="validation")
    schema["$schema"] = "https://json-schema.org/draft/2020-12/schema"
    schema["$id"] = f"https://gtmodel.invalid/schemas/{kind}.schema.json"
    schema["title"] = f"gtmodel {_what(kind)}, kind {kind}"
    schema["description"] = _title(kind)
    return schema


def _what(kind: str) -> str:
    return LOOP_KINDS[kind].what if kind in LOOP_KINDS else "problem file"


def _title(kind: str) -> str:
    if kind in LOOP_KINDS:
        return f"{LOOP_KINDS[kind].title}. Generated and checked by: {LOOP_KINDS[kind].command}"
    k = get_kind(kind)
    return k.title or (k.__doc__ or "").strip()


def _type(prop: dict[str, Any], defs: dict[str, Any]) -> str:
    if "$ref" in prop:
        return "table"
    if "anyOf" in prop:
        parts = [_type(p, defs) for p in prop["anyOf"] if p.get("type") != "null"]
        return " or ".join(parts)
    if "enum" in prop:
        return "one of " + ", ".join(f'`"{v}"`' for v in prop["enum"])
    if "const" in prop:
        return f'`"{prop["const"]}"`'
    t = prop.get("type", "any")
    if t == "array":
        item = prop.get("items", {})
        n = prop.get("minItems"), prop.get("maxItems")
        size = f"{n[0]}" if n[0] is not None and n[0] == n[1] else ""
        return f"list of {size + ' ' if size else ''}{_type(item, defs)}".replace("  ", " ")
    if t == "object":
        return "table of numbers" if "additionalProperties" in prop else "table"
    return {"number": "number", "integer": "integer", "string": "string", "boolean": "boolean"}.get(t, str(t))


def _range(prop: dict[str, Any]) -> str:
    for p in prop.get("anyOf", [prop]):
        if p.get("type") == "array":
            p = p.get("items", {})
        parts = []
        for key, sym in (("exclusiveMinimum", ">"), ("minimum", ">="), ("exclusiveMaximum", "<"), ("maximum", "<=")):
            if key in p:
                parts.append(f"{sym} {p[key]:g}")
        if parts:
            return ", ".join(parts)
    return ""


def _rows(model: type[BaseModel], prefix: str, defs: dict[str, Any], schema: dict[str, Any], out: list[str], tables: list[tuple[str, type[BaseModel]]]) -> None:
    props = schema.get("properties", {})
    required = set(schema.get("required", []))
    for field_name, info in model.model_fields.items():
        name = info.alias or field_name  # the key in the file (``class`` for ``class_``)
        prop = props.get(name, {})
        sub = _submodel(info.annotation)
        dotted = f"{prefix}{name}"
        if sub is not None:
            tables.append((dotted, sub))
            continue
        default = "required" if name in required else json.dumps(info.get_default(call_default_factory=True)) if not callable(info.default) else ""
        unit = prop.get("unit") or next((p.get("unit") for p in prop.get("anyOf", []) if isinstance(p, dict) and p.get("unit")), "")
        branch = next((p for p in prop.get("anyOf", []) if isinstance(p, dict) and p.get("description")), {})
        desc = (prop.get("description") or branch.get("description") or info.description or "").replace("|", "\\|")
        out.append(f"| `{dotted}` | {_type(prop, defs)} | {_range(prop)} | {unit} | {default} | {desc} |")


def _submodel(annotation: Any) -> type[BaseModel] | None:
    if isinstance(annotation, type) and issubclass(annotation, BaseModel):
        return annotation
    for arg in getattr(annotation, "__args__", ()) or ():
        if isinstance(arg, type) and issubclass(arg, BaseModel):
            return arg
    return None


def reference_markdown() -> str:
    """The problem-file reference page (``docs/problem_files.md``) of every kind.

    Returns
    -------
    str
        Markdown: per kind, one table per TOML table with type, range, unit, default and
        description of each field.
    """
    lines = [
        "# Problem files: field reference",
        "",
        "Generated from the schemas in `gtmodel/problems/kinds/` by `gtmodel schema --docs docs`;",
        "do not edit by hand (a test fails when this page is stale). Units are SI unless the",
        "field name says otherwise (`_deg`, `_mm`). Every field is validated on load; an error",
        "names the file, the dotted field, what was expected and what was given (exit code 2).",
        "",
        "Editors validate a file as it is typed from its JSON Schema (`gtmodel schema KIND`,",
        "or the copies in `docs/schemas/`): with taplo / Even Better TOML, put",
        "`#:schema ../docs/schemas/<kind>.schema.json` (relative to the problem file) on the",
        "first line, as the shipped files in `problems/` do.",
        "",
        "Kinds: " + ", ".join(f"[`{k}`](#{k})" for k in KINDS) + ".",
        "",
        "Loop-controller files (declared as the kinds are, generated and checked by `gtmodel codegen`,",
        "not solved; `gtmodel schema KIND` gives their schemas too): "
        + ", ".join(f"[`{k}`](#{k})" for k in LOOP_KINDS) + ".",
        "",
    ]
    for name in all_kinds():
        model = get_schema(name)
        schema = model.model_json_schema(mode="validation")
        defs = schema.get("$defs", {})
        lines += [f"## {name}", "", _title(name), ""]
        tables: list[tuple[str, type[BaseModel]]] = [("", model)]
        while tables:
            dotted, model = tables.pop(0)
            sub_schema = schema if not dotted else defs.get(model.__name__, {})
            rows: list[str] = []
            _rows(model, f"{dotted}." if dotted else "", defs, sub_schema, rows, tables)
            if not rows:
                continue
            head = "top level" if not dotted else f"`[{dotted}]`"
            doc = (model.__doc__ or "").strip().splitlines()[0] if dotted else ""
            lines += [f"### {head}", ""] + ([doc, ""] if doc else [])
            lines += ["| field | type | range | unit | default | description |", "|---|---|---|---|---|---|", *rows, ""]
    return "\n".join(lines).rstrip() + "\n"


def write_docs(folder: str | Path) -> list[Path]:
    """Write ``problem_files.md`` and ``schemas/<kind>.schema.json`` into a folder.

    Parameters
    ----------
    folder : str or pathlib.Path
        Usually the repository's ``docs/``.

    Returns
    -------
    list of pathlib.Path
        The files written.
    """
    folder = Path(folder)
    (folder / "schemas").mkdir(parents=True, exist_ok=True)
    written = [folder / "problem_files.md"]
    written[0].write_text(reference_markdown(), encoding="utf-8")
    for kind in all_kinds():
        target = folder / "schemas" / f"{kind}.schema.json"
        target.write_text(json.dumps(json_schema(kind), indent=2) + "\n", encoding="utf-8")
        written.append(target)
    return written
