model WithAssert "a decay guarded by an assert (pymoca 0.12 fails on it without a line)"
  parameter Real k = 1.0;
  Real x(start = 1.0);
equation
  der(x) = -k * x;
  assert(x > -1, "x too small");
end WithAssert;
