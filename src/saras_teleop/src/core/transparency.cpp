#include "saras_teleop/transparency.h"

#include <cmath>
#include <stdexcept>
#include <string>

namespace saras_teleop
{
void TransparencyParams::validate() const
{
  if (!(std::isfinite(pose_error_gain) && pose_error_gain >= 0.0))
    throw std::invalid_argument("parameter 'pose_error_gain' must be finite and >= 0 N/m");
  if (!(std::isfinite(scale_factor) && scale_factor > 0.0))
    throw std::invalid_argument("parameter 'scale_factor' must be finite and > 0");
  if (!(std::isfinite(rotation_scale) && rotation_scale >= 0.0))
    throw std::invalid_argument("parameter 'rotation_scale' must be finite and >= 0");
  if (!(std::isfinite(max_force) && max_force > 0.0))
    throw std::invalid_argument("parameter 'max_force' must be finite and > 0 N");
  if (!(std::isfinite(contact_force_scale) && contact_force_scale >= 0.0))
    throw std::invalid_argument("parameter 'contact_force_scale' must be finite and >= 0");
}

TransparencyChannel::TransparencyChannel(const TransparencyParams& p) : p_(p)
{
  p_.validate();
}

bool TransparencyChannel::setMasterPosition(const Eigen::Vector3d& m)
{
  if (!m.allFinite())
    return false;
  m_ = m;
  have_master_ = true;
  return true;
}

bool TransparencyChannel::setMasterTwist(const Vector6d& v)
{
  if (!v.allFinite())
    return false;
  v_ = v;
  return true;
}

bool TransparencyChannel::setSlavePosition(const Eigen::Vector3d& s)
{
  if (!s.allFinite())
    return false;
  s_ = s;
  have_slave_ = true;
  return true;
}

bool TransparencyChannel::setFixtureWrench(const Vector6d& w)
{
  if (!w.allFinite())
    return false;
  fixture_ = w;
  return true;
}

bool TransparencyChannel::setContactForce(const Eigen::Vector3d& f)
{
  if (!f.allFinite())
    return false;
  contact_ = f;
  return true;
}

TransparencyChannel::State TransparencyChannel::update(Vector6d& des_wrench, Vector6d& des_twist)
{
  des_wrench.setZero();
  des_twist.setZero();
  if (state_ == WAITING)
  {
    if (!(have_master_ && have_slave_))
      return state_;
    m0_ = m_;
    s0_ = s_;
    state_ = RUNNING;
  }
  const bool hold = clutch_ || !link_ok_;
  if (hold)
  {
    state_ = HOLD;
    return state_;
  }
  if (state_ == HOLD)
  {
    // Re-index: the operator moved the master (clutch) or the link was down; continue from here.
    m0_ = m_;
    s0_ = s_;
    state_ = RUNNING;
  }
  const Eigen::Vector3d err = (s_ - s0_) / p_.scale_factor - (m_ - m0_);
  Eigen::Vector3d f = p_.pose_error_gain * err + fixture_.head<3>();
  if (p_.contact_feedback)
    f += p_.contact_force_scale * contact_;
  const double n = f.norm();
  if (n > p_.max_force)
    f *= p_.max_force / n;
  des_wrench.head<3>() = f;
  des_wrench.tail<3>() = fixture_.tail<3>();
  des_twist.head<3>() = p_.scale_factor * v_.head<3>();
  des_twist.tail<3>() = p_.rotation_scale * v_.tail<3>();
  return state_;
}

}  // namespace saras_teleop
