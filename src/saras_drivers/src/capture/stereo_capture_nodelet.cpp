/**
 * @file stereo_capture_nodelet.cpp
 * @brief Nodelet saras_drivers/StereoCapture: the da Vinci endoscope's two video inputs (Decklink
 *        capture in production, any V4L2 device or GStreamer pipeline) as stereo image streams.
 *
 * ROS wiring only. Each eye is captured by its own EyeCapture thread (OpenCV cv::VideoCapture,
 * eye_capture.h); frames are stamped at the grab (minus ~latency) and paired by StereoPairer
 * (capture_core.h): a pair is published with one common stamp on, in the nodelet's namespace
 * (e.g. /endoscope/):
 *
 *   <eye>/image_raw              sensor_msgs/Image (image_transport::CameraPublisher; bgr8 for colour)
 *   <eye>/camera_info            sensor_msgs/CameraInfo from ~<eye>_camera_info_url
 *                                (camera_info_manager; <eye>/set_camera_info stores a new calibration)
 *   <eye>/image_raw/compressed   JPEG: image_transport's plugin, or this nodelet's own publisher
 *                                when the plugin is not installed (one stream either way)
 *
 * Frames without a partner within ~pair_tolerance are dropped and counted. No image is converted
 * while nobody subscribes. /diagnostics (hardware_id endoscope): "capture" (ERROR while an eye is
 * not open or delivers nothing for ~stall_timeout; counters), and the frame rates of each eye and
 * of the pairs (diagnostic_updater::FrequencyStatus around ~expected_rate). A source that fails is
 * reopened with back-off; errors are logged at most once per ~log_period per eye.
 * Parameters and units: config/stereo_capture.yaml (capture_params.h).
 */
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include <algorithm>

#include <camera_info_manager/camera_info_manager.h>
#include <diagnostic_updater/diagnostic_updater.h>
#include <diagnostic_updater/update_functions.h>
#include <image_transport/image_transport.h>
#include <nodelet/nodelet.h>
#include <opencv2/imgcodecs.hpp>
#include <pluginlib/class_list_macros.hpp>
#include <ros/ros.h>
#include <sensor_msgs/CompressedImage.h>
#include <sensor_msgs/Image.h>

#include <saras_common/nodelet_namespace.h>
#include <saras_common/params.h>

#include "saras_drivers/capture_core.h"
#include "saras_drivers/capture_params.h"
#include "saras_drivers/eye_capture.h"

namespace saras_drivers
{
namespace capture
{
namespace
{
const char* const kEyes[2] = { "left", "right" };
constexpr char kCompressedPlugin[] = "image_transport/compressed";

/// @p frame as a sensor_msgs/Image (one copy); null if its type has no encoding.
sensor_msgs::ImagePtr toImage(const cv::Mat& frame, const std_msgs::Header& header)
{
  const std::string encoding = encodingOf(frame.type());
  if (encoding.empty())
    return nullptr;
  auto msg = boost::make_shared<sensor_msgs::Image>();
  msg->header = header;
  msg->height = static_cast<uint32_t>(frame.rows);
  msg->width = static_cast<uint32_t>(frame.cols);
  msg->encoding = encoding;
  msg->step = static_cast<uint32_t>(frame.cols * frame.elemSize());
  msg->data.resize(static_cast<std::size_t>(msg->step) * frame.rows);
  for (int r = 0; r < frame.rows; ++r)
    std::copy(frame.ptr<uint8_t>(r), frame.ptr<uint8_t>(r) + msg->step, msg->data.begin() + r * msg->step);
  return msg;
}
}  // namespace

/// The capture's ROS side: calibration, publishers, eye threads, /diagnostics.
class StereoCapture
{
public:
  StereoCapture(ros::NodeHandle& nh, ros::NodeHandle& pnh, const std::string& name, const std::string& ns)
    : name_(name)
    , cfg_(readCaptureConfig(saras_common::Params(pnh)))
    , pairer_(cfg_.pair_tolerance, static_cast<std::size_t>(cfg_.pair_queue))
  {
    for (int e = 0; e < 2; ++e)
      advertise(e, ns);
    startDiagnostics(nh, pnh);
    started_ = ros::Time::now().toSec();
    for (int e = 0; e < 2; ++e)
    {
      EyeOptions o;
      o.name = kEyes[e];
      o.source = cfg_.source[e];
      o.backoff_min = cfg_.backoff_min;
      o.backoff_max = cfg_.backoff_max;
      o.max_failed_grabs = cfg_.max_failed_grabs;
      o.log_period = cfg_.log_period;
      const std::string node = name_;
      eyes_[e].reset(new EyeCapture(
          o, [] { return ros::Time::now().toSec(); }, [this, e](cv::Mat& f, double t) { onFrame(e, f, t); },
          [node](const std::string& m) { ROS_ERROR("%s: %s", node.c_str(), m.c_str()); }));
      ROS_INFO("%s: %s eye from '%s', calibration '%s'", name_.c_str(), kEyes[e], cfg_.source[e].open_string.c_str(),
               cfg_.camera_info_url[e].c_str());
    }
    // last: diagnose() reads the eyes
    timer_ = nh.createWallTimer(ros::WallDuration(cfg_.diagnostic_period),
                                [this](const ros::WallTimerEvent&) { updater_->force_update(); });
  }

