/**
 * @file endoscope_sim_nodelet.cpp
 * @brief Nodelet saras_simulation/EndoscopeSim: simulated da Vinci stereo endoscope (Decklink
 *        stand-in). ROS wiring only: parameters (endoscope_sim_config.h), TF as the PoseSource,
 *        publishers, timer, /diagnostics; the decisions are in endoscope_sim_core.h and the frame
 *        assembly in endoscope_stereo.h.
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
 * encoded only if compressed has subscribers. A persistent thread named "endoscope_sim" renders,
 * encodes and publishes both eyes (with ~parallel_eyes one thread per eye, "endoscope_sim_l" and
 * "endoscope_sim_r"); the timer thread only looks up TF and hands the frame out, and skips a tick
 * (never queues) while the previous frame is not published yet. So the simulator's CPU is that of
 * its named threads, apart from the other nodelets of a shared manager (e.g. the overlay).
 * Parameters and units: endoscope_sim_config.h (config/endoscope.yaml). A bad value throws at
 * start-up with a message naming the parameter (`nodelet standalone` then exits non-zero).
 */
#include <pthread.h>

#include <exception>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

#include <diagnostic_updater/diagnostic_updater.h>
#include <nodelet/nodelet.h>
#include <opencv2/core/utility.hpp>
#include <pluginlib/class_list_macros.hpp>
#include <ros/package.h>
#include <ros/ros.h>
#include <saras_common/nodelet_namespace.h>
#include <saras_common/params.h>
#include <std_msgs/String.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/transform_listener.h>

#include <fstream>

#include "saras_simulation/endoscope_sim_core.h"
#include "saras_simulation/endoscope_stereo.h"

