/**
 * @file velocity_integrator.h
 * @brief Slave pose set-point from the implemented slave twist (D7.2 Section 5.5), ROS-agnostic.
 *
 * pose <- KDL::addDelta(pose, twist, dt) (twist in the slave base frame: translation += v dt,
 * rotation <- Rot(w dt) * rotation). The twist is first limited (|v| <= max_linear_velocity,
 * |w| <= max_angular_velocity, direction kept), then the position is clamped to the workspace box.
 * While holding (stale master link, no recent twist) the set-point does not move.
 *
 * Re-synchronisation with the arm (as the dVRK's teleoperation does): the measured slave pose is
 * fed continuously (setMeasured). A step that would take the set-point further than max_lead from
 * the measured pose is shortened onto that sphere (the set-point waits for an arm that lags); if it
 * keeps waiting for longer than max_stall, or a fault is declared (console link stale, arm state
 * stale, ...), the integrator enters FAULT: the set-point freezes (at most max_lead from the
 * measured pose: the arm holds at, or short of, the target it already has). It leaves FAULT, and CLUTCHED, only through the
 * operator's clutch: press, then release; on the release the set-point is re-anchored on the
 * measured pose, so the first set-point after a recovery is the held pose and motion resumes from
 * there at <= max_linear_velocity.
 */
#ifndef SARAS_TELEOP_VELOCITY_INTEGRATOR_H
#define SARAS_TELEOP_VELOCITY_INTEGRATOR_H

#include <cstddef>
#include <string>

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
  double max_lead = 0.003;   ///< [m] largest set-point lead over the measured position
  double max_stall = 1.0;    ///< [s] longest time the lead may stay saturated before FAULT
  /// Throws std::invalid_argument naming the offending parameter.
  void validate() const;
};

class VelocityIntegrator
{
public:
  /// WAITING: no start pose; FOLLOWING: set-point integrates and is commanded; CLUTCHED: clutch
  /// pressed; FAULT: a hold that must be cleared by the operator's clutch (press, then release).
  enum class Mode
  {
    WAITING,
    FOLLOWING,
    CLUTCHED,
    FAULT
  };

  explicit VelocityIntegrator(const IntegratorParams& p);

  /// Start pose (measured slave pose). Returns false if not finite. Mode FOLLOWING, or FAULT with
  /// @p await_clutch (a restarted chain resumes only through the clutch).
  bool start(const KDL::Frame& pose, bool await_clutch = false);
  bool started() const { return started_; }

  /// Latest measured slave pose (re-anchoring and lead limit). Returns false if not finite.
  bool setMeasured(const KDL::Frame& pose);
  bool hasMeasured() const { return have_measured_; }
  /// Enter FAULT (no-op while WAITING): the set-point freezes; @p why is kept for the diagnostics.
  void fault(const std::string& why);
  /**
   * Operator clutch state. FOLLOWING + pressed -> CLUTCHED; FAULT + pressed -> CLUTCHED;
   * CLUTCHED + released -> set-point := measured pose (if known), FOLLOWING.
   * @return true when this call re-anchored and resumed
   */
  bool clutch(bool pressed);
  Mode mode() const { return mode_; }
  /// true while the set-point follows the master (FOLLOWING); otherwise it holds
  bool commanding() const { return mode_ == Mode::FOLLOWING; }
  const std::string& faultReason() const { return why_; }
  /// Distance set-point - measured position [m] (0 without a measurement)
  double lead() const;
  std::size_t faults() const { return faults_; }
  std::size_t leadLimitedSteps() const { return lead_limited_; }
  /// Degraded operation: the velocity limits are multiplied by @p scale in (0, 1] (others ignored).
  void setSpeedScale(double scale);
  double speedScale() const { return speed_scale_; }

  /**
   * Integrate one step.
   * @param twist commanded twist [m/s, rad/s] in the slave base frame (non-finite -> zero + counter)
   * @param dt    step [s]; ignored if not finite/positive or longer than 0.1 s
   * @param hold  true: keep the set-point
   * Integrates only while FOLLOWING.
   */
  void step(const Vector6d& twist, double dt, bool hold);

  const KDL::Frame& pose() const { return pose_; }
  std::size_t rejected() const { return rejected_; }
  std::size_t clampedSteps() const { return clamped_; }

private:
  /// Shortens the step onto the max_lead sphere around the measured position; true if it did.
  bool limitLead(KDL::Frame& next) const;

  IntegratorParams p_;
  bool started_ = false;
  Mode mode_ = Mode::WAITING;
  KDL::Frame pose_, measured_;
  bool have_measured_ = false;
  double stalled_ = 0.0;  // [s] time the lead has been saturated
  double speed_scale_ = 1.0;
  std::string why_;
  std::size_t faults_ = 0, lead_limited_ = 0;
  std::size_t rejected_ = 0;
  std::size_t clamped_ = 0;
};

}  // namespace saras_teleop

#endif  // SARAS_TELEOP_VELOCITY_INTEGRATOR_H
