// Core tests of the velocity integrator and the delay/loss channel (no ROS).
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

#include <gtest/gtest.h>

#include "saras_teleop/delay_channel.h"
#include "saras_teleop/velocity_integrator.h"

using saras_teleop::ChannelParams;
using saras_teleop::DelayChannel;
using saras_teleop::IntegratorParams;
using saras_teleop::LossModel;
using saras_teleop::VelocityIntegrator;
using saras_teleop::Vector6d;

TEST(VelocityIntegrator, IntegratesTwistExactly)
{
  IntegratorParams p;
  VelocityIntegrator vi(p);
  Vector6d v;
  v << 0.01, -0.02, 0.005, 0.0, 0.0, 0.0;
  vi.step(v, 0.001, false);  // not started: ignored
  ASSERT_TRUE(vi.start(KDL::Frame(KDL::Vector(0.1, 0.2, 0.3))));
  for (int k = 0; k < 1000; ++k)
    vi.step(v, 0.001, false);
  EXPECT_NEAR(vi.pose().p.x(), 0.11, 1e-12);
  EXPECT_NEAR(vi.pose().p.y(), 0.18, 1e-12);
  EXPECT_NEAR(vi.pose().p.z(), 0.305, 1e-12);
  // constant angular velocity about z: after 1 s, rotation of 0.5 rad
  Vector6d w = Vector6d::Zero();
  w[5] = 0.5;
  for (int k = 0; k < 1000; ++k)
    vi.step(w, 0.001, false);
  double r, pch, y;
  vi.pose().M.GetRPY(r, pch, y);
  EXPECT_NEAR(y, 0.5, 1e-9);
  // hold: no motion
  const KDL::Frame before = vi.pose();
  vi.step(v, 0.001, true);
  EXPECT_TRUE(KDL::Equal(before, vi.pose(), 1e-15));
}

TEST(VelocityIntegrator, LimitsVelocityAndWorkspace)
{
  IntegratorParams p;
  p.max_linear_velocity = 0.05;
  p.workspace_min = Eigen::Vector3d(-0.1, -0.1, -0.1);
  p.workspace_max = Eigen::Vector3d(0.1, 0.1, 0.1);
  VelocityIntegrator vi(p);
  vi.start(KDL::Frame::Identity());
  Vector6d v = Vector6d::Zero();
  v[0] = 3.0;
  v[1] = 4.0;  // |v| = 5 m/s -> limited to 0.05 along (0.6, 0.8)
  vi.step(v, 0.01, false);
  EXPECT_NEAR(vi.pose().p.x(), 0.0003, 1e-12);
  EXPECT_NEAR(vi.pose().p.y(), 0.0004, 1e-12);
  for (int k = 0; k < 1000; ++k)
    vi.step(v, 0.01, false);
  EXPECT_NEAR(vi.pose().p.x(), 0.1, 1e-12);
  EXPECT_NEAR(vi.pose().p.y(), 0.1, 1e-12);
  EXPECT_GT(vi.clampedSteps(), 0u);
  // bad inputs never move the set-point
  const KDL::Frame before = vi.pose();
  vi.step(Vector6d::Constant(std::nan("")), 0.001, false);
  vi.step(-v, std::nan(""), false);
  vi.step(-v, 5.0, false);  // a 5 s gap is not integrated
  EXPECT_TRUE(KDL::Equal(before, vi.pose(), 1e-15));
  EXPECT_EQ(vi.rejected(), 1u);
  EXPECT_FALSE(vi.start(KDL::Frame(KDL::Vector(std::nan(""), 0, 0))));
}

TEST(DelayChannel, ConstantDelayAndOrder)
{
  ChannelParams p;
  p.delay = 0.05;
  DelayChannel<int> ch(p);
  std::vector<std::pair<double, int>> out;
  for (int k = 0; k < 200; ++k)
  {
    const double t = k * 0.001;
    ch.push(k, t);
    ch.deliver(t, [&](int v) { out.emplace_back(t, v); });
  }
  ASSERT_EQ(out.size(), 150u);
  for (std::size_t i = 0; i < out.size(); ++i)
  {
    EXPECT_EQ(out[i].second, static_cast<int>(i));
    EXPECT_NEAR(out[i].first - out[i].second * 0.001, 0.05, 1e-9);
  }
}

