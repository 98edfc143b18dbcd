// Capsule-capsule gtests: closed forms, every clamping region, scale invariance, invalid inputs and
// >= 10000 random configurations against FCL (libfcl-dev 0.7) and the exact reference.
#include "geometry_test_support.h"

#include <cstdio>

using geometry_test::Vector3d;
using saras_collision::OrientedBox;
using namespace geometry_test;  // NOLINT(build/namespaces): this test's own helpers

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

// The witness points switch (axis points when intersecting, surface points otherwise) and its code at distance -1e-9 / +1e-9 exactly: crossing perpendicular axes
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

// A radius of -0 is a radius of 0 (r >= 0 holds), not an invalid input: the same answer as +0, on
// both entry points.
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

// The denominator |d1 x d2|^2 is a e - b^2 for axes more than ~1.8 degrees from parallel
// (sin^2 > 1e-3) and the cross product below (where a e - b^2 cancels): both sides of that
// switch, in every clamping region of both parameters, must be exact and never overstated.
TEST(CapsuleCapsule, ExactOnBothSidesOfTheCancellationAngle)
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

// Every clamping region (t interior / clamped to 0 / to 1, s interior
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

// Inputs beyond 2^200 m are rescaled by a power of two (products ~ length^4 would overflow): the
// result is the same, scaled, from 1e-12 to 1e300, and a distance that is not representable is
// kInvalidInput, never a wrong number.
TEST(CapsuleCapsule, ScaleInvariantFromPicometresTo1e300)
{
  Random rnd;
  int checked = 0;
  for (int k = 0; k < 300; ++k)
  {
    Vector3d p1, p2, p3, p4;
    rnd.segment(p1, p2, 0.04);
    rnd.segment(p3, p4, 0.04);
    if (k % 10 == 0)  // parallel pairs
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

// Longer capsules (up to 2.4 m) scaled by 2^105 .. 2^135: the same answer, scaled (scaling by a
// power of two is exact), for both entry points.
TEST(CapsuleCapsule, SameAnswerScaledByLargePowersOfTwo)
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
    for (int e = 105; e <= 135; ++e)
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
