#include "saras_visual_feedback/raw_projector.h"

#include <cmath>

#include <opencv2/calib3d.hpp>

namespace saras_visual_feedback
{
namespace
{
/// Normalised radius searched for the fold-back of the distortion (atan(10) = 84 deg off-axis:
/// wider than any endoscope), and the search step.
constexpr double kRadiusSearchLimit = 10.0;
constexpr double kRadiusSearchStep = 1e-3;
}  // namespace

bool parseDistortionModel(const std::string& name, DistortionModel* model)
{
  if (name == "plumb_bob")
    *model = DistortionModel::kPlumbBob;
  else if (name == "rational_polynomial")
    *model = DistortionModel::kRationalPolynomial;
  else if (name == "equidistant" || name == "fisheye")
    *model = DistortionModel::kEquidistant;
  else if (name.empty() || name == "none")
    *model = DistortionModel::kNone;
  else
    return false;
  return true;
}

bool RawProjector::configure(const CameraIntrinsics& k, std::string* error)
{
  auto fail = [error](const std::string& why) {
    if (error)
      *error = why;
    return false;
  };
  if (k.width <= 0 || k.height <= 0)
    return fail("image size must be positive (width " + std::to_string(k.width) + ", height " +
                std::to_string(k.height) + ")");
  if (!(std::isfinite(k.fx) && std::isfinite(k.fy) && k.fx > 0.0 && k.fy > 0.0))
    return fail("focal lengths fx, fy must be finite and positive (uncalibrated camera?)");
  if (!(std::isfinite(k.cx) && std::isfinite(k.cy)))
    return fail("principal point must be finite");
  for (double c : k.d)
    if (!std::isfinite(c))
      return fail("distortion coefficients must be finite");
  k_ = k;
  K_ = cv::Matx33d(k.fx, 0.0, k.cx, 0.0, k.fy, k.cy, 0.0, 0.0, 1.0);
  switch (k.model)
  {
    case DistortionModel::kPlumbBob:
      D_.assign(k.d.begin(), k.d.begin() + 5);
      break;
    case DistortionModel::kRationalPolynomial:
      D_.assign(k.d.begin(), k.d.end());
      break;
    case DistortionModel::kEquidistant:
      D_.assign(k.d.begin(), k.d.begin() + 4);
      break;
    case DistortionModel::kNone:
    default:
      D_.clear();
  }
  valid_ = true;
  r_max_ = foldBackRadius();
  return true;
}

void RawProjector::distort(const std::vector<cv::Point3d>& rays, std::vector<cv::Point2d>* pixels) const
{
  if (k_.model == DistortionModel::kEquidistant)
    cv::fisheye::projectPoints(rays, *pixels, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), K_, D_);
  else
    cv::projectPoints(rays, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), K_, D_, *pixels);
}

double RawProjector::foldBackRadius() const
{
  // Along each half-axis, the distance of the projected pixel from the principal point must keep
  // growing with the ideal radius; the smallest radius where it stops ends the valid range.
  const int steps = static_cast<int>(kRadiusSearchLimit / kRadiusSearchStep);
  std::vector<cv::Point3d> rays;
  rays.reserve(4 * steps);
  const cv::Point2d axes[4] = {{1, 0}, {-1, 0}, {0, 1}, {0, -1}};
  for (const cv::Point2d& a : axes)
    for (int i = 1; i <= steps; ++i)
      rays.emplace_back(a.x * i * kRadiusSearchStep, a.y * i * kRadiusSearchStep, 1.0);
  std::vector<cv::Point2d> px;
  distort(rays, &px);
  double r_max = kRadiusSearchLimit;
  for (int a = 0; a < 4; ++a)
  {
    double prev = 0.0;
    for (int i = 1; i <= steps; ++i)
    {
      const cv::Point2d& p = px[a * steps + i - 1];
      const double d = axes[a].x * (p.x - k_.cx) / k_.fx + axes[a].y * (p.y - k_.cy) / k_.fy;
      if (!(d > prev) || !std::isfinite(d))
      {
        r_max = std::min(r_max, (i - 1) * kRadiusSearchStep);
        break;
      }
      prev = d;
    }
  }
  return r_max;
}

void RawProjector::project(const cv::Point3d* points, std::size_t n, Projection* out) const
{
  rays_.clear();
  for (std::size_t i = 0; i < n; ++i)
  {
    const cv::Point3d& p = points[i];
    Projection& o = out[i];
    o = Projection();
    if (!valid_ || !(std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z)))
      continue;
    if (p.z <= 1e-9)
    {
      // Behind the camera (or in its plane): only the side it lies on is meaningful.
      o.direction = cv::Point2d(k_.fx * p.x, k_.fy * p.y);
      continue;
    }
    const double x = p.x / p.z, y = p.y / p.z;
    o.direction = cv::Point2d(k_.fx * x, k_.fy * y);
    if (x * x + y * y > r_max_ * r_max_)
      continue;
    o.projectable = true;
    rays_.emplace_back(x, y, 1.0);
  }
  if (rays_.empty())
    return;
  distort(rays_, &pixels_);
  std::size_t j = 0;
  for (std::size_t i = 0; i < n; ++i)
  {
    Projection& o = out[i];
    if (!o.projectable)
      continue;
    o.pixel = pixels_[j++];
    // Pixel centres are integers: the image covers [-0.5, size - 0.5).
    o.in_image = o.pixel.x >= -0.5 && o.pixel.y >= -0.5 && o.pixel.x < k_.width - 0.5 && o.pixel.y < k_.height - 0.5;
    if (!o.in_image)
      o.direction = cv::Point2d(o.pixel.x - k_.cx, o.pixel.y - k_.cy);
  }
}

Projection RawProjector::project(const cv::Point3d& p) const
{
  Projection out;
  project(&p, 1, &out);
  return out;
}

}  // namespace saras_visual_feedback
