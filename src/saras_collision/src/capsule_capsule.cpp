// Exact capsule-capsule distance (segment-segment, Ericson 5.1.9). See
// include/saras_collision/geometry.h for the definitions and the return codes.
#include "geometry_detail.h"

#include <algorithm>
#include <cmath>

namespace saras_collision
{
using namespace detail;  // NOLINT(build/namespaces): this library's own private helpers

namespace
{
/// Finite coordinates and radii >= 0 (checked before the computation).
bool capsuleInputsValid(const Eigen::Vector3d& p1, const Eigen::Vector3d& p2, double r1, const Eigen::Vector3d& p3,
                        const Eigen::Vector3d& p4, double r2)
{
  return p1.allFinite() && p2.allFinite() && p3.allFinite() && p4.allFinite() && validRadius(r1) &&
         validRadius(r2);
}

/**
 * Capsule-capsule core (inputs finite, radii >= 0), with magnitudes for which a e and
 * |d1 x d2|^2 (~ length^4) do not overflow (capsulePairAnyScale() scales larger inputs).
 *
 * Segment-segment: minimise |p1 + s d1 - p3 - t d2|^2 over [0,1]^2 (convex quadratic).
 * Interior stationary point from the 2x2 normal equations (denominator |d1 x d2|^2, taken from
 * the cross product when nearly parallel to avoid cancellation), clamped; then t is
 * re-optimised for s and, if t was clamped, s for t (Ericson, Real-Time Collision Detection
 * 5.1.9). Degenerate axes reduce to point-segment projections.
 * @return the DistanceCode; @p normal from capsule 2 towards capsule 1
 */
int capsulePair(const Eigen::Vector3d& p1, const Eigen::Vector3d& p2, double r1, const Eigen::Vector3d& p3,
                const Eigen::Vector3d& p4, double r2, double& distance, Eigen::Vector3d& point1,
                Eigen::Vector3d& point2, Eigen::Vector3d& normal)
{
  const Eigen::Vector3d d1 = p2 - p1;
  const Eigen::Vector3d d2 = p4 - p3;
  const Eigen::Vector3d w = p1 - p3;
  const double a = d1.squaredNorm();
  const double e = d2.squaredNorm();
  const double b = d1.dot(d2);
  const double c = d1.dot(w);
  const double f = d2.dot(w);
  double s = 0.0, t = 0.0;
  bool parallel = false;
  const bool point1_axis = a <= kDegenerateLength2;
  const bool point2_axis = e <= kDegenerateLength2;
  if (!point1_axis && !point2_axis)
  {
    // |d1 x d2|^2 = a e - b^2; near parallel the difference cancels, so it is then recomputed
    // from the cross product (relative error of a e - b^2 ~ 1e-16 / 1e-3 otherwise).
    double denom = a * e - b * b;
    if (denom < 1e-3 * a * e)
      denom = d1.cross(d2).squaredNorm();
    parallel = !(denom > kParallelSin2 * a * e);
    // Parallel: any s is optimal up to the clamping of t, fixed below.
    s = parallel ? 0.0 : clamp01((b * f - c * e) / denom);
    const double t_free = (b * s + f) / e;
    if (t_free < 0.0)
      s = clamp01(-c / a);  // t clamped to 0: s re-optimised
    else if (t_free > 1.0)
      s = clamp01((b - c) / a);  // t clamped to 1
    t = clamp01(t_free);
  }
  else if (point1_axis && !point2_axis)
  {
    t = clamp01(f / e);
  }
  else if (point2_axis && !point1_axis)
  {
    s = clamp01(-c / a);
  }
  const Eigen::Vector3d q1 = p1 + s * d1;
  const Eigen::Vector3d q2 = p3 + t * d2;
  const Eigen::Vector3d v = q1 - q2;
  const double axis2 = v.squaredNorm();
  const double axis = std::sqrt(axis2);
  distance = axis - r1 - r2;
  if (axis2 > kMinAxis2)
    normal = v / axis;
  else if (!point1_axis && !point2_axis && !parallel)
    normal = d1.cross(d2).normalized();
  else if (!point1_axis)
    normal = anyPerpendicular(d1);
  else if (!point2_axis)
    normal = anyPerpendicular(d2);
  else
    normal = Eigen::Vector3d::UnitZ();
  // Intersecting: witnesses = closest points of the axes; else surface points.
  const double k = surfaceFactor(distance);
  point1 = q1 - (k * r1) * normal;
  point2 = q2 + (k * r2) * normal;
  return classify(distance, parallel ? kParallel : kSeparated);
}

/**
 * capsulePair() for any finite magnitude: when a coordinate exceeds 2^200 (~1.6e60 m) in
 * magnitude, its products (a e, |d1 x d2|^2 ~ length^4) could overflow, so the inputs are
 * scaled by a power of two (exact) to magnitudes below 1, solved, and the distance and points
 * scaled back (the problem is homogeneous; the normal is scale-free). A result that is not
 * representable (distance beyond ~1.8e308) becomes non-finite; the callers reject it.
 */
int capsulePairAnyScale(const Eigen::Vector3d& p1, const Eigen::Vector3d& p2, double r1, const Eigen::Vector3d& p3,
                        const Eigen::Vector3d& p4, double r2, double& distance, Eigen::Vector3d& point1,
                        Eigen::Vector3d& point2, Eigen::Vector3d& normal)
{
  const double mag = std::max(std::max(p1.cwiseAbs().maxCoeff(), p2.cwiseAbs().maxCoeff()),
                              std::max(p3.cwiseAbs().maxCoeff(), p4.cwiseAbs().maxCoeff()));
  constexpr double kLarge = 0x1p200;
  if (!(mag > kLarge))
    return capsulePair(p1, p2, r1, p3, p4, r2, distance, point1, point2, normal);
  const int k = std::ilogb(mag) + 1;  // mag * 2^-k < 1
  const double down = std::ldexp(1.0, -k), up = std::ldexp(1.0, k);
  const int code = capsulePair(p1 * down, p2 * down, r1 * down, p3 * down, p4 * down, r2 * down, distance, point1,
                               point2, normal);
  distance *= up;
  point1 *= up;
  point2 *= up;
  return code;
}
}  // namespace

DistanceResult capsuleCapsule(const Eigen::Vector3d& p1, const Eigen::Vector3d& p2, double r1,
                              const Eigen::Vector3d& p3, const Eigen::Vector3d& p4, double r2)
{
  if (!capsuleInputsValid(p1, p2, r1, p3, p4, r2))
    return invalid(kInvalidInput);
  DistanceResult out;
  out.code = capsulePairAnyScale(p1, p2, r1, p3, p4, r2, out.distance, out.point1, out.point2, out.normal);
  if (!std::isfinite(out.distance))  // finite inputs, distance not representable
    return invalid(kInvalidInput);
  return out;
}

int dist_capsule_to_capsule(const Eigen::Vector3d& P1, const Eigen::Vector3d& P2, const Eigen::Vector3d& P3,
                            const Eigen::Vector3d& P4, double r1, double r2, double& distance,
                            Eigen::Vector3d& point_on_capsule1, Eigen::Vector3d& point_on_capsule2)
{
  const DistanceResult res = capsuleCapsule(P1, P2, r1, P3, P4, r2);
  if (!isValidCode(res.code))
    return invalidOutputs(res.code, distance, point_on_capsule1, point_on_capsule2);
  distance = res.distance;
  point_on_capsule1 = res.point1;
  point_on_capsule2 = res.point2;
  return res.code;
}

}  // namespace saras_collision
