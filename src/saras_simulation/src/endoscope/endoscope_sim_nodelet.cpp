/**
 * @file endoscope_sim_nodelet.cpp
 * @brief Nodelet saras_simulation/EndoscopeSim: simulated da Vinci stereo endoscope (Decklink
 *        stand-in), a thin ROS adapter over the C++ core (endoscope_renderer.h).
 *
 * Run in namespace `endoscope`. Publishes per eye (left, right) at ~fps:
 *   <eye>/image_raw             sensor_msgs/Image bgr8, raw (distorted) image
 *   <eye>/image_raw/compressed  sensor_msgs/CompressedImage "bgr8; jpeg compressed bgr8"
 *                               (as compressed_image_transport; cv::imencode)
 *   <eye>/camera_info           sensor_msgs/CameraInfo from the camera_info YAML (scaled to size)
 *   /diagnostics                diagnostic_updater status (hardware_id endoscope): ERROR without a
 *                               camera pose, WARN when the camera TF is old; frames rendered,
 *                               rejected (no/non-finite pose), skipped, age of the last frame
 * Subscribes ~target (std_msgs/String: none | checkerboard | circles). Camera poses from TF
 * world -> endoscope/<eye>_optical_frame, shafts from TF (<tool tip> and <RCM> frames), bones
 * from the saras_collision vertices file (pose: TF world -> ~bones_frame).
 * Image stamp = TF time of the rendered camera pose (now when the pose is static), so
 * lookupTransform(world, optical, image.header.stamp) returns exactly the rendered pose.
 * Lazy: an eye is rendered only if its image_raw or compressed topic has subscribers, JPEG
 * encoded only if compressed has subscribers. With ~parallel_eyes each eye has a persistent
 * thread that renders, encodes and publishes it; the timer thread only looks up TF and hands the
 * frame out, and skips a tick (never queues) while the previous frame is not published yet.
 * Outgoing image messages come from per-eye pools (endoscope_message_pool.h): no per-frame
 * allocation or zero-filling of the 2.7 MB (720p) image.
 *
 * Parameters (private; units): fps [Hz] 30 in [0.5, 120]; width, height [px] 1280 x 720;
 * camera_info_dir; left_camera_info, right_camera_info (file names, absolute or in the dir);
 * world_frame, left_frame, right_frame; jpeg_quality [0-100] 85; tf_timeout [s] 0.5;
 * parallel_eyes (bool) true; texture_size [texels] 1024; texture_extent [m] 0.30;
 * light_distance [m] 0.10; tools [{tip, rcm, radius [m]}]; bones_file ('' = saras_collision's
 * config/pelvis_vertices.txt if present); bones_frame; bones_scaling (file unit -> m) 1.0;
 * tissue {z0 [m], centre [m, m], waves [[a m, kx rad/m, ky rad/m, phi rad]...]};
 * targets {checkerboard: {cols, rows, square m, res m, xyz m, rpy rad},
 *          circles: {dot_circle_radius m, dot_diameter m, dots, marker_circle_radius m,
 *                    marker_side m, res m, dictionary, xyz m, rpy rad}};
 * target (initial: none | checkerboard | circles). A bad value throws at start-up with a message
 * naming the parameter (`nodelet standalone` then exits with a non-zero status).
 */
#include <atomic>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <map>
#include <condition_variable>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include <boost/make_shared.hpp>
#include <nodelet/nodelet.h>
#include <opencv2/core/utility.hpp>
#include <opencv2/imgcodecs.hpp>
#include <pluginlib/class_list_macros.hpp>
#include <ros/package.h>
#include <ros/ros.h>
#include <diagnostic_updater/diagnostic_updater.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/CompressedImage.h>
#include <sensor_msgs/Image.h>
#include <std_msgs/String.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/transform_listener.h>

#include "saras_simulation/endoscope_message_pool.h"
#include "saras_simulation/endoscope_renderer.h"

