"""Problem-file schemas, declared once with pydantic v2.

A kind's schema is a tree of :class:`Section` models. From that one declaration come
validation on load (every error names the file, the dotted field, what was expected and
what was given), the defaults, physically meaningful ranges (a force limit of 1e308 is
a load-time error), the JSON Schema of ``gtmodel schema KIND`` and the reference page
``docs/problem_files.md``.

Why pydantic: it is the maintained standard for declared, typed schemas in Python, its
models export JSON Schema (draft 2020-12) that editors and ``jsonschema`` understand, and
its per-field annotations carry the ranges and descriptions the documentation needs.

The field types below (:data:`Finite`, :func:`vector`, :func:`number`, ...) check their
input before pydantic does and fail with gtmodel's own phrases ("expected a finite
number", "expected a list of 3 finite numbers", "expected 3 positive numbers"), so the
messages stay as precise as the hand-written readers they replace.
"""

from __future__ import annotations

import math
import re
from pathlib import Path
from typing import Annotated, Any, Literal, Mapping

from pydantic import BaseModel, BeforeValidator, ConfigDict, Field, ValidationError
from pydantic_core import PydanticCustomError

from gtmodel.errors import ProblemError
from gtmodel.problems.results import MAX_FILE_NAME, is_file_name

__all__ = [
    "Section",
    "ProblemSchema",
    "number",
    "integer",
    "vector",
    "matrix",
    "choice",
    "Flag",
    "Expressions",
    "Text",
    "NonEmptyText",
    "FileName",
    "Identifier",
    "MAX_IDENTIFIER",
    "validate_document",
    "problem_error",
    "MAX_LENGTH_M",
    "MAX_FORCE_N",
]

#: Largest length or coordinate accepted in a problem file [m] (robots are metres, not
#: kilometres; the bound keeps 1e308 out of the solvers).
MAX_LENGTH_M = 1.0e3
#: Largest force accepted in a problem file [N].
MAX_FORCE_N = 1.0e7
#: Largest magnitude of a named number of the expressions (``[parameters]``, e.g. an
#: energy weight ``w``): a larger one is a typo or a unit slip, and makes the solver run
#: for minutes before it fails (``w = 2^63 - 1``: 40-135 CPU-s).
MAX_NAMED_NUMBER = 1.0e6


def _fail(expected: str) -> PydanticCustomError:
    return PydanticCustomError("gtmodel", "expected {expected}", {"expected": expected})


def _is_number(x: Any) -> bool:
    return isinstance(x, (int, float)) and not isinstance(x, bool)


def _fmt(x: float) -> str:
    return f"{x:g}"


def number(
    *,
    gt: float | None = None,
    ge: float | None = None,
    lt: float | None = None,
    le: float | None = None,
    description: str = "",
    unit: str = "",
    what: str | None = None,
) -> Any:
    """A finite number field with a range.

    Parameters
    ----------
    gt, ge, lt, le : float, optional
        Exclusive / inclusive bounds.
    description : str, optional
        Text for the JSON Schema and the reference page.
    unit : str, optional
        SI unit, shown in the documentation (e.g. ``"N"``).
    what : str, optional
        The phrase after "expected" in a range error (default from the bounds, e.g.
        "a positive number").

    Returns
    -------
    typing.Annotated
        The field type (use as ``x: number(...) = default``).
    """

    limits = " and ".join(f"{op} {_fmt(b)}" for op, b in ((">", gt), (">=", ge), ("<", lt), ("<=", le)) if b is not None)
    finite = "a finite number" + (f" {limits}" if limits else "")

    def check(v: Any) -> Any:
        if not _is_number(v) or not math.isfinite(v):
            raise _fail(finite)  # the range said at once: "expected a finite number >= 0 and <= 1e+07, got nan"
        if gt is not None and not v > gt:
            raise _fail(what or ("a positive number" if gt == 0 else f"a number > {_fmt(gt)}"))
        if ge is not None and not v >= ge:
            raise _fail(what or ("a non-negative number" if ge == 0 else f"a number >= {_fmt(ge)}"))
        if lt is not None and not v < lt:
            raise _fail(what or f"a number < {_fmt(lt)}")
        if le is not None and not v <= le:
            raise _fail(what or f"a number <= {_fmt(le)}")
        return float(v)

    return Annotated[
        float,
        BeforeValidator(check),
        Field(description=_describe(description, unit), json_schema_extra=_bounds(unit, gt=gt, ge=ge, lt=lt, le=le)),
    ]


