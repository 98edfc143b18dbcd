#include "saras_visual_feedback/visual_feedback_nodelet.h"

#include <chrono>
#include <cmath>
#include <cstring>
#include <ctime>
#include <limits>
#include <sstream>
#include <stdexcept>

#include <boost/bind/bind.hpp>
#include <boost/make_shared.hpp>
#include <cv_bridge/cv_bridge.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <pluginlib/class_list_macros.hpp>
#include <saras_msgs/ComponentStatus.h>
#include <sensor_msgs/CompressedImage.h>
#include <sensor_msgs/image_encodings.h>
#include <tf2/LinearMath/Transform.h>
#include <tf2_geometry_msgs/tf2_geometry_msgs.h>

#include "saras_visual_feedback/ros_conversions.h"

namespace saras_visual_feedback
{
namespace enc = sensor_msgs::image_encodings;

namespace
{
/// A start-up parameter error: names the parameter; makes onInit fail (the node exits non-zero).
std::runtime_error paramError(const std::string& name, const std::string& why)
{
  return std::runtime_error("invalid parameter ~" + name + ": " + why);
}

double readPositive(const ros::NodeHandle& pnh, const std::string& name, double def, const char* unit)
{
  double v = def;
  pnh.param(name, v, def);
  if (!(std::isfinite(v) && v > 0.0))
    throw paramError(name, "must be finite and > 0 " + std::string(unit) + ", got " + std::to_string(v));
  return v;
}

std::string xmlString(XmlRpc::XmlRpcValue& v, const std::string& key, const std::string& where, bool required,
                      const std::string& def = "")
{
  if (!v.hasMember(key))
  {
    if (required)
      throw paramError(where, "missing '" + key + "'");
    return def;
  }
  if (v[key].getType() != XmlRpc::XmlRpcValue::TypeString)
    throw paramError(where, "'" + key + "' must be a string");
  return static_cast<std::string>(v[key]);
}

bool finitePose(const geometry_msgs::Pose& p)
{
  return std::isfinite(p.position.x) && std::isfinite(p.position.y) && std::isfinite(p.position.z) &&
         std::isfinite(p.orientation.x) && std::isfinite(p.orientation.y) && std::isfinite(p.orientation.z) &&
         std::isfinite(p.orientation.w);
}

void atomicMax(std::atomic<std::uint64_t>& a, std::uint64_t v)
{
  std::uint64_t cur = a.load();
  while (v > cur && !a.compare_exchange_weak(cur, v))
  {
  }
}
}  // namespace

VisualFeedbackNodelet::~VisualFeedbackNodelet()
{
  status_timer_.stop();
  // Unloading: shut the subscriptions and publishers down here, under connect_mutex_, so that a
  // connection callback racing with the destruction (a viewer leaving as the publishers go away)
  // cannot shut the same subscription down concurrently with the member destructors.
  std::lock_guard<std::mutex> lock(connect_mutex_);
  shutting_down_ = true;
  for (Eye& eye : eyes_)
  {
    eye.sub.shutdown();
    eye.pub.shutdown();
    eye.compressed_pub.shutdown();
  }
  for (Tool& t : tools_)
    t.sub.shutdown();
  distances_sub_.shutdown();
}

void VisualFeedbackNodelet::readParameters()
{
  ros::NodeHandle& pnh = getPrivateNodeHandle();
  OverlayStyle s;
  pnh.param("collision_threshold", s.collision_threshold, s.collision_threshold);
  pnh.param("warning_threshold", s.warning_threshold, s.warning_threshold);
  const char* colour_names[4] = {"collision_colour", "warning_colour", "safe_colour", "unknown_colour"};
  Rgb* colours[4] = {&s.collision_colour, &s.warning_colour, &s.safe_colour, &s.unknown_colour};
  for (int i = 0; i < 4; ++i)
  {
    std::string text;
    if (pnh.getParam(colour_names[i], text) && !parseColour(text, colours[i]))
      throw paramError(colour_names[i], "must be \"#RRGGBB\", got \"" + text + "\"");
  }
  pnh.param("line_thickness", s.line_thickness, s.line_thickness);
  pnh.param("circle_radius", s.circle_radius, s.circle_radius);
  pnh.param("marker_size", s.marker_size, s.marker_size);
  pnh.param("shaft_segments", s.shaft_segments, s.shaft_segments);
  pnh.param("draw_hud", s.draw_hud, s.draw_hud);
  std::string why;
  if (!validateStyle(s, &why))
    throw paramError(why.substr(0, why.find(' ')), why);
  style_ = s;
  shaft_length_ = readPositive(pnh, "shaft_length", 0.05, "[m]");
  pnh.param("draw_dvrk", draw_dvrk_, true);
  pose_timeout_ = readPositive(pnh, "pose_timeout", 0.5, "[s]");
  distances_timeout_ = readPositive(pnh, "distances_timeout", 0.5, "[s]");
  image_timeout_ = readPositive(pnh, "image_timeout", 1.0, "[s]");
  pnh.param("pose_buffer_size", pose_buffer_size_, 512);
  if (pose_buffer_size_ < 2 || pose_buffer_size_ > 100000)
    throw paramError("pose_buffer_size", "must be in [2, 100000] samples, got " + std::to_string(pose_buffer_size_));
  pnh.param("pose_stamp_tolerance", pose_stamp_tolerance_, 0.03);
  if (!(std::isfinite(pose_stamp_tolerance_) && pose_stamp_tolerance_ >= 0.0))
    throw paramError("pose_stamp_tolerance", "must be finite and >= 0 [s], got " + std::to_string(pose_stamp_tolerance_));
  pnh.param("jpeg_quality", jpeg_quality_, 80);
  if (jpeg_quality_ < 1 || jpeg_quality_ > 100)
    throw paramError("jpeg_quality", "must be in [1, 100], got " + std::to_string(jpeg_quality_));
  pnh.param("queue_size", queue_size_, 6);
  if (queue_size_ < 1)
    throw paramError("queue_size", "must be >= 1");
  pnh.param<std::string>("component", component_, getName());

  XmlRpc::XmlRpcValue list;
  if (!pnh.getParam("tools", list))
  {
    // Defaults: the contract's topics and frames.
    list.setSize(0);
    const char* names[4] = {"mesa_left", "mesa_right", "PSM1", "PSM2"};
    const char* topics[4] = {"/mesa_left/ee_pose", "/mesa_right/ee_pose", "/dvrk/PSM1/position_cartesian_current",
                             "/dvrk/PSM2/position_cartesian_current"};
    const char* rcm[4] = {"mesa_left/rcm", "mesa_right/rcm", "PSM1", "PSM2"};
    for (int i = 0; i < 4; ++i)
    {
      list[i]["name"] = std::string(names[i]);
      list[i]["pose_topic"] = std::string(topics[i]);
      list[i]["rcm_frame"] = std::string(rcm[i]);
      list[i]["distance_index"] = i;
      list[i]["dvrk"] = i >= 2;
    }
  }
  if (list.getType() != XmlRpc::XmlRpcValue::TypeArray || list.size() < 1 ||
      list.size() > static_cast<int>(kMaxTools))
    throw paramError("tools", "must be a list of 1 to " + std::to_string(kMaxTools) + " tools");
  tools_ = std::vector<Tool>(list.size());
  for (int i = 0; i < list.size(); ++i)
  {
    const std::string where = "tools[" + std::to_string(i) + "]";
    if (list[i].getType() != XmlRpc::XmlRpcValue::TypeStruct)
      throw paramError(where, "must be a dictionary");
    Tool& t = tools_[i];
    t.history.setCapacity(static_cast<std::size_t>(pose_buffer_size_));
    t.name = xmlString(list[i], "name", where, true);
    t.label = xmlString(list[i], "label", where, false, t.name);
    t.pose_topic = xmlString(list[i], "pose_topic", where, true);
    t.rcm_frame = xmlString(list[i], "rcm_frame", where, false);
    if (!list[i].hasMember("distance_index") || list[i]["distance_index"].getType() != XmlRpc::XmlRpcValue::TypeInt ||
        static_cast<int>(list[i]["distance_index"]) < 0)
      throw paramError(where, "'distance_index' must be an integer >= 0 (index in /collision/distances)");
    t.distance_index = static_cast<int>(list[i]["distance_index"]);
    if (list[i].hasMember("dvrk"))
    {
      if (list[i]["dvrk"].getType() != XmlRpc::XmlRpcValue::TypeBoolean)
        throw paramError(where, "'dvrk' must be a boolean");
      t.dvrk = static_cast<bool>(list[i]["dvrk"]);
    }
    if (t.name.empty() || t.pose_topic.empty())
      throw paramError(where, "'name' and 'pose_topic' must not be empty");
  }
}

void VisualFeedbackNodelet::onInit()
{
  try
  {
    readParameters();
  }
  catch (const std::exception& e)
  {
    NODELET_FATAL("%s", e.what());
    throw;  // nodelet::Loader::load() fails: the standalone node and `nodelet load` exit non-zero
  }
  ros::NodeHandle& nh = getNodeHandle();
  ros::NodeHandle& pnh = getPrivateNodeHandle();
  tf_buffer_.reset(new tf2_ros::Buffer(ros::Duration(10.0)));
  tf_listener_.reset(new tf2_ros::TransformListener(*tf_buffer_, nh));
  // Multi-threaded handle: the two eyes are processed in parallel (each eye's callback is
  // serialised by its own mutex, as image and camera_info may complete a pair from two threads).
  it_ = std::make_shared<image_transport::ImageTransport>(getMTNodeHandle());
  eyes_[0].name = "left";
  eyes_[1].name = "right";

  reconfigure_server_.reset(new ReconfigureServer(reconfigure_mutex_, pnh));
  {
    // Start the server from the validated start-up values.
    VisualFeedbackConfig c;
    reconfigure_server_->getConfigDefault(c);
    c.collision_threshold = style_.collision_threshold;
    c.warning_threshold = style_.warning_threshold;
    char buf[8];
    auto hex = [&buf](const Rgb& rgb) {
      std::snprintf(buf, sizeof(buf), "#%02x%02x%02x", rgb.r, rgb.g, rgb.b);
      return std::string(buf);
    };
    c.collision_colour = hex(style_.collision_colour);
    c.warning_colour = hex(style_.warning_colour);
    c.safe_colour = hex(style_.safe_colour);
    c.unknown_colour = hex(style_.unknown_colour);
    c.line_thickness = style_.line_thickness;
    c.circle_radius = style_.circle_radius;
    c.marker_size = style_.marker_size;
    c.shaft_length = shaft_length_;
    c.draw_hud = style_.draw_hud;
    c.draw_dvrk = draw_dvrk_;
    reconfigure_server_->updateConfig(c);
  }
  reconfigure_server_->setCallback(
      boost::bind(&VisualFeedbackNodelet::reconfigureCb, this, boost::placeholders::_1, boost::placeholders::_2));

  status_pub_ = nh.advertise<saras_msgs::ComponentStatus>("/saras/status", 10);
  last_status_ = ros::WallTime::now();
  status_timer_ = nh.createWallTimer(ros::WallDuration(0.1), &VisualFeedbackNodelet::statusTimerCb, this);

  // Advertise under connect_mutex_ so that connectCb cannot run before the publishers exist.
  std::lock_guard<std::mutex> lock(connect_mutex_);
  image_transport::SubscriberStatusCallback cb = boost::bind(&VisualFeedbackNodelet::connectCb, this);
  ros::SubscriberStatusCallback ros_cb = boost::bind(&VisualFeedbackNodelet::connectCb, this);
  for (Eye& eye : eyes_)
  {
    // Publisher queue: only used for subscribers in other processes (serialised frames waiting
    // for the socket); intra-process subscribers get the shared pointer in their own queue.
    eye.pub = it_->advertise(eye.name + "/image", static_cast<uint32_t>(queue_size_), cb, cb);
    // JPEG stream for remote viewers (what compressed_image_transport would publish; that plugin
    // is not packaged in Debian). Encoded only while subscribed.
    eye.compressed_pub = getMTNodeHandle().advertise<sensor_msgs::CompressedImage>(eye.pub.getTopic() + "/compressed",
                                                                                   1, ros_cb, ros_cb);
  }
  NODELET_INFO("VisualFeedback ready: %zu tools, thresholds collision %.4f m, warning %.4f m (lazy: waiting for "
               "subscribers of %s and %s)",
               tools_.size(), style_.collision_threshold, style_.warning_threshold, eyes_[0].pub.getTopic().c_str(),
               eyes_[1].pub.getTopic().c_str());
}

void VisualFeedbackNodelet::connectCb()
{
  std::lock_guard<std::mutex> lock(connect_mutex_);
  if (shutting_down_)
    return;
  ros::NodeHandle& nh = getMTNodeHandle();
  bool any = false;
  for (std::size_t i = 0; i < eyes_.size(); ++i)
  {
    Eye& eye = eyes_[i];
    if (eye.pub.getNumSubscribers() == 0 && eye.compressed_pub.getNumSubscribers() == 0)
    {
      if (eye.sub)
      {
        NODELET_DEBUG("no subscribers to %s: unsubscribing the %s camera", eye.pub.getTopic().c_str(),
                      eye.name.c_str());
        eye.sub.shutdown();
      }
      continue;
    }
    any = true;
    if (!eye.sub)
    {
      image_transport::TransportHints hints("raw", ros::TransportHints().tcpNoDelay(), getPrivateNodeHandle());
      eye.sub = it_->subscribeCamera(
          eye.name + "/image_raw", static_cast<uint32_t>(queue_size_),
          boost::bind(&VisualFeedbackNodelet::imageCb, this, boost::placeholders::_1, boost::placeholders::_2, i),
          ros::VoidPtr(), hints);
    }
  }
  if (any && !subscribed_inputs_)
  {
    for (std::size_t i = 0; i < tools_.size(); ++i)
      tools_[i].sub = nh.subscribe<geometry_msgs::PoseStamped>(
          tools_[i].pose_topic, 1, boost::bind(&VisualFeedbackNodelet::poseCb, this, boost::placeholders::_1, i),
          ros::VoidConstPtr(), ros::TransportHints().tcpNoDelay());
    distances_sub_ = nh.subscribe("distances", 1, &VisualFeedbackNodelet::distancesCb, this,
                                  ros::TransportHints().tcpNoDelay());
    subscribed_inputs_ = true;
  }
  else if (!any && subscribed_inputs_)
  {
    for (Tool& t : tools_)
      t.sub.shutdown();
    distances_sub_.shutdown();
    subscribed_inputs_ = false;
  }
}

void VisualFeedbackNodelet::poseCb(const geometry_msgs::PoseStampedConstPtr& msg, std::size_t i)
{
  if (!finitePose(msg->pose) || msg->header.frame_id.empty())
  {
    std::uint64_t n;
    {
      std::lock_guard<std::mutex> lock(state_mutex_);
      n = ++tools_[i].rejected;
    }
    NODELET_ERROR_THROTTLE(1.0, "rejected pose of %s on %s (%s); %llu rejected so far; the tool is not drawn once "
                                "the last valid pose is older than %.2f s",
                           tools_[i].name.c_str(), tools_[i].pose_topic.c_str(),
                           msg->header.frame_id.empty() ? "empty frame_id" : "NaN/inf value",
                           static_cast<unsigned long long>(n), pose_timeout_);
    return;
  }
  // The sample is stamped with the pose's header.stamp (receipt time when unstamped), the clock of
  // the images' stamps, so that imageCb can take the pose at the image stamp.
  const ros::Time now = ros::Time::now();
  TimedPose sample;
  sample.stamp_ns = static_cast<std::int64_t>((msg->header.stamp.isZero() ? now : msg->header.stamp).toNSec());
  sample.position[0] = msg->pose.position.x;
  sample.position[1] = msg->pose.position.y;
  sample.position[2] = msg->pose.position.z;
  const geometry_msgs::Quaternion& q = msg->pose.orientation;
  const double norm = std::sqrt(q.x * q.x + q.y * q.y + q.z * q.z + q.w * q.w);
  if (norm > 1e-9)  // unset orientation (all zero): identity (only the tip position is drawn)
  {
    sample.orientation[0] = q.x / norm;
    sample.orientation[1] = q.y / norm;
    sample.orientation[2] = q.z / norm;
    sample.orientation[3] = q.w / norm;
  }
  std::lock_guard<std::mutex> lock(state_mutex_);
  Tool& t = tools_[i];
  if (t.frame_id != msg->header.frame_id)
  {
    t.history.clear();  // poses of different frames are not interpolated
    t.frame_id = msg->header.frame_id;
  }
  if (t.history.push(sample) == PosePush::kRestarted)
  {
    ++t.restarts;
    NODELET_WARN_THROTTLE(5.0, "pose stamps of %s on %s went backwards (clock reset?): pose history restarted "
                               "(%llu times)",
                          t.name.c_str(), t.pose_topic.c_str(), static_cast<unsigned long long>(t.restarts));
  }
  t.pose_received = now;
}

void VisualFeedbackNodelet::distancesCb(const std_msgs::Float64MultiArrayConstPtr& msg)
{
  std::size_t needed = 0;
  for (const Tool& t : tools_)
    needed = std::max(needed, static_cast<std::size_t>(t.distance_index) + 1);
  std::lock_guard<std::mutex> lock(state_mutex_);
  if (msg->data.size() < needed)
  {
    ++distances_rejected_;
    NODELET_WARN_THROTTLE(5.0, "/collision/distances has %zu values, %zu expected: missing ones are drawn as unknown",
                          msg->data.size(), needed);
  }
  distances_.assign(msg->data.begin(), msg->data.end());  // NaN entries stay NaN: drawn as unknown
  distances_received_ = ros::Time::now();
}

void VisualFeedbackNodelet::reconfigureCb(VisualFeedbackConfig& c, uint32_t /*level*/)
{
  std::lock_guard<std::mutex> lock(state_mutex_);
  OverlayStyle s = style_;
  s.collision_threshold = c.collision_threshold;
  s.warning_threshold = c.warning_threshold;
  s.line_thickness = c.line_thickness;
  s.circle_radius = c.circle_radius;
  s.marker_size = c.marker_size;
  s.draw_hud = c.draw_hud;
  std::string why;
  bool ok = parseColour(c.collision_colour, &s.collision_colour) && parseColour(c.warning_colour, &s.warning_colour) &&
            parseColour(c.safe_colour, &s.safe_colour) && parseColour(c.unknown_colour, &s.unknown_colour);
  if (!ok)
    why = "colours must be \"#RRGGBB\"";
  else
    ok = validateStyle(s, &why);
  if (!ok)
  {
    NODELET_ERROR("dynamic_reconfigure request rejected (%s); keeping collision_threshold %.4f m, warning_threshold "
                  "%.4f m",
                  why.c_str(), style_.collision_threshold, style_.warning_threshold);
    // Report the values actually in use back to the client.
    char buf[8];
    auto hex = [&buf](const Rgb& rgb) {
      std::snprintf(buf, sizeof(buf), "#%02x%02x%02x", rgb.r, rgb.g, rgb.b);
      return std::string(buf);
    };
    c.collision_threshold = style_.collision_threshold;
    c.warning_threshold = style_.warning_threshold;
    c.collision_colour = hex(style_.collision_colour);
    c.warning_colour = hex(style_.warning_colour);
    c.safe_colour = hex(style_.safe_colour);
    c.unknown_colour = hex(style_.unknown_colour);
    c.line_thickness = style_.line_thickness;
    c.circle_radius = style_.circle_radius;
    c.marker_size = style_.marker_size;
    c.draw_hud = style_.draw_hud;
    c.shaft_length = shaft_length_;
    c.draw_dvrk = draw_dvrk_;
    return;
  }
  style_ = s;
  shaft_length_ = c.shaft_length;
  draw_dvrk_ = c.draw_dvrk;
}

bool VisualFeedbackNodelet::transformPoint(const std::string& target, const std::string& source,
                                           const ros::Time& stamp, const cv::Point3d& p, cv::Point3d* out,
                                           bool* at_stamp, std::string* error) const
{
  // No timeout: never blocks the image callback.
  geometry_msgs::TransformStamped t;
  *at_stamp = true;
  try
  {
    t = tf_buffer_->lookupTransform(target, source, stamp);
  }
  catch (const tf2::TransformException&)
  {
    *at_stamp = false;
    try
    {
      t = tf_buffer_->lookupTransform(target, source, ros::Time(0));  // latest available
    }
    catch (const tf2::TransformException& e)
    {
      *error = e.what();
      return false;
    }
  }
  tf2::Transform tr;
  tf2::fromMsg(t.transform, tr);
  const tf2::Vector3 q = tr * tf2::Vector3(p.x, p.y, p.z);
  *out = cv::Point3d(q.x(), q.y(), q.z());
  return true;
}

void VisualFeedbackNodelet::imageCb(const sensor_msgs::ImageConstPtr& image,
                                    const sensor_msgs::CameraInfoConstPtr& info, std::size_t eye_index)
{
  const auto t0 = std::chrono::steady_clock::now();
  timespec c0;
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &c0);
  Eye& eye = eyes_[eye_index];
  std::lock_guard<std::mutex> eye_lock(eye.mutex);
  ++eye.received;
  eye.last_image_ns = static_cast<std::int64_t>(ros::WallTime::now().toNSec());

