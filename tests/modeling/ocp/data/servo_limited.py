"""Servos nobody tuned for: a torque command through a smooth signal block inside the model (a Limiter: saturation,
or a DeadZone), a backlash, and friction on the load; the problem's input is the command
(tests/modeling/ocp/test_infeasibility.py, tests/modeling/ocp/test_refinement_objective.py)."""
from gtmodel.modeling import Component, connect
from gtmodel.modeling.components.component import Input, Variable
from gtmodel.modeling.library import blocks
from gtmodel.modeling.library import rotational as rot


class SignalTorque(rot.Torque):
    tau = Variable(unit="N.m", description="accelerating torque, from a signal")


class LimitedDrive(Component):
    cmd = Input(unit="N.m", description="commanded torque")
    torque = SignalTorque()
    motor = rot.Inertia(J=0.01, phi=0.0, w=0.0)
    limit = blocks.Limiter(uMax=0.5, uMin=-0.5, smoothing=1e-3)
    backlash = rot.ElastoBacklash(c=100.0, d=0.3, b=0.02, smoothing=1e-4)
    load = rot.Inertia(J=0.05, phi=0.0, w=0.0)
    friction = rot.Friction(Fc=0.1, Fs=0.05, ws=0.5, dv=0.01, smoothing=1e-2)
    fixed = rot.Fixed()

    def equations(self):
        connect(self.torque.flange, self.motor.flange_a)
        connect(self.motor.flange_b, self.backlash.flange_a)
        connect(self.backlash.flange_b, self.load.flange_a)
        connect(self.load.flange_b, self.friction.flange_b)
        connect(self.friction.flange_a, self.fixed.flange)
        self.equation(self.limit.u, self.cmd)
        self.equation(self.torque.tau, self.limit.y)


class DeadZoneDrive(LimitedDrive):
    """The same servo with a dead zone of +-0.1 N m on its command in place of the limiter."""

    limit = blocks.DeadZone(uMax=0.1, uMin=-0.1, smoothing=1e-3)
