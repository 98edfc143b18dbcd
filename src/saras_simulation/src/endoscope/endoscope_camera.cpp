/**
 * @file endoscope_camera.cpp
 * @brief CameraModel: camera_calibration YAML parsing, scaling, distortion, pixel rays.
 */
#include "saras_simulation/endoscope_camera.h"

#include <cmath>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include <opencv2/calib3d.hpp>
#include <opencv2/core/persistence.hpp>

namespace saras_simulation
{
namespace endoscope
{
namespace
{
std::invalid_argument err(const std::string& what, const std::string& msg)
{
  return std::invalid_argument(what + ": " + msg);
}

/// {rows, cols, data} matrix node of a camera_calibration file (rows x cols must match data).
std::vector<double> readMatrix(const cv::FileNode& n, int rows, int cols, const std::string& name,
                               const std::string& what)
{
  if (!n.isMap())
    throw err(what, name + " missing or not a {rows, cols, data} mapping");
  const cv::FileNode data = n["data"];
  if (!data.isSeq())
    throw err(what, name + ".data missing or not a list");
  const int r = n["rows"].empty() ? rows : static_cast<int>(n["rows"].real());
  const int c = n["cols"].empty() ? cols : static_cast<int>(n["cols"].real());
  std::vector<double> v;
  for (const auto& e : data)
  {
    if (!e.isReal() && !e.isInt())
      throw err(what, name + ".data has a non-numeric entry");
    v.push_back(e.real());
  }
  if (rows > 0 && (r != rows || c != cols))
    throw err(what, name + " must be " + std::to_string(rows) + "x" + std::to_string(cols) + ", got " +
                        std::to_string(r) + "x" + std::to_string(c));
  if (static_cast<int>(v.size()) != r * c)
    throw err(what, name + " has " + std::to_string(v.size()) + " numbers for " + std::to_string(r) + "x" +
                        std::to_string(c));
  return v;
}
}  // namespace

CameraModel::CameraModel(int width, int height, const Eigen::Matrix3d& K, const std::vector<double>& D,
                         const Eigen::Matrix3d& R, const Eigen::Matrix<double, 3, 4>& P,
                         const std::string& distortion_model, const std::string& name)
  : width_(width), height_(height), K_(K), D_(D), R_(R), P_(P), model_(distortion_model), name_(name)
{
  if (width_ <= 0 || height_ <= 0)
    throw std::invalid_argument("camera_info image size must be positive, got " + std::to_string(width) + "x" +
                                std::to_string(height));
  if (!(K_(0, 0) > 0 && K_(1, 1) > 0) || !K_.allFinite())
    throw std::invalid_argument("camera_info camera_matrix needs finite fx, fy > 0");
  if (model_ != "plumb_bob" && model_ != "rational_polynomial")
    throw std::invalid_argument("camera_info distortion_model '" + model_ +
                                "' not supported (plumb_bob | rational_polynomial)");
  const size_t n = D_.size();
  if (!(n == 0 || n == 4 || n == 5 || n == 8 || n == 12 || n == 14))
    throw std::invalid_argument("camera_info distortion_coefficients: " + std::to_string(n) +
                                " coefficients (OpenCV takes 4, 5, 8, 12 or 14)");
  for (double d : D_)
    if (!std::isfinite(d))
      throw std::invalid_argument("camera_info distortion/projection must be finite");
  if (!P_.allFinite() || !R_.allFinite())
    throw std::invalid_argument("camera_info distortion/projection must be finite");
  for (int i = 0; i < 8; ++i)
    d8_[i] = i < static_cast<int>(n) ? D_[i] : 0.0;
  for (size_t i = 8; i < n; ++i)
    beyond8_ = beyond8_ || D_[i] != 0.0;
}

CameraModel CameraModel::fromYamlString(const std::string& text, const std::string& what)
{
  // camera_calibration writes plain YAML; OpenCV's parser wants its %YAML directive.
  const std::string doc = text.compare(0, 5, "%YAML") == 0 ? text : "%YAML:1.0\n---\n" + text;
  cv::FileStorage fs;
  try
  {
    fs.open(doc, cv::FileStorage::READ | cv::FileStorage::MEMORY | cv::FileStorage::FORMAT_YAML);
  }
  catch (const cv::Exception& e)
  {
    throw err(what, std::string("not a YAML mapping (") + e.msg + ")");
  }
  if (!fs.isOpened() || !fs.root().isMap())
    throw err(what, "not a YAML mapping");
  const cv::FileNode w = fs["image_width"], h = fs["image_height"];
  if (!(w.isInt() || w.isReal()) || !(h.isInt() || h.isReal()))
    throw err(what, "camera_info needs image_width and image_height");
  const std::vector<double> k = readMatrix(fs["camera_matrix"], 3, 3, "camera_matrix", what);
  std::vector<double> D{ 0, 0, 0, 0, 0 };
  if (!fs["distortion_coefficients"].empty())
    D = readMatrix(fs["distortion_coefficients"], -1, -1, "distortion_coefficients", what);
  Eigen::Matrix3d K = Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(k.data());
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  if (!fs["rectification_matrix"].empty())
  {
    const std::vector<double> r = readMatrix(fs["rectification_matrix"], 3, 3, "rectification_matrix", what);
    R = Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(r.data());
  }
  Eigen::Matrix<double, 3, 4> P;
  P << K, Eigen::Vector3d::Zero();
  if (!fs["projection_matrix"].empty())
  {
    const std::vector<double> p = readMatrix(fs["projection_matrix"], 3, 4, "projection_matrix", what);
    P = Eigen::Map<const Eigen::Matrix<double, 3, 4, Eigen::RowMajor>>(p.data());
  }
  const std::string model = fs["distortion_model"].empty() ? "plumb_bob" : fs["distortion_model"].string();
  const std::string name = fs["camera_name"].empty() ? "camera" : fs["camera_name"].string();
  try
  {
    return CameraModel(static_cast<int>(w.real()), static_cast<int>(h.real()), K, D, R, P, model, name);
  }
  catch (const std::invalid_argument& e)
  {
    throw err(what, e.what());
  }
}

CameraModel CameraModel::fromYamlFile(const std::string& path)
{
  std::ifstream f(path);
  if (!f)
    throw std::invalid_argument("cannot read camera_info file " + path);
  std::stringstream ss;
  ss << f.rdbuf();
  return fromYamlString(ss.str(), "camera_info file " + path);
}

CameraModel CameraModel::scaled(int width, int height) const
{
  const double sx = static_cast<double>(width) / width_, sy = static_cast<double>(height) / height_;
  Eigen::Matrix3d S;
  S << sx, 0.0, 0.5 * sx - 0.5, 0.0, sy, 0.5 * sy - 0.5, 0.0, 0.0, 1.0;
  return CameraModel(width, height, S * K_, D_, R_, S * P_, model_, name_);
}

Eigen::Vector2d CameraModel::distort(const Eigen::Vector2d& xy) const
{
  if (beyond8_)
  {
    std::vector<cv::Point3d> p{ cv::Point3d(xy.x(), xy.y(), 1.0) };
    std::vector<cv::Point2d> uv;
    cv::projectPoints(p, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), cvK(), cvD(), uv);
    return Eigen::Vector2d(uv[0].x, uv[0].y);
  }
  const double k1 = d8_[0], k2 = d8_[1], p1 = d8_[2], p2 = d8_[3], k3 = d8_[4], k4 = d8_[5], k5 = d8_[6],
               k6 = d8_[7];
  const double x = xy.x(), y = xy.y();
  const double r2 = x * x + y * y;
  const double radial = (1 + r2 * (k1 + r2 * (k2 + r2 * k3))) / (1 + r2 * (k4 + r2 * (k5 + r2 * k6)));
  const double xd = x * radial + 2 * p1 * x * y + p2 * (r2 + 2 * x * x);
  const double yd = y * radial + p1 * (r2 + 2 * y * y) + 2 * p2 * x * y;
  return Eigen::Vector2d(K_(0, 0) * xd + K_(0, 2), K_(1, 1) * yd + K_(1, 2));  // no skew, as OpenCV
}

cv::Mat CameraModel::cvK() const
{
  cv::Mat k(3, 3, CV_64F);
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c)
      k.at<double>(r, c) = K_(r, c);
  return k;
}

