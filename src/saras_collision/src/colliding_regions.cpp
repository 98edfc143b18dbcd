#include "saras_collision/colliding_regions.h"

#include <cmath>
#include <limits>

#include <saras_common/params.h>
#include <tf2_eigen/tf2_eigen.h>

#include "saras_collision/vertices_file.h"

namespace saras_collision
{
namespace
{
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

geometry_msgs::Point toPoint(const Eigen::Vector3d& v)
{
  geometry_msgs::Point p;
  p.x = v.x();
  p.y = v.y();
  p.z = v.z();
  return p;
}

std_msgs::ColorRGBA color(float r, float g, float b, float a)
{
  std_msgs::ColorRGBA c;
  c.r = r;
  c.g = g;
  c.b = b;
  c.a = a;
  return c;
}

std_msgs::ColorRGBA zoneColor(Zone zone)
{
  switch (zone)
  {
    case Zone::kCollision:
      return color(1.0f, 0.0f, 0.0f, 0.9f);
    case Zone::kWarning:
      return color(1.0f, 0.65f, 0.0f, 0.9f);
    case Zone::kSafe:
      return color(0.0f, 0.8f, 0.0f, 0.9f);
    default:
      return color(0.5f, 0.5f, 0.5f, 0.6f);
  }
}

/// Quaternion of a box frame (columns may be left-handed: then z is flipped, the cube is symmetric).
Eigen::Quaterniond boxOrientation(const Eigen::Matrix3d& axes)
{
  Eigen::Matrix3d m = axes;
  if (m.determinant() < 0.0)
    m.col(2) = -m.col(2);
  return Eigen::Quaterniond(m).normalized();
}
}  // namespace

namespace
{
/// The per-tool parameters under ~tool/<name>/.
CollidingRegionsConfig::Tool loadTool(const saras_common::Params& p, const std::string& name)
{
  using saras_common::nonEmpty;
  CollidingRegionsConfig::Tool t;
  t.name = name;
  const std::string prefix = "tool/" + name + "/";
  for (const char* required : { "topic", "frame", "trocar_frame", "radius" })
    if (!p.has(prefix + required))
      p.fail(prefix + required, "(not set)", "", "set (see config/colliding_regions.yaml)");
  t.topic = p.text(prefix + "topic", "", { nonEmpty() });  // tool-tip PoseStamped topic
  t.frame = p.text(prefix + "frame", "", { nonEmpty() });  // frame of the pose when its header has none
  t.trocar_frame = p.text(prefix + "trocar_frame", "", { nonEmpty() });  // TF frame at the trocar / RCM
  t.radius = p.number(prefix + "radius", 0.0, "m", { saras_common::inRange(0.0, 0.05) });  // shaft radius
  t.fixture_topic = p.text(prefix + "fixture_topic", "");
  return t;
}
}  // namespace

bool loadConfig(const ros::NodeHandle& pnh, CollidingRegionsConfig& c, std::string& error)
{
  using saras_common::inRange;
  using saras_common::nonEmpty;
  using saras_common::nonNegative;
  using saras_common::positive;
  try
  {
    const saras_common::Params p(pnh);
    c.rate = p.number("rate", c.rate, "Hz", { positive(), saras_common::atMost(10000.0) });
    if (!p.has("vertices_file"))
      p.fail("vertices_file", "(not set)", "", "the path of the forbidden-region vertices file");
    c.vertices_file = p.text("vertices_file", "", { nonEmpty() });
    c.scaling = p.number("scaling", c.scaling, "file unit -> m", { positive() });
    c.vertex_tolerance = p.number("vertex_tolerance", c.vertex_tolerance, "", { inRange(0.0, 0.1) });
    c.collision_threshold = p.number("thresholds/collision", c.collision_threshold, "m", { nonNegative() });
    c.warning_threshold = p.number("thresholds/warning", c.warning_threshold, "m");
    if (!(c.warning_threshold > c.collision_threshold))
      p.fail("thresholds/warning", c.warning_threshold, "m", "> thresholds/collision");
    c.tf_timeout = p.number("tf_timeout", c.tf_timeout, "s", { positive() });
    c.pose_timeout = p.number("pose_timeout", c.pose_timeout, "s", { positive() });
    c.marker_rate = p.number("marker_rate", c.marker_rate, "Hz (0: off)", { nonNegative() });
    c.world_frame = p.text("world_frame", c.world_frame, { nonEmpty() });
    c.bones_frame = p.text("bones_frame", c.bones_frame, { nonEmpty() });
    c.fixture_enabled = p.flag("fixture/enabled", c.fixture_enabled);
    c.fixture_stiffness = p.number("fixture/stiffness", c.fixture_stiffness, "N/m", { nonNegative() });
    c.fixture_max_force = p.number("fixture/max_force", c.fixture_max_force, "N", { nonNegative() });
    // Order of /collision/distances and /collision/report.
    const std::vector<std::string> names = p.texts("tools", {}, { nonEmpty() });
    if (names.empty())
      p.fail("tools", "(empty or not set)", "", "a non-empty list of tool names");
    c.tools.clear();
    for (const std::string& name : names)
      c.tools.push_back(loadTool(p, name));
  }
  catch (const saras_common::ParamError& e)
  {
    error = e.what();
    return false;
  }
  return true;
}

CollidingRegions::CollidingRegions(const ros::NodeHandle& nh, const CollidingRegionsConfig& config)
  : nh_(nh)
  , config_(config)
  , scene_([&config] {
    std::vector<ToolSpec> specs;
    for (const auto& t : config.tools)
      specs.push_back(ToolSpec{ t.name, t.radius });
    return specs;
  }())
  , tools_(config.tools.size())
  , updater_(nh)
{
}

bool CollidingRegions::start(std::string& error)
{
  if (!loadVerticesFile(config_.vertices_file, config_.scaling, config_.vertex_tolerance, boxes_bones_, error))
    return false;
  boxes_world_ = boxes_bones_;
  for (std::size_t i = 0; i < boxes_bones_.size(); ++i)
    box_names_.push_back("bone_" + std::to_string(i));
  ROS_INFO("colliding_regions: %zu forbidden-region boxes from %s (scaling %g), %zu tools, %.1f Hz",
           boxes_bones_.size(), config_.vertices_file.c_str(), config_.scaling, tools_.size(), config_.rate);

  tf_listener_.reset(new tf2_ros::TransformListener(tf_buffer_, nh_));
  const std::size_t n = tools_.size();
  distances_msg_.data.assign(n, kNaN);
  distances_msg_.layout.dim.resize(1);
  distances_msg_.layout.dim[0].label = "tool";
  distances_msg_.layout.dim[0].size = static_cast<uint32_t>(n);
  distances_msg_.layout.dim[0].stride = static_cast<uint32_t>(n);
  report_msg_.header.frame_id = config_.world_frame;
  report_msg_.tools.resize(n);
  for (std::size_t i = 0; i < n; ++i)
    report_msg_.tools[i].tool = config_.tools[i].name;

  distances_pub_ = nh_.advertise<std_msgs::Float64MultiArray>("/collision/distances", 10);
  report_pub_ = nh_.advertise<saras_msgs::CollisionReport>("/collision/report", 10);
  markers_pub_ = nh_.advertise<visualization_msgs::MarkerArray>("/collision/markers", 2);
  for (std::size_t i = 0; i < n; ++i)
  {
    tools_[i].frame = config_.tools[i].frame;
    const boost::function<void(const geometry_msgs::PoseStampedConstPtr&)> callback =
        [this, i](const geometry_msgs::PoseStampedConstPtr& msg) { poseCallback(i, msg); };
    tools_[i].sub = nh_.subscribe<geometry_msgs::PoseStamped>(config_.tools[i].topic, 10, callback,
                                                              ros::VoidConstPtr(), ros::TransportHints().tcpNoDelay());
    if (config_.fixture_enabled && !config_.tools[i].fixture_topic.empty())
    {
      tools_[i].fixture_pub = nh_.advertise<geometry_msgs::WrenchStamped>(config_.tools[i].fixture_topic, 10);
      tools_[i].wrench.header.frame_id = config_.tools[i].frame;
    }
  }
  updater_.setHardwareID("collision");
  min_rate_ = max_rate_ = config_.rate;
  cycle_rate_.reset(new diagnostic_updater::FrequencyStatus(
      diagnostic_updater::FrequencyStatusParam(&min_rate_, &max_rate_, 0.1, 5), "cycle rate"));
  updater_.add(*cycle_rate_);
  updater_.add("inputs", this, &CollidingRegions::inputsDiagnostic);
  start_time_ = ros::WallTime::now();
  cycle_timer_ = nh_.createSteadyTimer(ros::WallDuration(1.0 / config_.rate), &CollidingRegions::cycle, this);
  return true;
}

void CollidingRegions::poseCallback(std::size_t i, const geometry_msgs::PoseStampedConstPtr& msg)
{
  const geometry_msgs::Point& p = msg->pose.position;
  if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
  {
    ++rejected_;
    ROS_ERROR_THROTTLE(1.0, "colliding_regions: rejected non-finite tool-tip pose of %s (%lu rejected so far); "
                            "holding the last valid pose until ~pose_timeout",
                       config_.tools[i].name.c_str(), static_cast<unsigned long>(rejected_));
    return;
  }
  ToolState& t = tools_[i];
  t.tip_local = Eigen::Vector3d(p.x, p.y, p.z);
  if (!msg->header.frame_id.empty() && msg->header.frame_id != t.frame)
    t.frame = msg->header.frame_id;
  t.stamp_rx = ros::Time::now();
  t.have_pose = true;
  ++received_;
}

bool CollidingRegions::lookup(const std::string& frame, Eigen::Isometry3d& world_T_frame)
{
  try
  {
    const geometry_msgs::TransformStamped tf = tf_buffer_.lookupTransform(config_.world_frame, frame, ros::Time(0));
    world_T_frame = tf2::transformToEigen(tf);
    if (!world_T_frame.matrix().allFinite())
      throw tf2::TransformException("non-finite transform");
    return true;
  }
  catch (const tf2::TransformException& e)
  {
    ++tf_failures_;
    missing_frame_ = frame;
    if ((ros::WallTime::now() - start_time_).toSec() > config_.tf_timeout)
      ROS_ERROR_THROTTLE(2.0, "colliding_regions: no TF %s -> %s (%s); the affected objects are left out",
                         config_.world_frame.c_str(), frame.c_str(), e.what());
    else
      ROS_INFO_THROTTLE(1.0, "colliding_regions: waiting for TF %s -> %s", config_.world_frame.c_str(), frame.c_str());
    return false;
  }
}

void CollidingRegions::updateBones()
{
  Eigen::Isometry3d world_T_bones;
  if (!lookup(config_.bones_frame, world_T_bones))
  {
    if (have_bones_)
      return;  // keep the last known placement (the marker frame is static)
    scene_.setBoxes(std::vector<OrientedBox>());
    return;
  }
  if (have_bones_ && world_T_bones.matrix().isApprox(world_T_bones_.matrix(), 1e-12))
    return;
  world_T_bones_ = world_T_bones;
  have_bones_ = true;
  for (std::size_t b = 0; b < boxes_bones_.size(); ++b)
  {
    boxes_world_[b].center = world_T_bones * boxes_bones_[b].center;
    boxes_world_[b].axes = world_T_bones.linear() * boxes_bones_[b].axes;
  }
  scene_.setBoxes(boxes_world_);
  ROS_INFO("colliding_regions: forbidden regions placed by TF %s -> %s", config_.world_frame.c_str(),
           config_.bones_frame.c_str());
}

void CollidingRegions::cycle(const ros::SteadyTimerEvent&)
{
  const ros::Time now = ros::Time::now();
  ++cycles_;
  cycle_rate_->tick();
  updateBones();
  const std::size_t n = tools_.size();
  for (std::size_t i = 0; i < n; ++i)
  {
    ToolState& t = tools_[i];
    Eigen::Isometry3d world_T_base, world_T_trocar;
    if (!t.have_pose || (now - t.stamp_rx).toSec() > config_.pose_timeout || !lookup(t.frame, world_T_base) ||
        !lookup(config_.tools[i].trocar_frame, world_T_trocar))
    {
      scene_.invalidateTool(i);
      continue;
    }
    scene_.setToolAxis(i, world_T_base * t.tip_local, world_T_trocar.translation());
  }
  const std::vector<ToolProximityResult>& results = scene_.compute();

  report_msg_.header.stamp = now;
  for (std::size_t i = 0; i < n; ++i)
  {
    const ToolProximityResult& r = results[i];
    distances_msg_.data[i] = r.distance;
    saras_msgs::ToolProximity& tp = report_msg_.tools[i];
    tp.distance = r.distance;
    tp.result = r.code;
    if (r.nearest.kind == NearestObject::kTool)
      tp.nearest_object = config_.tools[r.nearest.index].name;
    else if (r.nearest.kind == NearestObject::kBox)
      tp.nearest_object = box_names_[r.nearest.index];
    else
      tp.nearest_object.clear();
    tp.point_on_tool = toPoint(r.point_on_tool);
    tp.point_on_object = toPoint(r.point_on_object);

    ToolState& t = tools_[i];
    if (t.fixture_pub)
    {
      Eigen::Vector3d force = Eigen::Vector3d::Zero();
      Eigen::Isometry3d world_T_base;
      if (scene_.toolValid(i) && lookup(config_.tools[i].frame, world_T_base))
        force = world_T_base.linear().transpose() *
                fixtureForce(r, config_.warning_threshold, config_.fixture_stiffness, config_.fixture_max_force);
      t.wrench.header.stamp = now;
      t.wrench.wrench.force.x = force.x();
      t.wrench.wrench.force.y = force.y();
      t.wrench.wrench.force.z = force.z();
      t.fixture_pub.publish(t.wrench);
    }
  }
  distances_pub_.publish(distances_msg_);
  report_pub_.publish(report_msg_);

  const ros::WallTime wall = ros::WallTime::now();
  if (config_.marker_rate > 0.0 && (wall - last_marker_time_).toSec() >= 1.0 / config_.marker_rate)
  {
    last_marker_time_ = wall;
    publishMarkers(now);
  }
  // Published at ~diagnostic_period (1 s), and at once when the level changes.
  const uint8_t level = computeLevel(nullptr);  // no allocation on the cycle path
  if (level != last_level_)
  {
    last_level_ = level;
    updater_.force_update();
  }
  else
  {
    updater_.update();
  }
}

std::size_t CollidingRegions::fillBoxMarkers(const ros::Time& now)
{
  const std::vector<OrientedBox>& boxes = scene_.boxes();
  std::vector<visualization_msgs::Marker>& m = markers_msg_.markers;
  for (std::size_t b = 0; b < boxes.size(); ++b)
  {
    visualization_msgs::Marker& mk = m[b];
    mk.header.frame_id = config_.world_frame;
    mk.header.stamp = now;
    mk.ns = "bones";
    mk.id = static_cast<int>(b);
    mk.type = visualization_msgs::Marker::CUBE;
    mk.action = visualization_msgs::Marker::ADD;
    mk.pose.position = toPoint(boxes[b].center);
    const Eigen::Quaterniond q = boxOrientation(boxes[b].axes);
    mk.pose.orientation.w = q.w();
    mk.pose.orientation.x = q.x();
    mk.pose.orientation.y = q.y();
    mk.pose.orientation.z = q.z();
    mk.scale.x = 2 * boxes[b].half.x();
    mk.scale.y = 2 * boxes[b].half.y();
    mk.scale.z = 2 * boxes[b].half.z();
    mk.color = color(0.93f, 0.9f, 0.8f, 0.6f);
  }
  return boxes.size();
}

void CollidingRegions::publishMarkers(const ros::Time& now)
{
  if (markers_pub_.getNumSubscribers() == 0)
    return;
  const std::size_t n = tools_.size();
  std::vector<visualization_msgs::Marker>& m = markers_msg_.markers;
  m.resize(scene_.boxes().size() + 2 * n + 1);
  const std::size_t k = fillBoxMarkers(now);
  const std::vector<ToolProximityResult>& results = scene_.results();
  visualization_msgs::Marker& lines = m[k + 2 * n];
  lines.header.frame_id = config_.world_frame;
  lines.header.stamp = now;
  lines.ns = "closest_points";
  lines.id = 0;
  lines.type = visualization_msgs::Marker::LINE_LIST;
  lines.action = visualization_msgs::Marker::ADD;
  lines.pose.orientation.w = 1.0;
  lines.scale.x = 0.001;
  lines.color = color(1.0f, 0.0f, 1.0f, 1.0f);
  lines.points.clear();
  for (std::size_t i = 0; i < n; ++i)
  {
    const Zone zone = classifyDistance(results[i].distance, config_.collision_threshold, config_.warning_threshold);
    const double r = config_.tools[i].radius;
    const bool valid = scene_.toolValid(i);
    const Eigen::Vector3d tip = scene_.toolTip(i), trocar = scene_.toolTrocar(i);
    // Shaft: cylinder between tip and trocar; ends: sphere list.
    visualization_msgs::Marker& shaft = m[k + 2 * i];
    visualization_msgs::Marker& ends = m[k + 2 * i + 1];
    shaft.header.frame_id = ends.header.frame_id = config_.world_frame;
    shaft.header.stamp = ends.header.stamp = now;
    shaft.ns = "tool_shafts";
    ends.ns = "tool_ends";
    shaft.id = ends.id = static_cast<int>(i);
    shaft.type = visualization_msgs::Marker::CYLINDER;
    ends.type = visualization_msgs::Marker::SPHERE_LIST;
    shaft.action = ends.action = valid ? visualization_msgs::Marker::ADD : visualization_msgs::Marker::DELETE;
    shaft.color = ends.color = zoneColor(zone);
    const double length = (trocar - tip).norm();
    shaft.pose.position = toPoint(0.5 * (tip + trocar));
    const Eigen::Quaterniond q = length > 0.0 ?
                                     Eigen::Quaterniond::FromTwoVectors(Eigen::Vector3d::UnitZ(), trocar - tip) :
                                     Eigen::Quaterniond::Identity();
    shaft.pose.orientation.w = q.w();
    shaft.pose.orientation.x = q.x();
    shaft.pose.orientation.y = q.y();
    shaft.pose.orientation.z = q.z();
    shaft.scale.x = shaft.scale.y = std::max(2 * r, 1e-4);
    shaft.scale.z = std::max(length, 1e-4);
    ends.pose.orientation.w = 1.0;
    ends.scale.x = ends.scale.y = ends.scale.z = std::max(2 * r, 1e-4);
    ends.points.resize(2);
    ends.points[0] = toPoint(tip);
    ends.points[1] = toPoint(trocar);
    if (valid && results[i].nearest.kind != NearestObject::kNone)
    {
      lines.points.push_back(toPoint(results[i].point_on_tool));
      lines.points.push_back(toPoint(results[i].point_on_object));
    }
  }
  if (lines.points.empty())
    lines.action = visualization_msgs::Marker::DELETE;
  markers_pub_.publish(markers_msg_);
}

uint8_t CollidingRegions::computeLevel(std::string* message) const
{
  using diagnostic_msgs::DiagnosticStatus;
  std::size_t valid = 0;
  for (std::size_t i = 0; i < tools_.size(); ++i)
    valid += scene_.toolValid(i) ? 1 : 0;
  if (have_bones_ && valid == tools_.size())
  {
    if (message != nullptr)
      *message = "ok";
    return DiagnosticStatus::OK;
  }
  const bool starting = (ros::WallTime::now() - start_time_).toSec() <= config_.tf_timeout;
  const uint8_t level = starting ? DiagnosticStatus::WARN : (valid == 0 ? DiagnosticStatus::STALE : DiagnosticStatus::ERROR);
  if (message != nullptr)
  {
    std::string missing;
    for (std::size_t i = 0; i < tools_.size(); ++i)
      if (!scene_.toolValid(i))
        missing += (missing.empty() ? "" : ", ") + config_.tools[i].name;
    if (!have_bones_)
      missing += (missing.empty() ? "" : ", ") + std::string("forbidden regions (no TF ") + config_.world_frame +
                 " -> " + config_.bones_frame + ")";
    *message = starting ? "waiting for: " + missing :
                          (valid == 0 ? "no tool has a current pose, nothing monitored; missing: " :
                                        "collision monitoring lost for: ") +
                              missing;
  }
  return level;
}

void CollidingRegions::inputsDiagnostic(diagnostic_updater::DiagnosticStatusWrapper& status)
{
  std::string message;
  const uint8_t level = computeLevel(&message);
  if (tf_failures_ > 0 && level != diagnostic_msgs::DiagnosticStatus::OK)
    message += " (last missing TF frame: " + missing_frame_ + ")";
  status.summary(level, message);
  const ros::Time now = ros::Time::now();
  for (std::size_t i = 0; i < tools_.size(); ++i)
  {
    const ToolState& t = tools_[i];
    const std::string key = config_.tools[i].name + " pose age [s]";
    if (t.have_pose)
      status.addf(key, "%.3f%s", (now - t.stamp_rx).toSec(), scene_.toolValid(i) ? "" : " (not monitored)");
    else
      status.add(key, "no pose received");
  }
  status.add("forbidden regions placed", have_bones_);
  status.add("poses received", received_);
  status.add("poses rejected (non-finite)", rejected_);
  status.add("TF lookup failures", tf_failures_);
  status.add("cycles", cycles_);
  const std::vector<ToolProximityResult>& results = scene_.results();
  double closest = std::numeric_limits<double>::infinity();
  std::string closest_tool;
  for (std::size_t i = 0; i < results.size() && i < tools_.size(); ++i)
    if (scene_.toolValid(i) && results[i].distance < closest)
    {
      closest = results[i].distance;
      closest_tool = config_.tools[i].name;
    }
  if (!closest_tool.empty())
  {
    status.addf("closest distance [m]", "%.6f", closest);
    status.add("closest tool", closest_tool);
  }
}

}  // namespace saras_collision
