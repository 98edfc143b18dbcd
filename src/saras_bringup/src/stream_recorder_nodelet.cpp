/**
 * @file stream_recorder_nodelet.cpp
 * @brief Nodelet saras_bringup/StreamRecorder: records topics published inside its own nodelet manager
 *        (the teleoperation's 1 kHz streams in /teleop/teleop_manager) into a bag of their own.
 *
 * Each message another process receives costs its publisher a serialisation, a TCP write and a wake-up
 * of roscpp's poll thread, and costs the receiver as much again: for the ~10 topics at 1 kHz of the
 * teleoperation manager this was most of the recording's CPU. Loaded into that manager, this nodelet
 * subscribes with the publishers' C++ types: roscpp hands each message over as a pointer, and the
 * callback runs at once in the publisher's thread (saras_common::InlineCallbackQueue), where it
 * serialises the message into a pooled buffer for the BagWriter (bag_writer.h), whose own thread
 * (named `stream_bag`) writes the bag. A topic of another type is recorded too (ShapeShifter, copied).
 *
 * Parameters (private, read once; a bad value refuses the nodelet with a message naming it):
 *   output       bag path (written as <output>.active, renamed when the nodelet is unloaded)
 *   topics       comma-separated absolute topic names
 *   buffer_mb    [MB] writer queue (default 256); chunk_kb [kB] bag chunk (4096); min_free_mb [MB] (64)
 * A topic is subscribed as soon as the ROS master knows its type (checked every 0.5 s; a warning names
 * the topics still unknown after 10 s). Health: /diagnostics, hardware_id `recording`, status
 * "<nodelet name>: bag" (BagWriter::diagnose). Unload (the loader's SIGINT) writes what is queued,
 * closes (indexes) and renames the bag.
 */
#include <map>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include <boost/make_shared.hpp>
#include <diagnostic_updater/diagnostic_updater.h>
#include <geometry_msgs/PoseStamped.h>
#include <geometry_msgs/TwistStamped.h>
#include <geometry_msgs/WrenchStamped.h>
#include <nodelet/nodelet.h>
#include <pluginlib/class_list_macros.hpp>
#include <ros/ros.h>
#include <rosbag/exceptions.h>
#include <saras_msgs/ComponentStatus.h>
#include <saras_msgs/HapticDeviceState.h>
#include <sensor_msgs/JointState.h>
#include <sensor_msgs/Joy.h>
#include <std_msgs/Float32.h>
#include <std_msgs/Float64.h>
#include <tf2_msgs/TFMessage.h>

#include "saras_bringup/bag_writer.h"
#include "saras_common/inline_callback_queue.h"
#include "saras_common/params.h"

