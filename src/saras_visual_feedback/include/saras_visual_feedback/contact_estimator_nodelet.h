/**
 * @file contact_estimator_nodelet.h
 * @brief ContactEstimator nodelet (D7.2 Section 8): thin ROS adapter around StereoContactEstimator.
 *        Pairs the raw stereo images by stamp, places each SARAS tool in the left optical frame
 *        at the image stamp (ToolScene + placeTools, as the overlay), estimates its contact and
 *        publishes saras_msgs/Contact. See README.md for topics and parameters.
 */
#ifndef SARAS_VISUAL_FEEDBACK_CONTACT_ESTIMATOR_NODELET_H
#define SARAS_VISUAL_FEEDBACK_CONTACT_ESTIMATOR_NODELET_H

#include <array>
#include <atomic>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include <diagnostic_updater/diagnostic_updater.h>
#include <geometry_msgs/PoseStamped.h>
#include <image_transport/image_transport.h>
#include <nodelet/nodelet.h>
#include <ros/ros.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/transform_listener.h>

#include "saras_visual_feedback/ros_conversions.h"
#include "saras_visual_feedback/stereo_contact.h"
#include "saras_visual_feedback/tool_scene.h"

namespace saras_visual_feedback
{

/// One estimated tool (the `tools` parameter).
struct ContactToolConfig
{
  ToolConfig tool;              ///< name, pose_topic, rcm_frame (shaft direction)
  double radius = 0.0025;       ///< [m] shaft radius (masked)
  std::string topic;            ///< saras_msgs/Contact output
  std::string direction_frame;  ///< frame of Contact.direction (the contact-force consumer's)
  bool estimate = true;         ///< false: only masked (e.g. the da Vinci tools)
};

/// The nodelet's private parameters, read once and validated (config/contact_estimator.yaml).
struct ContactEstimatorParams
{
  StereoContactParams estimator;
  std::vector<ContactToolConfig> tools;
  double pose_timeout = 0.5;          ///< [s]
  int pose_buffer_size = 512;         ///< samples per tool
  double pose_stamp_tolerance = 0.03; ///< [s]
  double image_timeout = 1.0;         ///< [s] diagnostics STALE without stereo pairs
  int queue_size = 2;                 ///< camera subscription queue [frames]
};

/// Reads the private parameters of @p pnh; throws std::runtime_error naming a bad one.
ContactEstimatorParams readContactEstimatorParams(const ros::NodeHandle& pnh);

class ContactEstimatorNodelet : public nodelet::Nodelet
{
public:
  ContactEstimatorNodelet() = default;
  ~ContactEstimatorNodelet() override;

private:
  /// Per-tool output and counters.
  struct Output
  {
    ros::Publisher contact;    ///< saras_msgs/Contact, only when known
    ros::Publisher estimate;   ///< std_msgs/Float64MultiArray, every processed frame (see README)
    std::array<std::atomic<std::uint64_t>, 3> states{};  ///< frames per ContactState
    std::atomic<std::uint64_t> direction_failures{0};
    std::string last_unknown;  ///< reason of the last unknown state (guarded by stats_mutex_)
    double last_depth = 0.0, last_confidence = 0.0;
  };

  void onInit() override;
  void connectCb();
  void imageCb(const sensor_msgs::ImageConstPtr& image, const sensor_msgs::CameraInfoConstPtr& info, std::size_t eye);
  void processPair(const sensor_msgs::ImageConstPtr images[2], const sensor_msgs::CameraInfoConstPtr infos[2]);
  void publishTool(std::size_t i, const ContactEstimate& c, const std::string& camera_frame, const ros::Time& stamp);
  void poseCb(const geometry_msgs::PoseStampedConstPtr& msg, std::size_t tool);
  void diagnose(diagnostic_updater::DiagnosticStatusWrapper& status);

  ContactEstimatorParams params_;
  std::unique_ptr<ToolScene> scene_;
  std::shared_ptr<image_transport::ImageTransport> it_;
  std::array<image_transport::CameraSubscriber, 2> cam_subs_;
  std::vector<ros::Subscriber> pose_subs_;
  std::vector<std::unique_ptr<Output>> outputs_;
  std::mutex connect_mutex_;
  bool shutting_down_ = false;

  std::mutex pair_mutex_;  ///< guards the pending halves of a stereo pair
  std::array<sensor_msgs::ImageConstPtr, 2> pending_image_;
  std::array<sensor_msgs::CameraInfoConstPtr, 2> pending_info_;
  std::mutex process_mutex_;  ///< one stereo pair at a time (estimator scratch, calibration)
  StereoContactEstimator estimator_;
  sensor_msgs::CameraInfo calibrated_[2];
  std::string calibration_error_;
  SceneSnapshot snapshot_;

  std::unique_ptr<tf2_ros::Buffer> tf_buffer_;
  std::unique_ptr<tf2_ros::TransformListener> tf_listener_;
  std::unique_ptr<TfPointTransformer> tf_points_;

  std::unique_ptr<diagnostic_updater::Updater> updater_;
  ros::WallTimer diagnostics_timer_;
  std::mutex stats_mutex_;
  std::atomic<std::uint64_t> pairs_{0}, unpaired_{0}, rejected_{0}, cpu_ns_{0}, latency_ns_{0}, max_latency_ns_{0};
  std::atomic<std::int64_t> last_pair_wall_ns_{0};
  std::uint64_t pairs_reported_ = 0;
  ros::WallTime last_report_;
};

}  // namespace saras_visual_feedback

#endif  // SARAS_VISUAL_FEEDBACK_CONTACT_ESTIMATOR_NODELET_H
