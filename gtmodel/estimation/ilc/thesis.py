"""The thesis' ILC figures, read from the package's data (one copy of the numbers).

Dressler (2012), section 7.4: Table 7.2 (tool-side error (7.25), mean of iterations 5-10
relative to iteration 0, x and y), eq. (7.28) (Case 1's sigma_max per actuator), the
sigma_max of Cases 2A, 2B and 3 in the text, and Case 1's actuator error after five
iterations ("about 2 %", Fig. 7.7). They live in table ``[ilc.table_7_2]`` of
``gtmodel/estimation/ilc/data/thesis_ilc.toml``, package data that an installed wheel carries;
the ``ilc`` kind's summary and the fidelity report both read them here.
"""

from __future__ import annotations

import functools
from pathlib import Path
from typing import Any

from gtmodel._toml import read_toml
from gtmodel.errors import InputError

__all__ = ["REFERENCE_FILE", "thesis_table_7_2"]


#: The package data holding ``[ilc.table_7_2]`` (installed with the package).
REFERENCE_FILE = Path(__file__).resolve().parent / "data" / "thesis_ilc.toml"
_PREFIX = "case_"


@functools.lru_cache(maxsize=4)
def _read(path: str) -> dict[str, dict[str, Any]]:
    doc = read_toml(Path(path), InputError, "reference data")
    table = doc.get("ilc", {}).get("table_7_2")
    if not isinstance(table, dict):
        raise InputError(f"{path}: no table [ilc.table_7_2] (Dressler (2012), Table 7.2)")
    out: dict[str, dict[str, Any]] = {}
    for key, row in table.items():
        if not key.startswith(_PREFIX):
            continue
        if not isinstance(row, dict) or not {"tool_x", "tool_y", "sigma_max"} <= set(row):
            raise InputError(f"{path}: [ilc.table_7_2].{key}: expected tool_x, tool_y and sigma_max")
        out[key[len(_PREFIX):]] = dict(row)
    return out


def thesis_table_7_2(path: str | Path | None = None) -> dict[str, dict[str, Any]]:
    """The thesis' Table 7.2 figures per case, from the reference data.

    Dressler (2012), section 7.4, Table 7.2 and eq. (7.28).

    Parameters
    ----------
    path : str or pathlib.Path, optional
        Reference file (default :data:`REFERENCE_FILE`).

    Returns
    -------
    dict of str to dict
        Per case name (``"1"``, ``"2A"``, ``"2B"``, ``"3"``): ``tool_x``, ``tool_y`` (fractions of
        iteration 0), ``sigma_max`` (list: per actuator for Case 1, one figure otherwise) and,
        for Case 1, ``actuator_relative_error``; a copy, safe to change.

    Raises
    ------
    InputError
        A file (the default one included: a broken installation) that is missing or cannot be
        read, or a file without a valid ``[ilc.table_7_2]``.
    """
    if path is None:
        path = REFERENCE_FILE
    return {k: dict(v) for k, v in _read(str(path)).items()}
