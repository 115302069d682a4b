"""One place for gtmodel's defaults: loop period, plot style, solver options.

In the style of python-control's ``control.config.defaults``: :data:`defaults` is a
documented dict of dotted keys that the functions read when they are called, so a notebook
can change a default for a session and :func:`reset_defaults` puts every key back::

    >>> from gtmodel import defaults
    >>> defaults.defaults["plot.dpi"] = 200      # sharper PNGs for this session
    >>> defaults.reset_defaults()
    >>> defaults.defaults["plot.dpi"]
    110

Keys
----
``loop.period``
    Period of the robot controller's loop [s] (Dressler (2012), ch. 3.2: 4 ms on the L1).
    Where a robot is known, its data file gives the period (the actuator models' sample
    time ``[actuators] sample_time_s`` of ``gtmodel/robots/data/<robot>_dynamics_models.toml``,
    :func:`gtmodel.robots.actuator_dynamics.loop_period`); this is the fallback, and the
    default argument of every function that samples at the loop (bound when the function's
    module is imported, so changing the key later does not change those defaults).
``plot.dpi``
    Resolution of every PNG the report layer writes [dots per inch].
``plot.figsize``
    Size of a one-panel figure [in] (width, height).
``plot.wide``, ``plot.tall``, ``plot.panel``
    Sizes [in] of a row of three panels, of a column of three panels, and of one panel in a
    row of per-case panels (width per panel, height).
``plot.layout``
    Matplotlib layout engine of new figures.
``nlp.max_iter``, ``nlp.tol``
    Iteration limit and tolerance of every NLP solver (IPOPT, fatrop) before the problem's
    own ``solver_options``.
``ipopt.options``
    Further IPOPT options of every collocation NLP (``solver_options`` override them).
    ``mumps_mem_percent``: MUMPS's workspace is its estimate plus this percentage (IPOPT's
    default 1000 allocates eleven times the estimate for every fresh solver; when a
    factorisation needs more, IPOPT doubles it and factorises again, so the iterates are the
    same). L1 minimum-time problem, fresh solver, quiet machine (issue 17): 139 -> 98 ms per
    iteration at 400 elements, 11.4 -> 10.5 at 50, the same 93 and 49 iterations and final
    times. 0 is not allowed: doubling 0 stays 0, and the solve fails.
``ocp.verification_tolerance``
    Tolerance of the verification of every collocation solution
    (:mod:`gtmodel.modeling.ocp.verification`): the largest deviation of a state's
    simulation under the optimal inputs from the transcribed state, scaled by
    ``max(1, max |x|)``; a solution beyond it is ``check_failed``, never ``optimal``.
    An :class:`~gtmodel.modeling.Optimization` may set its own (a problem file:
    ``[transcription] tolerance``). 1e-2 flags spurious minima of the NLP (the COPS
    hanging chain on 20 elements: 0.24) and keeps the shipped L1 motions on the thesis'
    50-element mesh, whose bang-bang forces switch inside elements (largest deviation
    3.6e-3 to 4.0e-3 of the TCP velocity); ask for 1e-3 or less with ``refine``.
``ocp.input_regularization``
    Weight ``varepsilon`` of the input energy that mesh refinement adds to a minimum-time objective from
    its second pass on (:mod:`gtmodel.modeling.ocp.regularization`; a problem file: ``[transcription]
    regularization``, 0 off), each input scaled by its RMS in the previous pass: the minimum time
    rises by about this fraction per input. 1e-3: the drive family's belt drive0_38, whose
    voltage rang on its current's bound arc and whose refinement sawed unverified for 21 passes
    (97 CPU-s), verifies in 14 (25 CPU-s); with 1e-4 it still sawed.
``ocp.refine_max_cpu_s``
    Budget of CPU time [s] of a mesh refinement
    (:func:`gtmodel.modeling.ocp.refinement.solve_refined`; a problem file:
    ``[transcription] max_cpu_s``): no pass starts once it is spent or the last pass's
    cost would overrun it, and the best verified pass is returned. 290 s: issue 64 allows a drive
    family member at most 300 CPU-s, and the run outside the refinement (loading, building,
    writing) costs a few. The family's ball screw ``drive0_33`` (a 155 Hz coupling mode behind a
    0.14 mm gap) verified at 168 CPU-s on 876 elements on one machine, where the former 100 s
    stopped it at pass 9 of 9, its deviations passed but the current 2.8 % over its limit between
    the points; on the 2-core machine of 2026-11-27 its same 13 passes cost 210 CPU-s alone and
    30-45 % more each beside two reference solves, where 250 s stopped it after 12 (238 CPU-s,
    the current 1.2 % over its limit). The drive models of ``problems/drive_*.toml`` end their refinement verified in 2
    to 66 CPU-s alone, within the 120 CPU-s of issue 49; on a loaded 2-core machine (CI's slow
    run, two test workers) the flexible joint's 13 passes cost 90 CPU-s.
``ocp.refine_max_passes``
    Limit on the solves of a mesh refinement (a problem file: ``[transcription]
    max_passes``); the CPU budget above usually ends a refinement that does not converge
    first. 30: the flexible-joint drive (``problems/drive_flexible_joint.toml``) keeps its
    current limit between the collocation points at pass 13 (69 CPU-s), where 10 passes
    end with the limit exceeded by 1.6 % (the other drives need 6 or 7 passes); the drive
    family's ``drive0_29`` (issue 64) ends verified at pass 17 of 18 in 25.6 CPU-s, where 16
    passes (19 CPU-s) stopped with the current 1.7 % over its limit between the points: the
    pass limit, not the CPU budget, had stopped it.
``ocp.refine_objective_tolerance``
    A mesh refinement whose pass is verified, ``optimal`` and has nothing left to split
    solves once more on that mesh with every element halved, and goes on refining from it
    while that improves the objective by more than this fraction (a problem file:
    ``[transcription] objective_tolerance``; 0: no such check). 1e-3: a held-out
    minimum-time drive with a 600 Hz compliant coupling verified at 90 elements 0.45 %
    above its optimum (the coarse mesh smooths the coupling that the optimum exploits);
    the halved mesh gains 0.30 % there, and the shipped L1 motion and drives change
    by less than this.
``ipopt.warm_start``
    IPOPT options of warm starts: start from the given primal-dual point with a small
    barrier parameter and without pushing it off the bounds.
"""

