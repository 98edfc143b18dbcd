/**
 * @file capture_core.cpp
 * @brief Source strings, encodings and health of the stereo capture (capture_core.h).
 */
#include "saras_drivers/capture_core.h"

#include <cctype>
#include <stdexcept>

#include <opencv2/core.hpp>

namespace saras_drivers
{
namespace capture
{
const char* const kAppSink = "video/x-raw,format=BGR ! appsink drop=true max-buffers=1 sync=false";

namespace
{
std::string trim(const std::string& s)
{
  const auto b = s.find_first_not_of(" \t\r\n");
  if (b == std::string::npos)
    return "";
  const auto e = s.find_last_not_of(" \t\r\n");
  return s.substr(b, e - b + 1);
}

bool allDigits(const std::string& s)
{
  if (s.empty() || s.size() > 6)
    return false;
  for (char c : s)
    if (!std::isdigit(static_cast<unsigned char>(c)))
      return false;
  return true;
}

/// Whether the last element of a pipeline is an appsink ("... ! appsink name=x drop=true").
bool endsInAppSink(const std::string& pipeline)
{
  const auto bang = pipeline.rfind('!');
  const std::string last = trim(bang == std::string::npos ? pipeline : pipeline.substr(bang + 1));
  return last.compare(0, 7, "appsink") == 0 && (last.size() == 7 || std::isspace(static_cast<unsigned char>(last[7])));
}
}  // namespace

VideoSource resolveSource(const std::string& spec)
{
  const std::string s = trim(spec);
  if (s.empty())
    throw std::invalid_argument("empty video source");
  VideoSource v;
  const std::string dev = "/dev/video";
  if (allDigits(s) || (s.compare(0, dev.size(), dev) == 0 && allDigits(s.substr(dev.size()))))
  {
    v.kind = SourceKind::V4L2_DEVICE;
    v.device_index = std::stoi(allDigits(s) ? s : s.substr(dev.size()));
    v.open_string = dev + std::to_string(v.device_index);
    return v;
  }
  const std::string decklink = "decklink:";
  if (s.compare(0, decklink.size(), decklink) == 0 && allDigits(s.substr(decklink.size())))
  {
    v.kind = SourceKind::GSTREAMER;
    v.open_string = decklinkPipeline(std::stoi(s.substr(decklink.size())));
    return v;
  }
  if (s.find('!') != std::string::npos)
  {
    v.kind = SourceKind::GSTREAMER;
    v.open_string = endsInAppSink(s) ? s : s + " ! videoconvert ! " + kAppSink;
    return v;
  }
  v.kind = SourceKind::FILE_OR_URL;
  v.open_string = s;
  return v;
}

std::string decklinkPipeline(int device_number, const std::string& mode, const std::string& connection)
{
  if (device_number < 0)
    throw std::invalid_argument("Decklink device number must be >= 0");
  std::string p = "decklinkvideosrc device-number=" + std::to_string(device_number);
  if (!mode.empty())
    p += " mode=" + mode;
  if (!connection.empty())
    p += " connection=" + connection;
  return p + " ! videoconvert ! " + kAppSink;
}

std::string encodingOf(int cv_type)
{
  switch (cv_type)
  {
    case CV_8UC1:
      return "mono8";
    case CV_8UC3:
      return "bgr8";
    case CV_8UC4:
      return "bgra8";
    case CV_16UC1:
      return "mono16";
    default:
      return "";
  }
}

Health assessHealth(const EyeStatus eyes[2], const int calib_size[2][2], double now, double started,
                    double stall_timeout)
{
  static const char* const kNames[2] = { "left", "right" };
  Health h;
  std::string errors, warnings;
  for (int e = 0; e < 2; ++e)
  {
    const EyeStatus& s = eyes[e];
    const std::string why = s.error.empty() ? "" : ": " + s.error;
    if (!s.open)
      errors += std::string(errors.empty() ? "" : "; ") + kNames[e] + " camera not open" + why;
    else if (s.last_frame < 0.0 ? now - started > stall_timeout : now - s.last_frame > stall_timeout)
      errors += std::string(errors.empty() ? "" : "; ") + kNames[e] + " camera delivers no frames" + why;
    else if (calib_size[e][0] > 0 && s.width > 0 && (s.width != calib_size[e][0] || s.height != calib_size[e][1]))
      warnings += std::string(warnings.empty() ? "" : "; ") + kNames[e] + " frames " + std::to_string(s.width) + "x" +
                  std::to_string(s.height) + " but calibrated at " + std::to_string(calib_size[e][0]) + "x" +
                  std::to_string(calib_size[e][1]);
  }
  if (!errors.empty())
  {
    h.level = Level::ERROR;
    h.message = errors;
  }
  else if (!warnings.empty())
  {
    h.level = Level::WARN;
    h.message = warnings;
  }
  else
    h.message = "capturing";
  return h;
}

}  // namespace capture
}  // namespace saras_drivers
