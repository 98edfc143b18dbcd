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
 * writer thread (--buffsize) is bounded and what it drops is counted and reported. The bag side
 * (queue, writer thread, split, disk-full stop) is BagWriter (bag_writer.h), shared with the
 * StreamRecorder nodelet that records a nodelet manager's own streams in-process.
 *
 * Usage: bag_recorder -O out.bag [--buffsize MB] [--chunksize KB] [--queue N] [--tcpnodelay]
 *                     [--duration S] [--min-free MB] [--split-size MB] [--split-duration S] /topic ...
 * The bag is written as out.bag.active and renamed when closed (SIGINT, SIGTERM, or after --duration s):
 * both signals leave an indexed bag. With --split-size / --split-duration the recording is a sequence
 * out_0.bag, out_1.bag, ... each closed (indexed) when it reaches that size [MB] or duration [s].
 * Disk full: when the filesystem of the bag has less than --min-free MB available (checked every
 * 100 ms; default 64, room for the index written at close) or a write fails, the recorder stops
 * writing, closes the bag (indexed, readable up to the fault), names the filesystem in an error and
 * on /diagnostics (ERROR), keeps running and counts per topic the messages it could no longer write.
 * Health: diagnostic_updater on /diagnostics (hardware_id `recording`), one status "<node>: bag" with
 * the messages received, dropped by the full buffer, queued and failed writes (WARN while messages are
 * dropped, ERROR after a write error).
 * ROS master lost (unreachable 2 s) or restarted: the bag is closed (safe stop) with an error.
 * Exit status: 0 closed cleanly, 1 bad arguments, the bag cannot be written, or a disk fault.
 */
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>
#include <vector>

#include <boost/make_shared.hpp>
#include <diagnostic_updater/diagnostic_updater.h>
#include <ros/callback_queue.h>
#include <ros/ros.h>
#include <rosbag/bag.h>
#include <rosbag/exceptions.h>
#include <topic_tools/shape_shifter.h>

#include "saras_bringup/bag_writer.h"
#include "saras_common/inline_callback_queue.h"

