/**
 * @file stereo_contact.h
 * @brief ROS-agnostic vision-based contact estimator (D7.2 Section 8): the penetration of a tool
 *        tip into the tissue, from the endoscope's stereo pair around the tip.
 *
 * Per tool and stereo frame: the tip and the shaft (known from kinematics, in the left optical
 * frame at the image stamp) are projected into the rectified pair; a region of interest around
 * the tip is rectified from the raw images (cv::remap of the ROI only), the instruments' shafts
 * are masked out (projected capsules, in both eyes), the disparity is matched with OpenCV's block
 * matcher over the disparity range the tip's depth allows, a disparity plane is fitted to the
 * matches robustly (RANSAC) and refined photometrically into a quadric disparity field
 * (disparity_surface.h: sub-pixel alignment of the whole region, robust to highlights and edges);
 * the field is triangulated, and a plane then a quadric height field are fitted in 3D. The surface point closest to the tip, its outward normal (towards
 * the camera) and the signed distance of the tip give the contact:
 * depth = max(0, -signed distance).
 *
 * When the estimator cannot know (tip out of view, too much of the region masked or occluded,
 * too little texture, no consistent surface) it says so (ContactState::kUnknown, confidence 0)
 * instead of reporting a confident zero.
 *
 * Frames: "left optical frame" is the raw left camera's optical frame (REP 103: z forward, x
 * right, y down), metres; the rectified frame is the left optical frame rotated by R_left.
 */
#ifndef SARAS_VISUAL_FEEDBACK_STEREO_CONTACT_H
#define SARAS_VISUAL_FEEDBACK_STEREO_CONTACT_H

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>

#include "saras_visual_feedback/raw_projector.h"

namespace saras_visual_feedback
{
struct DisparitySurface;
struct RefineResult;
}

namespace saras_visual_feedback
{

/// Calibration of the stereo pair, as image_geometry::StereoCameraModel provides it.
struct StereoCalibration
{
  CameraIntrinsics left, right;  ///< raw images (K, D, size)
  cv::Matx33d R_left = cv::Matx33d::eye(), R_right = cv::Matx33d::eye();  ///< rectification rotations
  cv::Matx34d P_left, P_right;   ///< rectified projections; P_right(0,3) = -fx' * baseline
};

/// Estimator parameters (config/stereo_contact.yaml).
struct StereoContactParams
{
  double patch_radius = 0.012;   ///< [m] tissue patch fitted around the tip
  double near_margin = 0.02;     ///< [m] surface searched up to this much closer to the camera than the tip
  double far_margin = 0.03;      ///< [m] ... and up to this much farther
  int block_size = 9;            ///< [px] matching window (odd, 5..31) at 1280 px width, scaled with fx
  int texture_threshold = 10;    ///< StereoBM texture threshold (pixels below are invalid)
  int uniqueness_ratio = 10;     ///< [%] StereoBM uniqueness margin
  double mask_margin = 0.0015;   ///< [m] added to each shaft's radius when masking
  int min_points = 150;          ///< fewer triangulated points: unknown (too little texture)
  double min_valid_fraction = 0.15;  ///< of the unmasked ROI pixels; fewer valid disparities: unknown
  double max_masked_fraction = 0.8;  ///< more of the ROI masked: unknown (occluded)
  double inlier_threshold = 0.0006;  ///< [m] RANSAC / refit inlier distance
  double min_inlier_ratio = 0.5;     ///< fewer inliers: unknown (no consistent surface)
  int ransac_iterations = 60;
  int refine_iterations = 10;        ///< photometric (Gauss-Newton) refinement of the disparity surface
  double contact_threshold = 0.0;    ///< [m] depth above this is a contact (0: any penetration)
  int max_roi = 160;                 ///< [px] largest ROI side (the patch is shrunk beyond)
  int sample_grid = 40;              ///< ROI samples per side at most (every max(1, side / sample_grid) px)
};

/// Checks ranges; on failure names the offending parameter in @p error.
bool validateStereoContactParams(const StereoContactParams& p, std::string* error);

/// One instrument, in the left optical frame at the image stamp.
struct InstrumentView
{
  bool valid = false;      ///< false: pose or transform missing (ignored for masking)
  cv::Point3d tip;         ///< [m]
  bool has_shaft = false;
  cv::Point3d shaft;       ///< [m] a point up the shaft (towards the trocar)
  double radius = 0.0025;  ///< [m] shaft radius
};

enum class ContactState
{
  kUnknown,    ///< cannot tell (see ContactUnknown)
  kNoContact,  ///< surface seen, tip above it (or penetration below contact_threshold)
  kContact     ///< tip below the surface
};

enum class ContactUnknown
{
  kNone,           ///< known
  kNoCalibration,  ///< configure() not called successfully
  kNoPose,         ///< the tool's pose/transform is missing
  kOutOfView,      ///< tip behind the camera or its region outside the images
  kOccluded,       ///< most of the region masked by instruments, or no surface on all sides of the tip
  kNoTexture,      ///< too few valid disparities / points
  kNoSurface       ///< no consistent surface (too few RANSAC inliers)
};

const char* toString(ContactState s);
const char* toString(ContactUnknown u);

/// Result for one tool and frame.
struct ContactEstimate
{
  ContactState state = ContactState::kUnknown;
  ContactUnknown unknown = ContactUnknown::kNoCalibration;
  double depth = 0.0;            ///< [m] >= 0, 0 unless kContact
  double signed_distance = 0.0;  ///< [m] of the tip from the surface along the normal (> 0 above)
  cv::Vec3d normal{0.0, 0.0, -1.0};  ///< unit outward normal (towards the camera), left optical frame
  cv::Point3d surface;           ///< [m] surface point closest to the tip, left optical frame
  double confidence = 0.0;       ///< [0, 1], 0 when unknown
  int points = 0;                ///< triangulated points
  int inliers = 0;               ///< of the final fit
  double rms = 0.0;              ///< [m] residual RMS of the final fit
  double photometric_rms = 0.0;  ///< [grey levels] intensity residual of the refined disparity surface
  cv::Rect roi;                  ///< region of the rectified left image used
};

/**
 * @brief Stereo contact estimator. configure() once per calibration; estimate() per tool and frame.
 *
 * Not thread-safe (scratch buffers reused): one instance per processing thread.
 */
class StereoContactEstimator
{
public:
  explicit StereoContactEstimator(const StereoContactParams& params = StereoContactParams());

