#include "saras_visual_feedback/contact_force.h"

#include <cmath>
#include <limits>

namespace saras_visual_feedback
{

const char* toString(ContactRejection r)
{
  switch (r)
  {
    case ContactRejection::kNone:
      return "accepted";
    case ContactRejection::kNonFinite:
      return "non-finite depth or direction";
    case ContactRejection::kNegativeDepth:
      return "negative depth";
    case ContactRejection::kZeroDirection:
      return "zero-length direction";
  }
  return "unknown";
}

bool validateContactForceParams(const ContactForceParams& p, std::string* error)
{
  auto fail = [error](const std::string& why) {
    if (error)
      *error = why;
    return false;
  };
  if (!(std::isfinite(p.k_skin) && p.k_skin > 0.0))
    return fail("k_skin must be finite and > 0 [N/m]");
  if (!(std::isfinite(p.stale_timeout) && p.stale_timeout > 0.0))
    return fail("stale_timeout must be finite and > 0 [s]");
  if (!(std::isfinite(p.max_force) && p.max_force >= 0.0))
    return fail("max_force must be finite and >= 0 [N] (0 disables saturation)");
  if (!(std::isfinite(p.min_direction_norm) && p.min_direction_norm > 0.0))
    return fail("min_direction_norm must be finite and > 0");
  return true;
}

ContactRejection ContactForceModel::update(double depth, const Vec3& d, double t)
{
  ContactRejection why = ContactRejection::kNone;
  const double norm = std::sqrt(d.x * d.x + d.y * d.y + d.z * d.z);
  if (!(std::isfinite(depth) && std::isfinite(norm)))
    why = ContactRejection::kNonFinite;
  else if (depth < 0.0)
    why = ContactRejection::kNegativeDepth;
  else if (norm < p_.min_direction_norm)
    why = ContactRejection::kZeroDirection;
  if (why != ContactRejection::kNone)
  {
    ++rejected_;
    return why;
  }
  const double scale = depth * p_.k_skin / norm;
  Vec3 f{scale * d.x, scale * d.y, scale * d.z};
  const double magnitude = depth * p_.k_skin;
  if (p_.max_force > 0.0 && magnitude > p_.max_force)
  {
    const double s = p_.max_force / magnitude;
    f = Vec3{f.x * s, f.y * s, f.z * s};
  }
  force_ = f;
  t_contact_ = t;
  has_contact_ = true;
  ++accepted_;
  return why;
}

double ContactForceModel::age(double t) const
{
  return has_contact_ ? t - t_contact_ : std::numeric_limits<double>::infinity();
}

bool ContactForceModel::fresh(double t) const
{
  const double a = age(t);
  // A sample stamped slightly in the future (clock jitter) still counts as fresh.
  return has_contact_ && a <= p_.stale_timeout;
}

Vec3 ContactForceModel::force(double t) const
{
  return fresh(t) ? force_ : Vec3{};
}

}  // namespace saras_visual_feedback
