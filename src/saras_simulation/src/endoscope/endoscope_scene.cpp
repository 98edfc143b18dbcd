/**
 * @file endoscope_scene.cpp
 * @brief Scene content: tissue surface, texture, bone boxes, calibration targets.
 */
#include "saras_simulation/endoscope_scene.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <numeric>
#include <sstream>
#include <stdexcept>

#include <opencv2/aruco.hpp>
#include <opencv2/imgproc.hpp>
#include <saras_collision/geometry.h>
#include <saras_collision/vertices_file.h>

namespace saras_simulation
{
namespace endoscope
{
std::vector<TissueSurface::Wave> TissueSurface::defaultWaves()
{
  return { { 0.004, 40.0, 15.0, 0.3 }, { 0.002, -25.0, 55.0, 1.1 }, { 0.001, 110.0, 90.0, 2.0 } };
}

TissueSurface::TissueSurface(double z0, double cx, double cy, const std::vector<Wave>& waves)
  : z0_(z0), cx_(cx), cy_(cy), waves_(waves)
{
  bool ok = std::isfinite(z0) && std::isfinite(cx) && std::isfinite(cy);
  for (const Wave& w : waves_)
    ok = ok && std::isfinite(w.a) && std::isfinite(w.kx) && std::isfinite(w.ky) && std::isfinite(w.phi);
  if (!ok)
    throw std::invalid_argument("tissue surface parameters must be finite");
}

double TissueSurface::height(double x, double y) const
{
  double z = z0_;
  for (const Wave& w : waves_)
    z += w.a * std::sin(w.kx * (x - cx_) + w.ky * (y - cy_) + w.phi);
  return z;
}

Eigen::Vector2d TissueSurface::gradient(double x, double y) const
{
  Eigen::Vector2d g(0, 0);
  for (const Wave& w : waves_)
  {
    const double c = w.a * std::cos(w.kx * (x - cx_) + w.ky * (y - cy_) + w.phi);
    g += Eigen::Vector2d(c * w.kx, c * w.ky);
  }
  return g;
}

Eigen::Vector3d TissueSurface::normal(double x, double y) const
{
  const Eigen::Vector2d g = gradient(x, y);
  return Eigen::Vector3d(-g.x(), -g.y(), 1.0).normalized();
}

cv::Mat tissueTexture(int size, unsigned seed)
{
  cv::RNG rng(seed);
  cv::Mat img(size, size, CV_32FC3, cv::Scalar(120, 110, 200));  // BGR pink
  const int scales[3] = { 8, 32, 128 };
  const float amps[3] = { 35.f, 18.f, 8.f };
  cv::Mat n, big;
  for (int s = 0; s < 3; ++s)
  {
    n.create(scales[s], scales[s], CV_32F);
    rng.fill(n, cv::RNG::NORMAL, 0.0, 1.0);
    cv::resize(n, big, cv::Size(size, size), 0, 0, cv::INTER_CUBIC);
    for (int j = 0; j < size; ++j)
    {
      const float* b = big.ptr<float>(j);
      cv::Vec3f* p = img.ptr<cv::Vec3f>(j);
      for (int i = 0; i < size; ++i)
        p[i] += amps[s] * b[i] * cv::Vec3f(0.6f, 0.8f, 1.0f);
    }
  }
  cv::Mat vessels = cv::Mat::zeros(size, size, CV_8U);
  for (int k = 0; k < 40; ++k)
  {
    cv::Point2d p(rng.uniform(0.0, double(size)), rng.uniform(0.0, double(size)));
    double ang = rng.uniform(0.0, 2 * M_PI);
    std::vector<cv::Point> pts;
    for (int s = 0; s < 30; ++s)
    {
      ang += rng.gaussian(0.25);
      p += 12.0 * cv::Point2d(std::cos(ang), std::sin(ang));
      pts.emplace_back(static_cast<int>(p.x), static_cast<int>(p.y));
    }
    cv::polylines(vessels, pts, false, cv::Scalar(255), rng.uniform(1, 4), cv::LINE_AA);
  }
  cv::GaussianBlur(vessels, vessels, cv::Size(5, 5), 0);
  cv::Mat out(size, size, CV_8UC3);
  const cv::Vec3f vc(40.f, 30.f, 130.f);
  for (int j = 0; j < size; ++j)
  {
    const uchar* v = vessels.ptr<uchar>(j);
    const cv::Vec3f* p = img.ptr<cv::Vec3f>(j);
    cv::Vec3b* o = out.ptr<cv::Vec3b>(j);
    for (int i = 0; i < size; ++i)
    {
      const float a = 0.55f * v[i] / 255.f;
      const cv::Vec3f c = p[i] * (1.f - a) + vc * a;
      for (int ch = 0; ch < 3; ++ch)
        o[i][ch] = static_cast<uchar>(std::min(255.f, std::max(0.f, c[ch])));
    }
  }
  return out;
}

std::array<Eigen::Vector3d, 8> Box::corners() const
{
  std::array<Eigen::Vector3d, 8> c;
  for (int b = 0; b < 8; ++b)
  {
    c[b] = centre;
    for (int i = 0; i < 3; ++i)
      c[b] += ((b >> i) & 1 ? 1.0 : -1.0) * half[i] * axes.row(i).transpose();
  }
  return c;
}

std::vector<std::array<Eigen::Vector3d, 8>> loadBoxes(const std::string& path, double scaling)
{
  // the forbidden-region file's own parser (one definition of the format, D7.2 Section 6.1)
  std::vector<saras_collision::OrientedBox> boxes;
  std::string error;
  if (!saras_collision::loadVerticesFile(path, scaling, saras_collision::kBoxRelativeTolerance, boxes, error))
    throw std::invalid_argument(error);
  std::vector<std::array<Eigen::Vector3d, 8>> out(boxes.size());
  for (size_t b = 0; b < boxes.size(); ++b)
    saras_collision::boxVertices(boxes[b], out[b].data());
  return out;
}

Box boxFromVertices(const std::array<Eigen::Vector3d, 8>& v)
{
  saras_collision::OrientedBox ob;
  const int code = saras_collision::makeBox(v.data(), saras_collision::kBoxRelativeTolerance, ob);
  if (code != saras_collision::kSeparated)
    throw std::invalid_argument(std::string("box vertices are not a rectangular box in the order v0, v0+x, v0+x+z, "
                                            "v0+z, v0+y, v0+x+y, v0+x+y+z, v0+y+z (") +
                                saras_collision::codeName(code) + ")");
  Box box;
  box.centre = ob.center;
  box.axes = ob.axes.transpose();  // rows: unit axes
  box.half = ob.half;
  return box;
}

PlanarTarget PlanarTarget::checkerboard(int cols, int rows, double square, double res)
{
  if (cols < 2 || rows < 2)
    throw std::invalid_argument("checkerboard needs cols, rows >= 2");
  if (!(res > 0) || !(square > 0))
    throw std::invalid_argument("checkerboard square and res must be > 0");
  const int k = static_cast<int>(std::nearbyint(square / res));
  if (k < 2 || std::abs(k * res - square) > 1e-9)
    throw std::invalid_argument("checkerboard square must be a multiple (>= 2) of the texel size");
  const int margin = 1;
  const int nx = cols + 1 + 2 * margin, ny = rows + 1 + 2 * margin;
  PlanarTarget t;
  t.kind = "checkerboard";
  t.texture = cv::Mat(ny * k, nx * k, CV_8U, cv::Scalar(255));
  for (int j = 0; j <= rows; ++j)
    for (int i = 0; i <= cols; ++i)
      if ((i + j) % 2 == 0)
        t.texture(cv::Rect((i + margin) * k, (j + margin) * k, k, k)).setTo(0);
  t.res = res;
  t.x_min = t.y_min = -(1 + margin) * square;
  for (int j = 0; j < rows; ++j)
    for (int i = 0; i < cols; ++i)
      t.points.emplace_back(i * square, j * square, 0.0);
  return t;
}

PlanarTarget PlanarTarget::circles(double dot_circle_radius, double dot_diameter, int dots,
                                   double marker_circle_radius, double marker_side, double res,
                                   const std::string& dictionary)
{
  if (!(res > 0) || !(dot_circle_radius > 0) || !(dot_diameter > 0) || dots < 1 || !(marker_side > 0) ||
      !(marker_circle_radius >= 0) || dot_circle_radius / res > 20000)
    throw std::invalid_argument("circles target sizes must be positive (and res not too small)");
  static const std::pair<const char*, cv::aruco::PREDEFINED_DICTIONARY_NAME> dicts[] = {
    { "DICT_4X4_50", cv::aruco::DICT_4X4_50 },   { "DICT_4X4_100", cv::aruco::DICT_4X4_100 },
    { "DICT_5X5_50", cv::aruco::DICT_5X5_50 },   { "DICT_6X6_50", cv::aruco::DICT_6X6_50 },
    { "DICT_ARUCO_ORIGINAL", cv::aruco::DICT_ARUCO_ORIGINAL },
  };
  int dict_id = -1;
  for (const auto& d : dicts)
    if (dictionary == d.first)
      dict_id = d.second;
  if (dict_id < 0)
    throw std::invalid_argument("circles target: unknown ArUco dictionary '" + dictionary + "'");
  PlanarTarget t;
  t.kind = "circles";
  const double half = dot_circle_radius + dot_diameter + 0.01;
  const int n = static_cast<int>(std::ceil(2 * half / res));
  t.texture = cv::Mat(n, n, CV_8U, cv::Scalar(255));
  t.res = res;
  t.x_min = t.y_min = -n * res / 2.0;
  for (int i = 0; i < dots; ++i)
  {
    const double a = 2 * M_PI * i / dots;
    const double x = dot_circle_radius * std::cos(a), y = dot_circle_radius * std::sin(a);
    t.points.emplace_back(x, y, 0.0);
    const double u = (x - t.x_min) / res - 0.5, v = (y - t.y_min) / res - 0.5;
    cv::circle(t.texture, cv::Point(int(std::nearbyint(u * 16)), int(std::nearbyint(v * 16))),
               int(std::nearbyint(dot_diameter / 2 / res * 16)), cv::Scalar(0), -1, cv::LINE_AA, 4);
  }
  const cv::Ptr<cv::aruco::Dictionary> dict = cv::aruco::getPredefinedDictionary(dict_id);
  const int side_px = static_cast<int>(std::nearbyint(marker_side / res));
  cv::Mat marker;
  for (int id = 0; id < 4; ++id)
  {
    const double a = M_PI / 4 + id * M_PI / 2;
    const double cx = marker_circle_radius * std::cos(a), cy = marker_circle_radius * std::sin(a);
    cv::aruco::drawMarker(dict, id, side_px, marker);
    const int u0 = static_cast<int>(std::nearbyint((cx - marker_side / 2 - t.x_min) / res));
    const int v0 = static_cast<int>(std::nearbyint((cy - marker_side / 2 - t.y_min) / res));
    if (u0 < 0 || v0 < 0 || u0 + side_px > n || v0 + side_px > n)
      throw std::invalid_argument("circles target: ArUco markers outside the board");
    marker.copyTo(t.texture(cv::Rect(u0, v0, side_px, side_px)));
    const double xm = t.x_min + u0 * res, ym = t.y_min + v0 * res, s = side_px * res;
    t.marker_corners.push_back({ Eigen::Vector3d(xm, ym, 0), Eigen::Vector3d(xm + s, ym, 0),
                                 Eigen::Vector3d(xm + s, ym + s, 0), Eigen::Vector3d(xm, ym + s, 0) });
  }
  return t;
}

Eigen::Matrix3d rpyToMatrix(double roll, double pitch, double yaw)
{
  return (Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
          Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX()))
      .toRotationMatrix();
}

}  // namespace endoscope
}  // namespace saras_simulation
