// JpegEncoder: the recorded JPEG streams (VisualFeedback /compressed, the simulated endoscope).
#include <cstdint>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "saras_visual_feedback/jpeg_encoder.h"

using saras_visual_feedback::ChannelOrder;
using saras_visual_feedback::JpegEncoder;

namespace
{
/// A smooth colour frame with edges (not a multiple of the 16 px MCU: edge padding is exercised).
cv::Mat frame(int w = 643, int h = 365)
{
  cv::Mat img(h, w, CV_8UC3);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      img.at<cv::Vec3b>(y, x) = cv::Vec3b(static_cast<uchar>(40 + x / 5), static_cast<uchar>(200 - y / 3),
                                          static_cast<uchar>((x + y) / 6));
  cv::circle(img, cv::Point(w / 2, h / 2), h / 4, cv::Scalar(0, 0, 255), 3, cv::LINE_AA);
  return img;
}

cv::Mat decode(const std::vector<std::uint8_t>& jpeg)
{
  return cv::imdecode(jpeg, cv::IMREAD_UNCHANGED);
}
}  // namespace

TEST(JpegEncoder, DecodesToTheSamePictureAsCvImencode)
{
  const cv::Mat img = frame();
  for (int q : { 50, 80, 95 })
  {
    JpegEncoder enc(q);
    std::vector<std::uint8_t> ours;
    std::vector<uchar> theirs;
    std::string error;
    ASSERT_TRUE(enc.encode(img, ChannelOrder::kBgr, &ours, &error)) << error;
    ASSERT_TRUE(cv::imencode(".jpg", img, theirs, { cv::IMWRITE_JPEG_QUALITY, q }));
    const cv::Mat a = decode(ours), b = decode(theirs);
    ASSERT_EQ(a.type(), CV_8UC3);
    ASSERT_EQ(a.size(), img.size());
    // same codec, same settings (4:2:0, standard tables): the same picture, whatever the bytes
    EXPECT_LE(cv::norm(a, b, cv::NORM_INF), 1.0) << "quality " << q;
    EXPECT_NEAR(static_cast<double>(ours.size()), static_cast<double>(theirs.size()), 0.02 * theirs.size());
    EXPECT_GT(cv::PSNR(a, img), q >= 80 ? 30.0 : 25.0) << "quality " << q;
  }
}

TEST(JpegEncoder, ReadsEachChannelOrderAsIs)
{
  const cv::Mat bgr = frame();
  cv::Mat rgb, bgra, rgba, grey;
  cv::cvtColor(bgr, rgb, cv::COLOR_BGR2RGB);
  cv::cvtColor(bgr, bgra, cv::COLOR_BGR2BGRA);
  cv::cvtColor(bgr, rgba, cv::COLOR_BGR2RGBA);
  cv::cvtColor(bgr, grey, cv::COLOR_BGR2GRAY);
  JpegEncoder enc(85);
  std::string error;
  std::vector<std::uint8_t> ref, out;
  ASSERT_TRUE(enc.encode(bgr, ChannelOrder::kBgr, &ref, &error)) << error;
  ASSERT_TRUE(enc.encode(rgb, ChannelOrder::kRgb, &out, &error)) << error;
  EXPECT_EQ(out, ref);  // the same colours, whatever the memory order
  ASSERT_TRUE(enc.encode(bgra, ChannelOrder::kBgr, &out, &error)) << error;
  EXPECT_EQ(out, ref);  // alpha ignored
  ASSERT_TRUE(enc.encode(rgba, ChannelOrder::kRgb, &out, &error)) << error;
  EXPECT_EQ(out, ref);
  // a wrong order swaps red and blue: the test above is not vacuous
  ASSERT_TRUE(enc.encode(rgb, ChannelOrder::kBgr, &out, &error)) << error;
  EXPECT_NE(out, ref);
  ASSERT_TRUE(enc.encode(grey, ChannelOrder::kBgr, &out, &error)) << error;
  const cv::Mat g = decode(out);
  ASSERT_EQ(g.type(), CV_8UC1);
  EXPECT_GT(cv::PSNR(g, grey), 30.0);
}

TEST(JpegEncoder, EncodesAViewWithItsStepAndReusesTheBuffer)
{
  const cv::Mat big = frame(800, 480);
  const cv::Mat view = big(cv::Rect(17, 9, 640, 360));  // step != cols * 3
  cv::Mat copy;
  view.copyTo(copy);
  JpegEncoder enc(80);
  std::string error;
  std::vector<std::uint8_t> a, b;
  ASSERT_TRUE(enc.encode(view, ChannelOrder::kBgr, &a, &error)) << error;
  ASSERT_TRUE(enc.encode(copy, ChannelOrder::kBgr, &b, &error)) << error;
  EXPECT_EQ(a, b);
  const std::uint8_t* data = a.data();
  ASSERT_TRUE(enc.encode(view, ChannelOrder::kBgr, &a, &error)) << error;
  EXPECT_EQ(a.data(), data);  // the capacity of the previous frame, no reallocation
  EXPECT_EQ(a, b);
  // a buffer far too small to start with grows as libjpeg writes
  std::vector<std::uint8_t> small;
  small.reserve(16);
  ASSERT_TRUE(JpegEncoder(100).encode(frame(1280, 720), ChannelOrder::kBgr, &small, &error)) << error;
  EXPECT_EQ(decode(small).size(), cv::Size(1280, 720));
}

TEST(JpegEncoder, RefusesWhatItCannotEncode)
{
  EXPECT_THROW(JpegEncoder(0), std::invalid_argument);
  EXPECT_THROW(JpegEncoder(101), std::invalid_argument);
  JpegEncoder enc(80);
  std::string error;
  std::vector<std::uint8_t> out{ 1, 2, 3 };
  EXPECT_FALSE(enc.encode(cv::Mat(10, 10, CV_16UC1, cv::Scalar(7)), ChannelOrder::kBgr, &out, &error));
  EXPECT_NE(error.find("8-bit"), std::string::npos) << error;
  EXPECT_TRUE(out.empty());
  EXPECT_FALSE(enc.encode(cv::Mat(), ChannelOrder::kBgr, &out, &error));
  // a libjpeg error (image wider than JPEG allows) is reported, and the encoder still works after it
  const cv::Mat wide(1, 70000, CV_8UC3, cv::Scalar(1, 2, 3));
  error.clear();
  EXPECT_FALSE(enc.encode(wide, ChannelOrder::kBgr, &out, &error));
  EXPECT_NE(error.find("JPEG encoding failed"), std::string::npos) << error;
  EXPECT_TRUE(enc.encode(frame(), ChannelOrder::kBgr, &out, &error)) << error;
  EXPECT_EQ(decode(out).size(), frame().size());
}

int main(int argc, char** argv)
{
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