  std::string why;
  if (!imageBufferConsistent(*image, &why))
  {
    ++eye.rejected;
    NODELET_ERROR_THROTTLE(1.0, "%s image rejected: %s (%llu rejected so far)", eye.name.c_str(), why.c_str(),
                           static_cast<unsigned long long>(eye.rejected.load()));
    return;
  }
  if (!eye.info_seen || !sameCalibration(*info, eye.last_info))
  {
    eye.last_info = *info;
    eye.info_seen = true;
    CameraIntrinsics k;
    if (intrinsicsFromCameraInfo(*info, &k, &why) && eye.model.configure(k, &why))
      eye.model_error.clear();
    else
    {
      eye.model = CameraModel();
      eye.model_error = why;
    }
  }
  if (eye.model.valid() &&
      (eye.model.intrinsics().width != static_cast<int>(image->width) ||
       eye.model.intrinsics().height != static_cast<int>(image->height)))
    why = "camera_info size " + std::to_string(eye.model.intrinsics().width) + "x" +
          std::to_string(eye.model.intrinsics().height) + " != image size " + std::to_string(image->width) + "x" +
          std::to_string(image->height);
  else
    why = eye.model_error;
  const bool model_ok = why.empty();
  if (!model_ok)
    NODELET_ERROR_THROTTLE(5.0, "%s camera: %s; publishing the image without overlay", eye.name.c_str(), why.c_str());