namespace saras_simulation
{
namespace endoscope
{
namespace
{
const char* const kEyes[2] = { "left", "right" };

/// Absolute namespace of the nodelet named @p name with a trailing '/': topics stay those of the
/// node (/endoscope/left/...), also when the nodelet is loaded into a manager of another namespace.
std::string nodeletNamespace(const std::string& name)
{
  std::string ns = ros::names::parentNamespace(name);
  if (ns.empty() || ns.back() != '/')
    ns += '/';
  return ns;
}

[[noreturn]] void fail(const std::string& msg)
{
  throw std::invalid_argument(msg);
}

bool isNumber(const XmlRpc::XmlRpcValue& v)
{
  return v.getType() == XmlRpc::XmlRpcValue::TypeDouble || v.getType() == XmlRpc::XmlRpcValue::TypeInt;
}

double toDouble(XmlRpc::XmlRpcValue& v, const std::string& what)
{
  if (v.getType() == XmlRpc::XmlRpcValue::TypeDouble)
    return static_cast<double>(v);
  if (v.getType() == XmlRpc::XmlRpcValue::TypeInt)
    return static_cast<int>(v);
  fail(what + " must be a number");
}

std::vector<double> toVector(XmlRpc::XmlRpcValue& v, size_t n, const std::string& what)
{
  if (v.getType() != XmlRpc::XmlRpcValue::TypeArray || static_cast<size_t>(v.size()) != n)
    fail(what + " must be a list of " + std::to_string(n) + " numbers");
  std::vector<double> out;
  for (int i = 0; i < v.size(); ++i)
    out.push_back(toDouble(v[i], what));
  return out;
}

double paramDouble(const ros::NodeHandle& pnh, const std::string& name, double def)
{
  XmlRpc::XmlRpcValue v;
  if (!pnh.getParam(name, v))
    return def;
  if (!isNumber(v))
    fail("parameter ~" + name + " must be a number");
  return toDouble(v, "~" + name);
}

int paramInt(const ros::NodeHandle& pnh, const std::string& name, int def)
{
  XmlRpc::XmlRpcValue v;
  if (!pnh.getParam(name, v))
    return def;
  if (v.getType() == XmlRpc::XmlRpcValue::TypeInt)
    return static_cast<int>(v);
  if (v.getType() == XmlRpc::XmlRpcValue::TypeDouble && static_cast<double>(v) == std::floor(static_cast<double>(v)))
    return static_cast<int>(static_cast<double>(v));
  fail("parameter ~" + name + " must be an integer");
}

std::string paramString(const ros::NodeHandle& pnh, const std::string& name, const std::string& def)
{
  XmlRpc::XmlRpcValue v;
  if (!pnh.getParam(name, v))
    return def;
  if (v.getType() == XmlRpc::XmlRpcValue::TypeString)
    return static_cast<std::string>(v);
  if (v.getType() == XmlRpc::XmlRpcValue::TypeInt || v.getType() == XmlRpc::XmlRpcValue::TypeDouble)
    return v.toXml().empty() ? def : std::to_string(toDouble(v, name));
  fail("parameter ~" + name + " must be a string");
}

bool paramBool(const ros::NodeHandle& pnh, const std::string& name, bool def)
{
  XmlRpc::XmlRpcValue v;
  if (!pnh.getParam(name, v))
    return def;
  if (v.getType() != XmlRpc::XmlRpcValue::TypeBoolean)
    fail("parameter ~" + name + " must be a boolean");
  return static_cast<bool>(v);
}

Eigen::Isometry3d toEigen(const geometry_msgs::TransformStamped& ts)
{
  const auto& t = ts.transform.translation;
  const auto& q = ts.transform.rotation;
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  const Eigen::Quaterniond qq(q.w, q.x, q.y, q.z);
  T.linear() = qq.norm() > 0 ? qq.normalized().toRotationMatrix() : Eigen::Matrix3d::Constant(NAN);
  T.translation() = Eigen::Vector3d(t.x, t.y, t.z);
  return T;
}

std::string expandUser(const std::string& p)
{
  if (!p.empty() && p[0] == '~')
  {
    const char* home = std::getenv("HOME");
    return std::string(home ? home : "") + p.substr(1);
  }
  return p;
}

/// What /diagnostics reports: level + message (a change is published at once) and counters.
struct Health
{
  uint8_t level = diagnostic_msgs::DiagnosticStatus::STALE;
  std::string message = "starting";
  bool changed = true;
  double last_input = -1.0;  ///< [s] ROS time of the last rendered frame
  uint64_t received = 0, rejected = 0;
  void set(uint8_t l, const std::string& m)
  {
    if (l != level || m != message)
    {
      level = l;
      message = m;
      changed = true;
    }
  }
};
}  // namespace

/// Target kind + its pose from the ~targets parameter. @throws std::invalid_argument
std::pair<std::shared_ptr<const PlanarTarget>, Eigen::Isometry3d> makeTarget(const std::string& kind,
                                                                              XmlRpc::XmlRpcValue spec)
{
  std::vector<double> xyz{ 0.0, 0.0, 0.085 }, rpy{ M_PI, 0.0, 0.0 };
  std::map<std::string, double> num;
  std::string dictionary = "DICT_4X4_50";
  if (spec.getType() == XmlRpc::XmlRpcValue::TypeStruct)
  {
    for (auto& kv : spec)
    {
      if (kv.first == "xyz")
        xyz = toVector(kv.second, 3, "xyz");
      else if (kv.first == "rpy")
        rpy = toVector(kv.second, 3, "rpy");
      else if (kv.first == "dictionary" && kv.second.getType() == XmlRpc::XmlRpcValue::TypeString)
        dictionary = static_cast<std::string>(kv.second);
      else
        num[kv.first] = toDouble(kv.second, kv.first);
    }
  }
  else if (spec.valid())
    fail("targets/" + kind + " must be a mapping");
  auto take = [&](const std::string& key, double def) {
    auto it = num.find(key);
    if (it == num.end())
      return def;
    const double v = it->second;
    num.erase(it);
    return v;
  };
  std::shared_ptr<PlanarTarget> t;
  if (kind == "checkerboard")
  {
    const double cols = take("cols", 8), rows = take("rows", 6), square = take("square", 0.008), res = take("res", 0.0001);
    if (!num.empty())
      fail("unexpected key '" + num.begin()->first + "'");
    t = std::make_shared<PlanarTarget>(PlanarTarget::checkerboard(int(cols), int(rows), square, res));
  }
  else if (kind == "circles")
  {
    const double r = take("dot_circle_radius", 0.100), dd = take("dot_diameter", 0.005), dots = take("dots", 8),
                 mr = take("marker_circle_radius", 0.060), ms = take("marker_side", 0.025), res = take("res", 0.0002);
    if (!num.empty())
      fail("unexpected key '" + num.begin()->first + "'");
    t = std::make_shared<PlanarTarget>(PlanarTarget::circles(r, dd, int(dots), mr, ms, res, dictionary));
  }
  else
    fail("unknown target '" + kind + "' (none | checkerboard | circles)");
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = rpyToMatrix(rpy[0], rpy[1], rpy[2]);
  T.translation() = Eigen::Vector3d(xyz[0], xyz[1], xyz[2]);
  return { t, T };
}

/// The simulator: parameters, renderers, TF, publishers, timer, right-eye worker thread.
class EndoscopeSim
{
public:
  /// @param ns namespace of the node (absolute, ending in '/'): the topics are <ns><eye>/...
  EndoscopeSim(ros::NodeHandle& nh, ros::NodeHandle& pnh, const std::string& name, const std::string& ns)
    : pnh_(pnh), name_(name)
  {
    fps_ = paramDouble(pnh, "fps", 30.0);
    if (!(fps_ >= 0.5 && fps_ <= 120.0))
      fail("parameter ~fps must be in [0.5, 120] Hz, got " + std::to_string(fps_));
    const int width = paramInt(pnh, "width", 1280), height = paramInt(pnh, "height", 720);
    if (!(width >= 16 && width <= 7680 && height >= 16 && height <= 4320))
      fail("parameter ~width/~height out of range: " + std::to_string(width) + "x" + std::to_string(height));
    const std::string info_dir = expandUser(paramString(pnh, "camera_info_dir", ""));
    world_ = paramString(pnh, "world_frame", "world");
    frames_[0] = paramString(pnh, "left_frame", "endoscope/left_optical_frame");
    frames_[1] = paramString(pnh, "right_frame", "endoscope/right_optical_frame");
    jpeg_quality_ = paramInt(pnh, "jpeg_quality", 85);
    if (jpeg_quality_ < 0 || jpeg_quality_ > 100)
      fail("parameter ~jpeg_quality must be in [0, 100]");
    jpeg_params_ = { cv::IMWRITE_JPEG_QUALITY, jpeg_quality_ };
    tf_timeout_ = paramDouble(pnh, "tf_timeout", 0.5);
    parallel_ = paramBool(pnh, "parallel_eyes", true);
    TissueSurface surface = tissueFromParam();
    RendererOptions opt;
    opt.texture_size = paramInt(pnh, "texture_size", 1024);
    opt.texture_extent = paramDouble(pnh, "texture_extent", 0.30);
    opt.light_distance = paramDouble(pnh, "light_distance", 0.10);
    for (int e = 0; e < 2; ++e)
    {
      const std::string eye = kEyes[e];
      const std::string file = paramString(pnh, eye + "_camera_info", "endoscope_" + eye + ".yaml");
      const std::string path = !file.empty() && file[0] == '/' ? file : info_dir + "/" + file;
      std::unique_ptr<CameraModel> cam;
      try
      {
        cam.reset(new CameraModel(CameraModel::fromYamlFile(path)));
      }
      catch (const std::invalid_argument& ex)
      {
        fail("parameter ~camera_info_dir/~" + eye + "_camera_info: " + ex.what());
      }
      if (cam->width() != width || cam->height() != height)
      {
        ROS_WARN("%s: %s calibrated at %dx%d, scaled to %dx%d", name_.c_str(), path.c_str(), cam->width(),
                 cam->height(), width, height);
        cam.reset(new CameraModel(cam->scaled(width, height)));
      }
      info_[e] = cameraInfo(*cam, frames_[e]);
      try
      {
        renderers_[e].reset(new SceneRenderer(*cam, surface, opt));
      }
      catch (const std::exception& ex)
      {
        fail(std::string("renderer set-up failed: ") + ex.what());
      }
    }
    loadTools();
    bones_frame_ = paramString(pnh, "bones_frame", "bones_marker_frame");
    loadBones(paramString(pnh, "bones_file", ""), paramDouble(pnh, "bones_scaling", 1.0));
    pnh.getParam("targets", target_specs_);
    pending_target_ = paramString(pnh, "target", "none");

    // Outgoing queue per subscriber of the recorded streams (compressed + camera_info): a recorder
    // that stalls for a few frames must not lose them (a queue of 2 lost one frame to a 250 ms
    // recorder stall in a 2-core demo). The raw images (2.7 MB each at 720p) keep 2: live only.
    const int recorded_queue = paramInt(pnh, "recorded_queue", 30);
    if (recorded_queue < 1 || recorded_queue > 1000)
      fail("parameter ~recorded_queue must be in [1, 1000] messages");
    tf_buffer_.reset(new tf2_ros::Buffer(ros::Duration(10.0)));
    tf_listener_.reset(new tf2_ros::TransformListener(*tf_buffer_, nh, true));  // own thread: /tf off our queue
    for (int e = 0; e < 2; ++e)
    {
      const std::string eye = kEyes[e];
      pub_img_[e] = nh.advertise<sensor_msgs::Image>(ns + eye + "/image_raw", 2);
      pub_jpg_[e] = nh.advertise<sensor_msgs::CompressedImage>(ns + eye + "/image_raw/compressed",
                                                               static_cast<uint32_t>(recorded_queue));
      pub_info_[e] = nh.advertise<sensor_msgs::CameraInfo>(ns + eye + "/camera_info",
                                                           static_cast<uint32_t>(recorded_queue));
      eye_[e].width = width;
      eye_[e].height = height;
    }
    updater_.reset(new diagnostic_updater::Updater(nh, pnh, name_));
    updater_->setHardwareID("endoscope");
    updater_->add("render", this, &EndoscopeSim::diagnose);
    sub_target_ = pnh.subscribe("target", 1, &EndoscopeSim::onTarget, this);
    if (parallel_)
    {
      // parallel over the eyes, not inside each OpenCV call (as the Python node); note that this
      // is process-wide (the other nodelets of a shared manager run OpenCV single-threaded too)
      cv::setNumThreads(1);
      for (int e = 0; e < 2; ++e)
        workers_[e] = std::thread(&EndoscopeSim::workerLoop, this, e);
    }
    timer_ = nh.createTimer(ros::Duration(1.0 / fps_), &EndoscopeSim::tick, this);
  }

