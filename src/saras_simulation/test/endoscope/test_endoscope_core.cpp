/**
 * @file test_endoscope_core.cpp
 * @brief gtests of the C++ endoscope core (no roscore): the camera (camera_info reading, scaling,
 *        validation; ray table and raw projection against image_geometry and cv::projectPoints),
 *        vertices-file validation, and projection truth
 *        of the rendered image (checkerboard corners, ArUco marker corners, box silhouette,
 *        shaft tip) against independently projected 3D points.
 */
#include <array>
#include <cstdio>
#include <fstream>
#include <string>

#include <gtest/gtest.h>
#include <opencv2/aruco.hpp>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "saras_simulation/endoscope_renderer.h"

using namespace saras_simulation::endoscope;
using image_geometry::PinholeCameraModel;

namespace
{
const std::string kConfig = ENDOSCOPE_TEST_CONFIG_DIR;

std::string writeTemp(const std::string& name, const std::string& text)
{
  const std::string path = ::testing::TempDir() + name;
  std::ofstream(path) << text;
  return path;
}

std::string yamlText(const std::string& model, const std::string& d, const std::string& k = "900.0, 0.0, 639.5, 0.0, 900.0, 359.5, 0.0, 0.0, 1.0",
                     int dcount = 5)
{
  return "image_width: 1280\nimage_height: 720\ncamera_name: t\ncamera_matrix:\n  rows: 3\n  cols: 3\n  data: [" + k +
         "]\ndistortion_model: " + model + "\ndistortion_coefficients:\n  rows: 1\n  cols: " +
         std::to_string(dcount) + "\n  data: [" + d +
         "]\nrectification_matrix:\n  rows: 3\n  cols: 3\n  data: [1, 0, 0, 0, 1, 0, 0, 0, 1]\n"
         "projection_matrix:\n  rows: 3\n  cols: 4\n  data: [900.0, 0.0, 639.5, -4.5, 0.0, 900.0, 359.5, 0.0, 0.0, "
         "0.0, 1.0, 0.0]\n";
}

/// Camera looking down at the tissue from (x, y, z) with small tilts (world z up).
Eigen::Isometry3d lookDown(double x, double y, double z, double tilt_x = 0.0, double tilt_y = 0.0, double yaw = 0.0)
{
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = rpyToMatrix(M_PI + tilt_x, tilt_y, yaw);
  T.translation() = Eigen::Vector3d(x, y, z);
  return T;
}

/// The 8 vertices of the axis-aligned box [lo, hi] in the vertices-file order (saras_collision):
/// v0, v0+x, v0+x+z, v0+z, v0+y, v0+x+y, v0+x+y+z, v0+y+z.
std::array<Eigen::Vector3d, 8> fileOrderBox(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi)
{
  const Eigen::Vector3d e = hi - lo;
  const Eigen::Vector3d x(e.x(), 0, 0), y(0, e.y(), 0), z(0, 0, e.z());
  return { lo, lo + x, lo + x + z, lo + z, lo + y, lo + x + y, lo + x + y + z, lo + y + z };
}

/// ENDOSCOPE_TEST_DUMP=dir: write the rendered images there (debugging).
void dump(const std::string& name, const cv::Mat& img)
{
  if (const char* d = std::getenv("ENDOSCOPE_TEST_DUMP"))
    cv::imwrite(std::string(d) + "/" + name + ".png", img);
}

cv::Mat cvK(const PinholeCameraModel& cam)
{
  return cv::Mat(cam.intrinsicMatrix());
}

cv::Mat cvD(const PinholeCameraModel& cam)
{
  return cam.distortionCoeffs();
}

cv::Point2d projectCv(const PinholeCameraModel& cam, const Eigen::Isometry3d& T_world_cam, const Eigen::Vector3d& pw)
{
  const Eigen::Vector3d pc = T_world_cam.inverse() * pw;
  std::vector<cv::Point3d> p{ cv::Point3d(pc.x(), pc.y(), pc.z()) };
  std::vector<cv::Point2d> uv;
  cv::projectPoints(p, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), cvK(cam), cvD(cam), uv);
  return uv[0];
}

