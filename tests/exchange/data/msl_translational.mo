// A mass on a spring-damper to the wall, pushed by a ramp force through a first-order lag, written
// with the Modelica Standard Library's class paths (Translational, Blocks); checked against SciPy.
model MSD "a mass on a spring-damper to the wall, driven by a ramp force through a first-order lag"
  Modelica.Mechanics.Translational.Components.Fixed wall;
  Modelica.Mechanics.Translational.Components.SpringDamper sd(c = 4, d = 0.4);
  Modelica.Mechanics.Translational.Components.Mass mass(m = 1, L = 0.2, s(start = 0.1), v(start = 0));
  Modelica.Mechanics.Translational.Sources.Force force;
  Modelica.Blocks.Sources.Ramp ramp(height = 2, duration = 0.5, startTime = 0.1);
  Modelica.Blocks.Continuous.FirstOrder lag(k = 1, T = 0.05);
  Modelica.Blocks.Math.Gain gain(k = 1);
  Modelica.Mechanics.Translational.Sensors.PositionSensor pos;
  Modelica.Blocks.Interfaces.RealOutput y;
equation
  connect(wall.flange, sd.flange_a);
  connect(sd.flange_b, mass.flange_a);
  connect(ramp.y, lag.u);
  connect(lag.y, gain.u);
  connect(gain.y, force.f);
  connect(force.flange, mass.flange_b);
  connect(pos.flange, mass.flange_a);
  connect(pos.s, y);
end MSD;