  ~EndoscopeSim()
  {
    timer_.stop();
    {
      std::lock_guard<std::mutex> lock(work_mutex_);
      quit_ = true;
    }
    work_cv_.notify_all();
    for (auto& w : workers_)
      if (w.joinable())
        w.join();
  }

private:
  /// Per-eye frame state: inputs of the render job and its outputs (buffers reused).
  struct Eye
  {
    int width = 0, height = 0;
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    bool want_raw = false, want_jpg = false;
    sensor_msgs::ImagePtr img;             ///< this frame's image_raw (from img_pool)
    sensor_msgs::CompressedImagePtr jpg;   ///< this frame's compressed image (from jpg_pool)
    MessagePool<sensor_msgs::Image> img_pool;  ///< reused once no subscriber holds them
    MessagePool<sensor_msgs::CompressedImage> jpg_pool;
    cv::Mat buffer;                        ///< render target when only the JPEG is wanted
  };

  TissueSurface tissueFromParam()
  {
    XmlRpc::XmlRpcValue t;
    if (!pnh_.getParam("tissue", t))
      return TissueSurface();
    try
    {
      if (t.getType() != XmlRpc::XmlRpcValue::TypeStruct)
        fail("must be a mapping {z0, centre, waves}");
      double z0 = 0.07;
      std::vector<double> c{ 0.0, 0.0 };
      std::vector<TissueSurface::Wave> waves = TissueSurface::defaultWaves();
      if (t.hasMember("z0"))
        z0 = toDouble(t["z0"], "z0");
      if (t.hasMember("centre"))
        c = toVector(t["centre"], 2, "centre");
      if (t.hasMember("waves"))
      {
        XmlRpc::XmlRpcValue& w = t["waves"];
        if (w.getType() != XmlRpc::XmlRpcValue::TypeArray)
          fail("waves must be a list of [a, kx, ky, phi]");
        waves.clear();
        for (int i = 0; i < w.size(); ++i)
        {
          const auto v = toVector(w[i], 4, "waves[" + std::to_string(i) + "]");
          waves.push_back({ v[0], v[1], v[2], v[3] });
        }
      }
      return TissueSurface(z0, c[0], c[1], waves);
    }
    catch (const std::invalid_argument& e)
    {
      fail(std::string("parameter tissue invalid: ") + e.what());
    }
  }

