/**
 * @file velocity_integrator.h
 * @brief Slave pose set-point from the implemented slave twist (D7.2 Section 5.5), ROS-agnostic.
 *
 * pose <- KDL::addDelta(pose, twist, dt) (twist in the slave base frame: translation += v dt,
 * rotation <- Rot(w dt) * rotation). The twist is first limited (|v| <= max_linear_velocity,
 * |w| <= max_angular_velocity, direction kept), then the position is clamped to the workspace box.
 * While holding (stale master link, no recent twist) the set-point does not move.
 */
#ifndef SARAS_TELEOP_VELOCITY_INTEGRATOR_H
#define SARAS_TELEOP_VELOCITY_INTEGRATOR_H

#include <cstddef>

#include <Eigen/Core>
#include <kdl/frames.hpp>

#include "saras_teleop/energy_tank.h"

namespace saras_teleop
{
struct IntegratorParams
{
  double max_linear_velocity = 0.05;   ///< [m/s]
  double max_angular_velocity = 1.0;   ///< [rad/s]
  Eigen::Vector3d workspace_min = Eigen::Vector3d::Constant(-1.0);  ///< box in the slave base frame [m]
  Eigen::Vector3d workspace_max = Eigen::Vector3d::Constant(1.0);   ///< [m]
  /// Throws std::invalid_argument naming the offending parameter.
  void validate() const;
};

class VelocityIntegrator
{
public:
  explicit VelocityIntegrator(const IntegratorParams& p);

  /// Start pose (measured slave pose). Returns false if not finite.
  bool start(const KDL::Frame& pose);
  bool started() const { return started_; }

  /**
   * Integrate one step.
   * @param twist commanded twist [m/s, rad/s] in the slave base frame (non-finite -> zero + counter)
   * @param dt    step [s]; ignored if not finite/positive or longer than 0.1 s
   * @param hold  true: keep the set-point
   */
  void step(const Vector6d& twist, double dt, bool hold);

  const KDL::Frame& pose() const { return pose_; }
  std::size_t rejected() const { return rejected_; }
  std::size_t clampedSteps() const { return clamped_; }

private:
  IntegratorParams p_;
  bool started_ = false;
  KDL::Frame pose_;
  std::size_t rejected_ = 0;
  std::size_t clamped_ = 0;
};

}  // namespace saras_teleop

#endif  // SARAS_TELEOP_VELOCITY_INTEGRATOR_H
