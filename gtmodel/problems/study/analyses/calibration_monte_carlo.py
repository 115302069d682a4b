"""Monte-Carlo calibration study: are the reported standard deviations honest?

Each case of the study is one synthetic measurement campaign (``truth.seed``) of a
calibration problem; its ``summary.json`` compares the first model's parameters with
the truth (``parameters``: estimate, truth, predicted standard deviation and role, see
:func:`gtmodel.problems.kinds.calibration_results.parameters_vs_truth`).

Per case (:meth:`CalibrationMonteCarlo.row`), for every free parameter ``p``:
``error[p] = estimate - truth``, ``std[p]`` (predicted, ``sigma^2 (J^T J)^-1`` of the
calibration) and ``z[p] = error[p] / std[p]``; fixed, tied and non-identifiable
parameters are left out (a fixed one has no spread, a tied one is biased by its tie when
the truth does not satisfy it, a non-identifiable one has no finite deviation).

Over the study (:meth:`CalibrationMonteCarlo.analyse`): the coverage of the 1- and
2-sigma intervals, the fraction of all ``|z| <= 1`` (resp. 2) over the free parameters
and solved cases. An honest covariance gives ``P(|Z| <= k)`` of a standard normal,
0.6827 and 0.9545 (a Student t with the residual degrees of freedom for few poses:
slightly less); the standard error is computed over cases (the parameters of one case are
correlated). Per parameter: coverage, bias and the ratio of the error's spread to the
predicted deviation. Accuracy against the number of poses: per pose choice
(``pose_method``, Dressler (2012), ch. 5.6: random or eq. 5.9) and number of calibration
poses, the TCP error against the noise-free truth (``truth_mean_error_m``).
"""

from __future__ import annotations

import math
from typing import Any, ClassVar, Mapping

import numpy as np
import pandas as pd

from gtmodel.problems.results import json_safe
from gtmodel.problems.study.analyses.common import check_analyse_args, finite_or_none, solved_rows, status_counts
from gtmodel.problems.study.analysis import StudyAnalysis
from gtmodel.report.study_plots import plot_accuracy_vs_poses, plot_normalised_errors, plot_parameter_spread

__all__ = ["CalibrationMonteCarlo", "NORMAL_COVERAGE", "COVERAGE_BANDS", "GROUP_COLUMNS"]

#: ``P(|Z| <= k)`` of a standard normal for k = 1, 2 (``erf(k / sqrt(2))``).
NORMAL_COVERAGE = {1: math.erf(1 / math.sqrt(2)), 2: math.erf(2 / math.sqrt(2))}
#: Coverage bands of an honest covariance over a 200-seed study (issue 16's criterion).
COVERAGE_BANDS = {1: (0.60, 0.76), 2: (0.90, 0.98)}
#: Columns that group the cases for "accuracy against the number of poses" (those present).
GROUP_COLUMNS = ("pose_method", "n_calibration")