PinholeCameraModel modelOf(const std::string& yaml)
{
  return cameraModel(parseCameraInfo(yaml));
}
}  // namespace

// ------------------------------------------------------------------------------------------
TEST(Camera, RawProjectionAndRaysAreImageGeometrys)
{
  const PinholeCameraModel pb = modelOf(yamlText("plumb_bob", "-0.12, 0.05, 0.0005, -0.0003, 0.01"));
  const PinholeCameraModel rp = modelOf(
      yamlText("rational_polynomial", "-0.3, 0.1, 0.001, -0.0007, 0.02, 0.05, -0.02, 0.01", "880.0, 0.0, 641.2, 0.0, 905.0, 355.1, 0.0, 0.0, 1.0", 8));
  for (const PinholeCameraModel* cam : { &pb, &rp })
  {
    // image_geometry's own round trip for a camera without baseline: a rectified pixel of a ray
    // (P = K) unrectified to the raw image = projectRaw of that ray
    const cv::Matx34d P0(cam->fx(), 0, cam->cx(), 0, 0, cam->fy(), cam->cy(), 0, 0, 0, 1, 0);
    cv::RNG rng(3);
    double worst = 0;
    for (int k = 0; k < 200; ++k)
    {
      const cv::Point3d X(rng.uniform(-0.06, 0.06), rng.uniform(-0.035, 0.035), rng.uniform(0.05, 0.15));
      const cv::Point2d rect(cam->fx() * X.x / X.z + cam->cx(), cam->fy() * X.y / X.z + cam->cy());
      const cv::Point2d ig = cam->unrectifyPoint(rect, cam->intrinsicMatrix(), P0);
      const Eigen::Vector2d p = projectRaw(*cam, Eigen::Vector3d(X.x, X.y, X.z));
      worst = std::max(worst, std::hypot(p.x() - ig.x, p.y() - ig.y));
    }
    EXPECT_LT(worst, 1e-9);
    // the ray table is the inverse of the projection (to float32), and the rays of rectifyPoint +
    // projectPixelTo3dRay are within their own convergence of it (a float point, OpenCV's default
    // 5 iterations: up to ~0.25 px at the corners of the strongly distorted rational camera)
    cv::Mat rx, ry;
    pixelRays(*cam, 1, rx, ry);
    ASSERT_EQ(rx.cols, 1280);
    ASSERT_EQ(rx.rows, 720);
    double worst_inverse = 0, worst_ig = 0;
    for (int v = 0; v < 720; v += 37)
      for (int u = 0; u < 1280; u += 41)
      {
        const Eigen::Vector2d p = projectRaw(*cam, Eigen::Vector3d(rx.at<float>(v, u), ry.at<float>(v, u), 1.0));
        worst_inverse = std::max(worst_inverse, std::hypot(p.x() - u, p.y() - v));
        const cv::Point3d ray = cam->projectPixelTo3dRay(cam->rectifyPoint(cv::Point2d(u, v), cam->intrinsicMatrix(), P0), P0);
        worst_ig = std::max(worst_ig, cam->fx() * std::hypot(ray.x / ray.z - rx.at<float>(v, u), ray.y / ray.z - ry.at<float>(v, u)));
      }
    EXPECT_LT(worst_inverse, 2e-3);  // float32 rays
    EXPECT_LT(worst_ig, 0.5);        // [px]
    EXPECT_GT(worst_inverse, 0.0);   // not a table of identical rays by accident
  }
}

