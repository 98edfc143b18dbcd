/**
 * @file colliding_regions.h
 * @brief ROS adapter of the collision scene: the colliding_regions node (D7.2 Section 6.1).
 *
 * Inputs: tool-tip poses (geometry_msgs/PoseStamped, any TF frame, default per tool), TF
 * world -> bones_marker_frame, tool base frames and trocar (RCM) frames, looked up every cycle
 * (so calibration updates and robot_state_publisher changes are followed).
 * Outputs: /collision/distances, /collision/report, /collision/markers, optional
 * /collision/<tool>/fixture_wrench, health on /diagnostics (hardware_id "collision": cycle rate,
 * input staleness, rejected inputs, closest distance). See README.md for parameters.
 */
#ifndef SARAS_COLLISION_COLLIDING_REGIONS_H
#define SARAS_COLLISION_COLLIDING_REGIONS_H

#include <memory>
#include <string>
#include <vector>

#include <Eigen/Geometry>
#include <diagnostic_updater/diagnostic_updater.h>
#include <diagnostic_updater/update_functions.h>
#include <geometry_msgs/PoseStamped.h>
#include <geometry_msgs/WrenchStamped.h>
#include <ros/ros.h>
#include <saras_msgs/CollisionReport.h>
#include <std_msgs/Float64MultiArray.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/transform_listener.h>
#include <visualization_msgs/MarkerArray.h>

#include "saras_collision/scene.h"

namespace saras_collision
{
/// Validated node parameters (units in comments).
struct CollidingRegionsConfig
{
  double rate = 20.0;  ///< cycle rate [Hz]
  std::string vertices_file;  ///< forbidden-region file (bones_marker_frame)
  double scaling = 1.0;  ///< file unit -> metres
  double vertex_tolerance = 1e-6;  ///< relative box tolerance
  double collision_threshold = 0.005;  ///< [m]
  double warning_threshold = 0.02;  ///< [m]
  double tf_timeout = 3.0;  ///< start-up grace before a missing TF frame or pose is an error [s]
  double pose_timeout = 0.5;  ///< a tool pose older than this is stale (no data) [s]
  double marker_rate = 10.0;  ///< marker publication rate [Hz] (<= rate)
  std::string world_frame = "world";
  std::string bones_frame = "bones_marker_frame";
  bool fixture_enabled = false;
  double fixture_stiffness = 200.0;  ///< [N/m]
  double fixture_max_force = 2.0;  ///< [N]

  struct Tool
  {
    std::string name;  ///< "mesa_left", ...
    std::string topic;  ///< tool-tip PoseStamped topic
    std::string frame;  ///< frame of the pose when its header has none
    std::string trocar_frame;  ///< TF frame whose origin is the trocar (RCM)
    double radius = 0.0;  ///< [m]
    std::string fixture_topic;  ///< WrenchStamped topic; empty: no fixture for this tool
  };
  std::vector<Tool> tools;
};

/**
 * @brief Read and validate the parameters from @p pnh.
 * @param[out] error names the offending parameter
 */
bool loadConfig(const ros::NodeHandle& pnh, CollidingRegionsConfig& config, std::string& error);

class CollidingRegions
{
public:
  CollidingRegions(const ros::NodeHandle& nh, const CollidingRegionsConfig& config);

  /// Load the vertices file and start subscribers, publishers and timers.
  bool start(std::string& error);

private:
  struct ToolState
  {
    Eigen::Vector3d tip_local = Eigen::Vector3d::Zero();  ///< tip in frame [m]
    std::string frame;  ///< frame of tip_local
    ros::Time stamp_rx;  ///< reception time of the last valid pose
    bool have_pose = false;
    ros::Subscriber sub;
    ros::Publisher fixture_pub;
    geometry_msgs::WrenchStamped wrench;
  };

  void poseCallback(std::size_t i, const geometry_msgs::PoseStampedConstPtr& msg);
  void cycle(const ros::SteadyTimerEvent& event);
  /// world_T_frame at the latest time; false (with throttled log) if unavailable.
  bool lookup(const std::string& frame, Eigen::Isometry3d& world_T_frame);
  void updateBones();
  void publishMarkers(const ros::Time& now);
  /// Box markers of the forbidden regions into markers_msg_ from index 0. @return their number
  std::size_t fillBoxMarkers(const ros::Time& now);
  /**
   * Health level (diagnostic_msgs/DiagnosticStatus OK .. STALE) of the inputs: OK when the
   * forbidden regions are placed and every tool has a current pose; WARN while something is
   * missing within the start-up grace (~tf_timeout); after it ERROR when a tool or the
   * forbidden regions are not monitored, STALE when no tool has a current pose (the node runs
   * but monitors nothing). The reason is built only if @p message is not null.
   */
  uint8_t computeLevel(std::string* message) const;
  /// diagnostic_updater task "inputs": computeLevel() plus the counters and ages.
  void inputsDiagnostic(diagnostic_updater::DiagnosticStatusWrapper& status);

  ros::NodeHandle nh_;
  CollidingRegionsConfig config_;
  tf2_ros::Buffer tf_buffer_;
  std::unique_ptr<tf2_ros::TransformListener> tf_listener_;
  CollisionScene scene_;
  std::vector<OrientedBox> boxes_bones_;  ///< boxes in bones_marker_frame
  std::vector<OrientedBox> boxes_world_;
  std::vector<std::string> box_names_;
  Eigen::Isometry3d world_T_bones_ = Eigen::Isometry3d::Identity();
  bool have_bones_ = false;
  std::vector<ToolState> tools_;
  ros::Publisher distances_pub_, report_pub_, markers_pub_;
  ros::SteadyTimer cycle_timer_;
  diagnostic_updater::Updater updater_;
  double min_rate_ = 0.0, max_rate_ = 0.0;  ///< bounds of the cycle-rate diagnostic [Hz]
  std::unique_ptr<diagnostic_updater::FrequencyStatus> cycle_rate_;
  std_msgs::Float64MultiArray distances_msg_;
  saras_msgs::CollisionReport report_msg_;
  visualization_msgs::MarkerArray markers_msg_;
  ros::WallTime start_time_;
  ros::WallTime last_marker_time_;
  uint64_t received_ = 0, rejected_ = 0, tf_failures_ = 0, cycles_ = 0;
  uint8_t last_level_ = 255;
  std::string missing_frame_;  ///< last frame that could not be looked up
};

}  // namespace saras_collision

#endif  // SARAS_COLLISION_COLLIDING_REGIONS_H
