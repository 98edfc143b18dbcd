/**
 * @file synthetic_stereo.h
 * @brief Test helper: ray-cast stereo pairs of a textured plane with instrument shafts (capsules),
 *        through a distorted (plumb_bob) camera pair with parallel optical frames.
 */
#ifndef SARAS_VISUAL_FEEDBACK_TEST_SYNTHETIC_STEREO_H
#define SARAS_VISUAL_FEEDBACK_TEST_SYNTHETIC_STEREO_H

#include <cmath>
#include <limits>
#include <vector>

#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

#include "saras_visual_feedback/stereo_contact.h"

namespace synthetic
{
using saras_visual_feedback::CameraIntrinsics;
using saras_visual_feedback::DistortionModel;
using saras_visual_feedback::StereoCalibration;

/// The simulated endoscope's calibration scaled to @p width (16:9), baseline @p baseline [m].
inline StereoCalibration calibration(int width, double baseline = 0.005)
{
  const double s = width / 1280.0;
  CameraIntrinsics k;
  k.width = width;
  k.height = width * 9 / 16;
  k.fx = k.fy = 900.0 * s;
  k.cx = (k.width - 1) / 2.0;
  k.cy = (k.height - 1) / 2.0;
  k.model = DistortionModel::kPlumbBob;
  k.d = {-0.12, 0.05, 0.0005, -0.0003, 0.0, 0, 0, 0};
  StereoCalibration c;
  c.left = c.right = k;
  c.P_left = cv::Matx34d(k.fx, 0, k.cx, 0, 0, k.fy, k.cy, 0, 0, 0, 1, 0);
  c.P_right = c.P_left;
  c.P_right(0, 3) = -k.fx * baseline;
  return c;
}

/// A capsule (instrument shaft) from tip to end [m], left optical frame.
struct Capsule
{
  cv::Vec3d tip, end;
  double radius;
};

/// Scene in the left optical frame: textured plane through point p with unit normal n.
struct Scene
{
  cv::Vec3d p{0, 0, 0.06}, n{0, 0, -1};
  cv::Mat texture;          ///< CV_32F, texel size `texel` [m], centred on p
  double texel = 1e-4;
  std::vector<Capsule> shafts;
  double noise = 1.5;       ///< image noise (grey levels)
};

/// Blurred random texture (size x size texels), or uniform when @p textured is false.
inline cv::Mat texture(int size = 1024, bool textured = true)
{
  cv::Mat t(size, size, CV_32F, cv::Scalar(140));
  if (!textured)
    return t;
  cv::RNG rng(42);
  cv::Mat noise(size, size, CV_32F);
  rng.fill(noise, cv::RNG::NORMAL, 0.0, 60.0);
  cv::GaussianBlur(noise, noise, cv::Size(0, 0), 2.0);
  return t + 2.5 * noise;
}

/// Distance along the unit ray o + t d to the capsule, +inf when missed.
inline double hitCapsule(const cv::Vec3d& o, const cv::Vec3d& d, const Capsule& c)
{
  const double inf = std::numeric_limits<double>::infinity();
  double best = inf;
  const cv::Vec3d axis = c.end - c.tip;
  const double len = cv::norm(axis);
  const cv::Vec3d w = axis / len;
  const cv::Vec3d m = o - c.tip;
  const cv::Vec3d dp = d - w * d.dot(w), mp = m - w * m.dot(w);
  const double A = dp.dot(dp), B = 2 * dp.dot(mp), C = mp.dot(mp) - c.radius * c.radius;
  const double disc = B * B - 4 * A * C;
  if (A > 1e-12 && disc >= 0)
  {
    const double t = (-B - std::sqrt(disc)) / (2 * A);
    const double s = (m + d * t).dot(w);
    if (t > 0 && s >= 0 && s <= len)
      best = t;
  }
  const double b = m.dot(d), cc = m.dot(m) - c.radius * c.radius, ds = b * b - cc;  // tip sphere
  if (ds >= 0 && -b - std::sqrt(ds) > 0)
    best = std::min(best, -b - std::sqrt(ds));
  return best;
}

/// Renders the raw image of one eye (centre @p eye_x [m] on the left optical frame's x axis).
inline cv::Mat render(const Scene& sc, const CameraIntrinsics& k, double eye_x, unsigned seed)
{
  std::vector<cv::Point2f> px;
  px.reserve(static_cast<std::size_t>(k.width) * k.height);
  for (int y = 0; y < k.height; ++y)
    for (int x = 0; x < k.width; ++x)
      px.emplace_back(static_cast<float>(x), static_cast<float>(y));
  std::vector<cv::Point2f> rays;
  const cv::Matx33d K(k.fx, 0, k.cx, 0, k.fy, k.cy, 0, 0, 1);
  cv::undistortPoints(px, rays, K, std::vector<double>(k.d.begin(), k.d.begin() + 5));
  cv::Vec3d e1 = std::abs(sc.n[0]) < 0.9 ? cv::Vec3d(1, 0, 0) : cv::Vec3d(0, 1, 0);
  e1 = e1 - sc.n * sc.n.dot(e1);
  e1 /= cv::norm(e1);
  const cv::Vec3d e2 = sc.n.cross(e1);
  const cv::Vec3d o(eye_x, 0, 0);
  cv::Mat img(k.height, k.width, CV_8UC3);
  cv::RNG rng(seed);
  for (int y = 0; y < k.height; ++y)
    for (int x = 0; x < k.width; ++x)
    {
      const cv::Point2f& r = rays[static_cast<std::size_t>(y) * k.width + x];
      cv::Vec3d d(r.x, r.y, 1.0);
      d /= cv::norm(d);
      const double den = d.dot(sc.n);
      const double tp = std::abs(den) > 1e-9 ? (sc.p - o).dot(sc.n) / den : -1.0;
      double ts = std::numeric_limits<double>::infinity();
      for (const Capsule& c : sc.shafts)
        ts = std::min(ts, hitCapsule(o, d, c));
      double v = 0.0;
      if (ts < (tp > 0 ? tp : std::numeric_limits<double>::infinity()))
        v = 200.0 + 20.0 * std::sin(ts * 3000.0);  // metallic shaft, nearly uniform
      else if (tp > 0)
      {
        const cv::Vec3d h = o + d * tp - sc.p;
        const double tu = h.dot(e1) / sc.texel + sc.texture.cols / 2.0, tv = h.dot(e2) / sc.texel + sc.texture.rows / 2.0;
        const int iu = static_cast<int>(std::floor(tu)), iv = static_cast<int>(std::floor(tv));
        if (iu >= 0 && iv >= 0 && iu + 1 < sc.texture.cols && iv + 1 < sc.texture.rows)
        {
          const double fu = tu - iu, fv = tv - iv;
          const float* r0 = sc.texture.ptr<float>(iv);
          const float* r1 = sc.texture.ptr<float>(iv + 1);
          v = (1 - fv) * ((1 - fu) * r0[iu] + fu * r0[iu + 1]) + fv * ((1 - fu) * r1[iu] + fu * r1[iu + 1]);
        }
      }
      v += rng.gaussian(sc.noise);
      const auto g = cv::saturate_cast<std::uint8_t>(v);
      img.at<cv::Vec3b>(y, x) = cv::Vec3b(cv::saturate_cast<std::uint8_t>(0.7 * g), cv::saturate_cast<std::uint8_t>(0.8 * g), g);
    }
  return img;
}

}  // namespace synthetic

#endif  // SARAS_VISUAL_FEEDBACK_TEST_SYNTHETIC_STEREO_H
