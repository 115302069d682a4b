// The Modelica Standard Library's interfaces, the subset gtmodel ships (issue 68, item 3).
//
// Written for gtmodel from the Modelica Language Specification 3.6 and the documented
// interfaces of the Modelica Standard Library 4.0 (class paths, connector, parameter and
// variable names, and the equations each class's documentation states); not copied from
// the MSL's source. What differs from the MSL, so that pymoca (gtmodel's Modelica front end)
// translates it:
//  * no conditional support flanges/heat ports (useSupport = false, useHeatPort = false:
//    the MSL's defaults); no temperature dependence of the resistor (alpha = 0);
//  * Modelica.Blocks.Interfaces.RealInput/RealOutput are declared as `input Real` /
//    `output Real` (pymoca drops short connector classes; gtmodel rewrites a user's
//    `Modelica.Blocks.Interfaces.RealInput u` the same way), and Modelica.Constants are
//    written as their numbers where used (pymoca does not look constants up across packages;
//    gtmodel writes a user's `Modelica.Constants.pi` as its number too);
//  * no annotations, icons or units checking (types carry their unit);
//  * the non-smooth elements (ElastoBacklash, Blocks.Nonlinear.Limiter and DeadZone) follow the
//    smoothed laws of gtmodel's library (gtmodel.modeling.library.rotational, .blocks: softplus
//    dead zone, logistic contact) with a parameter `smoothing`, the width, that the MSL does not
//    have; its quantity "SmoothingWidth" marks it for the continuation over smoothing
//    widths. MSL's damping clamp of ElastoBacklash and its strict/homotopy options are not modelled.
// A class the user's file names under `Modelica.` that is not here is refused with the
// file, line and class (gtmodel.exchange.msl).
package Modelica "the subset of the Modelica Standard Library gtmodel ships"
  package Constants
    constant Real pi = 3.14159265358979323846;
    constant Real e = 2.71828182845904523536;
    constant Real g_n = 9.80665 "standard acceleration of gravity [m/s2]";
  end Constants;

  package Units
    package SI
      type Time = Real(unit = "s");
      type Angle = Real(unit = "rad");
      type AngularVelocity = Real(unit = "rad/s");
      type AngularAcceleration = Real(unit = "rad/s2");
      type Torque = Real(unit = "N.m");
      type Inertia = Real(unit = "kg.m2");
      type RotationalSpringConstant = Real(unit = "N.m/rad");
      type RotationalDampingConstant = Real(unit = "N.m.s/rad");
      type Position = Real(unit = "m");
      type Length = Real(unit = "m");
      type Distance = Real(unit = "m");
      type Velocity = Real(unit = "m/s");
      type Acceleration = Real(unit = "m/s2");
      type Force = Real(unit = "N");
      type Mass = Real(unit = "kg");
      type TranslationalSpringConstant = Real(unit = "N/m");
      type TranslationalDampingConstant = Real(unit = "N.s/m");
      type Voltage = Real(unit = "V");
      type ElectricPotential = Real(unit = "V");
      type Current = Real(unit = "A");
      type Resistance = Real(unit = "Ohm");
      type Inductance = Real(unit = "H");
      type Capacitance = Real(unit = "F");
      type ElectricalTorqueConstant = Real(unit = "N.m/A");
      type Power = Real(unit = "W");
    end SI;
  end Units;

  package SIunits "the MSL 3 name of Modelica.Units.SI (JModelica.org-era files use it)"
    type Time = Real(unit = "s");
    type Angle = Real(unit = "rad");
    type AngularVelocity = Real(unit = "rad/s");
    type AngularAcceleration = Real(unit = "rad/s2");
    type Torque = Real(unit = "N.m");
    type Inertia = Real(unit = "kg.m2");
    type Position = Real(unit = "m");
    type Length = Real(unit = "m");
    type Velocity = Real(unit = "m/s");
    type Acceleration = Real(unit = "m/s2");
    type Force = Real(unit = "N");
    type Mass = Real(unit = "kg");
    type Voltage = Real(unit = "V");
    type Current = Real(unit = "A");
    type Resistance = Real(unit = "Ohm");
    type Inductance = Real(unit = "H");
    type Capacitance = Real(unit = "F");
  end SIunits;

  package Blocks
    package Sources
      block Constant "y = k"
        parameter Real k = 1 "constant output value";
        output Real y;
      equation
        y = k;
      end Constant;

      block Step "y = offset, plus height from startTime on"
        parameter Real height = 1;
        parameter Real offset = 0;
        parameter Real startTime = 0 "[s]";
        output Real y;
      equation
        y = offset + (if time < startTime then 0 else height);
      end Step;

      block Ramp "y = offset, rising by height over duration from startTime"
        parameter Real height = 1;
        parameter Real duration(min = 0) = 2 "[s]";
        parameter Real offset = 0;
        parameter Real startTime = 0 "[s]";
        output Real y;
      equation
        y = offset + (if time < startTime then 0 else if time < startTime + duration then (time - startTime) * height / duration else height);
      end Ramp;

      block Sine "y = offset + amplitude sin(2 pi f (time - startTime) + phase) from startTime on"
        parameter Real amplitude = 1;
        parameter Real f = 1 "frequency [Hz]";
        parameter Real phase = 0 "[rad]";
        parameter Real offset = 0;
        parameter Real startTime = 0 "[s]";
        output Real y;
      equation
        y = offset + (if time < startTime then 0 else amplitude * sin(2 * 3.14159265358979323846 * f * (time - startTime) + phase));
      end Sine;
    end Sources;

    package Math
      block Gain "y = k u"
        parameter Real k = 1;
        input Real u;
        output Real y;
      equation
        y = k * u;
      end Gain;

      block Feedback "y = u1 - u2"
        input Real u1;
        input Real u2;
        output Real y;
      equation
        y = u1 - u2;
      end Feedback;

      block Add "y = k1 u1 + k2 u2"
        parameter Real k1 = 1;
        parameter Real k2 = 1;
        input Real u1;
        input Real u2;
        output Real y;
      equation
        y = k1 * u1 + k2 * u2;
      end Add;
    end Math;

    package Nonlinear
      block Limiter "y = min(max(u, uMin), uMax), smoothed (gtmodel's smoothing width)"
        parameter Real uMax(start = 1) "upper limit";
        parameter Real uMin = -uMax "lower limit";
        parameter Real smoothing(quantity = "SmoothingWidth", min = 0) = 1.0e-3 "smoothing width (gtmodel's; not in the MSL)";
        input Real u;
        output Real y;
      equation
        y = uMin + max(u - uMin, 0) + smoothing * log(1 + exp(-abs(u - uMin) / smoothing)) - (max(u - uMax, 0) + smoothing * log(1 + exp(-abs(u - uMax) / smoothing)));
      end Limiter;

      block DeadZone "y = u - min(max(u, uMin), uMax), smoothed (gtmodel's smoothing width)"
        parameter Real uMax(start = 1) "upper end of the dead band";
        parameter Real uMin = -uMax "lower end of the dead band";
        parameter Real smoothing(quantity = "SmoothingWidth", min = 0) = 1.0e-3 "smoothing width (gtmodel's; not in the MSL)";
        input Real u;
        output Real y;
      equation
        y = max(u - uMax, 0) + smoothing * log(1 + exp(-abs(u - uMax) / smoothing)) - (max(uMin - u, 0) + smoothing * log(1 + exp(-abs(uMin - u) / smoothing)));
      end DeadZone;
    end Nonlinear;

    package Continuous
      block Integrator "der(y) = k u"
        parameter Real k = 1;
        parameter Real y_start = 0;
        input Real u;
        output Real y(start = y_start);
      equation
        der(y) = k * u;
      end Integrator;

      block FirstOrder "T der(y) + y = k u"
        parameter Real k = 1;
        parameter Real T(min = 0) = 1 "time constant [s]";
        parameter Real y_start = 0;
        input Real u;
        output Real y(start = y_start);
      equation
        der(y) = (k * u - y) / T;
      end FirstOrder;
    end Continuous;
  end Blocks;

  package Mechanics
    package Rotational
      package Interfaces
        connector Flange "a rotational flange: absolute angle, cut torque"
          Modelica.Units.SI.Angle phi;
          flow Modelica.Units.SI.Torque tau;
        end Flange;

        connector Flange_a
          extends Flange;
        end Flange_a;

        connector Flange_b
          extends Flange;
        end Flange_b;

        partial model PartialTwoFlanges
          Flange_a flange_a;
          Flange_b flange_b;
        end PartialTwoFlanges;

        partial model PartialCompliant "phi_rel = flange_b.phi - flange_a.phi, tau through"
          Flange_a flange_a;
          Flange_b flange_b;
          Modelica.Units.SI.Angle phi_rel(start = 0);
          Modelica.Units.SI.Torque tau;
        equation
          phi_rel = flange_b.phi - flange_a.phi;
          flange_b.tau = tau;
          flange_a.tau = -tau;
        end PartialCompliant;

        partial model PartialCompliantWithRelativeStates "PartialCompliant with w_rel = der(phi_rel)"
          Flange_a flange_a;
          Flange_b flange_b;
          Modelica.Units.SI.Angle phi_rel(start = 0);
          Modelica.Units.SI.AngularVelocity w_rel(start = 0);
          Modelica.Units.SI.Torque tau;
        equation
          phi_rel = flange_b.phi - flange_a.phi;
          w_rel = der(phi_rel);
          flange_b.tau = tau;
          flange_a.tau = -tau;
        end PartialCompliantWithRelativeStates;
      end Interfaces;

      package Components
        model Fixed "flange fixed at phi0"
          parameter Modelica.Units.SI.Angle phi0 = 0;
          Modelica.Mechanics.Rotational.Interfaces.Flange_b flange;
        equation
          flange.phi = phi0;
        end Fixed;

        model Inertia "J der(w) = flange_a.tau + flange_b.tau"
          parameter Modelica.Units.SI.Inertia J(min = 0, start = 1);
          Modelica.Mechanics.Rotational.Interfaces.Flange_a flange_a;
          Modelica.Mechanics.Rotational.Interfaces.Flange_b flange_b;
          Modelica.Units.SI.Angle phi;
          Modelica.Units.SI.AngularVelocity w;
          Modelica.Units.SI.AngularAcceleration a;
        equation
          phi = flange_a.phi;
          phi = flange_b.phi;
          w = der(phi);
          a = der(w);
          J * a = flange_a.tau + flange_b.tau;
        end Inertia;

        model Spring "tau = c (phi_rel - phi_rel0)"
          extends Modelica.Mechanics.Rotational.Interfaces.PartialCompliant;
          parameter Modelica.Units.SI.RotationalSpringConstant c(min = 0, start = 1.0e5);
          parameter Modelica.Units.SI.Angle phi_rel0 = 0;
        equation
          tau = c * (phi_rel - phi_rel0);
        end Spring;

        model Damper "tau = d w_rel"
          extends Modelica.Mechanics.Rotational.Interfaces.PartialCompliantWithRelativeStates;
          parameter Modelica.Units.SI.RotationalDampingConstant d(min = 0, start = 0);
        equation
          tau = d * w_rel;
        end Damper;

        model SpringDamper "tau = c (phi_rel - phi_rel0) + d w_rel"
          extends Modelica.Mechanics.Rotational.Interfaces.PartialCompliantWithRelativeStates;
          parameter Modelica.Units.SI.RotationalSpringConstant c(min = 0, start = 1.0e5);
          parameter Modelica.Units.SI.RotationalDampingConstant d(min = 0, start = 0);
          parameter Modelica.Units.SI.Angle phi_rel0 = 0;
        equation
          tau = c * (phi_rel - phi_rel0) + d * w_rel;
        end SpringDamper;

        model ElastoBacklash "backlash b in series with a spring-damper contact, smoothed (gtmodel's smoothing width)"
          extends Modelica.Mechanics.Rotational.Interfaces.PartialCompliantWithRelativeStates;
          parameter Modelica.Units.SI.RotationalSpringConstant c(min = 0, start = 1.0e5);
          parameter Modelica.Units.SI.RotationalDampingConstant d(min = 0, start = 0);
          parameter Modelica.Units.SI.Angle b(min = 0) = 0 "total backlash";
          parameter Modelica.Units.SI.Angle phi_rel0 = 0;
          parameter Real smoothing(quantity = "SmoothingWidth", unit = "rad", min = 0) = 1.0e-5 "smoothing width of the dead zone (gtmodel's; not in the MSL)";
        equation
          // x = phi_rel - phi_rel0; tau = c dz(x) + d w_rel contact(x), written out (no algebraic variables of
          // their own: an initialisation from x = 0 would have to cross the corners), with
          // dz(x) = softplus(x - b/2) - softplus(-x - b/2), softplus(y) = max(y, 0) + eps log(1 + exp(-|y|/eps)),
          // contact(x) = s(x - b/2) + s(-x - b/2), s(y) = (1 + tanh(y / (2 eps))) / 2
          tau = c * (max(phi_rel - phi_rel0 - b / 2, 0) + smoothing * log(1 + exp(-abs(phi_rel - phi_rel0 - b / 2) / smoothing))
                     - (max(phi_rel0 - phi_rel - b / 2, 0) + smoothing * log(1 + exp(-abs(phi_rel0 - phi_rel - b / 2) / smoothing))))
                + d * w_rel * (0.5 * (1 + tanh((phi_rel - phi_rel0 - b / 2) / (2 * smoothing)))
                               + 0.5 * (1 + tanh((phi_rel0 - phi_rel - b / 2) / (2 * smoothing))));
        end ElastoBacklash;

        model IdealGear "flange_a.phi = ratio flange_b.phi, lossless"
          parameter Real ratio(start = 1) "transmission ratio (flange_a.phi / flange_b.phi)";
          Modelica.Mechanics.Rotational.Interfaces.Flange_a flange_a;
          Modelica.Mechanics.Rotational.Interfaces.Flange_b flange_b;
          Modelica.Units.SI.Angle phi_a;
          Modelica.Units.SI.Angle phi_b;
        equation
          phi_a = flange_a.phi;
          phi_b = flange_b.phi;
          phi_a = ratio * phi_b;
          0 = ratio * flange_a.tau + flange_b.tau;
        end IdealGear;
      end Components;

      package Sources
        model Torque "flange.tau = -tau: the input torque drives the flange"
          input Real tau "driving torque [N.m]";
          Modelica.Mechanics.Rotational.Interfaces.Flange_b flange;
        equation
          flange.tau = -tau;
        end Torque;

        model ConstantTorque "a constant torque tau_constant acting on the flange"
          parameter Modelica.Units.SI.Torque tau_constant;
          Modelica.Mechanics.Rotational.Interfaces.Flange_b flange;
          Modelica.Units.SI.Torque tau;
        equation
          tau = -flange.tau;
          tau = tau_constant;
        end ConstantTorque;
      end Sources;

      package Sensors
        model AngleSensor "phi = flange.phi"
          Modelica.Mechanics.Rotational.Interfaces.Flange_a flange;
          output Real phi "[rad]";
        equation
          phi = flange.phi;
          0 = flange.tau;
        end AngleSensor;

        model SpeedSensor "w = der(flange.phi)"
          Modelica.Mechanics.Rotational.Interfaces.Flange_a flange;
          output Real w "[rad/s]";
        equation
          w = der(flange.phi);
          0 = flange.tau;
        end SpeedSensor;

        model TorqueSensor "tau = flange_a.tau, the cut torque between the flanges"
          Modelica.Mechanics.Rotational.Interfaces.Flange_a flange_a;
          Modelica.Mechanics.Rotational.Interfaces.Flange_b flange_b;
          output Real tau "[N.m]";
        equation
          flange_a.phi = flange_b.phi;
          flange_a.tau = tau;
          flange_b.tau = -tau;
        end TorqueSensor;
      end Sensors;
    end Rotational;

    package Translational
      package Interfaces
        connector Flange "a translational flange: absolute position, cut force"
          Modelica.Units.SI.Position s;
          flow Modelica.Units.SI.Force f;
        end Flange;

        connector Flange_a
          extends Flange;
        end Flange_a;

        connector Flange_b
          extends Flange;
        end Flange_b;

        partial model PartialCompliant "s_rel = flange_b.s - flange_a.s, f through"
          Flange_a flange_a;
          Flange_b flange_b;
          Modelica.Units.SI.Distance s_rel(start = 0);
          Modelica.Units.SI.Force f;
        equation
          s_rel = flange_b.s - flange_a.s;
          flange_b.f = f;
          flange_a.f = -f;
        end PartialCompliant;

        partial model PartialCompliantWithRelativeStates "PartialCompliant with v_rel = der(s_rel)"
          Flange_a flange_a;
          Flange_b flange_b;
          Modelica.Units.SI.Distance s_rel(start = 0);
          Modelica.Units.SI.Velocity v_rel(start = 0);
          Modelica.Units.SI.Force f;
        equation
          s_rel = flange_b.s - flange_a.s;
          v_rel = der(s_rel);
          flange_b.f = f;
          flange_a.f = -f;
        end PartialCompliantWithRelativeStates;
      end Interfaces;

      package Components
        model Fixed "flange fixed at s0"
          parameter Modelica.Units.SI.Position s0 = 0;
          Modelica.Mechanics.Translational.Interfaces.Flange_b flange;
        equation
          flange.s = s0;
        end Fixed;

        model Mass "m der(v) = flange_a.f + flange_b.f (a sliding mass of length L)"
          parameter Modelica.Units.SI.Mass m(min = 0, start = 1);
          parameter Modelica.Units.SI.Length L = 0;
          Modelica.Mechanics.Translational.Interfaces.Flange_a flange_a;
          Modelica.Mechanics.Translational.Interfaces.Flange_b flange_b;
          Modelica.Units.SI.Position s;
          Modelica.Units.SI.Velocity v;
          Modelica.Units.SI.Acceleration a;
        equation
          flange_a.s = s - L / 2;
          flange_b.s = s + L / 2;
          v = der(s);
          a = der(v);
          m * a = flange_a.f + flange_b.f;
        end Mass;

        model Spring "f = c (s_rel - s_rel0)"
          extends Modelica.Mechanics.Translational.Interfaces.PartialCompliant;
          parameter Modelica.Units.SI.TranslationalSpringConstant c(min = 0, start = 1);
          parameter Modelica.Units.SI.Distance s_rel0 = 0;
        equation
          f = c * (s_rel - s_rel0);
        end Spring;

        model Damper "f = d v_rel"
          extends Modelica.Mechanics.Translational.Interfaces.PartialCompliantWithRelativeStates;
          parameter Modelica.Units.SI.TranslationalDampingConstant d(min = 0, start = 0);
        equation
          f = d * v_rel;
        end Damper;

        model SpringDamper "f = c (s_rel - s_rel0) + d v_rel"
          extends Modelica.Mechanics.Translational.Interfaces.PartialCompliantWithRelativeStates;
          parameter Modelica.Units.SI.TranslationalSpringConstant c(min = 0, start = 1);
          parameter Modelica.Units.SI.TranslationalDampingConstant d(min = 0, start = 1);
          parameter Modelica.Units.SI.Distance s_rel0 = 0;
        equation
          f = c * (s_rel - s_rel0) + d * v_rel;
        end SpringDamper;
      end Components;

      package Sources
        model Force "flange.f = -f: the input force drives the flange"
          input Real f "driving force [N]";
          Modelica.Mechanics.Translational.Interfaces.Flange_b flange;
        equation
          flange.f = -f;
        end Force;
      end Sources;

      package Sensors
        model PositionSensor "s = flange.s"
          Modelica.Mechanics.Translational.Interfaces.Flange_a flange;
          output Real s "[m]";
        equation
          s = flange.s;
          0 = flange.f;
        end PositionSensor;

        model SpeedSensor "v = der(flange.s)"
          Modelica.Mechanics.Translational.Interfaces.Flange_a flange;
          output Real v "[m/s]";
        equation
          v = der(flange.s);
          0 = flange.f;
        end SpeedSensor;
      end Sensors;
    end Translational;
  end Mechanics;

  package Electrical
    package Analog
      package Interfaces
        connector Pin "an electrical pin: potential, current into the pin"
          Modelica.Units.SI.ElectricPotential v;
          flow Modelica.Units.SI.Current i;
        end Pin;

        connector PositivePin
          extends Pin;
        end PositivePin;

        connector NegativePin
          extends Pin;
        end NegativePin;

        partial model OnePort "v = p.v - n.v, i = p.i = -n.i"
          PositivePin p;
          NegativePin n;
          Modelica.Units.SI.Voltage v;
          Modelica.Units.SI.Current i;
        equation
          v = p.v - n.v;
          0 = p.i + n.i;
          i = p.i;
        end OnePort;
      end Interfaces;

      package Basic
        model Ground "p.v = 0"
          Modelica.Electrical.Analog.Interfaces.Pin p;
        equation
          p.v = 0;
        end Ground;

        model Resistor "v = R i"
          extends Modelica.Electrical.Analog.Interfaces.OnePort;
          parameter Modelica.Units.SI.Resistance R(start = 1);
        equation
          v = R * i;
        end Resistor;

        model Inductor "L der(i) = v"
          extends Modelica.Electrical.Analog.Interfaces.OnePort;
          parameter Modelica.Units.SI.Inductance L(start = 1);
        equation
          L * der(i) = v;
        end Inductor;

        model Capacitor "C der(v) = i"
          extends Modelica.Electrical.Analog.Interfaces.OnePort;
          parameter Modelica.Units.SI.Capacitance C(min = 0, start = 1);
        equation
          i = C * der(v);
        end Capacitor;

        model RotationalEMF "k w = v, flange.tau = -k i (MSL 4's name; EMF in MSL 3)"
          parameter Modelica.Units.SI.ElectricalTorqueConstant k(start = 1) "transformation coefficient";
          Modelica.Electrical.Analog.Interfaces.PositivePin p;
          Modelica.Electrical.Analog.Interfaces.NegativePin n;
          Modelica.Mechanics.Rotational.Interfaces.Flange_b flange;
          Modelica.Units.SI.Voltage v;
          Modelica.Units.SI.Current i;
          Modelica.Units.SI.Angle phi;
          Modelica.Units.SI.AngularVelocity w;
          Modelica.Units.SI.Torque tau;
        equation
          v = p.v - n.v;
          0 = p.i + n.i;
          i = p.i;
          phi = flange.phi;
          w = der(phi);
          k * w = v;
          tau = -k * i;
          tau = flange.tau;
        end RotationalEMF;

        model EMF "MSL 3's name of RotationalEMF"
          extends Modelica.Electrical.Analog.Basic.RotationalEMF;
        end EMF;
      end Basic;

      package Sources
        model SignalVoltage "v = p.v - n.v, the input voltage"
          Modelica.Electrical.Analog.Interfaces.PositivePin p;
          Modelica.Electrical.Analog.Interfaces.NegativePin n;
          input Real v "voltage between the pins [V]";
          Modelica.Units.SI.Current i;
        equation
          v = p.v - n.v;
          0 = p.i + n.i;
          i = p.i;
        end SignalVoltage;

        model ConstantVoltage "v = V"
          extends Modelica.Electrical.Analog.Interfaces.OnePort;
          parameter Modelica.Units.SI.Voltage V(start = 1);
        equation
          v = V;
        end ConstantVoltage;

        model SignalCurrent "i = p.i, the input current"
          Modelica.Electrical.Analog.Interfaces.PositivePin p;
          Modelica.Electrical.Analog.Interfaces.NegativePin n;
          input Real i "current through the source [A]";
          Modelica.Units.SI.Voltage v;
        equation
          v = p.v - n.v;
          0 = p.i + n.i;
          i = p.i;
        end SignalCurrent;
      end Sources;

      package Sensors
        model CurrentSensor "i = p.i, no voltage drop"
          Modelica.Electrical.Analog.Interfaces.PositivePin p;
          Modelica.Electrical.Analog.Interfaces.NegativePin n;
          output Real i "[A]";
        equation
          p.v = n.v;
          p.i = i;
          n.i = -i;
        end CurrentSensor;

        model VoltageSensor "v = p.v - n.v, no current"
          Modelica.Electrical.Analog.Interfaces.PositivePin p;
          Modelica.Electrical.Analog.Interfaces.NegativePin n;
          output Real v "[V]";
        equation
          p.i = 0;
          n.i = 0;
          v = p.v - n.v;
        end VoltageSensor;
      end Sensors;
    end Analog;
  end Electrical;
end Modelica;
