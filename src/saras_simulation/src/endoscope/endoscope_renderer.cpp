/**
 * @file endoscope_renderer.cpp
 * @brief SceneRenderer: set-up, scene, cached static layer, per-frame shafts (the tissue solve is
 *        in endoscope_renderer_tissue.cpp, bones and target in endoscope_renderer_boxes.cpp).
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
using detail::Clock;
using detail::kInf;
using detail::lap;

std::pair<int, int> tissueGridSteps(int width)
{
  const int colour = std::max(2, static_cast<int>(std::nearbyint(2.0 * width / 1280.0)));
  return { 2 * colour, colour };
}

SceneRenderer::SceneRenderer(const image_geometry::PinholeCameraModel& camera, const TissueSurface& surface,
                             const RendererOptions& options)
  : cam_(camera)
  , width_(camera.fullResolution().width)
  , height_(camera.fullResolution().height)
  , surface_(surface)
  , opt_(options)
{
  const auto steps = tissueGridSteps(width_);
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
  if (width_ / tissue_step_ < 2 || height_ / tissue_step_ < 2)
    throw std::invalid_argument("image too small for the tissue grid");
  pixelRays(cam_, 1, rays_x_, rays_y_);
  for (int a = 0; a < 2; ++a)
  {
    double lo, hi;
    cv::minMaxLoc(a ? rays_y_ : rays_x_, &lo, &hi);
    const double margin = 0.01 * (hi - lo);  // the rays of the 2 px margin of the row spans
    ray_lo_[a] = lo - margin;
    ray_hi_[a] = hi + margin;
  }
  pixelRays(cam_, tissue_step_, rays_lo_x_, rays_lo_y_);
  if (rays_lo_x_.cols % 2 == 0 && rays_lo_x_.rows % 2 == 0 && rays_lo_x_.cols >= 160)
  {
    pixelRays(cam_, 2 * tissue_step_, rays_c_x_, rays_c_y_);
    t_c_.create(rays_c_x_.size(), CV_32F);
  }
  if (opt_.tissue_iterations < 1 || opt_.refine_iterations < 0)
    throw std::invalid_argument("tissue iterations must be >= 1 (refine >= 0)");
  colour_size_ = cv::Size(width_ / colour_step_, height_ / colour_step_);
  fov_ = fieldOfViewBounds(cam_);
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
  taps(width_, rays_lo_x_.cols, col_i0_, col_a_);
  taps(height_, rays_lo_x_.rows, row_j0_, row_b_);
  bg_.create(height_, width_, CV_8UC3);
  depth_.create(height_, width_, CV_32F);
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
    out = cv::Rect(0, 0, width_, height_);
    return true;
  }
  lo = lo.cwiseMax(-1.02 * fov_);
  hi = hi.cwiseMin(1.02 * fov_);
  if (lo.x() > hi.x() || lo.y() > hi.y())
    return false;
  // the rectangle's border through the camera's distortion
  std::vector<cv::Point3d> border;
  for (int k = 0; k <= 16; ++k)
  {
    const double s = k / 16.0;
    border.emplace_back(lo.x() + s * (hi.x() - lo.x()), lo.y(), 1.0);
    border.emplace_back(lo.x() + s * (hi.x() - lo.x()), hi.y(), 1.0);
    border.emplace_back(lo.x(), lo.y() + s * (hi.y() - lo.y()), 1.0);
    border.emplace_back(hi.x(), lo.y() + s * (hi.y() - lo.y()), 1.0);
  }
  std::vector<cv::Point2d> uvs;
  projectRaw(cam_, border, uvs);
  double u0 = 1e300, v0 = 1e300, u1 = -1e300, v1 = -1e300;
  for (const cv::Point2d& uv : uvs)
  {
    u0 = std::min(u0, uv.x);
    v0 = std::min(v0, uv.y);
    u1 = std::max(u1, uv.x);
    v1 = std::max(v1, uv.y);
  }
  const int x0 = std::max(int(std::floor(u0)) - 3, 0), y0 = std::max(int(std::floor(v0)) - 3, 0);
  const int x1 = std::min(int(std::ceil(u1)) + 4, width_), y1 = std::min(int(std::ceil(v1)) + 4, height_);
  if (x0 >= x1 || y0 >= y1)
    return false;
  out = cv::Rect(x0, y0, x1 - x0, y1 - y0);
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
  const double f = cam_.fx();
  std::vector<cv::Point3d> pts(m);
  std::vector<cv::Point2d> px;
  for (size_t k = 0; k < m; ++k)
  {
    const Eigen::Vector3d& p = pc[first + k];
    pts[k] = cv::Point3d(p.x(), p.y(), p.z());
    half[k] = f * radius / p.z();
  }
  projectRaw(cam_, pts, px);
  for (size_t k = 0; k < m; ++k)
    uv[k] = Eigen::Vector2d(px[k].x, px[k].y);
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
