/**
 * @file tank_node.h
 * @brief ROS adapter of EnergyTank, shared by tank_master (wrench actions, measured master twists)
 *        and tank_slave (twist actions, measured interaction forces). One instance serves all channels.
 *
 * Relative names (remapped by the launch files), for each channel c in ~channels:
 *   master: sub c/meas_cart_vel (TwistStamped), c/des_wrench (WrenchStamped); pub c/tank_wrench
 *   slave:  sub c/contact_force (Twist, linear = force of the environment on the tool [N]),
 *           c/des_twist (TwistStamped); pub c/tank_twist
 *   both:   sub pin, ext_ereq (Float32); pub pout, ereq (Float32), energy (Float64, T [J]).
 *
 * Timing: the tank steps when the trigger input of a channel arrives (master: the measured twist,
 * i.e. each device sample; slave: the desired twist) and publishes that channel at once, with the
 * trigger's stamp; a timer at ~rate steps the tank if no input triggered a step for 1.5 periods and
 * then publishes the (safe) output of the channels whose trigger input is older than ~input_timeout.
 * The exchange (pout, ereq, energy) goes out once per control cycle: from the steps while every
 * channel's trigger flows (after every channel stepped once, or when a channel steps again before the
 * others), so that it follows the device samples as the outputs do and needs no timer tick (a late
 * tick on a loaded host would thin it out); from the timer, once per tick, while a trigger is
 * missing (older than 10 periods). While every channel's trigger flows the timer runs at
 * ~watchdog_rate (PacedTimer, node_common.h).
 * Energy exchange: a pout message carries the energy sent since the previous one divided by the
 * exchange period 1/rate [W]; the receiver credits msg * (1/rate) [J] once per message, so a lost or
 * delayed packet can only lose energy, never duplicate it (a latched power would).
 * Safety: a port whose action (or, with ~require_measurement, its measurement) is older than
 * ~input_timeout gets a zero action (only damping); non-finite inputs are rejected (counted) and
 * ignored. tank_slave defaults to require_measurement false: without a contact estimator the
 * interaction force is taken as zero (free motion) and the status says so (WARN).
 * tank_slave gates every contact force (ForceGate: ~max_contact_force [N], ~max_contact_force_step
 * [N] + ~max_contact_force_rate [N/s] * dt, non-finite): a violation zeroes the channel's action and
 * measurement for ~contact_force_hold_time [s] (the arm holds) and is reported (ERROR, counters);
 * <channel>/force_gate (std_msgs/Bool, latched) is true while it holds, so that the channel's
 * velocity_integrator holds the arm where it is and resumes only through the operator's clutch.
 * A tank restarted under the same ROS master (respawn) never comes back with fresh energy: with
 * ~energy_journal_dir (default /dev/shm; '' = off) it resumes with exactly the energy of its last
 * completed step before it died (EnergyJournal, a memory-mapped file bound to this master session by
 * the token in ~journal_token), otherwise (no journal, another session, unreadable) at T_min.
 */
#ifndef SARAS_TELEOP_TANK_NODE_H
#define SARAS_TELEOP_TANK_NODE_H

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include <geometry_msgs/Twist.h>
#include <geometry_msgs/TwistStamped.h>
#include <geometry_msgs/WrenchStamped.h>
#include <ros/ros.h>
#include <std_msgs/Bool.h>
#include <std_msgs/Float32.h>
#include <std_msgs/Float64.h>

#include "node_common.h"
#include "saras_teleop/energy_journal.h"
#include "saras_teleop/energy_tank.h"
#include "saras_teleop/force_gate.h"
#include "saras_common/message_pool.h"