from __future__ import annotations

import copy
from typing import Any

from gtmodel.errors import InputError

__all__ = ["LOOP_PERIOD_S", "NOISE_GAIN_LIMIT", "REST_NEIGHBOURHOOD", "REAL_TYPES", "FRICTION_FORMS", "DEFAULT_FRICTION_WIDTH", "PATH_METHODS", "STANDARD_GRAVITY", "INTERFACE_PORTS", "defaults", "reset_defaults", "get"]

#: Period of the controller loop [s], the fallback where no robot data file is at hand
#: (Dressler (2012), ch. 3.2: the L1's 4 ms loop). The one place this number is written.
LOOP_PERIOD_S = 0.004
#: A tracking law's largest one-sigma response of an input to the measurement noise, over the input's half range
#: (:func:`gtmodel.control.tracking.limit_noise_gain`, a tracking-controller file's ``noise_gain_limit``).
NOISE_GAIN_LIMIT = 0.1
#: The neighbourhood of a rest point in which a tracking law's gain there must be stable, over each state's range along
#: the reference (:func:`gtmodel.control.lqr.rest_linearization`: a regularised friction's slope at zero speed is
#: not a damping the loop keeps).
REST_NEIGHBOURHOOD = 0.1
#: Selectable floating-point types of generated code (``real=``; CasADi's ``casadi_real``).
REAL_TYPES = ("double", "float")
#: The selectable forms of the sign function of the friction model, and the default
#: velocity width [m/s] of the smooth ("tanh") and piecewise-linear forms: those of
#: :mod:`gtmodel.robots.friction` (equal, checked by the tests), here so that problem
#: schemas name them without importing the dynamics.
FRICTION_FORMS = ("exact", "tanh", "piecewise")
DEFAULT_FRICTION_WIDTH = 0.01
#: Methods of kind ``path_constrained``: the convex reformulation (Verscheure et al.
#: (2009), solved to the exact optimum of the gridded problem) and the thesis' projection
#: solved by collocation (Dressler (2012), ch. 3.5); :mod:`gtmodel.trajectory.path_constrained`.
PATH_METHODS = ("convex", "collocation")
#: Standard gravity [m/s^2] (that of :mod:`gtmodel.estimation.closed_loop.plant`, equal,
#: checked by the tests; here for the problem schemas' defaults).
STANDARD_GRAVITY = 9.80665
#: The robot interfaces' usual UDP ports, where the sensor side listens and the robot sends:
#: KUKA RSI's 49152 (the Ethernet object's ``PORT`` in KUKA's examples) and ABB EGM's 6510
#: (the UC device's remote port in ABB's examples); for the loop files' schema and the runtime.
INTERFACE_PORTS = {"rsi": 49152, "egm": 6510}

