/**
 * @file eye_capture.h
 * @brief One eye of the stereo capture: a thread reading frames from an OpenCV cv::VideoCapture
 *        (V4L2 device, GStreamer pipeline, file), reopening it with back-off when it fails. ROS-free.
 */
#ifndef SARAS_DRIVERS_EYE_CAPTURE_H
#define SARAS_DRIVERS_EYE_CAPTURE_H

#include <functional>
#include <limits>
#include <memory>
#include <string>

#include <opencv2/core.hpp>

#include "saras_drivers/capture_core.h"

namespace saras_drivers
{
namespace capture
{
/// At most one message per period; the next one says how many were held back.
class ThrottledLog
{
public:
  explicit ThrottledLog(double period) : period_(period) {}
  /// @return the text to log now ("" = held back) for @p message at @p now [s]
  std::string filter(const std::string& message, double now)
  {
    if (now - last_ < period_)
    {
      ++held_;
      return "";
    }
    last_ = now;
    std::string out = message;
    if (held_ > 0)
      out += " (" + std::to_string(held_) + " similar messages not shown)";
    held_ = 0;
    return out;
  }

private:
  double period_;
  double last_ = -std::numeric_limits<double>::infinity();
  unsigned long held_ = 0;
};

/**
 * Parse GStreamer pipeline @p pipeline (nothing is started). OpenCV's GStreamer backend hangs in
 * open() on a pipeline whose source element is missing (e.g. `decklinkvideosrc` without
 * gstreamer1.0-plugins-bad); EyeCapture checks every pipeline with this first.
 * @return "" if it parses with every element present, else GStreamer's error ("no element \"x\"")
 */
std::string checkPipeline(const std::string& pipeline);

/// Options of one eye.
struct EyeOptions
{
  std::string name = "left";    ///< for messages
  VideoSource source;           ///< what to open (resolveSource())
  double backoff_min = 0.5;     ///< [s] first delay before reopening
  double backoff_max = 8.0;     ///< [s] longest delay before reopening
  int max_failed_grabs = 10;    ///< consecutive failed reads after which the source is closed and reopened
  double log_period = 5.0;      ///< [s] at most one error line per period
};

/**
 * Captures one eye in its own thread from construction to destruction. Each frame goes to the sink
 * with its grab time (the clock read right after read() returned). A source that does not open, or
 * fails max_failed_grabs reads in a row, is (re)opened after a back-off delay (Backoff); errors go
 * to the log callback, at most one per log_period. Nothing throws out of the thread.
 *
 * The destructor stops the thread; a thread blocked inside the capture backend (a source that
 * hangs in read()) is left to finish on its own after a grace period, with the sink disconnected:
 * the sink is never called once the destructor has returned.
 */
class EyeCapture
{
public:
  using Clock = std::function<double()>;                        ///< now [s]
  using Sink = std::function<void(cv::Mat& frame, double grab_time)>;  ///< may move the frame out
  using Log = std::function<void(const std::string& message)>;  ///< error lines (already throttled)

  EyeCapture(const EyeOptions& options, Clock clock, Sink sink, Log log);
  ~EyeCapture();
  EyeCapture(const EyeCapture&) = delete;
  EyeCapture& operator=(const EyeCapture&) = delete;

  /// A snapshot of the eye's state and counters.
  EyeStatus status() const;

  struct Shared;

private:
  std::shared_ptr<Shared> shared_;
};

}  // namespace capture
}  // namespace saras_drivers

#endif  // SARAS_DRIVERS_EYE_CAPTURE_H
