/**
 * @file tool_scene.h
 * @brief ROS-agnostic state the overlay is drawn from: the tools' pose histories, the collision
 *        distances and the drawing style, with their freshness; thread-safe. snapshot() gives
 *        each tool at an image stamp (pose interpolated at the stamp, distance or unknown).
 */
#ifndef SARAS_VISUAL_FEEDBACK_TOOL_SCENE_H
#define SARAS_VISUAL_FEEDBACK_TOOL_SCENE_H

#include <array>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <mutex>
#include <string>
#include <vector>

#include "saras_visual_feedback/overlay.h"
#include "saras_visual_feedback/pose_history.h"

namespace saras_visual_feedback
{

/// Stamp meaning "the newest pose" (an unstamped image).
constexpr std::int64_t kLatestStamp = std::numeric_limits<std::int64_t>::max();

/// One tool drawn on the images (SARAS tool or da Vinci PSM), from the `tools` parameter.
struct ToolConfig
{
  std::string name;          ///< e.g. mesa_left
  std::string label;         ///< HUD label
  std::string pose_topic;    ///< PoseStamped of the tip
  std::string rcm_frame;     ///< TF frame of the trocar; "" = draw the tip only
  int distance_index = 0;    ///< index in /collision/distances
  bool dvrk = false;         ///< drawn only while draw_dvrk is true
};

/// Settings changed at run time (dynamic_reconfigure).
struct SceneStyle
{
  OverlayStyle overlay;
  double shaft_length = 0.05;  ///< drawn shaft length [m]
  bool draw_dvrk = true;       ///< draw the tools with ToolConfig::dvrk
};

/// One tool as seen at an image stamp.
struct ToolSample
{
  const ToolConfig* tool = nullptr;
  double distance = std::numeric_limits<double>::quiet_NaN();  ///< [m], NaN: unknown or stale
  PoseLookupResult pose;  ///< status kEmpty: no fresh pose
  std::string frame;      ///< frame of pose (capacity reused between frames)
};

/// The scene at one image stamp: the tools to draw, in configuration order.
struct SceneSnapshot
{
  SceneStyle style;
  std::size_t n = 0;
  std::array<ToolSample, kMaxTools> tools;
};

/// Counters of rejected input, for diagnostics.
struct SceneCounters
{
  std::uint64_t rejected_poses = 0;      ///< NaN/inf values or empty frame_id
  std::uint64_t rejected_distances = 0;  ///< arrays shorter than the largest distance_index + 1
  std::uint64_t history_restarts = 0;    ///< pose stamps went backwards
};

class ToolScene
{
public:
  /**
   * @param tools 1 to kMaxTools tools
   * @param pose_buffer_size samples of pose history per tool (>= 2)
   * @param pose_timeout_ns a tool is not drawn once its newest pose was received longer ago [ns]
   * @param distances_timeout_ns distances older than this are unknown [ns]
   */
  ToolScene(std::vector<ToolConfig> tools, std::size_t pose_buffer_size, std::int64_t pose_timeout_ns,
            std::int64_t distances_timeout_ns, const SceneStyle& style);

  const std::vector<ToolConfig>& tools() const { return tools_; }

  /// Adds a (valid) pose of tool @p i in @p frame, received at @p now_ns (any monotonic clock
  /// shared with snapshot()). Poses of a new frame restart the history.
  PosePush addPose(std::size_t i, const std::string& frame, const TimedPose& sample, std::int64_t now_ns);
  /// Counts a rejected pose of tool @p i; returns the count so far.
  std::uint64_t rejectPose(std::size_t i);
  /// Latches the distances [m] (NaN entries stay unknown); false when fewer than needed (counted).
  bool setDistances(const std::vector<double>& distances, std::int64_t now_ns);
  /// Largest distance_index + 1.
  std::size_t distancesNeeded() const { return distances_needed_; }

  void setStyle(const SceneStyle& style);
  SceneStyle style() const;
  SceneCounters counters() const;

  /// The tools to draw at @p image_stamp_ns (kLatestStamp: newest poses), seen at @p now_ns.
  void snapshot(std::int64_t now_ns, std::int64_t image_stamp_ns, SceneSnapshot* out) const;

private:
  struct History
  {
    PoseHistory poses;
    std::string frame;            ///< frame of the poses
    std::int64_t received_ns = 0; ///< receipt time of the newest pose
    bool any = false;
  };

  const std::vector<ToolConfig> tools_;
  const std::int64_t pose_timeout_ns_, distances_timeout_ns_;
  std::size_t distances_needed_ = 0;
  mutable std::mutex mutex_;
  std::vector<History> histories_;
  std::vector<double> distances_;
  std::int64_t distances_received_ns_ = 0;
  bool distances_seen_ = false;
  SceneStyle style_;
  SceneCounters counters_;
};

}  // namespace saras_visual_feedback

#endif  // SARAS_VISUAL_FEEDBACK_TOOL_SCENE_H
