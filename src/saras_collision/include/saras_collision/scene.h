/**
 * @file scene.h
 * @brief ROS-agnostic collision scene: tools (capsules) and forbidden regions (boxes), giving
 *        each tool's minimum distance, closest points and nearest object (D7.2 Section 6).
 *
 * Units: metres throughout; every pose is expressed in one common frame (the node uses world).
 * compute() does not allocate once the scene is built (results and boxes are preallocated).
 */
#ifndef SARAS_COLLISION_SCENE_H
#define SARAS_COLLISION_SCENE_H

#include <string>
#include <vector>

#include <Eigen/Core>

#include "saras_collision/geometry.h"

namespace saras_collision
{
/// Result code reported for a tool without valid pose data (its distance is NaN).
constexpr int kNoData = kInvalidInput;

/// One tool: a capsule from the tool tip to the trocar (remote centre of motion).
struct ToolSpec
{
  std::string name;  ///< e.g. "mesa_left"
  double radius = 0.0;  ///< instrument shaft radius [m]
};

/// What a tool is nearest to.
struct NearestObject
{
  enum Kind
  {
    kNone,  ///< nothing (no other valid object)
    kTool,  ///< another tool; index into the tool list
    kBox,  ///< a forbidden-region box; index into the box list
  };
  Kind kind = kNone;
  int index = -1;
};

/// Minimum-distance result of one tool.
struct ToolProximityResult
{
  double distance = 0.0;  ///< signed distance to the nearest object [m] (NaN: no data / no object)
  int code = kNoData;  ///< DistanceCode of the nearest pair, or kNoData
  NearestObject nearest;
  Eigen::Vector3d point_on_tool = Eigen::Vector3d::Zero();  ///< [m]
  Eigen::Vector3d point_on_object = Eigen::Vector3d::Zero();  ///< [m]
  /// Unit direction moving the tool away from the nearest object (see DistanceResult::normal).
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();
};

/**
 * @brief Tools + boxes -> per-tool minimum distance (all tool pairs, every tool vs every box).
 *
 * Box culling: a box is skipped when its bounding sphere is farther from the tool axis than
 * the tool's best distance so far; this never changes the result (the bounding-sphere distance
 * is a lower bound of the box distance).
 */
class CollisionScene
{
public:
  explicit CollisionScene(const std::vector<ToolSpec>& tools);

  std::size_t toolCount() const
  {
    return tools_.size();
  }
  const ToolSpec& tool(std::size_t i) const
  {
    return tools_[i];
  }

  /// Replace the boxes (common frame). Allocates: call at start-up or when the model moves.
  void setBoxes(const std::vector<OrientedBox>& boxes);
  const std::vector<OrientedBox>& boxes() const
  {
    return boxes_;
  }

  /**
   * @brief Set tool @p i's capsule axis. Non-finite input invalidates the tool.
   * @return false if the input was rejected (non-finite)
   */
  bool setToolAxis(std::size_t i, const Eigen::Vector3d& tip, const Eigen::Vector3d& trocar);
  /// Mark tool @p i as without data: it is ignored by the others and gets distance NaN.
  void invalidateTool(std::size_t i);
  bool toolValid(std::size_t i) const
  {
    return valid_[i];
  }
  const Eigen::Vector3d& toolTip(std::size_t i) const
  {
    return tips_[i];
  }
  const Eigen::Vector3d& toolTrocar(std::size_t i) const
  {
    return trocars_[i];
  }

  /// Enable/disable the bounding-sphere culling (for benchmarks; default on).
  void setCulling(bool enabled)
  {
    culling_ = enabled;
  }

  /// Compute every tool's minimum distance. No allocation.
  const std::vector<ToolProximityResult>& compute();
  const std::vector<ToolProximityResult>& results() const
  {
    return results_;
  }

private:
  void offer(std::size_t tool, const DistanceResult& r, bool tool_is_first, NearestObject::Kind kind, int index);

  std::vector<ToolSpec> tools_;
  std::vector<Eigen::Vector3d> tips_, trocars_;
  std::vector<bool> valid_;
  std::vector<OrientedBox> boxes_;
  std::vector<ToolProximityResult> results_;
  bool culling_ = true;
};

/// Threshold classification shared with the visual feedback (D7.2 Section 7).
enum class Zone
{
  kUnknown,  ///< no data (NaN distance)
  kSafe,  ///< distance > warning
  kWarning,  ///< collision < distance <= warning
  kCollision,  ///< distance <= collision
};
Zone classifyDistance(double distance, double collision_threshold, double warning_threshold);

/**
 * @brief Virtual fixture: repulsive force on a tool whose distance is below the warning
 *        threshold, F = min(k (d_warning - d), f_max) * n (n: away from the nearest object).
 * @param result the tool's proximity result
 * @param warning_threshold [m]; @param stiffness k [N/m]; @param max_force f_max [N]
 * @return force [N] in the scene frame; zero when d >= d_warning or d is NaN
 */
Eigen::Vector3d fixtureForce(const ToolProximityResult& result, double warning_threshold, double stiffness,
                             double max_force);

}  // namespace saras_collision

#endif  // SARAS_COLLISION_SCENE_H
