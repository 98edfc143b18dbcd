/**
 * @file bag_recorder.cpp
 * @brief bag_recorder: the platform's data-recording node (D7.2 Section 2.1), a `rosbag record`
 *        with a deep per-topic subscription queue.
 *
 * `rosbag record` subscribes every topic with a fixed queue of 100 messages. On a loaded host its
 * socket reads come in bursts after a stall (the kernel buffers hold hundreds of small messages);
 * such a burst overflows the 100-message queue and the bag silently loses part of a fast stream
 * (test/bag_recorder_burst.test shows it with --queue 100). This node
 * writes the same bag format (rosbag::Bag, receive-time stamps, connection headers, latched topics)
 * and takes the queue depth as an argument; the byte budget between the subscriptions and the
 * writer thread (--buffsize) is bounded and what it drops is counted and reported.
 *
 * Usage: bag_recorder -O out.bag [--buffsize MB] [--chunksize KB] [--queue N] [--tcpnodelay]
 *                     [--duration S] /topic ...
 * The bag is written as out.bag.active and renamed when closed (SIGINT, or after --duration s).
 * Health: diagnostic_updater on /diagnostics (hardware_id `recording`), one status "<node>: bag" with
 * the messages received, dropped by the full buffer, queued and failed writes (WARN while messages are
 * dropped, ERROR after a write error).
 * Exit status: 0 closed cleanly, 1 bad arguments or the bag cannot be written.
 */
#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include <boost/make_shared.hpp>
#include <diagnostic_updater/diagnostic_updater.h>
#include <ros/callback_queue.h>
#include <ros/ros.h>
#include <rosbag/bag.h>
#include <rosbag/exceptions.h>
#include <topic_tools/shape_shifter.h>

#include "saras_bringup/bounded_queue.h"

namespace saras_bringup
{
namespace
{
struct Options
{
  std::string output;
  std::size_t buffer_mb = 1024;  ///< [MB] writer queue budget
  std::uint32_t chunk_kb = 768;  ///< [kB] bag chunk size
  std::uint32_t queue = 2000;    ///< [messages] per-topic subscription queue
  bool tcp_nodelay = false;
  double duration = 0.0;  ///< [s] 0 = until SIGINT
  std::vector<std::string> topics;
};

bool parseUnsigned(const char* s, unsigned long long lo, unsigned long long hi, unsigned long long& out)
{
  char* end = nullptr;
  const unsigned long long v = std::strtoull(s, &end, 10);
  if (end == s || *end != '\0' || v < lo || v > hi)
    return false;
  out = v;
  return true;
}

/// Parses the arguments left after ros::init; false (with a message) on error.
bool parseOptions(int argc, char** argv, Options& o)
{
  for (int i = 1; i < argc; ++i)
  {
    const std::string a = argv[i];
    const bool has_value = i + 1 < argc;
    unsigned long long v = 0;
    auto value = [&](const std::string& name, unsigned long long lo, unsigned long long hi) {
      if (!has_value || !parseUnsigned(argv[++i], lo, hi, v))
      {
        std::fprintf(stderr, "bag_recorder: %s needs an integer in [%llu, %llu]\n", name.c_str(), lo, hi);
        return false;
      }
      return true;
    };
    if (a == "-O" && has_value)
      o.output = argv[++i];
    else if (a == "--buffsize")
    {
      if (!value(a, 1, 65536))
        return false;
      o.buffer_mb = v;
    }
    else if (a == "--chunksize")
    {
      if (!value(a, 1, 1048576))
        return false;
      o.chunk_kb = static_cast<std::uint32_t>(v);
    }
    else if (a == "--queue")
    {
      if (!value(a, 1, 1000000))
        return false;
      o.queue = static_cast<std::uint32_t>(v);
    }
    else if (a == "--duration" && has_value)
    {
      char* end = nullptr;
      o.duration = std::strtod(argv[++i], &end);
      if (*end != '\0' || !(o.duration > 0.0 && o.duration < 1e7))
      {
        std::fprintf(stderr, "bag_recorder: --duration needs seconds > 0\n");
        return false;
      }
    }
    else if (a == "--tcpnodelay")
      o.tcp_nodelay = true;
    else if (!a.empty() && a[0] == '/')
      o.topics.push_back(a);
    else
    {
      std::fprintf(stderr, "bag_recorder: unknown argument '%s' (topics must be absolute names)\n", a.c_str());
      return false;
    }
  }
  if (o.output.empty() || o.topics.empty())
  {
    std::fprintf(stderr, "usage: bag_recorder -O out.bag [--buffsize MB] [--chunksize KB] [--queue N] "
                         "[--tcpnodelay] [--duration S] /topic ...\n");
    return false;
  }
  return true;
}

/// One received message on its way to the bag.
struct Outgoing
{
  const std::string* topic = nullptr;  ///< one of Options::topics (stable for the recorder's life)
  topic_tools::ShapeShifter::ConstPtr msg;
  boost::shared_ptr<ros::M_string> header;
  ros::Time time;
};

class BagRecorder
{
public:
  explicit BagRecorder(const Options& o)
    : options_(o), queue_(o.buffer_mb * 1024 * 1024), counts_(o.topics.size(), 0)
  {
  }

