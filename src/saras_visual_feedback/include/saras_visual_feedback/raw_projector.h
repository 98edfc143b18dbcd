/**
 * @file raw_projector.h
 * @brief Projection of 3D points onto a camera's raw (distorted) image, for the overlay.
 *
 * The camera model itself is ROS's image_geometry::PinholeCameraModel, fed from camera_info (it
 * applies binning and region of interest); ros_conversions.h turns it into CameraIntrinsics. The
 * projection is OpenCV's cv::projectPoints / cv::fisheye::projectPoints with its K and D. This
 * class adds only what the overlay needs and image_geometry does not offer: a point in the raw
 * camera's optical frame straight to the raw image (image_geometry projects to the rectified
 * image), the range where the distortion polynomial is one-to-one (beyond it the polynomial folds
 * back and would draw far-away points in view), and a direction for the out-of-view marker.
 *
 * Conventions (REP 103 / sensor_msgs/CameraInfo): optical frame with z forward, x right, y down;
 * metres; pixels with (0,0) the centre of the top-left pixel.
 */
#ifndef SARAS_VISUAL_FEEDBACK_RAW_PROJECTOR_H
#define SARAS_VISUAL_FEEDBACK_RAW_PROJECTOR_H

#include <array>
#include <cstddef>
#include <string>
#include <vector>

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

/// Intrinsics of the image as published (binning / ROI applied), as image_geometry provides them.
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
  cv::Point2d pixel;        ///< [px]; meaningful only when projectable
  bool projectable = false; ///< in front of the camera and inside the one-to-one range of the lens
  bool in_image = false;    ///< projectable and inside the image
  /// Image-plane direction [px, arbitrary scale] from the principal point towards the point,
  /// valid also for points behind the camera; places the out-of-view border marker.
  cv::Point2d direction;
};

/// Parses a CameraInfo distortion_model string; false for unknown names.
bool parseDistortionModel(const std::string& name, DistortionModel* model);

/**
 * @brief Projects points from a camera's optical frame onto its raw image.
 *
 * Not thread-safe (project() reuses scratch buffers): one instance per image stream.
 */
class RawProjector
{
public:
  /// Validates and takes @p k; false (previous state kept) with a reason in @p error.
  bool configure(const CameraIntrinsics& k, std::string* error);
  bool valid() const { return valid_; }
  const CameraIntrinsics& intrinsics() const { return k_; }
  /// Largest normalised radius |(x/z, y/z)| up to which the lens mapping is one-to-one.
  double maxNormalizedRadius() const { return r_max_; }

  /// Projects @p n points (optical frame, metres) into @p out.
  void project(const cv::Point3d* points, std::size_t n, Projection* out) const;
  Projection project(const cv::Point3d& p) const;

private:
  /// cv::projectPoints (or the fisheye variant) of normalised points (x, y, 1).
  void distort(const std::vector<cv::Point3d>& rays, std::vector<cv::Point2d>* pixels) const;
  double foldBackRadius() const;

  CameraIntrinsics k_;
  cv::Matx33d K_;
  std::vector<double> D_;
  bool valid_ = false;
  double r_max_ = 0.0;
  mutable std::vector<cv::Point3d> rays_;    ///< scratch (capacity reused)
  mutable std::vector<cv::Point2d> pixels_;  ///< scratch (capacity reused)
};

}  // namespace saras_visual_feedback

#endif  // SARAS_VISUAL_FEEDBACK_RAW_PROJECTOR_H
