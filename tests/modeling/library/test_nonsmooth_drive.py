"""A small drive with backlash and friction composed from the library: its widths and its motion.

Drive: torque source -- motor Inertia -- ElastoBacklash -- load Inertia -- Friction -- Fixed.
Independent checks: ``Model.smoothing`` against the names written out by hand; the
simulation (IDAS, after gtmodel's structural passes) against the same ODE written by
hand with NumPy (the smooth laws as ``np.logaddexp`` softplus, ``scipy.special.expit``
logistic and ``np.tanh``) and integrated by SciPy's ``solve_ivp`` (DOP853, rtol 1e-11).
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.special import expit

from gtmodel.modeling import Component, connect
from gtmodel.modeling.library import rotational as rot
from gtmodel.modeling.library import translational as tr
from gtmodel.modeling.structure.discontinuities import sign_modes
from gtmodel.modeling.structure.index_reduction import structural_simplify

JM, JL = 0.01, 0.05  # kg m^2
C, D, B, EPS_B = 1e2, 0.3, 0.02, 1e-4  # N m/rad, N m s/rad, rad, rad
FC, FS, WS, DV, EPS_F = 0.1, 0.05, 0.5, 0.01, 1e-2  # N m, N m, rad/s, N m s/rad, rad/s


class BacklashDrive(Component):
    """torque -- motor -- backlash -- load -- friction -- fixed."""

    torque = rot.Torque()
    motor = rot.Inertia(J=JM, phi=0.0, w=0.0)
    backlash = rot.ElastoBacklash(c=C, d=D, b=B, smoothing=EPS_B)
    load = rot.Inertia(J=JL, phi=0.0, w=0.0)
    friction = rot.Friction(Fc=FC, Fs=FS, ws=WS, dv=DV, smoothing=EPS_F)
    fixed = rot.Fixed()

    def equations(self):
        connect(self.torque.flange, self.motor.flange_a)
        connect(self.motor.flange_b, self.backlash.flange_a)
        connect(self.backlash.flange_b, self.load.flange_a)
        connect(self.load.flange_b, self.friction.flange_b)
        connect(self.friction.flange_a, self.fixed.flange)


def test_widths_are_listed_by_name():
    assert BacklashDrive().to_model().smoothing == {"backlash.smoothing": EPS_B, "friction.smoothing": EPS_F}


def test_widths_survive_structural_simplify():
    # the drive has aliases (connections) and dependent states: a new model is built
    model = BacklashDrive(backlash={"smoothing": 2e-4}).to_model()
    reduced = structural_simplify(model)
    assert reduced is not model
    assert reduced.smoothing == {"backlash.smoothing": 2e-4, "friction.smoothing": EPS_F}


def test_the_smooth_laws_bring_no_events_into_the_simulation():
    # the smooth laws use no sign()/fabs() (whose derivative is sign): neither the model nor its
    # index-reduced form (differentiated equations) has a sign() for the event simulation to switch
    model = BacklashDrive().to_model()
    assert sign_modes(model) is None and sign_modes(structural_simplify(model)) is None


def _rhs(torque: float):
    """The drive's ODE by hand: states (phi_m, w_m, phi_l, w_l)."""

    def softplus(x, eps):
        return eps * np.logaddexp(0.0, x / eps)

    def f(t, s):
        phi_m, w_m, phi_l, w_l = s
        x, w_rel = phi_l - phi_m, w_l - w_m
        dead = softplus(x - B / 2, EPS_B) - softplus(-x - B / 2, EPS_B)
        contact = expit((x - B / 2) / EPS_B) + expit((-x - B / 2) / EPS_B)
        tau = C * dead + D * w_rel * contact  # on the load's flange_a as -tau, on the motor as +tau
        tau_f = (FC + FS * np.exp(-((w_l / WS) ** 2))) * np.tanh(w_l / EPS_F) + DV * w_l
        return [w_m, (torque + tau) / JM, w_l, (-tau - tau_f) / JL]

    return f


def test_simulation_matches_the_ode_written_by_hand():
    # +0.4 N m for 0.5 s, then -0.4 N m: the gap is crossed, contact made on both sides
    t1 = np.linspace(0.0, 0.5, 251)
    t2 = np.linspace(0.5, 1.0, 251)
    t = np.concatenate([t1, t2[1:]])
    u = np.where(t[:-1] < 0.5 - 1e-12, 0.4, -0.4)
    res = BacklashDrive().to_model().simulate(t, u=u[:, None])
    opts = {"method": "DOP853", "rtol": 1e-11, "atol": 1e-13}
    a = solve_ivp(_rhs(0.4), (0.0, 0.5), [0.0, 0.0, 0.0, 0.0], t_eval=t1, **opts)
    b = solve_ivp(_rhs(-0.4), (0.5, 1.0), a.y[:, -1], t_eval=t2, **opts)
    ref = np.hstack([a.y, b.y[:, 1:]])
    x = ref[2] - ref[0]
    assert x.max() > B / 2 + 10 * EPS_B and x.min() < -B / 2 - 10 * EPS_B  # contact on both sides, well off the corners
    got = np.vstack([res.x["motor.phi"], res.x["motor.w"], res.x["load.phi"], res.x["load.w"]])
    # measured: 2.6e-7 rad/s at most (IDAS at rtol 1e-8); LSODA and Radau give the same reference to 1e-9
    scale = np.abs(ref).max(axis=1, keepdims=True)
    np.testing.assert_array_less(np.abs(got - ref), np.broadcast_to(1e-6 * scale, ref.shape))


class BallScrewNut(Component):
    """force -- nut Mass -- translational ElastoBacklash -- table Mass -- translational Friction -- fixed."""

    force = tr.Force()
    nut = tr.Mass(m=2.0, s=0.0, v=0.0)
    backlash = tr.ElastoBacklash(c=2e5, d=200.0, b=5e-5, smoothing=1e-6)
    table = tr.Mass(m=50.0, s=0.0, v=0.0)
    friction = tr.Friction(Fc=20.0, Fs=0.0, dv=200.0, smoothing=1e-3)
    fixed = tr.Fixed()

    def equations(self):
        connect(self.force.flange, self.nut.flange_a)
        connect(self.nut.flange_b, self.backlash.flange_a)
        connect(self.backlash.flange_b, self.table.flange_a)
        connect(self.table.flange_b, self.friction.flange_b)
        connect(self.friction.flange_a, self.fixed.flange)


@pytest.mark.parametrize("force", [60.0, -60.0])
def test_translational_drive_reaches_the_steady_speed_of_the_exact_law(force):
    # independent: in steady sliding the force balance with the exact law, |F| = Fc + dv |v|
    # (tanh(v/eps) is 1 to 1e-30 at that speed), gives v = (|F| - Fc) / dv = +-0.2 m/s
    t = np.linspace(0.0, 3.0, 31)
    res = BallScrewNut().to_model().simulate(t, u=np.full((30, 1), force))
    v_exact = np.sign(force) * (abs(force) - 20.0) / 200.0
    assert res.x["table.v"][-1] == pytest.approx(v_exact, rel=1e-4)
    gap = res.x["table.s"][-1] - res.x["nut.s"][-1]
    # nut at steady speed: 0 = F + f (its flange_b takes the backlash force f = -F), and f = c (|x| - b/2)
    # in contact (the exact dead zone, the smooth one within c eps exp(-delta/eps) there)
    assert abs(gap) == pytest.approx(5e-5 / 2 + abs(force) / 2e5, rel=1e-3)
