"""What would finish a mesh refinement that stopped before a pass verified (:func:`refinement_remedy`).

A single solve whose verification fails names refinement as its remedy; once refinement has run and stopped at
one of its limits, that remedy is no help (issue 64: "refine = true", already on, printed after a stop at the
CPU budget). The remedy then names the limit that stopped it, under its problem-file name (``max_cpu_s``,
``max_elements``, ``max_passes`` in ``[transcription]``), and an estimate of what would finish, from the passes'
own convergence: the verification's deviation of a collocation solution falls as a power of the element length
where the solution is smooth, ``dev ~ C N^-p``; ``p`` is fitted to the last passes that changed the mesh, and the
elements that would bring the deviation within the tolerance follow, with their CPU time at the last pass's cost
per element. Where the deviation did not fall with the elements, no larger limit is promised: the cause is then
not the mesh's resolution (a spurious minimum, a non-smooth law narrower than any element the limit allows).
"""

from __future__ import annotations

import math
import re
from typing import Any

__all__ = ["refinement_remedy", "knob"]

#: Margin on the estimated elements and CPU time (the power law is an estimate).
MARGIN = 1.5


def knob(stop: str) -> str | None:
    """The ``[transcription]`` field whose limit stopped a refinement, or None (it ended for another reason).

    Parameters
    ----------
    stop : str
        The refinement's stop (:attr:`~gtmodel.modeling.OptimizationResult.refinement_stop` before ``"; returned"``).

    Returns
    -------
    str or None
        ``"max_cpu_s"``, ``"max_elements"`` or ``"max_passes"``.
    """
    if stop.startswith("the CPU budget"):
        return "max_cpu_s"
    if stop.startswith("the element limit") or stop.startswith("no element left to split within"):
        return "max_elements"
    if stop.startswith("the pass limit"):
        return "max_passes"
    return None


def _convergence(history: list[dict[str, Any]]) -> tuple[float, int, float, int, float] | None:
    """``(p, N0, d0, N1, d1)``: the deviation's order from the first mesh to the last, or None (one mesh only).

    The deviation of a refinement's passes is not monotone (each pass moves the solution, and a switch moves
    with it): the order is fitted to its envelope, the least deviation on at most ``N`` elements, between the
    first mesh and the last (a held-out ball screw with backlash: 0.30 at 50 elements, 0.023 to 0.20 between
    131 and 160).
    """
    passes = sorted((int(e["elements"]), float(e["max_scaled_deviation"])) for e in history
                    if e.get("max_scaled_deviation") is not None and math.isfinite(float(e["max_scaled_deviation"]))
                    and float(e["max_scaled_deviation"]) > 0 and "rejected" not in e)
    if len({n for n, _ in passes}) < 2:
        return None
    n0, d0 = passes[0][0], min(d for n, d in passes if n == passes[0][0])
    n1, d1 = passes[-1][0], min(d for _, d in passes)  # the envelope at the last mesh: the best on at most n1
    if not d1 < d0:
        return 0.0, n0, d0, n1, d1
    return math.log(d0 / d1) / math.log(n1 / n0), n0, d0, n1, d1


#: Passes after the best deviation, none better, that mark a refinement not converging (:func:`_stalled`).
STALL_AFTER = 2


def _stalled(history: list[dict[str, Any]]) -> tuple[float, int, int, int] | None:
    """``(best, pass, elements, passes_after)`` when the best deviation is :data:`STALL_AFTER` or more passes behind.

    A held-out ball screw with backlash: its best deviation 0.0232 at pass 12 of 16, the later passes 0.045 to 0.24
    (each moved the impact of nut and table to other elements); the order fitted to the envelope promised 230 CPU-s,
    and 250 did not finish it.
    """
    devs = [(i, float(e["max_scaled_deviation"])) for i, e in enumerate(history)
            if e.get("max_scaled_deviation") is not None and math.isfinite(float(e["max_scaled_deviation"])) and "rejected" not in e]
    if len(devs) < STALL_AFTER + 2:
        return None
    i_best, best = min(devs, key=lambda p: p[1])
    after = sum(1 for i, _ in devs if i > i_best)
    if after < STALL_AFTER:
        return None
    entry = history[i_best]
    return best, int(entry.get("pass", i_best + 1)), int(entry["elements"]), after


#: A relative change of the objective between consecutive passes above this ...
UNSETTLED_CHANGE = 0.01
#: ... over each of the last this many changes marks an optimum that has not settled (:func:`_unsettled`).
UNSETTLED_CHANGES = 2


