/**
 * @file bag_writer.cpp
 * @brief BagWriter (bag_writer.h): the recorder's queue, writer thread, bag, split and disk-fault stop.
 */
#include "saras_bringup/bag_writer.h"

#include <pthread.h>
#include <sys/statvfs.h>

#include <algorithm>
#include <climits>
#include <cstdio>
#include <cstdlib>
#include <fstream>

#include <ros/console.h>
#include <rosbag/exceptions.h>

namespace saras_bringup
{
namespace
{
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
constexpr std::size_t kMaxFreeBuffers = 4096;  ///< serialisation buffers kept for reuse

std::size_t bytesOf(const Outgoing& out)
{
  return out.msg ? out.msg->size() : out.bytes.size();
}
}  // namespace

BagWriter::BagWriter(const BagWriterOptions& o, const std::vector<std::string>& topics)
  : options_(o)
  , topics_(topics)
  , shifters_(topics.size())
  , queue_(o.buffer_mb * 1024 * 1024, std::min<std::size_t>(kWakeBytes, o.buffer_mb * 1024 * 1024 / 8))
  , counts_(topics.size())
  , seqs_(topics.size())
  , lost_(topics.size(), 0)
{
}

BagWriter::~BagWriter()
{
  if (started_ && !stopping_)
    stop();
}

void BagWriter::start()
{
  openBag();
  started_ = true;
  writer_ = std::thread([this] {
    pthread_setname_np(pthread_self(), options_.thread_name.substr(0, 15).c_str());
    writeLoop();
  });
}

void BagWriter::push(std::size_t topic, const topic_tools::ShapeShifter::ConstPtr& msg,
                     const boost::shared_ptr<ros::M_string>& header, const ros::Time& time)
{
  Outgoing out;
  out.topic = topic;
  out.msg = msg;
  out.header = header;
  out.time = time;
  enqueue(std::move(out));
}

void BagWriter::enqueue(Outgoing&& out)
{
  if (stopping_)
    return;
  ++counts_[out.topic];
  const std::size_t bytes = bytesOf(out);
  if (queue_.push(std::move(out), bytes) > 0)
    ROS_WARN_THROTTLE(5.0, "bag writer %s: buffer of %zu MB full, oldest messages dropped (%llu so far)",
                      options_.output.c_str(), options_.buffer_mb, static_cast<unsigned long long>(queue_.dropped()));
}

std::vector<std::uint8_t> BagWriter::takeBuffer()
{
  std::lock_guard<std::mutex> lock(buffers_mutex_);
  if (buffers_.empty())
    return std::vector<std::uint8_t>();
  std::vector<std::uint8_t> b = std::move(buffers_.back());
  buffers_.pop_back();
  return b;
}

void BagWriter::giveBuffer(std::vector<std::uint8_t>&& buffer)
{
  std::lock_guard<std::mutex> lock(buffers_mutex_);
  if (buffers_.size() < kMaxFreeBuffers)
    buffers_.push_back(std::move(buffer));
}

bool BagWriter::stop()
{
  if (!started_ || stopping_.exchange(true))
    return write_errors_ == 0 && !disk_fault_;
  queue_.close();
  writer_.join();
  const bool closed = disk_fault_ ? true : closeBag();
  std::uint64_t total = 0;
  for (std::size_t i = 0; i < topics_.size(); ++i)
  {
    total += counts_[i];
    if (lost_[i] > 0)
      std::printf("bag writer: lost after the disk fault: %s %llu messages\n", topics_[i].c_str(),
                  static_cast<unsigned long long>(lost_[i]));
  }
  std::printf("bag writer: %s closed: %llu messages received, %llu dropped by the %zu MB buffer, peak %.1f MB "
              "queued, %llu write errors, %llu lost after a disk fault%s\n",
              options_.output.c_str(), static_cast<unsigned long long>(total),
              static_cast<unsigned long long>(queue_.dropped()), options_.buffer_mb, queue_.peakBytes() / 1048576.0,
              static_cast<unsigned long long>(write_errors_.load()), static_cast<unsigned long long>(lost_total_.load()),
              disk_fault_ ? (" (" + faultMessage() + ")").c_str() : "");
  std::fflush(stdout);
  return closed && write_errors_ == 0 && !disk_fault_;
}

void BagWriter::diagnose(diagnostic_updater::DiagnosticStatusWrapper& stat)
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
  stat.add("topics", topics_.size());
  stat.add("messages received", received);
  stat.add("messages dropped (buffer full)", dropped);
  stat.add("messages lost (disk fault)", lost_total_.load());
  stat.add("write errors", errors);
  stat.addf("free on the bag's filesystem [MB]", "%.0f", free_mb_.load());
  stat.addf("queued [MB]", "%.1f", queue_.bytes() / 1048576.0);
  stat.addf("peak queued [MB]", "%.1f", queue_.peakBytes() / 1048576.0);
  stat.add("buffer [MB]", options_.buffer_mb);
}