TEST(Camera, ReadsConfigAndScales)
{
  const sensor_msgs::CameraInfo info = readCameraInfo(kConfig + "/endoscope_right.yaml");
  EXPECT_EQ(info.width, 1280u);
  EXPECT_DOUBLE_EQ(info.P[3], -4.5);
  const sensor_msgs::CameraInfo s = scaledCameraInfo(info, 640, 360);
  EXPECT_EQ(s.width, 640u);
  EXPECT_DOUBLE_EQ(s.K[0], 450.0);
  EXPECT_DOUBLE_EQ(s.K[2], 319.5);  // (639.5 + 0.5) / 2 - 0.5
  EXPECT_DOUBLE_EQ(s.K[5], 179.5);
  EXPECT_DOUBLE_EQ(s.P[3], -2.25);
  const sensor_msgs::CameraInfo b = scaledCameraInfo(info, 1920, 1080);
  EXPECT_DOUBLE_EQ(b.K[0], 1350.0);
  EXPECT_DOUBLE_EQ(b.K[2], 959.5);
  EXPECT_EQ(b.D, info.D);
  const PinholeCameraModel cam = cameraModel(b);
  EXPECT_EQ(cam.fullResolution(), cv::Size(1920, 1080));
  EXPECT_DOUBLE_EQ(cam.fx(), 1350.0);
}

void expectThrowWith(const std::function<void()>& f, const std::string& needle)
{
  try
  {
    f();
    ADD_FAILURE() << "no exception, expected one naming '" << needle << "'";
  }
  catch (const std::invalid_argument& e)
  {
    EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
  }
}

TEST(Camera, BadCameraInfoIsAClearError)
{
  expectThrowWith([] { readCameraInfo("/nonexistent/endoscope_left.yaml"); },
                  "cannot read camera_info file /nonexistent/endoscope_left.yaml");
  expectThrowWith([] { parseCameraInfo(yamlText("fisheye", "0, 0, 0, 0", "900.0, 0.0, 639.5, 0.0, 900.0, 359.5, 0.0, 0.0, 1.0", 4)); },
                  "distortion_model 'fisheye' not supported");
  expectThrowWith([] { parseCameraInfo(yamlText("plumb_bob", "0, 0, 0, 0, 0", "0.0, 0.0, 639.5, 0.0, 900.0, 359.5, 0.0, 0.0, 1.0")); },
                  "fx, fy > 0");
  expectThrowWith([] { parseCameraInfo(yamlText("plumb_bob", "0, 0, 0, 0, 0, 0", "900.0, 0.0, 639.5, 0.0, 900.0, 359.5, 0.0, 0.0, 1.0", 6)); },
                  "6 coefficients");
  expectThrowWith([] { parseCameraInfo(yamlText("plumb_bob", "0, 0, .nan, 0, 0")); }, "finite");
  expectThrowWith([] { parseCameraInfo(yamlText("plumb_bob", "0, 0, 0, 0, 0", "900.0, 0.0, 639.5, 0.0, 900.0, 359.5")); },
                  "not a camera_calibration YAML file");
  expectThrowWith([] { parseCameraInfo("image_width: 1280\nimage_height: 720\n"); }, "not a camera_calibration YAML file");
  const std::string p = writeTemp("endo_garbage.yaml", "- just\n- a list\n");
  expectThrowWith([&] { readCameraInfo(p); }, p);
}

