/**
 * @file endoscope_renderer.h
 * @brief Ray-casting renderer of the simulated surgical scene for one raw (distorted) camera
 *        (ROS-agnostic C++ port of endoscope_renderer.py's SceneRenderer).
 *
 * Per camera pose, a static layer is rendered and cached: tissue height field (solved on a
 * coarse grid of precomputed undistorted pixel rays, colour on a finer grid, upsampled),
 * pelvic-bone boxes (exact per-pixel ray/box intersection, z-tested against the tissue) and an
 * optional planar calibration target (per-pixel ray/plane intersection). Per frame only the
 * static layer is copied and the instrument shafts are drawn. No allocation per frame once the
 * buffers exist. One renderer per eye; a renderer is not thread-safe, two renderers are
 * independent (the node renders the two eyes in two threads).
 * Units: metres, radians, pixels (pixel centres at integer coordinates).
 */
#ifndef SARAS_DRIVERS_ENDOSCOPE_RENDERER_H
#define SARAS_DRIVERS_ENDOSCOPE_RENDERER_H

#include <array>
#include <memory>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "saras_drivers/endoscope_camera.h"
#include "saras_drivers/endoscope_scene.h"

namespace saras_drivers
{
namespace endoscope
{
/// Instrument shaft: from the tip towards the RCM (and 25 % beyond, outside the trocar).
struct Shaft
{
  Eigen::Vector3d tip;   ///< tool tip, world [m]
  Eigen::Vector3d rcm;   ///< remote centre of motion, world [m]
  double radius;         ///< shaft radius [m]
};

/// Renderer options (the node's ~texture_size, ~texture_extent, ~light_distance).
struct RendererOptions
{
  int texture_size = 1024;       ///< [texels] tissue texture / height map resolution
  double texture_extent = 0.30;  ///< [m] side of the textured tissue square (centred on the surface centre)
  double light_distance = 0.10;  ///< [m] distance at which the head light gives nominal exposure
  int tissue_iterations = 6;     ///< fixed-point iterations of the tissue ray/height-field solve
                                 ///< (on a grid twice coarser than the tissue grid when it is >= 160 wide)
  int refine_iterations = 3;     ///< then iterations on the tissue grid from the upsampled solution
  int tissue_subsample = 0;      ///< [px] tissue geometry grid step (0: 2 x colour step)
  int colour_subsample = 0;      ///< [px] tissue colour grid step (0: max(2, round(2 width / 1280)))
};

class SceneRenderer
{
public:
  /// @throws std::invalid_argument on inconsistent options
  SceneRenderer(const CameraModel& camera, const TissueSurface& surface,
                const RendererOptions& options = RendererOptions());

  /// Replace the bone boxes (8 vertices each, world frame [m]); invalidates the cached layer.
  void setBoxes(const std::vector<std::array<Eigen::Vector3d, 8>>& boxes_world);
  /// Show @p target at pose T_world_board; invalidates the cached layer.
  void setTarget(std::shared_ptr<const PlanarTarget> target, const Eigen::Isometry3d& T_world_board);
  /// Hide the calibration target.
  void clearTarget();
  /// Replace the tissue texture by a uniform grey (tests of geometry and shading only).
  void setUniformTexture(unsigned char grey);

  /**
   * Static layer (tissue, bones, target) for the camera pose T_world_cam (optical frame in
   * world), re-rendered only when the pose changes by more than 1e-7 or the scene changed.
   * The reference stays valid until the next call.
   */
  const cv::Mat& background(const Eigen::Isometry3d& T_world_cam);
  /**
   * Full frame into @p out (CV_8UC3, height x width; may wrap an external buffer, e.g. an image
   * message; (re)allocated only if its size/type differ): cached static layer + shafts.
   * Shaft parts below the tissue surface or behind the camera are hidden; farthest drawn first.
   */
  void render(const Eigen::Isometry3d& T_world_cam, const std::vector<Shaft>& shafts, cv::Mat& out);

  /// Times the static layer was rendered (cache misses).
  int backgroundRenders() const { return background_renders_; }
  const CameraModel& camera() const { return cam_; }
  int colourStep() const { return colour_step_; }
  int tissueStep() const { return tissue_step_; }

private:
  struct BoxCam;
  void renderBackground(const Eigen::Isometry3d& T_world_cam);
  void solveTissue(const Eigen::Matrix3f& R, const Eigen::Vector3f& o);
  float tissueDepthAt(int u, int v) const;
  bool roi(const Eigen::Isometry3d& T_cam_world, const std::vector<Eigen::Vector3d>& pts_world,
           cv::Rect& out) const;
  void renderBoxes(const Eigen::Isometry3d& T_world_cam, const cv::Rect& depth_rect);
  void renderTarget(const Eigen::Isometry3d& T_world_cam, const cv::Rect& r);
  void drawShaft(cv::Mat& img, const std::vector<Eigen::Vector3d>& pc, const std::vector<bool>& above,
                 double radius) const;

  CameraModel cam_;
  TissueSurface surface_;
  RendererOptions opt_;
  Eigen::Vector2d fov_;
  int tissue_step_, colour_step_;
  cv::Mat rays_x_, rays_y_;        ///< full-resolution normalised rays (CV_32F)
  cv::Mat rays_lo_x_, rays_lo_y_;  ///< tissue-grid rays
  cv::Mat rays_c_x_, rays_c_y_;    ///< rays of the grid twice coarser (empty: not used)
  cv::Mat t_c_, t_init_;           ///< coarse solution and its upsampling to the tissue grid
  cv::Size colour_size_;
  // tissue maps over the textured square
  cv::Mat hmap_;        ///< height [m] at texel centres (CV_32F)
  cv::Mat nmap_;        ///< unit normal at texel centres (CV_32FC3)
  cv::Mat tex_padded_;  ///< texture padded by half its size (BORDER_REFLECT)
  int tex_pad_;
  double tex_res_, tex_x0_, tex_y0_;
  // scene
  std::vector<Box> boxes_;
  std::shared_ptr<const PlanarTarget> target_;
  Eigen::Isometry3d T_world_board_ = Eigen::Isometry3d::Identity();
  // cache + buffers (allocated once)
  bool cache_valid_ = false;
  Eigen::Isometry3d cache_pose_ = Eigen::Isometry3d::Identity();
  int background_renders_ = 0;
  cv::Mat bg_;                  ///< static layer (CV_8UC3)
  cv::Mat depth_;               ///< optical depth [m] of bones/target (CV_32F, inf = none), in their rectangles
  cv::Mat t_lo_;                ///< tissue optical depth on the tissue grid (inf = miss)
  cv::Mat maps_lo_, shade_lo_;  ///< texture coordinates (CV_32FC2) and shade x 128 on the tissue grid
  cv::Mat maps_c_, shade_c_, col_c_;  ///< the same on the colour grid, and the shaded colour
  std::vector<float> row_kz_, row_bx_, row_by_, row_t_;  ///< per-row scratch of the tissue solve
  std::vector<cv::Point2f> hull_pts_, hull_;             ///< box silhouette scratch
  std::vector<float> box_tn_;                            ///< per-row box entry depth scratch
  std::vector<int> box_face_;                            ///< per-row box entry face scratch
  const std::array<double, 3> bone_bgr_{ { 190.0, 215.0, 230.0 } };
};

/// Default (tissue_subsample, colour_subsample) [px] for an image @p width px wide.
std::pair<int, int> tissueGridSteps(int width);

}  // namespace endoscope
}  // namespace saras_drivers

#endif  // SARAS_DRIVERS_ENDOSCOPE_RENDERER_H
