// Benchmark driver for saras_visual_feedback (run through bench/run; not a test).
//
//   visual_feedback_bench core [iterations]
//       Per-frame cost of the core (input copy + projection + drawing) at 1280x720 and 1920x1080,
//       stereo (both eyes), no ROS.
//   visual_feedback_bench pipeline <seconds> <rate_hz> <width> <height>
//       Loads the VisualFeedback nodelet in this process (as in a shared nodelet manager, zero
//       copy), publishes a simulated stereo endoscope at <rate_hz>, counts frames in and out and
//       the latency from the image stamp to the augmented image's arrival (the counter is an
//       intra-process subscriber: the same zero-copy path as a viewer nodelet in the manager).
//       Drops are split into the nodelet's input queue and after it. Needs a ROS master.
//   visual_feedback_bench pipeline-remote <seconds> <rate_hz> <width> <height>
//       The same, but the augmented images are counted by `count` in another process (roscpp
//       serialises every frame for it inside the nodelet's publish()).
//   visual_feedback_bench count [timeout_s]
//       That remote viewer: counts /visual_feedback/{left,right}/image and prints a line.
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <mutex>
#include <string>
#include <vector>

#include <geometry_msgs/PoseStamped.h>
#include <geometry_msgs/TransformStamped.h>
#include <nodelet/loader.h>
#include <ros/ros.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <std_msgs/Float64MultiArray.h>
#include <tf2_ros/static_transform_broadcaster.h>

#include <diagnostic_msgs/DiagnosticArray.h>
#include <image_geometry/pinhole_camera_model.h>

#include <saras_common/message_pool.h>
#include "saras_visual_feedback/overlay.h"
#include "saras_visual_feedback/pose_history.h"

using namespace saras_visual_feedback;  // NOLINT(build/namespaces) benchmark driver

namespace
{
/// CPU time of the calling thread [ms]: the cost without the preemption of a shared machine.
double threadCpuMs()
{
  timespec ts;
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return ts.tv_sec * 1e3 + ts.tv_nsec * 1e-6;
}

CameraIntrinsics intrinsics(int w, int h)
{
  CameraIntrinsics k;
  k.width = w;
  k.height = h;
  k.fx = k.fy = 0.82 * w;
  k.cx = 0.5 * w + 3.1;
  k.cy = 0.5 * h - 2.7;
  k.model = DistortionModel::kPlumbBob;
  k.d = {-0.28, 0.11, 0.0012, -0.0007, -0.021, 0, 0, 0};
  return k;
}

struct Stats
{
  std::vector<double> v;
  double mean() const
  {
    double s = 0;
    for (double x : v)
      s += x;
    return v.empty() ? 0.0 : s / v.size();
  }
  double pct(double p)
  {
    if (v.empty())
      return 0.0;
    std::sort(v.begin(), v.end());
    return v[std::min(v.size() - 1, static_cast<std::size_t>(p * (v.size() - 1) + 0.5))];
  }
};

/// Projection of one tool (tip + 8 shaft segments) into the raw image: RawProjector (one
/// cv::projectPoints call) against image_geometry's point API (project3dToPixel + unrectifyPoint,
/// per point; valid for a monocular camera only). The overlay's hot path is 4 tools per eye.
void runProjection()
{
  const CameraIntrinsics k = intrinsics(1920, 1080);
  RawProjector raw;
  raw.configure(k, nullptr);
  sensor_msgs::CameraInfo info;
  info.width = 1920;
  info.height = 1080;
  info.distortion_model = "plumb_bob";
  info.D.assign(k.d.begin(), k.d.begin() + 5);
  info.K = {k.fx, 0, k.cx, 0, k.fy, k.cy, 0, 0, 1};
  info.R = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  info.P = {k.fx, 0, k.cx, 0, 0, k.fy, k.cy, 0, 0, 0, 1, 0};
  image_geometry::PinholeCameraModel ig;
  ig.fromCameraInfo(info);
  cv::Point3d pts[9];
  for (int i = 0; i < 9; ++i)
    pts[i] = cv::Point3d(0.01 + 0.002 * i, -0.005, 0.1 + 0.005 * i);
  Projection out[9];
  const int n = 20000;
  double sink = 0.0;
  auto t0 = std::chrono::steady_clock::now();
  for (int r = 0; r < n; ++r)
  {
    raw.project(pts, 9, out);
    sink += out[8].pixel.x;
  }
  const double raw_us = std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0).count() / n;
  t0 = std::chrono::steady_clock::now();
  for (int r = 0; r < n; ++r)
    for (const cv::Point3d& p : pts)
      sink += ig.unrectifyPoint(ig.project3dToPixel(p)).x;
  const double ig_us = std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0).count() / n;
  std::printf("projection of one tool (9 points): RawProjector %.2f us, image_geometry point API %.2f us "
              "(checksum %.0f)\n\n",
              raw_us, ig_us, sink);
}

