/**
 * @file eye_capture.cpp
 * @brief Capture thread of one eye (eye_capture.h).
 */
#include "saras_drivers/eye_capture.h"

#include <chrono>
#include <condition_variable>
#include <exception>
#include <mutex>
#include <thread>

#include <gst/gst.h>
#include <opencv2/videoio.hpp>

namespace saras_drivers
{
namespace capture
{
std::string checkPipeline(const std::string& pipeline)
{
  GError* init_error = nullptr;
  if (!gst_init_check(nullptr, nullptr, &init_error))
  {
    const std::string why = init_error ? init_error->message : "unknown error";
    g_clear_error(&init_error);
    return "GStreamer does not initialise: " + why;
  }
  GError* error = nullptr;
  GstElement* p = gst_parse_launch_full(pipeline.c_str(), nullptr, GST_PARSE_FLAG_FATAL_ERRORS, &error);
  std::string why;
  if (error)
    why = error->message;
  else if (!p)
    why = "not a pipeline";
  g_clear_error(&error);
  if (p)
    gst_object_unref(p);
  return why;
}

struct EyeCapture::Shared
{
  EyeOptions options;
  Clock clock;
  Log log;
  mutable std::mutex mutex;  ///< status, stop, finished
  std::condition_variable wake;
  EyeStatus status;
  bool stop = false;
  bool finished = false;
  std::mutex sink_mutex;  ///< held while the sink or log runs; the destructor clears both under it
  Sink sink;
  ThrottledLog throttle{ 5.0 };

  void report(const std::string& message)
  {
    std::string line;
    {
      std::lock_guard<std::mutex> lock(mutex);
      status.error = message;
      line = throttle.filter(options.name + " camera: " + message, clock());
    }
    std::lock_guard<std::mutex> lock(sink_mutex);
    if (!line.empty() && log)
      log(line);
  }

  /// Sleep @p seconds or until stopped; @return false if stopped.
  bool sleep(double seconds)
  {
    std::unique_lock<std::mutex> lock(mutex);
    wake.wait_for(lock, std::chrono::duration<double>(seconds), [this] { return stop; });
    return !stop;
  }

  bool stopping() const
  {
    std::lock_guard<std::mutex> lock(mutex);
    return stop;
  }

  /// Open the source; @return "" or why it failed.
  std::string open(cv::VideoCapture& cap)
  {
    const VideoSource& s = options.source;
    bool ok = false;
    try
    {
      switch (s.kind)
      {
        case SourceKind::V4L2_DEVICE:
          ok = cap.open(s.device_index, cv::CAP_V4L2);
          break;
        case SourceKind::GSTREAMER:
        {
          const std::string why = checkPipeline(s.open_string);
          if (!why.empty())
            return why;
          ok = cap.open(s.open_string, cv::CAP_GSTREAMER);
          break;
        }
        case SourceKind::FILE_OR_URL:
          ok = cap.open(s.open_string, cv::CAP_ANY);
          break;
      }
    }
    catch (const std::exception& ex)
    {
      return std::string("OpenCV: ") + ex.what();
    }
    return ok ? "" : "OpenCV cannot open it";
  }

  void deliver(cv::Mat& frame, double t)
  {
    {
      std::lock_guard<std::mutex> lock(mutex);
      ++status.frames;
      status.last_frame = t;
      status.width = frame.cols;
      status.height = frame.rows;
      status.error.clear();
    }
    std::lock_guard<std::mutex> lock(sink_mutex);
    if (sink)
      sink(frame, t);
  }

  void run();
};

void EyeCapture::Shared::run()
{
  Backoff backoff(options.backoff_min, options.backoff_max);
  cv::VideoCapture cap;
  int failed_in_row = 0;
  bool delivered = false;  ///< since the last open
  bool ever_opened = false;
  while (!stopping())
  {
    if (!cap.isOpened())
    {
      const std::string why = open(cap);
      if (!why.empty())
      {
        {
          std::lock_guard<std::mutex> lock(mutex);
          ++status.open_failures;
        }
        report("cannot open '" + options.source.open_string + "' (" + why + "); retrying");
        sleep(backoff.next());
        continue;
      }
      std::lock_guard<std::mutex> lock(mutex);
      status.open = true;
      status.reopens += ever_opened ? 1 : 0;
      ever_opened = true;
      failed_in_row = 0;
      delivered = false;
    }
    cv::Mat frame;
    bool ok = false;
    try
    {
      ok = cap.read(frame) && !frame.empty();
    }
    catch (const std::exception& ex)
    {
      report(std::string("read threw: ") + ex.what());
    }
    const double t = clock();
    if (ok)
    {
      failed_in_row = 0;
      if (!delivered)
        backoff.reset();
      delivered = true;
      deliver(frame, t);
      continue;
    }
    {
      std::lock_guard<std::mutex> lock(mutex);
      ++status.failed_grabs;
    }
    if (++failed_in_row >= options.max_failed_grabs)
    {
      cap.release();
      {
        std::lock_guard<std::mutex> lock(mutex);
        status.open = false;
      }
      report("stopped delivering frames (" + std::to_string(failed_in_row) + " failed reads); reopening");
      sleep(backoff.next());
    }
  }
  cap.release();
  std::lock_guard<std::mutex> lock(mutex);
  status.open = false;
  finished = true;
  wake.notify_all();
}

EyeCapture::EyeCapture(const EyeOptions& options, Clock clock, Sink sink, Log log) : shared_(std::make_shared<Shared>())
{
  shared_->options = options;
  shared_->throttle = ThrottledLog(options.log_period);
  shared_->clock = std::move(clock);
  shared_->log = std::move(log);
  shared_->sink = std::move(sink);
  std::shared_ptr<Shared> s = shared_;  // the thread keeps the state alive if it outlives us
  std::thread([s] { s->run(); }).detach();
}

EyeCapture::~EyeCapture()
{
  {
    std::lock_guard<std::mutex> lock(shared_->sink_mutex);  // waits for a running sink call
    shared_->sink = nullptr;
    shared_->log = nullptr;
  }
  std::unique_lock<std::mutex> lock(shared_->mutex);
  shared_->stop = true;
  shared_->wake.notify_all();
  // a backend blocked in read() cannot be interrupted: give it a grace period, then leave it
  shared_->wake.wait_for(lock, std::chrono::seconds(3), [this] { return shared_->finished; });
}

EyeStatus EyeCapture::status() const
{
  std::lock_guard<std::mutex> lock(shared_->mutex);
  return shared_->status;
}

}  // namespace capture
}  // namespace saras_drivers