namespace saras_simulation
{
namespace endoscope
{
namespace
{
const char* const kEyes[2] = { "left", "right" };

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

/// The TF buffer as the planner's pose source.
class TfPoses : public PoseSource
{
public:
  TfPoses(tf2_ros::Buffer& buffer, const std::string& world) : buffer_(buffer), world_(world) {}
  Result lookup(const std::string& frame, const ros::Time& stamp, Eigen::Isometry3d& pose, ros::Time& pose_stamp,
                std::string& error) override
  {
    try
    {
      const geometry_msgs::TransformStamped ts = buffer_.lookupTransform(world_, frame, stamp);
      pose = toEigen(ts);
      pose_stamp = ts.header.stamp;
      return Result::OK;
    }
    catch (const tf2::ExtrapolationException& e)
    {
      error = e.what();
      return Result::EXTRAPOLATION;
    }
    catch (const tf2::TransformException& e)
    {
      error = e.what();
      return Result::UNAVAILABLE;
    }
  }

private:
  tf2_ros::Buffer& buffer_;
  std::string world_;
};

/// Bone boxes of ~bones_file ('' = saras_collision's config/pelvis_vertices.txt if present).
std::vector<std::array<Eigen::Vector3d, 8>> loadBones(const saras_common::Params& p, const EndoscopeConfig& c,
                                                     const std::string& name)
{
  std::string path = c.bones_file;
  if (path.empty())
  {
    const std::string pkg = ros::package::getPath("saras_collision");
    path = pkg.empty() ? "" : pkg + "/config/pelvis_vertices.txt";
    if (path.empty() || !std::ifstream(path).good())
    {
      ROS_INFO("%s: no saras_collision pelvis_vertices.txt, no bones drawn", name.c_str());
      return {};
    }
  }
  try
  {
    auto bones = loadBoxes(path, c.bones_scaling);
    ROS_INFO("%s: %zu bone boxes from %s", name.c_str(), bones.size(), path.c_str());
    return bones;
  }
  catch (const std::invalid_argument& e)
  {
    p.fail("bones_file", "'" + path + "'", "", std::string("a vertices file (") + e.what() + ")");
  }
}

/// camera_info of eye @p e, at the configured image size.
sensor_msgs::CameraInfo eyeInfo(const saras_common::Params& p, const EndoscopeConfig& c, int e, const std::string& name)
{
  const std::string param = std::string(kEyes[e]) + "_camera_info";
  sensor_msgs::CameraInfo info;
  try
  {
    info = readCameraInfo(c.camera_info[e]);
  }
  catch (const std::invalid_argument& ex)
  {
    p.fail(param, "'" + c.camera_info[e] + "'", "", std::string("a camera_info file (") + ex.what() + ")");
  }
  if (int(info.width) != c.width || int(info.height) != c.height)
  {
    ROS_WARN("%s: %s calibrated at %ux%u, scaled to %dx%d", name.c_str(), c.camera_info[e].c_str(), info.width,
             info.height, c.width, c.height);
    info = scaledCameraInfo(info, c.width, c.height);
  }
  info.header.frame_id = c.frames[e];
  return info;
}
}  // namespace

/// The simulator's ROS side: TF, publishers, timer, /diagnostics.
class EndoscopeSim
{
public:
  /// @param ns namespace of the node (absolute, ending in '/'): the topics are <ns><eye>/...
  EndoscopeSim(ros::NodeHandle& nh, ros::NodeHandle& pnh, const std::string& name, const std::string& ns)
    : name_(name)
    , cfg_(readEndoscopeConfig(saras_common::Params(pnh)))
    , planner_(cfg_.frames[0], cfg_.frames[1], cfg_.tools)
    , health_(cfg_.tf_timeout)
    , pending_target_(cfg_.initial_target)
  {
    const saras_common::Params p(pnh);
    sensor_msgs::CameraInfo info[2] = { eyeInfo(p, cfg_, 0, name), eyeInfo(p, cfg_, 1, name) };
    scene_.reset(new StereoScene(info, cfg_, loadBones(p, cfg_, name)));
    tf_buffer_.reset(new tf2_ros::Buffer(ros::Duration(10.0)));
    // own thread: /tf off our queue; started from a thread named endoscope_sim, whose name it
    // inherits (Linux copies the creating thread's name): the simulator's /tf work is counted as its own
    std::exception_ptr failed;
    std::thread([&] {
      pthread_setname_np(pthread_self(), StereoWorkers::kName);
      try
      {
        tf_listener_.reset(new tf2_ros::TransformListener(*tf_buffer_, nh, true));
      }
      catch (...)
      {
        failed = std::current_exception();
      }
    }).join();
    if (failed)
      std::rethrow_exception(failed);
    tf_poses_.reset(new TfPoses(*tf_buffer_, cfg_.world));
    // the recorded streams (compressed + camera_info) get a deep queue per subscriber: a recorder
    // that stalls for a few frames must not lose them; the raw images (2.7 MB at 720p) keep 2
    const uint32_t recorded = static_cast<uint32_t>(cfg_.recorded_queue);
    for (int e = 0; e < 2; ++e)
    {
      const std::string eye = ns + kEyes[e];
      out_[e].reset(new EyeOutput(info[e], cfg_.jpeg_quality));
      pub_img_[e] = nh.advertise<sensor_msgs::Image>(eye + "/image_raw", 2);
      pub_jpg_[e] = nh.advertise<sensor_msgs::CompressedImage>(eye + "/image_raw/compressed", recorded);
      pub_info_[e] = nh.advertise<sensor_msgs::CameraInfo>(eye + "/camera_info", recorded);
    }
    updater_.reset(new diagnostic_updater::Updater(nh, pnh, name_));
    updater_->setHardwareID("endoscope");
    updater_->add("render", this, &EndoscopeSim::diagnose);
    sub_target_ = pnh.subscribe("target", 1, &EndoscopeSim::onTarget, this);
    // Render, encode and publish on the simulator's own named threads (endoscope_sim, or
    // endoscope_sim_l/_r with ~parallel_eyes), not on the manager's workers: its CPU is counted
    // apart from the nodelets sharing the manager. OpenCV single-threaded, so that its work stays
    // on these threads (parallel over the eyes, not inside each call); process-wide: the other
    // nodelets of a shared manager run OpenCV single-threaded too.
    cv::setNumThreads(1);
    workers_.reset(new StereoWorkers([this](int e) { renderAndPublish(e); }, cfg_.parallel_eyes));
    timer_ = nh.createTimer(ros::Duration(1.0 / cfg_.fps), &EndoscopeSim::tick, this);
  }

  ~EndoscopeSim()
  {
    timer_.stop();
    workers_.reset();  // joins the eye threads
  }

private:
  void onTarget(const std_msgs::String::ConstPtr& msg)
  {
    std::string s = msg->data;
    const auto b = s.find_first_not_of(" \t\r\n"), e = s.find_last_not_of(" \t\r\n");
    std::lock_guard<std::mutex> lock(target_mutex_);
    pending_target_ = b == std::string::npos ? "" : s.substr(b, e - b + 1);
    target_requested_ = true;
  }

  /// Scene changes asked for since the last frame (only while no eye renders).
  void updateScene()
  {
    std::string kind, error;
    bool requested = false;
    {
      std::lock_guard<std::mutex> lock(target_mutex_);
      std::swap(requested, target_requested_);
      kind = pending_target_;
    }
    if (requested && !scene_->selectTarget(kind, error))
      ROS_ERROR("%s: target '%s' rejected: %s", name_.c_str(), kind.c_str(), error.c_str());
    Eigen::Isometry3d T;
    ros::Time stamp;
    if (scene_->bonesPending() && tf_poses_->lookup(cfg_.bones_frame, ros::Time(), T, stamp, error) == PoseSource::Result::OK &&
        !scene_->placeBones(T, error))
      ROS_ERROR_THROTTLE(2.0, "%s: bone boxes not drawn: %s", name_.c_str(), error.c_str());
  }