  /// Opens the bag and subscribes; throws rosbag::BagException when the bag cannot be opened.
  void start()
  {
    active_path_ = options_.output + ".active";
    bag_.open(active_path_, rosbag::bagmode::Write);
    bag_.setChunkThreshold(options_.chunk_kb * 1024);
    ros::NodeHandle nh;
    ros::TransportHints hints;
    if (options_.tcp_nodelay)
      hints = hints.tcpNoDelay();
    for (std::size_t i = 0; i < options_.topics.size(); ++i)
    {
      const std::string& topic = options_.topics[i];
      ros::SubscribeOptions ops;
      ops.topic = topic;
      ops.queue_size = options_.queue;
      ops.md5sum = ros::message_traits::md5sum<topic_tools::ShapeShifter>();
      ops.datatype = ros::message_traits::datatype<topic_tools::ShapeShifter>();
      ops.helper = boost::make_shared<
          ros::SubscriptionCallbackHelperT<const ros::MessageEvent<topic_tools::ShapeShifter const>&>>(
          [this, i](const ros::MessageEvent<topic_tools::ShapeShifter const>& e) { onMessage(i, e); });
      ops.transport_hints = hints;
      ops.callback_queue = &callbacks_;
      subscribers_.push_back(nh.subscribe(ops));
    }
    writer_ = std::thread([this] { writeLoop(); });
    spinner_.reset(new ros::AsyncSpinner(1, &callbacks_));
    spinner_->start();
    ROS_INFO("bag_recorder: recording %zu topics to %s (queue %u per topic, buffer %zu MB)", options_.topics.size(),
             options_.output.c_str(), options_.queue, options_.buffer_mb);
  }

  /// Unsubscribes, writes what is queued, closes and renames the bag. Returns false on a write error.
  bool stop()
  {
    spinner_->stop();
    subscribers_.clear();
    stopping_ = true;
    queue_.close();
    writer_.join();
    try
    {
      bag_.close();
    }
    catch (const rosbag::BagException& e)
    {
      ROS_ERROR("bag_recorder: closing %s: %s", active_path_.c_str(), e.what());
      return false;
    }
    if (std::rename(active_path_.c_str(), options_.output.c_str()) != 0)
    {
      ROS_ERROR("bag_recorder: cannot rename %s to %s", active_path_.c_str(), options_.output.c_str());
      return false;
    }
    std::uint64_t total = 0;
    for (const std::uint64_t c : counts_)
      total += c;
    std::printf("bag_recorder: %s closed: %llu messages, %llu dropped by the %zu MB buffer, peak %.1f MB queued, "
                "%llu write errors\n",
                options_.output.c_str(), static_cast<unsigned long long>(total),
                static_cast<unsigned long long>(queue_.dropped()), options_.buffer_mb, queue_.peakBytes() / 1048576.0,
                static_cast<unsigned long long>(write_errors_.load()));
    std::fflush(stdout);
    return write_errors_ == 0;
  }

