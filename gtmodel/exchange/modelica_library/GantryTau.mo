// The Gantry-Tau robots of gtmodel as Modelica classes (Dressler (2012), ch. 3.3-3.4, 4 and 6).
// Shipped with gtmodel (gtmodel.exchange.robot_library adds this package when a .mo/.mop file
// names GantryTau.); written for the thesis' Optimica listing opt_robot (problems/optimica/opt_robot.mop).
package GantryTau "Gantry-Tau robot models"

  model L1 "L1 Gantry-Tau, 3-link model: TCP states, actuator torque inputs, rigid-body dynamics with friction"
    // The structure of the thesis' robotmodel (ch. 3.3): tool and joint coordinates related by
    // f_kin, f_vel, f_acc; a force/torque balance f_t; the TCP position and velocity as states.
    // The values are those of gtmodel/robots/data/L1.toml: Table 5.1 modified nominal kinematics
    // (laser-tracker frame, z up) and Table 6.3 model 2 dynamics (symmetric Coulomb + viscous
    // friction, link masses identified as ~0 and neglected); the Coulomb sign is tanh(vq / w),
    // gtmodel's smooth form for optimisation (gtmodel.robots.friction, "tanh").
    parameter Real L[3] = {2.0608, 2.0633, 2.0611} "link lengths [m]";
    // As_i, the joint point of arm i at q_i = 0, and v_i, its guideway direction, by coordinate
    // (pymoca 0.12 reads no two-dimensional parameter: Asx[i] is As_i's x)
    parameter Real Asx[3] = {-1.8089, -1.8656, -1.8086} "x of As_i [m]";
    parameter Real Asy[3] = {3.5093, 2.2456, 3.2774} "y of As_i [m]";
    parameter Real Asz[3] = {0.0039, 0.2074, -1.4434} "z of As_i [m]";
    parameter Real vx[3] = {0.9994, 0.9990, 0.9997} "x of v_i";
    parameter Real vy[3] = {-0.0293, -0.0264, -0.0296} "y of v_i";
    parameter Real vz[3] = {-0.0022, -0.0045, -0.0014} "z of v_i";
    parameter Real s[3] = {-1, -1, -1} "inverse-kinematics root sign per arm (configuration 0: the TCP ahead of every cart)";
    parameter Real m_p = 9.13 "end-effector plate mass [kg]";
    parameter Real m_c[3] = {13.58, 13.64, 38.23} "cart masses [kg]";
    parameter Real f_c[3] = {128.62, 145.13, 194.57} "Coulomb friction [N]";
    parameter Real f_v[3] = {102.43, 355.25, 388.77} "viscous friction [N s/m]";
    parameter Real w = 0.01 "velocity width of the smooth Coulomb sign tanh(vq / w) [m/s]";
    parameter Real g = 9.81 "gravitational acceleration along -z [m/s2]";
    parameter Real F_nom = 450 "cart force of a unit actuator torque [N] (tau is normalised: |tau| <= 1 is |F| <= F_nom)";
    parameter Real jointAngleMax = 0.6981317007977318 "spherical-joint limit: link angle to its guideway, 40 deg [rad]";

    Real tcp[3] "tool centre point [m]";
    Real vtcp[3] "TCP velocity [m/s]";
    Real atcp[3] "TCP acceleration [m/s2]";
    Real q[3] "cart positions [m]";
    Real vq[3] "cart velocities [m/s]";
    Real aq[3] "cart accelerations [m/s2]";
    Real lambda[3] "link force per unit link vector (tension) [N/m]";
    Real F[3] "cart forces [N]";
    Real jointCos[3] "cosine of the link angle to its guideway";
    input Real tau[3] "actuator torques, normalised (F = F_nom * tau)";
  equation
    for i in 1:3 loop
      // f_kin: the closure |tcp - As_i - q_i v_i| = L_i (eq. 4.9) solved for q_i (inverse kinematics)
      q[i] = ((tcp[1] - Asx[i]) * vx[i] + (tcp[2] - Asy[i]) * vy[i] + (tcp[3] - Asz[i]) * vz[i]
              + s[i] * sqrt(((tcp[1] - Asx[i]) * vx[i] + (tcp[2] - Asy[i]) * vy[i] + (tcp[3] - Asz[i]) * vz[i]) ^ 2
                            - (vx[i] ^ 2 + vy[i] ^ 2 + vz[i] ^ 2)
                              * ((tcp[1] - Asx[i]) ^ 2 + (tcp[2] - Asy[i]) ^ 2 + (tcp[3] - Asz[i]) ^ 2 - L[i] ^ 2)))
             / (vx[i] ^ 2 + vy[i] ^ 2 + vz[i] ^ 2);
      // f_vel: the closure differentiated once
      0 = (tcp[1] - Asx[i] - q[i] * vx[i]) * (vtcp[1] - vq[i] * vx[i])
          + (tcp[2] - Asy[i] - q[i] * vy[i]) * (vtcp[2] - vq[i] * vy[i])
          + (tcp[3] - Asz[i] - q[i] * vz[i]) * (vtcp[3] - vq[i] * vz[i]);
      // f_acc: the closure differentiated twice
      0 = (tcp[1] - Asx[i] - q[i] * vx[i]) * (atcp[1] - aq[i] * vx[i])
          + (tcp[2] - Asy[i] - q[i] * vy[i]) * (atcp[2] - aq[i] * vy[i])
          + (tcp[3] - Asz[i] - q[i] * vz[i]) * (atcp[3] - aq[i] * vz[i])
          + (vtcp[1] - vq[i] * vx[i]) ^ 2 + (vtcp[2] - vq[i] * vy[i]) ^ 2 + (vtcp[3] - vq[i] * vz[i]) ^ 2;
      // f_t, cart i along its guideway: inertia and gravity = actuator force - friction + link force
      m_c[i] * (vx[i] ^ 2 + vy[i] ^ 2 + vz[i] ^ 2) * aq[i] + m_c[i] * g * vz[i]
        = F[i] - (f_c[i] * tanh(vq[i] / w) + f_v[i] * vq[i])
          + lambda[i] * ((tcp[1] - Asx[i] - q[i] * vx[i]) * vx[i] + (tcp[2] - Asy[i] - q[i] * vy[i]) * vy[i]
                         + (tcp[3] - Asz[i] - q[i] * vz[i]) * vz[i]);
      F[i] = F_nom * tau[i];
      jointCos[i] = -s[i] * ((tcp[1] - Asx[i] - q[i] * vx[i]) * vx[i] + (tcp[2] - Asy[i] - q[i] * vy[i]) * vy[i]
                             + (tcp[3] - Asz[i] - q[i] * vz[i]) * vz[i])
                    / (sqrt((tcp[1] - Asx[i] - q[i] * vx[i]) ^ 2 + (tcp[2] - Asy[i] - q[i] * vy[i]) ^ 2
                            + (tcp[3] - Asz[i] - q[i] * vz[i]) ^ 2)
                       * sqrt(vx[i] ^ 2 + vy[i] ^ 2 + vz[i] ^ 2));
    end for;
    // f_t, the plate (massless links: each pulls along itself)
    m_p * atcp[1] = -(lambda[1] * (tcp[1] - Asx[1] - q[1] * vx[1]) + lambda[2] * (tcp[1] - Asx[2] - q[2] * vx[2]) + lambda[3] * (tcp[1] - Asx[3] - q[3] * vx[3]));
    m_p * atcp[2] = -(lambda[1] * (tcp[2] - Asy[1] - q[1] * vy[1]) + lambda[2] * (tcp[2] - Asy[2] - q[2] * vy[2]) + lambda[3] * (tcp[2] - Asy[3] - q[3] * vy[3]));
    m_p * atcp[3] = -(lambda[1] * (tcp[3] - Asz[1] - q[1] * vz[1]) + lambda[2] * (tcp[3] - Asz[2] - q[2] * vz[2]) + lambda[3] * (tcp[3] - Asz[3] - q[3] * vz[3])) - m_p * g;
    // state equations
    der(tcp) = vtcp;
    der(vtcp) = atcp;
  end L1;

end GantryTau;
