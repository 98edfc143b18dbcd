/**
 * velocity_integrator: slave pose set-point from the implemented slave twist (one per channel).
 * Nodelet saras_teleop/VelocityIntegrator; executable velocity_integrator.
 *
 * Waits for the slave start pose on start_pose (PoseStamped, the arm's MEASURED pose; error after
 * ~start_timeout, keeps waiting without publishing) and keeps reading it (re-anchoring, lead limit,
 * VelocityIntegrator), then integrates tank_twist (TwistStamped, slave base frame) with
 * KDL::addDelta over the interval between the header stamps of consecutive twists, i.e. the master
 * sample times propagated through the chain: sum v_k (t_k - t_{k-1}) reproduces the scaled master
 * displacement regardless of transport jitter (integrating over arrival times loses or adds motion
 * whenever messages bunch up). A stamp that does not advance, or advances by more than ~max_step,
 * is not integrated (restart). The set-point is published at once on target_pose (PoseStamped in
 * ~frame_id, stamp of the twist) and every ~tf_decimation-th time as TF ~frame_id -> ~setpoint_frame.
 * A ~rate timer republishes the held set-point if twists stop and supervises the inputs below;
 * while twists flow it runs at ~watchdog_rate instead (PacedTimer, node_common.h). Holds (set-point frozen) when link_status (ComponentStatus) is STALE or
 * the last twist is older than ~input_timeout. Velocity and workspace limits from parameters:
 * max_linear_velocity [m/s], max_angular_velocity [rad/s], workspace_min/max [m] (3 values each).
 *
 * Faults (FAULT: the set-point freezes, <= max_lead from the measured pose; cleared only by the
 * operator's clutch on device_state (HapticDeviceState): press, release -> re-anchored on the
 * measured pose): console link STALE; measured pose older than ~measured_timeout; no twist for
 * ~fault_timeout after twists had flowed; set-point lead saturated (~max_lead) for ~max_stall;
 * a restart under the same ROS master (~await_clutch_on_restart). Before the first step integrated
 * with the link up (start-up) these are plain holds, not faults. Collision monitoring
 * (collision_report) silent for ~collision_timeout: ~collision_loss "hold" (FAULT), "slow" (velocity
 * limits x ~collision_loss_speed_scale) or "ignore"; reported on /diagnostics either way.
 *
 * force_gate (std_msgs/Bool, latched by tank_slave): true while an implausible contact force holds the
 * channel: a fault (the arm driver stops the arm where it is; resume through the clutch).
 *
 * arm_link (std_msgs/Bool, latched by the arm driver): false on its (re)start and while disconnected,
 * true while it forwards set-points. False is a fault, and so is its return to true: after a driver
 * or arm outage the set-point re-anchors on the measured pose at the operator's clutch, not before
 * (a clutch released while this link is down or the console link is stale holds again). No publisher: no effect. The arm_link
 * publisher's node dropping its target_pose subscription (the driver died) is a fault too, and the
 * link stays down until a driver publishes true.
 *
 * hold (std_msgs/Bool, latched): true from a fault until the clutch release that clears it,
 * published on each change: the arm driver then stops the arm where it is instead of letting it
 * complete the last set-point, and re-synchronises when it turns false (the set-point is
 * re-anchored on the measured pose at that release, when the stopped arm's measurement has settled).
 * A plain clutch press (no fault) keeps the hold false: the arm completes its last set-point and the
 * release re-anchors on the measured pose as before (a quick press on a slow measurement stream
 * would otherwise re-anchor on a pose the stopped arm has already left).
 *
 * Instrument jaw (JawChannel, jaw_channel.h): the Simball clip angle of device_state -> jaw_target
 * (sensor_msgs/JointState, scaled, clamped to the jaw range, rate-limited), held whenever the
 * set-point is not commanding (FAULT, CLUTCHED, WAITING) or holds (link stale, no twist).
 */
#include <string>

