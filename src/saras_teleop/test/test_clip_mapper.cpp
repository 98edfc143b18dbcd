// Core tests of the Simball clip -> instrument jaw mapping (no ROS).
#include <cmath>
#include <limits>
#include <stdexcept>

#include <gtest/gtest.h>

#include "saras_teleop/clip_mapper.h"

using saras_teleop::ClipMapper;
using saras_teleop::ClipParams;

namespace
{
ClipParams params()
{
  ClipParams p;
  p.scale = 1.0;
  p.offset = 0.0;
  p.jaw_min = 0.0;
  p.jaw_max = 1.0;
  p.max_velocity = 2.0;
  p.input_timeout = 0.1;
  p.max_step = 0.05;
  return p;
}

/// Feeds a constant clip angle at 1 kHz from t0 for @p seconds; returns the time reached.
double drive(ClipMapper& m, double clip, double t0, double seconds, bool hold = false)
{
  const int n = static_cast<int>(std::lround(seconds * 1000.0));
  for (int k = 1; k <= n; ++k)
  {
    const double t = t0 + k * 1e-3;
    m.setClip(clip, t);
    m.step(t, hold);
  }
  return t0 + n * 1e-3;
}
}  // namespace

TEST(ClipMapper, MapsScaledOffsetAndClampedToTheJawRange)
{
  ClipParams p = params();
  p.scale = 0.5;
  p.offset = 0.1;
  const ClipMapper m(p);
  EXPECT_DOUBLE_EQ(m.map(0.0), 0.1);
  EXPECT_DOUBLE_EQ(m.map(1.0), 0.6);
  EXPECT_DOUBLE_EQ(m.map(10.0), 1.0);   // clamped open
  EXPECT_DOUBLE_EQ(m.map(-10.0), 0.0);  // clamped closed
}

TEST(ClipMapper, NoCommandBeforeTheMeasuredJaw)
{
  ClipMapper m(params());
  drive(m, 0.8, 0.0, 0.2);
  EXPECT_FALSE(m.started());
  EXPECT_TRUE(m.holding());
  EXPECT_FALSE(m.setMeasured(std::nan("")));
  EXPECT_FALSE(m.started());
  EXPECT_TRUE(m.setMeasured(1.7));  // out of range: the command starts clamped
  EXPECT_DOUBLE_EQ(m.command(), 1.0);
  EXPECT_TRUE(m.setMeasured(0.3));  // later measurements do not move the command
  EXPECT_DOUBLE_EQ(m.command(), 1.0);
}

TEST(ClipMapper, OpensAndClosesAtTheSpeedLimit)
{
  ClipMapper m(params());
  m.setMeasured(0.0);
  m.step(0.0, false);
  // open fully: 1 rad at 2 rad/s takes 0.5 s
  double t = drive(m, 1.0, 0.0, 0.25);
  EXPECT_NEAR(m.command(), 0.5, 1e-9);
  EXPECT_FALSE(m.holding());
  t = drive(m, 1.0, t, 0.3);
  EXPECT_DOUBLE_EQ(m.command(), 1.0);
  // close: never faster than the limit, reaches the target exactly
  double prev = m.command(), t_prev = t;
  for (int k = 1; k <= 600; ++k)
  {
    const double tk = t + k * 1e-3;
    m.setClip(0.0, tk);
    const double c = m.step(tk, false);
    EXPECT_LE(prev - c, 2.0 * (tk - t_prev) + 1e-12);
    EXPECT_GE(c, 0.0);
    prev = c;
    t_prev = tk;
  }
  EXPECT_DOUBLE_EQ(m.command(), 0.0);
}

TEST(ClipMapper, LongPauseBetweenStepsIsLimitedToMaxStep)
{
  ClipMapper m(params());
  m.setMeasured(0.0);
  m.step(0.0, false);
  m.setClip(1.0, 1.0);
  m.step(1.0, false);  // 1 s since the last step: at most max_step (0.05 s) x 2 rad/s
  EXPECT_NEAR(m.command(), 0.1, 1e-12);
}

TEST(ClipMapper, HoldsOnHoldStaleOrAbsentInput)
{
  ClipMapper m(params());
  m.setMeasured(0.4);
  m.step(0.0, false);
  m.step(0.5, false);  // no clip sample yet
  EXPECT_TRUE(m.holding());
  EXPECT_DOUBLE_EQ(m.command(), 0.4);
  // caller's hold (link stale, clutch, safe hold): the jaw does not follow
  double t = drive(m, 1.0, 0.5, 0.5, true);
  EXPECT_TRUE(m.holding());
  EXPECT_DOUBLE_EQ(m.command(), 0.4);
  // input stops: once older than input_timeout the jaw holds where it is
  m.setClip(1.0, t + 0.001);
  m.step(t + 0.001, false);
  const double moved = m.command();
  EXPECT_GT(moved, 0.4);
  for (double s = t + 0.2; s < t + 2.0; s += 0.01)
    m.step(s, false);
  EXPECT_TRUE(m.holding());
  EXPECT_TRUE(m.stale(t + 2.0));
  EXPECT_LT(m.command(), moved + 2.0 * 0.1 + 1e-9);  // at most input_timeout of motion after the last sample
}

TEST(ClipMapper, NonFiniteClipIsRejectedAndHolds)
{
  ClipMapper m(params());
  m.setMeasured(0.5);
  m.step(0.0, false);
  double t = drive(m, 0.5, 0.0, 0.1);
  EXPECT_FALSE(m.setClip(std::numeric_limits<double>::infinity(), t + 0.001));
  EXPECT_FALSE(m.setClip(std::nan(""), t + 0.002));
  EXPECT_EQ(m.rejected(), 2u);
  for (int k = 3; k < 300; ++k)
    m.step(t + k * 1e-3, false);
  EXPECT_TRUE(m.holding());
  EXPECT_DOUBLE_EQ(m.command(), 0.5);
  m.step(std::nan(""), false);
  EXPECT_DOUBLE_EQ(m.command(), 0.5);
  EXPECT_TRUE(std::isfinite(m.command()));
  // the next valid sample resumes, rate-limited over the 101 ms since the last step (t + 0.299)
  t = drive(m, 1.0, t + 0.3, 0.1);
  EXPECT_FALSE(m.holding());
  EXPECT_NEAR(m.command(), 0.5 + 2.0 * 0.101, 1e-9);
}

TEST(ClipMapper, InvalidParametersAreNamed)
{
  const auto expectNamed = [](ClipParams p, const char* name) {
    try
    {
      ClipMapper m(p);
      ADD_FAILURE() << "accepted bad " << name;
    }
    catch (const std::invalid_argument& e)
    {
      EXPECT_NE(std::string(e.what()).find(name), std::string::npos) << e.what();
    }
  };
  ClipParams p = params();
  p.scale = 0.0;
  expectNamed(p, "jaw_scale");
  p = params();
  p.jaw_max = p.jaw_min;
  expectNamed(p, "jaw_max");
  p = params();
  p.jaw_min = std::nan("");
  expectNamed(p, "jaw_min");
  p = params();
  p.max_velocity = -1.0;
  expectNamed(p, "max_jaw_velocity");
  p = params();
  p.input_timeout = 0.0;
  expectNamed(p, "jaw_input_timeout");
  p = params();
  p.offset = std::numeric_limits<double>::infinity();
  expectNamed(p, "jaw_offset");
}
