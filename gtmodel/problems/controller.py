"""A tracking controller from an ``optimal_control`` result folder (``gtmodel codegen --controller RESULT_DIR``).

The folder a ``gtmodel solve`` of an ``optimal_control`` problem wrote holds
``summary.json`` (the model file and class, the parameter values of the solve, the problem
file) and ``trajectories.csv`` (the optimal states and inputs by scalar name on the
collocation mesh). :func:`tracking_from_result` rebuilds the model, reduces it to its
explicit ODE (:func:`gtmodel.modeling.explicit_ode`) with the solve's parameter values,
takes the bounds the summary records (the NLP's: the problem file's ``[bounds]`` over the
model's; the input bounds intersected with the model's declared ones) and builds the
feedforward + time-varying LQR controller of
:func:`gtmodel.control.tracking.tracking_controller` at the loop period. A result that
failed its verification (``check_failed``) or was not verified is taken only with
``accept_unverified`` (``--accept-unverified``), which the check's summary and verdict repeat;
an input bound recorded nowhere is named in them (its violations are not counted).
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import numpy as np

from gtmodel._tables import read_table
from gtmodel.defaults import LOOP_PERIOD_S
from gtmodel.errors import InputError
from gtmodel.control.tracking import TrackingController, tracking_controller
from gtmodel.modeling import ExplicitODE, explicit_ode
from gtmodel.problems.base import ProblemFile
from gtmodel.problems.loop_bounds import SOLVED, DeclaredBounds, dae_bounds, summary_bounds, unverified_reason
from gtmodel.problems.registry import MODEL_OCP_KINDS
from gtmodel.problems.loop_file import RESULT_TABLE, CheckSection, LoopModel, LoopSetup, loop_samples, loop_setup
from gtmodel.problems.user_model import load_user_model

__all__ = ["RESULT_TABLE", "is_result_folder", "tracking_from_result", "result_bounds", "result_loop_setup"]



def is_result_folder(path: Path) -> bool:
    """Whether ``path`` is a folder holding a ``summary.json`` (a result folder, not a controller file).

    Parameters
    ----------
    path : pathlib.Path
        The ``--controller`` argument.

    Returns
    -------
    bool
    """
    return path.is_dir() and (path / "summary.json").is_file()


def _table(path: Path) -> dict[str, np.ndarray]:
    """The columns of a result's ``trajectories.csv`` (the one CSV reader: caps, line-numbered errors; the text column ``point`` left out)."""
    table = read_table(path, "trajectory table", text_columns=("point",))
    if "t" not in table.columns or table.data.shape[0] < 2:
        raise InputError(f"{path}: expected a header row with a 't' column and at least two rows")
    return {name: table.data[:, j] for j, name in enumerate(table.columns)}


def tracking_from_result(
    result_dir: str | Path,
    dt: float = LOOP_PERIOD_S,
    method: str = "rk4",
    substeps: int = 1,
    Q: Any = None,
    R: Any = None,
    accept_unverified: bool = False,
) -> tuple[TrackingController, ExplicitODE]:
    """Feedforward + time-varying LQR along the optimal motion of an ``optimal_control`` (or ``optimica``) result.

    Parameters
    ----------
    result_dir : str or pathlib.Path
        The result folder (``summary.json``, ``trajectories.csv``).
    dt : float, optional
        Loop period [s] (default :data:`gtmodel.defaults.LOOP_PERIOD_S`).
    method : {"rk4", "implicit_euler", "radau2"}, optional
        The model's fixed step whose Jacobians give ``A_k``, ``B_k``.
    substeps : int, optional
        Its steps within one period.
    Q, R : array_like, optional
        LQR weights (default Bryson's rule, see
        :func:`~gtmodel.control.tracking.tracking_controller`).
    accept_unverified : bool, optional
        Take a result whose verification failed or was skipped (default False: refused).

    Returns
    -------
    controller : TrackingController
        Saturated at the input bounds of :func:`result_bounds`.
    ode : ExplicitODE
        The model's explicit ODE with the solve's parameter values as defaults.

    Raises
    ------
    InputError
        Not an ``optimal_control`` result of a solved problem, an unverified one without
        ``accept_unverified``, a missing table or column, non-numeric bounds.
    ProblemError
        Too many loop periods at ``dt`` (:func:`~gtmodel.problems.loop_file.loop_samples`,
        naming the table and its ``t``).
    ModelFileError, ModelError
        The model file cannot be loaded or reduced.
    """
    folder = Path(result_dir)
    summary_file = folder / "summary.json"
    try:
        summary = json.loads(summary_file.read_text(encoding="utf-8"))
    except (OSError, ValueError) as exc:
        raise InputError(f"{summary_file}: cannot read the result summary ({exc})") from None
    if summary.get("kind") not in MODEL_OCP_KINDS:
        raise InputError(f"{summary_file}: kind: expected an optimal_control (or optimica) result, got {summary.get('kind')!r}")
    status = summary.get("status")
    if status not in (*SOLVED, "check_failed"):
        raise InputError(f"{summary_file}: status: expected a solved problem ({' or '.join(SOLVED)}), got {status!r}")
    why = unverified_reason(status, summary.get("verification"))
    if why is not None and not accept_unverified:
        raise InputError(f"{summary_file}: expected a verified result ({why}); give --accept-unverified to track it unverified, "
                         "or solve again with the remedy the solve names (more [collocation] elements, [transcription] refine = true)")
    model_ref = summary.get("model") or {}
    if not model_ref.get("file") or not model_ref.get("class"):
        raise InputError(f"{summary_file}: model: expected the model file and class of the solve")
    model = load_user_model(model_ref["file"], model_ref["class"])
    ode = explicit_ode(model)
    values = {k: v for k, v in (summary.get("model_parameters") or {}).items() if k in ode.dae.p_vars}
    if values:
        ode.p_default = ode.dae.parameter_vector(values)
    table = _table(folder / RESULT_TABLE)
    missing = [n for n in ode.x_names + ode.u_names if n not in table]
    if missing:
        raise InputError(f"{folder / RESULT_TABLE}: no column {missing[0]!r} (the controller needs the states "
                         f"{', '.join(ode.x_names)} and inputs {', '.join(ode.u_names)})")
    t = table["t"]
    keep = np.append(np.diff(t) > 0, True)  # a mesh point written twice (element boundary): the later one
    rows = keep & np.all(np.isfinite(np.column_stack([table[n] for n in ["t"] + ode.x_names + ode.u_names])), axis=1)
    bounds, _ = result_bounds(folder, ode, summary)
    lb, ub = bounds.vectors(list(ode.u_names))
    lb, ub = np.maximum(lb, ode.u_lb), np.minimum(ub, ode.u_ub)
    # the size before the gains are computed: the loop periods and the generated C's tables (x*, u*, K per sample)
    loop_samples(ProblemFile(folder / RESULT_TABLE), "t", float(np.ptp(t[rows])) if rows.any() else 0.0, 0.0, dt,
                 ode.nx + ode.nu + ode.nu * ode.nx)
    controller = tracking_controller(
        ode, t[rows], np.column_stack([table[n][rows] for n in ode.x_names]), np.column_stack([table[n][rows] for n in ode.u_names]),
        dt=dt, Q=Q, R=R, u_lb=lb, u_ub=ub, method=method, substeps=substeps,
    )
    return controller, ode


