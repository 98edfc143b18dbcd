/**
 * @file test_capture_params.cpp
 * @brief readCaptureConfig through saras_common::Params over a map (no roscore): defaults, resolved
 *        sources, and a message naming parameter, value, unit and rule for bad values.
 */
#include <gtest/gtest.h>

#include <map>
#include <string>

#include "saras_drivers/capture_params.h"

using namespace saras_drivers::capture;

namespace
{
using Values = std::map<std::string, XmlRpc::XmlRpcValue>;

saras_common::Params paramsOf(const Values& given, bool with_pipelines = true)
{
  Values values = given;
  if (with_pipelines)
  {
    values.emplace("left_pipeline", XmlRpc::XmlRpcValue("/dev/video0"));
    values.emplace("right_pipeline", XmlRpc::XmlRpcValue("decklink:1"));
  }
  return saras_common::Params(
      [values](const std::string& n, XmlRpc::XmlRpcValue& v) {
        const auto it = values.find(n);
        if (it == values.end())
          return false;
        v = it->second;
        return true;
      },
      [](const std::string& n) { return "/endoscope/stereo_capture/" + n; });
}

std::string error(const Values& values, bool with_pipelines = true)
{
  try
  {
    readCaptureConfig(paramsOf(values, with_pipelines));
    return "accepted";
  }
  catch (const saras_common::ParamError& e)
  {
    return e.what();
  }
}
}  // namespace

TEST(CaptureParams, DefaultsAndSources)
{
  const CaptureConfig c = readCaptureConfig(paramsOf({}));
  EXPECT_EQ(c.source[0].kind, SourceKind::V4L2_DEVICE);
  EXPECT_EQ(c.source[1].kind, SourceKind::GSTREAMER);
  EXPECT_EQ(c.source[1].open_string, decklinkPipeline(1));
  EXPECT_EQ(c.frame_id[1], "endoscope/right_optical_frame");
  EXPECT_EQ(c.camera_name[0], "endoscope_left");
  EXPECT_DOUBLE_EQ(c.pair_tolerance, 0.010);
  EXPECT_DOUBLE_EQ(c.latency, 0.0);
  EXPECT_EQ(c.camera_info_url[0], "");
}

TEST(CaptureParams, PipelinesAreRequired)
{
  EXPECT_EQ(error({}, false), "parameter /endoscope/stereo_capture/left_pipeline = '' is invalid: must be a V4L2 "
                              "device (/dev/videoN), decklink:N, a GStreamer pipeline (elements joined by '!') or a video file");
}

TEST(CaptureParams, BadValuesNameTheRule)
{
  EXPECT_EQ(error({ { "pair_tolerance", XmlRpc::XmlRpcValue(0.0) } }),
            "parameter /endoscope/stereo_capture/pair_tolerance = 0 [s] is invalid: must be > 0 and <= 1");
  EXPECT_EQ(error({ { "latency", XmlRpc::XmlRpcValue(-0.1) } }),
            "parameter /endoscope/stereo_capture/latency = -0.1 [s] is invalid: must be in [0, 1]");
  EXPECT_EQ(error({ { "backoff_min", XmlRpc::XmlRpcValue(2.0) }, { "backoff_max", XmlRpc::XmlRpcValue(1.0) } }),
            "parameter /endoscope/stereo_capture/backoff_max = 1 [s] is invalid: must be >= backoff_min");
  EXPECT_EQ(error({ { "left_camera_info_url", XmlRpc::XmlRpcValue("/tmp/left.yaml") } }),
            "parameter /endoscope/stereo_capture/left_camera_info_url = '/tmp/left.yaml' is invalid: must be '' or a "
            "file:// or package:// URL");
  EXPECT_EQ(error({ { "expected_rate", XmlRpc::XmlRpcValue("fast") } }),
            "parameter /endoscope/stereo_capture/expected_rate = 'fast' [Hz] is invalid: must be a number");
}