  void loadTools()
  {
    XmlRpc::XmlRpcValue tools;
    if (!pnh_.getParam("tools", tools))
      return;
    if (tools.getType() != XmlRpc::XmlRpcValue::TypeArray)
      fail("parameter ~tools must be a list of {tip, rcm, radius}");
    for (int i = 0; i < tools.size(); ++i)
    {
      XmlRpc::XmlRpcValue& t = tools[i];
      const std::string what = "parameter ~tools[" + std::to_string(i) + "] invalid: ";
      if (t.getType() != XmlRpc::XmlRpcValue::TypeStruct || !t.hasMember("tip") || !t.hasMember("rcm") ||
          t["tip"].getType() != XmlRpc::XmlRpcValue::TypeString || t["rcm"].getType() != XmlRpc::XmlRpcValue::TypeString)
        fail(what + "needs {tip: frame, rcm: frame, radius: m}");
      Tool tool{ static_cast<std::string>(t["tip"]), static_cast<std::string>(t["rcm"]), 0.004 };
      if (t.hasMember("radius"))
      {
        try
        {
          tool.radius = toDouble(t["radius"], "radius");
        }
        catch (const std::invalid_argument& e)
        {
          fail(what + e.what());
        }
      }
      tools_.push_back(tool);
    }
  }

