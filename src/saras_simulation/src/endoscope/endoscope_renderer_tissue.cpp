/**
 * @file endoscope_renderer_tissue.cpp
 * @brief SceneRenderer::solveTissue: tissue depth, texture coordinates and shading on the tissue grid.
 */
#include "saras_simulation/endoscope_renderer.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include <opencv2/imgproc.hpp>

#include "endoscope_renderer_detail.h"

namespace saras_simulation
{
namespace endoscope
{
using detail::kInf;

namespace
{
using detail::gradientClamp;
using detail::sampleClamp;
using detail::sampleGradClamp;

/// One row of tissue rays at a time: the pose, the height map and the per-row scratch of
/// SceneRenderer::solveTissue. Its steps are inlined into each clone of the multiversioned caller.
struct TissueRows
{
  Eigen::Matrix3f R;  ///< camera rotation (optical frame in world)
  Eigen::Vector3f o;  ///< camera position [m]
  float inv_res, ax, ay, z0;
  const float* hm;    ///< height map [m], n x n texels
  int n;
  float *kzs, *bxs, *bys, *ts, *gxs, *gys;  ///< per ray: 1 / d_z (0: miss), d_xy [texel/m], depth, gradient

  /// Directions, start depth (tstart: previous solution, or the mean plane), fixed-point
  /// iterations t <- (h(o + t d) - o_z) / d_z; iteration-major, so that the samples of a row are
  /// independent loads (memory-level parallelism) while the iterations of one ray form a chain.
  SARAS_ENDOSCOPE_CLONE_INLINE inline void solve(const float* rx, const float* ry, int count, const float* tstart,
                                                 int iterations)
  {
    for (int i = 0; i < count; ++i)
    {
      const Eigen::Vector3f d = R * Eigen::Vector3f(rx[i], ry[i], 1.f);
      kzs[i] = d.z() < -1e-6f ? 1.f / d.z() : 0.f;  // 0: ray not pointing down (miss)
      bxs[i] = d.x() * inv_res;
      bys[i] = d.y() * inv_res;
      ts[i] = tstart ? tstart[i] : (z0 - o.z()) * (kzs[i] != 0.f ? kzs[i] : -1.f);
    }
    for (int it = 0; it < iterations; ++it)
      for (int i = 0; i < count; ++i)
        ts[i] = (sampleClamp(hm, n, ax + ts[i] * bxs[i], ay + ts[i] * bys[i]) - o.z()) * (kzs[i] != 0.f ? kzs[i] : -1.f);
  }

  /// Newton steps on f(t) = o_z + t d_z - h(o + t d) from a close start (the upsampled coarse
  /// solution): f'(t) = d_z - grad h . d_xy comes from the same four taps as h, and the error
  /// squares at every step instead of shrinking by |grad h . d_xy / d_z| (the fixed-point
  /// iteration's factor). Where the surface is nearly parallel to the ray (|f'| < |d_z| / 4) the
  /// step falls back to the fixed-point update.
  SARAS_ENDOSCOPE_CLONE_INLINE inline void newton(int count, int iterations)
  {
    for (int it = 0; it < iterations; ++it)
      for (int i = 0; i < count; ++i)
      {
        const float kz = kzs[i];
        float& gx = gxs[i];
        float& gy = gys[i];
        const float hv = sampleGradClamp(hm, n, ax + ts[i] * bxs[i], ay + ts[i] * bys[i], gx, gy);
        if (kz == 0.f)
        {
          ts[i] = o.z() - hv;  // not pointing down: stays a miss
          continue;
        }
        const float dz = 1.f / kz;
        const float fp = dz - (gx * bxs[i] + gy * bys[i]);
        const float f = o.z() + ts[i] * dz - hv;
        ts[i] -= fp < 0.25f * dz ? f / fp : f * kz;
      }
  }

