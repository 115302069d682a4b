"""The verdict rules of the fidelity report (``docs/fidelity.md``): the five verdicts, the case rule and the declared set-ups.

A row of :mod:`gtmodel.report.fidelity` is a :class:`Row`. Its verdict is one of :data:`VERDICTS`
(or a status of :data:`STATUSES`), and :func:`apply_rules` enforces what the page's head
(:data:`RULES`) promises:

- *reproduced* only within the tolerance and with the thesis' set-up (the declared set-up of
  :data:`DECLARED`; the other set-ups' rows are *variant* rows and carry no verdict);
- a case-specific figure (a :class:`Case` of a group: Dressler (2012)'s Cases 1-3 of (7.28), the
  D1's error models 1-5 of Table 5.3) is *reproduced* or *predicted* only if its cases differ as
  the thesis' do: for every other case of its group whose thesis value differs from its own by
  more than the tolerance, ours must differ in the same direction (:func:`cases_differ_as_thesis`);
- a row whose figure is its own input read back (it cannot fail) is a *check of a reading*;
- *predicted* is a figure computed with a quantity fitted to another table (named in the row)
  and held fixed, within the tolerance;
- *structure reproduced* only if the pattern across the cases is reproduced (the direction and, within
  twice the tolerance, the size of every gap the thesis has: :func:`pattern_as_thesis`), and an
  ordering that rests on a mechanism only if the effect is within what the thesis' mechanism can give
  (:class:`Mechanism`);
- no row better than *differs* rests on a quantity the thesis does not print (``Row.unprinted``: a
  tuning of ours, or a model taken equal to the simulated plant);
- a limit of the thesis' "<" rows passes only within :data:`LIMIT_DECADES` (half a decade);
- the run's own self-checks are *self-check* rows: not thesis rows, no verdict.
"""

from __future__ import annotations

from typing import Any, NamedTuple

import numpy as np

from gtmodel.estimation.fusion.limits import LIMIT_DECADES

__all__ = ["figure_text", "VERDICTS", "STATUSES", "DECLARED", "RULES", "LIMIT_DECADES", "REVISITED", "NOT_DIGITISED", "NOT_DIGITISED_ROW", "Case", "Mechanism", "Row",
           "cases_differ_as_thesis", "pattern_as_thesis", "limit_within", "limit_verdict", "apply_rules", "delay_pole_magnitude", "largest_stable_delay"]

#: The verdicts a row can carry, from the strongest.
VERDICTS = ("reproduced", "predicted", "structure reproduced", "check of a reading", "differs")
#: Labels of rows that carry no verdict.
STATUSES = ("variant", "not run", "not attempted", "self-check")
#: The largest distance [decades] between our limit and the thesis' "< limit" with which a limit row passes:
#: the one constant of :mod:`gtmodel.estimation.fusion.limits` (its own verdicts use it too).
#: The verdicts a row can only keep if it rests on nothing the thesis does not print.
_KIND = ("reproduced", "predicted", "structure reproduced")
#: Per figure family, the set-up whose rows carry the verdicts (the other set-ups' rows are variants).
DECLARED = {"ilc": "l1_ilc_thesis", "d1": "d1_error_models_thesis"}
#: Per figure family, its variant set-ups.
VARIANTS = {"l1_ilc": "ilc", "d1_error_models": "d1"}

