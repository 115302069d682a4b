model Oscillator "a mass on a spring with viscous damping, pushed by a force"
  parameter Real m(unit = "kg") = 1.0 "mass";
  parameter Real k(unit = "N/m") = 4.0 "stiffness";
  parameter Real c(unit = "N.s/m") = 0.0 "damping";
  Real x(start = 1.0, unit = "m") "position";
  Real v(start = 0.0, unit = "m/s") "velocity";
  input Real F(unit = "N") "force";
  output Real energy(unit = "J") "mechanical energy";
equation
  der(x) = v;
  m * der(v) = -k * x - c * v + F;
  energy = 0.5 * m * v^2 + 0.5 * k * x^2;
end Oscillator;
