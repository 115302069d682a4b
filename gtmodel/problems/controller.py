"""A tracking controller from an ``optimal_control`` result folder (``gtmodel codegen --controller RESULT_DIR``).

The folder a ``gtmodel solve`` of an ``optimal_control`` problem wrote holds
``summary.json`` (the model file and class, the parameter values of the solve, the problem
file) and ``trajectories.csv`` (the optimal states and inputs by scalar name on the
collocation mesh). :func:`tracking_from_result` rebuilds the model, reduces it to its
explicit ODE (:func:`gtmodel.modeling.explicit_ode`) with the solve's parameter values,
takes the input bounds of the problem file's ``[bounds]`` (numbers; intersected with the
model's declared bounds) and builds the feedforward + time-varying LQR controller of
:func:`gtmodel.estimation.tracking.tracking_controller` at the loop period.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import numpy as np

from gtmodel._tables import read_table
from gtmodel._toml import read_toml
from gtmodel.defaults import LOOP_PERIOD_S
from gtmodel.errors import InputError, ProblemError
from gtmodel.estimation.tracking import TrackingController, tracking_controller
from gtmodel.modeling import ExplicitODE, explicit_ode
from gtmodel.problems.base import ProblemFile
from gtmodel.problems.loop_file import CheckSection, LoopModel, LoopSetup, loop_samples, loop_setup
from gtmodel.problems.user_model import load_user_model

__all__ = ["RESULT_TABLE", "is_result_folder", "tracking_from_result", "result_loop_setup"]

#: The table of an ``optimal_control`` result folder.
RESULT_TABLE = "trajectories.csv"
_SOLVED = ("optimal", "acceptable")


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


def _bounds(problem: Path, ode: ExplicitODE) -> tuple[np.ndarray, np.ndarray]:
    """Input bounds: the model's, intersected with the problem file's numeric ``[bounds]``."""
    lb, ub = ode.u_lb.copy(), ode.u_ub.copy()
    if not problem.is_file():
        return lb, ub
    bounds = read_toml(problem, ProblemError, "problem file").get("bounds", {})
    for j, name in enumerate(ode.u_names):
        pair = bounds.get(name, bounds.get(name.split("[", 1)[0]))
        if pair is None:
            continue
        values = [float(v) if not isinstance(v, str) else {"inf": math.inf, "-inf": -math.inf}.get(v.strip().lower(), math.nan) for v in pair]
        if len(values) != 2 or any(math.isnan(v) for v in values):
            raise InputError(f"{problem}: [bounds] {name}: expected two numbers for the controller's saturation, got {pair!r}")
        lb[j], ub[j] = max(lb[j], values[0]), min(ub[j], values[1])
    return lb, ub


def tracking_from_result(
    result_dir: str | Path,
    dt: float = LOOP_PERIOD_S,
    method: str = "rk4",
    substeps: int = 1,
    Q: Any = None,
    R: Any = None,
) -> tuple[TrackingController, ExplicitODE]:
    """Feedforward + time-varying LQR along the optimal motion of an ``optimal_control`` result.

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
        :func:`~gtmodel.estimation.tracking.tracking_controller`).

    Returns
    -------
    controller : TrackingController
    ode : ExplicitODE
        The model's explicit ODE with the solve's parameter values as defaults.

    Raises
    ------
    InputError
        Not an ``optimal_control`` result of a solved problem, a missing table or column,
        non-numeric bounds.
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
    if summary.get("kind") != "optimal_control":
        raise InputError(f"{summary_file}: kind: expected an optimal_control result, got {summary.get('kind')!r}")
    if summary.get("status") not in _SOLVED:
        raise InputError(f"{summary_file}: status: expected a solved problem ({' or '.join(_SOLVED)}), got {summary.get('status')!r}")
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
    lb, ub = _bounds(Path(summary.get("problem", "")), ode)
    # the size before the gains are computed: the loop periods and the generated C's tables (x*, u*, K per sample)
    loop_samples(ProblemFile(folder / RESULT_TABLE), "t", float(np.ptp(t[rows])) if rows.any() else 0.0, 0.0, dt,
                 ode.nx + ode.nu + ode.nu * ode.nx)
    controller = tracking_controller(
        ode, t[rows], np.column_stack([table[n][rows] for n in ode.x_names]), np.column_stack([table[n][rows] for n in ode.u_names]),
        dt=dt, Q=Q, R=R, u_lb=lb, u_ub=ub, method=method, substeps=substeps,
    )
    return controller, ode


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
    return loop_setup(ProblemFile(Path(result_dir) / "summary.json"), f"tracking of {ode.name}", controller, model, check, controller.dt)
