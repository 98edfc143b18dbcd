// RawProjector: raw-image projection with OpenCV's distortion, lens fold-back range, out-of-view.
#include <gtest/gtest.h>

#include <cmath>

#include "saras_visual_feedback/raw_projector.h"

using namespace saras_visual_feedback;  // NOLINT(build/namespaces) test file

namespace
{
CameraIntrinsics camera(DistortionModel model, std::array<double, 8> d)
{
  CameraIntrinsics k;
  k.width = 1280;
  k.height = 720;
  k.fx = 1050.0;
  k.fy = 1042.5;
  k.cx = 652.3;
  k.cy = 371.9;
  k.model = model;
  k.d = d;
  return k;
}
}  // namespace

TEST(RawProjector, PinholeWithoutDistortion)
{
  RawProjector p;
  ASSERT_TRUE(p.configure(camera(DistortionModel::kNone, {}), nullptr));
  const Projection r = p.project(cv::Point3d(0.01, -0.02, 0.1));
  ASSERT_TRUE(r.in_image);
  EXPECT_NEAR(r.pixel.x, 652.3 + 1050.0 * 0.1, 1e-9);
  EXPECT_NEAR(r.pixel.y, 371.9 - 1042.5 * 0.2, 1e-9);
  EXPECT_DOUBLE_EQ(p.maxNormalizedRadius(), 10.0);  // a pinhole never folds back
}

TEST(RawProjector, BarrelDistortionFoldsBackAndIsCut)
{
  // k1 = -0.28: r (1 - 0.28 r^2) stops growing at r = 1/sqrt(3 * 0.28) = 1.091.
  RawProjector p;
  ASSERT_TRUE(p.configure(camera(DistortionModel::kPlumbBob, {-0.28, 0, 0, 0, 0, 0, 0, 0}), nullptr));
  EXPECT_NEAR(p.maxNormalizedRadius(), 1.0 / std::sqrt(3 * 0.28), 2e-3);
  // Far off-axis (r = 3): the polynomial would put it back near the image centre.
  const Projection far = p.project(cv::Point3d(0.3, 0.0, 0.1));
  EXPECT_FALSE(far.projectable);
  EXPECT_FALSE(far.in_image);
  EXPECT_GT(far.direction.x, 0.0);  // the marker points right
}

TEST(RawProjector, BehindTheCameraAndOutsideTheImage)
{
  RawProjector p;
  ASSERT_TRUE(p.configure(camera(DistortionModel::kNone, {}), nullptr));
  const Projection behind = p.project(cv::Point3d(-0.01, 0.0, -0.1));
  EXPECT_FALSE(behind.projectable);
  EXPECT_LT(behind.direction.x, 0.0);
  const Projection outside = p.project(cv::Point3d(0.0, 0.05, 0.1));  // 521 px below the centre
  EXPECT_TRUE(outside.projectable);
  EXPECT_FALSE(outside.in_image);
  EXPECT_GT(outside.direction.y, 0.0);
}

TEST(RawProjector, BatchEqualsSinglePointsAndFisheye)
{
  RawProjector p;
  ASSERT_TRUE(p.configure(camera(DistortionModel::kEquidistant, {0.05, -0.01, 0, 0, 0, 0, 0, 0}), nullptr));
  const cv::Point3d pts[3] = {{0.01, 0.01, 0.1}, {0.0, 0.0, -1.0}, {-0.02, 0.005, 0.07}};
  Projection batch[3];
  p.project(pts, 3, batch);
  for (int i = 0; i < 3; ++i)
  {
    const Projection one = p.project(pts[i]);
    EXPECT_EQ(one.projectable, batch[i].projectable);
    EXPECT_NEAR(one.pixel.x, batch[i].pixel.x, 1e-9);
    EXPECT_NEAR(one.pixel.y, batch[i].pixel.y, 1e-9);
  }
  // Equidistant: distorted radius theta (1 + k1 theta^2 + k2 theta^4), theta = atan(r).
  const double r = std::sqrt(0.02), t = std::atan(r), rd = t * (1 + 0.05 * t * t - 0.01 * t * t * t * t);
  EXPECT_NEAR(batch[0].pixel.x - 652.3, 1050.0 * 0.1 * rd / r, 1e-6);
}

TEST(RawProjector, RejectsBadIntrinsics)
{
  RawProjector p;
  std::string why;
  CameraIntrinsics k = camera(DistortionModel::kNone, {});
  k.fx = 0.0;
  EXPECT_FALSE(p.configure(k, &why));
  EXPECT_NE(why.find("focal"), std::string::npos);
  EXPECT_FALSE(p.valid());
  k = camera(DistortionModel::kPlumbBob, {NAN, 0, 0, 0, 0, 0, 0, 0});
  EXPECT_FALSE(p.configure(k, &why));
  EXPECT_FALSE(p.project(cv::Point3d(0, 0, 1)).projectable);
}

int main(int argc, char** argv)
{
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
