// CameraInfo -> intrinsics (binning, ROI, models) and Image buffer validation.
#include <gtest/gtest.h>

#include "saras_visual_feedback/ros_conversions.h"

using namespace saras_visual_feedback;  // NOLINT(build/namespaces) test file

namespace
{
sensor_msgs::CameraInfo info()
{
  sensor_msgs::CameraInfo i;
  i.width = 1280;
  i.height = 720;
  i.distortion_model = "plumb_bob";
  i.D = {-0.28, 0.11, 0.0012, -0.0007, -0.021};
  i.K = {1050.0, 0, 652.3, 0, 1042.5, 371.9, 0, 0, 1};
  return i;
}
}  // namespace

TEST(CameraInfo, PlumbBob)
{
  CameraIntrinsics k;
  std::string why;
  ASSERT_TRUE(intrinsicsFromCameraInfo(info(), &k, &why)) << why;
  EXPECT_EQ(k.width, 1280);
  EXPECT_EQ(k.height, 720);
  EXPECT_EQ(k.model, DistortionModel::kPlumbBob);
  EXPECT_DOUBLE_EQ(k.fx, 1050.0);
  EXPECT_DOUBLE_EQ(k.cy, 371.9);
  EXPECT_DOUBLE_EQ(k.d[4], -0.021);
  EXPECT_DOUBLE_EQ(k.d[5], 0.0);
}

TEST(CameraInfo, BinningAndRoi)
{
  sensor_msgs::CameraInfo i = info();
  i.binning_x = 2;
  i.binning_y = 2;
  CameraIntrinsics k;
  ASSERT_TRUE(intrinsicsFromCameraInfo(i, &k, nullptr));
  EXPECT_EQ(k.width, 640);
  EXPECT_EQ(k.height, 360);
  EXPECT_DOUBLE_EQ(k.fx, 525.0);
  EXPECT_DOUBLE_EQ(k.cx, 326.15);
  i = info();
  i.roi.x_offset = 100;
  i.roi.y_offset = 50;
  i.roi.width = 800;
  i.roi.height = 600;
  ASSERT_TRUE(intrinsicsFromCameraInfo(i, &k, nullptr));
  EXPECT_EQ(k.width, 800);
  EXPECT_EQ(k.height, 600);
  EXPECT_DOUBLE_EQ(k.cx, 552.3);
  EXPECT_DOUBLE_EQ(k.cy, 321.9);
}

TEST(CameraInfo, RejectsUncalibratedAndMalformed)
{
  std::string why;
  CameraIntrinsics k;
  sensor_msgs::CameraInfo i = info();
  i.K = {0, 0, 0, 0, 0, 0, 0, 0, 0};  // uncalibrated camera
  EXPECT_FALSE(intrinsicsFromCameraInfo(i, &k, &why));
  EXPECT_NE(why.find("focal"), std::string::npos) << why;
  i = info();
  i.distortion_model = "mei";
  EXPECT_FALSE(intrinsicsFromCameraInfo(i, &k, &why));
  EXPECT_NE(why.find("mei"), std::string::npos) << why;
  i = info();
  i.D = {0.1, 0.2};
  EXPECT_FALSE(intrinsicsFromCameraInfo(i, &k, &why));
  i = info();
  i.distortion_model = "equidistant";
  EXPECT_FALSE(intrinsicsFromCameraInfo(i, &k, &why));
  i.D = {0.01, 0.0, 0.0, 0.0};
  EXPECT_TRUE(intrinsicsFromCameraInfo(i, &k, &why)) << why;
  EXPECT_EQ(k.model, DistortionModel::kEquidistant);
  i = info();
  i.width = 0;
  EXPECT_FALSE(intrinsicsFromCameraInfo(i, &k, &why));
}

TEST(CameraInfo, RawProjectionMatchesImageGeometry)
{
  // A monocular camera (R = I, P = [K|0]): image_geometry's rectified projection followed by
  // unrectifyPoint is the raw-image projection the overlay draws with.
  sensor_msgs::CameraInfo i = info();
  i.R = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  i.P = {1050.0, 0, 652.3, 0, 0, 1042.5, 371.9, 0, 0, 0, 1, 0};
  image_geometry::PinholeCameraModel model;
  model.fromCameraInfo(i);
  CameraIntrinsics k;
  ASSERT_TRUE(intrinsicsFromCameraModel(model, &k, nullptr));
  RawProjector projector;
  ASSERT_TRUE(projector.configure(k, nullptr));
  for (const cv::Point3d& p : {cv::Point3d(0.01, -0.02, 0.1), cv::Point3d(-0.03, 0.01, 0.08), cv::Point3d(0, 0, 0.2)})
  {
    const Projection got = projector.project(p);
    ASSERT_TRUE(got.in_image);
    const cv::Point2d ref = model.unrectifyPoint(model.project3dToPixel(p));
    EXPECT_NEAR(got.pixel.x, ref.x, 1e-6);
    EXPECT_NEAR(got.pixel.y, ref.y, 1e-6);
  }
}

TEST(CameraInfo, EyeCameraRebuildsOnChangeAndChecksSize)
{
  EyeCamera eye;
  EXPECT_EQ(eye.update(info(), 1280, 720), "");
  EXPECT_NE(eye.update(info(), 640, 360).find("size"), std::string::npos);
  sensor_msgs::CameraInfo i = info();
  i.K[0] = 0.0;  // recalibrated to garbage: overlay off
  EXPECT_NE(eye.update(i, 1280, 720).find("focal"), std::string::npos);
  EXPECT_EQ(eye.update(info(), 1280, 720), "");
  EXPECT_DOUBLE_EQ(eye.projector().intrinsics().fx, 1050.0);
}

TEST(ImageBuffer, DetectsInconsistentBuffers)
{
  sensor_msgs::Image im;
  im.width = 4;
  im.height = 2;
  im.encoding = "bgr8";
  im.step = 12;
  im.data.resize(24);
  std::string why;
  EXPECT_TRUE(imageBufferConsistent(im, &why)) << why;
  im.data.resize(23);
  EXPECT_FALSE(imageBufferConsistent(im, &why));
  im.data.resize(24);
  im.step = 11;
  EXPECT_FALSE(imageBufferConsistent(im, &why));
  im.step = 12;
  im.encoding = "no_such_encoding";
  EXPECT_FALSE(imageBufferConsistent(im, &why));
  im.encoding = "bgr8";
  im.width = 0;
  EXPECT_FALSE(imageBufferConsistent(im, &why));
}

int main(int argc, char** argv)
{
  ::testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
