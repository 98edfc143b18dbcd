/**
 * @file test_eye_capture.cpp
 * @brief EyeCapture on real GStreamer pipelines (videotestsrc, gstreamer1.0-plugins-base), no ROS:
 *        a live source delivers stamped frames; a broken pipeline is retried and reported, never
 *        thrown; a source that ends is reopened. Generous margins (busy 2-core CI).
 */
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "saras_drivers/eye_capture.h"

using namespace saras_drivers::capture;

namespace
{
double now()
{
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

struct Received
{
  std::mutex m;
  std::vector<double> stamps;
  int width = 0, height = 0, type = -1;
  std::vector<std::string> log;
};

EyeOptions options(const std::string& pipeline)
{
  EyeOptions o;
  o.source = resolveSource(pipeline);
  o.backoff_min = 0.1;
  o.backoff_max = 0.4;
  o.max_failed_grabs = 2;
  o.log_period = 0.0;
  return o;
}

/// Wait up to @p timeout [s] for @p done.
template <typename F>
bool waitFor(F done, double timeout)
{
  const double end = now() + timeout;
  while (now() < end)
  {
    if (done())
      return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  return done();
}

std::unique_ptr<EyeCapture> start(const std::string& pipeline, Received& r)
{
  return std::unique_ptr<EyeCapture>(new EyeCapture(
      options(pipeline), now,
      [&r](cv::Mat& f, double t) {
        std::lock_guard<std::mutex> lock(r.m);
        r.stamps.push_back(t);
        r.width = f.cols;
        r.height = f.rows;
        r.type = f.type();
      },
      [&r](const std::string& line) {
        std::lock_guard<std::mutex> lock(r.m);
        r.log.push_back(line);
      }));
}
}  // namespace

TEST(EyeCapture, LiveTestSourceDeliversStampedFrames)
{
  Received r;
  const double t0 = now();
  auto eye = start("videotestsrc pattern=ball is-live=true ! video/x-raw,width=160,height=120,framerate=30/1", r);
  ASSERT_TRUE(waitFor([&] { return eye->status().frames >= 15; }, 20.0)) << eye->status().error;
  const EyeStatus s = eye->status();
  eye.reset();
  EXPECT_EQ(s.failed_grabs, 0u);
  EXPECT_EQ(s.open_failures, 0u);
  std::lock_guard<std::mutex> lock(r.m);
  EXPECT_EQ(r.width, 160);
  EXPECT_EQ(r.height, 120);
  EXPECT_EQ(r.type, CV_8UC3);
  ASSERT_GE(r.stamps.size(), 15u);
  for (std::size_t i = 1; i < r.stamps.size(); ++i)
    EXPECT_GT(r.stamps[i], r.stamps[i - 1]);
  EXPECT_GE(r.stamps.front(), t0);
  // live source: frames come at its rate, not as fast as possible (30 Hz +- generous margin)
  const double rate = (r.stamps.size() - 1) / (r.stamps.back() - r.stamps.front());
  EXPECT_LT(rate, 60.0);
  EXPECT_GT(rate, 10.0);
}

TEST(EyeCapture, BrokenPipelineIsRetriedAndReported)
{
  Received r;
  auto eye = start("nosuchelement_saras ! videoconvert ! appsink", r);
  ASSERT_TRUE(waitFor([&] { return eye->status().open_failures >= 2; }, 20.0))
      << "open " << eye->status().open << " failures " << eye->status().open_failures << " frames " << eye->status().frames
      << " failed grabs " << eye->status().failed_grabs << " error " << eye->status().error;
  const EyeStatus s = eye->status();
  EXPECT_FALSE(s.open);
  EXPECT_EQ(s.frames, 0u);
  EXPECT_NE(s.error.find("cannot open"), std::string::npos) << s.error;
  const double t = now();
  eye.reset();  // stops promptly (the thread sleeps in its back-off)
  EXPECT_LT(now() - t, 2.5);
  std::lock_guard<std::mutex> lock(r.m);
  ASSERT_FALSE(r.log.empty());
  EXPECT_NE(r.log.front().find("left camera: cannot open 'nosuchelement_saras"), std::string::npos) << r.log.front();
  EXPECT_NE(r.log.front().find("nosuchelement_saras\""), std::string::npos) << r.log.front();  // GStreamer's reason
}

TEST(CheckPipeline, NamesTheMissingElement)
{
  EXPECT_EQ(checkPipeline("videotestsrc ! videoconvert ! appsink"), "");
  EXPECT_NE(checkPipeline("nosuchelement_saras ! appsink").find("nosuchelement_saras"), std::string::npos);
  EXPECT_NE(checkPipeline("videotestsrc ! ! appsink"), "");
}

TEST(EyeCapture, SourceThatEndsIsReopened)
{
  Received r;
  auto eye = start("videotestsrc num-buffers=5 ! video/x-raw,width=64,height=48,framerate=30/1", r);
  ASSERT_TRUE(waitFor([&] { return eye->status().reopens >= 1 && eye->status().frames >= 8; }, 30.0))
      << "frames " << eye->status().frames << " reopens " << eye->status().reopens;
  EXPECT_GE(eye->status().failed_grabs, 2u);
  std::lock_guard<std::mutex> lock(r.m);
  bool reported = false;
  for (const std::string& l : r.log)
    reported = reported || l.find("stopped delivering frames") != std::string::npos;
  EXPECT_TRUE(reported);
}

TEST(EyeCapture, NoSinkCallAfterDestruction)
{
  std::atomic<int> calls{ 0 };
  std::atomic<bool> destroyed{ false };
  std::atomic<int> late{ 0 };
  {
    EyeCapture eye(options("videotestsrc is-live=true ! video/x-raw,width=64,height=48,framerate=60/1"), now,
                   [&](cv::Mat&, double) {
                     ++calls;
                     if (destroyed)
                       ++late;
                   },
                   nullptr);
    waitFor([&] { return calls >= 3; }, 20.0);
  }
  destroyed = true;
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  EXPECT_GE(calls.load(), 3);
  EXPECT_EQ(late.load(), 0);
}
