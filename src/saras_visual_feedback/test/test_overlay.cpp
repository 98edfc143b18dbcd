// Overlay drawing: drawn pixels against OpenCV's projection, colours per region, border markers.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

#include "saras_visual_feedback/overlay.h"

using namespace saras_visual_feedback;  // NOLINT(build/namespaces) test file

namespace
{
CameraIntrinsics distortedCamera()
{
  CameraIntrinsics k;
  k.width = 1280;
  k.height = 720;
  k.fx = 1050.0;
  k.fy = 1042.5;
  k.cx = 652.3;
  k.cy = 371.9;
  k.model = DistortionModel::kPlumbBob;
  k.d = {-0.28, 0.11, 0.0012, -0.0007, -0.021, 0, 0, 0};
  return k;
}

cv::Point2d opencvPixel(const CameraIntrinsics& k, const cv::Point3d& p)
{
  std::vector<cv::Point3d> in{p};
  std::vector<cv::Point2d> out;
  const cv::Matx33d K(k.fx, 0, k.cx, 0, k.fy, k.cy, 0, 0, 1);
  std::vector<double> d(k.d.begin(), k.d.begin() + 5);
  cv::projectPoints(in, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), K, d, out);
  return out[0];
}

OverlayStyle noHud()
{
  OverlayStyle s;
  s.draw_hud = false;
  return s;
}

cv::Vec3b bgr(const Rgb& c)
{
  return cv::Vec3b(c.b, c.g, c.r);
}

/// Centroid of the pixels exactly equal to @p colour inside a window around @p around.
cv::Point2d centroidOf(const cv::Mat& img, const cv::Vec3b& colour, cv::Point2d around, int half)
{
  double sx = 0, sy = 0, n = 0;
  for (int y = std::max(0, int(around.y) - half); y < std::min(img.rows, int(around.y) + half); ++y)
    for (int x = std::max(0, int(around.x) - half); x < std::min(img.cols, int(around.x) + half); ++x)
      if (img.at<cv::Vec3b>(y, x) == colour)
      {
        sx += x;
        sy += y;
        n += 1;
      }
  return n > 0 ? cv::Point2d(sx / n, sy / n) : cv::Point2d(-1e9, -1e9);
}

class OverlayTest : public ::testing::Test
{
protected:
  void SetUp() override
  {
    ASSERT_TRUE(camera.configure(distortedCamera(), nullptr));
    image = cv::Mat(720, 1280, CV_8UC3, cv::Scalar(0, 0, 0));
  }
  RawProjector camera;
  cv::Mat image;
};
}  // namespace

TEST(Classify, ThresholdRegions)
{
  OverlayStyle s;  // defaults: collision 0.005 m, warning 0.02 m
  EXPECT_EQ(classify(-0.001, s), Proximity::kCollision);  // penetration
  EXPECT_EQ(classify(0.0, s), Proximity::kCollision);
  EXPECT_EQ(classify(0.005, s), Proximity::kCollision);  // <= collision_threshold
  EXPECT_EQ(classify(0.0051, s), Proximity::kWarning);
  EXPECT_EQ(classify(0.0199, s), Proximity::kWarning);
  EXPECT_EQ(classify(0.02, s), Proximity::kSafe);  // not < warning_threshold
  EXPECT_EQ(classify(0.5, s), Proximity::kSafe);
  EXPECT_EQ(classify(INFINITY, s), Proximity::kSafe);
  EXPECT_EQ(classify(NAN, s), Proximity::kUnknown);
  s.collision_threshold = 0.01;
  s.warning_threshold = 0.03;
  EXPECT_EQ(classify(0.008, s), Proximity::kCollision);
  EXPECT_EQ(classify(0.025, s), Proximity::kWarning);
}

TEST(Style, ParsesColoursAndValidates)
{
  Rgb c;
  ASSERT_TRUE(parseColour("#FF8000", &c));
  EXPECT_EQ(c.r, 255);
  EXPECT_EQ(c.g, 128);
  EXPECT_EQ(c.b, 0);
  ASSERT_TRUE(parseColour("0a0b0c", &c));
  EXPECT_EQ(c.r, 10);
  EXPECT_EQ(c.b, 12);
  EXPECT_FALSE(parseColour("#ff80", &c));
  EXPECT_FALSE(parseColour("#gg0000", &c));
  EXPECT_FALSE(parseColour("red", &c));

  std::string why;
  OverlayStyle s;
  EXPECT_TRUE(validateStyle(s, &why));
  s.warning_threshold = 0.004;  // below collision_threshold
  EXPECT_FALSE(validateStyle(s, &why));
  EXPECT_EQ(why.rfind("warning_threshold", 0), 0u) << why;
  s = OverlayStyle();
  s.collision_threshold = NAN;
  EXPECT_FALSE(validateStyle(s, &why));
  EXPECT_EQ(why.rfind("collision_threshold", 0), 0u) << why;
  s = OverlayStyle();
  s.line_thickness = 0;
  EXPECT_FALSE(validateStyle(s, &why));
  EXPECT_EQ(why.rfind("line_thickness", 0), 0u) << why;
}

