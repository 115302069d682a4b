"""The two-sensor lead-through control law as one CasADi graph (Dressler (2012), ch. 8.3-8.4).

The operator guides the robot by a handle force/torque sensor while a tool sensor keeps the
contact force (surface tracking) or lets the tool comply (peg-in-hole). One step of the law,
every ``dt`` (4 ms), from the handle wrench ``F_h``, the tool wrench ``F_t`` and the nominal
contact normal ``n_n`` to the tool velocity reference ``V_tool`` the robot's velocity servo
tracks:

* tool force P control, eq. (8.4): ``V_t = K (F_ref - F_t)`` with ``F_ref = [f_ref n; 0]``;
* handle impedance control without position term, eqs. (8.5)-(8.7): the acceleration
  ``A_h = M^-1 (F_h - D V_tool)`` (velocity feedback from the *applied* reference, eq. 8.6)
  integrated to the handle velocity ``V_h``, with the anti-windup term of (8.7):
  ``V_h(k+1) = P_h(V_h(k)) + dt A_h(k)``;
* the contact-state projections of eq. (8.3): ``V_tool = P_h(V_h, c) + P_t(V_t, c)``,
  for surface tracking eqs. (8.8)-(8.9) (in contact the handle moves the tool in the
  surface's tangent plane and the tool force controller along the normal; orientation
  constant) and for peg-in-hole eq. (8.11) (the tool force controller also turns the
  tool: ``omega = omega_t``);
* the normal-vector estimate within a correction range ``phi_L`` of the nominal normal,
  eq. (8.10): ``n = f_t / |f_t|`` when it lies within ``phi_L`` of ``n_n``, else ``n_n``
  (peg-in-hole: the estimate in every direction, the contact normal of a wall being any);
* the contact state: taken when the tool force along ``n_n`` exceeds ``contact_force``;
  released when the operator pulls away from the surface with more than
  ``release_force`` (the force then has to fall below half the contact threshold before
  contact can be taken again); peg-in-hole: contact while ``|f_t|`` is above the threshold
  (half of it to leave);
* the safety saturation inside ``P_h`` (thesis, below eq. 8.7): the handle's translational
  and angular velocities are limited in norm to ``max_speed`` and ``max_angular_speed``,
  and so is the applied ``V_tool``.

Conventions (all vectors in the robot's base frame): a wrench is ``[force (N); torque (N m)]``
and a twist ``[velocity (m/s); angular velocity (rad/s)]``; ``F_t`` is the wrench the tool
exerts on the workpiece, so that pressing on a surface gives a force along the normal ``n``,
which points from the tool into the workpiece (the thesis' tool-frame ``n_n = (0, 0, 1)``
with the tool's z axis towards the surface; a horizontal surface below the tool has
``n_n = (0, 0, -1)`` in the base frame). ``F_h`` is the wrench the operator applies to the
handle.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import casadi as ca
import numpy as np

from gtmodel._arrays import finite_float
from gtmodel.defaults import LOOP_PERIOD_S
from gtmodel.errors import InputError

__all__ = [
    "TASKS",
    "STATE_SIZE",
    "NORMAL_TOLERANCE",
    "STEP_INPUTS",
    "STEP_OUTPUTS",
    "LeadThroughLaw",
    "LeadThroughStep",
    "unit_normal",
]

#: The two use cases of Dressler (2012), ch. 8.4.
TASKS = ("surface_tracking", "peg_in_hole")
#: Controller state: the handle velocity ``V_h`` (6), the contact flag ``c`` and the release flag ``r``.
STATE_SIZE = 8
#: Largest accepted ``| |n_n| - 1 |`` of the nominal normal (else the step's ``valid`` output is negative).
NORMAL_TOLERANCE = 1e-6
#: Names of the step Function's inputs and outputs, in order.
STEP_INPUTS = ("x", "F_h", "F_t", "n_n")
STEP_OUTPUTS = ("x_next", "V_tool", "n", "valid")
#: Below this tool force [N] the force has no direction: the normal estimate is the nominal normal.
_FORCE_FLOOR = 1e-9


def _matrix(value: Any, name: str, *, definite: bool) -> np.ndarray:
    """A finite 6x6 matrix from a scalar, 6 diagonal entries or a 6x6 array."""
    arr = np.asarray(value, dtype=float) if np.asarray(value).dtype.kind in "fiub" else None
    if arr is None:
        raise InputError(f"{name}: expected a number, 6 diagonal entries or a 6x6 matrix, got {value!r}")
    if arr.ndim == 0:
        arr = np.eye(6) * float(arr)
    elif arr.shape == (6,):
        arr = np.diag(arr)
    if arr.shape != (6, 6):
        raise InputError(f"{name}: expected a number, 6 diagonal entries or a 6x6 matrix, got shape {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise InputError(f"{name}: expected finite entries, got {arr.tolist()}")
    sym = 0.5 * (arr + arr.T)
    if not np.allclose(arr, sym, rtol=1e-12, atol=1e-15):
        raise InputError(f"{name}: expected a symmetric matrix")
    low = float(np.linalg.eigvalsh(sym).min())
    if definite and low <= 0.0:
        raise InputError(f"{name}: expected a symmetric positive definite matrix (smallest eigenvalue {low:.3g}); "
                         "a singular mass matrix has no acceleration (eq. 8.6)")
    if not definite and low < -1e-12 * max(1.0, float(np.abs(arr).max())):
        raise InputError(f"{name}: expected a symmetric positive semi-definite matrix (smallest eigenvalue {low:.3g})")
    out = arr.copy()
    out.setflags(write=False)
    return out




def unit_normal(value: Any, name: str = "nominal_normal") -> np.ndarray:
    """A unit 3-vector (normalised), refusing a zero or non-finite one.

    Parameters
    ----------
    value : array_like, shape (3,)
        The direction.
    name : str, optional
        Argument name for messages.

    Returns
    -------
    numpy.ndarray, shape (3,)
        ``value / |value|``.

    Raises
    ------
    InputError
        Not 3 finite numbers, or of norm below 1e-9 (a zero normal has no direction).
    """
    arr = np.asarray(value, dtype=float) if np.asarray(value).dtype.kind in "fiu" else None
    if arr is None or arr.shape != (3,) or not np.all(np.isfinite(arr)):
        raise InputError(f"{name}: expected 3 finite numbers, got {value!r}")
    norm = float(np.linalg.norm(arr))
    if norm < 1e-9:
        raise InputError(f"{name}: expected a non-zero direction, got {arr.tolist()}")
    return arr / norm


def _saturate(v: ca.SX, limit: float) -> ca.SX:
    """``v`` scaled to norm at most ``limit`` (direction kept): the safety saturation."""
    norm = ca.sqrt(ca.dot(v, v))
    return v * ca.fmin(1.0, limit / ca.fmax(norm, 1e-300))


@dataclass(frozen=True)
class LeadThroughLaw:
    """Parameters of the two-sensor lead-through controller (Dressler (2012), eqs. 8.3-8.11).

    Parameters
    ----------
    task : {"surface_tracking", "peg_in_hole"}
        Projections (8.8)-(8.9) or (8.8) with (8.11).
    M : float, array_like of 6 or array_like (6, 6)
        Mass matrix of the handle impedance [kg, kg m^2], symmetric positive definite, eq. (8.6).
    D : float, array_like of 6 or array_like (6, 6)
        Damping matrix [N s/m, N m s/rad], symmetric positive semi-definite, eq. (8.6).
    K : float, array_like of 6 or array_like (6, 6)
        Gain of the tool force P controller [m/(N s), rad/(N m s)], eq. (8.4).
    force_reference : float, optional
        Tool force reference along ``n`` [N] (``F_ref = force_reference n``; thesis: 2 N for
        surface tracking, 0 for peg-in-hole).
    correction_range_deg : float, optional
        ``phi_L`` [deg] in [0, 90], eq. (8.10) (surface tracking; not used by peg-in-hole).
    nominal_normal : array_like, shape (3,), optional
        Default nominal normal ``n_n`` (into the workpiece), normalised.
    contact_force : float, optional
        Tool force [N] along ``n_n`` (peg-in-hole: ``|f_t|``) above which contact is taken.
    release_force : float, optional
        Handle force [N] away from the surface above which contact is released.
    max_speed, max_angular_speed : float, optional
        Safety saturation [m/s], [rad/s].
    dt : float, optional
        Sample time [s] (the loop period, ``gtmodel.defaults.LOOP_PERIOD_S``: 4 ms).
    tool_force_control : bool, optional
        False: plain lead-through by the handle sensor alone (the tool sensor unused, never
        in contact: ``V_tool = P_h(V_h, no contact)``), the "without tool force control"
        case of Figure 8.4.

    Raises
    ------
    InputError
        An unknown task; a matrix that is not 6x6 symmetric, ``M`` not positive definite (a
        singular ``M``), ``D``/``K`` not positive semi-definite; a non-finite or negative
        value; ``phi_L`` outside [0, 90] degrees; a zero normal; ``release_force`` not above
        ``contact_force``.
    """

    task: str = "surface_tracking"
    M: Any = 2.0
    D: Any = 40.0
    K: Any = 0.005
    force_reference: float = 2.0
    correction_range_deg: float = 10.0
    nominal_normal: Any = (0.0, 0.0, -1.0)
    contact_force: float = 0.5
    release_force: float = 10.0
    max_speed: float = 0.25
    max_angular_speed: float = 0.5
    dt: float = LOOP_PERIOD_S
    tool_force_control: bool = True
    _cache: dict = field(default_factory=dict, init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        if self.task not in TASKS:
            raise InputError(f"task: expected one of {', '.join(TASKS)}, got {self.task!r}")
        object.__setattr__(self, "M", _matrix(self.M, "M", definite=True))
        object.__setattr__(self, "D", _matrix(self.D, "D", definite=False))
        object.__setattr__(self, "K", _matrix(self.K, "K", definite=False))
        if isinstance(self.force_reference, bool) or not isinstance(self.force_reference, (int, float, np.integer, np.floating)) \
                or not math.isfinite(float(self.force_reference)):
            raise InputError(f"force_reference: expected a finite force [N], got {self.force_reference!r}")
        object.__setattr__(self, "force_reference", float(self.force_reference))
        phi = finite_float(self.correction_range_deg, "correction_range_deg", "deg", nonnegative=True)
        if phi > 90.0:
            raise InputError(f"correction_range_deg: expected phi_L in [0, 90] degrees (eq. 8.10), got {self.correction_range_deg!r}")
        object.__setattr__(self, "correction_range_deg", phi)
        object.__setattr__(self, "nominal_normal", unit_normal(self.nominal_normal))
        for name, unit in (("contact_force", "N"), ("release_force", "N"), ("max_speed", "m/s"),
                           ("max_angular_speed", "rad/s"), ("dt", "s")):
            object.__setattr__(self, name, finite_float(getattr(self, name), name, unit, positive=True))
        if not isinstance(self.tool_force_control, (bool, np.bool_)):
            raise InputError(f"tool_force_control: expected true or false, got {self.tool_force_control!r}")
        if self.release_force <= self.contact_force:
            raise InputError(f"release_force: expected above contact_force ({self.contact_force} N), got {self.release_force} N")

    def step_function(self) -> ca.Function:
        """The controller step as a CasADi Function (the one graph; generated C wraps it).

        ``"lead_through_step"(x[8], F_h[6], F_t[6], n_n[3]) -> (x_next[8], V_tool[6], n[3], valid)``:
        from the state ``x = [V_h; c; r]`` (handle velocity, contact and release flags) and
        the measured wrenches to the next state, the applied tool velocity reference
        ``V_tool`` (eq. 8.3), the normal ``n`` used (eq. 8.10) and ``valid`` (``>= 0`` when
        ``| |n_n| - 1 | <= NORMAL_TOLERANCE``; the generated C returns ``GT_BAD_ARGUMENT``
        otherwise).

        Returns
        -------
        casadi.Function
            Inputs and outputs named as :data:`STEP_INPUTS` and :data:`STEP_OUTPUTS`.
        """
        if "step" not in self._cache:
            self._cache["step"] = self._build()
        return self._cache["step"]

    def _normal(self, f_t: ca.SX, n_n: ca.SX) -> ca.SX:
        """Eq. (8.10): the estimate ``f_t/|f_t|`` within ``phi_L`` of ``n_n`` (peg-in-hole: always), else ``n_n``."""
        norm = ca.sqrt(ca.dot(f_t, f_t))
        n_est = f_t / ca.fmax(norm, _FORCE_FLOOR)
        has_force = norm > _FORCE_FLOOR
        if self.task == "peg_in_hole":
            return ca.if_else(has_force, n_est, n_n)
        within = ca.dot(n_n, n_est) > math.cos(math.radians(self.correction_range_deg))
        return ca.if_else(ca.logic_and(has_force, within), n_est, n_n)

    def _contact(self, x: ca.SX, f_h: ca.SX, f_t: ca.SX, n_n: ca.SX, n: ca.SX) -> tuple[ca.SX, ca.SX]:
        """The contact and release flags of this sample (1/0)."""
        c_prev, r_prev = x[6], x[7]
        if not self.tool_force_control:
            return ca.SX(0.0), ca.SX(0.0)
        if self.task == "peg_in_hole":
            norm = ca.sqrt(ca.dot(f_t, f_t))
            c = ca.if_else(c_prev > 0.5, norm > 0.5 * self.contact_force, norm > self.contact_force)
            return c, ca.SX(0.0)
        pressing = ca.dot(n_n, f_t)
        release = -ca.dot(n, f_h) > self.release_force
        enter = ca.logic_and(pressing > self.contact_force, r_prev < 0.5)
        c = ca.if_else(c_prev > 0.5, ca.logic_not(release), enter)
        r = ca.logic_or(ca.logic_and(c_prev > 0.5, release), ca.logic_and(r_prev > 0.5, pressing >= 0.5 * self.contact_force))
        return c, r

    def _project_h(self, v_h: ca.SX, c: ca.SX, n: ca.SX) -> ca.SX:
        """Eq. (8.8) with the safety saturation: tangential velocity in contact, no rotation."""
        v = v_h[:3] - c * ca.dot(n, v_h[:3]) * n
        return ca.vertcat(_saturate(v, self.max_speed), ca.SX.zeros(3))

    def _project_t(self, v_t: ca.SX, c: ca.SX, n: ca.SX) -> ca.SX:
        """Eq. (8.9) (surface tracking) or (8.11) (peg-in-hole): the tool force controller in contact."""
        rot = v_t[3:] if self.task == "peg_in_hole" else ca.SX.zeros(3)
        return c * ca.vertcat(ca.dot(n, v_t[:3]) * n, rot)

    def _build(self) -> ca.Function:
        x, F_h, F_t, n_n = ca.SX.sym("x", STATE_SIZE), ca.SX.sym("F_h", 6), ca.SX.sym("F_t", 6), ca.SX.sym("n_n", 3)
        n = self._normal(F_t[:3], n_n)
        c, r = self._contact(x, F_h[:3], F_t[:3], n_n, n)
        v_t = ca.mtimes(ca.DM(self.K), ca.vertcat(self.force_reference * n, ca.SX.zeros(3)) - F_t)  # (8.4)
        ph = self._project_h(x[:6], c, n)
        v_tool = ph + self._project_t(v_t, c, n)  # (8.3)
        v_tool = ca.vertcat(_saturate(v_tool[:3], self.max_speed), _saturate(v_tool[3:], self.max_angular_speed))
        a_h = ca.mtimes(ca.DM(np.linalg.inv(self.M)), F_h - ca.mtimes(ca.DM(self.D), v_tool))  # (8.6), M constant
        v_h_next = ph + self.dt * a_h  # (8.5) with the anti-windup term of (8.7)
        valid = NORMAL_TOLERANCE - ca.fabs(ca.sqrt(ca.dot(n_n, n_n)) - 1.0)
        return ca.Function("lead_through_step", [x, F_h, F_t, n_n], [ca.vertcat(v_h_next, c, r), v_tool, n, valid],
                           list(STEP_INPUTS), list(STEP_OUTPUTS))

    def step(self, x: Any, F_h: Any, F_t: Any, n_n: Any | None = None) -> "LeadThroughStep":
        """One controller step from Python, with the argument checks of the generated C.

        Parameters
        ----------
        x : array_like, shape (8,)
            State ``[V_h (6); c; r]`` (zeros: at rest, no contact).
        F_h, F_t : array_like, shape (6,)
            Handle and tool wrenches [N, N m] (see the module conventions).
        n_n : array_like, shape (3,), optional
            Nominal normal (default :attr:`nominal_normal`); must have unit norm.

        Returns
        -------
        LeadThroughStep

        Raises
        ------
        InputError
            A wrong size or a non-finite value (named), or ``n_n`` not of unit norm.
        """
        args = {"x": (x, STATE_SIZE), "F_h": (F_h, 6), "F_t": (F_t, 6),
                "n_n": (self.nominal_normal if n_n is None else n_n, 3)}
        values = {}
        for name, (value, size) in args.items():
            arr = np.asarray(value, dtype=float).ravel() if np.asarray(value).dtype.kind in "fiub" else None
            if arr is None or arr.size != size or not np.all(np.isfinite(arr)):
                raise InputError(f"{name}: expected {size} finite numbers, got {value!r}")
            values[name] = arr
        if abs(np.linalg.norm(values["n_n"]) - 1.0) > NORMAL_TOLERANCE:
            raise InputError(f"n_n: expected a unit normal, got norm {np.linalg.norm(values['n_n']):.9g}")
        out = self.step_function()(*values.values())
        return LeadThroughStep(*(np.asarray(o, dtype=float).ravel() for o in out[:3]))


@dataclass(frozen=True)
class LeadThroughStep:
    """Outputs of one controller step.

    Parameters
    ----------
    x_next : numpy.ndarray, shape (8,)
        Next state ``[V_h (6); c; r]``.
    V_tool : numpy.ndarray, shape (6,)
        Applied tool velocity reference [m/s, rad/s], eq. (8.3).
    n : numpy.ndarray, shape (3,)
        Normal used, eq. (8.10).
    """

    x_next: np.ndarray
    V_tool: np.ndarray
    n: np.ndarray

    @property
    def contact(self) -> bool:
        """Contact state after the step."""
        return bool(self.x_next[6] > 0.5)
