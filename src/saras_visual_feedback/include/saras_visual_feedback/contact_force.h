/**
 * @file contact_force.h
 * @brief ROS-agnostic elastic contact force model of D7.2 Section 8:
 *        F = depth * K_skin * direction / |direction|, zero when the contact is stale or absent.
 */
#ifndef SARAS_VISUAL_FEEDBACK_CONTACT_FORCE_H
#define SARAS_VISUAL_FEEDBACK_CONTACT_FORCE_H

#include <cstdint>
#include <string>

namespace saras_visual_feedback
{

/// A 3-vector (force [N] or direction [any unit]).
struct Vec3
{
  double x = 0.0, y = 0.0, z = 0.0;
};

/// Parameters of the contact force model.
struct ContactForceParams
{
  double k_skin = 500.0;        ///< tissue stiffness K_skin [N/m], > 0
  double stale_timeout = 0.2;   ///< a contact older than this gives zero force [s], > 0
  double max_force = 15.0;      ///< saturation of |F| [N] protecting the haptic device; 0 = none
  double min_direction_norm = 1e-9;  ///< shorter directions are rejected as zero-length
};

/// Why a contact sample was rejected.
enum class ContactRejection
{
  kNone,               ///< accepted
  kNonFinite,          ///< NaN/inf depth or direction component
  kNegativeDepth,      ///< depth < 0 (Contact.msg requires depth >= 0)
  kZeroDirection       ///< |direction| below min_direction_norm
};

/// Human-readable reason.
const char* toString(ContactRejection r);

/// Validates parameters; on failure names the offending parameter in @p error.
bool validateContactForceParams(const ContactForceParams& p, std::string* error);

/**
 * @brief Latches the last valid contact and turns it into a force.
 *
 * Rejected samples are counted and do not change the latched contact (which then goes stale).
 * No allocation; not thread-safe (the node serialises calls).
 */
class ContactForceModel
{
public:
  explicit ContactForceModel(const ContactForceParams& params = ContactForceParams()) : p_(params) {}

  /// Offers a sample received at @p t [s]; returns kNone when it was accepted.
  ContactRejection update(double depth, const Vec3& direction, double t);

  /// Force [N] at time @p t [s]: zero without a contact or when older than stale_timeout.
  Vec3 force(double t) const;

  /// True when a valid sample younger than stale_timeout is latched at time @p t [s].
  bool fresh(double t) const;

  /// Age of the last valid sample at @p t [s]; +inf without one.
  double age(double t) const;

  std::uint64_t accepted() const { return accepted_; }
  std::uint64_t rejected() const { return rejected_; }
  const ContactForceParams& params() const { return p_; }

private:
  ContactForceParams p_;
  bool has_contact_ = false;
  double t_contact_ = 0.0;  ///< [s]
  Vec3 force_;              ///< force of the latched contact [N]
  std::uint64_t accepted_ = 0, rejected_ = 0;
};

}  // namespace saras_visual_feedback

#endif  // SARAS_VISUAL_FEEDBACK_CONTACT_FORCE_H
