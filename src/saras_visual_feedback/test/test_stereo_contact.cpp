// StereoContactEstimator on ray-cast stereo pairs of a textured plane (known geometry), with the
// instrument's shaft in the images.
#include <gtest/gtest.h>

#include <cmath>

#include "saras_visual_feedback/stereo_contact.h"
#include "synthetic_stereo.h"

using namespace saras_visual_feedback;  // NOLINT(build/namespaces) test file

namespace
{
constexpr double kDeg = CV_PI / 180.0;

/// Plane through (0, 0, 0.06) tilted by @p tilt about x, facing the camera.
synthetic::Scene tiltedPlane(double tilt, bool textured = true)
{
  synthetic::Scene sc;
  sc.n = cv::Vec3d(0, std::sin(tilt), -std::cos(tilt));
  sc.texture = synthetic::texture(1200, textured);
  return sc;
}

/// A tool whose tip is @p height [m] above (negative: below) the plane at its point under (x, y),
/// shaft coming from up-left-front towards the tip.
InstrumentView toolAbove(const synthetic::Scene& sc, double x, double y, double height)
{
  // point of the plane on the camera ray through (x, y, 1)
  const cv::Vec3d ray(x, y, 1.0);
  const cv::Vec3d s = ray * (sc.p.dot(sc.n) / ray.dot(sc.n));
  InstrumentView t;
  t.valid = true;
  const cv::Vec3d tip = s + sc.n * height;  // sc.n faces the camera: outward
  t.tip = cv::Point3d(tip[0], tip[1], tip[2]);
  const cv::Vec3d up = cv::normalize(cv::Vec3d(-0.6, -0.5, -0.6));
  t.has_shaft = true;
  t.shaft = cv::Point3d(tip[0] + 0.05 * up[0], tip[1] + 0.05 * up[1], tip[2] + 0.05 * up[2]);
  t.radius = 0.0025;
  return t;
}

struct Pair
{
  cv::Mat left, right;
};

Pair render(synthetic::Scene sc, const StereoCalibration& cal, const InstrumentView* tools, std::size_t n)
{
  for (std::size_t i = 0; i < n; ++i)
    sc.shafts.push_back({cv::Vec3d(tools[i].tip.x, tools[i].tip.y, tools[i].tip.z),
                         cv::Vec3d(tools[i].shaft.x, tools[i].shaft.y, tools[i].shaft.z), tools[i].radius});
  const double baseline = -cal.P_right(0, 3) / cal.P_right(0, 0);
  return {synthetic::render(sc, cal.left, 0.0, 1), synthetic::render(sc, cal.right, baseline, 2)};
}

double angleDeg(const cv::Vec3d& a, const cv::Vec3d& b)
{
  return std::acos(std::max(-1.0, std::min(1.0, a.dot(b) / (cv::norm(a) * cv::norm(b))))) / kDeg;
}

StereoContactEstimator configured(const StereoCalibration& cal)
{
  StereoContactEstimator e;
  std::string why;
  EXPECT_TRUE(e.configure(cal, &why)) << why;
  return e;
}
}  // namespace

TEST(StereoContact, ParamsValidated)
{
  StereoContactParams p;
  std::string why;
  EXPECT_TRUE(validateStereoContactParams(p, &why)) << why;
  p.block_size = 8;
  EXPECT_FALSE(validateStereoContactParams(p, &why));
  EXPECT_NE(why.find("block_size"), std::string::npos);
  p = StereoContactParams();
  p.sample_grid = 8;
  EXPECT_FALSE(validateStereoContactParams(p, &why));
  EXPECT_NE(why.find("sample_grid"), std::string::npos);
}

TEST(StereoContact, RejectsCalibrationWithoutBaseline)
{
  StereoCalibration cal = synthetic::calibration(640);
  cal.P_right(0, 3) = 0.0;
  StereoContactEstimator e;
  std::string why;
  EXPECT_FALSE(e.configure(cal, &why));
  EXPECT_NE(why.find("Tx"), std::string::npos);
  const cv::Mat img(360, 640, CV_8UC3, cv::Scalar(0));
  InstrumentView t;
  t.valid = true;
  t.tip = cv::Point3d(0, 0, 0.06);
  EXPECT_EQ(e.estimate(img, img, &t, 1, 0).unknown, ContactUnknown::kNoCalibration);
}

// Depth and normal against the plane's truth, tip above and below the surface (640x360).
class PenetrationSweep : public ::testing::TestWithParam<double>
{
};

TEST_P(PenetrationSweep, DepthAndNormalMatchThePlane)
{
  const double height = GetParam();  // [m] > 0 above the surface
  const StereoCalibration cal = synthetic::calibration(640);
  const synthetic::Scene sc = tiltedPlane(25 * kDeg);
  const InstrumentView tool = toolAbove(sc, 0.05, 0.03, height);
  const Pair pair = render(sc, cal, &tool, 1);
  StereoContactEstimator e = configured(cal);
  const ContactEstimate c = e.estimate(pair.left, pair.right, &tool, 1, 0);
  ASSERT_EQ(c.unknown, ContactUnknown::kNone) << toString(c.unknown) << " points " << c.points;
  EXPECT_NEAR(c.signed_distance, height, 0.0005);
  EXPECT_LT(angleDeg(c.normal, sc.n), 5.0);
  EXPECT_GT(c.confidence, 0.5);
  if (height < -0.001)
  {
    EXPECT_EQ(c.state, ContactState::kContact);
    EXPECT_NEAR(c.depth, -height, 0.0005);
  }
  else if (height > 0.001)
  {
    EXPECT_EQ(c.state, ContactState::kNoContact);
    EXPECT_EQ(c.depth, 0.0);
  }
}