TEST(DelayChannel, JitterKeepsOrderAndBounds)
{
  ChannelParams p;
  p.delay = 0.01;
  p.jitter = 0.02;
  DelayChannel<int> ch(p);
  int last = -1;
  double max_lat = 0.0, min_lat = 1.0;
  for (int k = 0; k < 5000; ++k)
  {
    const double t = k * 0.001;
    ch.push(k, t);
    ch.deliver(t, [&](int v) {
      EXPECT_GT(v, last);
      last = v;
      max_lat = std::max(max_lat, t - v * 0.001);
      min_lat = std::min(min_lat, t - v * 0.001);
    });
  }
  EXPECT_GE(min_lat, 0.01 - 1e-9);
  EXPECT_LE(max_lat, 0.031 + 1e-9);
  EXPECT_GT(max_lat - min_lat, 0.015);
}

TEST(DelayChannel, RandomAndBurstyLossRates)
{
  ChannelParams p;
  p.loss = 0.1;
  LossModel bern(p);
  int n = 200000, d = 0, runs = 0;
  bool prev = false;
  for (int i = 0; i < n; ++i)
  {
    const bool x = bern.drop();
    d += x;
    runs += (x && !prev);
    prev = x;
  }
  EXPECT_NEAR(static_cast<double>(d) / n, 0.1, 0.005);
  EXPECT_NEAR(static_cast<double>(d) / runs, 1.0 / 0.9, 0.05);  // geometric runs, mean 1/(1-p)
  p.burst_length = 20.0;
  p.seed = 7;
  LossModel burst(p);
  d = 0;
  runs = 0;
  prev = false;
  for (int i = 0; i < n; ++i)
  {
    const bool x = burst.drop();
    d += x;
    runs += (x && !prev);
    prev = x;
  }
  EXPECT_NEAR(static_cast<double>(d) / n, 0.1, 0.02);
  EXPECT_NEAR(static_cast<double>(d) / runs, 20.0, 3.0);
  ChannelParams bad;
  bad.loss = 1.0;
  EXPECT_THROW(bad.validate(), std::invalid_argument);
}

namespace
{
Vector6d linear(double x, double y, double z)
{
  Vector6d v = Vector6d::Zero();
  v << x, y, z, 0.0, 0.0, 0.0;
  return v;
}
}  // namespace

TEST(VelocityIntegratorResync, LeadLimitedThenFaultWhenTheArmStops)
{
  IntegratorParams p;
  p.max_lead = 0.003;
  p.max_stall = 0.5;  // (default 1 s)
  VelocityIntegrator vi(p);
  const KDL::Frame arm(KDL::Vector(0.1, 0.0, 0.0));
  ASSERT_TRUE(vi.start(arm));
  ASSERT_TRUE(vi.setMeasured(arm));  // the arm never moves
  double worst = 0.0;
  int k = 0;
  for (; k < 2000 && vi.commanding(); ++k)  // 20 mm/s for up to 2 s
  {
    vi.step(linear(0.02, 0.0, 0.0), 0.001, false);
    worst = std::max(worst, vi.lead());
  }
  EXPECT_LE(worst, 0.003 + 1e-9);  // never runs away from the arm
  EXPECT_EQ(vi.mode(), VelocityIntegrator::Mode::FAULT);
  // 3 mm reached after 150 ms, then saturated for max_stall: fault at ~650 ms (margin for dt sums)
  EXPECT_GT(k, 600);
  EXPECT_LT(k, 700);
  EXPECT_EQ(vi.faultReason(), "arm not following the set-point");
  // the held set-point is the frozen one, within max_lead of the arm
  EXPECT_LE(vi.lead(), 0.003 + 1e-9);
  // in FAULT nothing integrates
  const KDL::Frame held = vi.pose();
  vi.step(linear(0.02, 0.0, 0.0), 0.001, false);
  EXPECT_TRUE(KDL::Equal(held, vi.pose(), 1e-15));
}

TEST(VelocityIntegratorResync, ArmThatFollowsIsNeverLimited)
{
  IntegratorParams p;
  VelocityIntegrator vi(p);
  ASSERT_TRUE(vi.start(KDL::Frame::Identity()));
  for (int k = 0; k < 1000; ++k)
  {
    vi.step(linear(0.02, 0.01, 0.0), 0.001, false);
    KDL::Frame lagging = vi.pose();
    lagging.p -= KDL::Vector(0.001, 0.0, 0.0);  // the arm 1 mm behind
    vi.setMeasured(lagging);
  }
  EXPECT_TRUE(vi.commanding());
  EXPECT_EQ(vi.leadLimitedSteps(), 0u);
  EXPECT_NEAR(vi.pose().p.x(), 0.02, 1e-9);
}