// ------------------------------------------------------------------------------------------
TEST(Scene, VerticesFileValidation)
{
  const std::string good = writeTemp("endo_boxes.txt",
                                     "# comment\n1\n0 0 0\n1 0 0 # x\n1 0 1\n0 0 1\n0 2 0\n1 2 0\n1 2 1\n0 2 1\n");
  const auto boxes = loadBoxes(good, 0.01);
  ASSERT_EQ(boxes.size(), 1u);
  EXPECT_DOUBLE_EQ(boxes[0][4].y(), 0.02);
  const Box b = boxFromVertices(boxes[0]);
  EXPECT_NEAR((b.centre - Eigen::Vector3d(0.005, 0.01, 0.005)).norm(), 0.0, 1e-12);
  Eigen::Vector3d h = b.half;
  std::sort(h.data(), h.data() + 3);
  EXPECT_NEAR((h - Eigen::Vector3d(0.005, 0.005, 0.01)).norm(), 0.0, 1e-12);
  // the file is parsed by saras_collision::loadVerticesFile: its messages, prefixed with the path
  expectThrowWith([] { loadBoxes("/nonexistent/v.txt"); }, "/nonexistent/v.txt: cannot open");
  expectThrowWith([] { loadBoxes(writeTemp("endo_empty.txt", "# nothing\n")); }, "empty file");
  expectThrowWith([] { loadBoxes(writeTemp("endo_word.txt", "1\n0 0 zero\n")); }, "'zero' is not a finite number");
  expectThrowWith([] { loadBoxes(writeTemp("endo_count.txt", "2\n0 0 0\n1 0 0\n")); },
                  "unexpected end of file in box 0");
  expectThrowWith([] { loadBoxes(writeTemp("endo_nan.txt", "1\nnan 0 0\n1 0 0\n1 0 1\n0 0 1\n0 2 0\n1 2 0\n1 2 1\n0 2 1\n")); },
                  "'nan' is not a finite number");
  // not a rectangular box (v6 moved): the contract of the vertices file, a clear load error
  const std::string skew = writeTemp("endo_skew.txt", "1\n0 0 0\n1 0 0\n1 0 1\n0 0 1\n0 2 0\n1 2 0\n1.5 2 1\n0 2 1\n");
  expectThrowWith([&] { loadBoxes(skew); }, skew + ": lines 2-9: box 0 is not a rectangular box");
  // vertices out of the documented order are refused by the renderer's box model too
  std::array<Eigen::Vector3d, 8> swapped = boxes[0];
  std::swap(swapped[1], swapped[4]);
  expectThrowWith([&] { boxFromVertices(swapped); }, "not a rectangular box in the order");
}

TEST(Scene, TargetsValidateTheirSizes)
{
  EXPECT_THROW(PlanarTarget::checkerboard(8, 6, 0.00815, 0.0001), std::invalid_argument);
  EXPECT_THROW(PlanarTarget::circles(0.1, 0.005, 8, 0.06, 0.025, 0.0002, "DICT_NOPE"), std::invalid_argument);
  const PlanarTarget c = PlanarTarget::checkerboard();
  EXPECT_EQ(c.points.size(), 48u);
  EXPECT_EQ(c.texture.cols, 11 * 80);
}

// ------------------------------------------------------------------------------------------
// Projection truth in rendered images

class RenderTruth : public ::testing::Test
{
protected:
  RenderTruth() : info(readCameraInfo(kConfig + "/endoscope_left.yaml")), cam(cameraModel(info)) {}
  sensor_msgs::CameraInfo info;
  PinholeCameraModel cam;
};

TEST_F(RenderTruth, CheckerboardCornersLandOnTheirProjection)
{
  SceneRenderer r(cam, TissueSurface());
  Eigen::Isometry3d T_wb = Eigen::Isometry3d::Identity();
  T_wb.linear() = rpyToMatrix(M_PI + 0.15, -0.1, -0.3);
  T_wb.translation() = Eigen::Vector3d(-0.03, 0.0, 0.10);
  auto board = std::make_shared<PlanarTarget>(PlanarTarget::checkerboard());
  r.setTarget(board, T_wb);
  // two oblique views from ~120 mm above the board centre
  const Eigen::Vector3d c = T_wb * Eigen::Vector3d(0.028, 0.02, 0.0);
  for (const Eigen::Isometry3d& T : { lookDown(c.x() + 0.004, c.y() - 0.003, 0.22, 0.05, 0.08, 0.1),
                                      lookDown(c.x() - 0.006, c.y() + 0.004, 0.215, -0.1, 0.0, 0.25) })
  {
    cv::Mat img, gray;
    r.render(T, {}, img);
    dump("checkerboard", img);
    cv::cvtColor(img, gray, cv::COLOR_BGR2GRAY);
    std::vector<cv::Point2f> corners;
    ASSERT_TRUE(cv::findChessboardCorners(gray, cv::Size(8, 6), corners));
    cv::cornerSubPix(gray, corners, cv::Size(7, 7), cv::Size(-1, -1),
                     cv::TermCriteria(cv::TermCriteria::EPS | cv::TermCriteria::COUNT, 50, 1e-4));
    double worst = 0;
    for (const Eigen::Vector3d& p : board->points)
    {
      const cv::Point2d uv = projectCv(cam, T, T_wb * p);
      double best = 1e9;
      for (const auto& c : corners)
        best = std::min(best, std::hypot(c.x - uv.x, c.y - uv.y));
      worst = std::max(worst, best);
    }
    EXPECT_LT(worst, 0.5) << "max corner error " << worst << " px";
  }
}