  ~StereoCapture()
  {
    timer_.stop();  // waits for a running diagnose()
    for (auto& eye : eyes_)
      eye.reset();  // stops the thread; no frame arrives afterwards
  }

private:
  void advertise(int e, const std::string& ns)
  {
    ros::NodeHandle eye_nh(ns + kEyes[e]);
    info_[e].reset(new camera_info_manager::CameraInfoManager(eye_nh, cfg_.camera_name[e]));
    const std::string& url = cfg_.camera_info_url[e];
    if (!url.empty() && (!info_[e]->validateURL(url) || !info_[e]->loadCameraInfo(url) || !info_[e]->isCalibrated()))
      throw saras_common::ParamError(ros::names::resolve(name_, std::string(kEyes[e]) + "_camera_info_url"),
                                     "'" + url + "'", "", "a readable camera calibration YAML");
    const sensor_msgs::CameraInfo info = info_[e]->getCameraInfo();
    calib_size_[e][0] = static_cast<int>(info.width);
    calib_size_[e][1] = static_cast<int>(info.height);
    image_transport::ImageTransport it(eye_nh);
    pub_[e] = it.advertiseCamera(ns + kEyes[e] + "/image_raw", static_cast<uint32_t>(cfg_.image_queue));
    const std::vector<std::string> loadable = it.getLoadableTransports();
    std::vector<std::string> disabled;  // image_transport's own per-topic blacklist
    eye_nh.getParam(pub_[e].getTopic() + "/disable_pub_plugins", disabled);
    const bool plugin = std::find(loadable.begin(), loadable.end(), kCompressedPlugin) != loadable.end() &&
                        std::find(disabled.begin(), disabled.end(), kCompressedPlugin) == disabled.end();
    if (!plugin)
      jpeg_pub_[e] = eye_nh.advertise<sensor_msgs::CompressedImage>(pub_[e].getTopic() + "/compressed",
                                                                    static_cast<uint32_t>(cfg_.recorded_queue));
  }

  void startDiagnostics(ros::NodeHandle& nh, ros::NodeHandle& pnh)
  {
    updater_.reset(new diagnostic_updater::Updater(nh, pnh, name_));
    updater_->setHardwareID("endoscope");
    updater_->add("capture", this, &StereoCapture::diagnose);
    min_rate_ = cfg_.expected_rate * (1.0 - cfg_.rate_tolerance);
    max_rate_ = cfg_.expected_rate * (1.0 + cfg_.rate_tolerance);
    const diagnostic_updater::FrequencyStatusParam rate(&min_rate_, &max_rate_, 0.0, 5);
    const char* const names[3] = { "left frame rate", "right frame rate", "stereo pair rate" };
    for (int i = 0; i < 3; ++i)
    {
      rates_[i].reset(new diagnostic_updater::FrequencyStatus(rate, names[i]));
      updater_->add(*rates_[i]);
    }
  }

  /// An eye thread's frame: stamp, pair, publish a completed pair (on that thread).
  void onFrame(int e, cv::Mat& frame, double grab_time)
  {
    rates_[e]->tick();
    StereoPairer<cv::Mat>::Pair pair;
    {
      std::lock_guard<std::mutex> lock(pair_mutex_);
      if (!pairer_.push(e, captureStamp(grab_time, cfg_.latency), std::move(frame), pair))
        return;
    }
    rates_[2]->tick();
    const ros::Time stamp(pair.stamp);
    for (int i = 0; i < 2; ++i)
      publish(i, pair.frame[i], stamp);
  }

