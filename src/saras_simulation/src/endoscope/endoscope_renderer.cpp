/**
 * @file endoscope_renderer.cpp
 * @brief SceneRenderer: cached static layer (tissue, bones, target) + per-frame shafts.
 */
#include "saras_simulation/endoscope_renderer.h"

#include <algorithm>
#include <ctime>
#include <cmath>
#include <limits>
#include <stdexcept>

#include <opencv2/imgproc.hpp>

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
namespace
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
double lap(Clock::time_point& t0)
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

/// Convex hull (Andrew's monotone chain, counter-clockwise, no collinear points) of @p pts in
/// double precision (cv::convexHull takes float / int points only). @p pts is sorted in place.
void convexHull2d(std::vector<cv::Point2d>& pts, std::vector<cv::Point2d>& hull)
{
  hull.clear();
  const size_t n = pts.size();
  if (n < 3)
  {
    hull = pts;
    return;
  }
  std::sort(pts.begin(), pts.end(), [](const cv::Point2d& a, const cv::Point2d& b) {
    return a.x < b.x || (a.x == b.x && a.y < b.y);
  });
  auto cross = [](const cv::Point2d& o, const cv::Point2d& a, const cv::Point2d& b) {
    return (a.x - o.x) * (b.y - o.y) - (a.y - o.y) * (b.x - o.x);
  };
  hull.resize(2 * n);
  size_t k = 0;
  for (size_t i = 0; i < n; ++i)
  {
    while (k >= 2 && cross(hull[k - 2], hull[k - 1], pts[i]) <= 0)
      --k;
    hull[k++] = pts[i];
  }
  for (size_t i = n - 1, t = k + 1; i > 0; --i)
  {
    while (k >= t && cross(hull[k - 2], hull[k - 1], pts[i - 1]) <= 0)
      --k;
    hull[k++] = pts[i - 1];
  }
  hull.resize(k > 1 ? k - 1 : k);
}
}  // namespace

std::pair<int, int> tissueGridSteps(int width)
{
  const int colour = std::max(2, static_cast<int>(std::nearbyint(2.0 * width / 1280.0)));
  return { 2 * colour, colour };
}

SceneRenderer::SceneRenderer(const CameraModel& camera, const TissueSurface& surface, const RendererOptions& options)
  : cam_(camera), surface_(surface), opt_(options)
{
  const auto steps = tissueGridSteps(cam_.width());
  colour_step_ = opt_.colour_subsample > 0 ? opt_.colour_subsample : steps.second;
  tissue_step_ = opt_.tissue_subsample > 0 ? opt_.tissue_subsample : 2 * colour_step_;
  if (opt_.tissue_subsample < 0 || opt_.colour_subsample < 0 || tissue_step_ % colour_step_ != 0)
    throw std::invalid_argument("tissue_subsample must be a positive multiple of tissue_colour_subsample (>= 1)");
  if (opt_.texture_size < 16 || opt_.texture_size > 8192)
    throw std::invalid_argument("parameter ~texture_size must be in [16, 8192] texels");
  if (!(opt_.texture_extent > 0) || !std::isfinite(opt_.texture_extent))
    throw std::invalid_argument("parameter ~texture_extent must be > 0 m");
  if (!(opt_.light_distance > 0) || !std::isfinite(opt_.light_distance))
    throw std::invalid_argument("parameter ~light_distance must be > 0 m");
  if (cam_.width() / tissue_step_ < 2 || cam_.height() / tissue_step_ < 2)
    throw std::invalid_argument("image too small for the tissue grid");
  cam_.pixelRays(1, rays_x_, rays_y_);
  for (int a = 0; a < 2; ++a)
  {
    double lo, hi;
    cv::minMaxLoc(a ? rays_y_ : rays_x_, &lo, &hi);
    const double margin = 0.01 * (hi - lo);  // the rays of the 2 px margin of the row spans
    ray_lo_[a] = lo - margin;
    ray_hi_[a] = hi + margin;
  }
  cam_.pixelRays(tissue_step_, rays_lo_x_, rays_lo_y_);
  if (rays_lo_x_.cols % 2 == 0 && rays_lo_x_.rows % 2 == 0 && rays_lo_x_.cols >= 160)
  {
    cam_.pixelRays(2 * tissue_step_, rays_c_x_, rays_c_y_);
    t_c_.create(rays_c_x_.size(), CV_32F);
  }
  if (opt_.tissue_iterations < 1 || opt_.refine_iterations < 0)
    throw std::invalid_argument("tissue iterations must be >= 1 (refine >= 0)");
  colour_size_ = cv::Size(cam_.width() / colour_step_, cam_.height() / colour_step_);
  fov_ = cam_.fieldOfViewBounds();
  const int n = opt_.texture_size;
  const cv::Mat tex = tissueTexture(n);
  tex_pad_ = n / 2;
  cv::copyMakeBorder(tex, tex_padded_, tex_pad_, tex_pad_, tex_pad_, tex_pad_, cv::BORDER_REFLECT);
  tex_res_ = opt_.texture_extent / n;
  tex_x0_ = surface_.cx() - opt_.texture_extent / 2.0;
  tex_y0_ = surface_.cy() - opt_.texture_extent / 2.0;
  hmap_.create(n, n, CV_32F);
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i)
    {
      const double x = tex_x0_ + (i + 0.5) * tex_res_, y = tex_y0_ + (j + 0.5) * tex_res_;
      hmap_.at<float>(j, i) = static_cast<float>(surface_.height(x, y));
    }
  // tissue-grid interpolation taps and weights of every full-resolution column / row
  // (cv::resize INTER_LINEAR convention), for the z-test of bones and target
  auto taps = [&](int count, int cells, std::vector<int>& i0, std::vector<float>& a) {
    i0.resize(count);
    a.resize(count);
    for (int u = 0; u < count; ++u)
    {
      const float f = std::min(std::max((u + 0.5f) / tissue_step_ - 0.5f, 0.f), float(cells - 1));
      i0[u] = std::min(int(f), cells - 2);
      a[u] = f - i0[u];
    }
  };
  taps(cam_.width(), rays_lo_x_.cols, col_i0_, col_a_);
  taps(cam_.height(), rays_lo_x_.rows, row_j0_, row_b_);
  bg_.create(cam_.height(), cam_.width(), CV_8UC3);
  depth_.create(cam_.height(), cam_.width(), CV_32F);
  t_lo_.create(rays_lo_x_.size(), CV_32F);
  maps_lo_.create(rays_lo_x_.size(), CV_32FC2);
  shade_lo_.create(rays_lo_x_.size(), CV_32F);
}