INSTANTIATE_TEST_SUITE_P(Heights, PenetrationSweep, ::testing::Values(0.005, 0.002, -0.002, -0.005, -0.01));

TEST(StereoContact, FullResolutionContact)
{
  const StereoCalibration cal = synthetic::calibration(1280);
  const synthetic::Scene sc = tiltedPlane(-20 * kDeg);
  const InstrumentView tool = toolAbove(sc, -0.08, 0.05, -0.004);
  const Pair pair = render(sc, cal, &tool, 1);
  StereoContactEstimator e = configured(cal);
  const ContactEstimate c = e.estimate(pair.left, pair.right, &tool, 1, 0);
  ASSERT_EQ(c.state, ContactState::kContact) << toString(c.unknown);
  EXPECT_NEAR(c.depth, 0.004, 0.0005);
  EXPECT_LT(angleDeg(c.normal, sc.n), 5.0);
}

TEST(StereoContact, UntexturedSurfaceIsUnknownNotZero)
{
  const StereoCalibration cal = synthetic::calibration(640);
  const synthetic::Scene sc = tiltedPlane(10 * kDeg, false);
  const InstrumentView tool = toolAbove(sc, 0.0, 0.0, 0.003);
  const Pair pair = render(sc, cal, &tool, 1);
  StereoContactEstimator e = configured(cal);
  const ContactEstimate c = e.estimate(pair.left, pair.right, &tool, 1, 0);
  // Without texture the block matches are invalid (kNoTexture) or, where the image noise passes
  // the texture threshold, inconsistent (kNoSurface): unknown either way, never a confident zero.
  EXPECT_EQ(c.state, ContactState::kUnknown);
  EXPECT_TRUE(c.unknown == ContactUnknown::kNoTexture || c.unknown == ContactUnknown::kNoSurface)
      << toString(c.unknown);
  EXPECT_EQ(c.confidence, 0.0);
  EXPECT_EQ(c.depth, 0.0);
}

TEST(StereoContact, TipOutOfViewOrBehindIsUnknown)
{
  const StereoCalibration cal = synthetic::calibration(640);
  StereoContactEstimator e = configured(cal);
  const cv::Mat img(360, 640, CV_8UC3, cv::Scalar(100));
  InstrumentView t;
  t.valid = true;
  t.tip = cv::Point3d(0.2, 0.0, 0.06);  // far right of the field of view
  EXPECT_EQ(e.estimate(img, img, &t, 1, 0).unknown, ContactUnknown::kOutOfView);
  t.tip = cv::Point3d(0.0, 0.0, -0.01);  // behind the camera
  EXPECT_EQ(e.estimate(img, img, &t, 1, 0).unknown, ContactUnknown::kOutOfView);
  t.valid = false;
  EXPECT_EQ(e.estimate(img, img, &t, 1, 0).unknown, ContactUnknown::kNoPose);
}

TEST(StereoContact, TipHiddenBehindAnotherInstrumentIsUnknown)
{
  const StereoCalibration cal = synthetic::calibration(640);
  const synthetic::Scene sc = tiltedPlane(15 * kDeg);
  InstrumentView tools[2];
  tools[0] = toolAbove(sc, 0.02, 0.0, -0.003);
  // A thick instrument 2 cm in front of the tip, across its whole region.
  tools[1].valid = true;
  tools[1].tip = cv::Point3d(tools[0].tip.x - 0.03, tools[0].tip.y, tools[0].tip.z - 0.02);
  tools[1].has_shaft = true;
  tools[1].shaft = cv::Point3d(tools[0].tip.x + 0.03, tools[0].tip.y, tools[0].tip.z - 0.02);
  tools[1].radius = 0.006;
  const Pair pair = render(sc, cal, tools, 2);
  StereoContactEstimator e = configured(cal);
  const ContactEstimate c = e.estimate(pair.left, pair.right, tools, 2, 0);
  EXPECT_EQ(c.state, ContactState::kUnknown);
  EXPECT_EQ(c.unknown, ContactUnknown::kOccluded);
  EXPECT_EQ(c.confidence, 0.0);
}

TEST(StereoContact, ShaftMaskKeepsTheFitOnTissue)
{
  // Without masking the bright shaft, its points (at the tip's depth, in front of the surface)
  // would bias the fit; with the mask every triangulated point lies on the plane.
  const StereoCalibration cal = synthetic::calibration(640);
  const synthetic::Scene sc = tiltedPlane(0.0);
  const InstrumentView tool = toolAbove(sc, 0.0, 0.01, -0.003);
  const Pair pair = render(sc, cal, &tool, 1);
  StereoContactEstimator e = configured(cal);
  const ContactEstimate c = e.estimate(pair.left, pair.right, &tool, 1, 0);
  ASSERT_EQ(c.unknown, ContactUnknown::kNone);
  int off_plane = 0;
  for (const cv::Point3d& p : e.lastPoints())
    off_plane += std::abs((cv::Vec3d(p.x, p.y, p.z) - sc.p).dot(sc.n)) > 0.002 ? 1 : 0;
  EXPECT_LT(off_plane, static_cast<int>(e.lastPoints().size()) / 50) << "of " << e.lastPoints().size();
}

int main(int argc, char** argv)
{
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