#include <geometry_msgs/PoseStamped.h>
#include <geometry_msgs/TransformStamped.h>
#include <geometry_msgs/TwistStamped.h>
#include <pluginlib/class_list_macros.hpp>
#include <saras_msgs/CollisionReport.h>
#include <saras_msgs/ComponentStatus.h>
#include <saras_msgs/HapticDeviceState.h>
#include <std_msgs/Bool.h>
#include <tf2_ros/transform_broadcaster.h>

#include "jaw_channel.h"
#include "node_common.h"
#include "saras_common/message_pool.h"
#include "saras_teleop/velocity_integrator.h"

namespace saras_teleop
{
namespace node
{
namespace
{
IntegratorParams readParams(const ros::NodeHandle& pnh)
{
  const saras_common::Params prm(pnh);
  IntegratorParams p;
  p.max_linear_velocity = prm.number("max_linear_velocity", p.max_linear_velocity, "m/s", { saras_common::positive() });
  p.max_angular_velocity =
      prm.number("max_angular_velocity", p.max_angular_velocity, "rad/s", { saras_common::positive() });
  const auto box = [&prm](const char* name, const Eigen::Vector3d& def) {
    const std::vector<double> v = prm.numbers(name, { def.x(), def.y(), def.z() }, "m", {}, 3);
    return Eigen::Vector3d(v[0], v[1], v[2]);
  };
  p.workspace_min = box("workspace_min", p.workspace_min);
  p.workspace_max = box("workspace_max", p.workspace_max);
  p.max_lead = prm.number("max_lead", p.max_lead, "m", { saras_common::positive() });
  p.max_stall = prm.number("max_stall", p.max_stall, "s", { saras_common::positive() });
  p.validate();  // min < max (throws naming the parameter)
  return p;
}
}  // namespace

class VelocityIntegratorNode
{
public:
  /// @param name node or nodelet name without the leading '/' (the /diagnostics status is "<name>: set-point")
  VelocityIntegratorNode(ros::NodeHandle& nh, ros::NodeHandle& pnh, const std::string& name) : vi_(readParams(pnh))
  {
    using saras_common::positive;
    const saras_common::Params prm(pnh);
    const double rate = prm.number("rate", 1000.0, "Hz", { positive() });
    period_ = 1.0 / rate;
    const double watchdog = prm.number("watchdog_rate", 100.0, "Hz", { positive() });
    start_timeout_ = prm.number("start_timeout", 10.0, "s", { positive() });
    input_timeout_ = prm.number("input_timeout", 0.05, "s", { positive() });
    max_step_ = prm.number("max_step", 0.05, "s", { positive() });
    measured_timeout_ = prm.number("measured_timeout", 0.5, "s", { positive() });
    fault_timeout_ = prm.number("fault_timeout", 0.5, "s", { positive() });
    collision_timeout_ = prm.number("collision_timeout", 0.5, "s", { positive() });
    collision_loss_ = prm.text("collision_loss", "slow", { saras_common::oneOf({ "hold", "slow", "ignore" }) });
    collision_scale_ =
        prm.number("collision_loss_speed_scale", 0.2, "", { positive(), saras_common::inRange(0.0, 1.0) });
    await_clutch_ = prm.flag("await_clutch_on_restart", true) && restartedUnderThisMaster(pnh);
    frame_ = prm.text("frame_id", "mesa_left/sbs_world", { saras_common::nonEmpty() });
    tf_.header.frame_id = frame_;
    geometry_msgs::PoseStamped pose;
    pose.header.frame_id = frame_;
    pose_pool_.reset(new MessagePool<geometry_msgs::PoseStamped>(kPoolSize, pose));
    tf_.child_frame_id = prm.text("setpoint_frame", "mesa_left/setpoint", { saras_common::nonEmpty() });
    tf_decimation_ = static_cast<unsigned>(prm.integer("tf_decimation", 10, "set-points", { saras_common::atLeast(1) }));

    const ros::TransportHints fast = ros::TransportHints().tcpNoDelay();
    // the arm driver subscribes to the set-points: its subscription dropping (its process died: the
    // TCP connection closed; roscpp drops a subscriber link at once, while a subscriber keeps retrying
    // a dead publisher's link until the master tells it otherwise) is how the driver's death is seen
    pose_pub_ = nh.advertise<geometry_msgs::PoseStamped>(
        "target_pose", kStreamQueue, ros::SubscriberStatusCallback(),
        [this](const ros::SingleSubscriberPublisher& reader) { onSetpointReaderGone(reader); });
    hold_pub_ = nh.advertise<std_msgs::Bool>("hold", 1, true);
    start_sub_ = nh.subscribe("start_pose", 1, &VelocityIntegratorNode::onStart, this, fast);
    twist_sub_ = nh.subscribe("tank_twist", 10, &VelocityIntegratorNode::onTwist, this, fast);
    link_sub_ = nh.subscribe("link_status", 10, &VelocityIntegratorNode::onLink, this, fast);
    arm_link_sub_ = nh.subscribe("arm_link", 2, &VelocityIntegratorNode::onArmLink, this);
    gate_sub_ = nh.subscribe("force_gate", 2, &VelocityIntegratorNode::onForceGate, this);
    device_sub_ = nh.subscribe("device_state", 10, &VelocityIntegratorNode::onDevice, this, fast);
    collision_sub_ = nh.subscribe("collision_report", 2, &VelocityIntegratorNode::onCollision, this);
    jaw_.reset(new JawChannel(nh, pnh, max_step_, [this] { return hold_ || !vi_.commanding(); }));
    t0_ = ros::Time::now();
    timer_.reset(new PacedTimer(nh, period_, 1.0 / watchdog, [this](const ros::Time& now) { return onTimer(now); }));
    health_.reset(new Health(nh, pnh, name, "set-point",
                             [this](diagnostic_updater::DiagnosticStatusWrapper& s) { report(s); }));
  }

private:
  /// Measured slave pose: the start pose, then continuously (re-anchoring, lead limit)
  void onStart(const geometry_msgs::PoseStamped::ConstPtr& m)
  {
    const auto& p = m->pose.position;
    const auto& q = m->pose.orientation;
    const double qn = std::sqrt(q.x * q.x + q.y * q.y + q.z * q.z + q.w * q.w);
    const KDL::Frame f(KDL::Rotation::Quaternion(q.x, q.y, q.z, q.w), KDL::Vector(p.x, p.y, p.z));
    if (!(std::isfinite(qn) && std::fabs(qn - 1.0) < 1e-3) || !vi_.setMeasured(f))
    {
      ++rejected_;
      ROS_ERROR_THROTTLE(1.0, "velocity_integrator: invalid measured pose rejected (non-finite or non-unit quaternion)");
      return;
    }
    t_measured_ = ros::Time::now();
    if (vi_.started())
      return;
    vi_.start(f, await_clutch_);
    publishHold();  // the first (latched) state; then on each fault and clutch change
    ROS_INFO("velocity_integrator: start pose received, integrating in %s", frame_.c_str());
    if (await_clutch_)
      ROS_WARN("velocity_integrator: restarted; holding until the operator presses and releases the clutch");
  }

