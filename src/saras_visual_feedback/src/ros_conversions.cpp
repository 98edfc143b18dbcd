#include "saras_visual_feedback/ros_conversions.h"

#include <sensor_msgs/image_encodings.h>

namespace saras_visual_feedback
{

bool intrinsicsFromCameraInfo(const sensor_msgs::CameraInfo& info, CameraIntrinsics* out, std::string* error)
{
  auto fail = [error](const std::string& why) {
    if (error)
      *error = why;
    return false;
  };
  CameraIntrinsics k;
  if (!parseDistortionModel(info.distortion_model, &k.model))
    return fail("unsupported distortion_model '" + info.distortion_model + "'");
  const std::size_t nd = info.D.size();
  bool all_zero = true;
  for (double c : info.D)
    all_zero = all_zero && c == 0.0;
  switch (k.model)
  {
    case DistortionModel::kPlumbBob:
      if (nd != 4 && nd != 5 && nd != 8)  // 8: some drivers send rational-sized D as plumb_bob
        return fail("plumb_bob needs 5 distortion coefficients, got " + std::to_string(nd));
      break;
    case DistortionModel::kRationalPolynomial:
      if (nd != 8)
        return fail("rational_polynomial needs 8 distortion coefficients, got " + std::to_string(nd));
      break;
    case DistortionModel::kEquidistant:
      if (nd != 4)
        return fail("equidistant needs 4 distortion coefficients, got " + std::to_string(nd));
      break;
    case DistortionModel::kNone:
      if (!all_zero)
        return fail("distortion coefficients given without a distortion_model");
      break;
  }
  for (std::size_t i = 0; i < nd && i < k.d.size(); ++i)
    k.d[i] = info.D[i];
  if (k.model == DistortionModel::kPlumbBob)
    for (std::size_t i = 5; i < k.d.size(); ++i)
      k.d[i] = (nd == 8) ? info.D[i] : 0.0;

  const double bx = info.binning_x > 1 ? info.binning_x : 1.0;
  const double by = info.binning_y > 1 ? info.binning_y : 1.0;
  const auto& roi = info.roi;
  const bool full_roi = roi.width == 0 || roi.height == 0 || (roi.x_offset == 0 && roi.y_offset == 0 &&
                                                              roi.width == info.width && roi.height == info.height);
  const double x0 = full_roi ? 0.0 : roi.x_offset, y0 = full_roi ? 0.0 : roi.y_offset;
  const double w = full_roi ? info.width : roi.width, h = full_roi ? info.height : roi.height;
  k.fx = info.K[0] / bx;
  k.fy = info.K[4] / by;
  k.cx = (info.K[2] - x0) / bx;
  k.cy = (info.K[5] - y0) / by;
  k.width = static_cast<int>(w / bx);
  k.height = static_cast<int>(h / by);
  CameraModel check;
  if (!check.configure(k, error))
    return false;
  *out = k;
  return true;
}

bool sameCalibration(const sensor_msgs::CameraInfo& a, const sensor_msgs::CameraInfo& b)
{
  return a.width == b.width && a.height == b.height && a.distortion_model == b.distortion_model && a.D == b.D &&
         a.K == b.K && a.binning_x == b.binning_x && a.binning_y == b.binning_y && a.roi.x_offset == b.roi.x_offset &&
         a.roi.y_offset == b.roi.y_offset && a.roi.width == b.roi.width && a.roi.height == b.roi.height;
}

bool imageBufferConsistent(const sensor_msgs::Image& image, std::string* error)
{
  auto fail = [error](const std::string& why) {
    if (error)
      *error = why;
    return false;
  };
  if (image.width == 0 || image.height == 0)
    return fail("empty image (" + std::to_string(image.width) + "x" + std::to_string(image.height) + ")");
  int pixel_bytes = 0;
  try
  {
    pixel_bytes = sensor_msgs::image_encodings::numChannels(image.encoding) *
                  (sensor_msgs::image_encodings::bitDepth(image.encoding) / 8);
  }
  catch (const std::exception&)
  {
    return fail("unknown encoding '" + image.encoding + "'");
  }
  if (pixel_bytes <= 0)
    return fail("unsupported encoding '" + image.encoding + "'");
  if (static_cast<std::uint64_t>(image.step) < static_cast<std::uint64_t>(image.width) * pixel_bytes)
    return fail("step " + std::to_string(image.step) + " shorter than a row of " + std::to_string(image.width) +
                " pixels");
  if (image.data.size() < static_cast<std::uint64_t>(image.step) * image.height)
    return fail("data has " + std::to_string(image.data.size()) + " bytes, expected step*height = " +
                std::to_string(static_cast<std::uint64_t>(image.step) * image.height));
  return true;
}

}  // namespace saras_visual_feedback