RULES = (
    "Verdicts (enforced by `tests/report/test_fidelity.py`):\n\n"
    "- *reproduced*: ours is within the tolerance of the thesis' figure **and** was computed with the thesis' set-up "
    f"(the declared set-ups: `[{DECLARED['ilc']}]` for the ILC rows, `[{DECLARED['d1']}]` for the D1 rows). A case-specific figure "
    "(a case of (7.28) or Table 7.2, an error model of Table 5.3) is reproduced or predicted only if its cases differ as the thesis' do: for every other case "
    "whose thesis value differs from its own by more than the tolerance, ours differs in the same direction. A row whose cases "
    "coincide where the thesis' differ is demoted, and says so.\n"
    "- *predicted*: computed with a quantity fitted to another table (the row names the fit and the table), held fixed, and within "
    "the tolerance. Fitted quantities are labelled *fitted* where they appear; the set-up with a fitted quantity "
    "(`[l1_ilc_fitted]`, `[d1_error_models_fitted]`; the fits of `docs/fidelity_fits.json`) carries the predicted verdicts, its rows named "
    "*predicted from the ... fit*. A set-up choice the thesis states is the fit's default (Cvitanic (2021), sec. 4.2: the sine path "
    "at a constant tangential speed); the other reading (the feed along x) is shown beside it and carries no verdict. A prediction "
    "of the Table 8 fit holds on each of five noise seeds (the spread is shown) and with either Q_a that meets Table 8. The 5-axis "
    "EKF's Q (none printed either) is fitted the same way to Table 8's 5-axis acceleration and angular velocity ratios; what Table 8 "
    "does not fix (Q_alpha, the quaternion's Q) is swept, and a prediction holds only on every seed and at every swept value, each "
    "fit meeting Table 8 with the velocity the most improved.\n"
    "- *structure reproduced*: the thesis' ordering or pattern holds, the values differ (the cause is given). A pattern across "
    "cases (e.g. (7.28)'s 0.86 < 0.93 < 0.95 of Cases 2A / 2B / 3) holds only if, for every pair of cases whose thesis values differ by "
    "more than the tolerance, ours differ in the same direction and by the thesis' gap within twice the tolerance; an ordering "
    "the thesis explains by a mechanism (Table 7.2: the estimated structural deflection) holds only if our effect is within what "
    "that mechanism gives here (the change in um against the deflection in um). Otherwise the row *differs*, with the numbers.\n"
    "- No row is better than *differs* if it rests on a quantity the thesis does not print: a tuning of ours (e.g. the 5-axis EKF Q "
    "of Table 10) or a model taken equal to the simulated plant (e.g. Fig. 7.1's Kalman model): the row names it.\n"
    f"- A limit of a thesis' '<' row (Table 10) passes only within half a decade ({LIMIT_DECADES:g} in log10) of the thesis' value, "
    "on every noise seed it was run on. Each Table 10 cell (3-axis, 5-axis) is its own row, its verdict on the tuning the thesis "
    "states (the 3-axis KF: Appendix B's Q; the 5-axis EKF: none printed, so ours, and the row differs).\n"
    "- *check of a reading*: the figure is the set-up's input read back, or the figure a quantity was fitted or chosen to give "
    "(it cannot fail); it checks how the thesis' text is read, not a reproduction.\n"
    "- *differs*: with the measured cause and the deciding number the thesis does not print.\n"
    "- *variant*: the figure of a set-up other than the declared one, shown beside it; it carries no verdict. *not run*: the result "
    "folder was missing. *self-check*: the run's own checks (NEES, status), not a thesis figure: no verdict, not counted.\n"
)

