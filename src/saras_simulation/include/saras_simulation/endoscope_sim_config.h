/**
 * @file endoscope_sim_config.h
 * @brief Start-up configuration of the endoscope simulator (nodelet saras_simulation/EndoscopeSim),
 *        read once through saras_common::Params and validated (ROS-free: Params reads from a
 *        NodeHandle in the nodelet, from a map in the gtests).
 *
 * Parameters (private; units): fps [Hz] 30 in [0.5, 120]; width, height [px] 1280 x 720;
 * camera_info_dir; left_camera_info, right_camera_info (file names, absolute or in the dir);
 * world_frame, left_frame, right_frame; jpeg_quality [1-100] 85; recorded_queue [messages] 30;
 * tf_timeout [s] 0.5; parallel_eyes (bool) true; texture_size [texels] 1024; texture_extent [m] 0.30;
 * light_distance [m] 0.10; tools [{tip, rcm, radius [m]}]; bones_file ('' = saras_collision's
 * config/pelvis_vertices.txt if present); bones_frame; bones_scaling (file unit -> m) 1.0;
 * tissue {z0 [m], centre [m, m], waves [[a m, kx rad/m, ky rad/m, phi rad]...]};
 * targets {checkerboard: {cols, rows, square m, res m, xyz m, rpy rad},
 *          circles: {dot_circle_radius m, dot_diameter m, dots, marker_circle_radius m,
 *                    marker_side m, res m, dictionary, xyz m, rpy rad}};
 * target (initial: none | checkerboard | circles).
 */
#ifndef SARAS_SIMULATION_ENDOSCOPE_SIM_CONFIG_H
#define SARAS_SIMULATION_ENDOSCOPE_SIM_CONFIG_H

#include <map>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Geometry>
#include <saras_common/params.h>

#include "saras_simulation/endoscope_renderer.h"
#include "saras_simulation/endoscope_scene.h"

namespace saras_simulation
{
namespace endoscope
{
/// An instrument shaft drawn from two TF frames.
struct ToolFrames
{
  std::string tip, rcm;  ///< TF frames of the tool tip and of its remote centre of motion
  double radius;         ///< [m]
};

/// A calibration target's parameters (validated; the target itself is built on demand).
struct TargetSpec
{
  std::string kind;                      ///< checkerboard | circles
  std::map<std::string, double> values;  ///< numeric keys of the kind (defaults filled in)
  std::string dictionary = "DICT_4X4_50";
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();  ///< T_world_board
};

/// Everything the simulator reads at start-up.
struct EndoscopeConfig
{
  double fps = 30.0;           ///< [Hz]
  int width = 1280, height = 720;  ///< [px]
  std::string camera_info[2];  ///< camera_info files (left, right), resolved paths
  std::string world = "world";
  std::string frames[2] = { "endoscope/left_optical_frame", "endoscope/right_optical_frame" };
  int jpeg_quality = 85;       ///< [1-100]
  int recorded_queue = 30;     ///< [messages] per subscriber of compressed + camera_info
  double tf_timeout = 0.5;     ///< [s]
  bool parallel_eyes = true;
  RendererOptions renderer;
  TissueSurface tissue;
  std::vector<ToolFrames> tools;
  std::string bones_file;      ///< '' = the default (resolved by the caller: it needs the ROS package path)
  std::string bones_frame = "bones_marker_frame";
  double bones_scaling = 1.0;  ///< file unit -> m
  std::map<std::string, TargetSpec> targets;  ///< by kind: checkerboard, circles (defaults if not configured)
  std::string initial_target = "none";
};

/// Reads and validates the configuration. @throws saras_common::ParamError naming the parameter
EndoscopeConfig readEndoscopeConfig(const saras_common::Params& p);

/// The target of @p spec. @throws std::invalid_argument
std::shared_ptr<PlanarTarget> buildTarget(const TargetSpec& spec);

}  // namespace endoscope
}  // namespace saras_simulation

#endif  // SARAS_SIMULATION_ENDOSCOPE_SIM_CONFIG_H
