"""The fidelity report's rows of Cvitanic (2021)'s KR 500 runs: Table 10's limits, Table 2's joint stiffness, Table 8's velocity ordering.

Rows of :mod:`gtmodel.report.fidelity` (the page ``docs/fidelity.md``), read from the
figures that :func:`gtmodel.report.fidelity.collect` keeps of ``kr500_table_10`` and
``kr500_table_2``; verdicts by :mod:`gtmodel.report.fidelity_rules`. Sources: Cvitanic (2021),
section 4.3 (Table 10) and section 2 (Table 2).
"""

from __future__ import annotations

from typing import Any

from gtmodel.estimation.fusion.limits import THESIS_TABLE_10
from gtmodel.report.fidelity_rules import Row, limit_verdict
from gtmodel.report.fidelity_rules import figure_text as _f

__all__ = ["STATED_TUNING", "SEED_LIMITS", "table_10_rows", "table_2_rows", "velocity_most_rows", "orientation_sweep"]

_NAMES = {"position_mm": "position", "velocity_mm_s": "velocity", "acceleration_m_s2": "acceleration", "orientation_deg": "orientation",
          "angular_velocity_deg_s": "angular velocity", "angular_acceleration_deg_s2": "angular acceleration"}


_TABLE_10_TEXT = {"accel_noise_m_s2_rtHz": ("< 0.1", "< 0.1"), "accel_bias_m_s2": ("< 0.001", "< 0.001"), "gyro_noise_deg_s_rtHz": ("N/A", "< 0.1"),
                  "gyro_bias_deg_s": ("N/A", "< 1"), "transform_orientation_error_deg": ("< 10", "< 0.1"),
                  "transform_translation_error_mm": ("no constraint", "< 100 mm"), "sample_time_s": ("< 0.01", "< 0.01")}
