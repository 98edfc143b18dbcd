#include "saras_visual_feedback/ros_conversions.h"

#include <cmath>
#include <cstring>

#include <cv_bridge/cv_bridge.h>
#include <sensor_msgs/image_encodings.h>
#include <tf2/LinearMath/Transform.h>
#include <tf2_geometry_msgs/tf2_geometry_msgs.h>

namespace saras_visual_feedback
{
namespace enc = sensor_msgs::image_encodings;

namespace
{
/// Checks the number of distortion coefficients for the model.
bool checkDistortion(const sensor_msgs::CameraInfo& info, DistortionModel model, std::string* why)
{
  const std::size_t nd = info.D.size();
  bool all_zero = true;
  for (double c : info.D)
    all_zero = all_zero && c == 0.0;
  switch (model)
  {
    case DistortionModel::kPlumbBob:
      if (nd != 4 && nd != 5 && nd != 8)  // 8: some drivers send rational-sized D as plumb_bob
        *why = "plumb_bob needs 5 distortion coefficients, got " + std::to_string(nd);
      break;
    case DistortionModel::kRationalPolynomial:
      if (nd != 8)
        *why = "rational_polynomial needs 8 distortion coefficients, got " + std::to_string(nd);
      break;
    case DistortionModel::kEquidistant:
      if (nd != 4)
        *why = "equidistant needs 4 distortion coefficients, got " + std::to_string(nd);
      break;
    case DistortionModel::kNone:
      if (!all_zero)
        *why = "distortion coefficients given without a distortion_model";
      break;
  }
  return why->empty();
}
}  // namespace

bool intrinsicsFromCameraModel(const image_geometry::PinholeCameraModel& model, CameraIntrinsics* out,
                               std::string* error)
{
  std::string why;
  const sensor_msgs::CameraInfo& info = model.cameraInfo();
  CameraIntrinsics k;
  if (!parseDistortionModel(info.distortion_model, &k.model))
    why = "unsupported distortion_model '" + info.distortion_model + "'";
  else
    checkDistortion(info, k.model, &why);
  if (!why.empty())
  {
    if (error)
      *error = why;
    return false;
  }
  const cv::Mat_<double>& d = model.distortionCoeffs();
  for (int i = 0; i < static_cast<int>(d.total()) && i < static_cast<int>(k.d.size()); ++i)
    k.d[i] = d(i);
  const cv::Matx33d& K = model.intrinsicMatrix();  // binning and ROI applied
  const cv::Size size = model.reducedResolution();
  k.fx = K(0, 0);
  k.fy = K(1, 1);
  k.cx = K(0, 2);
  k.cy = K(1, 2);
  k.width = size.width;
  k.height = size.height;
  RawProjector check;
  if (!check.configure(k, error))
    return false;
  *out = k;
  return true;
}

bool intrinsicsFromCameraInfo(const sensor_msgs::CameraInfo& info, CameraIntrinsics* out, std::string* error)
{
  image_geometry::PinholeCameraModel model;
  model.fromCameraInfo(info);
  return intrinsicsFromCameraModel(model, out, error);
}

bool stereoCalibrationFromCameraInfo(const sensor_msgs::CameraInfo& left, const sensor_msgs::CameraInfo& right,
                                     StereoCalibration* calibration, std::string* error)
{
  image_geometry::PinholeCameraModel model[2];
  model[0].fromCameraInfo(left);
  model[1].fromCameraInfo(right);
  StereoCalibration c;
  CameraIntrinsics* k[2] = {&c.left, &c.right};
  cv::Matx33d* R[2] = {&c.R_left, &c.R_right};
  cv::Matx34d* P[2] = {&c.P_left, &c.P_right};
  for (int e = 0; e < 2; ++e)
  {
    if (!intrinsicsFromCameraModel(model[e], k[e], error))
      return false;
    *R[e] = model[e].rotationMatrix();
    *P[e] = model[e].projectionMatrix();  // binning and ROI applied, as K
  }
  *calibration = c;
  return true;
}

const std::string& EyeCamera::update(const sensor_msgs::CameraInfo& info, std::uint32_t width, std::uint32_t height)
{
  if (model_.fromCameraInfo(info) || !seen_)
  {
    seen_ = true;
    CameraIntrinsics k;
    if (intrinsicsFromCameraModel(model_, &k, &model_error_) && projector_.configure(k, &model_error_))
      model_error_.clear();
    else
      projector_ = RawProjector();
  }
  error_ = model_error_;
  const CameraIntrinsics& k = projector_.intrinsics();
  if (error_.empty() && (k.width != static_cast<int>(width) || k.height != static_cast<int>(height)))
    error_ = "camera_info size " + std::to_string(k.width) + "x" + std::to_string(k.height) + " != image size " +
             std::to_string(width) + "x" + std::to_string(height);
  return error_;
}

bool prepareCanvas(const sensor_msgs::ImageConstPtr& image, saras_common::MessagePool<sensor_msgs::Image>* pool, sensor_msgs::ImagePtr* out,
                   cv::Mat* canvas, ChannelOrder* order, std::string* error)
{
  if (!imageBufferConsistent(*image, error))
    return false;
  const std::string& e = image->encoding;
  *order = ChannelOrder::kBgr;
  try
  {
    if (e == enc::BGR8 || e == enc::BGRA8 || e == enc::RGB8 || e == enc::RGBA8)
    {
      // The input is shared and const when zero-copied from the camera nodelet: copied once.
      *order = (e == enc::RGB8 || e == enc::RGBA8) ? ChannelOrder::kRgb : ChannelOrder::kBgr;
      sensor_msgs::ImagePtr m = pool->nextWithData(image->data.size());
      m->header = image->header;
      m->height = image->height;
      m->width = image->width;
      m->encoding = image->encoding;
      m->is_bigendian = image->is_bigendian;
      m->step = image->step;
      std::memcpy(m->data.data(), image->data.data(), image->data.size());
      *out = m;
    }
    else
      *out = cv_bridge::toCvCopy(image, enc::BGR8)->toImageMsg();  // mono, bayer, 16 bit (allocates)
  }
  catch (const std::exception& ex)
  {
    *error = "cannot convert encoding '" + e + "' (" + ex.what() + ")";
    return false;
  }
  const sensor_msgs::Image& m = **out;
  *canvas = cv::Mat(static_cast<int>(m.height), static_cast<int>(m.width),
                    enc::numChannels(m.encoding) == 4 ? CV_8UC4 : CV_8UC3, const_cast<std::uint8_t*>(m.data.data()),
                    m.step);
  return true;
}

bool poseSampleFromMsg(const geometry_msgs::PoseStamped& msg, const ros::Time& now, TimedPose* sample,
                       std::string* error)
{
  const geometry_msgs::Point& p = msg.pose.position;
  const geometry_msgs::Quaternion& q = msg.pose.orientation;
  if (msg.header.frame_id.empty())
    *error = "empty frame_id";
  else if (!(std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z) && std::isfinite(q.x) &&
             std::isfinite(q.y) && std::isfinite(q.z) && std::isfinite(q.w)))
    *error = "NaN/inf value";
  else
    error->clear();
  if (!error->empty())
    return false;
  *sample = TimedPose();
  sample->stamp_ns = static_cast<std::int64_t>((msg.header.stamp.isZero() ? now : msg.header.stamp).toNSec());
  sample->position[0] = p.x;
  sample->position[1] = p.y;
  sample->position[2] = p.z;
  const double norm = std::sqrt(q.x * q.x + q.y * q.y + q.z * q.z + q.w * q.w);
  if (norm > 1e-9)  // unset orientation (all zero): identity (only the tip position is drawn)
  {
    sample->orientation[0] = q.x / norm;
    sample->orientation[1] = q.y / norm;
    sample->orientation[2] = q.z / norm;
    sample->orientation[3] = q.w / norm;
  }
  return true;
}