def integer(lo: int, hi: int, *, description: str = "") -> Any:
    """An integer field in ``lo..hi`` (booleans are refused).

    Parameters
    ----------
    lo, hi : int
        Inclusive range.
    description : str, optional
        Documentation text.

    Returns
    -------
    typing.Annotated
    """

    def check(v: Any) -> Any:
        if isinstance(v, bool) or not isinstance(v, int) or not lo <= v <= hi:
            raise _fail(f"an integer in {lo}..{hi}")
        return v

    return Annotated[int, BeforeValidator(check), Field(description=description or None, json_schema_extra=_bounds("", ge=lo, le=hi))]


def vector(
    n: int | None,
    *,
    positive: bool = False,
    nonnegative: bool = False,
    bound: float | None = None,
    min_length: int = 1,
    max_length: int | None = None,
    description: str = "",
    unit: str = "",
) -> Any:
    """A list of finite numbers.

    Parameters
    ----------
    n : int or None
        Required length (None: ``min_length..max_length``).
    positive, nonnegative : bool, optional
        Sign requirement on every entry.
    bound : float, optional
        Largest allowed absolute value of an entry (physical range).
    min_length, max_length : int, optional
        Length range when ``n`` is None.
    description, unit : str, optional
        Documentation.

    Returns
    -------
    typing.Annotated
    """
    lo = n if n is not None else min_length
    hi = n if n is not None else max_length

    def check(v: Any) -> Any:
        what = f"a list of {n} finite numbers" if n is not None else "a non-empty list of finite numbers"
        if n is None and max_length is not None:
            what = f"a list of {min_length} to {max_length} finite numbers"
        if not isinstance(v, list) or not (lo <= len(v) <= (hi if hi is not None else len(v))):
            raise _fail(what)
        if not all(_is_number(x) and math.isfinite(x) for x in v):
            raise _fail(what)
        if positive and any(x <= 0 for x in v):
            raise _fail(f"{len(v)} positive numbers")
        if nonnegative and any(x < 0 for x in v):
            raise _fail(f"{len(v)} non-negative numbers")
        if bound is not None and any(abs(x) > bound for x in v):
            raise _fail(f"numbers of magnitude <= {_fmt(bound)}" + (f" {unit}" if unit else ""))
        return [float(x) for x in v]

    item: dict[str, Any] = {}
    if positive:
        item["gt"] = 0
    elif nonnegative:
        item["ge"] = 0
    if bound is not None:
        item["le"] = bound
        if not (positive or nonnegative):
            item["ge"] = -bound
    return Annotated[
        list[Annotated[float, Field(**item)]],
        BeforeValidator(check),
        Field(min_length=lo, max_length=hi, description=_describe(description, unit), json_schema_extra=_unit(unit)),
    ]


def matrix(width: int, *, bound: float | None = None, description: str = "", unit: str = "") -> Any:
    """A non-empty list of rows, each a list of ``width`` finite numbers.

    Parameters
    ----------
    width : int
        Entries per row.
    bound : float, optional
        Largest allowed absolute value.
    description, unit : str, optional
        Documentation.

    Returns
    -------
    typing.Annotated
    """
    row = vector(width, bound=bound)

    def check(v: Any) -> Any:
        if not isinstance(v, list) or not v:
            raise _fail(f"a non-empty list of rows of {width} finite numbers")
        return v

    return Annotated[list[row], BeforeValidator(check), Field(min_length=1, description=_describe(description, unit))]


