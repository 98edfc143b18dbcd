/**
 * @file test_endoscope_sim.cpp
 * @brief gtests of the simulator's ROS-free frame logic (no roscore): configuration through
 *        saras_common::Params from a map, the pose/stamp policy over a table of poses, health
 *        decisions, eye-thread pacing, and the outgoing messages (only what is wanted, pooled).
 */
#include <pthread.h>

#include <atomic>
#include <chrono>
#include <map>
#include <mutex>
#include <string>
#include <thread>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include "saras_simulation/endoscope_sim_config.h"
#include "saras_simulation/endoscope_sim_core.h"
#include "saras_simulation/endoscope_stereo.h"

using namespace saras_simulation::endoscope;
using saras_common::ParamError;
using saras_common::Params;
using XmlRpc::XmlRpcValue;

namespace
{
const std::string kConfig = ENDOSCOPE_TEST_CONFIG_DIR;

/// Parameters from a map (names relative to /endo).
struct FakeParams
{
  std::map<std::string, XmlRpcValue> values;
  Params params() const
  {
    return Params([this](const std::string& n, XmlRpcValue& v) {
                    auto it = values.find(n);
                    if (it == values.end())
                      return false;
                    v = it->second;
                    return true;
                  },
                  [](const std::string& n) { return "/endo/" + n; });
  }
};

std::string errorOf(const FakeParams& f)
{
  try
  {
    readEndoscopeConfig(f.params());
  }
  catch (const ParamError& e)
  {
    return e.what();
  }
  return "";
}

XmlRpcValue list(std::initializer_list<double> v)
{
  XmlRpcValue l;
  l.setSize(static_cast<int>(v.size()));
  int i = 0;
  for (double x : v)
    l[i++] = x;
  return l;
}

/// Poses by frame: the latest, and optionally one exact stamp that is known (else extrapolation).
struct TablePoses : PoseSource
{
  struct Entry
  {
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    ros::Time stamp;  ///< zero: static
  };
  std::map<std::string, Entry> latest;
  std::map<std::string, Entry> at;  ///< pose at latest["endoscope/left_optical_frame"].stamp
  int lookups = 0;
  Result lookup(const std::string& frame, const ros::Time& stamp, Eigen::Isometry3d& pose, ros::Time& pose_stamp,
                std::string& error) override
  {
    ++lookups;
    auto it = latest.find(frame);
    if (it == latest.end())
    {
      error = "no frame " + frame;
      return Result::UNAVAILABLE;
    }
    const Entry* e = &it->second;
    if (!stamp.isZero() && !e->stamp.isZero() && stamp != e->stamp)
    {
      auto a = at.find(frame);
      if (a == at.end())
      {
        error = "extrapolation";
        return Result::EXTRAPOLATION;
      }
      e = &a->second;
    }
    pose = e->pose;
    pose_stamp = e->stamp;
    return Result::OK;
  }
};

Eigen::Isometry3d at(double x, double y, double z)
{
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() = Eigen::Vector3d(x, y, z);
  return T;
}

const std::string kLeft = "endoscope/left_optical_frame", kRight = "endoscope/right_optical_frame";
}  // namespace

// ------------------------------------------------------------------------------------------
TEST(Config, DefaultsAndTheShippedFile)
{
  FakeParams f;
  const EndoscopeConfig d = readEndoscopeConfig(f.params());
  EXPECT_DOUBLE_EQ(d.fps, 30.0);
  EXPECT_EQ(d.camera_info[1], "/endoscope_right.yaml");
  EXPECT_EQ(d.frames[0], kLeft);
  EXPECT_EQ(d.targets.size(), 2u);
  EXPECT_DOUBLE_EQ(d.targets.at("checkerboard").values.at("square"), 0.008);
  f.values["camera_info_dir"] = kConfig;
  f.values["fps"] = 15;  // an integer where a number is expected
  f.values["tissue"]["z0"] = 0.06;
  f.values["tissue"]["centre"] = list({ 0.01, -0.02 });
  f.values["tools"][0]["tip"] = "PSM1/tool_tip";
  f.values["tools"][0]["rcm"] = "PSM1";
  f.values["targets"]["circles"]["dots"] = 6;
  f.values["targets"]["circles"]["xyz"] = list({ 0.0, 0.01, 0.08 });
  f.values["target"] = "circles";
  const EndoscopeConfig c = readEndoscopeConfig(f.params());
  EXPECT_DOUBLE_EQ(c.fps, 15.0);
  EXPECT_EQ(c.camera_info[0], kConfig + "/endoscope_left.yaml");
  EXPECT_DOUBLE_EQ(c.tissue.z0(), 0.06);
  EXPECT_DOUBLE_EQ(c.tissue.cy(), -0.02);
  ASSERT_EQ(c.tools.size(), 1u);
  EXPECT_DOUBLE_EQ(c.tools[0].radius, 0.004);
  EXPECT_DOUBLE_EQ(c.targets.at("circles").values.at("dots"), 6.0);
  EXPECT_DOUBLE_EQ(c.targets.at("circles").pose.translation().y(), 0.01);
  EXPECT_EQ(c.initial_target, "circles");
}

