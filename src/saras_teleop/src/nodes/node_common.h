/**
 * @file node_common.h
 * @brief Shared helpers of the saras_teleop node adapters: validated parameters, message <-> Eigen
 *        conversions, the ComponentStatus heartbeat, the nodelet wrapper.
 */
#ifndef SARAS_TELEOP_NODE_COMMON_H
#define SARAS_TELEOP_NODE_COMMON_H

#include <atomic>
#include <cmath>
#include <initializer_list>
#include <memory>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include <geometry_msgs/Pose.h>
#include <geometry_msgs/Twist.h>
#include <geometry_msgs/Wrench.h>
#include <nodelet/nodelet.h>
#include <ros/callback_queue.h>
#include <ros/ros.h>
#include <saras_msgs/ComponentStatus.h>

#include "saras_common/message_pool.h"
#include "saras_common/params.h"
#include "saras_teleop/energy_tank.h"

namespace saras_teleop
{
namespace node
{
using saras_common::MessagePool;

/// Outgoing queue of the control-stream publishers, per subscriber connection [messages]: 0.1 s at
/// 1 kHz, 0.4 s at 250 Hz. It only fills while a TCP subscriber (e.g. the recorder) or this process's
/// writer thread is stalled; with ROS's 10 such a stall of 10 ms at 1 kHz already lost samples in the
/// bag. In-manager (zero-copy) subscribers never queue here.
constexpr uint32_t kStreamQueue = 100;

/// A 6-vector parameter: a list of 6 numbers, or one number used for every entry (each checked by @p rules).
inline Vector6d paramVector6(const saras_common::Params& p, const std::string& name, const Vector6d& def,
                             const std::string& unit, std::initializer_list<saras_common::NumberRule> rules = {})
{
  const std::vector<double> v = p.numbers(name, std::vector<double>(def.data(), def.data() + 6), unit, rules, 6);
  return Eigen::Map<const Vector6d>(v.data());
}

/// ~channels: the non-empty list of channel names (default left, right).
inline std::vector<std::string> paramChannels(const saras_common::Params& p)
{
  const std::vector<std::string> ch = p.texts("channels", { "left", "right" }, { saras_common::nonEmpty() });
  if (ch.empty())
    p.fail("channels", "[]", "", "a non-empty list of channel names");
  return ch;
}

inline Vector6d toVec(const geometry_msgs::Twist& t)
{
  Vector6d v;
  v << t.linear.x, t.linear.y, t.linear.z, t.angular.x, t.angular.y, t.angular.z;
  return v;
}

inline Vector6d toVec(const geometry_msgs::Wrench& w)
{
  Vector6d v;
  v << w.force.x, w.force.y, w.force.z, w.torque.x, w.torque.y, w.torque.z;
  return v;
}

inline void fromVec(const Vector6d& v, geometry_msgs::Twist& t)
{
  t.linear.x = v[0];
  t.linear.y = v[1];
  t.linear.z = v[2];
  t.angular.x = v[3];
  t.angular.y = v[4];
  t.angular.z = v[5];
}

inline void fromVec(const Vector6d& v, geometry_msgs::Wrench& w)
{
  w.force.x = v[0];
  w.force.y = v[1];
  w.force.z = v[2];
  w.torque.x = v[3];
  w.torque.y = v[4];
  w.torque.z = v[5];
}

/// Heartbeat on /saras/status: 1 Hz and immediately when the level changes.
class StatusReporter
{
public:
  StatusReporter(ros::NodeHandle& nh, const std::string& component) : component_(component)
  {
    pub_ = nh.advertise<saras_msgs::ComponentStatus>("/saras/status", 10);
    msg_.component = component;
  }
  /// Update the state; publishes if the level changed or a second has passed since the last heartbeat.
  void update(uint8_t level, const std::string& message, double input_age, uint64_t received, uint64_t rejected)
  {
    const ros::Time now = ros::Time::now();
    const bool changed = level != msg_.level || !published_;
    msg_.level = level;
    if (changed || message != msg_.message)
      msg_.message = message;
    msg_.input_age = input_age;
    msg_.received = received;
    msg_.rejected = rejected;
    if (changed || (now - last_).toSec() >= 1.0)
    {
      msg_.header.stamp = now;
      pub_.publish(msg_);
      last_ = now;
      published_ = true;
    }
  }

private:
  std::string component_;
  ros::Publisher pub_;
  saras_msgs::ComponentStatus msg_;
  ros::Time last_;
  bool published_ = false;
};

/**
 * A callback queue served by one thread of its own. A nodelet's own queue is served by the nodelet
 * manager in two steps (nodelet::detail::CallbackQueueManager: the queue notifies the manager
 * thread, which hands it to a worker thread), i.e. two thread wake-ups per intra-process hop; a
 * subscription on this queue wakes exactly one thread, the one that runs the callback. The thread
 * inherits the scheduling policy of its creator (the manager's, e.g. SCHED_FIFO under chrt).
 * Callbacks of one queue never run concurrently.
 */
class DedicatedCallbackThread
{
public:
  DedicatedCallbackThread() = default;
  DedicatedCallbackThread(const DedicatedCallbackThread&) = delete;
  DedicatedCallbackThread& operator=(const DedicatedCallbackThread&) = delete;
  ~DedicatedCallbackThread() { stop(); }