namespace saras_teleop
{
namespace node
{
struct MasterTraits
{
  typedef geometry_msgs::WrenchStamped Desired;
  typedef geometry_msgs::TwistStamped Conjugate;
  typedef geometry_msgs::WrenchStamped Output;
  static constexpr const char* kName = "tank_master";
  static constexpr const char* kDesired = "des_wrench";
  static constexpr const char* kConjugate = "meas_cart_vel";
  static constexpr const char* kOutput = "tank_wrench";
  static constexpr bool kTriggerOnDesired = false;
  static constexpr bool kRequireMeasurement = true;
  static constexpr bool kGateForce = false;
  static constexpr const char* kDampingUnit = "N s/m x3, N m s/rad x3";
  static Vector6d desired(const Desired& m) { return toVec(m.wrench); }
  static Vector6d conjugate(const Conjugate& m, double /*sign*/) { return toVec(m.twist); }
  static ros::Time stamp(const Conjugate& m) { return m.header.stamp; }
  static void fill(const Vector6d& v, Output& o) { fromVec(v, o.wrench); }
};

struct SlaveTraits
{
  typedef geometry_msgs::TwistStamped Desired;
  typedef geometry_msgs::Twist Conjugate;
  typedef geometry_msgs::TwistStamped Output;
  static constexpr const char* kName = "tank_slave";
  static constexpr const char* kDesired = "des_twist";
  static constexpr const char* kConjugate = "contact_force";
  static constexpr const char* kOutput = "tank_twist";
  static constexpr bool kTriggerOnDesired = true;
  static constexpr bool kRequireMeasurement = false;  // no contact estimator running = free motion
  static constexpr bool kGateForce = true;            // plausibility gate of the contact force
  static constexpr const char* kDampingUnit = "m/(N s) x3, rad/(N m s) x3";
  static Vector6d desired(const Desired& m) { return toVec(m.twist); }
  /// Effort the tool exerts on the environment = sign * (force of the environment on the tool).
  static Vector6d conjugate(const Conjugate& m, double sign)
  {
    Vector6d v = Vector6d::Zero();
    v << sign * m.linear.x, sign * m.linear.y, sign * m.linear.z, 0.0, 0.0, 0.0;
    return v;
  }
  static ros::Time stamp(const Conjugate& /*m*/) { return ros::Time(); }
  static void fill(const Vector6d& v, Output& o) { fromVec(v, o.twist); }
};

template <class Traits>
class TankNode
{
public:
  /// @param name node or nodelet name (the /diagnostics status is "<name>: energy tank")
  TankNode(ros::NodeHandle& nh, ros::NodeHandle& pnh, const std::string& name)
  {
    using saras_common::nonNegative;
    using saras_common::positive;
    const saras_common::Params prm(pnh);
    TankParams p;
    p.T_init = prm.number("T_init", p.T_init, "J", { positive() });
    p.T_max = prm.number("T_max", p.T_max, "J", { positive() });
    p.T_min = prm.number("T_min", p.T_min, "J", { positive() });
    p.T_req = prm.number("T_req", p.T_req, "J", { positive() });
    p.T_ava = prm.number("T_ava", p.T_ava, "J", { positive() });
    p.P_const = prm.number("P_const", p.P_const, "W", { nonNegative() });
    p.damping_std = paramVector6(prm, "damping_std", p.damping_std, Traits::kDampingUnit, { nonNegative() });
    p.damping_max = paramVector6(prm, "damping_max", p.damping_max, Traits::kDampingUnit, { nonNegative() });
    p.bypass = prm.flag("bypass", false);
    const double rate = prm.number("rate", 1000.0, "Hz", { positive() });
    period_ = 1.0 / rate;
    const double watchdog = prm.number("watchdog_rate", 100.0, "Hz", { positive() });
    input_timeout_ = prm.number("input_timeout", 0.1, "s", { positive() });
    force_sign_ = prm.number("contact_force_sign", -1.0, "", { saras_common::inRange(-1.0, 1.0) });
    require_measurement_ = prm.flag("require_measurement", Traits::kRequireMeasurement);
    const std::vector<std::string> channels = paramChannels(prm);
    ForceGateParams g;
    if (Traits::kGateForce)
    {
      g.max_force = prm.number("max_contact_force", g.max_force, "N", { positive() });
      g.max_step = prm.number("max_contact_force_step", g.max_step, "N", { positive() });
      g.max_rate = prm.number("max_contact_force_rate", g.max_rate, "N/s", { positive() });
      g.hold_time = prm.number("contact_force_hold_time", g.hold_time, "s", { positive() });
    }
    g.timeout = input_timeout_;
    resume(pnh, prm.text("energy_journal_dir", "/dev/shm"), name, p);
    p.validate();  // the order of the energy levels (throws naming the parameter)
    tank_.reset(new EnergyTank(p, channels.size()));
    if (p.bypass)
      ROS_WARN("%s: bypass:=true, the energy tank is DISABLED (passivity not guaranteed)", Traits::kName);

    const ros::TransportHints fast = ros::TransportHints().tcpNoDelay();
    ports_.resize(channels.size());
    for (std::size_t i = 0; i < channels.size(); ++i)
    {
      Port& pt = ports_[i];
      pt.name = channels[i];
      if (Traits::kGateForce)
      {
        pt.gate.reset(new ForceGate(g));
        pt.gate_pub = nh.advertise<std_msgs::Bool>(channels[i] + "/force_gate", 1, true);
        publishGate(pt, false);
      }
      typename Traits::Output proto;
      proto.header.frame_id = "mesa_" + channels[i] + "/sbs_world";
      pt.pool.reset(new MessagePool<typename Traits::Output>(kPoolSize, proto));
      pt.pub = nh.advertise<typename Traits::Output>(channels[i] + "/" + Traits::kOutput, kStreamQueue);
      pt.sub_des = nh.subscribe<typename Traits::Desired>(
          channels[i] + "/" + Traits::kDesired, 10,
          [this, i](const typename Traits::Desired::ConstPtr& m) { onDesired(i, *m); }, ros::VoidConstPtr(), fast);
      pt.sub_conj = nh.subscribe<typename Traits::Conjugate>(
          channels[i] + "/" + Traits::kConjugate, 10,
          [this, i](const typename Traits::Conjugate::ConstPtr& m) { onConjugate(i, *m); }, ros::VoidConstPtr(),
          fast);
    }
    pin_sub_ = nh.subscribe("pin", 100, &TankNode::onPin, this, fast);
    ereq_sub_ = nh.subscribe("ext_ereq", 10, &TankNode::onExtEreq, this, fast);
    pout_pub_ = nh.advertise<std_msgs::Float32>("pout", kStreamQueue);
    ereq_pub_ = nh.advertise<std_msgs::Float32>("ereq", kStreamQueue);
    energy_pub_ = nh.advertise<std_msgs::Float64>("energy", kStreamQueue);
    last_step_ = ros::Time::now();
    cycle_.assign(channels.size(), false);
    timer_.reset(new PacedTimer(nh, period_, 1.0 / watchdog, [this](const ros::Time& now) { return onTimer(now); }));
    health_.reset(new Health(nh, pnh, name, "energy tank",
                             [this](diagnostic_updater::DiagnosticStatusWrapper& s) { report(s); }));
    ROS_INFO("%s: %zu channel(s), T_init %.2f J, rate %.0f Hz", Traits::kName, channels.size(), p.T_init, rate);
  }

private:
  /// A fresh start takes T_init and a new journal session; a restart (same master) the journal's
  /// energy of this session, or T_min without one. The journal then records every step.
  void resume(ros::NodeHandle& pnh, const std::string& dir, const std::string& name, TankParams& p)
  {
    const bool restarted = restartedUnderThisMaster(pnh);
    std::string token_text;
    std::uint64_t token = 0;
    if (restarted && pnh.getParam("journal_token", token_text))
      token = std::strtoull(token_text.c_str(), nullptr, 16);
    if (token == 0)
    {
      token = EnergyJournal::newToken();
      char buf[17];
      std::snprintf(buf, sizeof(buf), "%016llx", static_cast<unsigned long long>(token));
      pnh.setParam("journal_token", std::string(buf));
    }
    double last = std::numeric_limits<double>::quiet_NaN();
    if (!dir.empty())
    {
      const std::size_t key = std::hash<std::string>()(ros::master::getURI() + "|" + name);
      char file[64];
      std::snprintf(file, sizeof(file), "/saras_energy_%016zx", key);
      last = journal_.open(dir + file, token);  // throws naming the file: a clear startup error
    }
    if (!restarted)
      return;
    if (std::isfinite(last) && last > p.T_min)
    {
      ROS_WARN("%s: restarted under the same ROS master: resuming with the energy it had, %.3f J (journal %s)",
               Traits::kName, last, journal_.path().c_str());
      p.T_init = std::min(last, p.T_max);
      return;
    }
    // a respawned tank must not come back with more energy than it had: start empty (T_min)
    ROS_WARN("%s: restarted under the same ROS master: no energy journal of this session%s, tank starts at "
             "T_min %.2f J (not T_init %.2f J)",
             Traits::kName, dir.empty() ? " (energy_journal_dir empty)" : "", p.T_min, p.T_init);
    p.T_init = std::nextafter(p.T_min, p.T_max);  // TankParams requires T_init > T_min
  }