  void publish(int e, const cv::Mat& frame, const ros::Time& stamp)
  {
    auto info = boost::make_shared<sensor_msgs::CameraInfo>(info_[e]->getCameraInfo());
    info->header.stamp = stamp;
    info->header.frame_id = cfg_.frame_id[e];
    if (info->width == 0)  // uncalibrated: at least the size
    {
      info->width = static_cast<uint32_t>(frame.cols);
      info->height = static_cast<uint32_t>(frame.rows);
    }
    if (jpeg_pub_[e] && jpeg_pub_[e].getNumSubscribers() > 0)
      publishJpeg(e, frame, info->header);
    if (pub_[e].getNumSubscribers() == 0)
      return;  // lazy: nobody listens (image, any transport or camera_info)
    const sensor_msgs::ImagePtr image = toImage(frame, info->header);
    if (!image)
    {
      std::lock_guard<std::mutex> lock(pair_mutex_);
      ++unsupported_;
      return;
    }
    pub_[e].publish(image, info);
  }

  void publishJpeg(int e, const cv::Mat& frame, const std_msgs::Header& header)
  {
    auto msg = boost::make_shared<sensor_msgs::CompressedImage>();
    msg->header = header;
    msg->format = encodingOf(frame.type()) + "; jpeg compressed bgr8";
    if (cv::imencode(".jpg", frame, msg->data, { cv::IMWRITE_JPEG_QUALITY, cfg_.jpeg_quality }))
      jpeg_pub_[e].publish(msg);
  }

  void diagnose(diagnostic_updater::DiagnosticStatusWrapper& stat)
  {
    EyeStatus s[2] = { eyes_[0]->status(), eyes_[1]->status() };
    const double now = ros::Time::now().toSec();
    const Health h = assessHealth(s, calib_size_, now, started_, cfg_.stall_timeout);
    stat.summary(static_cast<unsigned char>(h.level), h.message);
    PairCounters c;
    uint64_t unsupported;
    {
      std::lock_guard<std::mutex> lock(pair_mutex_);
      c = pairer_.counters();
      unsupported = unsupported_;
    }
    stat.add("pairs published", c.pairs);
    stat.add("pair_tolerance [s]", cfg_.pair_tolerance);
    stat.add("latency [s]", cfg_.latency);
    stat.add("frames without image encoding", unsupported);
    for (int e = 0; e < 2; ++e)
    {
      const std::string eye = kEyes[e];
      stat.add(eye + " source", cfg_.source[e].open_string);
      stat.add(eye + " open", s[e].open);
      stat.add(eye + " frames", s[e].frames);
      stat.add(eye + " unmatched (dropped)", c.unmatched[e]);
      stat.add(eye + " failed grabs", s[e].failed_grabs);
      stat.add(eye + " open failures", s[e].open_failures);
      stat.add(eye + " reopens", s[e].reopens);
      stat.add(eye + " frame age [s]", s[e].last_frame < 0.0 ? -1.0 : now - s[e].last_frame);
      stat.add(eye + " size [px]", std::to_string(s[e].width) + "x" + std::to_string(s[e].height));
      stat.add(eye + " last error", s[e].error);
    }
  }

  std::string name_;
  CaptureConfig cfg_;
  mutable std::mutex pair_mutex_;
  StereoPairer<cv::Mat> pairer_;
  uint64_t unsupported_ = 0;
  std::unique_ptr<camera_info_manager::CameraInfoManager> info_[2];
  int calib_size_[2][2] = { { 0, 0 }, { 0, 0 } };
  image_transport::CameraPublisher pub_[2];
  ros::Publisher jpeg_pub_[2];
  double min_rate_ = 0.0, max_rate_ = 0.0, started_ = 0.0;
  std::unique_ptr<diagnostic_updater::FrequencyStatus> rates_[3];
  std::unique_ptr<diagnostic_updater::Updater> updater_;
  ros::WallTimer timer_;
  std::unique_ptr<EyeCapture> eyes_[2];  ///< last: destroyed first (no frame arrives afterwards)
};

/// Nodelet `saras_drivers/StereoCapture` (nodelet_plugins.xml).
class StereoCaptureNodelet : public nodelet::Nodelet
{
private:
  void onInit() override
  {
    try
    {
      // topics in the nodelet's own namespace (e.g. /endoscope/left/...), not the manager's
      capture_.reset(
          new StereoCapture(getNodeHandle(), getPrivateNodeHandle(), getName(), saras_common::nodeletNamespace(getName())));
    }
    catch (const std::exception& e)
    {
      ROS_FATAL("%s: %s", getName().c_str(), e.what());
      throw;
    }
  }
  std::unique_ptr<StereoCapture> capture_;
};

}  // namespace capture
}  // namespace saras_drivers

PLUGINLIB_EXPORT_CLASS(saras_drivers::capture::StereoCaptureNodelet, nodelet::Nodelet)