  void tick(const ros::TimerEvent&)
  {
    std::unique_lock<std::mutex> busy(tick_mutex_, std::try_to_lock);
    if (!busy.owns_lock())
      return;  // previous tick still running: skip, never queue
    if (!workers_->idle())
    {
      health_.skipped();  // the render threads still work on the previous frame (nothing may change)
      return;
    }
    const ros::Time now = ros::Time::now();
    updateScene();
    std::string error;
    switch (planner_.plan(*tf_poses_, now, frame_, error))
    {
      case FramePlanner::Outcome::NO_POSE:
        health_.noPose();
        ROS_ERROR_THROTTLE(2.0, "%s: camera pose unavailable (%lu times): %s", name_.c_str(),
                           static_cast<unsigned long>(health_.rejected()), error.c_str());
        return status();
      case FramePlanner::Outcome::NON_FINITE_POSE:
        health_.nonFinitePose();
        ROS_ERROR_THROTTLE(2.0, "%s: %s", name_.c_str(), error.c_str());
        return status();
      case FramePlanner::Outcome::READY:
        break;
    }
    for (int e = 0; e < 2; ++e)
    {
      want_raw_[e] = pub_img_[e].getNumSubscribers() > 0;
      want_jpg_[e] = pub_jpg_[e].getNumSubscribers() > 0;
    }
    workers_->handOut();  // idle (checked above, only this thread hands out)
    health_.rendered(now.toSec(), frame_, cfg_.width, cfg_.height);
    status();
  }

  /// Eye @p e of frame_: render, encode, publish (on a render thread).
  void renderAndPublish(int e)
  {
    std::string error;
    const EyeMessages m = out_[e]->produce(*scene_, e, frame_, want_raw_[e], want_jpg_[e], error);
    if (!error.empty())
      ROS_ERROR_THROTTLE(2.0, "%s: %s eye: %s", name_.c_str(), kEyes[e], error.c_str());
    if (m.image)
      pub_img_[e].publish(m.image);
    if (m.jpeg)
      pub_jpg_[e].publish(m.jpeg);
    pub_info_[e].publish(out_[e]->cameraInfo(frame_.stamp));
  }

  /// Publishes /diagnostics at its period, at once when the level or the message changed.
  void status()
  {
    if (health_.takeChanged())
      updater_->force_update();
    else
      updater_->update();
  }

  void diagnose(diagnostic_updater::DiagnosticStatusWrapper& stat)
  {
    stat.summary(health_.level(), health_.message());
    stat.add("frames rendered", health_.frames());
    stat.add("rejected (no camera pose)", health_.rejected());
    stat.add("skipped (previous frame not done)", health_.skippedFrames());
    stat.add("input_age [s]", health_.inputAge(ros::Time::now().toSec()));
  }

  std::string name_;
  EndoscopeConfig cfg_;
  FramePlanner planner_;
  EndoscopeHealth health_;
  std::unique_ptr<StereoScene> scene_;
  std::unique_ptr<EyeOutput> out_[2];
  StereoFrame frame_;                       ///< the frame being rendered (read by the eye threads)
  bool want_raw_[2] = {}, want_jpg_[2] = {};  ///< this frame's subscribed outputs
  std::mutex target_mutex_, tick_mutex_;
  std::string pending_target_;
  bool target_requested_ = true;  ///< apply the initial ~target on the first tick
  std::unique_ptr<tf2_ros::Buffer> tf_buffer_;
  std::unique_ptr<tf2_ros::TransformListener> tf_listener_;
  std::unique_ptr<TfPoses> tf_poses_;
  ros::Publisher pub_img_[2], pub_jpg_[2], pub_info_[2];
  std::unique_ptr<diagnostic_updater::Updater> updater_;
  ros::Subscriber sub_target_;
  ros::Timer timer_;
  std::unique_ptr<StereoWorkers> workers_;  ///< render threads (~parallel_eyes: one per eye); last: joined first
};

/// Nodelet `saras_simulation/EndoscopeSim` (nodelet_plugins.xml).
class EndoscopeSimNodelet : public nodelet::Nodelet
{
private:
  void onInit() override
  {
    try
    {
      // topics in the nodelet's own namespace (e.g. /endoscope/left/...), not the manager's
      sim_.reset(new EndoscopeSim(getNodeHandle(), getPrivateNodeHandle(), getName(),
                                  saras_common::nodeletNamespace(getName())));
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