  /// Diagnostic task "bag": what was received, dropped, queued and not written since the start.
  void diagnose(diagnostic_updater::DiagnosticStatusWrapper& stat)
  {
    const std::uint64_t received = queue_.pushed();
    const std::uint64_t dropped = queue_.dropped();
    const std::uint64_t errors = write_errors_.load();
    if (errors > 0)
      stat.summaryf(diagnostic_msgs::DiagnosticStatus::ERROR, "%llu writes to the bag failed",
                    static_cast<unsigned long long>(errors));
    else if (dropped > reported_dropped_)
      stat.summaryf(diagnostic_msgs::DiagnosticStatus::WARN, "buffer full: %llu messages dropped so far",
                    static_cast<unsigned long long>(dropped));
    else
      stat.summary(diagnostic_msgs::DiagnosticStatus::OK, "recording");
    reported_dropped_ = dropped;
    stat.add("bag", options_.output);
    stat.add("topics", options_.topics.size());
    stat.add("messages received", received);
    stat.add("messages dropped (buffer full)", dropped);
    stat.add("write errors", errors);
    stat.addf("queued [MB]", "%.1f", queue_.bytes() / 1048576.0);
    stat.addf("peak queued [MB]", "%.1f", queue_.peakBytes() / 1048576.0);
    stat.add("buffer [MB]", options_.buffer_mb);
  }

private:
  /// Per message: no allocation besides the queue node (topic by pointer, counter by index).
  void onMessage(std::size_t index, const ros::MessageEvent<topic_tools::ShapeShifter const>& e)
  {
    Outgoing out{ &options_.topics[index], e.getConstMessage(), e.getConnectionHeaderPtr(), ros::Time::now() };
    const std::size_t bytes = out.msg->size();
    ++counts_[index];  // only the single spinner thread touches counts_ while recording
    if (queue_.push(std::move(out), bytes) > 0)
      ROS_WARN_THROTTLE(5.0, "bag_recorder: buffer of %zu MB full, oldest messages dropped (%llu so far)",
                        options_.buffer_mb, static_cast<unsigned long long>(queue_.dropped()));
  }

  void writeLoop()
  {
    Outgoing out;
    for (;;)
    {
      if (!queue_.pop(out, std::chrono::milliseconds(100)))
      {
        if (stopping_ && queue_.size() == 0)
          return;
        continue;
      }
      try
      {
        bag_.write(*out.topic, out.time, *out.msg, out.header);
      }
      catch (const rosbag::BagException& e)
      {
        ++write_errors_;
        ROS_ERROR_THROTTLE(5.0, "bag_recorder: write to %s failed: %s", active_path_.c_str(), e.what());
      }
    }
  }

  const Options options_;
  BoundedQueue<Outgoing> queue_;
  rosbag::Bag bag_;
  std::string active_path_;
  ros::CallbackQueue callbacks_;
  std::unique_ptr<ros::AsyncSpinner> spinner_;
  std::vector<ros::Subscriber> subscribers_;
  std::vector<std::uint64_t> counts_;  ///< messages received per topic (index of Options::topics)
  std::thread writer_;
  std::atomic<bool> stopping_{ false };
  std::atomic<std::uint64_t> write_errors_{ 0 };
  std::uint64_t reported_dropped_ = 0;  ///< drop count at the previous diagnostic update
};

}  // namespace
}  // namespace saras_bringup

int main(int argc, char** argv)
{
  bool named = false;  // __name:= given: keep it; else an anonymous name, as rosbag record
  for (int i = 1; i < argc; ++i)
    named = named || std::string(argv[i]).rfind("__name:=", 0) == 0;
  ros::init(argc, argv, "bag_recorder", named ? 0 : ros::init_options::AnonymousName);
  saras_bringup::Options options;
  if (!saras_bringup::parseOptions(argc, argv, options))
    return 1;
  ros::NodeHandle nh;
  saras_bringup::BagRecorder recorder(options);
  try
  {
    recorder.start();
  }
  catch (const rosbag::BagException& e)
  {
    ROS_FATAL("bag_recorder: cannot open %s.active: %s", options.output.c_str(), e.what());
    return 1;
  }
  diagnostic_updater::Updater updater;
  updater.setHardwareID("recording");
  updater.add("bag", &recorder, &saras_bringup::BagRecorder::diagnose);
  const bool timed = options.duration > 0.0;
  const ros::WallTime end = ros::WallTime::now() + ros::WallDuration(timed ? options.duration : 0.0);
  while (ros::ok() && (!timed || ros::WallTime::now() < end))
  {
    updater.update();  // publishes at ~diagnostic_period (1 s)
    ros::WallDuration(0.05).sleep();
  }
  return recorder.stop() ? 0 : 1;
}