bool encodeJpeg(const cv::Mat& canvas, ChannelOrder order, const std::string& encoding, JpegEncoder* encoder,
                sensor_msgs::CompressedImage* out, std::string* error)
{
  out->format = encoding + "; jpeg compressed bgr8";
  return encoder->encode(canvas, order, &out->data, error);
}

bool TfPointTransformer::transform(const std::string& target, const std::string& source, std::int64_t stamp_ns,
                                   const cv::Point3d& p, cv::Point3d* out, bool* at_stamp, std::string* error) const
{
  geometry_msgs::TransformStamped t;
  *at_stamp = true;
  ros::Time stamp;  // kLatestStamp: the latest transform (time 0)
  if (stamp_ns != kLatestStamp)
    stamp.fromNSec(static_cast<std::uint64_t>(stamp_ns));
  try
  {
    t = buffer_.lookupTransform(target, source, stamp);
  }
  catch (const tf2::TransformException&)
  {
    *at_stamp = false;
    try
    {
      t = buffer_.lookupTransform(target, source, ros::Time(0));
    }
    catch (const tf2::TransformException& e)
    {
      *error = e.what();
      return false;
    }
  }
  tf2::Transform tr;
  tf2::fromMsg(t.transform, tr);
  const tf2::Vector3 q = tr * tf2::Vector3(p.x, p.y, p.z);
  *out = cv::Point3d(q.x(), q.y(), q.z());
  return true;
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
