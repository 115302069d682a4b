"""Multiple shooting's honest edges: bounds between the nodes, and failures in one line.

Two jobs of :class:`~gtmodel.modeling.ocp.shooting.ShootingTranscription` kept apart from
its NLP:

* :func:`check_between_nodes`: every declared bound and path constraint is evaluated at
  the integrator's own points inside the intervals (the step ends of ``"rk"``/``"radau"``,
  the stage points of ``"collocation"``) and along a dense re-simulation of the answer
  (CVODES or IDAS, :data:`DENSE_POINTS` samples per interval, interval after interval from
  the initial state under the piecewise inputs). One exceeded by more than
  :data:`BOUND_TOLERANCE` times ``max(1, |bound|)`` makes an ``optimal`` or
  ``acceptable`` result ``check_failed``, its message naming the bound, the time, the value
  and the excess; ``verification.bounds["between_nodes"]`` holds each bounded quantity's
  true peak (issue 64: the radau-shot flexible joint reached 10.315 A between the
  integrator's steps while the summary said 10.0054 A).
* :func:`quiet_casadi` and :func:`failure_message`: CasADi prints the inputs of a function
  that failed (a rootfinder's, an integrator's; about 9 kB on the flexible joint) and its
  own warnings through Python's ``sys.stdout``/``sys.stderr``, and SUNDIALS may write to
  the file descriptors; both are captured (logged at DEBUG, truncated), and a failure
  becomes one line: the stage, the likely cause, the fix.
"""

from __future__ import annotations

import contextlib
import io
import logging
import os
import re
import sys
import tempfile
import time
from collections.abc import Iterator
from typing import Any

import casadi as ca
import numpy as np

from gtmodel.status import Status

__all__ = ["BOUND_TOLERANCE", "DENSE_POINTS", "EVALUATION_STATUSES", "check_between_nodes", "failure_message", "quiet_casadi",
           "clean_casadi_text", "CapturedOutput"]

_log = logging.getLogger("gtmodel")

#: A bound or path constraint is exceeded between the nodes when beyond it by more than this
#: times ``max(1, |bound|)`` (1 %: the issue's criterion, far above the re-simulation's error).
BOUND_TOLERANCE = 1e-2
#: Samples per shooting interval of the dense re-simulation (beside the integrator's own points).
DENSE_POINTS = 40
#: IPOPT's return statuses that follow a function it could not evaluate (with CasADi's error captured).
EVALUATION_STATUSES = ("Invalid_Number_Detected", "Error_In_Step_Computation", "Restoration_Failed", "Internal_Error",
                       "Unrecoverable_Exception", "NonIpopt_Exception_Thrown")
_DUMP = re.compile(r"^(Function \S+ \(0x[0-9a-f]+\)|Input \d+ \(|CasADi - \d{4}-|Error in |\.\.\./casadi/|.*\.cpp:\d+)")
_KEEP_DEBUG = 2000  # characters of captured CasADi text logged at DEBUG


class CapturedOutput:
    """What CasADi wrote while :func:`quiet_casadi` was active.

    Parameters
    ----------
    passthrough : bool
        Forward the lines that are not CasADi's error dumps to the real ``sys.stdout`` as
        they come (a verbose solve's IPOPT log).
    """

    def __init__(self, passthrough: bool) -> None:
        self.passthrough = passthrough
        self._parts: list[str] = []
        self._dumping = False
        self._stdout = sys.stdout

    def write(self, text: str) -> int:
        """Keep ``text``; forward its lines that are not error dumps when passing through.

        Parameters
        ----------
        text : str
            What was written.

        Returns
        -------
        int
            ``len(text)``.
        """
        self._parts.append(text)
        if self.passthrough:
            for line in text.splitlines(keepends=True):
                if _DUMP.match(line) or (self._dumping and line.startswith(("Input ", " "))):
                    self._dumping = True
                    continue
                self._dumping = False
                self._stdout.write(line)
        return len(text)

    def flush(self) -> None:
        """Flush the forwarded stream."""
        if self.passthrough:
            self._stdout.flush()

    def text(self) -> str:
        """Everything captured.

        Returns
        -------
        str
            What was written, as one string.
        """
        return "".join(self._parts)

    def failed_evaluation(self) -> bool:
        """Whether CasADi reported a function that failed.

        Returns
        -------
        bool
            True when the captured text names a failed rootfinder, integrator or evaluation.
        """
        text = self.text()
        return any(key in text for key in ("failed", "Error in Function", "rootfinder", "CV_", "IDA_"))


