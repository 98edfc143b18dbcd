/**
 * @file endoscope_camera.h
 * @brief Raw-image camera model of the simulated stereo endoscope (ROS-agnostic).
 *
 * Pinhole + OpenCV plumb_bob / rational_polynomial distortion, read from a camera_info YAML file
 * as written by camera_calibration (image_width, image_height, camera_name, camera_matrix,
 * distortion_model, distortion_coefficients, rectification_matrix, projection_matrix). The raw
 * image is the distorted one: a point X of the optical frame (x right, y down, z forward, metres)
 * lands at cv::projectPoints(X, 0, 0, K, D). Pixel centres at integer coordinates (OpenCV).
 */
#ifndef SARAS_SIMULATION_ENDOSCOPE_CAMERA_H
#define SARAS_SIMULATION_ENDOSCOPE_CAMERA_H

#include <string>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

namespace saras_simulation
{
namespace endoscope
{
/// Raw-image camera model: K, D plus the rectification R and projection P of camera_info.
class CameraModel
{
public:
  /**
   * @param width, height image size [px] (> 0)
   * @param K camera matrix [px] (fx, fy > 0, finite)
   * @param D distortion coefficients (k1 k2 p1 p2 [k3 [k4 k5 k6 [s1..s4 [tx ty]]]]), finite
   * @param R rectification rotation, @param P 3x4 projection [px, px*m]
   * @param distortion_model "plumb_bob" or "rational_polynomial"
   * @throws std::invalid_argument naming the problem ("camera_info ...")
   */
  CameraModel(int width, int height, const Eigen::Matrix3d& K, const std::vector<double>& D,
              const Eigen::Matrix3d& R, const Eigen::Matrix<double, 3, 4>& P,
              const std::string& distortion_model = "plumb_bob", const std::string& name = "camera");

  /// From a camera_calibration YAML file. @throws std::invalid_argument naming file and problem.
  static CameraModel fromYamlFile(const std::string& path);
  /// From the text of a camera_calibration YAML file. @throws std::invalid_argument
  static CameraModel fromYamlString(const std::string& text, const std::string& what = "camera_info");

  /// Same optics at another resolution (sensor binning/upscaling): K and P scale with
  /// S = [[sx, 0, sx/2 - 1/2], [0, sy, sy/2 - 1/2], [0, 0, 1]], sx = width / this->width.
  CameraModel scaled(int width, int height) const;

  /// Raw-image pixel [px] of normalised coordinates (x/z, y/z), exactly cv::projectPoints' model.
  Eigen::Vector2d distort(const Eigen::Vector2d& xy) const;
  /// Raw-image pixel [px] of an optical-frame point [m] (z > 0).
  Eigen::Vector2d project(const Eigen::Vector3d& p) const
  {
    return distort(Eigen::Vector2d(p.x() / p.z(), p.y() / p.z()));
  }
  /**
   * Normalised coordinates (x/z, y/z) of pixel centres, two CV_32F planes (rows = height/step,
   * cols = width/step). With step > 1, low-resolution pixel j sits at full-resolution coordinate
   * (j + 0.5) step - 0.5, the grid cv::resize(INTER_LINEAR) assumes.
   */
  void pixelRays(int step, cv::Mat& x, cv::Mat& y) const;
  /// Max |x/z|, |y/z| over the image border (normalised coordinates).
  Eigen::Vector2d fieldOfViewBounds() const;

  int width() const { return width_; }
  int height() const { return height_; }
  const Eigen::Matrix3d& K() const { return K_; }
  const std::vector<double>& D() const { return D_; }
  const Eigen::Matrix3d& R() const { return R_; }
  const Eigen::Matrix<double, 3, 4>& P() const { return P_; }
  const std::string& distortionModel() const { return model_; }
  const std::string& name() const { return name_; }
  /// cv::Mat copies of K (3x3) and D (1xN), CV_64F, for OpenCV calls.
  cv::Mat cvK() const;
  cv::Mat cvD() const;

private:
  int width_, height_;
  Eigen::Matrix3d K_;
  std::vector<double> D_;
  Eigen::Matrix3d R_;
  Eigen::Matrix<double, 3, 4> P_;
  std::string model_, name_;
  double d8_[8];         ///< k1 k2 p1 p2 k3 k4 k5 k6 (zero-padded)
  bool beyond8_ = false;  ///< thin-prism / tilt terms present: distort() uses cv::projectPoints
};

}  // namespace endoscope
}  // namespace saras_simulation

#endif  // SARAS_SIMULATION_ENDOSCOPE_CAMERA_H
