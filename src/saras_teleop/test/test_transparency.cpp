// Core tests of the transparency layer and the twist estimator (no ROS).
#include <cmath>
#include <stdexcept>

#include <gtest/gtest.h>

#include "saras_teleop/transparency.h"
#include "saras_teleop/twist_estimator.h"

using saras_teleop::TransparencyChannel;
using saras_teleop::TransparencyParams;
using saras_teleop::TwistEstimator;
using saras_teleop::Vector6d;

TEST(Transparency, WaitsThenComputesSetPoints)
{
  TransparencyParams p;
  p.pose_error_gain = 100.0;
  p.scale_factor = 0.5;
  p.max_force = 100.0;
  TransparencyChannel ch(p);
  Vector6d w, v;
  EXPECT_EQ(ch.update(w, v), TransparencyChannel::WAITING);
  ch.setMasterPosition(Eigen::Vector3d(1.0, 2.0, 3.0));
  EXPECT_EQ(ch.update(w, v), TransparencyChannel::WAITING);
  ch.setSlavePosition(Eigen::Vector3d(0.1, 0.2, 0.3));
  EXPECT_EQ(ch.update(w, v), TransparencyChannel::RUNNING);
  EXPECT_DOUBLE_EQ(w.norm(), 0.0);
  // master moves 1 cm in x, slave has moved 2 mm (scaled master would be 5 mm)
  ch.setMasterPosition(Eigen::Vector3d(1.01, 2.0, 3.0));
  ch.setSlavePosition(Eigen::Vector3d(0.102, 0.2, 0.3));
  Vector6d tw;
  tw << 0.1, -0.2, 0.3, 0.4, 0.5, 0.6;
  ch.setMasterTwist(tw);
  ch.update(w, v);
  // K * ((s - s0)/scale - (m - m0)) = 100 * (0.004 - 0.01) = -0.6 N
  EXPECT_NEAR(w[0], -0.6, 1e-12);
  EXPECT_NEAR(w[1], 0.0, 1e-12);
  EXPECT_NEAR(w.tail<3>().norm(), 0.0, 1e-15);
  EXPECT_NEAR(v[0], 0.05, 1e-15);
  EXPECT_NEAR(v[2], 0.15, 1e-15);
  EXPECT_NEAR(v[5], 0.6, 1e-15);  // rotation_scale 1
  // free motion with perfect scaled tracking: no force (the deliverable's unscaled error would give 50 N/m * ...)
  ch.setSlavePosition(Eigen::Vector3d(0.105, 0.2, 0.3));
  ch.update(w, v);
  EXPECT_NEAR(w.norm(), 0.0, 1e-12);
}

TEST(Transparency, ClutchReindexesWithoutJump)
{
  TransparencyParams p;
  p.pose_error_gain = 100.0;
  p.scale_factor = 1.0;
  TransparencyChannel ch(p);
  Vector6d w, v;
  ch.setMasterPosition(Eigen::Vector3d::Zero());
  ch.setSlavePosition(Eigen::Vector3d::Zero());
  ch.update(w, v);
  ch.setMasterTwist(Vector6d::Constant(0.1));
  ch.setClutch(true);
  EXPECT_EQ(ch.update(w, v), TransparencyChannel::HOLD);
  EXPECT_DOUBLE_EQ(w.norm() + v.norm(), 0.0);
  // operator repositions the master by 10 cm while clutched
  ch.setMasterPosition(Eigen::Vector3d(0.1, 0.0, 0.0));
  ch.update(w, v);
  ch.setClutch(false);
  ch.setMasterTwist(Vector6d::Zero());
  EXPECT_EQ(ch.update(w, v), TransparencyChannel::RUNNING);
  EXPECT_NEAR(w.norm(), 0.0, 1e-12);  // without re-indexing this would be 10 N
  EXPECT_TRUE(ch.masterOffset().isApprox(Eigen::Vector3d(0.1, 0.0, 0.0)));
  // stale link behaves the same
  ch.setLinkOk(false);
  ch.setMasterTwist(Vector6d::Constant(0.1));
  EXPECT_EQ(ch.update(w, v), TransparencyChannel::HOLD);
  EXPECT_DOUBLE_EQ(v.norm(), 0.0);
}

