// Geometry core tests: closed-form cases, FCL regression cases and >= 10000 random
// configurations per kind compared with FCL (libfcl-dev 0.7) and with independent exact
// references written differently from the library (candidate enumeration instead of the
// clamped normal equations / the piecewise-quadratic walk).
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
#include <cstdio>
#include <limits>
#include <random>

using Eigen::Vector3d;
using saras_collision::OrientedBox;

namespace
{
constexpr int kRandomCases = 10000;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// ---------------------------------------------------------------- independent references
double pointSegment(const Vector3d& p, const Vector3d& a, const Vector3d& b)
{
  const Vector3d d = b - a;
  const double dd = d.squaredNorm();
  const double t = dd == 0.0 ? 0.0 : std::min(1.0, std::max(0.0, (p - a).dot(d) / dd));
  return (a + t * d - p).norm();
}

/// Segment-segment distance by enumerating the KKT candidates: the four end-point-to-segment
/// distances and, if it lies inside both segments, the unconstrained critical pair.
double segmentSegmentRef(const Vector3d& p1, const Vector3d& p2, const Vector3d& p3, const Vector3d& p4)
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
::testing::AssertionResult answerNearReference(const Vector3d& p1, const Vector3d& p2, const Vector3d& p3,
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
double pointBoxSigned(const Vector3d& p, const OrientedBox& box)
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
bool segmentMeetsBox(const Vector3d& p1, const Vector3d& p2, const OrientedBox& box)
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
double segmentBoxRef(const Vector3d& p1, const Vector3d& p2, const OrientedBox& box)
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
double sampledAxisDepth(const Vector3d& p1, const Vector3d& p2, const OrientedBox& box, int n)
{
  double best = std::numeric_limits<double>::infinity();
  for (int k = 0; k <= n; ++k)
    best = std::min(best, pointBoxSigned(p1 + (p2 - p1) * (static_cast<double>(k) / n), box));
  return best;
}

// ---------------------------------------------------------------- FCL adapters
fcl::Transform3d capsuleTransform(const Vector3d& p1, const Vector3d& p2)
{
  fcl::Transform3d tf = fcl::Transform3d::Identity();
  tf.translation() = 0.5 * (p1 + p2);
  tf.linear() = Eigen::Quaterniond::FromTwoVectors(Vector3d::UnitZ(), p2 - p1).toRotationMatrix();
  return tf;
}

fcl::Transform3d boxTransform(const OrientedBox& box)
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

FclAnswer fclQuery(const fcl::CollisionGeometryd& g1, const fcl::Transform3d& tf1, const fcl::CollisionGeometryd& g2,
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

OrientedBox boxFromVertices(const Vector3d v[8])
{
  OrientedBox box;
  EXPECT_EQ(saras_collision::makeBox(v, 1e-9, box), saras_collision::kSeparated);
  return box;
}

/// Axis-aligned box [lo, hi] as 8 vertices in the documented order.
void aabbVertices(const Vector3d& lo, const Vector3d& hi, Vector3d v[8])
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
}  // namespace

// ===================================================================== capsule-capsule
TEST(CapsuleCapsule, CrossingAxesSeparatedTangentIntersecting)
{
  double d;
  Vector3d a, b;
  EXPECT_EQ(saras_collision::dist_capsule_to_capsule(Vector3d(-1, 0, 0), Vector3d(1, 0, 0), Vector3d(0, -1, 1),
                                                     Vector3d(0, 1, 1), 0.25, 0.25, d, a, b),
            saras_collision::kSeparated);
  EXPECT_NEAR(d, 0.5, 1e-15);
  EXPECT_TRUE(a.isApprox(Vector3d(0, 0, 0.25), 1e-15)) << a.transpose();
  EXPECT_TRUE(b.isApprox(Vector3d(0, 0, 0.75), 1e-15)) << b.transpose();

  EXPECT_EQ(saras_collision::dist_capsule_to_capsule(Vector3d(-1, 0, 0), Vector3d(1, 0, 0), Vector3d(0, -1, 0.5),
                                                     Vector3d(0, 1, 0.5), 0.25, 0.25, d, a, b),
            saras_collision::kTangent);
  EXPECT_NEAR(d, 0.0, 1e-15);
  EXPECT_NEAR((a - Vector3d(0, 0, 0.25)).norm(), 0.0, 1e-15);
  EXPECT_NEAR((b - a).norm(), 0.0, 1e-15);

  EXPECT_EQ(saras_collision::dist_capsule_to_capsule(Vector3d(-1, 0, 0), Vector3d(1, 0, 0), Vector3d(0, -1, 0.3),
                                                     Vector3d(0, 1, 0.3), 0.25, 0.25, d, a, b),
            saras_collision::kIntersecting);
  EXPECT_NEAR(d, -0.2, 1e-15);
  // Witnesses: closest points of the axes.
  EXPECT_TRUE(a.isApprox(Vector3d(0, 0, 0), 1e-15));
  EXPECT_TRUE(b.isApprox(Vector3d(0, 0, 0.3), 1e-15));
}

// The general-case path switches its witness points (axis points when intersecting, surface
// points otherwise) and its code at distance -1e-9 / +1e-9 exactly: crossing perpendicular axes
// whose closest points and distance are exact (s = t = 1/2, |v| = h, Sterbenz subtraction),
// on each switch and one ulp on either side, through both entry points and both argument orders.
TEST(CapsuleCapsule, WitnessPointsAndCodeSwitchAtTheTangentBand)
{
  const double tol = saras_collision::kTangentTolerance;
  auto check = [](double h, double r, int expected_code, double expected_distance, int line) {
    for (int swapped = 0; swapped < 2; ++swapped)
    {
      const Vector3d p1(-1, 0, 0), p2(1, 0, 0), p3(0, -1, h), p4(0, 1, h);
      double d;
      Vector3d a, b;
      const int code = swapped ? saras_collision::dist_capsule_to_capsule(p3, p4, p1, p2, r, r, d, b, a) :
                                 saras_collision::dist_capsule_to_capsule(p1, p2, p3, p4, r, r, d, a, b);
      const saras_collision::DistanceResult full = swapped ? saras_collision::capsuleCapsule(p3, p4, r, p1, p2, r) :
                                                             saras_collision::capsuleCapsule(p1, p2, r, p3, p4, r);
      EXPECT_EQ(code, expected_code) << "line " << line << " swapped " << swapped;
      EXPECT_EQ(full.code, expected_code) << "line " << line;
      EXPECT_EQ(d, expected_distance) << "line " << line;
      EXPECT_EQ(full.distance, expected_distance) << "line " << line;
      // Intersecting: the closest points of the axes; otherwise the surface points.
      const double k = expected_code == saras_collision::kIntersecting ? 0.0 : r;
      EXPECT_LE((a - Vector3d(0, 0, k)).norm(), 1e-24) << "line " << line << ": " << a.transpose();
      EXPECT_LE((b - Vector3d(0, 0, h - k)).norm(), 1e-24) << "line " << line << ": " << b.transpose();
    }
  };
  // +1e-9: zero radii, distance = h exactly.
  check(tol, 0.0, saras_collision::kTangent, tol, __LINE__);
  check(std::nextafter(tol, 1.0), 0.0, saras_collision::kSeparated, std::nextafter(tol, 1.0), __LINE__);
  check(std::nextafter(tol, 0.0), 0.0, saras_collision::kTangent, std::nextafter(tol, 0.0), __LINE__);
  // -1e-9: r1 + r2 = 2^-29, h = 2^-29 - 1e-9 (exact), distance = h - 2^-29 exactly.
  const double r = std::ldexp(1.0, -30), h = std::ldexp(1.0, -29) - tol;
  ASSERT_EQ(h - 2 * r, -tol);
  check(h, r, saras_collision::kTangent, -tol, __LINE__);
  check(std::nextafter(h, 1.0), r, saras_collision::kTangent, std::nextafter(h, 1.0) - 2 * r, __LINE__);
  check(std::nextafter(h, 0.0), r, saras_collision::kIntersecting, std::nextafter(h, 0.0) - 2 * r, __LINE__);
  // Zero distance of either sign is tangent.
  check(0.0, 0.0, saras_collision::kTangent, 0.0, __LINE__);
}

TEST(CapsuleCapsule, ParallelOverlappingGivesValidPoints)
{
  double d;
  Vector3d a, b;
  EXPECT_EQ(saras_collision::dist_capsule_to_capsule(Vector3d(0, 0, 0), Vector3d(1, 0, 0), Vector3d(0.5, 1, 0),
                                                     Vector3d(2, 1, 0), 0.1, 0.1, d, a, b),
            saras_collision::kParallel);
  EXPECT_NEAR(d, 0.8, 1e-15);
  EXPECT_NEAR((a - b).norm(), 0.8, 1e-15);
  EXPECT_NEAR(a.y(), 0.1, 1e-15);
  EXPECT_NEAR(b.y(), 0.9, 1e-15);
  EXPECT_NEAR(a.x(), b.x(), 1e-15);
  EXPECT_GE(a.x(), 0.5);
  EXPECT_LE(a.x(), 1.0);
  // Anti-parallel direction gives the same.
  EXPECT_EQ(saras_collision::dist_capsule_to_capsule(Vector3d(0, 0, 0), Vector3d(1, 0, 0), Vector3d(2, 1, 0),
                                                     Vector3d(0.5, 1, 0), 0.1, 0.1, d, a, b),
            saras_collision::kParallel);
  EXPECT_NEAR(d, 0.8, 1e-15);
  EXPECT_NEAR((a - b).norm(), 0.8, 1e-15);
}

TEST(CapsuleCapsule, ParallelDisjointAndCollinear)
{
  double d;
  Vector3d a, b;
  // Parallel, no overlap of the projections: closest pair = facing end-points.
  EXPECT_EQ(saras_collision::dist_capsule_to_capsule(Vector3d(0, 0, 0), Vector3d(1, 0, 0), Vector3d(2, 1, 0),
                                                     Vector3d(3, 1, 0), 0.1, 0.1, d, a, b),
            saras_collision::kParallel);
  EXPECT_NEAR(d, std::sqrt(2.0) - 0.2, 1e-15);
  const Vector3d n = Vector3d(1, 1, 0).normalized();
  EXPECT_TRUE(a.isApprox(Vector3d(1, 0, 0) + 0.1 * n, 1e-14)) << a.transpose();
  EXPECT_TRUE(b.isApprox(Vector3d(2, 1, 0) - 0.1 * n, 1e-14)) << b.transpose();
  // Collinear.
  EXPECT_EQ(saras_collision::dist_capsule_to_capsule(Vector3d(0, 0, 0), Vector3d(1, 0, 0), Vector3d(3, 0, 0),
                                                     Vector3d(2, 0, 0), 0.1, 0.1, d, a, b),
            saras_collision::kParallel);
  EXPECT_NEAR(d, 0.8, 1e-15);
  EXPECT_TRUE(a.isApprox(Vector3d(1.1, 0, 0), 1e-15));
  EXPECT_TRUE(b.isApprox(Vector3d(1.9, 0, 0), 1e-15));
  // Collinear and overlapping: intersecting.
  EXPECT_EQ(saras_collision::dist_capsule_to_capsule(Vector3d(0, 0, 0), Vector3d(1, 0, 0), Vector3d(0.5, 0, 0),
                                                     Vector3d(2, 0, 0), 0.1, 0.1, d, a, b),
            saras_collision::kIntersecting);
  EXPECT_NEAR(d, -0.2, 1e-15);
}

TEST(CapsuleCapsule, ZeroLengthCapsuleIsASphere)
{
  double d;
  Vector3d a, b;
  EXPECT_EQ(saras_collision::dist_capsule_to_capsule(Vector3d(0.3, 0, 2), Vector3d(0.3, 0, 2), Vector3d(-1, 0, 0),
                                                     Vector3d(1, 0, 0), 0.5, 0.5, d, a, b),
            saras_collision::kSeparated);
  EXPECT_NEAR(d, 1.0, 1e-15);
  EXPECT_TRUE(a.isApprox(Vector3d(0.3, 0, 1.5), 1e-15));
  EXPECT_TRUE(b.isApprox(Vector3d(0.3, 0, 0.5), 1e-15));
  // Sphere-sphere.
  EXPECT_EQ(saras_collision::dist_capsule_to_capsule(Vector3d(0, 0, 0), Vector3d(0, 0, 0), Vector3d(3, 4, 0),
                                                     Vector3d(3, 4, 0), 1.0, 1.5, d, a, b),
            saras_collision::kSeparated);
  EXPECT_NEAR(d, 2.5, 1e-15);
  EXPECT_TRUE(a.isApprox(Vector3d(0.6, 0.8, 0), 1e-15));
  EXPECT_TRUE(b.isApprox(Vector3d(2.1, 2.8, 0), 1e-15));
}

TEST(CapsuleCapsule, InvalidInputIsAnErrorCodeNotANumber)
{
  double d = 0.0;
  Vector3d a, b;
  EXPECT_EQ(saras_collision::dist_capsule_to_capsule(Vector3d(kNaN, 0, 0), Vector3d(1, 0, 0), Vector3d(0, 1, 0),
                                                     Vector3d(1, 1, 0), 0.1, 0.1, d, a, b),
            saras_collision::kInvalidInput);
  EXPECT_TRUE(std::isnan(d));
  EXPECT_EQ(saras_collision::dist_capsule_to_capsule(Vector3d(0, 0, 0), Vector3d(1, 0, 0), Vector3d(0, 1, 0),
                                                     Vector3d(1, 1, 0), -0.1, 0.1, d, a, b),
            saras_collision::kInvalidInput);
  EXPECT_EQ(saras_collision::dist_capsule_to_capsule(Vector3d(0, 0, 0), Vector3d(1, 0, 0), Vector3d(0, 1, 0),
                                                     Vector3d(1, std::numeric_limits<double>::infinity(), 0), 0.1,
                                                     0.1, d, a, b),
            saras_collision::kInvalidInput);
  EXPECT_TRUE(std::isnan(a.x()));
}

// A radius of -0 is a radius of 0 (r >= 0 holds), not an invalid input, though the fast path's
// bit-pattern range test hands it to the careful path: the same answer as +0, on both entry
// points.
TEST(CapsuleCapsule, NegativeZeroRadiusIsZero)
{
  const Vector3d p1(0, 0, 0), p2(1, 0, 0), p3(0.5, 0.3, 0.4), p4(0.5, 1.3, 0.4);
  for (const auto& radii : { std::make_pair(-0.0, 0.1), std::make_pair(0.1, -0.0), std::make_pair(-0.0, -0.0) })
  {
    double d_neg, d_pos;
    Vector3d a_neg, b_neg, a_pos, b_pos;
    const int code_neg = saras_collision::dist_capsule_to_capsule(p1, p2, p3, p4, radii.first, radii.second, d_neg,
                                                                  a_neg, b_neg);
    const int code_pos = saras_collision::dist_capsule_to_capsule(p1, p2, p3, p4, std::abs(radii.first),
                                                                  std::abs(radii.second), d_pos, a_pos, b_pos);
    EXPECT_EQ(code_neg, saras_collision::kSeparated);
    EXPECT_EQ(code_pos, saras_collision::kSeparated);
    EXPECT_NEAR(d_neg, 0.5 - std::abs(radii.first) - std::abs(radii.second), 1e-15);
    EXPECT_NEAR(d_neg, d_pos, 1e-15);
    EXPECT_LE((a_neg - a_pos).norm(), 1e-15);
    EXPECT_LE((b_neg - b_pos).norm(), 1e-15);
    const saras_collision::DistanceResult full =
        saras_collision::capsuleCapsule(p1, p2, radii.first, p3, p4, radii.second);
    EXPECT_EQ(full.code, saras_collision::kSeparated);
    EXPECT_EQ(full.distance, d_neg);
  }
}

TEST(CapsuleCapsule, RandomAgainstFclAndReference)
{
  Random rnd;
  int separated = 0, intersecting = 0, verdict_checked = 0;
  double worst_fcl = 0.0, worst_ref = 0.0;
  for (int k = 0; k < kRandomCases; ++k)
  {
    Vector3d p1, p2, p3, p4;
    rnd.segment(p1, p2, 0.04);
    rnd.segment(p3, p4, 0.04);
    if (k % 10 == 0)  // exactly parallel pairs
      p4 = p3 + (p2 - p1) * rnd.uniform(-1.5, 1.5);
    const double r1 = rnd.uniform(0.0, 0.01), r2 = rnd.uniform(0.0, 0.01);
    int code;
    double d, ref;
    Vector3d a, b;
    ASSERT_TRUE(answerNearReference(p1, p2, p3, p4, r1, r2, 1e-12, code, d, a, b, &ref)) << "case " << k;
    worst_ref = std::max(worst_ref, std::abs(d - ref));
    if (code == saras_collision::kSeparated || code == saras_collision::kParallel)
    {
      ++separated;
      // The points realise the distance and lie on the two surfaces.
      ASSERT_NEAR((a - b).norm(), d, 1e-12) << k;
      ASSERT_NEAR(pointSegment(a, p1, p2), r1, 1e-12) << k;
      ASSERT_NEAR(pointSegment(b, p3, p4), r2, 1e-12) << k;
    }
    else if (code == saras_collision::kIntersecting)
    {
      ++intersecting;
      ASSERT_LT(d, 0.0);
    }
    // FCL (capsules need a non-zero length there).
    if ((p2 - p1).norm() < 1e-3 || (p4 - p3).norm() < 1e-3)
      continue;
    const fcl::Capsuled c1(r1, (p2 - p1).norm()), c2(r2, (p4 - p3).norm());
    const FclAnswer f = fclQuery(c1, capsuleTransform(p1, p2), c2, capsuleTransform(p3, p4));
    if (std::abs(d) > 1e-6)
    {
      ++verdict_checked;
      ASSERT_EQ(f.collides, code == saras_collision::kIntersecting) << "case " << k << " d=" << d;
    }
    if (d > 1e-6)
    {
      worst_fcl = std::max(worst_fcl, std::abs(d - f.distance));
      ASSERT_NEAR(d, f.distance, 1e-6) << "case " << k;
    }
  }
  std::printf("capsule-capsule: %d separated, %d intersecting, %d verdicts vs FCL; max |ours-FCL| %.3g m, "
              "max |ours-ref| %.3g m\n",
              separated, intersecting, verdict_checked, worst_fcl, worst_ref);
  EXPECT_GT(separated, kRandomCases / 10);
  EXPECT_GT(intersecting, kRandomCases / 20);
}

// The general-case fast path (axes more than ~1.8 degrees from parallel: sin^2 > 1e-3, the
// switch lying between 1e-3 and 1.23e-3) and the careful path (cross-product denominator) meet
// at that angle: both sides of the switch, and
// every clamping region of both parameters, must still be exact and never overstated.
TEST(CapsuleCapsule, ExactOnBothSidesOfTheFastPathAngle)
{
  Random rnd;
  int checked = 0;
  for (int k = 0; k < 4000; ++k)
  {
    const Vector3d p1 = rnd.point(0.05);
    const Vector3d d1 = rnd.point(1.0).normalized() * rnd.uniform(0.001, 0.12);
    Vector3d axis = d1.cross(rnd.point(1.0));
    if (axis.norm() < 1e-6)
      continue;
    axis.normalize();
    const double angle = rnd.uniform(0.5, 1.5) * std::asin(std::sqrt(1e-3));  // switch at 1.0
    const Vector3d d2 = (Eigen::AngleAxisd(angle, axis) * d1).normalized() * rnd.uniform(0.001, 0.12) *
                        (k % 2 == 0 ? 1.0 : -1.0);
    const Vector3d p3 = p1 + rnd.point(0.08), p4 = p3 + d2;
    const Vector3d p2 = p1 + d1;
    const double r1 = rnd.uniform(0.0, 0.01), r2 = rnd.uniform(0.0, 0.01);
    int code;
    double d;
    Vector3d a, b;
    ASSERT_TRUE(answerNearReference(p1, p2, p3, p4, r1, r2, 1e-12, code, d, a, b)) << "case " << k;
    if (code == saras_collision::kSeparated)
    {
      ASSERT_NEAR((a - b).norm(), d, 1e-12) << k;
      ASSERT_NEAR(pointSegment(a, p1, p2), r1, 1e-12) << k;
      ASSERT_NEAR(pointSegment(b, p3, p4), r2, 1e-12) << k;
    }
    const saras_collision::DistanceResult full = saras_collision::capsuleCapsule(p1, p2, r1, p3, p4, r2);
    ASSERT_EQ(full.code, code) << k;
    ASSERT_EQ(full.distance, d) << k;
    ++checked;
  }
  EXPECT_GT(checked, 3900);
}

// Every clamping region of the general-case path (t interior / clamped to 0 / to 1, s interior
// or clamped, the re-optimisation of s after t is clamped), each with the segments in both
// directions and the capsules in both orders: exact closed forms, points on the surfaces.
TEST(CapsuleCapsule, EveryClampingRegionClosedForm)
{
  struct Case
  {
    Vector3d p3, p4, q1, q2;  // second axis; expected closest axis points
  };
  // First axis: x from -1 to 1 (y = z = 0); the second axis is never parallel to it.
  const Vector3d p1(-1, 0, 0), p2(1, 0, 0);
  const Case cases[] = {
    { Vector3d(0, -1, 1), Vector3d(0, 1, 1), Vector3d(0, 0, 0), Vector3d(0, 0, 1) },         // both interior
    { Vector3d(0, 2, 1), Vector3d(0, 3, 1), Vector3d(0, 0, 0), Vector3d(0, 2, 1) },          // t = 0, s re-optimised
    { Vector3d(0, -3, 1), Vector3d(0, -2, 1), Vector3d(0, 0, 0), Vector3d(0, -2, 1) },       // t = 1, s re-optimised
    { Vector3d(3, -1, 1), Vector3d(3, 1, 1), Vector3d(1, 0, 0), Vector3d(3, 0, 1) },         // s = 1, t interior
    { Vector3d(-3, -1, -1), Vector3d(-3, 1, -1), Vector3d(-1, 0, 0), Vector3d(-3, 0, -1) },  // s = 0, t interior
    { Vector3d(3, 2, 1), Vector3d(3, 3, 1), Vector3d(1, 0, 0), Vector3d(3, 2, 1) },          // s = 1, t = 0
    { Vector3d(0.5, 2, 1), Vector3d(2.5, 3, 1), Vector3d(0.5, 0, 0), Vector3d(0.5, 2, 1) },  // t = 0, oblique
    { Vector3d(3, 2, 1), Vector3d(5, 0.5, 1), Vector3d(1, 0, 0), Vector3d(3, 2, 1) },        // both clamped, oblique
  };
  const double r1 = 0.25, r2 = 0.125;
  int k = 0;
  for (const Case& c : cases)
  {
    const double axis = (c.q2 - c.q1).norm();
    const Vector3d n = (c.q2 - c.q1) / axis;  // from capsule 1 to capsule 2
    ASSERT_NEAR(segmentSegmentRef(p1, p2, c.p3, c.p4), axis, 1e-15) << k;  // the case itself is right
    for (int variant = 0; variant < 8; ++variant, ++k)
    {
      Vector3d a1 = p1, a2 = p2, b1 = c.p3, b2 = c.p4;
      if (variant & 1)
        std::swap(a1, a2);
      if (variant & 2)
        std::swap(b1, b2);
      const bool swapped = (variant & 4) != 0;
      double d;
      Vector3d a, b;
      const int code = swapped ? saras_collision::dist_capsule_to_capsule(b1, b2, a1, a2, r2, r1, d, b, a) :
                                 saras_collision::dist_capsule_to_capsule(a1, a2, b1, b2, r1, r2, d, a, b);
      EXPECT_EQ(code, saras_collision::kSeparated) << k;
      EXPECT_NEAR(d, axis - r1 - r2, 1e-15) << k;
      EXPECT_LE((a - (c.q1 + r1 * n)).norm(), 1e-15) << k << ": " << a.transpose();
      EXPECT_LE((b - (c.q2 - r2 * n)).norm(), 1e-15) << k << ": " << b.transpose();
    }
  }
}

/// dist_capsule_to_capsule() of the pair scaled by @p scale, with the distance and points
/// scaled back into @p d, @p a, @p b; expects capsuleCapsule() to give the same code and
/// distance bit for bit. @return the code
int scaledAnswer(const Vector3d& p1, const Vector3d& p2, const Vector3d& p3, const Vector3d& p4, double r1, double r2,
                 double scale, double& d, Vector3d& a, Vector3d& b)
{
  const int code = saras_collision::dist_capsule_to_capsule(p1 * scale, p2 * scale, p3 * scale, p4 * scale, r1 * scale,
                                                            r2 * scale, d, a, b);
  const saras_collision::DistanceResult full =
      saras_collision::capsuleCapsule(p1 * scale, p2 * scale, r1 * scale, p3 * scale, p4 * scale, r2 * scale);
  EXPECT_EQ(full.code, code) << "scale " << scale;
  EXPECT_EQ(full.distance, d) << "scale " << scale;
  d /= scale;
  a /= scale;
  b /= scale;
  return code;
}

// The general-case path requires its products (a e |d1 x d2|^2 and the scaled axis difference
// squared) to be normal numbers and falls back to the careful path otherwise, which rescales
// inputs beyond 2^200 m by a power of two: the result is the same, scaled, from 1e-12 to
// 1e300 (the general path runs up to ~1e35, the careful one above, rescaled above 1.6e60),
// and a distance that is not representable is kInvalidInput, never a wrong number.
TEST(CapsuleCapsule, ScaleInvariantAcrossTheFastPathGuards)
{
  Random rnd;
  int checked = 0;
  for (int k = 0; k < 300; ++k)
  {
    Vector3d p1, p2, p3, p4;
    rnd.segment(p1, p2, 0.04);
    rnd.segment(p3, p4, 0.04);
    if (k % 10 == 0)  // parallel pairs: careful path at every scale
      p4 = p3 + (p2 - p1) * rnd.uniform(-1.5, 1.5);
    const double r1 = rnd.uniform(0.0, 0.01), r2 = rnd.uniform(0.0, 0.01);
    int code;
    double d;
    Vector3d a, b;
    ASSERT_TRUE(answerNearReference(p1, p2, p3, p4, r1, r2, 1e-12, code, d, a, b)) << k;
    for (double scale : { 1e-12, 1e-6, 1e-3, 1e3, 1e12, 1e25, 1e30, 1e60, 1e75, 1e100, 1e150, 1e160, 1e300 })
    {
      double ds;
      Vector3d as, bs;
      const int code_s = scaledAnswer(p1, p2, p3, p4, r1, r2, scale, ds, as, bs);
      ASSERT_TRUE(saras_collision::isValidCode(code_s)) << k << " scale " << scale;
      ASSERT_NEAR(ds, d, 1e-13) << k << " scale " << scale;
      if (code != saras_collision::kIntersecting && code_s != saras_collision::kIntersecting)
      {
        ASSERT_LE((as - a).norm(), 1e-13) << k << " scale " << scale;
        ASSERT_LE((bs - b).norm(), 1e-13) << k << " scale " << scale;
      }
      if (std::abs(ds * scale) > 1e-9 && std::abs(d) > 1e-9)  // codes away from the 1 nm tangent band
      {
        ASSERT_EQ(code_s == saras_collision::kIntersecting, code == saras_collision::kIntersecting) << k;
        ASSERT_EQ(code_s == saras_collision::kParallel, code == saras_collision::kParallel) << k;
      }
      ++checked;
    }
  }
  EXPECT_EQ(checked, 300 * 13);
  // Finite inputs whose distance is not representable (> 1.8e308 m): an error code, not a number.
  double d;
  Vector3d a, b;
  const double big = 1.5e308;
  EXPECT_EQ(saras_collision::dist_capsule_to_capsule(Vector3d(-big, -big, 0), Vector3d(-big, -big, 1),
                                                     Vector3d(big, big, 0), Vector3d(big, big + 1, 0), 0.0, 0.0, d, a,
                                                     b),
            saras_collision::kInvalidInput);
  EXPECT_TRUE(std::isnan(d));
}

// The general-case path takes each of a, e, |v|^2, r1, r2 below 2^238 as its range (no product
// can overflow below it) and hands larger inputs to the careful path: the same answer, scaled, on
// both sides of the bound (scaling by a power of two is exact), for both entry points.
TEST(CapsuleCapsule, SameAnswerOnBothSidesOfTheFastPathRangeBound)
{
  Random rnd;
  int checked = 0;
  for (int k = 0; k < 200; ++k)
  {
    Vector3d p1, p2, p3, p4;
    rnd.segment(p1, p2, 0.5);
    rnd.segment(p3, p4, 0.5);
    p2 = p1 + (p2 - p1) * rnd.uniform(1.0, 20.0);  // up to 2.4 long, up to ~1.7 apart
    const double r1 = rnd.uniform(0.0, 0.01), r2 = rnd.uniform(0.0, 0.01);
    int code;
    double d;
    Vector3d a, b;
    ASSERT_TRUE(answerNearReference(p1, p2, p3, p4, r1, r2, 1e-12, code, d, a, b)) << k;
    for (int e = 105; e <= 135; ++e)  // the bound is crossed between 2^116 and 2^128 for these sizes
    {
      const double scale = std::ldexp(1.0, e);
      double ds;
      Vector3d as, bs;
      ASSERT_EQ(scaledAnswer(p1, p2, p3, p4, r1, r2, scale, ds, as, bs), code) << k << " 2^" << e;
      ASSERT_NEAR(ds, d, 1e-14) << k << " 2^" << e;
      ASSERT_LE((as - a).norm(), 1e-14) << k << " 2^" << e;
      ASSERT_LE((bs - b).norm(), 1e-14) << k << " 2^" << e;
      ++checked;
    }
  }
  EXPECT_EQ(checked, 200 * 31);
}

// ===================================================================== boxes
TEST(Box, VertexOrderAndValidation)
{
  Vector3d v[8];
  aabbVertices(Vector3d(0, 0, 0), Vector3d(1, 2, 3), v);
  OrientedBox box;
  ASSERT_EQ(saras_collision::makeBox(v, 1e-9, box), saras_collision::kSeparated);
  EXPECT_TRUE(box.center.isApprox(Vector3d(0.5, 1, 1.5)));
  EXPECT_TRUE(box.half.isApprox(Vector3d(0.5, 1, 1.5)));
  Vector3d back[8];
  saras_collision::boxVertices(box, back);
  for (int i = 0; i < 8; ++i)
    EXPECT_NEAR((back[i] - v[i]).norm(), 0.0, 1e-15) << i;

  double d;
  Vector3d a, b;
  Vector3d swapped[8];
  std::copy(v, v + 8, swapped);
  std::swap(swapped[2], swapped[3]);  // wrong order
  EXPECT_EQ(saras_collision::dist_sphere_to_parallelepiped(Vector3d(5, 5, 5), swapped, 0.1, d, a, b),
            saras_collision::kInvalidBox);
  EXPECT_TRUE(std::isnan(d));
  Vector3d sheared[8];
  std::copy(v, v + 8, sheared);
  for (int i : { 4, 5, 6, 7 })
    sheared[i].x() += 0.2;  // parallelepiped that is not rectangular
  EXPECT_EQ(saras_collision::dist_capsule_to_parallelepiped(Vector3d(5, 5, 5), Vector3d(6, 6, 6), sheared, 0.1, d, a,
                                                            b),
            saras_collision::kInvalidBox);
  Vector3d flat[8];
  aabbVertices(Vector3d(0, 0, 0), Vector3d(1, 2, 0), flat);
  EXPECT_EQ(saras_collision::dist_sphere_to_parallelepiped(Vector3d(5, 5, 5), flat, 0.1, d, a, b),
            saras_collision::kInvalidBox);
  Vector3d with_nan[8];
  std::copy(v, v + 8, with_nan);
  with_nan[6].z() = kNaN;
  EXPECT_EQ(saras_collision::dist_sphere_to_parallelepiped(Vector3d(5, 5, 5), with_nan, 0.1, d, a, b),
            saras_collision::kInvalidInput);
  EXPECT_EQ(saras_collision::dist_sphere_to_parallelepiped(Vector3d(5, kNaN, 5), v, 0.1, d, a, b),
            saras_collision::kInvalidInput);
  EXPECT_EQ(saras_collision::dist_sphere_to_parallelepiped(Vector3d(5, 5, 5), v, kNaN, d, a, b),
            saras_collision::kInvalidInput);
  EXPECT_EQ(saras_collision::dist_sphere_to_parallelepiped(Vector3d(5, 5, 5), nullptr, 0.1, d, a, b),
            saras_collision::kInvalidInput);
  // Left-handed order (y and z swapped roles) is still a rectangular box.
  Vector3d left[8] = { v[0], v[1], v[5], v[4], v[3], v[2], v[6], v[7] };
  EXPECT_EQ(saras_collision::dist_sphere_to_parallelepiped(Vector3d(0.5, 1, 4), left, 0.5, d, a, b),
            saras_collision::kSeparated);
  EXPECT_NEAR(d, 0.5, 1e-15);
}

TEST(SphereBox, FaceEdgeVertexInside)
{
  Vector3d v[8];
  aabbVertices(Vector3d(0, 0, 0), Vector3d(1, 2, 3), v);
  double d;
  Vector3d a, b;
  // Face region.
  EXPECT_EQ(saras_collision::dist_sphere_to_parallelepiped(Vector3d(0.5, 1, 4), v, 0.5, d, a, b),
            saras_collision::kSeparated);
  EXPECT_NEAR(d, 0.5, 1e-15);
  EXPECT_TRUE(a.isApprox(Vector3d(0.5, 1, 3.5)));
  EXPECT_TRUE(b.isApprox(Vector3d(0.5, 1, 3)));
  // Edge region.
  EXPECT_EQ(saras_collision::dist_sphere_to_parallelepiped(Vector3d(2, 1, 4), v, 0.0, d, a, b),
            saras_collision::kSeparated);
  EXPECT_NEAR(d, std::sqrt(2.0), 1e-15);
  EXPECT_TRUE(b.isApprox(Vector3d(1, 1, 3)));
  EXPECT_TRUE(a.isApprox(Vector3d(2, 1, 4)));
  // Vertex region.
  EXPECT_EQ(saras_collision::dist_sphere_to_parallelepiped(Vector3d(2, 3, 4), v, 0.5, d, a, b),
            saras_collision::kSeparated);
  EXPECT_NEAR(d, std::sqrt(3.0) - 0.5, 1e-15);
  EXPECT_TRUE(b.isApprox(Vector3d(1, 2, 3)));
  EXPECT_NEAR((a - b).norm(), d, 1e-15);
  // Tangent to a face.
  EXPECT_EQ(saras_collision::dist_sphere_to_parallelepiped(Vector3d(-0.25, 1, 1), v, 0.25, d, a, b),
            saras_collision::kTangent);
  EXPECT_TRUE(a.isApprox(Vector3d(0, 1, 1)));
  EXPECT_TRUE(b.isApprox(Vector3d(0, 1, 1)));
  // Overlapping from outside: negative distance, witnesses centre -> surface point.
  EXPECT_EQ(saras_collision::dist_sphere_to_parallelepiped(Vector3d(-0.1, 1, 1), v, 0.25, d, a, b),
            saras_collision::kIntersecting);
  EXPECT_NEAR(d, -0.15, 1e-15);
  // Centre inside: depth to the nearest face (x = 0 at 0.2) plus the radius.
  EXPECT_EQ(saras_collision::dist_sphere_to_parallelepiped(Vector3d(0.2, 1, 1.5), v, 0.1, d, a, b),
            saras_collision::kIntersecting);
  EXPECT_NEAR(d, -0.3, 1e-15);
  EXPECT_TRUE(a.isApprox(Vector3d(0.2, 1, 1.5)));
  EXPECT_TRUE(b.isApprox(Vector3d(0, 1, 1.5)));
  // Point (zero radius) on the surface: tangent.
  EXPECT_EQ(saras_collision::dist_sphere_to_parallelepiped(Vector3d(1, 1, 1), v, 0.0, d, a, b),
            saras_collision::kTangent);
}

TEST(CapsuleBox, ClosedFormCases)
{
  Vector3d v[8];
  aabbVertices(Vector3d(0, 0, 0), Vector3d(1, 2, 3), v);
  double d;
  Vector3d a, b;
  // Axis crossing the box along x at (y, z) = (1, 1.5): deepest at the centre, depth 0.5.
  EXPECT_EQ(saras_collision::dist_capsule_to_parallelepiped(Vector3d(-1, 1, 1.5), Vector3d(2, 1, 1.5), v, 0.1, d,
                                                            a, b),
            saras_collision::kIntersecting);
  EXPECT_NEAR(d, -0.6, 1e-15);
  // Parallel to the top face, above it: distance 0.3, points above each other.
  EXPECT_EQ(saras_collision::dist_capsule_to_parallelepiped(Vector3d(-1, 1, 3.5), Vector3d(2, 1, 3.5), v, 0.2, d, a,
                                                            b),
            saras_collision::kSeparated);
  EXPECT_NEAR(d, 0.3, 1e-15);
  EXPECT_NEAR(a.z(), 3.3, 1e-15);
  EXPECT_NEAR(b.z(), 3.0, 1e-15);
  EXPECT_NEAR(a.x(), b.x(), 1e-15);
  EXPECT_GE(b.x(), 0.0);
  EXPECT_LE(b.x(), 1.0);
  // Skew over an edge: axis from (2, -1, 4) to (2, 3, 4) passes over the edge x=1, z=3.
  EXPECT_EQ(saras_collision::dist_capsule_to_parallelepiped(Vector3d(2, -1, 4), Vector3d(2, 3, 4), v, 0.0, d, a, b),
            saras_collision::kSeparated);
  EXPECT_NEAR(d, std::sqrt(2.0), 1e-15);
  EXPECT_NEAR(b.x(), 1.0, 1e-15);
  EXPECT_NEAR(b.z(), 3.0, 1e-15);
  // Diagonal skew over the edge x=1,z=3: closest point at y = 1 on the edge.
  EXPECT_EQ(saras_collision::dist_capsule_to_parallelepiped(Vector3d(2, 0, 3), Vector3d(1, 2, 5), v, 0.0, d, a, b),
            saras_collision::kSeparated);
  EXPECT_NEAR(d, segmentSegmentRef(Vector3d(2, 0, 3), Vector3d(1, 2, 5), v[2], v[6]), 1e-15);
  // Whole capsule inside: depth of the deepest axis point.
  EXPECT_EQ(saras_collision::dist_capsule_to_parallelepiped(Vector3d(0.5, 0.5, 1.5), Vector3d(0.5, 1.5, 1.5), v, 0.1,
                                                            d, a, b),
            saras_collision::kIntersecting);
  EXPECT_NEAR(d, -0.6, 1e-15);
  // Rotating and translating everything does not change the distance.
  const Eigen::Isometry3d T = Eigen::Translation3d(0.3, -0.2, 0.1) *
                              Eigen::AngleAxisd(0.7, Vector3d(1, 2, 3).normalized());
  Vector3d w[8];
  for (int i = 0; i < 8; ++i)
    w[i] = T * v[i];
  EXPECT_EQ(saras_collision::dist_capsule_to_parallelepiped(T * Vector3d(-1, 1, 3.5), T * Vector3d(2, 1, 3.5), w, 0.2,
                                                            d, a, b),
            saras_collision::kSeparated);
  EXPECT_NEAR(d, 0.3, 1e-14);
}

// FCL issue #568 (capsule vs AABB reported as not colliding): the capsule end-point (30, 82, 29)
// lies 30 below the box face z = 59 with x, y inside it, radius 36 -> penetration 6.
TEST(CapsuleBox, FclIssue568Regression)
{
  Vector3d v[8];
  aabbVertices(Vector3d(26, 63, 59), Vector3d(98, 89, 99), v);
  double d;
  Vector3d a, b;
  EXPECT_EQ(saras_collision::dist_capsule_to_parallelepiped(Vector3d(30, 82, 29), Vector3d(67, 68, 11), v, 36.0, d, a,
                                                            b),
            saras_collision::kIntersecting);
  EXPECT_NEAR(d, -6.0, 1e-12);
  EXPECT_TRUE(a.isApprox(Vector3d(30, 82, 29)));
  EXPECT_TRUE(b.isApprox(Vector3d(30, 82, 59)));
  // Informative: what FCL says on this machine.
  const OrientedBox box = boxFromVertices(v);
  const fcl::Capsuled cap(36.0, (Vector3d(67, 68, 11) - Vector3d(30, 82, 29)).norm());
  const fcl::Boxd fbox(72, 26, 40);
  const FclAnswer f = fclQuery(cap, capsuleTransform(Vector3d(30, 82, 29), Vector3d(67, 68, 11)), fbox,
                               boxTransform(box));
  std::printf("FCL #568 case: collide=%d distance=%g (exact: collision, -6)\n", f.collides, f.distance);
}

// FCL issue #508 (box-box along y reported 3.16 instead of 3 by libccd): the same geometry with a
// capsule of radius 0.5 along x standing for the first box's y-extent.
TEST(CapsuleBox, FclIssue508Regression)
{
  Vector3d v[8];
  aabbVertices(Vector3d(-0.5, 3.5, -0.5), Vector3d(0.5, 4.5, 0.5), v);
  double d;
  Vector3d a, b;
  EXPECT_EQ(saras_collision::dist_capsule_to_parallelepiped(Vector3d(-0.5, 0, 0), Vector3d(0.5, 0, 0), v, 0.5, d, a,
                                                            b),
            saras_collision::kSeparated);
  EXPECT_NEAR(d, 3.0, 1e-15);
  EXPECT_NEAR(a.y(), 0.5, 1e-15);
  EXPECT_NEAR(b.y(), 3.5, 1e-15);
  // The issue's failing interval (translations beyond 1.99 along y), with a sphere of radius 0.5.
  for (double y : { 1.5, 1.99, 2.5, 4.0, 10.0 })
  {
    Vector3d u[8];
    aabbVertices(Vector3d(-0.5, y - 0.5, -0.5), Vector3d(0.5, y + 0.5, 0.5), u);
    EXPECT_EQ(saras_collision::dist_sphere_to_parallelepiped(Vector3d(0, 0, 0), u, 0.5, d, a, b),
              saras_collision::kSeparated);
    EXPECT_NEAR(d, y - 1.0, 1e-15) << y;
  }
}

// FCL issue #589 (capsule robot links vs a 0.3 x 0.3 x 0.5 box at (0.6, 0, 0.25): wrong
// collision and distance results): vertical capsules approaching the face x = 0.45.
TEST(CapsuleBox, FclIssue589Regression)
{
  Vector3d v[8];
  aabbVertices(Vector3d(0.45, -0.15, 0.0), Vector3d(0.75, 0.15, 0.5), v);
  double d;
  Vector3d a, b;
  const double r = 0.05;
  const struct
  {
    double x, expected;
    int code;
  } cases[] = { { 0.30, 0.10, saras_collision::kSeparated },
                { 0.40, 0.0, saras_collision::kTangent },
                { 0.42, -0.02, saras_collision::kIntersecting },
                { 0.60, -0.20, saras_collision::kIntersecting } };
  for (const auto& c : cases)
  {
    EXPECT_EQ(saras_collision::dist_capsule_to_parallelepiped(Vector3d(c.x, 0, 0.1), Vector3d(c.x, 0, 0.7), v, r, d,
                                                              a, b),
              c.code)
        << c.x;
    EXPECT_NEAR(d, c.expected, 1e-15) << c.x;
  }
}

namespace
{
void checkCapsuleBoxCase(Random& rnd, int k, bool sphere, int& separated, int& intersecting, double& worst_fcl,
                         double& worst_ref)
{
  const OrientedBox box = rnd.box();
  Vector3d p1, p2;
  rnd.segment(p1, p2);
  if (sphere)
    p2 = p1;
  const double r = rnd.uniform(0.0, 0.01);
  Vector3d v[8];
  saras_collision::boxVertices(box, v);
  double d;
  Vector3d a, b;
  const int code = sphere ? saras_collision::dist_sphere_to_parallelepiped(p1, v, r, d, a, b) :
                            saras_collision::dist_capsule_to_parallelepiped(p1, p2, v, r, d, a, b);
  ASSERT_TRUE(code == saras_collision::kSeparated || code == saras_collision::kTangent ||
              code == saras_collision::kIntersecting)
      << k << " code " << code;
  const double axis_ref = segmentBoxRef(p1, p2, box);
  if (axis_ref > 0.0)
  {
    const double ref = axis_ref - r;
    worst_ref = std::max(worst_ref, std::abs(d - ref));
    ASSERT_NEAR(d, ref, 1e-12) << "case " << k;
    ASSERT_LE(d, ref + 1e-12) << "overstated, case " << k;
  }
  else
  {
    // Axis meets the box: the signed distance is the deepest axis point's depth minus r.
    ASSERT_EQ(code, r > 0.0 ? saras_collision::kIntersecting : code) << k;
    const int n = 2000;
    const double sampled = sampledAxisDepth(p1, p2, box, n) - r;
    ASSERT_LE(d, sampled + 1e-12) << k << " code " << code << " r " << r << " p1 " << p1.transpose() << " p2 "
                                  << p2.transpose() << " c " << box.center.transpose() << " h "
                                  << box.half.transpose() << " a " << a.transpose() << " b " << b.transpose();
    ASSERT_GE(d, sampled - (p2 - p1).norm() / n - 1e-12) << k;
  }
  if (code == saras_collision::kSeparated)
  {
    ++separated;
    ASSERT_NEAR((a - b).norm(), d, 1e-12) << k;
    ASSERT_NEAR(pointSegment(a, p1, p2), r, 1e-12) << k;
    ASSERT_NEAR(pointBoxSigned(b, box), 0.0, 1e-12) << k;
  }
  else if (code == saras_collision::kIntersecting)
  {
    ++intersecting;
  }
  const fcl::Boxd fbox(2 * box.half);
  FclAnswer f;
  if (sphere)
  {
    const fcl::Sphered s(r);
    fcl::Transform3d tf = fcl::Transform3d::Identity();
    tf.translation() = p1;
    f = fclQuery(s, tf, fbox, boxTransform(box));
  }
  else
  {
    if ((p2 - p1).norm() < 1e-3)
      return;
    const fcl::Capsuled c(r, (p2 - p1).norm());
    f = fclQuery(c, capsuleTransform(p1, p2), fbox, boxTransform(box));
  }
  if (std::abs(d) > 1e-6)
    ASSERT_EQ(f.collides, code == saras_collision::kIntersecting) << "case " << k << " d=" << d;
  if (d > 1e-6)
  {
    worst_fcl = std::max(worst_fcl, std::abs(d - f.distance));
    ASSERT_NEAR(d, f.distance, 1e-6) << "case " << k;
  }
}
}  // namespace

TEST(CapsuleBox, RandomAgainstFclAndReference)
{
  Random rnd;
  int separated = 0, intersecting = 0;
  double worst_fcl = 0.0, worst_ref = 0.0;
  for (int k = 0; k < kRandomCases; ++k)
  {
    checkCapsuleBoxCase(rnd, k, false, separated, intersecting, worst_fcl, worst_ref);
    if (HasFatalFailure())
      return;
  }
  std::printf("capsule-box: %d separated, %d intersecting; max |ours-FCL| %.3g m, max |ours-ref| %.3g m\n",
              separated, intersecting, worst_fcl, worst_ref);
  EXPECT_GT(separated, kRandomCases / 10);
  EXPECT_GT(intersecting, kRandomCases / 20);
}

TEST(SphereBox, RandomAgainstFclAndReference)
{
  Random rnd;
  rnd.gen.seed(77);
  int separated = 0, intersecting = 0;
  double worst_fcl = 0.0, worst_ref = 0.0;
  for (int k = 0; k < kRandomCases; ++k)
  {
    checkCapsuleBoxCase(rnd, k, true, separated, intersecting, worst_fcl, worst_ref);
    if (HasFatalFailure())
      return;
  }
  std::printf("sphere-box: %d separated, %d intersecting; max |ours-FCL| %.3g m, max |ours-ref| %.3g m\n", separated,
              intersecting, worst_fcl, worst_ref);
  EXPECT_GT(separated, kRandomCases / 10);
  EXPECT_GT(intersecting, kRandomCases / 50);
}

// ===================================================================== fast-path regressions
// The deliverable-signature functions validate their inputs on branch-free fast paths
// (capsule-capsule: the finiteness check is done on the result; boxes: one combined test that
// is false on NaN). These tests pin that every bad input still gets its distinct error code.
namespace
{
constexpr double kInf = std::numeric_limits<double>::infinity();

bool allNaN(double d, const Vector3d& a, const Vector3d& b)
{
  return std::isnan(d) && a.array().isNaN().all() && b.array().isNaN().all();
}
}  // namespace

TEST(CapsuleCapsule, EveryNonFiniteInputIsRejected)
{
  // Configurations reaching every path: crossing, parallel, both / one degenerate axis.
  const Vector3d configs[][4] = {
    { Vector3d(-1, 0, 0), Vector3d(1, 0, 0), Vector3d(0, -1, 1), Vector3d(0, 1, 1) },
    { Vector3d(0, 0, 0), Vector3d(1, 0, 0), Vector3d(0.5, 1, 0), Vector3d(1.5, 1, 0) },
    { Vector3d(0, 0, 0), Vector3d(0, 0, 0), Vector3d(3, 4, 0), Vector3d(3, 4, 0) },
    { Vector3d(0.3, 0, 2), Vector3d(0.3, 0, 2), Vector3d(-1, 0, 0), Vector3d(1, 0, 0) },
    { Vector3d(-1, 0, 0), Vector3d(1, 0, 0), Vector3d(0.3, 0, 2), Vector3d(0.3, 0, 2) },
    { Vector3d(-1, 0, 0), Vector3d(1, 0, 0), Vector3d(0, -1, 0), Vector3d(0, 1, 0) },  // axes meet
  };
  int checked = 0;
  for (const auto& c : configs)
  {
    double d;
    Vector3d a, b;
    ASSERT_TRUE(saras_collision::isValidCode(
        saras_collision::dist_capsule_to_capsule(c[0], c[1], c[2], c[3], 0.1, 0.2, d, a, b)));
    for (int k = 0; k < 12; ++k)
    {
      for (double bad : { kNaN, kInf, -kInf })
      {
        Vector3d p[4] = { c[0], c[1], c[2], c[3] };
        p[k / 3][k % 3] = bad;
        d = 0.0;
        EXPECT_EQ(saras_collision::dist_capsule_to_capsule(p[0], p[1], p[2], p[3], 0.1, 0.2, d, a, b),
                  saras_collision::kInvalidInput)
            << "coordinate " << k << " = " << bad;
        EXPECT_TRUE(allNaN(d, a, b)) << k;
        const saras_collision::DistanceResult res = saras_collision::capsuleCapsule(p[0], p[1], 0.1, p[2], p[3], 0.2);
        EXPECT_EQ(res.code, saras_collision::kInvalidInput) << k;
        EXPECT_TRUE(std::isnan(res.distance)) << k;
        ++checked;
      }
    }
    for (double bad : { kNaN, kInf, -kInf, -1e-12 })
    {
      EXPECT_EQ(saras_collision::dist_capsule_to_capsule(c[0], c[1], c[2], c[3], bad, 0.2, d, a, b),
                saras_collision::kInvalidInput)
          << bad;
      EXPECT_TRUE(allNaN(d, a, b));
      EXPECT_EQ(saras_collision::dist_capsule_to_capsule(c[0], c[1], c[2], c[3], 0.1, bad, d, a, b),
                saras_collision::kInvalidInput)
          << bad;
      EXPECT_EQ(saras_collision::capsuleCapsule(c[0], c[1], bad, c[2], c[3], 0.2).code,
                saras_collision::kInvalidInput);
    }
  }
  EXPECT_EQ(checked, 6 * 12 * 3);
}

TEST(Box, FastValidationRejectsEveryBadVertexWithItsCode)
{
  Random rnd;
  rnd.gen.seed(4242);
  const OrientedBox box = rnd.box();
  Vector3d v[8];
  saras_collision::boxVertices(box, v);
  const double diag = 2.0 * box.half.norm();
  const Vector3d s = box.center + Vector3d(0.05, 0.01, -0.02), s2 = s + Vector3d(0.0, 0.03, 0.01);
  double d;
  Vector3d a, b;
  auto sphere = [&](const Vector3d w[8]) { return saras_collision::dist_sphere_to_parallelepiped(s, w, 0.001, d, a, b); };
  auto capsule = [&](const Vector3d w[8]) {
    return saras_collision::dist_capsule_to_parallelepiped(s, s2, w, 0.001, d, a, b);
  };
  ASSERT_EQ(sphere(v), saras_collision::kSeparated);
  ASSERT_EQ(capsule(v), saras_collision::kSeparated);
  int checked = 0;
  for (int i = 0; i < 8; ++i)
  {
    for (int j = 0; j < 3; ++j)
    {
      Vector3d w[8];
      for (double bad : { kNaN, kInf, -kInf })
      {
        std::copy(v, v + 8, w);
        w[i][j] = bad;
        EXPECT_EQ(sphere(w), saras_collision::kInvalidInput) << "vertex " << i << " coordinate " << j << " " << bad;
        EXPECT_TRUE(allNaN(d, a, b));
        EXPECT_EQ(capsule(w), saras_collision::kInvalidInput) << i << " " << j << " " << bad;
        EXPECT_TRUE(allNaN(d, a, b));
        OrientedBox out;
        EXPECT_EQ(saras_collision::makeBox(w, 1e-6, out), saras_collision::kInvalidInput) << i << " " << j;
      }
      // Outside the tolerance (1e-6 of the diagonal): not a box.
      std::copy(v, v + 8, w);
      w[i][j] += 2e-6 * diag;
      EXPECT_EQ(sphere(w), saras_collision::kInvalidBox) << "vertex " << i << " coordinate " << j;
      EXPECT_TRUE(allNaN(d, a, b));
      EXPECT_EQ(capsule(w), saras_collision::kInvalidBox) << i << " " << j;
      // Within it: accepted (relative to the shortest edge: moving v0, v1, v3 or v4 also
      // turns edges, and the angle tolerance is relative to the edge lengths).
      std::copy(v, v + 8, w);
      w[i][j] += 0.3e-6 * 2.0 * box.half.minCoeff();
      EXPECT_EQ(sphere(w), saras_collision::kSeparated) << "vertex " << i << " coordinate " << j;
      EXPECT_EQ(capsule(w), saras_collision::kSeparated) << i << " " << j;
      ++checked;
    }
  }
  EXPECT_EQ(checked, 24);
  // Every exchange of two vertices breaks the documented order.
  for (int i = 0; i < 8; ++i)
  {
    for (int j = i + 1; j < 8; ++j)
    {
      Vector3d w[8];
      std::copy(v, v + 8, w);
      std::swap(w[i], w[j]);
      EXPECT_EQ(sphere(w), saras_collision::kInvalidBox) << i << " <-> " << j;
      EXPECT_EQ(capsule(w), saras_collision::kInvalidBox) << i << " <-> " << j;
    }
  }
  // Degenerate boxes: a point, a segment, a flat rectangle.
  Vector3d point[8], segment[8], flat[8];
  aabbVertices(Vector3d(1, 1, 1), Vector3d(1, 1, 1), point);
  aabbVertices(Vector3d(0, 0, 0), Vector3d(1, 0, 0), segment);
  aabbVertices(Vector3d(0, 0, 0), Vector3d(1, 1, 0), flat);
  for (const Vector3d* w : { point, segment, flat })
  {
    EXPECT_EQ(sphere(w), saras_collision::kInvalidBox);
    EXPECT_EQ(capsule(w), saras_collision::kInvalidBox);
  }
  // Non-rectangular: y edge sheared by 2e-6 rad is rejected, by 0.3e-6 rad accepted.
  for (double angle : { 2e-6, 0.3e-6 })
  {
    Vector3d w[8];
    std::copy(v, v + 8, w);
    const Vector3d shift = (v[1] - v[0]) * (angle * (v[4] - v[0]).norm() / (v[1] - v[0]).norm());
    for (int i : { 4, 5, 6, 7 })
      w[i] += shift;
    const int expected = angle > 1e-6 ? saras_collision::kInvalidBox : saras_collision::kSeparated;
    EXPECT_EQ(sphere(w), expected) << angle;
    EXPECT_EQ(capsule(w), expected) << angle;
  }
  // Huge but finite coordinates overflow the squares: an invalid box, not a crash or a number.
  Vector3d huge[8];
  aabbVertices(Vector3d(0, 0, 0), Vector3d(1e200, 1e200, 1e200), huge);
  EXPECT_EQ(sphere(huge), saras_collision::kInvalidBox);
  EXPECT_TRUE(allNaN(d, a, b));
  // Non-finite sphere / capsule inputs.
  for (double bad : { kNaN, kInf, -kInf })
  {
    for (int j = 0; j < 3; ++j)
    {
      Vector3d t = s;
      t[j] = bad;
      EXPECT_EQ(saras_collision::dist_sphere_to_parallelepiped(t, v, 0.001, d, a, b), saras_collision::kInvalidInput);
      EXPECT_TRUE(allNaN(d, a, b));
      EXPECT_EQ(saras_collision::dist_capsule_to_parallelepiped(s, t, v, 0.001, d, a, b),
                saras_collision::kInvalidInput);
      EXPECT_EQ(saras_collision::dist_capsule_to_parallelepiped(t, s, v, 0.001, d, a, b),
                saras_collision::kInvalidInput);
    }
    EXPECT_EQ(saras_collision::dist_sphere_to_parallelepiped(s, v, bad, d, a, b), saras_collision::kInvalidInput);
    EXPECT_EQ(saras_collision::dist_capsule_to_parallelepiped(s, s2, v, bad, d, a, b), saras_collision::kInvalidInput);
  }
  EXPECT_EQ(saras_collision::dist_sphere_to_parallelepiped(s, v, -1e-12, d, a, b), saras_collision::kInvalidInput);
  // A finite centre so far away that the squared distance overflows: an error code, never an
  // infinite (overstated) distance; just below, the exact distance.
  EXPECT_EQ(saras_collision::dist_sphere_to_parallelepiped(Vector3d(1e160, 0, 0), v, 0.001, d, a, b),
            saras_collision::kInvalidInput);
  EXPECT_TRUE(allNaN(d, a, b));
  const Vector3d far(1e150, 0, 0);
  EXPECT_EQ(saras_collision::dist_sphere_to_parallelepiped(far, v, 0.001, d, a, b), saras_collision::kSeparated);
  EXPECT_NEAR(d / 1e150, 1.0, 1e-12);
}

// Each box condition just below / just above its threshold (relative 1e-3 either side), for
// the sphere centre outside the box (common path) and inside it (out-of-line path), the capsule
// and makeBox: the same verdict everywhere.
//  - vertex residual: v6 moved by (1 -+ 1e-3) rt diag (only the residual v6 - v5 - z changes);
//  - rectangularity: the y edges sheared by an angle (1 -+ 1e-3) rt (cosine sum = sin^2);
//  - flatness: the z edge (1 +- 1e-3) rt |(x, y)| long (|z|^2 > rt^2 diag^2).
TEST(Box, EveryConditionJustInsideAndJustOutsideItsTolerance)
{
  const double rt = saras_collision::kBoxRelativeTolerance;
  const double lx = 0.03, ly = 0.05, lz = 0.02;
  Vector3d v[8];
  aabbVertices(Vector3d(0, 0, 0), Vector3d(lx, ly, lz), v);
  const Eigen::Matrix3d rot = Eigen::AngleAxisd(0.7, Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  const Vector3d shift(0.1, -0.2, 0.05);
  auto place = [&](Vector3d w[8]) {
    for (int i = 0; i < 8; ++i)
      w[i] = rot * w[i] + shift;
  };
  const Vector3d outside = rot * Vector3d(0.05, 0.02, 0.01) + shift;
  int checked = 0;
  for (double side : { -1.0, 1.0 })  // -1: just inside the tolerance, +1: just outside
  {
    const double f = 1.0 + side * 1e-3;
    Vector3d residual[8], shear[8], flat[8];
    std::copy(v, v + 8, residual);
    residual[6] += Vector3d(0.3, -0.5, 0.8).normalized() * (f * rt * std::sqrt(lx * lx + ly * ly + lz * lz));
    std::copy(v, v + 8, shear);
    const double angle = std::asin(f * rt);
    for (int i : { 4, 5, 6, 7 })  // y edges turned towards x by the angle, same length
      shear[i] += Vector3d(ly * std::sin(angle), ly * (std::cos(angle) - 1.0), 0.0);
    // z edge length l with l^2 = rt^2 (lx^2 + ly^2 + l^2) at f = 1.
    const double lz_min = rt * std::sqrt((lx * lx + ly * ly) / (1.0 - rt * rt)) / f;
    aabbVertices(Vector3d(0, 0, 0), Vector3d(lx, ly, lz_min), flat);
    for (Vector3d* w : { residual, shear, flat })
    {
      place(w);
      const int expected = side < 0 ? saras_collision::kSeparated : saras_collision::kInvalidBox;
      Vector3d inside = Vector3d::Zero();  // the centroid
      for (int i = 0; i < 8; ++i)
        inside += w[i] / 8.0;
      OrientedBox box;
      EXPECT_EQ(saras_collision::makeBox(w, rt, box), expected) << checked;
      double d;
      Vector3d a, b;
      const int out_code = saras_collision::dist_sphere_to_parallelepiped(outside, w, 0.001, d, a, b);
      EXPECT_EQ(out_code, expected == saras_collision::kSeparated ? saras_collision::kSeparated : expected) << checked;
      EXPECT_EQ(std::isnan(d), expected != saras_collision::kSeparated) << checked;
      const int in_code = saras_collision::dist_sphere_to_parallelepiped(inside, w, 0.001, d, a, b);
      EXPECT_EQ(in_code, expected == saras_collision::kSeparated ? saras_collision::kIntersecting : expected)
          << checked;
      EXPECT_EQ(std::isnan(d), expected != saras_collision::kSeparated) << checked;
      EXPECT_EQ(saras_collision::dist_capsule_to_parallelepiped(outside, inside, w, 0.001, d, a, b),
                expected == saras_collision::kSeparated ? saras_collision::kIntersecting : expected)
          << checked;
      ++checked;
    }
  }
  EXPECT_EQ(checked, 6);
}

// The vertex-frame sphere-box hands the centre inside / on the box and every invalid input to
// an out-of-line path: both sides of that switch (centre 1e-90 .. 1e-110 m outside a face,
// on it, 1e-12 m inside) and invalid inputs with the centre inside give the same results as
// the prebuilt-box path and the same error codes as with the centre outside.
TEST(SphereBox, CommonAndOutOfLinePathsAgreeAtTheSwitch)
{
  Random rnd;
  rnd.gen.seed(777);
  for (int k = 0; k < 50; ++k)
  {
    const OrientedBox box = rnd.box();
    Vector3d v[8];
    saras_collision::boxVertices(box, v);
    const int face = k % 3;
    const double sign = k % 2 == 0 ? 1.0 : -1.0;
    for (double delta : { 1e-90, 1e-99, 1e-100, 1e-101, 1e-110, 0.0, -1e-12 })
    {
      Vector3d local(rnd.uniform(-0.5, 0.5) * box.half.x(), rnd.uniform(-0.5, 0.5) * box.half.y(),
                     rnd.uniform(-0.5, 0.5) * box.half.z());
      local[face] = sign * (box.half[face] + delta);
      const Vector3d s = box.center + box.axes * local;
      const double r = 0.002;
      double d;
      Vector3d a, b;
      const int code = saras_collision::dist_sphere_to_parallelepiped(s, v, r, d, a, b);
      const saras_collision::DistanceResult ref = saras_collision::capsuleBox(s, s, r, box);
      ASSERT_EQ(code, ref.code) << k << " delta " << delta;
      ASSERT_NEAR(d, ref.distance, 1e-15) << k << " delta " << delta;
      ASSERT_NEAR(d, pointBoxSigned(s, box) - r, 1e-15) << k << " delta " << delta;
      ASSERT_NEAR((a - ref.point1).norm(), 0.0, 1e-15) << k << " delta " << delta;
      ASSERT_NEAR((b - ref.point2).norm(), 0.0, 1e-15) << k << " delta " << delta;
      ASSERT_EQ(code, saras_collision::kIntersecting) << k;  // r = 2 mm: always overlapping
    }
    // Invalid inputs with the centre inside: the same codes as outside, NaN outputs.
    const Vector3d s_in = box.center;
    double d;
    Vector3d a, b;
    Vector3d w[8];
    std::copy(v, v + 8, w);
    w[5][1] += 1e-4;
    EXPECT_EQ(saras_collision::dist_sphere_to_parallelepiped(s_in, w, 0.001, d, a, b), saras_collision::kInvalidBox);
    EXPECT_TRUE(allNaN(d, a, b));
    w[5][1] = kNaN;
    EXPECT_EQ(saras_collision::dist_sphere_to_parallelepiped(s_in, w, 0.001, d, a, b), saras_collision::kInvalidInput);
    EXPECT_TRUE(allNaN(d, a, b));
    EXPECT_EQ(saras_collision::dist_sphere_to_parallelepiped(s_in, v, -0.001, d, a, b), saras_collision::kInvalidInput);
    EXPECT_TRUE(allNaN(d, a, b));
    EXPECT_EQ(saras_collision::dist_sphere_to_parallelepiped(s_in, v, kInf, d, a, b), saras_collision::kInvalidInput);
    EXPECT_TRUE(allNaN(d, a, b));
    EXPECT_EQ(saras_collision::dist_sphere_to_parallelepiped(s_in, nullptr, 0.001, d, a, b),
              saras_collision::kInvalidInput);
  }
}

TEST(SphereBox, VertexFramePathEqualsPrebuiltBoxPath)
{
  // dist_sphere_to_parallelepiped works in the vertex frame (no orthonormal frame);
  // capsuleBox(p, p) on makeBox() uses the orthonormal one: same codes, distances and points.
  Random rnd;
  rnd.gen.seed(99);
  int inside = 0;
  for (int k = 0; k < 5000; ++k)
  {
    const OrientedBox box = rnd.box();
    Vector3d v[8];
    saras_collision::boxVertices(box, v);
    const Vector3d p = k % 5 == 0 ? Vector3d(box.center + box.axes * box.half.cwiseProduct(rnd.point(1.0))) :
                                    rnd.point(0.08);
    const double r = k % 7 == 0 ? 0.0 : rnd.uniform(0.0, 0.01);
    double d;
    Vector3d a, b;
    const int code = saras_collision::dist_sphere_to_parallelepiped(p, v, r, d, a, b);
    OrientedBox built;
    ASSERT_EQ(saras_collision::makeBox(v, 1e-6, built), saras_collision::kSeparated);
    const saras_collision::DistanceResult ref = saras_collision::capsuleBox(p, p, r, built);
    ASSERT_EQ(code, ref.code) << k;
    ASSERT_NEAR(d, ref.distance, 1e-15) << k;
    ASSERT_NEAR((a - ref.point1).norm(), 0.0, 1e-15) << k;
    ASSERT_NEAR((b - ref.point2).norm(), 0.0, 1e-15) << k;
    ASSERT_NEAR(d, pointBoxSigned(p, box) - r, 1e-15) << k;
    inside += pointBoxSigned(p, box) < 0.0;
  }
  EXPECT_GT(inside, 500);
}

int main(int argc, char** argv)
{
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
