"""Field overrides of a problem file: ``--sweep FIELD=V1,V2`` and :func:`apply_override`."""

from __future__ import annotations

import copy
import tomllib
from pathlib import Path
from typing import Any

from gtmodel.errors import ProblemError

__all__ = ["parse_override", "apply_override"]


def parse_override(text: str) -> tuple[str, list[Any]]:
    """Parse a sweep/override argument ``field=v1,v2,...`` (values as TOML literals).

    Parameters
    ----------
    text : str
        E.g. ``"w=0,0.001,0.01"`` or ``"limits.force=[400,400,400],[450,450,450]"``.

    Returns
    -------
    field : str
        The (dotted) field name.
    values : list
        The parsed values.

    Raises
    ------
    ProblemError
        If the text has no ``=``, no values or a value is not a TOML literal.
    """
    if "=" not in text:
        raise ProblemError(f"--sweep {text!r}: expected FIELD=VALUE1,VALUE2,... (e.g. w=0,0.001,0.01)")
    field, _, rest = text.partition("=")
    field = field.strip()
    if not field or not rest.strip():
        raise ProblemError(f"--sweep {text!r}: expected FIELD=VALUE1,VALUE2,...")
    try:
        values = tomllib.loads(f"v = [{rest}]")["v"]
    except tomllib.TOMLDecodeError as exc:
        raise ProblemError(f"--sweep {text!r}: values must be TOML literals separated by commas ({exc})") from None
    if not values:
        raise ProblemError(f"--sweep {text!r}: no values")
    return field, values


def apply_override(data: dict[str, Any], field: str, value: Any, path: Path, create: bool = False) -> dict[str, Any]:
    """A copy of a problem document with one field replaced.

    A field without a dot is looked up in ``[parameters]`` first (named parameters of
    the objective and constraints, e.g. ``w``), then at the top level.

    Parameters
    ----------
    data : dict
        The parsed document (not modified).
    field : str
        Dotted field name or parameter name.
    value : Any
        New value.
    path : pathlib.Path
        The file (for messages).
    create : bool, optional
        Set the field even where the file leaves it (and its table) to the default: a
        command-line option such as ``gtmodel loop --listen``; the schema validates the
        result, so a field the kind does not have is still refused (default False).

    Returns
    -------
    dict
        The modified copy.

    Raises
    ------
    ProblemError
        If the field does not exist in the file and ``create`` is False (an override never
        adds fields silently), or a part of its path is not a table.
    """
    out = copy.deepcopy(data)
    parts = field.split(".")
    if len(parts) == 1 and isinstance(out.get("parameters"), dict) and field in out["parameters"]:
        parts = ["parameters", field]
    node: Any = out
    for part in parts[:-1]:
        if create and isinstance(node, dict) and part not in node:
            node[part] = {}
        if not isinstance(node, dict) or part not in node:
            raise ProblemError(f"{path}: cannot sweep '{field}': no table '{part}' in the file")
        node = node[part]
    if not isinstance(node, dict):
        raise ProblemError(f"{path}: cannot set '{field}': '{'.'.join(parts[:-1])}' is not a table in the file")
    if parts[-1] not in node and not create:
        raise ProblemError(f"{path}: cannot sweep '{field}': the field is not in the file (declare it, e.g. in [parameters])")
    node[parts[-1]] = value
    return out
