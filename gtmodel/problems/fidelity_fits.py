"""Runs the three fits of the fidelity report and writes ``docs/fidelity_fits.json`` (``python -m gtmodel.problems.fidelity_fits``).

Each fit is to one thesis table, whose quantity the report then holds fixed to predict the others
(:mod:`gtmodel.report.fidelity_fits` renders them):

- Cvitanic (2021), Tables 8-10: the 3-axis KF's diagonal ``Q`` fitted to Table 8
  (:func:`gtmodel.report.fidelity_fits.fit_table_8`), Tables 9 and 10 predicted
  (:func:`gtmodel.report.fidelity_fits.predict`); the 5-axis EKF's fitted to Table 8's 5-axis columns, Table 9's
  5-axis columns predicted (:mod:`gtmodel.report.fidelity_fits5`);
- Dressler (2012), Table 5.8: the D1 carts' transverse compliance (:mod:`gtmodel.calibration.cart_compliance`)
  fitted on model 1 of the thesis' set-up (:func:`fit_d1_cart_compliance`, which runs the ``calibration``
  kind, hence this layer); ``problems/thesis/d1_error_models_fitted.toml`` holds it and its run predicts Table 5.3;
- Dressler (2012), Table 7.2: the ILC structure's static TCP stiffness in y (eq. 6.14) fitted to Case 1's tool y
  (:func:`fit_l1_stiffness_y`, Case 1 of the thesis' ILC set-up alone); ``problems/thesis/l1_ilc_fitted.toml`` holds it and
  its run predicts the other cases of Table 7.2.

About ten minutes (the Table 8 fit on five noise seeds under both readings of the path's feed, the 5-axis fit on five seeds and a sweep);
``tests/report/test_fidelity_fits.py`` checks (slow) that it reproduces the stored file.
"""

from __future__ import annotations

import argparse
import json
import math
import re
import tempfile
import tomllib
from pathlib import Path
from typing import Any

import numpy as np
import scipy.optimize

from gtmodel.calibration import grid_poses
from gtmodel.calibration.cart_compliance import transverse_forces
from gtmodel.problems.run import run_problem
from gtmodel.report.fidelity_d1 import THESIS_FINAL_COST, THESIS_N_CALIBRATION, length_error_um
from gtmodel.estimation.fusion.study import FusionStudy
from gtmodel.report.fidelity_fits import D1_THESIS_FILE, FITS, best_acceleration_ratio, fit_table_8, other_crossing, predict
from gtmodel.report.fidelity_fits5 import five_axis_spread
from gtmodel.robots.closure import ThreeLinkClosure

__all__ = ["SEEDS", "FEEDS", "seed_spread", "L1_THESIS_FILE", "L1_FITTED_FILE", "TABLE_7_2_CASE_1_TOOL_Y", "d1_model_1_arms", "fit_d1_cart_compliance", "l1_case_1",
           "fit_l1_stiffness_y", "compute", "main"]

#: The ILC set-up the thesis' text defines, and the same with the static TCP stiffness in y fitted to Table 7.2's Case 1 tool y.
L1_THESIS_FILE = D1_THESIS_FILE.parent / "l1_ilc_thesis.toml"
L1_FITTED_FILE = D1_THESIS_FILE.parent / "l1_ilc_fitted.toml"
#: Dressler (2012), Table 7.2: Case 1, tool y, mean of iterations 5-10 over iteration 0.
TABLE_7_2_CASE_1_TOOL_Y = 0.361
#: Bracket of the fitted stiffness [N/m] (the upper end: the thesis set-up's 2e6, the D1's measured 2-4 N/um).
STIFFNESS_Y_BRACKET = (1e3, 2e6)


def d1_model_1_arms(compliance_um_per_N: Any) -> dict[str, Any]:
    """Model 1 of the thesis' D1 set-up with the carts' transverse compliance: the RMS length error per arm.

    Runs :data:`D1_THESIS_FILE`'s truth and its model 1 alone (the 3-link model with linear actuators,
    each arm calibrated separately) with ``truth.cart_compliance`` set
    (:mod:`gtmodel.calibration.cart_compliance`), about 0.1 s.

    Parameters
    ----------
    compliance_um_per_N : array_like, shape (3,)
        Transverse compliance of carts 1-3 [um/N] (>= 0).

    Returns
    -------
    dict
        ``arm_um`` (Table 5.8's figure: ``sqrt(V / N) / (2 L)`` per arm), ``mean_um`` / ``max_um`` (TCP error on the validation poses).

    Raises
    ------
    ProblemError
        The run fails.
    """
    c = [float(v) * 1e-6 for v in compliance_um_per_N]
    text = D1_THESIS_FILE.read_text(encoding="utf-8").split("\n", 1)[1]  # without the #:schema line (relative path)
    head, first = text.split("[[models]]")[:2]
    head = head.replace("\nseed = 0\n", f"\nseed = 0\ncart_compliance = {c!r}\n", 1)
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "d1_model_1.toml"
        path.write_text(head + "[[models]]" + first, encoding="utf-8")
        run_problem(path, Path(tmp) / "out", plots=False)
        m = json.loads((Path(tmp) / "out" / "summary.json").read_text(encoding="utf-8"))["models"][0]
    return {"arm_um": [length_error_um(r) for r in m["link_residual_rms_m2"]], "mean_um": 1e6 * m["mean_error_m"], "max_um": 1e6 * m["max_error_m"]}