#: The three largest groups of *differs* rows, revisited after the thesis' stated readings and the seed spread (issue 47, item 5).
REVISITED = (
    "The three largest groups of *differs* rows, revisited (issue 47, item 5): "
    "(1) Cvitanic (2021), Tables 8-10 (21 rows). Re-run at the thesis' stated path (constant tangential speed, sec. 4.2.2) and, for "
    "the 3-axis KF, its stated tuning (Appendix B's Q), Table 10 judged per cell: the 3-axis sample-time limit moves from > 0.1 s "
    "(feed along x) to 0.029 s (+0.47 decades) on seeds 1-4 and 0.034 s (+0.53) on seed 5, so it is not within half a decade on every "
    "seed and differs; the 5-axis cells rest on our EKF Q (the thesis prints none); the 5-axis gyro-bias limit leaves half a decade "
    "(2.7 -> 8.6 deg/s), its former agreement a product of the feed along x. The thesis' 'mean error' matches the norm of "
    "the per-axis mean absolute errors (1.382 sigma: its sensor columns 0.0089 mm, 0.889 mm, 0.070 deg/s), which accounts for the "
    "sensor columns, not for the fusion gaps. Table 9's 5-axis columns, predicted from the 5-axis EKF's Q fitted to Table 8's "
    "5-axis columns the same way (seeds 1-5, the quantities Table 8 does not fix swept), differ: acceleration 0.53-0.59 against "
    "0.245, angular velocity 0.18-0.31 against 0.5; the position, 0.50-0.52 against 0.461, is within 20 % but on a fit that leaves "
    "the velocity less improved than the acceleration (0.74-0.78 against 0.62-0.64), against section 4.3.2. "
    "(2) Dressler (2012), the ILC rows (15; the [l1_ilc_fitted] Fig. 7.7 row, which the fit does not enter, is a variant), "
    "unchanged (items 1-2 do not concern them): the tool rows are set by the actuator lag every "
    "case learns (2.74 / 2.64 mm RMS at k = 0) against a structural deflection of 0.85 / 1.7 um RMS, and Fig. 7.7 by the (6.11) "
    "servos (1.43 / 1.39 / 1.1 Hz from the printed models, where the text says about 1.1 Hz for all three); the deciding figures "
    "(Figs. 6.10, 7.8, 7.9) cannot be digitised here. "
    "(3) Dressler (2012), the D1 rows (13), unchanged: the synthetic truth carries Table 4.1's actuator errors, not the thesis' unmodelled "
    "per-arm residual (Table 5.8's 73 / 60 / 19 um; the cart compliance that would give it moves cart 1 by up to 10 mm), and model 3 "
    "falls into the plate-joint valley (scaled Jacobian condition 4.2e4). Each row gives its measured cause and deciding number. "
    "Issue 47 asks for at least 8 thesis rows reproduced or predicted and at most 35 that differ: the counts above the table fall "
    "short of both, and no rule was loosened to reach them.\n"
)

#: Why the ILC group's deciding figures are not digitised (Dressler (2012), Figs. 6.10, 7.8, 7.9; the seeds' text, checked).
NOT_DIGITISED = (
    "Digitised figures: none. The deciding figures of the ILC rows (Dressler (2012), Fig. 6.10: Bode diagrams of G_r (6.12) and "
    "G_c (6.13); Fig. 7.8: actuator error at k = 0 and 10; Fig. 7.9: tool error at k = 0 and 10) exist here only as the thesis' "
    "text converted from the PDF, which keeps each caption and no axis ticks, no plotted values and no printed amplitude: nothing "
    "to read points from, so no figure data are invented. What the text does print is used: the resonances of Table 6.4 (x 7.4 Hz; "
    "y 11.4-11.5 Hz, 11.4-11.9 Hz at first after an x impulse; x 10.4-10.7 Hz under a y force), the model orders (G_r seventh, G_c "
    "tenth order, 'resonances around 10 Hz'), Fig. 7.7's '2 % after five iterations', Table 7.2 and the trial of Fig. 7.8 "
    "(fully corrected from 1.6 to 4.1 s after a lead-in, then a lead-out: at least 1,100 samples at 4 ms; `[l1_ilc_thesis]` runs "
    "834 samples, 2.53 s corrected, a shorter lead-in and lead-out). Frequencies alone do not fix G_c's gain at 11.5 Hz, "
    "the deciding number of the tool rows; in its place Table 7.2's Case 1 tool y is used to fit the structure's y stiffness "
    "(`[l1_ilc_fitted]`), and the other cases are predicted with it.\n"
)
#: The sentence a differing ILC row carries (the page's paragraph :data:`NOT_DIGITISED` says more).
NOT_DIGITISED_ROW = ("Not digitisable here: Figs. 6.10, 7.8 and 7.9 are captions only in the available text (no axis ticks or values; "
                     "see 'Digitised figures' above the table)")


class Case(NamedTuple):
    """One case of a case-specific figure: its group, its name, the thesis' value, ours and the tolerance.

    Parameters
    ----------
    group : str
        The figure whose cases are compared (e.g. ``"(7.28) Cases [l1_ilc_thesis]"``).
    name : str
        The case (e.g. ``"2B"``, ``"model 4"``).
    thesis : float
        The thesis' value.
    ours : float
        Ours.
    tol : float
        The row's tolerance (same unit): thesis values further apart than this differ.
    """

    group: str
    name: str
    thesis: float
    ours: float
    tol: float


