/**
 * @file test_capture_core.cpp
 * @brief Capture core without ROS or cameras: source strings, Decklink pipeline, stamps, encodings,
 *        stereo pairing by time (pairs, common stamp, drops counted), back-off, health levels.
 */
#include <gtest/gtest.h>

#include <stdexcept>
#include <string>

#include <opencv2/core.hpp>

#include "saras_drivers/capture_core.h"
#include "saras_drivers/eye_capture.h"

using namespace saras_drivers::capture;

TEST(ResolveSource, V4l2DeviceByPathOrIndex)
{
  VideoSource s = resolveSource("/dev/video2");
  EXPECT_EQ(s.kind, SourceKind::V4L2_DEVICE);
  EXPECT_EQ(s.device_index, 2);
  EXPECT_EQ(s.open_string, "/dev/video2");
  s = resolveSource(" 0 ");
  EXPECT_EQ(s.kind, SourceKind::V4L2_DEVICE);
  EXPECT_EQ(s.device_index, 0);
  EXPECT_EQ(s.open_string, "/dev/video0");
}

TEST(ResolveSource, GstreamerPipelineKeptWhenItEndsInAppsink)
{
  const std::string p = "videotestsrc is-live=true ! videoconvert ! appsink drop=true";
  const VideoSource s = resolveSource(p);
  EXPECT_EQ(s.kind, SourceKind::GSTREAMER);
  EXPECT_EQ(s.open_string, p);
  EXPECT_EQ(resolveSource("videotestsrc ! appsink").open_string, "videotestsrc ! appsink");
}

TEST(ResolveSource, GstreamerPipelineGetsAnAppsink)
{
  const VideoSource s = resolveSource("videotestsrc ! video/x-raw,width=64,height=48");
  EXPECT_EQ(s.kind, SourceKind::GSTREAMER);
  EXPECT_EQ(s.open_string, std::string("videotestsrc ! video/x-raw,width=64,height=48 ! videoconvert ! ") + kAppSink);
  // an element merely named like an appsink is not one
  EXPECT_NE(resolveSource("videotestsrc ! appsinkx").open_string, "videotestsrc ! appsinkx");
}

TEST(ResolveSource, FileAndEmpty)
{
  EXPECT_EQ(resolveSource("/data/left.mp4").kind, SourceKind::FILE_OR_URL);
  EXPECT_EQ(resolveSource("/dev/video").kind, SourceKind::FILE_OR_URL);
  EXPECT_THROW(resolveSource("  "), std::invalid_argument);
  EXPECT_THROW(resolveSource(""), std::invalid_argument);
}

TEST(DecklinkPipeline, ProductionString)
{
  EXPECT_EQ(decklinkPipeline(0), std::string("decklinkvideosrc device-number=0 ! videoconvert ! ") + kAppSink);
  EXPECT_EQ(decklinkPipeline(1, "1080i5994", "sdi"),
            std::string("decklinkvideosrc device-number=1 mode=1080i5994 connection=sdi ! videoconvert ! ") + kAppSink);
  EXPECT_EQ(resolveSource(decklinkPipeline(1)).kind, SourceKind::GSTREAMER);
  EXPECT_EQ(resolveSource(decklinkPipeline(1)).open_string, decklinkPipeline(1));
  EXPECT_THROW(decklinkPipeline(-1), std::invalid_argument);
  const VideoSource s = resolveSource("decklink:1");  // the launch files' short form
  EXPECT_EQ(s.kind, SourceKind::GSTREAMER);
  EXPECT_EQ(s.open_string, decklinkPipeline(1));
  EXPECT_EQ(resolveSource("decklink:x").kind, SourceKind::FILE_OR_URL);
}

TEST(CaptureStamp, GrabMinusLatency)
{
  EXPECT_DOUBLE_EQ(captureStamp(100.0, 0.04), 99.96);
  EXPECT_DOUBLE_EQ(captureStamp(100.0, 0.0), 100.0);
}

