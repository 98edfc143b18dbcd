// Box gtests: validation of the 8 vertices (order, rectangularity, flatness, tolerances) and the
// error codes of every bad vertex, on makeBox() and both deliverable box signatures.
#include "geometry_test_support.h"

#include <cstdio>

using geometry_test::Vector3d;
using saras_collision::OrientedBox;
using namespace geometry_test;  // NOLINT(build/namespaces): this test's own helpers

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

namespace
{
/// A random valid box, a sphere centre and a capsule axis outside it, and both deliverable box
/// signatures on given vertices (their outputs in d, a, b).
class BadBox : public ::testing::Test
{
protected:
  void SetUp() override
  {
    Random rnd;
    rnd.gen.seed(4242);
    box = rnd.box();
    saras_collision::boxVertices(box, v);
    diag = 2.0 * box.half.norm();
    s = box.center + Vector3d(0.05, 0.01, -0.02);
    s2 = s + Vector3d(0.0, 0.03, 0.01);
    ASSERT_EQ(sphere(v), saras_collision::kSeparated);
    ASSERT_EQ(capsule(v), saras_collision::kSeparated);
  }
  int sphere(const Vector3d w[8])
  {
    return saras_collision::dist_sphere_to_parallelepiped(s, w, 0.001, d, a, b);
  }
  int capsule(const Vector3d w[8])
  {
    return saras_collision::dist_capsule_to_parallelepiped(s, s2, w, 0.001, d, a, b);
  }

  OrientedBox box;
  Vector3d v[8];
  double diag = 0.0;
  Vector3d s, s2;
  double d = 0.0;
  Vector3d a, b;
};
}  // namespace

TEST_F(BadBox, EveryNonFiniteOrMovedVertexGetsItsCode)
{
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
}

TEST_F(BadBox, WrongOrderDegenerateShearedOrOverflowingBoxIsInvalid)
{
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
}

TEST_F(BadBox, NonFiniteOrFarSphereAndCapsuleInputsAreInvalid)
{
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
// the sphere centre outside the box and inside it, the capsule
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
