/**
 * @file frame_composer.h
 * @brief ROS-agnostic composition of one augmented frame: each tool placed in the camera's
 *        optical frame at the image stamp (through a PointTransformer), drawn with its colour,
 *        and the per-eye statistics reported on /diagnostics.
 */
#ifndef SARAS_VISUAL_FEEDBACK_FRAME_COMPOSER_H
#define SARAS_VISUAL_FEEDBACK_FRAME_COMPOSER_H

#include <array>
#include <atomic>
#include <cstdint>
#include <string>

#include <opencv2/core.hpp>

#include "saras_visual_feedback/overlay.h"
#include "saras_visual_feedback/raw_projector.h"
#include "saras_visual_feedback/tool_scene.h"

namespace saras_visual_feedback
{

/// Expresses points of one frame in another at a stamp (implemented with tf2 by the nodelet).
class PointTransformer
{
public:
  virtual ~PointTransformer() = default;
  /**
   * @brief @p p [m] of frame @p source in frame @p target at @p stamp_ns (kLatestStamp: latest).
   * @param[out] at_stamp false when only the latest transform was available (a fallback)
   * @return false (reason in @p error) when no transform exists at all
   */
  virtual bool transform(const std::string& target, const std::string& source, std::int64_t stamp_ns,
                         const cv::Point3d& p, cv::Point3d* out, bool* at_stamp, std::string* error) const = 0;
};

/// What happened to one tool while placing it (for warnings and counters).
struct ToolPlacement
{
  bool pose_fallback = false;      ///< pose not available at the image stamp: the newest was used
  bool tip_failed = false;         ///< no transform of the tip: not drawn
  bool shaft_failed = false;       ///< no transform of the trocar: tip only
  int transform_fallbacks = 0;     ///< transforms taken at the latest time instead of the stamp
  std::string error;               ///< transform error (tip_failed / shaft_failed)
};

/// Outcome of one frame.
struct FrameReport
{
  std::size_t n = 0;  ///< tools considered
  std::array<ToolPlacement, kMaxTools> tools;
  std::array<ToolDrawResult, kMaxTools> drawn;
  bool overlay = false;  ///< false: camera model invalid, image published without tools
};

/**
 * @brief Places the tools of @p scene in @p camera_frame at @p stamp_ns into @p overlays
 *        (distance, tip, shaft towards the trocar clipped to the style's shaft length).
 * @param tolerance_ns an image newer than a tool's newest pose by at most this is "at the stamp"
 */
void placeTools(const SceneSnapshot& scene, const std::string& camera_frame, std::int64_t stamp_ns,
                std::int64_t tolerance_ns, const PointTransformer& tf, ToolOverlay* overlays, FrameReport* report);

/**
 * @brief Draws the frame: tools and HUD through @p camera, or, when @p camera is nullptr, only
 *        the HUD with "overlay off: <off_reason>" (tools listed, none drawn).
 */
void drawFrame(cv::Mat& canvas, ChannelOrder order, const RawProjector* camera, const std::string& off_reason,
               const SceneSnapshot& scene, ToolOverlay* overlays, HudCache* hud, FrameReport* report);

/// Per-eye counters since start; written by the eye's image callback, read by diagnostics.
struct EyeStats
{
  std::atomic<std::uint64_t> received{0}, published{0}, rejected{0};
  std::atomic<std::uint64_t> tf_failures{0}, pose_fallbacks{0}, tf_fallbacks{0};
  /// Frames in which at least one tool was drawn in each colour, indexed by Proximity.
  std::array<std::atomic<std::uint64_t>, 4> colour_frames{};
  std::atomic<std::uint64_t> busy_ns{0}, max_busy_ns{0};  ///< wall-clock processing time [ns]
  std::atomic<std::uint64_t> cpu_ns{0};                    ///< thread CPU time of the processing [ns]
  std::atomic<std::int64_t> last_image_ns{0};              ///< wall time of the last image [ns]

  /// Adds a composed frame's outcome.
  void record(const FrameReport& report);
  /// Adds one published frame's processing time.
  void addTiming(std::uint64_t wall_ns, std::uint64_t cpu_ns);
};

}  // namespace saras_visual_feedback

#endif  // SARAS_VISUAL_FEEDBACK_FRAME_COMPOSER_H