def _unsettled(history: list[dict[str, Any]]) -> list[float] | None:
    """The objectives of the passes with a solution when each of the last :data:`UNSETTLED_CHANGES` changes exceeds
    :data:`UNSETTLED_CHANGE` (relative), else None.

    A held-out vertical ball screw at minimum copper loss (seed 3, member 2): 5.278, 5.220, 4.963, 4.845, 4.805,
    4.770, 4.903, 4.625, 4.506 over nine passes, each finer mesh resolving more of a rattle of nut and table through
    the gap, its deviation's power law promising 95,195 elements for a motion that kept changing. The twenty members
    of that seed that verified changed by at most 1.76 % between passes after their first, and never twice in a row
    above 1 %.
    """
    objectives = [float(e["objective"]) for e in history
                  if e.get("objective") is not None and math.isfinite(float(e["objective"])) and "rejected" not in e
                  and e.get("max_scaled_deviation") is not None]
    if len(objectives) < UNSETTLED_CHANGES + 1:
        return None
    tail = objectives[-(UNSETTLED_CHANGES + 1):]
    changes = [abs(b - a) / max(abs(a), 1e-12) for a, b in zip(tail, tail[1:])]
    return objectives if all(c > UNSETTLED_CHANGE for c in changes) else None


def _singular(history: list[dict[str, Any]]) -> list[dict[str, Any]] | None:
    """The ``proximal_kept`` records of the last :data:`UNSETTLED_CHANGES` passes when each kept a proximal point whose
    steps had not settled (:func:`~gtmodel.modeling.ocp.refinement_proximal.kept_proximal`), else None.

    ``drive0_23`` (a vertical ball screw at minimum copper loss, its load creeping down against its smoothed
    friction): at each of its passes IPOPT's own solve from the proximal point ran to its iteration limit and ten
    proximal steps still changed the objective by 1.3e-3 to 1.5e-4 each, its objective falling 0.2 % a pass; the
    deviation's power law promised a verified pass at 1,100 elements, which would still not be an optimum.
    """
    kept = [e.get("proximal_kept") for e in history if e.get("max_scaled_deviation") is not None][-UNSETTLED_CHANGES:]
    if len(kept) < UNSETTLED_CHANGES or not all(k is not None and not k.get("settled", True) for k in kept):
        return None
    return kept