class Mechanism(NamedTuple):
    """What an ordering rests on: our effect against what the thesis' mechanism can give here.

    Parameters
    ----------
    effect : float
        The change the ordering shows (e.g. the drop of Table 7.2's tool y RMS error from Case 1 to 2A [um]).
    capacity : float
        The most the thesis' mechanism can change here, same unit (e.g. the structural deflection RMS the
        accelerometer estimates [um]).
    text : str
        What both are (one clause, named in the demoted row's cause).
    """

    effect: float
    capacity: float
    text: str


class Row(NamedTuple):
    """A row of the page: the six printed columns, its cases, whether it reads an input back, the demoted verdict.

    Parameters
    ----------
    figure : str
        The thesis figure, ending in ``[set-up]`` where several set-ups give it.
    thesis : str
        The thesis' value as printed.
    ours : str
        Ours.
    tolerance : str
        The tolerance or the criterion.
    verdict : str
        One of :data:`VERDICTS` or :data:`STATUSES`.
    cause : str
        The measured cause of a difference (or the fit a prediction holds fixed).
    cases : tuple of Case, optional
        The row's cases, for the case rule.
    reading : bool, optional
        True if the figure is the set-up's input read back (the row cannot fail).
    fallback : str, optional
        The verdict when the case rule demotes the row.
    unprinted : str, optional
        The quantity the figure rests on that the thesis does not print ("" if none): the row differs.
    limits : tuple of (float or None, float), optional
        ``(ours, thesis)`` of each "< limit" the row compares (None: no limit found); each must lie
        within :data:`LIMIT_DECADES`.
    mechanism : Mechanism or None, optional
        What an ordering row rests on (:class:`Mechanism`).
    self_check : bool, optional
        True for the run's own checks: a *self-check* row, not a thesis figure.
    """

    figure: str
    thesis: str
    ours: str
    tolerance: str
    verdict: str
    cause: str
    cases: tuple[Case, ...] = ()
    reading: bool = False
    fallback: str = "differs"
    unprinted: str = ""
    limits: tuple[tuple[float | None, float], ...] = ()
    mechanism: Mechanism | None = None
    self_check: bool = False


def cases_differ_as_thesis(case: Case, group: list[Case]) -> bool:
    """Whether ``case`` differs from the other cases of its group as the thesis' value does.

    Parameters
    ----------
    case : Case
        The case judged.
    group : list of Case
        Every case of its group (``case`` may be among them).

    Returns
    -------
    bool
        True if, for every other case whose thesis value differs from ``case.thesis`` by more
        than ``case.tol``, ours differs from ``case.ours`` with the same sign.
    """
    return all(np.sign(o.ours - case.ours) == np.sign(o.thesis - case.thesis) for o in group
               if o.name != case.name and abs(o.thesis - case.thesis) > case.tol + 1e-12)


def pattern_as_thesis(case: Case, group: list[Case]) -> bool:
    """Whether the pattern of ``case`` against its group is the thesis': the direction and size of every gap.

    Parameters
    ----------
    case : Case
        The case judged.
    group : list of Case
        Every case of its group.

    Returns
    -------
    bool
        True if, for every other case whose thesis value differs from ``case.thesis`` by more than
        ``case.tol``, ours differs in the same direction and ``|(o.ours - case.ours) - (o.thesis -
        case.thesis)| <= 2 case.tol`` (each value carries the tolerance).
    """
    return cases_differ_as_thesis(case, group) and all(
        abs((o.ours - case.ours) - (o.thesis - case.thesis)) <= 2.0 * case.tol + 1e-12 for o in group
        if o.name != case.name and abs(o.thesis - case.thesis) > case.tol + 1e-12)


def limit_within(ours: float | None, thesis: float, decades: float = LIMIT_DECADES) -> bool:
    """Whether our limit lies within ``decades`` of the thesis' "< thesis".

    Parameters
    ----------
    ours : float or None
        Our limit (None: none found over the search, which never passes).
    thesis : float
        The thesis' limit (> 0, same unit).
    decades : float, optional
        Allowed distance in ``log10``.

    Returns
    -------
    bool
    """
    return ours is not None and ours > 0 and abs(np.log10(ours / thesis)) <= decades + 1e-12