TEST_F(RenderTruth, ArucoMarkerCornersLandOnTheirProjection)
{
  const PinholeCameraModel c = cameraModel(scaledCameraInfo(info, 1920, 1080));
  SceneRenderer r(c, TissueSurface());
  Eigen::Isometry3d T_wb = Eigen::Isometry3d::Identity();
  T_wb.linear() = rpyToMatrix(M_PI, 0.0, 0.2);
  T_wb.translation() = Eigen::Vector3d(0.01, 0.0, 0.08);
  auto board = std::make_shared<PlanarTarget>(PlanarTarget::circles());
  r.setTarget(board, T_wb);
  const Eigen::Isometry3d T = lookDown(0.012, 0.0, 0.33, 0.03, -0.02, 0.0);
  cv::Mat img, gray;
  r.render(T, {}, img);
  cv::cvtColor(img, gray, cv::COLOR_BGR2GRAY);
  std::vector<int> ids;
  std::vector<std::vector<cv::Point2f>> corners;
  auto params = cv::aruco::DetectorParameters::create();
  params->cornerRefinementMethod = cv::aruco::CORNER_REFINE_SUBPIX;
  cv::aruco::detectMarkers(gray, cv::aruco::getPredefinedDictionary(cv::aruco::DICT_4X4_50), corners, ids, params);
  ASSERT_EQ(ids.size(), 4u);
  double worst = 0;
  for (size_t k = 0; k < ids.size(); ++k)
  {
    ASSERT_GE(ids[k], 0);
    ASSERT_LT(ids[k], 4);
    // the marker's outer black border corners are the texel-grid corners of the marker image
    for (int q = 0; q < 4; ++q)
    {
      const cv::Point2d uv = projectCv(c, T, T_wb * board->marker_corners[ids[k]][q]);
      double best = 1e9;
      for (const auto& d : corners[k])
        best = std::min(best, std::hypot(d.x - uv.x, d.y - uv.y));
      worst = std::max(worst, best);
    }
  }
  EXPECT_LT(worst, 1.0) << "max ArUco corner error " << worst << " px";
}

