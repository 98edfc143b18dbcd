// Zero copy with the camera source when both run in one nodelet manager (issue 7).
//
// This process plays the nodelet manager (nodelet::Loader, as `nodelet manager`), the endoscope
// source publishing from the same process (as a camera nodelet would) and a viewer. roscpp hands
// a message to a subscriber of the same process as the publisher's shared pointer; serialisation
// (a subscriber elsewhere, or a transport that needs it) would leave the publisher the only owner.
#include <gtest/gtest.h>

#include <atomic>
#include <cstring>
#include <functional>
#include <vector>
#include <mutex>
#include <string>

#include <boost/make_shared.hpp>
#include <nodelet/loader.h>
#include <ros/ros.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>

namespace
{
constexpr int kWidth = 640, kHeight = 360;

sensor_msgs::CameraInfoPtr cameraInfo(const ros::Time& stamp)
{
  auto info = boost::make_shared<sensor_msgs::CameraInfo>();
  info->header.stamp = stamp;
  info->header.frame_id = "endoscope/left_optical_frame";
  info->width = kWidth;
  info->height = kHeight;
  info->distortion_model = "plumb_bob";
  info->D = {-0.2, 0.05, 0.0, 0.0, 0.0};
  info->K = {500, 0, 320, 0, 500, 180, 0, 0, 1};
  info->R = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  info->P = {500, 0, 320, 0, 0, 500, 180, 0, 0, 0, 1, 0};
  return info;
}

sensor_msgs::ImagePtr image(const ros::Time& stamp)
{
  auto img = boost::make_shared<sensor_msgs::Image>();
  img->header.stamp = stamp;
  img->header.frame_id = "endoscope/left_optical_frame";
  img->width = kWidth;
  img->height = kHeight;
  img->encoding = "bgr8";
  img->step = 3 * kWidth;
  img->data.assign(static_cast<std::size_t>(img->step) * kHeight, 0);
  for (std::size_t i = 0; i < img->data.size(); ++i)
    img->data[i] = static_cast<std::uint8_t>(40 + (i % 7));  // not black: the HUD changes it
  return img;
}

bool waitFor(const std::function<bool()>& predicate, double timeout)
{
  const ros::WallTime until = ros::WallTime::now() + ros::WallDuration(timeout);
  while (!predicate())
  {
    if (ros::WallTime::now() > until)
      return false;
    ros::WallDuration(0.01).sleep();
  }
  return true;
}
}  // namespace

TEST(ZeroCopy, SameManagerGetsTheCameraMessageWithoutSerialisationAndNeverWritesIt)
{
  ros::NodeHandle nh;
  ros::Publisher image_pub = nh.advertise<sensor_msgs::Image>("/endoscope/left/image_raw", 5);
  ros::Publisher info_pub = nh.advertise<sensor_msgs::CameraInfo>("/endoscope/left/camera_info", 5);
  std::mutex mutex;
  sensor_msgs::ImageConstPtr received;
  std::atomic<int> outputs{0};
  ros::Subscriber viewer = nh.subscribe<sensor_msgs::Image>(
      "/visual_feedback/left/image", 5, [&](const sensor_msgs::ImageConstPtr& m) {
        std::lock_guard<std::mutex> lock(mutex);
        received = m;
        ++outputs;
      });

  nodelet::Loader manager(false);
  nodelet::M_string remap;
  remap["/left/image_raw"] = "/endoscope/left/image_raw";
  remap["/left/camera_info"] = "/endoscope/left/camera_info";
  remap["/left/image"] = "/visual_feedback/left/image";
  ASSERT_TRUE(manager.load("/zero_copy_vf", "saras_visual_feedback/VisualFeedback", remap, nodelet::V_string()));
  // Lazy: the nodelet subscribes the camera once our viewer is connected.
  ASSERT_TRUE(waitFor([&] { return image_pub.getNumSubscribers() > 0 && info_pub.getNumSubscribers() > 0; }, 10.0));

  const ros::Time stamp = ros::Time::now();
  sensor_msgs::ImagePtr input = image(stamp);
  const std::vector<std::uint8_t> pristine = input->data;
  EXPECT_EQ(input.use_count(), 1);
  image_pub.publish(input);
  // Without its camera_info the frame waits in the nodelet's synchroniser: it holds OUR message
  // (a serialised delivery would hold a deserialised copy and leave us the only owner).
  ASSERT_TRUE(waitFor([&] { return input.use_count() > 1; }, 5.0)) << "the nodelet did not get the shared message";
  ros::WallDuration(0.3).sleep();
  EXPECT_GT(input.use_count(), 1);
  EXPECT_EQ(outputs.load(), 0);

  info_pub.publish(cameraInfo(stamp));
  ASSERT_TRUE(waitFor([&] { return outputs.load() >= 1; }, 5.0)) << "no augmented image";
  // Released after processing, and never written to: the output is a separate buffer with the
  // overlay (the HUD) drawn on it.
  EXPECT_TRUE(waitFor([&] { return input.use_count() == 1; }, 5.0));
  EXPECT_TRUE(input->data == pristine) << "the shared input image was modified";
  std::lock_guard<std::mutex> lock(mutex);
  ASSERT_TRUE(received);
  EXPECT_EQ(received->header.stamp, stamp);
  ASSERT_EQ(received->data.size(), pristine.size());
  EXPECT_NE(received->data.data(), input->data.data());
  EXPECT_NE(std::memcmp(received->data.data(), pristine.data(), pristine.size()), 0) << "nothing drawn";
  manager.clear();
}

int main(int argc, char** argv)
{
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "test_zero_copy");
  ros::AsyncSpinner spinner(2);
  spinner.start();
  const int result = RUN_ALL_TESTS();
  spinner.stop();
  ros::shutdown();
  return result;
}