  struct Port
  {
    std::string name;
    ros::Subscriber sub_des, sub_conj;
    ros::Publisher pub;
    std::unique_ptr<MessagePool<typename Traits::Output>> pool;  // zero-copy publishing in a manager
    ros::Time t_des, t_conj;  // arrival times (ROS clock)
    ros::Time t_trigger;      // last step triggered by this port's input
    ros::Time stamp;          // header stamp propagated to the output
    Vector6d des = Vector6d::Zero(), conj = Vector6d::Zero();
    std::unique_ptr<ForceGate> gate;  // tank_slave: contact-force plausibility
    ros::Publisher gate_pub;          // <channel>/force_gate, latched
    bool gate_state = false;
  };

  /// On a change of the gate only (a fault: the one allocation is not on the steady-state path).
  static void publishGate(Port& pt, bool holding)
  {
    pt.gate_state = holding;
    std_msgs::BoolPtr m(new std_msgs::Bool);
    m->data = holding;
    pt.gate_pub.publish(m);
  }

  void onDesired(std::size_t i, const typename Traits::Desired& m)
  {
    const Vector6d v = Traits::desired(m);
    if (!v.allFinite())
    {
      reject("non-finite desired action on " + ports_[i].name);
      return;
    }
    ++received_;
    ports_[i].des = v;
    ports_[i].t_des = ros::Time::now();
    if (Traits::kTriggerOnDesired)
    {
      ports_[i].stamp = m.header.stamp;
      stepAndPublish(i);
    }
  }

