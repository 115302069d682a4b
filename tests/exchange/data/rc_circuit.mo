package Circuit
  connector Pin
    Real v;
    flow Real i;
  end Pin;
  model Resistor
    parameter Real R = 1.0 "resistance";
    Pin p; Pin n;
  equation
    p.v - n.v = R * p.i;
    p.i + n.i = 0;
  end Resistor;
  model Capacitor
    parameter Real C = 1e-3;
    Pin p; Pin n;
    Real u(start = 1.0);
  equation
    u = p.v - n.v;
    C * der(u) = p.i;
    p.i + n.i = 0;
  end Capacitor;
  model Ground
    Pin p;
  equation
    p.v = 0;
  end Ground;
  model RC
    Resistor r(R = 100.0);
    Capacitor c(C = 1e-3);
    Ground g;
  equation
    connect(r.p, c.p);
    connect(r.n, c.n);
    connect(c.n, g.p);
  end RC;
end Circuit;
