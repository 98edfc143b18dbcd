/**
 * @file endoscope_sim_core.h
 * @brief ROS-free decisions of the endoscope simulator per frame: which poses a stereo frame is
 *        rendered with and how it is stamped (FramePlanner over a PoseSource), what /diagnostics
 *        reports (EndoscopeHealth), and the pacing of the two eye threads (StereoWorkers: a frame
 *        is skipped, never queued, while the previous one is still being rendered).
 */
#ifndef SARAS_SIMULATION_ENDOSCOPE_SIM_CORE_H
#define SARAS_SIMULATION_ENDOSCOPE_SIM_CORE_H

#include <condition_variable>
#include <cstdint>
#include <functional>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include <Eigen/Geometry>
#include <ros/time.h>

#include "saras_simulation/endoscope_renderer.h"
#include "saras_simulation/endoscope_sim_config.h"

namespace saras_simulation
{
namespace endoscope
{
/// Where poses come from (the nodelet: a tf2_ros::Buffer; tests: a table).
class PoseSource
{
public:
  enum class Result
  {
    OK,
    EXTRAPOLATION,  ///< the frame exists but not at that time
    UNAVAILABLE     ///< no such frame / no connection to the world
  };
  virtual ~PoseSource() = default;
  /**
   * Pose of @p frame in the world at @p stamp (zero: the latest). On OK, @p pose and
   * @p pose_stamp (zero for a static transform) are set; @p error explains a failure.
   */
  virtual Result lookup(const std::string& frame, const ros::Time& stamp, Eigen::Isometry3d& pose,
                        ros::Time& pose_stamp, std::string& error) = 0;
};

/// What a stereo frame is rendered with.
struct StereoFrame
{
  ros::Time stamp;           ///< TF time of the left camera pose (now if the pose is static)
  bool is_static = false;    ///< the camera pose is a static transform
  Eigen::Isometry3d pose[2];  ///< T_world_optical of the left and right eye
  std::vector<Shaft> shafts;  ///< instrument shafts at the frame's time (those in TF)
};

/**
 * Pose policy: the left eye's latest pose sets the frame's stamp (lookupTransform(world, optical,
 * image.header.stamp) then returns exactly the rendered pose); the right eye and the tools are
 * looked up at that stamp, else at their latest; a static camera pose is stamped now.
 */
class FramePlanner
{
public:
  enum class Outcome
  {
    READY,
    NO_POSE,         ///< a camera pose is not in TF
    NON_FINITE_POSE  ///< a camera pose has NaN / inf
  };
  FramePlanner(const std::string& left_frame, const std::string& right_frame, const std::vector<ToolFrames>& tools);
  /// Fills @p frame at time @p now; @p error says why it is not READY.
  Outcome plan(PoseSource& tf, const ros::Time& now, StereoFrame& frame, std::string& error) const;

private:
  /// Pose at @p stamp, else the latest; false if unavailable.
  static bool poseAt(PoseSource& tf, const std::string& f, const ros::Time& stamp, Eigen::Isometry3d& pose,
                     std::string& error);
  std::string frames_[2];
  std::vector<ToolFrames> tools_;
};

/// Level, message and counters of the simulator's /diagnostics status.
class EndoscopeHealth
{
public:
  /// diagnostic_msgs/DiagnosticStatus levels
  enum Level : uint8_t
  {
    OK = 0,
    WARN = 1,
    ERROR = 2,
    STALE = 3
  };
  /// @param tf_timeout [s] a moving camera pose older than this is reported (WARN)
  explicit EndoscopeHealth(double tf_timeout) : tf_timeout_(tf_timeout) {}

  void noPose();            ///< ERROR, counted as rejected
  void nonFinitePose();     ///< ERROR, counted as rejected
  void skipped();           ///< the previous frame was not done: counted
  /// A frame handed out at @p now [s] for a pose of @p stamp [s]; @p width x @p height [px].
  void rendered(double now, const StereoFrame& frame, int width, int height);

  Level level() const { return level_; }
  const std::string& message() const { return message_; }
  /// Whether level or message changed since the last call (then publish at once).
  bool takeChanged();
  uint64_t frames() const { return frames_; }
  uint64_t rejected() const { return rejected_; }
  uint64_t skippedFrames() const { return skipped_; }
  /// [s] since the last frame at @p now (inf before the first).
  double inputAge(double now) const;

private:
  void set(Level level, const std::string& message);
  double tf_timeout_;
  Level level_ = STALE;
  std::string message_ = "starting";
  bool changed_ = true;
  double last_frame_ = -1.0;  ///< [s]
  uint64_t frames_ = 0, rejected_ = 0, skipped_ = 0;
};

/**
 * The simulator's render threads, each running job(eye) once per handed-out frame: one thread
 * named "endoscope_sim" rendering both eyes one after the other, or (parallel) one per eye named
 * "endoscope_sim_l" / "endoscope_sim_r". The whole simulator's per-frame work (render, JPEG,
 * publish) runs on these named threads, never on the nodelet manager's workers, so that a process
 * table can count it apart from the nodelets sharing the manager. handOut() refuses (returns false)
 * while an eye still works on the previous frame: frames are skipped, never queued, and nothing
 * the jobs read may change before they are done (idle() is true).
 */
class StereoWorkers
{
public:
  /// Thread names (pthread names: at most 15 characters).
  static constexpr const char* kName = "endoscope_sim";
  static constexpr const char* kEyeNames[2] = { "endoscope_sim_l", "endoscope_sim_r" };

  StereoWorkers(std::function<void(int eye)> job, bool parallel);
  ~StereoWorkers();
  StereoWorkers(const StereoWorkers&) = delete;
  StereoWorkers& operator=(const StereoWorkers&) = delete;

  /// No eye is working.
  bool idle();
  /// Starts both eyes on a frame; false (nothing started) if not idle().
  bool handOut();

private:
  /// Thread @p t: eye t (parallel) or both eyes (one thread).
  void loop(int t);
  std::function<void(int)> job_;
  bool parallel_;
  std::mutex mutex_;
  std::condition_variable cv_;
  bool pending_[2] = { false, false };
  bool quit_ = false;
  std::vector<std::thread> threads_;
};

}  // namespace endoscope
}  // namespace saras_simulation

#endif  // SARAS_SIMULATION_ENDOSCOPE_SIM_CORE_H