void SceneRenderer::setBoxes(const std::vector<std::array<Eigen::Vector3d, 8>>& boxes_world)
{
  std::vector<Box> boxes;
  for (const auto& v : boxes_world)
    boxes.push_back(boxFromVertices(v));  // may throw: the scene is then unchanged
  boxes_.swap(boxes);
  cache_valid_ = false;
}

void SceneRenderer::setTarget(std::shared_ptr<const PlanarTarget> target, const Eigen::Isometry3d& T_world_board)
{
  target_ = std::move(target);
  T_world_board_ = T_world_board;
  cache_valid_ = false;
}

void SceneRenderer::clearTarget()
{
  target_.reset();
  cache_valid_ = false;
}

void SceneRenderer::setUniformTexture(unsigned char grey)
{
  tex_padded_.setTo(cv::Scalar::all(grey));
  cache_valid_ = false;
}

const cv::Mat& SceneRenderer::background(const Eigen::Isometry3d& T_world_cam)
{
  if (!cache_valid_ || (cache_pose_.matrix() - T_world_cam.matrix()).cwiseAbs().maxCoeff() > 1e-7)
  {
    renderBackground(T_world_cam);
    cache_pose_ = T_world_cam;
    cache_valid_ = true;
    ++background_renders_;
  }
  return bg_;
}