_FACTORY: dict[str, Any] = {
    "loop.period": LOOP_PERIOD_S,
    "plot.dpi": 110,
    "plot.figsize": (7.0, 4.0),
    "plot.wide": (11.0, 3.6),
    "plot.tall": (8.0, 6.5),
    "plot.panel": (4.4, 3.4),
    "plot.layout": "constrained",
    "nlp.max_iter": 3000,
    "nlp.tol": 1e-8,
    "ipopt.options": {"mumps_mem_percent": 20},
    "ocp.verification_tolerance": 1e-2,
    "ocp.input_regularization": 1e-3,
    "ocp.refine_max_cpu_s": 290.0,
    "ocp.refine_max_passes": 30,
    "ocp.refine_objective_tolerance": 1e-3,
    "ipopt.warm_start": {
        "warm_start_init_point": "yes",
        "mu_init": 1e-4,
        "warm_start_bound_push": 1e-9,
        "warm_start_bound_frac": 1e-9,
        "warm_start_slack_bound_push": 1e-9,
        "warm_start_slack_bound_frac": 1e-9,
        "warm_start_mult_bound_push": 1e-9,
    },
}

#: The defaults in force, by dotted key (see the module docstring for each key).
defaults: dict[str, Any] = copy.deepcopy(_FACTORY)


def reset_defaults() -> None:
    """Put every key of :data:`defaults` back to its shipped value (keys added by a user are dropped).

    Option dicts (``ipopt.options``, ``ipopt.warm_start``) are refilled in place, so a module
    that holds one of them under its own name (e.g.
    :data:`gtmodel.modeling.collocation_nlp.IPOPT_DEFAULTS`) sees the reset too.
    """
    for key in [k for k in defaults if k not in _FACTORY]:
        del defaults[key]
    for key, value in _FACTORY.items():
        current = defaults.get(key)
        if isinstance(current, dict) and isinstance(value, dict):
            current.clear()
            current.update(copy.deepcopy(value))
        else:
            defaults[key] = copy.deepcopy(value)


def get(key: str, value: Any = None) -> Any:
    """``value`` if given, else the default of ``key`` (python-control's ``_get_param`` idiom).

    Parameters
    ----------
    key : str
        A dotted key of :data:`defaults`, e.g. ``"plot.dpi"``.
    value : object, optional
        An explicit value; returned unchanged unless None.

    Returns
    -------
    object
        ``value`` or ``defaults[key]``.

    Raises
    ------
    InputError
        ``key`` is not a key of :data:`defaults`.
    """
    if value is not None:
        return value
    try:
        return defaults[key]
    except KeyError:
        raise InputError(f"key: expected one of {', '.join(sorted(defaults))}, got {key!r}") from None