  void onConjugate(std::size_t i, const typename Traits::Conjugate& m)
  {
    const Vector6d v = Traits::conjugate(m, force_sign_);
    if (!v.allFinite())
    {
      reject("non-finite measurement on " + ports_[i].name);
      return;
    }
    ++received_;
    Port& pt = ports_[i];
    if (pt.gate && pt.gate->offer(v.head<3>(), ros::Time::now().toSec()) != ForceGate::Verdict::ACCEPTED)
    {
      reject("implausible contact force on " + pt.name + " (" + pt.gate->lastViolation() + "): holding");
      return;
    }
    pt.conj = v;
    pt.t_conj = ros::Time::now();
    if (!Traits::kTriggerOnDesired)
    {
      ports_[i].stamp = Traits::stamp(m);
      stepAndPublish(i);
    }
  }

  void onPin(const std_msgs::Float32::ConstPtr& m)
  {
    if (!std::isfinite(m->data) || m->data < 0.0f)
    {
      reject("invalid Pin");
      return;
    }
    inbox_ += static_cast<double>(m->data) * period_;
  }

  void onExtEreq(const std_msgs::Float32::ConstPtr& m)
  {
    if (!std::isfinite(m->data))
    {
      reject("invalid ext_ereq");
      return;
    }
    ext_ereq_ = m->data;
  }

  void reject(const std::string& why)
  {
    ++rejected_;
    ROS_ERROR_THROTTLE(1.0, "%s: rejected input (%s); %lu rejected so far", Traits::kName, why.c_str(),
                       static_cast<unsigned long>(rejected_));
  }

