/**
 * @file endoscope_renderer.h
 * @brief Ray-casting renderer of the simulated surgical scene for one raw (distorted) camera
 *        (no ROS runtime; the camera is an image_geometry::PinholeCameraModel).
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
#ifndef SARAS_SIMULATION_ENDOSCOPE_RENDERER_H
#define SARAS_SIMULATION_ENDOSCOPE_RENDERER_H

#include <array>
#include <memory>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "saras_simulation/endoscope_camera_info.h"
#include "saras_simulation/endoscope_scene.h"

namespace saras_simulation
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
  int tissue_iterations = 4;     ///< iterations of the tissue ray/height-field solve from the mean plane,
                                 ///< fixed-point, the last two Newton steps when there is a coarse grid
                                 ///< (twice coarser than the tissue grid, when that is >= 160 wide)
  int refine_iterations = 1;     ///< then Newton steps on the tissue grid from the upsampled solution
  int tissue_subsample = 0;      ///< [px] tissue geometry grid step (0: 2 x colour step)
  int colour_subsample = 0;      ///< [px] tissue colour grid step (0: max(2, round(2 width / 1280)))
};

/// Thread CPU time [ms] spent per stage since construction or resetStats() (profiling; the CLI prints it).
struct RenderStats
{
  double tissue_ms = 0;  ///< tissue ray/height-field solve + shading on the tissue grid
  double colour_ms = 0;  ///< texture sampling on the colour grid + upsampling to the image
  double boxes_ms = 0;   ///< bone silhouettes + per-pixel ray/box tests
  double target_ms = 0;  ///< calibration target
  double copy_ms = 0;    ///< static layer -> output image
  double shafts_ms = 0;  ///< instrument shafts
};

class SceneRenderer
{
public:
  /// @throws std::invalid_argument on inconsistent options
  /// @param camera the raw (distorted) camera, of a validated camera_info (cameraModel())
  SceneRenderer(const image_geometry::PinholeCameraModel& camera, const TissueSurface& surface,
                const RendererOptions& options = RendererOptions());

  /// Replace the bone boxes (8 vertices each in the vertices-file order, world frame [m]);
  /// invalidates the cached layer. @throws std::invalid_argument (boxFromVertices; scene unchanged)
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

  const RenderStats& stats() const { return stats_; }
  void resetStats() { stats_ = RenderStats(); }
  /// Times the static layer was rendered (cache misses).
  int backgroundRenders() const { return background_renders_; }
  const image_geometry::PinholeCameraModel& camera() const { return cam_; }
  int width() const { return width_; }
  int height() const { return height_; }
  int colourStep() const { return colour_step_; }
  /// Tissue optical depth z [m] of the last static layer on the tissue grid (CV_32F, inf = no
  /// tissue): cell (i, j) is the ray of raw pixel ((i + 0.5) tissueStep() - 0.5, (j + 0.5) tissueStep() - 0.5).
  const cv::Mat& tissueDepth() const { return t_lo_; }
  int tissueStep() const { return tissue_step_; }

private:
  struct BoxCam;
  /// Image region of a box for one camera pose: convex hull [px] of its outline, bounding rectangle.
  struct Silhouette
  {
    bool visible = false;
    std::vector<cv::Point2f> hull;
    cv::Rect rect;
    float zmin = 0;  ///< [m] smallest optical depth (z) of its corners
  };
  bool boxSilhouette(const Eigen::Isometry3d& T_cam_world, const std::array<Eigen::Vector3d, 8>& corners,
                     Silhouette& sil);
  /// The clipped outline clip_a_ (normalised coordinates) through the lens: convex hull [px] of
  /// its edges sampled every <= 16 px; false if a sample does not project.
  bool outlineThroughLens(std::vector<cv::Point2f>& hull);
  BoxCam boxInCamera(const Box& b, const Eigen::Isometry3d& T_cam_world) const;
  /// Ray/box test of row v, pixels [u0, u1), into bg_ / depth_ (z-tested).
  void castBoxRow(const BoxCam& bc, int v, int u0, int u1);
  void renderBackground(const Eigen::Isometry3d& T_world_cam);
  void solveTissue(const Eigen::Matrix3f& R, const Eigen::Vector3f& o);
  float tissueDepthAt(int u, int v) const;
  bool roi(const Eigen::Isometry3d& T_cam_world, const std::vector<Eigen::Vector3d>& pts_world,
           cv::Rect& out) const;
  void renderBoxes(const Eigen::Isometry3d& T_world_cam, const cv::Rect& depth_rect);
  void renderTarget(const Eigen::Isometry3d& T_world_cam, const cv::Rect& r);
  void drawShaft(cv::Mat& img, const std::vector<Eigen::Vector3d>& pc, const std::vector<bool>& above,
                 double radius) const;

  image_geometry::PinholeCameraModel cam_;
  int width_, height_;  ///< [px]
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
  RenderStats stats_;
  cv::Mat bg_;                  ///< static layer (CV_8UC3)
  cv::Mat depth_;               ///< optical depth [m] of bones/target (CV_32F, inf = none), in their rectangles
  cv::Mat t_lo_;                ///< tissue optical depth on the tissue grid (inf = miss)
  cv::Mat maps_lo_, shade_lo_;  ///< texture coordinates (CV_32FC2) and shade x 128 on the tissue grid
  cv::Mat maps_c_, shade_c_, col_c_;  ///< the same on the colour grid, and the shaded colour
  cv::Mat shade_u8_, shade_u8c3_;     ///< shade x 128 as uint8, and as 3 channels
  std::vector<float> row_kz_, row_bx_, row_by_, row_t_;  ///< per-row scratch of the tissue solve
  std::vector<float> row_gx_, row_gy_;                   ///< height gradient of the last Newton step
  std::vector<cv::Point2f> hull_pts_;                    ///< box silhouette scratch
  std::vector<cv::Point2d> poly_, clip_a_, clip_b_;      ///< box outline (normalised coordinates) scratch
  std::vector<cv::Point3d> lens_in_;                     ///< points to project through the lens (scratch)
  std::vector<cv::Point2d> lens_out_;                    ///< and their pixels
  std::vector<Silhouette> box_sil_;                      ///< per box, for the current pose
  double ray_lo_[2], ray_hi_[2];                         ///< range of the pixel rays' x/z, y/z (+ margin)
  std::vector<int> col_i0_, row_j0_;                     ///< tissue-grid taps of each pixel column / row
  std::vector<float> col_a_, row_b_;                     ///< and their weights
  std::vector<float> box_tn_;                            ///< per-row box entry depth scratch
  std::vector<int> box_face_;                            ///< per-row box entry face scratch
  const std::array<double, 3> bone_bgr_{ { 190.0, 215.0, 230.0 } };
};

/// Default (tissue_subsample, colour_subsample) [px] for an image @p width px wide.
std::pair<int, int> tissueGridSteps(int width);

}  // namespace endoscope
}  // namespace saras_simulation

#endif  // SARAS_SIMULATION_ENDOSCOPE_RENDERER_H