def result_bounds(result_dir: str | Path, ode: ExplicitODE, summary: dict[str, Any] | None = None) -> tuple[DeclaredBounds, list[str]]:
    """The bounds a result folder's summary records over the model's declared ones, and the notes of its check.

    Parameters
    ----------
    result_dir : str or pathlib.Path
        The result folder.
    ode : ExplicitODE
        Its model (the names kept: states, inputs, algebraic variables and outputs).
    summary : dict, optional
        Its parsed ``summary.json`` (default read from the folder).

    Returns
    -------
    bounds : DeclaredBounds
    notes : list of str
        An unverified result (taken by ``accept_unverified``), input bounds recorded nowhere.

    Raises
    ------
    InputError
        An unreadable ``summary.json``.
    """
    folder = Path(result_dir)
    if summary is None:
        try:
            summary = json.loads((folder / "summary.json").read_text(encoding="utf-8"))
        except (OSError, ValueError) as exc:
            raise InputError(f"{folder / 'summary.json'}: cannot read the result summary ({exc})") from None
    bounds = dae_bounds(ode.dae)
    recorded = summary_bounds(summary, source=f"the result's summary.json ({folder.name})")
    for name in recorded.names:
        bounds.add(name, recorded.lb[name], recorded.ub[name])
    bounds = bounds.restricted(list(ode.x_names) + list(ode.u_names) + list(ode.y_names))
    why = unverified_reason(summary.get("status", ""), summary.get("verification"))
    notes = [] if why is None else [f"reference NOT verified ({why}); accepted by --accept-unverified"]
    unknown = bounds.unknown(list(ode.u_names))
    if unknown:
        notes.append(f"input bounds unknown: {', '.join(unknown)} (recorded by neither the model nor the result's summary): "
                     "their violations are not counted")
    return bounds, notes


def result_loop_setup(result_dir: str | Path, controller: TrackingController, ode: ExplicitODE, parameter_factor: float = 1.0) -> LoopSetup:
    """The closed loop of a result folder's tracking controller: the model itself as the plant.

    The loop of a tracking-controller file's ``[check]`` (:func:`gtmodel.problems.loop_file.loop_setup`)
    without input delay (the result's controller does not compensate one), noise or disturbance,
    the error over all states, and the plant's parameters ``parameter_factor`` times the
    solve's (default 1: the nominal plant).

    Parameters
    ----------
    result_dir : str or pathlib.Path
        The result folder (named in errors).
    controller : TrackingController
        From :func:`tracking_from_result`.
    ode : ExplicitODE
        Its model (the solve's parameter values as defaults).
    parameter_factor : float, optional
        Plant parameters / model parameters.

    Returns
    -------
    LoopSetup
    """
    check = CheckSection(parameter_factor=parameter_factor, delay=0)
    model = LoopModel(ode=ode, plant=ode, plant_p=ode.p_default * parameter_factor, robot=False)
    bounds, notes = result_bounds(result_dir, ode)
    return loop_setup(ProblemFile(Path(result_dir) / "summary.json"), f"tracking of {ode.name}", controller, model, check, controller.dt,
                      bounds=bounds, notes=notes)