  /// Step the tank with all ports' latest inputs (stale ports get a zero action).
  void step(const ros::Time& now)
  {
    double dt = (now - last_step_).toSec();
    last_step_ = now;
    if (!(dt > 0.0))
      dt = 1e-6;  // two triggers in the same clock tick: a tiny step keeps the accounting exact
    dt = std::min(dt, 10.0 * period_);
    stale_ = false;
    for (std::size_t i = 0; i < ports_.size(); ++i)
    {
      Port& pt = ports_[i];
      const bool fresh_conj = !pt.t_conj.isZero() && (now - pt.t_conj).toSec() <= input_timeout_;
      const bool fresh_des = !pt.t_des.isZero() && (now - pt.t_des).toSec() <= input_timeout_;
      if (!fresh_conj)
        stale_ = true;
      tank_->setConjugate(i, fresh_conj ? pt.conj : Vector6d::Zero());
      // no trustworthy measurement -> the power of the action cannot be accounted -> no action
      // (unless ~require_measurement is false: the slave then assumes free motion)
      const bool measured = fresh_conj || !require_measurement_;
      const bool gated = pt.gate && pt.gate->holding(now.toSec());  // implausible force: hold the arm
      if (gated)
        tank_->setConjugate(i, Vector6d::Zero());
      if (pt.gate && gated != pt.gate_state)
        publishGate(pt, gated);
      tank_->setDesired(i, (fresh_des && measured && !gated) ? pt.des : Vector6d::Zero());
    }
    const double pin = inbox_ / dt;
    inbox_ = 0.0;
    tank_->step(dt, pin, ext_ereq_);
    outbox_ += tank_->pout() * dt;
    journal_.record(tank_->energy());  // one store into the mapped journal
  }

  void publishPort(std::size_t i, const ros::Time& stamp)
  {
    Port& pt = ports_[i];
    const boost::shared_ptr<typename Traits::Output> out = pt.pool->next();
    out->header.stamp = stamp.isZero() ? ros::Time::now() : stamp;
    Traits::fill(tank_->output(i), *out);
    pt.pub.publish(out);
    published_.count();
  }

  void stepAndPublish(std::size_t i)
  {
    const ros::Time now = ros::Time::now();
    const bool flowing = triggersFlow(now);
    if (flowing && cycle_[i])  // this channel steps again before the others did: close the cycle
      publishExchange();
    step(now);
    publishPort(i, ports_[i].stamp);
    last_trigger_ = now;
    ports_[i].t_trigger = now;
    if (!flowing)
      return;
    cycle_[i] = true;
    if (std::find(cycle_.begin(), cycle_.end(), false) == cycle_.end())
      publishExchange();
  }

  /// Every channel's trigger input stepped the tank within the last @p periods periods.
  bool triggeredWithin(const ros::Time& now, double periods) const
  {
    for (const Port& pt : ports_)
      if (pt.t_trigger.isZero() || (now - pt.t_trigger).toSec() > periods * period_)
        return false;
    return true;
  }

  /// The triggers flow: inputs a few periods late on a loaded host still do (their next cycle
  /// carries the exchange, exactly).
  bool triggersFlow(const ros::Time& now) const { return triggeredWithin(now, kFlowPeriods); }

  /// PacedTimer tick: true if a channel's trigger is older than 1.5 periods (the timer then runs at
  /// ~rate: it steps the tank when no trigger came and carries the exchange while one is missing)
  bool onTimer(const ros::Time& now)
  {
    const bool gap = !triggeredWithin(now, 1.5);
    if (last_trigger_.isZero() || (now - last_trigger_).toSec() > 1.5 * period_)
    {
      step(now);
      // a port whose trigger input still flows gets its output at the next trigger (keeps the
      // stamp sequence of the master samples); a port without input gets its safe output now
      for (std::size_t i = 0; i < ports_.size(); ++i)
      {
        const ros::Time& trig = Traits::kTriggerOnDesired ? ports_[i].t_des : ports_[i].t_conj;
        if (trig.isZero() || (now - trig).toSec() > input_timeout_)
          publishPort(i, ros::Time());
      }
    }
    if (!triggersFlow(now))  // else the steps follow the inputs and carry the exchange
      publishExchange();
    return gap;
  }