TEST_F(OverlayTest, TipIsDrawnWhereOpenCVProjectsIt)
{
  const OverlayStyle style = noHud();
  // Off-centre, where the distortion moves the pixel by tens of pixels.
  const cv::Point3d tip(0.041, -0.022, 0.095);
  const cv::Point2d ref = opencvPixel(camera.intrinsics(), tip);
  ToolOverlay tool;
  tool.visible = true;
  tool.tip = tip;
  tool.distance = 0.01;  // warning
  ToolDrawResult r;
  ASSERT_TRUE(drawOverlay(image, ChannelOrder::kBgr, camera, style, &tool, 1, &r));
  ASSERT_EQ(r.drawn, ToolDrawn::kShaft);
  EXPECT_NEAR(r.tip_pixel.x, ref.x, 1.0);
  EXPECT_NEAR(r.tip_pixel.y, ref.y, 1.0);
  // The drawn pixels: the pixel at the reference and the centroid of the filled tip circle.
  const cv::Vec3b yellow = bgr(style.warning_colour);
  EXPECT_EQ(image.at<cv::Vec3b>(int(std::lround(ref.y)), int(std::lround(ref.x))), yellow);
  const cv::Point2d c = centroidOf(image, yellow, ref, 3 * style.circle_radius);
  EXPECT_NEAR(c.x, ref.x, 1.0);
  EXPECT_NEAR(c.y, ref.y, 1.0);
  // Nothing far from it.
  EXPECT_EQ(image.at<cv::Vec3b>(int(ref.y), int(ref.x) + 40), cv::Vec3b(0, 0, 0));
}

TEST_F(OverlayTest, ShaftLineFollowsTheDistortedProjection)
{
  const OverlayStyle style = noHud();
  ToolOverlay tool;
  tool.visible = true;
  tool.tip = cv::Point3d(-0.02, 0.01, 0.10);
  tool.has_shaft = true;
  tool.shaft = cv::Point3d(-0.06, -0.03, 0.12);
  tool.distance = 0.1;  // safe
  ASSERT_TRUE(drawOverlay(image, ChannelOrder::kBgr, camera, style, &tool, 1, nullptr));
  const cv::Vec3b green = bgr(style.safe_colour);
  for (double a : {0.25, 0.5, 0.75, 1.0})
  {
    const cv::Point2d ref = opencvPixel(camera.intrinsics(), tool.tip + a * (tool.shaft - tool.tip));
    EXPECT_EQ(image.at<cv::Vec3b>(int(std::lround(ref.y)), int(std::lround(ref.x))), green) << "a = " << a;
  }
}

TEST_F(OverlayTest, ColourPerThresholdRegion)
{
  const OverlayStyle style = noHud();
  ToolOverlay tools[4];
  const double distances[4] = {0.003, 0.012, 0.05, NAN};
  const cv::Point3d tips[4] = {{-0.03, -0.015, 0.1}, {0.03, -0.015, 0.1}, {-0.03, 0.015, 0.1}, {0.03, 0.015, 0.1}};
  for (int i = 0; i < 4; ++i)
  {
    tools[i].visible = true;
    tools[i].tip = tips[i];
    tools[i].distance = distances[i];
  }
  ToolDrawResult r[4];
  // RGB image: the colour values land in RGB order.
  cv::Mat rgb(720, 1280, CV_8UC3, cv::Scalar(0, 0, 0));
  ASSERT_TRUE(drawOverlay(rgb, ChannelOrder::kRgb, camera, style, tools, 4, r));
  const Proximity expected[4] = {Proximity::kCollision, Proximity::kWarning, Proximity::kSafe, Proximity::kUnknown};
  const cv::Vec3b colour_rgb[4] = {cv::Vec3b(255, 0, 0), cv::Vec3b(255, 255, 0), cv::Vec3b(0, 255, 0),
                                   cv::Vec3b(160, 160, 160)};
  for (int i = 0; i < 4; ++i)
  {
    EXPECT_EQ(r[i].proximity, expected[i]) << i;
    const cv::Point2d ref = opencvPixel(camera.intrinsics(), tips[i]);
    EXPECT_EQ(rgb.at<cv::Vec3b>(int(std::lround(ref.y)), int(std::lround(ref.x))), colour_rgb[i]) << i;
  }
  // Same in a BGR image: channels swapped.
  ASSERT_TRUE(drawOverlay(image, ChannelOrder::kBgr, camera, style, tools, 4, r));
  const cv::Point2d ref0 = opencvPixel(camera.intrinsics(), tips[0]);
  EXPECT_EQ(image.at<cv::Vec3b>(int(std::lround(ref0.y)), int(std::lround(ref0.x))), cv::Vec3b(0, 0, 255));
}

