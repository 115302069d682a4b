partial model Base
  Real x(start = 1.0);
end Base;
model Saturated "extends and an if-expression"
  extends Base;
  parameter Real umax = 0.5;
  Real u;
equation
  u = if x > umax then umax else x;
  der(x) = -u;
end Saturated;