TEST(Config, BadValuesNameTheParameter)
{
  auto with = [](const std::string& name, const XmlRpcValue& v) {
    FakeParams f;
    f.values[name] = v;
    return errorOf(f);
  };
  EXPECT_NE(with("fps", 0.0).find("/endo/fps = 0 [Hz] is invalid: must be in [0.5, 120]"), std::string::npos);
  EXPECT_NE(with("width", 8).find("/endo/width"), std::string::npos);
  EXPECT_NE(with("jpeg_quality", 101).find("/endo/jpeg_quality"), std::string::npos);
  EXPECT_NE(with("recorded_queue", 0).find("/endo/recorded_queue"), std::string::npos);
  EXPECT_NE(with("texture_extent", -1.0).find("/endo/texture_extent"), std::string::npos);
  EXPECT_NE(with("target", "grid").find("/endo/target"), std::string::npos);
  XmlRpcValue tissue;
  tissue["z0"] = std::numeric_limits<double>::quiet_NaN();
  EXPECT_NE(with("tissue", tissue).find("/endo/tissue/z0"), std::string::npos);
  XmlRpcValue tools;
  tools[0]["tip"] = "PSM1/tool_tip";
  EXPECT_NE(with("tools", tools).find("/endo/tools[0]"), std::string::npos);
  XmlRpcValue targets;
  targets["checkerboard"]["square"] = 0.00815;  // not a whole number of texels: the board cannot be built
  EXPECT_NE(with("targets", targets).find("/endo/targets/checkerboard"), std::string::npos);
  targets = XmlRpcValue();
  targets["checkerboard"]["colour"] = 3;
  EXPECT_NE(with("targets", targets).find("/endo/targets/checkerboard/colour"), std::string::npos);
}

// ------------------------------------------------------------------------------------------
TEST(FramePlanner, StampsWithTheLeftPoseAndLooksTheRestUpAtThatTime)
{
  FramePlanner planner(kLeft, kRight, { { "tip", "rcm", 0.004 }, { "tip2", "missing", 0.002 } });
  TablePoses tf;
  const ros::Time t(100, 5);  // exact nanoseconds are kept
  tf.latest[kLeft] = { at(0, 0, 0.2), t };
  tf.latest[kRight] = { at(0.005, 0, 0.2), ros::Time(100.02) };  // newer: looked up at t instead
  tf.at[kRight] = { at(0.004, 0, 0.2), t };
  tf.latest["tip"] = { at(0.01, 0, 0.08), ros::Time(100.02) };     // no pose at t: the latest
  tf.latest["rcm"] = { at(0.05, 0, 0.16), ros::Time() };          // static
  tf.latest["tip2"] = { at(0, 0, 0.1), ros::Time() };
  StereoFrame f;
  std::string error;
  ASSERT_EQ(planner.plan(tf, ros::Time(100.1), f, error), FramePlanner::Outcome::READY) << error;
  EXPECT_EQ(f.stamp, t);
  EXPECT_FALSE(f.is_static);
  EXPECT_DOUBLE_EQ(f.pose[1].translation().x(), 0.004);
  ASSERT_EQ(f.shafts.size(), 1u);  // the tool with a missing frame is not drawn
  EXPECT_DOUBLE_EQ(f.shafts[0].tip.x(), 0.01);
  EXPECT_DOUBLE_EQ(f.shafts[0].radius, 0.004);
}

TEST(FramePlanner, StaticCameraIsStampedNowMissingOrNonFiniteIsNoFrame)
{
  FramePlanner planner(kLeft, kRight, {});
  TablePoses tf;
  tf.latest[kLeft] = { at(0, 0, 0.2), ros::Time() };
  StereoFrame f;
  std::string error;
  EXPECT_EQ(planner.plan(tf, ros::Time(7.5), f, error), FramePlanner::Outcome::NO_POSE);
  EXPECT_NE(error.find(kRight), std::string::npos);
  tf.latest[kRight] = { at(0.005, 0, 0.2), ros::Time() };
  ASSERT_EQ(planner.plan(tf, ros::Time(7.5), f, error), FramePlanner::Outcome::READY);
  EXPECT_TRUE(f.is_static);
  EXPECT_EQ(f.stamp, ros::Time(7.5));
  tf.latest[kRight].pose.translation().x() = NAN;
  EXPECT_EQ(planner.plan(tf, ros::Time(7.6), f, error), FramePlanner::Outcome::NON_FINITE_POSE);
}

