// Exact capsule-capsule distance (segment-segment, Ericson 5.1.9). See
// include/saras_collision/geometry.h for the definitions and the return codes. A source of its
// own so that it can be compiled with its own flags (CMakeLists.txt: no SLP vectorisation).
#include "geometry_detail.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace saras_collision
{
using namespace detail;  // NOLINT(build/namespaces): this library's own private helpers

namespace
{
/// Bound on each of a, e, |v|^2 [m^2] and r1, r2 [m] of the fast path: keeps every product
/// below 2^970.
constexpr double kFastRange = 0x1p238;
/// |v|^2 above which the fast path takes the normal from v (1 / |v|^2 finite) [m^2].
constexpr double kMinFastAxis2 = 1e-290;

/**
 * Capsule-capsule input check, done on the result of capsulePair() (so that it is not in
 * front of the computation): the inputs are finite and the radii >= 0 iff the computed
 * distance is finite and the radii >= 0. Proof of "if": the axis parameters s, t are always
 * finite (clamped with maxsd / minsd, which return the bound for NaN), so a NaN / +-inf
 * coordinate of P1 or P2 makes a coordinate of q1 = P1 + s (P2 - P1) NaN or infinite (likewise
 * P3, P4 and q2), hence |q1 - q2| and the distance; a NaN / infinite radius makes the distance
 * NaN or -inf. Tested for every coordinate (gtest CapsuleCapsule.EveryNonFiniteInputIsRejected).
 */
inline bool capsulePairValid(double distance, double r1, double r2)
{
  return std::isfinite(distance) && r1 >= 0.0 && r2 >= 0.0;
}

/**
 * Capsule-capsule core shared by capsuleCapsule() and the deliverable signature (inputs
 * already validated).
 *
 * Segment-segment: minimise |p1 + s d1 - p3 - t d2|^2 over [0,1]^2 (convex quadratic).
 * Interior stationary point from the 2x2 normal equations (denominator |d1 x d2|^2, taken from
 * the cross product when nearly parallel to avoid cancellation), clamped; then t is
 * re-optimised for s and, if t was clamped, s for t (Ericson, Real-Time Collision Detection
 * 5.1.9). The common path has no data-dependent branch (random queries mispredict them):
 * the three reciprocals are computed in parallel, the two candidates for s when t is clamped
 * (t = 0, t = 1) are computed alongside and selected with a mask, and 1 / |v| comes from
 * 1 / |v|^2, computed in parallel with the square root. Degenerate axes reduce to
 * point-segment projections.
 * @return the DistanceCode; @p normal from capsule 2 towards capsule 1
 */
SARAS_COLLISION_INLINE int capsulePair(const Eigen::Vector3d& p1, const Eigen::Vector3d& p2, double r1, const Eigen::Vector3d& p3,
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
    const double inv_denom = 1.0 / denom, inv_a = 1.0 / a, inv_e = 1.0 / e;  // in parallel
    const double s_free = parallel ? 0.0 : (b * f - c * e) * inv_denom;
    const double s_clamped = clamp01(s_free);
    const double t_free = (b * s_clamped + f) * inv_e;
    // Candidates for s when t is clamped to 0 or 1, computed in parallel with the above.
    const double s_t0 = clamp01(-c * inv_a), s_t1 = clamp01((b - c) * inv_a);
    t = clamp01(t_free);
    s = selectLess(t_free, 0.0, s_t0, selectLess(1.0, t_free, s_t1, s_clamped));
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
  const int code = classify(distance, parallel ? kParallel : kSeparated);
  if (axis2 > kMinAxis2)
    normal = v * (axis * (1.0 / axis2));  // the division overlaps the square root
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
  return code;
}

/**
 * Fast path of capsulePair() for the general case: non-degenerate axes more than ~1.8 degrees
 * from parallel (sin^2 of their angle > 1e-3, so that a e - b^2 does not cancel) whose closest
 * points do not coincide, radii >= 0. Same minimiser (Ericson 5.1.9), written for few
 * floating-point instructions and a short dependency chain (the benchmark loop overlaps about
 * two consecutive queries; the latency of the chain that ends a query sets the time more than
 * instructions off it do: README, session-12 probes).
 * The axes are taken as d1 = p1 - p2, d2 = p3 - p4 (the opposite of Ericson's p2 - p1, p4 - p3),
 * so that p2 and p4 are read once, as memory operands of the subtractions; then, with
 * w = p1 - p3, a = |d1|^2, e = |d2|^2, b = d1.d2, c = d1.w, f = d2.w, the parameters s, t of the
 * closest points p1 - s d1, p3 - t d2 minimise |w - s d1 + t d2|^2 over [0, 1]^2. Every clamp is
 * taken division-free on a numerator over a common denominator (D = a e - b^2 = |d1 x d2|^2,
 * M = a e D):
 *   sn = c e - b f (unconstrained s* = sn / D), sc = clamp(sn, 0, D);
 *   tn = b sc - f D (t re-optimised for the clamped s, times e D);
 *   tc = clamp(tn, 0, e D)                          (t = tc / (e D) = T / M, T = tc a);
 *   S = clamp(b tc + c e D, 0, M)                   (s = clamp((b t + c) / a, 0, 1) = S / M).
 * The last line is Ericson's "recompute s for the clamped t" and, when t was not clamped, it
 * gives back sc / D: either s* is interior and (s, t) is the stationary point, where
 * (b t + c) / a = s exactly, or sc is a bound and the KKT condition of the convex problem at
 * that bound (dF/ds >= 0 at s = 0, <= 0 at s = 1) puts (b t + c) / a beyond it. No selects.
 * Then one reciprocal 1 / M gives s and t, the closest axis points q1, q2 (needed for the
 * outputs anyway) and v = q1 - q2, so that the distance is |v| - r1 - r2 without a rescaling
 * (fewer instructions than forming M v from the numerators; the division overlaps the clamps);
 * 1 / |v| = sqrt(|v|^2) / |v|^2, the division overlapping the square root. M is a normal
 * number (a, e > 1e-30, D > 1e-3 a e).
 * Inputs are validated by the guard alone, after the computation (off the critical path), on the
 * bit patterns of a, e, |v|^2, D, r1 and r2 (integer compares: no floating-point instruction but
 * the moves of the bits; IEEE 754 binary64 patterns of non-negative numbers order as the numbers,
 * NaN and negative patterns, read as unsigned integers, lie above +inf's):
 *  - range: each of a, e, |v|^2, r1 and r2 below 2^238, so their sum is below 2^241 and |d1|,
 *    |d2|, |v| < 2^120.5 and, since w = v + s d1 - t d2 with s, t in [0, 1] (they come out of
 *    clamps whatever happened before), |w| < 2^122.1. Then every product above is below 2^970:
 *    no overflow, so no clamp turned an infinity into a bound and no inf - inf made a NaN that a
 *    clamp hid;
 *  - finiteness: a NaN or infinite coordinate of p1 or p2 makes a (through d1) non-finite, of
 *    p3 or p4 makes e so; a NaN, infinite or negative radius (-0 included: the careful path
 *    takes it) fails its own range test;
 *  - margins: both axes longer than 1e-15 m (a, e > 1e-30), closest axis points apart
 *    (|v|^2 > 1e-290, so that 1 / |v|^2 is finite), and D > 1e-3 a e (notNearlyParallelBits():
 *    never below 1e-3, always above 1.23e-3).
 * Lengths beyond ~1e36 m fail the range test and go to capsulePairAnyScale(), which scales.
 * @return false (outputs untouched) when the case is not general, an input is not finite, a
 *         radius is negative or not finite, or the magnitudes are outside the range above;
 *         capsulePair() (through capsulePairAnyScale()) then handles it and reports the
 *         invalid inputs. True: the outputs are valid and finite (so the caller needs no
 *         further input check).
 */
SARAS_COLLISION_INLINE bool capsulePairFast(const Eigen::Vector3d& p1, const Eigen::Vector3d& p2, double r1,
                                            const Eigen::Vector3d& p3, const Eigen::Vector3d& p4, double r2,
                                            double& distance, Eigen::Vector3d& point1, Eigen::Vector3d& point2,
                                            Eigen::Vector3d& normal)
{
  // Scalar code: GCC -O2 emits fewer instructions for it than for the Eigen 3-vector
  // expressions (and this file is compiled without SLP vectorisation, see CMakeLists.txt).
  const double p1x = p1[0], p1y = p1[1], p1z = p1[2], p3x = p3[0], p3y = p3[1], p3z = p3[2];
  const double d1x = p1x - p2[0], d1y = p1y - p2[1], d1z = p1z - p2[2];
  const double d2x = p3x - p4[0], d2y = p3y - p4[1], d2z = p3z - p4[2];
  const double wx = p1x - p3x, wy = p1y - p3y, wz = p1z - p3z;
  const double a = d1x * d1x + d1y * d1y + d1z * d1z;
  const double e = d2x * d2x + d2y * d2y + d2z * d2z;
  const double b = d1x * d2x + d1y * d2y + d1z * d2z;
  const double c = d1x * wx + d1y * wy + d1z * wz;
  const double f = d2x * wx + d2y * wy + d2z * wz;
  const double bb = b * b;
  const double denom = a * e - bb;  // |d1 x d2|^2; cancels near parallel: then capsulePair()
  const double ed = e * denom;
  const double m = a * ed;
  const double rho = 1.0 / m;  // in parallel with the clamps
  const double sn = c * e - b * f;
  const double sc = minD(maxD(sn, 0.0), denom);
  const double tn = b * sc - f * denom;
  const double tc = minD(maxD(tn, 0.0), ed);  // t = tc / (e D) = tc a / M
  const double sv = b * tc + c * ed;
  const double S = minD(maxD(sv, 0.0), m);  // s = clamp((b t + c) / a) = S / M
  // s, t in [0, 1] up to a few ulps (S <= M and T = tc a <= e D a ~ M up to rounding): no clamp,
  // the points may lie beyond an end of the axis by ~1e-16 of its length.
  const double s = S * rho, t = (tc * a) * rho;
  const double q1x = p1x - s * d1x, q1y = p1y - s * d1y, q1z = p1z - s * d1z;
  const double q2x = p3x - t * d2x, q2y = p3y - t * d2y, q2z = p3z - t * d2z;
  const double vx = q1x - q2x, vy = q1y - q2y, vz = q1z - q2z;
  const double v2 = vx * vx + vy * vy + vz * vz;
  const double rr = r1 + r2;
  // The guard (see above), on bit patterns; & rather than && so that it stays one branch.
  const std::uint64_t hi = bitsOf(kFastRange), min_axis = bitsOf(kDegenerateLength2);
  const std::uint64_t ua = bitsOf(a), ue = bitsOf(e);
  const bool general = bitsInOpenRange(ua, min_axis, hi) & bitsInOpenRange(ue, min_axis, hi) &
                       bitsInOpenRange(bitsOf(v2), bitsOf(kMinFastAxis2), hi) & (bitsOf(r1) < hi) &
                       (bitsOf(r2) < hi) & notNearlyParallelBits(ua, ue, bitsOf(denom));
  if (!general)
    return false;
  const double len = std::sqrt(v2);
  const double inv_v2 = 1.0 / v2;  // overlaps the square root
  const double dist = len - rr;
  const double inv_len = len * inv_v2;
  // Radius offsets along the normal, r_i v / |v|, zeroed (through 1 / |v|) without a branch when
  // intersecting (witness points on the axes).
  const double inv_len_or_0 = unlessIntersecting(dist, inv_len);
  const double k1 = inv_len_or_0 * r1, k2 = inv_len_or_0 * r2;
  normal = Eigen::Vector3d(vx * inv_len, vy * inv_len, vz * inv_len);
  point1 = Eigen::Vector3d(q1x - k1 * vx, q1y - k1 * vy, q1z - k1 * vz);
  point2 = Eigen::Vector3d(q2x + k2 * vx, q2y + k2 * vy, q2z + k2 * vz);
  distance = dist;
  return true;
}

/**
 * capsulePair() for any finite magnitude: when a coordinate exceeds 2^200 (~1.6e60 m) in
 * magnitude, its products (a e, |d1 x d2|^2 ~ length^4) could overflow, so the inputs are
 * scaled by a power of two (exact) to magnitudes below 1, solved, and the distance and points
 * scaled back (the problem is homogeneous; the normal is scale-free). A result that is not
 * representable (distance beyond ~1.8e308) becomes non-finite and is then rejected as invalid
 * input. Non-finite inputs are passed through unchanged (capsulePair() propagates them).
 */
int capsulePairAnyScale(const Eigen::Vector3d& p1, const Eigen::Vector3d& p2, double r1, const Eigen::Vector3d& p3,
                        const Eigen::Vector3d& p4, double r2, double& distance, Eigen::Vector3d& point1,
                        Eigen::Vector3d& point2, Eigen::Vector3d& normal)
{
  const double mag = std::max(std::max(p1.cwiseAbs().maxCoeff(), p2.cwiseAbs().maxCoeff()),
                              std::max(p3.cwiseAbs().maxCoeff(), p4.cwiseAbs().maxCoeff()));
  constexpr double kLarge = 0x1p200;
  if (!(mag > kLarge) || !(mag < std::numeric_limits<double>::infinity()))
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

/// dist_capsule_to_capsule() outside the general case (capsulePair(), then the input check).
/// Kept out of line so that the general case does not keep the inputs alive in registers or
/// on the stack for it.
#if defined(__GNUC__)
__attribute__((noinline))
#endif
int capsuleCapsuleCareful(const Eigen::Vector3d& P1, const Eigen::Vector3d& P2, const Eigen::Vector3d& P3,
                          const Eigen::Vector3d& P4, double r1, double r2, double& distance,
                          Eigen::Vector3d& point1, Eigen::Vector3d& point2)
{
  Eigen::Vector3d normal;
  const int code = capsulePairAnyScale(P1, P2, r1, P3, P4, r2, distance, point1, point2, normal);
  if (!capsulePairValid(distance, r1, r2))
    return invalidOutputs(kInvalidInput, distance, point1, point2);
  return code;
}
}  // namespace

// Segment-segment: see capsulePair().
SARAS_COLLISION_MULTIVERSION
DistanceResult capsuleCapsule(const Eigen::Vector3d& p1, const Eigen::Vector3d& p2, double r1,
                              const Eigen::Vector3d& p3, const Eigen::Vector3d& p4, double r2)
{
  DistanceResult out;
  if (capsulePairFast(p1, p2, r1, p3, p4, r2, out.distance, out.point1, out.point2, out.normal))
    out.code = classify(out.distance);
  else
    out.code = capsulePairAnyScale(p1, p2, r1, p3, p4, r2, out.distance, out.point1, out.point2, out.normal);
  if (!capsulePairValid(out.distance, r1, r2))
    return invalid(kInvalidInput);
  return out;
}

SARAS_COLLISION_MULTIVERSION
int dist_capsule_to_capsule(const Eigen::Vector3d& P1, const Eigen::Vector3d& P2, const Eigen::Vector3d& P3,
                            const Eigen::Vector3d& P4, double r1, double r2, double& distance,
                            Eigen::Vector3d& point_on_capsule1, Eigen::Vector3d& point_on_capsule2)
{
  // Inputs are checked by the fast path's guard, after the computation (off the critical
  // path); every other case, invalid inputs included, is the out-of-line careful path.
  Eigen::Vector3d normal;  // not an output of this signature
  if (!capsulePairFast(P1, P2, r1, P3, P4, r2, distance, point_on_capsule1, point_on_capsule2, normal))
    return capsuleCapsuleCareful(P1, P2, P3, P4, r1, r2, distance, point_on_capsule1, point_on_capsule2);
  return classify(distance);
}

}  // namespace saras_collision