  void onLink(const saras_msgs::ComponentStatus::ConstPtr& m)
  {
    link_ok_ = m->level != saras_msgs::ComponentStatus::STALE;
    if (!link_ok_)
      fault("console link stale");
  }

  void onArmLink(const ros::MessageEvent<std_msgs::Bool const>& event)
  {
    const std_msgs::Bool::ConstPtr& m = event.getConstMessage();
    driver_name_ = event.getPublisherName();
    const bool was_down = !arm_link_ok_;
    arm_link_ok_ = m->data;
    if (!arm_link_ok_)
      fault("arm link down (driver restarted or disconnected)");
    else if (was_down)
      fault("arm link back: re-synchronise on the measured pose");
  }

  void onForceGate(const std_msgs::Bool::ConstPtr& m)
  {
    if (m->data)
      fault("implausible contact force (tank_slave's gate)");
  }

  void onDevice(const saras_msgs::HapticDeviceState::ConstPtr& m)
  {
    if (m->stale)
      return;
    jaw_->onDevice(*m);
    const bool was_fault = vi_.faults() > clutch_faults_;
    const bool released = vi_.clutch(m->clutch);
    if (released && (!arm_link_ok_ || !link_ok_))  // resume only with both links up
    {
      clutch_faults_ = vi_.faults();
      fault(arm_link_ok_ ? "console link still stale" : "arm link still down");
    }
    else if (released && was_fault)
    {
      clutch_faults_ = vi_.faults();
      ROS_INFO("velocity_integrator: clutch released after a hold: re-anchored on the measured pose, %.2f mm from "
               "the last commanded set-point; following",
               1e3 * (vi_.pose().p - last_sent_).Norm());
    }
    publishHold();
  }

