#include "saras_visual_feedback/stereo_contact.h"
#include "saras_visual_feedback/disparity_surface.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

namespace saras_visual_feedback
{
namespace
{
constexpr int kMaxDisparities = 256;
constexpr int kSectors = 16;      ///< angular sectors around the tip checked for surface coverage
constexpr int kMaskSegments = 8;  ///< pieces of a projected shaft capsule

/// Remaps the rectified region [x0, x0 + w) x [y0, y0 + h) of @p src into @p dst (zeros outside the image).
void remapRegion(const cv::Mat& src, const cv::Mat map[2], int x0, int y0, int w, int h, cv::Mat* dst)
{
  dst->create(h, w, src.type());
  dst->setTo(cv::Scalar::all(0));
  const cv::Rect full(0, 0, map[0].cols, map[0].rows);
  const cv::Rect want(x0, y0, w, h);
  const cv::Rect r = want & full;
  if (r.area() <= 0)
    return;
  cv::Mat out = (*dst)(cv::Rect(r.x - x0, r.y - y0, r.width, r.height));
  cv::remap(src, out, map[0](r), map[1](r), cv::INTER_LINEAR, cv::BORDER_CONSTANT);
}

void toGray(const cv::Mat& in, cv::Mat* out)
{
  if (in.channels() == 1)
    in.copyTo(*out);
  else if (in.channels() == 3)
    cv::cvtColor(in, *out, cv::COLOR_BGR2GRAY);
  else
    cv::cvtColor(in, *out, cv::COLOR_BGRA2GRAY);
}

/// Unit normal of three points; false when degenerate.
bool planeOf(const cv::Point3d& a, const cv::Point3d& b, const cv::Point3d& c, cv::Vec3d* n)
{
  const cv::Vec3d u(b - a), v(c - a);
  const cv::Vec3d x = u.cross(v);
  const double len = cv::norm(x);
  if (!(len > 1e-12))
    return false;
  *n = x / len;
  return true;
}

/// Quadric height field w = c0 + c1 u + c2 v + c3 u^2 + c4 u v + c5 v^2 (c3..c5 zero for a plane).
struct HeightField
{
  cv::Point3d origin;
  cv::Vec3d e1, e2, e3;  ///< local frame, e3 = outward plane normal
  std::array<double, 6> c{};