def choice(*options: str, description: str = "") -> Any:
    """One of several strings.

    Parameters
    ----------
    *options : str
        Allowed values.
    description : str, optional
        Documentation.

    Returns
    -------
    typing.Annotated
    """

    def check(v: Any) -> Any:
        if v not in options:
            raise _fail(f"one of {', '.join(options)}")
        return v

    return Annotated[Literal[options], BeforeValidator(check), Field(description=description)]  # type: ignore[valid-type]


def _expressions(v: Any) -> Any:
    if not isinstance(v, list) or not all(isinstance(c, str) for c in v):
        raise _fail("a list of strings (expressions)")
    return v


#: A list of expressions of the problem language (``docs/problem_language.md``).
Expressions = Annotated[list[str], BeforeValidator(_expressions)]


def _strict(expected: str, test: Any) -> Any:
    def check(v: Any) -> Any:
        if not test(v):
            raise _fail(expected)
        return v

    return BeforeValidator(check)


#: ``true`` or ``false``.
Flag = Annotated[bool, _strict("true or false", lambda v: isinstance(v, bool))]
#: A string.
Text = Annotated[str, _strict("a string", lambda v: isinstance(v, str))]
#: A non-empty string.
NonEmptyText = Annotated[str, _strict("a non-empty string", lambda v: isinstance(v, str) and bool(v)), Field(min_length=1)]

#: A name that becomes a file or folder name (:func:`is_file_name`).
FileName = Annotated[str, _strict(f"a name of 1 to {MAX_FILE_NAME} bytes of printable characters without '/' or '\\', "
                                   "not '.' or '..' (it names a folder or file)", is_file_name), Field(min_length=1)]


#: Longest name that becomes a C identifier (:data:`Identifier`): ``gt_<name>_heap_stats``, the
#: longest symbol a loop controller's C declares, stays within the 63 significant characters
#: C99 guarantees for external identifiers.
MAX_IDENTIFIER = 40
_C_IDENTIFIER = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")

#: A name that becomes part of C identifiers (a loop controller's ``name``: the prefix ``gt_<name>``).
Identifier = Annotated[str, _strict(f"a C identifier of 1 to {MAX_IDENTIFIER} characters (ASCII letters, digits and '_', "
                                    "not starting with a digit; it becomes the C prefix gt_<name>)",
                                    lambda v: isinstance(v, str) and len(v) <= MAX_IDENTIFIER and _C_IDENTIFIER.fullmatch(v) is not None),
                       Field(min_length=1, max_length=MAX_IDENTIFIER)]


def _describe(description: str, unit: str) -> str | None:
    text = description + (f" [{unit}]" if unit and f"[{unit}]" not in description else "")
    return text or None


def _unit(unit: str) -> dict[str, Any] | None:
    return {"unit": unit} if unit else None


def _bounds(unit: str, gt: float | None = None, ge: float | None = None, lt: float | None = None, le: float | None = None) -> dict[str, Any] | None:
    """JSON Schema keywords of a range (the check itself is the field's validator)."""
    out: dict[str, Any] = dict(_unit(unit) or {})
    for key, value in (("exclusiveMinimum", gt), ("minimum", ge), ("exclusiveMaximum", lt), ("maximum", le)):
        if value is not None:
            out[key] = value
    return out or None


class Section(BaseModel):
    """A table of a problem file: unknown fields are errors, values are checked strictly."""

    model_config = ConfigDict(extra="forbid", frozen=True, validate_default=False)


