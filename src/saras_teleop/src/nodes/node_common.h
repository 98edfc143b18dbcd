/**
 * @file node_common.h
 * @brief Shared helpers of the saras_teleop node adapters: parameter shapes, message <-> Eigen
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
 * Nodelet wrapper of a node class `Node(ros::NodeHandle& nh, ros::NodeHandle& pnh, const std::string& name)`.
 * The node object lives as long as the nodelet; its callbacks (subscriptions and timers) never run
 * concurrently, so the node class needs no locking. Which thread runs them is the parameter
 * `callback_thread` (string, read once; the private `~callback_thread`, else the nearest one up the
 * namespace tree, NodeHandle::searchParam, so a launch file sets it once for a group of nodelets):
 *   - `shared` (default): the process's global callback queue (ros::getGlobalCallbackQueue()), which
 *     the nodelet manager's main thread (and `nodelet standalone`) serves with ros::spin(): every
 *     nodelet with `shared` runs on that one thread, so a message published from one of their
 *     callbacks is handled by the next right after the current callback returns, without a thread
 *     wake-up; the hops of a chain of such nodelets cost no context switch. (The manager's load/unload
 *     services share that thread.)
 *   - `manager`: the nodelet's single-threaded queue, served by the manager's worker threads
 *     (nodelet::detail::CallbackQueueManager: two thread wake-ups per intra-process hop).
 * A std::exception from the constructor (bad parameter) is logged with ROS_FATAL naming the nodelet
 * and rethrown: the manager refuses the nodelet and `nodelet load` / `nodelet standalone` exit non-zero.
 */
template <class Node>
class NodeletAdapter : public nodelet::Nodelet
{
public:
  ~NodeletAdapter() override { node_.reset(); }

private:
  void onInit() override
  {
    try
    {
      ros::NodeHandle nh = getNodeHandle(), pnh = getPrivateNodeHandle();
      if (callbackThreadParam() == "shared")
      {
        nh.setCallbackQueue(ros::getGlobalCallbackQueue());
        pnh.setCallbackQueue(ros::getGlobalCallbackQueue());
      }
      node_.reset(new Node(nh, pnh, getName().substr(getName().empty() ? 0 : 1)));
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
    std::string key;
    if (!getPrivateNodeHandle().searchParam("callback_thread", key))
      return "shared";
    return saras_common::Params(ros::NodeHandle()).text(key, "shared", { saras_common::oneOf({ "shared", "manager" }) });
  }

  std::unique_ptr<Node> node_;
};

}  // namespace node
}  // namespace saras_teleop

#endif  // SARAS_TELEOP_NODE_COMMON_H