  // Copy the input (shared and const when zero-copied from the camera nodelet) into an output
  // buffer from the pool: one memcpy, no allocation in steady state.
  sensor_msgs::ImagePtr out_msg;
  cv::Mat canvas;
  ChannelOrder order = ChannelOrder::kBgr;
  const std::string& e = image->encoding;
  const bool direct = e == enc::BGR8 || e == enc::BGRA8 || e == enc::RGB8 || e == enc::RGBA8;
  try
  {
    if (direct)
    {
      order = (e == enc::RGB8 || e == enc::RGBA8) ? ChannelOrder::kRgb : ChannelOrder::kBgr;
      out_msg = eye.pool.acquire(image->data.size());
      out_msg->header = image->header;
      out_msg->height = image->height;
      out_msg->width = image->width;
      out_msg->encoding = image->encoding;
      out_msg->is_bigendian = image->is_bigendian;
      out_msg->step = image->step;
      std::memcpy(out_msg->data.data(), image->data.data(), image->data.size());
      canvas = cv::Mat(static_cast<int>(image->height), static_cast<int>(image->width),
                       enc::numChannels(e) == 4 ? CV_8UC4 : CV_8UC3, out_msg->data.data(), image->step);
    }
    else
    {
      // mono, bayer, 16 bit: converted for colour drawing (allocates; not the endoscope's format).
      cv_bridge::CvImagePtr converted = cv_bridge::toCvCopy(image, enc::BGR8);
      out_msg = converted->toImageMsg();
      canvas = cv::Mat(static_cast<int>(out_msg->height), static_cast<int>(out_msg->width), CV_8UC3,
                       out_msg->data.data(), out_msg->step);
    }
  }
  catch (const std::exception& ex)
  {
    ++eye.rejected;
    NODELET_ERROR_THROTTLE(1.0, "%s image rejected: cannot convert encoding '%s' (%s)", eye.name.c_str(), e.c_str(),
                           ex.what());
    return;
  }

