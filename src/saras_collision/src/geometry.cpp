// Exact capsule / sphere / box distances. See include/saras_collision/geometry.h for the
// definitions and the return codes; the derivations are summarised next to each function.
#include "saras_collision/geometry.h"

#include <Eigen/Geometry>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include <algorithm>
#include <cmath>
#include <limits>

// Hot helpers are forced inline: GCC -O2 keeps a large helper called from several places out
// of line and then passes its results through the stack.
#if defined(__GNUC__)
#define SARAS_COLLISION_INLINE inline __attribute__((always_inline))
#else
#define SARAS_COLLISION_INLINE inline
#endif

namespace saras_collision
{
namespace
{
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
/// Squared length below which a capsule axis is treated as a point [m^2] (length < 1e-15 m).
constexpr double kDegenerateLength2 = 1e-30;
/// Squared axis-to-axis distance below which the capsule-capsule normal is taken from the axes
/// directions, not from the (then meaningless) closest-point difference [m^2] (1e-100 m).
constexpr double kMinAxis2 = 1e-200;

inline bool validRadius(double r)
{
  return std::isfinite(r) && r >= 0.0;
}

/// All coordinates finite: NaN and +-inf propagate through the sum (finite values whose sum
/// overflows, > 1e307 m, are rejected too, which is intended).
inline bool allFinite(const Eigen::Vector3d& a, const Eigen::Vector3d& b)
{
  return std::isfinite((a + b).sum() + (a - b).sum());
}

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

/// The 8 vertices all finite (pairwise sum, see allFinite).
inline bool verticesFinite(const Eigen::Vector3d v[])
{
  const Eigen::Vector3d s = ((v[0] + v[1]) + (v[2] + v[3])) + ((v[4] + v[5]) + (v[6] + v[7]));
  return std::isfinite(s.sum());
}

// Branch-free min / max (minsd / maxsd): GCC -O2 turns std::min / std::max into compare-and-
// jump sequences, which random queries mispredict. Not for NaN arguments (inputs are checked).
// GCC / Clang: one instruction in inline assembly (the intrinsics' _mm_set_sd adds a movq that
// zeroes the unused upper lane to every call: ~5 % of the capsule-capsule instructions).
inline double minD(double a, double b)
{
#if defined(__SSE2__) && defined(__GNUC__)
  __asm__("minsd %1, %0" : "+x"(a) : "x"(b));  // a < b ? a : b, no zeroing of the upper lane
  return a;
#elif defined(__SSE2__)
  return _mm_cvtsd_f64(_mm_min_sd(_mm_set_sd(a), _mm_set_sd(b)));
#else
  return a < b ? a : b;
#endif
}

inline double maxD(double a, double b)
{
#if defined(__SSE2__) && defined(__GNUC__)
  __asm__("maxsd %1, %0" : "+x"(a) : "x"(b));  // a > b ? a : b
  return a;
#elif defined(__SSE2__)
  return _mm_cvtsd_f64(_mm_max_sd(_mm_set_sd(a), _mm_set_sd(b)));
#else
  return a > b ? a : b;
#endif
}

/// x < y ? if_less : otherwise, without a branch (and / andnot / or on a compare mask).
inline double selectLess(double x, double y, double if_less, double otherwise)
{
#if defined(__SSE2__)
  const __m128d mask = _mm_cmplt_sd(_mm_set_sd(x), _mm_set_sd(y));
  return _mm_cvtsd_f64(_mm_or_pd(_mm_and_pd(mask, _mm_set_sd(if_less)), _mm_andnot_pd(mask, _mm_set_sd(otherwise))));
#else
  return x < y ? if_less : otherwise;
#endif
}

inline double clamp01(double x)
{
  return minD(maxD(x, 0.0), 1.0);
}

inline double clampTo(double x, double h)
{
  return minD(maxD(x, -h), h);
}

DistanceResult invalid(int code)
{
  DistanceResult r;
  r.code = code;
  r.distance = kNaN;
  r.point1 = Eigen::Vector3d::Constant(kNaN);
  r.point2 = Eigen::Vector3d::Constant(kNaN);
  r.normal = Eigen::Vector3d::Constant(kNaN);
  return r;
}

/// Any unit vector orthogonal to a non-zero @p v.
Eigen::Vector3d anyPerpendicular(const Eigen::Vector3d& v)
{
  Eigen::Vector3d other = std::abs(v.x()) <= std::abs(v.y()) && std::abs(v.x()) <= std::abs(v.z()) ?
                              Eigen::Vector3d::UnitX() :
                              (std::abs(v.y()) <= std::abs(v.z()) ? Eigen::Vector3d::UnitY() :
                                                                    Eigen::Vector3d::UnitZ());
  return v.cross(other).normalized();
}

/// Return code of a valid signed @p distance, without branches (random queries would
/// mispredict them): kIntersecting below -tol, kTangent within +-tol, else @p separated_code
/// (kSeparated or kParallel).
inline int classify(double distance, int separated_code = kSeparated)
{
  return static_cast<int>(distance > kTangentTolerance) * separated_code -
         static_cast<int>(distance < -kTangentTolerance);
}

/// 1 if the code keeps surface points (not intersecting), else 0: selects the witness points
/// without a branch.
inline double surfaceFactor(double distance)
{
  return selectLess(distance, -kTangentTolerance, 0.0, 1.0);
}

/// Edge vectors of 8 box vertices (documented order) and their squared lengths.
struct BoxEdges
{
  Eigen::Vector3d ex, ey, ez;  ///< v1 - v0, v4 - v0, v3 - v0 [m]
  double lx2, ly2, lz2;  ///< squared edge lengths [m^2]
};

/// Edge vectors and squared lengths of 8 vertices (documented order), first part of the box test.
SARAS_COLLISION_INLINE void boxEdges(const Eigen::Vector3d v[], BoxEdges& e)
{
  const Eigen::Vector3d& v0 = v[0];
  e.ex = v[1] - v0;
  e.ey = v[4] - v0;
  e.ez = v[3] - v0;
  e.lx2 = e.ex.squaredNorm();
  e.ly2 = e.ey.squaredNorm();
  e.lz2 = e.ez.squaredNorm();
}

/// The combined test of validateBox() on edges from boxEdges(): true for a box within rt.
SARAS_COLLISION_INLINE bool boxShapePasses(const Eigen::Vector3d v[], const BoxEdges& e, double rt2)
{
  const double diag2 = e.lx2 + e.ly2 + e.lz2;
  const double tol2 = rt2 * diag2;
  const double xy = e.ex.dot(e.ey), xz = e.ex.dot(e.ez), yz = e.ey.dot(e.ez);
  const double cos2 = (xy * xy) * e.lz2 + (xz * xz) * e.ly2 + (yz * yz) * e.lx2;
  const Eigen::Array3d r2 = ((v[2] - v[3]) - e.ex).array(), r5 = ((v[5] - v[4]) - e.ex).array();
  const Eigen::Array3d r6 = ((v[6] - v[5]) - e.ez).array(), r7 = ((v[7] - v[4]) - e.ez).array();
  const double residual2 = ((r2 * r2 + r5 * r5) + (r6 * r6 + r7 * r7)).sum();
  // Bitwise & on purpose: one combined test, no branch per condition.
  return (diag2 < std::numeric_limits<double>::infinity()) & (minD(minD(e.lx2, e.ly2), e.lz2) > tol2) &
         (cos2 <= rt2 * (e.lx2 * e.ly2 * e.lz2)) & (residual2 <= tol2);
}

/// boxEdges() then boxShapePasses().
SARAS_COLLISION_INLINE bool boxTestPasses(const Eigen::Vector3d v[], double rt2, BoxEdges& e)
{
  boxEdges(v, e);
  return boxShapePasses(v, e, rt2);
}

/**
 * Checks that 8 vertices are a rectangular box in the documented order, within the relative
 * tolerance rt (@p rt2 = rt^2):
 *  - edges finite and not flat: min_i |e_i|^2 > rt^2 |diag|^2, |diag|^2 = sum_i |e_i|^2;
 *  - rectangular: sum over the 3 edge pairs of cos^2 <= rt^2, tested without division as
 *    sum (e_i.e_j)^2 |e_k|^2 <= rt^2 |e_x|^2 |e_y|^2 |e_z|^2;
 *  - order: the 4 residuals v2 - v3 - e_x, v5 - v4 - e_x, v6 - v5 - e_z, v7 - v4 - e_z (zero
 *    for a box: each is one parallel edge minus another) have a sum of squared norms
 *    <= rt^2 |diag|^2. Every vertex enters one of them.
 * Branch-free: one combined test, each written to be false on NaN, so non-finite vertices fail
 * it (an infinite edge fails the first test, then every residual with a non-finite vertex is
 * NaN or infinite); only then are the vertices scanned to tell kInvalidInput from kInvalidBox.
 * Split into boxEdges() and boxShapePasses() so that a caller can interleave its own work.
 * @return kSeparated (valid), kInvalidBox or kInvalidInput
 */
SARAS_COLLISION_INLINE int validateBox(const Eigen::Vector3d v[], double rt2, BoxEdges& e)
{
  if (boxTestPasses(v, rt2, e))
    return kSeparated;
  return verticesFinite(v) ? kInvalidBox : kInvalidInput;
}

/// Fills centre, axes and half extents of @p box from validated vertices (not the bounding
/// radius). Gram-Schmidt keeps x exact; the residual non-orthogonality is within the
/// tolerance. The handedness of the vertex order is kept.
SARAS_COLLISION_INLINE void boxFrame(const Eigen::Vector3d v[], const BoxEdges& e, OrientedBox& box)
{
  const double lx = std::sqrt(e.lx2), ly = std::sqrt(e.ly2), lz = std::sqrt(e.lz2);
  const Eigen::Vector3d x = e.ex * (1.0 / lx);
  Eigen::Vector3d y = e.ey - e.ey.dot(x) * x;
  y *= 1.0 / y.norm();
  const Eigen::Vector3d z = x.cross(y);
  box.center = 0.5 * (v[0] + v[6]);  // midpoint of the main diagonal
  box.axes.col(0) = x;
  box.axes.col(1) = y;
  box.axes.col(2) = z.dot(e.ez) < 0.0 ? Eigen::Vector3d(-z) : z;
  box.half = Eigen::Vector3d(lx, ly, lz) * 0.5;
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
 * from parallel (sin^2 > 1e-3, so that a e - b^2 does not cancel) whose closest points do not
 * coincide. Same minimiser (Ericson 5.1.9), written for a short dependency chain and few
 * instructions: every clamp is taken division-free on a numerator over the common denominator
 * M = a e D (D = a e - b^2 = |d1 x d2|^2), and the one reciprocal 1 / M runs in parallel:
 *   sn = b f - c e (unconstrained s* = sn / D), sc = clamp(sn, 0, D);
 *   tn = b sc + f D (t re-optimised for the clamped s, times e D);
 *   tc = clamp(tn, 0, e D)                          (t = tc / (e D) = T / M, T = tc a);
 *   S = clamp(b tc - c e D, 0, M)                   (s = clamp((b t - c) / a, 0, 1) = S / M).
 * The last line is Ericson's "recompute s for the clamped t" and, when t was not clamped, it
 * gives back sc / D: either s* is interior and (s, t) is the stationary point, where
 * (b t - c) / a = s exactly, or sc is a bound and the KKT condition of the convex problem at
 * that bound (dF/ds >= 0 at s = 0, <= 0 at s = 1) puts (b t - c) / a beyond it. No selects.
 * The axis difference scaled by M, V = M w + S d1 - T d2 = M (q1 - q2), is formed without
 * waiting for the division, so the square root of |V|^2 starts early; |q1 - q2| = |V| / M and
 * the unit normal V / |V| (1 / |V| = sqrt(|V|^2) / |V|^2, the division overlapping the square
 * root). M is a normal number (a, e > 1e-30, D > 1e-3 a e) and |V|^2 is required to be one.
 * @return false (outputs untouched) when the case is not general, an input is not finite or a
 *         product overflows or underflows (every comparison below is false on NaN);
 *         capsulePair() (through capsulePairAnyScale()) then handles it.
 */
SARAS_COLLISION_INLINE bool capsulePairFast(const Eigen::Vector3d& p1, const Eigen::Vector3d& p2, double r1,
                                            const Eigen::Vector3d& p3, const Eigen::Vector3d& p4, double r2,
                                            double& distance, Eigen::Vector3d& point1, Eigen::Vector3d& point2,
                                            Eigen::Vector3d& normal)
{
  // Scalar code: GCC -O2 emits fewer instructions for it than for the Eigen 3-vector
  // expressions.
  constexpr double kInf = std::numeric_limits<double>::infinity();
  const double p1x = p1[0], p1y = p1[1], p1z = p1[2], p3x = p3[0], p3y = p3[1], p3z = p3[2];
  const double d1x = p2[0] - p1x, d1y = p2[1] - p1y, d1z = p2[2] - p1z;
  const double d2x = p4[0] - p3x, d2y = p4[1] - p3y, d2z = p4[2] - p3z;
  const double wx = p1x - p3x, wy = p1y - p3y, wz = p1z - p3z;
  const double a = d1x * d1x + d1y * d1y + d1z * d1z;
  const double e = d2x * d2x + d2y * d2y + d2z * d2z;
  const double b = d1x * d2x + d1y * d2y + d1z * d2z;
  const double c = d1x * wx + d1y * wy + d1z * wz;
  const double f = d2x * wx + d2y * wy + d2z * wz;
  const double ae = a * e;
  const double denom = ae - b * b;  // |d1 x d2|^2; cancels near parallel: then capsulePair()
  const double ed = e * denom;
  const double m = ae * denom;
  const double sn = b * f - c * e;
  const double sc = minD(maxD(sn, 0.0), denom);
  const double tn = b * sc + f * denom;
  const double rho = 1.0 / m;  // in parallel with everything up to the square root
  const double tc = minD(maxD(tn, 0.0), ed);  // t = tc / (e D) = tc a / M
  const double T = tc * a;
  const double sv = b * tc - c * ed;
  const double S = minD(maxD(sv, 0.0), m);  // s = clamp((b t - c) / a) = S / M
  const double vx = (m * wx + S * d1x) - T * d2x;
  const double vy = (m * wy + S * d1y) - T * d2y;
  const double vz = (m * wz + S * d1z) - T * d2z;
  const double v2 = vx * vx + vy * vy + vz * vz;
  // One predictable branch for every special case (each test is false on NaN; sn, tn, sv
  // finite: no product overflowed, so no clamp above turned an overflow into a number; an
  // overflow in V makes |V|^2 infinite).
  if (!((minD(a, e) > kDegenerateLength2) & (denom > 1e-3 * ae) & (m < kInf) &
        ((std::abs(sn) + std::abs(tn)) + std::abs(sv) < kInf) & (v2 > 1e-290) & (v2 < kInf)))
    return false;
  const double len = std::sqrt(v2);
  const double inv_v2 = 1.0 / v2;  // overlaps the square root, as do the next products
  const double rr = r1 + r2, r1_v2 = r1 * inv_v2, r2_v2 = r2 * inv_v2;
  const double dist = len * rho - rr;
  const double inv_len = len * inv_v2;
  // Radius offsets along the normal, r_i V / |V| = V (len r_i / |V|^2), zeroed without a
  // multiplication when intersecting (witness points on the axes).
  const double k1 = selectLess(dist, -kTangentTolerance, 0.0, len * r1_v2);
  const double k2 = selectLess(dist, -kTangentTolerance, 0.0, len * r2_v2);
  const double s = clamp01(S * rho), t = clamp01(T * rho);
  normal = Eigen::Vector3d(vx * inv_len, vy * inv_len, vz * inv_len);
  point1 = Eigen::Vector3d((p1x + s * d1x) - k1 * vx, (p1y + s * d1y) - k1 * vy, (p1z + s * d1z) - k1 * vz);
  point2 = Eigen::Vector3d((p3x + t * d2x) + k2 * vx, (p3y + t * d2y) + k2 * vy, (p3z + t * d2z) + k2 * vz);
  distance = dist;
  return true;
}

/// Writes the error outputs of the deliverable signatures (NaN distance and points).
inline int invalidOutputs(int code, double& distance, Eigen::Vector3d& point1, Eigen::Vector3d& point2)
{
  distance = kNaN;
  point1 = Eigen::Vector3d::Constant(kNaN);
  point2 = Eigen::Vector3d::Constant(kNaN);
  return code;
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

/// min over t in [0,1] of G(t) = max_i(|a_i + t d_i| - h_i) (see capsuleBox), with its argmin.
/// @param t_hint an extra candidate
double minimumDepth(const Eigen::Vector3d& a, const Eigen::Vector3d& d, const Eigen::Vector3d& h, double t_hint,
                    double* argmin = nullptr)
{
  auto depth = [&](double tt) {
    double g = -std::numeric_limits<double>::infinity();
    for (int i = 0; i < 3; ++i)
      g = std::max(g, std::abs(a[i] + tt * d[i]) - h[i]);
    return g;
  };
  double best_t = 0.0, best = depth(0.0);
  auto consider = [&](double tt) {
    if (!(tt >= 0.0 && tt <= 1.0))
      return;
    const double g = depth(tt);
    if (g < best)
    {
      best = g;
      best_t = tt;
    }
  };
  consider(1.0);
  consider(t_hint);
  // Pieces: sigma * (a_i + t d_i) - h_i, for i in {0,1,2}, sigma in {+1,-1}; the minimum of
  // their maximum is at an end-point or at a crossing of two pieces.
  for (int p = 0; p < 6; ++p)
  {
    const int i = p / 2;
    const double si = p % 2 == 0 ? 1.0 : -1.0;
    for (int q = p + 1; q < 6; ++q)
    {
      const int j = q / 2;
      const double sj = q % 2 == 0 ? 1.0 : -1.0;
      const double den = si * d[i] - sj * d[j];
      if (den == 0.0)
        continue;
      consider((h[i] - h[j] - si * a[i] + sj * a[j]) / den);
    }
  }
  if (argmin != nullptr)
    *argmin = best_t;
  return best;
}
}  // namespace

const char* codeName(int code)
{
  switch (code)
  {
    case kInvalidInput:
      return "invalid_input";
    case kInvalidBox:
      return "invalid_box";
    case kIntersecting:
      return "intersecting";
    case kTangent:
      return "tangent";
    case kSeparated:
      return "separated";
    case kParallel:
      return "parallel";
    default:
      return "unknown";
  }
}

int makeBox(const Eigen::Vector3d vertices[], double relative_tolerance, OrientedBox& box)
{
  if (!verticesFinite(vertices))
    return kInvalidInput;
  if (!(relative_tolerance >= 0.0) || !std::isfinite(relative_tolerance))
    return kInvalidInput;
  BoxEdges e;
  const int code = validateBox(vertices, relative_tolerance * relative_tolerance, e);
  if (code != kSeparated)
    return code;
  boxFrame(vertices, e, box);
  box.bounding_radius = box.half.norm();
  return kSeparated;
}

void boxVertices(const OrientedBox& box, Eigen::Vector3d vertices[])
{
  const Eigen::Vector3d x = box.axes.col(0) * (2.0 * box.half.x());
  const Eigen::Vector3d y = box.axes.col(1) * (2.0 * box.half.y());
  const Eigen::Vector3d z = box.axes.col(2) * (2.0 * box.half.z());
  const Eigen::Vector3d v0 = box.center - 0.5 * (x + y + z);
  vertices[0] = v0;
  vertices[1] = v0 + x;
  vertices[2] = v0 + x + z;
  vertices[3] = v0 + z;
  vertices[4] = v0 + y;
  vertices[5] = v0 + x + y;
  vertices[6] = v0 + x + y + z;
  vertices[7] = v0 + y + z;
}

// Segment-segment: see capsulePair().
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

// Capsule-box, in the box frame (centre c, axes R, half extents h). With x(t) = a + t d the
// axis in box coordinates, the squared axis-box distance is
//   F(t) = sum_i phi_i(x_i(t)),  phi_i(u) = (|u| - h_i)_+^2,
// convex, C1 and piecewise quadratic; F'(t)/2 = sum_i d_i (x_i - clamp(x_i, -h_i, h_i)) is
// continuous, non-decreasing and piecewise linear with breakpoints where x_i(t) = +-h_i.
// Walking the (at most 6) sorted breakpoints locates the zero of F' exactly by linear
// interpolation inside one piece. If the axis reaches the box (F = 0), the signed distance
// uses G(t) = max_i(|x_i(t)| - h_i), which equals the box's signed distance function where it
// is <= 0; G is convex piecewise linear, so its minimum on [0,1] is at an end-point or at a
// crossing of two of its 6 linear pieces (kinks of |.| included).
namespace
{
/// capsuleBox() without the input checks (inputs finite, r >= 0).
DistanceResult capsuleBoxChecked(const Eigen::Vector3d& p1, const Eigen::Vector3d& p2, double r,
                                 const OrientedBox& box)
{
  const Eigen::Matrix3d& R = box.axes;
  const Eigen::Vector3d& h = box.half;
  const Eigen::Vector3d a = R.transpose() * (p1 - box.center);
  if (p1 == p2)
  {
    // Sphere: closest box point = clamped centre (the general path below gives the same).
    const Eigen::Vector3d q(clampTo(a[0], h[0]), clampTo(a[1], h[1]), clampTo(a[2], h[2]));
    const Eigen::Vector3d v = a - q;
    const double axis2 = v.squaredNorm();
    // Centre outside the box (inside: the general path, whose depth walk reduces to the
    // nearest face for d = 0).
    if (axis2 > 0.0)
    {
      const double axis = std::sqrt(axis2);
      DistanceResult out;
      out.distance = axis - r;
      out.code = classify(out.distance);
      const Eigen::Vector3d v_world = R * v;
      out.normal = v_world * (1.0 / axis);
      out.point2 = p1 - v_world;
      out.point1 = p1 - (surfaceFactor(out.distance) * r) * out.normal;
      return out;
    }
  }
  const Eigen::Vector3d d = R.transpose() * (p2 - p1);  // exactly zero for a sphere

  auto slope = [&](double t) {
    double g = 0.0;
    for (int i = 0; i < 3; ++i)
    {
      const double x = a[i] + t * d[i];
      g += d[i] * (x - clampTo(x, h[i]));
    }
    return g;
  };

  double t = 0.0;
  const double g0 = d.isZero(0.0) ? 0.0 : slope(0.0);  // sphere: t = 0
  if (g0 < 0.0)
  {
    const double g1 = slope(1.0);
    if (g1 <= 0.0)
    {
      t = 1.0;
    }
    else
    {
      double bp[7];
      int n = 0;
      for (int i = 0; i < 3; ++i)
      {
        if (d[i] == 0.0)
          continue;
        const double ta = (-h[i] - a[i]) / d[i];
        const double tb = (h[i] - a[i]) / d[i];
        if (ta > 0.0 && ta < 1.0)
          bp[n++] = ta;
        if (tb > 0.0 && tb < 1.0)
          bp[n++] = tb;
      }
      for (int i = 1; i < n; ++i)  // insertion sort of <= 6 values
      {
        const double key = bp[i];
        int j = i - 1;
        for (; j >= 0 && bp[j] > key; --j)
          bp[j + 1] = bp[j];
        bp[j + 1] = key;
      }
      bp[n++] = 1.0;
      double t_prev = 0.0, g_prev = g0;
      t = 1.0;
      for (int k = 0; k < n; ++k)
      {
        const double g = k + 1 == n ? g1 : slope(bp[k]);
        if (g >= 0.0)
        {
          t = t_prev + (-g_prev) * (bp[k] - t_prev) / (g - g_prev);
          t = std::min(std::max(t, t_prev), bp[k]);
          break;
        }
        t_prev = bp[k];
        g_prev = g;
      }
    }
  }

  DistanceResult out;
  Eigen::Vector3d x = a + t * d;
  Eigen::Vector3d q(clampTo(x[0], h[0]), clampTo(x[1], h[1]), clampTo(x[2], h[2]));
  const Eigen::Vector3d v = x - q;
  const double axis = v.norm();
  // Entering the box leaves x(t*) on its boundary up to rounding: below the tangent tolerance
  // the depth computation below decides (it returns >= 0 only if the axis merely touches).
  if (axis > kTangentTolerance || (axis > 0.0 && minimumDepth(a, d, h, t) >= 0.0))
  {
    out.distance = axis - r;
    out.code = classify(out.distance);
    const Eigen::Vector3d v_world = R * v;  // axis point - box point, world
    out.normal = v_world * (1.0 / axis);
    const Eigen::Vector3d axis_point = p1 + t * (p2 - p1);
    out.point2 = axis_point - v_world;
    out.point1 = axis_point - (surfaceFactor(out.distance) * r) * out.normal;
    return out;
  }

  // The axis reaches the box.
  double best_t = t;
  const double best = minimumDepth(a, d, h, t, &best_t);
  x = a + best_t * d;
  const Eigen::Vector3d axis_point = p1 + best_t * (p2 - p1);
  out.distance = std::min(best, 0.0) - r;
  out.code = classify(out.distance);
  int face = 0;
  double face_g = std::abs(x[0]) - h[0];
  for (int i = 1; i < 3; ++i)
  {
    const double g = std::abs(x[i]) - h[i];
    if (g > face_g)
    {
      face_g = g;
      face = i;
    }
  }
  const double sign = x[face] < 0.0 ? -1.0 : 1.0;
  out.normal = R.col(face) * sign;
  if (out.code == kIntersecting)
  {
    Eigen::Vector3d on_face = x;
    on_face[face] = sign * h[face];
    out.point1 = axis_point;
    out.point2 = box.center + R * on_face;
  }
  else
  {
    out.point1 = axis_point;  // tangent: zero radius axis touching the box
    out.point2 = axis_point;
  }
  return out;
}

}  // namespace

DistanceResult capsuleBox(const Eigen::Vector3d& p1, const Eigen::Vector3d& p2, double r, const OrientedBox& box)
{
  if (!allFinite(p1, p2) || !validRadius(r))
    return invalid(kInvalidInput);
  return capsuleBoxChecked(p1, p2, r, box);
}

int dist_capsule_to_capsule(const Eigen::Vector3d& P1, const Eigen::Vector3d& P2, const Eigen::Vector3d& P3,
                            const Eigen::Vector3d& P4, double r1, double r2, double& distance,
                            Eigen::Vector3d& point_on_capsule1, Eigen::Vector3d& point_on_capsule2)
{
  // Inputs are checked after the computation (see capsulePairValid), off the critical path.
  Eigen::Vector3d normal;  // not an output of this signature
  if (!capsulePairFast(P1, P2, r1, P3, P4, r2, distance, point_on_capsule1, point_on_capsule2, normal))
    return capsuleCapsuleCareful(P1, P2, P3, P4, r1, r2, distance, point_on_capsule1, point_on_capsule2);
  if (!capsulePairValid(distance, r1, r2))
    return invalidOutputs(kInvalidInput, distance, point_on_capsule1, point_on_capsule2);
  return classify(distance);
}

// The box is validated (branch-free fast path) and its frame built on every call; the query is
// then capsuleBox(). Prebuild an OrientedBox with makeBox() for repeated queries.
int dist_capsule_to_parallelepiped(const Eigen::Vector3d& p1, const Eigen::Vector3d& p2,
                                   const Eigen::Vector3d vertices[], double r, double& distance,
                                   Eigen::Vector3d& point_on_capsule, Eigen::Vector3d& point_on_parall)
{
  if (vertices == nullptr || !allFinite(p1, p2) || !validRadius(r))
    return invalidOutputs(kInvalidInput, distance, point_on_capsule, point_on_parall);
  BoxEdges e;
  const int valid = validateBox(vertices, kBoxRelativeTolerance * kBoxRelativeTolerance, e);
  if (valid != kSeparated)
    return invalidOutputs(valid, distance, point_on_capsule, point_on_parall);
  OrientedBox box;
  boxFrame(vertices, e, box);
  const DistanceResult res = capsuleBoxChecked(p1, p2, r, box);
  distance = res.distance;
  point_on_capsule = res.point1;
  point_on_parall = res.point2;
  return res.code;
}

// Sphere-box directly in the (validated) vertex frame, without building an orthonormal frame:
// with e_i the edge vectors from v0 and u_i = (s - v0).e_i, the centre's coordinates along the
// edges are u_i / |e_i|^2 in [0, 1] inside the box; the closest box point clamps u_i to
// [0, |e_i|^2] (Ericson 5.1.4), and s minus it is sum_i (u_i - clamp(u_i)) / |e_i|^2 e_i.
// Only a centre inside the box needs the edge lengths (depth to the nearest face).
namespace
{
/// dist_sphere_to_parallelepiped() in every case (invalid input, invalid box, centre inside or
/// on the box), out of line: the common case below does not keep its values alive.
#if defined(__GNUC__)
__attribute__((noinline))
#endif
int sphereBoxCareful(const Eigen::Vector3d& s, const Eigen::Vector3d vertices[], double r, double& distance,
                     Eigen::Vector3d& point_on_sphere, Eigen::Vector3d& point_on_parall)
{
  if (vertices == nullptr || !std::isfinite(s.sum() + r) || !(r >= 0.0))
    return invalidOutputs(kInvalidInput, distance, point_on_sphere, point_on_parall);
  BoxEdges e;
  const int valid = validateBox(vertices, kBoxRelativeTolerance * kBoxRelativeTolerance, e);
  if (valid != kSeparated)
    return invalidOutputs(valid, distance, point_on_sphere, point_on_parall);
  const Eigen::Vector3d w = s - vertices[0];
  const double ux = w.dot(e.ex), uy = w.dot(e.ey), uz = w.dot(e.ez);
  const double cx = minD(maxD(ux, 0.0), e.lx2);
  const double cy = minD(maxD(uy, 0.0), e.ly2);
  const double cz = minD(maxD(uz, 0.0), e.lz2);
  // Centre minus closest box point, world [m]. The reciprocals depend only on the edges, so
  // they are ready before the projections (off the dependency chain).
  const double ix = 1.0 / e.lx2, iy = 1.0 / e.ly2, iz = 1.0 / e.lz2;
  const Eigen::Vector3d off = ((ux - cx) * ix) * e.ex + ((uy - cy) * iy) * e.ey + ((uz - cz) * iz) * e.ez;
  const double axis2 = off.squaredNorm();
  // Squared distance overflowed (centre beyond ~1e154 m from the box): not a number to use.
  if (!(axis2 < std::numeric_limits<double>::infinity()))
    return invalidOutputs(kInvalidInput, distance, point_on_sphere, point_on_parall);
  if (axis2 > kMinAxis2)  // centre outside the box (by more than 1e-100 m)
  {
    const double axis = std::sqrt(axis2);
    const double dist = axis - r;
    const double scale = surfaceFactor(dist) * r * (axis * (1.0 / axis2));  // division overlaps the sqrt
    distance = dist;
    point_on_parall = s - off;
    point_on_sphere = s - scale * off;
    return classify(dist);
  }
  // Centre inside (or on the surface): depth to the nearest face, min_i min(u_i, l_i^2 - u_i) / l_i.
  const double l2[3] = { e.lx2, e.ly2, e.lz2 };
  const double u[3] = { ux, uy, uz };
  const Eigen::Vector3d* edge[3] = { &e.ex, &e.ey, &e.ez };
  int face = 0;
  double depth = std::numeric_limits<double>::infinity(), sign = 1.0, length = 1.0;
  for (int i = 0; i < 3; ++i)
  {
    const double l = std::sqrt(l2[i]);
    const double high = l2[i] - u[i];  // towards the face at v0 + e_i
    const double di = std::min(u[i], high) / l;
    if (di < depth)
    {
      depth = di;
      face = i;
      sign = high <= u[i] ? 1.0 : -1.0;
      length = l;
    }
  }
  distance = -depth - r;
  const Eigen::Vector3d normal = *edge[face] * (sign / length);
  point_on_sphere = s;
  point_on_parall = s + ((1.0 - surfaceFactor(distance)) * depth) * normal;  // tangent: s
  return classify(distance);
}

}  // namespace

// Common case (valid inputs and box, centre outside the box) with one predictable branch; the
// box test and the projection are independent, so they overlap. Everything else is
// sphereBoxCareful(), which recomputes from the inputs.
int dist_sphere_to_parallelepiped(const Eigen::Vector3d& s, const Eigen::Vector3d vertices[], double r,
                                  double& distance, Eigen::Vector3d& point_on_sphere,
                                  Eigen::Vector3d& point_on_parall)
{
  if (vertices == nullptr)
    return invalidOutputs(kInvalidInput, distance, point_on_sphere, point_on_parall);
  BoxEdges e;
  boxEdges(vertices, e);
  const Eigen::Vector3d w = s - vertices[0];
  const double ux = w.dot(e.ex), uy = w.dot(e.ey), uz = w.dot(e.ez);
  const double cx = minD(maxD(ux, 0.0), e.lx2);
  const double cy = minD(maxD(uy, 0.0), e.ly2);
  const double cz = minD(maxD(uz, 0.0), e.lz2);
  const double ix = 1.0 / e.lx2, iy = 1.0 / e.ly2, iz = 1.0 / e.lz2;
  const Eigen::Vector3d off = ((ux - cx) * ix) * e.ex + ((uy - cy) * iy) * e.ey + ((uz - cz) * iz) * e.ez;
  const double axis2 = off.squaredNorm();
  // The rest of the box test after the projection (fewer values alive at once). Each test is
  // false on NaN. A non-finite centre coordinate s_j makes axis2 NaN: every u_i is NaN or
  // +-inf (w.e_i with w_j infinite: inf * 0 = NaN when e_ij = 0), so is u_i - c_i (c_i is
  // finite), and a component k != j of off sums +-inf terms of both signs (the products
  // e_ij e_ik of orthogonal edges have both signs), inf - inf = NaN (gtest
  // Box.FastValidationRejectsEveryBadVertexWithItsCode sets each coordinate to NaN / +-inf).
  // axis2 < inf also sends an overflow (centre beyond ~1e154 m) to the out-of-line path.
  const bool box_ok = boxShapePasses(vertices, e, kBoxRelativeTolerance * kBoxRelativeTolerance);
  constexpr double kInf = std::numeric_limits<double>::infinity();
  if (!(box_ok & (axis2 > kMinAxis2) & (axis2 < kInf) & (r >= 0.0) & (r < kInf)))
    return sphereBoxCareful(s, vertices, r, distance, point_on_sphere, point_on_parall);
  const double axis = std::sqrt(axis2);
  const double dist = axis - r;
  const double scale = surfaceFactor(dist) * r * (axis * (1.0 / axis2));  // division overlaps the sqrt
  distance = dist;
  point_on_parall = s - off;
  point_on_sphere = s - scale * off;
  return classify(dist);
}

}  // namespace saras_collision
