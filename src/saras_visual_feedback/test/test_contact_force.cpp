// Contact force model: F = depth * K_skin * direction / |direction|, staleness and bad input.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "saras_visual_feedback/contact_force.h"

using saras_visual_feedback::ContactForceModel;
using saras_visual_feedback::ContactForceParams;
using saras_visual_feedback::ContactRejection;
using saras_visual_feedback::Vec3;

namespace
{
ContactForceParams params(double k = 500.0, double stale = 0.2, double max_force = 0.0)
{
  ContactForceParams p;
  p.k_skin = k;
  p.stale_timeout = stale;
  p.max_force = max_force;
  return p;
}
}  // namespace

TEST(ContactForce, ElasticForceAlongTheUnitDirection)
{
  ContactForceModel m(params(500.0));
  // depth 1 cm, K 500 N/m -> 5 N along (3, 0, 4) / 5.
  ASSERT_EQ(m.update(0.01, Vec3{3.0, 0.0, 4.0}, 10.0), ContactRejection::kNone);
  Vec3 f = m.force(10.05);
  EXPECT_NEAR(f.x, 3.0, 1e-12);
  EXPECT_NEAR(f.y, 0.0, 1e-12);
  EXPECT_NEAR(f.z, 4.0, 1e-12);
  // The direction's length does not matter.
  ASSERT_EQ(m.update(0.002, Vec3{0.0, -1e-3, 0.0}, 10.1), ContactRejection::kNone);
  f = m.force(10.1);
  EXPECT_NEAR(f.x, 0.0, 1e-12);
  EXPECT_NEAR(f.y, -1.0, 1e-12);
  EXPECT_NEAR(f.z, 0.0, 1e-12);
  // Zero depth: zero force (touching, no penetration).
  ASSERT_EQ(m.update(0.0, Vec3{1.0, 1.0, 1.0}, 10.2), ContactRejection::kNone);
  f = m.force(10.2);
  EXPECT_EQ(f.x, 0.0);
  EXPECT_EQ(m.accepted(), 3u);
  EXPECT_EQ(m.rejected(), 0u);
}

TEST(ContactForce, ArbitraryDirectionMatchesHandComputation)
{
  ContactForceModel m(params(320.0));
  const Vec3 d{-0.2, 0.7, 1.3};
  const double depth = 0.0042;
  ASSERT_EQ(m.update(depth, d, 0.0), ContactRejection::kNone);
  const double n = std::sqrt(0.04 + 0.49 + 1.69);
  const Vec3 f = m.force(0.0);
  EXPECT_NEAR(f.x, depth * 320.0 * -0.2 / n, 1e-12);
  EXPECT_NEAR(f.y, depth * 320.0 * 0.7 / n, 1e-12);
  EXPECT_NEAR(f.z, depth * 320.0 * 1.3 / n, 1e-12);
  EXPECT_NEAR(std::sqrt(f.x * f.x + f.y * f.y + f.z * f.z), depth * 320.0, 1e-12);
}

TEST(ContactForce, ZeroWhenAbsentOrStale)
{
  ContactForceModel m(params(500.0, 0.2));
  Vec3 f = m.force(1.0);  // never received
  EXPECT_EQ(f.x, 0.0);
  EXPECT_EQ(f.y, 0.0);
  EXPECT_EQ(f.z, 0.0);
  EXPECT_FALSE(m.fresh(1.0));
  EXPECT_TRUE(std::isinf(m.age(1.0)));
  ASSERT_EQ(m.update(0.01, Vec3{0.0, 0.0, 1.0}, 2.0), ContactRejection::kNone);
  EXPECT_NEAR(m.force(2.1999).z, 5.0, 1e-12);  // just inside the timeout: still fresh
  EXPECT_EQ(m.force(2.2001).z, 0.0);        // stale
  EXPECT_NEAR(m.age(2.5), 0.5, 1e-12);
}

TEST(ContactForce, BadInputIsRejectedCountedAndDoesNotChangeTheForce)
{
  ContactForceModel m(params(500.0, 0.2));
  ASSERT_EQ(m.update(0.01, Vec3{1.0, 0.0, 0.0}, 0.0), ContactRejection::kNone);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  EXPECT_EQ(m.update(0.01, Vec3{0.0, 0.0, 0.0}, 0.01), ContactRejection::kZeroDirection);
  EXPECT_EQ(m.update(0.01, Vec3{1e-12, 0.0, 0.0}, 0.01), ContactRejection::kZeroDirection);
  EXPECT_EQ(m.update(nan, Vec3{1.0, 0.0, 0.0}, 0.02), ContactRejection::kNonFinite);
  EXPECT_EQ(m.update(0.01, Vec3{nan, 0.0, 0.0}, 0.03), ContactRejection::kNonFinite);
  EXPECT_EQ(m.update(0.01, Vec3{0.0, inf, 0.0}, 0.04), ContactRejection::kNonFinite);
  EXPECT_EQ(m.update(inf, Vec3{0.0, 1.0, 0.0}, 0.05), ContactRejection::kNonFinite);
  EXPECT_EQ(m.update(-0.001, Vec3{0.0, 1.0, 0.0}, 0.06), ContactRejection::kNegativeDepth);
  EXPECT_EQ(m.rejected(), 7u);
  EXPECT_EQ(m.accepted(), 1u);
  // The last valid contact still rules, until it goes stale (the rejected ones do not refresh it).
  const Vec3 f = m.force(0.1);
  EXPECT_NEAR(f.x, 5.0, 1e-12);
  EXPECT_TRUE(std::isfinite(f.y) && f.y == 0.0);
  EXPECT_EQ(m.force(0.21).x, 0.0);
}

TEST(ContactForce, SaturatesTheMagnitudeKeepingTheDirection)
{
  ContactForceModel m(params(1000.0, 0.2, 10.0));
  ASSERT_EQ(m.update(0.05, Vec3{0.0, 3.0, 4.0}, 0.0), ContactRejection::kNone);  // 50 N requested
  const Vec3 f = m.force(0.0);
  EXPECT_NEAR(f.y, 6.0, 1e-12);
  EXPECT_NEAR(f.z, 8.0, 1e-12);
  ASSERT_EQ(m.update(0.005, Vec3{0.0, 3.0, 4.0}, 0.0), ContactRejection::kNone);  // 5 N: untouched
  EXPECT_NEAR(m.force(0.0).z, 4.0, 1e-12);
}

TEST(ContactForce, ValidatesParameters)
{
  std::string why;
  EXPECT_TRUE(saras_visual_feedback::validateContactForceParams(params(), &why));
  EXPECT_FALSE(saras_visual_feedback::validateContactForceParams(params(0.0), &why));
  EXPECT_EQ(why.rfind("k_skin", 0), 0u) << why;
  EXPECT_FALSE(saras_visual_feedback::validateContactForceParams(params(-1.0), &why));
  EXPECT_FALSE(saras_visual_feedback::validateContactForceParams(params(500.0, 0.0), &why));
  EXPECT_EQ(why.rfind("stale_timeout", 0), 0u) << why;
  EXPECT_FALSE(saras_visual_feedback::validateContactForceParams(params(500.0, 0.2, -1.0), &why));
  EXPECT_EQ(why.rfind("max_force", 0), 0u) << why;
  EXPECT_FALSE(saras_visual_feedback::validateContactForceParams(
      params(std::numeric_limits<double>::quiet_NaN()), &why));
}

int main(int argc, char** argv)
{
  ::testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