  /// Builds the rectification maps; false (reason in @p error) for an unusable calibration.
  bool configure(const StereoCalibration& calibration, std::string* error);
  bool configured() const { return configured_; }
  const StereoCalibration& calibration() const { return cal_; }
  const StereoContactParams& params() const { return p_; }

  /**
   * @brief Contact of tool @p which among @p tools (all valid tools' shafts are masked).
   * @param left, right raw images, CV_8UC1/3/4 (colour in BGR or RGB: only luminance is used),
   *        of the calibrated size
   */
  ContactEstimate estimate(const cv::Mat& left, const cv::Mat& right, const InstrumentView* tools, std::size_t n,
                           std::size_t which);

  /// Rectified left pixel of a point in the left optical frame (false when behind the camera).
  bool projectRectified(const cv::Point3d& p, bool right_eye, cv::Point2d* pixel) const;

  /// Triangulated points (left optical frame) of the last estimate() (for drawing and tests).
  const std::vector<cv::Point3d>& lastPoints() const { return points_; }

private:
  /// Rectifies, masks and block-matches the region around the tip at depth @p z [m].
  void matchRegion(const cv::Mat& left, const cv::Mat& right, const InstrumentView* tools, std::size_t n,
                   const cv::Rect& roi, double z, int* shift, int* num_disp);
  bool rectifyStrips(const cv::Mat& left, const cv::Mat& right, const cv::Rect& roi, int shift, int num_disp);
  void maskShafts(const InstrumentView* tools, std::size_t n, const cv::Rect& roi, int shift, int num_disp);
  int collectSamples(const cv::Rect& roi, int shift, int num_disp, int step, int* unmasked);
  /// Photometric refinement of @p ds on the strips of the last matchRegion().
  RefineResult refine(const cv::Rect& roi, int shift, int num_disp, int step, bool quadric, DisparitySurface* ds);
  void surfacePoints(const DisparitySurface& ds, const cv::Rect& roi, int num_disp, int step);
  bool fitSurface(const cv::Point3d& tip, ContactEstimate* out);

  StereoContactParams p_;
  StereoCalibration cal_;
  bool configured_ = false;
  double fx_ = 0.0, fy_ = 0.0, cx_ = 0.0, cy_ = 0.0, fb_ = 0.0;  ///< rectified intrinsics; fb = fx' * baseline
  cv::Mat map_left_[2], map_right_[2];  ///< fixed-point rectification maps (CV_16SC2 + CV_16UC1)
  cv::Mat strip_colour_, strip_left_, strip_right_, mask_left_, mask_right_, disparity_;
  std::vector<cv::Point3f> samples_;  ///< block-matching samples (u, v, disparity) [px]
  std::vector<cv::Point3d> points_;
  std::vector<int> inlier_idx_;
  cv::Ptr<cv::StereoBM> matcher_;
};

}  // namespace saras_visual_feedback

#endif  // SARAS_VISUAL_FEEDBACK_STEREO_CONTACT_H
