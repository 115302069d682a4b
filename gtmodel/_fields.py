"""Reading validated fields from a parsed problem file (shared by every problem kind).

Every error is a :class:`~gtmodel.errors.ProblemError` whose message names the file and
the field (dotted, e.g. ``optimization.final_time.bounds``) and what was expected.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any, Mapping

import numpy as np

from gtmodel.errors import ProblemError

__all__ = ["FieldReader"]


class FieldReader:
    """Typed access to the fields of a TOML document with messages naming file and field.

    Parameters
    ----------
    data : Mapping[str, Any]
        The parsed document.
    path : pathlib.Path
        The file (used in messages).
    """

    def __init__(self, data: Mapping[str, Any], path: Path) -> None:
        self.data = data
        self.path = path

    @staticmethod
    def _name(table: str, key: str) -> str:
        return key if table == "" else f"{table}.{key}"

    def fail(self, field: str, expected: str, got: Any = ...) -> ProblemError:
        """An error naming the file and the field.

        Parameters
        ----------
        field : str
            Dotted field name.
        expected : str
            What was expected.
        got : Any, optional
            The offending value (omitted from the message if not given).

        Returns
        -------
        ProblemError
            The error (to be raised by the caller).
        """
        tail = "" if got is ... else f", got {got!r}"
        return ProblemError(f"{self.path}: field '{field}': expected {expected}{tail}")

    def has(self, table: str) -> bool:
        """Whether a (dotted) table is present.

        Parameters
        ----------
        table : str
            Dotted table name, ``""`` for the top level.

        Returns
        -------
        bool
        """
        node: Any = self.data
        for part in [p for p in table.split(".") if p]:
            if not isinstance(node, Mapping) or part not in node:
                return False
            node = node[part]
        return isinstance(node, Mapping)

    def table(self, name: str, required: bool) -> Mapping[str, Any]:
        """A (dotted) table.

        Parameters
        ----------
        name : str
            Dotted table name, ``""`` for the top level.
        required : bool
            Raise if missing (else return an empty mapping).

        Returns
        -------
        Mapping[str, Any]

        Raises
        ------
        ProblemError
            Missing required table, or the field is not a table.
        """
        node: Any = self.data
        walked = []
        for part in [p for p in name.split(".") if p]:
            walked.append(part)
            if part not in node:
                if required:
                    raise ProblemError(f"{self.path}: missing table '[{'.'.join(walked)}]'")
                return {}
            node = node[part]
            if not isinstance(node, Mapping):
                raise self.fail(".".join(walked), "a table", node)
        return node

    def get(self, table: str, key: str, default: Any = ...) -> Any:
        """A raw field value.

        Parameters
        ----------
        table : str
            Dotted table name, ``""`` for the top level.
        key : str
            Field name.
        default : Any, optional
            Value when missing; required field if omitted.

        Returns
        -------
        Any

        Raises
        ------
        ProblemError
            Missing required field or table.
        """
        src = self.table(table, required=default is ...)
        if key not in src:
            if default is ...:
                raise ProblemError(f"{self.path}: missing field '{self._name(table, key)}'")
            return default
        return src[key]

    def number(self, table: str, key: str, default: Any = ..., positive: bool = False, nonnegative: bool = False) -> float:
        """A finite number.

        Parameters
        ----------
        table, key : str
            Where the field is.
        default : Any, optional
            Value when missing.
        positive, nonnegative : bool, optional
            Sign requirements.

        Returns
        -------
        float

        Raises
        ------
        ProblemError
            Missing, not a finite number, or the wrong sign.
        """
        field = self._name(table, key)
        value = self.get(table, key, default)
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
            raise self.fail(field, "a finite number", value)
        if positive and value <= 0:
            raise self.fail(field, "a positive number", value)
        if nonnegative and value < 0:
            raise self.fail(field, "a non-negative number", value)
        return float(value)

    def integer(self, table: str, key: str, default: Any, lo: int, hi: int) -> int:
        """An integer in ``lo..hi``.

        Parameters
        ----------
        table, key : str
            Where the field is.
        default : Any
            Value when missing (``...`` for required).
        lo, hi : int
            Inclusive range.

        Returns
        -------
        int

        Raises
        ------
        ProblemError
            Missing or out of range.
        """
        value = self.get(table, key, default)
        if isinstance(value, bool) or not isinstance(value, int) or not lo <= value <= hi:
            raise self.fail(self._name(table, key), f"an integer in {lo}..{hi}", value)
        return int(value)

    def boolean(self, table: str, key: str, default: Any) -> bool:
        """A boolean.

        Parameters
        ----------
        table, key : str
            Where the field is.
        default : Any
            Value when missing (``...`` for required).

        Returns
        -------
        bool

        Raises
        ------
        ProblemError
            Not ``true``/``false``.
        """
        value = self.get(table, key, default)
        if not isinstance(value, bool):
            raise self.fail(self._name(table, key), "true or false", value)
        return value

    def string(self, table: str, key: str, default: Any = ...) -> str:
        """A string.

        Parameters
        ----------
        table, key : str
            Where the field is.
        default : Any, optional
            Value when missing.

        Returns
        -------
        str

        Raises
        ------
        ProblemError
            Missing or not a string.
        """
        value = self.get(table, key, default)
        if not isinstance(value, str):
            raise self.fail(self._name(table, key), "a string", value)
        return value

    def vector(self, table: str, key: str, n: int | None, default: Any = ..., positive: bool = False) -> np.ndarray:
        """A list of finite numbers.

        Parameters
        ----------
        table, key : str
            Where the field is.
        n : int or None
            Required length (any length >= 1 if None).
        default : Any, optional
            Value when missing.
        positive : bool, optional
            All entries must be positive.

        Returns
        -------
        numpy.ndarray, shape (n,)

        Raises
        ------
        ProblemError
            Missing, wrong length, not finite or not positive.
        """
        field = self._name(table, key)
        value = self.get(table, key, default)
        ok = isinstance(value, list) and (len(value) == n if n is not None else len(value) >= 1) and all(
            isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x) for x in value
        )
        what = f"a list of {n} finite numbers" if n is not None else "a non-empty list of finite numbers"
        if not ok:
            raise self.fail(field, what, value)
        arr = np.array(value, dtype=float)
        if positive and np.any(arr <= 0):
            raise self.fail(field, f"{len(arr)} positive numbers", value)
        return arr

    def choice(self, table: str, key: str, options: tuple[str, ...], default: Any) -> str:
        """One of a set of strings.

        Parameters
        ----------
        table, key : str
            Where the field is.
        options : tuple of str
            Allowed values.
        default : Any
            Value when missing (``...`` for required).

        Returns
        -------
        str

        Raises
        ------
        ProblemError
            Not one of ``options``.
        """
        value = self.get(table, key, default)
        if value not in options:
            raise self.fail(self._name(table, key), f"one of {', '.join(options)}", value)
        return value

    def check_unknown(self, schema: Mapping[str, set[str]]) -> None:
        """Reject fields not in the schema.

        Parameters
        ----------
        schema : Mapping[str, set of str]
            Dotted table name (``""`` top level) to its allowed keys (sub-tables included).

        Raises
        ------
        ProblemError
            Naming the first unknown field and the allowed ones.
        """
        for table, allowed in schema.items():
            if not self.has(table):
                continue
            for key in self.table(table, required=False):
                if key not in allowed:
                    raise ProblemError(
                        f"{self.path}: unknown field '{self._name(table, key)}' (allowed here: {', '.join(sorted(allowed))})"
                    )