TEST(VelocityIntegratorResync, FaultResumesOnlyThroughClutchAtTheMeasuredPose)
{
  IntegratorParams p;
  VelocityIntegrator vi(p);
  ASSERT_TRUE(vi.start(KDL::Frame::Identity()));
  vi.fault("console link stale");
  EXPECT_FALSE(vi.commanding());
  // the master keeps moving while the chain is held: nothing integrates
  for (int k = 0; k < 100; ++k)
    vi.step(linear(0.05, 0.0, 0.0), 0.001, false);
  // the arm is somewhere else now (e.g. an arm controller restart)
  const KDL::Frame arm(KDL::Vector(0.0134, 0.0, 0.0));
  vi.setMeasured(arm);
  EXPECT_FALSE(vi.clutch(false));  // a release without a press does not resume
  EXPECT_FALSE(vi.commanding());
  EXPECT_FALSE(vi.clutch(true));
  EXPECT_EQ(vi.mode(), VelocityIntegrator::Mode::CLUTCHED);
  EXPECT_TRUE(vi.clutch(false));
  EXPECT_TRUE(vi.commanding());
  // first set-point after recovery: the held (measured) pose, 0 mm jump
  EXPECT_LT((vi.pose().p - arm.p).Norm(), 1e-12);
  // then at most max_linear_velocity
  vi.step(linear(5.0, 0.0, 0.0), 0.004, false);
  EXPECT_NEAR((vi.pose().p - arm.p).Norm(), p.max_linear_velocity * 0.004, 1e-12);
}

TEST(VelocityIntegratorResync, RestartAwaitsClutchAndNormalClutchReanchors)
{
  IntegratorParams p;
  VelocityIntegrator restarted(p);
  ASSERT_TRUE(restarted.start(KDL::Frame::Identity(), true));
  EXPECT_EQ(restarted.mode(), VelocityIntegrator::Mode::FAULT);
  EXPECT_EQ(restarted.faults(), 1u);

  VelocityIntegrator vi(p);
  ASSERT_TRUE(vi.start(KDL::Frame::Identity()));
  vi.step(linear(0.01, 0.0, 0.0), 0.1, false);  // set-point 1 mm ahead
  vi.clutch(true);
  vi.step(linear(0.01, 0.0, 0.0), 0.1, false);  // clutched: no motion
  EXPECT_NEAR(vi.pose().p.x(), 0.001, 1e-12);
  const KDL::Frame arm(KDL::Vector(0.0008, 0.0, 0.0));
  vi.setMeasured(arm);
  EXPECT_TRUE(vi.clutch(false));
  EXPECT_NEAR(vi.pose().p.x(), 0.0008, 1e-12);
  EXPECT_EQ(vi.faults(), 0u);
  // non-finite measurements are refused and keep the last one
  EXPECT_FALSE(vi.setMeasured(KDL::Frame(KDL::Vector(NAN, 0.0, 0.0))));
  EXPECT_TRUE(vi.hasMeasured());
}

TEST(VelocityIntegratorResync, InvalidLeadParametersThrow)
{
  IntegratorParams p;
  p.max_lead = 0.0;
  EXPECT_THROW(p.validate(), std::invalid_argument);
  p = IntegratorParams();
  p.max_stall = std::nan("");
  EXPECT_THROW(p.validate(), std::invalid_argument);
}

TEST(VelocityIntegratorResync, SpeedScaleReducesTheLimit)
{
  IntegratorParams p;
  p.max_linear_velocity = 0.05;
  VelocityIntegrator vi(p);
  ASSERT_TRUE(vi.start(KDL::Frame::Identity()));
  vi.setSpeedScale(0.2);
  vi.setSpeedScale(0.0);  // ignored
  EXPECT_DOUBLE_EQ(vi.speedScale(), 0.2);
  vi.step(linear(1.0, 0.0, 0.0), 0.01, false);
  EXPECT_NEAR(vi.pose().p.x(), 0.01 * 0.01, 1e-12);
}
