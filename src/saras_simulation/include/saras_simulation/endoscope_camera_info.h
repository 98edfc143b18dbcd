/**
 * @file endoscope_camera_info.h
 * @brief The endoscope's camera: sensor_msgs/CameraInfo from a camera_calibration YAML file
 *        (camera_calibration_parsers), validated and scaled, and the ray table and raw-image
 *        projection the renderer needs, both derived from image_geometry::PinholeCameraModel.
 *
 * The raw image is the distorted one: a point X of the optical frame (x right, y down, z forward,
 * metres) lands where image_geometry's unrectifyPoint puts it, i.e. at
 * cv::projectPoints(X, 0, 0, K, D) with the model's intrinsicMatrix() and distortionCoeffs()
 * (plumb_bob or rational_polynomial). Pixel centres at integer coordinates (OpenCV).
 * No ROS runtime needed (messages and image_geometry only).
 */
#ifndef SARAS_SIMULATION_ENDOSCOPE_CAMERA_INFO_H
#define SARAS_SIMULATION_ENDOSCOPE_CAMERA_INFO_H

#include <string>
#include <vector>

#include <Eigen/Core>
#include <image_geometry/pinhole_camera_model.h>
#include <opencv2/core.hpp>
#include <sensor_msgs/CameraInfo.h>

namespace saras_simulation
{
namespace endoscope
{
/// camera_info of a camera_calibration YAML file, validated (validateCameraInfo).
/// @throws std::invalid_argument naming the file and the problem
sensor_msgs::CameraInfo readCameraInfo(const std::string& path);
/// camera_info from the text of a camera_calibration YAML file. @throws std::invalid_argument
sensor_msgs::CameraInfo parseCameraInfo(const std::string& yaml, const std::string& what = "camera_info");
/**
 * Checks what the renderer relies on: image size > 0; finite K with fx, fy > 0; finite R, P and D;
 * distortion_model plumb_bob or rational_polynomial with 0, 4, 5, 8, 12 or 14 coefficients.
 * @throws std::invalid_argument "<what>: ..."
 */
void validateCameraInfo(const sensor_msgs::CameraInfo& info, const std::string& what = "camera_info");
/// Same optics at another resolution (sensor binning / upscaling): K and P scale with
/// S = [[sx, 0, sx/2 - 1/2], [0, sy, sy/2 - 1/2], [0, 0, 1]], sx = width / info.width.
sensor_msgs::CameraInfo scaledCameraInfo(const sensor_msgs::CameraInfo& info, int width, int height);
/// The camera model of a validated camera_info.
image_geometry::PinholeCameraModel cameraModel(const sensor_msgs::CameraInfo& info);

/// Raw-image pixels [px] of optical-frame points [m] (z > 0), one OpenCV call for all.
void projectRaw(const image_geometry::PinholeCameraModel& cam, const std::vector<cv::Point3d>& points,
                std::vector<cv::Point2d>& pixels);
/// Raw-image pixel [px] of one optical-frame point [m] (z > 0).
Eigen::Vector2d projectRaw(const image_geometry::PinholeCameraModel& cam, const Eigen::Vector3d& point);
/**
 * Ray table: normalised coordinates (x/z, y/z) in the optical frame of pixel centres, two CV_32F
 * planes (rows = height / step, cols = width / step). With step > 1, cell j sits at full-resolution
 * coordinate (j + 0.5) step - 0.5, the grid cv::resize(INTER_LINEAR) assumes. These are the rays of
 * image_geometry's rectifyPoint + projectPixelTo3dRay rotated back from the rectified frame by R^T,
 * i.e. cv::undistortPoints(pixels, K, D) of the model's matrices, computed in one batched call with
 * tighter convergence (40 iterations, 1e-12) than rectifyPoint's single-point float call.
 */
void pixelRays(const image_geometry::PinholeCameraModel& cam, int step, cv::Mat& x, cv::Mat& y);
/// Max |x/z|, |y/z| of the rays through the image border (normalised coordinates).
Eigen::Vector2d fieldOfViewBounds(const image_geometry::PinholeCameraModel& cam);

}  // namespace endoscope
}  // namespace saras_simulation

#endif  // SARAS_SIMULATION_ENDOSCOPE_CAMERA_INFO_H