def fit_d1_cart_compliance() -> dict[str, Any]:
    """The carts' transverse compliances fitted to Table 5.8 (model 1's final cost per arm, 73 / 60 / 19 um).

    :func:`scipy.optimize.least_squares` on the three arm errors of :func:`d1_model_1_arms` against
    the thesis', compliances >= 0 [um/N], from 100 um/N on arms 1 and 2 and 1 um/N on arm 3.

    Returns
    -------
    dict
        ``compliance_um_per_N``, ``arm_um`` (ours with it), ``target_um`` (the thesis'), ``mean_um``,
        ``max_um`` (model 1's TCP error with it), ``unloaded`` (:func:`d1_model_1_arms` at 0),
        ``transverse_force_N`` (per arm the min and max over the grid) and ``cart_displacement_um``
        (per arm the largest ``c_i |F_perp|``).
    """
    target = [length_error_um(math.sqrt(v / THESIS_N_CALIBRATION)) for v in THESIS_FINAL_COST[1].values()]
    res = scipy.optimize.least_squares(lambda c: np.asarray(d1_model_1_arms(c)["arm_um"]) - target, x0=[100.0, 100.0, 1.0], bounds=(0.0, 1000.0),
                                       diff_step=1e-2, xtol=1e-6, ftol=1e-6)
    c = [float(v) for v in res.x]
    best = d1_model_1_arms(c)
    model = ThreeLinkClosure("D1")
    q = grid_poses(model, 0.16)
    T, _ = model.fk(q)
    F = np.linalg.norm(transverse_forces(T, q), axis=2)
    return {"compliance_um_per_N": c, "arm_um": best["arm_um"], "target_um": target, "mean_um": best["mean_um"], "max_um": best["max_um"],
            "unloaded": d1_model_1_arms([0.0, 0.0, 0.0]), "transverse_force_N": [[float(F[:, i].min()), float(F[:, i].max())] for i in range(3)],
            "cart_displacement_um": [float(c[i] * F[:, i].max()) for i in range(3)]}


def l1_case_1(stiffness_y: float) -> dict[str, Any]:
    """Case 1 of the thesis' ILC set-up with the static TCP stiffness in y replaced: Table 7.2's figures.

    Runs :data:`L1_THESIS_FILE` with its first case alone and without the coupled check (about 3 s).

    Parameters
    ----------
    stiffness_y : float
        Static TCP stiffness in y [N/m] (``[structure] stiffness``'s second entry, Dressler (2012), eq. 6.14).

    Returns
    -------
    dict
        ``tool_x``, ``tool_y`` (mean of iterations 5-10 over iteration 0), ``actuator`` (per actuator),
        ``deflection_rms_um`` (x, y, of the uncorrected trial).

    Raises
    ------
    ProblemError
        The run fails.
    """
    text = L1_THESIS_FILE.read_text(encoding="utf-8").split("\n", 1)[1]
    kx = tomllib.loads(text)["structure"]["stiffness"][0]
    text = re.sub(r"(?m)^stiffness = \[[^\]]*\]", f"stiffness = [{kx!r}, {float(stiffness_y)!r}]", text, count=1)
    text = text.replace("coupled_check = true", "coupled_check = false")
    head, rest = text.split("[[cases]]", 1)
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "l1_case_1.toml"
        path.write_text(head + "[[cases]]" + rest.split("[[cases]]")[0], encoding="utf-8")
        run_problem(path, Path(tmp) / "out", plots=False)
        c = json.loads((Path(tmp) / "out" / "summary.json").read_text(encoding="utf-8"))["cases"]["1"]
    return {"tool_x": c["table_7_2"]["tool_x"], "tool_y": c["table_7_2"]["tool_y"], "actuator": c["table_7_2"]["actuator"],
            "deflection_rms_um": [1e6 * v for v in c["deflection_rms_m"][:2]]}


