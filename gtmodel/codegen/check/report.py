"""The results of the self-checks of generated C: per-function comparisons, status probes, reports.

Shared by the checks of the robot functions (:mod:`gtmodel.codegen.check.robot`), the
controller (:mod:`gtmodel.codegen.check.controller`) and the KF/EKF steps
(:mod:`gtmodel.codegen.check.filter`): :func:`within` is the one comparison of C outputs
with their Python values against a tolerance, :class:`FunctionCheck` its result; a
function is reported OK only when it is within its tolerance as printed.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Sequence

import numpy as np

from gtmodel.codegen.declarations import FLOAT_RELATIVE_TOLERANCE, STATUS_CODES
from gtmodel.status import Status

__all__ = ["SENTINEL", "FLOAT_RELATIVE_TOLERANCE", "FunctionCheck", "StatusProbe", "CheckReport", "within", "with_timings", "run_check", "status_probe"]

#: Value pre-filled into output buffers to detect writes on a non-OK status.
SENTINEL = 1234.5678
#: The rule of :data:`FLOAT_RELATIVE_TOLERANCE`, as printed after the tolerance.
FLOAT_RULE = "x (1 + |Python|)"

_STATUS_NAMES = {v[0]: k for k, v in STATUS_CODES.items()}


def within(c: np.ndarray, r: np.ndarray, real: str, tol: float, rtol: float = 0.0,
           float_tol: float = FLOAT_RELATIVE_TOLERANCE) -> tuple[float, float, float, bool]:
    """Compare C outputs with their Python values against a tolerance.

    Parameters
    ----------
    c : numpy.ndarray
        C values, any shape.
    r : numpy.ndarray
        Python values, the same shape.
    real : {"double", "float"}
        Floating-point type of the C code: ``"float"`` bounds each element by
        ``float_tol (1 + |r|)``.
    tol : float
        Absolute tolerance (double precision).
    rtol : float, optional
        Relative tolerance (double precision): an element within ``max(tol, rtol |r|)``
        passes; 0 (default): absolute only.
    float_tol : float, optional
        Relative tolerance of single-precision code (default :data:`FLOAT_RELATIVE_TOLERANCE`).

    Returns
    -------
    max_abs : float
        Largest ``|c - r|`` (inf if any is not finite; 0 for no element).
    max_rel : float
        Largest ``|c - r| / |r|`` over the elements with ``r != 0``.
    max_ratio : float
        Largest ``|c - r|`` divided by its element's bound (``<= 1`` within tolerance).
    ok : bool
        Every element within its bound.
    """
    c, r = np.asarray(c, dtype=float), np.asarray(r, dtype=float)
    d = np.abs(c - r)
    if d.size == 0:
        return 0.0, 0.0, 0.0, True
    if not np.all(np.isfinite(d)):
        return np.inf, np.inf, np.inf, False
    nz = np.abs(r) > 0
    rel = float((d[nz] / np.abs(r[nz])).max()) if nz.any() else 0.0
    bound = float_tol * (1.0 + np.abs(r)) if real == "float" else np.maximum(tol, rtol * np.abs(r))
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = np.where(d == 0, 0.0, d / bound)
    return float(d.max()), rel, float(ratio.max()), bool(np.all(d <= bound))


def tolerance_rule(real: str, rtol: float = 0.0) -> str:
    """The rule printed after a tolerance (:attr:`FunctionCheck.tolerance_rule`).

    Parameters
    ----------
    real : {"double", "float"}
        Floating-point type of the C code.
    rtol : float, optional
        Relative tolerance of a double-precision comparison (0: none).

    Returns
    -------
    str
        ``"x (1 + |Python|)"`` in single precision, ``"or <rtol> x |Python|"`` with a
        relative tolerance, else empty.
    """
    if real == "float":
        return FLOAT_RULE
    return f"or {rtol:g} x |Python|" if rtol > 0 else ""


@dataclass(frozen=True)
class FunctionCheck:
    """Comparison of one C function with the Python evaluation.

    Parameters
    ----------
    name : str
        Function name.
    n : int
        Number of samples compared.
    max_abs_diff : float
        Largest ``|C - Python|`` over all samples and output elements (unit ``unit``).
    tolerance : float
        Largest accepted absolute difference.
    unit : str
        Unit of the outputs (``""`` if dimensionless).
    n_not_ok : int
        Samples (all valid for Python) on which the C function returned a non-OK status.
    passed : bool
        Every sample within tolerance (absolute, or relative where declared) and
        ``n_not_ok == 0``.
    max_rel_diff : float, optional
        Largest ``|C - Python| / |Python|`` (elements with ``|Python| > 0``).
    ns_per_call : float or None, optional
        Mean time per call of the C function in a C loop [ns] (None if not timed).
    n_refused : int, optional
        Random samples the Python model refused (no convergence): skipped.
    tolerance_rule : str, optional
        How ``tolerance`` bounds an element's ``|C - Python|`` when it is not simply
        absolute: ``"x (1 + |Python|)"`` (single precision, :data:`FLOAT_RELATIVE_TOLERANCE`)
        or ``"or <r> x |Python|"`` (an absolute or relative tolerance); empty: absolute.
    max_ratio : float or None, optional
        Largest ``|C - Python|`` divided by the bound of its element (``<= 1`` within
        tolerance; :func:`within`); None: not computed (absolute tolerance).
    """

    name: str
    n: int
    max_abs_diff: float
    tolerance: float
    unit: str
    n_not_ok: int
    passed: bool
    max_rel_diff: float = 0.0
    ns_per_call: float | None = None
    n_refused: int = 0
    tolerance_rule: str = ""
    max_ratio: float | None = None

    @property
    def within_tolerance(self) -> bool:
        """Whether every difference is within the tolerance as printed.

        With an absolute tolerance (``tolerance_rule`` empty) ``max_abs_diff <= tolerance``;
        with a rule, ``max_ratio <= 1``. A check outside its tolerance is never reported
        OK, whatever ``passed`` says.
        """
        if not self.tolerance_rule:
            return bool(self.max_abs_diff <= self.tolerance and (self.max_ratio is None or self.max_ratio <= 1.0))
        return self.max_ratio is not None and bool(self.max_ratio <= 1.0)

    @property
    def ok(self) -> bool:
        """The verdict printed and counted: ``passed`` and :attr:`within_tolerance`."""
        return bool(self.passed and self.within_tolerance)

    def tolerance_text(self) -> str:
        """The tolerance as printed, e.g. ``"tol 1e-12"`` or ``"tol 0.0001 x (1 + |Python|), worst 3% of it"``.

        Returns
        -------
        str
            The tolerance, its rule and, with a rule, the largest share of it used.
        """
        if not self.tolerance_rule:
            return f"tol {self.tolerance:g}"
        used = "inf" if self.max_ratio is None or not np.isfinite(self.max_ratio) else f"{100 * self.max_ratio:.3g}%"
        return f"tol {self.tolerance:g} {self.tolerance_rule}, worst {used} of it"


@dataclass(frozen=True)
class StatusProbe:
    """One status-code probe: an edge-case input must give a given status.

    Parameters
    ----------
    function : str
        Function probed.
    case : str
        What was fed, e.g. ``"unreachable pose"``.
    expected : str
        Expected status macro, e.g. ``"GT_UNREACHABLE"`` (alternatives separated by ``|``).
    status : int
        Returned status.
    untouched : bool
        For a non-OK status: the output buffers kept their pre-filled values. For
        ``GT_OK``: the outputs equal the Python evaluation within the tolerance.
    passed : bool
        ``status`` is an expected one and ``untouched`` holds.
    """

    function: str
    case: str
    expected: str
    status: int
    untouched: bool
    passed: bool


@dataclass(frozen=True)
class CheckReport:
    """Result of :func:`check`.

    Parameters
    ----------
    robot : str
        Robot (parameter-set) name.
    prefix : str
        C prefix of the library.
    n : int
        Number of random inputs per function.
    seed : int
        Seed of the random generator.
    functions : tuple of FunctionCheck
        One comparison per generated function.
    probes : tuple of StatusProbe
        Status-code probes.
    version : str
        Version string reported by the compiled library.
    library : pathlib.Path
        The shared library checked.
    timings : dict
        Extra C timings [ns/call], e.g. ``{"fk (default start)": 25000.0}``.
    harness : str
        What the C unit tests of the harness (:func:`run_harness_unit_tests`) did: the
        program run and its last output line, why they could not run, or why they do
        not apply (empty if not attempted).
    harness_passed : bool or None
        Its verdict (None if not run).
    """

    robot: str
    prefix: str
    n: int
    seed: int
    functions: tuple[FunctionCheck, ...]
    probes: tuple[StatusProbe, ...]
    version: str = ""
    library: Path | None = field(default=None, compare=False)
    timings: dict[str, float] = field(default_factory=dict, compare=False)
    harness: str = ""
    harness_passed: bool | None = None

    @property
    def passed(self) -> bool:
        """True if every comparison (within its tolerance as printed), every status probe and the C unit tests (if run) passed."""
        return (
            all(f.ok for f in self.functions)
            and all(p.passed for p in self.probes)
            and self.harness_passed is not False
        )

    @property
    def status(self) -> Status:
        """The shared status of the check: ``converged`` when it :attr:`passed`, else ``check_failed``."""
        return Status.CONVERGED if self.passed else Status.CHECK_FAILED

    def summary_lines(self) -> list[str]:
        """Printable lines: one per function, then the status probes and the verdict.

        Returns
        -------
        list of str
            E.g. ``"ik: max |C - Python| = 2.2e-16 m (tol 1e-12), 85 ns/call OK"``.
        """
        lines = [f"check of {self.prefix} ({self.robot}) on {self.n} random valid inputs per function (seed {self.seed}):"]
        for f in self.functions:
            unit = f" {f.unit}" if f.unit else ""
            verdict = "OK" if f.ok else "FAILED"
            extra = f", {f.n_not_ok} valid inputs gave a non-OK status" if f.n_not_ok else ""
            rel = f", max rel {f.max_rel_diff:.1e}" if f.max_rel_diff else ""
            timing = f", {f.ns_per_call:.0f} ns/call" if f.ns_per_call is not None else ""
            refused = f" ({f.n_refused} refused by Python, skipped)" if f.n_refused else ""
            lines.append(
                f"{f.name}: max |C - Python| = {f.max_abs_diff:.1e}{unit}{rel} ({f.tolerance_text()}){timing}{extra}{refused} {verdict}"
            )
        for k, v in self.timings.items():
            lines.append(f"{k}: {v:.0f} ns/call")
        ok = sum(p.passed for p in self.probes)
        lines.append(f"edge cases: {ok}/{len(self.probes)} probes OK (expected status; outputs untouched, or equal to Python if OK)")
        for p in self.probes:
            if not p.passed:
                got = _STATUS_NAMES.get(p.status, str(p.status))
                touched = "" if p.untouched else ", outputs WRITTEN or wrong"
                lines.append(f"  FAILED {p.function} on {p.case}: expected {p.expected}, got {got}{touched}")
        if self.harness:
            lines.append(f"C unit tests: {self.harness}")
        lines.append("PASSED" if self.passed else "FAILED")
        return lines


def with_timings(results: Sequence[FunctionCheck], times: dict[str, float]) -> list[FunctionCheck]:
    """The comparisons with their C timings (:attr:`FunctionCheck.ns_per_call`) filled in.

    Parameters
    ----------
    results : sequence of FunctionCheck
        The comparisons.
    times : dict
        Mean time per call [ns] by function name; a name missing gives None (not timed).

    Returns
    -------
    list of FunctionCheck
        The same comparisons (of their own class), each with ``ns_per_call = times.get(name)``.
    """
    return [replace(r, ns_per_call=times.get(r.name)) for r in results]


def run_check(name: str, n: int, pairs: Sequence[tuple[np.ndarray, np.ndarray]], real: str, tol: float, unit: str,
              n_not_ok: int) -> FunctionCheck:
    """The :class:`FunctionCheck` of C values against Python values over a run (:func:`within` per pair).

    Parameters
    ----------
    name : str
        Function name as reported.
    n : int
        Samples compared.
    pairs : sequence of tuple of numpy.ndarray
        ``(C values, Python values)``, each pair of one shape.
    real : {"double", "float"}
        Floating-point type of the C code.
    tol : float
        Absolute tolerance of double-precision code.
    unit : str
        Unit of the values.
    n_not_ok : int
        Calls that returned a non-OK status (the check fails if any).

    Returns
    -------
    FunctionCheck
        The largest ``|C - Python|`` and its share of the tolerance; passed when every
        pair is within tolerance and ``n_not_ok == 0``.
    """
    results = [within(c, r, real, tol) for c, r in pairs]
    worst = max((x[0] for x in results), default=0.0)
    ratio = max((x[2] for x in results), default=0.0)
    ok = all(x[3] for x in results) and n_not_ok == 0
    return FunctionCheck(name, n, worst, FLOAT_RELATIVE_TOLERANCE if real == "float" else tol, unit, int(n_not_ok), bool(ok),
                         tolerance_rule=tolerance_rule(real), max_ratio=ratio)


def status_probe(function: str, case: str, expected: str, status: int, untouched: bool) -> StatusProbe:
    """A :class:`StatusProbe` of one expected status.

    Parameters
    ----------
    function : str
        Function probed.
    case : str
        What was fed.
    expected : str
        Expected status macro, e.g. ``"GT_BAD_ARGUMENT"``.
    status : int
        Returned status.
    untouched : bool
        The outputs (and state) kept their values.

    Returns
    -------
    StatusProbe
        Passed when ``status`` is the expected one and ``untouched`` holds.
    """
    return StatusProbe(function, case, expected, int(status), bool(untouched), bool(status == STATUS_CODES[expected][0] and untouched))