  void onCollision(const saras_msgs::CollisionReport::ConstPtr&)
  {
    t_collision_ = ros::Time::now();
  }

  void fault(const std::string& why)
  {
    // start-up (console, arm state and twists not all up yet) is a hold, not a fault
    if (vi_.mode() == VelocityIntegrator::Mode::FAULT || !vi_.started() || !engaged_)
      return;
    vi_.fault(why);
    publishHold();  // the driver stops the arm now
    ROS_ERROR("velocity_integrator: HOLD (%s): set-point frozen, the arm holds until the operator presses and "
              "releases the clutch",
              why.c_str());
  }

  /// A subscriber of the set-points went away; the arm driver (the node that publishes arm_link): it
  /// died or unsubscribed, an event, not a timeout; the link counts as down until a driver publishes true.
  void onSetpointReaderGone(const ros::SingleSubscriberPublisher& reader)
  {
    if (driver_name_.empty() || reader.getSubscriberName() != driver_name_ || !arm_link_ok_)
      return;
    arm_link_ok_ = false;
    fault("arm link lost (the arm driver " + driver_name_ + " is gone)");
  }

  /// Timer-side supervision: stale measurement, twist stream gone, collision monitoring gone.
  void supervise(const ros::Time& now)
  {
    if (!t_measured_.isZero() && (now - t_measured_).toSec() > measured_timeout_)
      fault("arm state stale (no measured pose)");
    if (!t_twist_.isZero() && (now - t_twist_).toSec() > fault_timeout_)
      fault("no twist from the teleoperation chain");
    const bool collision_lost = collision_loss_ != "ignore" && (now - t0_).toSec() > start_timeout_ &&
                                (t_collision_.isZero() || (now - t_collision_).toSec() > collision_timeout_);
    if (collision_lost != collision_lost_)
    {
      collision_lost_ = collision_lost;
      if (collision_lost)
        ROS_ERROR("velocity_integrator: collision monitoring lost (no collision_report for %.2f s): %s",
                  collision_timeout_, collision_loss_ == "hold" ? "holding" : "reduced speed");
      else
        ROS_WARN("velocity_integrator: collision monitoring back");
    }
    vi_.setSpeedScale(collision_lost && collision_loss_ == "slow" ? collision_scale_ : 1.0);
    if (collision_lost && collision_loss_ == "hold")
      fault("collision monitoring lost");
  }

  void onTwist(const geometry_msgs::TwistStamped::ConstPtr& m)
  {
    const Vector6d v = toVec(m->twist);
    if (!v.allFinite())
    {
      ++rejected_;
      ROS_ERROR_THROTTLE(1.0, "velocity_integrator: non-finite twist rejected, holding");
      twist_.setZero();
      return;
    }
    ++received_;
    const ros::Time now = ros::Time::now();
    t_twist_ = now;
    hold_ = !link_ok_;
    const ros::Time stamp = m->header.stamp.isZero() ? now : m->header.stamp;
    if (vi_.started())
    {
      const double dt = last_stamp_.isZero() ? 0.0 : (stamp - last_stamp_).toSec();
      if (dt > 0.0 && dt <= max_step_)
      {
        vi_.step(v, dt, hold_);  // this twist held over the sample interval it represents
        engaged_ = engaged_ || (!hold_ && vi_.commanding());
      }
      if (dt > 0.0 || last_stamp_.isZero() || dt < -max_step_)
        last_stamp_ = stamp;
    }
    publish(stamp);
  }

