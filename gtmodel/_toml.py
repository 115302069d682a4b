"""Reading TOML files with errors that name the file (internal helper)."""

from __future__ import annotations

import tomllib
from pathlib import Path
from typing import Any

from gtmodel.errors import GtModelError

#: Largest TOML file read [bytes] (problem, study and parameter files are a few kB).
MAX_TOML_BYTES = 16_000_000


def read_toml(path: Path, error: type[GtModelError], what: str, origin: str | None = None, text: str | None = None) -> dict[str, Any]:
    """Parse a TOML file; unreadable files and syntax errors raise ``error`` naming the file.

    Parameters
    ----------
    path : pathlib.Path
        The file.
    error : type of GtModelError
        Exception class to raise.
    what : str
        What the file is, for the message (e.g. ``"problem file"``).
    origin : str, optional
        Name of the file in messages (default ``str(path)``).
    text : str, optional
        The file's content, when already read (e.g. a packaged resource).

    Returns
    -------
    dict
        The parsed document.

    Raises
    ------
    GtModelError
        Of class ``error``: the file cannot be read, is larger than :data:`MAX_TOML_BYTES`
        (checked while reading), is not UTF-8 or is not valid TOML.
    """
    origin = str(path) if origin is None else origin
    if text is None:
        try:
            with open(path, "rb") as fh:
                raw = fh.read(MAX_TOML_BYTES + 1)
            if len(raw) > MAX_TOML_BYTES:
                raise error(f"{origin}: {what} larger than {MAX_TOML_BYTES} bytes")
            text = raw.decode("utf-8")
        except OSError as exc:
            raise error(f"{origin}: cannot read {what} ({exc.strerror})") from None
        except UnicodeDecodeError as exc:
            raise error(f"{origin}: {what} is not UTF-8 text (byte {exc.start}: {exc.reason})") from None
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise error(f"{origin}: invalid TOML: {exc}") from None
