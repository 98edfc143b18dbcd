// CameraModel against OpenCV's cv::projectPoints / cv::fisheye::projectPoints (independent reference).
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include <opencv2/calib3d.hpp>

#include "saras_visual_feedback/camera_model.h"

using saras_visual_feedback::CameraIntrinsics;
using saras_visual_feedback::CameraModel;
using saras_visual_feedback::DistortionModel;
using saras_visual_feedback::Projection;

namespace
{
CameraIntrinsics endoscope(DistortionModel model)
{
  CameraIntrinsics k;
  k.width = 1280;
  k.height = 720;
  k.fx = 1050.0;
  k.fy = 1042.5;
  k.cx = 652.3;
  k.cy = 371.9;
  k.model = model;
  if (model == DistortionModel::kPlumbBob)
    k.d = {-0.28, 0.11, 0.0012, -0.0007, -0.021, 0, 0, 0};
  else if (model == DistortionModel::kRationalPolynomial)
    k.d = {-0.31, 0.09, 0.0009, 0.0011, 0.004, -0.02, 0.015, 0.002};
  else if (model == DistortionModel::kEquidistant)
    k.d = {-0.013, 0.021, -0.007, 0.001, 0, 0, 0, 0};
  return k;
}

cv::Matx33d cameraMatrix(const CameraIntrinsics& k)
{
  return cv::Matx33d(k.fx, 0, k.cx, 0, k.fy, k.cy, 0, 0, 1);
}

/// Reference pixel from OpenCV.
cv::Point2d opencvProject(const CameraIntrinsics& k, const cv::Point3d& p)
{
  std::vector<cv::Point3d> in{p};
  std::vector<cv::Point2d> out;
  if (k.model == DistortionModel::kEquidistant)
  {
    cv::Vec4d d(k.d[0], k.d[1], k.d[2], k.d[3]);
    cv::fisheye::projectPoints(in, out, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), cameraMatrix(k), d);
  }
  else
  {
    std::vector<double> d;
    if (k.model == DistortionModel::kPlumbBob)
      d.assign(k.d.begin(), k.d.begin() + 5);
    else if (k.model == DistortionModel::kRationalPolynomial)
      d.assign(k.d.begin(), k.d.end());
    cv::projectPoints(in, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), cameraMatrix(k), d, out);
  }
  return out[0];
}

/// Points in front of a 1280x720 endoscope at 3-30 cm, most of them in its field of view.
std::vector<cv::Point3d> pointsInView(int n)
{
  std::mt19937 rng(42);
  std::uniform_real_distribution<double> z(0.03, 0.30), xy(-0.5, 0.5);
  std::vector<cv::Point3d> pts;
  for (int i = 0; i < n; ++i)
  {
    const double zz = z(rng);
    pts.emplace_back(xy(rng) * 1.4 * zz, xy(rng) * 0.8 * zz, zz);  // some fall outside the image
  }
  return pts;
}

class ModelsVsOpenCV : public ::testing::TestWithParam<DistortionModel>
{
};
}  // namespace

TEST_P(ModelsVsOpenCV, MatchesOpenCVWithinMicroPixels)
{
  const CameraIntrinsics k = endoscope(GetParam());
  CameraModel model;
  std::string error;
  ASSERT_TRUE(model.configure(k, &error)) << error;
  int in_image = 0;
  for (const cv::Point3d& p : pointsInView(500))
  {
    const Projection pr = model.project(p);
    ASSERT_TRUE(pr.projectable) << p;
    const cv::Point2d ref = opencvProject(k, p);
    EXPECT_NEAR(pr.pixel.x, ref.x, 1e-6) << p;
    EXPECT_NEAR(pr.pixel.y, ref.y, 1e-6) << p;
    const bool ref_inside = ref.x >= -0.5 && ref.y >= -0.5 && ref.x < k.width - 0.5 && ref.y < k.height - 0.5;
    EXPECT_EQ(pr.in_image, ref_inside) << p;
    in_image += pr.in_image ? 1 : 0;
  }
  EXPECT_GT(in_image, 200);  // the sample exercises both the image area
  EXPECT_LT(in_image, 500);  // and the outside
}

INSTANTIATE_TEST_CASE_P(AllDistortionModels, ModelsVsOpenCV,
                        ::testing::Values(DistortionModel::kNone, DistortionModel::kPlumbBob,
                                          DistortionModel::kRationalPolynomial, DistortionModel::kEquidistant));

