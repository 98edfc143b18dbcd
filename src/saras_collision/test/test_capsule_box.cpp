// Sphere-box and capsule-box gtests: closed forms, FCL issue regressions, the inside / outside
// switch and >= 10000 random configurations against FCL (libfcl-dev 0.7) and the exact references.
#include "geometry_test_support.h"

#include <cstdio>

using geometry_test::Vector3d;
using saras_collision::OrientedBox;
using namespace geometry_test;  // NOLINT(build/namespaces): this test's own helpers

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

// The vertex-frame sphere-box switches from the closest-point projection (centre outside) to
// the nearest-face depth (centre inside or on the box): both sides of that switch (centre
// 1e-90 .. 1e-110 m outside a face, on it, 1e-12 m inside) and invalid inputs with the centre
// inside give the same results as the prebuilt-box path and the same error codes as with the
// centre outside.
TEST(SphereBox, InsideAndOutsideAgreeAtTheSwitch)
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

