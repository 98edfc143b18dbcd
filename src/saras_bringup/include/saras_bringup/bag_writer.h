/**
 * @file bag_writer.h
 * @brief The recorder's bag side, shared by the `bag_recorder` node and the `StreamRecorder` nodelet:
 *        a bounded hand-off queue, a writer thread, the bag (split, disk-full stop, close and rename)
 *        and its health for /diagnostics. No subscriptions: the adapters push what they receive.
 *
 * Two kinds of message are pushed:
 *   - received over TCP (topic_tools::ShapeShifter, the node): the message is queued as is;
 *   - typed, from a publisher in the same process (the nodelet): serialised at once into a buffer
 *     taken from a free list (no allocation once the list is warm), so that the publisher's pooled
 *     message is not held for the writer's batching period (its pool would then allocate). roscpp
 *     numbers header.seq only in what it serialises for TCP subscribers; here each typed topic's
 *     messages are numbered 0, 1, ... at the push, so a message the writer drops leaves a gap.
 * The bag is written as <output>.active and renamed to <output> when closed. With split_mb /
 * split_duration the recording is a sequence <output without .bag>_<N>.bag, each closed when it
 * reaches that size [MB] or age [s]. Disk full: when the bag's filesystem has less than min_free_mb
 * available (checked every 100 ms) or a write fails, the writer stops writing, closes the bag (indexed,
 * readable up to the fault), reports the filesystem (ERROR) and counts per topic what it could no
 * longer write.
 */
#ifndef SARAS_BRINGUP_BAG_WRITER_H
#define SARAS_BRINGUP_BAG_WRITER_H

#include <atomic>
#include <chrono>
#include <cstdint>
#include <cstring>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include <diagnostic_updater/DiagnosticStatusWrapper.h>
#include <ros/message_traits.h>
#include <ros/serialization.h>
#include <ros/time.h>
#include <rosbag/bag.h>
#include <topic_tools/shape_shifter.h>

#include "saras_bringup/bounded_queue.h"

namespace saras_bringup
{
struct BagWriterOptions
{
  std::string output;             ///< bag path (.bag)
  std::size_t buffer_mb = 1024;   ///< [MB] writer queue budget
  std::uint32_t chunk_kb = 768;   ///< [kB] bag chunk size
  std::size_t min_free_mb = 64;   ///< [MB] stop writing below this much free space
  std::size_t split_mb = 0;       ///< [MB] 0 = one bag
  double split_duration = 0.0;    ///< [s] 0 = one bag
  std::string thread_name = "bag_writer";  ///< name of the writer thread (/proc/PID/task/TID/comm, <= 15 chars)
};

/// One received message on its way to the bag.
struct Outgoing
{
  std::size_t topic = 0;                           ///< index in the writer's topics
  topic_tools::ShapeShifter::ConstPtr msg;         ///< received over TCP, or null
  std::vector<std::uint8_t> bytes;                 ///< serialised typed message (msg null)
  boost::shared_ptr<ros::M_string> header;         ///< connection header (null: from the topic's type)
  ros::Time time;                                  ///< receive time
};

class BagWriter
{
public:
  /// @param topics the recorded topics (absolute names); pushes refer to them by index
  BagWriter(const BagWriterOptions& options, const std::vector<std::string>& topics);
  ~BagWriter();

  /// Opens the bag and starts the writer thread; throws rosbag::BagException if it cannot be opened.
  void start();

  /// Queues a message received over TCP (any thread, never blocks).
  void push(std::size_t topic, const topic_tools::ShapeShifter::ConstPtr& msg,
            const boost::shared_ptr<ros::M_string>& header, const ros::Time& time);

  /// Declares the type of a topic whose messages are pushed typed (before its first pushTyped).
  template <class M>
  void setType(std::size_t topic)
  {
    shifters_.at(topic).morph(ros::message_traits::md5sum<M>(), ros::message_traits::datatype<M>(),
                              ros::message_traits::definition<M>(), "0");
  }

  /// Serialises a typed message into a pooled buffer and queues it (any thread, never blocks).
  template <class M>
  void pushTyped(std::size_t topic, const M& msg, const ros::Time& time)
  {
    Outgoing out;
    out.topic = topic;
    out.time = time;
    out.bytes = takeBuffer();
    out.bytes.resize(ros::serialization::serializationLength(msg));
    ros::serialization::OStream stream(out.bytes.data(), static_cast<std::uint32_t>(out.bytes.size()));
    ros::serialization::serialize(stream, msg);
    if (ros::message_traits::HasHeader<M>::value)  // header.seq first: number the topic's messages as
    {                                              // roscpp does for a TCP subscriber (gaps = losses)
      const std::uint32_t seq = seqs_[topic]++;
      std::memcpy(out.bytes.data(), &seq, sizeof seq);  // little-endian, as ROS serialisation
    }
    enqueue(std::move(out));
  }

  /// Writes what is queued, closes and renames the bag, joins the writer. False on a write error or
  /// a disk fault (the bag is then closed up to the fault). Pushes after stop() are ignored.
  bool stop();

  /// Diagnostic task "bag": what was received, dropped, queued and not written since the start.
  void diagnose(diagnostic_updater::DiagnosticStatusWrapper& stat);

  /// "<mount point> (<device>)" of the filesystem holding the bag.
  std::string filesystem() const;
  const std::vector<std::string>& topics() const { return topics_; }

private:
  void enqueue(Outgoing&& out);
  std::vector<std::uint8_t> takeBuffer();
  void giveBuffer(std::vector<std::uint8_t>&& buffer);
  std::string partPath() const;
  void openBag();
  bool closeBag();
  void maybeSplit();
  std::string faultMessage();
  void diskFault(const std::string& why);
  bool diskLow(std::string& why);
  void write(Outgoing& out);
  void writeLoop();

  const BagWriterOptions options_;
  const std::vector<std::string> topics_;
  std::vector<topic_tools::ShapeShifter> shifters_;  ///< per typed topic, morphed once (setType): the bag's
                                                     ///< input for its serialised messages (writer thread)
  BoundedQueue<Outgoing> queue_;
  std::mutex buffers_mutex_;
  std::vector<std::vector<std::uint8_t>> buffers_;  ///< free list of serialisation buffers
  rosbag::Bag bag_;
  std::string path_, active_path_;
  unsigned part_ = 0;
  std::chrono::steady_clock::time_point opened_, last_free_check_;
  std::vector<std::atomic<std::uint64_t>> counts_;  ///< received per topic
  std::vector<std::atomic<std::uint32_t>> seqs_;    ///< next header.seq per typed topic
  std::vector<std::uint64_t> lost_;                 ///< per topic, not written because of a disk fault (writer)
  std::thread writer_;
  std::atomic<bool> started_{ false }, stopping_{ false }, disk_fault_{ false };
  std::atomic<std::uint64_t> write_errors_{ 0 }, lost_total_{ 0 };
  std::atomic<double> free_mb_{ -1.0 };
  std::mutex fault_mutex_;
  std::string fault_;                   ///< the disk-fault message (fault_mutex_)
  std::uint64_t reported_dropped_ = 0;  ///< drop count at the previous diagnostic update
};

}  // namespace saras_bringup

#endif  // SARAS_BRINGUP_BAG_WRITER_H