int runCore(int iterations)
{
  runProjection();
  std::printf("wall-clock times, except cpu/frame = CPU time of the thread (immune to preemption)\n");
  std::printf("%-10s %-14s %10s %10s %10s %10s\n", "image", "unit", "mean_ms", "p50_ms", "p99_ms", "max_ms");
  const int sizes[2][2] = {{1280, 720}, {1920, 1080}};
  for (const auto& sz : sizes)
  {
    RawProjector eye[2];
    eye[0].configure(intrinsics(sz[0], sz[1]), nullptr);
    eye[1].configure(intrinsics(sz[0], sz[1]), nullptr);
    cv::Mat input(sz[1], sz[0], CV_8UC3);
    cv::randu(input, 0, 255);
    cv::Mat out[2] = {cv::Mat(sz[1], sz[0], CV_8UC3), cv::Mat(sz[1], sz[0], CV_8UC3)};  // pooled buffers
    OverlayStyle style;
    ToolOverlay tools[4];
    const char* labels[4] = {"mesa_left", "mesa_right", "PSM1", "PSM2"};
    Stats copy, draw, per_eye, per_pair, cpu_eye;
    HudCache hud[2];
    // Each tool's pose history (512 samples at 250 Hz, as the nodelet keeps): the tips are looked
    // up at the image stamp, 50 ms behind the newest pose, inside the timed section.
    PoseHistory history[4];
    const std::int64_t kPosePeriod = 4000000;  // [ns] 250 Hz
    for (std::int64_t j = 0; j < 512; ++j)
      for (int i = 0; i < 4; ++i)
      {
        TimedPose p;
        p.stamp_ns = j * kPosePeriod;
        p.position[0] = -0.03 + 0.02 * i + 0.005 * std::sin(1e-9 * p.stamp_ns);
        p.position[1] = 0.01 * std::cos(1e-9 * p.stamp_ns + i);
        p.position[2] = 0.1;
        history[i].push(p);
      }
    for (int it = 0; it < iterations; ++it)
    {
      const double phase = 0.05 * it;
      for (int i = 0; i < 4; ++i)
      {
        tools[i].label = labels[i];
        tools[i].visible = true;
        tools[i].tip = cv::Point3d(-0.03 + 0.02 * i + 0.005 * std::sin(phase), 0.01 * std::cos(phase + i), 0.1);
        tools[i].has_shaft = true;
        tools[i].shaft = tools[i].tip + cv::Point3d(0.02, -0.03, 0.035);
        tools[i].distance = 0.001 + 0.01 * i + 0.0001 * (it / 3);  // HUD text changes at 20 Hz, as the distances
      }
      tools[3].tip.x = 0.4;  // one out of view: border marker
      const auto p0 = std::chrono::steady_clock::now();
      for (int e = 0; e < 2; ++e)
      {
        const double c0 = threadCpuMs();
        const auto t0 = std::chrono::steady_clock::now();
        input.copyTo(out[e]);  // the nodelet's one memcpy into a pooled output buffer
        const auto t1 = std::chrono::steady_clock::now();
        const std::int64_t image_stamp = 511 * kPosePeriod - 50000000 + (it % 97) * 123457;
        for (int i = 0; i < 4; ++i)
        {
          const PoseLookupResult r = history[i].lookup(image_stamp);
          tools[i].tip.x = r.pose.position[0];
          tools[i].shaft = tools[i].tip + cv::Point3d(0.02, -0.03, 0.035);
        }
        tools[3].tip.x = 0.4;
        drawOverlay(out[e], ChannelOrder::kBgr, eye[e], style, tools, 4, nullptr, nullptr, &hud[e]);
        const auto t2 = std::chrono::steady_clock::now();
        cpu_eye.v.push_back(threadCpuMs() - c0);
        copy.v.push_back(std::chrono::duration<double, std::milli>(t1 - t0).count());
        draw.v.push_back(std::chrono::duration<double, std::milli>(t2 - t1).count());
        per_eye.v.push_back(std::chrono::duration<double, std::milli>(t2 - t0).count());
      }
      per_pair.v.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - p0).count());
    }
    char name[32];
    std::snprintf(name, sizeof(name), "%dx%d", sz[0], sz[1]);
    Stats* rows[5] = {&copy, &draw, &per_eye, &cpu_eye, &per_pair};
    const char* units[5] = {"copy/frame", "draw/frame", "total/frame", "cpu/frame", "total/stereo"};
    for (int i = 0; i < 5; ++i)
      std::printf("%-10s %-14s %10.3f %10.3f %10.3f %10.3f\n", name, units[i], rows[i]->mean(), rows[i]->pct(0.5),
                  rows[i]->pct(0.99), rows[i]->pct(1.0));
  }
  return 0;
}

