/**
 * @file teleop_sim.h
 * @brief Core-level closed-loop simulation of one teleoperation channel with the real core classes
 *        (TwistEstimator, TransparencyChannel, EnergyTank x2, VelocityIntegrator, DelayChannel).
 *
 * Operator: spring-damper hand pulling a master of mass m_m towards x_h(t) = A sin(2 pi f t) e_x.
 * Master: m_m a = K_h (x_h - x) - B_h v + F_dev, F_dev = tank_master output (zero-order hold).
 * Link: master pose/twist forward and desired wrench backward through DelayChannel, tank powers
 * exchanged as energy packets (each packet = Pout * dt, consumed once by the receiver).
 * Slave: velocity_integrator set-point p; a position servo of stiffness K_r holds the tool at p
 * unless a wall at x = x_w (stiffness K_e) stops it (quasi-static): s = p, or
 * s_x = (K_r p_x + K_e x_w) / (K_r + K_e) in contact. The contact force is sampled at force_rate.
 *
 * Energies [J] (exact for the discrete simulation): work of the master device on operator+master,
 * E_dev = sum F_dev . (x_{k+1} - x_k); energy put into servo and wall springs by the slave,
 * E_slave = U(t) - U(0); E_out = E_dev + E_slave is what the teleoperator delivered at its ports.
 * Passivity with tanks: E_out(t) <= T_master(0) + T_slave(0) for all t.
 */
#ifndef SARAS_TELEOP_TELEOP_SIM_H
#define SARAS_TELEOP_TELEOP_SIM_H

#include <vector>

#include <Eigen/Core>

#include "saras_teleop/delay_channel.h"
#include "saras_teleop/energy_tank.h"
#include "saras_teleop/transparency.h"
#include "saras_teleop/velocity_integrator.h"

namespace saras_teleop
{
struct SimParams
{
  double dt = 1e-3;             ///< control period [s]
  double duration = 10.0;       ///< [s]
  double master_mass = 0.15;    ///< device + hand mass [kg]
  double hand_stiffness = 100.0;///< [N/m]
  double hand_damping = 1.0;    ///< [N s/m]
  double hand_amplitude = 0.03; ///< [m]
  double hand_frequency = 0.5;  ///< [Hz]
  double wall = 1.0;            ///< wall position along slave x, relative to the slave start [m]
  double env_stiffness = 2000.0;   ///< K_e [N/m]
  double robot_stiffness = 5000.0; ///< K_r [N/m]
  double force_rate = 60.0;     ///< contact-force sample rate [Hz] (D7.2 Section 8: 60 Hz)
  double twist_cutoff = 50.0;   ///< tf_transformer low-pass [Hz]
  ChannelParams forward;        ///< master -> slave (pose, twist, Pout, Ereq)
  ChannelParams backward;       ///< slave -> master (desired wrench, Pout, Ereq)
  TankParams master_tank;
  TankParams slave_tank;
  TransparencyParams transparency;
  IntegratorParams integrator;
  double contact_force_sign = -1.0;  ///< slave tank conjugate = sign * (force of the wall on the tool)
  int trace_every = 10;         ///< keep every n-th sample in the trace
};

struct SimSample
{
  double t, master_x, slave_x, setpoint_x, T_master, T_slave, E_out, force_dev;
};

struct SimResult
{
  double E0 = 0.0;            ///< initial tank energy [J]
  double E_dev = 0.0;         ///< final work of the master device [J]
  double E_slave = 0.0;       ///< final energy in servo + wall springs [J]
  double E_out_max = -1e300;  ///< max over time of E_dev + E_slave [J]
  double E_out_final = 0.0;
  double T_master_min = 1e300, T_slave_min = 1e300;
  double master_excursion = 0.0;  ///< max |x_m - x_m(0)| [m]
  double slave_excursion = 0.0;   ///< max |s - s(0)| [m]
  double tracking_rms = 0.0;      ///< RMS |p - p0 - scale (x_m - x_m0)| over the run [m]
  double max_force = 0.0;         ///< max |F_dev| [N]
  std::vector<SimSample> trace;
};

SimResult runSimulation(const SimParams& p);

}  // namespace saras_teleop

#endif  // SARAS_TELEOP_TELEOP_SIM_H
