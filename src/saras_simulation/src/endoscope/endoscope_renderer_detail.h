/**
 * @file endoscope_renderer_detail.h
 * @brief Internals shared by the renderer's translation units (endoscope_renderer*.cpp): the
 *        multiversioning attributes, the profiling clock, bilinear height-map samplers and the
 *        tissue depth at a full-resolution pixel. Not installed.
 */
#ifndef SARAS_SIMULATION_ENDOSCOPE_RENDERER_DETAIL_H
#define SARAS_SIMULATION_ENDOSCOPE_RENDERER_DETAIL_H

#include <algorithm>
#include <ctime>
#include <limits>

#include "saras_simulation/endoscope_renderer.h"

// The hot per-pixel loops (tissue solve + shading, bone ray casting) are multiversioned with GCC's
// target_clones: an x86-64-v3 clone (AVX2 + FMA, 8-wide float, gathers) and the baseline x86-64
// one, chosen once at load time (ifunc), as saras_collision's geometry. Debian builds for the
// baseline; -DSARAS_ENDOSCOPE_NO_MULTIVERSION builds the baseline code alone.
#if defined(__GNUC__) && !defined(__clang__) && __GNUC__ >= 12 && defined(__x86_64__) && defined(__ELF__) && \
    !defined(SARAS_ENDOSCOPE_NO_MULTIVERSION)
#define SARAS_ENDOSCOPE_MULTIVERSION __attribute__((target_clones("arch=x86-64-v3", "default")))
// a lambda of a multiversioned function, inlined into each clone (an out-of-line lambda would be
// compiled for the baseline only)
#define SARAS_ENDOSCOPE_CLONE_INLINE __attribute__((always_inline))
#else
#define SARAS_ENDOSCOPE_MULTIVERSION
#define SARAS_ENDOSCOPE_CLONE_INLINE
#endif

namespace saras_simulation
{
namespace endoscope
{
namespace detail
{
/// CPU time of the calling thread (profiling: independent of the other processes' load).
struct Clock
{
  using time_point = double;  ///< [ms]
  static time_point now()
  {
    timespec ts;
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
    return 1e3 * ts.tv_sec + 1e-6 * ts.tv_nsec;
  }
};
/// [ms] of thread CPU time since @p t0; resets @p t0 to now.
inline double lap(Clock::time_point& t0)
{
  const Clock::time_point t = Clock::now();
  const double ms = t - t0;
  t0 = t;
  return ms;
}

constexpr float kInf = std::numeric_limits<float>::infinity();

/// Bilinear sample of a CV_32F map with clamped (replicated) borders at texel coordinates (x, y).
inline float sampleClamp(const float* m, int n, float x, float y)
{
  x = std::min(std::max(x, 0.f), float(n - 1));
  y = std::min(std::max(y, 0.f), float(n - 1));
  const int i0 = std::min(int(x), n - 2), j0 = std::min(int(y), n - 2);
  const float a = x - i0, b = y - j0;
  const float* r0 = m + size_t(j0) * n + i0;
  const float* r1 = r0 + n;
  return (1 - b) * ((1 - a) * r0[0] + a * r0[1]) + b * ((1 - a) * r1[0] + a * r1[1]);
}

/// Bilinear sample (as sampleClamp) and its gradient (per texel) from the same four taps.
inline float sampleGradClamp(const float* m, int n, float x, float y, float& gx, float& gy)
{
  x = std::min(std::max(x, 0.f), float(n - 1));
  y = std::min(std::max(y, 0.f), float(n - 1));
  const int i0 = std::min(int(x), n - 2), j0 = std::min(int(y), n - 2);
  const float a = x - i0, b = y - j0;
  const float* r0 = m + size_t(j0) * n + i0;
  const float* r1 = r0 + n;
  gx = (1 - b) * (r0[1] - r0[0]) + b * (r1[1] - r1[0]);
  gy = (1 - a) * (r1[0] - r0[0]) + a * (r1[1] - r0[1]);
  return (1 - b) * ((1 - a) * r0[0] + a * r0[1]) + b * ((1 - a) * r1[0] + a * r1[1]);
}

/// Gradient (d/dx, d/dy per texel) of the bilinear interpolant at (x, y): the same four taps as
/// the height sample (the normal costs no memory traffic beyond the height sample's).
inline void gradientClamp(const float* m, int n, float x, float y, float& gx, float& gy)
{
  sampleGradClamp(m, n, x, y, gx, gy);
}
}  // namespace detail

inline float SceneRenderer::tissueDepthAt(int u, int v) const
{
  // the full-resolution tissue depth of cv::resize(INTER_LINEAR) of the tissue grid at pixel
  // (u, v), inf where an interpolation tap misses the tissue
  const int i0 = col_i0_[u], j0 = row_j0_[v];
  const float a = col_a_[u], b = row_b_[v];
  const float* r0 = t_lo_.ptr<float>(j0) + i0;
  const float* r1 = t_lo_.ptr<float>(j0 + 1) + i0;
  const float d = (1 - b) * ((1 - a) * r0[0] + a * r0[1]) + b * ((1 - a) * r1[0] + a * r1[1]);
  return d < detail::kInf ? d : detail::kInf;  // NaN (inf - inf) -> inf
}

}  // namespace endoscope
}  // namespace saras_simulation

#endif  // SARAS_SIMULATION_ENDOSCOPE_RENDERER_DETAIL_H