class Pipeline
{
public:
  /// @p count_outputs: subscribe the augmented images in this process (intra-process, zero
  /// copy, as a viewer nodelet in the same manager); false when a separate process counts them.
  Pipeline(int w, int h, bool count_outputs) : w_(w), h_(h), count_outputs_(count_outputs)
  {
    ros::NodeHandle nh;
    for (int e = 0; e < 2; ++e)
    {
      const std::string eye = e == 0 ? "left" : "right";
      image_pub_[e] = nh.advertise<sensor_msgs::Image>("/endoscope/" + eye + "/image_raw", 2);
      info_pub_[e] = nh.advertise<sensor_msgs::CameraInfo>("/endoscope/" + eye + "/camera_info", 2);
      if (count_outputs_)
        out_sub_[e] = nh.subscribe<sensor_msgs::Image>("/visual_feedback/" + eye + "/image", 10,
                                                       [this, e](const sensor_msgs::ImageConstPtr& m) { onOut(m, e); });
      const CameraIntrinsics k = intrinsics(w, h);
      info_[e].header.frame_id = "endoscope/" + eye + "_optical_frame";
      info_[e].width = w;
      info_[e].height = h;
      info_[e].distortion_model = "plumb_bob";
      info_[e].D.assign(k.d.begin(), k.d.begin() + 5);
      info_[e].K = {k.fx, 0, k.cx, 0, k.fy, k.cy, 0, 0, 1};
      info_[e].R = {1, 0, 0, 0, 1, 0, 0, 0, 1};
      info_[e].P = {k.fx, 0, k.cx, 0, 0, k.fy, k.cy, 0, 0, 0, 1, 0};
    }
    pose_pub_[0] = nh.advertise<geometry_msgs::PoseStamped>("/mesa_left/ee_pose", 1);
    pose_pub_[1] = nh.advertise<geometry_msgs::PoseStamped>("/mesa_right/ee_pose", 1);
    dist_pub_ = nh.advertise<std_msgs::Float64MultiArray>("/collision/distances", 1);
    status_sub_ = nh.subscribe<diagnostic_msgs::DiagnosticArray>(
        "/diagnostics", 10, [this](const diagnostic_msgs::DiagnosticArrayConstPtr& m) {
          std::lock_guard<std::mutex> lock(mutex_);
          for (const diagnostic_msgs::DiagnosticStatus& st : m->status)
            if (st.name.rfind("bench_vf:", 0) == 0)
            {
              status_.clear();
              for (const diagnostic_msgs::KeyValue& kv : st.values)
                if (kv.key.find("frames in") != std::string::npos || kv.key.find("[ms]") != std::string::npos)
                  status_ += kv.key + ": " + kv.value + "; ";
              status_stamp_ = ros::WallTime::now();
            }
        });
    // Tools' frames 10 cm in front of the cameras.
    std::vector<geometry_msgs::TransformStamped> tfs;
    const char* parents[4] = {"endoscope/left_optical_frame", "endoscope/left_optical_frame",
                              "endoscope/left_optical_frame", "endoscope/left_optical_frame"};
    const char* children[4] = {"bench/tools", "mesa_left/rcm", "mesa_right/rcm", "endoscope/right_optical_frame"};
    const double xyz[4][3] = {{0, 0, 0.1}, {-0.03, -0.04, 0.06}, {0.03, -0.04, 0.06}, {0.005, 0, 0}};
    for (int i = 0; i < 4; ++i)
    {
      geometry_msgs::TransformStamped t;
      t.header.frame_id = parents[i];
      t.child_frame_id = children[i];
      t.transform.translation.x = xyz[i][0];
      t.transform.translation.y = xyz[i][1];
      t.transform.translation.z = xyz[i][2];
      t.transform.rotation.w = 1.0;
      tfs.push_back(t);
    }
    static_tf_.sendTransform(tfs);
  }