TEST(EncodingOf, CommonTypes)
{
  EXPECT_EQ(encodingOf(CV_8UC3), "bgr8");
  EXPECT_EQ(encodingOf(CV_8UC1), "mono8");
  EXPECT_EQ(encodingOf(CV_8UC4), "bgra8");
  EXPECT_EQ(encodingOf(CV_16UC1), "mono16");
  EXPECT_EQ(encodingOf(CV_32FC3), "");
}

TEST(StereoPairer, SynchronisedEyesPairEveryFrameWithTheMeanStamp)
{
  StereoPairer<int> p(0.010, 3);
  StereoPairer<int>::Pair out;
  for (int i = 0; i < 10; ++i)
  {
    const double t = 1.0 + i / 30.0;
    EXPECT_FALSE(p.push(0, t, 100 + i, out));
    ASSERT_TRUE(p.push(1, t + 0.002, 200 + i, out));
    EXPECT_DOUBLE_EQ(out.stamp, t + 0.001);
    EXPECT_EQ(out.frame[0], 100 + i);
    EXPECT_EQ(out.frame[1], 200 + i);
  }
  EXPECT_EQ(p.counters().pairs, 10u);
  EXPECT_EQ(p.counters().unmatched[0] + p.counters().unmatched[1], 0u);
  EXPECT_EQ(p.counters().frames[0], 10u);
}

TEST(StereoPairer, RightBeforeLeftPairsToo)
{
  StereoPairer<int> p(0.010, 3);
  StereoPairer<int>::Pair out;
  EXPECT_FALSE(p.push(1, 2.000, 7, out));
  ASSERT_TRUE(p.push(0, 2.004, 3, out));
  EXPECT_EQ(out.frame[0], 3);
  EXPECT_EQ(out.frame[1], 7);
  EXPECT_DOUBLE_EQ(out.stamp, 2.002);
}

TEST(StereoPairer, FramesOutsideTheToleranceAreDroppedAndCounted)
{
  StereoPairer<int> p(0.010, 3);
  StereoPairer<int>::Pair out;
  EXPECT_FALSE(p.push(0, 1.000, 1, out));
  EXPECT_FALSE(p.push(1, 1.020, 2, out));  // too far: left 1.000 can never match now
  EXPECT_EQ(p.counters().unmatched[0], 1u);
  EXPECT_FALSE(p.push(0, 1.040, 3, out));  // too far from right 1.020: it is dropped
  EXPECT_EQ(p.counters().unmatched[1], 1u);
  ASSERT_TRUE(p.push(1, 1.041, 4, out));
  EXPECT_EQ(out.frame[0], 3);
  EXPECT_EQ(p.counters().pairs, 1u);
}

TEST(StereoPairer, LostFrameOfOneEyeDropsOnlyItsPartner)
{
  StereoPairer<int> p(0.005, 3);
  StereoPairer<int>::Pair out;
  int pairs = 0;
  for (int i = 0; i < 30; ++i)
  {
    const double t = i / 30.0;
    pairs += p.push(0, t, i, out) ? 1 : 0;
    if (i != 10)  // the right eye loses frame 10
      pairs += p.push(1, t + 0.001, i, out) ? 1 : 0;
  }
  EXPECT_EQ(pairs, 29);
  EXPECT_EQ(p.counters().unmatched[0], 1u);
  EXPECT_EQ(p.counters().unmatched[1], 0u);
}

TEST(StereoPairer, NearestWaitingFrameWinsAndOlderOnesAreDropped)
{
  StereoPairer<int> p(0.030, 5);
  StereoPairer<int>::Pair out;
  EXPECT_FALSE(p.push(0, 1.000, 1, out));
  EXPECT_FALSE(p.push(0, 1.020, 2, out));
  ASSERT_TRUE(p.push(1, 1.021, 9, out));
  EXPECT_EQ(out.frame[0], 2);
  EXPECT_EQ(p.counters().unmatched[0], 1u);
}

