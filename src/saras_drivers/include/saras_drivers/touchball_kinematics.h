/**
 * @file touchball_kinematics.h
 * @brief Inverse kinematics of the Touch haptic device (3 actuated arm joints + 3-DOF gimbal),
 *        used by the Touchball receiver for the decimated touch_<side>/joint_states (rviz only).
 *
 * The reference model is saras_description's forward kinematics
 * (saras_description.kinematics.touch_handle_in_base, which also generates the Touch URDF); this
 * is the platform's Touch inverse kinematics. The gtest test/touchball/test_touchball_kinematics.cpp
 * requires touchIk to invert a table of joint values and poses computed by that reference
 * (test/touchball/data/touch_fk_table.csv; test_touch_fk_table.py keeps the table current), so a
 * change on either side fails a test. Joint order: waist (z), shoulder (y), elbow (y), then the
 * gimbal yaw (z), pitch (y), roll (x). Base frame: z up, x away from the user. Units: m, rad.
 */
#ifndef SARAS_DRIVERS_TOUCHBALL_KINEMATICS_H
#define SARAS_DRIVERS_TOUCHBALL_KINEMATICS_H

#include <array>
#include <cmath>

namespace saras_drivers
{
namespace touchball
{
/// Touch dimensions [m] and joint limits [rad] (saras_description/geometry.py TouchGeometry).
struct TouchGeometry
{
  double shoulder_height = 0.15;  ///< waist axis origin to the shoulder axis [m]
  double upper_arm = 0.1325;      ///< shoulder axis to elbow axis [m]
  double forearm = 0.1325;        ///< elbow axis to gimbal centre (handle frame) [m]
  /// lower / upper limit per joint (waist, shoulder, elbow, yaw, pitch, roll) [rad]
  std::array<double, 6> lower{ { -60.0 * M_PI / 180, -10.0 * M_PI / 180, -60.0 * M_PI / 180, -150.0 * M_PI / 180,
                                 -80.0 * M_PI / 180, -150.0 * M_PI / 180 } };
  std::array<double, 6> upper{ { 60.0 * M_PI / 180, 100.0 * M_PI / 180, 70.0 * M_PI / 180, 150.0 * M_PI / 180,
                                 80.0 * M_PI / 180, 150.0 * M_PI / 180 } };
};

/// Joint names without prefix, in joint order.
extern const char* const kTouchJointNames[6];

/**
 * Joint values whose handle pose equals (@p position [m], unit quaternion @p q x, y, z, w) in
 * touch_<side>/base. Of the two arm branches the one inside the limits is taken. Returns true if
 * the pose is reachable within the limits; otherwise @p joints holds the first branch clamped
 * into the limits. Allocation-free.
 */
bool touchIk(const TouchGeometry& g, const double position[3], const double q[4], std::array<double, 6>& joints);

}  // namespace touchball
}  // namespace saras_drivers

#endif  // SARAS_DRIVERS_TOUCHBALL_KINEMATICS_H