  void onOut(const sensor_msgs::ImageConstPtr& m, int e)
  {
    const double latency_ms = (ros::Time::now() - m->header.stamp).toSec() * 1e3;
    std::lock_guard<std::mutex> lock(mutex_);
    ++out_[e];
    latency_.v.push_back(latency_ms);
  }

  /// Tool poses (every frame, stamped now); the distances only when @p distances (20 Hz as
  /// /collision/distances: they change the HUD text, which is re-rendered on change).
  void publishAuxiliary(double t, bool distances)
  {
    for (int s = 0; s < 2; ++s)
    {
      geometry_msgs::PoseStamped p;
      p.header.stamp = ros::Time::now();
      p.header.frame_id = "bench/tools";
      p.pose.position.x = (s == 0 ? -0.02 : 0.02) + 0.01 * std::sin(t);
      p.pose.position.y = 0.005 * std::cos(t);
      p.pose.orientation.w = 1.0;
      pose_pub_[s].publish(p);
    }
    if (!distances)
      return;
    std_msgs::Float64MultiArray d;
    d.data = {0.015 + 0.015 * std::sin(t), 0.015 + 0.015 * std::cos(t), 0.05, 0.05};
    dist_pub_.publish(d);
  }

  void publishFrame()
  {
    const ros::Time stamp = ros::Time::now();
    for (int e = 0; e < 2; ++e)
    {
      // Pooled input buffers: the publisher's cost is not what is measured here.
      sensor_msgs::ImagePtr img = input_pool_[e].nextWithData(static_cast<std::size_t>(3 * w_) * h_);
      img->header.stamp = stamp;
      img->header.frame_id = info_[e].header.frame_id;
      img->width = w_;
      img->height = h_;
      img->encoding = "bgr8";
      img->step = 3 * w_;
      sensor_msgs::CameraInfoPtr info(new sensor_msgs::CameraInfo(info_[e]));
      info->header.stamp = stamp;
      info_pub_[e].publish(info);
      image_pub_[e].publish(img);
      ++in_[e];
    }
  }

  bool subscribed() const
  {
    // The nodelet subscribes its inputs only once its outputs have subscribers (lazy).
    return image_pub_[0].getNumSubscribers() > 0 && image_pub_[1].getNumSubscribers() > 0 &&
           (!count_outputs_ || (out_sub_[0].getNumPublishers() > 0 && out_sub_[1].getNumPublishers() > 0));
  }

  /// Waits (up to @p timeout s) for a heartbeat sent after @p since: its counts are final.
  void waitForHeartbeat(const ros::WallTime& since, double timeout)
  {
    const ros::WallTime until = ros::WallTime::now() + ros::WallDuration(timeout);
    while (ros::WallTime::now() < until)
    {
      {
        std::lock_guard<std::mutex> lock(mutex_);
        if (status_stamp_ > since)
          return;
      }
      ros::WallDuration(0.05).sleep();
    }
  }

