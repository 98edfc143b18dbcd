#include "saras_visual_feedback/contact_estimator_nodelet.h"

#include <algorithm>
#include <cmath>
#include <ctime>
#include <limits>

#include <boost/bind/bind.hpp>
#include <boost/make_shared.hpp>
#include <cv_bridge/cv_bridge.h>
#include <pluginlib/class_list_macros.hpp>
#include <saras_msgs/Contact.h>
#include <sensor_msgs/image_encodings.h>
#include <std_msgs/Float64MultiArray.h>

#include "saras_visual_feedback/frame_composer.h"

namespace saras_visual_feedback
{
namespace
{
std::uint64_t threadCpuNs()
{
  timespec t;
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<std::uint64_t>(t.tv_sec) * 1000000000ULL + static_cast<std::uint64_t>(t.tv_nsec);
}

/// The 8-bit image shared (no copy) as a cv::Mat; false for other encodings or a bad buffer.
bool shareImage(const sensor_msgs::ImageConstPtr& image, cv::Mat* out, std::string* why)
{
  namespace enc = sensor_msgs::image_encodings;
  if (!imageBufferConsistent(*image, why))
    return false;
  const std::string& e = image->encoding;
  if (e != enc::BGR8 && e != enc::RGB8 && e != enc::BGRA8 && e != enc::RGBA8 && e != enc::MONO8)
  {
    *why = "unsupported encoding " + e + " (bgr8, rgb8, bgra8, rgba8, mono8)";
    return false;
  }
  *out = cv_bridge::toCvShare(image)->image;
  return true;
}

bool sameCalibration(const sensor_msgs::CameraInfo& a, const sensor_msgs::CameraInfo& b)
{
  return a.width == b.width && a.height == b.height && a.K == b.K && a.D == b.D && a.R == b.R && a.P == b.P &&
         a.distortion_model == b.distortion_model && a.binning_x == b.binning_x && a.binning_y == b.binning_y &&
         a.roi == b.roi;
}

void atomicMax(std::atomic<std::uint64_t>& a, std::uint64_t v)
{
  std::uint64_t cur = a.load();
  while (v > cur && !a.compare_exchange_weak(cur, v))
  {
  }
}
}  // namespace

ContactEstimatorNodelet::~ContactEstimatorNodelet()
{
  diagnostics_timer_.stop();
  std::lock_guard<std::mutex> lock(connect_mutex_);
  shutting_down_ = true;
  for (auto& s : cam_subs_)
    s.shutdown();
  for (ros::Subscriber& s : pose_subs_)
    s.shutdown();
}

void ContactEstimatorNodelet::onInit()
{
  try
  {
    params_ = readContactEstimatorParams(getPrivateNodeHandle());
  }
  catch (const std::exception& e)
  {
    NODELET_FATAL("%s", e.what());
    throw;
  }
  const ContactEstimatorParams& p = params_;
  estimator_ = StereoContactEstimator(p.estimator);
  std::vector<ToolConfig> tools;
  for (const ContactToolConfig& t : p.tools)
    tools.push_back(t.tool);
  SceneStyle style;
  style.shaft_length = 0.05;  // masked shaft length from the tip [m]
  style.draw_dvrk = true;
  scene_.reset(new ToolScene(tools, static_cast<std::size_t>(p.pose_buffer_size),
                             static_cast<std::int64_t>(p.pose_timeout * 1e9), std::numeric_limits<std::int64_t>::max(),
                             style));
  tf_buffer_.reset(new tf2_ros::Buffer(ros::Duration(10.0)));
  tf_listener_.reset(new tf2_ros::TransformListener(*tf_buffer_, getNodeHandle()));
  tf_points_.reset(new TfPointTransformer(*tf_buffer_));
  it_ = std::make_shared<image_transport::ImageTransport>(getMTNodeHandle());
  pose_subs_.resize(p.tools.size());

  updater_.reset(new diagnostic_updater::Updater(getNodeHandle(), getPrivateNodeHandle(), getName()));
  updater_->setHardwareID("visual_feedback");
  updater_->add("stereo contact", this, &ContactEstimatorNodelet::diagnose);
  last_report_ = ros::WallTime::now();
  diagnostics_timer_ =
      getNodeHandle().createWallTimer(ros::WallDuration(0.1), [this](const ros::WallTimerEvent&) { updater_->update(); });

  std::lock_guard<std::mutex> lock(connect_mutex_);
  ros::SubscriberStatusCallback cb = boost::bind(&ContactEstimatorNodelet::connectCb, this);
  for (const ContactToolConfig& t : p.tools)
  {
    outputs_.emplace_back(new Output);
    if (!t.estimate)
      continue;
    outputs_.back()->contact = getNodeHandle().advertise<saras_msgs::Contact>(t.topic, 10, cb, cb);
    outputs_.back()->estimate =
        getNodeHandle().advertise<std_msgs::Float64MultiArray>(t.topic + "_estimate", 10, cb, cb);
  }
  NODELET_INFO("ContactEstimator ready: %zu tools (lazy: cameras subscribed while a contact topic has subscribers)",
               p.tools.size());
}

void ContactEstimatorNodelet::connectCb()
{
  std::lock_guard<std::mutex> lock(connect_mutex_);
  if (shutting_down_)
    return;
  bool any = false;
  for (const auto& o : outputs_)
    any = any || o->contact.getNumSubscribers() > 0 || o->estimate.getNumSubscribers() > 0;
  if (any == static_cast<bool>(cam_subs_[0]))
    return;
  if (!any)
  {
    for (auto& s : cam_subs_)
      s.shutdown();
    for (ros::Subscriber& s : pose_subs_)
      s.shutdown();
    return;
  }
  ros::NodeHandle& nh = getMTNodeHandle();
  for (std::size_t i = 0; i < pose_subs_.size(); ++i)
    pose_subs_[i] = nh.subscribe<geometry_msgs::PoseStamped>(
        params_.tools[i].tool.pose_topic, 10,
        boost::bind(&ContactEstimatorNodelet::poseCb, this, boost::placeholders::_1, i), ros::VoidConstPtr(),
        ros::TransportHints().tcpNoDelay());
  const char* names[2] = {"left", "right"};
  image_transport::TransportHints hints("raw", ros::TransportHints().tcpNoDelay(), getPrivateNodeHandle());
  for (std::size_t e = 0; e < 2; ++e)
    cam_subs_[e] = it_->subscribeCamera(
        std::string(names[e]) + "/image_raw", static_cast<uint32_t>(params_.queue_size),
        boost::bind(&ContactEstimatorNodelet::imageCb, this, boost::placeholders::_1, boost::placeholders::_2, e),
        ros::VoidPtr(), hints);
}

void ContactEstimatorNodelet::poseCb(const geometry_msgs::PoseStampedConstPtr& msg, std::size_t i)
{
  const ros::Time now = ros::Time::now();
  TimedPose sample;
  std::string why;
  if (!poseSampleFromMsg(*msg, now, &sample, &why))
  {
    scene_->rejectPose(i);
    NODELET_ERROR_THROTTLE(1.0, "rejected pose of %s (%s)", params_.tools[i].tool.name.c_str(), why.c_str());
    return;
  }
  scene_->addPose(i, msg->header.frame_id, sample, static_cast<std::int64_t>(now.toNSec()));
}

void ContactEstimatorNodelet::imageCb(const sensor_msgs::ImageConstPtr& image,
                                      const sensor_msgs::CameraInfoConstPtr& info, std::size_t eye)
{
  sensor_msgs::ImageConstPtr images[2];
  sensor_msgs::CameraInfoConstPtr infos[2];
  {
    // A stereo pair = left and right images with the same stamp; an older pending half is dropped.
    std::lock_guard<std::mutex> lock(pair_mutex_);
    const std::size_t other = 1 - eye;
    pending_image_[eye] = image;
    pending_info_[eye] = info;
    const sensor_msgs::ImageConstPtr& o = pending_image_[other];
    if (!o || o->header.stamp != image->header.stamp)
    {
      if (o && o->header.stamp < image->header.stamp)
      {
        pending_image_[other].reset();
        ++unpaired_;
      }
      return;
    }
    for (std::size_t e = 0; e < 2; ++e)
    {
      images[e] = pending_image_[e];
      infos[e] = pending_info_[e];
      pending_image_[e].reset();
      pending_info_[e].reset();
    }
  }
  processPair(images, infos);
}

void ContactEstimatorNodelet::processPair(const sensor_msgs::ImageConstPtr images[2],
                                          const sensor_msgs::CameraInfoConstPtr infos[2])
{
  std::lock_guard<std::mutex> lock(process_mutex_);
  const std::uint64_t cpu0 = threadCpuNs();
  last_pair_wall_ns_ = static_cast<std::int64_t>(ros::WallTime::now().toNSec());
  cv::Mat mats[2];
  std::string why;
  if (!shareImage(images[0], &mats[0], &why) || !shareImage(images[1], &mats[1], &why))
  {
    ++rejected_;
    NODELET_ERROR_THROTTLE(1.0, "stereo pair rejected: %s", why.c_str());
    return;
  }
  if (!estimator_.configured() || !sameCalibration(*infos[0], calibrated_[0]) ||
      !sameCalibration(*infos[1], calibrated_[1]))
  {
    StereoCalibration cal;
    calibrated_[0] = *infos[0];
    calibrated_[1] = *infos[1];
    calibration_error_.clear();
    if (!stereoCalibrationFromCameraInfo(*infos[0], *infos[1], &cal, &calibration_error_) ||
        !estimator_.configure(cal, &calibration_error_))
      NODELET_ERROR("stereo calibration unusable: %s (every contact is unknown)", calibration_error_.c_str());
  }
  const ros::Time stamp = images[0]->header.stamp;
  const std::int64_t stamp_ns = stamp.isZero() ? kLatestStamp : static_cast<std::int64_t>(stamp.toNSec());
  const std::string& frame = images[0]->header.frame_id.empty() ? infos[0]->header.frame_id : images[0]->header.frame_id;
  scene_->snapshot(static_cast<std::int64_t>(ros::Time::now().toNSec()), stamp_ns, &snapshot_);
  std::array<ToolOverlay, kMaxTools> placed;
  FrameReport report;
  placeTools(snapshot_, frame, stamp_ns, static_cast<std::int64_t>(params_.pose_stamp_tolerance * 1e9), *tf_points_,
             placed.data(), &report);
  std::array<InstrumentView, kMaxTools> views;
  for (std::size_t i = 0; i < snapshot_.n; ++i)
  {
    views[i].valid = placed[i].visible;
    views[i].tip = placed[i].tip;
    views[i].has_shaft = placed[i].has_shaft;
    views[i].shaft = placed[i].shaft;
    views[i].radius = params_.tools[i].radius;
  }
  for (std::size_t i = 0; i < snapshot_.n; ++i)
    if (params_.tools[i].estimate)
      publishTool(i, estimator_.estimate(mats[0], mats[1], views.data(), snapshot_.n, i), frame, stamp);
  ++pairs_;
  cpu_ns_ += threadCpuNs() - cpu0;
  const std::int64_t latency = static_cast<std::int64_t>((ros::Time::now() - stamp).toNSec());
  if (!stamp.isZero() && latency > 0)
  {
    latency_ns_ += static_cast<std::uint64_t>(latency);
    atomicMax(max_latency_ns_, static_cast<std::uint64_t>(latency));
  }
}

void ContactEstimatorNodelet::publishTool(std::size_t i, const ContactEstimate& c, const std::string& camera_frame,
                                          const ros::Time& stamp)
{
  const ContactToolConfig& t = params_.tools[i];
  Output& o = *outputs_[i];
  ++o.states[static_cast<std::size_t>(c.state)];
  // The normal in the consumer's frame: two points through TF at the image stamp.
  cv::Vec3d dir(0, 0, 0);
  bool direction_ok = c.state != ContactState::kUnknown;
  if (direction_ok)
  {
    cv::Point3d a, b;
    bool at_stamp = true;
    std::string why;
    const std::int64_t ns = stamp.isZero() ? kLatestStamp : static_cast<std::int64_t>(stamp.toNSec());
    direction_ok = tf_points_->transform(t.direction_frame, camera_frame, ns, cv::Point3d(0, 0, 0), &a, &at_stamp, &why) &&
                   tf_points_->transform(t.direction_frame, camera_frame, ns, cv::Point3d(c.normal), &b, &at_stamp, &why);
    if (!direction_ok)
    {
      ++o.direction_failures;
      NODELET_ERROR_THROTTLE(2.0, "%s: no transform %s -> %s (%s): contact not published", t.tool.name.c_str(),
                             camera_frame.c_str(), t.direction_frame.c_str(), why.c_str());
    }
    dir = cv::Vec3d(b - a);
  }
  if (direction_ok && o.contact.getNumSubscribers() > 0)
  {
    saras_msgs::ContactPtr m = boost::make_shared<saras_msgs::Contact>();
    m->depth = c.depth;
    m->direction.x = dir[0];
    m->direction.y = dir[1];
    m->direction.z = dir[2];
    o.contact.publish(m);
  }
  if (o.estimate.getNumSubscribers() > 0)
  {
    // [image stamp s, state (0 unknown, 1 no contact, 2 contact), depth m, signed distance m,
    //  confidence, direction x y z (direction_frame), unknown reason code,
    //  surface point x y z m and normal x y z (camera optical frame; NaN when unknown),
    //  region of interest x y width height (rectified left image, px; 0 when the tip is not projected)]
    std_msgs::Float64MultiArrayPtr m = boost::make_shared<std_msgs::Float64MultiArray>();
    const bool known = direction_ok;
    const double nan = std::nan("");
    m->data = {stamp.toSec(),
               known ? static_cast<double>(c.state) : 0.0,
               known ? c.depth : nan,
               known ? c.signed_distance : nan,
               known ? c.confidence : 0.0,
               dir[0], dir[1], dir[2],
               static_cast<double>(c.unknown),
               known ? c.surface.x : nan, known ? c.surface.y : nan, known ? c.surface.z : nan,
               known ? c.normal[0] : nan, known ? c.normal[1] : nan, known ? c.normal[2] : nan,
               static_cast<double>(c.roi.x), static_cast<double>(c.roi.y),
               static_cast<double>(c.roi.width), static_cast<double>(c.roi.height)};
    o.estimate.publish(m);
  }
  std::lock_guard<std::mutex> lock(stats_mutex_);
  o.last_unknown = c.state == ContactState::kUnknown ? toString(c.unknown) : "";
  o.last_depth = c.depth;
  o.last_confidence = c.confidence;
}

void ContactEstimatorNodelet::diagnose(diagnostic_updater::DiagnosticStatusWrapper& stat)
{
  using diagnostic_msgs::DiagnosticStatus;
  const ros::WallTime now = ros::WallTime::now();
  const double period = std::max(1e-3, (now - last_report_).toSec());
  last_report_ = now;
  const std::uint64_t pairs = pairs_;
  stat.addf("stereo pairs", "%llu", static_cast<unsigned long long>(pairs));
  stat.addf("rate [Hz]", "%.1f", (pairs - pairs_reported_) / period);
  pairs_reported_ = pairs;
  stat.addf("unpaired images", "%llu", static_cast<unsigned long long>(unpaired_.load()));
  stat.addf("rejected pairs", "%llu", static_cast<unsigned long long>(rejected_.load()));
  stat.addf("mean CPU per pair [ms]", "%.3f", pairs > 0 ? cpu_ns_.load() / 1e6 / pairs : 0.0);
  stat.addf("mean latency image stamp -> contact [ms]", "%.2f", pairs > 0 ? latency_ns_.load() / 1e6 / pairs : 0.0);
  stat.addf("max latency [ms]", "%.2f", max_latency_ns_.load() / 1e6);
  std::string calibration_error;
  {
    std::lock_guard<std::mutex> lock(process_mutex_);
    calibration_error = calibration_error_;
  }
  bool unknown = false;
  {
    std::lock_guard<std::mutex> lock(stats_mutex_);
    for (std::size_t i = 0; i < outputs_.size(); ++i)
    {
      const Output& o = *outputs_[i];
      if (!params_.tools[i].estimate)
        continue;
      const std::string& n = params_.tools[i].tool.name;
      stat.addf(n + " frames unknown / no contact / contact", "%llu / %llu / %llu",
                static_cast<unsigned long long>(o.states[0].load()), static_cast<unsigned long long>(o.states[1].load()),
                static_cast<unsigned long long>(o.states[2].load()));
      stat.add(n + " state", o.last_unknown.empty() ? "known" : "unknown: " + o.last_unknown);
      stat.addf(n + " depth [mm]", "%.2f", o.last_depth * 1e3);
      stat.addf(n + " confidence", "%.2f", o.last_confidence);
      stat.addf(n + " direction transform failures", "%llu", static_cast<unsigned long long>(o.direction_failures.load()));
      unknown = unknown || !o.last_unknown.empty();
    }
  }
  const std::int64_t last = last_pair_wall_ns_;
  const double age = last > 0 ? (now.toNSec() - last) * 1e-9 : std::numeric_limits<double>::infinity();
  stat.addf("stereo pair age [s]", "%.3f", age);
  if (!cam_subs_[0])
    stat.summary(DiagnosticStatus::OK, "idle: no subscribers to the contact topics");
  else if (!(age <= params_.image_timeout))
    stat.summaryf(DiagnosticStatus::STALE, "no stereo pair for %.1f s", std::isfinite(age) ? age : -1.0);
  else if (!calibration_error.empty())
    stat.summary(DiagnosticStatus::ERROR, "stereo calibration unusable: " + calibration_error);
  else if (unknown)
    stat.summary(DiagnosticStatus::WARN, "contact unknown for a tool (see its state)");
  else
    stat.summary(DiagnosticStatus::OK, "estimating");
}

}  // namespace saras_visual_feedback

PLUGINLIB_EXPORT_CLASS(saras_visual_feedback::ContactEstimatorNodelet, nodelet::Nodelet)
