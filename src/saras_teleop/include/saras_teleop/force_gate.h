/**
 * @file force_gate.h
 * @brief Plausibility gate of a measured interaction force entering an energy tank, ROS-agnostic.
 *
 * A sample is implausible when it is not finite, its magnitude exceeds max_force, or it differs from
 * the last accepted sample by more than max_step + max_rate * dt. An implausible sample puts the
 * port on HOLD for hold_time (restarted by every further violation): the caller then zeroes the
 * port's action and measurement, so the robot does not move. A sample of plausible magnitude still
 * becomes the reference of the rate check while on hold (a genuine step costs one hold, not all).
 * A force older than timeout is stale: the caller uses zero (free motion) and reports it.
 */
#ifndef SARAS_TELEOP_FORCE_GATE_H
#define SARAS_TELEOP_FORCE_GATE_H

#include <cstddef>
#include <string>

#include <Eigen/Core>

namespace saras_teleop
{
struct ForceGateParams
{
  double max_force = 30.0;  ///< [N] largest plausible |F|
  double max_step = 10.0;   ///< [N] largest change between two samples, plus max_rate * dt
  double max_rate = 300.0;  ///< [N/s]
  double hold_time = 0.5;   ///< [s] hold after a violation
  double timeout = 0.1;     ///< [s] older force = stale (zero)
  /// Throws std::invalid_argument naming the offending parameter.
  void validate() const;
};

class ForceGate
{
public:
  enum class Verdict
  {
    ACCEPTED,
    MAGNITUDE,  ///< |F| > max_force (or not finite)
    RATE        ///< change too fast
  };

  explicit ForceGate(const ForceGateParams& p);

  /// New sample @p f [N] at time @p t [s] (monotonic).
  Verdict offer(const Eigen::Vector3d& f, double t);
  /// true while a violation holds the port (at time @p t)
  bool holding(double t) const { return t < hold_until_; }
  /// true if the last accepted sample is older than timeout (or none yet)
  bool stale(double t) const { return !have_ || t - t_ > p_.timeout; }
  /// Force to use at @p t: the last accepted one, zero if stale or holding.
  Eigen::Vector3d force(double t) const;
  std::size_t violations() const { return violations_; }
  /// Last violation in words (empty if none)
  const std::string& lastViolation() const { return why_; }
  const ForceGateParams& params() const { return p_; }

private:
  ForceGateParams p_;
  Eigen::Vector3d f_ = Eigen::Vector3d::Zero();  // last accepted (or rate reference)
  double t_ = 0.0, hold_until_ = -1.0;
  bool have_ = false;
  std::size_t violations_ = 0;
  std::string why_;
};

}  // namespace saras_teleop

#endif  // SARAS_TELEOP_FORCE_GATE_H