  // Snapshot of the latched state.
  const ros::Time now = ros::Time::now();
  OverlayStyle style;
  double shaft_length;
  bool draw_dvrk;
  std::array<ToolOverlay, kMaxTools> overlays;
  std::array<PoseLookupResult, kMaxTools> poses;  // status kEmpty: no fresh pose
  std::size_t n = 0;
  // The tools are drawn where they were when the image was taken: poses interpolated at the image
  // stamp (an unstamped image gets the newest poses, counted as fallbacks).
  const std::int64_t image_stamp_ns = image->header.stamp.isZero()
                                          ? std::numeric_limits<std::int64_t>::max()
                                          : static_cast<std::int64_t>(image->header.stamp.toNSec());
  {
    std::lock_guard<std::mutex> lock(state_mutex_);
    style = style_;
    shaft_length = shaft_length_;
    draw_dvrk = draw_dvrk_;
    const bool distances_fresh = !distances_received_.isZero() && (now - distances_received_).toSec() <= distances_timeout_;
    for (std::size_t i = 0; i < tools_.size() && n < kMaxTools; ++i)
    {
      const Tool& t = tools_[i];
      if (t.dvrk && !draw_dvrk)
        continue;
      ToolOverlay& o = overlays[n];
      o.label = t.label.c_str();
      o.distance = (distances_fresh && static_cast<std::size_t>(t.distance_index) < distances_.size())
                       ? distances_[t.distance_index]
                       : std::numeric_limits<double>::quiet_NaN();
      if (std::isinf(o.distance) && o.distance < 0)
        o.distance = std::numeric_limits<double>::quiet_NaN();
      const bool pose_fresh = !t.history.empty() && (now - t.pose_received).toSec() <= pose_timeout_;
      poses[n] = pose_fresh ? t.history.lookup(image_stamp_ns) : PoseLookupResult();
      if (pose_fresh)
        eye.pose_frames[n] = t.frame_id;  // string capacity reused: no allocation in steady state
      ++n;
    }
  }

