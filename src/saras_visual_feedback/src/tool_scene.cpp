#include "saras_visual_feedback/tool_scene.h"

#include <algorithm>
#include <cmath>
#include <utility>

namespace saras_visual_feedback
{

ToolScene::ToolScene(std::vector<ToolConfig> tools, std::size_t pose_buffer_size, std::int64_t pose_timeout_ns,
                     std::int64_t distances_timeout_ns, const SceneStyle& style)
  : tools_(std::move(tools))
  , pose_timeout_ns_(pose_timeout_ns)
  , distances_timeout_ns_(distances_timeout_ns)
  , histories_(tools_.size())
  , style_(style)
{
  for (const ToolConfig& t : tools_)
    distances_needed_ = std::max(distances_needed_, static_cast<std::size_t>(t.distance_index) + 1);
  for (History& h : histories_)
    h.poses.setCapacity(pose_buffer_size);
}

PosePush ToolScene::addPose(std::size_t i, const std::string& frame, const TimedPose& sample, std::int64_t now_ns)
{
  std::lock_guard<std::mutex> lock(mutex_);
  History& h = histories_.at(i);
  if (h.frame != frame)
  {
    h.poses.clear();  // poses of different frames are not interpolated
    h.frame = frame;
  }
  const PosePush r = h.poses.push(sample);
  if (r == PosePush::kRestarted)
    ++counters_.history_restarts;
  h.received_ns = now_ns;
  h.any = true;
  return r;
}

std::uint64_t ToolScene::rejectPose(std::size_t /*i*/)
{
  std::lock_guard<std::mutex> lock(mutex_);
  return ++counters_.rejected_poses;
}

bool ToolScene::setDistances(const std::vector<double>& distances, std::int64_t now_ns)
{
  std::lock_guard<std::mutex> lock(mutex_);
  distances_.assign(distances.begin(), distances.end());
  distances_received_ns_ = now_ns;
  distances_seen_ = true;
  if (distances.size() >= distances_needed_)
    return true;
  ++counters_.rejected_distances;
  return false;
}

void ToolScene::setStyle(const SceneStyle& style)
{
  std::lock_guard<std::mutex> lock(mutex_);
  style_ = style;
}

SceneStyle ToolScene::style() const
{
  std::lock_guard<std::mutex> lock(mutex_);
  return style_;
}

SceneCounters ToolScene::counters() const
{
  std::lock_guard<std::mutex> lock(mutex_);
  return counters_;
}

void ToolScene::snapshot(std::int64_t now_ns, std::int64_t image_stamp_ns, SceneSnapshot* out) const
{
  std::lock_guard<std::mutex> lock(mutex_);
  out->style = style_;
  out->n = 0;
  const bool distances_fresh = distances_seen_ && now_ns - distances_received_ns_ <= distances_timeout_ns_;
  for (std::size_t i = 0; i < tools_.size() && out->n < kMaxTools; ++i)
  {
    const ToolConfig& t = tools_[i];
    if (t.dvrk && !style_.draw_dvrk)
      continue;
    ToolSample& s = out->tools[out->n++];
    s.tool = &t;
    const auto idx = static_cast<std::size_t>(t.distance_index);
    s.distance = (distances_fresh && idx < distances_.size()) ? distances_[idx] : std::nan("");
    if (std::isinf(s.distance) && s.distance < 0)
      s.distance = std::nan("");
    const History& h = histories_[i];
    const bool pose_fresh = h.any && !h.poses.empty() && now_ns - h.received_ns <= pose_timeout_ns_;
    s.pose = pose_fresh ? h.poses.lookup(image_stamp_ns) : PoseLookupResult();
    if (pose_fresh)
      s.frame = h.frame;  // string capacity reused: no allocation in steady state
  }
}

}  // namespace saras_visual_feedback