  /// hold topic: on each change of "held by a fault", until the clutch release that clears it (latched)
  void publishHold()
  {
    const bool pending = vi_.faults() > clutch_faults_;  // a fault not yet cleared by a clutch release
    const bool held = vi_.started() && (vi_.mode() == VelocityIntegrator::Mode::FAULT ||
                                         (vi_.mode() == VelocityIntegrator::Mode::CLUTCHED && pending));
    if (hold_sent_ && held == held_)
      return;
    held_ = held;
    hold_sent_ = true;
    hold_msg_.data = held;
    hold_pub_.publish(hold_msg_);
  }

  void publish(const ros::Time& stamp)
  {
    if (!vi_.started())
      return;  // FAULT / CLUTCHED: the held set-point (the measured pose at the fault) is published
    const KDL::Frame& f = vi_.pose();
    const boost::shared_ptr<geometry_msgs::PoseStamped> pose = pose_pool_->next();  // zero-copy in a manager
    pose->header.stamp = stamp.isZero() ? ros::Time::now() : stamp;
    pose->pose.position.x = f.p.x();
    pose->pose.position.y = f.p.y();
    pose->pose.position.z = f.p.z();
    last_sent_ = f.p;
    f.M.GetQuaternion(pose->pose.orientation.x, pose->pose.orientation.y, pose->pose.orientation.z,
                      pose->pose.orientation.w);
    pose_pub_.publish(pose);
    published_.count();
    t_pub_ = ros::Time::now();
    if (++count_ % tf_decimation_ == 0)
    {
      tf_.header.stamp = pose->header.stamp;
      tf_.transform.translation.x = f.p.x();
      tf_.transform.translation.y = f.p.y();
      tf_.transform.translation.z = f.p.z();
      tf_.transform.rotation = pose->pose.orientation;
      broadcaster_.sendTransform(tf_);
    }
  }

  /// PacedTimer tick: true if the twist stream stopped (the held set-point was republished) or not started
  bool onTimer(const ros::Time& now)
  {
    if (!vi_.started())
    {
      const double waited = (now - t0_).toSec();
      if (waited > start_timeout_)
      {
        ROS_ERROR_THROTTLE(start_timeout_, "velocity_integrator: no slave start pose on %s after %.1f s; not commanding",
                           start_sub_.getTopic().c_str(), waited);
      }
      return true;
    }
    if (t_twist_.isZero() || (now - t_twist_).toSec() > input_timeout_)
      hold_ = true;  // no twist stream: the set-point is frozen
    supervise(now);
    if (t_pub_.isZero() || (now - t_pub_).toSec() > 1.5 * period_)
    {
      publish(ros::Time());
      return true;
    }
    return false;
  }

