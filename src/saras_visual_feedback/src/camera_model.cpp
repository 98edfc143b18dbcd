#include "saras_visual_feedback/camera_model.h"

#include <cmath>

namespace saras_visual_feedback
{
namespace
{
/// Normalised radius searched for the fold-back of the distortion polynomial (atan(10) = 84 deg
/// off-axis: wider than any endoscope).
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

bool CameraModel::configure(const CameraIntrinsics& k, std::string* error)
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
  valid_ = true;
  // Largest radius over which the radial profile keeps increasing.
  r_max_ = kRadiusSearchLimit;
  double prev = 0.0;
  for (double r = kRadiusSearchStep; r <= kRadiusSearchLimit; r += kRadiusSearchStep)
  {
    const double rd = radialProfile(r);
    if (!(rd > prev))
    {
      r_max_ = r - kRadiusSearchStep;
      break;
    }
    prev = rd;
  }
  return true;
}

double CameraModel::radialProfile(double r) const
{
  const auto& d = k_.d;
  switch (k_.model)
  {
    case DistortionModel::kPlumbBob:
    case DistortionModel::kRationalPolynomial:
    {
      const double r2 = r * r, r4 = r2 * r2, r6 = r4 * r2;
      const double num = 1.0 + d[0] * r2 + d[1] * r4 + d[4] * r6;
      const double den = 1.0 + d[5] * r2 + d[6] * r4 + d[7] * r6;
      return den > 0.0 ? r * num / den : -1.0;  // a pole ends the valid range
    }
    case DistortionModel::kEquidistant:
    {
      const double t = std::atan(r), t2 = t * t, t4 = t2 * t2;
      return t * (1.0 + d[0] * t2 + d[1] * t4 + d[2] * t4 * t2 + d[3] * t4 * t4);
    }
    case DistortionModel::kNone:
    default:
      return r;
  }
}

cv::Point2d CameraModel::distortNormalized(double x, double y) const
{
  const auto& d = k_.d;
  double xd = x, yd = y;
  switch (k_.model)
  {
    case DistortionModel::kPlumbBob:
    case DistortionModel::kRationalPolynomial:
    {
      const double r2 = x * x + y * y, r4 = r2 * r2, r6 = r4 * r2;
      const double radial = (1.0 + d[0] * r2 + d[1] * r4 + d[4] * r6) /
                             (1.0 + d[5] * r2 + d[6] * r4 + d[7] * r6);
      const double p1 = d[2], p2 = d[3];
      xd = x * radial + 2.0 * p1 * x * y + p2 * (r2 + 2.0 * x * x);
      yd = y * radial + p1 * (r2 + 2.0 * y * y) + 2.0 * p2 * x * y;
      break;
    }
    case DistortionModel::kEquidistant:
    {
      const double r = std::sqrt(x * x + y * y);
      if (r > 1e-12)
      {
        const double t = std::atan(r), t2 = t * t, t4 = t2 * t2;
        const double td = t * (1.0 + d[0] * t2 + d[1] * t4 + d[2] * t4 * t2 + d[3] * t4 * t4);
        xd = x * td / r;
        yd = y * td / r;
      }
      break;
    }
    case DistortionModel::kNone:
    default:
      break;
  }
  return {k_.fx * xd + k_.cx, k_.fy * yd + k_.cy};
}

Projection CameraModel::project(const cv::Point3d& p) const
{
  Projection out;
  if (!valid_ || !(std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z)))
    return out;
  if (p.z <= 1e-9)
  {
    // Behind the camera (or in its plane): only the side it lies on is meaningful.
    out.direction = cv::Point2d(k_.fx * p.x, k_.fy * p.y);
    return out;
  }
  const double x = p.x / p.z, y = p.y / p.z;
  out.direction = cv::Point2d(k_.fx * x, k_.fy * y);
  if (x * x + y * y > r_max_ * r_max_)
    return out;
  out.projectable = true;
  out.pixel = distortNormalized(x, y);
  // Pixel centres are integers: the image covers [-0.5, size - 0.5).
  out.in_image = out.pixel.x >= -0.5 && out.pixel.y >= -0.5 && out.pixel.x < k_.width - 0.5 &&
                 out.pixel.y < k_.height - 0.5;
  if (!out.in_image)
    out.direction = cv::Point2d(out.pixel.x - k_.cx, out.pixel.y - k_.cy);
  return out;
}

}  // namespace saras_visual_feedback
