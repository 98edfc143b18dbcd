/**
 * @file ros_conversions.h
 * @brief The ROS side of the VisualFeedback nodelet's data (no roscore needed): camera_info
 *        through image_geometry::PinholeCameraModel, image buffers, poses, tf2 and JPEG.
 */
#ifndef SARAS_VISUAL_FEEDBACK_ROS_CONVERSIONS_H
#define SARAS_VISUAL_FEEDBACK_ROS_CONVERSIONS_H

#include <string>

#include <geometry_msgs/PoseStamped.h>
#include <saras_common/message_pool.h>
#include <image_geometry/pinhole_camera_model.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/CompressedImage.h>
#include <sensor_msgs/Image.h>
#include <tf2_ros/buffer.h>

#include "saras_visual_feedback/frame_composer.h"
#include "saras_visual_feedback/jpeg_encoder.h"
#include "saras_visual_feedback/pose_history.h"
#include "saras_visual_feedback/raw_projector.h"
#include "saras_visual_feedback/stereo_contact.h"

namespace saras_visual_feedback
{

/**
 * @brief Intrinsics of the raw image described by @p model (K and D with binning and region of
 *        interest applied by image_geometry; R and P describe the rectified image, not needed).
 * @return false with a reason in @p error for an uncalibrated (K = 0) or malformed calibration.
 */
bool intrinsicsFromCameraModel(const image_geometry::PinholeCameraModel& model, CameraIntrinsics* intrinsics,
                               std::string* error);

/// intrinsicsFromCameraModel() of a PinholeCameraModel built from @p info.
bool intrinsicsFromCameraInfo(const sensor_msgs::CameraInfo& info, CameraIntrinsics* intrinsics, std::string* error);

/**
 * @brief The stereo calibration of a pair of camera_info (image_geometry::StereoCameraModel:
 *        raw K and D, rectification R and projection P of each eye).
 * @return false with a reason in @p error for an uncalibrated or malformed pair.
 */
bool stereoCalibrationFromCameraInfo(const sensor_msgs::CameraInfo& left, const sensor_msgs::CameraInfo& right,
                                     StereoCalibration* calibration, std::string* error);

/// One eye's camera: image_geometry's model of its camera_info and the raw projector built from it.
class EyeCamera
{
public:
  /**
   * @brief Takes the camera_info of an image of @p width x @p height px (the projector is
   *        rebuilt only when the calibration changed). @return "" when the projector fits the
   *        image, else why the overlay is off.
   */
  const std::string& update(const sensor_msgs::CameraInfo& info, std::uint32_t width, std::uint32_t height);
  const RawProjector& projector() const { return projector_; }

private:
  image_geometry::PinholeCameraModel model_;
  RawProjector projector_;
  bool seen_ = false;
  std::string model_error_, error_;
};

/**
 * @brief Checks that an Image's buffer matches its declared geometry (step >= width * pixel
 *        size, data.size() >= step * height) so that wrapping it in a cv::Mat cannot read out of
 *        bounds. @return false with a reason in @p error.
 */
bool imageBufferConsistent(const sensor_msgs::Image& image, std::string* error);

/**
 * @brief The output frame: a copy of @p image to draw on, in a buffer from @p pool for 8-bit
 *        colour encodings (one memcpy, no allocation in steady state), converted to bgr8 for
 *        others. @return false with a reason in @p error for an inconsistent or unconvertible image.
 */
bool prepareCanvas(const sensor_msgs::ImageConstPtr& image, saras_common::MessagePool<sensor_msgs::Image>* pool, sensor_msgs::ImagePtr* out,
                   cv::Mat* canvas, ChannelOrder* order, std::string* error);

/// The pose sample of @p msg (stamped with @p now when unstamped); false (reason in @p error)
/// for NaN/inf values or an empty frame_id. A zero quaternion becomes the identity.
bool poseSampleFromMsg(const geometry_msgs::PoseStamped& msg, const ros::Time& now, TimedPose* sample,
                       std::string* error);

/// JPEG of @p canvas (any channel order, no conversion copy) by @p encoder into @p out (format
/// "<encoding>; jpeg compressed bgr8", as compressed_image_transport); false (reason in @p error) on failure.
bool encodeJpeg(const cv::Mat& canvas, ChannelOrder order, const std::string& encoding, JpegEncoder* encoder,
                sensor_msgs::CompressedImage* out, std::string* error);

/// PointTransformer over a tf2 buffer; never blocks (no timeout), falls back to the latest transform.
class TfPointTransformer : public PointTransformer
{
public:
  explicit TfPointTransformer(const tf2_ros::Buffer& buffer) : buffer_(buffer) {}
  bool transform(const std::string& target, const std::string& source, std::int64_t stamp_ns, const cv::Point3d& p,
                 cv::Point3d* out, bool* at_stamp, std::string* error) const override;

private:
  const tf2_ros::Buffer& buffer_;
};

}  // namespace saras_visual_feedback

#endif  // SARAS_VISUAL_FEEDBACK_ROS_CONVERSIONS_H