TEST_F(OverlayTest, OutOfViewTipGetsABorderMarker)
{
  const OverlayStyle style = noHud();
  ToolOverlay tool;
  tool.visible = true;
  tool.tip = cv::Point3d(0.30, 0.0, 0.10);  // far right, beyond the lens's valid range
  tool.distance = 0.003;                    // collision: red
  ToolDrawResult r;
  ASSERT_TRUE(drawOverlay(image, ChannelOrder::kBgr, camera, style, &tool, 1, &r));
  ASSERT_EQ(r.drawn, ToolDrawn::kBorderMarker);
  // On the right edge, inset by the marker size, at the principal point's height (ray along +x).
  EXPECT_NEAR(r.marker_pixel.x, 1280 - 1 - style.marker_size, 1e-6);
  EXPECT_NEAR(r.marker_pixel.y, camera.intrinsics().cy, 1e-6);
  const cv::Vec3b red = bgr(style.collision_colour);
  EXPECT_EQ(image.at<cv::Vec3b>(int(std::lround(r.marker_pixel.y)), int(std::lround(r.marker_pixel.x))), red);
  // The triangle points outwards: its apex region (towards the border) is red too.
  EXPECT_EQ(image.at<cv::Vec3b>(int(std::lround(r.marker_pixel.y)), int(r.marker_pixel.x) + style.marker_size / 2),
            red);
  // Nothing drawn in the middle of the image.
  cv::Mat centre = image(cv::Rect(100, 100, 1000, 500));
  EXPECT_EQ(cv::countNonZero(centre.reshape(1)), 0);
}

TEST_F(OverlayTest, TipBehindTheCameraGetsAMarkerOnItsSide)
{
  const OverlayStyle style = noHud();
  ToolOverlay tool;
  tool.visible = true;
  tool.tip = cv::Point3d(-0.05, -0.2, -0.02);  // behind, up-left
  tool.distance = 0.05;
  ToolDrawResult r;
  ASSERT_TRUE(drawOverlay(image, ChannelOrder::kBgr, camera, style, &tool, 1, &r));
  ASSERT_EQ(r.drawn, ToolDrawn::kBorderMarker);
  EXPECT_NEAR(r.marker_pixel.y, style.marker_size, 1e-6);  // top edge
  EXPECT_LT(r.marker_pixel.x, camera.intrinsics().cx);
  EXPECT_EQ(image.at<cv::Vec3b>(int(std::lround(r.marker_pixel.y)), int(std::lround(r.marker_pixel.x))),
            bgr(style.safe_colour));
}

TEST_F(OverlayTest, ToolOutsideTheImageButInFrontGetsAMarkerTowardsIt)
{
  const OverlayStyle style = noHud();
  ToolOverlay tool;
  tool.visible = true;
  tool.tip = cv::Point3d(-0.02, 0.045, 0.08);  // below the image (v > 720)
  tool.distance = 0.01;
  ToolDrawResult r;
  ASSERT_TRUE(drawOverlay(image, ChannelOrder::kBgr, camera, style, &tool, 1, &r));
  ASSERT_EQ(r.drawn, ToolDrawn::kBorderMarker);
  EXPECT_NEAR(r.marker_pixel.y, 720 - 1 - style.marker_size, 1e-6);  // bottom edge
  EXPECT_LT(r.marker_pixel.x, camera.intrinsics().cx);
}