TEST(CameraModel, DistortionReallyMatters)
{
  // Guard against a test that passes with distortion ignored: near the corner the distorted
  // pixel is tens of pixels away from the pinhole one.
  CameraIntrinsics k = endoscope(DistortionModel::kPlumbBob);
  CameraModel model;
  ASSERT_TRUE(model.configure(k, nullptr));
  const cv::Point3d p(0.05, 0.025, 0.1);
  const cv::Point2d pinhole(k.fx * 0.5 + k.cx, k.fy * 0.25 + k.cy);
  const Projection pr = model.project(p);
  ASSERT_TRUE(pr.in_image);
  EXPECT_GT(cv::norm(pr.pixel - pinhole), 30.0);
}

TEST(CameraModel, BehindCameraIsNotProjectableButHasASide)
{
  CameraModel model;
  ASSERT_TRUE(model.configure(endoscope(DistortionModel::kPlumbBob), nullptr));
  const Projection pr = model.project(cv::Point3d(0.02, -0.01, -0.05));
  EXPECT_FALSE(pr.projectable);
  EXPECT_FALSE(pr.in_image);
  EXPECT_GT(pr.direction.x, 0.0);  // to the right
  EXPECT_LT(pr.direction.y, 0.0);  // and up
  EXPECT_FALSE(model.project(cv::Point3d(0.0, 0.0, 0.0)).projectable);
  EXPECT_FALSE(model.project(cv::Point3d(NAN, 0.0, 0.1)).projectable);
}

TEST(CameraModel, FoldBackOfStrongBarrelDistortionIsOutOfView)
{
  // r_d = r (1 + k1 r^2) with k1 = -0.5 peaks at r = 1/sqrt(1.5) = 0.816; OpenCV maps a point at
  // r = 1.6 back inside the image, the model must call it out of view.
  CameraIntrinsics k = endoscope(DistortionModel::kPlumbBob);
  k.d = {-0.5, 0, 0, 0, 0, 0, 0, 0};
  CameraModel model;
  ASSERT_TRUE(model.configure(k, nullptr));
  EXPECT_NEAR(model.maxNormalizedRadius(), 1.0 / std::sqrt(1.5), 2e-3);
  const cv::Point3d far(0.16, 0.0, 0.1);  // r = 1.6
  const cv::Point2d ref = opencvProject(k, far);
  ASSERT_GT(ref.x, 0.0);
  ASSERT_LT(ref.x, k.width);  // OpenCV: "visible" (folded)
  const Projection pr = model.project(far);
  EXPECT_FALSE(pr.projectable);
  EXPECT_FALSE(pr.in_image);
  EXPECT_GT(pr.direction.x, 0.0);
}

TEST(CameraModel, PointOutsideTheImageIsNotInImage)
{
  CameraModel model;
  ASSERT_TRUE(model.configure(endoscope(DistortionModel::kNone), nullptr));
  const Projection pr = model.project(cv::Point3d(-0.1, 0.0, 0.1));  // u = 652.3 - 1050 < 0
  EXPECT_TRUE(pr.projectable);
  EXPECT_FALSE(pr.in_image);
  EXPECT_NEAR(pr.pixel.x, 652.3 - 1050.0, 1e-9);
  EXPECT_LT(pr.direction.x, 0.0);
}

TEST(CameraModel, RejectsInvalidIntrinsics)
{
  CameraModel model;
  std::string error;
  CameraIntrinsics k = endoscope(DistortionModel::kPlumbBob);
  k.fx = 0.0;
  EXPECT_FALSE(model.configure(k, &error));
  EXPECT_NE(error.find("focal"), std::string::npos);
  EXPECT_FALSE(model.valid());
  k = endoscope(DistortionModel::kPlumbBob);
  k.width = 0;
  EXPECT_FALSE(model.configure(k, &error));
  k = endoscope(DistortionModel::kPlumbBob);
  k.d[1] = NAN;
  EXPECT_FALSE(model.configure(k, &error));
  k = endoscope(DistortionModel::kPlumbBob);
  EXPECT_TRUE(model.configure(k, &error));
  EXPECT_TRUE(model.valid());
}

TEST(CameraModel, ParsesDistortionModelNames)
{
  DistortionModel m;
  EXPECT_TRUE(saras_visual_feedback::parseDistortionModel("plumb_bob", &m));
  EXPECT_EQ(m, DistortionModel::kPlumbBob);
  EXPECT_TRUE(saras_visual_feedback::parseDistortionModel("rational_polynomial", &m));
  EXPECT_EQ(m, DistortionModel::kRationalPolynomial);
  EXPECT_TRUE(saras_visual_feedback::parseDistortionModel("equidistant", &m));
  EXPECT_EQ(m, DistortionModel::kEquidistant);
  EXPECT_TRUE(saras_visual_feedback::parseDistortionModel("", &m));
  EXPECT_EQ(m, DistortionModel::kNone);
  EXPECT_FALSE(saras_visual_feedback::parseDistortionModel("mei", &m));
}

int main(int argc, char** argv)
{
  ::testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