class ProblemSchema(Section):
    """Top level of every problem file: ``name``, ``kind``, ``description``.

    Each kind subclasses it with ``kind: Literal["<kind>"]`` and its tables.

    Parameters
    ----------
    name : str, optional
        Problem name (default: the file name without ``.toml``).
    description : str, optional
        Free text.
    """

    name: FileName | None = Field(default=None, description="problem name, the default result folder results/<name> (default: the file name without .toml)")
    description: Text = Field(default="", description="free text")


def _dotted(loc: tuple[Any, ...]) -> str:
    out = ""
    for part in loc:
        if isinstance(part, int):
            out += f"[{part}]"
        elif not isinstance(part, str) or part.startswith("function-") or part in ("list", "literal"):
            continue
        else:
            out += ("." if out else "") + part
    return out


def _allowed(schema: type[BaseModel], loc: tuple[Any, ...]) -> list[str]:
    model: Any = schema
    for part in loc[:-1]:
        if isinstance(part, int) or model is None:
            continue
        info = getattr(model, "model_fields", {}).get(part)
        if info is None:
            return []
        model = _section_type(info.annotation)
    return sorted(info.alias or name for name, info in getattr(model, "model_fields", {}).items())


def _section_type(annotation: Any) -> Any:
    if isinstance(annotation, type) and issubclass(annotation, BaseModel):
        return annotation
    for arg in getattr(annotation, "__args__", ()) or ():
        found = _section_type(arg)
        if found is not None:
            return found
    return None


def problem_error(path: Path | str, error: ValidationError, schema: type[BaseModel]) -> ProblemError:
    """The first error of a pydantic validation as a :class:`ProblemError` naming file and field.

    Parameters
    ----------
    path : pathlib.Path or str
        The problem file.
    error : pydantic.ValidationError
        The validation failure.
    schema : type
        The schema validated against (for the list of allowed fields).

    Returns
    -------
    ProblemError
        ``"<file>: field 'a.b': expected ..., got ..."``, ``"<file>: missing field 'a.b'"``
        or ``"<file>: unknown field 'a.c' (allowed here: ...)"``.
    """
    errors = error.errors(include_url=False)
    # an unknown field (often a misspelt one) explains the missing field it stands for
    errors.sort(key=lambda e: e["type"] != "extra_forbidden")
    first = errors[0]
    loc = tuple(first["loc"])
    field = _dotted(loc)
    more = f" (and {len(errors) - 1} more)" if len(errors) > 1 else ""
    kind = first["type"]
    if kind == "missing":
        return ProblemError(f"{path}: missing field '{field}'{more}")
    if kind == "extra_forbidden":
        allowed = _allowed(schema, loc)
        return ProblemError(f"{path}: unknown field '{field}' (allowed here: {', '.join(allowed)}){more}")
    if kind in ("model_type", "model_attributes_type", "dict_type"):
        return ProblemError(f"{path}: field '{field}': expected a table, got {first['input']!r}{more}")
    msg = first["msg"]
    if kind != "gtmodel":
        msg = "expected " + msg[0].lower() + msg[1:] if msg else "expected a valid value"
        msg = msg.replace("expected input should be", "expected")
    return ProblemError(f"{path}: field '{field}': {msg}, got {_short(first.get('input'))}{more}")


def _short(value: Any) -> str:
    text = repr(value)
    return text if len(text) <= 80 else text[:77] + "..."


def validate_document(schema: type[ProblemSchema], data: Mapping[str, Any], path: Path | str) -> ProblemSchema:
    """Validate a parsed problem file against its kind's schema.

    Parameters
    ----------
    schema : type of ProblemSchema
        The kind's schema.
    data : Mapping[str, Any]
        The parsed TOML document.
    path : pathlib.Path or str
        The file (for messages).

    Returns
    -------
    ProblemSchema
        The validated, defaults-filled document.

    Raises
    ------
    ProblemError
        The first invalid, missing or unknown field, named with the file.
    """
    try:
        return schema.model_validate(dict(data))
    except ValidationError as exc:
        raise problem_error(path, exc, schema) from None