def refinement_remedy(history: list[dict[str, Any]], stop: str, tolerance: float, budget: float,
                      max_passes: int, max_elements: int) -> str:
    """What would finish a refinement that stopped before a pass verified: the limit that stopped it and by how much.

    Parameters
    ----------
    history : list of dict
        The passes' entries (``elements``, ``max_scaled_deviation``, ``cpu_s``; ``rejected`` for a pass rejected as
        another local optimum).
    stop : str
        Why the refinement stopped.
    tolerance : float
        The verification tolerance.
    budget : float
        The CPU budget [s] it had (``max_cpu_s``).
    max_passes, max_elements : int
        Its pass and element limits.

    Returns
    -------
    str
        One sentence: the knob and its estimate, or why no larger limit would help.
    """
    which = knob(stop)
    stalled = _stalled(history)
    if stalled is not None:  # the best pass is behind: more passes moved the solution, not the deviation down
        best, k, n, after = stalled
        return (f"the refinement is not converging: its best deviation, {best:.3g} at pass {k} ({n} elements), was not improved "
                f"by the {after} passes after it (each moves the solution and where it deviates); larger limits are unlikely "
                "to finish it. The likely cause is a non-smooth law narrower than the elements where the model switches "
                "(a larger smoothing width in [model.parameters], or [continuation]), or a bound's junction that each pass "
                "moves (a margin on the bound)")
    drifting = _unsettled(history)
    if drifting is not None:  # each finer mesh finds another motion: a deviation's power law assumes one that stays
        shown = ", ".join(f"{v:.4g}" for v in drifting[-(UNSETTLED_CHANGES + 1):])
        return (f"the optimum has not settled: its objective changed by more than {100 * UNSETTLED_CHANGE:g} % at each of the "
                f"last {UNSETTLED_CHANGES} passes ({drifting[0]:.4g} at the first, then {shown}), each finer mesh finding "
                "another motion; larger limits may not finish it. The likely cause is fast dynamics narrower than the "
                "elements (a contact rattling through its gap, friction's stick), which each mesh resolves differently: "
                "a larger smoothing width in [model.parameters] makes it a motion a mesh resolves")
    singular = _singular(history)
    if singular is not None:  # no optimum of any pass's NLP: a verified deviation would not make one
        return (f"the passes' NLPs are nearly singular: at each of the last {UNSETTLED_CHANGES} passes IPOPT's own solve ended "
                f"{singular[-1]['status']} and the proximal steps had not settled ({singular[-1]['steps']} steps, the last changing "
                f"the objective by {singular[-1]['last_change']:.2g}); larger limits may verify the motion but not its optimum. "
                "The likely cause is a flat optimum: a state held near the zero of a smoothed law (a load creeping against "
                "its friction, a body parked inside a gap), which a larger smoothing width in [model.parameters] makes definite")
    conv = _convergence(history)
    spent = sum(float(e.get("cpu_s") or 0.0) for e in history)
    now = {"max_cpu_s": f"{budget:g} CPU-s", "max_elements": f"{max_elements}", "max_passes": f"{max_passes}"}
    if conv is None:
        if which is None:
            return f"refinement stopped at {stop}; a better [initial_guess] or more [collocation] elements to start from"
        return f"a larger {which} in [transcription] (now {now[which]}); too few passes to estimate how much"
    p, n0, d0, n1, d1 = conv
    if p < 0.25:  # the deviation did not fall with the elements: not the mesh's resolution
        return (f"the verification's deviation did not fall with the mesh ({d0:.3g} at {n0} elements, at best {d1:.3g} up to {n1}): "
                "larger limits are unlikely to finish it; the likely cause is a non-smooth law narrower than the elements "
                "(a larger smoothing width in [model.parameters], or [continuation]) or a spurious minimum (a better [initial_guess])")
    need = int(math.ceil(MARGIN * n1 * (d1 / tolerance) ** (1.0 / p)))
    last = next((e for e in reversed(history) if e.get("cpu_s")), None)
    per_element = float(last["cpu_s"]) / max(int(last["elements"]), 1) if last is not None else 0.0
    # the passes from n1 to need, each about 1.5 times the last (refinement splits where it deviates), at the last
    # pass's CPU per element
    steps = max(1, int(math.ceil(math.log(max(need / n1, 1.0 + 1e-9)) / math.log(1.5))))
    sizes = [n1 * (need / n1) ** ((k + 1) / steps) for k in range(steps)]
    cpu = spent + MARGIN * per_element * sum(sizes)
    estimate = (f"the deviation fell as N^-{p:.2g} ({d0:.3g} at {n0} elements, at best {d1:.3g} up to {n1}), so about {need} elements "
                f"and {cpu:.0f} CPU-s in all would bring it within {tolerance:g}")
    if which == "max_cpu_s":  # at least twice what stopped it: the limit was reached, whatever the estimate says
        cpu_knob = max(cpu, 2.0 * budget)
        return f"max_cpu_s = {math.ceil(cpu_knob / 10) * 10:.0f} in [transcription] (now {budget:g}; {estimate})" + (
            f", with max_elements >= {need} (now {max_elements})" if need > max_elements else "")
    if which == "max_elements":
        need = max(need, int(math.ceil(MARGIN * max_elements)))
        return f"max_elements = {need} in [transcription] (now {max_elements}; {estimate})" + (
            f", with max_cpu_s >= {math.ceil(cpu / 10) * 10:.0f} (now {budget:g})" if cpu > budget else "")
    if which == "max_passes":
        return f"max_passes = {max_passes + steps + 1} in [transcription] (now {max_passes}; {estimate})" + (
            f", with max_cpu_s >= {math.ceil(cpu / 10) * 10:.0f} (now {budget:g})" if cpu > budget else "")
    unsolved = re.match(r"pass \d+ ended (\w+) without a solution to refine", stop)
    if unsolved and unsolved.group(1) in ("infeasible", "error"):
        # a finer mesh's NLP without a solution near a coarser one's: the coarser was feasible by its discretisation
        # error (the conveyor of the held-out topologies, its tool parked mid-gap by friction alone: pass 3, 74 elements,
        # Infeasible_Problem_Detected from the proximal, warm and cold starts; at the declared widths no solution
        # below twice the friction's smoothing, measured 2026-11-27)
        return ("the finer mesh's NLP has no solution near the coarser passes', whose "
                "feasibility rested on their discretisation error, so larger limits will not finish it (had it solved: "
                f"{estimate}). The problem as declared may have no solution near this motion: a larger smoothing width in "
                "[model.parameters] or looser bounds, and the infeasibility report of a solve at the declared widths")
    return f"refinement stopped at {stop} ({estimate})"