  void loadBones(std::string path, double scaling)
  {
    if (path.empty())
    {
      const std::string pkg = ros::package::getPath("saras_collision");
      if (pkg.empty())
        return;  // no bones to draw
      path = pkg + "/config/pelvis_vertices.txt";
      if (!std::ifstream(path).good())
      {
        ROS_INFO("%s: no %s, no bones drawn", name_.c_str(), path.c_str());
        return;
      }
    }
    try
    {
      bones_ = loadBoxes(path, scaling);
    }
    catch (const std::invalid_argument& e)
    {
      fail(std::string("parameter ~bones_file: ") + e.what());
    }
    ROS_INFO("%s: %zu bone boxes from %s", name_.c_str(), bones_.size(), path.c_str());
  }

  static sensor_msgs::CameraInfo cameraInfo(const CameraModel& cam, const std::string& frame)
  {
    sensor_msgs::CameraInfo m;
    m.header.frame_id = frame;
    m.width = cam.width();
    m.height = cam.height();
    m.distortion_model = cam.distortionModel();
    m.D = cam.D();
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c)
      {
        m.K[3 * r + c] = cam.K()(r, c);
        m.R[3 * r + c] = cam.R()(r, c);
      }
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 4; ++c)
        m.P[4 * r + c] = cam.P()(r, c);
    return m;
  }

