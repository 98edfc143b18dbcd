/**
 * @file camera_model.h
 * @brief ROS-agnostic monocular camera model: projects 3D points given in a camera's optical
 *        frame onto its (raw, distorted) image, with the OpenCV / ROS distortion models.
 *
 * Conventions (REP 103 / sensor_msgs/CameraInfo): optical frame with z forward, x right, y down;
 * distances in metres, pixel coordinates in pixels with (0,0) the centre of the top-left pixel.
 * The distortion formulas are those of OpenCV's cv::projectPoints (plumb_bob, rational_polynomial)
 * and cv::fisheye::projectPoints (equidistant); they are re-implemented here so that projection
 * does not allocate and so that the tests can use OpenCV as an independent reference.
 */
#ifndef SARAS_VISUAL_FEEDBACK_CAMERA_MODEL_H
#define SARAS_VISUAL_FEEDBACK_CAMERA_MODEL_H

#include <array>
#include <string>

#include <opencv2/core.hpp>

namespace saras_visual_feedback
{

/// Lens distortion model, named as in sensor_msgs/CameraInfo.distortion_model.
enum class DistortionModel
{
  kNone,                ///< pinhole, no distortion (D empty or all zeros)
  kPlumbBob,            ///< "plumb_bob": D = [k1 k2 p1 p2 k3]
  kRationalPolynomial,  ///< "rational_polynomial": D = [k1 k2 p1 p2 k3 k4 k5 k6]
  kEquidistant          ///< "equidistant" (OpenCV fisheye): D = [k1 k2 k3 k4]
};

/// Intrinsic parameters of one camera, as found in sensor_msgs/CameraInfo.
struct CameraIntrinsics
{
  int width = 0;   ///< image width [px]
  int height = 0;  ///< image height [px]
  double fx = 0.0, fy = 0.0;  ///< focal lengths [px]
  double cx = 0.0, cy = 0.0;  ///< principal point [px]
  DistortionModel model = DistortionModel::kNone;
  /// Distortion coefficients, unused entries zero. plumb_bob/rational: k1 k2 p1 p2 k3 k4 k5 k6;
  /// equidistant: k1 k2 k3 k4.
  std::array<double, 8> d{};
};

/// Result of projecting one 3D point.
struct Projection
{
  /// Pixel [px]; meaningful only when @ref projectable is true.
  cv::Point2d pixel;
  /// The point is in front of the camera and inside the range where the distortion model is
  /// one-to-one (beyond it the polynomial folds back and would draw far-away points in view).
  bool projectable = false;
  /// projectable and the pixel lies inside the image.
  bool in_image = false;
  /// Image-plane direction [px, arbitrary scale] from the principal point towards the point,
  /// valid also for points behind the camera; used to place the out-of-view border marker.
  cv::Point2d direction;
};

/**
 * @brief Projects points from a camera's optical frame onto its raw image.
 *
 * Not thread-safe for concurrent configure()/project(); project() itself is const, does not
 * allocate and costs well under a microsecond.
 */
class CameraModel
{
public:
  /**
   * @brief Sets the intrinsics after validating them.
   * @param[out] error reason when the intrinsics are rejected (may be nullptr)
   * @return false (and the model keeps its previous state) for non-positive sizes or focal
   *         lengths, non-finite values.
   */
  bool configure(const CameraIntrinsics& intrinsics, std::string* error);

  /// True once a valid configuration was accepted.
  bool valid() const { return valid_; }

  const CameraIntrinsics& intrinsics() const { return k_; }

  /**
   * @brief Largest normalised radius (|(x/z, y/z)|, dimensionless) up to which the distortion
   *        function is monotonic; points beyond it are reported as not projectable.
   */
  double maxNormalizedRadius() const { return r_max_; }

  /// Projects @p p (camera optical frame, metres).
  Projection project(const cv::Point3d& p) const;

  /// Applies the distortion to normalised coordinates (x/z, y/z) and returns the pixel.
  cv::Point2d distortNormalized(double x, double y) const;

private:
  double radialProfile(double r) const;  ///< distorted radius as a function of the ideal radius

  CameraIntrinsics k_;
  bool valid_ = false;
  double r_max_ = 0.0;
};

/// Parses a CameraInfo distortion_model string; false for unknown names.
bool parseDistortionModel(const std::string& name, DistortionModel* model);

}  // namespace saras_visual_feedback

#endif  // SARAS_VISUAL_FEEDBACK_CAMERA_MODEL_H