@contextlib.contextmanager
def quiet_casadi(passthrough: bool = False) -> Iterator[CapturedOutput]:
    """Capture what CasADi (and the C libraries under it) print while the block runs.

    Parameters
    ----------
    passthrough : bool, optional
        Forward what is not an error dump to ``sys.stdout`` (IPOPT's log of a verbose
        solve); default False: everything is kept and logged at DEBUG.

    Yields
    ------
    CapturedOutput
        The captured text (``text()``, ``failed_evaluation()``).
    """
    captured = CapturedOutput(passthrough)
    err = io.StringIO()
    saved, tmp = [], None
    try:  # the file descriptors too (SUNDIALS, MUMPS print with C's stdio); not where there are none (a notebook's kernel)
        tmp = tempfile.TemporaryFile(mode="w+b")
        for fd in (1, 2):
            saved.append((fd, os.dup(fd)))
        sys.stdout.flush()
        sys.stderr.flush()
        for fd, _ in saved:
            if not (passthrough and fd == 1):
                os.dup2(tmp.fileno(), fd)
    except (OSError, ValueError, AttributeError):
        for fd, copy in saved:
            os.close(copy)
        saved = []
    try:
        with contextlib.redirect_stdout(captured), contextlib.redirect_stderr(err):  # type: ignore[type-var]
            yield captured
    finally:
        for fd, copy in saved:
            os.dup2(copy, fd)
            os.close(copy)
        native = ""
        if tmp is not None:
            tmp.seek(0)
            native = tmp.read().decode(errors="replace")
            tmp.close()
        captured._parts.append(err.getvalue() + native)
        text = captured.text()
        if text.strip():
            _log.debug("CasADi wrote (%d characters, captured): %s", len(text), text[:_KEEP_DEBUG])


def failure_message(integrator: str, stage: str, text: str, steps: int) -> str:
    """One line for a failed CasADi evaluation of a shooting solve: the stage, the likely cause, the fix.

    Parameters
    ----------
    integrator : str
        The shooting integrator (``"rk"``, ``"radau"``, ``"collocation"``, ``"cvodes"``, ``"idas"``).
    stage : str
        Where it failed (``"the start"``, ``"iteration 0"``, ``"the returned point"``, ...).
    text : str
        CasADi's error text and what it printed (read for the cause, never repeated).
    steps : int
        The integrator's steps per interval.

    Returns
    -------
    str
        ``"multiple shooting failed at <stage>: <cause>; likely cause: ...; fix: ..."``, one line.
    """
    flag = re.search(r"\b((?:CV|IDA|KIN)_[A-Z_]+)\b", text)
    if "rootfinder" in text or "Newton" in text:
        cause = f"the {integrator} integrator's Newton rootfinder did not converge on a shooting interval"
    elif flag or integrator in ("cvodes", "idas"):
        cause = f"the {integrator} integrator failed on a shooting interval" + (f" ({flag.group(1)})" if flag else "")
    else:
        cause = "a function of the NLP could not be evaluated (NaN, Inf, or a failed integrator)"
    others = ", ".join(f'"{i}"' for i in ("radau", "rk", "collocation", "idas") if i != integrator)
    fix = (f"more transcription.steps (now {steps}) or intervals, another integrator ({others}), or a better initial guess "
           "([initial_guess], e.g. a collocation solution's trajectories.csv)")
    follows = (f"the variable-step {integrator} integrator can follow" if integrator in ("cvodes", "idas") else
               f"{steps} {integrator} step{'s' if steps > 1 else ''} per interval can follow")
    line = (f"multiple shooting failed at {stage}: {cause}; likely cause: the guess or an iterate is far from a trajectory "
            f"that {follows} (stiff or nonlinear dynamics, or a solution that escapes); fix: {fix}")
    return " ".join(line.split())


def clean_casadi_text(text: str) -> str:
    """``text`` without CasADi's source locations, dumps and advice, on one line.

    Parameters
    ----------
    text : str
        A message that may quote a CasADi exception (e.g. a failed verifying simulation's
        ``'.../casadi/interfaces/sundials/cvodes_interface.cpp:403: CVode returned "CV_TOO_MUCH_WORK". Consult CVODES
        documentation.'``).

    Returns
    -------
    str
        The same message with the quoted part reduced to its SUNDIALS or CasADi flag
        (``CVode returned "CV_TOO_MUCH_WORK"``), one line.
    """
    text = re.sub(r"(?:\.\.\./)?casadi/[\w/.-]+\.(?:cpp|hpp):\d+:\s*", "", text)
    text = re.sub(r"\s*(?:Consult \w+ documentation\.|Set 'error_on_fail' option to false to ignore this error\.)", "", text)
    text = re.sub(r"Error in Function::\w+\(\) for '[^']*' \[\w+\] at\s*", "", text)
    return " ".join(text.split())


