/**
 * @file touchball_kinematics.cpp
 * @brief Touch inverse kinematics (joint_states for rviz).
 */
#include "saras_drivers/touchball_kinematics.h"

#include <algorithm>
#include <cmath>

#include <Eigen/Geometry>

namespace saras_drivers
{
namespace touchball
{
const char* const kTouchJointNames[6] = { "waist", "shoulder", "elbow", "yaw", "pitch", "roll" };

namespace
{
double wrapAngle(double a)
{
  return std::atan2(std::sin(a), std::cos(a));
}

/// Arm joints for waist angle @p waist with the gimbal centre at signed distance @p r toward the
/// user (-x of the waist frame) and @p height [m]; then the gimbal angles. Returns reachable.
bool branch(const TouchGeometry& g, double waist, double r, double height, const Eigen::Matrix3d& rot,
            std::array<double, 6>& q)
{
  const double l1 = g.upper_arm, l2 = g.forearm;
  const double z = height - g.shoulder_height;
  double s3 = (r * r + z * z - l1 * l1 - l2 * l2) / (2.0 * l1 * l2);
  const bool reachable = std::fabs(s3) <= 1.0 + 1e-12;
  s3 = std::max(-1.0, std::min(1.0, s3));
  const double elbow = std::asin(s3);
  // (r, z) is (l1 + l2 sin(elbow), -l2 cos(elbow)) rotated by the shoulder angle
  const double shoulder = wrapAngle(std::atan2(z, r) - std::atan2(-l2 * std::cos(elbow), l1 + l2 * s3));
  // rotation after the elbow: Rz(waist) Ry(shoulder) Ry(elbow); gimbal: Rz(yaw) Ry(pitch) Rx(roll)
  const Eigen::Matrix3d re =
      (Eigen::AngleAxisd(waist, Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(shoulder + elbow, Eigen::Vector3d::UnitY()))
          .toRotationMatrix();
  const Eigen::Matrix3d rw = re.transpose() * rot;
  q[0] = waist;
  q[1] = shoulder;
  q[2] = elbow;
  q[3] = std::atan2(rw(1, 0), rw(0, 0));
  q[4] = std::atan2(-rw(2, 0), std::hypot(rw(0, 0), rw(1, 0)));
  q[5] = std::atan2(rw(2, 1), rw(2, 2));
  return reachable;
}

bool within(const TouchGeometry& g, const std::array<double, 6>& q)
{
  for (int i = 0; i < 6; ++i)
    if (!(q[i] >= g.lower[i] - 1e-9 && q[i] <= g.upper[i] + 1e-9))
      return false;
  return true;
}
}  // namespace

bool touchIk(const TouchGeometry& g, const double position[3], const double q[4], std::array<double, 6>& joints)
{
  const Eigen::Matrix3d rot = Eigen::Quaterniond(q[3], q[0], q[1], q[2]).normalized().toRotationMatrix();
  const double horizontal = std::hypot(position[0], position[1]);
  const double waist = horizontal > 1e-12 ? std::atan2(-position[1], -position[0]) : 0.0;
  std::array<double, 6> first, other;
  if (branch(g, waist, horizontal, position[2], rot, first) && within(g, first))
  {
    joints = first;
    return true;
  }
  if (branch(g, wrapAngle(waist + M_PI), -horizontal, position[2], rot, other) && within(g, other))
  {
    joints = other;
    return true;
  }
  for (int i = 0; i < 6; ++i)
    joints[i] = std::max(g.lower[i], std::min(g.upper[i], first[i]));
  return false;
}

}  // namespace touchball
}  // namespace saras_drivers
