#include "saras_teleop/clip_mapper.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace saras_teleop
{
void ClipParams::validate() const
{
  const auto fail = [](const char* name, const std::string& what) {
    throw std::invalid_argument(std::string("parameter '") + name + "' " + what);
  };
  const auto positive = [&fail](double v, const char* name, const char* unit) {
    if (!(std::isfinite(v) && v > 0.0))
      fail(name, std::string("must be finite and > 0 ") + unit);
  };
  positive(scale, "jaw_scale", "(jaw rad per clip rad)");
  if (!std::isfinite(offset))
    fail("jaw_offset", "must be finite [rad]");
  if (!std::isfinite(jaw_min))
    fail("jaw_min", "must be finite [rad]");
  if (!(std::isfinite(jaw_max) && jaw_max > jaw_min))
    fail("jaw_max", "must be finite and > jaw_min [rad]");
  positive(max_velocity, "max_jaw_velocity", "rad/s");
  positive(input_timeout, "jaw_input_timeout", "s");
  positive(max_step, "max_step", "s");
}

ClipMapper::ClipMapper(const ClipParams& p) : p_(p)
{
  p_.validate();
}

double ClipMapper::map(double clip) const
{
  return std::min(std::max(p_.offset + p_.scale * clip, p_.jaw_min), p_.jaw_max);
}

bool ClipMapper::setMeasured(double jaw)
{
  if (!std::isfinite(jaw))
    return false;
  if (!started_)
  {
    cmd_ = std::min(std::max(jaw, p_.jaw_min), p_.jaw_max);
    started_ = true;
  }
  return true;
}

bool ClipMapper::setClip(double clip, double t)
{
  if (!std::isfinite(clip) || !std::isfinite(t))
  {
    ++rejected_;
    have_clip_ = false;  // hold until the next valid sample
    return false;
  }
  target_ = map(clip);
  t_clip_ = t;
  have_clip_ = true;
  return true;
}

double ClipMapper::step(double t, bool hold)
{
  const double dt = stepped_ ? std::min(std::max(t - t_step_, 0.0), p_.max_step) : 0.0;
  if (std::isfinite(t))
  {
    t_step_ = t;
    stepped_ = true;
  }
  holding_ = hold || !started_ || !std::isfinite(t) || stale(t);
  if (holding_)
    return cmd_;
  const double limit = p_.max_velocity * dt;
  cmd_ += std::min(std::max(target_ - cmd_, -limit), limit);
  return cmd_;
}

}  // namespace saras_teleop
