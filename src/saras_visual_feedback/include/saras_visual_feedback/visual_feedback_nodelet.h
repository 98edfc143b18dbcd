/**
 * @file visual_feedback_nodelet.h
 * @brief VisualFeedback nodelet (D7.2 Section 7): thin ROS adapter around ToolScene (poses,
 *        distances, style), placeTools/drawFrame (the overlay) and EyeCamera (image_geometry).
 *        See README.md for topics and parameters.
 */
#ifndef SARAS_VISUAL_FEEDBACK_VISUAL_FEEDBACK_NODELET_H
#define SARAS_VISUAL_FEEDBACK_VISUAL_FEEDBACK_NODELET_H

#include <array>
#include <memory>
#include <mutex>
#include <string>

#include <diagnostic_updater/diagnostic_updater.h>
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
#include "saras_visual_feedback/frame_composer.h"
#include "saras_visual_feedback/jpeg_encoder.h"
#include "saras_visual_feedback/ros_conversions.h"
#include "saras_visual_feedback/tool_scene.h"
#include "saras_visual_feedback/visual_feedback_params.h"

namespace saras_visual_feedback
{

class VisualFeedbackNodelet : public nodelet::Nodelet
{
public:
  VisualFeedbackNodelet() = default;
  ~VisualFeedbackNodelet() override;

private:
  /// One endoscope eye: its camera subscription, model and augmented-image publishers.
  struct Eye
  {
    std::string name;                       ///< "left" / "right"
    image_transport::CameraSubscriber sub;  ///< <name>/image_raw + <name>/camera_info
    image_transport::Publisher pub;         ///< <name>/image (+ the installed transport plugins)
    /// <name>/image/compressed encoded here, only when image_transport's compressed plugin is not
    /// active (not installed, or disabled by <name>/image/disable_pub_plugins).
    ros::Publisher jpeg_pub;
    std::unique_ptr<JpegEncoder> jpeg;  ///< encoder of jpeg_pub (~jpeg_quality)
    /// Output buffers, reused once every subscriber released them (publisher queue + viewers).
    saras_common::MessagePool<sensor_msgs::Image> pool{6};
    saras_common::MessagePool<sensor_msgs::CompressedImage> jpeg_pool{4};  ///< JPEG buffers, reused
    HudCache hud;              ///< rendered HUD text, redrawn on change only
    std::mutex mutex;          ///< serialises this eye's callback
    EyeCamera camera;          ///< touched only by this eye's callback
    SceneSnapshot scene;       ///< scratch: the tools at the image stamp
    EyeStats stats;
    std::uint64_t published_reported = 0;  ///< for the output rate on /diagnostics
  };

  void onInit() override;
  void startReconfigure();
  void advertise();
  void connectCb();
  void imageCb(const sensor_msgs::ImageConstPtr& image, const sensor_msgs::CameraInfoConstPtr& info, std::size_t eye);
  void publish(Eye& eye, const sensor_msgs::ImagePtr& out, const cv::Mat& canvas, ChannelOrder order);
  void warnFrame(const Eye& eye, const sensor_msgs::Image& image, const FrameReport& report) const;
  void poseCb(const geometry_msgs::PoseStampedConstPtr& msg, std::size_t tool);
  void distancesCb(const std_msgs::Float64MultiArrayConstPtr& msg);
  void reconfigureCb(VisualFeedbackConfig& config, uint32_t level);
  void diagnose(diagnostic_updater::DiagnosticStatusWrapper& status);
  /// True when image_transport publishes <topic>/compressed itself.
  bool compressedPluginActive(const std::string& topic) const;

  VisualFeedbackParams params_;
  std::unique_ptr<ToolScene> scene_;
  std::shared_ptr<image_transport::ImageTransport> it_;
  std::array<Eye, 2> eyes_;
  std::vector<ros::Subscriber> pose_subs_;
  ros::Subscriber distances_sub_;
  std::mutex connect_mutex_;
  bool subscribed_inputs_ = false;
  bool shutting_down_ = false;  ///< set by the destructor (under connect_mutex_): connectCb does nothing
  bool own_jpeg_ = false;       ///< the eyes' /compressed streams are encoded here

  std::unique_ptr<tf2_ros::Buffer> tf_buffer_;
  std::unique_ptr<tf2_ros::TransformListener> tf_listener_;
  std::unique_ptr<TfPointTransformer> tf_points_;

  std::unique_ptr<diagnostic_updater::Updater> updater_;
  ros::WallTimer diagnostics_timer_;
  std::uint64_t problems_reported_ = 0;  ///< missing transforms + fallbacks at the last report
  ros::WallTime last_report_;

  using ReconfigureServer = dynamic_reconfigure::Server<VisualFeedbackConfig>;
  boost::recursive_mutex reconfigure_mutex_;
  std::unique_ptr<ReconfigureServer> reconfigure_server_;
};

}  // namespace saras_visual_feedback

#endif  // SARAS_VISUAL_FEEDBACK_VISUAL_FEEDBACK_NODELET_H