  // Tool points in this eye's optical frame.
  const std::string& camera_frame = image->header.frame_id.empty() ? info->header.frame_id : image->header.frame_id;
  std::size_t k = 0;
  for (std::size_t i = 0; i < tools_.size() && k < n; ++i)
  {
    const Tool& t = tools_[i];
    if (t.dvrk && !draw_dvrk)
      continue;
    ToolOverlay& o = overlays[k];
    const PoseLookupResult& pose = poses[k];
    const std::string& pose_frame = eye.pose_frames[k];
    ++k;
    if (pose.status == PoseLookup::kEmpty || !model_ok)
      continue;
    const bool pose_at_stamp =
        pose.status == PoseLookup::kInterpolated ||
        (pose.status == PoseLookup::kAfterNewest && pose.offset_ns <= static_cast<std::int64_t>(pose_stamp_tolerance_ * 1e9));
    if (!pose_at_stamp)
    {
      ++eye.pose_fallbacks;
      if (image->header.stamp.isZero())
        NODELET_WARN_THROTTLE(2.0, "%s image has no stamp: drawing %s at its latest pose (%llu fallbacks)",
                              eye.name.c_str(), t.name.c_str(),
                              static_cast<unsigned long long>(eye.pose_fallbacks.load()));
      else
        NODELET_WARN_THROTTLE(2.0, "%s image stamp %.3f s is %.3f s %s the buffered poses of %s: drawing its latest "
                                   "pose (%llu fallbacks; see pose_buffer_size, pose_stamp_tolerance)",
                              eye.name.c_str(), image->header.stamp.toSec(), pose.offset_ns * 1e-9,
                              pose.status == PoseLookup::kAfterNewest ? "newer than" : "older than",
                              t.name.c_str(), static_cast<unsigned long long>(eye.pose_fallbacks.load()));
    }
    const cv::Point3d tip_in_pose(pose.pose.position[0], pose.pose.position[1], pose.pose.position[2]);
    bool at_stamp = true;
    if (!transformPoint(camera_frame, pose_frame, image->header.stamp, tip_in_pose, &o.tip, &at_stamp, &why))
    {
      ++eye.tf_failures;
      NODELET_ERROR_THROTTLE(2.0, "no transform %s -> %s for %s (%s); the tool is not drawn", pose_frame.c_str(),
                             camera_frame.c_str(), t.name.c_str(), why.c_str());
      continue;
    }
    if (!at_stamp)
    {
      ++eye.tf_fallbacks;
      NODELET_WARN_THROTTLE(2.0, "no transform %s -> %s at the image stamp %.3f s for %s: latest used (%llu fallbacks)",
                            pose_frame.c_str(), camera_frame.c_str(), image->header.stamp.toSec(), t.name.c_str(),
                            static_cast<unsigned long long>(eye.tf_fallbacks.load()));
    }
    o.visible = true;
    cv::Point3d rcm;
    if (!t.rcm_frame.empty())
    {
      // The shaft's far point (towards the trocar) at the image stamp too.
      if (transformPoint(camera_frame, t.rcm_frame, image->header.stamp, cv::Point3d(0, 0, 0), &rcm, &at_stamp, &why))
      {
        if (!at_stamp)
        {
          ++eye.tf_fallbacks;
          NODELET_WARN_THROTTLE(2.0, "no transform %s -> %s at the image stamp %.3f s for %s's shaft: latest used "
                                     "(%llu fallbacks)",
                                t.rcm_frame.c_str(), camera_frame.c_str(), image->header.stamp.toSec(),
                                t.name.c_str(), static_cast<unsigned long long>(eye.tf_fallbacks.load()));
        }
        const cv::Point3d d = rcm - o.tip;
        const double len = std::sqrt(d.dot(d));
        if (len > 1e-6)
        {
          o.shaft = len > shaft_length ? o.tip + (shaft_length / len) * d : rcm;
          o.has_shaft = true;
        }
      }
      else
      {
        ++eye.tf_failures;
        NODELET_ERROR_THROTTLE(2.0, "no transform %s -> %s for %s's shaft (%s); drawing its tip only",
                               t.rcm_frame.c_str(), camera_frame.c_str(), t.name.c_str(), why.c_str());
      }
    }
  }