TEST_F(RenderTruth, BoxSilhouetteAndShaftTipLandOnTheirProjection)
{
  SceneRenderer r(cam, TissueSurface());
  r.setUniformTexture(128);
  // one box on the tissue, axis-aligned top face at z = 0.09 (camera above at 0.17)
  const Eigen::Vector3d lo(-0.02, -0.01, 0.06), hi(0.01, 0.012, 0.09);
  r.setBoxes({ fileOrderBox(lo, hi) });
  const Eigen::Isometry3d T = lookDown(0.0, 0.0, 0.17);  // top face seen head-on: its silhouette is the outline
  cv::Mat img, tissue_only;
  r.render(T, {}, img);
  SceneRenderer r0(cam, TissueSurface());
  r0.setUniformTexture(128);
  r0.render(T, {}, tissue_only);
  // reference: the top face outline projected with cv::projectPoints (dense edge samples)
  std::vector<cv::Point2f> outline;
  const Eigen::Vector3d c4[4] = { { lo.x(), lo.y(), hi.z() }, { hi.x(), lo.y(), hi.z() }, { hi.x(), hi.y(), hi.z() }, { lo.x(), hi.y(), hi.z() } };
  for (int e = 0; e < 4; ++e)
    for (int k = 0; k < 64; ++k)
    {
      const cv::Point2d uv = projectCv(cam, T, c4[e] + (k / 64.0) * (c4[(e + 1) % 4] - c4[e]));
      outline.emplace_back(float(uv.x), float(uv.y));
    }
  // pixel centres inside the projected outline
  cv::Mat ref = cv::Mat::zeros(img.size(), CV_8U);
  const cv::Rect box = cv::boundingRect(outline);
  for (int y = box.y - 2; y < box.y + box.height + 2; ++y)
    for (int x = box.x - 2; x < box.x + box.width + 2; ++x)
      if (cv::pointPolygonTest(outline, cv::Point2f(float(x), float(y)), false) > 0)
        ref.at<uchar>(y, x) = 255;
  // bone pixels: those the box changed (grey tissue vs. bone colour: >= 20 levels apart)
  cv::Mat absdiff, bone;
  cv::absdiff(img, tissue_only, absdiff);
  cv::cvtColor(absdiff, absdiff, cv::COLOR_BGR2GRAY);
  bone = absdiff > 4;
  dump("box", img);
  dump("box_mask", bone);
  dump("box_ref", ref);
  cv::Mat diff;
  cv::bitwise_xor(bone, ref, diff);
  const int area = cv::countNonZero(ref), mismatch = cv::countNonZero(diff);
  const double perimeter = cv::arcLength(outline, true);
  ASSERT_GT(area, 10000);
  // exact per-pixel silhouette: only pixels whose centre is within rounding of the edge differ
  EXPECT_LT(mismatch, 0.1 * perimeter) << "mismatch " << mismatch << " px, perimeter " << perimeter;
  // a 1 px shift of the reference would fail the test (the test can fail)
  cv::Mat shifted = cv::Mat::zeros(ref.size(), CV_8U);
  ref(cv::Rect(0, 0, ref.cols - 1, ref.rows)).copyTo(shifted(cv::Rect(1, 0, ref.cols - 1, ref.rows)));
  cv::bitwise_xor(bone, shifted, diff);
  EXPECT_GT(cv::countNonZero(diff), 0.3 * perimeter);

  // shaft: tip above the tissue next to the box; its dark tip disc is centred on the projection
  const Shaft s{ Eigen::Vector3d(0.03, -0.005, 0.1), Eigen::Vector3d(0.06, -0.03, 0.16), 0.004 };
  r.render(T, { s }, img);
  const cv::Point2d tip = projectCv(cam, T, s.tip);
  const double radius_px = cam.fx() * 0.004 / (T.inverse() * s.tip).z();
  // the dark tip disc (60, 60, 62) in a window of 2 radii around the projected tip
  const int win = int(2 * radius_px);
  const cv::Rect roi(int(tip.x) - win, int(tip.y) - win, 2 * win + 1, 2 * win + 1);
  ASSERT_EQ(roi & cv::Rect(0, 0, img.cols, img.rows), roi);
  cv::Mat dark;
  cv::inRange(img(roi), cv::Scalar(0, 0, 0), cv::Scalar(75, 75, 75), dark);
  // the highlight line crosses the disc: its centre and radius from the enclosing circle of the
  // dark pixels (the disc's outer boundary is intact)
  std::vector<cv::Point> dark_px;
  cv::findNonZero(dark, dark_px);
  ASSERT_GT(dark_px.size(), 100u);
  cv::Point2f centre;
  float radius = 0;
  cv::minEnclosingCircle(dark_px, centre, radius);
  EXPECT_NEAR(radius, radius_px, 1.5);
  EXPECT_LT(std::hypot(centre.x + roi.x - tip.x, centre.y + roi.y - tip.y), 1.0)
      << "tip disc centre " << centre.x + roi.x << ", " << centre.y + roi.y << " projected tip " << tip;
}

