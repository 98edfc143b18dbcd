#include "saras_teleop/force_gate.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

namespace saras_teleop
{
void ForceGateParams::validate() const
{
  const auto check = [](double v, const char* name, const char* unit) {
    if (!(std::isfinite(v) && v > 0.0))
      throw std::invalid_argument(std::string("parameter '") + name + "' must be finite and > 0 " + unit);
  };
  check(max_force, "max_contact_force", "N");
  check(max_step, "max_contact_force_step", "N");
  check(max_rate, "max_contact_force_rate", "N/s");
  check(hold_time, "contact_force_hold_time", "s");
  check(timeout, "input_timeout", "s");
}

ForceGate::ForceGate(const ForceGateParams& p) : p_(p)
{
  p_.validate();
}

ForceGate::Verdict ForceGate::offer(const Eigen::Vector3d& f, double t)
{
  char buf[128];
  const double n = f.norm();
  if (!std::isfinite(n) || n > p_.max_force)
  {
    std::snprintf(buf, sizeof buf, "|F| = %.3g N > max %.3g N", n, p_.max_force);
    why_ = buf;
    ++violations_;
    hold_until_ = t + p_.hold_time;
    return Verdict::MAGNITUDE;
  }
  const double dt = have_ ? std::max(0.0, t - t_) : 0.0;
  const double step = (f - f_).norm();
  const bool too_fast = have_ && step > p_.max_step + p_.max_rate * dt;
  f_ = f;  // reference of the next rate check (also while holding)
  t_ = t;
  have_ = true;
  if (too_fast)
  {
    std::snprintf(buf, sizeof buf, "force changed by %.3g N in %.3g s", step, dt);
    why_ = buf;
    ++violations_;
    hold_until_ = t + p_.hold_time;
    return Verdict::RATE;
  }
  return Verdict::ACCEPTED;
}

Eigen::Vector3d ForceGate::force(double t) const
{
  if (stale(t) || holding(t))
    return Eigen::Vector3d::Zero();
  return f_;
}

}  // namespace saras_teleop
