/**
 * @file geometry.h
 * @brief Exact distance between capsules, spheres and oriented rectangular boxes (no ROS).
 *
 * Units: every length (points, radii, distances) is in the caller's unit, metres on the
 * SARAS platform. All functions are allocation-free and thread-safe (no state).
 *
 * Definitions
 *  - A capsule is the set of points within radius r of the segment [P, Q] (its axis). A sphere
 *    is a capsule whose two end-points coincide.
 *  - A box ("parallelepiped" in deliverable D7.2) is a rectangular cuboid given by its 8
 *    vertices in this order (D7.2 Figure 11 convention, max_x = v1, max_y = v4, max_z = v3):
 *      v0 = origin corner, v1 = v0+x, v2 = v0+x+z, v3 = v0+z,
 *      v4 = v0+y, v5 = v0+x+y, v6 = v0+x+y+z, v7 = v0+y+z
 *    where x, y, z are mutually orthogonal edge vectors (either handedness).
 *  - The signed distance between a capsule and a box is  min over the axis of sd_box(p) - r,
 *    with sd_box the exact signed distance function of the box (negative inside). It is the
 *    Euclidean distance between the solids when they are separated, and minus the depth
 *    reached by the capsule (axis depth + r) when they intersect. Between two capsules it is
 *    the axis-to-axis distance minus r1 + r2.
 *
 * Return codes (D7.2 Section 6.1, made exact):
 *  - kIntersecting (-1): the solids overlap; distance < -kTangentTolerance. The output points
 *    are witnesses, not surface points: for capsule-capsule the closest points of the two
 *    axes; for capsule/sphere-box the deepest axis point and its projection on the nearest box
 *    face.
 *  - kTangent (0): |distance| <= kTangentTolerance; both points are the (common) contact point.
 *  - kSeparated (1): distance > kTangentTolerance; the points are exact closest points on
 *    the two surfaces, |point1 - point2| == distance.
 *  - kParallel (2): capsule-capsule only, separated and with parallel axes; the distance and
 *    (one pair of) closest points are valid as for kSeparated.
 *  - kInvalidBox (-2): the 8 vertices are not a rectangular box in the order above.
 *  - kInvalidInput (-3): a NaN/infinite coordinate or a negative/non-finite radius (also: finite
 *    capsule-capsule inputs whose distance is not representable, beyond ~1.8e308 m, and a
 *    dist_sphere_to_parallelepiped() centre beyond ~1e154 m from the box, whose squared
 *    distance overflows).
 *  On an error code the distance and points are set to NaN: never use them as a number.
 */
#ifndef SARAS_COLLISION_GEOMETRY_H
#define SARAS_COLLISION_GEOMETRY_H

#include <Eigen/Core>