#: The tuning each motion's verdict is taken on: the 3-axis KF's Q is the thesis' Appendix B ("Q and R ... for the KF ...
#: see Appendix B", Cvitanic (2021), sec. 4.2.2); the thesis prints no Q for its 5-axis EKF, so only ours runs there.
STATED_TUNING = {"3-axis": "appendix_b", "5-axis": "white_jerk"}
_UNPRINTED = "our white-jerk Q (the thesis prints no Q for its 5-axis EKF)"
#: The measured cause of each Table 10 cell where ours differs (problems/thesis/kr500_table_10.toml at the thesis' constant
#: tangential speed, 3 s with the crest at 1.84 s, seed 1; "x feed": the same file with feed = "x", the former default).
_TABLE_10_CAUSE = {
    ("3-axis", "accel_noise_m_s2_rtHz"): "with Appendix B's Q (Q_a 98.1e-4 (m/s^2)^2 per sample) the fused velocity follows the accelerometer and "
                                         "its error grows in proportion to the noise (0.49 / 3.15 / 29.6 mm/s at 0.00039 / 0.0039 / 0.039), "
                                         "crossing the regression's 4.58 mm/s at the limit shown (-1.25 decades; x feed: the same 0.0056); a "
                                         "limit at 0.1 needs that error to grow about 18 x slower. Our white-jerk Q (R follows the sweep) "
                                         "levels off at 1.59 mm/s and never stops paying (> 3.9): the thesis' 0.1 lies between the two "
                                         "tunings. Deciding numbers: whether the thesis' R followed the swept noise, and the Q behind Table 10",
    ("3-axis", "accel_bias_m_s2"): "the bias limit is set by Q_p: Appendix B's 2.54e-4 m^2 lets a bias of 0.0085 m/s^2 into the velocity (+0.93 "
                                   "decades; x feed 0.0098, +0.99), our white-jerk Q up to 0.085 (+1.93). Deciding number: the thesis' Q_p behind "
                                   "Table 10 (Table 8 bounds it only from below, the fitted rows)",
    ("3-axis", "transform_orientation_error_deg"): "the error about the thesis' axis (its z: the sine's amplitude direction) rotates the measured "
                                                   "acceleration; at the tangential feed it acts (Appendix B Q: fused velocity error 0.49 / 0.75 / "
                                                   "3.47 mm/s at 0.01 / 10 / 90 deg; our Q 0.10 / 0.20 / 1.06; x feed: flat, the acceleration on the "
                                                   "rotation axis) but stays below the regression's 4.58 mm/s up to 90 deg: no limit where the thesis "
                                                   "has < 10. Deciding number: the thesis' velocity errors at 10 deg (or its regression error)",
    ("3-axis", "sample_time_s"): "the thesis' 3-axis KF at the thesis' path stops paying near 0.01 s as Table 10 says, but at the rule's edge: "
                                 "on seed 1 it pays at 0.027 and not at 0.032 (+0.44 to +0.50 decades), on seed 5 it pays at 0.032 and "
                                 "not at 0.037 (limit +0.53), so the row does not hold across the noise seeds. With the feed along x it pays up to 0.1 s (the "
                                 "reading of the path moves this limit by more than half a decade); against the lag-free centred regression "
                                 "it stops at 0.0093 (-0.03): the causal regression's 1.5-sample lag (the thesis' 'last four positions') "
                                 "decides the distance. Deciding number: the thesis' 3-axis tracker-only velocity error at 0.01 s",
    ("5-axis", "accel_noise_m_s2_rtHz"): "the EKF is told the noise (R follows the sweep) and falls back on its white-jerk model, which smooths the "
                                         "tracker better than the four-point regression even with the accelerometer ignored (1.59 against 4.58 "
                                         "mm/s at 3.9), so fusion never stops paying",
    ("5-axis", "accel_bias_m_s2"): "our white-jerk Q keeps a bias out of the velocity up to the limit shown (+1.87 decades; x feed 0.085)",
    ("5-axis", "gyro_noise_deg_s_rtHz"): "as for the accelerometer noise: the EKF is told the gyro noise (R follows the sweep) and the tracker's "
                                         "orientation carries the rotation, so fusion never stops paying",
    ("5-axis", "gyro_bias_deg_s"): "set by our Q, as the accelerometer-bias limit is (the EKF keeps a bias out of the velocity up to where Q lets "
                                   "the tracker correct it): +0.93 decades at the tangential feed, within half a decade (2.7) with the feed along "
                                   "x, so the former agreement came from the reading of the path, not the thesis' filter",
    ("5-axis", "transform_orientation_error_deg"): "the error acts as a bias of sin(error) |a|; with our Q the limit shown is +2.6 decades off "
                                                   "(x feed 7.0, a crest every 0.6 s, +1.8)",
    ("5-axis", "transform_translation_error_mm"): "the tool normal to the path turns at up to 49 rad/s at the crest (curvature radius 0.86 mm), so "
                                                  "a lever-arm error e gives omega^2 e = 2.4 m/s^2 per mm there; at the tangential feed one crest "
                                                  "in 3 s gives the limit shown (-1.31 decades; 7.5 mm over the thesis' 5 s window; x feed 1.0 mm, "
                                                  "a crest every 0.6 s): the dilution by the feed explains a factor 5, not the thesis' 100",
    ("5-axis", "sample_time_s"): "within half a decade (-0.47; x feed 0.0045) and the thesis' mechanism: the constant-acceleration model "
                                 "(21)-(28) breaks at the crest",
}
#: Per cell, the limit on the noise seeds 1-5 where seed 1 alone would pass (each must: the rule of the fits' predictions,
#: issue 47 item 2). Measured with problems/thesis/kr500_table_10.toml, [sensors] seed = 1..5, [study.limits]
#: tunings = ["appendix_b"], parameters = ["sample_time_s"], sweep_motions = ["3-axis"] (the slow test recomputes seed 5).
SEED_LIMITS = {("3-axis", "sample_time_s"): {1: 0.029427, 2: 0.029427, 3: 0.029427, 4: 0.029427, 5: 0.033982}}
#: 3-axis cells that cannot fail: without rotation the lever arm enters nowhere (eq. (29): alpha x r + omega x (omega x r) = 0).
_READINGS = {("3-axis", "transform_translation_error_mm"): "without rotation both points perceive the same motion (eq. (29) with "
             "alpha = omega = 0, as the thesis says), so no lever-arm error can stop fusion: the row checks that reading, it cannot fail"}


def _thesis_limit(text: str) -> float | None:
    """The number of a thesis' "< x" entry of Table 10 (None for "N/A" or "no constraint")."""
    return float(text.split()[1]) if text.startswith("<") else None


