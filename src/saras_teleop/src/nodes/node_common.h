/**
 * @file node_common.h
 * @brief Shared helpers of the saras_teleop node adapters: parameter shapes, message <-> Eigen
 *        conversions, health on /diagnostics, the nodelet wrapper.
 */
#ifndef SARAS_TELEOP_NODE_COMMON_H
#define SARAS_TELEOP_NODE_COMMON_H

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <functional>
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
#include <diagnostic_updater/diagnostic_updater.h>

#include "saras_common/message_pool.h"
#include "saras_common/params.h"
#include "saras_teleop/energy_tank.h"

namespace saras_teleop
{
namespace node
{
using saras_common::MessagePool;

/// Outgoing queue of the control-stream publishers, per subscriber connection [messages]: 1 s at
/// 1 kHz. It only fills while a TCP subscriber (e.g. the recorder) is stalled; with 100 a recorder
/// descheduled for 100 ms on a saturated 2-core host lost a burst of samples in the bag (make demo at
/// 1 kHz: 61-100 per stream). The serialised messages are ~100-200 bytes. Subscribers that want only
/// the newest message (the arm driver's set-point) drop the older ones on their side. In-manager
/// (zero-copy) subscribers never queue here.
constexpr uint32_t kStreamQueue = 1000;

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

/**
 * Health of a teleop node on /diagnostics (diagnostic_updater, hardware_id `teleoperation`): one status
 * "<node name>: <task>", filled by @p fill every ~diagnostic_period (default 1 s). The update runs on
 * a timer of the node's own NodeHandle, i.e. on the node's serialised callback queue: it never runs
 * concurrently with the node's callbacks, so @p fill reads their state and counters without locks,
 * and the control callbacks only increment counters (no allocation, no status work at control rate).
 */
class Health
{
public:
  using Fill = std::function<void(diagnostic_updater::DiagnosticStatusWrapper&)>;

  /// @param name node name without the leading '/' (the status name starts with it)
  Health(ros::NodeHandle& nh, ros::NodeHandle& pnh, const std::string& name, const std::string& task, const Fill& fill)
    : updater_(nh, pnh, "/" + name)
  {
    updater_.setHardwareID("teleoperation");
    updater_.add(task, fill);
    timer_ = nh.createSteadyTimer(ros::WallDuration(updater_.getPeriod()), &Health::onTimer, this);
  }

private:
  void onTimer(const ros::SteadyTimerEvent&) { updater_.force_update(); }

  diagnostic_updater::Updater updater_;
  ros::SteadyTimer timer_;
};

/**
 * The ~rate timer of an event-driven node: its outputs follow its inputs, and the timer only fills
 * in (republishes, steps, supervises) when an input stream stops. tick(now) does the node's timer
 * work and returns true when it found a gap (an input older than 1.5 periods, or the node not
 * started yet). While the inputs arrive densely (kDenseTicks ticks without two gaps in a row) the
 * timer runs at the slower watchdog period instead of ~rate; a watchdog tick that finds a gap does
 * that tick's fill-in, and the second consecutive one returns the timer to ~rate (a single late input
 * on a loaded host does not). A stopped stream is thus filled in at ~rate after at most two watchdog
 * periods, and every timeout (all >= 50 ms) is then checked at ~rate as before; in steady operation
 * the node costs no timer callback per control period (roscpp's timer thread wakes up after each).
 * A watchdog period <= the period keeps the timer at ~rate (no pacing). Runs on the node's queue.
 */
class PacedTimer
{
public:
  using Tick = std::function<bool(const ros::Time& now)>;
  static constexpr int kDenseTicks = 20;  ///< ticks without a gap before the watchdog period

  /// @param period [s] the node's control period (1/~rate); @param watchdog_period [s] (1/~watchdog_rate)
  PacedTimer(ros::NodeHandle& nh, double period, double watchdog_period, const Tick& tick)
    : period_(period), watchdog_(watchdog_period), tick_(tick)
  {
    timer_ = nh.createSteadyTimer(ros::WallDuration(period_), &PacedTimer::onTimer, this);
  }
  /// true while the inputs are dense and the timer runs at the watchdog period
  bool paced() const { return paced_; }
  /// /diagnostics text: the timer's current rate and why
  std::string describe() const
  {
    char text[96];
    std::snprintf(text, sizeof text, paced_ ? "%.0f Hz watchdog (inputs dense)" : "%.0f Hz", 1.0 / (paced_ ? watchdog_ : period_));
    return text;
  }

private:
  void onTimer(const ros::SteadyTimerEvent&)
  {
    if (tick_(ros::Time::now()))
    {
      // a gap at a single tick is an input late on a loaded host (the tick filled it in); a gap at
      // two consecutive ticks is a stopped stream: back to ~rate, dense again after kDenseTicks
      if (++gaps_ >= 2)
      {
        dense_ = 0;
        if (paced_)
        {
          paced_ = false;
          timer_.setPeriod(ros::WallDuration(period_));
        }
      }
      return;
    }
    gaps_ = 0;
    if (!paced_ && watchdog_ > period_ && ++dense_ >= kDenseTicks)
    {
      paced_ = true;
      timer_.setPeriod(ros::WallDuration(watchdog_));
    }
  }

  double period_, watchdog_;
  Tick tick_;
  ros::SteadyTimer timer_;
  int dense_ = 0;
  int gaps_ = 0;  ///< consecutive paced ticks that found a gap
  bool paced_ = false;
};

/// Messages per second between two diagnostics updates: count() on the control path, rate() in the update.
class RateMeter
{
public:
  void count() { ++n_; }
  /// [Hz] since the previous call (0 on the first)
  double rate()
  {
    const ros::WallTime now = ros::WallTime::now();
    const double dt = last_.isZero() ? 0.0 : (now - last_).toSec();
    const double r = dt > 0.0 ? static_cast<double>(n_ - n_last_) / dt : 0.0;
    last_ = now;
    n_last_ = n_;
    return r;
  }

private:
  std::uint64_t n_ = 0, n_last_ = 0;
  ros::WallTime last_;
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

/**
 * Restart detection for state that must not come back better than it was (tank energy, a
 * commanding set-point): true if this node already ran under the current ROS master (its private
 * parameter `~run_marker` exists, set here on every start; the master's parameter server outlives
 * a respawned node or manager).
 */
inline bool restartedUnderThisMaster(const ros::NodeHandle& pnh)
{
  const bool before = pnh.hasParam("run_marker");
  pnh.setParam("run_marker", true);
  return before;
}

}  // namespace node
}  // namespace saras_teleop

#endif  // SARAS_TELEOP_NODE_COMMON_H