  if (model_ok)
  {
    std::array<ToolDrawResult, kMaxTools> results;
    drawOverlay(canvas, order, eye.model, style, overlays.data(), n, results.data(), nullptr, &eye.hud);
    // Colour census: frames in which a tool was drawn (shaft or border marker) in each colour.
    std::array<bool, 4> seen{};
    for (std::size_t i = 0; i < n; ++i)
      if (results[i].drawn != ToolDrawn::kNothing)
        seen[static_cast<std::size_t>(results[i].proximity)] = true;
    for (std::size_t c = 0; c < seen.size(); ++c)
      if (seen[c])
        ++eye.colour_frames[c];
  }
  else
  {
    const std::string line = "overlay off: " + why.substr(0, 60);
    CameraModel placeholder;
    CameraIntrinsics ki;
    ki.width = canvas.cols;
    ki.height = canvas.rows;
    ki.fx = ki.fy = 1.0;
    placeholder.configure(ki, nullptr);
    for (std::size_t i = 0; i < n; ++i)
      overlays[i].visible = false;
    drawOverlay(canvas, order, placeholder, style, overlays.data(), n, nullptr, line.c_str(), &eye.hud);
  }
  if (eye.pub.getNumSubscribers() > 0)
    eye.pub.publish(sensor_msgs::ImageConstPtr(out_msg));
  if (eye.compressed_pub.getNumSubscribers() > 0)
  {
    cv::Mat bgr = canvas;
    if (canvas.channels() == 4)
      cv::cvtColor(canvas, eye.jpeg_bgr, order == ChannelOrder::kRgb ? cv::COLOR_RGBA2BGR : cv::COLOR_BGRA2BGR);
    else if (order == ChannelOrder::kRgb)
      cv::cvtColor(canvas, eye.jpeg_bgr, cv::COLOR_RGB2BGR);
    if (canvas.channels() == 4 || order == ChannelOrder::kRgb)
      bgr = eye.jpeg_bgr;
    sensor_msgs::CompressedImagePtr jpeg = boost::make_shared<sensor_msgs::CompressedImage>();
    jpeg->header = out_msg->header;
    jpeg->format = out_msg->encoding + "; jpeg compressed bgr8";
    const std::vector<int> params{cv::IMWRITE_JPEG_QUALITY, jpeg_quality_};
    if (cv::imencode(".jpg", bgr, jpeg->data, params))
      eye.compressed_pub.publish(jpeg);
  }
  ++eye.published;
  const auto ns = static_cast<std::uint64_t>(
      std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now() - t0).count());
  eye.busy_ns += ns;
  atomicMax(eye.max_busy_ns, ns);
  timespec c1;
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &c1);
  eye.cpu_ns += static_cast<std::uint64_t>((c1.tv_sec - c0.tv_sec) * 1000000000LL + (c1.tv_nsec - c0.tv_nsec));
}

