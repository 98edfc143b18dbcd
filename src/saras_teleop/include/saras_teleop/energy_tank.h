/**
 * @file energy_tank.h
 * @brief Energy tank of the passivity layer (Ferraguti et al., IEEE T-RO 2015; Franken et al.,
 *        IEEE T-RO 2011), ROS-agnostic.
 *
 * One tank serves several power ports (one per teleoperation channel). Each port pairs a desired
 * action a (6-vector: a wrench [N, N m] on the master side, a twist [m/s, rad/s] on the slave side)
 * with its measured conjugate variable m (the measured twist of the master device, or the effort
 * the slave tool exerts on the environment). The power that leaves the tank through a port is
 * a_impl . m [W].
 *
 * Tank state xt with stored energy T = xt^2 / 2 [J]. Energy balance (per step, exact):
 *
 *     dT/dt = sigma*D - sum_ports(a_impl . m) + sigma*Pin - Pout
 *
 * hence, since dT/dt = xt * dxt/dt,
 *
 *     dxt/dt = (sigma*D + sigma*Pin - Pout) / xt - sum_ports(a_impl . m) / xt
 *
 * (the deliverable's printed update adds sigma*D without dividing by xt; that is fixed here).
 * The tank integrates T directly, so the ledger closes to rounding error; xt = sqrt(2 T).
 *
 *  - sigma = 1 if T < T_max (the tank may store), else 0;
 *  - beta  = 1 if T > T_ava (the tank may give energy to its peer);
 *  - Ereq  = 1 if T < T_req (the tank asks its peer for energy);
 *  - D     = sum m' B(T) m, power of the damping injected at the ports (B diagonal, scheduled);
 *  - Pout  = (1 - sigma) * D + extEreq * beta * P_const, power sent to the peer tank;
 *  - KE    = Ereq * (1 - (T - T_min) / (T_req - T_min)) in [0, 1], set-point reduction;
 *  - the reduced action (1 - KE) a is implemented only if the tank stays above T_min afterwards,
 *    otherwise it is zero; the damping action -B m is always added.
 */
#ifndef SARAS_TELEOP_ENERGY_TANK_H
#define SARAS_TELEOP_ENERGY_TANK_H

#include <cstddef>
#include <string>
#include <vector>

#include <Eigen/Core>

namespace saras_teleop
{
/// 6-vector [linear(3); angular(3)].
typedef Eigen::Matrix<double, 6, 1> Vector6d;

/// Tank parameters. Defaults from Ferraguti 2015 (upper bound 20 J, T_ava 10 J, T_req 5 J, T_min 1 J).
struct TankParams
{
  double T_init = 10.0;   ///< initial energy [J]
  double T_max = 20.0;    ///< upper bound; above it dissipated power is passed on [J]
  double T_min = 1.0;     ///< lower bound, never crossed [J]
  double T_req = 5.0;     ///< below it the tank requests energy and reduces set-points [J]
  double T_ava = 10.0;    ///< above it the tank may give energy on request [J]
  double P_const = 2.0;   ///< power sent to the peer tank on request [W]
  Vector6d damping_std = Vector6d::Constant(0.5);  ///< damping with enough energy [N s/m | N m s/rad] (master) or [m/(N s)] (slave)
  Vector6d damping_max = Vector6d::Constant(5.0);  ///< damping at T_min, same units
  bool bypass = false;    ///< pass desired actions through unchanged (for comparison experiments only)

  /// Throws std::invalid_argument naming the offending parameter.
  void validate() const;
};

/**
 * Continuous damping schedule: d_std for T >= T_req, d_max for T <= T_min, linear in between.
 * T_max and T_ava are accepted to mirror the deliverable's get_damping() signature; the schedule
 * does not depend on them.
 */
double getDamping(double T_max, double T_min, double T_req, double T_ava, double d_std, double d_max,
                  double T);

/// What happened in the last step (for publishing and tests).
struct TankStepInfo
{
  double sigma = 1.0;
  double beta = 0.0;
  double ereq = 0.0;
  double KE = 0.0;
  double D = 0.0;          ///< damping power [W]
  double pin = 0.0;        ///< accepted input power from the peer [W]
  double pout = 0.0;       ///< output power to the peer [W]
  double port_power = 0.0; ///< sum a_impl . m [W]
  double clipped = 0.0;    ///< energy discarded by the T_max clamp in this step [J]
  bool implemented = true; ///< false if the reduced action was zeroed for lack of energy
};

/// Cumulative energy ledger [J]: T - T_init == stored_damping + received - sent - ports - clipped.
struct TankLedger
{
  double stored_damping = 0.0;
  double received = 0.0;
  double sent = 0.0;
  double ports = 0.0;
  double clipped = 0.0;
};

/**
 * Energy tank with a fixed number of ports. step() does not allocate.
 */
class EnergyTank
{
public:
  EnergyTank(const TankParams& params, std::size_t num_ports);

  std::size_t numPorts() const { return desired_.size(); }
  /// Desired action of a port (held until changed). Non-finite values are replaced by zero.
  void setDesired(std::size_t port, const Vector6d& a);
  /// Measured conjugate variable of a port (held). Non-finite values are replaced by zero.
  void setConjugate(std::size_t port, const Vector6d& m);

  /**
   * Advance by dt [s].
   * @param pin     power received from the peer tank during this step [W] (negative/NaN -> 0)
   * @param ext_ereq peer's energy request (> 0.5 means requested)
   * @return false (and no state change) if dt is not finite and positive.
   */
  bool step(double dt, double pin, double ext_ereq);

  /// Implemented action of a port after the last step (reduced action + damping).
  const Vector6d& output(std::size_t port) const { return output_[port]; }
  double energy() const { return T_; }
  double xt() const { return xt_; }
  double pout() const { return info_.pout; }
  double ereq() const { return info_.ereq; }
  const TankStepInfo& info() const { return info_; }
  const TankLedger& ledger() const { return ledger_; }
  const TankParams& params() const { return p_; }
  /// Inputs replaced by zero because they were not finite (since start).
  std::size_t rejectedInputs() const { return rejected_; }

  /// Right-hand side of the xt dynamics for given flows (for tests and documentation) [sqrt(J)/s].
  static double xtDot(double xt, double sigma, double D, double pin, double pout, double port_power);

private:
  TankParams p_;
  std::vector<Vector6d> desired_;
  std::vector<Vector6d> conjugate_;
  std::vector<Vector6d> output_;
  double T_;
  double xt_;
  TankStepInfo info_;
  TankLedger ledger_;
  std::size_t rejected_ = 0;
};

}  // namespace saras_teleop

#endif  // SARAS_TELEOP_ENERGY_TANK_H