def limit_verdict(row: dict[str, Any]) -> str:
    """The verdict of one searched Table 10 limit against the thesis: the page's rule (:func:`limit_within`), for every report.

    The one rule for Table 10's limits (the fidelity page and the result folder's ``table_10_limits.md`` of
    :func:`gtmodel.report.fusion.write_limits_table`): a thesis "< x" passes only within :data:`LIMIT_DECADES`.

    Parameters
    ----------
    row : dict
        A row of :func:`gtmodel.estimation.fusion.limits.velocity_limit`: ``thesis_limit`` (None: N/A,
        ``inf``: "no constraint", else the thesis' "< x"), ``stops_at`` (None: fusion pays over the whole
        search) and ``limit`` (the geometric mean of the final bracket).

    Returns
    -------
    str
        ``"N/A"`` (the thesis has no limit for the motion), ``"reproduced"`` (a "no constraint" where fusion
        pays over the whole search, or a limit within half a decade) or ``"differs"``.
    """
    thesis, stops = row["thesis_limit"], row["stops_at"]
    if thesis is None:
        return "N/A"
    if np.isinf(thesis):
        return "reproduced" if stops is None else "differs"
    return "reproduced" if limit_within(row["limit"] if stops is not None else None, thesis) else "differs"


def _demote(r: Row, groups: dict[str, list[Case]]) -> Row:
    """The tightened rules of issue 47 on one row (a row already *differs* or a status is left alone)."""
    if r.verdict not in _KIND:
        return r
    if r.unprinted:
        return r._replace(verdict="differs", cause=f"rests on {r.unprinted}, which the thesis does not print (a {r.verdict} figure may not)"
                          + (f". {r.cause}" if r.cause else ""))
    far = [(o, t) for o, t in r.limits if not limit_within(o, t)]
    if far and r.verdict in ("reproduced", "predicted"):
        text = ", ".join(("no limit found" if o is None else f"{o:.3g} ({np.log10(o / t):+.2f} decades)") + f" against < {t:g}" for o, t in far)
        return r._replace(verdict="differs", cause=f"beyond half a decade: {text}" + (f". {r.cause}" if r.cause else ""))
    if r.verdict == "structure reproduced":
        bad = [c for c in r.cases if not pattern_as_thesis(c, groups[c.group])]
        if bad:
            c = bad[0]
            gaps = ", ".join(f"{o.name} - {c.name}: ours {o.ours - c.ours:+.3g}, thesis {o.thesis - c.thesis:+.3g}" for o in groups[c.group]
                             if o.name != c.name and abs(o.thesis - c.thesis) > c.tol + 1e-12)
            return r._replace(verdict="differs", cause=f"the thesis' pattern across the cases is not reproduced (gaps beyond twice the "
                              f"tolerance {c.tol:g}: {gaps})" + (f". {r.cause}" if r.cause else ""))
        m = r.mechanism
        if m is not None and not m.effect <= m.capacity:
            return r._replace(verdict="differs", cause=f"the ordering holds, but not by the thesis' mechanism: {m.text} "
                              f"({m.effect:.3g} against {m.capacity:.3g})" + (f". {r.cause}" if r.cause else ""))
    return r


def _family(figure: str) -> tuple[str | None, str | None]:
    tag = figure.rsplit("[", 1)[-1].rstrip("]") if figure.endswith("]") else None
    return tag, VARIANTS.get(tag or "")


