// The Van der Pol oscillator (a textbook Modelica example), started by an initial equation.
model VanDerPol
  parameter Real lambda = 1.0 "damping parameter";
  Real x "first state";
  Real y(start = 0.0, fixed = true) "second state";
initial equation
  x = 2.0;
equation
  der(x) = y;
  der(y) = -x + lambda * (1 - x * x) * y;
end VanDerPol;