  /// Energy exchange with the peer tank (pout, ereq) and the energy: what was sent since the last
  /// message, as power over the exchange period (the peer credits msg * period: exact whatever the
  /// messages' timing); starts a new control cycle.
  void publishExchange()
  {
    std::fill(cycle_.begin(), cycle_.end(), false);
    pout_msg_.data = static_cast<float>(outbox_ / period_);
    outbox_ -= static_cast<double>(pout_msg_.data) * period_;  // keep the float rounding for next time
    pout_pub_.publish(pout_msg_);
    ereq_msg_.data = static_cast<float>(tank_->ereq());
    ereq_pub_.publish(ereq_msg_);
    energy_msg_.data = tank_->energy();
    energy_pub_.publish(energy_msg_);
  }

  /// /diagnostics (Health, 1 Hz): level and message as below, energies and counters as key/values.
  void report(diagnostic_updater::DiagnosticStatusWrapper& s)
  {
    using diagnostic_msgs::DiagnosticStatus;
    std::size_t violations = 0;
    std::string gated;
    for (const Port& pt : ports_)
      if (pt.gate)
      {
        violations += pt.gate->violations();
        if (pt.gate->holding(ros::Time::now().toSec()))
          gated += (gated.empty() ? "" : ", ") + pt.name + " (" + pt.gate->lastViolation() + ")";
      }
    if (!gated.empty())
      s.summary(DiagnosticStatus::ERROR, "implausible contact force, holding: " + gated);
    else if (stale_ && require_measurement_)
      s.summary(DiagnosticStatus::STALE, "measurement inputs stale: actions zeroed");
    else if (stale_)
      s.summary(DiagnosticStatus::WARN, "no interaction-force measurement: assuming free motion");
    else if (tank_->energy() < tank_->params().T_req)
      s.summary(DiagnosticStatus::WARN, "tank low: set-points reduced");
    else
      s.summary(DiagnosticStatus::OK, "tank ok");
    const TankParams& p = tank_->params();
    s.add("energy [J]", tank_->energy());
    s.add("T_min [J]", p.T_min);
    s.add("T_req [J]", p.T_req);
    s.add("T_max [J]", p.T_max);
    s.add("set-point reduction KE", tank_->info().KE);
    s.add("energy request (ereq)", tank_->ereq());
    s.add("peer energy request (ext_ereq)", ext_ereq_);
    s.add("bypass", p.bypass);
    s.add("output rate [Hz]", published_.rate());
    s.add("received", received_);
    s.add("rejected", rejected_);
    s.add("timer", timer_->describe());
    if (Traits::kGateForce)
      s.add("contact force violations", violations);
  }

  static constexpr std::size_t kPoolSize = 16;   // > subscriber queue sizes (10)
  static constexpr double kFlowPeriods = 10.0;  // triggersFlow() window [periods]
  std::unique_ptr<EnergyTank> tank_;
  EnergyJournal journal_;  // the energy after every step, for a restart
  std::vector<Port> ports_;
  ros::Subscriber pin_sub_, ereq_sub_;
  ros::Publisher pout_pub_, ereq_pub_, energy_pub_;
  std::unique_ptr<PacedTimer> timer_;  // ~rate; ~watchdog_rate while every channel's trigger flows
  std::vector<bool> cycle_;  // channels stepped since the last exchange (while every trigger flows)
  std_msgs::Float32 pout_msg_, ereq_msg_;
  std_msgs::Float64 energy_msg_;
  std::unique_ptr<Health> health_;  // /diagnostics, created at the end of the constructor
  RateMeter published_;             // outputs on the channels' tank_wrench / tank_twist
  double period_ = 0.001, input_timeout_ = 0.1, force_sign_ = -1.0;
  double inbox_ = 0.0, outbox_ = 0.0, ext_ereq_ = 0.0;
  ros::Time last_step_, last_trigger_;
  bool stale_ = true;
  bool require_measurement_ = true;
  uint64_t received_ = 0, rejected_ = 0;
};

}  // namespace node
}  // namespace saras_teleop

#endif  // SARAS_TELEOP_TANK_NODE_H