namespace saras_bringup
{
namespace
{
constexpr std::uint32_t kQueue = 1000;  ///< roscpp subscription queue (inline: only concurrent publishers queue)

using SubscribeFn = ros::Subscriber (*)(ros::NodeHandle&, const std::string&, std::size_t, BagWriter&,
                                        ros::CallbackQueueInterface*);

/// Zero-copy subscription of a topic of type M: the callback serialises into the writer's buffer.
template <class M>
ros::Subscriber subscribeTyped(ros::NodeHandle& nh, const std::string& topic, std::size_t index, BagWriter& writer,
                               ros::CallbackQueueInterface* queue)
{
  writer.setType<M>(index);
  ros::SubscribeOptions ops;
  ops.template init<M>(topic, kQueue, [&writer, index](const boost::shared_ptr<M const>& m) {
    writer.pushTyped(index, *m, ros::Time::now());
  });
  ops.callback_queue = queue;
  ops.transport_hints = ros::TransportHints().tcpNoDelay();
  return nh.subscribe(ops);
}

/// Any other type: the serialised message (ShapeShifter), copied from the publisher's.
ros::Subscriber subscribeAny(ros::NodeHandle& nh, const std::string& topic, std::size_t index, BagWriter& writer,
                             ros::CallbackQueueInterface* queue)
{
  ros::SubscribeOptions ops;
  ops.topic = topic;
  ops.queue_size = kQueue;
  ops.md5sum = ros::message_traits::md5sum<topic_tools::ShapeShifter>();
  ops.datatype = ros::message_traits::datatype<topic_tools::ShapeShifter>();
  ops.helper = boost::make_shared<
      ros::SubscriptionCallbackHelperT<const ros::MessageEvent<topic_tools::ShapeShifter const>&>>(
      [&writer, index](const ros::MessageEvent<topic_tools::ShapeShifter const>& e) {
        writer.push(index, e.getConstMessage(), e.getConnectionHeaderPtr(), ros::Time::now());
      });
  ops.callback_queue = queue;
  ops.transport_hints = ros::TransportHints().tcpNoDelay();
  return nh.subscribe(ops);
}

/// The types recorded zero-copy (the teleoperation manager's published types).
const std::map<std::string, SubscribeFn>& typedSubscribers()
{
  static const std::map<std::string, SubscribeFn> table = {
    { "geometry_msgs/PoseStamped", &subscribeTyped<geometry_msgs::PoseStamped> },
    { "geometry_msgs/TwistStamped", &subscribeTyped<geometry_msgs::TwistStamped> },
    { "geometry_msgs/WrenchStamped", &subscribeTyped<geometry_msgs::WrenchStamped> },
    { "saras_msgs/ComponentStatus", &subscribeTyped<saras_msgs::ComponentStatus> },
    { "saras_msgs/HapticDeviceState", &subscribeTyped<saras_msgs::HapticDeviceState> },
    { "sensor_msgs/JointState", &subscribeTyped<sensor_msgs::JointState> },
    { "sensor_msgs/Joy", &subscribeTyped<sensor_msgs::Joy> },
    { "std_msgs/Float32", &subscribeTyped<std_msgs::Float32> },
    { "std_msgs/Float64", &subscribeTyped<std_msgs::Float64> },
    { "tf2_msgs/TFMessage", &subscribeTyped<tf2_msgs::TFMessage> },
  };
  return table;
}

/// "a, b,c" -> {a, b, c}; empty items dropped.
std::vector<std::string> splitList(const std::string& text)
{
  std::vector<std::string> out;
  std::stringstream in(text);
  std::string item;
  while (std::getline(in, item, ','))
  {
    const std::size_t b = item.find_first_not_of(" \t"), e = item.find_last_not_of(" \t");
    if (b != std::string::npos)
      out.push_back(item.substr(b, e - b + 1));
  }
  return out;
}

BagWriterOptions readOptions(const saras_common::Params& p, std::vector<std::string>& topics)
{
  using saras_common::atLeast;
  BagWriterOptions o;
  o.output = p.text("output", "", { saras_common::nonEmpty() });
  o.buffer_mb = static_cast<std::size_t>(p.integer("buffer_mb", 256, "MB", { atLeast(16) }));
  o.chunk_kb = static_cast<std::uint32_t>(p.integer("chunk_kb", 4096, "kB", { atLeast(64) }));
  o.min_free_mb = static_cast<std::size_t>(p.integer("min_free_mb", 64, "MB", { atLeast(1) }));
  o.thread_name = "stream_bag";
  const std::string list = p.text("topics", "", { saras_common::nonEmpty() });
  topics = splitList(list);
  for (const std::string& t : topics)
    if (t.empty() || t[0] != '/')
      p.fail("topics", "'" + list + "'", "", "comma-separated absolute topic names");
  if (topics.empty())
    p.fail("topics", "'" + list + "'", "", "at least one topic");
  return o;
}
}  // namespace

class StreamRecorder : public nodelet::Nodelet
{
public:
  ~StreamRecorder() override
  {
    discovery_.stop();
    subscribers_.clear();  // returns once no callback runs any more (roscpp's subscription callback lock)
    if (writer_)
      writer_->stop();
  }

private:
  void onInit() override
  {
    ros::NodeHandle& nh = getNodeHandle();
    std::vector<std::string> topics;
    BagWriterOptions o;
    try
    {
      o = readOptions(saras_common::Params(getPrivateNodeHandle()), topics);
      writer_.reset(new BagWriter(o, topics));
      writer_->start();
    }
    catch (const std::exception& e)  // a bad parameter, or the bag cannot be opened
    {
      NODELET_FATAL("%s", e.what());
      throw;
    }
    subscribers_.resize(topics.size());
    updater_.reset(new diagnostic_updater::Updater(nh, getPrivateNodeHandle(), getName()));
    updater_->setHardwareID("recording");
    updater_->add("bag", writer_.get(), &BagWriter::diagnose);
    started_ = ros::WallTime::now();
    discovery_ = nh.createWallTimer(ros::WallDuration(0.5), &StreamRecorder::onDiscovery, this);
    NODELET_INFO("recording %zu topics published in this manager to %s (on %s)", topics.size(), o.output.c_str(),
                 writer_->filesystem().c_str());
  }

  /// Subscribes the topics whose type the master knows; diagnostics.
  void onDiscovery(const ros::WallTimerEvent&)
  {
    updater_->update();
    if (pending_ == 0)
      return;
    ros::master::V_TopicInfo known;
    if (!ros::master::getTopics(known))
      return;
    std::map<std::string, std::string> types;
    for (const auto& t : known)
      types[t.name] = t.datatype;
    pending_ = 0;
    std::string missing;
    for (std::size_t i = 0; i < subscribers_.size(); ++i)
    {
      if (subscribers_[i])
        continue;
      const std::string& topic = writer_->topics()[i];
      const auto type = types.find(topic);
      if (type == types.end())
      {
        ++pending_;
        missing += " " + topic;
        continue;
      }
      const auto typed = typedSubscribers().find(type->second);
      const SubscribeFn fn = typed != typedSubscribers().end() ? typed->second : &subscribeAny;
      subscribers_[i] = fn(getNodeHandle(), topic, i, *writer_, &inline_);
    }
    if (pending_ > 0 && (ros::WallTime::now() - started_).toSec() > 10.0)
      NODELET_WARN_THROTTLE(10.0, "not advertised yet (will be recorded once they are):%s", missing.c_str());
  }

  std::unique_ptr<BagWriter> writer_;
  std::unique_ptr<diagnostic_updater::Updater> updater_;
  saras_common::InlineCallbackQueue inline_;  ///< callbacks run in the publisher's thread
  std::vector<ros::Subscriber> subscribers_;  ///< per topic (index of the writer's topics); empty until typed
  std::size_t pending_ = SIZE_MAX;            ///< topics not subscribed yet
  ros::WallTimer discovery_;
  ros::WallTime started_;
};

}  // namespace saras_bringup

PLUGINLIB_EXPORT_CLASS(saras_bringup::StreamRecorder, nodelet::Nodelet)