  /// /diagnostics (Health, 1 Hz)
  void report(diagnostic_updater::DiagnosticStatusWrapper& s)
  {
    using diagnostic_msgs::DiagnosticStatus;
    const ros::Time now = ros::Time::now();
    if (!vi_.started())
      s.summary((now - t0_).toSec() > start_timeout_ ? DiagnosticStatus::ERROR : DiagnosticStatus::WARN,
                "no slave start pose");
    else if (vi_.mode() == VelocityIntegrator::Mode::FAULT)
      s.summary(DiagnosticStatus::ERROR, "HOLD: " + vi_.faultReason() + "; resume: press and release the clutch");
    else if (collision_lost_)
      s.summary(collision_loss_ == "ignore" ? DiagnosticStatus::WARN : DiagnosticStatus::ERROR,
                "collision monitoring lost: " +
                    std::string(collision_loss_ == "slow" ? "reduced speed" : "not supervised"));
    else if (vi_.mode() == VelocityIntegrator::Mode::CLUTCHED)
      s.summary(DiagnosticStatus::OK, "clutch: holding, re-anchors on release");
    else if (hold_)
      s.summary(DiagnosticStatus::STALE, "holding: master link stale or no twist");
    else
      s.summary(DiagnosticStatus::OK, "integrating");
    s.add("input age [s]", t_twist_.isZero() ? 1e6 : std::min((now - t_twist_).toSec(), 1e6));
    s.add("target_pose rate [Hz]", published_.rate());
    s.add("link ok", link_ok_);
    s.add("arm link ok", arm_link_ok_);
    s.add("measured pose age [s]", t_measured_.isZero() ? 1e6 : std::min((now - t_measured_).toSec(), 1e6));
    s.add("set-point lead [mm]", 1e3 * vi_.lead());
    s.add("lead-limited steps", vi_.leadLimitedSteps());
    s.add("faults", vi_.faults());
    s.add("collision monitoring", collision_lost_ ? "lost" : "ok");
    s.add("speed scale", vi_.speedScale());
    s.add("received", received_);
    s.add("rejected", rejected_);
    s.add("timer", timer_->describe());
    jaw_->report(s);
  }

  VelocityIntegrator vi_;
  std::unique_ptr<JawChannel> jaw_;  // Simball clip -> instrument jaw
  std::unique_ptr<Health> health_;  // /diagnostics, created at the end of the constructor
  RateMeter published_;
  tf2_ros::TransformBroadcaster broadcaster_;
  double period_ = 0.001, start_timeout_ = 10.0, input_timeout_ = 0.05, max_step_ = 0.05;
  double measured_timeout_ = 0.5, fault_timeout_ = 0.5, collision_timeout_ = 0.5, collision_scale_ = 0.2;
  KDL::Vector last_sent_;  // position of the last published set-point
  std::size_t clutch_faults_ = 0;  // faults already cleared by a clutch
  std::string collision_loss_ = "slow";
  bool await_clutch_ = false, collision_lost_ = false;
  bool engaged_ = false;  // integrated once with the link up: holds from now on are faults
  std::string frame_;
  unsigned tf_decimation_ = 10;
  unsigned long count_ = 0;
  Vector6d twist_ = Vector6d::Zero();
  bool link_ok_ = true, hold_ = true, arm_link_ok_ = true;
  std::string driver_name_;  ///< node that publishes arm_link (the arm driver), once heard
  static constexpr std::size_t kPoolSize = 16;  // > subscriber queue sizes (10)
  std::unique_ptr<MessagePool<geometry_msgs::PoseStamped>> pose_pool_;
  geometry_msgs::TransformStamped tf_;
  ros::Publisher pose_pub_, hold_pub_;
  std_msgs::Bool hold_msg_;
  bool held_ = false, hold_sent_ = false;
  ros::Subscriber start_sub_, twist_sub_, link_sub_, arm_link_sub_, gate_sub_, device_sub_, collision_sub_;
  std::unique_ptr<PacedTimer> timer_;  ///< fill-in and supervision (~rate; ~watchdog_rate while twists flow)
  ros::Time t0_, t_twist_, t_pub_, last_stamp_, t_measured_, t_collision_;
  uint64_t received_ = 0, rejected_ = 0;
};

/// Nodelet `saras_teleop/VelocityIntegrator` (nodelet_plugins.xml).
class VelocityIntegratorNodelet : public NodeletAdapter<VelocityIntegratorNode>
{
};

}  // namespace node
}  // namespace saras_teleop

PLUGINLIB_EXPORT_CLASS(saras_teleop::node::VelocityIntegratorNodelet, nodelet::Nodelet)
