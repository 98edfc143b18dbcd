/**
 * @file endoscope_renderer_boxes.cpp
 * @brief SceneRenderer: bone boxes (silhouettes, per-pixel ray/box tests) and the calibration target.
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
namespace
{
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

/// Sutherland-Hodgman: @p poly clipped to the rectangle lo <= (x, y) <= hi (4 axis-aligned
/// half-planes); @p scratch is a buffer.
void clipToRect(std::vector<cv::Point2d>& poly, std::vector<cv::Point2d>& scratch, const double lo[2], const double hi[2])
{
  for (int side = 0; side < 4 && !poly.empty(); ++side)
  {
    const int axis = side / 2;
    const double lim = side % 2 ? hi[axis] : lo[axis];
    auto inside = [&](const cv::Point2d& p) { return side % 2 ? (axis ? p.y : p.x) <= lim : (axis ? p.y : p.x) >= lim; };
    scratch.clear();
    const size_t n = poly.size();
    for (size_t i = 0; i < n; ++i)
    {
      const cv::Point2d& p = poly[i];
      const cv::Point2d& q = poly[(i + 1) % n];
      const bool ip = inside(p), iq = inside(q);
      if (ip)
        scratch.push_back(p);
      if (ip != iq)
      {
        const double pv = axis ? p.y : p.x, qv = axis ? q.y : q.x;
        scratch.push_back(p + (lim - pv) / (qv - pv) * (q - p));
      }
    }
    poly.swap(scratch);
  }
}

/// x range [u0, u1) of the pixels of row @p v within 2 px of the convex @p hull (clipped to the
/// given range); false if the row band misses the hull.
bool hullRowSpan(const std::vector<cv::Point2f>& hull, int v, int& u0, int& u1)
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
    return false;
  u0 = std::max(u0, int(std::floor(lo)) - 2);
  u1 = std::min(u1, int(std::ceil(hi)) + 3);
  return u0 < u1;
}
}  // namespace

using detail::kInf;

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
  clipToRect(clip_a_, clip_b_, ray_lo_, ray_hi_);
  if (clip_a_.empty() || !outlineThroughLens(sil.hull))
    return false;
  float bx0 = 1e30f, by0 = 1e30f, bx1 = -1e30f, by1 = -1e30f;
  for (const cv::Point2f& p : sil.hull)
  {
    bx0 = std::min(bx0, p.x);
    by0 = std::min(by0, p.y);
    bx1 = std::max(bx1, p.x);
    by1 = std::max(by1, p.y);
  }
  const int x0 = std::max(int(std::floor(bx0)) - 3, 0), y0 = std::max(int(std::floor(by0)) - 3, 0);
  const int x1 = std::min(int(std::ceil(bx1)) + 4, width_);
  const int y1 = std::min(int(std::ceil(by1)) + 4, height_);
  if (x0 >= x1 || y0 >= y1)
    return false;
  sil.rect = cv::Rect(x0, y0, x1 - x0, y1 - y0);
  return true;
}

bool SceneRenderer::outlineThroughLens(std::vector<cv::Point2f>& hull)
{
  // the polygon's vertices, then its edges sampled every <= 16 px, through the camera's distortion
  const size_t n = clip_a_.size();
  lens_in_.clear();
  for (const cv::Point2d& p : clip_a_)
    lens_in_.emplace_back(p.x, p.y, 1.0);
  projectRaw(cam_, lens_in_, lens_out_);
  const std::vector<cv::Point2d> corners(lens_out_);
  lens_in_.clear();
  for (size_t i = 0; i < n; ++i)
  {
    const cv::Point2d &p = clip_a_[i], &q = clip_a_[(i + 1) % n];
    const double len = cv::norm(corners[(i + 1) % n] - corners[i]);
    const int steps = std::min(std::max(static_cast<int>(std::ceil(len / 16.0)), 1), 256);
    for (int k = 0; k < steps; ++k)
    {
      const cv::Point2d xy = p + (double(k) / steps) * (q - p);
      lens_in_.emplace_back(xy.x, xy.y, 1.0);
    }
  }
  projectRaw(cam_, lens_in_, lens_out_);
  hull_pts_.clear();
  for (const cv::Point2d& uv : lens_out_)
  {
    if (!std::isfinite(uv.x) || !std::isfinite(uv.y))
      return false;
    hull_pts_.emplace_back(float(uv.x), float(uv.y));
  }
  cv::convexHull(hull_pts_, hull);
  return true;
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

SceneRenderer::BoxCam SceneRenderer::boxInCamera(const Box& b, const Eigen::Isometry3d& Tcw) const
{
  const double L = opt_.light_distance;
  BoxCam bc;
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
        bc.colour[2 * i + sg][ch] = cv::saturate_cast<uchar>(std::min(std::max(shade * bone_bgr_[ch], 1.0), 255.0));
    }
  }
  return bc;
}

SARAS_ENDOSCOPE_MULTIVERSION
void SceneRenderer::renderBoxes(const Eigen::Isometry3d& T_world_cam, const cv::Rect& depth_rect)
{
  const Eigen::Isometry3d Tcw = T_world_cam.inverse();
  box_tn_.resize(width_);
  box_face_.resize(width_);
  for (size_t k = 0; k < boxes_.size(); ++k)
  {
    const Silhouette& sil = box_sil_[k];
    if (!sil.visible)
      continue;
    BoxCam bc = boxInCamera(boxes_[k], Tcw);
    bc.rect = sil.rect & depth_rect;
    for (int v = bc.rect.y; v < bc.rect.y + bc.rect.height; ++v)
    {
      int u0 = bc.rect.x, u1 = bc.rect.x + bc.rect.width;
      if (!hullRowSpan(sil.hull, v, u0, u1))
        continue;
      // the whole span behind the tissue (every interpolation tap of the tissue depth nearer
      // than the box's nearest corner): nothing of this box is visible in the row
      const float* t0 = t_lo_.ptr<float>(row_j0_[v]);
      const float* t1 = t_lo_.ptr<float>(row_j0_[v] + 1);
      float tmax = 0.f;
      for (int i = col_i0_[u0], ie = col_i0_[u1 - 1] + 1; i <= ie; ++i)
        tmax = std::max(tmax, std::max(t0[i], t1[i]));
      if (sil.zmin > tmax)
        continue;
      castBoxRow(bc, v, u0, u1);
    }
  }
}

SARAS_ENDOSCOPE_CLONE_INLINE inline void SceneRenderer::castBoxRow(const BoxCam& bc, int v, int u0, int u1)
{
  const float near = 1e-3f;
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

}  // namespace endoscope
}  // namespace saras_simulation