  ros::CallbackQueue* queue() { return &queue_; }

  /// Start serving the queue (idempotent).
  void start()
  {
    if (thread_.joinable())
      return;
    running_ = true;
    thread_ = std::thread([this] {
      while (running_ && ros::ok())
        queue_.callAvailable(ros::WallDuration(kWait));
    });
  }

  /// Stop and join the thread (callbacks already queued are dropped by the queue's destructor).
  void stop()
  {
    running_ = false;
    if (thread_.joinable())
      thread_.join();
  }

private:
  static constexpr double kWait = 0.1;  ///< [s] longest wait for a callback before re-checking running_
  ros::CallbackQueue queue_;
  std::atomic<bool> running_{ false };
  std::thread thread_;
};

/**
 * Nodelet wrapper of a node class `Node(ros::NodeHandle& nh, ros::NodeHandle& pnh, const std::string& name)`.
 * The node object lives as long as the nodelet; its callbacks (subscriptions and timers) never run
 * concurrently, so the node class needs no locking. Which thread runs them is the parameter
 * `callback_thread` (string, read once; the private `~callback_thread`, else the nearest one up the
 * namespace tree, NodeHandle::searchParam, so a launch file sets it once for a group of nodelets):
 *   - `manager` (default): the nodelet's single-threaded queue, served by the manager's worker threads
 *     (nodelet::detail::CallbackQueueManager: two thread wake-ups per intra-process hop);
 *   - `own`: a DedicatedCallbackThread of this nodelet (one wake-up per hop);
 *   - `shared`: the process's global callback queue (ros::getGlobalCallbackQueue()), which the nodelet
 *     manager's main thread serves with ros::spin(): every nodelet with `shared` runs on that one thread,
 *     so a message published from one of their callbacks is handled by the next, right after the
 *     current callback returns, without any thread wake-up; the hops of a chain of such nodelets cost
 *     no context switch. (The manager's load/unload services share that thread.)
 * A std::exception
 * from the constructor (bad parameter) is logged with ROS_FATAL naming the nodelet and rethrown:
 * the manager refuses the nodelet and the loader (`nodelet load` or the standalone executable)
 * exits non-zero.
 */
template <class Node>
class NodeletAdapter : public nodelet::Nodelet
{
public:
  ~NodeletAdapter() override
  {
    thread_.stop();  // no callback runs while the node is destroyed (it unsubscribes)
    node_.reset();
  }

private:
  void onInit() override
  {
    try
    {
      const std::string mode = callbackThreadParam();
      ros::NodeHandle nh = getNodeHandle(), pnh = getPrivateNodeHandle();
      ros::CallbackQueue* queue = mode == "own"    ? thread_.queue() :
                                  mode == "shared" ? ros::getGlobalCallbackQueue() :
                                                     nullptr;
      if (queue != nullptr)
      {
        nh.setCallbackQueue(queue);
        pnh.setCallbackQueue(queue);
      }
      node_.reset(new Node(nh, pnh, getName().substr(getName().empty() ? 0 : 1)));
      if (mode == "own")
        thread_.start();
    }
    catch (const std::exception& e)
    {
      ROS_FATAL("%s: %s", getName().c_str(), e.what());
      throw;
    }
  }
  /// The `callback_thread` parameter (see the class comment), validated.
  std::string callbackThreadParam()
  {
    ros::NodeHandle& pnh = getPrivateNodeHandle();
    std::string key, mode = "manager";
    if (!pnh.searchParam("callback_thread", key))
      return mode;
    if (!pnh.getParam(key, mode) || (mode != "manager" && mode != "own" && mode != "shared"))
      throw std::invalid_argument("parameter '" + key + "' must be one of the strings manager, own, shared");
    return mode;
  }

  DedicatedCallbackThread thread_;  // declared before node_: destroyed after it
  std::unique_ptr<Node> node_;
};

}  // namespace node
}  // namespace saras_teleop

#endif  // SARAS_TELEOP_NODE_COMMON_H
