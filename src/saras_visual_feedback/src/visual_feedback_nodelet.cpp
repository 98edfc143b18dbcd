#include "saras_visual_feedback/visual_feedback_nodelet.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <ctime>
#include <limits>

#include <boost/bind/bind.hpp>
#include <pluginlib/class_list_macros.hpp>
#include <sensor_msgs/CompressedImage.h>

namespace saras_visual_feedback
{
namespace
{
constexpr char kCompressedPlugin[] = "image_transport/compressed";

std::uint64_t threadCpuNs()
{
  timespec t;
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<std::uint64_t>(t.tv_sec) * 1000000000ULL + static_cast<std::uint64_t>(t.tv_nsec);
}

std::string hexColour(const Rgb& rgb)
{
  char buf[8];
  std::snprintf(buf, sizeof(buf), "#%02x%02x%02x", rgb.r, rgb.g, rgb.b);
  return buf;
}

/// The dynamic_reconfigure view of @p s.
void toConfig(const SceneStyle& s, VisualFeedbackConfig* c)
{
  c->collision_threshold = s.overlay.collision_threshold;
  c->warning_threshold = s.overlay.warning_threshold;
  c->collision_colour = hexColour(s.overlay.collision_colour);
  c->warning_colour = hexColour(s.overlay.warning_colour);
  c->safe_colour = hexColour(s.overlay.safe_colour);
  c->unknown_colour = hexColour(s.overlay.unknown_colour);
  c->line_thickness = s.overlay.line_thickness;
  c->circle_radius = s.overlay.circle_radius;
  c->marker_size = s.overlay.marker_size;
  c->draw_hud = s.overlay.draw_hud;
  c->shaft_length = s.shaft_length;
  c->draw_dvrk = s.draw_dvrk;
}
}  // namespace

VisualFeedbackNodelet::~VisualFeedbackNodelet()
{
  diagnostics_timer_.stop();
  // Unloading: shut the subscriptions and publishers down here, under connect_mutex_, so that a
  // connection callback racing with the destruction (a viewer leaving as the publishers go away)
  // cannot shut the same subscription down concurrently with the member destructors.
  std::lock_guard<std::mutex> lock(connect_mutex_);
  shutting_down_ = true;
  for (Eye& eye : eyes_)
  {
    eye.sub.shutdown();
    eye.pub.shutdown();
    eye.jpeg_pub.shutdown();
  }
  for (ros::Subscriber& s : pose_subs_)
    s.shutdown();
  distances_sub_.shutdown();
}

void VisualFeedbackNodelet::onInit()
{
  try
  {
    params_ = readVisualFeedbackParams(getPrivateNodeHandle());
  }
  catch (const std::exception& e)
  {
    NODELET_FATAL("%s", e.what());
    throw;  // nodelet::Loader::load() fails: `nodelet standalone` and `nodelet load` exit non-zero
  }
  const VisualFeedbackParams& p = params_;
  scene_.reset(new ToolScene(p.tools, static_cast<std::size_t>(p.pose_buffer_size),
                             static_cast<std::int64_t>(p.pose_timeout * 1e9),
                             static_cast<std::int64_t>(p.distances_timeout * 1e9), p.style));
  pose_subs_.resize(p.tools.size());
  tf_buffer_.reset(new tf2_ros::Buffer(ros::Duration(10.0)));
  tf_listener_.reset(new tf2_ros::TransformListener(*tf_buffer_, getNodeHandle()));
  tf_points_.reset(new TfPointTransformer(*tf_buffer_));
  // Multi-threaded handle: the two eyes are processed in parallel (each eye's callback is
  // serialised by its own mutex, as image and camera_info may complete a pair from two threads).
  it_ = std::make_shared<image_transport::ImageTransport>(getMTNodeHandle());
  eyes_[0].name = "left";
  eyes_[1].name = "right";
  for (Eye& eye : eyes_)
    eye.jpeg.reset(new JpegEncoder(p.jpeg_quality));  // validated in [1, 100]
  startReconfigure();

  // Diagnostics under this nodelet's name (not the manager's), hardware_id visual_feedback.
  updater_.reset(new diagnostic_updater::Updater(getNodeHandle(), getPrivateNodeHandle(), getName()));
  updater_->setHardwareID("visual_feedback");
  updater_->add("augmented images", this, &VisualFeedbackNodelet::diagnose);
  last_report_ = ros::WallTime::now();
  diagnostics_timer_ =
      getNodeHandle().createWallTimer(ros::WallDuration(0.1), [this](const ros::WallTimerEvent&) { updater_->update(); });
  advertise();
}

void VisualFeedbackNodelet::startReconfigure()
{
  reconfigure_server_.reset(new ReconfigureServer(reconfigure_mutex_, getPrivateNodeHandle()));
  VisualFeedbackConfig c;  // the server starts from the validated start-up values
  reconfigure_server_->getConfigDefault(c);
  toConfig(params_.style, &c);
  reconfigure_server_->updateConfig(c);
  reconfigure_server_->setCallback(
      boost::bind(&VisualFeedbackNodelet::reconfigureCb, this, boost::placeholders::_1, boost::placeholders::_2));
}

bool VisualFeedbackNodelet::compressedPluginActive(const std::string& topic) const
{
  const std::vector<std::string> loadable = it_->getLoadableTransports();
  if (std::find(loadable.begin(), loadable.end(), kCompressedPlugin) == loadable.end())
    return false;
  std::vector<std::string> disabled;  // image_transport's own per-topic blacklist
  getNodeHandle().getParam(topic + "/disable_pub_plugins", disabled);
  return std::find(disabled.begin(), disabled.end(), kCompressedPlugin) == disabled.end();
}

void VisualFeedbackNodelet::advertise()
{
  // Advertise under connect_mutex_ so that connectCb cannot run before the publishers exist.
  std::lock_guard<std::mutex> lock(connect_mutex_);
  image_transport::SubscriberStatusCallback cb = boost::bind(&VisualFeedbackNodelet::connectCb, this);
  ros::SubscriberStatusCallback ros_cb = boost::bind(&VisualFeedbackNodelet::connectCb, this);
  const auto queue = static_cast<uint32_t>(params_.queue_size);
  for (Eye& eye : eyes_)
  {
    // Publisher queue: only used for subscribers in other processes (serialised frames waiting
    // for the socket); intra-process subscribers get the shared pointer in their own queue.
    eye.pub = it_->advertise(eye.name + "/image", queue, cb, cb);
    // One /compressed stream per eye: image_transport's plugin when it is active, else ours.
    own_jpeg_ = !compressedPluginActive(eye.pub.getTopic());
    if (own_jpeg_)
      eye.jpeg_pub = getMTNodeHandle().advertise<sensor_msgs::CompressedImage>(eye.pub.getTopic() + "/compressed", 1,
                                                                               ros_cb, ros_cb);
  }
  NODELET_INFO("VisualFeedback ready: %zu tools, thresholds collision %.4f m, warning %.4f m, /compressed by %s "
               "(lazy: waiting for subscribers of %s and %s)",
               params_.tools.size(), params_.style.overlay.collision_threshold,
               params_.style.overlay.warning_threshold, own_jpeg_ ? "this nodelet" : "image_transport",
               eyes_[0].pub.getTopic().c_str(), eyes_[1].pub.getTopic().c_str());
}

void VisualFeedbackNodelet::connectCb()
{
  std::lock_guard<std::mutex> lock(connect_mutex_);
  if (shutting_down_)
    return;
  bool any = false;
  for (std::size_t i = 0; i < eyes_.size(); ++i)
  {
    Eye& eye = eyes_[i];
    if (eye.pub.getNumSubscribers() == 0 && eye.jpeg_pub.getNumSubscribers() == 0)
    {
      if (eye.sub)
        eye.sub.shutdown();
      continue;
    }
    any = true;
    if (!eye.sub)
    {
      image_transport::TransportHints hints("raw", ros::TransportHints().tcpNoDelay(), getPrivateNodeHandle());
      eye.sub = it_->subscribeCamera(
          eye.name + "/image_raw", static_cast<uint32_t>(params_.queue_size),
          boost::bind(&VisualFeedbackNodelet::imageCb, this, boost::placeholders::_1, boost::placeholders::_2, i),
          ros::VoidPtr(), hints);
    }
  }
  if (any == subscribed_inputs_)
    return;
  ros::NodeHandle& nh = getMTNodeHandle();
  for (std::size_t i = 0; i < pose_subs_.size(); ++i)
    if (any)
      pose_subs_[i] = nh.subscribe<geometry_msgs::PoseStamped>(
          params_.tools[i].pose_topic, 1, boost::bind(&VisualFeedbackNodelet::poseCb, this, boost::placeholders::_1, i),
          ros::VoidConstPtr(), ros::TransportHints().tcpNoDelay());
    else
      pose_subs_[i].shutdown();
  if (any)
    distances_sub_ =
        nh.subscribe("distances", 1, &VisualFeedbackNodelet::distancesCb, this, ros::TransportHints().tcpNoDelay());
  else
    distances_sub_.shutdown();
  subscribed_inputs_ = any;
}

void VisualFeedbackNodelet::poseCb(const geometry_msgs::PoseStampedConstPtr& msg, std::size_t i)
{
  const ToolConfig& t = params_.tools[i];
  const ros::Time now = ros::Time::now();
  TimedPose sample;
  std::string why;
  if (!poseSampleFromMsg(*msg, now, &sample, &why))
  {
    const std::uint64_t n = scene_->rejectPose(i);
    NODELET_ERROR_THROTTLE(1.0, "rejected pose of %s on %s (%s); %llu rejected so far; the tool is not drawn once "
                                "the last valid pose is older than %.2f s",
                           t.name.c_str(), t.pose_topic.c_str(), why.c_str(), static_cast<unsigned long long>(n),
                           params_.pose_timeout);
    return;
  }
  if (scene_->addPose(i, msg->header.frame_id, sample, static_cast<std::int64_t>(now.toNSec())) ==
      PosePush::kRestarted)
    NODELET_WARN_THROTTLE(5.0, "pose stamps of %s on %s went backwards (clock reset?): pose history restarted",
                          t.name.c_str(), t.pose_topic.c_str());
}

void VisualFeedbackNodelet::distancesCb(const std_msgs::Float64MultiArrayConstPtr& msg)
{
  // NaN entries stay NaN: drawn as unknown.
  if (!scene_->setDistances(msg->data, static_cast<std::int64_t>(ros::Time::now().toNSec())))
    NODELET_WARN_THROTTLE(5.0, "/collision/distances has %zu values, %zu expected: missing ones are drawn as unknown",
                          msg->data.size(), scene_->distancesNeeded());
}

void VisualFeedbackNodelet::reconfigureCb(VisualFeedbackConfig& c, uint32_t /*level*/)
{
  SceneStyle s = scene_->style();
  const SceneStyle current = s;
  OverlayStyle& o = s.overlay;
  o.collision_threshold = c.collision_threshold;
  o.warning_threshold = c.warning_threshold;
  o.line_thickness = c.line_thickness;
  o.circle_radius = c.circle_radius;
  o.marker_size = c.marker_size;
  o.draw_hud = c.draw_hud;
  s.shaft_length = c.shaft_length;
  s.draw_dvrk = c.draw_dvrk;
  std::string why = "colours must be \"#RRGGBB\"";
  const bool ok = parseColour(c.collision_colour, &o.collision_colour) &&
                  parseColour(c.warning_colour, &o.warning_colour) && parseColour(c.safe_colour, &o.safe_colour) &&
                  parseColour(c.unknown_colour, &o.unknown_colour) && validateStyle(o, &why);
  if (ok)
  {
    scene_->setStyle(s);
    return;
  }
  NODELET_ERROR("dynamic_reconfigure request rejected (%s); keeping collision_threshold %.4f m, warning_threshold "
                "%.4f m",
                why.c_str(), current.overlay.collision_threshold, current.overlay.warning_threshold);
  toConfig(current, &c);  // report the values actually in use back to the client
}

void VisualFeedbackNodelet::imageCb(const sensor_msgs::ImageConstPtr& image,
                                    const sensor_msgs::CameraInfoConstPtr& info, std::size_t eye_index)
{
  const auto t0 = std::chrono::steady_clock::now();
  const std::uint64_t cpu0 = threadCpuNs();
  Eye& eye = eyes_[eye_index];
  std::lock_guard<std::mutex> eye_lock(eye.mutex);
  ++eye.stats.received;
  eye.stats.last_image_ns = static_cast<std::int64_t>(ros::WallTime::now().toNSec());

  sensor_msgs::ImagePtr out;
  cv::Mat canvas;
  ChannelOrder order;
  std::string why;
  if (!prepareCanvas(image, &eye.pool, &out, &canvas, &order, &why))
  {
    ++eye.stats.rejected;
    NODELET_ERROR_THROTTLE(1.0, "%s image rejected: %s (%llu rejected so far)", eye.name.c_str(), why.c_str(),
                           static_cast<unsigned long long>(eye.stats.rejected.load()));
    return;
  }
  const std::string& off = eye.camera.update(*info, image->width, image->height);
  if (!off.empty())
    NODELET_ERROR_THROTTLE(5.0, "%s camera: %s; publishing the image without overlay", eye.name.c_str(), off.c_str());

  // The tools are drawn where they were when the image was taken: poses interpolated at the image
  // stamp, transforms looked up at it (an unstamped image gets the newest, counted as fallbacks).
  const std::int64_t stamp_ns =
      image->header.stamp.isZero() ? kLatestStamp : static_cast<std::int64_t>(image->header.stamp.toNSec());
  scene_->snapshot(static_cast<std::int64_t>(ros::Time::now().toNSec()), stamp_ns, &eye.scene);
  std::array<ToolOverlay, kMaxTools> overlays;
  FrameReport report;
  if (off.empty())
  {
    const std::string& camera_frame = image->header.frame_id.empty() ? info->header.frame_id : image->header.frame_id;
    placeTools(eye.scene, camera_frame, stamp_ns, static_cast<std::int64_t>(params_.pose_stamp_tolerance * 1e9),
               *tf_points_, overlays.data(), &report);
  }
  drawFrame(canvas, order, off.empty() ? &eye.camera.projector() : nullptr, off, eye.scene, overlays.data(), &eye.hud,
            &report);
  warnFrame(eye, *image, report);
  eye.stats.record(report);
  publish(eye, out, canvas, order);
  eye.stats.addTiming(static_cast<std::uint64_t>(std::chrono::duration_cast<std::chrono::nanoseconds>(
                                                     std::chrono::steady_clock::now() - t0)
                                                     .count()),
                      threadCpuNs() - cpu0);
}

void VisualFeedbackNodelet::publish(Eye& eye, const sensor_msgs::ImagePtr& out, const cv::Mat& canvas,
                                    ChannelOrder order)
{
  // image_transport publishes raw and, when installed, its plugins (compressed, theora, ...)
  // to their subscribers only.
  if (eye.pub.getNumSubscribers() > 0)
    eye.pub.publish(sensor_msgs::ImageConstPtr(out));
  if (eye.jpeg_pub && eye.jpeg_pub.getNumSubscribers() > 0)
  {
    // pooled: the encoder writes into the capacity of a previous frame's message
    sensor_msgs::CompressedImagePtr jpeg = eye.jpeg_pool.next();
    jpeg->header = out->header;
    std::string why;
    if (encodeJpeg(canvas, order, out->encoding, eye.jpeg.get(), jpeg.get(), &why))
      eye.jpeg_pub.publish(sensor_msgs::CompressedImageConstPtr(jpeg));
    else
      NODELET_ERROR_THROTTLE(5.0, "%s/image/compressed not published: %s", eye.name.c_str(), why.c_str());
  }
}

void VisualFeedbackNodelet::warnFrame(const Eye& eye, const sensor_msgs::Image& image, const FrameReport& report) const
{
  for (std::size_t i = 0; i < report.n; ++i)
  {
    const ToolPlacement& p = report.tools[i];
    const ToolSample& s = eye.scene.tools[i];
    const char* name = s.tool->name.c_str();
    if (p.pose_fallback)
      NODELET_WARN_THROTTLE(2.0, "%s image stamp %.3f s: %s drawn at its latest pose, %.3f s away (%llu fallbacks; "
                                 "see pose_buffer_size, pose_stamp_tolerance)",
                            eye.name.c_str(), image.header.stamp.toSec(), name, s.pose.offset_ns * 1e-9,
                            static_cast<unsigned long long>(eye.stats.pose_fallbacks.load()));
    if (p.tip_failed || p.shaft_failed)
      NODELET_ERROR_THROTTLE(2.0, "no transform to %s for %s%s (%s)", image.header.frame_id.c_str(), name,
                             p.tip_failed ? ": not drawn" : "'s shaft: tip only", p.error.c_str());
    if (p.transform_fallbacks > 0)
      NODELET_WARN_THROTTLE(2.0, "no transform at the image stamp %.3f s for %s: latest used (%llu fallbacks)",
                            image.header.stamp.toSec(), name,
                            static_cast<unsigned long long>(eye.stats.tf_fallbacks.load()));
  }
}

void VisualFeedbackNodelet::diagnose(diagnostic_updater::DiagnosticStatusWrapper& stat)
{
  using diagnostic_msgs::DiagnosticStatus;
  const ros::WallTime now = ros::WallTime::now();
  const double period = std::max(1e-3, (now - last_report_).toSec());
  last_report_ = now;
  std::int64_t last_ns = 0;
  std::uint64_t problems = 0;
  std::array<std::uint64_t, 4> colours{};
  bool subscribed = false;
  for (Eye& e : eyes_)
  {
    const EyeStats& s = e.stats;
    const std::uint64_t pub = s.published;
    stat.addf(e.name + " frames in", "%llu", static_cast<unsigned long long>(s.received.load()));
    stat.addf(e.name + " frames out", "%llu", static_cast<unsigned long long>(pub));
    stat.addf(e.name + " output rate [Hz]", "%.1f", (pub - e.published_reported) / period);
    stat.addf(e.name + " rejected images", "%llu", static_cast<unsigned long long>(s.rejected.load()));
    stat.addf(e.name + " mean processing [ms]", "%.3f", pub > 0 ? s.busy_ns.load() / 1e6 / pub : 0.0);
    stat.addf(e.name + " max processing [ms]", "%.3f", s.max_busy_ns.load() / 1e6);
    stat.addf(e.name + " mean CPU [ms]", "%.3f", pub > 0 ? s.cpu_ns.load() / 1e6 / pub : 0.0);
    e.published_reported = pub;
    for (std::size_t c = 0; c < colours.size(); ++c)
      colours[c] += s.colour_frames[c];
    problems += s.tf_failures + s.pose_fallbacks + s.tf_fallbacks;
    last_ns = std::max(last_ns, s.last_image_ns.load());
    subscribed = subscribed || e.pub.getNumSubscribers() > 0 || e.jpeg_pub.getNumSubscribers() > 0;
  }
  const char* names[4] = {"grey", "green", "yellow", "red"};  // indexed by Proximity
  for (std::size_t c = 0; c < colours.size(); ++c)
    stat.addf(std::string("frames with a ") + names[c] + " tool", "%llu", static_cast<unsigned long long>(colours[c]));
  std::uint64_t tf_failures = 0, pose_fallbacks = 0, tf_fallbacks = 0;
  for (const Eye& e : eyes_)
  {
    tf_failures += e.stats.tf_failures;
    pose_fallbacks += e.stats.pose_fallbacks;
    tf_fallbacks += e.stats.tf_fallbacks;
  }
  stat.addf("missing transforms", "%llu", static_cast<unsigned long long>(tf_failures));
  stat.addf("poses not at the image stamp", "%llu", static_cast<unsigned long long>(pose_fallbacks));
  stat.addf("transforms not at the image stamp", "%llu", static_cast<unsigned long long>(tf_fallbacks));
  const SceneCounters sc = scene_->counters();
  stat.addf("rejected poses", "%llu", static_cast<unsigned long long>(sc.rejected_poses));
  stat.addf("rejected distance arrays", "%llu", static_cast<unsigned long long>(sc.rejected_distances));
  stat.addf("pose history restarts", "%llu", static_cast<unsigned long long>(sc.history_restarts));
  stat.add("compressed stream", own_jpeg_ ? "visual_feedback" : "image_transport");
  // signed: an image may arrive between `now` and reading its counter (a negative age is 0, not 584 years)
  const double age = last_ns > 0 ? std::max<std::int64_t>(0, static_cast<std::int64_t>(now.toNSec()) - last_ns) * 1e-9
                                 : std::numeric_limits<double>::infinity();
  stat.addf("image age [s]", "%.3f", age);
  if (!subscribed)
    stat.summary(DiagnosticStatus::OK, "idle: no subscribers to the augmented images");
  else if (!(age <= params_.image_timeout))
    stat.summaryf(DiagnosticStatus::STALE, "no endoscope image for %.1f s", std::isfinite(age) ? age : -1.0);
  else if (problems > problems_reported_)
    stat.summaryf(DiagnosticStatus::WARN, "%llu missing transforms or poses/transforms not at the image stamp in "
                                          "the last period",
                  static_cast<unsigned long long>(problems - problems_reported_));
  else
    stat.summary(DiagnosticStatus::OK, "augmenting");
  problems_reported_ = problems;
}

}  // namespace saras_visual_feedback

PLUGINLIB_EXPORT_CLASS(saras_visual_feedback::VisualFeedbackNodelet, nodelet::Nodelet)