def _verdict(r: dict[str, Any]) -> str:
    """The page's rule on one collected limit (:func:`~gtmodel.report.fidelity_rules.limit_verdict`, the thesis' limit of its motion)."""
    return limit_verdict({**r, "thesis_limit": THESIS_TABLE_10[r["parameter"]][r["motion"] == "5-axis"]})


def _limit_text(r: dict[str, Any]) -> str:
    if r["stops_at"] is None:
        return f"> {_f(r['search'][1])}"
    if r["pays_up_to"] is None:
        return f"<= {_f(r['search'][0])}"
    return _f(r["limit"], 2)


def table_10_rows(f: dict[str, Any], t10: dict[str, Any] | None) -> list[tuple[str, ...]]:
    """Cvitanic (2021), Table 10: the limits of problems/thesis/kr500_table_10.toml beside the shipped sweep at the Table 7 offsets.

    Parameters
    ----------
    f : dict
        The collected ``kr500_state_estimation`` figures (its ``table_10`` sweep).
    t10 : dict or None
        The collected ``kr500_table_10`` figures (its ``limits``), None when not run.

    Returns
    -------
    list of tuple or Row
        The rows, before :func:`~gtmodel.report.fidelity_rules.apply_rules`.
    """
    src = "Cvitanic (2021)"
    limits = (t10 or {}).get("limits", [])
    out: list[Any] = []
    for par, (l3, l5) in _TABLE_10_TEXT.items():
        sweep = "; ".join(f"{r['motion']} {_f(r['value'])}: {'pays' if r['velocity'] and r['velocity']['fusion'] < r['velocity']['sensor'] else 'not'}"
                          for r in f["table_10"] if r["parameter"] == par)
        found = [r for r in limits if r["parameter"] == par]
        if not found:
            out.append((f"{src}, Table 10: limit of {par} (3-axis / 5-axis)", f"{l3} / {l5}", f"Table 7 offsets: {sweep or 'not run'}", "half a decade",
                        "not run", "run problems/thesis/kr500_table_10.toml, then collect"))
            continue
        for motion, text in (("3-axis", l3), ("5-axis", l5)):
            mine = [r for r in found if r["motion"] == motion]
            if text == "N/A" or not mine:
                continue
            stated = next((r for r in mine if r["tuning"] == STATED_TUNING[motion] and r.get("baseline", "causal") == "causal"), None)
            ours = "; ".join(f"{'our Q' if r['tuning'] == 'white_jerk' else 'Appendix B Q'}{' vs the centred regression' if r.get('baseline') == 'centred' else ''}"
                             f" {_limit_text(r)}" + (f" (bracket {_f(r['pays_up_to'], 2)}-{_f(r['stops_at'], 2)})" if r is stated and r["stops_at"] is not None
                                                     and r["pays_up_to"] is not None else "") for r in mine)
            where = ("the tool normal to the path, " if motion == "5-axis" else "") + "at the constant tangential speed"
            shipped = f"; kr500_state_estimation at the Table 7 offsets: {sweep}" if sweep else ""
            key = (motion, par)
            name = f"{src}, Table 10: {motion} limit of {par} [kr500_table_10]"
            if stated is None:
                out.append(Row(name, text, f"{ours} ({where})", "half a decade", "differs", "the verdict's tuning was not run (tunings of [study.limits])"))
                continue
            thesis = _thesis_limit(text)
            verdict = _verdict(stated)
            tuning = "the thesis' Appendix B Q (its 3-axis KF)" if stated["tuning"] == "appendix_b" else "our white-jerk Q"
            seeds = SEED_LIMITS.get(key, {})
            if seeds:
                ours += f"; seeds {', '.join(map(str, seeds))}: {_f(min(seeds.values()), 2)}-{_f(max(seeds.values()), 2)}"
            out.append(Row(name, text, f"{ours} ({where}{shipped})", "half a decade" if thesis is not None else "fusion pays over the search",
                           verdict if verdict != "N/A" else "differs", f"verdict on {tuning}. " + (_READINGS.get(key) or _TABLE_10_CAUSE[key]),
                           limits=(((stated["limit"] if stated["stops_at"] is not None else None, thesis),)
                                   + tuple((v, thesis) for v in seeds.values())) if thesis is not None else (),
                           unprinted=_UNPRINTED if stated["tuning"] == "white_jerk" else "", reading=key in _READINGS))
    if t10 is not None and t10.get("nees"):
        fails, nees = t10.get("failed_checks") or [], t10["nees"].get("5-axis", {})
        out.append(Row(f"{src}, Table 10 run (problems/thesis/kr500_table_10.toml): self-checks", "-",
                    f"status {t10['status']}; failed: {', '.join(fails) or 'none'}; 5-axis NEES {_f(nees.get('mean'))} (band {_f(nees.get('band'))})",
                    "-", "reproduced" if not fails else "differs",
                    "" if not fails else "the thesis' tool normal to the path turns at up to 49 rad/s and 1600 rad/s^2 at the crests: the EKF's "
                    "constant-angular-acceleration model (26)-(28), with the white angular jerk set to the path's largest, is overconfident "
                    "there (the thesis: its EKF and UKF 'struggle' at the peaks); the run's status says so (check_failed, exit 1)", self_check=True))
    return out


