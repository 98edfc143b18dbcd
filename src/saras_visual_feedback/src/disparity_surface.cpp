#include "saras_visual_feedback/disparity_surface.h"

#include <algorithm>
#include <cmath>

#include <opencv2/imgproc.hpp>

namespace saras_visual_feedback
{
namespace
{
constexpr int kParams = 9;  ///< 6 quadric coefficients + photometric: offset, x and y gradient
constexpr int kFineIterations = 2;     ///< refinement iterations kept for the full sample set
constexpr double kCoarseStep = 0.02;   ///< [px] update below which the coarse iterations end
constexpr int kCoarseMinPixels = 2000; ///< smaller regions (in samples) are refined at full density only

/// Least-squares plane d = c0 + c1 x + c2 y on the samples within @p threshold of @p s (or all when < 0).
int refitPlane(const std::vector<cv::Point3f>& samples, double threshold, DisparitySurface* s)
{
  cv::Matx33d A = cv::Matx33d::zeros();
  cv::Vec3d b(0, 0, 0);
  int n = 0;
  for (const cv::Point3f& p : samples)
  {
    if (threshold >= 0 && std::abs(p.z - (*s)(p.x, p.y)) >= threshold)
      continue;
    const double x = (p.x - s->u0) / s->s, y = (p.y - s->v0) / s->s;
    const cv::Vec3d r(1.0, x, y);
    A += r * r.t();
    b += r * static_cast<double>(p.z);
    ++n;
  }
  cv::Vec3d c;
  if (n < 3 || !cv::solve(A, b, c, cv::DECOMP_CHOLESKY))
    return 0;
  s->c = {c[0], c[1], c[2], 0.0, 0.0, 0.0};
  return n;
}

/// Linear interpolation of row @p row at fractional column @p x (0 <= x < cols - 1).
inline float sampleRow(const float* row, double x)
{
  const int i = static_cast<int>(x);
  const float f = static_cast<float>(x - i);
  return row[i] + f * (row[i + 1] - row[i]);
}

struct Sample
{
  float r, g, x, y;  ///< residual, right gradient, normalised coordinates
};
/// Left-eye intensity predicted from the right eye's: R + offset + gx x + gy y. Each eye sees the tissue
/// under its own light: an intensity gradient between the eyes across the region, read as disparity,
/// tilts the surface (contact_accuracy, 640x360: normal error RMS 9.1 deg with an offset only, 4.7 deg
/// with the gradient; an intensity gain as well did not help).
struct Photometric
{
  double offset = 0.0, gx = 0.0, gy = 0.0;
  double operator()(double ri, double x, double y) const { return ri + offset + gx * x + gy * y; }
};
/// Residuals and right gradients of the unmasked ROI pixels (every @p stride px) under @p s.
void residuals(const StereoRegion& g, const cv::Mat& left, const cv::Mat& right, const cv::Mat& grad,
               const DisparitySurface& s, const Photometric& ph, int stride, std::vector<Sample>* samples,
               std::vector<float>* abs_r)
{
  samples->clear();
  abs_r->clear();
  const int lx0 = g.roi.x - g.origin_left.x, ly0 = g.roi.y - g.origin_left.y;
  for (int y = ly0; y < ly0 + g.roi.height; y += stride)
  {
    const float* l = left.ptr<float>(y);
    const float* r = right.ptr<float>(y);
    const float* gr = grad.ptr<float>(y);
    const std::uint8_t* ml = g.mask_left.ptr<std::uint8_t>(y);
    const std::uint8_t* mr = g.mask_right.ptr<std::uint8_t>(y);
    const double v = y + g.origin_left.y;
    for (int x = lx0; x < lx0 + g.roi.width; x += stride)
    {
      if (ml[x])
        continue;
      const double u = x + g.origin_left.x;
      const double xr = u - s(u, v) - g.origin_right.x;
      if (!(xr >= 0.0 && xr < right.cols - 1) || mr[static_cast<int>(xr + 0.5)])
        continue;
      const float ri = sampleRow(r, xr), nx = static_cast<float>((u - s.u0) / s.s),
                  ny = static_cast<float>((v - s.v0) / s.s);
      const float res = static_cast<float>(l[x] - ph(ri, nx, ny));
      samples->push_back({res, sampleRow(gr, xr), nx, ny});
      abs_r->push_back(std::abs(res));
    }
  }
}
}  // namespace

int fitDisparityPlane(const std::vector<cv::Point3f>& samples, double threshold, int iterations,
                      DisparitySurface* surface)
{
  const int n = static_cast<int>(samples.size());
  if (n < 3)
    return 0;
  cv::RNG rng(0x5a4a5);  // deterministic
  int best = -1;
  DisparitySurface best_s = *surface;
  for (int it = 0; it < iterations; ++it)
  {
    const cv::Point3f& a = samples[rng.uniform(0, n)];
    const cv::Point3f& b = samples[rng.uniform(0, n)];
    const cv::Point3f& c = samples[rng.uniform(0, n)];
    // plane through three (u, v, d) samples: d = p0 + p1 u + p2 v
    const cv::Matx33d M(1, a.x, a.y, 1, b.x, b.y, 1, c.x, c.y);
    cv::Vec3d p;
    if (std::abs(cv::determinant(M)) < 1e-6 || !cv::solve(M, cv::Vec3d(a.z, b.z, c.z), p))
      continue;
    int count = 0;
    for (int i = 0; i < n; i += 2)  // half the samples score a hypothesis
      count += std::abs(samples[i].z - (p[0] + p[1] * samples[i].x + p[2] * samples[i].y)) < threshold ? 1 : 0;
    if (count > best)
    {
      best = count;
      const double x0 = surface->u0, y0 = surface->v0, sc = surface->s;
      best_s.c = {p[0] + p[1] * x0 + p[2] * y0, p[1] * sc, p[2] * sc, 0.0, 0.0, 0.0};
    }
  }
  if (best < 3)
    return 0;
  *surface = best_s;
  refitPlane(samples, threshold, surface);
  return refitPlane(samples, threshold, surface);
}

RefineResult refineDisparity(const StereoRegion& g, int stride, int iterations, bool quadric, DisparitySurface* s)
{
  RefineResult out;
  cv::Mat left, right, grad;
  cv::GaussianBlur(g.left, left, cv::Size(5, 5), 1.0);  // widens the convergence basin, lowers noise
  cv::GaussianBlur(g.right, right, cv::Size(5, 5), 1.0);
  cv::Sobel(right, grad, CV_32F, 1, 0, 1, 0.5);  // central difference d/du
  std::vector<Sample> samples;
  std::vector<float> abs_r;
  Photometric ph;
  // Coarse to fine: Gauss-Newton iterations on every other sample (a quarter of the pixels) until the
  // update is small, then on all of them, which decide the result (same optimum, ~half the CPU).
  bool fine = iterations <= kFineIterations || g.roi.area() < kCoarseMinPixels * stride * stride;
  for (int it = 0; it < iterations; ++it)
  {
    residuals(g, left, right, grad, *s, ph, fine ? stride : 2 * stride, &samples, &abs_r);
    if (samples.size() < 50)
      return out;
    // Tukey biweight, scale from the median absolute residual.
    std::nth_element(abs_r.begin(), abs_r.begin() + abs_r.size() / 2, abs_r.end());
    const double sigma = std::max(1.0, 1.4826 * abs_r[abs_r.size() / 2]);
    const double c = 4.685 * sigma;
    cv::Matx<double, kParams, kParams> A = cv::Matx<double, kParams, kParams>::zeros();
    cv::Vec<double, kParams> b = cv::Vec<double, kParams>::all(0.0);
    double ss = 0.0, ws = 0.0;
    int used = 0;
    for (const Sample& q : samples)
    {
      if (std::abs(q.r) >= c)
        continue;
      const double t = 1.0 - (q.r / c) * (q.r / c), w = t * t;
      // r = L - R(u - d) - offset - gx x - gy y: dr/dc_k = R' phi_k, dr/d(offset, gx, gy) = -(1, x, y)
      const double J[kParams] = {q.g, q.g * q.x, q.g * q.y, q.g * q.x * q.x, q.g * q.x * q.y, q.g * q.y * q.y,
                                 -1.0, -q.x, -q.y};
      for (int i = 0; i < kParams; ++i)
      {
        b[i] -= w * J[i] * q.r;
        for (int j = i; j < kParams; ++j)
          A(i, j) += w * J[i] * J[j];
      }
      ss += w * q.r * q.r;
      ws += w;
      ++used;
    }
    for (int i = 0; i < kParams; ++i)
      for (int j = 0; j < i; ++j)
        A(i, j) = A(j, i);
    if (!quadric)  // plane only: the curvature terms are held at zero
      for (int i = 3; i < 6; ++i)
      {
        for (int j = 0; j < kParams; ++j)
          A(i, j) = A(j, i) = 0.0;
        A(i, i) = 1.0;
        b[i] = -s->c[static_cast<std::size_t>(i)];
      }
    cv::Vec<double, kParams> delta;
    if (used < 50 || !cv::solve(A, b, delta, cv::DECOMP_CHOLESKY))
      return out;
    double step = 0.0;
    for (int i = 0; i < 6; ++i)
    {
      s->c[static_cast<std::size_t>(i)] += delta[i];
      step += std::abs(delta[i]);
    }
    ph.offset += delta[6];
    ph.gx += delta[7];
    ph.gy += delta[8];
    out.pixels = used;
    out.rms = std::sqrt(ss / std::max(1e-9, ws));
    out.step = step;
    if (!fine)
      fine = step < kCoarseStep || it + 1 >= iterations - kFineIterations;
    else if (step < 1e-3)
      break;
  }
  return out;
}

}  // namespace saras_visual_feedback