def _dense_simulation(tr: Any, args: tuple[np.ndarray, np.ndarray, np.ndarray], points: int) -> tuple[np.ndarray, ...] | None:
    """The answer re-simulated from the initial state under its piecewise inputs, ``points`` samples per interval.

    Returns ``(tau (N*points,), k (N*points,), x (nx, K), z (nz, K))`` or None when the simulation fails."""
    problem = tr._guess_problem
    xk, zk, pk = args
    nz_sim = problem["z"].numel() if "z" in problem else 0
    grid = np.linspace(0.0, 1.0, points + 1)[1:]
    try:
        sim = ca.integrator("dense", "idas" if nz_sim else "cvodes", problem, 0.0, grid,
                            {"abstol": 1e-10, "reltol": 1e-8, "max_num_steps": 100000})
    except RuntimeError:
        return None
    x = xk[:, 0]
    z = zk[:, 0] if nz_sim else np.zeros(0)
    xs, zs = [], []
    for k in range(pk.shape[1]):
        try:
            out = sim(x0=x, z0=z if nz_sim else ca.DM(0, 1), p=pk[:, k])
        except RuntimeError:
            return None
        xo = np.array(out["xf"], dtype=float).reshape(-1, points)
        xs.append(xo)
        x = xo[:, -1]
        if nz_sim:
            zo = np.array(out["zf"], dtype=float).reshape(-1, points)
            zs.append(zo)
            z = zo[:, -1]
    n = pk.shape[1]
    x_all = np.hstack(xs)
    if not np.all(np.isfinite(x_all)):
        return None
    z_all = np.hstack(zs) if nz_sim else np.zeros((0, x_all.shape[1]))
    return np.tile(grid, n), np.repeat(np.arange(n), points), x_all, z_all


