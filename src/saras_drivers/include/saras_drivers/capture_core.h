/**
 * @file capture_core.h
 * @brief ROS-free logic of the stereo endoscope capture (nodelet saras_drivers/StereoCapture):
 *        video source strings, capture stamps, stereo pairing by time, reopen back-off, health.
 *
 * Times are seconds of the caller's clock (ROS time in the nodelet, any clock in tests).
 */
#ifndef SARAS_DRIVERS_CAPTURE_CORE_H
#define SARAS_DRIVERS_CAPTURE_CORE_H

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <string>
#include <utility>

namespace saras_drivers
{
namespace capture
{
/// How OpenCV opens a source string.
enum class SourceKind
{
  V4L2_DEVICE,  ///< /dev/videoN or a bare device index N (cv::CAP_V4L2)
  GSTREAMER,    ///< a GStreamer pipeline (contains '!'), ending in an appsink (cv::CAP_GSTREAMER)
  FILE_OR_URL   ///< anything else: a video file or URL (cv::CAP_ANY)
};

/// A source string resolved for cv::VideoCapture::open().
struct VideoSource
{
  SourceKind kind = SourceKind::FILE_OR_URL;
  std::string open_string;  ///< what is passed to open() (GStreamer: the pipeline, appsink appended if missing)
  int device_index = -1;    ///< V4L2: N of /dev/videoN (opened by index)
};

/// The appsink OpenCV reads from: BGR, at most one buffer waiting, newest kept (no latency build-up).
extern const char* const kAppSink;

/**
 * Resolve @p spec: "/dev/videoN" or "N" => V4L2 device N; "decklink:N" => decklinkPipeline(N)
 * (Decklink input N, mode and connection auto-detected); a string containing '!' => GStreamer
 * pipeline (if its last element is not an appsink, " ! videoconvert ! <kAppSink>" is appended);
 * else a file or URL.
 * @throws std::invalid_argument for an empty or blank spec
 */
VideoSource resolveSource(const std::string& spec);

/**
 * The production pipeline of one Decklink input (Blackmagic `decklinkvideosrc`, gst-plugins-bad):
 * `decklinkvideosrc device-number=N [mode=M] [connection=C] ! videoconvert ! <kAppSink>`.
 * @param mode Decklink mode nick ("1080i5994", "720p60", ... ; "" = auto)
 * @param connection "sdi", "hdmi", "composite", "svideo", "component" ("" = auto)
 */
std::string decklinkPipeline(int device_number, const std::string& mode = "", const std::string& connection = "");

/// Capture stamp of a frame grabbed at @p grab_time [s]: the grab time minus the fixed @p latency [s].
inline double captureStamp(double grab_time, double latency)
{
  return grab_time - latency;
}

/// sensor_msgs/image_encodings name of an OpenCV matrix type (CV_8UC3 ...), "" if unsupported.
std::string encodingOf(int cv_type);

/// Counters of the pairing (monotonic).
struct PairCounters
{
  uint64_t frames[2] = { 0, 0 };  ///< frames offered per eye (0 = left, 1 = right)
  uint64_t pairs = 0;             ///< pairs formed
  uint64_t unmatched[2] = { 0, 0 };  ///< frames dropped per eye: no frame of the other eye within the tolerance
};

/**
 * Pairs the frames of two free-running capture threads by capture time.
 *
 * A frame of one eye is paired with the nearest waiting frame of the other eye if their stamps
 * differ by at most the tolerance; the pair gets the mean of the two stamps. Waiting frames of the
 * other eye older than the matched one, or older than (new stamp - tolerance), can no longer match
 * and are dropped (counted as unmatched). Each eye keeps at most @p depth waiting frames (the
 * oldest is dropped). Not thread-safe: the caller serialises push().
 *
 * With synchronised (genlocked) inputs the tolerance should be below half the frame period (each
 * frame has at most one candidate); with free-running inputs up to one period pairs every frame.
 */
template <typename Frame>
class StereoPairer
{
public:
  struct Pair
  {
    double stamp;     ///< common stamp of the pair [s]
    Frame frame[2];   ///< left, right
  };

