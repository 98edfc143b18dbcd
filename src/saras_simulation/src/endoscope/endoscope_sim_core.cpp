/**
 * @file endoscope_sim_core.cpp
 * @brief FramePlanner, EndoscopeHealth, StereoWorkers.
 */
#include "saras_simulation/endoscope_sim_core.h"

#include <pthread.h>

#include <cstdio>
#include <limits>

namespace saras_simulation
{
namespace endoscope
{
FramePlanner::FramePlanner(const std::string& left_frame, const std::string& right_frame,
                           const std::vector<ToolFrames>& tools)
  : frames_{ left_frame, right_frame }, tools_(tools)
{
}

bool FramePlanner::poseAt(PoseSource& tf, const std::string& f, const ros::Time& stamp, Eigen::Isometry3d& pose,
                          std::string& error)
{
  ros::Time s;
  PoseSource::Result r = tf.lookup(f, stamp, pose, s, error);
  if (r == PoseSource::Result::EXTRAPOLATION)
    r = tf.lookup(f, ros::Time(), pose, s, error);
  return r == PoseSource::Result::OK;
}

FramePlanner::Outcome FramePlanner::plan(PoseSource& tf, const ros::Time& now, StereoFrame& frame,
                                         std::string& error) const
{
  ros::Time stamp;
  if (tf.lookup(frames_[0], ros::Time(), frame.pose[0], stamp, error) != PoseSource::Result::OK)
    return Outcome::NO_POSE;
  frame.is_static = stamp.isZero();
  if (!poseAt(tf, frames_[1], stamp, frame.pose[1], error))
    return Outcome::NO_POSE;
  frame.stamp = frame.is_static ? now : stamp;
  if (!frame.pose[0].matrix().allFinite() || !frame.pose[1].matrix().allFinite())
  {
    error = "non-finite camera pose";
    return Outcome::NON_FINITE_POSE;
  }
  frame.shafts.clear();
  for (const ToolFrames& t : tools_)
  {
    Eigen::Isometry3d tip, rcm;
    std::string ignored;
    // a tool not (yet) in the scene is not drawn
    if (poseAt(tf, t.tip, frame.stamp, tip, ignored) && poseAt(tf, t.rcm, frame.stamp, rcm, ignored))
      frame.shafts.push_back({ tip.translation(), rcm.translation(), t.radius });
  }
  return Outcome::READY;
}

// ---------------------------------------------------------------------------------------------
void EndoscopeHealth::set(Level level, const std::string& message)
{
  if (level != level_ || message != message_)
  {
    level_ = level;
    message_ = message;
    changed_ = true;
  }
}

void EndoscopeHealth::noPose()
{
  ++rejected_;
  set(ERROR, "no camera pose in TF: not publishing");
}

void EndoscopeHealth::nonFinitePose()
{
  ++rejected_;
  set(ERROR, "non-finite camera pose in TF: not publishing");
}

void EndoscopeHealth::skipped()
{
  ++skipped_;
}

void EndoscopeHealth::rendered(double now, const StereoFrame& frame, int width, int height)
{
  ++frames_;
  last_frame_ = now;
  const double age = now - frame.stamp.toSec();
  if (!frame.is_static && age > tf_timeout_)
  {
    char buf[96];
    std::snprintf(buf, sizeof(buf), "camera TF is %.1f s old (dVRK stopped?)", age);
    set(WARN, buf);
  }
  else
    set(OK, "rendering " + std::to_string(width) + "x" + std::to_string(height));
}

bool EndoscopeHealth::takeChanged()
{
  const bool c = changed_;
  changed_ = false;
  return c;
}

double EndoscopeHealth::inputAge(double now) const
{
  return last_frame_ < 0 ? std::numeric_limits<double>::infinity() : now - last_frame_;
}

// ---------------------------------------------------------------------------------------------
constexpr const char* StereoWorkers::kName;
constexpr const char* StereoWorkers::kEyeNames[2];

StereoWorkers::StereoWorkers(std::function<void(int)> job, bool parallel) : job_(std::move(job)), parallel_(parallel)
{
  for (int t = 0; t < (parallel ? 2 : 1); ++t)
    threads_.emplace_back(&StereoWorkers::loop, this, t);
}

StereoWorkers::~StereoWorkers()
{
  {
    std::lock_guard<std::mutex> lock(mutex_);
    quit_ = true;
  }
  cv_.notify_all();
  for (auto& t : threads_)
    if (t.joinable())
      t.join();
}

bool StereoWorkers::idle()
{
  std::lock_guard<std::mutex> lock(mutex_);
  return !pending_[0] && !pending_[1];
}

bool StereoWorkers::handOut()
{
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (pending_[0] || pending_[1])
      return false;
    pending_[0] = pending_[1] = true;
  }
  cv_.notify_all();
  return true;
}

void StereoWorkers::loop(int t)
{
  pthread_setname_np(pthread_self(), parallel_ ? kEyeNames[t] : kName);
  const int first = parallel_ ? t : 0, last = parallel_ ? t : 1;
  std::unique_lock<std::mutex> lock(mutex_);
  while (true)
  {
    cv_.wait(lock, [this, first] { return pending_[first] || quit_; });
    if (quit_)
      return;
    lock.unlock();
    for (int e = first; e <= last; ++e)
      job_(e);
    lock.lock();
    for (int e = first; e <= last; ++e)
      pending_[e] = false;
  }
}

}  // namespace endoscope
}  // namespace saras_simulation