// ---------------------------------------------------------------------------------------------
// Tissue: fixed-point iteration t <- (h(o + t d) - o_z) / d_z along the rays pointing down; t is
// the optical depth (d = R (x, y, 1)). Texture coordinates (texels) are affine in t.
SARAS_ENDOSCOPE_MULTIVERSION
void SceneRenderer::solveTissue(const Eigen::Matrix3f& R, const Eigen::Vector3f& o)
{
  const int h = rays_lo_x_.rows, w = rays_lo_x_.cols, n = opt_.texture_size;
  const float inv_res = static_cast<float>(1.0 / tex_res_);
  const float ax = static_cast<float>((o.x() - tex_x0_) / tex_res_ - 0.5);
  const float ay = static_cast<float>((o.y() - tex_y0_) / tex_res_ - 0.5);
  const float z0 = static_cast<float>(surface_.z0());
  const float pad = static_cast<float>(tex_pad_);
  const float L = static_cast<float>(opt_.light_distance);
  const float* hm = hmap_.ptr<float>();
  row_kz_.resize(w);
  row_bx_.resize(w);
  row_by_.resize(w);
  row_t_.resize(w);
  float* kzs = row_kz_.data();
  float* bxs = row_bx_.data();
  float* bys = row_by_.data();
  float* ts = row_t_.data();
  // one row of rays: directions, start depth (tstart: previous solution, or the mean plane),
  // fixed-point iterations; iteration-major, so that the samples of a row are independent loads
  // (memory-level parallelism) while the iterations of one ray form a dependent chain
  auto solveRow = [&](const float* rx, const float* ry, int count, const float* tstart,
                      int iterations) SARAS_ENDOSCOPE_CLONE_INLINE {
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
  };
  // Newton steps on f(t) = o_z + t d_z - h(o + t d) from a close start (the upsampled coarse
  // solution): f'(t) = d_z - grad h . d_xy comes from the same four taps as h, and the error
  // squares at every step instead of shrinking by |grad h . d_xy / d_z| (the fixed-point
  // iteration's factor). Where the surface is nearly parallel to the ray (|f'| < |d_z| / 4) the
  // step falls back to the fixed-point update.
  row_gx_.resize(w);
  row_gy_.resize(w);
  float* gxs = row_gx_.data();
  float* gys = row_gy_.data();
  auto newtonRow = [&](int count, int iterations) SARAS_ENDOSCOPE_CLONE_INLINE {
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
  };
  const bool coarse = !rays_c_x_.empty();
  if (coarse)
  {
    // all iterations on a grid twice coarser, upsampled to the tissue grid as the start
    for (int j = 0; j < rays_c_x_.rows; ++j)
    {
      // fixed-point iterations from the mean plane (robust), the last two as Newton steps
      const int newton = std::min(2, opt_.tissue_iterations - 1);
      solveRow(rays_c_x_.ptr<float>(j), rays_c_y_.ptr<float>(j), rays_c_x_.cols, nullptr, opt_.tissue_iterations - newton);
      newtonRow(rays_c_x_.cols, newton);
      std::copy(ts, ts + rays_c_x_.cols, t_c_.ptr<float>(j));
    }
    cv::resize(t_c_, t_init_, t_lo_.size(), 0, 0, cv::INTER_LINEAR);
  }
  for (int j = 0; j < h; ++j)
  {
    const float* rx = rays_lo_x_.ptr<float>(j);
    const float* ry = rays_lo_y_.ptr<float>(j);
    float* tt = t_lo_.ptr<float>(j);
    cv::Vec2f* mp = maps_lo_.ptr<cv::Vec2f>(j);
    float* sh = shade_lo_.ptr<float>(j);
    if (coarse)
    {
      solveRow(rx, ry, w, t_init_.ptr<float>(j), 0);
      newtonRow(w, opt_.refine_iterations);
    }
    else
      solveRow(rx, ry, w, nullptr, opt_.tissue_iterations);
    for (int i = 0; i < w; ++i)
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
      // unit normal (-dz/dx, -dz/dy, 1) / norm of the interpolated height field; after Newton
      // steps, the gradient of the last one (evaluated a Newton correction, << 1 texel, before the
      // solution: the same bilinear patch, i.e. the same gradient up to ~1e-3 of its variation)
      float gx, gy;
      if (coarse && opt_.refine_iterations > 0)
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
}

inline float SceneRenderer::tissueDepthAt(int u, int v) const
{
  // the full-resolution tissue depth of cv::resize(INTER_LINEAR) of the tissue grid at pixel
  // (u, v), inf where an interpolation tap misses the tissue
  const int i0 = col_i0_[u], j0 = row_j0_[v];
  const float a = col_a_[u], b = row_b_[v];
  const float* r0 = t_lo_.ptr<float>(j0) + i0;
  const float* r1 = t_lo_.ptr<float>(j0 + 1) + i0;
  const float d = (1 - b) * ((1 - a) * r0[0] + a * r0[1]) + b * ((1 - a) * r1[0] + a * r1[1]);
  return d < kInf ? d : kInf;  // NaN (inf - inf) -> inf
}

bool SceneRenderer::roi(const Eigen::Isometry3d& T_cam_world, const std::vector<Eigen::Vector3d>& pts_world,
                        cv::Rect& out) const
{
  const double near = 1e-4;
  bool all_behind = true, any_behind = false;
  Eigen::Vector2d lo(1e300, 1e300), hi(-1e300, -1e300);
  for (const auto& p : pts_world)
  {
    const Eigen::Vector3d pc = T_cam_world * p;
    all_behind = all_behind && pc.z() <= near;
    any_behind = any_behind || pc.z() <= near;
    if (pc.z() > near)
    {
      const Eigen::Vector2d xy = pc.head<2>() / pc.z();
      lo = lo.cwiseMin(xy);
      hi = hi.cwiseMax(xy);
    }
  }
  if (all_behind)
    return false;
  if (any_behind)
  {
    out = cv::Rect(0, 0, cam_.width(), cam_.height());
    return true;
  }
  lo = lo.cwiseMax(-1.02 * fov_);
  hi = hi.cwiseMin(1.02 * fov_);
  if (lo.x() > hi.x() || lo.y() > hi.y())
    return false;
  double u0 = 1e300, v0 = 1e300, u1 = -1e300, v1 = -1e300;
  for (int k = 0; k <= 16; ++k)
  {
    const double s = k / 16.0;
    const Eigen::Vector2d e[4] = { { lo.x() + s * (hi.x() - lo.x()), lo.y() },
                                   { lo.x() + s * (hi.x() - lo.x()), hi.y() },
                                   { lo.x(), lo.y() + s * (hi.y() - lo.y()) },
                                   { hi.x(), lo.y() + s * (hi.y() - lo.y()) } };
    for (const auto& xy : e)
    {
      const Eigen::Vector2d uv = cam_.distort(xy);
      u0 = std::min(u0, uv.x());
      v0 = std::min(v0, uv.y());
      u1 = std::max(u1, uv.x());
      v1 = std::max(v1, uv.y());
    }
  }
  const int x0 = std::max(int(std::floor(u0)) - 3, 0), y0 = std::max(int(std::floor(v0)) - 3, 0);
  const int x1 = std::min(int(std::ceil(u1)) + 4, cam_.width()), y1 = std::min(int(std::ceil(v1)) + 4, cam_.height());
  if (x0 >= x1 || y0 >= y1)
    return false;
  out = cv::Rect(x0, y0, x1 - x0, y1 - y0);
  return true;
}

// ---------------------------------------------------------------------------------------------
// Image region of a box (conservative): the box clipped to z >= near is convex, so its central
// projection onto the normalised plane (x/z, y/z) is the convex hull of the projected vertices
// of the clipped box (corners in front + edge/near-plane intersections). That polygon is clipped
// to the rectangle of the image's pixel rays (where the distortion model is used by the
// calibration), its edges are sampled every <= 16 px through the distortion model and the convex
// hull of the samples (+ 2 px margin in the row spans) bounds the pixels whose ray can hit the box.
bool SceneRenderer::boxSilhouette(const Eigen::Isometry3d& T_cam_world, const std::array<Eigen::Vector3d, 8>& corners,
                                  Silhouette& sil)
{
  static const int edges[12][2] = { { 0, 1 }, { 2, 3 }, { 4, 5 }, { 6, 7 }, { 0, 2 }, { 1, 3 },
                                    { 4, 6 }, { 5, 7 }, { 0, 4 }, { 1, 5 }, { 2, 6 }, { 3, 7 } };
  const double near = 1e-3;
  Eigen::Vector3d pc[8];
  sil.zmin = std::numeric_limits<float>::infinity();
  for (int k = 0; k < 8; ++k)
  {
    pc[k] = T_cam_world * corners[k];
    sil.zmin = std::min(sil.zmin, static_cast<float>(pc[k].z()));
  }
  poly_.clear();
  for (int k = 0; k < 8; ++k)
    if (pc[k].z() >= near)
      poly_.emplace_back(pc[k].x() / pc[k].z(), pc[k].y() / pc[k].z());
  for (const auto& e : edges)
  {
    const Eigen::Vector3d &a = pc[e[0]], &b = pc[e[1]];
    if ((a.z() < near) != (b.z() < near))
    {
      const Eigen::Vector3d p = a + (near - a.z()) / (b.z() - a.z()) * (b - a);
      poly_.emplace_back(p.x() / near, p.y() / near);
    }
  }
  if (poly_.empty())
    return false;
  convexHull2d(poly_, clip_a_);
  // Sutherland-Hodgman against the ray rectangle (4 axis-aligned half-planes)
  for (int side = 0; side < 4 && !clip_a_.empty(); ++side)
  {
    const int axis = side / 2;
    const double lim = side % 2 ? ray_hi_[axis] : ray_lo_[axis];
    auto inside = [&](const cv::Point2d& p) { return side % 2 ? (axis ? p.y : p.x) <= lim : (axis ? p.y : p.x) >= lim; };
    clip_b_.clear();
    const size_t n = clip_a_.size();
    for (size_t i = 0; i < n; ++i)
    {
      const cv::Point2d& p = clip_a_[i];
      const cv::Point2d& q = clip_a_[(i + 1) % n];
      const bool ip = inside(p), iq = inside(q);
      if (ip)
        clip_b_.push_back(p);
      if (ip != iq)
      {
        const double pv = axis ? p.y : p.x, qv = axis ? q.y : q.x;
        clip_b_.push_back(p + (lim - pv) / (qv - pv) * (q - p));
      }
    }
    clip_a_.swap(clip_b_);
  }
  if (clip_a_.empty())
    return false;
  // polygon edges through the distortion model
  hull_pts_.clear();
  const size_t n = clip_a_.size();
  for (size_t i = 0; i < n; ++i)
  {
    const Eigen::Vector2d p(clip_a_[i].x, clip_a_[i].y), q(clip_a_[(i + 1) % n].x, clip_a_[(i + 1) % n].y);
    const double len = (cam_.distort(q) - cam_.distort(p)).norm();
    const int steps = std::min(std::max(static_cast<int>(std::ceil(len / 16.0)), 1), 256);
    for (int k = 0; k < steps; ++k)
    {
      const Eigen::Vector2d uv = cam_.distort(p + (double(k) / steps) * (q - p));
      if (!uv.allFinite())
        return false;
      hull_pts_.emplace_back(float(uv.x()), float(uv.y()));
    }
  }
  cv::convexHull(hull_pts_, sil.hull);
  float bx0 = 1e30f, by0 = 1e30f, bx1 = -1e30f, by1 = -1e30f;
  for (const cv::Point2f& p : sil.hull)
  {
    bx0 = std::min(bx0, p.x);
    by0 = std::min(by0, p.y);
    bx1 = std::max(bx1, p.x);
    by1 = std::max(by1, p.y);
  }
  const int x0 = std::max(int(std::floor(bx0)) - 3, 0), y0 = std::max(int(std::floor(by0)) - 3, 0);
  const int x1 = std::min(int(std::ceil(bx1)) + 4, cam_.width());
  const int y1 = std::min(int(std::ceil(by1)) + 4, cam_.height());
  if (x0 >= x1 || y0 >= y1)
    return false;
  sil.rect = cv::Rect(x0, y0, x1 - x0, y1 - y0);
  return true;
}

void SceneRenderer::renderBackground(const Eigen::Isometry3d& T_world_cam)
{
  const Eigen::Matrix3f R = T_world_cam.linear().cast<float>();
  const Eigen::Vector3f o = T_world_cam.translation().cast<float>();
  Clock::time_point t0 = Clock::now();
  solveTissue(R, o);
  stats_.tissue_ms += lap(t0);
  // colour layer: texture coordinates + shade upsampled to the colour grid, texture sampled
  // there, shaded (shade rounded to uint8 x 1/128, as the Python reference), upsampled to the image
  cv::resize(maps_lo_, maps_c_, colour_size_, 0, 0, cv::INTER_LINEAR);
  cv::resize(shade_lo_, shade_c_, colour_size_, 0, 0, cv::INTER_LINEAR);
  cv::remap(tex_padded_, col_c_, maps_c_, cv::noArray(), cv::INTER_LINEAR, cv::BORDER_REFLECT);
  // colour x saturate_cast<uchar>(shade) / 128, rounded (OpenCV's vectorised kernels)
  shade_c_.convertTo(shade_u8_, CV_8U);
  cv::cvtColor(shade_u8_, shade_u8c3_, cv::COLOR_GRAY2BGR);
  cv::multiply(col_c_, shade_u8c3_, col_c_, 1.0 / 128.0);
  if (col_c_.size() == bg_.size())
    col_c_.copyTo(bg_);
  else
    cv::resize(col_c_, bg_, bg_.size(), 0, 0, cv::INTER_LINEAR);
  stats_.colour_ms += lap(t0);
  if (boxes_.empty() && !target_)
    return;
  // rectangles that need a full-resolution depth: the bones' and the target's
  const Eigen::Isometry3d Tcw = T_world_cam.inverse();
  const Eigen::Vector3d od = T_world_cam.translation();
  cv::Rect all;
  std::vector<Eigen::Vector3d> pts;
  box_sil_.resize(boxes_.size());
  for (size_t k = 0; k < boxes_.size(); ++k)
  {
    const Box& b = boxes_[k];
    Silhouette& sil = box_sil_[k];
    // camera inside the box: no face is visible from outside (as the reference)
    const Eigen::Vector3d ob = b.axes * (od - b.centre);
    sil.visible = (ob.cwiseAbs() - b.half).maxCoeff() > 0.0 && boxSilhouette(Tcw, b.corners(), sil);
    if (sil.visible)
      all = all.area() ? (all | sil.rect) : sil.rect;
  }
  cv::Rect target_rect;
  if (target_)
  {
    pts.clear();
    for (double x : { target_->x_min, target_->xMax() })
      for (double y : { target_->y_min, target_->yMax() })
        pts.push_back(T_world_board_ * Eigen::Vector3d(x, y, 0.0));
    if (roi(Tcw, pts, target_rect))
      all = all.area() ? (all | target_rect) : target_rect;
  }
  if (all.area() == 0)
    return;
  // depth_ holds the optical depth of the bones/target drawn so far (inf = none); the tissue
  // depth is interpolated only at the pixels they hit
  depth_(all).setTo(kInf);
  if (!boxes_.empty())
    renderBoxes(T_world_cam, all);
  stats_.boxes_ms += lap(t0);
  if (target_rect.area() > 0)
    renderTarget(T_world_cam, target_rect);
  stats_.target_ms += lap(t0);
}

// ---------------------------------------------------------------------------------------------
// Bones: exact ray/oriented-box intersection (slabs) at every pixel centre of the box's image
// rectangle, z-tested against the depth; flat shading per face (Lambert at the face centre x
// head-light fall-off), as the Python reference.
struct SceneRenderer::BoxCam
{
  Eigen::Matrix3f A;    ///< rows: box axes in the camera frame
  Eigen::Vector3f s;    ///< axis . centre (camera frame)
  Eigen::Vector3f h;    ///< half extents
  cv::Vec3b colour[6];  ///< face (axis i, sign) -> colour index 2 i + (sign > 0)
  cv::Rect rect;
};

SARAS_ENDOSCOPE_MULTIVERSION
void SceneRenderer::renderBoxes(const Eigen::Isometry3d& T_world_cam, const cv::Rect& depth_rect)
{
  const Eigen::Isometry3d Tcw = T_world_cam.inverse();
  const double L = opt_.light_distance;
  box_tn_.resize(cam_.width());
  box_face_.resize(cam_.width());
  for (size_t k = 0; k < boxes_.size(); ++k)
  {
    const Box& b = boxes_[k];
    const Silhouette& sil = box_sil_[k];
    if (!sil.visible)
      continue;
    BoxCam bc;
    bc.rect = sil.rect & depth_rect;
    const Eigen::Vector3d cc = Tcw * b.centre;
    for (int i = 0; i < 3; ++i)
    {
      const Eigen::Vector3d a = Tcw.linear() * b.axes.row(i).transpose();
      bc.A.row(i) = a.cast<float>().transpose();
      bc.s[i] = static_cast<float>(a.dot(cc));
      bc.h[i] = static_cast<float>(b.half[i]);
      for (int sg = 0; sg < 2; ++sg)
      {
        const Eigen::Vector3d nrm = (sg ? 1.0 : -1.0) * a;
        const Eigen::Vector3d fc = cc + nrm * b.half[i];
        const double dist = std::max(fc.norm(), 1e-3);
        const double fall = std::min(std::max(std::pow(L / dist, 1.5), 0.3), 1.3);
        const double lam = std::max(-nrm.dot(fc) / dist, 0.0);
        const double shade = std::min((0.25 + 0.75 * lam) * fall, 1.3);
        for (int ch = 0; ch < 3; ++ch)
          bc.colour[2 * i + sg][ch] =
              cv::saturate_cast<uchar>(std::min(std::max(shade * bone_bgr_[ch], 1.0), 255.0));
      }
    }
    const float near = 1e-3f;
    const std::vector<cv::Point2f>& hull = sil.hull;
    for (int v = bc.rect.y; v < bc.rect.y + bc.rect.height; ++v)
    {
      int u0 = bc.rect.x, u1 = bc.rect.x + bc.rect.width;
      {
        float lo = 1e30f, hi = -1e30f;
        const size_t nh = hull.size();
        for (size_t e = 0; e < nh; ++e)
        {
          const cv::Point2f& p = hull[e];
          const cv::Point2f& q = hull[(e + 1) % nh];
          // the row band [v - 2, v + 2] against edge p-q: x range of the edge within the band
          const float ya = std::max(std::min(p.y, q.y), v - 2.f), yb = std::min(std::max(p.y, q.y), v + 2.f);
          if (ya > yb)
            continue;
          if (std::abs(q.y - p.y) < 1e-6f)
          {
            lo = std::min(lo, std::min(p.x, q.x));
            hi = std::max(hi, std::max(p.x, q.x));
            continue;
          }
          const float xa = p.x + (ya - p.y) * (q.x - p.x) / (q.y - p.y);
          const float xb = p.x + (yb - p.y) * (q.x - p.x) / (q.y - p.y);
          lo = std::min(lo, std::min(xa, xb));
          hi = std::max(hi, std::max(xa, xb));
        }
        if (lo > hi)
          continue;
        u0 = std::max(u0, int(std::floor(lo)) - 2);
        u1 = std::min(u1, int(std::ceil(hi)) + 3);
      }
      if (u0 >= u1)
        continue;
      // the whole span behind the tissue (every interpolation tap of the tissue depth nearer
      // than the box's nearest corner): nothing of this box is visible in the row
      {
        const float* t0 = t_lo_.ptr<float>(row_j0_[v]);
        const float* t1 = t_lo_.ptr<float>(row_j0_[v] + 1);
        float tmax = 0.f;
        for (int i = col_i0_[u0], ie = col_i0_[u1 - 1] + 1; i <= ie; ++i)
          tmax = std::max(tmax, std::max(t0[i], t1[i]));
        if (sil.zmin > tmax)
          continue;
      }
      const float* rx = rays_x_.ptr<float>(v);
      const float* ry = rays_y_.ptr<float>(v);
      float* dp = depth_.ptr<float>(v);
      cv::Vec3b* img = bg_.ptr<cv::Vec3b>(v);
      // pass 1 (branch-free, vectorisable): entry depth (inf = miss) and entry face per pixel
      float* tn_row = box_tn_.data();
      int* face_row = box_face_.data();
      const float a00 = bc.A(0, 0), a01 = bc.A(0, 1), a02 = bc.A(0, 2), a10 = bc.A(1, 0), a11 = bc.A(1, 1),
                  a12 = bc.A(1, 2), a20 = bc.A(2, 0), a21 = bc.A(2, 1), a22 = bc.A(2, 2);
      const float lo0 = bc.s[0] - bc.h[0], hi0 = bc.s[0] + bc.h[0], lo1 = bc.s[1] - bc.h[1], hi1 = bc.s[1] + bc.h[1],
                  lo2 = bc.s[2] - bc.h[2], hi2 = bc.s[2] + bc.h[2];
      for (int u = u0; u < u1; ++u)
      {
        const float x = rx[u], y = ry[u];
        // ray . axis; an exactly parallel ray gives +-inf / NaN slab bounds: treated as a miss
        const float i0 = 1.f / (a00 * x + a01 * y + a02), i1 = 1.f / (a10 * x + a11 * y + a12),
                    i2 = 1.f / (a20 * x + a21 * y + a22);
        const float p0 = lo0 * i0, q0 = hi0 * i0, p1 = lo1 * i1, q1 = hi1 * i1, p2 = lo2 * i2, q2 = hi2 * i2;
        const float n0 = std::min(p0, q0), f0 = std::max(p0, q0), n1 = std::min(p1, q1), f1 = std::max(p1, q1),
                    n2 = std::min(p2, q2), f2 = std::max(p2, q2);
        const float tn = std::max(n0, std::max(n1, n2)), tf = std::min(f0, std::min(f1, f2));
        // entering face: axis of the largest near bound, side opposing the ray (1: + side)
        const int ax = n0 >= n1 ? (n0 >= n2 ? 0 : 2) : (n1 >= n2 ? 1 : 2);
        const float iv = ax == 0 ? i0 : (ax == 1 ? i1 : i2);
        face_row[u - u0] = 2 * ax + (iv > 0.f ? 0 : 1);
        tn_row[u - u0] = (tn <= tf && tn >= near) ? tn : kInf;
      }
      // pass 2: z-test against what is drawn and the tissue
      for (int u = u0; u < u1; ++u)
      {
        const float tn = tn_row[u - u0];
        if (!(tn < dp[u]) || !(tn < tissueDepthAt(u, v)))
          continue;
        dp[u] = tn;
        img[u] = bc.colour[face_row[u - u0]];
      }
    }
  }
}

// ---------------------------------------------------------------------------------------------
// Target: ray/board-plane intersection per pixel, bilinear texture, matte paper (0.85 v + 20).
void SceneRenderer::renderTarget(const Eigen::Isometry3d& T_world_cam, const cv::Rect& r)
{
  const PlanarTarget& tg = *target_;
  const Eigen::Isometry3d T_board_cam = T_world_board_.inverse() * T_world_cam;
  const Eigen::Matrix3d Rbc = T_board_cam.linear();
  const Eigen::Vector3d ob = T_board_cam.translation();
  const double xmin = tg.x_min, ymin = tg.y_min, xmax = tg.xMax(), ymax = tg.yMax(), inv_res = 1.0 / tg.res;
  const int tw = tg.texture.cols, th = tg.texture.rows;
  for (int v = r.y; v < r.y + r.height; ++v)
  {
    const float* rx = rays_x_.ptr<float>(v);
    const float* ry = rays_y_.ptr<float>(v);
    float* dp = depth_.ptr<float>(v);
    cv::Vec3b* img = bg_.ptr<cv::Vec3b>(v);
    for (int u = r.x; u < r.x + r.width; ++u)
    {
      const Eigen::Vector3d db = Rbc * Eigen::Vector3d(rx[u], ry[u], 1.0);
      const double t = -ob.z() / db.z();
      if (!(t > 0) || !std::isfinite(t) || !(t < dp[u]))
        continue;
      const double x = ob.x() + t * db.x(), y = ob.y() + t * db.y();
      if (x < xmin || x >= xmax || y < ymin || y >= ymax || !(t < tissueDepthAt(u, v)))
        continue;
      double mx = (x - xmin) * inv_res - 0.5, my = (y - ymin) * inv_res - 0.5;
      mx = std::min(std::max(mx, 0.0), double(tw - 1));
      my = std::min(std::max(my, 0.0), double(th - 1));
      const int i0 = std::min(int(mx), tw - 2), j0 = std::min(int(my), th - 2);
      const double a = mx - i0, b = my - j0;
      const uchar* t0 = tg.texture.ptr<uchar>(j0) + i0;
      const uchar* t1 = tg.texture.ptr<uchar>(j0 + 1) + i0;
      const double val = std::nearbyint((1 - b) * ((1 - a) * t0[0] + a * t0[1]) + b * ((1 - a) * t1[0] + a * t1[1]));
      const uchar g = static_cast<uchar>(val * 0.85 + 20.0);  // matte paper
      img[u] = cv::Vec3b(g, g, g);
      dp[u] = static_cast<float>(t);
    }
  }
}

// ---------------------------------------------------------------------------------------------
void SceneRenderer::render(const Eigen::Isometry3d& T_world_cam, const std::vector<Shaft>& shafts, cv::Mat& out)
{
  const cv::Mat& bg = background(T_world_cam);
  Clock::time_point t0 = Clock::now();
  bg.copyTo(out);
  stats_.copy_ms += lap(t0);
  if (shafts.empty())
    return;
  const Eigen::Isometry3d Tcw = T_world_cam.inverse();
  struct Item
  {
    double zmin;
    std::vector<Eigen::Vector3d> pc;
    std::vector<bool> above;
    double radius;
  };
  std::vector<Item> items;
  items.reserve(shafts.size());
  for (const Shaft& s : shafts)
  {
    if (!s.tip.allFinite() || !s.rcm.allFinite() || !std::isfinite(s.radius))
      continue;
    Item it;
    it.radius = s.radius;
    it.zmin = std::numeric_limits<double>::infinity();
    for (int k = 0; k < 17; ++k)
    {
      const Eigen::Vector3d pw = k < 16 ? Eigen::Vector3d(s.tip + (k / 15.0) * (s.rcm - s.tip))
                                        : Eigen::Vector3d(s.rcm + 0.25 * (s.rcm - s.tip));
      it.above.push_back(pw.z() >= surface_.height(pw.x(), pw.y()) - 1e-4);
      it.pc.push_back(Tcw * pw);
      it.zmin = std::min(it.zmin, it.pc.back().z());
    }
    items.push_back(std::move(it));
  }
  std::stable_sort(items.begin(), items.end(), [](const Item& a, const Item& b) { return a.zmin > b.zmin; });
  for (const Item& it : items)
    drawShaft(out, it.pc, it.above, it.radius);
  stats_.shafts_ms += lap(t0);
}

void SceneRenderer::drawShaft(cv::Mat& img, const std::vector<Eigen::Vector3d>& pc, const std::vector<bool>& above,
                              double radius) const
{
  const size_t n = pc.size();
  std::vector<bool> ok(n);
  for (size_t k = 0; k < n; ++k)
  {
    const Eigen::Vector3d& p = pc[k];
    ok[k] = above[k] && p.z() > 0.003 && std::abs(p.x() / p.z()) < 2.0 * fov_.x() &&
            std::abs(p.y() / p.z()) < 2.0 * fov_.y();
  }
  // longest run of consecutive visible samples starting at the first visible one (nearest the tip)
  size_t first = 0;
  while (first < n && !ok[first])
    ++first;
  size_t last = first;
  while (last + 1 < n && ok[last + 1])
    ++last;
  if (first >= n || last - first + 1 < 2)
    return;
  const size_t m = last - first + 1;
  std::vector<Eigen::Vector2d> uv(m), nrm(m);
  std::vector<double> half(m);
  const double f = cam_.K()(0, 0);
  for (size_t k = 0; k < m; ++k)
  {
    uv[k] = cam_.project(pc[first + k]);
    half[k] = f * radius / pc[first + k].z();
  }
  for (size_t k = 0; k < m; ++k)
  {
    Eigen::Vector2d tang = k == 0 ? Eigen::Vector2d(uv[1] - uv[0]) :
                                    k == m - 1 ? Eigen::Vector2d(uv[m - 1] - uv[m - 2]) :
                                                 Eigen::Vector2d((uv[k + 1] - uv[k - 1]) / 2.0);
    Eigen::Vector2d nn(-tang.y(), tang.x());
    nrm[k] = nn / std::max(nn.norm(), 1e-9);
  }
  std::vector<cv::Point> poly(2 * m), hl(m);
  for (size_t k = 0; k < m; ++k)
  {
    const Eigen::Vector2d l = uv[k] + nrm[k] * half[k], r = uv[k] - nrm[k] * half[k];
    if (!l.allFinite() || !r.allFinite() || l.cwiseAbs().maxCoeff() > 1e5 || r.cwiseAbs().maxCoeff() > 1e5)
      return;
    poly[k] = cv::Point(int(std::nearbyint(l.x() * 16)), int(std::nearbyint(l.y() * 16)));
    poly[2 * m - 1 - k] = cv::Point(int(std::nearbyint(r.x() * 16)), int(std::nearbyint(r.y() * 16)));
    const Eigen::Vector2d h = uv[k] + nrm[k] * (0.35 * half[k]);
    hl[k] = cv::Point(int(std::nearbyint(h.x() * 16)), int(std::nearbyint(h.y() * 16)));
  }
  const cv::Point* pp = poly.data();
  const int np = static_cast<int>(poly.size());
  cv::fillPoly(img, &pp, &np, 1, cv::Scalar(105, 108, 112), cv::LINE_AA, 4);
  cv::circle(img, cv::Point(int(std::nearbyint(uv[0].x() * 16)), int(std::nearbyint(uv[0].y() * 16))),
             int(std::nearbyint(half[0] * 16)), cv::Scalar(60, 60, 62), -1, cv::LINE_AA, 4);
  std::vector<double> hs(half);
  std::sort(hs.begin(), hs.end());
  const double med = m % 2 ? hs[m / 2] : 0.5 * (hs[m / 2 - 1] + hs[m / 2]);
  const int w = std::max(1, int(std::nearbyint(0.3 * med)));
  const cv::Point* ph = hl.data();
  const int nh = static_cast<int>(hl.size());
  cv::polylines(img, &ph, &nh, 1, false, cv::Scalar(190, 192, 195), w, cv::LINE_AA, 4);
}

}  // namespace endoscope
}  // namespace saras_simulation
