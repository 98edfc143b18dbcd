// Private header of the saras_collision library (not installed): small helpers shared by
// geometry.cpp (boxes) and capsule_capsule.cpp. ROS-agnostic, plain portable C++.
#ifndef SARAS_COLLISION_SRC_GEOMETRY_DETAIL_H
#define SARAS_COLLISION_SRC_GEOMETRY_DETAIL_H

#include "saras_collision/geometry.h"

#include <Eigen/Geometry>

#include <cmath>
#include <limits>

namespace saras_collision
{
namespace detail
{
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
/// Squared length below which a capsule axis is treated as a point [m^2] (length < 1e-15 m).
constexpr double kDegenerateLength2 = 1e-30;
/// Squared axis-to-axis distance below which the capsule-capsule normal is taken from the axes
/// directions, not from the (then meaningless) closest-point difference [m^2] (1e-100 m).
constexpr double kMinAxis2 = 1e-200;

inline bool validRadius(double r)
{
  return std::isfinite(r) && r >= 0.0;
}

/// All coordinates finite: NaN and +-inf propagate through the sum (finite values whose sum
/// overflows, > 1e307 m, are rejected too, which is intended).
inline bool allFinite(const Eigen::Vector3d& a, const Eigen::Vector3d& b)
{
  return std::isfinite((a + b).sum() + (a - b).sum());
}

/// @p x clamped to [0, 1]. Inputs are never NaN here (checked before or after the computation).
inline double clamp01(double x)
{
  return std::min(std::max(x, 0.0), 1.0);
}

/// @p x clamped to [-h, h].
inline double clampTo(double x, double h)
{
  return std::min(std::max(x, -h), h);
}

inline DistanceResult invalid(int code)
{
  DistanceResult r;
  r.code = code;
  r.distance = kNaN;
  r.point1 = Eigen::Vector3d::Constant(kNaN);
  r.point2 = Eigen::Vector3d::Constant(kNaN);
  r.normal = Eigen::Vector3d::Constant(kNaN);
  return r;
}

/// Any unit vector orthogonal to a non-zero @p v.
inline Eigen::Vector3d anyPerpendicular(const Eigen::Vector3d& v)
{
  Eigen::Vector3d other = std::abs(v.x()) <= std::abs(v.y()) && std::abs(v.x()) <= std::abs(v.z()) ?
                              Eigen::Vector3d::UnitX() :
                              (std::abs(v.y()) <= std::abs(v.z()) ? Eigen::Vector3d::UnitY() :
                                                                    Eigen::Vector3d::UnitZ());
  return v.cross(other).normalized();
}

/**
 * Return code of a signed @p distance: kIntersecting below -kTangentTolerance, kTangent within
 * +-kTangentTolerance, else @p separated_code (kSeparated or kParallel). NaN gives kTangent (0);
 * the callers reject NaN distances as invalid input before returning.
 */
inline int classify(double distance, int separated_code = kSeparated)
{
  if (distance < -kTangentTolerance)
    return kIntersecting;
  if (distance > kTangentTolerance)
    return separated_code;
  return kTangent;
}

/**
 * The witness-point switch of every distance function: @p value unless the signed @p distance
 * is intersecting (below -kTangentTolerance, exactly where classify() says kIntersecting), then
 * +0. NaN gives @p value.
 */
inline double unlessIntersecting(double distance, double value)
{
  return distance < -kTangentTolerance ? 0.0 : value;
}

/// 1 if the distance keeps surface points (not intersecting), else 0 (unlessIntersecting()).
inline double surfaceFactor(double distance)
{
  return unlessIntersecting(distance, 1.0);
}

/// Writes the error outputs of the deliverable signatures (NaN distance and points).
inline int invalidOutputs(int code, double& distance, Eigen::Vector3d& point1, Eigen::Vector3d& point2)
{
  distance = kNaN;
  point1 = Eigen::Vector3d::Constant(kNaN);
  point2 = Eigen::Vector3d::Constant(kNaN);
  return code;
}
}  // namespace detail
}  // namespace saras_collision

#endif  // SARAS_COLLISION_SRC_GEOMETRY_DETAIL_H
