/**
 * @file visual_feedback_params.h
 * @brief The VisualFeedback nodelet's private parameters, read once and validated (units in
 *        config/visual_feedback.yaml).
 */
#ifndef SARAS_VISUAL_FEEDBACK_VISUAL_FEEDBACK_PARAMS_H
#define SARAS_VISUAL_FEEDBACK_VISUAL_FEEDBACK_PARAMS_H

#include <vector>

#include <ros/node_handle.h>

#include "saras_visual_feedback/tool_scene.h"

namespace saras_visual_feedback
{

struct VisualFeedbackParams
{
  SceneStyle style;                   ///< initial drawing style (dynamic_reconfigure changes it)
  std::vector<ToolConfig> tools;      ///< 1 to kMaxTools tools (default: the platform's four)
  double pose_timeout = 0.5;          ///< [s] a tool is not drawn once its newest pose is older
  double distances_timeout = 0.5;     ///< [s] distances older than this are drawn as unknown
  double image_timeout = 1.0;         ///< [s] diagnostics STALE without images while subscribed
  int pose_buffer_size = 512;         ///< samples of pose history per tool (≈ 2 s at 250 Hz)
  double pose_stamp_tolerance = 0.03; ///< [s] an image newer than the newest pose by more is a fallback
  int jpeg_quality = 80;              ///< JPEG quality of the own /compressed stream [1, 100]
  int queue_size = 6;                 ///< camera subscription and publisher queue [frames]
};

/// Reads the private parameters of @p pnh; throws std::runtime_error naming a bad one.
VisualFeedbackParams readVisualFeedbackParams(const ros::NodeHandle& pnh);

}  // namespace saras_visual_feedback

#endif  // SARAS_VISUAL_FEEDBACK_VISUAL_FEEDBACK_PARAMS_H
