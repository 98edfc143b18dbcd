/**
 * @file endoscope_stereo.cpp
 * @brief StereoScene and EyeOutput.
 */
#include "saras_simulation/endoscope_stereo.h"

#include <stdexcept>


namespace saras_simulation
{
namespace endoscope
{
StereoScene::StereoScene(const sensor_msgs::CameraInfo info[2], const EndoscopeConfig& config,
                         std::vector<std::array<Eigen::Vector3d, 8>> bones)
  : bones_(std::move(bones)), specs_(config.targets)
{
  for (int e = 0; e < 2; ++e)
    renderers_[e].reset(new SceneRenderer(cameraModel(info[e]), config.tissue, config.renderer));
}

bool StereoScene::selectTarget(const std::string& kind, std::string& error)
{
  if (kind.empty() || kind == "none")
  {
    for (auto& r : renderers_)
      r->clearTarget();
    return true;
  }
  const auto spec = specs_.find(kind);
  if (spec == specs_.end())
  {
    error = "unknown target '" + kind + "' (none | checkerboard | circles)";
    return false;
  }
  auto& target = built_[kind];
  try
  {
    if (!target)
      target = buildTarget(spec->second);
  }
  catch (const std::invalid_argument& e)
  {
    built_.erase(kind);
    error = e.what();
    return false;
  }
  for (auto& r : renderers_)
    r->setTarget(target, spec->second.pose);
  return true;
}

bool StereoScene::placeBones(const Eigen::Isometry3d& T_world_bones, std::string& error)
{
  if (!T_world_bones.matrix().allFinite())
  {
    error = "non-finite bones pose";
    return false;
  }
  auto world = bones_;
  for (auto& b : world)
    for (auto& v : b)
      v = T_world_bones * v;
  try
  {
    for (auto& r : renderers_)
      r->setBoxes(world);
  }
  catch (const std::invalid_argument& e)  // not expected: a rigid transform keeps the boxes rectangular
  {
    error = e.what();
    return false;
  }
  bones_placed_ = true;
  return true;
}

// ---------------------------------------------------------------------------------------------
EyeOutput::EyeOutput(const sensor_msgs::CameraInfo& info, int jpeg_quality, std::size_t pool_size)
  : info_(info), jpeg_(jpeg_quality), images_(pool_size), jpegs_(pool_size)
{
}

EyeMessages EyeOutput::produce(StereoScene& scene, int e, const StereoFrame& frame, bool want_raw, bool want_jpeg,
                               std::string& error)
{
  EyeMessages m;
  if (!want_raw && !want_jpeg)
    return m;
  const int w = static_cast<int>(info_.width), h = static_cast<int>(info_.height);
  try
  {
    cv::Mat* target = &buffer_;
    cv::Mat wrap;
    if (want_raw)
    {
      // a pooled message: its buffer is rendered over, never allocated or zero-filled per frame
      m.image = images_.nextWithData(static_cast<std::size_t>(w) * h * 3);
      m.image->height = h;
      m.image->width = w;
      m.image->encoding = "bgr8";
      m.image->is_bigendian = 0;
      m.image->step = w * 3;
      wrap = cv::Mat(h, w, CV_8UC3, m.image->data.data());
      target = &wrap;
    }
    scene.render(e, frame.pose[e], frame.shafts, *target);
    if (want_jpeg)
    {
      m.jpeg = jpegs_.next();
      m.jpeg->format = "bgr8; jpeg compressed bgr8";
      // encoded straight into the message (its capacity is reused), BGR read as is
      if (!jpeg_.encode(*target, saras_visual_feedback::ChannelOrder::kBgr, &m.jpeg->data, &error))
        m.jpeg.reset();
    }
  }
  catch (const std::exception& ex)
  {
    m = EyeMessages();
    error = ex.what();
    return m;
  }
  for (std_msgs::Header* hdr : { m.image ? &m.image->header : nullptr, m.jpeg ? &m.jpeg->header : nullptr })
    if (hdr)
    {
      hdr->stamp = frame.stamp;
      hdr->frame_id = info_.header.frame_id;
    }
  return m;
}

const sensor_msgs::CameraInfo& EyeOutput::cameraInfo(const ros::Time& stamp)
{
  info_.header.stamp = stamp;
  return info_;
}

}  // namespace endoscope
}  // namespace saras_simulation
