/**
 * @file ros_conversions.h
 * @brief Conversions between ROS messages and the ROS-agnostic core (no roscore needed).
 */
#ifndef SARAS_VISUAL_FEEDBACK_ROS_CONVERSIONS_H
#define SARAS_VISUAL_FEEDBACK_ROS_CONVERSIONS_H

#include <string>

#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>

#include "saras_visual_feedback/camera_model.h"

namespace saras_visual_feedback
{

/**
 * @brief Intrinsics of the raw (unrectified) image described by @p info.
 *
 * Uses K and D (the raw image is distorted; R and P describe the rectified image and are not
 * needed). Binning and a region of interest are applied as image_geometry does: the model
 * describes the image actually published (width/binning_x × height/binning_y, or the ROI).
 * @return false with a reason in @p error for an uncalibrated (K = 0) or malformed message.
 */
bool intrinsicsFromCameraInfo(const sensor_msgs::CameraInfo& info, CameraIntrinsics* intrinsics,
                              std::string* error);

/// True when the intrinsics-relevant fields of two CameraInfo messages are equal.
bool sameCalibration(const sensor_msgs::CameraInfo& a, const sensor_msgs::CameraInfo& b);

/**
 * @brief Checks that an Image's buffer matches its declared geometry (step >= width * pixel
 *        size, data.size() >= step * height) so that wrapping it in a cv::Mat cannot read out of
 *        bounds. @return false with a reason in @p error.
 */
bool imageBufferConsistent(const sensor_msgs::Image& image, std::string* error);

}  // namespace saras_visual_feedback

#endif  // SARAS_VISUAL_FEEDBACK_ROS_CONVERSIONS_H