// ------------------------------------------------------------------------------------------
TEST(Health, LevelsMessagesAndCounters)
{
  EndoscopeHealth h(0.5);
  EXPECT_EQ(h.level(), EndoscopeHealth::STALE);
  EXPECT_TRUE(h.takeChanged());
  EXPECT_FALSE(h.takeChanged());
  EXPECT_TRUE(std::isinf(h.inputAge(1.0)));
  h.noPose();
  EXPECT_EQ(h.level(), EndoscopeHealth::ERROR);
  EXPECT_TRUE(h.takeChanged());
  h.noPose();
  EXPECT_FALSE(h.takeChanged());  // same level and message: no immediate report
  EXPECT_EQ(h.rejected(), 2u);
  StereoFrame f;
  f.stamp = ros::Time(10.0);
  h.rendered(10.2, f, 1280, 720);
  EXPECT_EQ(h.level(), EndoscopeHealth::OK);
  EXPECT_EQ(h.message(), "rendering 1280x720");
  h.rendered(11.0, f, 1280, 720);  // the camera TF is 1 s old while moving
  EXPECT_EQ(h.level(), EndoscopeHealth::WARN);
  EXPECT_NE(h.message().find("1.0 s old"), std::string::npos);
  f.is_static = true;  // a static pose never ages
  h.rendered(20.0, f, 1280, 720);
  EXPECT_EQ(h.level(), EndoscopeHealth::OK);
  h.skipped();
  EXPECT_EQ(h.frames(), 3u);
  EXPECT_EQ(h.skippedFrames(), 1u);
  EXPECT_DOUBLE_EQ(h.inputAge(20.5), 0.5);
}

// ------------------------------------------------------------------------------------------
namespace
{
/// Name of the calling thread (pthread_getname_np).
std::string threadName()
{
  char name[16] = {};
  pthread_getname_np(pthread_self(), name, sizeof(name));
  return name;
}

/// Both eyes run once per handed-out frame, on threads named endoscope_sim (one thread) or
/// endoscope_sim_l / _r (parallel), and a frame handed out while busy is refused.
void checkWorkers(bool parallel)
{
  std::atomic<int> runs[2] = { { 0 }, { 0 } };
  std::atomic<bool> release{ false };
  std::mutex names_mutex;
  std::string names[2];
  StereoWorkers w(
      [&](int e) {
        {
          std::lock_guard<std::mutex> lock(names_mutex);
          names[e] = threadName();
        }
        while (!release)
          std::this_thread::sleep_for(std::chrono::milliseconds(1));
        ++runs[e];
      },
      parallel);
  EXPECT_TRUE(w.idle());
  EXPECT_TRUE(w.handOut());
  EXPECT_FALSE(w.idle());
  EXPECT_FALSE(w.handOut());  // the eyes still work on the first frame: refused, not queued
  release = true;
  const auto end = std::chrono::steady_clock::now() + std::chrono::seconds(20);
  while (!w.idle() && std::chrono::steady_clock::now() < end)
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  ASSERT_TRUE(w.idle());
  EXPECT_EQ(runs[0], 1);
  EXPECT_EQ(runs[1], 1);
  std::lock_guard<std::mutex> lock(names_mutex);
  EXPECT_EQ(names[0], parallel ? "endoscope_sim_l" : "endoscope_sim");
  EXPECT_EQ(names[1], parallel ? "endoscope_sim_r" : "endoscope_sim");
  EXPECT_NE(threadName(), names[0]);  // not the caller's thread
  EXPECT_TRUE(w.handOut());
}
}  // namespace

TEST(StereoWorkers, OneNamedThreadRunsBothEyesOncePerFrame)
{
  checkWorkers(false);
}

TEST(StereoWorkers, TwoNamedThreadsRunOneEyeEachOncePerFrame)
{
  checkWorkers(true);
}

