/**
 * @file jaw_channel.h
 * @brief Node side of the Simball clip -> instrument jaw mapping (ClipMapper), part of the
 *        velocity_integrator node of one channel (the jaw holds exactly when the arm's set-point does).
 *
 * Subscribes jaw_state (sensor_msgs/JointState, = /mesa_<side>/joint_states: the measured jaw
 * `~jaw_joint` starts the command), takes the clip angle from the device_state messages the
 * integrator already receives (onDevice), and publishes jaw_target (sensor_msgs/JointState, one
 * joint `~jaw_joint`, position [rad], stamp = the console sample it follows) at `~jaw_rate` on
 * its own timer once the measured jaw is known, the held command included (stamped now). Parameters (units):
 * `~clip_teleop` (false: nothing is subscribed or published), `~jaw_scale` [rad/rad],
 * `~jaw_offset`, `~jaw_min`, `~jaw_max` [rad], `~max_jaw_velocity` [rad/s], `~jaw_input_timeout`
 * [s], `~jaw_rate` [Hz], `~jaw_joint`.
 */
#ifndef SARAS_TELEOP_JAW_CHANNEL_H
#define SARAS_TELEOP_JAW_CHANNEL_H

#include <cmath>
#include <cstdint>
#include <functional>
#include <string>

#include <saras_msgs/HapticDeviceState.h>
#include <sensor_msgs/JointState.h>

#include "node_common.h"
#include "saras_teleop/clip_mapper.h"

namespace saras_teleop
{
namespace node
{
class JawChannel
{
public:
  /// @param hold true while the jaw must not follow the clip (the arm holds)
  /// @param max_step [s] longest interval integrated in one step (the integrator's ~max_step)
  JawChannel(ros::NodeHandle& nh, const ros::NodeHandle& pnh, double max_step, std::function<bool()> hold)
    : clip_(readParams(pnh, max_step)), hold_(std::move(hold))
  {
    const saras_common::Params prm(pnh);
    enabled_ = prm.flag("clip_teleop", true);
    joint_ = prm.text("jaw_joint", "mesa_left/jaw", { saras_common::nonEmpty() });
    const double rate = prm.number("jaw_rate", 100.0, "Hz", { saras_common::positive() });
    if (!enabled_)
      return;
    msg_.name.assign(1, joint_);
    msg_.position.assign(1, 0.0);
    pub_ = nh.advertise<sensor_msgs::JointState>("jaw_target", kStreamQueue);
    state_sub_ = nh.subscribe("jaw_state", 1, &JawChannel::onJawState, this, ros::TransportHints().tcpNoDelay());
    timer_ = nh.createSteadyTimer(ros::WallDuration(1.0 / rate), &JawChannel::onTimer, this);
  }

  /// Clip angle of a (non-stale) console sample.
  void onDevice(const saras_msgs::HapticDeviceState& m)
  {
    if (!enabled_)
      return;
    if (!clip_.setClip(m.clip_angle, ros::WallTime::now().toSec()))
    {
      ROS_ERROR_THROTTLE(1.0, "velocity_integrator: non-finite clip angle rejected, jaw holds (%zu so far)",
                         clip_.rejected());
      return;
    }
    stamp_ = m.header.stamp;
  }

  void report(diagnostic_updater::DiagnosticStatusWrapper& s)
  {
    if (!enabled_)
    {
      s.add("jaw", "clip_teleop off");
      return;
    }
    s.add("jaw", !clip_.started() ? "no measured jaw" : clip_.holding() ? "holding" : "following the clip");
    s.add("jaw command [rad]", clip_.command());
    s.add("jaw_target rate [Hz]", published_.rate());
    s.add("clip rejected", clip_.rejected());
  }

private:
  static ClipParams readParams(const ros::NodeHandle& pnh, double max_step)
  {
    const saras_common::Params prm(pnh);
    ClipParams p;
    p.scale = prm.number("jaw_scale", p.scale, "rad/rad", { saras_common::positive() });
    p.offset = prm.number("jaw_offset", p.offset, "rad");
    p.jaw_min = prm.number("jaw_min", p.jaw_min, "rad");
    p.jaw_max = prm.number("jaw_max", p.jaw_max, "rad");
    p.max_velocity = prm.number("max_jaw_velocity", p.max_velocity, "rad/s", { saras_common::positive() });
    p.input_timeout = prm.number("jaw_input_timeout", p.input_timeout, "s", { saras_common::positive() });
    p.max_step = max_step;
    p.validate();  // jaw_min < jaw_max (throws naming the parameter)
    return p;
  }

  void onJawState(const sensor_msgs::JointState::ConstPtr& m)
  {
    if (clip_.started())
    {
      state_sub_.shutdown();  // only the start value is needed
      return;
    }
    for (std::size_t i = 0; i < m->name.size() && i < m->position.size(); ++i)
      if (m->name[i] == joint_ && clip_.setMeasured(m->position[i]))
        ROS_INFO("velocity_integrator: measured jaw %.3f rad; the jaw follows the Simball clip", m->position[i]);
  }

  void onTimer(const ros::SteadyTimerEvent&)
  {
    const double cmd = clip_.step(ros::WallTime::now().toSec(), hold_());
    if (!clip_.started())
      return;
    // following: the stamp of the console sample (latency); holding: now (a fresh, unchanged command)
    msg_.header.stamp = clip_.holding() || stamp_.isZero() ? ros::Time::now() : stamp_;
    msg_.position[0] = cmd;
    pub_.publish(msg_);
    published_.count();
  }

  ClipMapper clip_;
  std::function<bool()> hold_;
  bool enabled_ = true;
  std::string joint_;
  sensor_msgs::JointState msg_;
  ros::Time stamp_;
  RateMeter published_;
  ros::Publisher pub_;
  ros::Subscriber state_sub_;
  ros::SteadyTimer timer_;
};

}  // namespace node
}  // namespace saras_teleop

#endif  // SARAS_TELEOP_JAW_CHANNEL_H
