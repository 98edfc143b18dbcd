/**
 * @file transparency.h
 * @brief Transparency layer of one teleoperation channel (D7.2 Section 5.4), ROS-agnostic.
 *
 * State WAITING until a master pose and a slave pose have been received; then the initial
 * positions m0, s0 are stored and the channel RUNS:
 *
 *   des_wrench = [ K * ((s - s0) / scale - (m - m0)) + f_fixture + c * f_contact ; tau_fixture ]  (master) [N, N m]
 *   des_twist  = [ scale * v_master ; rotation_scale * w_master ]                 (slave side) [m/s, rad/s]
 *
 * all expressed in the slave base frame. The position error is compared in master space, so the
 * scale factor does not create a spurious force in free motion (the deliverable compares
 * (s - s0) - (m - m0), which is only right for scale 1). While the clutch is pressed or the master
 * f_contact is the force of the tissue on the tool (D7.2 Section 8 contact force, slave base frame),
 * reflected on the operator's hand scaled by c = contact_force_scale while contact_feedback is on; it
 * enters des_wrench, so tank_master lets through only what its energy allows (passivity kept).
 * While the clutch is pressed or the master
 * link is stale the channel HOLDS (zero wrench and twist); on leaving HOLD the offsets are re-indexed
 * (m0 = m, s0 = s), so the commanded force does not jump. The force is saturated to max_force.
 */
#ifndef SARAS_TELEOP_TRANSPARENCY_H
#define SARAS_TELEOP_TRANSPARENCY_H

#include <cstddef>

#include <Eigen/Core>

#include "saras_teleop/energy_tank.h"

namespace saras_teleop
{
struct TransparencyParams
{
  double pose_error_gain = 200.0;  ///< K, master-side stiffness of the position error [N/m]
  double scale_factor = 0.5;       ///< slave translation / master translation [-]
  double rotation_scale = 1.0;     ///< slave rotation rate / master rotation rate [-]
  double max_force = 3.0;          ///< saturation of |des force| [N] (Touch: 3.3 N peak)
  bool contact_feedback = true;    ///< reflect the contact force on the master
  double contact_force_scale = 0.5;  ///< master force / contact force [-] (= scale_factor: power-consistent)
  /// Throws std::invalid_argument naming the offending parameter.
  void validate() const;
};

class TransparencyChannel
{
public:
  enum State
  {
    WAITING = 0,
    RUNNING = 1,
    HOLD = 2
  };

  explicit TransparencyChannel(const TransparencyParams& p);

  /// Master position [m] in the slave base frame. Returns false (ignored) if not finite.
  bool setMasterPosition(const Eigen::Vector3d& m);
  /// Master twist [m/s, rad/s] in the slave base frame. Returns false (ignored) if not finite.
  bool setMasterTwist(const Vector6d& v);
  /// Measured slave position [m] in the slave base frame. Returns false (ignored) if not finite.
  bool setSlavePosition(const Eigen::Vector3d& s);
  /// Virtual-fixture wrench [N, N m] in the slave base frame (zero to clear).
  bool setFixtureWrench(const Vector6d& w);
  /// Contact force of the tissue on the tool [N] in the slave base frame (zero to clear).
  bool setContactForce(const Eigen::Vector3d& f);
  void setClutch(bool pressed) { clutch_ = pressed; }
  void setLinkOk(bool ok) { link_ok_ = ok; }

  /// Compute the set-points; returns the state after the update.
  State update(Vector6d& des_wrench, Vector6d& des_twist);

  State state() const { return state_; }
  const Eigen::Vector3d& masterOffset() const { return m0_; }
  const Eigen::Vector3d& slaveOffset() const { return s0_; }

private:
  TransparencyParams p_;
  State state_ = WAITING;
  bool have_master_ = false, have_slave_ = false;
  bool clutch_ = false, link_ok_ = true;
  Eigen::Vector3d m_ = Eigen::Vector3d::Zero(), s_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d m0_ = Eigen::Vector3d::Zero(), s0_ = Eigen::Vector3d::Zero();
  Vector6d v_ = Vector6d::Zero();
  Vector6d fixture_ = Vector6d::Zero();
  Eigen::Vector3d contact_ = Eigen::Vector3d::Zero();
};

}  // namespace saras_teleop

#endif  // SARAS_TELEOP_TRANSPARENCY_H