cv::Mat CameraModel::cvD() const
{
  cv::Mat d(1, static_cast<int>(D_.size()), CV_64F);
  for (size_t i = 0; i < D_.size(); ++i)
    d.at<double>(0, static_cast<int>(i)) = D_[i];
  return d;
}

void CameraModel::pixelRays(int step, cv::Mat& x, cv::Mat& y) const
{
  const int w = width_ / step, h = height_ / step;
  std::vector<cv::Point2d> pts;
  pts.reserve(static_cast<size_t>(w) * h);
  for (int j = 0; j < h; ++j)
    for (int i = 0; i < w; ++i)
      pts.emplace_back((i + 0.5) * step - 0.5, (j + 0.5) * step - 0.5);
  std::vector<cv::Point2d> xy;
  if (D_.empty())
  {
    xy.resize(pts.size());
    for (size_t k = 0; k < pts.size(); ++k)
      xy[k] = cv::Point2d((pts[k].x - K_(0, 2)) / K_(0, 0), (pts[k].y - K_(1, 2)) / K_(1, 1));
  }
  else
  {
    cv::undistortPoints(pts, xy, cvK(), cvD(), cv::noArray(), cv::noArray(),
                        cv::TermCriteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 40, 1e-12));
  }
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

Eigen::Vector2d CameraModel::fieldOfViewBounds() const
{
  std::vector<cv::Point2d> b, xy;
  for (int k = 0; k < 9; ++k)
  {
    const double v = (height_ - 1) * k / 8.0, u = (width_ - 1) * k / 8.0;
    b.emplace_back(0, v);
    b.emplace_back(width_ - 1, v);
    b.emplace_back(u, 0);
    b.emplace_back(u, height_ - 1);
  }
  if (D_.empty())
    for (const auto& p : b)
      xy.emplace_back((p.x - K_(0, 2)) / K_(0, 0), (p.y - K_(1, 2)) / K_(1, 1));
  else
    cv::undistortPoints(b, xy, cvK(), cvD());
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
