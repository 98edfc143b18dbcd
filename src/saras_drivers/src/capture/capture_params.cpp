/**
 * @file capture_params.cpp
 * @brief Reading and validation of the stereo capture parameters (capture_params.h).
 */
#include "saras_drivers/capture_params.h"

#include <stdexcept>

namespace saras_drivers
{
namespace capture
{
using saras_common::atLeast;
using saras_common::inRange;
using saras_common::nonNegative;
using saras_common::positive;

namespace
{
const char* const kEyes[2] = { "left", "right" };

/// The eye's source: required, resolvable; a GStreamer pipeline must end in an appsink if it names one.
void readEye(const saras_common::Params& p, int e, CaptureConfig& c)
{
  const std::string eye = kEyes[e];
  c.pipeline[e] = p.text(eye + "_pipeline", "");
  try
  {
    c.source[e] = resolveSource(c.pipeline[e]);
  }
  catch (const std::invalid_argument&)
  {
    p.fail(eye + "_pipeline", "'" + c.pipeline[e] + "'", "",
           "a V4L2 device (/dev/videoN), decklink:N, a GStreamer pipeline (elements joined by '!') or a video file");
  }
  c.camera_info_url[e] = p.text(eye + "_camera_info_url", "");
  const std::string& url = c.camera_info_url[e];
  if (!url.empty() && url.compare(0, 7, "file://") != 0 && url.compare(0, 10, "package://") != 0)
    p.fail(eye + "_camera_info_url", "'" + url + "'", "", "'' or a file:// or package:// URL");
  c.camera_name[e] = p.text(eye + "_camera_name", c.camera_name[e], { saras_common::nonEmpty() });
  c.frame_id[e] = p.text(eye + "_frame", c.frame_id[e], { saras_common::nonEmpty() });
}
}  // namespace

CaptureConfig readCaptureConfig(const saras_common::Params& p)
{
  CaptureConfig c;
  for (int e = 0; e < 2; ++e)
    readEye(p, e, c);
  c.latency = p.number("latency", c.latency, "s", { inRange(0.0, 1.0) });
  c.pair_tolerance = p.number("pair_tolerance", c.pair_tolerance, "s", { positive(), saras_common::atMost(1.0) });
  c.pair_queue = p.integer("pair_queue", c.pair_queue, "frames", { inRange(1, 100) });
  c.expected_rate = p.number("expected_rate", c.expected_rate, "Hz", { positive() });
  c.rate_tolerance = p.number("rate_tolerance", c.rate_tolerance, "", { positive(), saras_common::atMost(0.99) });
  c.stall_timeout = p.number("stall_timeout", c.stall_timeout, "s", { positive() });
  c.backoff_min = p.number("backoff_min", c.backoff_min, "s", { positive() });
  c.backoff_max = p.number("backoff_max", c.backoff_max, "s", { positive() });
  if (c.backoff_max < c.backoff_min)
    p.fail("backoff_max", c.backoff_max, "s", ">= backoff_min");
  c.max_failed_grabs = p.integer("max_failed_grabs", c.max_failed_grabs, "", { atLeast(1) });
  c.log_period = p.number("log_period", c.log_period, "s", { nonNegative() });
  c.diagnostic_period = p.number("diagnostic_period", c.diagnostic_period, "s", { positive() });
  c.image_queue = p.integer("image_queue", c.image_queue, "messages", { atLeast(1) });
  c.recorded_queue = p.integer("recorded_queue", c.recorded_queue, "messages", { atLeast(1) });
  c.jpeg_quality = p.integer("jpeg_quality", c.jpeg_quality, "", { inRange(0, 100) });
  return c;
}

}  // namespace capture
}  // namespace saras_drivers