void VisualFeedbackNodelet::statusTimerCb(const ros::WallTimerEvent& /*event*/)
{
  const ros::WallTime now = ros::WallTime::now();
  saras_msgs::ComponentStatus msg;
  msg.component = component_;
  std::uint64_t received = 0, rejected = 0, tf_failures = 0, fallbacks = 0;
  std::array<std::uint64_t, 4> colours{};
  std::int64_t last_ns = 0;
  bool subscribed = false;
  std::string model_errors;
  for (const Eye& e : eyes_)
  {
    received += e.received;
    rejected += e.rejected;
    tf_failures += e.tf_failures;
    fallbacks += e.pose_fallbacks + e.tf_fallbacks;
    for (std::size_t c = 0; c < colours.size(); ++c)
      colours[c] += e.colour_frames[c];
    last_ns = std::max(last_ns, e.last_image_ns.load());
    subscribed = subscribed || e.pub.getNumSubscribers() > 0 || e.compressed_pub.getNumSubscribers() > 0;
  }
  {
    std::lock_guard<std::mutex> lock(state_mutex_);
    rejected += distances_rejected_;
    for (const Tool& t : tools_)
      rejected += t.rejected;
  }
  msg.received = received;
  msg.rejected = rejected;
  msg.input_age = last_ns > 0 ? (now.toNSec() - last_ns) * 1e-9 : std::numeric_limits<double>::infinity();
  std::ostringstream text;
  if (!subscribed)
  {
    msg.level = saras_msgs::ComponentStatus::OK;
    text << "idle: no subscribers to the augmented images";
  }
  else if (!(msg.input_age <= image_timeout_))
  {
    msg.level = saras_msgs::ComponentStatus::STALE;
    text << "no endoscope image for " << (std::isfinite(msg.input_age) ? msg.input_age : -1.0) << " s";
  }
  else
  {
    msg.level = saras_msgs::ComponentStatus::OK;
    for (const Eye& e : eyes_)
    {
      const std::uint64_t pub = e.published;
      text << e.name << ": " << e.received.load() << " in, " << pub << " out";
      if (pub > 0)
        text << ", mean " << (e.busy_ns.load() / 1e6 / static_cast<double>(pub))
             << " ms, max " << e.max_busy_ns.load() / 1e6 << " ms, cpu mean "
             << (e.cpu_ns.load() / 1e6 / static_cast<double>(pub)) << " ms; ";
      else
        text << "; ";
    }
    text << "frames per colour (both eyes): red " << colours[static_cast<int>(Proximity::kCollision)] << ", yellow "
         << colours[static_cast<int>(Proximity::kWarning)] << ", green " << colours[static_cast<int>(Proximity::kSafe)]
         << ", grey " << colours[static_cast<int>(Proximity::kUnknown)] << "; ";
    if (tf_failures > tf_failures_reported_)
    {
      msg.level = saras_msgs::ComponentStatus::WARN;
      text << (tf_failures - tf_failures_reported_) << " missing transforms in the last period; ";
    }
    if (fallbacks > fallbacks_reported_)
    {
      msg.level = saras_msgs::ComponentStatus::WARN;
      text << (fallbacks - fallbacks_reported_) << " poses/transforms not at the image stamp (latest used) in the "
           << "last period; ";
    }
  }
  msg.message = text.str();
  if (msg.level != last_level_ || (now - last_status_).toSec() >= 1.0)
  {
    msg.header.stamp = ros::Time::now();
    status_pub_.publish(msg);
    last_level_ = msg.level;
    last_status_ = now;
    tf_failures_reported_ = tf_failures;
    fallbacks_reported_ = fallbacks;
  }
}

}  // namespace saras_visual_feedback

PLUGINLIB_EXPORT_CLASS(saras_visual_feedback::VisualFeedbackNodelet, nodelet::Nodelet)
