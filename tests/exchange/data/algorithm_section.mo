model Alg
  Real x(start=1);
  Real y;
algorithm
  y := 2*x;
equation
  der(x) = -y;
end Alg;