  void report(double seconds, double rate)
  {
    std::lock_guard<std::mutex> lock(mutex_);
    char name[32];
    std::snprintf(name, sizeof(name), "%dx%d", w_, h_);
    // Frames the nodelet took from its input queues, per eye, from /diagnostics ("left frames in: N").
    long long taken[2] = {-1, -1};
    const char* eyes[2] = {"left frames in: ", "right frames in: "};
    for (int e = 0; e < 2; ++e)
    {
      const std::size_t at = status_.find(eyes[e]);
      if (at != std::string::npos)
        taken[e] = std::atoll(status_.c_str() + at + std::strlen(eyes[e]));
    }
    if (count_outputs_)
    {
      std::printf("%-10s %6s %6s %8s %8s %8s %8s %12s %12s %12s\n", "image", "rate", "secs", "in_L", "out_L", "in_R",
                  "out_R", "lat_mean_ms", "lat_p99_ms", "lat_max_ms");
      std::printf("%-10s %6.1f %6.1f %8llu %8llu %8llu %8llu %12.3f %12.3f %12.3f\n", name, rate, seconds,
                  static_cast<unsigned long long>(in_[0]), static_cast<unsigned long long>(out_[0]),
                  static_cast<unsigned long long>(in_[1]), static_cast<unsigned long long>(out_[1]), latency_.mean(),
                  latency_.pct(0.99), latency_.pct(1.0));
    }
    else
      std::printf("%-10s %6.1f Hz %6.1f s: published %llu left, %llu right (outputs counted by the remote "
                  "process below)\n",
                  name, rate, seconds, static_cast<unsigned long long>(in_[0]),
                  static_cast<unsigned long long>(in_[1]));
    std::printf("nodelet per-frame cost (/diagnostics): %s\n", status_.c_str());
    // Where frames were lost: before the nodelet's callback (subscription/synchroniser queues
    // overflowing while it is stalled) or after it (the viewer's queue).
    for (int e = 0; e < 2; ++e)
    {
      if (taken[e] < 0)
      {
        std::printf("drops %s: no heartbeat\n", e == 0 ? "left" : "right");
        continue;
      }
      const long long in = static_cast<long long>(in_[e]);
      if (count_outputs_)
        std::printf("drops %-5s: %lld (%lld in the nodelet's input queue, %lld after it)\n", e == 0 ? "left" : "right",
                    in - static_cast<long long>(out_[e]), in - taken[e], taken[e] - static_cast<long long>(out_[e]));
      else
        std::printf("drops %-5s: %lld in the nodelet's input queue\n", e == 0 ? "left" : "right", in - taken[e]);
    }
  }

private:
  int w_, h_;
  ros::Publisher image_pub_[2], info_pub_[2], pose_pub_[2], dist_pub_;
  ros::Subscriber out_sub_[2], status_sub_;
  saras_common::MessagePool<sensor_msgs::Image> input_pool_[2]{saras_common::MessagePool<sensor_msgs::Image>(6),
                                                              saras_common::MessagePool<sensor_msgs::Image>(6)};
  bool count_outputs_;
  std::string status_;
  ros::WallTime status_stamp_;
  sensor_msgs::CameraInfo info_[2];
  tf2_ros::StaticTransformBroadcaster static_tf_;
  std::mutex mutex_;
  std::uint64_t in_[2] = {0, 0}, out_[2] = {0, 0};
  Stats latency_;
};

int runPipeline(int argc, char** argv, bool count_outputs)
{
  const double seconds = argc > 2 ? std::atof(argv[2]) : 60.0;
  const double rate = argc > 3 ? std::atof(argv[3]) : 60.0;
  const int w = argc > 4 ? std::atoi(argv[4]) : 1920;
  const int h = argc > 5 ? std::atoi(argv[5]) : 1080;
  ros::init(argc, argv, "visual_feedback_bench", ros::init_options::AnonymousName);
  ros::AsyncSpinner spinner(2);
  spinner.start();
  Pipeline pipe(w, h, count_outputs);
  // The heartbeat keeps its per-frame counts for a while after the last frame (the bench reads
  // the final counts from it); everything else at its default.
  ros::param::set("/bench_vf/image_timeout", 10.0);
  nodelet::Loader loader(false);
  nodelet::M_string remap;
  remap["/left/image_raw"] = "/endoscope/left/image_raw";
  remap["/right/image_raw"] = "/endoscope/right/image_raw";
  remap["/left/camera_info"] = "/endoscope/left/camera_info";
  remap["/right/camera_info"] = "/endoscope/right/camera_info";
  remap["/left/image"] = "/visual_feedback/left/image";
  remap["/right/image"] = "/visual_feedback/right/image";
  remap["/distances"] = "/collision/distances";
  if (!loader.load("/bench_vf", "saras_visual_feedback/VisualFeedback", remap, nodelet::V_string()))
  {
    std::fprintf(stderr, "cannot load the VisualFeedback nodelet\n");
    return 1;
  }
  const ros::WallTime wait_until = ros::WallTime::now() + ros::WallDuration(10.0);
  while (!pipe.subscribed() && ros::WallTime::now() < wait_until)
    ros::WallDuration(0.05).sleep();
  if (!pipe.subscribed())
  {
    std::fprintf(stderr, "the nodelet did not connect within 10 s\n");
    return 1;
  }
  ros::WallDuration(0.5).sleep();
  ros::WallRate r(rate);
  const ros::WallTime start = ros::WallTime::now();
  int k = 0;
  while ((ros::WallTime::now() - start).toSec() < seconds && ros::ok())
  {
    // Poses with every frame (the nodelet draws them at the image stamp), distances at rate / 3.
    pipe.publishAuxiliary(0.02 * k, k % 3 == 0);
    pipe.publishFrame();
    ++k;
    r.sleep();
  }
  const ros::WallTime end = ros::WallTime::now();
  ros::WallDuration(0.5).sleep();  // let the last frames arrive
  pipe.waitForHeartbeat(ros::WallTime::now(), 3.0);  // counts after the last frame
  pipe.report((end - start).toSec(), rate);
  std::fflush(stdout);  // before the teardown
  loader.clear();       // unload the nodelet while the spinner still serves the bench's callbacks
  ros::WallDuration(0.2).sleep();
  spinner.stop();
  return 0;
}

