/**
 * @file endoscope_camera_info.cpp
 * @brief camera_info reading (camera_calibration_parsers), validation, scaling; ray table and
 *        raw-image projection from image_geometry::PinholeCameraModel.
 */
#include "saras_simulation/endoscope_camera_info.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include <camera_calibration_parsers/parse_yml.h>
#include <opencv2/calib3d.hpp>
#include <sensor_msgs/distortion_models.h>

namespace saras_simulation
{
namespace endoscope
{
namespace
{
template <class C>
bool allFinite(const C& c)
{
  return std::all_of(c.begin(), c.end(), [](double v) { return std::isfinite(v); });
}
}  // namespace

void validateCameraInfo(const sensor_msgs::CameraInfo& info, const std::string& what)
{
  auto fail = [&](const std::string& msg) { throw std::invalid_argument(what + ": " + msg); };
  if (info.width == 0 || info.height == 0)
    fail("image size must be positive, got " + std::to_string(info.width) + "x" + std::to_string(info.height));
  if (!allFinite(info.K) || !(info.K[0] > 0 && info.K[4] > 0))
    fail("camera_matrix needs finite fx, fy > 0");
  const std::string& model = info.distortion_model;
  if (model != sensor_msgs::distortion_models::PLUMB_BOB && model != sensor_msgs::distortion_models::RATIONAL_POLYNOMIAL)
    fail("distortion_model '" + model + "' not supported (plumb_bob | rational_polynomial)");
  const size_t n = info.D.size();
  if (!(n == 0 || n == 4 || n == 5 || n == 8 || n == 12 || n == 14))
    fail("distortion_coefficients: " + std::to_string(n) + " coefficients (OpenCV takes 4, 5, 8, 12 or 14)");
  if (!allFinite(info.D) || !allFinite(info.R) || !allFinite(info.P))
    fail("distortion/rectification/projection must be finite");
}

sensor_msgs::CameraInfo parseCameraInfo(const std::string& yaml, const std::string& what)
{
  std::istringstream in(yaml);
  std::string name;
  sensor_msgs::CameraInfo info;
  if (!camera_calibration_parsers::readCalibrationYml(in, name, info))
    throw std::invalid_argument(what + ": not a camera_calibration YAML file (image_width, image_height, camera_name, "
                                       "camera_matrix, distortion_model, distortion_coefficients, "
                                       "rectification_matrix, projection_matrix)");
  validateCameraInfo(info, what);
  return info;
}

sensor_msgs::CameraInfo readCameraInfo(const std::string& path)
{
  std::ifstream f(path);
  if (!f)
    throw std::invalid_argument("cannot read camera_info file " + path);
  std::stringstream ss;
  ss << f.rdbuf();
  return parseCameraInfo(ss.str(), "camera_info file " + path);
}

sensor_msgs::CameraInfo scaledCameraInfo(const sensor_msgs::CameraInfo& info, int width, int height)
{
  if (width <= 0 || height <= 0)
    throw std::invalid_argument("camera_info scaled to a non-positive size");
  const double sx = static_cast<double>(width) / info.width, sy = static_cast<double>(height) / info.height;
  sensor_msgs::CameraInfo s = info;
  s.width = static_cast<uint32_t>(width);
  s.height = static_cast<uint32_t>(height);
  // rows 0 and 1 of K (3 columns) and P (4 columns): S * M
  for (int c = 0; c < 3; ++c)
  {
    s.K[c] = sx * info.K[c] + (0.5 * sx - 0.5) * info.K[6 + c];
    s.K[3 + c] = sy * info.K[3 + c] + (0.5 * sy - 0.5) * info.K[6 + c];
  }
  for (int c = 0; c < 4; ++c)
  {
    s.P[c] = sx * info.P[c] + (0.5 * sx - 0.5) * info.P[8 + c];
    s.P[4 + c] = sy * info.P[4 + c] + (0.5 * sy - 0.5) * info.P[8 + c];
  }
  return s;
}

image_geometry::PinholeCameraModel cameraModel(const sensor_msgs::CameraInfo& info)
{
  validateCameraInfo(info);
  image_geometry::PinholeCameraModel cam;
  cam.fromCameraInfo(info);
  return cam;
}

void projectRaw(const image_geometry::PinholeCameraModel& cam, const std::vector<cv::Point3d>& points,
                std::vector<cv::Point2d>& pixels)
{
  if (points.empty())
  {
    pixels.clear();
    return;
  }
  cv::projectPoints(points, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), cam.intrinsicMatrix(), cam.distortionCoeffs(),
                    pixels);
}

Eigen::Vector2d projectRaw(const image_geometry::PinholeCameraModel& cam, const Eigen::Vector3d& point)
{
  std::vector<cv::Point2d> uv;
  projectRaw(cam, { cv::Point3d(point.x(), point.y(), point.z()) }, uv);
  return Eigen::Vector2d(uv[0].x, uv[0].y);
}

namespace
{
/// Normalised optical-frame coordinates of raw pixels (the inverse of projectRaw at z = 1).
void undistort(const image_geometry::PinholeCameraModel& cam, const std::vector<cv::Point2d>& pixels,
               std::vector<cv::Point2d>& xy)
{
  cv::undistortPoints(pixels, xy, cam.intrinsicMatrix(), cam.distortionCoeffs(), cv::noArray(), cv::noArray(),
                      cv::TermCriteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 40, 1e-12));
}
}  // namespace

void pixelRays(const image_geometry::PinholeCameraModel& cam, int step, cv::Mat& x, cv::Mat& y)
{
  const cv::Size full = cam.fullResolution();
  const int w = full.width / step, h = full.height / step;
  std::vector<cv::Point2d> pts, xy;
  pts.reserve(static_cast<size_t>(w) * h);
  for (int j = 0; j < h; ++j)
    for (int i = 0; i < w; ++i)
      pts.emplace_back((i + 0.5) * step - 0.5, (j + 0.5) * step - 0.5);
  undistort(cam, pts, xy);
  x.create(h, w, CV_32F);
  y.create(h, w, CV_32F);
  for (int j = 0; j < h; ++j)
  {
    float* px = x.ptr<float>(j);
    float* py = y.ptr<float>(j);
    for (int i = 0; i < w; ++i)
    {
      px[i] = static_cast<float>(xy[static_cast<size_t>(j) * w + i].x);
      py[i] = static_cast<float>(xy[static_cast<size_t>(j) * w + i].y);
    }
  }
}

Eigen::Vector2d fieldOfViewBounds(const image_geometry::PinholeCameraModel& cam)
{
  const cv::Size full = cam.fullResolution();
  std::vector<cv::Point2d> b, xy;
  for (int k = 0; k < 9; ++k)
  {
    const double v = (full.height - 1) * k / 8.0, u = (full.width - 1) * k / 8.0;
    b.emplace_back(0, v);
    b.emplace_back(full.width - 1, v);
    b.emplace_back(u, 0);
    b.emplace_back(u, full.height - 1);
  }
  // a bound with margins in its users: OpenCV's default convergence (as rectifyPoint) is enough
  cv::undistortPoints(b, xy, cam.intrinsicMatrix(), cam.distortionCoeffs());
  Eigen::Vector2d m(0, 0);
  for (const auto& p : xy)
  {
    m.x() = std::max(m.x(), std::abs(p.x));
    m.y() = std::max(m.y(), std::abs(p.y));
  }
  return m;
}

}  // namespace endoscope
}  // namespace saras_simulation