def apply_rules(rows: list[Row]) -> list[Row]:
    """The rows with :data:`RULES` applied: readings, variant set-ups and coinciding cases.

    Parameters
    ----------
    rows : list of Row
        The rows as the figures give them.

    Returns
    -------
    list of Row
        Self-checks as *self-check*; readings as *check of a reading*; reproduced / predicted rows
        whose cases coincide where the thesis' differ demoted to the row's ``fallback`` with the cases
        in the cause; then rows resting on an unprinted quantity, limits beyond half a decade,
        patterns or mechanisms not the thesis' demoted to *differs*; rows of a variant set-up as
        *variant* (their own verdict in the cause).
    """
    groups: dict[str, list[Case]] = {}
    for r in rows:
        for c in r.cases:
            groups.setdefault(c.group, []).append(c)
    out = []
    for r in rows:
        if r.self_check:
            out.append(r._replace(verdict="self-check", cause=f"the run's own check, not a thesis figure (it would be: {r.verdict})"
                                  + (f"; {r.cause}" if r.cause else "")))
            continue
        if r.verdict in STATUSES[1:]:
            out.append(r)
            continue
        if r.reading:
            r = r._replace(verdict="check of a reading")
        elif r.verdict in ("reproduced", "predicted") and not all(cases_differ_as_thesis(c, groups[c.group]) for c in r.cases):
            bad = [c for c in r.cases if not cases_differ_as_thesis(c, groups[c.group])]
            text = "; ".join(f"case {c.name}: ours {c.ours:.4g} within {c.tol:g} of the thesis' {c.thesis:.4g}, but its cases "
                             + ", ".join(f"{o.name} {o.ours:.4g} (thesis {o.thesis:.4g})" for o in groups[c.group] if o.name != c.name)
                             + " do not differ as the thesis' do" for c in bad)
            r = r._replace(verdict=r.fallback, cause=f"coincidence, not a reproduction: {text}" + (f". {r.cause}" if r.cause else ""))
        if not r.reading:
            r = _demote(r, groups)
        family = _family(r.figure)[1]
        if family is not None:
            r = r._replace(verdict="variant", cause=f"variant of [{DECLARED[family]}], which carries the verdict (here: {r.verdict}"
                           + (f"; {r.cause}" if r.cause else "") + ")")
        out.append(r)
    return out


def delay_pole_magnitude(gain: float, delay_cycles: int) -> float:
    """Largest pole magnitude of the accumulating correction loop with a pure delay, as the loop is run.

    The loop of Cvitanic (2021), eq. (33), ``K z / (z - 1) z^-d P(z)`` with ``P = 1`` (the
    correction executed with DC gain 1): the delay alone. Its characteristic equation is
    ``(z - 1) z^d + K z = 0``, i.e. ``z^(d-1) (z - 1) + K = 0`` (the accumulator's ``z`` cancels one
    cycle: the loop run with d = 13 is ``z^12 (z - 1) + K``, critical gain ``2 sin(pi / 50) = 0.126``).

    Parameters
    ----------
    gain : float
        Proportional gain K.
    delay_cycles : int
        Delay d [cycles] (>= 1) of ``z^-d``.

    Returns
    -------
    float
        ``max |z|`` over the ``d`` roots of ``z^(d-1) (z - 1) + K`` (> 1: unstable).
    """
    p = np.zeros(int(delay_cycles) + 1)
    p[0], p[1], p[-1] = 1.0, -1.0, float(gain)
    if p.size == 2:  # d = 1: z - 1 + K
        p[1] = float(gain) - 1.0
    return float(np.max(np.abs(np.roots(p))))


def largest_stable_delay(gain: float, max_delay: int = 60) -> int:
    """The largest delay [cycles] for which :func:`delay_pole_magnitude` stays below 1 at ``gain`` (0 if none).

    Parameters
    ----------
    gain : float
        Proportional gain K.
    max_delay : int, optional
        Largest delay tried [cycles].

    Returns
    -------
    int
    """
    stable = [d for d in range(1, max_delay + 1) if delay_pole_magnitude(gain, d) < 1.0]
    return max(stable) if stable else 0


def figure_text(x: Any, digits: int = 3) -> str:
    """A figure as the page prints it: ``digits`` significant digits, lists joined by " / ", None as "n/a".

    Parameters
    ----------
    x : float, int, str, list, tuple or None
        The figure.
    digits : int, optional
        Significant digits of a float (default 3).

    Returns
    -------
    str
        The text.
    """
    if x is None:
        return "n/a"
    if isinstance(x, (list, tuple)):
        return " / ".join(figure_text(v, digits) for v in x)
    return f"{x:.{digits}g}" if isinstance(x, float) else str(x)