std::string BagWriter::filesystem() const
{
  return filesystemOf(options_.output);
}

std::string BagWriter::partPath() const
{
  if (options_.split_mb == 0 && options_.split_duration <= 0.0)
    return options_.output;
  const std::string& o = options_.output;
  const bool ext = o.size() > 4 && o.compare(o.size() - 4, 4, ".bag") == 0;
  return (ext ? o.substr(0, o.size() - 4) : o) + "_" + std::to_string(part_) + ".bag";
}

void BagWriter::openBag()
{
  path_ = partPath();
  active_path_ = path_ + ".active";
  bag_.open(active_path_, rosbag::bagmode::Write);
  bag_.setChunkThreshold(options_.chunk_kb * 1024);
  opened_ = std::chrono::steady_clock::now();
}

bool BagWriter::closeBag()
{
  try
  {
    bag_.close();
  }
  catch (const rosbag::BagException& e)
  {
    ROS_ERROR("bag writer: closing %s: %s", active_path_.c_str(), e.what());
    return false;
  }
  if (std::rename(active_path_.c_str(), path_.c_str()) != 0)
  {
    ROS_ERROR("bag writer: cannot rename %s to %s", active_path_.c_str(), path_.c_str());
    return false;
  }
  return true;
}

void BagWriter::maybeSplit()
{
  const double age = std::chrono::duration<double>(std::chrono::steady_clock::now() - opened_).count();
  const bool by_size = options_.split_mb > 0 && bag_.getSize() >= options_.split_mb * 1048576ull;
  const bool by_time = options_.split_duration > 0.0 && age >= options_.split_duration;
  if (!(by_size || by_time))
    return;
  closeBag();
  ++part_;
  openBag();
  ROS_INFO("bag writer: split, now writing %s", path_.c_str());
}

std::string BagWriter::faultMessage()
{
  std::lock_guard<std::mutex> lock(fault_mutex_);
  return fault_;
}

void BagWriter::diskFault(const std::string& why)
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
  ROS_ERROR("bag writer: %s", buf);
}

bool BagWriter::diskLow(std::string& why)
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

void BagWriter::write(Outgoing& out)
{
  const std::string& topic = topics_[out.topic];
  if (out.msg)
  {
    bag_.write(topic, out.time, *out.msg, out.header);
    return;
  }
  topic_tools::ShapeShifter& shifter = shifters_[out.topic];
  ros::serialization::IStream stream(out.bytes.data(), static_cast<std::uint32_t>(out.bytes.size()));
  shifter.read(stream);
  bag_.write(topic, out.time, shifter, out.header);
  giveBuffer(std::move(out.bytes));
}

void BagWriter::writeLoop()
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
    if (!disk_fault_ && diskLow(why))
      diskFault(why);
    if (disk_fault_)
    {
      ++lost_[out.topic];
      ++lost_total_;
      continue;
    }
    try
    {
      write(out);
      maybeSplit();
    }
    catch (const rosbag::BagException& e)
    {
      ++write_errors_;
      ++lost_[out.topic];
      ++lost_total_;
      diskFault(std::string("write failed: ") + e.what());
    }
  }
}

}  // namespace saras_bringup