def check_between_nodes(tr: Any, result: Any, w: np.ndarray, pfull: np.ndarray) -> dict[str, Any] | None:
    """Check every bound and path constraint between the shooting nodes; downgrade an ``optimal`` result that exceeds one.

    Parameters
    ----------
    tr : ShootingTranscription
        The transcription that solved (its check function, bounds, integrator's points).
    result : OptimizationResult
        Its result at ``w``; changed in place: ``verification.bounds["between_nodes"]``
        (when verified), ``status`` ``check_failed`` and ``message`` when a bound is
        exceeded by more than :data:`BOUND_TOLERANCE` relative to ``max(1, |bound|)``.
    w : numpy.ndarray
        The NLP's solution vector.
    pfull : numpy.ndarray
        The NLP's parameters (the model's, then the rootfinder starts).

    Returns
    -------
    dict or None
        The ``between_nodes`` block (None when nothing is bounded or the solve is not verified):
        ``method``, ``tolerance``, ``points``, ``dense_simulation`` (``"passed"`` or why not),
        ``max_violation``, ``max_scaled_violation``, ``variable``, ``at_time_s``, ``value``,
        ``bound``, ``where``, ``within_tolerance``, ``peaks`` (per bounded quantity its
        largest and smallest value and their times) and ``cpu_s`` (the check's CPU time, s).
    """
    lb, ub = tr._check_lb, tr._check_ub
    bounded = np.flatnonzero(np.isfinite(lb) | np.isfinite(ub))
    if not tr.verify or bounded.size == 0 or result.dae is None:
        return None
    cpu = time.process_time()
    dae, N, t0 = tr.dae, tr.intervals, tr.optimization.start_time
    nu, npar = dae.nu, int(dae.p.numel())
    npm = int(dae.p.numel())
    args = tuple(np.array(v, dtype=float) for v in tr._interval_args(w, pfull[:npm]))
    xk, zk, pk = args
    zk = zk.reshape(-1, N) if zk.size else np.zeros((0, N))
    args = (xk, zk, pk)
    tf = float(pk[2 * nu + npar, 0])
    h = (tf - t0) / N

    def inputs(k: np.ndarray, tau: np.ndarray) -> np.ndarray:
        ua, ub_ = pk[:nu][:, k], pk[nu:2 * nu][:, k]
        return ua if tr.controls == "constant" else (1 - tau) * ua + tau * ub_

    sets: list[tuple[str, np.ndarray, np.ndarray, np.ndarray, np.ndarray]] = []  # where, t, x, z, u
    if result.t.size:
        rows_x, rows_u, rows_z = (np.array(result.collocation.evaluate(result.t)[i], dtype=float).T for i in (0, 1, 2))
        sets.append(("the written rows", result.t, rows_x, rows_z, rows_u))
    if tr.stepwise:
        ti, xi, zi, ui = (np.array(v, dtype=float) for v in tr._inner_points(w, pfull))
        if ti.size:
            n = ti.size
            sets.append((f"the {tr.integrator} integrator's steps", ti.reshape(-1), xi.reshape(dae.nx, n), zi.reshape(dae.nz, n),
                         ui.reshape(nu, n)))
    dense = _dense_simulation(tr, args, DENSE_POINTS)
    dense_state = "passed"
    if dense is None:
        dense_state = "failed (the variable-step integrator stopped); checked at the integrator's points only"
    else:
        tau, k, xd, zd = dense
        ud = inputs(k, tau)
        td = t0 + (k + tau) * h
        if dae.nz and not zd.size:  # the explicit form: z(t, x, u, p)
            zfun = ca.Function("z_of", [dae.t, dae.x, dae.u, dae.p], [tr._z_expr]).map(td.size)
            zd = np.array(zfun(td.reshape(1, -1), xd, ud, pk[2 * nu:2 * nu + npar, :1]), dtype=float)
        sets.append(("the dense re-simulation", td, xd, zd, ud))
    pm = pk[2 * nu:2 * nu + npar, 0]
    best = None
    peaks: dict[str, dict[str, float]] = {}
    scale = np.maximum(1.0, np.maximum(np.where(np.isfinite(lb), np.abs(lb), 0.0), np.where(np.isfinite(ub), np.abs(ub), 0.0)))
    n_points = 0
    for where, t, x, z, u in sets:
        if t.size == 0:
            continue
        n_points += t.size
        vals = np.array(tr._check_fn.map(t.size)(t.reshape(1, -1), x, z, u, pm, tf), dtype=float)
        with np.errstate(invalid="ignore"):
            over = np.maximum(vals - ub[:, None], lb[:, None] - vals)
        for i in bounded:
            name = tr._check_names[i]
            j_max, j_min = int(np.nanargmax(vals[i])), int(np.nanargmin(vals[i]))
            peak = peaks.setdefault(name, {"max": -np.inf, "max_at_time_s": 0.0, "min": np.inf, "min_at_time_s": 0.0})
            if vals[i, j_max] > peak["max"]:
                peak.update(max=float(vals[i, j_max]), max_at_time_s=float(t[j_max]))
            if vals[i, j_min] < peak["min"]:
                peak.update(min=float(vals[i, j_min]), min_at_time_s=float(t[j_min]))
            j = int(np.nanargmax(over[i]))
            excess = float(over[i, j])
            if best is None or excess / scale[i] > best["max_scaled_violation"]:
                upper = vals[i, j] > ub[i] if np.isfinite(ub[i]) else False
                best = {"max_violation": max(excess, 0.0), "max_scaled_violation": max(excess, 0.0) / float(scale[i]),
                        "variable": name, "at_time_s": float(t[j]), "value": float(vals[i, j]),
                        "bound": float(ub[i] if upper or not np.isfinite(lb[i]) else lb[i]), "where": where}
    if best is None:
        return None
    best["within_tolerance"] = bool(best["max_scaled_violation"] <= BOUND_TOLERANCE)
    block = {"method": f"bounds and path constraints at the written rows, the integrator's points inside the intervals and a "
                       f"dense re-simulation ({DENSE_POINTS} samples per interval, CVODES/IDAS from the initial state)",
             "tolerance": BOUND_TOLERANCE, "points": n_points, "dense_simulation": dense_state, **best, "peaks": peaks,
             "cpu_s": time.process_time() - cpu}
    v = result.verification
    if v is not None:
        bounds = dict(v.bounds or {})
        bounds["between_nodes"] = block
        top = bounds.get("max_violation")
        if best["variable"].startswith("state ") and (top is None or best["max_violation"] > top):
            # the reported peak is the true one (was the verification's samples at the nodes and written points)
            bounds.update({k: best[k] for k in ("max_violation", "value", "bound", "at_time_s")},
                          variable=best["variable"][len("state '"):-1], max_scaled_violation=best["max_scaled_violation"],
                          within_tolerance=best["within_tolerance"])
        v.bounds = bounds
    if not best["within_tolerance"]:
        remedy = (f"more transcription.steps (now {tr.steps}) or intervals: the bounds are imposed at the integrator's "
                  "points, the trajectory overshoots between them" if tr.stepwise else
                  'integrator = "radau", "rk" or "collocation" imposes the bounds at every integration step; or more intervals')
        side = "upper" if best["value"] > best["bound"] else "lower"
        text = (f"{best['variable']} exceeds its {side} bound {best['bound']:.6g} between the shooting nodes: {best['value']:.6g} "
                f"at t = {best['at_time_s']:.6g} s in {best['where']} (excess {best['max_violation']:.4g}, "
                f"{100 * best['max_scaled_violation']:.3g} % of max(1, |bound|) > {100 * BOUND_TOLERANCE:g} %); likely remedy: {remedy}")
        _log.warning("multiple shooting solve of %s: %s", dae.name, text)
        if result.status in (Status.OPTIMAL, Status.ACCEPTABLE):
            result.status = Status.CHECK_FAILED
        result.message = f"{result.message}; {text}"
    return block