class CalibrationMonteCarlo(StudyAnalysis):
    """Coverage of the predicted parameter deviations over Monte-Carlo seeds, accuracy vs poses.

    Attributes
    ----------
    name : str
        ``"calibration_monte_carlo"``.
    description : str
        One line for the documentation.
    """

    name: ClassVar[str] = "calibration_monte_carlo"
    description: ClassVar[str] = "coverage of the 1/2-sigma parameter intervals over seeds; accuracy against the number of poses"

    def row(self, summary: Mapping[str, Any]) -> dict[str, Any]:
        """Per free parameter: ``error[p]``, ``std[p]``, ``z[p]``; counts within 1 and 2 sigma.

        Parameters
        ----------
        summary : Mapping[str, Any]
            A calibration case's ``summary.json``.

        Returns
        -------
        dict
            ``mc_n_free``, ``mc_within_1sigma``, ``mc_within_2sigma`` (None without a
            truth comparison) and the three columns per free parameter with a finite
            positive deviation (absent in a failed case: NaN in the table).
        """
        out: dict[str, Any] = {"mc_n_free": None, "mc_within_1sigma": None, "mc_within_2sigma": None}
        params = summary.get("parameters") if isinstance(summary, Mapping) else None
        if not isinstance(params, Mapping):
            return out
        z_all = []
        for name, p in params.items():
            if not isinstance(p, Mapping) or p.get("role") != "free":
                continue
            est, tru, s = (finite_or_none(p.get(k)) for k in ("estimate", "truth", "std"))
            if est is None or tru is None or s is None or s <= 0:
                continue
            err = est - tru
            out[f"error[{name}]"], out[f"std[{name}]"], out[f"z[{name}]"] = err, s, err / s
            z_all.append(abs(err / s))
        z = np.asarray(z_all)
        out.update(mc_n_free=int(z.size), mc_within_1sigma=int(np.sum(z <= 1.0)), mc_within_2sigma=int(np.sum(z <= 2.0)))
        return out

    def analyse(self, table: pd.DataFrame, out: Any, plots: bool) -> tuple[dict[str, Any], list[str]]:
        """Coverage over all free parameters and solved cases; per parameter; per pose choice.

        Parameters
        ----------
        table : pandas.DataFrame
            The study table (``status`` and the ``z[...]``, ``error[...]``, ``std[...]``
            columns of :meth:`row`).
        out : str or pathlib.Path
            The study folder (existing).
        plots : bool
            Write ``normalised_errors.png``, ``parameter_spread.png`` and
            ``accuracy_vs_poses.png``.

        Returns
        -------
        figures : dict
            ``coverage_1sigma``, ``coverage_2sigma`` (None without data, with a
            ``message``), their standard errors over cases, the normal values, the
            bands and ``honest`` (both inside their band), ``n_values``, ``n_cases``,
            ``statuses``, ``per_parameter`` and ``accuracy_vs_poses`` records.
        files : list of str
            ``coverage_per_parameter.csv``, ``accuracy_vs_poses.csv`` and the plots.

        Raises
        ------
        InputError
            A table without a ``status`` column, ``out`` not a folder, ``plots`` not a bool.
        """
        table, folder = check_analyse_args(table, out, plots)
        solved = solved_rows(table)
        zcols = [c for c in table.columns if str(c).startswith("z[")]
        names = [str(c)[2:-1] for c in zcols]
        Z = solved[zcols].apply(pd.to_numeric, errors="coerce").to_numpy(dtype=float) if zcols else np.zeros((len(solved), 0))
        used = np.isfinite(Z).any(axis=1) if Z.size else np.zeros(len(solved), dtype=bool)
        figures: dict[str, Any] = {
            "n_cases": int(len(table)),
            "n_cases_used": int(used.sum()),
            "statuses": status_counts(table),
            "normal_coverage_1sigma": NORMAL_COVERAGE[1],
            "normal_coverage_2sigma": NORMAL_COVERAGE[2],
            "band_1sigma": list(COVERAGE_BANDS[1]),
            "band_2sigma": list(COVERAGE_BANDS[2]),
        }
        if not used.any():
            figures.update(coverage_1sigma=None, coverage_2sigma=None, n_values=0, honest=None,
                           message="no solved case compares its parameters with a truth (synthetic data, matching model)")
            return figures, []
        Z = Z[used]
        vals = np.abs(Z[np.isfinite(Z)])
        for k in (1, 2):
            inside = np.where(np.isfinite(Z), np.abs(Z) <= k, np.nan)
            per_case = np.nanmean(inside, axis=1)
            figures[f"coverage_{k}sigma"] = float(np.mean(vals <= k))
            figures[f"coverage_{k}sigma_stderr"] = float(np.std(per_case, ddof=1) / math.sqrt(per_case.size)) if per_case.size > 1 else None
        figures["n_values"] = int(vals.size)
        figures["n_parameters"] = len(names)
        figures["honest"] = bool(all(COVERAGE_BANDS[k][0] <= figures[f"coverage_{k}sigma"] <= COVERAGE_BANDS[k][1] for k in (1, 2)))
        per_param = _per_parameter(solved[used], names)
        groups = _accuracy_groups(solved[used])
        figures["per_parameter"] = per_param.to_dict(orient="records")
        figures["accuracy_vs_poses"] = groups.to_dict(orient="records")
        files = ["coverage_per_parameter.csv"]
        per_param.to_csv(folder / files[0], index=False)
        if len(groups):
            groups.to_csv(folder / "accuracy_vs_poses.csv", index=False)
            files.append("accuracy_vs_poses.csv")
        if plots:
            title = f"{figures['n_cases_used']} cases, {len(names)} free parameters"
            plot_normalised_errors(Z[np.isfinite(Z)], folder / "normalised_errors.png",
                                   coverage=(figures["coverage_1sigma"], figures["coverage_2sigma"]), title=title)
            plot_parameter_spread(per_param, folder / "parameter_spread.png", title=title)
            files += ["normalised_errors.png", "parameter_spread.png"]
            if len(groups) and "truth_mean_error_m_median" in groups:
                plot_accuracy_vs_poses(groups, folder / "accuracy_vs_poses.png")
                files.append("accuracy_vs_poses.png")
        return json_safe(figures), files


