// Shared pieces of the geometry gtests: independent exact references (written differently from
// the library: candidate enumeration instead of the clamped normal equations / the
// piecewise-quadratic walk), FCL adapters and random generators.
#ifndef SARAS_COLLISION_TEST_GEOMETRY_TEST_SUPPORT_H
#define SARAS_COLLISION_TEST_GEOMETRY_TEST_SUPPORT_H

#include "saras_collision/geometry.h"

#include <fcl/geometry/shape/box.h>
#include <fcl/geometry/shape/capsule.h>
#include <fcl/geometry/shape/sphere.h>
#include <fcl/narrowphase/collision.h>
#include <fcl/narrowphase/distance.h>
#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

namespace geometry_test
{
using Eigen::Vector3d;
using saras_collision::OrientedBox;

constexpr int kRandomCases = 10000;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// ---------------------------------------------------------------- independent references
inline double pointSegment(const Vector3d& p, const Vector3d& a, const Vector3d& b)
{
  const Vector3d d = b - a;
  const double dd = d.squaredNorm();
  const double t = dd == 0.0 ? 0.0 : std::min(1.0, std::max(0.0, (p - a).dot(d) / dd));
  return (a + t * d - p).norm();
}

/// Segment-segment distance by enumerating the KKT candidates: the four end-point-to-segment
/// distances and, if it lies inside both segments, the unconstrained critical pair.
inline double segmentSegmentRef(const Vector3d& p1, const Vector3d& p2, const Vector3d& p3, const Vector3d& p4)
{
  double best = std::min(std::min(pointSegment(p1, p3, p4), pointSegment(p2, p3, p4)),
                         std::min(pointSegment(p3, p1, p2), pointSegment(p4, p1, p2)));
  const Vector3d u = p2 - p1, v = p4 - p3, w = p1 - p3;
  Eigen::Matrix2d A;
  A << u.dot(u), -u.dot(v), -u.dot(v), v.dot(v);
  const Eigen::Vector2d rhs(-u.dot(w), v.dot(w));
  if (std::abs(A.determinant()) > 1e-14 * A(0, 0) * A(1, 1))
  {
    const Eigen::Vector2d st = A.fullPivLu().solve(rhs);
    if (st[0] >= 0 && st[0] <= 1 && st[1] >= 0 && st[1] <= 1)
      best = std::min(best, (p1 + st[0] * u - p3 - st[1] * v).norm());
  }
  return best;
}

/// dist_capsule_to_capsule() on one pair (outputs @p code, @p d, @p a, @p b), checked against the
/// exact reference segmentSegmentRef() - r1 - r2 (also written to @p reference when given): a valid
/// code, the distance within @p tolerance of the reference and not above it by more than that
/// (never overstated).
inline ::testing::AssertionResult answerNearReference(const Vector3d& p1, const Vector3d& p2, const Vector3d& p3,
                                               const Vector3d& p4, double r1, double r2, double tolerance, int& code,
                                               double& d, Vector3d& a, Vector3d& b, double* reference = nullptr)
{
  code = saras_collision::dist_capsule_to_capsule(p1, p2, p3, p4, r1, r2, d, a, b);
  const double ref = segmentSegmentRef(p1, p2, p3, p4) - r1 - r2;
  if (reference != nullptr)
    *reference = ref;
  if (!saras_collision::isValidCode(code))
    return ::testing::AssertionFailure() << "invalid code " << code;
  if (!(std::abs(d - ref) <= tolerance))
    return ::testing::AssertionFailure() << "distance " << d << " vs reference " << ref;
  if (!(d <= ref + tolerance))
    return ::testing::AssertionFailure() << "overstated: " << d << " vs reference " << ref;
  return ::testing::AssertionSuccess();
}

/// Exact signed distance of a point to a box (negative inside).
inline double pointBoxSigned(const Vector3d& p, const OrientedBox& box)
{
  const Vector3d x = box.axes.transpose() * (p - box.center);
  Vector3d outside;
  double inside = -std::numeric_limits<double>::infinity();
  for (int i = 0; i < 3; ++i)
  {
    outside[i] = std::max(std::abs(x[i]) - box.half[i], 0.0);
    inside = std::max(inside, std::abs(x[i]) - box.half[i]);
  }
  return outside.squaredNorm() > 0.0 ? outside.norm() : inside;
}

/// Liang-Barsky clipping: does the segment meet the closed box?
inline bool segmentMeetsBox(const Vector3d& p1, const Vector3d& p2, const OrientedBox& box)
{
  const Vector3d a = box.axes.transpose() * (p1 - box.center);
  const Vector3d d = box.axes.transpose() * (p2 - p1);
  double t0 = 0.0, t1 = 1.0;
  for (int i = 0; i < 3; ++i)
  {
    if (d[i] == 0.0)
    {
      if (std::abs(a[i]) > box.half[i])
        return false;
      continue;
    }
    double ta = (-box.half[i] - a[i]) / d[i], tb = (box.half[i] - a[i]) / d[i];
    if (ta > tb)
      std::swap(ta, tb);
    t0 = std::max(t0, ta);
    t1 = std::min(t1, tb);
    if (t0 > t1)
      return false;
  }
  return true;
}

/// Axis-to-box distance by the deliverable's decomposition (end-points as spheres + the 12
/// edges as zero-radius capsules), valid when the axis does not meet the box.
inline double segmentBoxRef(const Vector3d& p1, const Vector3d& p2, const OrientedBox& box)
{
  if (segmentMeetsBox(p1, p2, box))
    return 0.0;
  Vector3d v[8];
  saras_collision::boxVertices(box, v);
  const int edges[12][2] = { { 0, 1 }, { 1, 2 }, { 2, 3 }, { 3, 0 }, { 4, 5 }, { 5, 6 },
                             { 6, 7 }, { 7, 4 }, { 0, 4 }, { 1, 5 }, { 2, 6 }, { 3, 7 } };
  double best = std::min(pointBoxSigned(p1, box), pointBoxSigned(p2, box));
  for (const auto& e : edges)
    best = std::min(best, segmentSegmentRef(p1, p2, v[e[0]], v[e[1]]));
  return best;
}

/// Minimum of the box signed distance along the axis by dense sampling (upper bound of the
/// exact minimum, within |p2 - p1| / (2 n) of it since the signed distance is 1-Lipschitz).
inline double sampledAxisDepth(const Vector3d& p1, const Vector3d& p2, const OrientedBox& box, int n)
{
  double best = std::numeric_limits<double>::infinity();
  for (int k = 0; k <= n; ++k)
    best = std::min(best, pointBoxSigned(p1 + (p2 - p1) * (static_cast<double>(k) / n), box));
  return best;
}

// ---------------------------------------------------------------- FCL adapters
inline fcl::Transform3d capsuleTransform(const Vector3d& p1, const Vector3d& p2)
{
  fcl::Transform3d tf = fcl::Transform3d::Identity();
  tf.translation() = 0.5 * (p1 + p2);
  tf.linear() = Eigen::Quaterniond::FromTwoVectors(Vector3d::UnitZ(), p2 - p1).toRotationMatrix();
  return tf;
}

inline fcl::Transform3d boxTransform(const OrientedBox& box)
{
  fcl::Transform3d tf = fcl::Transform3d::Identity();
  tf.translation() = box.center;
  tf.linear() = box.axes;
  return tf;
}

struct FclAnswer
{
  double distance;
  bool collides;
};

inline FclAnswer fclQuery(const fcl::CollisionGeometryd& g1, const fcl::Transform3d& tf1, const fcl::CollisionGeometryd& g2,
                   const fcl::Transform3d& tf2)
{
  fcl::DistanceRequestd request;
  request.enable_nearest_points = false;
  request.distance_tolerance = 1e-12;  // the default 1e-6 leaves GJK up to ~0.5 mm off
  request.gjk_solver_type = fcl::GST_LIBCCD;
  fcl::DistanceResultd result;
  fcl::distance(&g1, tf1, &g2, tf2, request, result);
  fcl::CollisionRequestd creq;
  fcl::CollisionResultd cres;
  fcl::collide(&g1, tf1, &g2, tf2, creq, cres);
  return { result.min_distance, cres.isCollision() };
}

// ---------------------------------------------------------------- random generators
struct Random
{
  std::mt19937_64 gen{ 20260521 };
  double uniform(double lo, double hi)
  {
    return std::uniform_real_distribution<double>(lo, hi)(gen);
  }
  Vector3d point(double extent)
  {
    return Vector3d(uniform(-extent, extent), uniform(-extent, extent), uniform(-extent, extent));
  }
  Eigen::Matrix3d rotation()
  {
    Eigen::Quaterniond q(uniform(-1, 1), uniform(-1, 1), uniform(-1, 1), uniform(-1, 1));
    if (q.norm() < 1e-3)
      q = Eigen::Quaterniond::Identity();
    return q.normalized().toRotationMatrix();
  }
  OrientedBox box()
  {
    OrientedBox b;
    b.center = point(0.02);
    b.axes = rotation();
    b.half = Vector3d(uniform(0.003, 0.04), uniform(0.003, 0.04), uniform(0.003, 0.04));
    b.bounding_radius = b.half.norm();
    return b;
  }
  /// Segment of length in [1 mm, 120 mm] around the scene.
  void segment(Vector3d& p1, Vector3d& p2, double extent = 0.08)
  {
    p1 = point(extent);
    Vector3d dir = point(1.0);
    while (dir.norm() < 1e-3)
      dir = point(1.0);
    p2 = p1 + dir.normalized() * uniform(0.001, 0.12);
  }
};

inline OrientedBox boxFromVertices(const Vector3d v[8])
{
  OrientedBox box;
  EXPECT_EQ(saras_collision::makeBox(v, 1e-9, box), saras_collision::kSeparated);
  return box;
}

/// Axis-aligned box [lo, hi] as 8 vertices in the documented order.
inline void aabbVertices(const Vector3d& lo, const Vector3d& hi, Vector3d v[8])
{
  const Vector3d x(hi.x() - lo.x(), 0, 0), y(0, hi.y() - lo.y(), 0), z(0, 0, hi.z() - lo.z());
  v[0] = lo;
  v[1] = lo + x;
  v[2] = lo + x + z;
  v[3] = lo + z;
  v[4] = lo + y;
  v[5] = lo + x + y;
  v[6] = lo + x + y + z;
  v[7] = lo + y + z;
}

constexpr double kInf = std::numeric_limits<double>::infinity();

/// The error outputs: NaN distance and points.
inline bool allNaN(double d, const Vector3d& a, const Vector3d& b)
{
  return std::isnan(d) && a.array().isNaN().all() && b.array().isNaN().all();
}
}  // namespace geometry_test

#endif  // SARAS_COLLISION_TEST_GEOMETRY_TEST_SUPPORT_H