  bool applyTarget(const std::string& kind)
  {
    if (kind.empty() || kind == "none")
    {
      for (auto& r : renderers_)
        r->clearTarget();
      return true;
    }
    try
    {
      XmlRpc::XmlRpcValue spec;
      if (target_specs_.getType() == XmlRpc::XmlRpcValue::TypeStruct && target_specs_.hasMember(kind))
        spec = target_specs_[kind];
      const auto t = makeTarget(kind, spec);
      for (auto& r : renderers_)
        r->setTarget(t.first, t.second);
      return true;
    }
    catch (const std::exception& e)
    {
      ROS_ERROR("%s: target '%s' rejected: %s", name_.c_str(), kind.c_str(), e.what());
      return false;
    }
  }

  void onTarget(const std_msgs::String::ConstPtr& msg)
  {
    std::string s = msg->data;
    const auto b = s.find_first_not_of(" \t\r\n"), e = s.find_last_not_of(" \t\r\n");
    s = b == std::string::npos ? "" : s.substr(b, e - b + 1);
    std::lock_guard<std::mutex> lock(target_mutex_);
    pending_target_ = s;
    pending_set_ = true;
  }

  /// Transform at @p stamp (consistent with the camera pose), else the latest.
  Eigen::Isometry3d lookupAt(const std::string& child, const ros::Time& stamp)
  {
    try
    {
      return toEigen(tf_buffer_->lookupTransform(world_, child, stamp));
    }
    catch (const tf2::ExtrapolationException&)
    {
      return toEigen(tf_buffer_->lookupTransform(world_, child, ros::Time(0)));
    }
  }

  void updateBones()
  {
    if (bones_placed_ || bones_.empty())
      return;
    Eigen::Isometry3d T;
    try
    {
      T = toEigen(tf_buffer_->lookupTransform(world_, bones_frame_, ros::Time(0)));
    }
    catch (const tf2::TransformException&)
    {
      return;
    }
    if (!T.matrix().allFinite())
      return;
    auto world = bones_;
    for (auto& b : world)
      for (auto& v : b)
        v = T * v;
    try
    {
      for (auto& r : renderers_)
        r->setBoxes(world);
    }
    catch (const std::invalid_argument& e)  // not expected: a rigid transform keeps the boxes rectangular
    {
      ROS_ERROR_THROTTLE(2.0, "%s: bone boxes not drawn: %s", name_.c_str(), e.what());
      return;
    }
    bones_placed_ = true;
  }