def _per_parameter(rows: pd.DataFrame, names: list[str]) -> pd.DataFrame:
    """Per free parameter: cases, coverage, bias and spread against the predicted deviation."""
    recs = []
    for n in names:
        z = pd.to_numeric(rows[f"z[{n}]"], errors="coerce").to_numpy(dtype=float)
        e = pd.to_numeric(rows.get(f"error[{n}]"), errors="coerce").to_numpy(dtype=float) if f"error[{n}]" in rows else np.full(z.shape, np.nan)
        s = pd.to_numeric(rows.get(f"std[{n}]"), errors="coerce").to_numpy(dtype=float) if f"std[{n}]" in rows else np.full(z.shape, np.nan)
        ok = np.isfinite(z)
        z, e, s = z[ok], e[ok], s[ok]
        rms_std = float(np.sqrt(np.mean(s**2))) if s.size else math.nan
        spread = float(np.std(e, ddof=1)) if e.size > 1 else math.nan
        recs.append({
            "parameter": n,
            "n": int(z.size),
            "coverage_1sigma": float(np.mean(np.abs(z) <= 1)) if z.size else math.nan,
            "coverage_2sigma": float(np.mean(np.abs(z) <= 2)) if z.size else math.nan,
            "mean_z": float(np.mean(z)) if z.size else math.nan,
            "std_z": float(np.std(z, ddof=1)) if z.size > 1 else math.nan,
            "error_std": spread,
            "predicted_std_rms": rms_std,
            "spread_ratio": spread / rms_std if rms_std > 0 else math.nan,
        })
    return pd.DataFrame.from_records(recs)


def _accuracy_groups(rows: pd.DataFrame) -> pd.DataFrame:
    """Per pose choice and number of calibration poses: TCP errors and coverage."""
    keys = [c for c in GROUP_COLUMNS if c in rows.columns]
    if not keys:
        return pd.DataFrame()
    recs = []
    for key, g in rows.groupby(keys, dropna=False, sort=True):
        key = key if isinstance(key, tuple) else (key,)
        rec: dict[str, Any] = {k: (v.item() if hasattr(v, "item") else v) for k, v in zip(keys, key)}
        rec["n_cases"] = int(len(g))
        for col in ("truth_mean_error_m", "mean_error_m", "pose_acceptance"):
            if col in g:
                v = pd.to_numeric(g[col], errors="coerce").to_numpy(dtype=float)
                v = v[np.isfinite(v)]
                rec[f"{col}_median"] = float(np.median(v)) if v.size else math.nan
                if col == "truth_mean_error_m":
                    rec[f"{col}_q10"] = float(np.quantile(v, 0.1)) if v.size else math.nan
                    rec[f"{col}_q90"] = float(np.quantile(v, 0.9)) if v.size else math.nan
        for k in (1, 2):
            within, n = (pd.to_numeric(g.get(c), errors="coerce").sum() if c in g else 0 for c in (f"mc_within_{k}sigma", "mc_n_free"))
            rec[f"coverage_{k}sigma"] = float(within / n) if n else math.nan
        recs.append(rec)
    return pd.DataFrame.from_records(recs)

