// The non-smooth elements under the Modelica Standard Library's class paths, smoothed as gtmodel's
// library smooths them: a load on an ElastoBacklash to the wall, released outside the gap; and a sine
// through a Limiter and a DeadZone, each integrated (tests/exchange/test_msl.py checks them against
// the laws integrated by SciPy).
model Rattle
  Modelica.Mechanics.Rotational.Components.Fixed wall;
  Modelica.Mechanics.Rotational.Components.ElastoBacklash gap(c = 100, d = 0.5, b = 0.02, smoothing = 1e-4,
    phi_rel(start = 0.05), w_rel(start = 0));
  Modelica.Mechanics.Rotational.Components.Inertia load(J = 0.1, phi(start = 0.05, fixed = true), w(start = 0, fixed = true));
  Modelica.Blocks.Sources.Sine sine(amplitude = 2, f = 1);
  Modelica.Blocks.Nonlinear.Limiter limiter(uMax = 1, smoothing = 1e-4);
  Modelica.Blocks.Nonlinear.DeadZone deadZone(uMax = 1, smoothing = 1e-4);
  Modelica.Blocks.Continuous.Integrator limited;
  Modelica.Blocks.Continuous.Integrator dead;
equation
  connect(wall.flange, gap.flange_a);
  connect(gap.flange_b, load.flange_a);
  connect(sine.y, limiter.u);
  connect(sine.y, deadZone.u);
  connect(limiter.y, limited.u);
  connect(deadZone.y, dead.u);
end Rattle;