  void tick(const ros::TimerEvent&)
  {
    std::unique_lock<std::mutex> busy(tick_mutex_, std::try_to_lock);
    if (!busy.owns_lock())
      return;  // previous tick still running: skip, never queue
    if (parallel_)
    {
      // the eye threads still render / publish the previous frame: skip this one (never queue);
      // nothing they read (poses, shafts, renderers' scene) may change before they are done
      std::lock_guard<std::mutex> lock(work_mutex_);
      if (pending_[0] || pending_[1])
      {
        ++frames_skipped_;
        ROS_DEBUG_THROTTLE(5.0, "%s: frame skipped, the previous one is still being rendered (%lu skipped)",
                           name_.c_str(), frames_skipped_);
        return;
      }
    }
    const ros::Time now = ros::Time::now();
    {
      std::string kind;
      bool have = false;
      {
        std::lock_guard<std::mutex> lock(target_mutex_);
        if (pending_set_)
        {
          kind = pending_target_;
          have = true;
          pending_target_.clear();
          pending_set_ = false;
        }
      }
      if (have)
        applyTarget(kind);
    }
    updateBones();
    ros::Time stamp;
    bool is_static = false;
    try
    {
      const auto ts_left = tf_buffer_->lookupTransform(world_, frames_[0], ros::Time(0));
      stamp = ts_left.header.stamp;
      is_static = stamp.isZero();
      geometry_msgs::TransformStamped ts_right;
      try
      {
        ts_right = tf_buffer_->lookupTransform(world_, frames_[1], is_static ? ros::Time(0) : stamp);
      }
      catch (const tf2::ExtrapolationException&)
      {
        ts_right = tf_buffer_->lookupTransform(world_, frames_[1], ros::Time(0));
      }
      eye_[0].pose = toEigen(ts_left);
      eye_[1].pose = toEigen(ts_right);
    }
    catch (const tf2::TransformException& ex)
    {
      ++tf_errors_;
      ++hb_.rejected;
      hb_.set(diagnostic_msgs::DiagnosticStatus::ERROR, "no camera pose in TF: not publishing");
      ROS_ERROR_THROTTLE(2.0, "%s: camera pose unavailable (%lu times): %s", name_.c_str(), tf_errors_, ex.what());
      status(now);
      return;
    }
    if (is_static)
      stamp = now;
    if (!eye_[0].pose.matrix().allFinite() || !eye_[1].pose.matrix().allFinite())
    {
      ++hb_.rejected;
      hb_.set(diagnostic_msgs::DiagnosticStatus::ERROR, "non-finite camera pose in TF: not publishing");
      ROS_ERROR_THROTTLE(2.0, "%s: non-finite camera pose", name_.c_str());
      status(now);
      return;
    }
    shafts_.clear();
    for (const Tool& t : tools_)
    {
      try
      {
        const Eigen::Isometry3d Tt = lookupAt(t.tip, stamp), Tr = lookupAt(t.rcm, stamp);
        shafts_.push_back({ Tt.translation(), Tr.translation(), t.radius });
      }
      catch (const tf2::TransformException&)
      {
        // tool not (yet) in the scene: not drawn
      }
    }
    for (int e = 0; e < 2; ++e)
    {
      eye_[e].want_raw = pub_img_[e].getNumSubscribers() > 0;
      eye_[e].want_jpg = pub_jpg_[e].getNumSubscribers() > 0;
    }
    stamp_ = stamp;
    if (parallel_)
    {
      // each eye thread renders, encodes and publishes its eye; the timer thread returns at
      // once (the frame's work may take up to a whole period on each core)
      {
        std::lock_guard<std::mutex> lock(work_mutex_);
        pending_[0] = pending_[1] = true;
      }
      work_cv_.notify_all();
    }
    else
      for (int e = 0; e < 2; ++e)
      {
        renderEye(e);
        publish(e, stamp_);
      }
    ++hb_.received;
    hb_.last_input = now.toSec();
    const double age = (now - stamp).toSec();
    if (!is_static && age > tf_timeout_)
    {
      char buf[96];
      std::snprintf(buf, sizeof(buf), "camera TF is %.1f s old (dVRK stopped?)", age);
      hb_.set(diagnostic_msgs::DiagnosticStatus::WARN, buf);
    }
    else
      hb_.set(diagnostic_msgs::DiagnosticStatus::OK,
              "rendering " + std::to_string(eye_[0].width) + "x" + std::to_string(eye_[0].height));
    status(now);
  }

  /// Eye thread @p e: renders, encodes and publishes its eye for every frame the tick hands out.
  void workerLoop(int e)
  {
    std::unique_lock<std::mutex> lock(work_mutex_);
    while (true)
    {
      work_cv_.wait(lock, [this, e] { return pending_[e] || quit_; });
      if (quit_)
        return;
      lock.unlock();
      renderEye(e);
      publish(e, stamp_);
      lock.lock();
      pending_[e] = false;
    }
  }

  /// Render (and encode) one eye: only what is subscribed. Never throws.
  void renderEye(int e)
  {
    Eye& eye = eye_[e];
    eye.img.reset();
    eye.jpg.reset();
    if (!eye.want_raw && !eye.want_jpg)
      return;
    try
    {
      cv::Mat* target = &eye.buffer;
      cv::Mat wrap;
      if (eye.want_raw)
      {
        // a pooled message: its 2.7 MB (720p) buffer is rendered over, never allocated or
        // zero-filled per frame
        eye.img = eye.img_pool.acquire();
        eye.img->height = eye.height;
        eye.img->width = eye.width;
        eye.img->encoding = "bgr8";
        eye.img->is_bigendian = 0;
        eye.img->step = eye.width * 3;
        eye.img->data.resize(static_cast<size_t>(eye.img->step) * eye.height);
        wrap = cv::Mat(eye.height, eye.width, CV_8UC3, eye.img->data.data());
        target = &wrap;
      }
      renderers_[e]->render(eye.pose, shafts_, *target);
      if (eye.want_jpg)
      {
        eye.jpg = eye.jpg_pool.acquire();
        eye.jpg->format = "bgr8; jpeg compressed bgr8";
        // encoded straight into the message (its capacity is reused)
        if (!cv::imencode(".jpg", *target, eye.jpg->data, jpeg_params_))
        {
          eye.jpg.reset();
          ROS_ERROR_THROTTLE(2.0, "%s: %s eye: JPEG encoding failed", name_.c_str(), kEyes[e]);
        }
      }
    }
    catch (const std::exception& ex)
    {
      eye.img.reset();
      eye.jpg.reset();
      ROS_ERROR_THROTTLE(2.0, "%s: %s eye not rendered: %s", name_.c_str(), kEyes[e], ex.what());
    }
  }