// ------------------------------------------------------------------------------------------
class Output : public ::testing::Test
{
protected:
  Output()
  {
    FakeParams f;
    f.values["width"] = 320;
    f.values["height"] = 180;
    cfg = readEndoscopeConfig(f.params());
    for (int e = 0; e < 2; ++e)
    {
      info[e] = scaledCameraInfo(readCameraInfo(kConfig + (e ? "/endoscope_right.yaml" : "/endoscope_left.yaml")), 320, 180);
      info[e].header.frame_id = cfg.frames[e];
    }
    scene.reset(new StereoScene(info, cfg, {}));
    frame.stamp = ros::Time(42, 7);
    frame.pose[0] = frame.pose[1] = at(0, 0, 0.2);
    frame.pose[0].linear() = rpyToMatrix(M_PI, 0, 0);
    frame.pose[1].linear() = frame.pose[0].linear();
  }
  EndoscopeConfig cfg;
  sensor_msgs::CameraInfo info[2];
  std::unique_ptr<StereoScene> scene;
  StereoFrame frame;
};

TEST_F(Output, OnlyWhatIsWantedStampedAndPooled)
{
  EyeOutput out(info[1], 85, 2);
  std::string error;
  EyeMessages m = out.produce(*scene, 1, frame, false, false, error);
  EXPECT_FALSE(m.image);
  EXPECT_FALSE(m.jpeg);
  m = out.produce(*scene, 1, frame, true, false, error);
  ASSERT_TRUE(m.image);
  EXPECT_FALSE(m.jpeg);
  EXPECT_EQ(m.image->header.stamp, frame.stamp);
  EXPECT_EQ(m.image->header.frame_id, kRight);
  EXPECT_EQ(m.image->data.size(), 320u * 180u * 3u);
  cv::Mat direct;
  scene->render(1, frame.pose[1], {}, direct);
  EXPECT_EQ(cv::norm(direct, cv::Mat(180, 320, CV_8UC3, m.image->data.data()), cv::NORM_INF), 0.0);
  m = out.produce(*scene, 1, frame, false, true, error);
  ASSERT_TRUE(m.jpeg);
  const cv::Mat decoded = cv::imdecode(m.jpeg->data, cv::IMREAD_COLOR);
  EXPECT_EQ(decoded.size(), cv::Size(320, 180));
  EXPECT_LT(cv::norm(decoded, direct, cv::NORM_L1) / decoded.total() / 3, 4.0);  // JPEG 85: a few grey levels
  EXPECT_EQ(out.cameraInfo(frame.stamp).header.stamp, frame.stamp);
  // steady state (each frame's messages held until the next is produced, as by a publisher queue
  // of 1): after both slots have their buffers, nothing is allocated
  for (int k = 0; k < 3; ++k)
    m = out.produce(*scene, 1, frame, true, true, error);
  const uint64_t before = out.allocations();
  for (int k = 0; k < 5; ++k)
    m = out.produce(*scene, 1, frame, true, true, error);
  EXPECT_EQ(out.allocations(), before);
  EXPECT_GT(before, 0u);  // the warm-up allocated: the counter counts
  EXPECT_TRUE(error.empty()) << error;
}

TEST_F(Output, TargetsAndBonesChangeTheScene)
{
  cv::Mat plain, board;
  scene->render(0, frame.pose[0], {}, plain);
  std::string error;
  EXPECT_FALSE(scene->selectTarget("grid", error));
  EXPECT_NE(error.find("unknown target 'grid'"), std::string::npos);
  ASSERT_TRUE(scene->selectTarget("checkerboard", error)) << error;
  scene->render(0, frame.pose[0], {}, board);
  EXPECT_GT(cv::norm(plain, board, cv::NORM_INF), 100.0);
  ASSERT_TRUE(scene->selectTarget("none", error));
  scene->render(0, frame.pose[0], {}, board);
  EXPECT_EQ(cv::norm(plain, board, cv::NORM_INF), 0.0);
  StereoScene with_bones(info, cfg, { { at(0, 0, 0).translation(), Eigen::Vector3d(0.01, 0, 0), Eigen::Vector3d(0.01, 0, 0.01),
                                        Eigen::Vector3d(0, 0, 0.01), Eigen::Vector3d(0, 0.01, 0), Eigen::Vector3d(0.01, 0.01, 0),
                                        Eigen::Vector3d(0.01, 0.01, 0.01), Eigen::Vector3d(0, 0.01, 0.01) } });
  EXPECT_TRUE(with_bones.bonesPending());
  Eigen::Isometry3d bad = at(0, 0, 0.1);
  bad.translation().x() = NAN;
  EXPECT_FALSE(with_bones.placeBones(bad, error));
  EXPECT_TRUE(with_bones.bonesPending());
  ASSERT_TRUE(with_bones.placeBones(at(-0.005, -0.005, 0.1), error)) << error;
  EXPECT_FALSE(with_bones.bonesPending());
  cv::Mat bones;
  with_bones.render(0, frame.pose[0], {}, bones);
  EXPECT_GT(cv::norm(plain, bones, cv::NORM_INF), 50.0);
}

int main(int argc, char** argv)
{
  ::testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
