/**
 * @file twist_estimator.h
 * @brief Pose tracking and low-pass filtered twist of the master (tf_transformer core), ROS-agnostic.
 *
 * Twist from consecutive pose samples (by sample time, not loop time): linear = dp/dt,
 * angular = rotation vector of R_k R_{k-1}^T / dt (both in the reference frame), then a first-order
 * low-pass filter y += alpha (x - y), alpha = dt / (dt + 1 / (2 pi f_c)). Samples with a non-increasing
 * time are ignored (no new data), non-finite samples are rejected, a gap longer than max_gap resets
 * the estimate to zero.
 */
#ifndef SARAS_TELEOP_TWIST_ESTIMATOR_H
#define SARAS_TELEOP_TWIST_ESTIMATOR_H

#include <cstddef>

#include <kdl/frames.hpp>

#include "saras_teleop/energy_tank.h"

namespace saras_teleop
{
class TwistEstimator
{
public:
  /**
   * @param cutoff_hz low-pass cut-off frequency [Hz] (> 0)
   * @param max_gap   longest sample gap still differentiated [s] (> 0)
   */
  TwistEstimator(double cutoff_hz, double max_gap);

  enum Result
  {
    UPDATED,
    SAME_SAMPLE,  ///< time not newer than the last sample: ignored
    REJECTED,     ///< non-finite pose or time
    RESET         ///< first sample or gap > max_gap: twist set to zero
  };
  /// Add a pose sample taken at time t [s].
  Result addSample(double t, const KDL::Frame& pose);
  /// Decay to zero when no sample arrives (stale master): twist is cleared.
  void clear() { twist_.setZero(); }

  const Vector6d& twist() const { return twist_; }
  const KDL::Frame& pose() const { return last_; }
  bool valid() const { return have_; }
  double lastTime() const { return t_last_; }
  std::size_t rejected() const { return rejected_; }

private:
  double tau_;
  double max_gap_;
  bool have_ = false;
  double t_last_ = 0.0;
  KDL::Frame last_;
  Vector6d twist_ = Vector6d::Zero();
  std::size_t rejected_ = 0;
};

/// Rotate a wrench (force, torque) given in frame A into frame B with R = rotation of A in B.
/// The point of application is kept (the stylus), so no moment transfer is added.
Vector6d rotateWrench(const KDL::Rotation& R_b_a, const Vector6d& w_a);

}  // namespace saras_teleop

#endif  // SARAS_TELEOP_TWIST_ESTIMATOR_H