/// Largest |z - height(x, y)| [m] of the tissue-grid points of @p r's last static layer
/// (rays from cv::undistortPoints, independent of the renderer's ray tables) inside the
/// textured square; @p hits, @p checked: rays that hit the tissue / were compared.
double tissueHeightError(const PinholeCameraModel& cam, const SceneRenderer& r, const TissueSurface& surface,
                         const Eigen::Isometry3d& T, int& hits, int& checked)
{
  const cv::Mat& t = r.tissueDepth();
  const int step = r.tissueStep();
  std::vector<cv::Point2d> px, xy;
  for (int j = 0; j < t.rows; ++j)
    for (int i = 0; i < t.cols; ++i)
      px.emplace_back((i + 0.5) * step - 0.5, (j + 0.5) * step - 0.5);
  cv::undistortPoints(px, xy, cvK(cam), cvD(cam), cv::noArray(), cv::noArray(),
                      cv::TermCriteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 50, 1e-14));
  double worst = 0.0;
  hits = checked = 0;
  for (int j = 0; j < t.rows; ++j)
    for (int i = 0; i < t.cols; ++i)
    {
      const float d = t.at<float>(j, i);
      if (!std::isfinite(d))
        continue;
      ++hits;
      const cv::Point2d& n = xy[size_t(j) * t.cols + i];
      const Eigen::Vector3d p = T * (double(d) * Eigen::Vector3d(n.x, n.y, 1.0));
      if (std::abs(p.x()) > 0.14 || std::abs(p.y()) > 0.14)
        continue;  // outside the textured square (the height map is clamped there)
      ++checked;
      worst = std::max(worst, std::abs(p.z() - surface.height(p.x(), p.y())));
    }
  return worst;
}

TEST_F(RenderTruth, TissueDepthLiesOnTheAnalyticSurface)
{
  // every tissue-grid ray at its solved depth lies on the analytic height field (1 px at 10 cm
  // is 0.11 mm; required: 0.01 mm)
  const TissueSurface surface;
  SceneRenderer r(cam, surface);
  RendererOptions no_refine;  // the coarse solution alone, upsampled (sensitivity check)
  no_refine.refine_iterations = 0;
  SceneRenderer r_coarse(cam, surface, no_refine);
  Eigen::Isometry3d oblique = Eigen::Isometry3d::Identity();  // ECM-like: 37 deg off vertical
  oblique.linear() = rpyToMatrix(M_PI, -0.65, 0.0);
  oblique.translation() = Eigen::Vector3d(0.083, 0.0, 0.170);
  const Eigen::Isometry3d poses[3] = { lookDown(0.0, 0.0, 0.17), lookDown(0.01, -0.02, 0.12, 0.3, -0.25, 0.5), oblique };
  double worst_coarse = 0.0;
  for (const auto& T : poses)
  {
    cv::Mat img;
    r.render(T, {}, img);
    int hits = 0, checked = 0;
    const double worst = tissueHeightError(cam, r, surface, T, hits, checked);
    const int cells = r.tissueDepth().rows * r.tissueDepth().cols;
    EXPECT_EQ(hits, cells);  // the tissue fills these views
    EXPECT_GT(checked, cells / 4);
    std::printf("tissue grid: %d rays checked, max height error %.2g mm\n", checked, worst * 1e3);
    EXPECT_LT(worst, 1e-5) << "max height error " << worst * 1e3 << " mm";
    r_coarse.render(T, {}, img);
    worst_coarse = std::max(worst_coarse, tissueHeightError(cam, r_coarse, surface, T, hits, checked));
  }
  std::printf("without the Newton step: max height error %.2g mm\n", worst_coarse * 1e3);
  EXPECT_GT(worst_coarse, 1e-5);  // the check can fail
}

