model Chain "three masses in a chain, arrays and a for equation"
  parameter Real k = 10.0;
  parameter Integer n = 3;
  Real x[n](each start = 0.0);
  Real v[n](each start = 1.0);
equation
  for i in 1:n loop
    der(x[i]) = v[i];
  end for;
  der(v[1]) = -k * x[1];
  der(v[2]) = -k * (x[2] - x[1]);
  der(v[3]) = -k * (x[3] - x[2]);
end Chain;