  double h(double u, double v) const { return c[0] + c[1] * u + c[2] * v + c[3] * u * u + c[4] * u * v + c[5] * v * v; }
  double hu(double u, double v) const { return c[1] + 2 * c[3] * u + c[4] * v; }
  double hv(double u, double v) const { return c[2] + c[4] * u + 2 * c[5] * v; }
  cv::Vec3d local(const cv::Point3d& p) const
  {
    const cv::Vec3d d(p - origin);
    return cv::Vec3d(d.dot(e1), d.dot(e2), d.dot(e3));
  }
  double residual(const cv::Point3d& p) const
  {
    const cv::Vec3d l = local(p);
    return l[2] - h(l[0], l[1]);
  }
};

/// Least-squares fit of @p f's coefficients on @p idx of @p pts (quadric when @p quadric).
bool fitHeight(const std::vector<cv::Point3d>& pts, const std::vector<int>& idx, bool quadric, HeightField* f)
{
  const int m = quadric ? 6 : 3;
  cv::Matx66d A = cv::Matx66d::zeros();
  cv::Vec6d b(0, 0, 0, 0, 0, 0);
  for (int i : idx)
  {
    const cv::Vec3d l = f->local(pts[i]);
    const double row[6] = {1.0, l[0], l[1], l[0] * l[0], l[0] * l[1], l[1] * l[1]};
    for (int r = 0; r < m; ++r)
    {
      b[r] += row[r] * l[2];
      for (int c = 0; c < m; ++c)
        A(r, c) += row[r] * row[c];
    }
  }
  for (int r = m; r < 6; ++r)
    A(r, r) = 1.0;
  cv::Vec6d x;
  if (!cv::solve(A, b, x, cv::DECOMP_CHOLESKY))
    return false;
  for (int r = 0; r < 6; ++r)
    f->c[static_cast<std::size_t>(r)] = r < m ? x[r] : 0.0;
  return true;
}

/// Largest run of consecutive empty sectors (of kSectors) around (0, 0) among @p idx's local (u, v).
int largestGap(const std::vector<cv::Point3d>& pts, const std::vector<int>& idx, const HeightField& f,
               const cv::Vec3d& tip)
{
  std::array<int, kSectors> count{};
  for (int i : idx)
  {
    const cv::Vec3d l = f.local(pts[i]);
    const double a = std::atan2(l[1] - tip[1], l[0] - tip[0]);
    const int s = static_cast<int>(std::floor((a + CV_PI) / (2 * CV_PI) * kSectors)) % kSectors;
    ++count[static_cast<std::size_t>(s)];
  }
  const int min_count = std::max<int>(3, static_cast<int>(idx.size()) / (kSectors * 10));
  int best = 0, run = 0;
  for (int k = 0; k < 2 * kSectors; ++k)
  {
    run = count[static_cast<std::size_t>(k % kSectors)] < min_count ? run + 1 : 0;
    best = std::max(best, std::min(run, kSectors));
  }
  return best;
}
/// Surface point of @p f closest to @p tl (local frame), by iterated tangent-plane projection:
/// signed distance, outward normal and point (camera frame) into @p out.
void closestPoint(const HeightField& f, const cv::Vec3d& tl, ContactEstimate* out)
{
  double u = tl[0], v = tl[1];
  cv::Vec3d nl;
  for (int k = 0; k < 4; ++k)
  {
    nl = cv::Vec3d(-f.hu(u, v), -f.hv(u, v), 1.0);
    nl /= cv::norm(nl);
    const cv::Vec3d q = tl - nl * nl.dot(tl - cv::Vec3d(u, v, f.h(u, v)));
    u = q[0];
    v = q[1];
  }
  const cv::Vec3d s(u, v, f.h(u, v));
  out->signed_distance = nl.dot(tl - s);
  const cv::Vec3d n_cam = f.e1 * nl[0] + f.e2 * nl[1] + f.e3 * nl[2];
  out->normal = n_cam / cv::norm(n_cam);
  out->surface = f.origin + cv::Point3d(f.e1 * s[0] + f.e2 * s[1] + f.e3 * s[2]);
}

/// Largest run of consecutive empty sectors (of kSectors) of the matching inliers around the tip pixel.
int largestImageGap(const std::vector<cv::Point3f>& samples, const DisparitySurface& ds, const cv::Point2d& tip)
{
  std::array<int, kSectors> count{};
  int n = 0;
  for (const cv::Point3f& p : samples)
  {
    if (std::abs(p.z - ds(p.x, p.y)) >= 1.0)
      continue;
    const double a = std::atan2(p.y - tip.y, p.x - tip.x);
    ++count[static_cast<std::size_t>(static_cast<int>(std::floor((a + CV_PI) / (2 * CV_PI) * kSectors)) % kSectors)];
    ++n;
  }
  const int min_count = std::max(3, n / (kSectors * 10));
  int best = 0, run = 0;
  for (int k = 0; k < 2 * kSectors; ++k)
  {
    run = count[static_cast<std::size_t>(k % kSectors)] < min_count ? run + 1 : 0;
    best = std::max(best, std::min(run, kSectors));
  }
  return best;
}
}  // namespace

const char* toString(ContactState s)
{
  switch (s)
  {
    case ContactState::kContact:
      return "contact";
    case ContactState::kNoContact:
      return "no contact";
    default:
      return "unknown";
  }
}

const char* toString(ContactUnknown u)
{
  switch (u)
  {
    case ContactUnknown::kNone:
      return "known";
    case ContactUnknown::kNoCalibration:
      return "no calibration";
    case ContactUnknown::kNoPose:
      return "no tool pose";
    case ContactUnknown::kOutOfView:
      return "tip out of view";
    case ContactUnknown::kOccluded:
      return "tip region occluded";
    case ContactUnknown::kNoTexture:
      return "too little texture";
    default:
      return "no consistent surface";
  }
}

bool validateStereoContactParams(const StereoContactParams& p, std::string* error)
{
  std::string why;
  if (!(p.patch_radius > 0.0005 && p.patch_radius < 0.05))
    why = "patch_radius must be in (0.0005, 0.05) m";
  else if (!(p.near_margin > 0.0 && p.far_margin > 0.0))
    why = "near_margin and far_margin must be > 0 m";
  else if (p.block_size < 5 || p.block_size > 31 || p.block_size % 2 == 0)
    why = "block_size must be odd in [5, 31] px";
  else if (p.texture_threshold < 0 || p.uniqueness_ratio < 0 || p.uniqueness_ratio > 100)
    why = "texture_threshold must be >= 0 and uniqueness_ratio in [0, 100]";
  else if (!(p.mask_margin >= 0.0))
    why = "mask_margin must be >= 0 m";
  else if (p.min_points < 10)
    why = "min_points must be >= 10";
  else if (!(p.min_valid_fraction >= 0.0 && p.min_valid_fraction < 1.0 && p.max_masked_fraction > 0.0 &&
             p.max_masked_fraction <= 1.0 && p.min_inlier_ratio >= 0.0 && p.min_inlier_ratio < 1.0))
    why = "min_valid_fraction, max_masked_fraction and min_inlier_ratio must be fractions";
  else if (!(p.inlier_threshold > 0.0))
    why = "inlier_threshold must be > 0 m";
  else if (p.ransac_iterations < 1)
    why = "ransac_iterations must be >= 1";
  else if (p.refine_iterations < 0 || p.refine_iterations > 100)
    why = "refine_iterations must be in [0, 100]";
  else if (!(p.contact_threshold >= 0.0))
    why = "contact_threshold must be >= 0 m";
  else if (p.max_roi < 32 || p.sample_grid < 16)
    why = p.max_roi < 32 ? "max_roi must be >= 32 px" : "sample_grid must be >= 16 samples";
  if (error)
    *error = why;
  return why.empty();
}

StereoContactEstimator::StereoContactEstimator(const StereoContactParams& params) : p_(params)
{
}

bool StereoContactEstimator::configure(const StereoCalibration& cal, std::string* error)
{
  configured_ = false;
  std::string why;
  RawProjector check;
  if (!check.configure(cal.left, &why) || !check.configure(cal.right, &why))
    why = "invalid camera: " + why;
  else if (cal.left.width != cal.right.width || cal.left.height != cal.right.height)
    why = "left and right images differ in size";
  else if (!(cal.P_left(0, 0) > 0 && cal.P_left(1, 1) > 0))
    why = "rectified projection P of the left camera is not set";
  else if (!(-cal.P_right(0, 3) > 0))
    why = "P of the right camera must have Tx = -fx * baseline < 0 (horizontal pair, right eye to the right)";
  if (!why.empty())
  {
    if (error)
      *error = why;
    return false;
  }
  cal_ = cal;
  fx_ = cal.P_left(0, 0);
  fy_ = cal.P_left(1, 1);
  cx_ = cal.P_left(0, 2);
  cy_ = cal.P_left(1, 2);
  fb_ = -cal.P_right(0, 3);
  const cv::Size size(cal.left.width, cal.left.height);
  const CameraIntrinsics* k[2] = {&cal.left, &cal.right};
  const cv::Matx33d* R[2] = {&cal.R_left, &cal.R_right};
  const cv::Matx34d* P[2] = {&cal.P_left, &cal.P_right};
  cv::Mat* maps[2] = {map_left_, map_right_};
  for (int e = 0; e < 2; ++e)
  {
    const cv::Matx33d K(k[e]->fx, 0, k[e]->cx, 0, k[e]->fy, k[e]->cy, 0, 0, 1);
    const cv::Matx33d newK = P[e]->get_minor<3, 3>(0, 0);
    if (k[e]->model == DistortionModel::kEquidistant)
      cv::fisheye::initUndistortRectifyMap(K, std::vector<double>(k[e]->d.begin(), k[e]->d.begin() + 4), *R[e], newK,
                                           size, CV_16SC2, maps[e][0], maps[e][1]);
    else
      cv::initUndistortRectifyMap(K, std::vector<double>(k[e]->d.begin(), k[e]->d.end()), *R[e], newK, size, CV_16SC2,
                                  maps[e][0], maps[e][1]);
  }
  configured_ = true;
  return true;
}

bool StereoContactEstimator::projectRectified(const cv::Point3d& p, bool right_eye, cv::Point2d* pixel) const
{
  const cv::Vec3d q = cal_.R_left * cv::Vec3d(p.x, p.y, p.z);
  if (!(q[2] > 1e-4))
    return false;
  const cv::Matx34d& P = right_eye ? cal_.P_right : cal_.P_left;
  const cv::Vec3d h = P * cv::Vec4d(q[0], q[1], q[2], 1.0);
  *pixel = cv::Point2d(h[0] / h[2], h[1] / h[2]);
  return true;
}

bool StereoContactEstimator::rectifyStrips(const cv::Mat& left, const cv::Mat& right, const cv::Rect& roi, int shift,
                                           int num_disp)
{
  // Left strip: the ROI plus num_disp columns on its left (the matcher's search margin); right
  // strip: the same rows, shifted left by `shift`, so that a strip disparity d' is d' + shift.
  const int w = roi.width + num_disp;
  remapRegion(left, map_left_, roi.x - num_disp, roi.y, w, roi.height, &strip_colour_);
  toGray(strip_colour_, &strip_left_);
  remapRegion(right, map_right_, roi.x - num_disp - shift, roi.y, w, roi.height, &strip_colour_);
  toGray(strip_colour_, &strip_right_);
  return true;
}

void StereoContactEstimator::maskShafts(const InstrumentView* tools, std::size_t n, const cv::Rect& roi, int shift,
                                        int num_disp)
{
  const int w = roi.width + num_disp;
  mask_left_.create(roi.height, w, CV_8U);
  mask_right_.create(roi.height, w, CV_8U);
  mask_left_.setTo(0);
  mask_right_.setTo(0);
  for (std::size_t i = 0; i < n; ++i)
  {
    const InstrumentView& t = tools[i];
    if (!t.valid)
      continue;
    cv::Point3d a = t.tip, b = t.has_shaft ? t.shaft : t.tip;
    // Keep the segment in front of the camera (z >= 5 mm in the rectified frame).
    double za = (cal_.R_left * cv::Vec3d(a.x, a.y, a.z))[2], zb = (cal_.R_left * cv::Vec3d(b.x, b.y, b.z))[2];
    const double zmin = 0.005;
    if (za < zmin && zb < zmin)
      continue;
    if (za < zmin)
    {
      a = b + (a - b) * ((zb - zmin) / (zb - za));
      za = zmin;
    }
    else if (zb < zmin)
    {
      b = a + (b - a) * ((za - zmin) / (za - zb));
      zb = zmin;
    }
    // The capsule tapers with depth: drawn as kMaskSegments pieces, each as thick as its near end.
    const double r = t.radius + p_.mask_margin;
    for (int e = 0; e < 2; ++e)
    {
      const cv::Point2d origin(roi.x - num_disp - (e == 1 ? shift : 0), roi.y);
      cv::Mat& m = e == 1 ? mask_right_ : mask_left_;
      cv::Point prev;
      for (int k = 0; k <= kMaskSegments; ++k)
      {
        const double f = static_cast<double>(k) / kMaskSegments;
        const cv::Point3d q = a + (b - a) * f;
        const double zn = std::min(za + (zb - za) * f, za + (zb - za) * std::max(0.0, f - 1.0 / kMaskSegments));
        cv::Point2d pq;
        if (!projectRectified(q, e == 1, &pq))
          break;
        const cv::Point iq((pq - origin) * 16.0);
        const int radius16 = static_cast<int>(std::ceil(16.0 * fx_ * r / zn));
        if (k == 0)
          cv::circle(m, iq, radius16, cv::Scalar(255), cv::FILLED, cv::LINE_8, 4);
        else
          cv::line(m, prev, iq, cv::Scalar(255), std::max(1, (radius16 * 2 + 15) / 16), cv::LINE_8, 4);
        prev = iq;
      }
    }
  }
}

int StereoContactEstimator::collectSamples(const cv::Rect& roi, int shift, int num_disp, int step, int* unmasked)
{
  samples_.clear();
  int free = 0;
  for (int y = 0; y < roi.height; y += step)
  {
    const std::int16_t* d = disparity_.ptr<std::int16_t>(y);
    const std::uint8_t* ml = mask_left_.ptr<std::uint8_t>(y);
    const std::uint8_t* mr = mask_right_.ptr<std::uint8_t>(y);
    for (int x = num_disp; x < num_disp + roi.width; x += step)
    {
      if (ml[x])
        continue;
      ++free;
      if (d[x] < 0)
        continue;  // invalid (StereoBM marks them minDisparity - 1)
      const int xr = static_cast<int>(std::lround(x - d[x] / 16.0));
      if (xr < 0 || xr >= mask_right_.cols || mr[xr])
        continue;  // matched into an instrument in the right image
      samples_.emplace_back(static_cast<float>(roi.x + x - num_disp), static_cast<float>(roi.y + y),
                            static_cast<float>(d[x] / 16.0 + shift));
    }
  }
  *unmasked = free;
  return static_cast<int>(samples_.size());
}

void StereoContactEstimator::surfacePoints(const DisparitySurface& ds, const cv::Rect& roi, int num_disp, int step)
{
  points_.clear();
  const cv::Matx33d Rt = cal_.R_left.t();
  const double dcx = cal_.P_left(0, 2) - cal_.P_right(0, 2);
  for (int y = 0; y < roi.height; y += step)
  {
    const std::uint8_t* ml = mask_left_.ptr<std::uint8_t>(y);
    for (int x = num_disp; x < num_disp + roi.width; x += step)
    {
      if (ml[x])
        continue;
      const double u = roi.x + x - num_disp, v = roi.y + y;
      const double z = fb_ / (ds(u, v) - dcx);
      if (!(z > 0))
        continue;
      const cv::Vec3d p = Rt * cv::Vec3d((u - cx_) * z / fx_, (v - cy_) * z / fy_, z);
      points_.emplace_back(p[0], p[1], p[2]);
    }
  }
}

bool StereoContactEstimator::fitSurface(const cv::Point3d& tip, ContactEstimate* out)
{
  const int n = static_cast<int>(points_.size());
  cv::RNG rng(0x5a4a5);  // deterministic
  int best_count = -1;
  cv::Vec3d best_n;
  cv::Point3d best_p;
  for (int it = 0; it < p_.ransac_iterations; ++it)
  {
    const cv::Point3d& a = points_[rng.uniform(0, n)];
    const cv::Point3d& b = points_[rng.uniform(0, n)];
    const cv::Point3d& c = points_[rng.uniform(0, n)];
    cv::Vec3d nrm;
    if (!planeOf(a, b, c, &nrm))
      continue;
    int count = 0;
    for (int i = 0; i < n; i += 2)  // half the points score a hypothesis
      count += std::abs(nrm.dot(cv::Vec3d(points_[i] - a))) < p_.inlier_threshold ? 1 : 0;
    if (count > best_count)
    {
      best_count = count;
      best_n = nrm;
      best_p = a;
    }
  }
  if (best_count < 3)
    return false;
  HeightField f;
  f.origin = best_p;
  f.e3 = best_n.dot(cv::Vec3d(-best_p.x, -best_p.y, -best_p.z)) > 0 ? best_n : -best_n;  // towards the camera
  f.e1 = std::abs(f.e3[0]) < 0.9 ? cv::Vec3d(1, 0, 0) : cv::Vec3d(0, 1, 0);
  f.e1 = f.e1 - f.e3 * f.e3.dot(f.e1);
  f.e1 /= cv::norm(f.e1);
  f.e2 = f.e3.cross(f.e1);
  const cv::Vec3d tl = f.local(tip);
  // Refit: plane on the RANSAC inliers, then the quadric (plane if the tip is not surrounded by
  // surface points: a quadric would extrapolate its curvature) twice on the re-selected inliers.
  bool quadric = false;
  for (int pass = 0; pass < 3; ++pass)
  {
    inlier_idx_.clear();
    for (int i = 0; i < n; ++i)
      if (std::abs(f.residual(points_[i])) < p_.inlier_threshold)
        inlier_idx_.push_back(i);
    if (static_cast<int>(inlier_idx_.size()) < p_.min_points / 2)
      return false;
    if (pass == 1)
      quadric = largestGap(points_, inlier_idx_, f, tl) < kSectors / 2;
    if (!fitHeight(points_, inlier_idx_, quadric && pass > 0, &f))
      return false;
  }
  double ss = 0.0;
  for (int i : inlier_idx_)
    ss += f.residual(points_[i]) * f.residual(points_[i]);
  out->inliers = static_cast<int>(inlier_idx_.size());
  out->rms = std::sqrt(ss / std::max<std::size_t>(1, inlier_idx_.size()));
  const int gap = largestGap(points_, inlier_idx_, f, tl);
  if (gap >= 3 * kSectors / 4)
  {
    out->unknown = ContactUnknown::kOccluded;  // surface on one side only: the tip's is a guess
    return false;
  }
  closestPoint(f, tl, out);
  out->confidence = quadric ? 1.0 : 0.5;  // scaled by the matching's inlier ratio by the caller
  return true;
}

void StereoContactEstimator::matchRegion(const cv::Mat& left, const cv::Mat& right, const InstrumentView* tools,
                                         std::size_t n, const cv::Rect& roi, double z, int* shift_out, int* num_disp_out)
{
  // Disparity range from the depths the surface may have around the tip.
  const double dcx = cal_.P_left(0, 2) - cal_.P_right(0, 2);
  const double z_near = std::max(0.3 * z, z - p_.near_margin), z_far = z + p_.far_margin;
  const int shift = std::max(0, static_cast<int>(std::floor(fb_ / z_far + dcx)));
  const int d_max = static_cast<int>(std::ceil(fb_ / z_near + dcx));
  const int num_disp = std::min(kMaxDisparities, std::max(16, (d_max - shift + 1 + 15) / 16 * 16));

  rectifyStrips(left, right, roi, shift, num_disp);
  maskShafts(tools, n, roi, shift, num_disp);
  const double scale = left.cols / 1280.0;
  const int block = std::max(5, (static_cast<int>(std::lround(p_.block_size * scale)) / 2) * 2 + 1);
  if (!matcher_ || matcher_->getNumDisparities() != num_disp || matcher_->getBlockSize() != block)
  {
    matcher_ = cv::StereoBM::create(num_disp, block);
    matcher_->setTextureThreshold(p_.texture_threshold);
    matcher_->setUniquenessRatio(p_.uniqueness_ratio);
    matcher_->setSpeckleWindowSize(0);
    matcher_->setDisp12MaxDiff(1);
  }
  matcher_->compute(strip_left_, strip_right_, disparity_);
  *shift_out = shift;
  *num_disp_out = num_disp;
}

RefineResult StereoContactEstimator::refine(const cv::Rect& roi, int shift, int num_disp, int step, bool quadric,
                                            DisparitySurface* ds)
{
  StereoRegion region;
  strip_left_.convertTo(region.left, CV_32F);
  strip_right_.convertTo(region.right, CV_32F);
  region.mask_left = mask_left_;
  region.mask_right = mask_right_;
  region.origin_left = cv::Point(roi.x - num_disp, roi.y);
  region.origin_right = cv::Point(roi.x - num_disp - shift, roi.y);
  region.roi = roi;
  return refineDisparity(region, step, p_.refine_iterations, quadric, ds);
}

ContactEstimate StereoContactEstimator::estimate(const cv::Mat& left, const cv::Mat& right,
                                                 const InstrumentView* tools, std::size_t n, std::size_t which)
{
  ContactEstimate out;
  points_.clear();
  if (!configured_ || left.size() != cv::Size(cal_.left.width, cal_.left.height) || right.size() != left.size())
    return out;
  if (which >= n || !tools[which].valid)
  {
    out.unknown = ContactUnknown::kNoPose;
    return out;
  }
  const cv::Point3d& tip = tools[which].tip;
  out.unknown = ContactUnknown::kOutOfView;
  cv::Point2d px;
  if (!projectRectified(tip, false, &px))
    return out;
  const double z = (cal_.R_left * cv::Vec3d(tip.x, tip.y, tip.z))[2];
  const int half = std::max(8, std::min(p_.max_roi / 2, static_cast<int>(fx_ * p_.patch_radius / z)));
  const cv::Rect image(0, 0, left.cols, left.rows);
  const cv::Rect roi = cv::Rect(static_cast<int>(std::lround(px.x)) - half, static_cast<int>(std::lround(px.y)) - half,
                                2 * half, 2 * half) & image;
  out.roi = roi;
  if (!image.contains(cv::Point(static_cast<int>(px.x), static_cast<int>(px.y))) ||
      roi.area() < 2 * half * half)
    return out;
  int shift = 0, num_disp = 0;
  matchRegion(left, right, tools, n, roi, z, &shift, &num_disp);

  const int step = std::max(1, roi.width / p_.sample_grid);
  int unmasked = 0;
  const int count = collectSamples(roi, shift, num_disp, step, &unmasked);
  out.points = count;
  const int sampled = ((roi.width + step - 1) / step) * ((roi.height + step - 1) / step);
  if (unmasked < (1.0 - p_.max_masked_fraction) * sampled)
  {
    out.unknown = ContactUnknown::kOccluded;
    return out;
  }
  if (count < p_.min_points || count < p_.min_valid_fraction * unmasked)
  {
    out.unknown = ContactUnknown::kNoTexture;
    return out;
  }
  // Disparity plane of the block matches (RANSAC), refined photometrically, then the surface in 3D.
  out.unknown = ContactUnknown::kNoSurface;
  DisparitySurface ds;
  ds.u0 = px.x;
  ds.v0 = px.y;
  ds.s = half;
  const int inliers = fitDisparityPlane(samples_, 1.0, p_.ransac_iterations, &ds);
  const double ratio = static_cast<double>(inliers) / count;
  if (ratio < p_.min_inlier_ratio)
    return out;
  const int gap = largestImageGap(samples_, ds, px);
  if (gap >= 3 * kSectors / 4)
  {
    out.unknown = ContactUnknown::kOccluded;  // surface on one side of the tip only: a guess
    return out;
  }
  const RefineResult refined = refine(roi, shift, num_disp, step, gap < kSectors / 2, &ds);
  out.photometric_rms = refined.rms;
  surfacePoints(ds, roi, num_disp, step);
  if (static_cast<int>(points_.size()) < p_.min_points / 2 || !fitSurface(tip, &out))
  {
    out.confidence = 0.0;
    out.signed_distance = 0.0;
    return out;
  }
  out.confidence *= std::min(1.0, ratio * std::min(1.0, inliers / (2.0 * p_.min_points))) * (refined.pixels > 0 ? 1.0 : 0.5);
  out.unknown = ContactUnknown::kNone;
  out.depth = std::max(0.0, -out.signed_distance);
  out.state = out.depth > p_.contact_threshold ? ContactState::kContact : ContactState::kNoContact;
  if (out.state == ContactState::kNoContact)
    out.depth = 0.0;
  return out;
}

}  // namespace saras_visual_feedback