TEST(Transparency, SaturatesAndRejectsBadInput)
{
  TransparencyParams p;
  p.pose_error_gain = 1000.0;
  p.max_force = 3.0;
  TransparencyChannel ch(p);
  Vector6d w, v;
  ch.setMasterPosition(Eigen::Vector3d::Zero());
  ch.setSlavePosition(Eigen::Vector3d::Zero());
  ch.update(w, v);
  EXPECT_FALSE(ch.setMasterPosition(Eigen::Vector3d(std::nan(""), 0, 0)));
  EXPECT_FALSE(ch.setMasterTwist(Vector6d::Constant(INFINITY)));
  ch.setMasterPosition(Eigen::Vector3d(0.0, 0.1, 0.1));
  ch.update(w, v);
  EXPECT_NEAR(w.head<3>().norm(), 3.0, 1e-12);
  EXPECT_TRUE(w.allFinite() && v.allFinite());
  Vector6d fix = Vector6d::Zero();
  fix[5] = 0.2;
  ch.setFixtureWrench(fix);
  ch.update(w, v);
  EXPECT_DOUBLE_EQ(w[5], 0.2);
  TransparencyParams bad;
  bad.scale_factor = 0.0;
  EXPECT_THROW(TransparencyChannel c(bad), std::invalid_argument);
}

TEST(TwistEstimator, RecoversConstantTwist)
{
  TwistEstimator est(50.0, 0.1);
  const KDL::Vector v(0.02, -0.01, 0.03), w(0.0, 0.0, 0.5);
  KDL::Frame f(KDL::Rotation::RPY(0.1, 0.2, 0.3), KDL::Vector(0.1, 0.2, 0.3));
  EXPECT_EQ(est.addSample(0.0, f), TwistEstimator::RESET);
  for (int k = 1; k <= 500; ++k)
  {
    f = KDL::addDelta(f, KDL::Twist(v, w), 0.001);
    ASSERT_EQ(est.addSample(k * 0.001, f), TwistEstimator::UPDATED);
  }
  EXPECT_NEAR(est.twist()[0], 0.02, 1e-6);
  EXPECT_NEAR(est.twist()[2], 0.03, 1e-6);
  EXPECT_NEAR(est.twist()[5], 0.5, 1e-6);
  EXPECT_EQ(est.addSample(0.5, f), TwistEstimator::SAME_SAMPLE);
  KDL::Frame bad = f;
  bad.p[1] = std::nan("");
  EXPECT_EQ(est.addSample(0.6, bad), TwistEstimator::REJECTED);
  EXPECT_EQ(est.addSample(1.0, f), TwistEstimator::RESET);  // 0.5 s gap > max_gap
  EXPECT_DOUBLE_EQ(est.twist().norm(), 0.0);
}

TEST(TwistEstimator, LowPassAttenuatesAtCutoff)
{
  // a sinusoid at the cut-off frequency is attenuated to 1/sqrt(2) (first-order filter)
  const double fc = 20.0;
  TwistEstimator est(fc, 0.1);
  const double A = 0.001, w = 2.0 * M_PI * fc, dt = 1e-4;
  double peak = 0.0;
  for (int k = 0; k <= 20000; ++k)
  {
    const double t = k * dt;
    est.addSample(t, KDL::Frame(KDL::Vector(A * std::sin(w * t), 0, 0)));
    if (t > 1.0)
      peak = std::max(peak, std::fabs(est.twist()[0]));
  }
  EXPECT_NEAR(peak / (A * w), 1.0 / std::sqrt(2.0), 0.01);
}

TEST(TfTransformer, RotateWrenchKeepsMagnitudeNoLever)
{
  const KDL::Rotation R = KDL::Rotation::RotZ(M_PI / 2);
  Vector6d w;
  w << 1.0, 0.0, 0.0, 0.0, 0.0, 0.0;
  const Vector6d b = saras_teleop::rotateWrench(R, w);
  EXPECT_NEAR(b[0], 0.0, 1e-15);
  EXPECT_NEAR(b[1], 1.0, 1e-15);
  EXPECT_NEAR(b.tail<3>().norm(), 0.0, 1e-15);
}
