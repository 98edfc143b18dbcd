// Core tests of the transparency layer and the twist estimator (no ROS).
#include <cmath>
#include <stdexcept>

#include <gtest/gtest.h>

#include "saras_teleop/energy_tank.h"
#include "saras_teleop/transparency.h"
#include "saras_teleop/twist_estimator.h"

using saras_teleop::EnergyTank;
using saras_teleop::TankParams;
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

TEST(Transparency, ContactForceReflectedScaledAndSwitchable)
{
  TransparencyParams p;
  p.contact_force_scale = 0.5;
  for (bool on : {true, false})
  {
    p.contact_feedback = on;
    TransparencyChannel ch(p);
    Vector6d w, v;
    ch.setMasterPosition(Eigen::Vector3d::Zero());
    ch.setSlavePosition(Eigen::Vector3d::Zero());
    ch.update(w, v);
    EXPECT_TRUE(ch.setContactForce(Eigen::Vector3d(0.3, -0.4, 2.0)));  // tissue pushing the tool back [N]
    EXPECT_FALSE(ch.setContactForce(Eigen::Vector3d(NAN, 0.0, 0.0)));  // rejected, previous kept
    ch.update(w, v);
    if (on)
      EXPECT_NEAR((w.head<3>() - 0.5 * Eigen::Vector3d(0.3, -0.4, 2.0)).norm(), 0.0, 1e-12);
    else
      EXPECT_NEAR(w.norm(), 0.0, 1e-12);
  }
  p.contact_force_scale = -1.0;
  EXPECT_THROW(p.validate(), std::invalid_argument);
}

// The operator pushes the tool into tissue: the contact force (depth x K_skin along the outward
// normal) reaches the hand through transparency and tank_master, in its direction and within 10 %
// of force x contact_force_scale, while the tank keeps T >= T_min (it absorbs: the force opposes
// the motion).
TEST(Transparency, ContactForceReachesTheHandThroughTheMasterTank)
{
  TransparencyParams p;
  p.contact_force_scale = 0.5;
  TransparencyChannel ch(p);
  EnergyTank tank(TankParams(), 1);
  const Eigen::Vector3d normal = Eigen::Vector3d(0.2, -0.3, 1.0).normalized();  // outward, slave base frame
  const double k_skin = 500.0, dt = 1e-3, speed = 0.004;  // [N/m], [s], [m/s] master speed into the tissue
  Eigen::Vector3d m = Eigen::Vector3d::Zero();
  ch.setMasterPosition(m);
  ch.setSlavePosition(m);
  Vector6d w, v, twist = Vector6d::Zero();
  twist.head<3>() = -speed * normal;
  double worst = 0.0;
  for (int k = 1; k <= 2000; ++k)
  {
    m += dt * twist.head<3>();
    ch.setMasterPosition(m);
    ch.setSlavePosition(p.scale_factor * m);  // the slave follows (the tissue does not stop it)
    ch.setMasterTwist(twist);
    const double depth = p.scale_factor * speed * k * dt;
    const Eigen::Vector3d f_contact = depth * k_skin * normal;
    ch.setContactForce(f_contact);
    ch.update(w, v);
    tank.setDesired(0, w);
    tank.setConjugate(0, twist);
    ASSERT_TRUE(tank.step(dt, 0.0, 0.0));
    const Eigen::Vector3d hand = tank.output(0).head<3>();
    const Eigen::Vector3d expected = p.contact_force_scale * f_contact;
    if (expected.norm() > 0.1)  // [N] the damping alone dominates near zero
    {
      EXPECT_GT(hand.dot(normal), 0.0) << "the hand is pushed out of the tissue";
      worst = std::max(worst, (hand - expected).norm() / expected.norm());
    }
  }
  EXPECT_LT(worst, 0.10);
  EXPECT_GE(tank.energy(), TankParams().T_min);
  EXPECT_GT(tank.energy(), TankParams().T_init);  // the reflected force absorbed energy
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
