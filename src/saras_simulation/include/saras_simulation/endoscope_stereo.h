/**
 * @file endoscope_stereo.h
 * @brief ROS-free frame assembly of the endoscope simulator: the stereo scene (two renderers,
 *        bones, the shown calibration target) and, per eye, the outgoing messages (raw image,
 *        JPEG, camera_info) from saras_common::MessagePool (no per-frame allocation or
 *        zero-filling of the 2.7 MB (720p) image).
 */
#ifndef SARAS_SIMULATION_ENDOSCOPE_STEREO_H
#define SARAS_SIMULATION_ENDOSCOPE_STEREO_H

#include <array>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include <saras_common/message_pool.h>
#include <saras_visual_feedback/jpeg_encoder.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/CompressedImage.h>
#include <sensor_msgs/Image.h>

#include "saras_simulation/endoscope_renderer.h"
#include "saras_simulation/endoscope_sim_config.h"
#include "saras_simulation/endoscope_sim_core.h"

namespace saras_simulation
{
namespace endoscope
{
/// The scene both eyes see. Not thread-safe: change it only while no eye renders.
class StereoScene
{
public:
  /**
   * @param info camera_info of the left and right eye (validated, at the image size)
   * @param bones bone boxes in the bones frame [m] (8 vertices each, vertices-file order)
   * @throws std::invalid_argument if a renderer cannot be set up
   */
  StereoScene(const sensor_msgs::CameraInfo info[2], const EndoscopeConfig& config,
              std::vector<std::array<Eigen::Vector3d, 8>> bones);

  /// Shows target @p kind (none | a key of config.targets); false (scene unchanged) otherwise.
  bool selectTarget(const std::string& kind, std::string& error);
  /// Bones still to be placed (there are bones and placeBones() has not succeeded).
  bool bonesPending() const { return !bones_.empty() && !bones_placed_; }
  /// Places the bones at T_world_bones; false if the pose is not finite.
  bool placeBones(const Eigen::Isometry3d& T_world_bones, std::string& error);
  /// Renders eye @p e at @p pose (T_world_optical) with @p shafts into @p out.
  void render(int e, const Eigen::Isometry3d& pose, const std::vector<Shaft>& shafts, cv::Mat& out)
  {
    renderers_[e]->render(pose, shafts, out);
  }

private:
  std::unique_ptr<SceneRenderer> renderers_[2];
  std::vector<std::array<Eigen::Vector3d, 8>> bones_;
  bool bones_placed_ = false;
  std::map<std::string, TargetSpec> specs_;
  std::map<std::string, std::shared_ptr<const PlanarTarget>> built_;  ///< targets built so far
};

/// What an eye publishes for one frame (null: not wanted / failed).
struct EyeMessages
{
  sensor_msgs::ImagePtr image;
  sensor_msgs::CompressedImagePtr jpeg;
};

/// One eye's outgoing messages: renders into a pooled image message, encodes a pooled JPEG
/// (saras_visual_feedback::JpegEncoder: libjpeg-turbo reading the BGR render as is, 4:2:0).
class EyeOutput
{
public:
  /// @param info camera_info of the eye (its frame_id is the messages' frame)
  /// @param jpeg_quality [1-100]; @param pool_size messages per pool
  EyeOutput(const sensor_msgs::CameraInfo& info, int jpeg_quality, std::size_t pool_size = 4);

  /**
   * Renders eye @p e of @p frame through @p scene into this frame's messages: the raw image if
   * @p want_raw, the JPEG if @p want_jpeg, stamped @p frame.stamp. Errors are returned in
   * @p error (the messages are then null).
   */
  EyeMessages produce(StereoScene& scene, int e, const StereoFrame& frame, bool want_raw, bool want_jpeg,
                      std::string& error);
  /// camera_info stamped @p stamp.
  const sensor_msgs::CameraInfo& cameraInfo(const ros::Time& stamp);
  /// Allocations of the pools since construction (constant in steady state).
  uint64_t allocations() const { return images_.allocations() + jpegs_.allocations(); }

private:
  sensor_msgs::CameraInfo info_;
  saras_visual_feedback::JpegEncoder jpeg_;
  saras_common::MessagePool<sensor_msgs::Image> images_;
  saras_common::MessagePool<sensor_msgs::CompressedImage> jpegs_;
  cv::Mat buffer_;  ///< render target when only the JPEG is wanted
};

}  // namespace endoscope
}  // namespace saras_simulation

#endif  // SARAS_SIMULATION_ENDOSCOPE_STEREO_H