def fit_l1_stiffness_y() -> dict[str, Any]:
    """The static TCP stiffness in y fitted to Table 7.2's Case 1 tool y (0.361).

    :func:`scipy.optimize.brentq` in ``log10`` of the stiffness over :data:`STIFFNESS_Y_BRACKET`
    on :func:`l1_case_1`'s tool y.

    Returns
    -------
    dict
        ``stiffness_y_N_per_m``, ``case_1`` (:func:`l1_case_1` with it), ``thesis_set_up`` (at the thesis set-up's stiffness),
        ``target`` (0.361).
    """
    lo, hi = (math.log10(v) for v in STIFFNESS_Y_BRACKET)
    x = scipy.optimize.brentq(lambda x: l1_case_1(10.0**x)["tool_y"] - TABLE_7_2_CASE_1_TOOL_Y, lo, hi, xtol=1e-3)
    k = 10.0**x
    return {"stiffness_y_N_per_m": k, "case_1": l1_case_1(k), "thesis_set_up": l1_case_1(STIFFNESS_Y_BRACKET[1]), "target": TABLE_7_2_CASE_1_TOOL_Y}


#: The noise seeds of the spread of the Table 8 fit (issue 47: at least five), and both readings of the sine path's speed.
SEEDS = (1, 2, 3, 4, 5)
FEEDS = ("tangential", "x")


def seed_spread(seeds: tuple[int, ...] = SEEDS, feeds: tuple[str, ...] = FEEDS) -> dict[str, Any]:
    """The Table 8 fit and its Table 9 predictions on every noise seed, under both readings of the feed.

    Parameters
    ----------
    seeds : tuple of int, optional
        Noise seeds of :class:`~gtmodel.estimation.fusion.study.FusionStudy`.
    feeds : tuple of str, optional
        ``"tangential"`` (the thesis' stated constant tangential speed, Cvitanic (2021), sec. 4.2) and ``"x"``.

    Returns
    -------
    dict
        Per feed, per seed (as a string): ``reached`` (the 2/3 acceleration ratio is reachable), ``least_acceleration_ratio``,
        ``q_p``, ``q_a``, ``table_8``, ``table_9`` (:func:`gtmodel.report.fidelity_fits.predict`'s ratios, Table 10 left out) and
        ``other_crossing`` (:func:`gtmodel.report.fidelity_fits.other_crossing`).
    """
    out: dict[str, Any] = {}
    for feed in feeds:
        out[feed] = {}
        for seed in seeds:
            study = FusionStudy(seed=seed, feed=feed)
            fit = fit_table_8(study)
            t9 = predict(fit, study, table_10=False)["table_9"]
            out[feed][str(seed)] = {k: fit[k] for k in ("reached", "least_acceleration_ratio", "q_p", "q_a", "table_8")} | {
                "table_9": {q: v["ratio"] for q, v in t9.items()}, "other_crossing": other_crossing(fit, study)}
    return out


def compute() -> dict[str, Any]:
    """The fit and the predictions (what ``docs/fidelity_fits.json`` holds).

    Returns
    -------
    dict
        ``command``, ``cvitanic_tables_8_10``: ``fit`` (:func:`fit_table_8`, at the thesis' tangential feed, seed 1) and
        ``predicted`` (:func:`predict`), ``x_feed`` (the same at the feed along x), ``seeds`` (:func:`seed_spread`), ``table_8_at_implied_noise``
        (:func:`~gtmodel.report.fidelity_fits.best_acceleration_ratio` with Table 7's bias and without);
        ``cvitanic_5_axis`` (:func:`~gtmodel.report.fidelity_fits5.five_axis_spread`: the 5-axis EKF's Q fitted to Table 8, Table 9 predicted);
        ``d1_cart_compliance`` (:func:`fit_d1_cart_compliance`); ``l1_stiffness_y`` (:func:`fit_l1_stiffness_y`).
    """
    fit = fit_table_8()
    x_fit = fit_table_8(FusionStudy(feed="x"))
    return {"command": "python -m gtmodel.problems.fidelity_fits", "cvitanic_tables_8_10": {"fit": fit, "predicted": predict(fit),
                                                                                        "x_feed": {"fit": x_fit, "predicted": predict(x_fit, FusionStudy(feed="x"))},
                                                                                        "seeds": seed_spread(),
                                                                                        "table_8_at_implied_noise": [best_acceleration_ratio(),
                                                                                                                     best_acceleration_ratio(bias=0.0)]},
            "cvitanic_5_axis": five_axis_spread(), "d1_cart_compliance": fit_d1_cart_compliance(), "l1_stiffness_y": fit_l1_stiffness_y()}



def main(argv: list[str] | None = None) -> int:
    """``python -m gtmodel.problems.fidelity_fits``: compute the fits and write ``docs/fidelity_fits.json``.

    Parameters
    ----------
    argv : list of str, optional
        Arguments (default ``sys.argv[1:]``; none are taken).

    Returns
    -------
    int
        Exit code (0).
    """
    argparse.ArgumentParser(prog="python -m gtmodel.problems.fidelity_fits", description=__doc__.splitlines()[0]).parse_args(argv)
    FITS.write_text(json.dumps(compute(), indent=1, sort_keys=True) + "\n", encoding="utf-8")
    return 0


if __name__ == "__main__":  # pragma: no cover - the command line
    raise SystemExit(main())