TEST_F(OverlayTest, InvisibleToolDrawsNothingAndHudDrawsText)
{
  ToolOverlay tool;  // visible = false
  tool.label = "mesa_left";
  ToolDrawResult r;
  ASSERT_TRUE(drawOverlay(image, ChannelOrder::kBgr, camera, noHud(), &tool, 1, &r));
  EXPECT_EQ(r.drawn, ToolDrawn::kNothing);
  EXPECT_EQ(cv::countNonZero(image.reshape(1)), 0);
  OverlayStyle hud;
  ASSERT_TRUE(drawOverlay(image, ChannelOrder::kBgr, camera, hud, &tool, 1, &r));
  EXPECT_GT(cv::countNonZero(image(cv::Rect(0, 0, 400, 60)).reshape(1)), 50);  // HUD text top-left
  EXPECT_EQ(cv::countNonZero(image(cv::Rect(0, 100, 1280, 620)).reshape(1)), 0);
}

TEST_F(OverlayTest, HudCacheRendersOncePerContentAndMatchesDirectDrawing)
{
  OverlayStyle style;  // HUD on
  ToolOverlay tools[2];
  tools[0].label = "SARAS L";
  tools[0].visible = true;
  tools[0].tip = cv::Point3d(0.0, 0.0, 0.1);
  tools[0].distance = 0.0123;
  tools[1].label = "SARAS R";  // not visible
  HudCache hud;
  cv::Mat direct = image.clone(), cached = image.clone();
  ASSERT_TRUE(drawOverlay(direct, ChannelOrder::kBgr, camera, style, tools, 2, nullptr));
  ASSERT_TRUE(drawOverlay(cached, ChannelOrder::kBgr, camera, style, tools, 2, nullptr, nullptr, &hud));
  EXPECT_EQ(cv::norm(direct, cached, cv::NORM_INF), 0.0);
  EXPECT_EQ(hud.renders(), 1u);
  EXPECT_GT(cv::countNonZero(cached(cv::Rect(0, 0, 300, 60)).reshape(1)), 100);
  cv::Mat again = image.clone();
  ASSERT_TRUE(drawOverlay(again, ChannelOrder::kBgr, camera, style, tools, 2, nullptr, nullptr, &hud));
  EXPECT_EQ(hud.renders(), 1u);  // same text: blitted
  EXPECT_EQ(cv::norm(direct, again, cv::NORM_INF), 0.0);
  tools[0].distance = 0.0031;  // new text and colour
  ASSERT_TRUE(drawOverlay(again, ChannelOrder::kBgr, camera, style, tools, 2, nullptr, nullptr, &hud));
  EXPECT_EQ(hud.renders(), 2u);
  // The HUD line is now red somewhere in the first text line.
  cv::Mat first_line = again(cv::Rect(0, 0, 300, 20));
  std::vector<cv::Mat> ch;
  cv::split(first_line, ch);
  EXPECT_GT(cv::countNonZero((ch[2] > 150) & (ch[1] < 60)), 10);
}

TEST_F(OverlayTest, RejectsUnsupportedImages)
{
  cv::Mat mono(720, 1280, CV_8UC1, cv::Scalar(0));
  ToolOverlay tool;
  EXPECT_FALSE(drawOverlay(mono, ChannelOrder::kBgr, camera, noHud(), &tool, 1, nullptr));
  RawProjector unconfigured;
  EXPECT_FALSE(drawOverlay(image, ChannelOrder::kBgr, unconfigured, noHud(), &tool, 1, nullptr));
}

TEST(BorderPoint, RayFromPrincipalPointToTheInsetBorder)
{
  CameraIntrinsics k;
  k.width = 640;
  k.height = 480;
  k.cx = 320;
  k.cy = 240;
  const cv::Point2d p = borderPoint(cv::Point2d(1.0, 1.0), k, 10.0);
  // y reaches 469 first (t = 229) -> x = 549.
  EXPECT_NEAR(p.y, 469.0, 1e-9);
  EXPECT_NEAR(p.x, 549.0, 1e-9);
  const cv::Point2d q = borderPoint(cv::Point2d(-3.0, 0.0), k, 10.0);
  EXPECT_NEAR(q.x, 10.0, 1e-9);
  EXPECT_NEAR(q.y, 240.0, 1e-9);
}

/// Ink-weighted centroid of a single-channel image.
cv::Point2d inkCentroid(const cv::Mat& grey)
{
  const cv::Moments m = cv::moments(grey, false);
  return {m.m10 / m.m00, m.m01 / m.m00};
}

