#include "saras_teleop/velocity_integrator.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace saras_teleop
{
void IntegratorParams::validate() const
{
  if (!(std::isfinite(max_linear_velocity) && max_linear_velocity > 0.0))
    throw std::invalid_argument("parameter 'max_linear_velocity' must be finite and > 0 m/s");
  if (!(std::isfinite(max_angular_velocity) && max_angular_velocity > 0.0))
    throw std::invalid_argument("parameter 'max_angular_velocity' must be finite and > 0 rad/s");
  if (!(workspace_min.allFinite() && workspace_max.allFinite() &&
        (workspace_min.array() < workspace_max.array()).all()))
    throw std::invalid_argument("parameters 'workspace_min'/'workspace_max' must be finite with min < max on every axis");
}

VelocityIntegrator::VelocityIntegrator(const IntegratorParams& p) : p_(p)
{
  p_.validate();
}

bool VelocityIntegrator::start(const KDL::Frame& pose)
{
  for (int i = 0; i < 3; ++i)
    if (!std::isfinite(pose.p[i]))
      return false;
  double x, y, z, w;
  pose.M.GetQuaternion(x, y, z, w);
  if (!(std::isfinite(x) && std::isfinite(y) && std::isfinite(z) && std::isfinite(w)))
    return false;
  pose_ = pose;
  started_ = true;
  return true;
}

void VelocityIntegrator::step(const Vector6d& twist, double dt, bool hold)
{
  if (!started_ || hold || !(std::isfinite(dt) && dt > 0.0 && dt <= 0.1))
    return;
  Vector6d v = twist;
  if (!v.allFinite())
  {
    ++rejected_;
    return;
  }
  const double nl = v.head<3>().norm();
  if (nl > p_.max_linear_velocity)
    v.head<3>() *= p_.max_linear_velocity / nl;
  const double na = v.tail<3>().norm();
  if (na > p_.max_angular_velocity)
    v.tail<3>() *= p_.max_angular_velocity / na;
  const KDL::Twist t(KDL::Vector(v[0], v[1], v[2]), KDL::Vector(v[3], v[4], v[5]));
  KDL::Frame next = KDL::addDelta(pose_, t, dt);
  bool clamped = false;
  for (int i = 0; i < 3; ++i)
  {
    // A coordinate already outside the box (start pose) may only move back towards it.
    const double lo = std::min(p_.workspace_min[i], pose_.p[i]);
    const double hi = std::max(p_.workspace_max[i], pose_.p[i]);
    const double c = std::min(hi, std::max(lo, next.p[i]));
    if (c != next.p[i])
      clamped = true;
    next.p[i] = c;
  }
  if (clamped)
    ++clamped_;
  pose_ = next;
}

}  // namespace saras_teleop
