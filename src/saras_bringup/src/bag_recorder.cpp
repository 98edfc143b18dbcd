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
#include <sys/statvfs.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <csignal>
#include <fstream>
#include <mutex>
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
#include "saras_common/inline_callback_queue.h"

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
  std::size_t min_free_mb = 64;   ///< [MB] stop writing below this much free space
  std::size_t split_mb = 0;       ///< [MB] 0 = one bag
  double split_duration = 0.0;    ///< [s] 0 = one bag
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
    else if (a == "--min-free")
    {
      if (!value(a, 1, 1048576))
        return false;
      o.min_free_mb = v;
    }
    else if (a == "--split-size")
    {
      if (!value(a, 1, 1048576))
        return false;
      o.split_mb = v;
    }
    else if ((a == "--duration" || a == "--split-duration") && has_value)
    {
      char* end = nullptr;
      double& d = a == "--duration" ? o.duration : o.split_duration;
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
  if (o.output.empty() || o.topics.empty())
  {
    std::fprintf(stderr, "usage: bag_recorder -O out.bag [--buffsize MB] [--chunksize KB] [--queue N] "
                         "[--tcpnodelay] [--duration S] [--min-free MB] [--split-size MB] [--split-duration S] "
                         "/topic ...\n");
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

/// Directory part of @p path ("." if none).
std::string dirOf(const std::string& path)
{
  const std::size_t slash = path.rfind('/');
  return slash == std::string::npos ? "." : (slash == 0 ? "/" : path.substr(0, slash));
}

/// "<mount point> (<device>)" of the filesystem holding @p path: longest matching /proc/mounts entry.
std::string filesystemOf(const std::string& path)
{
  char buf[4096];
  const std::string abs = realpath(dirOf(path).c_str(), buf) ? std::string(buf) : dirOf(path);
  std::ifstream mounts("/proc/mounts");
  std::string dev, mnt, rest, best = "?", best_dev = "?";
  while (mounts >> dev >> mnt && std::getline(mounts, rest))
  {
    const bool prefix = abs.compare(0, mnt.size(), mnt) == 0 &&
                        (abs.size() == mnt.size() || mnt == "/" || abs[mnt.size()] == '/');
    if (prefix && (best == "?" || mnt.size() > best.size()))
    {
      best = mnt;
      best_dev = dev;
    }
  }
  return best + " (" + best_dev + ")";
}

/// Space available to this user on the filesystem of @p path [MB] (-1 if unknown).
double freeMb(const std::string& path)
{
  struct statvfs st;
  if (statvfs(dirOf(path).c_str(), &st) != 0)
    return -1.0;
  return static_cast<double>(st.f_bavail) * static_cast<double>(st.f_frsize) / 1048576.0;
}

/// The writer thread takes the queued messages every kWriterPoll, or at once when kWakeBytes are queued
/// (a video frame or a burst): batches instead of one thread wake-up per 1 kHz message.
constexpr std::chrono::milliseconds kWriterPoll(20);
constexpr std::size_t kWakeBytes = 1024 * 1024;

class BagRecorder
{
public:
  explicit BagRecorder(const Options& o)
    : options_(o)
    , queue_(o.buffer_mb * 1024 * 1024, std::min<std::size_t>(kWakeBytes, o.buffer_mb * 1024 * 1024 / 8))
    , counts_(o.topics.size(), 0), lost_(o.topics.size(), 0)
  {
  }

  /// Opens the bag and subscribes; throws rosbag::BagException when the bag cannot be opened.
  void start()
  {
    openBag();
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
    ROS_INFO("bag_recorder: recording %zu topics to %s (queue %u per topic, buffer %zu MB, stops below %zu MB free "
             "on %s)",
             options_.topics.size(), options_.output.c_str(), options_.queue, options_.buffer_mb,
             options_.min_free_mb, filesystemOf(options_.output).c_str());
  }

  /// Unsubscribes, writes what is queued, closes and renames the bag. Returns false on a write error
  /// or a disk fault (the bag is then closed up to the fault).
  bool stop()
  {
    subscribers_.clear();  // returns once no callback runs any more (roscpp's subscription callback lock)
    stopping_ = true;
    queue_.close();
    writer_.join();
    const bool closed = disk_fault_ ? true : closeBag();
    std::uint64_t total = 0, lost = 0;
    for (std::size_t i = 0; i < counts_.size(); ++i)
    {
      total += counts_[i];
      lost += lost_[i];
      if (lost_[i] > 0)
        std::printf("bag_recorder: lost after the disk fault: %s %llu messages\n", options_.topics[i].c_str(),
                    static_cast<unsigned long long>(lost_[i]));
    }
    std::printf("bag_recorder: %s closed: %llu messages received, %llu dropped by the %zu MB buffer, peak %.1f MB "
                "queued, %llu write errors, %llu lost after a disk fault%s\n",
                options_.output.c_str(), static_cast<unsigned long long>(total),
                static_cast<unsigned long long>(queue_.dropped()), options_.buffer_mb, queue_.peakBytes() / 1048576.0,
                static_cast<unsigned long long>(write_errors_.load()), static_cast<unsigned long long>(lost),
                disk_fault_ ? (" (" + faultMessage() + ")").c_str() : "");
    std::fflush(stdout);
    return closed && write_errors_ == 0 && !disk_fault_;
  }

  /// Diagnostic task "bag": what was received, dropped, queued and not written since the start.
  void diagnose(diagnostic_updater::DiagnosticStatusWrapper& stat)
  {
    const std::uint64_t received = queue_.pushed();
    const std::uint64_t dropped = queue_.dropped();
    const std::uint64_t errors = write_errors_.load();
    if (disk_fault_)
      stat.summary(diagnostic_msgs::DiagnosticStatus::ERROR, faultMessage());
    else if (errors > 0)
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
    stat.add("messages lost (disk fault)", lost_total_.load());
    stat.add("write errors", errors);
    stat.addf("free on the bag's filesystem [MB]", "%.0f", free_mb_.load());
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
    ++counts_[index];  // only roscpp's single poll thread runs this while recording (InlineCallbackQueue)
    if (queue_.push(std::move(out), bytes) > 0)
      ROS_WARN_THROTTLE(5.0, "bag_recorder: buffer of %zu MB full, oldest messages dropped (%llu so far)",
                        options_.buffer_mb, static_cast<unsigned long long>(queue_.dropped()));
  }

  /// Path of the current bag: the output, or <output without .bag>_<part>.bag when splitting.
  std::string partPath() const
  {
    if (options_.split_mb == 0 && options_.split_duration <= 0.0)
      return options_.output;
    const std::string& o = options_.output;
    const bool ext = o.size() > 4 && o.compare(o.size() - 4, 4, ".bag") == 0;
    return (ext ? o.substr(0, o.size() - 4) : o) + "_" + std::to_string(part_) + ".bag";
  }

  void openBag()
  {
    path_ = partPath();
    active_path_ = path_ + ".active";
    bag_.open(active_path_, rosbag::bagmode::Write);
    bag_.setChunkThreshold(options_.chunk_kb * 1024);
    opened_ = std::chrono::steady_clock::now();
  }

  /// Closes (writes the index) and renames the current bag; false with an error message on failure.
  bool closeBag()
  {
    try
    {
      bag_.close();
    }
    catch (const rosbag::BagException& e)
    {
      ROS_ERROR("bag_recorder: closing %s: %s", active_path_.c_str(), e.what());
      return false;
    }
    if (std::rename(active_path_.c_str(), path_.c_str()) != 0)
    {
      ROS_ERROR("bag_recorder: cannot rename %s to %s", active_path_.c_str(), path_.c_str());
      return false;
    }
    return true;
  }

  /// Split: the current part is full (size or duration) -> close it and open the next.
  void maybeSplit()
  {
    const double age = std::chrono::duration<double>(std::chrono::steady_clock::now() - opened_).count();
    const bool by_size = options_.split_mb > 0 && bag_.getSize() >= options_.split_mb * 1048576ull;
    const bool by_time = options_.split_duration > 0.0 && age >= options_.split_duration;
    if (!(by_size || by_time))
      return;
    closeBag();
    ++part_;
    openBag();
    ROS_INFO("bag_recorder: split, now writing %s", path_.c_str());
  }

  std::string faultMessage()
  {
    std::lock_guard<std::mutex> lock(fault_mutex_);
    return fault_;
  }

  /// Disk full (or a failed write): stop writing, close the bag up to here, say where and why.
  void diskFault(const std::string& why)
  {
    const bool closed = closeBag();
    char buf[1024];
    std::snprintf(buf, sizeof buf,
                  "disk fault on %s: %s; stopped writing %s, %s; later messages are not recorded (counted)",
                  filesystemOf(options_.output).c_str(), why.c_str(), path_.c_str(),
                  closed ? "bag closed and indexed up to the fault" : "bag could NOT be closed (run rosbag reindex)");
    {
      std::lock_guard<std::mutex> lock(fault_mutex_);
      fault_ = buf;
    }
    disk_fault_ = true;
    ROS_ERROR("bag_recorder: %s", buf);
  }

  /// true if the bag's filesystem has less than --min-free MB (checked at most every 100 ms)
  bool diskLow(std::string& why)
  {
    const auto now = std::chrono::steady_clock::now();
    if (now - last_free_check_ < std::chrono::milliseconds(100))
      return false;
    last_free_check_ = now;
    const double mb = freeMb(active_path_);
    free_mb_ = mb;
    if (mb < 0.0 || mb >= static_cast<double>(options_.min_free_mb))
      return false;
    char buf[128];
    std::snprintf(buf, sizeof buf, "%.1f MB free < --min-free %zu MB", mb, options_.min_free_mb);
    why = buf;
    return true;
  }

  void writeLoop()
  {
    Outgoing out;
    std::string why;
    for (;;)
    {
      if (!queue_.pop(out, kWriterPoll))
      {
        if (stopping_ && queue_.size() == 0)
          return;
        continue;
      }
      const std::size_t index = static_cast<std::size_t>(out.topic - options_.topics.data());
      if (!disk_fault_ && diskLow(why))
        diskFault(why);
      if (disk_fault_)
      {
        ++lost_[index];
        ++lost_total_;
        continue;
      }
      try
      {
        bag_.write(*out.topic, out.time, *out.msg, out.header);
        maybeSplit();
      }
      catch (const rosbag::BagException& e)
      {
        ++write_errors_;
        ++lost_[index];
        ++lost_total_;
        diskFault(std::string("write failed: ") + e.what());
      }
    }
  }

  const Options options_;
  BoundedQueue<Outgoing> queue_;
  rosbag::Bag bag_;
  std::string path_, active_path_;
  unsigned part_ = 0;
  std::chrono::steady_clock::time_point opened_, last_free_check_;
  saras_common::InlineCallbackQueue callbacks_;  ///< onMessage runs in roscpp's poll thread: no hand-off
  std::vector<ros::Subscriber> subscribers_;
  std::vector<std::uint64_t> counts_;  ///< messages received per topic (index of Options::topics)
  std::vector<std::uint64_t> lost_;    ///< per topic, not written because of a disk fault (writer thread)
  std::thread writer_;
  std::atomic<bool> stopping_{ false }, disk_fault_{ false };
  std::atomic<std::uint64_t> write_errors_{ 0 }, lost_total_{ 0 };
  std::atomic<double> free_mb_{ -1.0 };
  std::mutex fault_mutex_;
  std::string fault_;  ///< the disk-fault message (fault_mutex_)
  std::uint64_t reported_dropped_ = 0;  ///< drop count at the previous diagnostic update
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
    ROS_FATAL("bag_recorder: cannot open %s.active: %s", options.output.c_str(), e.what());
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
