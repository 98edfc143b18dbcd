#include "saras_teleop/twist_estimator.h"

#include <cmath>
#include <stdexcept>

namespace saras_teleop
{
namespace
{
bool finiteFrame(const KDL::Frame& f)
{
  for (int i = 0; i < 3; ++i)
  {
    if (!std::isfinite(f.p[i]))
      return false;
    for (int j = 0; j < 3; ++j)
      if (!std::isfinite(f.M(i, j)))
        return false;
  }
  return true;
}
}  // namespace

TwistEstimator::TwistEstimator(double cutoff_hz, double max_gap)
{
  if (!(std::isfinite(cutoff_hz) && cutoff_hz > 0.0))
    throw std::invalid_argument("parameter 'low_pass_cutoff' must be finite and > 0 Hz");
  if (!(std::isfinite(max_gap) && max_gap > 0.0))
    throw std::invalid_argument("parameter 'max_gap' must be finite and > 0 s");
  tau_ = 1.0 / (2.0 * M_PI * cutoff_hz);
  max_gap_ = max_gap;
}

TwistEstimator::Result TwistEstimator::addSample(double t, const KDL::Frame& pose)
{
  if (!std::isfinite(t) || !finiteFrame(pose))
  {
    ++rejected_;
    return REJECTED;
  }
  if (!have_ || t - t_last_ > max_gap_)
  {
    have_ = true;
    t_last_ = t;
    last_ = pose;
    twist_.setZero();
    return RESET;
  }
  const double dt = t - t_last_;
  if (dt <= 0.0)
    return SAME_SAMPLE;
  const KDL::Twist d = KDL::diff(last_, pose, dt);  // base-frame twist: vel = dp/dt, rot = rotvec(R R0^T)/dt
  Vector6d raw;
  raw << d.vel.x(), d.vel.y(), d.vel.z(), d.rot.x(), d.rot.y(), d.rot.z();
  const double alpha = dt / (dt + tau_);
  twist_ += alpha * (raw - twist_);
  t_last_ = t;
  last_ = pose;
  return UPDATED;
}

Vector6d rotateWrench(const KDL::Rotation& R_b_a, const Vector6d& w_a)
{
  const KDL::Vector f = R_b_a * KDL::Vector(w_a[0], w_a[1], w_a[2]);
  const KDL::Vector tq = R_b_a * KDL::Vector(w_a[3], w_a[4], w_a[5]);
  Vector6d w_b;
  w_b << f.x(), f.y(), f.z(), tq.x(), tq.y(), tq.z();
  return w_b;
}

}  // namespace saras_teleop