  /// Depth (inf = miss), texture coordinates (+ pad) and shade x 128 of the solved row. With
  /// @p last_gradient the gradient of the last Newton step is used for the normal (evaluated a
  /// Newton correction, << 1 texel, before the solution: the same bilinear patch, i.e. the same
  /// gradient up to ~1e-3 of its variation), else it is sampled at the solution.
  SARAS_ENDOSCOPE_CLONE_INLINE inline void shade(const float* rx, const float* ry, int count, bool last_gradient,
                                                 float pad, float L, float* tt, cv::Vec2f* mp, float* sh) const
  {
    for (int i = 0; i < count; ++i)
    {
      const float t = ts[i];
      const float mx = ax + t * bxs[i], my = ay + t * bys[i];
      mp[i] = cv::Vec2f(mx + pad, my + pad);
      if (kzs[i] == 0.f || !(t > 0.f))
      {
        tt[i] = kInf;
        sh[i] = 0.f;
        continue;
      }
      tt[i] = t;
      const Eigen::Vector3f d = R * Eigen::Vector3f(rx[i], ry[i], 1.f);
      // unit normal (-dz/dx, -dz/dy, 1) / norm of the interpolated height field
      float gx, gy;
      if (last_gradient)
      {
        gx = gxs[i];
        gy = gys[i];
      }
      else
        gradientClamp(hm, n, mx, my, gx, gy);
      gx *= inv_res;
      gy *= inv_res;
      const float dn = d.norm();
      const float lam = std::min(std::max((gx * d.x() + gy * d.y() - d.z()) / (dn * std::sqrt(1.f + gx * gx + gy * gy)), 0.f), 1.f);
      const float x = L / std::max(t * dn, 1e-3f);
      const float fall = std::min(std::max(x * std::sqrt(x), 0.3f), 1.3f);  // (L / distance)^1.5
      sh[i] = (0.15f + 0.85f * lam) * fall * 128.f;
    }
  }
};
}  // namespace

// ---------------------------------------------------------------------------------------------
// Tissue: ray / height-field intersection along the rays pointing down; t is the optical depth
// (d = R (x, y, 1)). Texture coordinates (texels) are affine in t.
SARAS_ENDOSCOPE_MULTIVERSION
void SceneRenderer::solveTissue(const Eigen::Matrix3f& R, const Eigen::Vector3f& o)
{
  const int h = rays_lo_x_.rows, w = rays_lo_x_.cols;
  for (auto* row : { &row_kz_, &row_bx_, &row_by_, &row_t_, &row_gx_, &row_gy_ })
    row->resize(w);
  TissueRows rows;
  rows.R = R;
  rows.o = o;
  rows.inv_res = static_cast<float>(1.0 / tex_res_);
  rows.ax = static_cast<float>((o.x() - tex_x0_) / tex_res_ - 0.5);
  rows.ay = static_cast<float>((o.y() - tex_y0_) / tex_res_ - 0.5);
  rows.z0 = static_cast<float>(surface_.z0());
  rows.hm = hmap_.ptr<float>();
  rows.n = opt_.texture_size;
  rows.kzs = row_kz_.data();
  rows.bxs = row_bx_.data();
  rows.bys = row_by_.data();
  rows.ts = row_t_.data();
  rows.gxs = row_gx_.data();
  rows.gys = row_gy_.data();
  const bool coarse = !rays_c_x_.empty();
  if (coarse)
  {
    // all iterations on a grid twice coarser, upsampled to the tissue grid as the start
    for (int j = 0; j < rays_c_x_.rows; ++j)
    {
      // fixed-point iterations from the mean plane (robust), the last two as Newton steps
      const int newton = std::min(2, opt_.tissue_iterations - 1);
      rows.solve(rays_c_x_.ptr<float>(j), rays_c_y_.ptr<float>(j), rays_c_x_.cols, nullptr,
                 opt_.tissue_iterations - newton);
      rows.newton(rays_c_x_.cols, newton);
      std::copy(rows.ts, rows.ts + rays_c_x_.cols, t_c_.ptr<float>(j));
    }
    cv::resize(t_c_, t_init_, t_lo_.size(), 0, 0, cv::INTER_LINEAR);
  }
  const float pad = static_cast<float>(tex_pad_), L = static_cast<float>(opt_.light_distance);
  for (int j = 0; j < h; ++j)
  {
    const float* rx = rays_lo_x_.ptr<float>(j);
    const float* ry = rays_lo_y_.ptr<float>(j);
    if (coarse)
    {
      rows.solve(rx, ry, w, t_init_.ptr<float>(j), 0);
      rows.newton(w, opt_.refine_iterations);
    }
    else
      rows.solve(rx, ry, w, nullptr, opt_.tissue_iterations);
    rows.shade(rx, ry, w, coarse && opt_.refine_iterations > 0, pad, L, t_lo_.ptr<float>(j),
               maps_lo_.ptr<cv::Vec2f>(j), shade_lo_.ptr<float>(j));
  }
}

}  // namespace endoscope
}  // namespace saras_simulation
