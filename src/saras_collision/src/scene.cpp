#include "saras_collision/scene.h"

#include <cmath>
#include <limits>

namespace saras_collision
{
namespace
{
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

/// Distance from point @p c to segment [p, p + d] [m].
inline double pointSegmentDistance(const Eigen::Vector3d& c, const Eigen::Vector3d& p, const Eigen::Vector3d& d)
{
  const double dd = d.squaredNorm();
  double t = dd > 0.0 ? (c - p).dot(d) / dd : 0.0;
  t = t < 0.0 ? 0.0 : (t > 1.0 ? 1.0 : t);
  return (p + t * d - c).norm();
}
}  // namespace

CollisionScene::CollisionScene(const std::vector<ToolSpec>& tools)
  : tools_(tools)
  , tips_(tools.size(), Eigen::Vector3d::Zero())
  , trocars_(tools.size(), Eigen::Vector3d::Zero())
  , valid_(tools.size(), false)
  , results_(tools.size())
{
}

void CollisionScene::setBoxes(const std::vector<OrientedBox>& boxes)
{
  boxes_ = boxes;
}

bool CollisionScene::setToolAxis(std::size_t i, const Eigen::Vector3d& tip, const Eigen::Vector3d& trocar)
{
  if (!tip.allFinite() || !trocar.allFinite())
  {
    valid_[i] = false;
    return false;
  }
  tips_[i] = tip;
  trocars_[i] = trocar;
  valid_[i] = true;
  return true;
}

void CollisionScene::invalidateTool(std::size_t i)
{
  valid_[i] = false;
}

void CollisionScene::offer(std::size_t tool, const DistanceResult& r, bool tool_is_first, NearestObject::Kind kind,
                           int index)
{
  ToolProximityResult& best = results_[tool];
  if (!isValidCode(r.code))
    return;
  if (best.nearest.kind != NearestObject::kNone && !(r.distance < best.distance))
    return;
  best.distance = r.distance;
  best.code = r.code;
  best.nearest.kind = kind;
  best.nearest.index = index;
  best.point_on_tool = tool_is_first ? r.point1 : r.point2;
  best.point_on_object = tool_is_first ? r.point2 : r.point1;
  best.normal = tool_is_first ? r.normal : Eigen::Vector3d(-r.normal);
}

const std::vector<ToolProximityResult>& CollisionScene::compute()
{
  const std::size_t n = tools_.size();
  for (std::size_t i = 0; i < n; ++i)
  {
    ToolProximityResult& res = results_[i];
    res.distance = kNaN;
    res.code = kNoData;
    res.nearest = NearestObject();
    res.point_on_tool = res.point_on_object = Eigen::Vector3d::Constant(kNaN);
    res.normal = Eigen::Vector3d::Constant(kNaN);
  }
  // Tool pairs.
  for (std::size_t i = 0; i < n; ++i)
  {
    if (!valid_[i])
      continue;
    for (std::size_t j = i + 1; j < n; ++j)
    {
      if (!valid_[j])
        continue;
      const DistanceResult r =
          capsuleCapsule(tips_[i], trocars_[i], tools_[i].radius, tips_[j], trocars_[j], tools_[j].radius);
      offer(i, r, true, NearestObject::kTool, static_cast<int>(j));
      offer(j, r, false, NearestObject::kTool, static_cast<int>(i));
    }
  }
  // Tools against boxes.
  for (std::size_t i = 0; i < n; ++i)
  {
    if (!valid_[i])
      continue;
    const Eigen::Vector3d d = trocars_[i] - tips_[i];
    const double radius = tools_[i].radius;
    ToolProximityResult& res = results_[i];
    for (std::size_t b = 0; b < boxes_.size(); ++b)
    {
      const OrientedBox& box = boxes_[b];
      if (culling_ && res.nearest.kind != NearestObject::kNone)
      {
        const double lower_bound = pointSegmentDistance(box.center, tips_[i], d) - box.bounding_radius - radius;
        if (lower_bound >= res.distance)
          continue;
      }
      offer(i, capsuleBox(tips_[i], trocars_[i], radius, box), true, NearestObject::kBox, static_cast<int>(b));
    }
  }
  return results_;
}

Zone classifyDistance(double distance, double collision_threshold, double warning_threshold)
{
  if (std::isnan(distance))
    return Zone::kUnknown;
  if (distance <= collision_threshold)
    return Zone::kCollision;
  if (distance <= warning_threshold)
    return Zone::kWarning;
  return Zone::kSafe;
}

Eigen::Vector3d fixtureForce(const ToolProximityResult& result, double warning_threshold, double stiffness,
                             double max_force)
{
  if (!std::isfinite(result.distance) || !result.normal.allFinite() || !(result.distance < warning_threshold))
    return Eigen::Vector3d::Zero();
  double magnitude = stiffness * (warning_threshold - result.distance);
  if (magnitude > max_force)
    magnitude = max_force;
  if (!(magnitude > 0.0))
    return Eigen::Vector3d::Zero();
  return magnitude * result.normal;
}

}  // namespace saras_collision