TEST_F(RenderTruth, BoxPartlyBehindTheCameraAndBeyondTheViewIsExact)
{
  // a wall next to the camera reaching behind it (above the camera, which looks down) and far
  // beyond the field of view, above the tissue: its pixels are exactly those whose ray (from
  // cv::undistortPoints) hits it, by a brute-force double-precision slab test here
  SceneRenderer r(cam, TissueSurface());
  r.setUniformTexture(128);
  SceneRenderer r0(cam, TissueSurface());
  r0.setUniformTexture(128);
  const Eigen::Vector3d lo(0.012, -0.5, 0.09), hi(0.5, 0.5, 0.30);
  r.setBoxes({ fileOrderBox(lo, hi) });
  const Eigen::Isometry3d T = lookDown(0.0, 0.0, 0.17, 0.0, 0.0, 0.2);
  cv::Mat img, tissue_only;
  r.render(T, {}, img);
  r0.render(T, {}, tissue_only);
  cv::Mat absdiff;
  cv::absdiff(img, tissue_only, absdiff);
  cv::cvtColor(absdiff, absdiff, cv::COLOR_BGR2GRAY);
  const cv::Mat wall = absdiff > 4;
  std::vector<cv::Point2d> px, xy;
  for (int y = 0; y < img.rows; ++y)
    for (int x = 0; x < img.cols; ++x)
      px.emplace_back(x, y);
  cv::undistortPoints(px, xy, cvK(cam), cvD(cam), cv::noArray(), cv::noArray(),
                      cv::TermCriteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 50, 1e-14));
  const Eigen::Vector3d o = T.translation();
  cv::Mat ref = cv::Mat::zeros(img.size(), CV_8U);
  for (int y = 0; y < img.rows; ++y)
    for (int x = 0; x < img.cols; ++x)
    {
      const cv::Point2d& n = xy[size_t(y) * img.cols + x];
      const Eigen::Vector3d d = T.linear() * Eigen::Vector3d(n.x, n.y, 1.0);  // world, t = optical depth
      double tn = -1e300, tf = 1e300;
      for (int a = 0; a < 3; ++a)
      {
        const double p = (lo[a] - o[a]) / d[a], q = (hi[a] - o[a]) / d[a];
        tn = std::max(tn, std::min(p, q));
        tf = std::min(tf, std::max(p, q));
      }
      if (tn <= tf && tn >= 1e-3)
        ref.at<uchar>(y, x) = 255;
    }
  cv::Mat diff;
  cv::bitwise_xor(wall, ref, diff);
  const int area = cv::countNonZero(ref), mismatch = cv::countNonZero(diff);
  ASSERT_GT(area, 50000);
  ASSERT_LT(area, img.rows * img.cols - 50000);
  EXPECT_LT(mismatch, 0.002 * area) << "mismatch " << mismatch << " of " << area << " px";
}

TEST_F(RenderTruth, StaticLayerIsCachedPerPose)
{
  SceneRenderer r(cam, TissueSurface());
  cv::Mat a, b;
  const Eigen::Isometry3d T = lookDown(0.0, 0.0, 0.17);
  r.render(T, {}, a);
  r.render(T, { Shaft{ Eigen::Vector3d(0.0, 0.0, 0.1), Eigen::Vector3d(0.02, 0.0, 0.16), 0.004 } }, b);
  EXPECT_EQ(r.backgroundRenders(), 1);
  EXPECT_GT(cv::norm(a, b, cv::NORM_L1), 0.0);
  Eigen::Isometry3d T2 = T;
  T2.translation().x() += 1e-4;
  r.render(T2, {}, b);
  EXPECT_EQ(r.backgroundRenders(), 2);
  // the tissue occupies the whole view from above, shaded, not black
  cv::Scalar mean = cv::mean(a);
  EXPECT_GT(mean[2], 80.0);
  EXPECT_GT(mean[2], mean[1]);
}

int main(int argc, char** argv)
{
  ::testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
