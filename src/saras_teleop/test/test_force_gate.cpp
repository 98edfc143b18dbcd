// Core tests of the contact-force plausibility gate (no ROS).
#include <cmath>
#include <limits>

#include <gtest/gtest.h>

#include "saras_teleop/force_gate.h"

using saras_teleop::ForceGate;
using saras_teleop::ForceGateParams;

TEST(ForceGate, HugeForceHoldsAndIsNeverUsed)
{
  ForceGate g{ ForceGateParams() };
  EXPECT_EQ(g.offer(Eigen::Vector3d(1.0, 0.0, 0.0), 0.0), ForceGate::Verdict::ACCEPTED);
  EXPECT_FALSE(g.holding(0.0));
  // a spoofed 1e6 N stream at 60 Hz for 4 s: every sample rejected, the port holds throughout
  for (int k = 1; k <= 240; ++k)
  {
    const double t = k / 60.0;
    EXPECT_EQ(g.offer(Eigen::Vector3d(0.0, 0.0, 1e6), t), ForceGate::Verdict::MAGNITUDE);
    EXPECT_TRUE(g.holding(t + 0.01));
    EXPECT_EQ(g.force(t + 0.01), Eigen::Vector3d::Zero());
  }
  EXPECT_EQ(g.violations(), 240u);
  EXPECT_NE(g.lastViolation().find("max"), std::string::npos);
  // hold ends hold_time after the last violation
  EXPECT_TRUE(g.holding(4.0 + 0.45));
  EXPECT_FALSE(g.holding(4.0 + 0.55));
}

TEST(ForceGate, NonFiniteIsAViolation)
{
  ForceGate g{ ForceGateParams() };
  EXPECT_EQ(g.offer(Eigen::Vector3d(std::nan(""), 0.0, 0.0), 0.0), ForceGate::Verdict::MAGNITUDE);
  EXPECT_EQ(g.offer(Eigen::Vector3d(std::numeric_limits<double>::infinity(), 0.0, 0.0), 0.0),
            ForceGate::Verdict::MAGNITUDE);
  EXPECT_TRUE(g.holding(0.1));
}

TEST(ForceGate, RateLimitCostsOneHoldThenRebases)
{
  ForceGateParams p;
  p.max_step = 5.0;
  p.max_rate = 100.0;
  p.hold_time = 0.2;
  ForceGate g(p);
  EXPECT_EQ(g.offer(Eigen::Vector3d::Zero(), 0.0), ForceGate::Verdict::ACCEPTED);
  // 20 N in 1/60 s: > 5 + 100/60 N
  EXPECT_EQ(g.offer(Eigen::Vector3d(20.0, 0.0, 0.0), 1.0 / 60), ForceGate::Verdict::RATE);
  EXPECT_TRUE(g.holding(0.1));
  // the same (plausible magnitude) value again: accepted, but the hold lasts until 1/60 + 0.2 s
  EXPECT_EQ(g.offer(Eigen::Vector3d(20.0, 0.0, 0.0), 2.0 / 60), ForceGate::Verdict::ACCEPTED);
  EXPECT_EQ(g.force(0.1), Eigen::Vector3d::Zero());
  EXPECT_EQ(g.offer(Eigen::Vector3d(20.5, 0.0, 0.0), 0.25), ForceGate::Verdict::ACCEPTED);
  EXPECT_FALSE(g.holding(0.25));
  EXPECT_NEAR(g.force(0.25).x(), 20.5, 1e-12);
  // smooth ramps within the rate are accepted
  for (int k = 1; k <= 60; ++k)
    EXPECT_EQ(g.offer(Eigen::Vector3d(20.5 - 0.1 * k, 0.0, 0.0), 0.25 + k / 60.0), ForceGate::Verdict::ACCEPTED);
}

TEST(ForceGate, StaleForceIsZero)
{
  ForceGateParams p;
  p.timeout = 0.1;
  ForceGate g(p);
  EXPECT_TRUE(g.stale(0.0));
  g.offer(Eigen::Vector3d(3.0, 0.0, 0.0), 1.0);
  EXPECT_FALSE(g.stale(1.05));
  EXPECT_NEAR(g.force(1.05).x(), 3.0, 1e-12);
  EXPECT_TRUE(g.stale(1.2));
  EXPECT_EQ(g.force(1.2), Eigen::Vector3d::Zero());
}

TEST(ForceGate, InvalidParametersThrowNamingThem)
{
  ForceGateParams p;
  p.max_force = -1.0;
  try
  {
    ForceGate g(p);
    FAIL();
  }
  catch (const std::invalid_argument& e)
  {
    EXPECT_NE(std::string(e.what()).find("max_contact_force"), std::string::npos);
  }
}
