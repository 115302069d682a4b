"""A tracking-controller file: a declared ``[controller]`` for ``gtmodel codegen --controller FILE.toml --out DIR [--check]``.

A TOML file with three tables, validated on load (pydantic, unknown fields refused; every
error names the file and the field, the CLI exits with 2):

``[controller]``
    ``model`` (a Gantry-Tau parameter set such as ``"L1"``: its rigid-body dynamics with
    friction in TCP states ``T``, ``T_dot`` and input ``tau``; or ``"FILE.py:Class"`` a
    user's model), ``period`` [s] (1e-5 .. 1, default the 4 ms loop), ``method`` and ``substeps``
    (the fixed step whose Jacobians are the linearisation ``A_k``, ``B_k``),
    ``state_weights`` / ``input_weights`` / ``terminal_weights`` (tables by variable name,
    an unknown variable refused, each weight 0 .. 1e12; default Bryson's rule), ``u_lb`` / ``u_ub`` (default: the
    reference problem's bounds, else the model's declared ones), ``time_varying`` (default
    true: the gains of the backward discrete Riccati recursion along the reference; false:
    one time-invariant LQR gain, that of the held end), ``input_delay`` (0 default, or 1:
    the input computed at ``t_k`` acts from ``t_{k+1}``, and the law applies the gain to
    the state predicted then by the model's step from the last input), ``integral_weights``
    (a table by state name: integral action on those states, each weight in (0, 1e12] that of
    its integrated error; default none), ``hold_state_bounds`` (default true: the declared state
    bounds, a motor's current limit, held over the period each input acts,
    :mod:`gtmodel.control.state_limits`).
``[reference]``, ``[check]``
    The motion tracked and the closed loop of ``--check``, as in an MPC file
    (:mod:`gtmodel.problems.loop_file`).

The controller is the feedforward ``u*_k`` plus the time-varying LQR
(:func:`gtmodel.control.tracking.tracking_controller`; Anderson & Moore, Optimal Control:
Linear Quadratic Methods, sec. 2.4), saturated at the input bounds, generated as C through
:func:`gtmodel.codegen.loop_step.tracking_step` (the loop-step interface of the MPC).
"""

from __future__ import annotations

from pathlib import Path

from gtmodel.errors import GtModelError
from gtmodel.control.tracking import limit_noise_gain, tracking_controller
from gtmodel.problems.kinds.schemas.tracking_controller import ControllerSection, TrackingFile
from gtmodel.problems.loop_filter import with_measurement_filter
from gtmodel.problems.loop_file import LoopSetup, loop_inputs, loop_setup, read_loop_file, weight_diagonal

__all__ = ["ControllerSection", "TrackingFile", "load_tracking_file"]


def load_tracking_file(path: str | Path, replan: bool = False) -> LoopSetup:
    """Read, validate and build a tracking-controller file (see the module docstring).

    Parameters
    ----------
    path : str or pathlib.Path
        The TOML file.
    replan : bool, optional
        Solve ``[reference] problem`` even when its plan is cached (``--replan``,
        :mod:`~gtmodel.problems.plan_cache`).

    Returns
    -------
    LoopSetup
        Its :class:`~gtmodel.control.tracking.TrackingController`, the plant of the
        check and the loop options.

    Raises
    ------
    ProblemError
        Naming the file and the field: unreadable TOML, an unknown or invalid field (a
        number not finite or out of its documented range, e.g. a period outside 1e-5..1 s,
        a weight above 1e12, an integral weight not > 0), an unknown variable in a weight
        table, a missing ``[reference]``, too many loop periods or gains in the generated
        C (:func:`~gtmodel.problems.loop_file.loop_samples`), a reference that cannot be
        read or solved, a controller that cannot be built (e.g. a time-invariant LQR where
        the end is not stabilisable), an integral weight of a state the model does not have.
    """
    doc, file = read_loop_file(path, "tracking_controller")
    c = doc.controller
    ni = len(c.integral_weights)
    i = loop_inputs(file, doc, "controller", per_sample=lambda ode: ode.nx + ode.nu + ode.nu * (ode.nx + ni),  # x*, u*, K, Ki per sample
                    before_reference=lambda model: weight_diagonal(file, "controller.integral_weights", c.integral_weights, list(model.ode.x_names)),
                    replan=replan)
    try:
        controller = tracking_controller(i.model.ode, i.t, i.x_ref, i.u_ref, dt=c.period, Q=i.Q, R=i.R, Qf=i.Qf, u_lb=i.u_lb, u_ub=i.u_ub,
                                         method=c.method, substeps=c.substeps, time_varying=c.time_varying, delay=c.input_delay,
                                         integral_weights=c.integral_weights or None,
                                         state_bounds={n: (i.bounds.lb[n], i.bounds.ub[n]) for n in i.bounds.lb} if c.hold_state_bounds else None)
    except GtModelError as exc:
        raise file.wrap("controller", exc) from None
    controller = with_measurement_filter(file, "controller.measurement_noise", controller, c.measurement_noise, doc.check.noise, i.model.ode)
    if c.noise_gain_limit and controller.state_filter is not None:  # the noise the law's filter assumes
        controller = limit_noise_gain(controller, controller.state_filter.sigma, c.noise_gain_limit)
    return loop_setup(file, doc.name, controller, i.model, doc.check, c.period, bounds=i.bounds, notes=i.notes)
