"""Where tracker + IMU fusion stops paying: the limits of Cvitanic (2021), Table 10, located by search.

Table 10 gives, per Table 7 parameter and per motion (3-axis, 5-axis), the value below which the
fused VELOCITY is better than the tracker's four-point regression, "each value ... assuming all
other parameters are baseline" (section 4.3.3). Table 7's own offsets stop short of several of
those limits (e.g. the accelerometer noise: offsets up to 0.039, limit 0.1; the transform
translation error: offsets up to 2.54 mm, limit 0.1 m), so the thesis swept further than Table 7
lists; its grid is not printed. Its limits are decades, so ONE GRID STEP is taken as one decade.

:func:`velocity_limit` locates our limit for one parameter: the parameter on a decade grid from
the search range's low end upwards (:data:`SEARCH_RANGE`), one run of
:meth:`~gtmodel.estimation.fusion.study.FusionStudy.run_case` per value, until the fused velocity
error is no longer below the regression's; then ``bisections`` halvings of that decade in
``log10`` (a bracket of ``10^(1 / 2^n)``). The limit reported is the geometric mean of the final
bracket ``[pays_up_to, stops_at]``. :func:`judge` compares it with the thesis (:data:`THESIS_TABLE_10`):
``reproduced`` when ``|log10(limit / thesis)| <= LIMIT_DECADES`` (half a decade: a decade's tolerance
passed anything from 0.01 to 1 against "< 0.1"; the rule of the fidelity page,
:mod:`gtmodel.report.fidelity_rules`, reads this one constant), ``differs`` otherwise;
a thesis "no constraint" is reproduced when fusion still pays at the top of the search range.

Baselines: ``"causal"`` (the study's tracker-only velocity: the slope of the last four positions taken as
the velocity NOW, as the thesis describes it; it lags 1.5 sample times) and ``"centred"`` (the same slope
compared with the true velocity at the window's centre, :func:`centred_velocity_error`: no lag, the
noise alone), to measure how much of the sample-time limit the baseline's lag decides.

Tunings: ``"white_jerk"`` (the study's own ``Q``, :meth:`FusionStudy.process_noise`) and
``"appendix_b"`` (the thesis' diagonal ``Q`` of its 3-axis KF, Appendix B; 3-axis only, the thesis
gives no ``Q`` for its 5-axis EKF). ``R`` follows the swept sensor figures in both (the filter is
told the sensor it has).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from gtmodel.errors import InputError

__all__ = ["LIMIT_DECADES", "THESIS_TABLE_10", "ROTATION_ONLY_PARAMETERS", "SEARCH_RANGE", "TUNINGS", "BASELINES", "velocity_limit", "judge", "decade_grid",
           "limits", "centred_velocity_error"]

#: The largest distance [decades, log10] between our limit and the thesis' "< limit" with which a
#: limit is reproduced (issue 47: at most half a decade; the fidelity page's rule is this constant).
LIMIT_DECADES = 0.5

#: Cvitanic (2021), Table 10: the limit per parameter ``(3-axis, 5-axis)`` in the Table 7 units
#: (:data:`~gtmodel.estimation.fusion.tracker_imu.TABLE_7`); ``None``: "N/A", ``math.inf``: "No
#: constraint". The translation error's "< 0.1 m" is written in mm. The gyro noise's unit is
#: printed as deg/s in Table 10 and as deg/s/sqrt(Hz) in Table 7 (read here as the Table 7 density).
THESIS_TABLE_10: dict[str, tuple[float | None, float | None]] = {
    "accel_noise_m_s2_rtHz": (0.1, 0.1),
    "accel_bias_m_s2": (0.001, 0.001),
    "gyro_noise_deg_s_rtHz": (None, 0.1),
    "gyro_bias_deg_s": (None, 1.0),
    "transform_orientation_error_deg": (10.0, 0.1),
    "transform_translation_error_mm": (math.inf, 100.0),
    "sample_time_s": (0.01, 0.01),
}
#: Table 7 parameters a 3-axis run does not measure (the 9-D model has no orientation states).
ROTATION_ONLY_PARAMETERS = ("orientation_noise_deg", "gyro_bias_deg_s", "gyro_noise_deg_s_rtHz")
#: Search range per parameter ``(low, high)``, Table 7 units: from the Table 7 baseline (or the
#: first offset of a zero baseline) to at least ten times the thesis' largest limit.
SEARCH_RANGE: dict[str, tuple[float, float]] = {
    "accel_noise_m_s2_rtHz": (3.9e-4, 3.9),
    "accel_bias_m_s2": (2.5e-4, 2.5),
    "gyro_noise_deg_s_rtHz": (1.6e-3, 16.0),
    "gyro_bias_deg_s": (8e-4, 80.0),
    "transform_orientation_error_deg": (0.01, 90.0),
    "transform_translation_error_mm": (0.254, 2540.0),
    "sample_time_s": (1e-3, 0.1),
}
#: The filter tunings of the search (module docstring).
TUNINGS = ("white_jerk", "appendix_b")
#: The tracker-only velocity baselines (module docstring).
BASELINES = ("causal", "centred")
#: Weights of the least-squares slope of four equally spaced samples (times 1 / dt): ``(-3, -1, 1, 3) / 10``.
_SLOPE = np.array([-1.5, -0.5, 0.5, 1.5]) / 5.0
#: The quantity Table 10 judges (section 4.3.3: "the velocity estimation ... improved the most").
QUANTITY = "velocity_mm_s"


def decade_grid(low: float, high: float) -> list[float]:
    """``low, 10 low, 100 low, ...`` up to ``high`` (``high`` appended when it is not on the grid).

    Parameters
    ----------
    low, high : float
        Ends of the range, ``0 < low < high``.

    Returns
    -------
    list of float

    Raises
    ------
    InputError
        ``low`` not positive or not below ``high``.
    """
    if not (low > 0 and high > low and math.isfinite(high)):
        raise InputError(f"low, high: expected 0 < low < high (finite), got {low!r}, {high!r}")
    n = int(math.floor(math.log10(high / low) + 1e-9))
    grid = [low * 10.0**k for k in range(n + 1)]
    if high > grid[-1] * (1 + 1e-9):
        grid.append(high)
    return grid


def centred_velocity_error(study: Any, case: Any, duration: float) -> float:
    """Mean norm [mm/s] of the four-point slope of the tracker positions against the TRUE velocity at the window's centre.

    The slope of samples ``k .. k+3`` (least squares, ``(-3, -1, 1, 3) / (10 dt)``) is compared with the
    velocity at ``t_k + 1.5 dt``, taken from the closed-form path sampled at ``dt / 2`` (index ``2k + 3``);
    windows ending from ``case.first`` on are scored. The causal baseline of the study compares the same
    slope with the velocity at ``t_{k+3}``.

    Parameters
    ----------
    study : FusionStudy
        The study that ran the case (its path).
    case : FusionRun
        The run (its spec, truth and tracker positions).
    duration : float
        The run's length [s].

    Returns
    -------
    float
        Mean Euclidean norm of the error [mm/s].
    """
    dt = case.spec.dt
    p = case.measurements.position
    n = p.shape[0] - 3
    slope = sum(_SLOPE[j] * p[j : j + n] for j in range(4)) / dt
    half = study.path(case.truth.rotation, case.spec, duration).truth(dt / 2.0).velocity
    err = np.linalg.norm(slope - half[3 : 3 + 2 * n : 2], axis=1)
    first = max(0, case.first - 3)
    return 1e3 * float(np.mean(err[first:]))


def _evaluate(study: Any, rotation: bool, parameter: str, value: float, q_diag: Any, duration: float, baseline: str) -> dict[str, Any]:
    spec = study.spec.replace(**{parameter: value})
    try:
        case = study.run_case(rotation, spec, q_diag=q_diag, duration=duration, label=f"limit {parameter}={value:g}")
    except InputError as exc:  # e.g. a sample time leaving too few samples
        return {"value": value, "sensor": None, "fusion": None, "pays": False, "status": "error", "message": str(exc)}
    e = case.errors.get(QUANTITY)
    if e is None:
        return {"value": value, "sensor": None, "fusion": None, "pays": False, "status": str(case.status), "message": case.message}
    sensor = e["sensor"] if baseline == "causal" else centred_velocity_error(study, case, duration)
    return {"value": value, "sensor": sensor, "fusion": e["fusion"], "pays": bool(e["fusion"] < sensor),
            "status": str(case.status), "message": case.message}


def velocity_limit(study: Any, rotation: bool, parameter: str, *, tuning: str = "white_jerk", bisections: int = 4,
                   duration: float | None = None, search: tuple[float, float] | None = None, baseline: str = "causal") -> dict[str, Any]:
    """Locate the value of one Table 7 parameter where fusion stops paying in velocity (Cvitanic (2021), Table 10).

    Parameters
    ----------
    study : FusionStudy
        The study (its baseline sensors, path and filter set-up).
    rotation : bool
        5-axis (True) or 3-axis.
    parameter : str
        A key of :data:`THESIS_TABLE_10`.
    tuning : {"white_jerk", "appendix_b"}, optional
        The filter's ``Q`` (module docstring); ``"appendix_b"`` needs the 3-axis model.
    bisections : int, optional
        Halvings of the bracketing decade in ``log10`` (>= 0).
    duration : float, optional
        Length of each run [s] (default the study's ``sweep_duration`` or ``duration``).
    search : tuple of float, optional
        ``(low, high)`` instead of :data:`SEARCH_RANGE`.
    baseline : {"causal", "centred"}, optional
        The tracker-only velocity fusion is judged against (module docstring).

    Returns
    -------
    dict
        ``motion, parameter, tuning, baseline, thesis_limit`` (None: N/A, ``inf``: no constraint),
        ``search`` (low, high), ``pays_up_to`` (largest value seen paying, None if the first did
        not), ``stops_at`` (smallest value seen not paying, None if none up to ``high``),
        ``limit`` (geometric mean of the two; ``low`` or ``high`` where one is missing),
        ``evaluations`` (per run ``value, sensor, fusion, pays, status, message``; velocity in
        mm/s), and the :func:`judge` fields ``verdict``, ``decades_from_thesis``.

    Raises
    ------
    InputError
        An unknown parameter, tuning or baseline, ``"appendix_b"`` on the 5-axis model, a parameter the
        3-axis model does not measure, a negative ``bisections``.
    """
    if parameter not in THESIS_TABLE_10:
        raise InputError(f"parameter: expected one of {', '.join(THESIS_TABLE_10)}, got {parameter!r}")
    if tuning not in TUNINGS:
        raise InputError(f"tuning: expected one of {', '.join(TUNINGS)}, got {tuning!r}")
    if baseline not in BASELINES:
        raise InputError(f"baseline: expected one of {', '.join(BASELINES)}, got {baseline!r}")
    if tuning == "appendix_b" and rotation:
        raise InputError("tuning: 'appendix_b' is the thesis' 3-axis KF (Appendix B gives no Q for the 5-axis EKF)")
    if not rotation and parameter in ROTATION_ONLY_PARAMETERS:
        raise InputError(f"parameter: {parameter} is not measured by the 3-axis model (Table 10: N/A)")
    if isinstance(bisections, bool) or int(bisections) != bisections or bisections < 0:
        raise InputError(f"bisections: expected an integer >= 0, got {bisections!r}")
    low, high = SEARCH_RANGE[parameter] if search is None else search
    duration = duration if duration is not None else (study.sweep_duration or study.duration)
    q_diag = study.appendix_b_q if tuning == "appendix_b" else None
    evals: list[dict[str, Any]] = []
    pays_up_to = stops_at = None
    for value in decade_grid(low, high):
        ev = _evaluate(study, rotation, parameter, value, q_diag, duration, baseline)
        evals.append(ev)
        if not ev["pays"]:
            stops_at = value
            break
        pays_up_to = value
    if pays_up_to is not None and stops_at is not None:
        for _ in range(int(bisections)):
            mid = math.sqrt(pays_up_to * stops_at)
            ev = _evaluate(study, rotation, parameter, mid, q_diag, duration, baseline)
            evals.append(ev)
            if ev["pays"]:
                pays_up_to = mid
            else:
                stops_at = mid
    limit = math.sqrt(pays_up_to * stops_at) if pays_up_to is not None and stops_at is not None else (low if stops_at is not None else high)
    thesis = THESIS_TABLE_10[parameter][1 if rotation else 0]
    row = {"motion": "5-axis" if rotation else "3-axis", "parameter": parameter, "tuning": tuning, "baseline": baseline, "thesis_limit": thesis,
           "search": [low, high], "pays_up_to": pays_up_to, "stops_at": stops_at, "limit": limit, "evaluations": evals}
    row.update(judge(row))
    return row


def judge(row: dict[str, Any]) -> dict[str, Any]:
    """The verdict of one limit against the thesis: within :data:`LIMIT_DECADES` of it (module docstring).

    Parameters
    ----------
    row : dict
        ``thesis_limit``, ``stops_at``, ``limit`` (as :func:`velocity_limit` gives them).

    Returns
    -------
    dict
        ``verdict`` (``"reproduced"``, ``"differs"`` or ``"N/A"``) and ``decades_from_thesis``
        (``log10(limit / thesis)``; None where the thesis has no finite limit or ours was not found).
    """
    thesis, stops, limit = row["thesis_limit"], row["stops_at"], row["limit"]
    if thesis is None:
        return {"verdict": "N/A", "decades_from_thesis": None}
    if math.isinf(thesis):
        return {"verdict": "reproduced" if stops is None else "differs", "decades_from_thesis": None}
    if stops is None:  # fusion pays over the whole range: our limit lies above it
        return {"verdict": "differs", "decades_from_thesis": None}
    d = float(np.log10(limit / thesis))
    return {"verdict": "reproduced" if abs(d) <= LIMIT_DECADES + 1e-9 else "differs", "decades_from_thesis": d}


def limits(study: Any, motions: Any, tunings: Any = ("white_jerk",), parameters: Any = None, bisections: int = 4,
           centred: Any = ()) -> list[dict[str, Any]]:
    """Every limit of Table 10 for the given motions and tunings (:func:`velocity_limit`).

    Parameters
    ----------
    study : FusionStudy
        The study.
    motions : sequence of str
        ``"3-axis"`` and/or ``"5-axis"``.
    tunings : sequence of str, optional
        Of :data:`TUNINGS`; ``"appendix_b"`` runs on the 3-axis motion only.
    parameters : sequence of str, optional
        Keys of :data:`THESIS_TABLE_10` (default all); a parameter the motion does not measure is skipped.
    bisections : int, optional
        As :func:`velocity_limit`.
    centred : sequence of str, optional
        Parameters searched a second time against the centred baseline (``baseline="centred"``).

    Returns
    -------
    list of dict
        One :func:`velocity_limit` row per (motion, tuning, parameter, baseline).

    Raises
    ------
    InputError
        An unknown motion, tuning or parameter, a negative ``bisections``.
    """
    parameters = list(THESIS_TABLE_10) if parameters is None else list(parameters)
    rows = []
    for motion in motions:
        if motion not in ("3-axis", "5-axis"):
            raise InputError(f"motions: expected '3-axis' or '5-axis', got {motion!r}")
        rotation = motion == "5-axis"
        for tuning in tunings:
            if tuning == "appendix_b" and rotation:
                continue
            for p in parameters:
                if not rotation and p in ROTATION_ONLY_PARAMETERS:
                    continue
                for baseline in ("causal", "centred") if p in centred else ("causal",):
                    rows.append(velocity_limit(study, rotation, p, tuning=tuning, bisections=bisections, baseline=baseline))
    return rows