def table_2_rows(d: dict[str, Any]) -> list[tuple[str, ...]]:
    """Cvitanic (2021), Table 2: CP, CP x10 and DPP as the thesis defines them (problems/thesis/kr500_table_2.toml) against the truth.

    Parameters
    ----------
    d : dict
        The collected figures (its ``kr500_table_2``).

    Returns
    -------
    list of tuple or Row
        The row, before :func:`~gtmodel.report.fidelity_rules.apply_rules`.
    """
    t2 = d.get("kr500_table_2")
    name = "Cvitanic (2021), Table 2: joint stiffness by CP vs DPP, DPP closer to the truth"
    if t2 is None or not t2.get("monte_carlo"):
        return [(name, "DPP below CP on every joint (CP / DPP 1.2-6.5), DPP closer", "not run", "-", "not run",
                 "run problems/thesis/kr500_table_2.toml, then collect")]
    mc = t2["monte_carlo"]
    w = t2["rotation_weight"]
    cp, cps = f"CP w={w['CP']:g}", f"CP w={w['CP_rotations_scaled_x10']:g}"
    ok = mc["dpp_below_cp_every_joint"] and mc["dpp_closer_to_truth"]
    cause = ("with the thesis' definitions (force-only gravity + pulley loads at the Table 1 poses, three-target rotation noise, CP's "
             "residual in mm and rad, DPP's eq. (5) on the TCP translation) and an exact joint-spring model, every method is "
             "median-unbiased to about 1 %: the thesis' CP / DPP gap of 1.2-6.5 is not measurement noise but data the joint-spring model "
             "does not fit. The one mechanism found that moves CP with the rotation weight (an unmodelled rotation-only compliance of "
             "0.3 MN m/rad, scenario table_2) biases DPP, not CP, with these definitions (50 seeds: DPP joints 1-2 2.9x / 3.5x the truth, "
             "CP 1.00), the opposite of the thesis. Deciding numbers: the ten measured deflection screws and wrenches (or each method's "
             "residuals), the units of the CP residual, and the KR 500-3's DH table (the geometry here is illustrative)")
    rows = [(name, "DPP below CP on every joint (CP / DPP 1.2-6.5), DPP closer",
             f"{mc['seeds']} seeds: median CP / DPP {_f(mc['median_cp_over_dpp'], 3)}; mean abs(ln(k / k_true)) CP {_f(mc[cp]['mean_abs_log_ratio'], 2)}, "
             f"DPP {_f(mc['DPP']['mean_abs_log_ratio'], 2)}; DPP closer in {100 * mc['dpp_closer_fraction']:.0f} % of the seeds",
             "ordering", "reproduced" if ok else "differs", "" if ok else cause)]
    ok = mc["cp_scaled_below_dpp_joints_1_3"]
    rows.append(("Cvitanic (2021), Table 2: CP with rotations x10 below DPP on the arm joints 1-3", "2.13 / 1.59 / 1.12 < 2.86 / 2.36 / 1.67",
                 f"median k / k_true: CP x10 {_f(mc[cps]['median_ratio'][:3], 3)}, DPP {_f(mc['DPP']['median_ratio'][:3], 3)}", "ordering",
                 "reproduced" if ok else "differs",
                 "" if ok else "with an exact model the rotation weight does not move CP (the weighting only matters when data and model disagree)"))
    return rows


