function sq "a square"
  input Real a;
  output Real b;
algorithm
  b := a * a;
end sq;
model WithFunction
  Real x(start = 1.0);
equation
  der(x) = -sq(x);
end WithFunction;