/// A viewer in another process: counts the augmented images (serialised over TCP) and their
/// latency; exits @p idle_s after the last frame (or when none came within @p timeout_s).
int runCount(int argc, char** argv)
{
  const double timeout_s = argc > 2 ? std::atof(argv[2]) : 90.0;
  const double idle_s = 2.0;
  ros::init(argc, argv, "visual_feedback_bench_viewer", ros::init_options::AnonymousName);
  ros::NodeHandle nh;
  std::mutex mutex;
  std::uint64_t out[2] = {0, 0};
  Stats latency;
  ros::WallTime last = ros::WallTime::now();
  ros::Subscriber sub[2];
  for (int e = 0; e < 2; ++e)
    sub[e] = nh.subscribe<sensor_msgs::Image>(
        std::string("/visual_feedback/") + (e == 0 ? "left" : "right") + "/image", 10,
        [&, e](const sensor_msgs::ImageConstPtr& m) {
          const double ms = (ros::Time::now() - m->header.stamp).toSec() * 1e3;
          std::lock_guard<std::mutex> lock(mutex);
          ++out[e];
          latency.v.push_back(ms);
          last = ros::WallTime::now();
        },
        ros::VoidConstPtr(), ros::TransportHints().tcpNoDelay());
  ros::AsyncSpinner spinner(2);
  spinner.start();
  const ros::WallTime start = ros::WallTime::now();
  while (ros::ok())
  {
    ros::WallDuration(0.1).sleep();
    std::lock_guard<std::mutex> lock(mutex);
    const ros::WallTime now = ros::WallTime::now();
    if ((out[0] + out[1] > 0 && (now - last).toSec() > idle_s) || (now - start).toSec() > timeout_s)
      break;
  }
  spinner.stop();
  std::lock_guard<std::mutex> lock(mutex);
  std::printf("remote viewer (separate process, TCP): out_L %llu, out_R %llu, latency mean %.3f ms, p99 %.3f ms, "
              "max %.3f ms\n",
              static_cast<unsigned long long>(out[0]), static_cast<unsigned long long>(out[1]), latency.mean(),
              latency.pct(0.99), latency.pct(1.0));
  std::fflush(stdout);
  return 0;
}
}  // namespace

int main(int argc, char** argv)
{
  const std::string mode = argc > 1 ? argv[1] : "core";
  if (mode == "core")
    return runCore(argc > 2 ? std::atoi(argv[2]) : 300);
  if (mode == "pipeline")
    return runPipeline(argc, argv, true);
  if (mode == "pipeline-remote")
    return runPipeline(argc, argv, false);
  if (mode == "count")
    return runCount(argc, argv);
  std::fprintf(stderr,
               "usage: %s core [iterations] | pipeline <seconds> <rate_hz> <width> <height> | pipeline-remote <seconds> "
               "<rate_hz> <width> <height> | count [timeout_s]\n",
               argv[0]);
  return 2;
}