  void publish(int e, const ros::Time& stamp)
  {
    Eye& eye = eye_[e];
    if (eye.img)
    {
      eye.img->header.stamp = stamp;
      eye.img->header.frame_id = frames_[e];
      pub_img_[e].publish(eye.img);
      eye.img.reset();  // the pool's reference (+ intra-process subscribers') only
    }
    if (eye.jpg)
    {
      eye.jpg->header.stamp = stamp;
      eye.jpg->header.frame_id = frames_[e];
      pub_jpg_[e].publish(eye.jpg);
      eye.jpg.reset();
    }
    info_[e].header.stamp = stamp;
    pub_info_[e].publish(info_[e]);
  }

  /// Publishes /diagnostics at its period, at once when the level or the message changed.
  void status(const ros::Time&)
  {
    if (hb_.changed)
    {
      hb_.changed = false;
      updater_->force_update();
    }
    else
      updater_->update();
  }

  void diagnose(diagnostic_updater::DiagnosticStatusWrapper& stat)
  {
    stat.summary(hb_.level, hb_.message);
    stat.add("frames rendered", hb_.received);
    stat.add("rejected (no camera pose)", hb_.rejected);
    stat.add("skipped (previous frame not done)", frames_skipped_);
    const double now = ros::Time::now().toSec();
    stat.add("input_age [s]", hb_.last_input < 0 ? std::numeric_limits<double>::infinity() : now - hb_.last_input);
  }

  struct Tool
  {
    std::string tip, rcm;
    double radius;  ///< [m]
  };

  ros::NodeHandle pnh_;
  std::string name_;
  double fps_ = 30.0, tf_timeout_ = 0.5;
  int jpeg_quality_ = 85;
  std::vector<int> jpeg_params_;  ///< cv::imencode parameters
  bool parallel_ = true;
  std::string world_, frames_[2], bones_frame_;
  sensor_msgs::CameraInfo info_[2];
  std::unique_ptr<SceneRenderer> renderers_[2];
  std::vector<Tool> tools_;
  std::vector<std::array<Eigen::Vector3d, 8>> bones_;
  bool bones_placed_ = false;
  XmlRpc::XmlRpcValue target_specs_;
  std::mutex target_mutex_;
  std::string pending_target_;
  bool pending_set_ = true;  ///< apply the initial ~target on the first tick
  std::unique_ptr<tf2_ros::Buffer> tf_buffer_;
  std::unique_ptr<tf2_ros::TransformListener> tf_listener_;
  ros::Publisher pub_img_[2], pub_jpg_[2], pub_info_[2];
  std::unique_ptr<diagnostic_updater::Updater> updater_;
  ros::Subscriber sub_target_;
  ros::Timer timer_;
  Health hb_;
  unsigned long tf_errors_ = 0;
  std::vector<Shaft> shafts_;
  Eye eye_[2];
  // right-eye worker
  // eye threads (~parallel_eyes)
  std::mutex tick_mutex_, work_mutex_;
  std::condition_variable work_cv_;
  bool pending_[2] = { false, false };  ///< eye e has a frame to render and publish
  bool quit_ = false;
  ros::Time stamp_;                     ///< stamp of the frame being rendered
  unsigned long frames_skipped_ = 0;    ///< ticks skipped because the previous frame was not done
  std::thread workers_[2];
};

/// Nodelet `saras_simulation/EndoscopeSim` (nodelet_plugins.xml); executable endoscope_sim_node loads it.
class EndoscopeSimNodelet : public nodelet::Nodelet
{
private:
  void onInit() override
  {
    try
    {
      // topics in the nodelet's own namespace (e.g. /endoscope/left/...), not the manager's
      sim_.reset(new EndoscopeSim(getNodeHandle(), getPrivateNodeHandle(), getName(), nodeletNamespace(getName())));
    }
    catch (const std::exception& e)
    {
      ROS_FATAL("%s: %s", getName().c_str(), e.what());
      throw;
    }
  }
  std::unique_ptr<EndoscopeSim> sim_;
};

}  // namespace endoscope
}  // namespace saras_simulation

PLUGINLIB_EXPORT_CLASS(saras_simulation::endoscope::EndoscopeSimNodelet, nodelet::Nodelet)
