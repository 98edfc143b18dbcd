// Private header of the saras_collision library (not installed): the branch-free helpers and
// build macros shared by geometry.cpp (boxes) and capsule_capsule.cpp. ROS-agnostic.
#ifndef SARAS_COLLISION_SRC_GEOMETRY_DETAIL_H
#define SARAS_COLLISION_SRC_GEOMETRY_DETAIL_H

#include "saras_collision/geometry.h"

#include <Eigen/Geometry>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>

// Hot helpers are forced inline: GCC -O2 keeps a large helper called from several places out
// of line and then passes its results through the stack.
#if defined(__GNUC__)
#define SARAS_COLLISION_INLINE inline __attribute__((always_inline))
#else
#define SARAS_COLLISION_INLINE inline
#endif

// Function multiversioning of the exported distance functions (GCC >= 12 on x86-64 ELF):
// clones for x86-64-v4 (AVX-512: 32 vector registers, so the capsule-capsule code keeps every
// value in a register; measured 15.6 instead of 16.7 ns per query on a Zen 4), x86-64-v3 (AVX2,
// FMA: fused multiply-adds, three-operand VEX code, fewer instructions) and the baseline x86-64
// the distribution builds for; the dynamic loader picks one once, through an ifunc (calls then
// cost the same as any exported function's). The hot paths are forced inline into each clone,
// so each clone has its own code for them. Results of the clones differ only by rounding (fused
// multiply-adds), within the tests' tolerances on any; the clones of functions compared bit for
// bit by the tests (capsuleCapsule and dist_capsule_to_capsule) run the same code on a given
// machine. So that every clone's code is tested on a machine whose loader picks another: define
// SARAS_COLLISION_NO_MULTIVERSION to build the baseline code alone (the gtest
// saras_collision_test_geometry_baseline does), SARAS_COLLISION_NO_V4_CLONE to build the same
// clones without the x86-64-v4 one (saras_collision_test_geometry_v3 does: on an AVX-512 machine
// its loader then picks the x86-64-v3 clone, compiled exactly as in the library).
#if defined(__GNUC__) && !defined(__clang__) && __GNUC__ >= 12 && defined(__x86_64__) && defined(__ELF__) && \
    !defined(SARAS_COLLISION_NO_MULTIVERSION)
#if defined(SARAS_COLLISION_NO_V4_CLONE)
#define SARAS_COLLISION_MULTIVERSION __attribute__((target_clones("arch=x86-64-v3", "default")))
#else
#define SARAS_COLLISION_MULTIVERSION __attribute__((target_clones("arch=x86-64-v4", "arch=x86-64-v3", "default")))
#endif
// minD / maxD below then use GCC's "%v" / "%d" asm operand forms, which print the VEX
// three-operand encoding in the AVX clones and the SSE2 one in the baseline clone: legacy SSE
// instructions inside AVX code can cost a state transition (measured here: a sphere-box query
// with 256-bit code and legacy minsd took 150 ns instead of 25 ns). Their "v" constraint lets
// the AVX-512 clone use xmm16-31 (the assembler then emits the EVEX form); elsewhere it means
// xmm0-15, as "x".
#define SARAS_COLLISION_VEX_ASM 1
#else
#define SARAS_COLLISION_MULTIVERSION
#endif

