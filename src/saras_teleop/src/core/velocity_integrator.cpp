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
  if (!(std::isfinite(max_lead) && max_lead > 0.0))
    throw std::invalid_argument("parameter 'max_lead' must be finite and > 0 m");
  if (!(std::isfinite(max_stall) && max_stall > 0.0))
    throw std::invalid_argument("parameter 'max_stall' must be finite and > 0 s");
}

namespace
{
bool finiteFrame(const KDL::Frame& pose)
{
  for (int i = 0; i < 3; ++i)
    if (!std::isfinite(pose.p[i]))
      return false;
  double x, y, z, w;
  pose.M.GetQuaternion(x, y, z, w);
  return std::isfinite(x) && std::isfinite(y) && std::isfinite(z) && std::isfinite(w);
}
}  // namespace

VelocityIntegrator::VelocityIntegrator(const IntegratorParams& p) : p_(p)
{
  p_.validate();
}

bool VelocityIntegrator::start(const KDL::Frame& pose, bool await_clutch)
{
  if (!finiteFrame(pose))
    return false;
  pose_ = pose;
  started_ = true;
  mode_ = Mode::FOLLOWING;
  if (await_clutch)
    fault("restarted: waiting for the operator's clutch");
  return true;
}

bool VelocityIntegrator::setMeasured(const KDL::Frame& pose)
{
  if (!finiteFrame(pose))
    return false;
  measured_ = pose;
  have_measured_ = true;
  return true;
}

void VelocityIntegrator::fault(const std::string& why)
{
  if (mode_ == Mode::WAITING)
    return;
  if (mode_ != Mode::FAULT)
    ++faults_;
  // the set-point freezes: the arm already holds this (latest) target, so holding it adds no motion;
  // the measured pose is not re-commanded here (under load it is up to a few 100 ms old)
  mode_ = Mode::FAULT;
  why_ = why;
  stalled_ = 0.0;
}

bool VelocityIntegrator::clutch(bool pressed)
{
  if (pressed && (mode_ == Mode::FOLLOWING || mode_ == Mode::FAULT))
  {
    mode_ = Mode::CLUTCHED;
    return false;
  }
  if (!pressed && mode_ == Mode::CLUTCHED)
  {
    if (have_measured_)
      pose_ = measured_;  // re-anchor: resume from where the arm is
    mode_ = Mode::FOLLOWING;
    why_.clear();
    stalled_ = 0.0;
    return true;
  }
  return false;
}

void VelocityIntegrator::setSpeedScale(double scale)
{
  if (std::isfinite(scale) && scale > 0.0 && scale <= 1.0)
    speed_scale_ = scale;
}

double VelocityIntegrator::lead() const
{
  return have_measured_ ? (pose_.p - measured_.p).Norm() : 0.0;
}

bool VelocityIntegrator::limitLead(KDL::Frame& next) const
{
  if (!have_measured_)
    return false;
  const KDL::Vector d = next.p - measured_.p;
  const double n = d.Norm();
  const double allowed = std::max(p_.max_lead, (pose_.p - measured_.p).Norm());
  if (n <= p_.max_lead || n <= allowed - 1e-12)
    return false;
  next.p = measured_.p + d * (allowed / n);
  return true;
}

void VelocityIntegrator::step(const Vector6d& twist, double dt, bool hold)
{
  if (!started_ || mode_ != Mode::FOLLOWING || hold || !(std::isfinite(dt) && dt > 0.0 && dt <= 0.1))
    return;
  Vector6d v = twist;
  if (!v.allFinite())
  {
    ++rejected_;
    return;
  }
  const double vmax = speed_scale_ * p_.max_linear_velocity, wmax = speed_scale_ * p_.max_angular_velocity;
  const double nl = v.head<3>().norm();
  if (nl > vmax)
    v.head<3>() *= vmax / nl;
  const double na = v.tail<3>().norm();
  if (na > wmax)
    v.tail<3>() *= wmax / na;
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
  if (limitLead(next))
  {
    ++lead_limited_;
    stalled_ += dt;
    if (stalled_ > p_.max_stall)
    {
      fault("arm not following the set-point");
      return;
    }
  }
  else
    stalled_ = 0.0;
  pose_ = next;
}

}  // namespace saras_teleop
