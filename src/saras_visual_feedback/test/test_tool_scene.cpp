// ToolScene (freshness, interpolation at the stamp, unknown distances) and frame composition
// (placement through a transformer, fallbacks, failures, colour census).
#include <gtest/gtest.h>

#include <cmath>
#include <map>

#include "saras_visual_feedback/frame_composer.h"
#include "saras_visual_feedback/tool_scene.h"

using namespace saras_visual_feedback;  // NOLINT(build/namespaces) test file

namespace
{
constexpr std::int64_t kMs = 1000000;

std::vector<ToolConfig> tools()
{
  ToolConfig a;
  a.name = a.label = "a";
  a.pose_topic = "/a";
  a.rcm_frame = "a_rcm";
  a.distance_index = 0;
  ToolConfig b = a;
  b.name = b.label = "psm";
  b.rcm_frame = "";
  b.distance_index = 1;
  b.dvrk = true;
  return {a, b};
}

TimedPose pose(std::int64_t stamp_ns, double x)
{
  TimedPose p;
  p.stamp_ns = stamp_ns;
  p.position[0] = x;
  p.position[2] = 0.1;
  return p;
}

/// Frames related by pure translations; "late" frames exist only at the latest time.
class FakeTf : public PointTransformer
{
public:
  std::map<std::string, cv::Point3d> offset;  ///< source frame -> its origin in the camera frame
  std::map<std::string, bool> latest_only;
  bool transform(const std::string& /*target*/, const std::string& source, std::int64_t /*stamp_ns*/,
                 const cv::Point3d& p, cv::Point3d* out, bool* at_stamp, std::string* error) const override
  {
    auto it = offset.find(source);
    if (it == offset.end())
    {
      *error = "unknown frame " + source;
      return false;
    }
    *at_stamp = latest_only.count(source) == 0;
    *out = p + it->second;
    return true;
  }
};
}  // namespace

TEST(ToolScene, InterpolatesAtTheImageStampAndTimesOut)
{
  ToolScene scene(tools(), 16, 500 * kMs, 500 * kMs, SceneStyle());
  scene.addPose(0, "world", pose(1000 * kMs, 0.0), 1000 * kMs);
  scene.addPose(0, "world", pose(1020 * kMs, 0.02), 1020 * kMs);
  SceneSnapshot s;
  scene.snapshot(1030 * kMs, 1010 * kMs, &s);
  ASSERT_EQ(s.n, 2u);
  EXPECT_EQ(s.tools[0].pose.status, PoseLookup::kInterpolated);
  EXPECT_NEAR(s.tools[0].pose.pose.position[0], 0.01, 1e-12);
  EXPECT_EQ(s.tools[0].frame, "world");
  EXPECT_EQ(s.tools[1].pose.status, PoseLookup::kEmpty);  // never received
  EXPECT_TRUE(std::isnan(s.tools[0].distance));            // no distances yet
  scene.snapshot(1600 * kMs, 1010 * kMs, &s);               // 580 ms after the last pose
  EXPECT_EQ(s.tools[0].pose.status, PoseLookup::kEmpty);
}

TEST(ToolScene, DistancesFreshShortAndHiddenDvrk)
{
  ToolScene scene(tools(), 16, 500 * kMs, 500 * kMs, SceneStyle());
  EXPECT_FALSE(scene.setDistances({0.003}, 0));  // 2 needed
  EXPECT_EQ(scene.counters().rejected_distances, 1u);
  EXPECT_TRUE(scene.setDistances({0.003, -INFINITY}, 0));
  SceneSnapshot s;
  scene.snapshot(100 * kMs, kLatestStamp, &s);
  EXPECT_DOUBLE_EQ(s.tools[0].distance, 0.003);
  EXPECT_TRUE(std::isnan(s.tools[1].distance));  // -inf: unknown
  scene.snapshot(600 * kMs, kLatestStamp, &s);    // stale
  EXPECT_TRUE(std::isnan(s.tools[0].distance));
  SceneStyle style;
  style.draw_dvrk = false;
  scene.setStyle(style);
  scene.snapshot(0, kLatestStamp, &s);
  EXPECT_EQ(s.n, 1u);
}

TEST(FrameComposer, PlacesShaftCountsFallbacksAndFailures)
{
  ToolScene scene(tools(), 16, 500 * kMs, 500 * kMs, SceneStyle());
  scene.addPose(0, "world", pose(1000 * kMs, 0.0), 1000 * kMs);
  scene.addPose(1, "nowhere", pose(1000 * kMs, 0.0), 1000 * kMs);
  SceneSnapshot s;
  scene.snapshot(1000 * kMs, 1100 * kMs, &s);  // image 100 ms newer than the poses
  FakeTf tf;
  tf.offset["world"] = cv::Point3d(0, 0, 0);
  tf.offset["a_rcm"] = cv::Point3d(0, 0, 0.3);  // trocar 0.2 m behind the tip along z
  tf.latest_only["a_rcm"] = true;
  std::array<ToolOverlay, kMaxTools> o;
  FrameReport r;
  placeTools(s, "camera", 1100 * kMs, 30 * kMs, tf, o.data(), &r);
  ASSERT_EQ(r.n, 2u);
  EXPECT_TRUE(o[0].visible);
  EXPECT_TRUE(o[0].has_shaft);
  EXPECT_NEAR(o[0].shaft.z, 0.1 + 0.05, 1e-12);  // clipped to shaft_length 0.05 m
  EXPECT_TRUE(r.tools[0].pose_fallback);          // 100 ms > 30 ms tolerance
  EXPECT_EQ(r.tools[0].transform_fallbacks, 1);
  EXPECT_FALSE(o[1].visible);
  EXPECT_TRUE(r.tools[1].tip_failed);

  // Drawn in a 640x480 image: tool a (distance unknown) lands grey.
  cv::Mat canvas(480, 640, CV_8UC3, cv::Scalar::all(0));
  RawProjector cam;
  CameraIntrinsics k;
  k.width = 640;
  k.height = 480;
  k.fx = k.fy = 500;
  k.cx = 320;
  k.cy = 240;
  ASSERT_TRUE(cam.configure(k, nullptr));
  drawFrame(canvas, ChannelOrder::kBgr, &cam, "", s, o.data(), nullptr, &r);
  EXPECT_TRUE(r.overlay);
  EXPECT_EQ(r.drawn[0].drawn, ToolDrawn::kShaft);
  EyeStats stats;
  stats.record(r);
  EXPECT_EQ(stats.colour_frames[static_cast<int>(Proximity::kUnknown)].load(), 1u);
  EXPECT_EQ(stats.pose_fallbacks.load(), 2u);  // both tools' poses are 100 ms old
  EXPECT_EQ(stats.tf_failures.load(), 1u);

  // Without a camera model: nothing drawn, counted as no colour.
  drawFrame(canvas, ChannelOrder::kBgr, nullptr, "no calibration", s, o.data(), nullptr, &r);
  EXPECT_FALSE(r.overlay);
  EXPECT_EQ(r.drawn[0].drawn, ToolDrawn::kNothing);
}

int main(int argc, char** argv)
{
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