TEST(StereoPairer, QueueDepthBoundsTheWaitingFrames)
{
  StereoPairer<int> p(0.010, 2);
  StereoPairer<int>::Pair out;
  for (int i = 0; i < 5; ++i)
    EXPECT_FALSE(p.push(0, 1.0 + i * 0.001, i, out));  // the right eye is silent
  EXPECT_EQ(p.counters().unmatched[0], 3u);
  p.flush(0);
  EXPECT_EQ(p.counters().unmatched[0], 5u);
  EXPECT_FALSE(p.push(1, 1.004, 0, out));  // nothing left to pair with
}

TEST(Backoff, DoublesUpToMaxAndResets)
{
  Backoff b(0.5, 3.0);
  EXPECT_DOUBLE_EQ(b.next(), 0.5);
  EXPECT_DOUBLE_EQ(b.next(), 1.0);
  EXPECT_DOUBLE_EQ(b.next(), 2.0);
  EXPECT_DOUBLE_EQ(b.next(), 3.0);
  EXPECT_DOUBLE_EQ(b.next(), 3.0);
  b.reset();
  EXPECT_DOUBLE_EQ(b.next(), 0.5);
}

TEST(ThrottledLog, OneLinePerPeriodWithTheHeldBackCount)
{
  ThrottledLog log(5.0);
  EXPECT_EQ(log.filter("a", 0.0), "a");
  EXPECT_EQ(log.filter("a", 1.0), "");
  EXPECT_EQ(log.filter("a", 2.0), "");
  EXPECT_EQ(log.filter("b", 5.5), "b (2 similar messages not shown)");
}

namespace
{
EyeStatus running(double last, int w = 640, int h = 360)
{
  EyeStatus s;
  s.open = true;
  s.frames = 10;
  s.last_frame = last;
  s.width = w;
  s.height = h;
  return s;
}
}  // namespace

TEST(AssessHealth, Levels)
{
  const int calib[2][2] = { { 640, 360 }, { 640, 360 } };
  EyeStatus eyes[2] = { running(9.9), running(9.95) };
  EXPECT_EQ(assessHealth(eyes, calib, 10.0, 0.0, 2.0).level, Level::OK);
  eyes[1].open = false;
  eyes[1].error = "cannot open 'x'";
  Health h = assessHealth(eyes, calib, 10.0, 0.0, 2.0);
  EXPECT_EQ(h.level, Level::ERROR);
  EXPECT_NE(h.message.find("right camera not open: cannot open 'x'"), std::string::npos) << h.message;
  eyes[1] = running(7.0);  // stalled
  h = assessHealth(eyes, calib, 10.0, 0.0, 2.0);
  EXPECT_EQ(h.level, Level::ERROR);
  EXPECT_NE(h.message.find("right camera delivers no frames"), std::string::npos) << h.message;
  eyes[1] = running(-1.0);  // open, nothing yet: fine during the first stall_timeout
  EXPECT_EQ(assessHealth(eyes, calib, 1.0, 0.0, 2.0).level, Level::OK);
  EXPECT_EQ(assessHealth(eyes, calib, 3.0, 0.0, 2.0).level, Level::ERROR);
  eyes[1] = running(9.95, 1280, 720);
  h = assessHealth(eyes, calib, 10.0, 0.0, 2.0);
  EXPECT_EQ(h.level, Level::WARN);
  EXPECT_NE(h.message.find("right frames 1280x720 but calibrated at 640x360"), std::string::npos) << h.message;
  const int unknown[2][2] = { { 0, 0 }, { 0, 0 } };
  EXPECT_EQ(assessHealth(eyes, unknown, 10.0, 0.0, 2.0).level, Level::OK);
}

int main(int argc, char** argv)
{
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