namespace saras_collision
{
/// Return codes of the distance functions (see file documentation).
enum DistanceCode : int
{
  kInvalidInput = -3,
  kInvalidBox = -2,
  kIntersecting = -1,
  kTangent = 0,
  kSeparated = 1,
  kParallel = 2,
};

/// |distance| at or below this is reported as kTangent [m] (1 nm).
constexpr double kTangentTolerance = 1e-9;
/// Two capsule axes are parallel when sin^2 of their angle is below this (angle < 1e-7 rad).
constexpr double kParallelSin2 = 1e-14;
/// Default relative tolerance on the box vertices (fraction of the box diagonal and of the
/// cosine between edges) used by the deliverable-signature functions.
constexpr double kBoxRelativeTolerance = 1e-6;

/// @return true for codes that carry a valid distance (kIntersecting .. kParallel).
inline bool isValidCode(int code)
{
  return code >= kIntersecting && code <= kParallel;
}

/// Human-readable name of a return code ("separated", "invalid_box", ...).
const char* codeName(int code);

/**
 * @brief Oriented box in centre / axes / half-extents form, built once from 8 vertices.
 *
 * Precompute it with makeBox() when the same box is queried many times (the scene does).
 */
struct OrientedBox
{
  Eigen::Vector3d center = Eigen::Vector3d::Zero();  ///< box centre [m]
  Eigen::Matrix3d axes = Eigen::Matrix3d::Identity();  ///< columns: unit x, y, z edge directions
  Eigen::Vector3d half = Eigen::Vector3d::Zero();  ///< half edge lengths along x, y, z [m]
  double bounding_radius = 0.0;  ///< |half|: radius of the circumscribed sphere [m]
};

/**
 * @brief Build an OrientedBox from 8 vertices in the documented order.
 * @param vertices array of 8 vertices [m]
 * @param relative_tolerance allowed deviation rt from a perfect box: every edge longer than
 *        rt x diagonal; root-sum-square of the cosines of the 3 edge pairs <= rt; root-sum-square
 *        of the 4 vertex residuals (v2 - v3 - x, v5 - v4 - x, v6 - v5 - z, v7 - v4 - z)
 *        <= rt x diagonal
 * @param[out] box the box (unchanged on error)
 * @return kSeparated (1) on success, kInvalidInput on non-finite coordinates, kInvalidBox
 *         when the vertices are not a rectangular box in the documented order
 */
int makeBox(const Eigen::Vector3d vertices[], double relative_tolerance, OrientedBox& box);

/// The 8 vertices of @p box in the documented order [m].
void boxVertices(const OrientedBox& box, Eigen::Vector3d vertices[]);

/**
 * @brief Full result of a distance query (used by the scene and the virtual fixture).
 */
struct DistanceResult
{
  int code = kInvalidInput;  ///< DistanceCode
  double distance = 0.0;  ///< signed distance [m]
  Eigen::Vector3d point1 = Eigen::Vector3d::Zero();  ///< point on the first object [m]
  Eigen::Vector3d point2 = Eigen::Vector3d::Zero();  ///< point on the second object [m]
  /// Unit direction in which moving the first object increases the distance fastest
  /// (from object 2 towards object 1); defined for every valid code.
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();
};

/// Capsule [p1, p2] radius r1 against capsule [p3, p4] radius r2. Radii >= 0 [m].
DistanceResult capsuleCapsule(const Eigen::Vector3d& p1, const Eigen::Vector3d& p2, double r1,
                              const Eigen::Vector3d& p3, const Eigen::Vector3d& p4, double r2);

/// Capsule [p1, p2] radius r against a prebuilt box. point1 is on the capsule.
DistanceResult capsuleBox(const Eigen::Vector3d& p1, const Eigen::Vector3d& p2, double r,
                          const OrientedBox& box);

/**
 * @brief Capsule-to-capsule distance (D7.2 signature).
 * @param P1, P2 axis end-points of capsule 1 [m]; @param P3, P4 of capsule 2 [m]
 * @param r1, r2 radii [m], >= 0
 * @param[out] distance signed distance [m]; @param[out] point_on_capsule1, point_on_capsule2
 * @return DistanceCode
 */
int dist_capsule_to_capsule(const Eigen::Vector3d& P1, const Eigen::Vector3d& P2,
                            const Eigen::Vector3d& P3, const Eigen::Vector3d& P4, double r1, double r2,
                            double& distance, Eigen::Vector3d& point_on_capsule1,
                            Eigen::Vector3d& point_on_capsule2);

/**
 * @brief Capsule-to-box distance (D7.2 signature).
 * @param p1, p2 axis end-points [m]; @param vertices 8 box vertices [m] (documented order)
 * @param r capsule radius [m], >= 0
 * @return DistanceCode (never kParallel)
 */
int dist_capsule_to_parallelepiped(const Eigen::Vector3d& p1, const Eigen::Vector3d& p2,
                                   const Eigen::Vector3d vertices[], double r, double& distance,
                                   Eigen::Vector3d& point_on_capsule, Eigen::Vector3d& point_on_parall);

/**
 * @brief Sphere-to-box distance (D7.2 signature).
 * @param s sphere centre [m]; @param vertices 8 box vertices [m]; @param r radius [m], >= 0
 * @return DistanceCode (never kParallel)
 */
int dist_sphere_to_parallelepiped(const Eigen::Vector3d& s, const Eigen::Vector3d vertices[], double r,
                                  double& distance, Eigen::Vector3d& point_on_sphere,
                                  Eigen::Vector3d& point_on_parall);

}  // namespace saras_collision

#endif  // SARAS_COLLISION_GEOMETRY_H