  StereoPairer(double tolerance, std::size_t depth) : tolerance_(tolerance), depth_(depth < 1 ? 1 : depth) {}

  /**
   * Offer frame @p f of eye @p eye (0 left, 1 right) captured at @p stamp [s].
   * @return true and @p out filled when it completed a pair
   */
  bool push(int eye, double stamp, Frame f, Pair& out)
  {
    const int other = 1 - eye;
    ++counters_.frames[eye];
    std::deque<Entry>& q = waiting_[other];
    std::size_t best = q.size();
    double best_dt = tolerance_;
    for (std::size_t i = 0; i < q.size(); ++i)
    {
      const double dt = std::fabs(q[i].stamp - stamp);
      if (dt <= best_dt)
      {
        best = i;
        best_dt = dt;
      }
    }
    if (best < q.size())
    {
      counters_.unmatched[other] += best;  // older frames of the other eye: skipped over
      out.stamp = 0.5 * (stamp + q[best].stamp);
      out.frame[eye] = std::move(f);
      out.frame[other] = std::move(q[best].frame);
      q.erase(q.begin(), q.begin() + static_cast<std::ptrdiff_t>(best) + 1);
      ++counters_.pairs;
      return true;
    }
    while (!q.empty() && q.front().stamp < stamp - tolerance_)
    {
      q.pop_front();
      ++counters_.unmatched[other];
    }
    std::deque<Entry>& mine = waiting_[eye];
    mine.push_back(Entry{ stamp, std::move(f) });
    while (mine.size() > depth_)
    {
      mine.pop_front();
      ++counters_.unmatched[eye];
    }
    return false;
  }

  /// Drop the waiting frames of @p eye (its camera was reopened), counted as unmatched.
  void flush(int eye)
  {
    counters_.unmatched[eye] += waiting_[eye].size();
    waiting_[eye].clear();
  }

  const PairCounters& counters() const { return counters_; }
  double tolerance() const { return tolerance_; }

private:
  struct Entry
  {
    double stamp;
    Frame frame;
  };
  double tolerance_;
  std::size_t depth_;
  std::deque<Entry> waiting_[2];
  PairCounters counters_;
};

/// Exponential back-off between reopen attempts: min, 2 min, 4 min ... capped at max [s].
class Backoff
{
public:
  Backoff(double min_delay, double max_delay) : min_(min_delay), max_(max_delay), next_(min_delay) {}
  /// Delay before the next attempt [s]; doubles the following one.
  double next()
  {
    const double d = next_;
    next_ = std::min(max_, 2.0 * next_);
    return d;
  }
  /// A source opened and delivered: start again from min.
  void reset() { next_ = min_; }

private:
  double min_, max_, next_;
};

/// State of one eye's capture, as its thread reports it (counters monotonic).
struct EyeStatus
{
  bool open = false;            ///< the source is open
  uint64_t frames = 0;          ///< frames grabbed
  uint64_t failed_grabs = 0;    ///< read() returned no frame
  uint64_t open_failures = 0;   ///< open() failed
  uint64_t reopens = 0;         ///< the source was closed after failures and opened again
  double last_frame = -1.0;     ///< grab time of the last frame [s]; < 0 = none yet
  int width = 0, height = 0;    ///< size of the last frame [px]
  std::string error;            ///< last error ("" = none since the last frame)
};

/// Diagnostic level (values of diagnostic_msgs/DiagnosticStatus).
enum class Level : int8_t
{
  OK = 0,
  WARN = 1,
  ERROR = 2
};

/// Summary of the capture's health.
struct Health
{
  Level level = Level::OK;
  std::string message;
};

/**
 * Health of the two eyes at @p now [s]: ERROR if an eye is not open, never delivered a frame for
 * @p stall_timeout since @p started, or delivered none for @p stall_timeout; WARN if a frame size
 * differs from its calibration (@p calib_w/@p calib_h, 0 = unknown); else OK.
 */
Health assessHealth(const EyeStatus eyes[2], const int calib_size[2][2], double now, double started,
                    double stall_timeout);

}  // namespace capture
}  // namespace saras_drivers

#endif  // SARAS_DRIVERS_CAPTURE_CORE_H