def velocity_most_rows(t8: dict[str, Any], d: dict[str, Any]) -> list[Row]:
    """Table 8's "velocity improved most" (Cvitanic (2021), sec. 4.3.2) per motion, each on the tuning the thesis states.

    The 3-axis row is judged with Appendix B's printed Q; the 5-axis row rests on our white-jerk EKF Q (the thesis prints
    none), so it differs (:func:`gtmodel.report.fidelity_rules.apply_rules`), with what the 5-axis fits to Table 8 give.

    Parameters
    ----------
    t8 : dict
        ``kr500_state_estimation``'s Table 8 figures per motion and quantity (``sensor``, ``fusion``, ``fusion_appendix_b``).
    d : dict
        The collected figures with ``fits`` (``docs/fidelity_fits.json``; its ``cvitanic_5_axis`` runs, if any).

    Returns
    -------
    list of Row
    """
    src, out = "Cvitanic (2021)", []  # the rows' order: 3-axis, 5-axis
    for m, key, tuning in (("3-axis", "fusion_appendix_b", "Appendix B's printed Q"), ("5-axis", "fusion", "our white-jerk EKF Q")):
        if m not in t8 or any(key not in v for v in t8[m].values()):
            continue
        r = {q: v[key] / v["sensor"] for q, v in t8[m].items()}
        most = r["velocity_mm_s"] <= min(r.values()) + 1e-12
        ours = f"with {tuning}: fused / sensor-only " + ", ".join(f"{_NAMES.get(q, q)} {v:.3g}" for q, v in sorted(r.items(), key=lambda x: x[1]))
        cause = f"the velocity is {'the most' if most else 'not the most'} improved quantity with {tuning}"
        if m == "3-axis":
            ours_q = {q: v["fusion"] / v["sensor"] for q, v in t8[m].items()}
            cause += (f"; with our white-jerk Q the velocity ratio is {ours_q['velocity_mm_s']:.3g}, "
                      f"{'also' if ours_q['velocity_mm_s'] <= min(ours_q.values()) + 1e-12 else 'not'} the most improved")
            out.append(Row(f"{src}, Table 8: velocity improved most, 3-axis", "velocity the largest gain", ours, "ordering",
                           "structure reproduced" if most else "differs", cause))
            continue
        fits = ((d.get("fits") or {}).get("cvitanic_5_axis") or {}).get("runs") or []
        if fits:
            v = [f["table_8"]["velocity_mm_s"] for f in fits]
            a = [f["table_8"]["acceleration_m_s2"] for f in fits]
            cause += (f"; with the 5-axis Q fitted to Table 8's 5-axis columns (the fit rows) the velocity is the most improved in "
                      f"{sum(f['velocity_most'] for f in fits)} of {len(fits)} fits (velocity {min(v):.2g}-{max(v):.2g}, acceleration "
                      f"{min(a):.2g}-{max(a):.2g}): the ordering is the tuning's")
        out.append(Row(f"{src}, Table 8: velocity improved most, 5-axis", "velocity the largest gain", ours, "ordering",
                       "structure reproduced" if most else "differs", cause, unprinted="our white-jerk 5-axis EKF Q"))
    return out


def orientation_sweep(d: dict[str, Any]) -> str:
    """The sentence of Table 8's 5-axis orientation row: the fused over tracker orientation error of the 5-axis fits.

    Parameters
    ----------
    d : dict
        The collected figures with ``fits`` (``docs/fidelity_fits.json``; :mod:`gtmodel.report.fidelity_fits5`).

    Returns
    -------
    str
        "" if the 5-axis fits were not run.
    """
    runs = ((d.get("fits") or {}).get("cvitanic_5_axis") or {}).get("runs")
    if not runs:
        return ""
    o, qq = [r["table_8"]["orientation_deg"] for r in runs], sorted({r["q_q"] for r in runs})
    return (f". Measured: the 5-axis fits to Table 8 (quaternion Q {' and '.join(f'{v:g}' for v in qq)} per sample, the Table 8 5-axis row's fit) "
            f"give fused / tracker orientation {min(o):.2g}-{max(o):.2g}, " + ("never worse than the tracker (the thesis: 9.2)" if max(o) < 1.0 else
                                                                          f"worse than the tracker in {sum(v >= 1.0 for v in o)} of {len(o)} (the thesis: 9.2)"))
