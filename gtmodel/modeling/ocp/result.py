"""Results of optimal control solves (in the style of python-control's OptimalControlResult).

Trajectories are stored at the collocation mesh; :meth:`OptimizationResult.sample` and
:meth:`OptimizationResult.resample` evaluate the collocation polynomials elsewhere:
states through the ``d + 1`` points of an element (its start and the ``d`` collocation
points), inputs and algebraic variables through the ``d`` collocation points. A time on
an element boundary is evaluated with the element to its left (``tau = 1``), except the
start time, which uses the first element at ``tau = 0`` (an extrapolation for inputs and
algebraics).
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Mapping

import numpy as np

from gtmodel.errors import GtModelError, InputError
from gtmodel.status import Status, StatusResult
from gtmodel.modeling.dae import FlatDAE, _columns, _eval_outputs, _frame, _unpack, _write_columns

__all__ = ["OptimizationResult", "CollocationData", "normalize_ipopt_status", "lagrange_basis"]

_log = logging.getLogger("gtmodel")

_IPOPT_STATUS = {
    "Solve_Succeeded": Status.OPTIMAL,
    "Solved_To_Acceptable_Level": Status.ACCEPTABLE,
    "Feasible_Point_Found": Status.ACCEPTABLE,
    "Infeasible_Problem_Detected": Status.INFEASIBLE,
    "Maximum_Iterations_Exceeded": Status.MAX_ITERATIONS,
    "Maximum_CpuTime_Exceeded": Status.MAX_ITERATIONS,
    "Maximum_WallTime_Exceeded": Status.MAX_ITERATIONS,
}


#: What an IPOPT failure means and what to try, appended to the result's message.
IPOPT_HINTS = {
    "Restoration_Failed": "IPOPT's feasibility restoration could not reduce the constraint violation: infeasible or degenerate "
                          "constraints (e.g. bounds duplicating an equality such as u1^2 + u2^2 = 1) or a guess far from feasible",
    "Search_Direction_Becomes_Too_Small": "IPOPT's steps became too small: often scaling (set nominal values)",
}


def normalize_ipopt_status(return_status: str) -> Status:
    """Map an IPOPT ``return_status`` string to a gtmodel status.

    Parameters
    ----------
    return_status : str
        IPOPT's return status, e.g. ``"Solve_Succeeded"``.

    Returns
    -------
    Status
        One of ``"optimal"`` (Solve_Succeeded), ``"acceptable"``
        (Solved_To_Acceptable_Level, Feasible_Point_Found), ``"infeasible"``
        (Infeasible_Problem_Detected), ``"max_iterations"`` (iteration, CPU- or
        wall-time limit) and ``"error"`` for everything else (Restoration_Failed,
        Invalid_Number_Detected, Search_Direction_Becomes_Too_Small, exceptions, ...).
    """
    return _IPOPT_STATUS.get(str(return_status), Status.ERROR)


def lagrange_basis(nodes: np.ndarray, tau: np.ndarray) -> np.ndarray:
    """Values of the Lagrange basis polynomials through ``nodes`` at points ``tau``.

    Parameters
    ----------
    nodes : numpy.ndarray
        Distinct interpolation nodes, shape ``(m,)``.
    tau : numpy.ndarray
        Evaluation points, shape ``(K,)``.

    Returns
    -------
    numpy.ndarray
        Shape ``(K, m)``; row ``i`` holds ``l_j(tau_i)``.
    """
    nodes = np.asarray(nodes, dtype=float).reshape(-1)
    tau = np.asarray(tau, dtype=float).reshape(-1)
    out = np.ones((tau.size, nodes.size))
    for j in range(nodes.size):
        for r in range(nodes.size):
            if r != j:
                out[:, j] *= (tau - nodes[r]) / (nodes[j] - nodes[r])
    return out


@dataclass
class CollocationData:
    """Collocation polynomial data of a solution (used for sampling).

    Parameters
    ----------
    t0, tf : float
        Start and final time, s.
    elements : int
        Number of elements ``N``.
    points : int
        Collocation points per element ``d``.
    scheme : str
        ``"radau"`` or ``"legendre"``.
    tau_root : numpy.ndarray
        ``[0, tau_1, ..., tau_d]`` on the unit element, shape ``(d + 1,)``.
    xc : numpy.ndarray
        State values at ``tau_root`` per element, shape ``(N, d + 1, nx)``.
    uc : numpy.ndarray
        Input values at the collocation points, shape ``(N, d, nu)``.
    zc : numpy.ndarray
        Algebraic values at the collocation points, shape ``(N, d, nz)``.
    fractions : numpy.ndarray or None, optional
        Element lengths as fractions of the horizon, shape ``(N,)``, summing to 1;
        ``None`` for a uniform mesh.
    shooting : str or None, optional
        ``None`` for collocation polynomials; for a multiple-shooting result the input
        parametrisation (``"constant"`` or ``"linear"``): ``xc`` then holds the node
        states and the integrated states at ``tau_root[1:]`` (samples of the integrated
        trajectory, not a polynomial), ``uc`` the inputs there.
    zn, un : numpy.ndarray or None, optional
        Multiple shooting: the algebraic variables and inputs at each interval's start
        (its node), shapes ``(N, nz)`` and ``(N, nu)``; :meth:`evaluate` then interpolates
        them with the samples (the start row consistent with the start state, not
        extrapolated from the interval's samples). None otherwise.
    """

    t0: float
    tf: float
    elements: int
    points: int
    scheme: str
    tau_root: np.ndarray
    xc: np.ndarray
    uc: np.ndarray
    zc: np.ndarray
    fractions: np.ndarray | None = None
    shooting: str | None = None
    zn: np.ndarray | None = None
    un: np.ndarray | None = None

    def breaks(self) -> np.ndarray:
        """Element boundaries ``t_0 < t_1 < ... < t_N = tf``.

        Returns
        -------
        numpy.ndarray
            Times, s, shape ``(N + 1,)``.
        """
        span = self.tf - self.t0
        if self.fractions is None:
            return self.t0 + span * np.arange(self.elements + 1) / self.elements
        cum = np.concatenate([[0.0], np.cumsum(self.fractions)])
        cum[-1] = 1.0
        return self.t0 + span * cum

    def mesh(self) -> np.ndarray:
        """Collocation mesh: start time, interior collocation points and element ends.

        Returns
        -------
        numpy.ndarray
            Increasing times, s, shape ``(K,)``.
        """
        inner = [c for c in self.tau_root[1:] if c < 1.0 - 1e-12]
        local = np.array(inner + [1.0])
        if self.fractions is None:
            h = (self.tf - self.t0) / self.elements
            ts = [np.array([self.t0])]
            for k in range(self.elements):
                ts.append(self.t0 + (k + local) * h)
            return np.concatenate(ts)
        b = self.breaks()
        return np.concatenate([[self.t0], (b[:-1, None] + local[None, :] * np.diff(b)[:, None]).reshape(-1)])

    def point_kinds(self) -> np.ndarray:
        """What each time of :meth:`mesh` is in the transcription.

        Returns
        -------
        numpy.ndarray of str
            Shape ``(K,)``: ``"start"`` (the start time, no collocation point: states as
            solved, inputs the first element's polynomial, algebraic variables consistent
            with them), ``"collocation"`` (an interior collocation point),
            ``"collocation_boundary"`` (an element end that is a collocation point: Radau),
            ``"boundary"`` (an element end that is none: Legendre; inputs the element's
            polynomial, algebraic variables consistent with them).
        """
        inner = sum(1 for c in self.tau_root[1:] if c < 1.0 - 1e-12)
        end = "collocation_boundary" if inner < len(self.tau_root) - 1 else "boundary"
        per = np.array(["collocation"] * inner + [end])
        return np.concatenate([np.array(["start"]), np.tile(per, self.elements)]).astype("<U20")

    def evaluate(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Evaluate the collocation polynomials.

        Parameters
        ----------
        t : numpy.ndarray
            Times within ``[t0, tf]``, s, shape ``(K,)``.

        Returns
        -------
        tuple of numpy.ndarray
            ``(x, u, z)`` of shapes ``(K, nx)``, ``(K, nu)``, ``(K, nz)``.

        Raises
        ------
        InputError
            If a time lies outside the horizon.
        """
        t = np.asarray(t, dtype=float).reshape(-1)
        span = self.tf - self.t0
        tol = 1e-9 * max(1.0, abs(span))
        if np.any(~np.isfinite(t)) or np.any(t < self.t0 - tol) or np.any(t > self.tf + tol):
            raise InputError(f"sample times must lie in [{self.t0}, {self.tf}]")
        if self.fractions is None:
            h = span / self.elements
            s = (t - self.t0) / h
            k = np.clip(np.ceil(s - 1e-9) - 1, 0, self.elements - 1).astype(int)
            tau = np.clip(s - k, 0.0, 1.0)
        else:
            b = self.breaks()
            hb = np.diff(b)
            k = np.clip(np.searchsorted(b, t - 1e-9 * hb.min(), side="left") - 1, 0, self.elements - 1)
            tau = np.clip((t - b[k]) / hb[k], 0.0, 1.0)
        nx, nu, nz = self.xc.shape[2], self.uc.shape[2], self.zc.shape[2]
        xs, us, zs = np.zeros((t.size, nx)), np.zeros((t.size, nu)), np.zeros((t.size, nz))
        lx = lagrange_basis(self.tau_root, tau)
        lu = lagrange_basis(self.tau_root[1:], tau)
        # multiple shooting: inputs and algebraic variables through the node values too
        uc = self.uc if self.un is None else np.concatenate([self.un[:, None, :], self.uc], axis=1)
        zc = self.zc if self.zn is None else np.concatenate([self.zn[:, None, :], self.zc], axis=1)
        bu = lu if self.un is None else lx
        bz = lu if self.zn is None else lx
        for i in range(t.size):
            xs[i] = lx[i] @ self.xc[k[i]]
            if nu:
                us[i] = bu[i] @ uc[k[i]]
            if nz:
                zs[i] = bz[i] @ zc[k[i]]
        return xs, us, zs


@dataclass
class OptimizationResult(StatusResult):
    """Result of an optimal control solve.

    Implements :class:`gtmodel.status.SolverResult`: :attr:`success` is True only if
    ``status == "optimal"``.

    Parameters
    ----------
    status : Status
        ``"optimal"``, ``"acceptable"``, ``"infeasible"``, ``"max_iterations"`` or
        ``"error"`` (see :func:`normalize_ipopt_status`); keyword only.
    message : str
        IPOPT's ``return_status`` text, or the exception message on errors; keyword only.
    iterations : int
        IPOPT iterations.
    solve_time : float
        Wall-clock time of the NLP solve, s.
    objective : float
        Objective value at the returned point.
    final_time : float
        Final time, s (optimised when free).
    max_constraint_violation : float
        Largest violation of ``lbg <= g(w) <= ubg`` and ``lbw <= w <= ubw`` at the
        returned point (0 if all hold; NaN if the constraints evaluate to NaN).
    t : numpy.ndarray
        Collocation mesh, s, shape ``(K,)``.
    states, inputs, algebraics, outputs : dict of str to numpy.ndarray
        Declared name -> values on the mesh, ``(K,)`` or ``(K, n)``.
    parameters : dict of str to numpy.ndarray
        Parameter values used.
    last_iterate : bool
        True when the trajectories are IPOPT's last iterate of a solve that did not
        reach "optimal" or "acceptable" (not a solution).
    stats : dict
        Raw solver statistics.
    collocation : CollocationData or None
        Polynomial data used by :meth:`sample`.
    dae : FlatDAE or None
        Flattened model (for outputs when sampling).
    w : numpy.ndarray or None
        Raw NLP decision vector (for warm starts).
    transcription_key : tuple or None
        Identifies the transcription that produced ``w``.
    lam_w, lam_g : numpy.ndarray or None
        Multipliers of the bounds of ``w`` and of the constraints (for warm starts).
    verification : Verification or None
        The check of the solution by simulation
        (:class:`gtmodel.modeling.ocp.verification.Verification`); None when not verified
        (a failed solve, or ``verify=False``).
    refinement : list of dict
        The mesh refinement passes that led to this result (elements, objective, error
        per pass; :mod:`gtmodel.modeling.ocp.refinement`), empty without refinement.
    timing : dict
        Wall and CPU seconds per phase of the run that produced it, ``phase ->
        {"wall_s", "cpu_s"}`` (:mod:`gtmodel._timing`: ``build``, ``guess``, ``solve`` (the
        solver's call, as :attr:`solve_time`), ``verification``, ...); empty when not timed.
    warnings : list of str
        What the transcription found wrong with the returned solution that its status does
        not say (multiple shooting: a bound or path constraint exceeded between the
        shooting nodes, a stage Newton iteration that did not converge); the problem kinds
        print them and write them to ``summary.json`` (``warnings``).
    refinement_stop : str
        Why the refinement ended and which pass it returned (``""`` without refinement).
    continuation : dict
        The continuation over the model's smoothing widths that led to this result
        (:func:`gtmodel.modeling.ocp.continuation.record_final`: the steps, the widths each element
        ended at, the objective's change over the last step); empty without one.
    """

    iterations: int
    solve_time: float
    objective: float
    final_time: float
    max_constraint_violation: float
    t: np.ndarray
    states: dict[str, np.ndarray]
    inputs: dict[str, np.ndarray]
    algebraics: dict[str, np.ndarray]
    outputs: dict[str, np.ndarray]
    parameters: dict[str, np.ndarray] = field(default_factory=dict)
    last_iterate: bool = False
    stats: dict[str, Any] = field(default_factory=dict)
    collocation: CollocationData | None = field(default=None, repr=False)
    dae: FlatDAE | None = field(default=None, repr=False)
    w: np.ndarray | None = field(default=None, repr=False)
    transcription_key: tuple | None = field(default=None, repr=False)
    lam_w: np.ndarray | None = field(default=None, repr=False)
    lam_g: np.ndarray | None = field(default=None, repr=False)
    verification: Any = field(default=None, repr=False)
    refinement: list[dict[str, Any]] = field(default_factory=list, repr=False)
    timing: dict[str, dict[str, float]] = field(default_factory=dict, repr=False)
    warnings: list[str] = field(default_factory=list, repr=False)
    refinement_stop: str = ""
    continuation: dict[str, Any] = field(default_factory=dict, repr=False)

    def sample(self, t: Any) -> dict[str, Any]:
        """Evaluate the solution at given times with the collocation polynomials.

        Parameters
        ----------
        t : array_like
            Times within ``[start_time, final_time]``, s, shape ``(K,)``.

        Returns
        -------
        dict
            ``{"t": (K,), "states": {...}, "inputs": {...}, "algebraics": {...},
            "outputs": {...}}`` with ``(K,)`` or ``(K, n)`` arrays per declared name.

        Raises
        ------
        InputError
            If no polynomial data is available or a time is outside the horizon.
        """
        if self.collocation is None or self.dae is None:
            raise InputError("this result holds no collocation data to sample")
        tt = np.asarray(t, dtype=float).reshape(-1)
        xs, us, zs = self.collocation.evaluate(tt)
        pv = self.dae.parameter_vector(self.parameters)
        return {
            "t": tt,
            "states": _unpack(self.dae.x_vars, xs),
            "inputs": _unpack(self.dae.u_vars, us),
            "algebraics": _unpack(self.dae.z_vars, zs),
            "outputs": _eval_outputs(self.dae, tt, xs, zs, us, pv),
        }

    def resample(self, dt: float) -> dict[str, Any]:
        """Sample the solution on the uniform grid ``t0, t0 + dt, ...`` (up to ``tf``).

        Parameters
        ----------
        dt : float
            Sample period, s (e.g. :data:`gtmodel.defaults.LOOP_PERIOD_S` for the 4 ms controller). The grid ends at the
            last multiple of ``dt`` not after the final time (within 1e-9 dt).

        Returns
        -------
        dict
            As :meth:`sample`.

        Raises
        ------
        InputError
            If ``dt`` is not positive or no polynomial data is available.
        """
        if self.collocation is None:
            raise InputError("this result holds no collocation data to sample")
        dt = float(dt)
        if not dt > 0 or not np.isfinite(dt):
            raise InputError(f"dt must be positive, got {dt}")
        t0, tf = self.collocation.t0, self.collocation.tf
        n = int(np.floor((tf - t0) / dt + 1e-9)) + 1
        return self.sample(t0 + dt * np.arange(n))

    def plot(self, *args: Any, **kwargs: Any) -> Any:
        """Moved to the report layer: ``gtmodel.report.plot_result(result, *names, ...)``.

        The modelling layer never draws (nor imports the report layer that does); the
        plot of a result is :func:`gtmodel.report.plot_result`, with the same arguments
        after the result.

        Parameters
        ----------
        *args, **kwargs : Any
            Not used.

        Raises
        ------
        GtModelError
            Always, naming the function that draws a result.
        """
        raise GtModelError("result.plot() moved to the report layer: from gtmodel.report import plot_result; "
                           "plot_result(result, *names, bounds=..., units=..., path=..., title=...)")

    def _point_kinds(self) -> np.ndarray | None:
        """The kind of each time of :attr:`t` (:meth:`CollocationData.point_kinds`), None without collocation data."""
        if self.collocation is None:
            return None
        kinds = self.collocation.point_kinds()
        return kinds if kinds.size == np.size(self.t) else None

    def to_dataframe(self, dt: float | None = None) -> Any:
        """Trajectories as a pandas DataFrame.

        Parameters
        ----------
        dt : float, optional
            If given, resample uniformly with this period (s); else use the mesh.

        Returns
        -------
        pandas.DataFrame
            Column ``"t"``, on the mesh a column ``"point"`` (what each time is:
            :meth:`CollocationData.point_kinds`), then one column per scalar element of states, inputs,
            algebraics and outputs (``"T[0]"`` style names for vectors).
        """
        if dt is None:
            frame = _frame(self.t, self.states, self.inputs, self.algebraics, self.outputs)
            if self._point_kinds() is not None:
                frame.insert(1, "point", self._point_kinds())
            return frame
        s = self.resample(dt)
        return _frame(s["t"], s["states"], s["inputs"], s["algebraics"], s["outputs"])

    def to_csv(self, path: str | Path, dt: float | None = None, units: Mapping[str, str] | None = None) -> Path:
        """Write the trajectories to a CSV file (header row, SI units).

        Parameters
        ----------
        path : str or pathlib.Path
            Output file.
        dt : float, optional
            Uniform sample period, s; default the collocation mesh.
        units : Mapping[str, str], optional
            Variable name (scalar, ``"ind.i"``, or its vector's, ``"T"`` for ``"T[0]"``) -> unit
            (e.g. ``model.units``): the header then names each column's unit, ``ind.i [A]``,
            and time's, ``t [s]`` (:func:`gtmodel._tables.split_unit` reads them back);
            default plain names.

        Returns
        -------
        pathlib.Path
            The written file.
        """
        p = Path(path)
        if dt is None:
            cols = _columns(self.t, self.states, self.inputs, self.algebraics, self.outputs)
            if self._point_kinds() is not None:
                cols = {"t": cols.pop("t"), "point": self._point_kinds(), **cols}
        else:
            s = self.resample(dt)
            cols = _columns(s["t"], s["states"], s["inputs"], s["algebraics"], s["outputs"])
        if units is not None:
            units = {c: units.get(c, units.get(c.split("[", 1)[0])) for c in cols if c != "point"} | {"t": "s"}
        _write_columns(p, cols, units)  # the columns of to_dataframe(dt), without importing pandas
        return p
