model WithFunction
  function sq
    input Real a;
    output Real b;
  algorithm
    b := a * a;
  end sq;
  Real x(start = 1.0);
equation
  der(x) = -sq(x);
end WithFunction;
