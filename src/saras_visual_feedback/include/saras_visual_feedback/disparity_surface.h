/**
 * @file disparity_surface.h
 * @brief ROS-agnostic disparity surface of a rectified stereo region: robust plane fit of block-
 *        matching disparities, then direct photometric refinement (Gauss-Newton on the image
 *        intensities, Lucas-Kanade style) of a quadric disparity field d(u, v).
 *
 * In a rectified pair a 3D plane has a disparity affine in (u, v); a smooth surface is close to a
 * quadric over a small region. Block matching gives integer-biased disparities (1/16 px steps with
 * pixel locking); the refinement aligns the whole region at once and reaches a small fraction of a
 * pixel on textured tissue. Robust (Tukey) weights discard specular highlights, vessel edges and
 * occlusion boundaries.
 */
#ifndef SARAS_VISUAL_FEEDBACK_DISPARITY_SURFACE_H
#define SARAS_VISUAL_FEEDBACK_DISPARITY_SURFACE_H

#include <array>
#include <vector>

#include <opencv2/core.hpp>

namespace saras_visual_feedback
{

/// d(u, v) = c0 + c1 x + c2 y + c3 x^2 + c4 x y + c5 y^2 with x = (u - u0) / s, y = (v - v0) / s [px].
struct DisparitySurface
{
  double u0 = 0.0, v0 = 0.0, s = 1.0;  ///< centre and scale of the normalised coordinates [px]
  std::array<double, 6> c{};
  double operator()(double u, double v) const
  {
    const double x = (u - u0) / s, y = (v - v0) / s;
    return c[0] + c[1] * x + c[2] * y + c[3] * x * x + c[4] * x * y + c[5] * y * y;
  }
};

/**
 * @brief RANSAC plane d = c0 + c1 x + c2 y through @p samples (u, v, d) [px], refitted by least
 *        squares on its inliers (|residual| < @p threshold px). Deterministic.
 * @return inlier count (0 on failure)
 */
int fitDisparityPlane(const std::vector<cv::Point3f>& samples, double threshold, int iterations,
                      DisparitySurface* surface);

/// One rectified region of both eyes.
struct StereoRegion
{
  cv::Mat left, right;            ///< CV_32F intensities
  cv::Mat mask_left, mask_right;  ///< CV_8U, non-zero = instrument (not tissue)
  cv::Point origin_left, origin_right;  ///< rectified image coordinates of each strip's (0, 0) [px]
  cv::Rect roi;                   ///< left pixels refined, rectified image coordinates
};

struct RefineResult
{
  int pixels = 0;       ///< pixels with a non-zero weight in the last iteration
  double rms = 0.0;     ///< weighted intensity residual RMS [grey levels]
  double step = 0.0;    ///< size of the last disparity update at the region's corners [px]
};

/**
 * @brief Photometric refinement of @p surface (a quadric, or a plane when @p quadric is false, plus an
 *        intensity offset and gradient between the eyes) over the region's unmasked left pixels sampled every
 *        @p stride px. @return pixels 0 when it could not run (too few pixels, singular system).
 */
RefineResult refineDisparity(const StereoRegion& region, int stride, int iterations, bool quadric,
                             DisparitySurface* surface);

}  // namespace saras_visual_feedback

#endif  // SARAS_VISUAL_FEEDBACK_DISPARITY_SURFACE_H