namespace saras_bringup
{
namespace
{
struct Options
{
  BagWriterOptions bag;          ///< output, buffer, chunk, min free space, split (bag_writer.h)
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
      o.bag.output = argv[++i];
    else if (a == "--buffsize")
    {
      if (!value(a, 1, 65536))
        return false;
      o.bag.buffer_mb = v;
    }
    else if (a == "--chunksize")
    {
      if (!value(a, 1, 1048576))
        return false;
      o.bag.chunk_kb = static_cast<std::uint32_t>(v);
    }
    else if (a == "--queue")
    {
      if (!value(a, 1, 1000000))
        return false;
      o.queue = static_cast<std::uint32_t>(v);
    }
    else if (a == "--min-free")
    {
      if (!value(a, 1, 1048576))
        return false;
      o.bag.min_free_mb = v;
    }
    else if (a == "--split-size")
    {
      if (!value(a, 1, 1048576))
        return false;
      o.bag.split_mb = v;
    }
    else if ((a == "--duration" || a == "--split-duration") && has_value)
    {
      char* end = nullptr;
      double& d = a == "--duration" ? o.duration : o.bag.split_duration;
      d = std::strtod(argv[++i], &end);
      if (*end != '\0' || !(d > 0.0 && d < 1e7))
      {
        std::fprintf(stderr, "bag_recorder: %s needs seconds > 0\n", a.c_str());
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
  if (o.bag.output.empty() || o.topics.empty())
  {
    std::fprintf(stderr, "usage: bag_recorder -O out.bag [--buffsize MB] [--chunksize KB] [--queue N] "
                         "[--tcpnodelay] [--duration S] [--min-free MB] [--split-size MB] [--split-duration S] "
                         "/topic ...\n");
    return false;
  }
  return true;
}

/**
 * The node: ShapeShifter subscriptions of every topic, each message handed to a BagWriter in roscpp's
 * poll thread (InlineCallbackQueue: no spinner wake-up per message).
 */
class BagRecorder
{
public:
  explicit BagRecorder(const Options& o) : options_(o), writer_(o.bag, o.topics) {}

  /// Opens the bag and subscribes; throws rosbag::BagException when the bag cannot be opened.
  void start()
  {
    writer_.start();
    ros::NodeHandle nh;
    ros::TransportHints hints;
    if (options_.tcp_nodelay)
      hints = hints.tcpNoDelay();
    for (std::size_t i = 0; i < options_.topics.size(); ++i)
    {
      ros::SubscribeOptions ops;
      ops.topic = options_.topics[i];
      ops.queue_size = options_.queue;
      ops.md5sum = ros::message_traits::md5sum<topic_tools::ShapeShifter>();
      ops.datatype = ros::message_traits::datatype<topic_tools::ShapeShifter>();
      ops.helper = boost::make_shared<
          ros::SubscriptionCallbackHelperT<const ros::MessageEvent<topic_tools::ShapeShifter const>&>>(
          [this, i](const ros::MessageEvent<topic_tools::ShapeShifter const>& e) {
            writer_.push(i, e.getConstMessage(), e.getConnectionHeaderPtr(), ros::Time::now());
          });
      ops.transport_hints = hints;
      ops.callback_queue = &callbacks_;
      subscribers_.push_back(nh.subscribe(ops));
    }
    ROS_INFO("bag_recorder: recording %zu topics to %s (queue %u per topic, buffer %zu MB, stops below %zu MB free "
             "on %s)",
             options_.topics.size(), options_.bag.output.c_str(), options_.queue, options_.bag.buffer_mb,
             options_.bag.min_free_mb, writer_.filesystem().c_str());
  }

  /// Unsubscribes, writes what is queued, closes and renames the bag. False on a write error or a
  /// disk fault (the bag is then closed up to the fault).
  bool stop()
  {
    subscribers_.clear();  // returns once no callback runs any more (roscpp's subscription callback lock)
    return writer_.stop();
  }

  void diagnose(diagnostic_updater::DiagnosticStatusWrapper& stat) { writer_.diagnose(stat); }

private:
  const Options options_;
  BagWriter writer_;
  saras_common::InlineCallbackQueue callbacks_;  ///< callbacks run in roscpp's poll thread: no hand-off
  std::vector<ros::Subscriber> subscribers_;
};

/**
 * ROS master loss: unreachable for 2 s, or restarted (other PID: this node is no longer registered,
 * nothing it records can be inspected or restarted). Polled every 0.5 s from the main loop.
 */
class MasterWatch
{
public:
  /// Empty while the master is fine, else the reason.
  std::string poll()
  {
    const ros::WallTime now = ros::WallTime::now();
    if (now < next_)
      return "";
    next_ = now + ros::WallDuration(0.5);
    XmlRpc::XmlRpcValue args, result, payload;
    args[0] = ros::this_node::getName();
    if (!ros::master::execute("getPid", args, result, payload, false))
    {
      if (down_since_.isZero())
        down_since_ = now;
      return (now - down_since_).toSec() >= 2.0 ? "ROS master unreachable for 2 s" : "";
    }
    down_since_ = ros::WallTime();
    const int pid = static_cast<int>(payload);
    if (pid_ != 0 && pid != pid_)
      return "ROS master restarted (pid " + std::to_string(pid_) + " -> " + std::to_string(pid) + ")";
    pid_ = pid;
    return "";
  }

private:
  ros::WallTime next_, down_since_;
  int pid_ = 0;
};

/// SIGTERM as SIGINT: ros::ok() turns false, main closes (indexes) the bag.
void onTerm(int)
{
  ros::requestShutdown();
}

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
  std::signal(SIGTERM, saras_bringup::onTerm);
  saras_bringup::BagRecorder recorder(options);
  try
  {
    recorder.start();
  }
  catch (const rosbag::BagException& e)
  {
    ROS_FATAL("bag_recorder: cannot open %s.active: %s", options.bag.output.c_str(), e.what());
    return 1;
  }
  diagnostic_updater::Updater updater;
  updater.setHardwareID("recording");
  updater.add("bag", &recorder, &saras_bringup::BagRecorder::diagnose);
  const bool timed = options.duration > 0.0;
  const ros::WallTime end = ros::WallTime::now() + ros::WallDuration(timed ? options.duration : 0.0);
  saras_bringup::MasterWatch master;
  while (ros::ok() && (!timed || ros::WallTime::now() < end))
  {
    updater.update();  // publishes at ~diagnostic_period (1 s)
    const std::string lost = master.poll();
    if (!lost.empty())
    {
      ROS_ERROR("bag_recorder: %s: closing the bag (safe stop; restart the platform to record again)", lost.c_str());
      break;
    }
    ros::WallDuration(0.05).sleep();
  }
  return recorder.stop() ? 0 : 1;
}