// The HUD's glyph atlas against cv::putText itself (the independent reference): same footprint
// to 1 px, same ink (coverage) to 2 %, same ink centroid to 0.25 px, at the HUD's 720p and
// 1080p sizes and a small one; and each character is rasterised once.
TEST(HudText, GlyphAtlasMatchesPutText)
{
  const char* text = "mesa_left: 12.3 mm | PSM2: -- mm (no pose) ?#~";
  const struct
  {
    double scale;
    int thickness;
  } fonts[] = {{0.6, 1}, {0.9, 1}, {0.4, 1}, {1.2, 2}};
  const cv::Scalar colour(0, 200, 255);  // BGR
  for (const auto& f : fonts)
  {
    SCOPED_TRACE("scale " + std::to_string(f.scale));
    const cv::Point origin(10, 60);
    cv::Mat ref = cv::Mat::zeros(120, 1400, CV_8UC3), ref_mask = cv::Mat::zeros(120, 1400, CV_8UC1);
    cv::putText(ref, text, origin, cv::FONT_HERSHEY_SIMPLEX, f.scale, colour, f.thickness, cv::LINE_AA);
    cv::putText(ref_mask, text, origin, cv::FONT_HERSHEY_SIMPLEX, f.scale, cv::Scalar(255), f.thickness + 2,
                cv::LINE_AA);
    cv::threshold(ref_mask, ref_mask, 0, 255, cv::THRESH_BINARY);

    HudCache hud;
    cv::Mat out = cv::Mat::zeros(ref.size(), CV_8UC3), mask = cv::Mat::zeros(ref.size(), CV_8UC1);
    hud.drawLine(out, &mask, text, origin, f.scale, f.thickness, f.thickness + 2, colour);

    // Footprints equal up to the 0.5 px placement rounding of each glyph.
    const cv::Mat k3 = cv::getStructuringElement(cv::MORPH_RECT, cv::Size(3, 3));
    cv::Mat grown_ref, grown_out;
    cv::dilate(ref_mask, grown_ref, k3);
    cv::dilate(mask, grown_out, k3);
    EXPECT_EQ(cv::countNonZero(mask & ~grown_ref), 0);
    EXPECT_EQ(cv::countNonZero(ref_mask & ~grown_out), 0);
    EXPECT_GT(cv::countNonZero(ref_mask), 1000);
    cv::Mat ref_ch[3], out_ch[3];
    cv::split(ref, ref_ch);
    cv::split(out, out_ch);
    EXPECT_EQ(cv::countNonZero(out_ch[0]), 0);  // blue 0 in the colour: nothing drawn there
    for (int c = 1; c < 3; ++c)
    {
      const double ink_ref = cv::sum(ref_ch[c])[0], ink_out = cv::sum(out_ch[c])[0];
      EXPECT_NEAR(ink_out / ink_ref, 1.0, 0.02) << "channel " << c;
      const cv::Point2d c_ref = inkCentroid(ref_ch[c]), c_out = inkCentroid(out_ch[c]);
      EXPECT_NEAR(c_out.x, c_ref.x, 0.25);
      EXPECT_NEAR(c_out.y, c_ref.y, 0.25);
      // Vertical placement is exact (integer baseline): the row profiles agree closely.
      cv::Mat rows_ref, rows_out;
      cv::reduce(ref_ch[c], rows_ref, 1, cv::REDUCE_SUM, CV_64F);
      cv::reduce(out_ch[c], rows_out, 1, cv::REDUCE_SUM, CV_64F);
      EXPECT_LT(cv::norm(rows_ref, rows_out, cv::NORM_L1) / ink_ref, 0.05);
    }
    // Distinct characters of the text, each rasterised once; drawing again costs no rendering.
    bool seen[256] = {};
    std::size_t distinct = 0;
    for (const char* p = text; *p; ++p)
      if (!seen[static_cast<unsigned char>(*p)])
      {
        seen[static_cast<unsigned char>(*p)] = true;
        ++distinct;
      }
    EXPECT_EQ(hud.glyphRenders(), distinct);
    hud.drawLine(out, &mask, "12.3 mm", cv::Point(10, 100), f.scale, f.thickness, f.thickness + 2, colour);
    EXPECT_EQ(hud.glyphRenders(), distinct);
  }
}

// A glyph partly outside the image is clipped, not written out of bounds.
TEST(HudText, ClipsAtTheImageBorder)
{
  HudCache hud;
  cv::Mat img = cv::Mat::zeros(20, 30, CV_8UC4), mask = cv::Mat::zeros(20, 30, CV_8UC1);
  hud.drawLine(img, &mask, "WWW 888", cv::Point(-5, 15), 0.9, 1, 3, cv::Scalar(255, 255, 255, 255));
  EXPECT_GT(cv::countNonZero(mask), 50);
  EXPECT_LT(cv::countNonZero(mask), 20 * 30);
}

int main(int argc, char** argv)
{
  ::testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
