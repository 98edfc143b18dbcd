/**
 * @file visual_feedback_nodelet.h
 * @brief VisualFeedback nodelet (D7.2 Section 7): thin ROS adapter around CameraModel and
 *        drawOverlay. See README.md for topics and parameters.
 */
#ifndef SARAS_VISUAL_FEEDBACK_VISUAL_FEEDBACK_NODELET_H
#define SARAS_VISUAL_FEEDBACK_VISUAL_FEEDBACK_NODELET_H

#include <array>
#include <atomic>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include <dynamic_reconfigure/server.h>
#include <geometry_msgs/PoseStamped.h>
#include <image_transport/image_transport.h>
#include <nodelet/nodelet.h>
#include <ros/ros.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <std_msgs/Float64MultiArray.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/transform_listener.h>

#include "saras_visual_feedback/VisualFeedbackConfig.h"
#include "saras_visual_feedback/camera_model.h"
#include "saras_visual_feedback/image_pool.h"
#include "saras_visual_feedback/overlay.h"
#include "saras_visual_feedback/pose_history.h"

namespace saras_visual_feedback
{

class VisualFeedbackNodelet : public nodelet::Nodelet
{
public:
  VisualFeedbackNodelet() = default;
  ~VisualFeedbackNodelet() override;

private:
  /// One endoscope eye: its camera subscription, model and augmented-image publisher.
  struct Eye
  {
    std::string name;                          ///< "left" / "right"
    image_transport::CameraSubscriber sub;     ///< <name>/image_raw + <name>/camera_info
    image_transport::Publisher pub;            ///< <name>/image
    ros::Publisher compressed_pub;             ///< <name>/image/compressed (JPEG, on demand)
    cv::Mat jpeg_bgr;                          ///< colour-conversion buffer for the JPEG encoder
    ImagePool pool;                            ///< output buffers, reused once released
    HudCache hud;                              ///< rendered HUD text, redrawn on change only
    std::mutex mutex;                          ///< serialises this eye's callback
    CameraModel model;                         ///< touched only by this eye's callback
    sensor_msgs::CameraInfo last_info;         ///< calibration the model was built from
    bool info_seen = false;
    std::string model_error;                   ///< why the model is invalid ("" when valid)
    std::atomic<std::uint64_t> received{0}, published{0}, rejected{0}, tf_failures{0};
    /// Tool poses / transforms that could not be taken at the image stamp (latest used instead).
    std::atomic<std::uint64_t> pose_fallbacks{0}, tf_fallbacks{0};
    /// Frames in which at least one tool was drawn in each colour, indexed by Proximity.
    std::array<std::atomic<std::uint64_t>, 4> colour_frames{};
    std::array<std::string, kMaxTools> pose_frames;  ///< scratch: frame of each tool's pose (no allocation)
    std::atomic<std::uint64_t> busy_ns{0}, max_busy_ns{0};  ///< wall-clock processing time since start [ns]
    std::atomic<std::uint64_t> cpu_ns{0};                    ///< thread CPU time of the processing [ns]
    std::atomic<std::int64_t> last_image_ns{0};              ///< wall time of the last image [ns]
  };

  /// One tool drawn on the images (SARAS tool or da Vinci PSM).
  struct Tool
  {
    std::string name;          ///< e.g. mesa_left
    std::string label;         ///< HUD label
    std::string pose_topic;    ///< PoseStamped of the tip
    std::string rcm_frame;     ///< TF frame of the trocar; "" = draw the tip only
    int distance_index = 0;    ///< index in /collision/distances
    bool dvrk = false;         ///< drawn only while draw_dvrk is true
    ros::Subscriber sub;
    // Latched under state_mutex_:
    PoseHistory history;       ///< recent tip poses, in frame_id, stamped with header.stamp
    std::string frame_id;      ///< frame of the poses in history
    ros::Time pose_received;   ///< receipt time of the newest pose (for pose_timeout)
    std::uint64_t rejected = 0;
    std::uint64_t restarts = 0;  ///< history restarted because the pose stamps went backwards
  };

  void onInit() override;
  void readParameters();
  void connectCb();
  void imageCb(const sensor_msgs::ImageConstPtr& image, const sensor_msgs::CameraInfoConstPtr& info, std::size_t eye);
  void poseCb(const geometry_msgs::PoseStampedConstPtr& msg, std::size_t tool);
  void distancesCb(const std_msgs::Float64MultiArrayConstPtr& msg);
  void reconfigureCb(VisualFeedbackConfig& config, uint32_t level);
  void statusTimerCb(const ros::WallTimerEvent& event);
  /// Point @p p of frame @p source expressed in @p target at @p stamp; falls back to the latest
  /// transform (then @p at_stamp is false); false when neither exists.
  bool transformPoint(const std::string& target, const std::string& source, const ros::Time& stamp,
                      const cv::Point3d& p, cv::Point3d* out, bool* at_stamp, std::string* error) const;

  std::shared_ptr<image_transport::ImageTransport> it_;
  std::array<Eye, 2> eyes_;
  std::vector<Tool> tools_;
  ros::Subscriber distances_sub_;
  ros::Publisher status_pub_;
  ros::WallTimer status_timer_;
  std::mutex connect_mutex_;
  bool subscribed_inputs_ = false;
  bool shutting_down_ = false;  ///< set by the destructor (under connect_mutex_): connectCb does nothing

  std::unique_ptr<tf2_ros::Buffer> tf_buffer_;
  std::unique_ptr<tf2_ros::TransformListener> tf_listener_;

  // Latched state shared by callbacks.
  mutable std::mutex state_mutex_;
  OverlayStyle style_;
  double shaft_length_ = 0.05;      ///< [m]
  bool draw_dvrk_ = true;
  std::vector<double> distances_;   ///< [m]
  ros::Time distances_received_;
  std::uint64_t distances_rejected_ = 0;

  // Fixed parameters (read once).
  double pose_timeout_ = 0.5;       ///< [s]
  double distances_timeout_ = 0.5;  ///< [s]
  double image_timeout_ = 1.0;      ///< [s] STALE heartbeat without images while subscribed
  int pose_buffer_size_ = 512;      ///< samples of pose history per tool (≈ 2 s at 250 Hz)
  double pose_stamp_tolerance_ = 0.02;  ///< [s] an image newer than the newest pose by more is a fallback
  int jpeg_quality_ = 80;          ///< JPEG quality of the compressed stream [1, 100]
  int queue_size_ = 6;             ///< camera subscription and publisher queue [frames]
  std::string component_;

  // Heartbeat.
  std::uint8_t last_level_ = 255;
  ros::WallTime last_status_;
  std::uint64_t tf_failures_reported_ = 0;
  std::uint64_t fallbacks_reported_ = 0;

  using ReconfigureServer = dynamic_reconfigure::Server<VisualFeedbackConfig>;
  boost::recursive_mutex reconfigure_mutex_;
  std::unique_ptr<ReconfigureServer> reconfigure_server_;
};

}  // namespace saras_visual_feedback

#endif  // SARAS_VISUAL_FEEDBACK_VISUAL_FEEDBACK_NODELET_H
