#include "saras_visual_feedback/frame_composer.h"

#include <cmath>

namespace saras_visual_feedback
{
namespace
{
/// The shaft's far end: towards the trocar at @p rcm, at most @p length [m] from the tip.
bool shaftEnd(const cv::Point3d& tip, const cv::Point3d& rcm, double length, cv::Point3d* end)
{
  const cv::Point3d d = rcm - tip;
  const double len = std::sqrt(d.dot(d));
  if (!(len > 1e-6))
    return false;
  *end = len > length ? tip + (length / len) * d : rcm;
  return true;
}

void placeTool(const ToolSample& s, const SceneStyle& style, const std::string& camera_frame, std::int64_t stamp_ns,
               std::int64_t tolerance_ns, const PointTransformer& tf, ToolOverlay* o, ToolPlacement* r)
{
  const PoseLookupResult& pose = s.pose;
  r->pose_fallback = !(pose.status == PoseLookup::kInterpolated ||
                       (pose.status == PoseLookup::kAfterNewest && pose.offset_ns <= tolerance_ns)) ||
                     stamp_ns == kLatestStamp;
  const cv::Point3d tip(pose.pose.position[0], pose.pose.position[1], pose.pose.position[2]);
  bool at_stamp = true;
  if (!tf.transform(camera_frame, s.frame, stamp_ns, tip, &o->tip, &at_stamp, &r->error))
  {
    r->tip_failed = true;
    return;
  }
  r->transform_fallbacks += at_stamp ? 0 : 1;
  o->visible = true;
  if (s.tool->rcm_frame.empty())
    return;
  cv::Point3d rcm;
  if (!tf.transform(camera_frame, s.tool->rcm_frame, stamp_ns, cv::Point3d(0, 0, 0), &rcm, &at_stamp, &r->error))
  {
    r->shaft_failed = true;
    return;
  }
  r->transform_fallbacks += at_stamp ? 0 : 1;
  o->has_shaft = shaftEnd(o->tip, rcm, style.shaft_length, &o->shaft);
}

void atomicMax(std::atomic<std::uint64_t>& a, std::uint64_t v)
{
  std::uint64_t cur = a.load();
  while (v > cur && !a.compare_exchange_weak(cur, v))
  {
  }
}
}  // namespace

void placeTools(const SceneSnapshot& scene, const std::string& camera_frame, std::int64_t stamp_ns,
                std::int64_t tolerance_ns, const PointTransformer& tf, ToolOverlay* overlays, FrameReport* report)
{
  report->n = scene.n;
  for (std::size_t i = 0; i < scene.n; ++i)
  {
    const ToolSample& s = scene.tools[i];
    ToolOverlay& o = overlays[i];
    o = ToolOverlay();
    o.label = s.tool->label.c_str();
    o.distance = s.distance;
    report->tools[i] = ToolPlacement();
    if (s.pose.status != PoseLookup::kEmpty)
      placeTool(s, scene.style, camera_frame, stamp_ns, tolerance_ns, tf, &o, &report->tools[i]);
  }
}

void drawFrame(cv::Mat& canvas, ChannelOrder order, const RawProjector* camera, const std::string& off_reason,
               const SceneSnapshot& scene, ToolOverlay* overlays, HudCache* hud, FrameReport* report)
{
  report->n = scene.n;
  report->overlay = camera != nullptr && camera->valid();
  if (report->overlay)
  {
    drawOverlay(canvas, order, *camera, scene.style.overlay, overlays, scene.n, report->drawn.data(), nullptr, hud);
    return;
  }
  // No usable camera model: the image goes out with the HUD and the reason, no tool drawn.
  const std::string line = "overlay off: " + off_reason.substr(0, 60);
  RawProjector placeholder;
  CameraIntrinsics k;
  k.width = canvas.cols;
  k.height = canvas.rows;
  k.fx = k.fy = 1.0;
  placeholder.configure(k, nullptr);
  for (std::size_t i = 0; i < scene.n; ++i)
  {
    overlays[i].visible = false;
    report->drawn[i] = ToolDrawResult();
  }
  drawOverlay(canvas, order, placeholder, scene.style.overlay, overlays, scene.n, nullptr, line.c_str(), hud);
}

void EyeStats::record(const FrameReport& report)
{
  std::array<bool, 4> seen{};
  for (std::size_t i = 0; i < report.n; ++i)
  {
    const ToolPlacement& p = report.tools[i];
    pose_fallbacks += p.pose_fallback ? 1 : 0;
    tf_failures += (p.tip_failed ? 1 : 0) + (p.shaft_failed ? 1 : 0);
    tf_fallbacks += static_cast<std::uint64_t>(p.transform_fallbacks);
    if (report.overlay && report.drawn[i].drawn != ToolDrawn::kNothing)
      seen[static_cast<std::size_t>(report.drawn[i].proximity)] = true;
  }
  for (std::size_t c = 0; c < seen.size(); ++c)
    colour_frames[c] += seen[c] ? 1 : 0;
}

void EyeStats::addTiming(std::uint64_t wall_ns, std::uint64_t thread_cpu_ns)
{
  ++published;
  busy_ns += wall_ns;
  atomicMax(max_busy_ns, wall_ns);
  cpu_ns += thread_cpu_ns;
}

}  // namespace saras_visual_feedback