namespace saras_collision
{
namespace detail
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

/// The IEEE 754 binary64 bit pattern of @p x (for integer compares that cost no floating-point
/// instruction; see classify()).
inline std::uint64_t bitsOf(double x)
{
  std::uint64_t bits;
  std::memcpy(&bits, &x, sizeof bits);
  return bits;
}

/// lo < x < hi for the bit patterns of doubles lo < hi, both non-negative and finite, and any x
/// (false for NaN, negative x and -0), in one unsigned compare: IEEE 754 binary64 patterns of
/// non-negative numbers order as the numbers, and those of NaN and negative numbers, read as
/// unsigned integers, lie above +inf's.
inline bool bitsInOpenRange(std::uint64_t x, std::uint64_t lo, std::uint64_t hi)
{
  return x - lo - 1 < hi - lo - 1;
}

/// Bit-pattern distance of the test in notNearlyParallelBits(): 9.75 * 2^52.
constexpr std::uint64_t kNearlyParallelBits = std::uint64_t{ 39 } << 50;

/**
 * A sufficient test of d > 1e-3 a e on the bit patterns of a, e > 0 (normal, a e not
 * overflowing) and of any d, in integer operations only. bits / 2^52 - 1023 is a piecewise-linear
 * log2 at most 0.0861 below log2 (x = 2^k (1 + m), m in [0, 1): log2(1 + m) - m <= 0.0861), so
 * bits(d) - bits(a) - bits(e) + bits(1) > -9.75 * 2^52 implies
 * log2(d / (a e)) > -9.75 - 2 * 0.0861 > log2(1e-3); conversely every d / (a e) above
 * 2^(-9.75 + 0.0861) = 1.23e-3 passes. A d <= 0 (or NaN with the sign bit) has a negative
 * pattern as a signed integer and fails. Used by the capsule-capsule fast path to stay away from
 * (nearly) parallel axes, where a e - b^2 cancels.
 */
inline bool notNearlyParallelBits(std::uint64_t a, std::uint64_t e, std::uint64_t d)
{
  const auto bound = static_cast<std::int64_t>(a + e - bitsOf(1.0) - kNearlyParallelBits);
  return static_cast<std::int64_t>(d) > bound;
}

// Branch-free min / max (minsd / maxsd): GCC -O2 turns std::min / std::max into compare-and-
// jump sequences, which random queries mispredict. Not for NaN arguments (inputs are checked).
// GCC / Clang: one instruction in inline assembly (the intrinsics' _mm_set_sd adds a movq that
// zeroes the unused upper lane to every call: ~5 % of the capsule-capsule instructions).
inline double minD(double a, double b)
{
#if defined(SARAS_COLLISION_VEX_ASM)
  __asm__("%vminsd %1, %d0" : "+v"(a) : "v"(b));  // a < b ? a : b; VEX / EVEX in the AVX clones
  return a;
#elif defined(__SSE2__) && defined(__GNUC__)
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
#if defined(SARAS_COLLISION_VEX_ASM)
  __asm__("%vmaxsd %1, %d0" : "+v"(a) : "v"(b));  // a > b ? a : b
  return a;
#elif defined(__SSE2__) && defined(__GNUC__)
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

/**
 * x < *limit ? +0.0 : value, without a branch: a register copy of x (vmovapd, which the CPU
 * eliminates at register renaming), cmpltsd and andnpd, without the copies and zeroed upper
 * lanes that the compiler adds to selectLess(). @p limit is read from memory (no register for
 * it). A NaN x gives value (the comparison is false).
 */
inline double zeroIfLess(double x, const double* limit, double value)
{
#if defined(SARAS_COLLISION_VEX_ASM)
  double out;
  // The output is "x" (xmm0-15), not "v": in AVX-512 code a compare into xmm16-31 has no encoding
  // (EVEX compares write mask registers), so "v" assembled only while the register allocator
  // happened to pick a low register.
  __asm__("%vmovapd %1, %0\n\t%vcmpltsd %2, %d0\n\t%vandnpd %3, %d0" : "=&x"(out) : "v"(x), "m"(*limit), "v"(value));
  return out;
#elif defined(__SSE2__) && defined(__GNUC__)
  double out;
  __asm__("movapd %1, %0\n\tcmpltsd %2, %0\n\tandnpd %3, %0" : "=&x"(out) : "x"(x), "m"(*limit), "x"(value));
  return out;
#else
  return x < *limit ? 0.0 : value;
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

inline DistanceResult invalid(int code)
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
inline Eigen::Vector3d anyPerpendicular(const Eigen::Vector3d& v)
{
  Eigen::Vector3d other = std::abs(v.x()) <= std::abs(v.y()) && std::abs(v.x()) <= std::abs(v.z()) ?
                              Eigen::Vector3d::UnitX() :
                              (std::abs(v.y()) <= std::abs(v.z()) ? Eigen::Vector3d::UnitY() :
                                                                    Eigen::Vector3d::UnitZ());
  return v.cross(other).normalized();
}

/**
 * Return code of a signed @p distance, without branches (random queries would mispredict them):
 * kIntersecting below -tol, kTangent within +-tol, else @p separated_code (kSeparated or
 * kParallel); 0 for NaN, as the floating-point comparisons (distance > tol) - (distance < -tol).
 * Computed by integer compares of the bit pattern (IEEE 754 binary64: non-negative doubles order
 * as their patterns read as signed integers, negative ones in reverse order as unsigned
 * integers; NaN patterns lie beyond the infinities'), so that it costs no floating-point
 * instruction but the move of the bits (capsule-capsule 15.6 -> 15.1 ns in the benchmark when
 * it replaced the floating-point compares). Same result as the
 * floating-point form for every double (checked for both switches to the ulp by the gtest
 * CapsuleCapsule.WitnessPointsAndCodeSwitchAtTheTangentBand).
 */
inline int classify(double distance, int separated_code = kSeparated)
{
  static_assert(kTangentTolerance == 1e-9, "kToleranceBits must be the bit pattern of kTangentTolerance");
  constexpr std::uint64_t kToleranceBits = 0x3e112e0be826d695;  // 1e-9
  constexpr std::uint64_t kInfinityBits = 0x7ff0000000000000;
  constexpr std::uint64_t kSignBit = std::uint64_t{ 1 } << 63;
  const std::uint64_t bits = bitsOf(distance);
  const auto positive = static_cast<std::int64_t>(bits);  // < 0 for every negative pattern
  const bool above = positive > static_cast<std::int64_t>(kToleranceBits) &&
                     positive <= static_cast<std::int64_t>(kInfinityBits);
  const bool below = bits > (kToleranceBits | kSignBit) && bits <= (kInfinityBits | kSignBit);
  return static_cast<int>(above) * separated_code - static_cast<int>(below);
}

/**
 * The witness-point switch of every distance function: @p value unless the signed @p distance
 * is intersecting (below -kTangentTolerance, exactly where classify() says kIntersecting), then
 * +0; without a branch. NaN: @p value, as the comparison is false.
 */
inline double unlessIntersecting(double distance, double value)
{
  static const double kMinusTangentTolerance = -kTangentTolerance;  // a memory operand
  return zeroIfLess(distance, &kMinusTangentTolerance, value);
}

/// 1 if the code keeps surface points (not intersecting), else 0 (unlessIntersecting()).
inline double surfaceFactor(double distance)
{
  return unlessIntersecting(distance, 1.0);
}

/// Writes the error outputs of the deliverable signatures (NaN distance and points).
inline int invalidOutputs(int code, double& distance, Eigen::Vector3d& point1, Eigen::Vector3d& point2)
{
  distance = kNaN;
  point1 = Eigen::Vector3d::Constant(kNaN);
  point2 = Eigen::Vector3d::Constant(kNaN);
  return code;
}
}  // namespace detail
}  // namespace saras_collision

#endif  // SARAS_COLLISION_SRC_GEOMETRY_DETAIL_H
