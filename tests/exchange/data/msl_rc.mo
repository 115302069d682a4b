// A capacitor charged through a resistor from a constant voltage, written with the Modelica
// Standard Library's class paths (Electrical.Analog): v_C = U (1 - exp(-t / (R C))).
model Charge
  Modelica.Electrical.Analog.Sources.ConstantVoltage source(V = 2);
  Modelica.Electrical.Analog.Basic.Resistor resistor(R = 100);
  Modelica.Electrical.Analog.Basic.Capacitor capacitor(C = 1e-3, v(start = 0, fixed = true));
  Modelica.Electrical.Analog.Basic.Ground ground;
equation
  connect(source.p, resistor.p);
  connect(resistor.n, capacitor.p);
  connect(capacitor.n, source.n);
  connect(source.n, ground.p);
end Charge;
